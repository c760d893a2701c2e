//! Structural validation of a built tree (any builder's output, in the node layout of `node.rs`).
//!
//! Not a method from the literature: the checker every builder's output goes through in tests.
//! It walks the tree from the root with an explicit stack (trees can be deep) and checks that
//! - the node array is non-empty, every child index is in range, no node is reached twice (which
//!   catches cycles and shared subtrees) and every node is reachable from the root;
//! - leaves are non-empty, their ranges lie inside `prim_indices`, every `prim_indices` entry is
//!   used by exactly one leaf, every triangle id is in range and every triangle is referenced
//!   exactly once;
//! - boxes hold no NaN, every internal node's box contains both children's boxes and every leaf's
//!   box contains its triangles' boxes, with zero tolerance (builders compute exact unions of f32
//!   values, and min/max never round).
//!
//! [`validate_with_references`] is the relaxed mode for trees whose builder splits triangles into
//! several references (SBVH spatial splits, pre-splitting): a triangle may be referenced by several
//! leaves (at least once, never twice by the same leaf), and a leaf's box need only overlap its
//! triangles' boxes (it bounds the clipped parts); every other check is the same.

use super::Bvh;
use crate::geometry::Aabb;
use crate::scene::Triangle;

/// Summary of a valid tree, as returned by [`validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidationStats {
    /// Number of nodes (all reachable).
    pub nodes: usize,
    /// Number of leaves.
    pub leaves: usize,
    /// Largest number of edges from the root to a node (0 for a single-leaf tree).
    pub max_depth: usize,
    /// Largest number of primitives in one leaf.
    pub max_leaf_size: usize,
}

/// The first defect [`validate`] found; node, entry (`prim_indices` position) and triangle indices
/// name the offender.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValidationError {
    #[error("the tree has no nodes")]
    Empty,
    #[error("node {node} has child index {child}, but there are only {node_count} nodes")]
    ChildOutOfRange {
        node: usize,
        child: usize,
        node_count: usize,
    },
    #[error("node {child} is reached a second time (from node {node}): cycle or shared subtree")]
    NodeReachedTwice { node: usize, child: usize },
    #[error("node {node} is not reachable from the root")]
    UnreachableNode { node: usize },
    #[error("leaf {node} is empty")]
    EmptyLeaf { node: usize },
    #[error(
        "leaf {node} references prim_indices[{first}..{first}+{count}], \
         but prim_indices has only {len} entries"
    )]
    LeafRangeOutOfBounds {
        node: usize,
        first: usize,
        count: usize,
        len: usize,
    },
    #[error("prim_indices[{entry}] is used by leaf {node} and by another leaf")]
    EntrySharedByLeaves { node: usize, entry: usize },
    #[error("prim_indices[{entry}] is not used by any leaf")]
    UnusedEntry { entry: usize },
    #[error(
        "leaf {node} references triangle {triangle} (prim_indices[{entry}]), \
         but there are only {triangle_count} triangles"
    )]
    TriangleOutOfRange {
        node: usize,
        entry: usize,
        triangle: usize,
        triangle_count: usize,
    },
    #[error("triangle {triangle} is referenced a second time, by leaf {node}")]
    TriangleReferencedTwice { node: usize, triangle: usize },
    #[error("triangle {triangle} is not referenced by any leaf")]
    TriangleMissing { triangle: usize },
    #[error("node {node} has a NaN in its box")]
    NanBounds { node: usize },
    #[error("the box of node {node} does not contain the box of its child {child}")]
    ChildNotContained { node: usize, child: usize },
    #[error("the box of leaf {node} does not contain triangle {triangle}")]
    TriangleNotContained { node: usize, triangle: usize },
    #[error("leaf {node} references triangle {triangle} more than once")]
    TriangleTwiceInLeaf { node: usize, triangle: usize },
    #[error("the box of leaf {node} does not overlap triangle {triangle}")]
    TriangleNotOverlapped { node: usize, triangle: usize },
    #[error("wide node {node} has no children")]
    EmptyWideNode { node: usize },
    #[error("wide node {node} has an exponent outside 1..=254 or a NaN origin")]
    BadQuantizationFrame { node: usize },
    #[error(
        "slot {slot} of wide node {node} does not contain what lies beneath it \
         (its quantized box is not conservative)"
    )]
    SlotNotContaining { node: usize, slot: usize },
}

/// How often a triangle may be referenced, and how a leaf box must relate to its triangles.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum References {
    /// Exactly once in the whole tree; leaf boxes contain their triangles.
    Single,
    /// At least once, at most once per leaf; leaf boxes overlap their triangles.
    Multiple,
}

