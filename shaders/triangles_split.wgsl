// Pre-splitting step 3 (Karras & Aila 2013, §5): each triangle becomes its s_t + 1 references.
// Pieces are split recursively at the coarsest Morton-grid plane crossing the piece (see
// `split_plane`; planes on the power-of-two subdivision of the scene's cubic grid, so neighbouring
// triangles' splits agree). A piece carries the grid cells it covers as integers: the side cut at
// a plane ends exactly at that plane's cell, whatever the rounding of the plane's position and of
// the grid scale (a float cell range would put a side that ends on the plane into the next cell on
// some devices, and the piece would then be "split" at its own side again, emitting copies of one
// box). Each side is the box of the triangle clipped to the piece box on that side
// (Sutherland–Hodgman), and the remaining pieces are shared by the sides' extents in cells (integer
// arithmetic, rounded half up). A piece that cannot be split (inside one grid cell, or clipping
// leaves a side empty) is emitted as often as it still owes references, so every triangle writes
// exactly its count. Writes the reference boxes and each reference's triangle, at the triangle's
// scanned offset. CPU twin: `split_triangle`.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
// The exclusive scan of the reference counts, block by block (sort::PrefixScan's block-local
// scan), and the scanned block totals: see `first_reference`.
@group(0) @binding(2) var<storage, read> ref_offsets: array<u32>;
@group(0) @binding(3) var<storage, read> block_offsets: array<u32>;
// [0]: total references
@group(0) @binding(4) var<storage, read> ref_total: array<u32>;
@group(0) @binding(5) var<storage, read_write> prim_boxes: array<Aabb>;
@group(0) @binding(6) var<storage, read_write> ref_tris: array<u32>;

// The scene box as box words (box_words.wgsl).
@group(0) @binding(7) var<storage, read> scene_bounds: array<vec4<u32>>;

// The first reference of triangle i.
fn first_reference(i: u32) -> u32 {
    return ref_offsets[i] + block_offsets[i / SCAN_BLOCK];
}

#include "split_grid.wgsl"

const MAX_PIECES: u32 = 32u;
const MAX_POLYGON: u32 = 9u;

struct Piece {
    lo: vec3<f32>,
    hi: vec3<f32>,
    first: vec3<u32>,
    last: vec3<u32>,
    pieces: u32,
}

// The piece of box [lo, hi] within the cells [first, last] of its parent.
fn piece_within(grid: SplitGrid, lo: vec3<f32>, hi: vec3<f32>, first: vec3<u32>, last: vec3<u32>, pieces: u32) -> Piece {
    let cells = cell_range(grid, lo, hi);
    let f = clamp(cells.first, first, last);
    let l = clamp(cells.last, f, last);
    return Piece(lo, hi, f, l, pieces);
}

// Extent in cells along the piece's longest axis.
fn piece_cells(p: Piece) -> u32 {
    let e = p.last - p.first + vec3<u32>(1u);
    return max(e.x, max(e.y, e.z));
}

struct Clipped {
    lo: vec3<f32>,
    hi: vec3<f32>,
    empty: bool,
}

// Whether coordinate v lies on the side of a clip plane at `bound` that is kept (below it, or
// above it), the plane included.
fn on_kept_side(v: f32, bound: f32, keep_below: bool) -> bool {
    return select(v >= bound, v <= bound, keep_below);
}

// Box of the triangle clipped to [lo, hi], intersected with [lo, hi]. Sutherland–Hodgman over
// the six planes, the polygon alternating between the two halves of `poly` (no copy back). A plane
// that keeps every vertex leaves the polygon as it is and is skipped; one that keeps none empties
// it. Both give what the full clip gives (the CPU twin's `clip_triangle`), without its work.
fn clip_triangle(t: Triangle, lo: vec3<f32>, hi: vec3<f32>) -> Clipped {
    var poly: array<vec3<f32>, 2u * MAX_POLYGON>;
    poly[0] = t.v0;
    poly[1] = t.v1;
    poly[2] = t.v2;
    var n = 3u;
    var src = 0u;
    for (var plane = 0u; plane < 6u && n > 0u; plane++) {
        let axis = plane % 3u;
        let keep_below = plane >= 3u;
        let bound = select(lo[axis], hi[axis], keep_below);
        var kept = 0u;
        for (var k = 0u; k < n; k++) {
            let v = poly[src + k][axis];
            kept += select(0u, 1u, on_kept_side(v, bound, keep_below));
        }
        if kept == n {
            continue;
        }
        let dst = MAX_POLYGON - src;
        var m = 0u;
        if kept != 0u {
            for (var k = 0u; k < n; k++) {
                let a = poly[src + k];
                let b = poly[src + select(k + 1u, 0u, k + 1u == n)];
                let a_in = on_kept_side(a[axis], bound, keep_below);
                let b_in = on_kept_side(b[axis], bound, keep_below);
                if a_in && m < MAX_POLYGON {
                    poly[dst + m] = a;
                    m++;
                }
                if a_in != b_in && m < MAX_POLYGON {
                    let s = (bound - a[axis]) / (b[axis] - a[axis]);
                    var p = a + vec3<f32>(s * (b.x - a.x), s * (b.y - a.y), s * (b.z - a.z));
                    p[axis] = bound;
                    poly[dst + m] = p;
                    m++;
                }
            }
        }
        n = m;
        src = dst;
    }
    var out = Clipped(vec3<f32>(F32_MAX), vec3<f32>(-F32_MAX), n == 0u);
    for (var k = 0u; k < n; k++) {
        out.lo = min(out.lo, poly[src + k]);
        out.hi = max(out.hi, poly[src + k]);
    }
    out.lo = clamp(out.lo, lo, hi);
    out.hi = clamp(out.hi, lo, hi);
    return out;
}

