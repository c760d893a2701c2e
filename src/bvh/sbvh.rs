//! CPU SBVH builder: Stich, Friedrich & Dietrich, "Spatial Splits in Bounding Volume Hierarchies"
//! (HPG 2009). The quality anchor for split-aware builders; a reference, never the per-frame path.
//!
//! A greedy top-down SAH build over *references* (a triangle id and a box that may cover only a
//! part of the triangle). Each node considers
//! - **object splits**: a full sweep (every position, not binned) over the references sorted by
//!   box centroid along each axis, ties broken by triangle id: the sweep builder's (`sweep.rs`)
//!   sweep, sort key, leaf rule and node layout, all from the shared top-down core
//!   (`topdown.rs`), so where no spatial split happens both builders produce the same tree;
//! - **spatial splits**, only where the best object split's children overlap by more than
//!   α = 1e-5 of the root's surface area (the paper's λ > α test; always where no object split
//!   exists, e.g. all centroids equal): 32 equal bins per axis across the node box. A reference
//!   spanning several bins is chopped bin by bin: each bin receives the box of the triangle
//!   clipped to the bin's slab (vertices inside it plus the edges' crossings of its two planes),
//!   intersected with the reference box; entry/exit counts give N(L) and N(R) at the 31 planes.
//!
//! The cheaper candidate by SAH (`Ci + Ct·(A(L)·N(L) + A(R)·N(R)) / A(node)`, [`SahParams`]:
//! Ci = 1.2, Ct = 1 by default) wins; a binned spatial estimate that beats the object split is
//! performed exactly and kept only if its exact cost still wins. Performing a spatial split clips
//! each straddling reference exactly: Sutherland–Hodgman polygon clipping (`geometry::Polygon`)
//! of the triangle against the reference box and the half-space on either side of the plane, in
//! f64; a side the triangle does not reach strictly past the plane gets nothing. **Reference
//! unsplitting** (paper §4.4) is done: straddlers, in triangle id order, go wholly to one side
//! when that is cheaper than duplicating them. Leaf termination is the core's: a leaf when
//! `N ≤ max_leaf_size` and `Ct·N` is no more than the best split, always a split when
//! `N > max_leaf_size` (a count split in the middle, in triangle id order, where no SAH split
//! exists: degenerate boxes, all centroids equal and no spatial split).
//!
//! Properties: each node holds at most one reference per triangle (a reference goes left, right
//! or both), so no leaf references a triangle twice, while a triangle may be referenced by several
//! leaves. Reference boxes are boxes of clipped polygons, rounded outward to f32 (after a 1e-12
//! relative margin for the f64 arithmetic) and intersected with the parent reference box, so leaf
//! boxes cover the clipped parts (conservatively, never less) and lie inside the triangles' boxes.
//! The total number of references is capped at 3× the triangle count (a budget of 2 extra
//! references per triangle, shared among subtrees in proportion to their reference counts; a
//! node whose share is spent only unsplits); with α = 1e-5 real scenes stay far below it.
//!
//! Implementation: each node's references are kept in triangle id order, so a (centroid, local
//! index) key sorts exactly like the sweep builder; each node sorts its keys per axis
//! (O(n log² n) in total). Measured: the 1.1M-triangle `field-1m` in about 10 s, a pathological
//! 2M-triangle soup of large overlapping triangles in about 2 minutes, under 0.6 GB. Every split
//! leaves both children non-empty and either shrinks the reference count or spends budget, so the
//! build terminates.

use glam::{DVec3, Vec3};

use super::topdown::{self, centroid_key, NodeSplitter, ObjectSplit, ObjectSweep, MAX_REFERENCES};
use super::{Bvh, SahParams};
use crate::geometry::{Aabb, HalfSpace, Polygon};
use crate::scene::Triangle;

/// Bins per axis for spatial split candidates.
const SPATIAL_BINS: usize = 32;
/// Stich et al.'s α: spatial splits are tried where the object split's child overlap area exceeds
/// this fraction of the root's surface area.
const OVERLAP_THRESHOLD: f32 = 1e-5;
/// Extra references allowed per triangle: at most 3× the triangle count in total.
const EXTRA_REFERENCES_PER_TRIANGLE: usize = 2;
/// Vertex capacity of a clipped polygon (a triangle clipped by 8 planes has at most 11).
const MAX_POLYGON_VERTICES: usize = 16;
/// Relative margin (of the triangle's coordinate magnitude) covering f64 clipping round-off.
const CLIP_MARGIN: f64 = 1e-12;

/// A triangle (or the part of it inside `bounds`) as seen by one node.
#[derive(Clone, Copy, Debug)]
struct Reference {
    bounds: Aabb,
    tri: u32,
}

/// A triangle clipped by axis-aligned planes, in f64. Overflow (only conceivable for numerically
/// degenerate input) makes its box the conservative clip box.
type ClippedTriangle = Polygon<MAX_POLYGON_VERTICES>;

