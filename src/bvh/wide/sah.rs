//! SAH cost of wide trees, to measure the greedy collapse of the conversion against the
//! SAH-optimal one of Ylitie, Karras & Laine 2017 (§3.1, the dynamic program over binary nodes)
//! on the same binary tree with the same leaves: cost = (Ci·Σ_wide nodes A + Ct·Σ_leaves A·N) /
//! A(root), a wide node visit costing Ci like a binary one. `treelet bench` reports both costs
//! for the wide layout. The program is `OptimalCollapse`'s.

use super::convert::open_children;
use super::optimal::{relative_area, OptimalCollapse};
use crate::bvh::{Bvh, SahParams};

/// The wide SAH cost of the collapse whose wide node made from binary node `source` takes the
/// binary nodes `children(source)` as its children.
pub(crate) fn collapse_cost(
    bvh: &Bvh,
    params: &SahParams,
    children: impl Fn(u32) -> Vec<u32>,
) -> f64 {
    let area = relative_area(bvh);
    let (ci, ct) = (f64::from(params.ci), f64::from(params.ct));
    let mut total = 0.0;
    let mut stack = vec![0u32];
    while let Some(source) = stack.pop() {
        total += ci * area(&bvh.nodes[source as usize]);
        for c in children(source) {
            let child = &bvh.nodes[c as usize];
            if child.is_leaf() {
                total += ct * area(child) * f64::from(child.prim_count());
            } else {
                stack.push(c);
            }
        }
    }
    total
}

/// (greedy, optimal) wide SAH of `bvh` converted by `WideBvh::from_binary` and by the optimal
/// collapse. An empty tree costs 0; a root of zero area takes every area as 1, as `sah_cost` does.
pub fn wide_sah_costs(bvh: &Bvh, params: &SahParams) -> (f64, f64) {
    if bvh.nodes.is_empty() {
        return (0.0, 0.0);
    }
    let greedy = collapse_cost(bvh, params, |source| open_children(bvh, source));
    (greedy, OptimalCollapse::new(bvh, params).cost(bvh))
}

#[cfg(test)]
mod tests {
    use super::super::convert::half_area;
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
        let params = SahParams::default();
        let (greedy, optimal) = wide_sah_costs(&bvh, &params);
        // The program runs in f32 (as on the GPU): its optimum is exact up to f32 rounding.
        assert!(
            optimal > 0.0 && optimal <= greedy * (1.0 + 1e-5),
            "{greedy} {optimal}"
        );
        // The optimal collapse's children make a tree of the program's own cost (f32, in units
        // of half the root's area).
        let collapse = OptimalCollapse::new(&bvh, &params);
        let program = f64::from(collapse.root_cost()) / f64::from(half_area(&bvh.nodes[0]));
        assert!(
            (program - optimal).abs() <= 1e-5 * optimal,
            "built {optimal}, program {program}"
        );
        assert!(optimal < greedy * 0.999, "{greedy} {optimal}");
        // A wide tree visits fewer nodes than the binary one: its cost is below the binary SAH.
        let binary = f64::from(crate::bvh::sah_cost(&bvh, &SahParams::default()));
        assert!(greedy < binary, "greedy {greedy} vs binary {binary}");
    }
}
