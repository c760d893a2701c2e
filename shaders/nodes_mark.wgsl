// Leaf collapse, step 1 (Karras & Aila 2013, §3 "we collapse subtrees into leaves"): marks which
// nodes of the optimized working tree survive. A node "collapses" when it is a leaf or when its
// SAH cost as one leaf, Ct·A·N, does not exceed its subtree cost C (and N <= max leaf size) —
// the choice the treelet pass already made in C = min(split, leaf). A node is kept when no proper
// ancestor collapses; a kept collapsing node becomes an output leaf holding its N primitives.
// One invocation per node walks up its parent links, only as far as the first ancestor of more
// than max_leaf_size primitives: no ancestor from there up can collapse (counts grow upwards), so
// the walk takes at most max_leaf_size steps instead of the node's depth. Writes flags (bit 0
// kept, bit 1 output leaf) and the two inputs of the compaction scans (kept count, leaf primitive
// count), and where nodes_compact.wgsl writes each working leaf's primitive (`leaf_slots`: the
// output leaf that holds it and its position in that leaf's range), so that compaction walks no
// subtree:
// - without pre-split references, a working leaf's walk goes on to the node of more than
//   max_leaf_size primitives: its output leaf is the highest collapsing node on the way (or the
//   leaf itself), its position the primitives of the left subtrees it climbed out of
//   (depth-first order, left first);
// - with them, an output leaf counts each triangle once: its invocation finds its subtree's
//   working leaves in depth-first order, maps the references to triangle ids and gives each its
//   slot, the first occurrence of a triangle the next position, a repeat none (NO_SLOT). A leaf of
//   up to FRONTIER references does it in registers, a level of its subtree at a time (the nodes
//   of a level loaded at once, so a GPU waits for one load per level, not one per node and three
//   per reference); a larger one walks its subtree with a stack.
#include "bvh_node.wgsl"
#include "unfused.wgsl"

struct CollapseParams {
    // Leaves of the working tree (at most; see count_limit): it has 2n - 1 nodes.
    leaf_count: u32,
    row_pitch: u32,
    max_leaf_size: u32,
    ct: f32,
    // Always 0: see unfused.wgsl; the area must round as it did in the treelet rounds, so
    // that Ct·A·N <= C finds exactly the leaves the treelet pass chose.
    zero: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// 1 when the primitives are pre-split references mapped through `ref_tris` (trbvh-split), 0 when
// they are triangles: fixed per pipeline (`Collapse`), so that a pipeline holds the code of one
// (RADV: without references 24 vector registers and 1,168 bytes of code, where the kernel with
// both paths took 84 registers and 11,532 bytes).
override HAS_REFS: u32 = 1u;

@group(0) @binding(0) var<uniform> params: CollapseParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> parents: array<u32>;
@group(0) @binding(3) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read> costs: array<f32>;
@group(0) @binding(5) var<storage, read_write> flags: array<u32>;
// The compaction scans' inputs, two columns of 2·leaf_count - 1: kept (1 or 0), then the output
// leaf's primitive count (0 for other nodes).
@group(0) @binding(6) var<storage, read_write> scans: array<u32>;
@group(0) @binding(7) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(8) var<storage, read> ref_tris: array<u32>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.leaf_count, count_limit[0])
// leaves. The dispatch covers 2·params.leaf_count - 1 nodes; the nodes past the tree's get zeros,
// so that the scans over all of them give the tree's totals.
@group(0) @binding(9) var<storage, read> count_limit: array<u32>;
// Per working leaf (at its first primitive's index): its output leaf and the position of its
// first primitive in that leaf's range (NO_SLOT: a repeated triangle, not written).
@group(0) @binding(10) var<storage, read_write> leaf_slots: array<vec2<u32>>;

// The stack holds disjoint subtrees of the output leaf's, each of at least one reference.
const GATHER_STACK: u32 = MAX_GPU_LEAF_SIZE;
// Output leaves of at most this many references are gathered in registers (`gather_frontier`).
const FRONTIER: u32 = 8u;

// Entry k (< 8) of a frontier held as two vec4.
fn entry(low: vec4<u32>, high: vec4<u32>, k: u32) -> u32 {
    return select(low, high, k >= 4u)[k & 3u];
}

// With references, an output leaf of at most FRONTIER of them (`gather_references`' result):
// its subtree's frontier, left to right, starts at the root; each step replaces every internal
// node of it by its two children (shifting what follows), until only working leaves are left.
// Working leaves keep their LBVH places, leaf j at n - 1 + j (the rounds reuse internal nodes
// only), so the frontier's leaves need no load. No array is indexed by a computed value.
fn gather_frontier(root: u32, n: u32) -> u32 {
    let first_leaf = n - 1u;
    let lanes = vec4<u32>(0u, 1u, 2u, 3u);
    var low = vec4<u32>(root, 0u, 0u, 0u);
    var high = vec4<u32>(0u);
    var count = 1u;
    loop {
        // The internal nodes' children, all loaded before any is placed.
        var lefts = array<u32, FRONTIER>();
        var rights = array<u32, FRONTIER>();
        var opened = 0u;
        for (var k = 0u; k < FRONTIER; k++) {
            let node = entry(low, high, k);
            if k < count && node < first_leaf {
                let children = nodes[node];
                lefts[k] = children.left_or_first;
                rights[k] = children.right_or_count;
                opened |= 1u << k;
            }
        }
        if opened == 0u {
            break;
        }
        var new_low = vec4<u32>(0u);
        var new_high = vec4<u32>(0u);
        var at = 0u;
        for (var k = 0u; k < FRONTIER; k++) {
            let split = (opened & (1u << k)) != 0u;
            let first = select(entry(low, high, k), lefts[k], split);
            new_low = select(new_low, vec4<u32>(first), lanes == vec4<u32>(at));
            new_high = select(new_high, vec4<u32>(first), lanes + 4u == vec4<u32>(at));
            // The right child's place; past the frontier (no lane) for a node not opened.
            let second = select(FRONTIER, at + 1u, split);
            new_low = select(new_low, vec4<u32>(rights[k]), lanes == vec4<u32>(second));
            new_high = select(new_high, vec4<u32>(rights[k]), lanes + 4u == vec4<u32>(second));
            at += select(0u, select(1u, 2u, split), k < count);
        }
        low = new_low;
        high = new_high;
        count = at;
    }
    // The references' triangles, all loaded at once, then each the first of its triangle or not.
    var triangles = array<u32, FRONTIER>();
    for (var k = 0u; k < FRONTIER; k++) {
        if k < count {
            triangles[k] = ref_tris[prim_indices[entry(low, high, k) - first_leaf]];
        }
    }
    var slot = 0u;
    for (var k = 0u; k < FRONTIER; k++) {
        if k < count {
            var fresh = true;
            for (var j = 0u; j < k; j++) {
                fresh = fresh && triangles[j] != triangles[k];
            }
            leaf_slots[entry(low, high, k) - first_leaf] = vec2<u32>(root, select(NO_SLOT, slot, fresh));
            slot += select(0u, 1u, fresh);
        }
    }
    return slot;
}

