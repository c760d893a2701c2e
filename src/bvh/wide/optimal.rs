//! The SAH-optimal binary-to-wide collapse of Ylitie, Karras & Laine 2017 (§3.1): the CPU twin
//! of the GPU's (kernels `nodes_link` and `costs_climb`, then `wide_collapse.wgsl` follows the
//! choices), operation for operation in f32, so both choose the same children.
//!
//! The dynamic program, per binary node n and slot count i in 1..=7: C(n, i) is the least cost of
//! n's subtree spread over at most i slots of the wide node above it; C(n, i) = Ct·A·N for a
//! leaf (binary leaves stay leaves: they are not merged or split), and for an internal node
//! C(n, 1) = Ci·A(n) + C_dist(n, 8) (n becomes a wide node of its own), C(n, i) =
//! min(C(n, i − 1), C_dist(n, i)), C_dist(n, i) = min over 0 < k < i of C(l, k) + C(r, i − k).
//! A is half the surface area (`half_area`), so the costs are the wide SAH times A(root); a
//! parent never gives a child 8 slots, so C(n, 8) is not needed. Each choice is recorded (ties:
//! fewer slots, then the smallest k), and a wide node made from n takes the children that
//! C_dist(n, 8)'s choices expand to.

use super::convert::half_area;
use super::node::WIDTH;
use super::sah::collapse_cost;
use crate::bvh::{Bvh, BvhNode, SahParams};
use crate::gpu::constants::COLLAPSE_COST_WORDS;

/// What C(n, i) chose: fewer slots (i − 1), or a split with k slots for the left child.
const FEWER: u8 = 0;
/// Slot counts a child can be given (C(n, 1..=7)), as many as the GPU stores costs per node.
const CHILD_SLOTS: usize = WIDTH - 1;
const _: () = assert!(CHILD_SLOTS == COLLAPSE_COST_WORDS as usize);

/// The optimal collapse of one binary tree: each node's costs and choices.
pub struct OptimalCollapse {
    /// C(n, i) at [n][i − 1].
    costs: Vec<[f32; CHILD_SLOTS]>,
    /// [n][i − 1] for i in 2..=7: C(n, i)'s choice (FEWER or k); [n][CHILD_SLOTS]: C_dist(n, 8)'s
    /// k.
    choices: Vec<[u8; CHILD_SLOTS + 1]>,
    params: SahParams,
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

/// C_dist over `slots` (2..=8): the least C(l, k) + C(r, slots − k) and its k (the smallest of a
/// tie; k = 1 whatever the costs, infinite ones included), as in costs_climb.wgsl.
fn best_split(left: &[f32; CHILD_SLOTS], right: &[f32; CHILD_SLOTS], slots: usize) -> (f32, u8) {
    let mut best = (left[0] + right[slots - 2], 1u8);
    for k in 2..slots {
        let c = left[k - 1] + right[slots - k - 1];
        if c < best.0 {
            best = (c, k as u8);
        }
    }
    best
}

impl OptimalCollapse {
    /// The program over `bvh` (not empty) under `params`' Ci and Ct.
    pub fn new(bvh: &Bvh, params: &SahParams) -> Self {
        let (ci, ct) = (params.ci, params.ct);
        let mut costs = vec![[0.0f32; CHILD_SLOTS]; bvh.nodes.len()];
        let mut choices = vec![[FEWER; CHILD_SLOTS + 1]; bvh.nodes.len()];
        for &i in top_down(bvh).iter().rev() {
            let n = &bvh.nodes[i];
            if n.is_leaf() {
                costs[i] = [ct * half_area(n) * n.prim_count() as f32; CHILD_SLOTS];
                continue;
            }
            let (l, r) = n.children();
            let (cl, cr) = (costs[l as usize], costs[r as usize]);
            let (wide, k) = best_split(&cl, &cr, WIDTH);
            let c = &mut costs[i];
            c[0] = ci * half_area(n) + wide;
            choices[i][CHILD_SLOTS] = k;
            for slots in 2..=CHILD_SLOTS {
                let (split, k) = best_split(&cl, &cr, slots);
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
            params: *params,
        }
    }

    /// The wide SAH cost of the tree this collapse makes (relative areas, in f64, like
    /// `wide_sah_costs`' greedy cost).
    pub fn cost(&self, bvh: &Bvh) -> f64 {
        collapse_cost(bvh, &self.params, |source| self.children(bvh, source))
    }

    /// The program's own cost of the wide tree, C(root, 1) (f32, in units of half the root's
    /// area; a leaf root costs its leaf alone).
    pub fn root_cost(&self) -> f32 {
        self.costs[0][0]
    }

    /// The children (binary nodes) of the wide node made from binary node `source`: the leaf
    /// itself for a leaf root, else what C_dist(source, 8)'s choices expand to.
    pub fn children(&self, bvh: &Bvh, source: u32) -> Vec<u32> {
        let top = &bvh.nodes[source as usize];
        if top.is_leaf() {
            return vec![source];
        }
        let (l, r) = top.children();
        let k = usize::from(self.choices[source as usize][CHILD_SLOTS]);
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
