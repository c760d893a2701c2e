// Treelet round, step 2: the treelet roots of levels 1 ..= level_dispatches + 1 (counted by
// nodes_level.wgsl) into one array ordered by level (`roots`: level L's roots start after those of
// the levels below; their order within a level is free, as a level's treelets are disjoint), and
// the indirect dispatch arguments of each level's treelets_optimize dispatch (invocation 0: a
// workgroup per treelet below params.team_below treelets, else per 32 treelets). One
// invocation per internal node; also zeroes the node's arrival counter for treelets_climb.
#include "treelet_round.wgsl"

const WORKGROUP: u32 = 64u;
// Workgroup size of treelets_optimize.wgsl.
const OPTIMIZE_WORKGROUP: u32 = 32u;
const MAX_WORKGROUPS_X: u32 = 65535u;

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(2) var<storage, read> levels: array<u32>;
@group(0) @binding(3) var<storage, read_write> arrivals: array<u32>;
@group(0) @binding(4) var<storage, read_write> schedule: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> roots: array<u32>;
@group(0) @binding(6) var<storage, read> count_limit: array<u32>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = min(params.count, count_limit[0]);
    if j == 0u {
        for (var level = 1u; level <= params.level_dispatches; level++) {
            // A workgroup per treelet when teams optimize the level, else per OPTIMIZE_WORKGROUP.
            let size = atomicLoad(&schedule[level - 1u]);
            let groups = select((size + OPTIMIZE_WORKGROUP - 1u) / OPTIMIZE_WORKGROUP, size, size < params.team_below);
            let y = (groups + MAX_WORKGROUPS_X - 1u) / MAX_WORKGROUPS_X;
            let at = SCHEDULE_ARGS + 3u * (level - 1u);
            atomicStore(&schedule[at], select(0u, (groups + y - 1u) / max(y, 1u), y > 0u));
            atomicStore(&schedule[at + 1u], y);
            atomicStore(&schedule[at + 2u], 1u);
        }
    }
    if j + 1u >= n {
        return;
    }
    arrivals[j] = 0u;
    let level = levels[j];
    if prim_counts[j] >= params.gamma && level <= params.level_dispatches + 1u {
        var first = 0u;
        for (var below = 1u; below < level; below++) {
            first += atomicLoad(&schedule[below - 1u]);
        }
        roots[first + atomicAdd(&schedule[SCHEDULE_CURSORS + level - 1u], 1u)] = j;
    }
}
