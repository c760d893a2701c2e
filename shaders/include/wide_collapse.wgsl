// Binary-to-wide conversion, one wide node per invocation (CPU twins: `WideBvh::from_binary` and
// `WideBvh::from_binary_optimal`, src/bvh/wide/convert.rs; the kernels run it top-down:
// wide_nodes_emit.wgsl level by level, then wide_nodes_finish.wgsl a subtree per invocation).
// Wide node w is made from a binary node (the root from node 0; `wide_sources[w]` holds, for the
// greedy collapse, that node's two children, which its parent's draft had loaded, so that a
// level's draft loads them without first loading the node; for the optimal one the node itself):
// 1. Children, by one of two collapses (the pipeline constant `WIDE_COLLAPSE`):
//    - optimal: the split of 8 slots that costs_climb.wgsl chose for the binary node, each part
//      expanded by its node's choices (collapse_choices.wgsl), left before right: Ylitie et al.'s
//      SAH-optimal collapse;
//    - greedy: start from its two children; while fewer than 8, open the internal child of the
//      largest surface area (its two children replace it), the common cheaper collapse.
// 2. Slots: child by child, child j goes to the free slot s maximizing Σ_a ±(centre_j −
//    centre_node)_a (+ where bit a of s is set) (the paper's octant assignment, greedy instead of
//    an auction); the traversal then visits slots in ray-octant order.
// 3. Quantization: per axis the smallest exponent e with origin + 255·2^e ≥ the node's max, and
//    per child lo = the largest q with origin + q·2^e ≤ min, hi = the smallest with ≥ max (f32
//    arithmetic; the products are exact, so fused or not every device rounds alike).
// 4. Output: internal children get consecutive wide nodes from an atomic counter (their sources
//    are written for the next level), leaf children's references get consecutive entries of
//    `wide_prims`, each holding the reference's position in the binary tree's `prim_indices`:
//    triangles_gather.wgsl, a dispatch of one invocation per reference, replaces it with the
//    triangle's index. A store per reference, no load: a copy here loaded each index before
//    storing it, a round trip to memory per reference in a wide node's chain of dependent steps.
//    A workgroup emits its nodes in waves and allocates for a wave at once (`emit_wave_node`):
//    one device atomic per counter and wave, not per node.
// Every decision uses additions, exact products or `unfused` ones: the tree is the same on every
// device, up to the numbering of nodes and reference blocks (allocation order).
#include "bvh_node.wgsl"
#include "wide_node.wgsl"
#include "unfused.wgsl"
#include "collapse_choices.wgsl"

struct WideParams {
    // Level of the tree this dispatch emits (0: the root); the per-level kernel only.
    level: u32,
    // Indirect level dispatches after the root's (records 1..=level_dispatches + 1 exist).
    level_dispatches: u32,
    // Wide nodes `wide_nodes` holds.
    capacity: u32,
    // Always 0 (see unfused.wgsl).
    zero: u32,
}

// Values of `WIDE_COLLAPSE` (Rust twin: `WideCollapse`).
const COLLAPSE_GREEDY: u32 = 0u;
const COLLAPSE_OPTIMAL: u32 = 1u;
// The collapse, fixed per pipeline (`WideConverter`): a pipeline holds the code of one, not a
// branch over both (RADV: `wide_nodes_emit` 31,632 bytes of code with both, 27,156 greedy only).
override WIDE_COLLAPSE: u32 = COLLAPSE_GREEDY;

