// Pre-splitting step 2b (Karras & Aila 2013, §5), after the last step of the budget search
// (splits_search.wgsl): per triangle, its reference count s_t + 1 at the scale found (the low end
// of the final interval; the input of the offsets scan); the scale's bits go to
// budget_state[SPLIT_SCALE_WORD].
#include "splits_search.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        interval = search_interval(SPLIT_SEARCH_STEPS);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * params.row_pitch;
    if i == 0u {
        atomicStore(&budget_state[SPLIT_SCALE_WORD], interval.x);
    }
    if i < params.count {
        ref_counts[i] = splits_at(bitcast<f32>(interval.x), priorities[i]) + 1u;
    }
}
