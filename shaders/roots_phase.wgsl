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
// its root (treelet_dp.wgsl's formation), so their treelets are disjoint.
// A root's slot comes from the bucket's counter, and whoever takes a slot that needs one more
// workgroup of the phase's treelets_optimize dispatch raises its indirect arguments to cover it
// (`atomicMax`: the schedule is zero at the round's start), so no workgroup waits for the others
// and none finishes the phase. On GPUs a workgroup takes its roots' slots with one device atomic
// (`AGGREGATE_ROOTS`, two workgroup barriers); a CPU device takes one per root, as a kernel with
// barriers runs there as a coroutine of its SIMD batches (lavapipe, conference: about 8 → 5 ms
// per dispatch).
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
#include "treelet_arguments.wgsl"

// The stamp of phase k: k + 1 above the 24 bits of the depth residue + 1.
const PHASE_STAMP: u32 = 1u << 24u;

// 1: a workgroup reserves its roots' slots with one device atomic (GPUs); 0: each root its own
// (CPU devices: no barrier in the kernel).
override AGGREGATE_ROOTS: u32 = 1u;

var<workgroup> workgroup_roots: atomic<u32>;
var<workgroup> workgroup_first: u32;

// Raises the phase's treelets_optimize arguments to cover `treelets` treelets
// (`optimize_workgroups`). Each word ends as the most that any count raised it to, and one
// count's x times y covers it, so the final count is covered: a dispatch of teams that turns lone
// past params.team_below keeps the teams' larger grid, whose extra workgroups find no treelet.
fn raise_arguments(treelets: u32) {
    raise_level_arguments(params.level, optimize_workgroups(treelets));
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
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
    let bucket = params.level - 1u;
    if AGGREGATE_ROOTS == 0u {
        if takes {
            let slot = atomicAdd(&schedule[bucket], 1u);
            roots[slot] = j;
            // Only counts that need one more workgroup raise the arguments: each team's, or the
            // first treelet of each workgroup of lone invocations.
            if slot % OPTIMIZE_WORKGROUP == 0u || slot + 1u < params.team_below {
                raise_arguments(slot + 1u);
            }
        }
        return;
    }
    var rank = 0u;
    if takes {
        rank = atomicAdd(&workgroup_roots, 1u);
    }
    workgroupBarrier();
    if lid == 0u {
        let count = atomicLoad(&workgroup_roots);
        if count != 0u {
            let first = atomicAdd(&schedule[bucket], count);
            workgroup_first = first;
            raise_arguments(first + count);
        }
    }
    workgroupBarrier();
    if takes {
        roots[workgroup_first + rank] = j;
    }
}