@group(0) @binding(0) var<uniform> params: WideParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> wide_nodes: array<WideNode>;
// Per reference, its position in the binary tree's `prim_indices` (triangles_gather.wgsl replaces
// it with the triangle's index).
@group(0) @binding(3) var<storage, read_write> wide_prims: array<u32>;
// Per wide node but the root, where it comes from: its binary node's children (left, right) with
// the greedy collapse, the binary node (x; y unused) with the optimal one. Read once, by the
// node's draft: wide_nodes_finish.wgsl then keeps the link of its walk there.
@group(0) @binding(4) var<storage, read_write> wide_sources: array<vec2<u32>>;
// [0] wide nodes allocated, [1] references written, [2] capacity overflows.
@group(0) @binding(5) var<storage, read_write> wide_counters: array<atomic<u32>>;
// Level records, 8 words per level: [workgroups x, y, z, first node, end node, 0, 0, 0]; even
// levels in one buffer, odd in the other, so that a level dispatch reads its own record (and
// its indirect arguments) from one and sizes the next level in the other.
@group(0) @binding(6) var<storage, read> this_level: array<u32>;
@group(0) @binding(7) var<storage, read_write> next_level: array<atomic<u32>>;
// The optimal collapse's choices per binary node (costs_climb.wgsl; unused by the greedy one).
@group(0) @binding(8) var<storage, read> choices: array<u32>;

const RECORD_WORDS: u32 = 8u;
const EMIT_WORKGROUP: u32 = 64u;

fn record_word(level: u32, word: u32) -> u32 {
    return RECORD_WORDS * level + word;
}

// The wide nodes [first, end) of level `level`'s record (this_level), which a dispatch sized by
// that record emits or walks from.
fn record_range(level: u32) -> vec2<u32> {
    let first = this_level[record_word(level, 3u)];
    return vec2<u32>(first, max(this_level[record_word(level, 4u)], first));
}

// The smallest biased exponent e (1..=253) with lo + 255·2^(e−127) ≥ hi.
fn axis_exponent(lo: f32, hi: f32) -> u32 {
    let bits = bitcast<u32>(hi - lo);
    // extent = m·2^(E−127), m in [1, 2): 255·2^(E−134) = 1.99·2^(E−127) covers m ≤ 255/128.
    var e = i32(bits >> 23u) - 7 + select(0, 1, (bits & 0x7fffffu) > 0x7f0000u);
    e = clamp(e, 1, 253);
    while e < 253 && lo + 255.0 * exponent_scale(u32(e)) < hi {
        e++;
    }
    return u32(e);
}

fn quantize_lo(v: f32, origin: f32, e: u32) -> u32 {
    let step = exponent_scale(e);
    var q = u32(clamp(floor((v - origin) * exponent_scale(254u - e)), 0.0, 255.0));
    while q > 0u && origin + f32(q) * step > v {
        q--;
    }
    return q;
}

fn quantize_hi(v: f32, origin: f32, e: u32) -> u32 {
    let step = exponent_scale(e);
    var q = u32(clamp(ceil((v - origin) * exponent_scale(254u - e)), 0.0, 255.0));
    while q < 255u && origin + f32(q) * step < v {
        q++;
    }
    return q;
}

// `bytes` with `value` or-ed into byte `slot`.
fn with_byte(bytes: vec2<u32>, slot: u32, value: u32) -> vec2<u32> {
    let shifted = value << ((slot & 3u) * 8u);
    return bytes | select(vec2<u32>(shifted, 0u), vec2<u32>(0u, shifted), slot >= 4u);
}

// The greedy collapse's key of a child: its half area if it is an internal node, else -1 (never
// opened; an internal node's area is at least 0).
fn openable_area(node: BvhNode) -> f32 {
    return select(half_area(node.min, node.max, params.zero), -1.0, (node.right_or_count & LEAF_FLAG) != 0u);
}

// Makes `node` (binary node `index`) child `at` of a wide node being drafted, by selects over
// every entry: arrays indexed only at indices the loops fix stay out of memory.
fn set_child(child: ptr<function, array<BvhNode, 8>>, child_index: ptr<function, array<u32, 8>>, at: u32, node: BvhNode, index: u32) {
    for (var t = 0u; t < 8u; t++) {
        let here = t == at;
        (*child)[t].min = select((*child)[t].min, node.min, here);
        (*child)[t].left_or_first = select((*child)[t].left_or_first, node.left_or_first, here);
        (*child)[t].max = select((*child)[t].max, node.max, here);
        (*child)[t].right_or_count = select((*child)[t].right_or_count, node.right_or_count, here);
        (*child_index)[t] = select((*child_index)[t], index, here);
    }
}

