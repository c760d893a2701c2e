// LBVH hierarchy emission (Karras 2012, "Maximizing Parallelism in the Construction of BVHs,
// Octrees, and k-d Trees", §4, Figure 4): one invocation per internal node i of n-1. Internal nodes
// are 0..n-2 (root 0), leaf j is node n-1+j. Equal keys are told apart by their index: every δ
// evaluation uses δ(i,j) = clz(k_i ^ k_j), or 64 + clz(i ^ j) when the keys are equal.
// Writes the children of each internal node (its box comes later, bottom-up) and parent links.
#include "bvh_node.wgsl"
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(3) var<storage, read_write> parents: array<u32>;
// The item count's limit (`gpu::ItemCount`): the kernel works on min(params.count, count_limit[0]).
@group(0) @binding(4) var<storage, read> count_limit: array<u32>;

// The leaf count n.
var<private> leaf_count: u32;

// Length of the common prefix of the keys (with index tie-break) at i and j; -1 outside [0, n).
fn delta(i: i32, j: i32) -> i32 {
    if j < 0 || j >= i32(leaf_count) {
        return -1;
    }
    let x = keys[i] ^ keys[j];
    if x.y != 0u {
        return i32(countLeadingZeros(x.y));
    }
    if x.x != 0u {
        return 32 + i32(countLeadingZeros(x.x));
    }
    return 64 + i32(countLeadingZeros(u32(i) ^ u32(j)));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = gid.x + gid.y * params.row_pitch;
    leaf_count = min(params.count, count_limit[0]);
    if index + 1u >= leaf_count {
        return;
    }
    let i = i32(index);
    let d = select(-1, 1, delta(i, i + 1) > delta(i, i - 1));
    // Upper bound of the range's length, then its exact other end j.
    let delta_min = delta(i, i - d);
    var l_max = 2;
    while delta(i, i + l_max * d) > delta_min {
        l_max *= 2;
    }
    var l = 0;
    for (var t = l_max / 2; t >= 1; t /= 2) {
        if delta(i, i + (l + t) * d) > delta_min {
            l += t;
        }
    }
    let j = i + l * d;
    // Split position: the last index sharing more than delta_node prefix bits with i.
    let delta_node = delta(i, j);
    var s = 0;
    var t = l;
    loop {
        t = (t + 1) / 2;
        if delta(i, i + (s + t) * d) > delta_node {
            s += t;
        }
        if t <= 1 {
            break;
        }
    }
    let gamma = i + s * d + min(d, 0);
    let leaf_base = leaf_count - 1u;
    let left = select(u32(gamma), leaf_base + u32(gamma), min(i, j) == gamma);
    let right = select(u32(gamma + 1), leaf_base + u32(gamma + 1), max(i, j) == gamma + 1);
    nodes[index].left_or_first = left;
    nodes[index].right_or_count = right;
    parents[left] = index;
    parents[right] = index;
}
