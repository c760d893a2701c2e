// Treelet restructuring (Karras & Aila 2013, §3-4), one round. Bottom-up climb as in
// bounds_refit.wgsl (one invocation per leaf, per-node arrival counters, the second arrival goes
// on; device-scope storageBarriers order the atomically stored node data around the counter
// increments). At each node the climb updates the primitive count N and the SAH cost
//     C(n) = min(Ci·A(n) + (C(left) + C(right)),  Ct·A(n)·N(n) if N(n) <= max leaf size)
// and, where N >= gamma, the node roots a treelet that the whole workgroup optimizes together:
//   1. formation (one invocation): start from the root's two children, then repeatedly expand the
//      treelet leaf of largest surface area that is an internal node, up to treelet_size leaves;
//   2. subset areas a(S) and primitive counts t(S) for all 2^m subsets, in parallel;
//   3. dynamic programming over subset sizes 2..m-1 (subsets of one size in parallel, a barrier
//      between sizes): c(S) = min(Ci·a(S) + min_P (c(P) + c(S\P)), Ct·a(S)·t(S)), each unordered
//      partition once (P ranges over the non-empty subsets of S without its lowest bit); a table
//      of all 8-bit subsets ordered by size (then value), built once per workgroup, hands each
//      invocation its subsets directly: the subsets of m leaves of size k are the first C(m, k)
//      entries of size k;
//   4. the full set's partitions spread over the workgroup and a min-reduce (ties: smaller P);
//   5. if the optimal cost is lower than the current one, write the new topology back, reusing
//      the treelet's internal nodes (root keeps its index), with boxes, N, C and parent links.
// Node data is shared across workgroups, so all of it lives in atomics. The CPU twin is
// `WorkingTree::optimize_round` (same operation order, same tie-breaking; costs agree to a few
// ulps, as the GPU may fuse Ci·A into the following add).
#include "bvh_node.wgsl"

const WORKGROUP: u32 = 32u;
const SUBSETS: u32 = 256u;
const F32_MAX: f32 = 3.40282347e38;

struct TreeletParams {
    count: u32,
    row_pitch: u32,
    gamma: u32,
    treelet_size: u32,
    max_leaf_size: u32,
    ci: f32,
    ct: f32,
    // Always 0 (see `unfused`).
    zero: u32,
}

@group(0) @binding(0) var<uniform> params: TreeletParams;
@group(0) @binding(1) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> parents: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> costs: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> arrivals: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.count, count_limit[0]) leaves.
@group(0) @binding(6) var<storage, read> count_limit: array<u32>;

#include "node_words.wgsl"

var<workgroup> climbing: atomic<u32>;
var<workgroup> any_climbing: u32;
var<workgroup> queue: array<u32, WORKGROUP>;
var<workgroup> queue_len: atomic<u32>;
var<workgroup> queue_total: u32;
var<workgroup> leaf_count: u32;
var<workgroup> treelet_leaves: array<u32, MAX_TREELET>;
var<workgroup> treelet_internal: array<u32, MAX_TREELET>;
var<workgroup> leaf_min: array<vec3<f32>, MAX_TREELET>;
var<workgroup> leaf_max: array<vec3<f32>, MAX_TREELET>;
var<workgroup> subset_area: array<f32, SUBSETS>;
var<workgroup> subset_cost: array<f32, SUBSETS>;
var<workgroup> subset_prims: array<u32, SUBSETS>;
var<workgroup> subset_split: array<u32, SUBSETS>;
var<workgroup> reduce_cost: array<f32, WORKGROUP>;
var<workgroup> reduce_split: array<u32, WORKGROUP>;
var<workgroup> subsets_by_size: array<u32, SUBSETS>;