// Below every score: a slot scores more than this to be taken over the first free one (the CPU
// twin's start).
const NO_SCORE: f32 = -3.4e38;

// A child's scores for slots 0-3 and 4-7: Σ_a ±(centre_child − centre_node)_a, + where bit a of
// the slot is set (the CPU twin's sums, in its order).
fn slot_scores(c: BvhNode, centre: vec3<f32>) -> array<vec4<f32>, 2> {
    let d = (c.min + c.max) - centre;
    let xy = vec4<f32>(-d.x, d.x, -d.x, d.x) + vec4<f32>(-d.y, -d.y, d.y, d.y);
    return array<vec4<f32>, 2>(xy + vec4<f32>(-d.z), xy + vec4<f32>(d.z));
}

// A wide node before its children and references are allocated: the node (child_base and
// prim_base 0), its internal children and references, and per slot what its child's
// `wide_sources` entry gets (internal: the binary child's children with the greedy collapse, the
// binary child with the optimal one) or its first reference (leaf).
struct WideDraft {
    node: WideNode,
    internal: u32,
    prims: u32,
    slot_words: array<vec2<u32>, 8>,
}

// The greedy collapse's binary node's children (x: left, y: right), or a binary node (x; the
// optimal collapse), of wide node w's `wide_sources` entry; the root's from binary node 0, with
// y = NO_SOURCE where that node is a leaf (a tree of one leaf).
const NO_SOURCE: u32 = 0xffffffffu;

fn wide_node_source(w: u32) -> vec2<u32> {
    if w != 0u {
        return wide_sources[w];
    }
    let root = nodes[0];
    if (root.right_or_count & LEAF_FLAG) != 0u {
        return vec2<u32>(0u, NO_SOURCE);
    }
    if WIDE_COLLAPSE == COLLAPSE_OPTIMAL {
        return vec2<u32>(0u);
    }
    return vec2<u32>(root.left_or_first, root.right_or_count);
}

