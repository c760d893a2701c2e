// SAH-optimal wide collapse, step 2 (Ylitie, Karras & Laine 2017, §3.1; CPU twin
// `OptimalCollapse`, src/bvh/wide/optimal.rs): the dynamic program over the binary tree,
// bottom-up. Per node n and slot count i, C(n, i) is the least cost of n's subtree spread over at
// most i slots of the wide node above it: Ct·A(n)·N(n) for a leaf (binary leaves stay leaves),
// and for an internal node C(n, 1) = Ci·A(n) + C_dist(n, 8) (n becomes a wide node of its own),
// C(n, i) = min(C(n, i − 1), C_dist(n, i)), C_dist(n, i) = min over 0 < k < i of
// C(l, k) + C(r, i − k). A = half the surface area (the costs are the wide SAH times
// A(root)/2). Ties keep fewer slots, then the smallest k. One invocation per node; each leaf
// climbs (bottom_up_climb.wgsl) and the second arrival at a node computes its costs, stored for
// its parent (C(n, 1..=7), through atomics), and its choices (collapse_choices.wgsl), read by
// the conversion (wide_collapse.wgsl). Every cost is a sum of correctly rounded f32 products
// (`unfused`), so every device makes the CPU twin's choices. Arrival counters start at zero
// (nodes_link.wgsl).
#include "bvh_node.wgsl"
#include "unfused.wgsl"
#include "collapse_choices.wgsl"

