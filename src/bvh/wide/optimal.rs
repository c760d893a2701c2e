//! The SAH-optimal binary-to-wide collapse of Ylitie, Karras & Laine 2017 (§3.1), on the CPU: a
//! reference to measure the GPU conversion's greedy collapse against (`wide_sah_costs` reports
//! both costs; `treelet bench --wide-collapse optimal` traces the wide tree this collapse makes,
//! uploaded, where the build's `wide` stage still times the greedy GPU conversion).
//!
//! The dynamic program, per binary node n and slot count i in 1..=8: C(n, i) is the least cost of
//! n's subtree spread over at most i slots of the wide node above it; C(n, i) = Ct·A·N for a
//! leaf (binary leaves stay leaves: they are not merged or split), and for an internal node
//! C(n, 1) = Ci·A(n) + C_dist(n, 8) (n becomes a wide node of its own), C(n, i) =
//! min(C(n, i − 1), C_dist(n, i)), C_dist(n, i) = min over 0 < k < i of C(l, k) + C(r, i − k).
//! Areas are relative to the root's, so the costs are wide SAH costs. Each choice is recorded
//! (ties: fewer slots, then the smallest k), and a wide node made from n takes the children that
//! C_dist(n, 8)'s choices expand to.

use super::node::WIDTH;
use crate::bvh::{Bvh, BvhNode, SahParams};

/// What C(n, i) chose: fewer slots (i − 1), or a split with k slots for the left child.
const FEWER: u8 = 0;

/// The optimal collapse of one binary tree: each node's costs and choices.
pub struct OptimalCollapse {
    /// C(n, i) at [n][i − 1].
    costs: Vec<[f64; WIDTH]>,
    /// [n][i − 1] for i in 2..=8: C(n, i)'s choice (FEWER or k); [n][WIDTH]: C_dist(n, 8)'s k.
    choices: Vec<[u8; WIDTH + 1]>,
    /// Ci · A(root) / A(root) for a root that is a leaf (it gets a wide node of its own).
    root_node_cost: f64,
}

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

/// Surface area relative to the root's; every area is 1 for a root of zero or non-finite area,
/// as `sah_cost` does.
pub(crate) fn relative_area(bvh: &Bvh) -> impl Fn(&BvhNode) -> f64 + '_ {
    let root_area = bvh.nodes[0].bounds().surface_area();
    let degenerate = !(root_area > 0.0 && root_area.is_finite());
    move |n: &BvhNode| {
        if degenerate {
            1.0
        } else {
            f64::from(n.bounds().surface_area()) / f64::from(root_area)
        }
    }
}

impl OptimalCollapse {
    /// The program over `bvh` (not empty) under `params`' Ci and Ct.
    pub fn new(bvh: &Bvh, params: &SahParams) -> Self {
        let area = relative_area(bvh);
        let (ci, ct) = (f64::from(params.ci), f64::from(params.ct));
        let mut costs = vec![[0.0f64; WIDTH]; bvh.nodes.len()];
        let mut choices = vec![[FEWER; WIDTH + 1]; bvh.nodes.len()];
        for &i in top_down(bvh).iter().rev() {
            let n = &bvh.nodes[i];
            if n.is_leaf() {
                costs[i] = [ct * area(n) * f64::from(n.prim_count()); WIDTH];
                continue;
            }
            let (l, r) = n.children();
            let (cl, cr) = (costs[l as usize], costs[r as usize]);
            let dist = |slots: usize| {
                let mut best = (f64::MAX, 0u8);
                for k in 1..slots {
                    let c = cl[k - 1] + cr[slots - k - 1];
                    if c < best.0 {
                        best = (c, k as u8);
                    }
                }
                best
            };
            let (wide, k) = dist(WIDTH);
            let c = &mut costs[i];
            c[0] = ci * area(n) + wide;
            choices[i][WIDTH] = k;
            for slots in 2..=WIDTH {
                let (split, k) = dist(slots);
                if c[slots - 2] <= split {
                    c[slots - 1] = c[slots - 2];
                } else {
                    c[slots - 1] = split;
                    choices[i][slots - 1] = k;
                }
            }
        }
        Self {
            costs,
            choices,
            root_node_cost: ci * area(&bvh.nodes[0]),
        }
    }

    /// The wide SAH cost of the optimal collapse.
    pub fn cost(&self, bvh: &Bvh) -> f64 {
        if bvh.nodes[0].is_leaf() {
            // One wide node holding the leaf.
            self.root_node_cost + self.costs[0][0]
        } else {
            self.costs[0][0]
        }
    }

    /// The children (binary nodes) of the wide node made from binary node `source`: the leaf
    /// itself for a leaf root, else what C_dist(source, 8)'s choices expand to.
    pub fn children(&self, bvh: &Bvh, source: u32) -> Vec<u32> {
        let top = &bvh.nodes[source as usize];
        if top.is_leaf() {
            return vec![source];
        }
        let (l, r) = top.children();
        let k = usize::from(self.choices[source as usize][WIDTH]);
        let mut children = Vec::with_capacity(WIDTH);
        self.expand(bvh, l, k, &mut children);
        self.expand(bvh, r, WIDTH - k, &mut children);
        children
    }

    /// The slots node n takes when given at most `slots`.
    fn expand(&self, bvh: &Bvh, n: u32, slots: usize, out: &mut Vec<u32>) {
        let node = &bvh.nodes[n as usize];
        if node.is_leaf() || slots == 1 {
            out.push(n);
            return;
        }
        match self.choices[n as usize][slots - 1] {
            FEWER => self.expand(bvh, n, slots - 1, out),
            k => {
                let (l, r) = node.children();
                self.expand(bvh, l, usize::from(k), out);
                self.expand(bvh, r, slots - usize::from(k), out);
            }
        }
    }
}
