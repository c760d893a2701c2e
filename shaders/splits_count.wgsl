// Pre-splitting step 2a (Karras & Aila 2013, §5), one dispatch per step of the budget search
// (splits_search.wgsl): per triangle, its split count s_t at each of the step's candidate scales,
// summed per workgroup, then into the step's words of `budget_state`.
#include "splits_search.wgsl"

var<workgroup> workgroup_sums: array<atomic<u32>, SPLIT_SEARCH_CANDIDATES>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if lid < SPLIT_SEARCH_CANDIDATES {
        atomicStore(&workgroup_sums[lid], 0u);
    }
    if lid == 0u {
        interval = search_interval(params.step);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        let q = priorities[i];
        let lo = interval.x;
        let hi = interval.y;
        // s_t grows with E: nothing to add below the first candidate where it is not zero.
        if splits_at(bitcast<f32>(candidate(lo, hi, SPLIT_SEARCH_CANDIDATES - 1u)), q) > 0u {
            for (var j = 0u; j < SPLIT_SEARCH_CANDIDATES; j++) {
                let s = splits_at(bitcast<f32>(candidate(lo, hi, j)), q);
                if s > 0u {
                    atomicAdd(&workgroup_sums[j], s);
                }
            }
        }
    }
    workgroupBarrier();
    if lid < SPLIT_SEARCH_CANDIDATES {
        let sum = atomicLoad(&workgroup_sums[lid]);
        if sum > 0u {
            atomicAdd(&budget_state[1u + params.step * SPLIT_SEARCH_CANDIDATES + lid], sum);
        }
    }
}