struct CostParams {
    // Node slots dispatched (the tree's node count is count_limit[0]).
    count: u32,
    row_pitch: u32,
    ci: f32,
    ct: f32,
    // Always 0 (see unfused.wgsl).
    zero: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// Invocations per workgroup: 64, or the device's climb width (`Kernel::climb`; 8 on CPU devices).
override WORKGROUP_WIDTH: u32 = 64u;

@group(0) @binding(0) var<uniform> params: CostParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> arrivals: array<atomic<u32>>;
// C(n, 1..=7) of each internal node n, f32 bits, COLLAPSE_COST_WORDS words per node.
@group(0) @binding(4) var<storage, read_write> costs: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> choices: array<u32>;
@group(0) @binding(6) var<storage, read> count_limit: array<u32>;

#include "bottom_up_climb.wgsl"

// C(n, 1..=7): C(n, 1..=4) in `low`, C(n, 5..=7) in `high` (values, not an array: an array
// indexed in a loop would live in memory).
struct Costs {
    low: vec4<f32>,
    high: vec3<f32>,
}

// C(child, 1..=7): the same Ct·A·N for every slot count for a leaf.
fn child_costs(child: u32) -> Costs {
    let node = nodes[child];
    if (node.right_or_count & LEAF_FLAG) != 0u {
        let leaf = params.ct * half_area(node.min, node.max, params.zero) * f32(node.right_or_count & ~LEAF_FLAG);
        return Costs(vec4<f32>(leaf), vec3<f32>(leaf));
    }
    let w = child * COLLAPSE_COST_WORDS;
    let low = vec4<u32>(atomicLoad(&costs[w]), atomicLoad(&costs[w + 1u]), atomicLoad(&costs[w + 2u]), atomicLoad(&costs[w + 3u]));
    let high = vec3<u32>(atomicLoad(&costs[w + 4u]), atomicLoad(&costs[w + 5u]), atomicLoad(&costs[w + 6u]));
    return Costs(bitcast<vec4<f32>>(low), bitcast<vec3<f32>>(high));
}

struct Split {
    cost: f32,
    left_slots: u32,
}

// Keeps the split of `left_slots` when it costs less (a tie keeps the smaller k found first).
fn consider(best: ptr<function, Split>, cost: f32, left_slots: u32) {
    if cost < (*best).cost {
        *best = Split(cost, left_slots);
    }
}

// C(n, slots) = min(C(n, slots − 1), C_dist(n, slots)) (a tie keeps fewer slots), its choice
// or-ed into `choice_word`.
fn take(fewer: f32, split: Split, slots: u32, choice_word: ptr<function, u32>) -> f32 {
    if fewer <= split.cost {
        return fewer;
    }
    *choice_word |= split.left_slots << (3u * (slots - 2u));
    return split.cost;
}

fn finish_parent(parent: u32) {
    let node = nodes[parent];
    let left = child_costs(node.left_or_first);
    let right = child_costs(node.right_or_count);
    // C_dist(n, s) = min over 0 < k < s of C(l, k) + C(r, s − k), written out for s = 8, 2..=7.
    var wide = Split(left.low.x + right.high.z, 1u);
    consider(&wide, left.low.y + right.high.y, 2u);
    consider(&wide, left.low.z + right.high.x, 3u);
    consider(&wide, left.low.w + right.low.w, 4u);
    consider(&wide, left.high.x + right.low.z, 5u);
    consider(&wide, left.high.y + right.low.y, 6u);
    consider(&wide, left.high.z + right.low.x, 7u);
    let split2 = Split(left.low.x + right.low.x, 1u);
    var split3 = Split(left.low.x + right.low.y, 1u);
    consider(&split3, left.low.y + right.low.x, 2u);
    var split4 = Split(left.low.x + right.low.z, 1u);
    consider(&split4, left.low.y + right.low.y, 2u);
    consider(&split4, left.low.z + right.low.x, 3u);
    var split5 = Split(left.low.x + right.low.w, 1u);
    consider(&split5, left.low.y + right.low.z, 2u);
    consider(&split5, left.low.z + right.low.y, 3u);
    consider(&split5, left.low.w + right.low.x, 4u);
    var split6 = Split(left.low.x + right.high.x, 1u);
    consider(&split6, left.low.y + right.low.w, 2u);
    consider(&split6, left.low.z + right.low.z, 3u);
    consider(&split6, left.low.w + right.low.y, 4u);
    consider(&split6, left.high.x + right.low.x, 5u);
    var split7 = Split(left.low.x + right.high.y, 1u);
    consider(&split7, left.low.y + right.high.x, 2u);
    consider(&split7, left.low.z + right.low.w, 3u);
    consider(&split7, left.low.w + right.low.z, 4u);
    consider(&split7, left.high.x + right.low.y, 5u);
    consider(&split7, left.high.y + right.low.x, 6u);
    var choice_word = wide.left_slots << CHOICE_WIDE_SHIFT;
    let c1 = unfused(params.ci * half_area(node.min, node.max, params.zero), params.zero) + wide.cost;
    let c2 = take(c1, split2, 2u, &choice_word);
    let c3 = take(c2, split3, 3u, &choice_word);
    let c4 = take(c3, split4, 4u, &choice_word);
    let c5 = take(c4, split5, 5u, &choice_word);
    let c6 = take(c5, split6, 6u, &choice_word);
    let c7 = take(c6, split7, 7u, &choice_word);
    let w = parent * COLLAPSE_COST_WORDS;
    atomicStore(&costs[w], bitcast<u32>(c1));
    atomicStore(&costs[w + 1u], bitcast<u32>(c2));
    atomicStore(&costs[w + 2u], bitcast<u32>(c3));
    atomicStore(&costs[w + 3u], bitcast<u32>(c4));
    atomicStore(&costs[w + 4u], bitcast<u32>(c5));
    atomicStore(&costs[w + 5u], bitcast<u32>(c6));
    atomicStore(&costs[w + 6u], bitcast<u32>(c7));
    choices[parent] = choice_word;
}

@compute @workgroup_size(WORKGROUP_WIDTH)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = gid.x + gid.y * params.row_pitch;
    var is_leaf = false;
    if i < min(params.count, count_limit[0]) {
        is_leaf = (nodes[i].right_or_count & LEAF_FLAG) != 0u;
    }
    climb(i, is_leaf, lid);
}
