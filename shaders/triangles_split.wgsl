// Pre-splitting step 3 (Karras & Aila 2013, §5): each triangle becomes its s_t + 1 references.
// Pieces are split recursively at the coarsest Morton-grid plane crossing the piece
// (triangle_pieces.wgsl: planes on the power-of-two subdivision of the scene's cubic grid, so
// neighbouring triangles' splits agree). A piece carries the grid cells it covers as integers: the
// side cut at a plane ends exactly at that plane's cell, whatever the rounding of the plane's
// position and of the grid scale (a float cell range would put a side that ends on the plane into
// the next cell on some devices, and the piece would then be "split" at its own side again,
// emitting copies of one box). Each side is the box of the triangle's part on that side of the
// plane (its vertices there and its edges' crossings of the plane) intersected with the piece
// box's side, as the paper and SBVH's reference splits do. Clipping the triangle to each side box
// instead (a polygon in a private array) made the kernel 3-4x slower on lavapipe for boxes that
// are tighter only where the triangle reaches beyond the piece (SAH within 0.8 %; README,
// "Pre-splitting against SBVH"). The remaining pieces are shared by the sides' extents in cells
// (integer arithmetic, rounded half up). A piece that cannot be split (inside one grid cell, or a
// side left empty) is emitted as often as it still owes references, so every triangle writes
// exactly its count.
// One invocation per triangle writes its references' triangles, and the boxes of a triangle of
// up to SPLIT_INLINE_PIECES references (its pieces one after another). A triangle of more
// references (up to MAX_SPLITS + 1) lists them in `heavy_refs` instead, and
// references_split.wgsl finds each one's box with an invocation of its own: one invocation
// splitting 32 pieces in turn would hold up its whole SIMD group for 63 cuts. Writes the
// reference boxes and each reference's triangle at the triangle's scanned offset. CPU twin:
// `split_triangle`.
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
// The budget search's state; [SPLIT_HEAVY_WORD]: the entries of `heavy_refs` so far (zeroed
// before the stage).
@group(0) @binding(8) var<storage, read_write> budget_state: array<atomic<u32>>;
// The references of triangles of more than SPLIT_INLINE_PIECES references.
@group(0) @binding(9) var<storage, read_write> heavy_refs: array<u32>;

#include "split_grid.wgsl"
#include "triangle_pieces.wgsl"

// Splits triangle t (box [lo, hi]) into its references first_out .. end - 1 (at most
// SPLIT_INLINE_PIECES). The loop goes on with the side of fewer references and stacks the other,
// so at most PIECE_STACK = log2(SPLIT_INLINE_PIECES) pieces wait: with d pieces waiting, the
// current one owes at most 1/2^d of the triangle's references (the side taken owes at most half
// of its parent's, a waiting one less than its parent). A function of its own, called only for a
// triangle of several references, so that the others do not pay for its piece stack
// (zero-initialized, as every WGSL `var`).
fn split_triangle(grid: SplitGrid, t: Triangle, lo: vec3<f32>, hi: vec3<f32>, first_out: u32, end: u32) {
    var stack: array<Piece, PIECE_STACK>;
    var piece = triangle_piece(grid, lo, hi, end - first_out, first_out);
    var sp = 0u;
    loop {
        let cut = cut_piece(grid, t, piece);
        if cut.split {
            if cut.left.pieces <= cut.right.pieces {
                stack[sp] = cut.right;
                piece = cut.left;
            } else {
                stack[sp] = cut.left;
                piece = cut.right;
            }
            sp++;
        } else {
            for (var k = 0u; k < piece.pieces; k++) {
                prim_boxes[piece.out + k] = Aabb(piece.lo, 0u, piece.hi, 0u);
            }
            if sp == 0u {
                break;
            }
            sp--;
            piece = stack[sp];
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
    let end = reference_end(i, params.count);
    let lo = min(t.v0, min(t.v1, t.v2));
    let hi = max(t.v0, max(t.v1, t.v2));
    for (var j = out; j < end; j++) {
        ref_tris[j] = i;
    }
    if end - out == 1u {
        // Unsplit: the triangle's box (what the piece loop emits for a single piece).
        prim_boxes[out] = Aabb(lo, 0u, hi, 0u);
    } else if end - out <= SPLIT_INLINE_PIECES {
        split_triangle(split_grid(), t, lo, hi, out, end);
    } else {
        let slot = atomicAdd(&budget_state[SPLIT_HEAVY_WORD], end - out);
        for (var j = out; j < end; j++) {
            heavy_refs[slot + j - out] = j;
        }
    }
}
