// Phased treelet rounds (`TreeletSettings::phases`; CPU twin `WorkingTree::optimize_phased`): the
// roots of one phase. Invocation j takes internal node j; if it roots a treelet (at least gamma
// primitives) it walks up the parent links towards the tree's root, and a node at depth ≡
// params.residue (mod params.phases) goes into the phase's bucket: schedule word params.level − 1,
// roots from slot 0 (the phase's treelets_optimize dispatch reads them there). The tree is the one
// the phases before left (a dispatch boundary orders memory: plain loads). Every root publishes
// its depth (mod phases) once it knows it, and a walk stops at the first ancestor that has
// published: an ancestor of a root is a root, so the walks of one phase share their upper parts
// (on a GPU, where all walk at once, a walk ends about halfway up). Published depths are exact
// whichever walker got there first, so the phase's roots are too: the same tree every time.
// A published depth carries its phase's stamp (k + 1 in the high byte), so a phase reads only
// its own and no phase zeroes the words for the next (the round starts with all zero). Roots of
// one phase lie at least `phases` levels apart and a treelet's leaves at most `phases` − 1 below
// its root (treelet_dp.wgsl's formation), so their treelets are disjoint. A workgroup reserves
// the slots of its roots with one device atomic; the workgroup that finishes last (a ticket that
// counts on over the round's phases, each a dispatch of the same grid) writes the phase's
// indirect arguments (`optimize_workgroups`, treelet_round.wgsl).
#include "treelet_round.wgsl"

const WORKGROUP: u32 = 256u;

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read> parents: array<u32>;
@group(0) @binding(2) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(3) var<storage, read_write> schedule: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.count, count_limit[0]) leaves.
@group(0) @binding(4) var<storage, read> count_limit: array<u32>;
@group(0) @binding(5) var<storage, read_write> roots: array<u32>;
// Per internal node its depth mod phases + 1 with the stamp of the phase that published it
// (`PHASE_STAMP`); another phase's stamp, or 0, reads as not known yet.
@group(0) @binding(6) var<storage, read_write> depths: array<atomic<u32>>;

// The stamp of phase k: k + 1 above the 24 bits of the depth residue + 1.
const PHASE_STAMP: u32 = 1u << 24u;

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
    let phase = params.phases - 1u - params.residue;
    let stamp = (phase + 1u) * PHASE_STAMP;
    var takes = false;
    if j + 1u < n && prim_counts[j] >= params.gamma {
        // Steps up to the tree's root (depth 0), or to an ancestor of known depth.
        var steps = 0u;
        var known = 0u;
        var node = j;
        while node != 0u {
            let word = atomicLoad(&depths[node]);
            if word >= stamp && word < stamp + PHASE_STAMP {
                known = word - stamp;
                break;
            }
            node = parents[node];
            steps++;
        }
        let residue = (select(0u, known - 1u, known != 0u) + steps) % params.phases;
        atomicStore(&depths[j], stamp + residue + 1u);
        takes = residue == params.residue;
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
    let args = dispatch_args(optimize_workgroups(atomicLoad(&schedule[slot])));
    let at = SCHEDULE_ARGS + 3u * slot;
    atomicStore(&schedule[at], args.x);
    atomicStore(&schedule[at + 1u], args.y);
    atomicStore(&schedule[at + 2u], args.z);
}
