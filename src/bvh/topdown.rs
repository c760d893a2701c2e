//! The greedy top-down SAH build shared by the CPU reference builders (MacDonald & Booth 1990; the
//! full-sweep formulation of Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", 2007): the node-emission loop, the leaf-termination rule, the centroid sort key
//! and the object-split sweep. A builder says how a node's primitives are held, searched and
//! divided ([`NodeSplitter`]): `sweep.rs` with object splits over three presorted arrays,
//! `sbvh.rs` with object and spatial splits over per-node reference lists (Stich et al. 2009).
//!
//! A split into L and R costs `Ci + Ct·(A(L)·N(L) + A(R)·N(R)) / A(node)`, the node as a leaf
//! costs `Ct·N` ([`SahParams`]). A node of one primitive is a leaf; a node of `N ≤ max_leaf_size`
//! is a leaf unless a split is cheaper; a node of `N > max_leaf_size` is always split, by count in
//! the middle where no SAH split exists (zero or non-finite surface area, all centroids equal).
//!
//! Layout: the root is node 0 and nodes are emitted depth-first from an explicit stack (trees can
//! be deep), so an internal node's left child follows it; its right child is patched in when
//! emitted. Leaves reference contiguous ranges of `prim_indices`.

use super::{Bvh, BvhNode, SahParams, LEAF_FLAG};
use crate::geometry::Aabb;

/// The most primitive references a tree may hold: node indices (up to 2n − 1) must stay clear of
/// the leaf flag bit.
pub(super) const MAX_REFERENCES: usize = (LEAF_FLAG / 2) as usize;

/// A key whose unsigned order is the total order of the centroid coordinate `value`, with `index`
/// as tie-break: the order every builder sorts and sweeps primitives in.
pub(super) fn centroid_key(value: f32, index: u32) -> u64 {
    let bits = value.to_bits();
    let ordered = if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    };
    (u64::from(ordered) << 32) | u64::from(index)
}

/// A split of a node's primitives in [`centroid_key`] order along `axis`: the first `left_count`
/// go left.
pub(super) struct ObjectSplit {
    pub axis: usize,
    pub left_count: usize,
    pub left_bounds: Aabb,
    pub right_bounds: Aabb,
}

/// The full-sweep object-split search's scratch, reused from node to node.
pub(super) struct ObjectSweep {
    /// Suffix areas of the current sweep.
    suffix_area: Vec<f32>,
}

impl ObjectSweep {
    pub fn new() -> Self {
        Self {
            suffix_area: Vec::new(),
        }
    }

    /// Starts the search of one node.
    pub fn search(&mut self) -> SweepSearch<'_> {
        SweepSearch {
            suffix_area: &mut self.suffix_area,
            best: None,
        }
    }
}

/// The search for a node's cheapest object split, one axis at a time: every split position along
/// the axis, with suffix areas precomputed right to left and prefix boxes accumulated left to
/// right.
pub(super) struct SweepSearch<'a> {
    suffix_area: &'a mut Vec<f32>,
    /// (axis, left count, left bounds, cost sum) of the cheapest split so far.
    best: Option<(usize, usize, Aabb, f32)>,
}

impl SweepSearch<'_> {
    /// Sweeps `sorted`, the node's boxes in [`centroid_key`] order along `axis`; returns whether
    /// the axis holds the cheapest split so far (strictly cheaper than those of the axes swept
    /// before; the first of equal costs along an axis).
    pub fn sweep_axis(&mut self, axis: usize, sorted: &[Aabb]) -> bool {
        let count = sorted.len();
        if self.suffix_area.len() < count {
            self.suffix_area.resize(count, 0.0);
        }
        let mut acc = Aabb::EMPTY;
        for i in (1..count).rev() {
            acc = acc.union(sorted[i]);
            self.suffix_area[i] = acc.surface_area();
        }
        let mut improved = false;
        let mut left = Aabb::EMPTY;
        for i in 1..count {
            left = left.union(sorted[i - 1]);
            let sum = left.surface_area() * i as f32 + self.suffix_area[i] * (count - i) as f32;
            if sum < self.best.map_or(f32::INFINITY, |b| b.3) {
                self.best = Some((axis, i, left, sum));
                improved = true;
            }
        }
        improved
    }

    /// The cheapest split swept and its cost sum `A(L)·N(L) + A(R)·N(R)`, `None` if no split had
    /// a finite cost. `right_of(axis, left_count)` gives the boxes right of the split, in sorted
    /// order, for its right bounds.
    pub fn finish<I: IntoIterator<Item = Aabb>>(
        self,
        right_of: impl FnOnce(usize, usize) -> I,
    ) -> Option<(ObjectSplit, f32)> {
        self.best.map(|(axis, left_count, left_bounds, sum)| {
            let right_bounds = right_of(axis, left_count)
                .into_iter()
                .fold(Aabb::EMPTY, Aabb::union);
            let split = ObjectSplit {
                axis,
                left_count,
                left_bounds,
                right_bounds,
            };
            (split, sum)
        })
    }
}

