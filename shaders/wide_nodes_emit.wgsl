// One level of the binary-to-wide conversion (wide_collapse.wgsl). Level 0 (a direct dispatch
// of one workgroup) emits the root from binary node 0 and, level after level with a barrier
// between, the levels below it up to top = min(START_LEVELS, level_dispatches): at most 8 and 64
// wide nodes, one wave of the workgroup each, so these levels cost no dispatch of their own.
// Level L > top (an indirect dispatch of the size level L − 1 wrote) emits the wide nodes
// [first, end) of its record, the workgroups striding over them a wave at a time (one device
// atomic per wave and counter allocates the wave's children and references). The last level of a
// dispatch writes the record of the next: first = end of this level (the children allocated here
// follow it), end = the largest end of those children (each workgroup raises it once, for all its
// nodes), and ceil((end − first) / 64) workgroups (capped; the invocations stride): none once a
// level allocates no children, so the level dispatches past the tree's depth cost only their
// launch. The record the last dispatch writes sizes wide_nodes_finish.wgsl, which emits the rest
// of the tree.
#include "wide_collapse.wgsl"

// The end of the children this workgroup's nodes of the level allocated (0: none).
var<workgroup> workgroup_children_end: atomic<u32>;

// Sizes the next level's record to cover the children that this workgroup's nodes of level
// `level` allocated, up to `children_end` (this invocation's; 0: none), with one device atomic
// per word for the workgroup: per node, a level's thousands of nodes would all raise the same two
// words. Every invocation of the workgroup calls it once per level (uniform control flow).
fn size_next_level(level: u32, first: u32, children_end: u32, lid: u32) {
    if children_end != 0u {
        atomicMax(&workgroup_children_end, children_end);
    }
    workgroupBarrier();
    if lid == 0u {
        let end = atomicLoad(&workgroup_children_end);
        if end != 0u {
            atomicMax(&next_level[record_word(level + 1u, 4u)], end);
            let groups = min((end - first + EMIT_WORKGROUP - 1u) / EMIT_WORKGROUP, 65535u);
            atomicMax(&next_level[record_word(level + 1u, 0u)], groups);
        }
    }
}

// The end of the internal children that emit_wave_node returned (first, count): 0 for none.
fn allocated_end(children: vec2<u32>) -> u32 {
    return select(0u, children.x + children.y, children.y > 0u);
}

fn open_next_level(level: u32, first: u32) {
    atomicStore(&next_level[record_word(level + 1u, 1u)], 1u);
    atomicStore(&next_level[record_word(level + 1u, 2u)], 1u);
    atomicMax(&next_level[record_word(level + 1u, 3u)], first);
    atomicMax(&next_level[record_word(level + 1u, 4u)], first);
}

// Levels below the root that the root's workgroup emits (level L holds at most 8^L wide nodes:
// 64 = EMIT_WORKGROUP at level 2). Rust twin: `START_LEVELS` in src/bvh/wide/converter.rs.
const START_LEVELS: u32 = 2u;

var<workgroup> start_end: u32;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    // The levels this dispatch emits, [level, top]: the root's (one workgroup) the root and the
    // levels below it, a level dispatch its record's. One loop and one call of emit_wave_node for
    // both, so that the kernel holds one copy of the draft (RADV: 23,108 → 11,860 bytes of code):
    // a lone invocation's draft waits on its instructions as well as on its loads.
    var level = params.level;
    var top = params.level;
    var first = 0u;
    var end = 1u;
    if params.level == 0u {
        top = min(START_LEVELS, params.level_dispatches);
        if lid == 0u {
            atomicStore(&wide_counters[0], 1u);
        }
    } else {
        let range = record_range(params.level);
        first = range.x;
        end = range.y;
    }
    // The workgroups stride over the level's nodes a wave at a time.
    let stride = groups.x * EMIT_WORKGROUP;
    loop {
        if level == top && gid.x == 0u {
            open_next_level(top, end);
        }
        var children_end = 0u;
        for (var wave = first + wid.x * EMIT_WORKGROUP; wave < end; wave += stride) {
            let children = emit_wave_node(wave + lid, wave + lid < end, lid);
            children_end = max(children_end, allocated_end(children));
        }
        if level == top {
            size_next_level(top, end, children_end, lid);
            return;
        }
        // The root's workgroup: this level's sources are stored before the next level reads them.
        storageBarrier();
        if lid == 0u {
            // An overflow (capacity too small) ends the conversion.
            start_end = select(atomicLoad(&wide_counters[0]), end, atomicLoad(&wide_counters[2]) != 0u);
        }
        first = end;
        end = workgroupUniformLoad(&start_end);
        level++;
    }
}