/// (min, max) of coordinate `axis` of `polygon`'s vertices; (∞, −∞) when empty.
fn coordinate_range(polygon: &ClippedTriangle, axis: usize) -> (f64, f64) {
    polygon
        .vertices()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v[axis]), hi.max(v[axis]))
        })
}

/// The box of `polygon` rounded outward to f32 (after widening by `margin`) and intersected with
/// `limit`; `None` when the polygon or the intersection is empty. An overflowed polygon gives
/// `limit` itself (conservative).
fn bounds_within(polygon: &ClippedTriangle, limit: &Aabb, margin: f64) -> Option<Aabb> {
    if polygon.overflowed() {
        return Some(*limit);
    }
    let (first, rest) = polygon.vertices().split_first()?;
    let (lo, hi) = rest
        .iter()
        .fold((*first, *first), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let bounds = Aabb::new(
        round_down(lo - DVec3::splat(margin)).max(limit.min),
        round_up(hi + DVec3::splat(margin)).min(limit.max),
    );
    (!bounds.is_empty()).then_some(bounds)
}

/// The largest f32 vector ≤ `v` per component.
fn round_down(v: DVec3) -> Vec3 {
    let f = |x: f64| {
        let y = x as f32;
        if f64::from(y) > x {
            y.next_down()
        } else {
            y
        }
    };
    Vec3::new(f(v.x), f(v.y), f(v.z))
}

/// The smallest f32 vector ≥ `v` per component.
fn round_up(v: DVec3) -> Vec3 {
    -round_down(-v)
}

/// Margin covering f64 round-off when clipping `triangle`.
fn clip_margin(triangle: &Triangle) -> f64 {
    let b = triangle.bounds();
    f64::from(b.min.abs().max(b.max.abs()).max_element()) * CLIP_MARGIN
}

/// `triangle` clipped to `bounds` (only against the planes the triangle crosses).
fn clip_to_box(triangle: &Triangle, bounds: &Aabb) -> ClippedTriangle {
    let tri_bounds = triangle.bounds();
    let mut polygon = ClippedTriangle::triangle(triangle.vertices().map(Vec3::as_dvec3));
    for axis in 0..3 {
        if tri_bounds.min[axis] < bounds.min[axis] {
            let plane = f64::from(bounds.min[axis]);
            polygon = polygon.clip(axis, plane, HalfSpace::Above);
        }
        if tri_bounds.max[axis] > bounds.max[axis] {
            let plane = f64::from(bounds.max[axis]);
            polygon = polygon.clip(axis, plane, HalfSpace::Below);
        }
    }
    polygon
}

/// A triangle with its vertices sorted along one axis, for cutting it by many parallel planes.
struct SortedTriangle {
    axis: usize,
    /// Sorted by coordinate `axis`.
    vertices: [Vec3; 3],
    /// Edges lo→hi, lo→mid, mid→hi as (start, direction, 1 / direction[axis]).
    edges: [(Vec3, Vec3, f32); 3],
}

impl SortedTriangle {
    fn new(triangle: &Triangle, axis: usize) -> Self {
        let mut vertices = triangle.vertices();
        vertices.sort_unstable_by(|a, b| a[axis].total_cmp(&b[axis]));
        let [lo, mid, hi] = vertices;
        let edge = |a: Vec3, b: Vec3| (a, b - a, 1.0 / (b[axis] - a[axis]));
        Self {
            axis,
            vertices,
            edges: [edge(lo, hi), edge(lo, mid), edge(mid, hi)],
        }
    }

    /// The point where edge `e` crosses the plane at `pos` (strictly inside the edge's range).
    #[inline]
    fn crossing(&self, e: usize, pos: f32) -> Vec3 {
        let (a, d, inv) = self.edges[e];
        let mut p = a + d * ((pos - a[self.axis]) * inv);
        p = p.clamp(a.min(a + d), a.max(a + d));
        p[self.axis] = pos;
        p
    }

    /// The box of the points where the triangle's edges cross the plane `axis = pos` strictly
    /// (the crossing points of the triangle clipped to a slab bounded by that plane); empty if
    /// the plane does not cut the triangle.
    #[inline]
    fn crossings(&self, pos: f32) -> Aabb {
        let [lo, mid, hi] = self.vertices;
        let axis = self.axis;
        if !(lo[axis] < pos && pos < hi[axis]) {
            return Aabb::EMPTY;
        }
        let long = self.crossing(0, pos);
        let short = if pos < mid[axis] {
            self.crossing(1, pos)
        } else if pos > mid[axis] {
            self.crossing(2, pos)
        } else {
            mid
        };
        Aabb::new(long.min(short), long.max(short))
    }
}

/// `bounds` restricted to `[lo, hi]` along `axis`.
fn slab(bounds: &Aabb, axis: usize, lo: f32, hi: f32) -> Aabb {
    let mut b = *bounds;
    b.min[axis] = b.min[axis].max(lo);
    b.max[axis] = b.max[axis].min(hi);
    b
}

/// Splits reference `r` of `triangle` at the plane `axis = pos`: the boxes of the parts below
/// and above, `None` for a side the triangle does not reach strictly beyond the plane (points on
/// the plane belong to both sides).
fn split_reference(
    triangle: &Triangle,
    r: &Reference,
    axis: usize,
    pos: f32,
) -> (Option<Aabb>, Option<Aabb>) {
    let polygon = clip_to_box(triangle, &r.bounds);
    let margin = clip_margin(triangle);
    let p = f64::from(pos);
    let below = polygon.clip(axis, p, HalfSpace::Below);
    let above = polygon.clip(axis, p, HalfSpace::Above);
    let left = if below.overflowed() || coordinate_range(&below, axis).0 < p {
        bounds_within(
            &below,
            &slab(&r.bounds, axis, f32::NEG_INFINITY, pos),
            margin,
        )
    } else {
        None
    };
    let right = if above.overflowed() || coordinate_range(&above, axis).1 > p {
        bounds_within(&above, &slab(&r.bounds, axis, pos, f32::INFINITY), margin)
    } else {
        None
    };
    (left, right)
}

fn union_all(refs: &[Reference]) -> Aabb {
    refs.iter().fold(Aabb::EMPTY, |b, r| b.union(r.bounds))
}

fn intersection(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb::new(a.min.max(b.min), a.max.min(b.max))
}

/// A best spatial split candidate from the bins.
struct SpatialCandidate {
    axis: usize,
    position: f32,
    /// Binned estimate of `A(L)·N(L) + A(R)·N(R)`.
    sum: f32,
}

/// A node's references divided between its two children.
struct Partition {
    left: Vec<Reference>,
    left_bounds: Aabb,
    right: Vec<Reference>,
    right_bounds: Aabb,
    /// `A(L)·N(L) + A(R)·N(R)`.
    sum: f32,
    /// References added by splitting (`N(L) + N(R) − N`).
    duplicates: usize,
}

impl Partition {
    fn new(left: Vec<Reference>, right: Vec<Reference>, parent_count: usize) -> Self {
        let left_bounds = union_all(&left);
        let right_bounds = union_all(&right);
        let sum = left_bounds.surface_area() * left.len() as f32
            + right_bounds.surface_area() * right.len() as f32;
        let duplicates = (left.len() + right.len()).saturating_sub(parent_count);
        Self {
            left,
            left_bounds,
            right,
            right_bounds,
            sum,
            duplicates,
        }
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    entries: u32,
    exits: u32,
}

/// A node's references, in triangle id order, and its share of the reference budget.
struct NodeReferences {
    refs: Vec<Reference>,
    budget: usize,
}

/// Object and spatial splits with reference unsplitting, within the reference budget.
struct SbvhSplitter<'a> {
    triangles: &'a [Triangle],
    root_area: f32,
    sweep: ObjectSweep,
    /// Scratch: sort keys (centroid, local index) along the axis being swept.
    keys: Vec<u64>,
    /// Scratch: the keys of the best object split so far.
    best_keys: Vec<u64>,
    /// Scratch: the references' boxes in `keys` order.
    sorted_boxes: Vec<Aabb>,
    /// Scratch: which references (by local index) the object split sends left.
    goes_left: Vec<bool>,
}

impl SbvhSplitter<'_> {
    /// The best full-sweep object split over the axes along which the centroids spread; its order
    /// of the references is left in `best_keys`.
    fn find_object_split(&mut self, refs: &[Reference]) -> Option<(ObjectSplit, f32)> {
        let mut search = self.sweep.search();
        for axis in 0..3 {
            let (lo, hi) = refs
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), r| {
                    let c = r.bounds.centroid()[axis];
                    (lo.min(c), hi.max(c))
                });
            if hi - lo <= 0.0 {
                continue;
            }
            // References are in triangle id order, so the local index is the sweep builder's
            // tie-break.
            self.keys.clear();
            self.keys.extend(
                refs.iter()
                    .enumerate()
                    .map(|(j, r)| centroid_key(r.bounds.centroid()[axis], j as u32)),
            );
            self.keys.sort_unstable();
            self.sorted_boxes.clear();
            self.sorted_boxes
                .extend(self.keys.iter().map(|&k| refs[k as u32 as usize].bounds));
            if search.sweep_axis(axis, &self.sorted_boxes) {
                std::mem::swap(&mut self.keys, &mut self.best_keys);
            }
        }
        let best_keys = &self.best_keys;
        search.finish(|_, left_count| {
            best_keys[left_count..]
                .iter()
                .map(|&k| refs[k as u32 as usize].bounds)
        })
    }

    /// Applies the object split found last: its left set (the first `left_count` of
    /// `best_keys`) and the rest, both kept in triangle id order.
    fn object_partition(&mut self, refs: &[Reference], split: &ObjectSplit, sum: f32) -> Partition {
        self.goes_left.clear();
        self.goes_left.resize(refs.len(), false);
        for &k in &self.best_keys[..split.left_count] {
            self.goes_left[k as u32 as usize] = true;
        }
        let mut left = Vec::with_capacity(split.left_count);
        let mut right = Vec::with_capacity(refs.len() - split.left_count);
        for (r, &goes_left) in refs.iter().zip(&self.goes_left) {
            if goes_left {
                left.push(*r);
            } else {
                right.push(*r);
            }
        }
        Partition {
            left,
            left_bounds: split.left_bounds,
            right,
            right_bounds: split.right_bounds,
            sum,
            duplicates: 0,
        }
    }

    /// The cheapest binned spatial split of `refs` (box `bounds`) whose estimated duplicates fit
    /// into `budget`.
    fn find_spatial_split(
        &self,
        refs: &[Reference],
        bounds: &Aabb,
        budget: usize,
    ) -> Option<SpatialCandidate> {
        let n = refs.len();
        let mut best: Option<SpatialCandidate> = None;
        for axis in 0..3 {
            let (lo, hi) = (bounds.min[axis], bounds.max[axis]);
            if hi <= lo {
                continue;
            }
            let mut planes = [hi; SPATIAL_BINS + 1];
            for (i, p) in planes.iter_mut().enumerate().take(SPATIAL_BINS) {
                *p = (lo + (hi - lo) * (i as f32 / SPATIAL_BINS as f32)).min(hi);
            }
            planes[0] = lo;
            let scale = SPATIAL_BINS as f64 / (f64::from(hi) - f64::from(lo));
            let estimate = |x: f32| {
                let b = ((f64::from(x) - f64::from(lo)) * scale).floor();
                b.clamp(0.0, (SPATIAL_BINS - 1) as f64) as usize
            };
            // The bin holding a box's min: the last b with planes[b] ≤ x.
            let first_bin = |x: f32| {
                let mut b = estimate(x);
                while b > 0 && planes[b] > x {
                    b -= 1;
                }
                while b + 1 < SPATIAL_BINS && planes[b + 1] <= x {
                    b += 1;
                }
                b
            };
            // The bin holding a box's max: the first b with planes[b + 1] ≥ x.
            let last_bin = |x: f32| {
                let mut b = estimate(x);
                while b > 0 && planes[b] >= x {
                    b -= 1;
                }
                while b + 1 < SPATIAL_BINS && planes[b + 1] < x {
                    b += 1;
                }
                b
            };
            let mut bins = [Bin {
                bounds: Aabb::EMPTY,
                entries: 0,
                exits: 0,
            }; SPATIAL_BINS];
            for r in refs {
                let first = first_bin(r.bounds.min[axis]);
                let last = last_bin(r.bounds.max[axis]).max(first);
                if first == last {
                    let bin = &mut bins[first];
                    bin.bounds = bin.bounds.union(r.bounds);
                    bin.entries += 1;
                    bin.exits += 1;
                    continue;
                }
                // Chop the triangle bin by bin: each bin gets the box of the triangle clipped
                // to the bin's slab, intersected with the reference box (an estimate: the
                // performed split clips exactly against the reference box too).
                let sorted = SortedTriangle::new(&self.triangles[r.tri as usize], axis);
                let mut lo_crossings = sorted.crossings(planes[first]);
                let mut touched: Option<(usize, usize)> = None;
                for b in first..=last {
                    let (slab_lo, slab_hi) = (planes[b], planes[b + 1]);
                    let hi_crossings = sorted.crossings(slab_hi);
                    let mut piece = lo_crossings.union(hi_crossings);
                    lo_crossings = hi_crossings;
                    for v in sorted.vertices {
                        if v[axis] >= slab_lo && v[axis] <= slab_hi {
                            piece = piece.grow(v);
                        }
                    }
                    let piece = intersection(&piece, &slab(&r.bounds, axis, slab_lo, slab_hi));
                    // Skip empty pieces and pieces that only touch a plane shared with a
                    // neighbouring piece.
                    if piece.is_empty()
                        || (piece.max[axis] <= slab_lo && b != first)
                        || (piece.min[axis] >= slab_hi && b != last)
                    {
                        continue;
                    }
                    bins[b].bounds = bins[b].bounds.union(piece);
                    touched = Some(touched.map_or((b, b), |(f, _)| (f, b)));
                }
                // The triangle misses the reference box's slabs (numerically): count the whole
                // box in its first bin.
                let (f, l) = touched.unwrap_or_else(|| {
                    bins[first].bounds = bins[first].bounds.union(r.bounds);
                    (first, first)
                });
                bins[f].entries += 1;
                bins[l].exits += 1;
            }
            // Sweep the planes between bins.
            let mut suffix = [(Aabb::EMPTY, 0u32); SPATIAL_BINS];
            let mut acc = (Aabb::EMPTY, 0u32);
            for k in (1..SPATIAL_BINS).rev() {
                acc = (acc.0.union(bins[k].bounds), acc.1 + bins[k].exits);
                suffix[k] = acc;
            }
            let mut left = (Aabb::EMPTY, 0u32);
            for k in 1..SPATIAL_BINS {
                left = (
                    left.0.union(bins[k - 1].bounds),
                    left.1 + bins[k - 1].entries,
                );
                let (right_bounds, right_count) = suffix[k];
                let (left_bounds, left_count) = left;
                if left_count == 0 || right_count == 0 {
                    continue;
                }
                let duplicates = (left_count as usize + right_count as usize).saturating_sub(n);
                if duplicates > budget {
                    continue;
                }
                let sum = left_bounds.surface_area() * left_count as f32
                    + right_bounds.surface_area() * right_count as f32;
                if sum < best.as_ref().map_or(f32::INFINITY, |b| b.sum) {
                    best = Some(SpatialCandidate {
                        axis,
                        position: planes[k],
                        sum,
                    });
                }
            }
        }
        best
    }

    /// Performs the spatial split of `refs` at `axis = pos` with reference unsplitting, adding at
    /// most `budget` references; `None` if a side ends up empty.
    fn spatial_partition(
        &self,
        refs: &[Reference],
        axis: usize,
        pos: f32,
        budget: usize,
    ) -> Option<Partition> {
        // Which side each reference goes to, with its box there.
        enum Side {
            Left(Aabb),
            Right(Aabb),
            Both(Aabb, Aabb),
        }
        let (mut left_bounds, mut right_bounds) = (Aabb::EMPTY, Aabb::EMPTY);
        let (mut nl, mut nr) = (0usize, 0usize);
        let mut sides: Vec<Side> = refs
            .iter()
            .map(|r| {
                let side = if r.bounds.min[axis] >= pos {
                    Side::Right(r.bounds)
                } else if r.bounds.max[axis] <= pos {
                    Side::Left(r.bounds)
                } else {
                    match split_reference(&self.triangles[r.tri as usize], r, axis, pos) {
                        (Some(l), Some(h)) => return Side::Both(l, h),
                        (Some(l), None) => Side::Left(l),
                        (None, Some(h)) => Side::Right(h),
                        // Numerically degenerate clipping: keep the whole box.
                        (None, None) => Side::Right(r.bounds),
                    }
                };
                match side {
                    Side::Left(b) => {
                        left_bounds = left_bounds.union(b);
                        nl += 1;
                    }
                    Side::Right(b) | Side::Both(_, b) => {
                        right_bounds = right_bounds.union(b);
                        nr += 1;
                    }
                }
                side
            })
            .collect();
        // Reference unsplitting, straddler by straddler in order.
        let mut duplicates = 0;
        for (r, side) in refs.iter().zip(&mut sides) {
            let Side::Both(l, h) = *side else {
                continue;
            };
            let (fl, fr) = (nl as f32, nr as f32);
            let whole_left = left_bounds.union(r.bounds);
            let whole_right = right_bounds.union(r.bounds);
            let unsplit_left =
                whole_left.surface_area() * (fl + 1.0) + right_bounds.surface_area() * fr;
            let unsplit_right =
                left_bounds.surface_area() * fl + whole_right.surface_area() * (fr + 1.0);
            let split = left_bounds.union(l).surface_area() * (fl + 1.0)
                + right_bounds.union(h).surface_area() * (fr + 1.0);
            if duplicates < budget && split < unsplit_left.min(unsplit_right) {
                duplicates += 1;
                left_bounds = left_bounds.union(l);
                right_bounds = right_bounds.union(h);
                nl += 1;
                nr += 1;
            } else if unsplit_left <= unsplit_right {
                *side = Side::Left(r.bounds);
                left_bounds = whole_left;
                nl += 1;
            } else {
                *side = Side::Right(r.bounds);
                right_bounds = whole_right;
                nr += 1;
            }
        }
        if nl == 0 || nr == 0 {
            return None;
        }
        let mut left = Vec::with_capacity(nl);
        let mut right = Vec::with_capacity(nr);
        for (r, side) in refs.iter().zip(sides) {
            let with = |bounds| Reference { bounds, ..*r };
            match side {
                Side::Left(b) => left.push(with(b)),
                Side::Right(b) => right.push(with(b)),
                Side::Both(l, h) => {
                    left.push(with(l));
                    right.push(with(h));
                }
            }
        }
        Some(Partition::new(left, right, refs.len()))
    }
}