/// The reference checks both layouts' validators share (this module and `wide::validate`): each
/// leaf's range lies inside `prim_indices`, every entry is used by one leaf, triangle ids are in
/// range, each triangle is referenced once (or at most once per leaf) and lies in (or overlaps)
/// its leaf's box; at the end, no entry is unused and no triangle unreferenced.
pub(crate) struct ReferenceLedger<'a> {
    prim_indices: &'a [u32],
    triangles: &'a [Triangle],
    mode: References,
    entry_used: Vec<bool>,
    /// The last leaf that referenced each triangle.
    triangle_leaf: Vec<usize>,
}

impl<'a> ReferenceLedger<'a> {
    pub fn new(prim_indices: &'a [u32], triangles: &'a [Triangle], mode: References) -> Self {
        Self {
            prim_indices,
            triangles,
            mode,
            entry_used: vec![false; prim_indices.len()],
            triangle_leaf: vec![usize::MAX; triangles.len()],
        }
    }

    /// Checks the leaf `leaf` (an id no other leaf has) of node `node`: `count` entries from
    /// `first`, in a leaf box `bounds`; `misfit(triangle)` is the error for a triangle the box does
    /// not contain (single mode) or overlap (multiple mode).
    pub fn leaf(
        &mut self,
        node: usize,
        leaf: usize,
        (first, count): (usize, usize),
        bounds: &Aabb,
        misfit: impl Fn(usize) -> ValidationError,
    ) -> Result<(), ValidationError> {
        let len = self.prim_indices.len();
        if first > len || count > len - first {
            return Err(ValidationError::LeafRangeOutOfBounds {
                node,
                first,
                count,
                len,
            });
        }
        for entry in first..first + count {
            if std::mem::replace(&mut self.entry_used[entry], true) {
                return Err(ValidationError::EntrySharedByLeaves { node, entry });
            }
            let triangle = self.prim_indices[entry] as usize;
            if triangle >= self.triangles.len() {
                return Err(ValidationError::TriangleOutOfRange {
                    node,
                    entry,
                    triangle,
                    triangle_count: self.triangles.len(),
                });
            }
            let previous = std::mem::replace(&mut self.triangle_leaf[triangle], leaf);
            let tri_bounds = self.triangles[triangle].bounds();
            let fits = match self.mode {
                References::Single if previous != usize::MAX => {
                    return Err(ValidationError::TriangleReferencedTwice { node, triangle })
                }
                References::Multiple if previous == leaf => {
                    return Err(ValidationError::TriangleTwiceInLeaf { node, triangle })
                }
                References::Single => bounds.contains(&tri_bounds, 0.0),
                References::Multiple => overlaps(bounds, &tri_bounds),
            };
            if !fits {
                return Err(misfit(triangle));
            }
        }
        Ok(())
    }

    /// After every leaf: no entry unused, no triangle unreferenced.
    pub fn finish(&self) -> Result<(), ValidationError> {
        if let Some(entry) = self.entry_used.iter().position(|&used| !used) {
            return Err(ValidationError::UnusedEntry { entry });
        }
        if let Some(triangle) = self.triangle_leaf.iter().position(|&l| l == usize::MAX) {
            return Err(ValidationError::TriangleMissing { triangle });
        }
        Ok(())
    }
}

/// Whether two boxes share a point.
pub(crate) fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

fn has_nan(b: &Aabb) -> bool {
    b.min.is_nan() || b.max.is_nan()
}

/// Checks `bvh` against the `triangles` it was built over; see the module documentation for the
/// list of checks. Returns statistics of the tree, or the first defect found.
pub fn validate(bvh: &Bvh, triangles: &[Triangle]) -> Result<ValidationStats, ValidationError> {
    validate_mode(bvh, triangles, References::Single)
}

/// [`validate`] relaxed for trees with split triangles: every triangle is referenced at least once
/// (not exactly once) and no leaf references a triangle twice; each leaf's box overlaps (need not
/// contain) its triangles' boxes, while internal boxes still contain their children exactly.
pub fn validate_with_references(
    bvh: &Bvh,
    triangles: &[Triangle],
) -> Result<ValidationStats, ValidationError> {
    validate_mode(bvh, triangles, References::Multiple)
}

