// The LBVH's hierarchy found bottom-up (Apetrei 2014, "Fast and Simple Agglomerative LBVH
// Construction"), in the node layout of Karras 2012: the same binary radix tree over the sorted
// keys, with the same node numbers (CPU twin: `hierarchy_cpu`, Karras's top-down emission), but
// emitted by the bottom-up climb that computes the boxes instead of a top-down pass of its own.
//
// A node covers a range [first, last] of sorted leaves. Its parent joins it with the neighbouring
// range across whichever end has the longer common key prefix (δ of the split between two
// adjacent keys, ties broken by index as in Karras 2012; two splits a node could hang from never
// have equal δ), so the node is its parent's left child when δ(last) > δ(first − 1) (or first is
// 0), and its parent's split is `last`, else the right child of split first − 1. Karras's layout
// stores an internal node at its last leaf's index when it is a left child, at its first's when it
// is a right child, the root (all leaves) at 0, and leaf j at n − 1 + j; the children of the node
// with split s are s and s + 1 (or the leaves there when their range is one leaf).
//
// The climb: an invocation that finished a node announces its range's far end (the end its parent
// keeps) in its parent split's word of `arrivals` with an atomicExchange of far end + 1. The first
// to arrive stops; the second reads its sibling's far end, zeroes the word (arrivals are zero
// again after a climb), and finishes the parent. A node carries the δ at both its ends, so each
// step loads the keys at one split only (the sibling's far end), and the climbing invocation
// carries its node's box, so it loads only the sibling's. `emit_leaf` and `emit_parent`
// write the nodes: children, parent links and boxes; `climb` runs the loop. Node data is shared
// across workgroups, so it goes through atomics (node_words.wgsl), and storageBarriers order it
// around the arrivals (release before, acquire after). The including kernel declares `keys:
// array<vec2<u32>>` (the sorted keys, low word first), `arrivals: array<atomic<u32>>` and
// `parents: array<u32>`, includes node_words.wgsl before this file, defines
// `finish_parent(p: EmittedParent)` (what else it computes per parent, from the climbing child's
// data, which it may carry in private variables, and the sibling's), and
// sets `leaf_count` before the climb.

var<private> leaf_count: u32;

// δ of the split between sorted leaves i and i + 1: the length of their keys' common prefix, the
// leaf indices extending equal keys.
fn split_delta(i: u32) -> u32 {
    let x = keys[i] ^ keys[i + 1u];
    if x.y != 0u {
        return countLeadingZeros(x.y);
    }
    if x.x != 0u {
        return 32u + countLeadingZeros(x.x);
    }
    return 64u + countLeadingZeros(i ^ (i + 1u));
}

// A finished node on the climb: its range, its node index, the δ of the splits at its ends (0
// past the first or last leaf), and the side it hangs from.
struct RangeNode {
    first: u32,
    last: u32,
    node: u32,
    delta_before: u32,
    delta_after: u32,
    is_left: bool,
}

// The node of range [first, last] whose end splits have δ `before` (split first − 1) and `after`
// (split last).
fn range_node(first: u32, last: u32, before: u32, after: u32) -> RangeNode {
    if first == 0u && last + 1u == leaf_count {
        // The root, which hangs from nothing.
        return RangeNode(first, last, 0u, before, after, false);
    }
    let is_left = first == 0u || (last + 1u != leaf_count && after > before);
    let node = select(first, last, is_left);
    return RangeNode(first, last, select(node, leaf_count - 1u + first, first == last), before, after, is_left);
}

fn leaf_range_node(j: u32) -> RangeNode {
    var before = 0u;
    if j > 0u {
        before = split_delta(j - 1u);
    }
    var after = 0u;
    if j + 1u < leaf_count {
        after = split_delta(j);
    }
    return range_node(j, j, before, after);
}

// The split of `r`'s parent.
fn parent_split(r: RangeNode) -> u32 {
    return select(r.first - 1u, r.last, r.is_left);
}

// Announces `r` at its parent's split: the sibling's far end + 1 if it arrived first, else 0 (then
// the sibling's invocation finishes the parent).
fn arrive(r: RangeNode) -> u32 {
    let split = parent_split(r);
    let sibling = atomicExchange(&arrivals[split], select(r.last, r.first, r.is_left) + 1u);
    if sibling != 0u {
        atomicStore(&arrivals[split], 0u);
    }
    return sibling;
}

