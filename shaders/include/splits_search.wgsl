// The budget search of pre-splitting (Karras & Aila 2013, §5), shared by its two kernels,
// dispatched in order: per step splits_count.wgsl, then splits_assign.wgsl. The split counts
// s_t = floor(D·p_t) under the budget Σ s_t ≤ β·N: with q = p³ and E = D³, s_t = the largest
// k ≤ MAX_SPLITS with k³ ≤ E·q_t (exact in f32 on every device: k³ ≤ 32768 and the product is
// correctly rounded). E is the largest bit pattern below hi = (budget+1)³ / q_max whose sum fits
// (non-negative floats order like their bits). The search narrows [0, hi) on the bit patterns:
// each step evaluates the sums at SPLIT_SEARCH_CANDIDATES evenly spaced patterns at once and keeps
// the gap after the last one that fits, a 16-ary search that needs 8 steps where bisection needs
// 32. Every step's sums go to their own words of `budget_state` (zeroed before the stage), so the
// interval before step k is a function of the sums of steps 0..k-1 that each workgroup replays
// itself (`search_interval`): one dispatch per step, no dispatch to narrow the interval.
// CPU twin: `budget_scale` and `splits_at` (src/bvh/presplit/cpu.rs).

struct BudgetParams {
    count: u32,
    row_pitch: u32,
    budget: u32,
    // splits_count: the search step (0-based).
    step: u32,
}

#include "constants.wgsl"

// [0] largest q (bits; triangles_priority.wgsl), [1 + k·CANDIDATES + j] Σ s_t at candidate j of
// step k, [SPLIT_SCALE_WORD] the scale found (bits of E; written by splits_assign, read by tests).
@group(0) @binding(0) var<uniform> params: BudgetParams;
@group(0) @binding(1) var<storage, read> priorities: array<f32>;
@group(0) @binding(2) var<storage, read_write> budget_state: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> ref_counts: array<u32>;

// The search interval [lo, hi) of this dispatch's step (bit patterns of E).
var<workgroup> interval: vec2<u32>;

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

// The interval before step `steps`: [0, (budget + 1)³ / q_max), narrowed by the sums of steps
// 0..steps-1. Sums grow with the candidate: each step keeps the gap from the last candidate that
// fits (or lo) to the next one (or hi).
fn search_interval(steps: u32) -> vec2<u32> {
    let q_max = bitcast<f32>(atomicLoad(&budget_state[0]));
    let b = f32(params.budget + 1u);
    var lo = 0u;
    var hi = 0u;
    if q_max > 0.0 {
        hi = bitcast<u32>(b * b * b / q_max);
    }
    for (var k = 0u; k < steps; k++) {
        var new_lo = lo;
        var new_hi = hi;
        for (var j = 0u; j < SPLIT_SEARCH_CANDIDATES; j++) {
            let c = candidate(lo, hi, j);
            if atomicLoad(&budget_state[1u + k * SPLIT_SEARCH_CANDIDATES + j]) <= params.budget {
                new_lo = c;
            } else if new_hi == hi {
                new_hi = c;
            }
        }
        lo = new_lo;
        hi = new_hi;
    }
    return vec2<u32>(lo, hi);
}
