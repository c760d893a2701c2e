//! CPU twin of triangle pre-splitting (Karras & Aila 2013, §5; kernels `triangles_priority.wgsl`,
//! `splits_search.wgsl`, `triangles_split.wgsl`): the same float operations in the same order.
//! GPUs may fuse products into adds and divide approximately, so priorities and piece boxes agree
//! with the kernels' to rounding; split counts from the same priorities and scale agree exactly.

use glam::{UVec3, Vec3};

use crate::geometry::Aabb;
use crate::gpu::constants::{MAX_SPLITS, MORTON_GRID};
use crate::scene::Triangle;

/// Bisection steps of the budget search.
/// Halvings of the CPU twin's search: 32 span every bit pattern below 2^32.
const BISECTION_STEPS: u32 = 32;
const GRID: f32 = MORTON_GRID as f32;
const GRID_MAX: f32 = (MORTON_GRID - 1) as f32;

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

/// The importance exponent of a triangle's priority: i = b/3 − 20 ≤ 0 for the highest differing
/// Morton bit b of its box corners' cells; None when the box lies in one cell.
pub fn split_importance(t: &Triangle, grid: &SplitGrid) -> Option<i32> {
    let b = t.bounds();
    let (first, last) = grid.cell_range(b.min, b.max);
    highest_differing_bit(first, last).map(|bit| (bit / 3) as i32 - 20)
}

