// One level of the binary-to-wide conversion (wide_collapse.wgsl). Level 0 (a direct dispatch
// of one workgroup) emits the root from binary node 0. Level L ≥ 1 (an indirect dispatch of the
// size level L − 1 wrote) emits the wide nodes [first, end) of its record, each invocation
// striding over them. Every level writes the record of the next: first = end of this level (the
// children allocated here follow it), end = the largest end of those children, and
// max(1, ceil((end − first) / 64)) workgroups (capped; the invocations stride), so every level
// dispatch runs and passes `first` on even when a level is empty.
#include "wide_collapse.wgsl"

fn size_next_level(level: u32, first: u32, children_end: u32) {
    atomicMax(&next_level[record_word(level + 1u, 4u)], children_end);
    let groups = min((children_end - first + EMIT_WORKGROUP - 1u) / EMIT_WORKGROUP, 65535u);
    atomicMax(&next_level[record_word(level + 1u, 0u)], groups);
}

fn open_next_level(level: u32, first: u32) {
    atomicMax(&next_level[record_word(level + 1u, 0u)], 1u);
    atomicStore(&next_level[record_word(level + 1u, 1u)], 1u);
    atomicStore(&next_level[record_word(level + 1u, 2u)], 1u);
    atomicMax(&next_level[record_word(level + 1u, 3u)], first);
    atomicMax(&next_level[record_word(level + 1u, 4u)], first);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    if params.level == 0u {
        if gid.x != 0u {
            return;
        }
        atomicStore(&wide_counters[0], 1u);
        open_next_level(0u, 1u);
        var base = 0u;
        let children = emit_wide_node(0u, 0u, &base);
        if children > 0u {
            size_next_level(0u, 1u, base + children);
        }
        return;
    }
    let first = this_level[record_word(params.level, 3u)];
    let end = max(this_level[record_word(params.level, 4u)], first);
    if gid.x == 0u {
        open_next_level(params.level, end);
    }
    let stride = groups.x * EMIT_WORKGROUP;
    for (var w = first + gid.x; w < end; w += stride) {
        var base = 0u;
        let children = emit_wide_node(w, wide_sources[w], &base);
        if children > 0u {
            size_next_level(params.level, end, base + children);
        }
    }
}
