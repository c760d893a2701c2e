// The wide layout's references and their triangles (src/bvh/wide/triangles_gather.rs), the last
// step of the conversion: reference i of the wide tree holds its position in the binary tree's
// `prim_indices` (wide_collapse.wgsl) and gets the triangle's index from there; then a copy of its
// triangle, with the triangle's index in the word after v1 (`pad1`), so that the wide traversal
// tests a leaf's triangles from consecutive words, without a load of the reference's index before
// each (Ylitie et al. 2017 keep the triangles in leaf order too). One invocation per reference
// slot; the conversion's counters give the references written. The words move as integers (bound
// as u32 vectors), so no float semantics (a flush of the denormal bit patterns of small indices
// and materials) can touch them.
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<u32>>; // Triangle, three words each
// The binary tree's references.
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read_write> wide_prims: array<u32>;
// The conversion's counters: [1] the references written (wide_collapse.wgsl).
@group(0) @binding(4) var<storage, read> wide_counters: array<u32>;
@group(0) @binding(5) var<storage, read_write> wide_triangles: array<vec4<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= min(params.count, wide_counters[1]) {
        return;
    }
    let tri = prim_indices[wide_prims[i]];
    wide_prims[i] = tri;
    wide_triangles[3u * i] = triangles[3u * tri];
    wide_triangles[3u * i + 1u] = vec4<u32>(triangles[3u * tri + 1u].xyz, tri);
    wide_triangles[3u * i + 2u] = triangles[3u * tri + 2u];
}