// The wide node made from `source` (`wide_node_source`; steps 1-3).
fn draft_wide_node(source: vec2<u32>) -> WideDraft {
    // Written through `set_child` only, and read at indices the loops fix: no index a lane
    // computes (see the slots below).
    var child: array<BvhNode, 8>;
    var child_index: array<u32, 8>;
    var count = 0u;
    if source.y == NO_SOURCE {
        // A tree of one leaf.
        set_child(&child, &child_index, 0u, nodes[0], 0u);
        count = 1u;
    } else if WIDE_COLLAPSE == COLLAPSE_OPTIMAL {
        let top = nodes[source.x];
        // (binary node, slots) still to expand, the next on top: at most 8, as each holds a slot.
        var pending: array<vec2<u32>, 8>;
        let k = wide_split(choices[source.x]);
        pending[0] = vec2<u32>(top.right_or_count, 8u - k);
        pending[1] = vec2<u32>(top.left_or_first, k);
        var sp = 2u;
        while sp > 0u {
            sp--;
            let n = pending[sp].x;
            var slots = pending[sp].y;
            let node = nodes[n];
            loop {
                if (node.right_or_count & LEAF_FLAG) != 0u || slots == 1u {
                    set_child(&child, &child_index, count, node, n);
                    count++;
                    break;
                }
                let left_slots = slots_choice(choices[n], slots);
                if left_slots == 0u {
                    slots--;
                    continue;
                }
                pending[sp] = vec2<u32>(node.right_or_count, slots - left_slots);
                pending[sp + 1u] = vec2<u32>(node.left_or_first, left_slots);
                sp += 2u;
                break;
            }
        }
    } else {
        set_child(&child, &child_index, 0u, nodes[source.x], source.x);
        set_child(&child, &child_index, 1u, nodes[source.y], source.y);
        // Each child's area once, when it is loaded; -1 for a leaf or no child (never opened).
        var area = array<f32, 8>(openable_area(child[0]), openable_area(child[1]), -1.0, -1.0, -1.0, -1.0, -1.0, -1.0);
        count = 2u;
        while count < 8u {
            var widest = 8u;
            var widest_area = -1.0;
            // The widest child's children (left, right).
            var opened = vec2<u32>(0u);
            for (var j = 0u; j < 8u; j++) {
                let wider = area[j] > widest_area;
                widest = select(widest, j, wider);
                widest_area = select(widest_area, area[j], wider);
                opened = select(opened, vec2<u32>(child[j].left_or_first, child[j].right_or_count), wider);
            }
            if widest == 8u {
                break;
            }
            let left = nodes[opened.x];
            let right = nodes[opened.y];
            set_child(&child, &child_index, widest, left, opened.x);
            set_child(&child, &child_index, count, right, opened.y);
            let left_area = openable_area(left);
            let right_area = openable_area(right);
            for (var t = 0u; t < 8u; t++) {
                area[t] = select(select(area[t], left_area, t == widest), right_area, t == count);
            }
            count++;
        }
    }

    var lo = child[0].min;
    var hi = child[0].max;
    for (var j = 1u; j < 8u; j++) {
        lo = select(lo, min(lo, child[j].min), j < count);
        hi = select(hi, max(hi, child[j].max), j < count);
    }
    let centre = lo + hi;

    // Octant slots, child by child in the draft's order: each takes the free slot of its best
    // score Σ_a ±offset_a (+ where bit a of the slot is set; the first of equal scores, the first
    // free slot where none beats NO_SCORE), the CPU twin's scan. A child's eight scores are two
    // vec4 of slots 0-3 and 4-7 (`slot_scores`, the twin's sums in its order). The loops run over
    // all eight children (those past `count` take no slot), so that no array is indexed by a value
    // a lane computes: such an array lives in memory (a GPU's local memory, a gather per lane on
    // lavapipe).
    // Three bits per child: its slot.
    var slot_bits = 0u;
    var free = 0xffu;
    for (var j = 0u; j < 8u; j++) {
        let scores = slot_scores(child[j], centre);
        var best_score = NO_SCORE;
        var slot = firstTrailingBit(free);
        for (var s = 0u; s < 8u; s++) {
            let score = select(scores[1][s & 3u], scores[0][s & 3u], s < 4u);
            let better = ((free >> s) & 1u) != 0u && score > best_score;
            best_score = select(best_score, score, better);
            slot = select(slot, s, better);
        }
        let takes = j < count;
        slot_bits |= select(0u, slot << (3u * j), takes);
        free &= select(0xffu, ~(1u << slot), takes);
    }

    let e = vec3<u32>(axis_exponent(lo.x, hi.x), axis_exponent(lo.y, hi.y), axis_exponent(lo.z, hi.z));
    var out: WideNode;
    out.origin = lo;
    var imask = 0u;
    var internal = 0u;
    var prims = 0u;
    var slot_words: array<vec2<u32>, 8>;
    for (var j = 0u; j < 8u; j++) {
        if j >= count {
            continue;
        }
        let s = (slot_bits >> (3u * j)) & 7u;
        let c = child[j];
        out.lo_x = with_byte(out.lo_x, s, quantize_lo(c.min.x, lo.x, e.x));
        out.lo_y = with_byte(out.lo_y, s, quantize_lo(c.min.y, lo.y, e.y));
        out.lo_z = with_byte(out.lo_z, s, quantize_lo(c.min.z, lo.z, e.z));
        out.hi_x = with_byte(out.hi_x, s, quantize_hi(c.max.x, lo.x, e.x));
        out.hi_y = with_byte(out.hi_y, s, quantize_hi(c.max.y, lo.y, e.y));
        out.hi_z = with_byte(out.hi_z, s, quantize_hi(c.max.z, lo.z, e.z));
        let is_leaf = (c.right_or_count & LEAF_FLAG) != 0u;
        if is_leaf {
            let n = c.right_or_count & ~LEAF_FLAG;
            out.leaf_counts = with_byte(out.leaf_counts, s, n);
            prims += n;
        } else {
            imask |= 1u << s;
            internal++;
        }
        // Written to every slot, kept in slot s: no array indexed by s.
        let internal_source = select(vec2<u32>(child_index[j], 0u), vec2<u32>(c.left_or_first, c.right_or_count), WIDE_COLLAPSE == COLLAPSE_GREEDY);
        let word = select(internal_source, vec2<u32>(c.left_or_first, 0u), is_leaf);
        for (var t = 0u; t < 8u; t++) {
            slot_words[t] = select(slot_words[t], word, t == s);
        }
    }
    out.exponents = e.x | (e.y << 8u) | (e.z << 16u) | (imask << 24u);
    return WideDraft(out, internal, prims, slot_words);
}