// First entry of each subset size in `subsets_by_size` (sums of C(8, j), j < k).
const SIZE_OFFSET = array<u32, 9>(0u, 1u, 9u, 37u, 93u, 163u, 219u, 247u, 255u);
// C(m, k) for m, k <= 8, row m.
const BINOMIAL = array<array<u32, 9>, 9>(
    array<u32, 9>(1u, 0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u),
    array<u32, 9>(1u, 1u, 0u, 0u, 0u, 0u, 0u, 0u, 0u),
    array<u32, 9>(1u, 2u, 1u, 0u, 0u, 0u, 0u, 0u, 0u),
    array<u32, 9>(1u, 3u, 3u, 1u, 0u, 0u, 0u, 0u, 0u),
    array<u32, 9>(1u, 4u, 6u, 4u, 1u, 0u, 0u, 0u, 0u),
    array<u32, 9>(1u, 5u, 10u, 10u, 5u, 1u, 0u, 0u, 0u),
    array<u32, 9>(1u, 6u, 15u, 20u, 15u, 6u, 1u, 0u, 0u),
    array<u32, 9>(1u, 7u, 21u, 35u, 35u, 21u, 7u, 1u, 0u),
    array<u32, 9>(1u, 8u, 28u, 56u, 70u, 56u, 28u, 8u, 1u),
);

// Fills `subsets_by_size`: subset s goes after every smaller subset of its size.
fn build_subset_table(lid: u32) {
    for (var s = lid; s < SUBSETS; s += WORKGROUP) {
        let size = countOneBits(s);
        var rank = 0u;
        for (var t = 0u; t < s; t++) {
            rank += select(0u, 1u, countOneBits(t) == size);
        }
        subsets_by_size[SIZE_OFFSET[size] + rank] = s;
    }
}

fn word(node: u32, k: u32) -> u32 {
    return atomicLoad(&node_words[node * 8u + k]);
}

fn is_leaf(node: u32) -> bool {
    return (word(node, 7u) & LEAF_FLAG) != 0u;
}

// XOR with a zero the compiler cannot see keeps a product from being fused into a following add
// (FMA contraction, which GPU compilers do and WGSL allows). Used for surface areas only: the
// collapse (nodes_mark.wgsl) recomputes a node's area to find the leaves this kernel chose
// (Ct·A·N == C), so both kernels must round it identically.
fn unfused(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ params.zero);
}

fn surface_area(lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let e = hi - lo;
    return 2.0 * (unfused(e.x * e.y) + unfused(e.y * e.z) + unfused(e.z * e.x));
}

fn get_cost(node: u32) -> f32 {
    return bitcast<f32>(atomicLoad(&costs[node]));
}

// Cost of a node of area a and n primitives whose children cost `children` in total.
fn combine_cost(a: f32, n: u32, children: f32) -> f32 {
    var c = params.ci * a + children;
    if n <= params.max_leaf_size {
        c = min(c, params.ct * a * f32(n));
    }
    return c;
}

fn write_internal(node: u32, lo: vec3<f32>, hi: vec3<f32>, left: u32, right: u32) {
    store_box(node, lo, hi);
    atomicStore(&node_words[node * 8u + 3u], left);
    atomicStore(&node_words[node * 8u + 7u], right);
}

// Step 1, one invocation: grow the treelet below `root`.
fn form_treelet(root: u32) {
    treelet_leaves[0] = word(root, 3u);
    treelet_leaves[1] = word(root, 7u);
    treelet_internal[0] = root;
    var count = 2u;
    loop {
        if count >= params.treelet_size {
            break;
        }
        var best = MAX_TREELET;
        var best_area = -1.0;
        for (var i = 0u; i < count; i++) {
            let node = treelet_leaves[i];
            if !is_leaf(node) {
                let a = surface_area(load_min(node), load_max(node));
                if a > best_area {
                    best_area = a;
                    best = i;
                }
            }
        }
        if best == MAX_TREELET {
            break;
        }
        let expanded = treelet_leaves[best];
        treelet_leaves[best] = word(expanded, 3u);
        treelet_leaves[count] = word(expanded, 7u);
        treelet_internal[count - 1u] = expanded;
        count++;
    }
    for (var i = 0u; i < count; i++) {
        leaf_min[i] = load_min(treelet_leaves[i]);
        leaf_max[i] = load_max(treelet_leaves[i]);
    }
    leaf_count = count;
}