impl NodeSplitter for SbvhSplitter<'_> {
    type Node = NodeReferences;
    type Split = Partition;

    fn count(&self, node: &NodeReferences) -> usize {
        node.refs.len()
    }

    /// The cheaper of the best object split and, where its children overlap (or it does not
    /// exist), the best spatial split.
    fn best_split(&mut self, node: &NodeReferences, bounds: &Aabb) -> Option<(Partition, f32)> {
        let refs = &node.refs;
        let object = self.find_object_split(refs);
        let object_sum = object.as_ref().map_or(f32::INFINITY, |o| o.1);
        let try_spatial = self.root_area > 0.0
            && self.root_area.is_finite()
            && object.as_ref().is_none_or(|(o, _)| {
                let overlap = intersection(&o.left_bounds, &o.right_bounds);
                overlap.surface_area() / self.root_area > OVERLAP_THRESHOLD
            });
        let spatial = if try_spatial {
            self.find_spatial_split(refs, bounds, node.budget)
                .filter(|c| c.sum < object_sum)
                .and_then(|c| self.spatial_partition(refs, c.axis, c.position, node.budget))
                .filter(|p| p.sum < object_sum)
        } else {
            None
        };
        spatial
            .or_else(|| object.map(|(o, sum)| self.object_partition(refs, &o, sum)))
            .map(|partition| {
                let sum = partition.sum;
                (partition, sum)
            })
    }

    /// In triangle id order.
    fn count_split(&mut self, node: &NodeReferences) -> Partition {
        let refs = &node.refs;
        let mid = refs.len() / 2;
        Partition::new(refs[..mid].to_vec(), refs[mid..].to_vec(), refs.len())
    }

    /// The children share the budget left after the split in proportion to their reference
    /// counts.
    fn divide(
        &mut self,
        node: NodeReferences,
        partition: Partition,
    ) -> [(NodeReferences, Aabb); 2] {
        let remaining = node.budget - partition.duplicates;
        let (nl, nr) = (partition.left.len(), partition.right.len());
        let left_budget = (remaining as u128 * nl as u128 / (nl + nr) as u128) as usize;
        let left = NodeReferences {
            refs: partition.left,
            budget: left_budget,
        };
        let right = NodeReferences {
            refs: partition.right,
            budget: remaining - left_budget,
        };
        [
            (left, partition.left_bounds),
            (right, partition.right_bounds),
        ]
    }

    /// In the sweep builder's order (by centroid x, then id): identical trees where no spatial
    /// split happens.
    fn emit_leaf(&mut self, node: NodeReferences, prim_indices: &mut Vec<u32>) {
        let mut refs = node.refs;
        refs.sort_unstable_by_key(|r| centroid_key(r.bounds.centroid().x, r.tri));
        prim_indices.extend(refs.iter().map(|r| r.tri));
    }
}

