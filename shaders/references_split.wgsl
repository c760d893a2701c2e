// Pre-splitting step 4 (Karras & Aila 2013, §5): the box of each reference that triangles_split.wgsl
// listed in `heavy_refs` (those of triangles of more than SPLIT_INLINE_PIECES references), one
// invocation per reference. Reference k of a triangle is the k-th leaf of its piece tree, left to
// right (triangle_pieces.wgsl): from the triangle's piece down, each cut goes on with the side
// whose references hold k, so an invocation makes as many cuts as its leaf is deep (at most
// MAX_SPLITS; about log2 of the references for even shares), not the 2·R − 1 cuts of the whole
// tree, and needs no piece stack. The same cuts as triangles_split.wgsl's loop, so the same boxes.
// Dispatched over the most entries `heavy_refs` can hold (`PreSplitter::heavy_capacity`);
// invocations past the count written return. CPU twin: `split_triangle`.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

// `count`: the triangles (the scan's length); the grid (`row_pitch`) spans the entries.
@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> ref_offsets: array<u32>;
@group(0) @binding(3) var<storage, read> block_offsets: array<u32>;
@group(0) @binding(4) var<storage, read> ref_total: array<u32>;
@group(0) @binding(5) var<storage, read_write> prim_boxes: array<Aabb>;
@group(0) @binding(6) var<storage, read> ref_tris: array<u32>;
@group(0) @binding(7) var<storage, read> scene_bounds: array<vec4<u32>>;
// [SPLIT_HEAVY_WORD]: the entries of `heavy_refs`.
@group(0) @binding(8) var<storage, read> budget_state: array<u32>;
@group(0) @binding(9) var<storage, read> heavy_refs: array<u32>;

#include "split_grid.wgsl"
#include "triangle_pieces.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let entry = gid.x + gid.y * params.row_pitch;
    if entry >= budget_state[SPLIT_HEAVY_WORD] {
        return;
    }
    let j = heavy_refs[entry];
    let i = ref_tris[j];
    let t = triangles[i];
    let out = first_reference(i);
    let grid = split_grid();
    let lo = min(t.v0, min(t.v1, t.v2));
    let hi = max(t.v0, max(t.v1, t.v2));
    var piece = triangle_piece(grid, lo, hi, reference_end(i, params.count) - out, out);
    var k = j - out;
    loop {
        let cut = cut_piece(grid, t, piece);
        if !cut.split {
            break;
        }
        if k < cut.left.pieces {
            piece = cut.left;
        } else {
            k -= cut.left.pieces;
            piece = cut.right;
        }
    }
    prim_boxes[j] = Aabb(piece.lo, 0u, piece.hi, 0u);
}
