// Treelet round, step 2: the treelets of one level (params.level <= level_dispatches), bucketed by
// nodes_level.wgsl. Dispatched indirectly with the level's workgroup count: a level of at least
// params.team_below treelets gives each an invocation (treelet_dp.wgsl), 32 per workgroup; a
// smaller level gives each a workgroup, whose 32 invocations share its DP (treelet_team.wgsl). The
// dispatches of the levels below have finished, so node data is read with plain loads.

const WORKGROUP: u32 = OPTIMIZE_WORKGROUP;
const TEAMS: u32 = 1u;

#include "treelet_roots.wgsl"
// `treelet::subsets_by_size`.
@group(0) @binding(7) var<storage, read> subset_order: array<u32>;
// The next round's level of each node a treelet finishes (treelet_dp.wgsl).
@group(0) @binding(8) var<storage, read_write> next_levels: array<u32>;

#include "treelet_dp.wgsl"
#include "treelet_team.wgsl"

var<workgroup> level_size: u32;

@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let first = params.level_first;
    let group = wid.x + wid.y * groups.x;
    let i = group * WORKGROUP + lid;
    // An invocation's root is loaded before the level's size is known (past the level's roots it
    // is another bucket's, or clamped into the buffer, and unused): both loads go out at once,
    // where the root's waited for the size, one round trip to memory more before the treelet.
    let root = roots[first + i];
    if lid == 0u {
        level_size = schedule[params.level - 1u];
    }
    let size = workgroupUniformLoad(&level_size);
    if by_teams(size) {
        let has_treelet = group < size;
        optimize_treelet_team(select(0u, roots[first + min(group, size - 1u)], has_treelet), has_treelet, 0u, lid);
    } else if i < size {
        optimize_treelet(root);
    }
}
