// Pre-splitting step 2 (Karras & Aila 2013, §5): the split counts s_t = floor(D·p_t) under the
// budget Σ s_t ≤ β·N. With q = p³ and E = D³, s_t = the largest k ≤ MAX_SPLITS with k³ ≤ E·q_t
// (exact in f32 on every device: k³ ≤ 32768 and the product is correctly rounded). E is the largest
// bit pattern below hi = (budget+1)³ / q_max whose sum fits (non-negative floats order like their
// bits). The search narrows [lo, hi) on the bit patterns: each step evaluates the sums at
// SPLIT_SEARCH_CANDIDATES evenly spaced patterns at once and keeps the gap after the last one that
// fits, a 16-ary search that needs 8 steps (2 dispatches each) where bisection needs 32.
// Entry points, dispatched in order: `init_search` (one invocation: [0, hi)), then per step
// `count_splits` (per triangle: its s_t at every candidate, summed per workgroup, then globally)
// and `narrow_search` (one invocation: keep the gap), and last `write_counts` (per triangle: its
// reference count s_t + 1 at the final lower bound, the input of the offsets scan).

struct BudgetParams {
    count: u32,
    row_pitch: u32,
    budget: u32,
    pad: u32,
}

#include "constants.wgsl"

// [0] largest q (bits), [1] lo, [2] hi (bits of E), [3 + j] Σ s_t at candidate j
@group(0) @binding(0) var<uniform> params: BudgetParams;
@group(0) @binding(1) var<storage, read> priorities: array<f32>;
@group(0) @binding(2) var<storage, read_write> budget_state: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> ref_counts: array<u32>;

const LO: u32 = 1u;
const HI: u32 = 2u;
const SUMS: u32 = 3u;

var<workgroup> workgroup_sums: array<atomic<u32>, SPLIT_SEARCH_CANDIDATES>;

// The largest k ≤ MAX_SPLITS (31) with k³ ≤ e·q, by binary search over k.
fn splits_at(e: f32, q: f32) -> u32 {
    let target_value = e * q;
    var k = 0u;
    for (var step = 16u; step > 0u; step >>= 1u) {
        let next = f32(k + step);
        if k + step <= MAX_SPLITS && next * next * next <= target_value {
            k += step;
        }
    }
    return k;
}

// Candidate j (0-based) of [lo, hi): lo + floor((hi - lo) · (j + 1) / (CANDIDATES + 1)), in u32
// arithmetic; consecutive candidates are at most ceil((hi - lo) / 16) apart.
fn candidate(lo: u32, hi: u32, j: u32) -> u32 {
    let parts = SPLIT_SEARCH_CANDIDATES + 1u;
    let range = hi - lo;
    return lo + (range / parts) * (j + 1u) + ((range % parts) * (j + 1u)) / parts;
}

@compute @workgroup_size(1)
fn init_search() {
    let q_max = bitcast<f32>(atomicLoad(&budget_state[0]));
    let b = f32(params.budget + 1u);
    var hi = 0.0;
    if q_max > 0.0 {
        hi = b * b * b / q_max;
    }
    atomicStore(&budget_state[LO], 0u);
    atomicStore(&budget_state[HI], bitcast<u32>(hi));
    for (var j = 0u; j < SPLIT_SEARCH_CANDIDATES; j++) {
        atomicStore(&budget_state[SUMS + j], 0u);
    }
}

@compute @workgroup_size(64)
fn count_splits(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if lid < SPLIT_SEARCH_CANDIDATES {
        atomicStore(&workgroup_sums[lid], 0u);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        let q = priorities[i];
        let lo = atomicLoad(&budget_state[LO]);
        let hi = atomicLoad(&budget_state[HI]);
        // s_t grows with E: nothing to add below the first candidate where it is not zero.
        if splits_at(bitcast<f32>(candidate(lo, hi, SPLIT_SEARCH_CANDIDATES - 1u)), q) > 0u {
            for (var j = 0u; j < SPLIT_SEARCH_CANDIDATES; j++) {
                let s = splits_at(bitcast<f32>(candidate(lo, hi, j)), q);
                if s > 0u {
                    atomicAdd(&workgroup_sums[j], s);
                }
            }
        }
    }
    workgroupBarrier();
    if lid < SPLIT_SEARCH_CANDIDATES {
        let sum = atomicLoad(&workgroup_sums[lid]);
        if sum > 0u {
            atomicAdd(&budget_state[SUMS + lid], sum);
        }
    }
}

@compute @workgroup_size(1)
fn narrow_search() {
    let lo = atomicLoad(&budget_state[LO]);
    let hi = atomicLoad(&budget_state[HI]);
    // Sums grow with the candidate: the new interval starts at the last one that fits (or lo) and
    // ends at the next one (or hi).
    var new_lo = lo;
    var new_hi = hi;
    for (var j = 0u; j < SPLIT_SEARCH_CANDIDATES; j++) {
        let c = candidate(lo, hi, j);
        if atomicLoad(&budget_state[SUMS + j]) <= params.budget {
            new_lo = c;
        } else if new_hi == hi {
            new_hi = c;
        }
        atomicStore(&budget_state[SUMS + j], 0u);
    }
    atomicStore(&budget_state[LO], new_lo);
    atomicStore(&budget_state[HI], new_hi);
}

@compute @workgroup_size(64)
fn write_counts(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i < params.count {
        ref_counts[i] = splits_at(bitcast<f32>(atomicLoad(&budget_state[LO])), priorities[i]) + 1u;
    }
}
