// Pre-splitting step 2a (Karras & Aila 2013, §5), one dispatch per step of the budget search
// (splits_search.wgsl): per triangle (SPLIT_COUNT_ITEMS per invocation), the candidate scale of
// the step at which each of its splits first fits, counted per workgroup, then added into the
// step's histogram in `budget_state`; the workgroup that finishes last narrows the interval for
// the next step.
// A triangle's split count s_t grows with the scale, so its k-th split fits from the first
// candidate j with k³ ≤ c_j·q on: the splits that fit at the step's first candidate go to bin 0,
// each further one up to the count at the last candidate to the bin its binary search over the
// candidates finds. The sum at candidate j is then the count of bins 0..=j.
#include "splits_search.wgsl"
#include "workgroup_scan.wgsl"

const WORKGROUP: u32 = 256u;
// The binary search's first stride: the highest power of two of SPLIT_SEARCH_CANDIDATES.
const FIRST_STRIDE: u32 = 1u << (31u - countLeadingZeros(SPLIT_SEARCH_CANDIDATES));

var<workgroup> workgroup_bins: array<atomic<u32>, SPLIT_SEARCH_CANDIDATES>;
var<workgroup> is_last: u32;

// The scale of candidate j of [lo, hi).
fn scale_at(lo: u32, hi: u32, j: u32) -> f32 {
    return bitcast<f32>(candidate(lo, hi, j));
}

// The first candidate j of [lo, hi) with k³ ≤ c_j·q (the last candidate's holds): a binary
// search with fixed strides (the same steps in every invocation).
fn first_fitting(lo: u32, hi: u32, q: f32, k: u32) -> u32 {
    let cube = f32(k * k * k);
    var j = 0u;
    for (var stride = FIRST_STRIDE; stride > 0u; stride >>= 1u) {
        if j + stride <= SPLIT_SEARCH_CANDIDATES && !(cube <= scale_at(lo, hi, j + stride - 1u) * q) {
            j += stride;
        }
    }
    return j;
}

// The last workgroup of step `step`, every invocation: the interval after it, from the step's
// histogram: the gap after the last candidate whose sum fits the budget, [c(J - 1), c(J)) for the
// first candidate J that does not fit (c(-1) = lo, c(CANDIDATES) = hi). Invocation j loads bin j,
// a workgroup scan gives the sums (so no invocation waits for the bins one after another), and
// the one invocation at the gap stores it: j = J, or the last candidate when all fit.
fn narrow(step: u32, lid: u32) {
    let lo = interval.x;
    let hi = interval.y;
    var bin = 0u;
    if lid < SPLIT_SEARCH_CANDIDATES {
        bin = atomicLoad(&budget_state[STEP_BINS + step * SPLIT_SEARCH_CANDIDATES + lid]);
    }
    // The sums at candidates lid - 1 and lid (sums grow with j).
    let before = workgroup_scan(lid, bin).x;
    let fits = before + bin <= params.budget;
    let last = SPLIT_SEARCH_CANDIDATES - 1u;
    var gap = vec2<u32>(0u);
    var at_gap = false;
    if lid < SPLIT_SEARCH_CANDIDATES && !fits && before <= params.budget {
        gap = vec2<u32>(select(lo, candidate(lo, hi, lid - 1u), lid > 0u), candidate(lo, hi, lid));
        at_gap = true;
    } else if lid == last && fits {
        gap = vec2<u32>(candidate(lo, hi, last), hi);
        at_gap = true;
    }
    if at_gap {
        atomicStore(&budget_state[STEP_INTERVALS + 2u * step], gap.x);
        atomicStore(&budget_state[STEP_INTERVALS + 2u * step + 1u], gap.y);
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    for (var b = lid; b < SPLIT_SEARCH_CANDIDATES; b += WORKGROUP) {
        atomicStore(&workgroup_bins[b], 0u);
    }
    if lid == 0u {
        interval = search_interval(params.step);
    }
    workgroupBarrier();
    let lo = interval.x;
    let hi = interval.y;
    // SPLIT_COUNT_ITEMS triangles per invocation, WORKGROUP apart.
    let first = (wid.x + wid.y * nwg.x) * WORKGROUP * SPLIT_COUNT_ITEMS + lid;
    for (var item = 0u; item < SPLIT_COUNT_ITEMS; item++) {
        let i = first + item * WORKGROUP;
        if i >= params.count {
            break;
        }
        let q = priorities[i];
        let most = splits_at(scale_at(lo, hi, SPLIT_SEARCH_CANDIDATES - 1u), q);
        if most > 0u {
            let least = splits_at(scale_at(lo, hi, 0u), q);
            if least > 0u {
                atomicAdd(&workgroup_bins[0], least);
            }
            for (var k = least + 1u; k <= most; k++) {
                atomicAdd(&workgroup_bins[first_fitting(lo, hi, q, k)], 1u);
            }
        }
    }
    workgroupBarrier();
    for (var b = lid; b < SPLIT_SEARCH_CANDIDATES; b += WORKGROUP) {
        let count = atomicLoad(&workgroup_bins[b]);
        if count > 0u {
            atomicAdd(&budget_state[STEP_BINS + params.step * SPLIT_SEARCH_CANDIDATES + b], count);
        }
    }
    // Release: the workgroup's counts are added before its ticket is taken.
    storageBarrier();
    if lid == 0u {
        is_last = u32(atomicAdd(&budget_state[STEP_TICKETS + params.step], 1u) + 1u == nwg.x * nwg.y);
    }
    if workgroupUniformLoad(&is_last) == 0u {
        return;
    }
    // Acquire: every workgroup's counts are visible.
    storageBarrier();
    narrow(params.step, lid);
}
