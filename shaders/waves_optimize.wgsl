// Overlapped treelet rounds, step 2 of a wave (treelet_waves.wgsl): each of the wave's treelets,
// one per invocation (treelet_dp.wgsl), or in a wave of fewer than params.team_below treelets
// one per workgroup, whose 32 invocations share its DP (treelet_team.wgsl; waves_find.wgsl sized
// the dispatch accordingly), and the candidates it adds to the next wave. The workgroup that
// finishes last writes the next wave's find arguments and clears this wave's counts (the
// candidates its find read, its treelets).

const TEAMS: u32 = 1u;

#include "treelet_wave_bindings.wgsl"
// The next wave's find dispatch's indirect arguments.
@group(0) @binding(10) var<storage, read_write> find_args: array<u32>;
// `treelet::subsets_by_size`, for the teams.
@group(0) @binding(11) var<storage, read> subset_order: array<u32>;

#include "treelet_dp.wgsl"
#include "treelet_team.wgsl"
#include "treelet_waves.wgsl"
#include "treelet_wave_optimize.wgsl"

@compute @workgroup_size(WAVE_WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let wave = params.wave;
    let group = wid.x + wid.y * nwg.x;
    let i = group * WAVE_WORKGROUP + lid;
    // An invocation's entry is loaded with the wave's state, before its treelet count is known
    // (past the wave's treelets, or clamped into the buffer, it is unused): one round trip to
    // memory before the treelet, not two.
    let lone_entry = lists[ops_base() + i];
    let state = stopped_and_state_word(lid, OPS_COUNT);
    if state.x != 0u {
        return;
    }
    let treelets = state.y;
    if by_teams(treelets) {
        let has_treelet = group < treelets;
        let entry = lists[ops_base() + min(group, max(treelets, 1u) - 1u)];
        queued = 0u;
        optimize_treelet_team(entry & NODE_MASK, has_treelet, 0u, lid);
        if has_treelet && lid == 0u {
            finish_entry(entry, wave);
        }
    } else if i < treelets {
        optimize_entry(lone_entry, wave);
    }
    if last_workgroup(lid, nwg.x * nwg.y, OPTIMIZE_TICKET) && lid == 0u {
        let candidates = atomicLoad(&wave_state[CANDIDATE_COUNT + ((wave + 1u) & 1u)]);
        let args = wave_args(candidates, WAVE_WORKGROUP);
        find_args[0] = args.x;
        find_args[1] = args.y;
        find_args[2] = args.z;
        end_wave(wave);
    }
}