// Step 3 for one subset: best partition and cost.
fn solve_subset(s: u32) {
    let delta = (s - 1u) & s;
    var p = (0u - delta) & s;
    var best = F32_MAX;
    var best_p = 0u;
    loop {
        let c = subset_cost[p] + subset_cost[s ^ p];
        if c < best {
            best = c;
            best_p = p;
        }
        p = (p - delta) & s;
        if p == 0u {
            break;
        }
    }
    subset_cost[s] = combine_cost(subset_area[s], subset_prims[s], best);
    subset_split[s] = best_p;
}

fn subset_bounds_min(s: u32, m: u32) -> vec3<f32> {
    var lo = vec3<f32>(F32_MAX);
    for (var i = 0u; i < m; i++) {
        if ((s >> i) & 1u) != 0u {
            lo = min(lo, leaf_min[i]);
        }
    }
    return lo;
}

fn subset_bounds_max(s: u32, m: u32) -> vec3<f32> {
    var hi = vec3<f32>(-F32_MAX);
    for (var i = 0u; i < m; i++) {
        if ((s >> i) & 1u) != 0u {
            hi = max(hi, leaf_max[i]);
        }
    }
    return hi;
}

// Step 5, one invocation: rebuild the treelet from the DP's splits. Left child = the partition P
// (without the lowest leaf), right child = S\P; internal nodes are reused in breadth-first order.
fn write_back(m: u32) {
    let full = (1u << m) - 1u;
    var stack_set: array<u32, MAX_TREELET>;
    var stack_node: array<u32, MAX_TREELET>;
    var sp = 1u;
    stack_set[0] = full;
    stack_node[0] = treelet_internal[0];
    var next_internal = 1u;
    var head = 0u;
    // Breadth-first: a queue over stack_set/stack_node (at most m-1 internal nodes).
    while head < sp {
        let s = stack_set[head];
        let node = stack_node[head];
        head++;
        let sets = array<u32, 2>(subset_split[s], s ^ subset_split[s]);
        var child = array<u32, 2>(0u, 0u);
        for (var k = 0u; k < 2u; k++) {
            let part = sets[k];
            if countOneBits(part) == 1u {
                child[k] = treelet_leaves[firstTrailingBit(part)];
            } else {
                child[k] = treelet_internal[next_internal];
                next_internal++;
                stack_set[sp] = part;
                stack_node[sp] = child[k];
                sp++;
            }
            atomicStore(&parents[child[k]], node);
        }
        write_internal(node, subset_bounds_min(s, m), subset_bounds_max(s, m), child[0], child[1]);
        atomicStore(&prim_counts[node], subset_prims[s]);
        atomicStore(&costs[node], bitcast<u32>(subset_cost[s]));
    }
}