// With references: the triangles under output leaf `root` depth-first (left first), each once;
// stores each working leaf's slot and returns the number of triangles. Working leaves hold one
// reference each and keep their LBVH places (the rounds reuse internal nodes only): leaf j is
// node first_leaf + j (first_leaf = n - 1), so the walk loads internal nodes only. Output leaves
// hold at most MAX_GPU_LEAF_SIZE references (the collapse's max leaf size limit).
fn gather_references(root: u32, first_leaf: u32) -> u32 {
    var triangles: array<u32, MAX_GPU_LEAF_SIZE>;
    var count = 0u;
    var stack: array<u32, GATHER_STACK>;
    var sp = 1u;
    stack[0] = root;
    while sp > 0u {
        sp--;
        let node = stack[sp];
        if node >= first_leaf {
            let leaf = node - first_leaf;
            let triangle = ref_tris[prim_indices[leaf]];
            var fresh = count < MAX_GPU_LEAF_SIZE;
            for (var j = 0u; j < count; j++) {
                fresh = fresh && triangles[j] != triangle;
            }
            var slot = NO_SLOT;
            if fresh {
                triangles[count] = triangle;
                slot = count;
                count++;
            }
            leaf_slots[leaf] = vec2<u32>(root, slot);
        } else if sp + 2u <= GATHER_STACK {
            // Right first on the stack, so the left subtree is gathered first.
            let n = nodes[node];
            stack[sp] = n.right_or_count;
            stack[sp + 1u] = n.left_or_first;
            sp += 2u;
        }
    }
    return count;
}

// Whether a node (`b`, of `n` primitives and SAH cost `cost`) becomes an output leaf's root
// candidate: a working leaf, or a node whose primitives cost no more as one leaf.
fn collapses(b: BvhNode, n: u32, cost: f32) -> bool {
    if (b.right_or_count & LEAF_FLAG) != 0u {
        return true;
    }
    let a = surface_area(b.min, b.max, params.zero);
    return n <= params.max_leaf_size && params.ct * a * f32(n) <= cost;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    let column_len = 2u * params.leaf_count - 1u;
    if i >= column_len {
        return;
    }
    if i >= 2u * min(params.leaf_count, count_limit[0]) - 1u {
        flags[i] = 0u;
        scans[i] = 0u;
        scans[column_len + i] = 0u;
        return;
    }
    var kept = true;
    let node = nodes[i];
    let count = prim_counts[i];
    let cost = costs[i];
    let slotted = HAS_REFS == 0u && (node.right_or_count & LEAF_FLAG) != 0u;
    // The output leaf holding a working leaf's primitives and their position in its range.
    var owner = i;
    var position = 0u;
    var before = 0u;
    // A node of more than max_leaf_size primitives is kept: so are its ancestors, which have more.
    // Each step up loads what it tests of the ancestor at once (node, count, cost and its own
    // link up, for the next step), and a right child's left sibling has the ancestor's primitives
    // but the child's: one round trip to memory per step, where the link, then the count, then
    // the node and the left sibling's count took up to four.
    var x = select(i, 0u, count > params.max_leaf_size);
    var child_count = count;
    var up = parents[i];
    while x != 0u {
        let child = x;
        x = up;
        let above = nodes[x];
        let above_count = prim_counts[x];
        let above_cost = costs[x];
        up = parents[x];
        if above_count > params.max_leaf_size {
            break;
        }
        if slotted && above.left_or_first != child {
            before += above_count - child_count;
        }
        if collapses(above, above_count, above_cost) {
            kept = false;
            owner = x;
            position = before;
            if !slotted {
                break;
            }
        }
        child_count = above_count;
    }
    if slotted {
        leaf_slots[node.left_or_first] = vec2<u32>(owner, position);
    }
    let leaf = kept && collapses(node, count, cost);
    flags[i] = select(0u, 1u, kept) | select(0u, 2u, leaf);
    scans[i] = select(0u, 1u, kept);
    var prims = 0u;
    if leaf {
        // Not a select: WGSL evaluates both of its arguments, and the gather walks the subtree.
        if HAS_REFS != 0u {
            let n = min(params.leaf_count, count_limit[0]);
            if count <= FRONTIER {
                prims = gather_frontier(i, n);
            } else {
                prims = gather_references(i, n - 1u);
            }
        } else {
            prims = count;
        }
    }
    scans[column_len + i] = prims;
}