fn validate_mode(
    bvh: &Bvh,
    triangles: &[Triangle],
    mode: References,
) -> Result<ValidationStats, ValidationError> {
    let nodes = &bvh.nodes;
    if nodes.is_empty() {
        return Err(ValidationError::Empty);
    }
    let mut node_seen = vec![false; nodes.len()];
    let mut references = ReferenceLedger::new(&bvh.prim_indices, triangles, mode);
    let mut stats = ValidationStats {
        nodes: nodes.len(),
        leaves: 0,
        max_depth: 0,
        max_leaf_size: 0,
    };

    if has_nan(&nodes[0].bounds()) {
        return Err(ValidationError::NanBounds { node: 0 });
    }
    node_seen[0] = true;
    // (node, depth); every node on the stack has been marked seen and NaN-checked.
    let mut stack = vec![(0usize, 0usize)];
    while let Some((index, depth)) = stack.pop() {
        stats.max_depth = stats.max_depth.max(depth);
        let node = &nodes[index];
        let bounds = node.bounds();
        if node.is_leaf() {
            let first = node.left_or_first as usize;
            let count = node.prim_count() as usize;
            if count == 0 {
                return Err(ValidationError::EmptyLeaf { node: index });
            }
            let misfit = |triangle| match mode {
                References::Single => ValidationError::TriangleNotContained {
                    node: index,
                    triangle,
                },
                References::Multiple => ValidationError::TriangleNotOverlapped {
                    node: index,
                    triangle,
                },
            };
            references.leaf(index, index, (first, count), &bounds, misfit)?;
            stats.leaves += 1;
            stats.max_leaf_size = stats.max_leaf_size.max(count);
        } else {
            let (left, right) = node.children();
            for child in [left as usize, right as usize] {
                if child >= nodes.len() {
                    return Err(ValidationError::ChildOutOfRange {
                        node: index,
                        child,
                        node_count: nodes.len(),
                    });
                }
                if std::mem::replace(&mut node_seen[child], true) {
                    return Err(ValidationError::NodeReachedTwice { node: index, child });
                }
                let child_bounds = nodes[child].bounds();
                if has_nan(&child_bounds) {
                    return Err(ValidationError::NanBounds { node: child });
                }
                if !bounds.contains(&child_bounds, 0.0) {
                    return Err(ValidationError::ChildNotContained { node: index, child });
                }
                stack.push((child, depth + 1));
            }
        }
    }

    if let Some(node) = node_seen.iter().position(|&seen| !seen) {
        return Err(ValidationError::UnreachableNode { node });
    }
    references.finish()?;
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhNode;
    use glam::Vec3;

    /// Four small triangles along x, one per unit cell.
    fn triangles() -> Vec<Triangle> {
        (0..4)
            .map(|i| {
                let o = Vec3::new(i as f32, 0.0, 0.0);
                Triangle::new(
                    o,
                    o + Vec3::new(1.0, 0.0, 0.0),
                    o + Vec3::new(0.0, 1.0, 1.0),
                    0,
                )
            })
            .collect()
    }

    fn union(tris: &[Triangle], ids: &[u32]) -> Aabb {
        ids.iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(tris[i as usize].bounds()))
    }

    /// root 0 -> (1, 4); node 1 -> leaves (2: tris 0,1) and (3: tri 2); node 4 = leaf (tri 3).
    fn valid_tree(tris: &[Triangle]) -> Bvh {
        let prim_indices = vec![1, 0, 2, 3];
        let nodes = vec![
            BvhNode::internal(union(tris, &[0, 1, 2, 3]), 1, 4),
            BvhNode::internal(union(tris, &[0, 1, 2]), 2, 3),
            BvhNode::leaf(union(tris, &[0, 1]), 0, 2),
            BvhNode::leaf(union(tris, &[2]), 2, 1),
            BvhNode::leaf(union(tris, &[3]), 3, 1),
        ];
        Bvh {
            nodes,
            prim_indices,
        }
    }

    #[test]
    fn valid_tree_passes_with_stats() {
        let tris = triangles();
        let stats = validate(&valid_tree(&tris), &tris).unwrap();
        assert_eq!(
            stats,
            ValidationStats {
                nodes: 5,
                leaves: 3,
                max_depth: 2,
                max_leaf_size: 2,
            }
        );
        let single = Bvh {
            nodes: vec![BvhNode::leaf(union(&tris, &[0, 1, 2, 3]), 0, 4)],
            prim_indices: vec![3, 2, 1, 0],
        };
        let stats = validate(&single, &tris).unwrap();
        assert_eq!((stats.nodes, stats.leaves, stats.max_depth), (1, 1, 0));
    }

    #[test]
    fn empty_tree_is_rejected() {
        let tris = triangles();
        assert_eq!(
            validate(&Bvh::default(), &tris),
            Err(ValidationError::Empty)
        );
    }

    #[test]
    fn child_out_of_range_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        bvh.nodes[1].right_or_count = 17;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::ChildOutOfRange {
                node: 1,
                child: 17,
                node_count: 5,
            })
        );
    }

    #[test]
    fn cycle_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        // Node 1's right child points back at the root (its ancestor); node 3 becomes unreachable,
        // but the cycle is found first.
        bvh.nodes[1].right_or_count = 0;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::NodeReachedTwice { node: 1, child: 0 })
        );
        // A subtree shared by two parents.
        let mut bvh = valid_tree(&tris);
        bvh.nodes[0].right_or_count = 1;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::NodeReachedTwice { node: 0, child: 1 })
        );
    }

    #[test]
    fn unreachable_node_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        // An extra leaf that no node points to, over an extra entry for a triangle it would
        // otherwise duplicate: the unreachable node is what gets reported.
        bvh.nodes.push(BvhNode::leaf(union(&tris, &[3]), 4, 1));
        bvh.prim_indices.push(3);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::UnreachableNode { node: 5 })
        );
    }

    #[test]
    fn primitive_referenced_twice_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        // Leaf 4 now references triangle 0 (also in leaf 2), with a box that holds it.
        bvh.prim_indices[3] = 0;
        bvh.nodes[4] = BvhNode::leaf(union(&tris, &[0, 3]), 3, 1);
        let err = validate(&bvh, &tris).unwrap_err();
        assert_eq!(
            err,
            ValidationError::TriangleReferencedTwice {
                node: 2,
                triangle: 0,
            }
        );
        // Overlapping leaf ranges share a prim_indices entry.
        let mut bvh = valid_tree(&tris);
        bvh.nodes[3] = BvhNode::leaf(union(&tris, &[0, 1, 2]), 1, 1);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::EntrySharedByLeaves { node: 2, entry: 1 })
        );
    }

    #[test]
    fn primitive_missing_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        // Leaf 2 shrinks to one primitive: triangle 0 (entry 1) is no longer referenced.
        bvh.nodes[2] = BvhNode::leaf(union(&tris, &[0, 1]), 0, 1);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::UnusedEntry { entry: 1 })
        );
        // A triangle that no leaf references (the tree was built over fewer triangles).
        let mut more = tris.clone();
        more.push(tris[0]);
        let err = validate(&valid_tree(&tris), &more).unwrap_err();
        assert_eq!(err, ValidationError::TriangleMissing { triangle: 4 });
    }

    #[test]
    fn shrunken_box_is_caught() {
        let tris = triangles();
        // An internal node whose box misses part of a child.
        let mut bvh = valid_tree(&tris);
        bvh.nodes[0].max[0] -= 0.5;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::ChildNotContained { node: 0, child: 4 })
        );
        // A leaf whose box misses part of a triangle, by one ulp.
        let mut bvh = valid_tree(&tris);
        bvh.nodes[4].min[1] = f32::from_bits(0.0f32.to_bits() + 1);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::TriangleNotContained {
                node: 4,
                triangle: 3,
            })
        );
    }

    #[test]
    fn nan_box_is_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        bvh.nodes[2].max[2] = f32::NAN;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::NanBounds { node: 2 })
        );
        let mut bvh = valid_tree(&tris);
        bvh.nodes[0].min[0] = f32::NAN;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::NanBounds { node: 0 })
        );
    }

    #[test]
    fn other_leaf_defects_are_caught() {
        let tris = triangles();
        let mut bvh = valid_tree(&tris);
        bvh.nodes[4] = BvhNode::leaf(union(&tris, &[3]), 3, 0);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::EmptyLeaf { node: 4 })
        );
        let mut bvh = valid_tree(&tris);
        bvh.nodes[4] = BvhNode::leaf(union(&tris, &[3]), 3, 2);
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::LeafRangeOutOfBounds {
                node: 4,
                first: 3,
                count: 2,
                len: 4,
            })
        );
        let mut bvh = valid_tree(&tris);
        bvh.prim_indices[3] = 9;
        assert_eq!(
            validate(&bvh, &tris),
            Err(ValidationError::TriangleOutOfRange {
                node: 4,
                entry: 3,
                triangle: 9,
                triangle_count: 4,
            })
        );
    }

    /// Triangle 1 (x in [1, 2]) split at x = 1.5: leaf 1 holds triangles 0 and 1 clipped to
    /// x ≤ 1.5, leaf 2 triangles 1, 2, 3 clipped to x ≥ 1.5.
    fn split_tree(tris: &[Triangle]) -> Bvh {
        let all = union(tris, &[0, 1, 2, 3]);
        let mut left = union(tris, &[0, 1]);
        left.max.x = 1.5;
        let mut right = union(tris, &[1, 2, 3]);
        right.min.x = 1.5;
        Bvh {
            nodes: vec![
                BvhNode::internal(all, 1, 2),
                BvhNode::leaf(left, 0, 2),
                BvhNode::leaf(right, 2, 3),
            ],
            prim_indices: vec![0, 1, 1, 2, 3],
        }
    }

    #[test]
    fn relaxed_mode_accepts_split_triangles() {
        let tris = triangles();
        // Single-reference trees pass both modes with the same statistics.
        let single = valid_tree(&tris);
        assert_eq!(
            validate_with_references(&single, &tris),
            validate(&single, &tris)
        );
        let split = split_tree(&tris);
        let stats = validate_with_references(&split, &tris).unwrap();
        assert_eq!(
            stats,
            ValidationStats {
                nodes: 3,
                leaves: 2,
                max_depth: 1,
                max_leaf_size: 3,
            }
        );
        // The strict mode rejects the clipped leaf box and the second reference.
        assert_eq!(
            validate(&split, &tris),
            Err(ValidationError::TriangleNotContained {
                node: 2,
                triangle: 1,
            })
        );
    }

    #[test]
    fn relaxed_mode_catches_duplicates_within_a_leaf() {
        let tris = triangles();
        let mut bvh = split_tree(&tris);
        // Leaf 2 references triangle 1 twice (instead of triangle 2, which leaf 1 now holds).
        bvh.prim_indices = vec![0, 2, 1, 1, 3];
        bvh.nodes[1] = BvhNode::leaf(union(&tris, &[0, 1, 2]), 0, 2);
        bvh.nodes[0] = BvhNode::internal(union(&tris, &[0, 1, 2, 3]), 1, 2);
        assert_eq!(
            validate_with_references(&bvh, &tris),
            Err(ValidationError::TriangleTwiceInLeaf {
                node: 2,
                triangle: 1,
            })
        );
    }

    #[test]
    fn relaxed_mode_catches_missing_triangles_and_bad_boxes() {
        let tris = triangles();
        // Triangle 3 is dropped from leaf 2.
        let mut bvh = split_tree(&tris);
        bvh.nodes[2] = BvhNode::leaf(bvh.nodes[2].bounds(), 2, 2);
        bvh.prim_indices.pop();
        assert_eq!(
            validate_with_references(&bvh, &tris),
            Err(ValidationError::TriangleMissing { triangle: 3 })
        );
        // A triangle outside the tree's triangles is still caught.
        let mut more = tris.clone();
        more.push(tris[0]);
        assert_eq!(
            validate_with_references(&split_tree(&tris), &more),
            Err(ValidationError::TriangleMissing { triangle: 4 })
        );
        // A leaf box that misses one of its triangles entirely.
        let mut bvh = split_tree(&tris);
        bvh.nodes[1].max[0] = 0.5;
        bvh.nodes[1].min[0] = 0.0;
        assert_eq!(
            validate_with_references(&bvh, &tris),
            Err(ValidationError::TriangleNotOverlapped {
                node: 1,
                triangle: 1,
            })
        );
        // Internal boxes must still contain their children exactly.
        let mut bvh = split_tree(&tris);
        bvh.nodes[0].max[0] = 3.5;
        assert_eq!(
            validate_with_references(&bvh, &tris),
            Err(ValidationError::ChildNotContained { node: 0, child: 2 })
        );
        // Shared entries stay an error (leaf 2 is checked first, then leaf 1 reuses entry 1).
        let mut bvh = split_tree(&tris);
        bvh.nodes[2] = BvhNode::leaf(bvh.nodes[2].bounds(), 1, 1);
        assert_eq!(
            validate_with_references(&bvh, &tris),
            Err(ValidationError::EntrySharedByLeaves { node: 1, entry: 1 })
        );
    }

    #[test]
    fn errors_have_readable_messages() {
        let msg = ValidationError::NodeReachedTwice { node: 1, child: 0 }.to_string();
        assert!(msg.contains("node 0") && msg.contains("cycle"), "{msg}");
        let boxed: Box<dyn std::error::Error> = Box::new(ValidationError::Empty);
        assert_eq!(boxed.to_string(), "the tree has no nodes");
    }
}
