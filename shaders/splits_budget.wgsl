// Pre-splitting step 2 (Karras & Aila 2013, §5): the split counts s_t = floor(D·p_t) under the
// budget Σ s_t ≤ β·N, with D found by bisection. With q = p³ and E = D³:
// (the bisection runs on the bit patterns of E, which order like the non-negative floats they
// encode: exact integer midpoints, and 32 halvings span the whole float range)
// s_t = the largest k with k³ ≤ E·q_t (capped at MAX_SPLITS), exact in f32 on both CPU and GPU.
// Entry points, dispatched in order: `init_search` (one invocation: the search interval [0, hi] with
// hi = (budget+1)³ / q_max), then per step `count_splits` (per triangle: Σ s_t at the midpoint)
// and `bisect_step` (one invocation: keep the half whose sum fits), and last `write_counts` (per triangle:
// its reference count s_t + 1 at the final lower bound, the input of the offsets scan).

struct BudgetParams {
    count: u32,
    row_pitch: u32,
    budget: u32,
    pad: u32,
}

// [0] largest q (bits), [1] Σ s_t at mid, [2] lo, [3] hi, [4] mid (bits of E)
@group(0) @binding(0) var<uniform> params: BudgetParams;
@group(0) @binding(1) var<storage, read> priorities: array<f32>;
@group(0) @binding(2) var<storage, read_write> budget_state: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> ref_counts: array<u32>;

#include "constants.wgsl"

var<workgroup> workgroup_sum: atomic<u32>;

fn splits_at(e: f32, q: f32) -> u32 {
    let target_value = e * q;
    var k = 0u;
    loop {
        let next = f32(k + 1u);
        if k >= MAX_SPLITS || next * next * next > target_value {
            break;
        }
        k++;
    }
    return k;
}

fn load_f32(i: u32) -> f32 {
    return bitcast<f32>(atomicLoad(&budget_state[i]));
}

@compute @workgroup_size(1)
fn init_search() {
    let q_max = load_f32(0u);
    let b = f32(params.budget + 1u);
    var hi = 0.0;
    if q_max > 0.0 {
        hi = b * b * b / q_max;
    }
    atomicStore(&budget_state[2], 0u);
    atomicStore(&budget_state[3], bitcast<u32>(hi));
    atomicStore(&budget_state[4], bitcast<u32>(hi) / 2u);
    atomicStore(&budget_state[1], 0u);
}

@compute @workgroup_size(64)
fn count_splits(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        atomicStore(&workgroup_sum, 0u);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        atomicAdd(&workgroup_sum, splits_at(load_f32(4u), priorities[i]));
    }
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&budget_state[1], atomicLoad(&workgroup_sum));
    }
}

@compute @workgroup_size(1)
fn bisect_step() {
    let mid = atomicLoad(&budget_state[4]);
    if atomicLoad(&budget_state[1]) <= params.budget {
        atomicStore(&budget_state[2], mid);
    } else {
        atomicStore(&budget_state[3], mid);
    }
    let lo = atomicLoad(&budget_state[2]);
    let hi = atomicLoad(&budget_state[3]);
    atomicStore(&budget_state[4], lo + (hi - lo) / 2u);
    atomicStore(&budget_state[1], 0u);
}

@compute @workgroup_size(64)
fn write_counts(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        ref_counts[i] = splits_at(load_f32(2u), priorities[i]) + 1u;
    }
}
