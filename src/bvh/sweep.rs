//! CPU full-sweep SAH builder: the classic greedy top-down "gold standard" BVH (MacDonald & Booth
//! 1990; the full-sweep formulation as in Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", 2007). A quality anchor and test oracle, never the per-frame path.
//!
//! Object splits only: each node considers every split position of its primitives sorted by
//! centroid along each of the three axes. The cost model, the leaf rule, the sweep and the node
//! layout are the shared top-down core's (`topdown.rs`); degenerate nodes (zero or non-finite
//! surface area, or all centroids equal) are split by count in the middle, along the axis of
//! largest centroid extent, when they must be split.
//!
//! Implementation: the primitives are sorted by centroid once per axis; each node owns the same
//! range `[start, end)` of the three sorted arrays, and after a split the two arrays not split
//! along are partitioned stably (the standard three-array approach), so a node costs O(N) and the
//! build O(n log n) for balanced splits. Each array carries the primitives' boxes next to their
//! ids, so sweeps and partitions stream through memory. Node boxes are exact unions of the
//! triangles' vertex boxes.

use std::ops::Range;

use super::topdown::{self, centroid_key, NodeSplitter, ObjectSplit, ObjectSweep};
use super::{Bvh, SahParams};
use crate::geometry::Aabb;
use crate::scene::Triangle;

/// Primitives sorted by centroid along one axis: ids and their boxes, partitioned per node.
struct Sorted {
    ids: Vec<u32>,
    boxes: Vec<Aabb>,
}

/// Object splits over the three sorted arrays; a node is a range `[start, end)` of all three.
struct SweepSplitter {
    /// Sorted along x, y and z.
    sorted: [Sorted; 3],
    sweep: ObjectSweep,
    /// Scratch: which side each primitive (by id) goes to in the current partition.
    goes_left: Vec<bool>,
    /// Scratch: the right-hand side during a stable partition.
    scratch: Sorted,
}

fn union_all(boxes: &[Aabb]) -> Aabb {
    boxes.iter().fold(Aabb::EMPTY, |b, &t| b.union(t))
}

/// Extent of the centroids of `boxes` along `axis` (the boxes are sorted along it).
fn centroid_extent(boxes: &[Aabb], axis: usize) -> f32 {
    boxes[boxes.len() - 1].centroid()[axis] - boxes[0].centroid()[axis]
}

impl NodeSplitter for SweepSplitter {
    type Node = Range<usize>;
    type Split = ObjectSplit;

    fn count(&self, range: &Range<usize>) -> usize {
        range.len()
    }

    fn best_split(&mut self, range: &Range<usize>, _: &Aabb) -> Option<(ObjectSplit, f32)> {
        let mut search = self.sweep.search();
        for axis in 0..3 {
            let boxes = &self.sorted[axis].boxes[range.clone()];
            if centroid_extent(boxes, axis) <= 0.0 {
                continue;
            }
            search.sweep_axis(axis, boxes);
        }
        search.finish(|axis, left_count| {
            self.sorted[axis].boxes[range.start + left_count..range.end]
                .iter()
                .copied()
        })
    }

    /// Count split in the middle along the axis of largest centroid extent.
    fn count_split(&mut self, range: &Range<usize>) -> ObjectSplit {
        let mut axis = 0;
        let mut widest = f32::NEG_INFINITY;
        for a in 0..3 {
            let extent = centroid_extent(&self.sorted[a].boxes[range.clone()], a);
            if extent > widest {
                widest = extent;
                axis = a;
            }
        }
        let mid = range.start + range.len() / 2;
        let boxes = &self.sorted[axis].boxes;
        ObjectSplit {
            axis,
            left_count: mid - range.start,
            left_bounds: union_all(&boxes[range.start..mid]),
            right_bounds: union_all(&boxes[mid..range.end]),
        }
    }

    /// The split axis is already ordered; the other two arrays are partitioned stably so every
    /// array holds the left set first.
    fn divide(&mut self, range: Range<usize>, split: ObjectSplit) -> [(Range<usize>, Aabb); 2] {
        let Range { start, end } = range;
        let mid = start + split.left_count;
        let split_ids = &self.sorted[split.axis].ids;
        for &p in &split_ids[start..mid] {
            self.goes_left[p as usize] = true;
        }
        for &p in &split_ids[mid..end] {
            self.goes_left[p as usize] = false;
        }
        for axis in (0..3).filter(|&a| a != split.axis) {
            let Sorted { ids, boxes } = &mut self.sorted[axis];
            let mut left = start;
            let mut right = 0;
            for i in start..end {
                let (p, b) = (ids[i], boxes[i]);
                if self.goes_left[p as usize] {
                    ids[left] = p;
                    boxes[left] = b;
                    left += 1;
                } else {
                    self.scratch.ids[right] = p;
                    self.scratch.boxes[right] = b;
                    right += 1;
                }
            }
            debug_assert_eq!(left, mid);
            ids[mid..end].copy_from_slice(&self.scratch.ids[..right]);
            boxes[mid..end].copy_from_slice(&self.scratch.boxes[..right]);
        }
        [
            (start..mid, split.left_bounds),
            (mid..end, split.right_bounds),
        ]
    }