/// Builds an SBVH over `triangles` (see the module documentation).
///
/// The root is node 0 and nodes are laid out depth-first (left subtree first); leaves reference
/// contiguous ranges of `prim_indices` (triangle ids; a triangle may appear in several leaves,
/// never twice in one) and hold at most `params.max_leaf_size` references (a maximum of 0 is
/// treated as 1). An empty input gives a tree with no nodes.
///
/// # Panics
/// If `triangles` has more than 2^30 entries (node indices must stay clear of the leaf flag).
pub fn build_sbvh(triangles: &[Triangle], params: &SahParams) -> Bvh {
    let n = triangles.len();
    let budget = n
        .saturating_mul(EXTRA_REFERENCES_PER_TRIANGLE)
        .min(MAX_REFERENCES.saturating_sub(n));
    let refs: Vec<Reference> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| Reference {
            bounds: t.bounds(),
            tri: i as u32,
        })
        .collect();
    let root_bounds = union_all(&refs);
    let mut splitter = SbvhSplitter {
        triangles,
        root_area: root_bounds.surface_area(),
        sweep: ObjectSweep::new(),
        keys: Vec::with_capacity(n),
        best_keys: Vec::with_capacity(n),
        sorted_boxes: Vec::with_capacity(n),
        goes_left: Vec::with_capacity(n),
    };
    let root = NodeReferences { refs, budget };
    topdown::build(&mut splitter, root, root_bounds, params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_sweep_sah, sah_cost, validate, validate_with_references};
    use crate::geometry::Ray;
    use crate::trace::brute_force_closest_hit;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// `n` random triangles in the unit cube, sizes from `min_size` to 100× that (fixed seed).
    fn soup(n: usize, min_size: f32, seed: u64) -> Vec<Triangle> {
        let mut rng = Pcg64::seed_from_u64(seed);
        let v = |rng: &mut Pcg64| Vec3::new(rng.random(), rng.random(), rng.random());
        (0..n)
            .map(|_| {
                let c = v(&mut rng);
                let size = min_size * 10f32.powf(rng.random_range(0.0..2.0));
                let corner = |rng: &mut Pcg64| c + size * (v(rng) - Vec3::splat(0.5));
                let (a, b, d) = (corner(&mut rng), corner(&mut rng), corner(&mut rng));
                Triangle::new(a, b, d, 0)
            })
            .collect()
    }

    /// A fan of `n` long thin slivers around the z axis, each from near the centre to radius 1
    /// on a diagonal: the case spatial splits exist for.
    fn fan(n: usize) -> Vec<Triangle> {
        (0..n)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / n as f32;
                let (s, c) = a.sin_cos();
                let d = Vec3::new(c, s, 0.3 * (3.0 * a).sin());
                let side = Vec3::new(-s, c, 0.0) * 0.002;
                Triangle::new(0.01 * d, d + side, d - side, 0)
            })
            .collect()
    }

    /// Rays aimed at random points of random triangles from random directions, plus rays from
    /// inside the scene box: the tree's hits equal brute force (ties at equal distance allowed).
    fn assert_traversal_matches(bvh: &Bvh, tris: &[Triangle], count: usize, seed: u64) {
        let mut rng = Pcg64::seed_from_u64(seed);
        let bounds = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let diag = bounds.extent().length();
        let mut hits = 0;
        for k in 0..count {
            let dir = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let ray = if k % 2 == 0 {
                let [a, b, c] = tris[rng.random_range(0..tris.len())].vertices();
                let (u, v): (f32, f32) =
                    (rng.random_range(0.05..0.45), rng.random_range(0.05..0.45));
                let target = a + u * (b - a) + v * (c - a);
                let origin = target - dir.normalize_or(Vec3::X) * diag;
                Ray::new(origin, target - origin, 0.0, f32::MAX)
            } else {
                let origin = bounds.min
                    + bounds.extent() * Vec3::new(rng.random(), rng.random(), rng.random());
                Ray::new(origin, dir, 0.0, f32::MAX)
            };
            let expected = brute_force_closest_hit(tris, &ray);
            let got = bvh.closest_hit(tris, &ray);
            hits += usize::from(expected.is_hit());
            assert_eq!(
                expected.is_hit(),
                got.is_hit(),
                "ray {k}: {expected:?} vs {got:?}"
            );
            if expected.is_hit() {
                assert!(
                    expected.tri == got.tri || (expected.t - got.t).abs() <= 1e-5 * expected.t,
                    "ray {k}: {expected:?} vs {got:?}"
                );
            }
        }
        assert!(hits >= count / 2, "only {hits} of {count} rays hit");
    }

    fn leaf_sizes_ok(bvh: &Bvh, params: &SahParams) {
        for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            assert!(node.prim_count() <= params.max_leaf_size.max(1));
        }
    }

    #[test]
    fn random_soups_are_valid_and_traced_exactly() {
        let params = SahParams::default();
        for (seed, &n) in [1usize, 2, 3, 17, 1000, 5000].iter().enumerate() {
            let tris = soup(n, 0.01, seed as u64);
            let bvh = build_sbvh(&tris, &params);
            let stats =
                validate_with_references(&bvh, &tris).unwrap_or_else(|e| panic!("n = {n}: {e}"));
            assert_eq!(stats.nodes, bvh.nodes.len());
            leaf_sizes_ok(&bvh, &params);
            assert!(bvh.prim_indices.len() <= 3 * n);
            // Depth-first layout: an internal node's left child follows it.
            for (i, node) in bvh.nodes.iter().enumerate() {
                if !node.is_leaf() {
                    assert_eq!(node.children().0 as usize, i + 1);
                }
            }
            let cost = sah_cost(&bvh, &params);
            assert!(cost.is_finite() && cost > 0.0, "n = {n}: cost {cost}");
            assert_traversal_matches(&bvh, &tris, 300, seed as u64);
        }
    }

    #[test]
    fn large_triangles_get_spatial_splits_and_a_lower_sah_than_sweep() {
        let params = SahParams::default();
        let tris = soup(2000, 0.05, 11);
        let sbvh = build_sbvh(&tris, &params);
        validate_with_references(&sbvh, &tris).unwrap();
        assert!(sbvh.prim_indices.len() > tris.len());
        let sweep = build_sweep_sah(&tris, &params);
        let (a, b) = (sah_cost(&sbvh, &params), sah_cost(&sweep, &params));
        assert!(a < b, "sbvh {a} vs sweep {b}");
        assert_traversal_matches(&sbvh, &tris, 1000, 3);
    }

    #[test]
    fn fan_of_slivers_is_split_and_traced_exactly() {
        let params = SahParams::default();
        let tris = fan(500);
        let bvh = build_sbvh(&tris, &params);
        validate_with_references(&bvh, &tris).unwrap();
        assert!(
            bvh.prim_indices.len() > 2 * tris.len(),
            "{} references",
            bvh.prim_indices.len()
        );
        assert!(bvh.prim_indices.len() <= 3 * tris.len());
        // Leaf boxes lie inside the triangles' boxes (they bound clipped parts).
        for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            let first = node.left_or_first as usize;
            let tris_box = bvh.prim_indices[first..first + node.prim_count() as usize]
                .iter()
                .fold(Aabb::EMPTY, |b, &t| b.union(tris[t as usize].bounds()));
            assert!(tris_box.contains(&node.bounds(), 0.0));
        }
        let sweep = build_sweep_sah(&tris, &params);
        let (a, b) = (sah_cost(&bvh, &params), sah_cost(&sweep, &params));
        assert!(a < 0.7 * b, "sbvh {a} vs sweep {b}");
        assert_traversal_matches(&bvh, &tris, 2000, 4);
    }

    #[test]
    fn small_triangles_give_the_sweep_tree() {
        // Tiny, well separated triangles: no overlap worth a spatial split anywhere.
        let params = SahParams::default();
        let tris: Vec<Triangle> = (0..512)
            .map(|i| {
                let o = Vec3::new((i % 8) as f32, ((i / 8) % 8) as f32, (i / 64) as f32);
                Triangle::new(
                    o,
                    o + Vec3::new(0.1, 0.0, 0.0),
                    o + Vec3::new(0.0, 0.1, 0.1),
                    0,
                )
            })
            .collect();
        let sbvh = build_sbvh(&tris, &params);
        let sweep = build_sweep_sah(&tris, &params);
        validate(&sbvh, &tris).unwrap();
        assert_eq!(sbvh, sweep);
    }

    #[test]
    fn degenerate_inputs_are_handled() {
        let params = SahParams::default();
        assert_eq!(build_sbvh(&[], &params), Bvh::default());
        let a = Vec3::ZERO;
        let cases: Vec<(&str, Vec<Triangle>)> = vec![
            // The same triangle 40 times: all centroids and boxes equal.
            ("identical", vec![Triangle::new(a, Vec3::X, Vec3::Y, 0); 40]),
            // Large triangles all centred on the origin (a star): no object split exists.
            (
                "star",
                (0..40)
                    .map(|i| {
                        let t = i as f32 * 0.157;
                        let d = Vec3::new(t.cos(), t.sin(), 0.2 * t.sin());
                        let e = Vec3::new(-t.sin(), t.cos(), 0.5) * 0.05;
                        Triangle::new(-d - e, d - e, 2.0 * e, 0)
                    })
                    .collect(),
            ),
            // Flat: all in the plane z = 0, long diagonal slivers.
            (
                "flat",
                (0..200)
                    .map(|i| {
                        let o = Vec3::new(i as f32 * 0.01, 0.0, 0.0);
                        Triangle::new(
                            o,
                            o + Vec3::new(1.0, 1.0, 0.0),
                            o + Vec3::new(1.01, 1.0, 0.0),
                            0,
                        )
                    })
                    .collect(),
            ),
            // Degenerate (collinear or point) triangles mixed with a real one.
            (
                "collinear",
                (0..30)
                    .map(|i| {
                        let o = Vec3::splat(i as f32 * 0.1);
                        match i % 3 {
                            0 => Triangle::new(o, o + Vec3::ONE, o + 2.0 * Vec3::ONE, 0),
                            1 => Triangle::new(o, o, o, 0),
                            _ => Triangle::new(o, o + Vec3::X, o + Vec3::Y, 0),
                        }
                    })
                    .collect(),
            ),
            // Far from the origin with tiny extents.
            (
                "far",
                soup(300, 0.01, 5)
                    .into_iter()
                    .map(|t| {
                        let [p, q, r] = t.vertices().map(|v| v * 1e-3 + Vec3::splat(1e5));
                        Triangle::new(p, q, r, 0)
                    })
                    .collect(),
            ),
        ];
        for max_leaf_size in [0, 1, 4, 8] {
            let params = SahParams {
                max_leaf_size,
                ..params
            };
            for (name, tris) in &cases {
                let bvh = build_sbvh(tris, &params);
                validate_with_references(&bvh, tris).unwrap_or_else(|e| panic!("{name}: {e}"));
                leaf_sizes_ok(&bvh, &params);
                assert!(bvh.prim_indices.len() <= 3 * tris.len(), "{name}");
                assert!(sah_cost(&bvh, &params).is_finite(), "{name}");
            }
        }
    }

    #[test]
    fn clipping_bounds_the_part_inside_the_box() {
        // Right triangle (0,0,0), (2,0,0), (0,2,0); clipped to x ≤ 1 and to x ≥ 1.
        let t = Triangle::new(
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            0,
        );
        let r = Reference {
            bounds: t.bounds(),
            tri: 0,
        };
        let (left, right) = split_reference(&t, &r, 0, 1.0);
        let (left, right) = (left.unwrap(), right.unwrap());
        assert_eq!(left.min, Vec3::ZERO);
        assert_eq!(left.max, Vec3::new(1.0, 2.0, 0.0));
        assert_eq!(right.min, Vec3::new(1.0, 0.0, 0.0));
        // The part right of x = 1 reaches y = 1 only (rounded outward by at most an ulp).
        assert!(right.max.y >= 1.0 && right.max.y < 1.0 + 1e-6, "{right:?}");
        assert_eq!(right.max.x, 2.0);
        // A plane the triangle only touches gives one side.
        let (left, right) = split_reference(&t, &r, 1, 2.0);
        assert!(left.is_some() && right.is_none());
        // Clipping to a reference box keeps the part inside it: x ∈ [1, 2] clipped at y = 0.5.
        let r = Reference {
            bounds: Aabb::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)),
            tri: 0,
        };
        let (below, above) = split_reference(&t, &r, 1, 0.5);
        let (below, above) = (below.unwrap(), above.unwrap());
        assert_eq!(below.max.x, 2.0);
        assert!(above.max.x >= 1.5 && above.max.x < 1.5 + 1e-6, "{above:?}");
        assert_eq!((above.min.y, below.max.y), (0.5, 0.5));
    }

    #[test]
    fn rounding_is_outward() {
        let v = DVec3::new(0.1, -0.1, 1.0);
        let (lo, hi) = (round_down(v), round_up(v));
        for a in 0..3 {
            assert!(f64::from(lo[a]) <= v[a] && f64::from(hi[a]) >= v[a]);
            assert!(hi[a] == lo[a] || hi[a] == lo[a].next_up());
        }
        assert_eq!(lo.z, 1.0);
        assert_eq!(hi.z, 1.0);
    }
}