const NO_AXIS: u32 = 3u;

struct SplitPlane {
    // NO_AXIS when no grid plane crosses the piece.
    axis: u32,
    // Cells below `cell` lie left of the plane.
    cell: u32,
    position: f32,
}

// The split plane of a piece, skipping the axes in `tried` (a bit mask): on each axis, the grid
// plane of the highest bit in which the first and last covered cells differ (the coarsest
// Morton-grid plane crossing the piece on that axis); of the planes inside the piece box by more
// than a cell on both sides, the one of the highest level, ties in Morton bit order (x, y, z). A
// side thinner than a cell is not worth a reference, and the margin keeps the choice from turning
// on rounding: the grid's 2^21 cells per axis are near the precision of the coordinates, so a
// piece that ends on a plane (mathematically) may end a fraction of a cell beyond it.
fn split_plane(grid: SplitGrid, p: Piece, tried: u32) -> SplitPlane {
    var best = SplitPlane(NO_AXIS, 0u, 0.0);
    var best_level = 0u;
    for (var axis = 0u; axis < 3u; axis++) {
        let differing = p.first[axis] ^ p.last[axis];
        if differing == 0u || (tried & (1u << axis)) != 0u {
            continue;
        }
        let level = 31u - countLeadingZeros(differing);
        let cell = (p.last[axis] >> level) << level;
        let position = grid.scene_min[axis] + f32(cell) * grid.cell;
        let inside = p.lo[axis] < position - grid.cell && position + grid.cell < p.hi[axis];
        if inside && (best.axis == NO_AXIS || level > best_level) {
            best = SplitPlane(axis, cell, position);
            best_level = level;
        }
    }
    return best;
}

// Splits triangle i (box [lo, hi], covering `cells`) into the references first_out .. end - 1.
// A function of its own, called only for a triangle of several references, so that the others
// do not pay for its piece stack (2 KiB per invocation, zero-initialized as every WGSL `var`).
fn split_triangle(grid: SplitGrid, i: u32, t: Triangle, lo: vec3<f32>, hi: vec3<f32>, cells: CellRange, first_out: u32, end: u32) {
    var out = first_out;
    var stack: array<Piece, MAX_PIECES>;
    stack[0] = piece_within(grid, lo, hi, cells.first, cells.last, end - out);
    var sp = 1u;
    while sp > 0u {
        sp--;
        let piece = stack[sp];
        // A plane whose cut leaves one side empty (the piece only grazes it, by rounding) gives
        // way to the next candidate.
        var split = false;
        var tried = select(7u, 0u, piece.pieces > 1u && sp + 2u <= MAX_PIECES);
        var plane = SplitPlane(NO_AXIS, 0u, 0.0);
        var left = Clipped(piece.lo, piece.hi, false);
        var right = left;
        while !split {
            plane = split_plane(grid, piece, tried);
            if plane.axis == NO_AXIS {
                break;
            }
            tried |= 1u << plane.axis;
            var left_hi = piece.hi;
            left_hi[plane.axis] = plane.position;
            var right_lo = piece.lo;
            right_lo[plane.axis] = plane.position;
            left = clip_triangle(t, piece.lo, left_hi);
            right = clip_triangle(t, right_lo, piece.hi);
            split = !left.empty && !right.empty;
        }
        if split {
            var below = piece.last;
            below[plane.axis] = plane.cell - 1u;
            var above = piece.first;
            above[plane.axis] = plane.cell;
            var l = piece_within(grid, left.lo, left.hi, piece.first, below, 0u);
            var r = piece_within(grid, right.lo, right.hi, above, piece.last, 0u);
            // Shared by extent in cells, rounded half up.
            let n = piece.pieces;
            let wl = piece_cells(l);
            let wr = piece_cells(r);
            let nl = clamp((2u * n * wl + wl + wr) / (2u * (wl + wr)), 1u, n - 1u);
            l.pieces = nl;
            r.pieces = n - nl;
            stack[sp] = r;
            stack[sp + 1u] = l;
            sp += 2u;
        } else {
            for (var k = 0u; k < piece.pieces && out < end; k++) {
                prim_boxes[out] = Aabb(piece.lo, 0u, piece.hi, 0u);
                ref_tris[out] = i;
                out++;
            }
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= params.count {
        return;
    }
    let t = triangles[i];
    let out = first_reference(i);
    var end = ref_total[0];
    if i + 1u < params.count {
        end = first_reference(i + 1u);
    }
    let lo = min(t.v0, min(t.v1, t.v2));
    let hi = max(t.v0, max(t.v1, t.v2));
    if end - out == 1u {
        // Unsplit: the triangle's box (what the piece loop emits for a single piece).
        prim_boxes[out] = Aabb(lo, 0u, hi, 0u);
        ref_tris[out] = i;
        return;
    }
    let grid = split_grid();
    split_triangle(grid, i, t, lo, hi, cell_range(grid, lo, hi), out, end);
}
