// The levels of the binary-to-wide conversion after the last level dispatch, in one workgroup:
// it emits the wide nodes from the first one no level dispatch reached (wide_counters[3], the
// end of what they emitted) to the current end of the allocation, then
// the nodes those allocated, and so on until no level adds any (a barrier between levels orders
// the sources). Deep, narrow tails of the tree cost one wave per level here instead of one
// dispatch each.
#include "wide_collapse.wgsl"

const FINISH_WORKGROUP: u32 = 256u;

var<workgroup> level_end: u32;
var<workgroup> emitted_end: u32;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        emitted_end = atomicLoad(&wide_counters[3]);
    }
    var first = workgroupUniformLoad(&emitted_end);
    loop {
        if lid == 0u {
            // An overflow (capacity too small) ends the conversion.
            level_end = select(atomicLoad(&wide_counters[0]), 0u, atomicLoad(&wide_counters[2]) != 0u);
        }
        let end = workgroupUniformLoad(&level_end);
        if first >= end {
            break;
        }
        for (var wave = first; wave < end; wave += FINISH_WORKGROUP) {
            emit_wave_node(wave + lid, end, lid);
        }
        storageBarrier();
        first = end;
    }
}
