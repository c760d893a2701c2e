// The pieces of a triangle in pre-splitting (Karras & Aila 2013, §5), shared by
// triangles_split.wgsl (a triangle's pieces one after another) and references_split.wgsl (one
// reference's piece, found from the root piece down). A piece is cut at the coarsest Morton-grid
// plane crossing it (`split_plane`); each side is the box of the triangle's part on that side,
// intersected with the piece box's side; the sides share the piece's references by their extents
// in cells (`cut_piece`). The pieces form a binary tree whose leaves are the references, left to
// right: a piece's references start at `out`, its left side's first. CPU twin: `split_triangle`.
// The including kernel declares `ref_offsets`, `block_offsets` and `ref_total` (the block-local
// scan of the reference counts, its block totals and the total) and includes split_grid.wgsl.

// The first reference of triangle i.
fn first_reference(i: u32) -> u32 {
    return ref_offsets[i] + block_offsets[i / SCAN_BLOCK];
}

// One past the last reference of triangle i of `count`.
fn reference_end(i: u32, count: u32) -> u32 {
    if i + 1u < count {
        return first_reference(i + 1u);
    }
    return ref_total[0];
}

struct Piece {
    lo: vec3<f32>,
    hi: vec3<f32>,
    first: vec3<u32>,
    last: vec3<u32>,
    // References the piece owes, and where the first goes.
    pieces: u32,
    out: u32,
}

// The piece of box [lo, hi] within the cells [first, last] of its parent.
fn piece_within(grid: SplitGrid, lo: vec3<f32>, hi: vec3<f32>, first: vec3<u32>, last: vec3<u32>, pieces: u32) -> Piece {
    let cells = cell_range(grid, lo, hi);
    let f = clamp(cells.first, first, last);
    let l = clamp(cells.last, f, last);
    return Piece(lo, hi, f, l, pieces, 0u);
}

// The whole triangle of box [lo, hi] as a piece that owes `pieces` references from `out`: the root
// of its piece tree, where both kernels start.
fn triangle_piece(grid: SplitGrid, lo: vec3<f32>, hi: vec3<f32>, pieces: u32, out: u32) -> Piece {
    let cells = cell_range(grid, lo, hi);
    var piece = piece_within(grid, lo, hi, cells.first, cells.last, pieces);
    piece.out = out;
    return piece;
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

// The two sides of a piece cut at a plane: each side's part of the triangle, boxed so far.
struct Sides {
    below_lo: vec3<f32>,
    below_hi: vec3<f32>,
    above_lo: vec3<f32>,
    above_hi: vec3<f32>,
}

// Adds edge a -> b of the triangle to the sides of the plane at `position` on `axis`: a to the
// side(s) it lies on (both when on the plane), and the edge's crossing of the plane to both when
// a and b lie strictly on opposite sides.
fn add_edge(sides: ptr<function, Sides>, a: vec3<f32>, b: vec3<f32>, axis: u32, position: f32) {
    let ax = a[axis];
    let bx = b[axis];
    if ax <= position {
        (*sides).below_lo = min((*sides).below_lo, a);
        (*sides).below_hi = max((*sides).below_hi, a);
    }
    if ax >= position {
        (*sides).above_lo = min((*sides).above_lo, a);
        (*sides).above_hi = max((*sides).above_hi, a);
    }
    if (ax < position && bx > position) || (ax > position && bx < position) {
        let s = (position - ax) / (bx - ax);
        var p = a + vec3<f32>(s * (b.x - a.x), s * (b.y - a.y), s * (b.z - a.z));
        p[axis] = position;
        (*sides).below_lo = min((*sides).below_lo, p);
        (*sides).below_hi = max((*sides).below_hi, p);
        (*sides).above_lo = min((*sides).above_lo, p);
        (*sides).above_hi = max((*sides).above_hi, p);
    }
}

// The part of the triangle boxed by [lo, hi] within the side box [side_lo, side_hi]: their
// intersection, empty when they do not meet.
fn within_side(lo: vec3<f32>, hi: vec3<f32>, side_lo: vec3<f32>, side_hi: vec3<f32>) -> Clipped {
    let empty = any(lo > side_hi) || any(hi < side_lo);
    return Clipped(clamp(lo, side_lo, side_hi), clamp(hi, side_lo, side_hi), empty);
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

// A piece cut in two, or not (`split` false: no grid plane crosses it, it owes one reference, or
// every plane leaves a side empty), with the sides' shares of its references.
struct Cut {
    split: bool,
    left: Piece,
    right: Piece,
}

// Cuts `piece` of triangle t. A plane whose cut leaves one side empty (the piece only grazes it,
// by rounding) gives way to the next candidate.
fn cut_piece(grid: SplitGrid, t: Triangle, piece: Piece) -> Cut {
    var split = false;
    var tried = select(7u, 0u, piece.pieces > 1u);
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
        // The triangle cut at the plane, each side intersected with its half of the piece.
        var sides = Sides(vec3<f32>(F32_MAX), vec3<f32>(-F32_MAX), vec3<f32>(F32_MAX), vec3<f32>(-F32_MAX));
        add_edge(&sides, t.v0, t.v1, plane.axis, plane.position);
        add_edge(&sides, t.v1, t.v2, plane.axis, plane.position);
        add_edge(&sides, t.v2, t.v0, plane.axis, plane.position);
        left = within_side(sides.below_lo, sides.below_hi, piece.lo, left_hi);
        right = within_side(sides.above_lo, sides.above_hi, right_lo, piece.hi);
        split = !left.empty && !right.empty;
    }
    if !split {
        return Cut(false, piece, piece);
    }
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
    l.out = piece.out;
    r.pieces = n - nl;
    r.out = piece.out + nl;
    return Cut(true, l, r);
}
