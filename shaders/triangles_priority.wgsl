// Pre-splitting step 1 (Karras & Aila 2013, §5): each triangle's split priority, kept as its cube
//     q = 2^i · (A_aabb − A_ideal),   p = q^(1/3)
// with i = (highest differing Morton bit of the box corners) / 3 − 20 (≤ 0; larger boxes in the
// Morton hierarchy matter more), A_aabb the box's surface area and A_ideal = |d1×d2|₁ the area its
// boxes approach under infinitely many splits. Keeping q (no cube root) makes the split counts
// exact integers shared with the CPU twin. Also the largest q (atomicMax on the bits of a
// non-negative float, per workgroup, then once per workgroup into budget_state) for the budget
// search.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read_write> priorities: array<f32>;
// [0]: bits of the largest priority
@group(0) @binding(3) var<storage, read_write> budget_state: array<atomic<u32>>;

// The scene box as box words (box_words.wgsl).
@group(0) @binding(4) var<storage, read> scene_bounds: array<vec4<u32>>;

#include "split_grid.wgsl"

// The priority q of triangle t.
fn priority(t: Triangle) -> f32 {
    let lo = min(t.v0, min(t.v1, t.v2));
    let hi = max(t.v0, max(t.v1, t.v2));
    let grid = split_grid();
    let cells = cell_range(grid, lo, hi);
    let bit = highest_differing_bit(cells.first, cells.last);
    if bit == NO_BIT {
        return 0.0;
    }
    let d1 = t.v1 - t.v0;
    let d2 = t.v2 - t.v0;
    let c = vec3<f32>(
        d1.y * d2.z - d1.z * d2.y,
        d1.z * d2.x - d1.x * d2.z,
        d1.x * d2.y - d1.y * d2.x,
    );
    let ideal = abs(c.x) + abs(c.y) + abs(c.z);
    let importance = i32(bit / 3u) - 20;
    return ldexp(max(box_area(lo, hi) - ideal, 0.0), importance);
}

// The workgroup's largest q (zero-initialized, as all workgroup memory): one device atomic per
// workgroup instead of one per triangle, all on the same word.
var<workgroup> workgroup_max: atomic<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        let q = priority(triangles[i]);
        priorities[i] = q;
        atomicMax(&workgroup_max, bitcast<u32>(q));
    }
    workgroupBarrier();
    if lid == 0u {
        atomicMax(&budget_state[0], atomicLoad(&workgroup_max));
    }
}
