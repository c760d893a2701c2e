//! CPU twin of triangle pre-splitting (Karras & Aila 2013, §5; kernels `triangles_priority.wgsl`,
//! `splits_budget.wgsl`, `triangles_split.wgsl`): the same float operations in the same order, so
//! split counts match the GPU exactly and boxes to rounding.

use glam::{UVec3, Vec3};

use crate::geometry::Aabb;
use crate::scene::Triangle;

/// Splits per triangle at most (pieces = splits + 1 ≤ 32).
pub const MAX_SPLITS: u32 = 31;
/// Bisection steps of the budget search.
pub const BISECTION_STEPS: u32 = 32;
const GRID: f32 = 2_097_152.0;
const GRID_MAX: f32 = 2_097_151.0;

/// The cubic Morton grid over the scene box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitGrid {
    pub scene_min: Vec3,
    /// Cells per unit.
    pub scale: f32,
    /// Units per cell.
    pub cell: f32,
}

impl SplitGrid {
    pub fn new(scene: &Aabb) -> Self {
        let extent = (scene.max - scene.min).max_element();
        let (scale, cell) = if extent > 0.0 {
            (GRID / extent, extent / GRID)
        } else {
            (0.0, 0.0)
        };
        Self {
            scene_min: scene.min,
            scale,
            cell,
        }
    }

    /// The first and last grid cells a box [lo, hi] overlaps on each axis. The last is the cell
    /// below hi when hi lies exactly on a cell boundary (a piece cut at a grid plane does not
    /// reach into the next cell). See `cell_range` in `split_grid.wgsl`.
    fn cell_range(&self, lo: Vec3, hi: Vec3) -> (UVec3, UVec3) {
        let first = ((lo - self.scene_min) * self.scale)
            .floor()
            .clamp(Vec3::ZERO, Vec3::splat(GRID_MAX));
        let last = (((hi - self.scene_min) * self.scale).ceil() - Vec3::ONE)
            .clamp(Vec3::ZERO, Vec3::splat(GRID_MAX))
            .max(first);
        (first.as_uvec3(), last.as_uvec3())
    }
}

/// Highest differing Morton bit of two grid points (see `split_grid.wgsl`).
fn highest_differing_bit(a: UVec3, b: UVec3) -> Option<u32> {
    (0..3)
        .filter_map(|axis| {
            let x = a[axis] ^ b[axis];
            (x != 0).then(|| 3 * (31 - x.leading_zeros()) + 2 - axis as u32)
        })
        .max()
}

