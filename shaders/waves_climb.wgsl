// Overlapped treelet rounds, the waves after the dispatched ones (treelet_waves.wgsl), in one
// workgroup: the waves near the end hold few treelets, where a dispatch each would mostly cost
// its launch. Each wave: the candidates sorted (step 1), a barrier, the treelets optimized
// (step 2), a barrier; it ends with the first wave that has no treelet (none is left then: the
// CPU twin ends likewise). A wave of few treelets (treelet_team.wgsl's climb_wave_by_teams) is
// optimized by the workgroup's TEAMS teams of 32 invocations, a treelet per team at a time
// (treelet_team.wgsl), as in treelets_climb.wgsl; a larger one a treelet per invocation. Node
// data is only shared within the workgroup: storageBarriers order it.

const WORKGROUP: u32 = 128u;
const TEAMS: u32 = 4u;

#include "treelet_wave_bindings.wgsl"
// `treelet::subsets_by_size`, for the teams.
@group(0) @binding(10) var<storage, read> subset_order: array<u32>;

#include "treelet_dp.wgsl"
#include "treelet_team.wgsl"
#include "treelet_waves.wgsl"
#include "treelet_wave_optimize.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) lid: u32) {
    var wave = params.wave;
    if rounds_stopped(lid) {
        return;
    }
    loop {
        // The candidates stored by the wave before (or the dispatches before) are visible.
        storageBarrier();
        let candidates = state_word(lid, CANDIDATE_COUNT + (wave & 1u));
        for (var i = lid; i < candidates; i += WORKGROUP) {
            find_candidate(lists[candidates_base(wave) + i], wave);
        }
        storageBarrier();
        let treelets = state_word(lid, OPS_COUNT);
        if treelets == 0u {
            break;
        }
        if climb_wave_by_teams(treelets) {
            let team = lid / TEAM_LANES;
            let lane = lid % TEAM_LANES;
            for (var done = 0u; done < treelets; done += TEAMS) {
                let i = done + team;
                let has_treelet = i < treelets;
                let entry = lists[ops_base() + min(i, treelets - 1u)];
                queued = 0u;
                optimize_treelet_team(entry & NODE_MASK, has_treelet, team, lane);
                if has_treelet && lane == 0u {
                    finish_entry(entry, wave);
                }
            }
        } else {
            for (var i = lid; i < treelets; i += WORKGROUP) {
                optimize_entry(lists[ops_base() + i], wave);
            }
        }
        storageBarrier();
        workgroupBarrier();
        if lid == 0u {
            end_wave(wave);
        }
        wave++;
    }
}
