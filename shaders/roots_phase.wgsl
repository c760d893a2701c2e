// Phased treelet rounds (`TreeletSettings::phases`; CPU twin `WorkingTree::optimize_phased`): the
// roots of one phase. Invocation j takes internal node j; if it roots a treelet (at least gamma
// primitives) it walks up the parent links to the tree's root, and a node at depth ≡
// params.residue (mod params.phases) goes into the phase's bucket: schedule word params.level − 1,
// roots from slot 0 (the phase's treelets_optimize dispatch reads them there). The tree is the one
// the phases before left (a dispatch boundary orders memory: plain loads). Roots of one phase lie
// at least `phases` levels apart, more than a treelet reaches below its root, so their treelets
// are disjoint. A workgroup reserves the slots of its roots with one device atomic; the workgroup
// that finishes last (a ticket that counts on over the round's phases, each a dispatch of the same
// grid) writes the phase's indirect arguments: a workgroup per 32 treelets, or per treelet in a
// phase of fewer than params.team_below (a team of 32 invocations each, treelets_optimize.wgsl).
#include "treelet_round.wgsl"

const WORKGROUP: u32 = 64u;
// Workgroup size of treelets_optimize.wgsl.
const OPTIMIZE_WORKGROUP: u32 = 32u;

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read> parents: array<u32>;
@group(0) @binding(2) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(3) var<storage, read_write> schedule: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.count, count_limit[0]) leaves.
@group(0) @binding(4) var<storage, read> count_limit: array<u32>;
@group(0) @binding(5) var<storage, read_write> roots: array<u32>;

var<workgroup> workgroup_roots: atomic<u32>;
var<workgroup> workgroup_first: u32;
var<workgroup> is_last: u32;

@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = min(params.count, count_limit[0]);
    var takes = false;
    if j + 1u < n && prim_counts[j] >= params.gamma {
        var depth = 0u;
        for (var node = j; node != 0u; node = parents[node]) {
            depth++;
        }
        takes = depth % params.phases == params.residue;
    }
    let slot = params.level - 1u;
    var rank = 0u;
    if takes {
        rank = atomicAdd(&workgroup_roots, 1u);
    }
    workgroupBarrier();
    if lid == 0u {
        let count = atomicLoad(&workgroup_roots);
        if count != 0u {
            workgroup_first = atomicAdd(&schedule[slot], count);
        }
    }
    workgroupBarrier();
    if takes {
        roots[workgroup_first + rank] = j;
    }
    // Release: the workgroup's roots are counted before the ticket is taken.
    storageBarrier();
    if lid == 0u {
        let ticket = atomicAdd(&schedule[SCHEDULE_TICKET], 1u) + 1u;
        is_last = u32(ticket == params.level * nwg.x * nwg.y);
    }
    if workgroupUniformLoad(&is_last) == 0u {
        return;
    }
    // Acquire: every workgroup's count is visible.
    storageBarrier();
    if lid != 0u {
        return;
    }
    let size = atomicLoad(&schedule[slot]);
    let per_group = select(OPTIMIZE_WORKGROUP, 1u, size < params.team_below);
    let args = dispatch_args((size + per_group - 1u) / per_group);
    let at = SCHEDULE_ARGS + 3u * slot;
    atomicStore(&schedule[at], args.x);
    atomicStore(&schedule[at + 1u], args.y);
    atomicStore(&schedule[at + 2u], args.z);
}