fn box_area(lo: Vec3, hi: Vec3) -> f32 {
    let e = hi - lo;
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

/// q = p³ of one triangle (see `triangles_priority.wgsl`).
pub fn split_priority(t: &Triangle, grid: &SplitGrid) -> f32 {
    let [v0, v1, v2] = t.vertices();
    let (lo, hi) = (v0.min(v1.min(v2)), v0.max(v1.max(v2)));
    let (first, last) = grid.cell_range(lo, hi);
    let Some(bit) = highest_differing_bit(first, last) else {
        return 0.0;
    };
    let (d1, d2) = (v1 - v0, v2 - v0);
    let c = Vec3::new(
        d1.y * d2.z - d1.z * d2.y,
        d1.z * d2.x - d1.x * d2.z,
        d1.x * d2.y - d1.y * d2.x,
    );
    let ideal = c.x.abs() + c.y.abs() + c.z.abs();
    let importance = (bit / 3) as i32 - 20;
    (box_area(lo, hi) - ideal).max(0.0) * 2f32.powi(importance)
}

/// The largest k ≤ MAX_SPLITS with k³ ≤ e·q.
pub fn splits_at(e: f32, q: f32) -> u32 {
    let target = e * q;
    let mut k = 0u32;
    while k < MAX_SPLITS {
        let next = (k + 1) as f32;
        if next * next * next > target {
            break;
        }
        k += 1;
    }
    k
}

/// E = D³ of the budget search: the bisection of `splits_budget.wgsl`, on the bit patterns of E
/// (non-negative floats order like their bits, so integer midpoints halve the interval exactly
/// and 32 halvings span every float from 0 to the upper bound).
pub fn budget_scale(priorities: &[f32], budget: u32) -> f32 {
    let q_max = priorities.iter().copied().fold(0.0f32, f32::max);
    let b = (budget + 1) as f32;
    let hi0 = if q_max > 0.0 { b * b * b / q_max } else { 0.0 };
    let (mut lo, mut hi) = (0u32, hi0.to_bits());
    let mut mid = hi / 2;
    for _ in 0..BISECTION_STEPS {
        let e = f32::from_bits(mid);
        let sum: u64 = priorities.iter().map(|&q| u64::from(splits_at(e, q))).sum();
        if sum <= u64::from(budget) {
            lo = mid;
        } else {
            hi = mid;
        }
        mid = lo + (hi - lo) / 2;
    }
    f32::from_bits(lo)
}

/// The box of triangle `t` clipped to [lo, hi] (Sutherland–Hodgman), or None if nothing is left.
fn clip_triangle(t: &Triangle, lo: Vec3, hi: Vec3) -> Option<(Vec3, Vec3)> {
    let mut poly: Vec<Vec3> = t.vertices().to_vec();
    for plane in 0..6 {
        let axis = plane % 3;
        let keep_below = plane >= 3;
        let bound = if keep_below { hi[axis] } else { lo[axis] };
        let inside = |p: Vec3| {
            if keep_below {
                p[axis] <= bound
            } else {
                p[axis] >= bound
            }
        };
        let mut next = Vec::with_capacity(9);
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            if inside(a) && next.len() < 9 {
                next.push(a);
            }
            if inside(a) != inside(b) && next.len() < 9 {
                let s = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut p = a + Vec3::new(s * (b.x - a.x), s * (b.y - a.y), s * (b.z - a.z));
                p[axis] = bound;
                next.push(p);
            }
        }
        poly = next;
    }
    if poly.is_empty() {
        return None;
    }
    let (mut plo, mut phi) = (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
    for p in &poly {
        plo = plo.min(*p);
        phi = phi.max(*p);
    }
    Some((plo.clamp(lo, hi), phi.clamp(lo, hi)))
}

/// The split plane of a piece box [lo, hi] as (axis, position): on each axis, the grid plane of
/// the highest bit in which the first and last overlapped cells differ (the coarsest Morton-grid
/// plane crossing the box on that axis); of the planes strictly inside the box, the one of the
/// highest level, ties in Morton bit order (x, y, z). None when no grid plane crosses the box.
/// See `split_plane` in `triangles_split.wgsl`.
fn split_plane(grid: &SplitGrid, lo: Vec3, hi: Vec3) -> Option<(usize, f32)> {
    let (first, last) = grid.cell_range(lo, hi);
    let mut best: Option<(u32, usize, f32)> = None;
    for axis in 0..3 {
        let differing = first[axis] ^ last[axis];
        if differing == 0 {
            continue;
        }
        let level = 31 - differing.leading_zeros();
        let cells = ((last[axis] >> level) << level) as f32;
        let plane = grid.scene_min[axis] + cells * grid.cell;
        let inside = lo[axis] < plane && plane < hi[axis];
        if inside && best.is_none_or(|(l, _, _)| level > l) {
            best = Some((level, axis, plane));
        }
    }
    best.map(|(_, axis, plane)| (axis, plane))
}

/// The `pieces` reference boxes of triangle `t` (see `triangles_split.wgsl`).
pub fn split_triangle(t: &Triangle, pieces: u32, grid: &SplitGrid) -> Vec<Aabb> {
    const MAX_PIECES: usize = 32;
    let mut out = Vec::with_capacity(pieces as usize);
    let [v0, v1, v2] = t.vertices();
    let mut stack = vec![(v0.min(v1.min(v2)), v0.max(v1.max(v2)), pieces)];
    while let Some((lo, hi, n)) = stack.pop() {
        let mut halves = None;
        if n > 1 && stack.len() + 2 <= MAX_PIECES {
            if let Some((axis, plane)) = split_plane(grid, lo, hi) {
                let (mut left_hi, mut right_lo) = (hi, lo);
                left_hi[axis] = plane;
                right_lo[axis] = plane;
                if let (Some(l), Some(r)) = (
                    clip_triangle(t, lo, left_hi),
                    clip_triangle(t, right_lo, hi),
                ) {
                    halves = Some((l, r));
                }
            }
        }
        match halves {
            Some((l, r)) => {
                let (wl, wr) = ((l.1 - l.0).max_element(), (r.1 - r.0).max_element());
                let share = if wl + wr > 0.0 { wl / (wl + wr) } else { 0.5 };
                let nl = ((n as f32 * share).round_ties_even() as u32).clamp(1, n - 1);
                stack.push((r.0, r.1, n - nl));
                stack.push((l.0, l.1, nl));
            }
            None => out.extend((0..n).map(|_| Aabb::new(lo, hi))),
        }
    }
    out
}

/// The whole pre-splitting stage on the CPU: reference boxes and each reference's triangle, in
/// triangle order, with at most `budget` extra references.
pub fn presplit_cpu(triangles: &[Triangle], budget: u32) -> (Vec<Aabb>, Vec<u32>) {
    let scene = triangles
        .iter()
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let grid = SplitGrid::new(&scene);
    let priorities: Vec<f32> = triangles.iter().map(|t| split_priority(t, &grid)).collect();
    let e = budget_scale(&priorities, budget);
    let mut boxes = Vec::new();
    let mut tris = Vec::new();
    for (i, (t, &q)) in triangles.iter().zip(&priorities).enumerate() {
        let pieces = splits_at(e, q) + 1;
        for b in split_triangle(t, pieces, &grid) {
            boxes.push(b);
            tris.push(i as u32);
        }
    }
    (boxes, tris)
}
