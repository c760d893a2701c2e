// Treelet round, step 3: the levels above level_dispatches, in one workgroup (a few treelets per
// level near the top of a tree: one dispatch each would mostly cost dispatch overhead). It starts
// from the roots of level top = level_dispatches + 1 (bucketed by nodes_level.wgsl) and climbs a
// level per wave: a root's level is one more than its children's highest (nodes_level.wgsl), so
// the parents in the level above the wave's are exactly the next wave, each added once, by the
// first of its children in the wave to claim it (an atomicMax of the next level into its arrival
// counter, zeroed by nodes_level.wgsl). Works for trees of any height. The next wave is found
// before this wave's treelets are optimized, as they change neither a root's parent link nor any
// level (no root of a wave is an ancestor of another), and by the workgroup's last invocations,
// so that in a wave of few treelets a team without one finds it while the others optimize.
// A wave of few treelets (treelet_team.wgsl's climb_wave_by_teams) is optimized by the workgroup's
// TEAMS teams of 32 invocations, a treelet per team at a time (treelet_team.wgsl: the waves near
// the top hold one to a few treelets); a larger wave one treelet per invocation (treelet_dp.wgsl).
// Node data is only shared within the workgroup: storageBarriers order it.

const WORKGROUP: u32 = 128u;
const TEAMS: u32 = 4u;

#include "treelet_roots.wgsl"
// `treelet::subsets_by_size`.
@group(0) @binding(7) var<storage, read> subset_order: array<u32>;
// The next round's level of each node a treelet finishes (treelet_dp.wgsl).
@group(0) @binding(8) var<storage, read_write> next_levels: array<u32>;
// This round's level of each root.
@group(0) @binding(9) var<storage, read> levels: array<u32>;
// Per internal node: the highest level whose wave claimed it (0: none), zeroed by
// nodes_level.wgsl.
@group(0) @binding(10) var<storage, read_write> arrivals: array<atomic<u32>>;
// Two halves of `half` entries each: the current wave and the next.
@group(0) @binding(11) var<storage, read_write> waves: array<u32>;

#include "treelet_dp.wgsl"
#include "treelet_team.wgsl"

var<workgroup> wave_size: u32;
var<workgroup> next_size: atomic<u32>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) lid: u32) {
    let top = params.level_dispatches + 1u;
    let half = arrayLength(&waves) / 2u;
    let first = params.level_first;
    let start = schedule[top - 1u];
    for (var i = lid; i < start; i += WORKGROUP) {
        waves[i] = roots[first + i];
    }
    if lid == 0u {
        wave_size = start;
        atomicStore(&next_size, 0u);
    }
    var current = 0u;
    var level = top;
    loop {
        // The wave's entries (and the last wave's node data) are stored before they are read.
        storageBarrier();
        let size = workgroupUniformLoad(&wave_size);
        if size == 0u {
            break;
        }
        let wave = current * half;
        let next = (1u - current) * half;
        // The next wave: the parents one level up, the last invocations first.
        for (var i = WORKGROUP - 1u - lid; i < size; i += WORKGROUP) {
            let root = waves[wave + i];
            if root != 0u {
                let parent = parents[root];
                // Both requests at once; only the first child of the wave to claim adds the parent.
                let unclaimed = atomicMax(&arrivals[parent], level + 1u) <= level;
                if levels[parent] == level + 1u && unclaimed {
                    waves[next + atomicAdd(&next_size, 1u)] = parent;
                }
            }
        }
        if climb_wave_by_teams(size) {
            let team = lid / TEAM_LANES;
            for (var done = 0u; done < size; done += TEAMS) {
                let i = done + team;
                let has_treelet = i < size;
                optimize_treelet_team(select(0u, waves[wave + min(i, size - 1u)], has_treelet), has_treelet, team, lid % TEAM_LANES);
            }
        } else {
            for (var i = lid; i < size; i += WORKGROUP) {
                optimize_treelet(waves[wave + i]);
            }
        }
        workgroupBarrier();
        if lid == 0u {
            wave_size = atomicLoad(&next_size);
            atomicStore(&next_size, 0u);
        }
        current = 1u - current;
        level++;
    }
}