// Steps 1-5 for the treelet rooted at `root`, by the whole workgroup (uniform control flow).
fn optimize_treelet(root: u32, lid: u32) {
    if lid == 0u {
        form_treelet(root);
    }
    let m = workgroupUniformLoad(&leaf_count);
    if m < 3u {
        return;
    }
    let full = (1u << m) - 1u;
    for (var s = lid + 1u; s <= full; s += WORKGROUP) {
        subset_area[s] = surface_area(subset_bounds_min(s, m), subset_bounds_max(s, m));
        var prims = 0u;
        for (var i = 0u; i < m; i++) {
            if ((s >> i) & 1u) != 0u {
                prims += atomicLoad(&prim_counts[treelet_leaves[i]]);
            }
        }
        subset_prims[s] = prims;
        if countOneBits(s) == 1u {
            subset_cost[s] = get_cost(treelet_leaves[firstTrailingBit(s)]);
        }
    }
    workgroupBarrier();
    for (var size = 2u; size < m; size++) {
        let count = BINOMIAL[m][size];
        for (var i = lid; i < count; i += WORKGROUP) {
            solve_subset(subsets_by_size[SIZE_OFFSET[size] + i]);
        }
        workgroupBarrier();
    }
    // The full set: partitions P = x << 1 for x in 1 .. 2^(m-1)-1, spread over the workgroup.
    var best = F32_MAX;
    var best_p = 0u;
    for (var x = lid + 1u; x < (1u << (m - 1u)); x += WORKGROUP) {
        let p = x << 1u;
        let c = subset_cost[p] + subset_cost[full ^ p];
        if c < best {
            best = c;
            best_p = p;
        }
    }
    reduce_cost[lid] = best;
    reduce_split[lid] = best_p;
    workgroupBarrier();
    for (var stride = WORKGROUP / 2u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            let c = reduce_cost[lid + stride];
            let p = reduce_split[lid + stride];
            if c < reduce_cost[lid] || (c == reduce_cost[lid] && p < reduce_split[lid] && p != 0u) {
                reduce_cost[lid] = c;
                reduce_split[lid] = p;
            }
        }
        workgroupBarrier();
    }
    if lid == 0u {
        let cost = combine_cost(subset_area[full], subset_prims[full], reduce_cost[0]);
        subset_cost[full] = cost;
        subset_split[full] = reduce_split[0];
        if cost < get_cost(root) {
            write_back(m);
        }
    }
    workgroupBarrier();
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = min(params.count, count_limit[0]);
    var node = n - 1u + j;
    var is_climbing = false;
    if lid == 0u {
        atomicStore(&climbing, 0u);
        atomicStore(&queue_len, 0u);
    }
    build_subset_table(lid);
    workgroupBarrier();
    if j < n {
        atomicStore(&prim_counts[node], 1u);
        atomicStore(&costs[node], bitcast<u32>(params.ct * surface_area(load_min(node), load_max(node))));
        is_climbing = node != 0u;
        if is_climbing {
            atomicAdd(&climbing, 1u);
        }
    }
    loop {
        // Release: this node's data is stored before the parent's counter is incremented.
        storageBarrier();
        if is_climbing {
            let parent = atomicLoad(&parents[node]);
            if atomicAdd(&arrivals[parent], 1u) == 0u {
                is_climbing = false;
                atomicSub(&climbing, 1u);
            } else {
                node = parent;
            }
        }
        // Acquire: the sibling subtree's data, stored before its increment, is visible now.
        storageBarrier();
        if is_climbing {
            let left = word(node, 3u);
            let right = word(node, 7u);
            let prims = atomicLoad(&prim_counts[left]) + atomicLoad(&prim_counts[right]);
            let a = surface_area(load_min(node), load_max(node));
            atomicStore(&prim_counts[node], prims);
            atomicStore(&costs[node], bitcast<u32>(combine_cost(a, prims, get_cost(left) + get_cost(right))));
            if prims >= params.gamma {
                queue[atomicAdd(&queue_len, 1u)] = node;
            }
        }
        workgroupBarrier();
        if lid == 0u {
            queue_total = atomicLoad(&queue_len);
        }
        let total = workgroupUniformLoad(&queue_total);
        for (var q = 0u; q < total; q++) {
            optimize_treelet(queue[q], lid);
        }
        if is_climbing && node == 0u {
            is_climbing = false;
            atomicSub(&climbing, 1u);
        }
        workgroupBarrier();
        if lid == 0u {
            atomicStore(&queue_len, 0u);
            any_climbing = atomicLoad(&climbing);
        }
        if workgroupUniformLoad(&any_climbing) == 0u {
            break;
        }
    }
}
