//! SAH cost of wide trees, to measure the greedy collapse of the conversion against the
//! SAH-optimal one of Ylitie, Karras & Laine 2017 (§3.1, the dynamic program over binary nodes)
//! on the same binary tree with the same leaves: cost = (Ci·Σ_wide nodes A + Ct·Σ_leaves A·N) /
//! A(root), a wide node visit costing Ci like a binary one. The optimum is computed, not built:
//! the GPU conversion stays greedy, and `treelet bench` reports both costs for the wide layout.
//!
//! The program, per binary node n and slot count i in 1..=8: C(n, i) is the least cost of n's
//! subtree spread over at most i slots of the wide node above it; C(n, 1) = Ct·A·N for a leaf and
//! Ci·A(n) + C_dist(n, 8) otherwise (n becomes a wide node), C(n, i) = min(C(n, i − 1),
//! C_dist(n, i)), C_dist(n, i) = min over 0 < k < i of C(l, k) + C(r, i − k) (leaves keep their
//! binary leaves: they are not merged or split).

use super::node::WIDTH;
use crate::bvh::{Bvh, BvhNode, SahParams};

/// Nodes reachable from the root, children after parents.
fn top_down(bvh: &Bvh) -> Vec<usize> {
    let mut order = Vec::with_capacity(bvh.nodes.len());
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        order.push(i);
        let n = &bvh.nodes[i];
        if !n.is_leaf() {
            let (l, r) = n.children();
            stack.extend([l as usize, r as usize]);
        }
    }
    order
}

/// (greedy, optimal) wide SAH of `bvh` converted by `WideBvh::from_binary` and by the optimal
/// collapse. An empty tree costs 0; a root of zero area takes every area as 1, as `sah_cost` does.
pub fn wide_sah_costs(bvh: &Bvh, params: &SahParams) -> (f64, f64) {
    let Some(root) = bvh.nodes.first() else {
        return (0.0, 0.0);
    };
    let root_area = root.bounds().surface_area();
    let degenerate = !(root_area > 0.0 && root_area.is_finite());
    let area = |n: &BvhNode| {
        if degenerate {
            1.0
        } else {
            f64::from(n.bounds().surface_area()) / f64::from(root_area)
        }
    };
    let (ci, ct) = (f64::from(params.ci), f64::from(params.ct));
    let order = top_down(bvh);
    let leaf_cost = |n: &BvhNode| ct * area(n) * f64::from(n.prim_count());
    // Optimal: cost[n][i - 1] = C(n, i).
    let mut cost = vec![[0.0f64; WIDTH]; bvh.nodes.len()];
    for &i in order.iter().rev() {
        let n = &bvh.nodes[i];
        if n.is_leaf() {
            cost[i] = [leaf_cost(n); WIDTH];
            continue;
        }
        let (l, r) = n.children();
        let (cl, cr) = (cost[l as usize], cost[r as usize]);
        let dist = |slots: usize| {
            (1..slots)
                .map(|k| cl[k - 1] + cr[slots - k - 1])
                .fold(f64::MAX, f64::min)
        };
        let mut c = [0.0; WIDTH];
        c[0] = ci * area(n) + dist(WIDTH);
        for slots in 2..=WIDTH {
            c[slots - 1] = c[slots - 2].min(dist(slots));
        }
        cost[i] = c;
    }
    let optimal = if bvh.nodes[0].is_leaf() {
        // One wide node holding the leaf.
        ci * area(&bvh.nodes[0]) + cost[0][0]
    } else {
        cost[0][0]
    };
    // Greedy: the children of each wide node as the conversion opens them.
    let greedy_node = |source: usize, stack: &mut Vec<usize>| -> f64 {
        let top = &bvh.nodes[source];
        let mut total = ci * area(top);
        if top.is_leaf() {
            return total + leaf_cost(top);
        }
        for c in super::convert::open_children(bvh, source as u32) {
            let child = &bvh.nodes[c as usize];
            if child.is_leaf() {
                total += leaf_cost(child);
            } else {
                stack.push(c as usize);
            }
        }
        total
    };
    let mut greedy = 0.0;
    let mut stack = vec![0usize];
    while let Some(source) = stack.pop() {
        greedy += greedy_node(source, &mut stack);
    }
    (greedy, optimal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::build_sweep_sah;
    use crate::scene::Triangle;
    use glam::Vec3;

    #[test]
    fn greedy_is_never_below_the_optimum() {
        let mut triangles = Vec::new();
        let mut s = 7u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..2000 {
            let p = Vec3::new(next(), next(), next()) * 10.0;
            let d = Vec3::new(next(), next(), next()) * 0.3;
            triangles.push(Triangle::new(
                p,
                p + Vec3::new(d.x, 0.0, 0.0),
                p + Vec3::new(0.0, d.y, d.z),
                0,
            ));
        }
        let bvh = build_sweep_sah(&triangles, &SahParams::default());
        let (greedy, optimal) = wide_sah_costs(&bvh, &SahParams::default());
        assert!(
            optimal > 0.0 && optimal <= greedy * (1.0 + 1e-9),
            "{greedy} {optimal}"
        );
        // A wide tree visits fewer nodes than the binary one: its cost is below the binary SAH.
        let binary = f64::from(crate::bvh::sah_cost(&bvh, &SahParams::default()));
        assert!(greedy < binary, "greedy {greedy} vs binary {binary}");
    }
}
