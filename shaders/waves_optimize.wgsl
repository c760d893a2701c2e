// Overlapped treelet rounds, step 2 of a wave (treelet_waves.wgsl): each of the wave's treelets,
// one per invocation (treelet_dp.wgsl), and the candidates it adds to the next wave. The
// workgroup that finishes last writes the next wave's find arguments and clears this wave's
// counts (the candidates its find read, its treelets).
#include "bvh_node.wgsl"
#include "treelet_round.wgsl"

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> costs: array<f32>;
// The next round's levels, which the overlapped rounds do not use (params.next_gamma is
// u32::MAX: treelet_dp.wgsl stores zeros).
@group(0) @binding(5) var<storage, read_write> next_levels: array<u32>;
@group(0) @binding(6) var<storage, read_write> done: array<u32>;
@group(0) @binding(7) var<storage, read_write> candidate_waves: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> lists: array<u32>;
@group(0) @binding(9) var<storage, read_write> wave_state: array<atomic<u32>>;
// The next wave's find dispatch's indirect arguments.
@group(0) @binding(10) var<storage, read_write> find_args: array<u32>;

#include "treelet_dp.wgsl"
#include "treelet_waves.wgsl"
#include "treelet_wave_optimize.wgsl"

@compute @workgroup_size(WAVE_WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let wave = params.wave;
    if rounds_stopped(lid) {
        return;
    }
    let i = (wid.x + wid.y * nwg.x) * WAVE_WORKGROUP + lid;
    if i < atomicLoad(&wave_state[OPS_COUNT]) {
        optimize_entry(lists[ops_base() + i], wave);
    }
    if last_workgroup(lid, nwg.x * nwg.y, OPTIMIZE_TICKET) && lid == 0u {
        let args = wave_args(atomicLoad(&wave_state[CANDIDATE_COUNT + ((wave + 1u) & 1u)]));
        find_args[0] = args.x;
        find_args[1] = args.y;
        find_args[2] = args.z;
        end_wave(wave);
    }
}