// Writes `draft` as wide node `w`, its internal children's sources from `child_base` and its
// leaves' references (their positions in `prim_indices`) from `prim_base`, both in slot order
// (step 4).
fn commit_wide_node(w: u32, draft: WideDraft, prim_base: u32, child_base: u32) {
    var out = draft.node;
    out.prim_base = select(0u, prim_base, draft.prims > 0u);
    out.child_base = select(0u, child_base, draft.internal > 0u);
    let imask = internal_slots(out);
    var next_prim = prim_base;
    var next_child = child_base;
    for (var s = 0u; s < 8u; s++) {
        if ((imask >> s) & 1u) != 0u {
            wide_sources[next_child] = draft.slot_words[s];
            next_child++;
        } else {
            let first = draft.slot_words[s].x;
            let n = slot_byte(out.leaf_counts, s);
            for (var i = 0u; i < n; i++) {
                wide_prims[next_prim + i] = first + i;
            }
            next_prim += n;
        }
    }
    wide_nodes[w] = out;
}

// A wave's allocation: its nodes' internal children and references so far, then where they
// start (child node, reference).
var<workgroup> wave_children: atomic<u32>;
var<workgroup> wave_prims: atomic<u32>;
var<workgroup> wave_bases: vec2<u32>;

// Emits wide node `w` if `emits` (from its `wide_sources` entry, the root from node 0), in a
// wave with the workgroup's other invocations: the wave's children and references are allocated
// with one device atomic per counter, not one per node. Returns w's internal children (first wide
// node, count; count 0: none, or not emitted). Every invocation of the workgroup calls it
// (uniform control flow).
fn emit_wave_node(w: u32, emits: bool, lid: u32) -> vec2<u32> {
    var draft: WideDraft;
    var child_offset = 0u;
    var prim_offset = 0u;
    if emits {
        draft = draft_wide_node(wide_node_source(w));
        child_offset = atomicAdd(&wave_children, draft.internal);
        prim_offset = atomicAdd(&wave_prims, draft.prims);
    }
    workgroupBarrier();
    if lid == 0u {
        let children = atomicExchange(&wave_children, 0u);
        let prims = atomicExchange(&wave_prims, 0u);
        var bases = vec2<u32>(0u);
        if children > 0u {
            bases.x = atomicAdd(&wide_counters[0], children);
        }
        if prims > 0u {
            bases.y = atomicAdd(&wide_counters[1], prims);
        }
        wave_bases = bases;
    }
    let bases = workgroupUniformLoad(&wave_bases);
    if !emits {
        return vec2<u32>(0u);
    }
    let child_base = bases.x + child_offset;
    if child_base + draft.internal > params.capacity {
        atomicAdd(&wide_counters[2], 1u);
        return vec2<u32>(0u);
    }
    commit_wide_node(w, draft, bases.y + prim_offset, child_base);
    return vec2<u32>(child_base, draft.internal);
}
