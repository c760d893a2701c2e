// Overlapped treelet rounds, step 1 of a wave (treelet_waves.wgsl): each of the wave's candidates
// goes to the wave's treelets, to the next wave's candidates or nowhere. The workgroup that
// finishes last writes the arguments of the wave's optimize dispatch (a workgroup per 32
// treelets, or per treelet below params.team_below: waves_optimize.wgsl); a wave without
// treelets stops the rounds (no later wave could find one: nothing changes any more).
#include "bvh_node.wgsl"
#include "treelet_round.wgsl"

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> parents: array<u32>;
@group(0) @binding(3) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> done: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> candidate_waves: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> lists: array<u32>;
@group(0) @binding(7) var<storage, read_write> wave_state: array<atomic<u32>>;
// The wave's optimize dispatch's indirect arguments.
@group(0) @binding(8) var<storage, read_write> optimize_args: array<u32>;

#include "treelet_waves.wgsl"

@compute @workgroup_size(WAVE_WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let wave = params.wave;
    let i = (wid.x + wid.y * nwg.x) * WAVE_WORKGROUP + lid;
    // An invocation's candidate is loaded with the wave's state, before the candidate count is
    // known (past the wave's candidates, or clamped into the buffer, it is unused): one round
    // trip to memory before the candidate's own loads, where there were three.
    let candidate = lists[candidates_base(wave) + i];
    let state = stopped_and_state_word(lid, CANDIDATE_COUNT + (wave & 1u));
    if state.x != 0u {
        return;
    }
    if i < state.y {
        find_candidate(candidate, wave);
    }
    if last_workgroup(lid, nwg.x * nwg.y, FIND_TICKET) && lid == 0u {
        let treelets = atomicLoad(&wave_state[OPS_COUNT]);
        let args = wave_args(treelets, select(WAVE_WORKGROUP, 1u, treelets < params.team_below));
        optimize_args[0] = args.x;
        optimize_args[1] = args.y;
        optimize_args[2] = args.z;
        if treelets == 0u {
            atomicStore(&wave_state[STOPPED], 1u);
        }
    }
}
