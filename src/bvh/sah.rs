//! The surface area heuristic (SAH) cost of a whole tree, the quality measure every builder is
//! judged by (Goldsmith & Salmon 1987, MacDonald & Booth 1990; in the form used by Karras & Aila
//! 2013, see DESIGN.md §1 "Cost model"):
//!
//! ```text
//! SAH = (Ci · Σ_internal A(n) + Ct · Σ_leaf A(l) · N(l)) / A(root)
//! ```
//!
//! with A the surface area of a node's box and N the number of primitive references of a leaf.

use super::Bvh;

/// Constants of the SAH cost model.
///
/// `ci` is the cost of visiting an internal node (a ray/box test pair), `ct` the cost of one
/// ray/triangle test, and `max_leaf_size` the largest number of primitives a builder may put into
/// one leaf. The defaults are the paper's constants (Karras & Aila 2013): Ci = 1.2, Ct = 1.0, and a
/// maximum leaf size of 8.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahParams {
    pub ci: f32,
    pub ct: f32,
    pub max_leaf_size: u32,
}

impl Default for SahParams {
    fn default() -> Self {
        Self {
            ci: 1.2,
            ct: 1.0,
            max_leaf_size: 8,
        }
    }
}

/// SAH cost of `bvh` under `params` (only `ci` and `ct` are used).
///
/// Walks the nodes reachable from the root (node 0) with an explicit stack, so arbitrarily deep
/// trees are fine; the tree must be well formed (see [`super::validate`]): child indices in range
/// and no cycles. An empty tree costs 0.
///
/// When the root box has zero surface area (e.g. a single degenerate triangle), the conditional
/// hit probabilities A(n)/A(root) are 0/0; they are then taken to be 1 (a ray that reaches the
/// root reaches every node), which gives Ct·N for a single leaf and never NaN.
pub fn sah_cost(bvh: &Bvh, params: &SahParams) -> f32 {
    let Some(root) = bvh.nodes.first() else {
        return 0.0;
    };
    let root_area = root.bounds().surface_area();
    let degenerate = !(root_area > 0.0 && root_area.is_finite());
    // Accumulate in f64: large trees sum millions of terms.
    let mut internal_sum = 0.0f64;
    let mut leaf_sum = 0.0f64;
    let mut stack = vec![0u32];
    while let Some(index) = stack.pop() {
        let node = &bvh.nodes[index as usize];
        let area = if degenerate {
            1.0
        } else {
            f64::from(node.bounds().surface_area())
        };
        if node.is_leaf() {
            leaf_sum += area * f64::from(node.prim_count());
        } else {
            internal_sum += area;
            let (left, right) = node.children();
            stack.push(right);
            stack.push(left);
        }
    }
    let numerator = f64::from(params.ci) * internal_sum + f64::from(params.ct) * leaf_sum;
    let denominator = if degenerate {
        1.0
    } else {
        f64::from(root_area)
    };
    (numerator / denominator) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhNode;
    use crate::geometry::Aabb;
    use glam::Vec3;

    fn unit_box(min: Vec3, size: Vec3) -> Aabb {
        Aabb::new(min, min + size)
    }

    #[test]
    fn defaults_are_the_papers_constants() {
        let p = SahParams::default();
        assert_eq!((p.ci, p.ct, p.max_leaf_size), (1.2, 1.0, 8));
    }

    #[test]
    fn three_node_tree_has_the_hand_computed_cost() {
        // Root: 2×1×1 box (area 10); left leaf: unit cube (area 6) with 2 primitives; right leaf:
        // 1×1×0.5 box (area 2·(1 + 0.5 + 0.5) = 4) with 3 primitives.
        let root = unit_box(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        let left = unit_box(Vec3::ZERO, Vec3::ONE);
        let right = unit_box(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.5));
        let bvh = Bvh {
            nodes: vec![
                BvhNode::internal(root, 1, 2),
                BvhNode::leaf(left, 0, 2),
                BvhNode::leaf(right, 2, 3),
            ],
            prim_indices: vec![0, 1, 2, 3, 4],
        };
        let params = SahParams::default();
        // (1.2·10 + 1.0·(6·2 + 4·3)) / 10 = (12 + 24) / 10 = 3.6
        let cost = sah_cost(&bvh, &params);
        assert!((cost - 3.6).abs() < 1e-6, "cost {cost}");
        // Constants are honoured.
        let cost = sah_cost(
            &bvh,
            &SahParams {
                ci: 2.0,
                ct: 0.5,
                max_leaf_size: 4,
            },
        );
        assert!((cost - 3.2).abs() < 1e-6, "cost {cost}");
    }

    #[test]
    fn single_leaf_costs_ct_times_count() {
        let params = SahParams::default();
        let leaf = Bvh {
            nodes: vec![BvhNode::leaf(unit_box(Vec3::ZERO, Vec3::ONE), 0, 3)],
            prim_indices: vec![0, 1, 2],
        };
        assert!((sah_cost(&leaf, &params) - 3.0).abs() < 1e-6);
    }

    #[test]
    fn zero_area_root_does_not_give_nan() {
        let params = SahParams::default();
        // A degenerate (point) box: area 0.
        let point = Aabb::new(Vec3::ONE, Vec3::ONE);
        let leaf = Bvh {
            nodes: vec![BvhNode::leaf(point, 0, 1)],
            prim_indices: vec![0],
        };
        assert_eq!(sah_cost(&leaf, &params), 1.0);
        let tree = Bvh {
            nodes: vec![
                BvhNode::internal(point, 1, 2),
                BvhNode::leaf(point, 0, 1),
                BvhNode::leaf(point, 1, 1),
            ],
            prim_indices: vec![0, 1],
        };
        let cost = sah_cost(&tree, &params);
        assert!((cost - 3.2).abs() < 1e-6, "cost {cost}");
        assert_eq!(sah_cost(&Bvh::default(), &params), 0.0);
    }

    #[test]
    fn deep_chain_does_not_overflow_the_stack() {
        // A right-leaning chain of 200_000 internal nodes, all with the same box.
        let b = unit_box(Vec3::ZERO, Vec3::ONE);
        let depth = 200_000u32;
        let mut nodes = Vec::new();
        for i in 0..depth {
            nodes.push(BvhNode::internal(b, 2 * i + 1, 2 * i + 2));
            nodes.push(BvhNode::leaf(b, i, 1));
        }
        nodes.push(BvhNode::leaf(b, depth, 1));
        let bvh = Bvh {
            nodes,
            prim_indices: (0..=depth).collect(),
        };
        let cost = sah_cost(&bvh, &SahParams::default());
        let expected = 1.2 * depth as f32 + (depth + 1) as f32;
        assert!((cost - expected).abs() / expected < 1e-6, "cost {cost}");
    }
}