/// How a builder holds, searches and divides a node's primitives.
pub(super) trait NodeSplitter {
    /// A node's primitives.
    type Node;
    /// A division of a node's primitives into two non-empty children.
    type Split;

    /// The number of primitive references in `node`.
    fn count(&self, node: &Self::Node) -> usize;

    /// The cheapest SAH split of `node` (box `bounds`, of positive finite surface area) and its
    /// cost sum `A(L)·N(L) + A(R)·N(R)`; `None` if there is none.
    fn best_split(&mut self, node: &Self::Node, bounds: &Aabb) -> Option<(Self::Split, f32)>;

    /// A split by count in the middle, for a node that must be split but has no SAH split.
    fn count_split(&mut self, node: &Self::Node) -> Self::Split;

    /// Divides `node` by `split`: the left and right children with their boxes.
    fn divide(&mut self, node: Self::Node, split: Self::Split) -> [(Self::Node, Aabb); 2];

    /// Appends the triangle ids of leaf `node` to `prim_indices`.
    fn emit_leaf(&mut self, node: Self::Node, prim_indices: &mut Vec<u32>);
}

/// A node still to be emitted: its primitives and box, and where to write its index in the
/// parent (`(parent, is_right)`; `None` for the root).
struct Task<N> {
    node: N,
    bounds: Aabb,
    parent: Option<(usize, bool)>,
}

/// How to handle `node` (box `bounds`): `None` makes it a leaf (see the module documentation).
fn choose_split<S: NodeSplitter>(
    splitter: &mut S,
    node: &S::Node,
    bounds: &Aabb,
    params: &SahParams,
) -> Option<S::Split> {
    let count = splitter.count(node);
    if count == 1 {
        return None;
    }
    let must_split = count > params.max_leaf_size.max(1) as usize;
    let area = bounds.surface_area();
    if area > 0.0 && area.is_finite() {
        if let Some((split, sum)) = splitter.best_split(node, bounds) {
            let split_cost = params.ci + params.ct * sum / area;
            let leaf_cost = params.ct * count as f32;
            return (must_split || split_cost < leaf_cost).then_some(split);
        }
    }
    must_split.then(|| splitter.count_split(node))
}

/// Builds the tree over `root` (box `root_bounds`) top-down with `splitter` (see the module
/// documentation). An empty root gives a tree with no nodes.
///
/// # Panics
/// If `root` holds more than [`MAX_REFERENCES`] references.
pub(super) fn build<S: NodeSplitter>(
    splitter: &mut S,
    root: S::Node,
    root_bounds: Aabb,
    params: &SahParams,
) -> Bvh {
    let n = splitter.count(&root);
    if n == 0 {
        return Bvh::default();
    }
    assert!(
        n <= MAX_REFERENCES,
        "too many triangles for the node layout: {n}"
    );
    let mut nodes: Vec<BvhNode> = Vec::with_capacity(2 * n - 1);
    let mut prim_indices: Vec<u32> = Vec::with_capacity(n);
    let mut stack = vec![Task {
        node: root,
        bounds: root_bounds,
        parent: None,
    }];
    while let Some(Task {
        node,
        bounds,
        parent,
    }) = stack.pop()
    {
        let index = nodes.len();
        match parent {
            Some((parent, false)) => nodes[parent].left_or_first = index as u32,
            Some((parent, true)) => nodes[parent].right_or_count = index as u32,
            None => {}
        }
        match choose_split(splitter, &node, &bounds, params) {
            None => {
                let first = prim_indices.len();
                splitter.emit_leaf(node, &mut prim_indices);
                let count = prim_indices.len() - first;
                nodes.push(BvhNode::leaf(bounds, first as u32, count as u32));
            }
            Some(split) => {
                // Children are patched in when they are emitted.
                nodes.push(BvhNode::internal(bounds, 0, 0));
                let [(left, left_bounds), (right, right_bounds)] = splitter.divide(node, split);
                stack.push(Task {
                    node: right,
                    bounds: right_bounds,
                    parent: Some((index, true)),
                });
                stack.push(Task {
                    node: left,
                    bounds: left_bounds,
                    parent: Some((index, false)),
                });
            }
        }
    }
    Bvh {
        nodes,
        prim_indices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centroid_keys_sort_in_total_order_then_by_index() {
        let values = [
            f32::NAN,
            1.0,
            -0.0,
            f32::NEG_INFINITY,
            0.0,
            -f32::NAN,
            f32::MIN_POSITIVE,
            -1.0,
            f32::INFINITY,
            1.0,
            -0.0,
        ];
        let mut by_key: Vec<u32> = (0..values.len() as u32).collect();
        by_key.sort_by_key(|&i| centroid_key(values[i as usize], i));
        let mut by_total_order = by_key.clone();
        by_total_order.sort_by(|&a, &b| {
            values[a as usize]
                .total_cmp(&values[b as usize])
                .then(a.cmp(&b))
        });
        assert_eq!(by_key, by_total_order);
        assert_eq!(by_key, [5, 3, 7, 2, 10, 4, 6, 1, 9, 8, 0]);
    }
}