/// q = p³ of one triangle (see `triangles_priority.wgsl`).
pub fn split_priority(t: &Triangle, grid: &SplitGrid) -> f32 {
    let Some(importance) = split_importance(t, grid) else {
        return 0.0;
    };
    let [v0, v1, v2] = t.vertices();
    let (lo, hi) = (v0.min(v1.min(v2)), v0.max(v1.max(v2)));
    let (d1, d2) = (v1 - v0, v2 - v0);
    let c = Vec3::new(
        d1.y * d2.z - d1.z * d2.y,
        d1.z * d2.x - d1.x * d2.z,
        d1.x * d2.y - d1.y * d2.x,
    );
    let ideal = c.x.abs() + c.y.abs() + c.z.abs();
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

/// E = D³ of the budget search: the largest bit pattern below hi = (budget + 1)³ / q_max whose
/// split sum fits the budget (non-negative floats order like their bits). Found here by bisection
/// on the bit patterns (integer midpoints halve the interval exactly, and 32 halvings span every
/// float from 0 to hi); `splits_count.wgsl` finds the same E by a 256-ary search.
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

/// The boxes of triangle `t`'s parts below and above the plane at `position` on `axis`, each
/// intersected with its side box ([lo, below_hi] and [above_lo, hi]), or None for a side they
/// miss: vertices extend the side(s) they lie on (both when on the plane), each edge crossing
/// the plane extends both by its crossing point. See `add_edge` in `triangles_split.wgsl`.
fn split_sides(
    t: &Triangle,
    axis: usize,
    position: f32,
    (lo, below_hi): (Vec3, Vec3),
    (above_lo, hi): (Vec3, Vec3),
) -> [Option<(Vec3, Vec3)>; 2] {
    let empty = (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
    let (mut below, mut above) = (empty, empty);
    let extend = |side: &mut (Vec3, Vec3), p: Vec3| *side = (side.0.min(p), side.1.max(p));
    let [v0, v1, v2] = t.vertices();
    for (a, b) in [(v0, v1), (v1, v2), (v2, v0)] {
        let (ax, bx) = (a[axis], b[axis]);
        if ax <= position {
            extend(&mut below, a);
        }
        if ax >= position {
            extend(&mut above, a);
        }
        if (ax < position && bx > position) || (ax > position && bx < position) {
            let s = (position - ax) / (bx - ax);
            let mut p = a + Vec3::new(s * (b.x - a.x), s * (b.y - a.y), s * (b.z - a.z));
            p[axis] = position;
            extend(&mut below, p);
            extend(&mut above, p);
        }
    }
    let within = |(plo, phi): (Vec3, Vec3), side_lo: Vec3, side_hi: Vec3| {
        let misses = plo.cmpgt(side_hi).any() || phi.cmplt(side_lo).any();
        (!misses).then(|| (plo.clamp(side_lo, side_hi), phi.clamp(side_lo, side_hi)))
    };
    [within(below, lo, below_hi), within(above, above_lo, hi)]
}

/// A piece of a triangle being split: its box, the grid cells it covers on each axis (integers,
/// so that a side cut at a grid plane ends exactly at that plane's cell whatever the rounding of
/// the plane's position), and the references it still owes.
#[derive(Clone, Copy)]
struct Piece {
    lo: Vec3,
    hi: Vec3,
    first: UVec3,
    last: UVec3,
    pieces: u32,
}

impl Piece {
    /// The piece of box [lo, hi] within the cells [first, last] of its parent.
    fn within(
        grid: &SplitGrid,
        (lo, hi): (Vec3, Vec3),
        first: UVec3,
        last: UVec3,
        pieces: u32,
    ) -> Self {
        let (f, l) = grid.cell_range(lo, hi);
        let f = f.clamp(first, last);
        let l = l.clamp(f, last);
        Self {
            lo,
            hi,
            first: f,
            last: l,
            pieces,
        }
    }

    /// Extent in cells along the piece's longest axis.
    fn cells(&self) -> u32 {
        (self.last - self.first + UVec3::ONE).max_element()
    }
}

/// The split plane of a piece as (axis, cell, position), skipping the axes in `tried` (a bit
/// mask): on each axis, the grid plane of the highest bit in which the first and last covered
/// cells differ (the coarsest Morton-grid plane crossing the piece on that axis; cells below
/// `cell` lie left of it); of the planes inside the piece box by more than a cell on both sides,
/// the one of the highest level, ties in Morton bit order (x, y, z). None when no such plane
/// crosses the piece. See `split_plane` in `triangles_split.wgsl`.
fn split_plane(grid: &SplitGrid, piece: &Piece, tried: u32) -> Option<(usize, u32, f32)> {
    let mut best: Option<(u32, usize, u32, f32)> = None;
    for axis in 0..3 {
        let differing = piece.first[axis] ^ piece.last[axis];
        if tried & (1 << axis) != 0 {
            continue;
        }
        if differing == 0 {
            continue;
        }
        let level = 31 - differing.leading_zeros();
        let cell = (piece.last[axis] >> level) << level;
        let plane = grid.scene_min[axis] + cell as f32 * grid.cell;
        let inside = piece.lo[axis] < plane - grid.cell && plane + grid.cell < piece.hi[axis];
        if inside && best.is_none_or(|(l, ..)| level > l) {
            best = Some((level, axis, cell, plane));
        }
    }
    best.map(|(_, axis, cell, plane)| (axis, cell, plane))
}

/// The `pieces` reference boxes of triangle `t` (see `triangles_split.wgsl`).
pub fn split_triangle(t: &Triangle, pieces: u32, grid: &SplitGrid) -> Vec<Aabb> {
    let mut out = Vec::with_capacity(pieces as usize);
    let b = t.bounds();
    let (first, last) = grid.cell_range(b.min, b.max);
    let mut stack = vec![Piece::within(grid, (b.min, b.max), first, last, pieces)];
    while let Some(piece) = stack.pop() {
        let mut halves = None;
        // A plane whose cut leaves one side empty (the piece only grazes it, by rounding) gives
        // way to the next candidate.
        let mut tried = if piece.pieces > 1 { 0 } else { 0b111 };
        while halves.is_none() {
            let Some((axis, cell, plane)) = split_plane(grid, &piece, tried) else {
                break;
            };
            tried |= 1 << axis;
            let (mut left_hi, mut right_lo) = (piece.hi, piece.lo);
            left_hi[axis] = plane;
            right_lo[axis] = plane;
            if let [Some(l), Some(r)] =
                split_sides(t, axis, plane, (piece.lo, left_hi), (right_lo, piece.hi))
            {
                let (mut below, mut above) = (piece.last, piece.first);
                below[axis] = cell - 1;
                above[axis] = cell;
                let left = Piece::within(grid, l, piece.first, below, 0);
                let right = Piece::within(grid, r, above, piece.last, 0);
                halves = Some((left, right));
            }
        }
        match halves {
            Some((mut left, mut right)) => {
                // Shared by extent in cells, rounded half up: integers, the same on every device.
                let n = piece.pieces;
                let (wl, wr) = (left.cells(), right.cells());
                let nl = ((2 * n * wl + wl + wr) / (2 * (wl + wr))).clamp(1, n - 1);
                left.pieces = nl;
                right.pieces = n - nl;
                stack.push(right);
                stack.push(left);
            }
            None => out.extend((0..piece.pieces).map(|_| Aabb::new(piece.lo, piece.hi))),
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
