// Pre-splitting step 3 (Karras & Aila 2013, §5): each triangle becomes its s_t + 1 references.
// Pieces are split recursively at the coarsest Morton-grid plane crossing the piece box (see
// `split_plane`; planes on the power-of-two subdivision of the scene's cubic grid, so neighbouring
// triangles' splits agree). Only planes strictly inside the box count: a piece whose side was cut
// at a plane must not be "split" there again, which would emit copies of the same box. Each side
// is the box of the triangle clipped to the piece box on that side (Sutherland–Hodgman), and the
// remaining pieces are shared by the two sides' extents. A piece that cannot be split (inside one
// grid cell, or clipping leaves a side empty) is emitted as often as it still owes references, so
// every triangle writes exactly its count. Writes the reference boxes and each reference's
// triangle, at the triangle's scanned offset.
#include "bvh_node.wgsl"
#include "aabb.wgsl"

struct SplitParams {
    count: u32,
    row_pitch: u32,
    zero: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: SplitParams;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> ref_offsets: array<u32>;
// [0]: total references
@group(0) @binding(3) var<storage, read> ref_total: array<u32>;
@group(0) @binding(4) var<storage, read_write> prim_boxes: array<Aabb>;
@group(0) @binding(5) var<storage, read_write> ref_tris: array<u32>;

// [0]: the scene box
@group(0) @binding(6) var<storage, read> scene_bounds: array<Aabb>;

#include "split_grid.wgsl"

const MAX_PIECES: u32 = 32u;
const MAX_POLYGON: u32 = 9u;

struct Piece {
    lo: vec3<f32>,
    hi: vec3<f32>,
    pieces: u32,
}

struct Clipped {
    lo: vec3<f32>,
    hi: vec3<f32>,
    empty: bool,
}

// Box of the triangle clipped to [lo, hi], intersected with [lo, hi].
fn clip_triangle(t: Triangle, lo: vec3<f32>, hi: vec3<f32>) -> Clipped {
    var poly: array<vec3<f32>, MAX_POLYGON>;
    var next: array<vec3<f32>, MAX_POLYGON>;
    poly[0] = t.v0;
    poly[1] = t.v1;
    poly[2] = t.v2;
    var n = 3u;
    for (var plane = 0u; plane < 6u; plane++) {
        let axis = plane % 3u;
        let keep_below = plane >= 3u;
        let bound = select(lo[axis], hi[axis], keep_below);
        var m = 0u;
        for (var k = 0u; k < n; k++) {
            let a = poly[k];
            let b = poly[(k + 1u) % n];
            let a_in = select(a[axis] >= bound, a[axis] <= bound, keep_below);
            let b_in = select(b[axis] >= bound, b[axis] <= bound, keep_below);
            if a_in && m < MAX_POLYGON {
                next[m] = a;
                m++;
            }
            if a_in != b_in && m < MAX_POLYGON {
                let s = (bound - a[axis]) / (b[axis] - a[axis]);
                var p = a + vec3<f32>(unfused(s * (b.x - a.x)), unfused(s * (b.y - a.y)), unfused(s * (b.z - a.z)));
                p[axis] = bound;
                next[m] = p;
                m++;
            }
        }
        n = m;
        for (var k = 0u; k < n; k++) {
            poly[k] = next[k];
        }
    }
    var out = Clipped(vec3<f32>(F32_MAX), vec3<f32>(-F32_MAX), n == 0u);
    for (var k = 0u; k < n; k++) {
        out.lo = min(out.lo, poly[k]);
        out.hi = max(out.hi, poly[k]);
    }
    out.lo = clamp(out.lo, lo, hi);
    out.hi = clamp(out.hi, lo, hi);
    return out;
}

const NO_AXIS: u32 = 3u;

struct SplitPlane {
    // NO_AXIS when no grid plane crosses the piece.
    axis: u32,
    position: f32,
}

// The split plane of a piece box: on each axis, the grid plane of the highest bit in which the
// first and last overlapped cells differ (the coarsest Morton-grid plane crossing the box on that
// axis); of the planes strictly inside the box, the one of the highest level, ties in Morton bit
// order (x, y, z).
fn split_plane(grid: SplitGrid, lo: vec3<f32>, hi: vec3<f32>) -> SplitPlane {
    let cells = cell_range(grid, lo, hi);
    var best = SplitPlane(NO_AXIS, 0.0);
    var best_level = 0u;
    for (var axis = 0u; axis < 3u; axis++) {
        let differing = cells.first[axis] ^ cells.last[axis];
        if differing == 0u {
            continue;
        }
        let level = 31u - countLeadingZeros(differing);
        let position = grid.scene_min[axis] + unfused(f32((cells.last[axis] >> level) << level) * grid.cell);
        let inside = lo[axis] < position && position < hi[axis];
        if inside && (best.axis == NO_AXIS || level > best_level) {
            best = SplitPlane(axis, position);
            best_level = level;
        }
    }
    return best;
}

fn max_extent(lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let e = hi - lo;
    return max(e.x, max(e.y, e.z));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= params.count {
        return;
    }
    let t = triangles[i];
    var out = ref_offsets[i];
    var end = ref_total[0];
    if i + 1u < params.count {
        end = ref_offsets[i + 1u];
    }
    let grid = split_grid();
    var stack: array<Piece, MAX_PIECES>;
    stack[0] = Piece(min(t.v0, min(t.v1, t.v2)), max(t.v0, max(t.v1, t.v2)), end - out);
    var sp = 1u;
    while sp > 0u {
        sp--;
        let piece = stack[sp];
        var split = piece.pieces > 1u && sp + 2u <= MAX_PIECES;
        var left = Clipped(piece.lo, piece.hi, false);
        var right = left;
        if split {
            let plane = split_plane(grid, piece.lo, piece.hi);
            split = plane.axis != NO_AXIS;
            if split {
                var left_hi = piece.hi;
                left_hi[plane.axis] = plane.position;
                var right_lo = piece.lo;
                right_lo[plane.axis] = plane.position;
                left = clip_triangle(t, piece.lo, left_hi);
                right = clip_triangle(t, right_lo, piece.hi);
                split = !left.empty && !right.empty;
            }
        }
        if split {
            let wl = max_extent(left.lo, left.hi);
            let wr = max_extent(right.lo, right.hi);
            var share = 0.5;
            if wl + wr > 0.0 {
                share = wl / (wl + wr);
            }
            let nl = clamp(u32(round(f32(piece.pieces) * share)), 1u, piece.pieces - 1u);
            stack[sp] = Piece(right.lo, right.hi, piece.pieces - nl);
            stack[sp + 1u] = Piece(left.lo, left.hi, nl);
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