// The parent of `r`, whose sibling announced `sibling` (arrive's value): the δ at `r`'s far end
// is known, the one at the sibling's far end is loaded.
fn parent_range_node(r: RangeNode, sibling: u32) -> RangeNode {
    let end = sibling - 1u;
    if r.is_left {
        var after = 0u;
        if end + 1u < leaf_count {
            after = split_delta(end);
        }
        return range_node(r.first, end, r.delta_before, after);
    }
    var before = 0u;
    if end > 0u {
        before = split_delta(end - 1u);
    }
    return range_node(end, r.last, before, r.delta_after);
}

// The children (left, right) of internal node `p` whose split is `split`.
fn range_children(p: RangeNode, split: u32) -> vec2<u32> {
    let leaf_base = leaf_count - 1u;
    let left = select(split, leaf_base + split, p.first == split);
    let right = select(split + 1u, leaf_base + split + 1u, p.last == split + 1u);
    return vec2<u32>(left, right);
}

// Stores leaf j's node (box `b`, one primitive: sorted leaf j) and returns it for the climb.
fn emit_leaf(j: u32, b: Aabb) -> RangeNode {
    let r = leaf_range_node(j);
    store_box(r.node, b.min, b.max);
    atomicStore(&node_words[r.node * 8u + 3u], j);
    atomicStore(&node_words[r.node * 8u + 7u], LEAF_FLAG | 1u);
    return r;
}

// A parent the second arrival finished: its range node, its child that is not the climbing node
// (`sibling`) and its box.
struct EmittedParent {
    range: RangeNode,
    sibling: u32,
    lo: vec3<f32>,
    hi: vec3<f32>,
}

// The second arrival at the parent of `r`, whose box is [lo, hi] (the sibling announced
// `sibling`): stores the parent's children, their parent links and its box, the union of theirs
// (the sibling's loaded, `r`'s carried by the climb; min and max take the left child's first).
fn emit_parent(r: RangeNode, lo: vec3<f32>, hi: vec3<f32>, sibling: u32) -> EmittedParent {
    let split = parent_split(r);
    let p = parent_range_node(r, sibling);
    let c = range_children(p, split);
    atomicStore(&node_words[p.node * 8u + 3u], c.x);
    atomicStore(&node_words[p.node * 8u + 7u], c.y);
    parents[c.x] = p.node;
    parents[c.y] = p.node;
    let other = select(c.x, c.y, r.is_left);
    let other_lo = load_min(other);
    let other_hi = load_max(other);
    let union_lo = min(select(other_lo, lo, r.is_left), select(lo, other_lo, r.is_left));
    let union_hi = max(select(other_hi, hi, r.is_left), select(hi, other_hi, r.is_left));
    store_box(p.node, union_lo, union_hi);
    return EmittedParent(p, other, union_lo, union_hi);
}

var<workgroup> climbing: atomic<u32>;
var<workgroup> any_climbing: u32;

// Climbs from `leaf` (emit_leaf's, of box `leaf_box`, with the kernel's own data of it stored)
// when `has_leaf`: at each parent the second arrival emits it (emit_parent), lets the kernel
// finish it (`finish_parent`) and goes on, up to the root. The climbing node's box is carried,
// only the sibling's is loaded. Barriers need uniform control flow, so every invocation of the
// workgroup calls this and steps the loop until all are done.
fn climb(leaf: RangeNode, leaf_box: Aabb, has_leaf: bool, lid: u32) {
    if lid == 0u {
        atomicStore(&climbing, 0u);
    }
    workgroupBarrier();
    var r = leaf;
    var lo = leaf_box.min;
    var hi = leaf_box.max;
    var is_climbing = has_leaf && r.node != 0u;
    if is_climbing {
        atomicAdd(&climbing, 1u);
    }
    loop {
        // Release: this node's data is stored before the arrival.
        storageBarrier();
        var sibling = 0u;
        if is_climbing {
            sibling = arrive(r);
            if sibling == 0u {
                // First arrival: the sibling's invocation will finish the parent.
                is_climbing = false;
                atomicSub(&climbing, 1u);
            }
        }
        // Acquire: the sibling's data, stored before its arrival, is visible now.
        storageBarrier();
        if is_climbing {
            let parent = emit_parent(r, lo, hi, sibling);
            finish_parent(parent);
            r = parent.range;
            lo = parent.lo;
            hi = parent.hi;
            if r.node == 0u {
                is_climbing = false;
                atomicSub(&climbing, 1u);
            }
        }
        workgroupBarrier();
        if lid == 0u {
            any_climbing = atomicLoad(&climbing);
        }
        if workgroupUniformLoad(&any_climbing) == 0u {
            break;
        }
    }
}
