// The budget search of pre-splitting (Karras & Aila 2013, §5), shared by its two kernels,
// dispatched in order: per step splits_count.wgsl, then splits_assign.wgsl. The split counts
// s_t = floor(D·p_t) under the budget Σ s_t ≤ β·N: with q = p³ and E = D³, s_t = the largest
// k ≤ MAX_SPLITS with k³ ≤ E·q_t (exact in f32 on every device: k³ ≤ 32768 and the product is
// correctly rounded). E is the largest bit pattern below hi = (budget+1)³ / q_max whose sum fits
// (non-negative floats order like their bits). The search narrows [0, hi) on the bit patterns:
// each step evaluates the sums at SPLIT_SEARCH_CANDIDATES evenly spaced patterns at once and keeps
// the gap after the last one that fits, a 256-ary search that needs 4 steps where bisection needs
// 32. A step counts, per candidate, the splits that first fit there (a histogram: the sum at
// candidate j is the count of bins 0..=j), and the workgroup that finishes the step last (a
// ticket; no workgroup waits for another) narrows the interval for the next step: one dispatch
// per step. CPU twin: `budget_scale` (the same E by bisection) and `splits_at`
// (src/bvh/presplit/cpu.rs).

struct BudgetParams {
    count: u32,
    // splits_assign's grid (splits_count takes its triangles by workgroup index).
    row_pitch: u32,
    budget: u32,
    // splits_count: the search step (0-based).
    step: u32,
}

#include "constants.wgsl"

// `budget_state` (zeroed before the stage): [0] the largest q (bits; triangles_priority.wgsl),
// [STEP_TICKETS + k] the ticket of step k, [STEP_INTERVALS + 2k, + 1] the interval (lo, hi) after
// step k, [STEP_BINS + k·CANDIDATES + j] step k's histogram, [SPLIT_SCALE_WORD] the scale found
// (bits of E; written by splits_assign, read by tests). SPLIT_SCALE_WORD (gpu::constants) is the
// word after the last step's histogram.
const STEP_TICKETS: u32 = 1u;
const STEP_INTERVALS: u32 = STEP_TICKETS + SPLIT_SEARCH_STEPS;
const STEP_BINS: u32 = STEP_INTERVALS + 2u * SPLIT_SEARCH_STEPS;

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
// arithmetic; consecutive candidates are at most ceil((hi - lo) / (CANDIDATES + 1)) apart.
fn candidate(lo: u32, hi: u32, j: u32) -> u32 {
    let parts = SPLIT_SEARCH_CANDIDATES + 1u;
    let range = hi - lo;
    return lo + (range / parts) * (j + 1u) + ((range % parts) * (j + 1u)) / parts;
}

// The interval before step `step` (`steps` = SPLIT_SEARCH_STEPS: the final one, whose lo is E):
// [0, (budget + 1)³ / q_max) before the first, else what the step before narrowed it to.
fn search_interval(step: u32) -> vec2<u32> {
    if step > 0u {
        let at = STEP_INTERVALS + 2u * (step - 1u);
        return vec2<u32>(atomicLoad(&budget_state[at]), atomicLoad(&budget_state[at + 1u]));
    }
    let q_max = bitcast<f32>(atomicLoad(&budget_state[0]));
    let b = f32(params.budget + 1u);
    var hi = 0u;
    if q_max > 0.0 {
        hi = bitcast<u32>(b * b * b / q_max);
    }
    return vec2<u32>(0u, hi);
}