    /// In the x array's order.
    fn emit_leaf(&mut self, range: Range<usize>, prim_indices: &mut Vec<u32>) {
        prim_indices.extend_from_slice(&self.sorted[0].ids[range]);
    }
}

/// Builds a BVH over `triangles` with the greedy full-sweep SAH (see the module documentation).
///
/// The root is node 0 and nodes are laid out depth-first (left subtree first); leaves reference
/// contiguous ranges of `prim_indices` (triangle ids) and hold at most `params.max_leaf_size`
/// triangles (a maximum of 0 is treated as 1). An empty input gives a tree with no nodes.
pub fn build_sweep_sah(triangles: &[Triangle], params: &SahParams) -> Bvh {
    let n = triangles.len();
    let boxes: Vec<Aabb> = triangles.iter().map(Triangle::bounds).collect();
    let sorted = std::array::from_fn(|axis| {
        let mut keys: Vec<u64> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| centroid_key(b.centroid()[axis], i as u32))
            .collect();
        keys.sort_unstable();
        let ids: Vec<u32> = keys.into_iter().map(|k| k as u32).collect();
        let boxes = ids.iter().map(|&i| boxes[i as usize]).collect();
        Sorted { ids, boxes }
    });
    let root_bounds = union_all(&boxes);
    drop(boxes);
    let mut splitter = SweepSplitter {
        sorted,
        sweep: ObjectSweep::new(),
        goes_left: vec![false; n],
        scratch: Sorted {
            ids: vec![0; n],
            boxes: vec![Aabb::EMPTY; n],
        },
    };
    topdown::build(&mut splitter, 0..n, root_bounds, params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{sah_cost, validate, BvhNode};
    use glam::Vec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// A soup of `n` random triangles in the unit cube with sizes spread over two orders of
    /// magnitude (fixed seed).
    fn soup(n: usize, seed: u64) -> Vec<Triangle> {
        let mut rng = Pcg64::seed_from_u64(seed);
        let v = |rng: &mut Pcg64| Vec3::new(rng.random(), rng.random(), rng.random());
        (0..n)
            .map(|_| {
                let c = v(&mut rng);
                let size = 0.01 * 10f32.powf(rng.random_range(0.0..2.0));
                let corner = |rng: &mut Pcg64| c + size * (v(rng) - Vec3::splat(0.5));
                let (a, b, d) = (corner(&mut rng), corner(&mut rng), corner(&mut rng));
                Triangle::new(a, b, d, 0)
            })
            .collect()
    }

    /// Reference: median split along the widest centroid axis until at most `leaf_size` remain.
    fn median_tree(triangles: &[Triangle], leaf_size: usize) -> Bvh {
        let mut ids: Vec<u32> = (0..triangles.len() as u32).collect();
        let bounds = |ids: &[u32]| {
            ids.iter()
                .fold(Aabb::EMPTY, |b, &i| b.union(triangles[i as usize].bounds()))
        };
        let mut nodes: Vec<BvhNode> = Vec::new();
        let mut stack = vec![(0, ids.len(), None::<(usize, bool)>)];
        while let Some((start, end, parent)) = stack.pop() {
            let index = nodes.len();
            match parent {
                Some((p, false)) => nodes[p].left_or_first = index as u32,
                Some((p, true)) => nodes[p].right_or_count = index as u32,
                None => {}
            }
            let b = bounds(&ids[start..end]);
            if end - start <= leaf_size {
                nodes.push(BvhNode::leaf(b, start as u32, (end - start) as u32));
                continue;
            }
            let cb = ids[start..end].iter().fold(Aabb::EMPTY, |cb, &i| {
                cb.grow(triangles[i as usize].bounds().centroid())
            });
            let axis = cb.largest_axis();
            ids[start..end].sort_by(|&a, &b| {
                let ca = triangles[a as usize].bounds().centroid()[axis];
                let cb = triangles[b as usize].bounds().centroid()[axis];
                ca.total_cmp(&cb)
            });
            nodes.push(BvhNode::internal(b, 0, 0));
            let mid = (start + end) / 2;
            stack.push((mid, end, Some((index, true))));
            stack.push((start, mid, Some((index, false))));
        }
        Bvh {
            nodes,
            prim_indices: ids,
        }
    }

    #[test]
    fn random_soups_are_valid() {
        let params = SahParams::default();
        for (seed, &n) in [1usize, 2, 3, 17, 1000, 5000].iter().enumerate() {
            let tris = soup(n, seed as u64);
            let bvh = build_sweep_sah(&tris, &params);
            let stats = validate(&bvh, &tris).unwrap_or_else(|e| panic!("n = {n}: {e}"));
            assert!(stats.max_leaf_size <= params.max_leaf_size as usize);
            assert_eq!(stats.nodes, bvh.nodes.len());
            // Depth-first layout: an internal node's left child follows it.
            for (i, node) in bvh.nodes.iter().enumerate() {
                if !node.is_leaf() {
                    assert_eq!(node.children().0 as usize, i + 1);
                }
            }
            let cost = sah_cost(&bvh, &params);
            assert!(cost.is_finite() && cost > 0.0, "n = {n}: cost {cost}");
        }
    }

    #[test]
    fn single_triangle_is_one_leaf() {
        let tris = soup(1, 7);
        let bvh = build_sweep_sah(&tris, &SahParams::default());
        assert_eq!(bvh.nodes, vec![BvhNode::leaf(tris[0].bounds(), 0, 1)]);
        assert_eq!(bvh.prim_indices, vec![0]);
    }

    #[test]
    fn empty_input_gives_no_nodes() {
        let bvh = build_sweep_sah(&[], &SahParams::default());
        assert!(bvh.nodes.is_empty() && bvh.prim_indices.is_empty());
    }

    #[test]
    fn beats_a_median_split_tree() {
        let params = SahParams::default();
        for (seed, n) in [(11, 1000), (12, 5000)] {
            let tris = soup(n, seed);
            let sweep = build_sweep_sah(&tris, &params);
            let median = median_tree(&tris, 4);
            validate(&median, &tris).unwrap();
            let (s, m) = (sah_cost(&sweep, &params), sah_cost(&median, &params));
            assert!(s < 0.95 * m, "n = {n}: sweep SAH {s} vs median SAH {m}");
        }
    }

    #[test]
    fn identical_centroids_split_by_count() {
        // 100 copies of one triangle: no SAH split separates them; must still respect the leaf size.
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
        let tris = vec![t; 100];
        let params = SahParams::default();
        let bvh = build_sweep_sah(&tris, &params);
        let stats = validate(&bvh, &tris).unwrap();
        assert!(stats.max_leaf_size <= 8);
        // Count splits in the middle: a balanced tree (100 → 50 → 25 → 12/13 → 6/7).
        assert_eq!(stats.max_depth, 4);
        // Same-centroid triangles of different sizes (nested), and fully degenerate points.
        let nested: Vec<Triangle> = (1..=40)
            .map(|i| {
                let s = i as f32;
                Triangle::new(
                    Vec3::new(-s, -s, 0.0),
                    Vec3::new(s, -s, 0.0),
                    Vec3::new(0.0, s, 0.0),
                    0,
                )
            })
            .collect();
        let stats = validate(&build_sweep_sah(&nested, &params), &nested).unwrap();
        assert!(stats.max_leaf_size <= 8);
        let points = vec![Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE, 0); 33];
        let bvh = build_sweep_sah(&points, &params);
        let stats = validate(&bvh, &points).unwrap();
        assert!(stats.max_leaf_size <= 8);
        assert!(sah_cost(&bvh, &params).is_finite());
    }

    #[test]
    fn max_leaf_size_is_respected() {
        let tris = soup(2000, 3);
        for max_leaf_size in [0, 1, 2, 5, 16] {
            // Splits so expensive that the SAH would rather make one big leaf: the cap must hold.
            let params = SahParams {
                ci: 1000.0,
                ct: 1.0,
                max_leaf_size,
            };
            let bvh = build_sweep_sah(&tris, &params);
            let stats = validate(&bvh, &tris).unwrap();
            assert!(
                stats.max_leaf_size <= max_leaf_size.max(1) as usize,
                "cap {max_leaf_size}: leaf of {}",
                stats.max_leaf_size
            );
            if max_leaf_size == 16 {
                // Leaves grow past the default cap: the larger child of the last forced split of
                // more than 16 triangles holds at least 9.
                assert!(stats.max_leaf_size > 8);
            }
        }
    }

    #[test]
    fn prefers_a_leaf_when_splits_do_not_pay() {
        // Four triangles with nearly the same unit-cube box (distinct centroids): any split leaves
        // both children almost as large as the parent, so a leaf is cheaper.
        let tris: Vec<Triangle> = (0..4)
            .map(|i| {
                let o = Vec3::splat(0.01 * i as f32);
                Triangle::new(o, o + Vec3::new(1.0, 1.0, 0.0), o + Vec3::Z, 0)
            })
            .collect();
        let params = SahParams::default();
        let bvh = build_sweep_sah(&tris, &params);
        assert_eq!(bvh.nodes.len(), 1);
        assert!(bvh.nodes[0].is_leaf());
        validate(&bvh, &tris).unwrap();
        // The same triangles spread far apart are split.
        let apart: Vec<Triangle> = (0..4)
            .map(|i| {
                let o = Vec3::splat(10.0 * i as f32);
                Triangle::new(o, o + Vec3::new(1.0, 1.0, 0.0), o + Vec3::Z, 0)
            })
            .collect();
        let bvh = build_sweep_sah(&apart, &params);
        assert_eq!(validate(&bvh, &apart).unwrap().leaves, 4);
    }
}
