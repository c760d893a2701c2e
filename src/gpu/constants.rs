//! Numbers the kernels and their Rust twins share, defined once: Rust uses these constants, and
//! kernels get them from the generated include `constants.wgsl` (`#include "constants.wgsl"`).

/// Set in a leaf node's `right_or_count` (`BvhNode`).
pub const LEAF_FLAG: u32 = 0x8000_0000;
/// The triangle id of a miss (`Hit::MISS`).
pub const MISS: u32 = u32::MAX;
/// Cells per axis of the Morton grid the LBVH keys quantize centroids in and the pre-splitting
/// planes share.
pub const MORTON_GRID: u32 = 1 << 21;
/// Grid bits per axis of the full LBVH key (the high ones): 48 bits, of which each builder keeps
/// the high `key_bits` (`bvh::lbvh::LBVH_KEY_BITS`, `TRBVH_KEY_BITS`). Measured on 8 scenes (7
/// shared ones and a dense model in a 500× larger "stadium"): trees identical to those of all 21
/// bits per axis (README, "Build floor").
pub const MORTON_AXIS_BITS: u32 = 16;
/// Splits per triangle at most in pre-splitting (pieces ≤ `MAX_SPLITS + 1`).
pub const MAX_SPLITS: u32 = 31;
/// References of a triangle that `triangles_split.wgsl` splits in its own invocation, piece after
/// piece; the references of a triangle of more are split one per invocation
/// (`references_split.wgsl`).
pub const SPLIT_INLINE_PIECES: u32 = 8;
/// Pieces waiting at most while one invocation splits a triangle (`split_triangle` in
/// `triangles_split.wgsl`: the loop goes on with the side of fewer references, so a waiting piece
/// owes at least as many as everything below it): ⌊log2(SPLIT_INLINE_PIECES)⌋.
pub const PIECE_STACK: u32 = SPLIT_INLINE_PIECES.ilog2();
/// Candidate scales the pre-splitting budget search evaluates per step (`splits_search.wgsl`):
/// 255 split the interval in 256, so `SPLIT_SEARCH_STEPS` steps narrow 2^32 bit patterns to one.
pub const SPLIT_SEARCH_CANDIDATES: u32 = 255;
/// Steps of the pre-splitting budget search (one dispatch each).
pub const SPLIT_SEARCH_STEPS: u32 = 4;
const _: () = assert!(
    (SPLIT_SEARCH_CANDIDATES as u64 + 1).pow(SPLIT_SEARCH_STEPS) >= 1 << 32,
    "the budget search must narrow every bit pattern interval to one"
);
/// Triangles per invocation of a budget search step (`splits_count.wgsl`, 256 invocations per
/// workgroup, so 1024 triangles per workgroup): each workgroup clears, fills and adds up a
/// histogram of the candidates, which cost more than the counting itself at a triangle per
/// invocation (lavapipe, conference: a step 8 -> 2.3 ms, the first 24 -> 16 ms). Four leave a
/// GPU hundreds of workgroups from ~300k triangles.
pub const SPLIT_COUNT_ITEMS: u32 = 4;
/// Word of the budget search's state that holds the scale found: after q_max, a ticket per step,
/// the interval after each step and each step's histogram of its candidates
/// (`splits_search.wgsl`).
pub const SPLIT_SCALE_WORD: u32 =
    1 + 3 * SPLIT_SEARCH_STEPS + SPLIT_SEARCH_STEPS * SPLIT_SEARCH_CANDIDATES;
/// Word of the budget search's state after the scale: the references `triangles_split.wgsl`
/// listed for `references_split.wgsl`.
pub const SPLIT_HEAVY_WORD: u32 = SPLIT_SCALE_WORD + 1;
/// Largest treelet (leaves): each treelet invocation keeps the costs of its 2^8 subsets and
/// the boxes of two halves of 4 leaves (`treelet_dp.wgsl`).
pub const MAX_TREELET_SIZE: u32 = 8;
/// Smallest treelet (leaves).
pub const MIN_TREELET_SIZE: u32 = 3;
/// Treelet levels a restructuring round gives one dispatch each at most; the levels above are
/// climbed by one workgroup (`bvh::treelet`).
pub const MAX_LEVEL_DISPATCHES: u32 = 32;
/// Treelet levels a round optimizes per subtree at most (`RoundSchedule::subtree_levels`): a
/// subtree of K levels holds up to 2^K − 1 treelet roots, which its workgroup lists
/// (`subtrees_optimize.wgsl`).
pub const MAX_SUBTREE_LEVELS: u32 = 8;
const _: () = assert!(MAX_SUBTREE_LEVELS <= MAX_LEVEL_DISPATCHES);
/// Treelet roots a workgroup of `subtrees_optimize.wgsl` lists at most (in workgroup memory): it
/// takes as many subtrees of level l as fit in the worst case, ⌊SUBTREE_LIST / (2^l − 1)⌋, at
/// most one per invocation.
pub const SUBTREE_LIST: u32 = 1024;
const _: () = assert!(SUBTREE_LIST >= (1 << MAX_SUBTREE_LEVELS) - 1);
/// Costs per binary node of the SAH-optimal wide collapse, C(n, 1..=7): the slot counts a wide
/// node's expansion can give a child (`bvh::wide::OptimalCollapse`, costs_climb.wgsl).
pub const COLLAPSE_COST_WORDS: u32 = 7;
/// Largest leaf the GPU collapse may create (its gather stack holds a leaf's subtree).
pub const MAX_GPU_LEAF_SIZE: u32 = 32;
/// Widening of a box's exit distance in the traversal's box test (Ize 2013): rounding never culls
/// a box that the ray touches (see `box_entry` in bvh_traverse.wgsl).
pub const BOX_EXIT_SLACK: f32 = 1.000_001_9;
/// Dispatches one path trace records at most. Each counts its rays and stack overflows in a pair
/// of the tracer's counters and, where the trace counts its traversal steps, their two 64-bit
/// counts in four words after all the pairs (from `TRACE_STEPS_AT`).
pub const MAX_TRACE_DISPATCHES: u32 = 64;
/// The word of the tracer's counters where the traversal steps of the first dispatch start.
pub const TRACE_STEPS_AT: u32 = 2 * MAX_TRACE_DISPATCHES;
/// Bits per radix-sort digit.
pub const RADIX_BITS: u32 = 4;
/// Elements per workgroup of the prefix scan.
pub const SCAN_BLOCK: u32 = 4096;
/// Items per workgroup of a box reduction (`centroids_reduce`, `triangles_bounds`; four per
/// invocation, box_reduce.wgsl).
pub const REDUCE_TILE: u32 = 1024;

/// The text of the include `constants.wgsl`.
pub fn wgsl() -> String {
    let f32_const = |name: &str, value: f32| format!("const {name}: f32 = {value:?};\n");
    let u32_const = |name: &str, value: u32| format!("const {name}: u32 = {value}u;\n");
    [
        u32_const("LEAF_FLAG", LEAF_FLAG),
        u32_const("MISS", MISS),
        f32_const("MORTON_GRID", MORTON_GRID as f32),
        f32_const("MORTON_GRID_MAX", (MORTON_GRID - 1) as f32),
        u32_const("MORTON_AXIS_BITS", MORTON_AXIS_BITS),
        u32_const("MAX_SPLITS", MAX_SPLITS),
        u32_const("SPLIT_INLINE_PIECES", SPLIT_INLINE_PIECES),
        u32_const("PIECE_STACK", PIECE_STACK),
        u32_const("SPLIT_SEARCH_CANDIDATES", SPLIT_SEARCH_CANDIDATES),
        u32_const("SPLIT_COUNT_ITEMS", SPLIT_COUNT_ITEMS),
        u32_const("SPLIT_SEARCH_STEPS", SPLIT_SEARCH_STEPS),
        u32_const("SPLIT_SCALE_WORD", SPLIT_SCALE_WORD),
        u32_const("SPLIT_HEAVY_WORD", SPLIT_HEAVY_WORD),
        u32_const("MAX_TREELET", MAX_TREELET_SIZE),
        u32_const("MAX_GPU_LEAF_SIZE", MAX_GPU_LEAF_SIZE),
        u32_const("COLLAPSE_COST_WORDS", COLLAPSE_COST_WORDS),
        u32_const("MAX_LEVEL_DISPATCHES", MAX_LEVEL_DISPATCHES),
        u32_const("MAX_SUBTREE_LEVELS", MAX_SUBTREE_LEVELS),
        u32_const("SUBTREE_LIST", SUBTREE_LIST),
        f32_const("BOX_EXIT_SLACK", BOX_EXIT_SLACK),
        u32_const("RADIX_BITS", RADIX_BITS),
        u32_const("SCAN_BLOCK", SCAN_BLOCK),
        u32_const("REDUCE_TILE", REDUCE_TILE),
        u32_const("TRACE_STEPS_AT", TRACE_STEPS_AT),
        f32_const("F32_MAX", f32::MAX),
        // A working leaf without a slot in its output leaf (a repeated triangle; `leaf_slots` of
        // nodes_mark.wgsl and nodes_compact.wgsl).
        u32_const("NO_SLOT", u32::MAX),
    ]
    .concat()
}

#[cfg(test)]
mod tests {
    #[test]
    fn floats_print_exactly() {
        // `{:?}` prints the shortest text that parses back to the same f32.
        let text = super::wgsl();
        assert!(
            text.contains("const BOX_EXIT_SLACK: f32 = 1.0000019;"),
            "{text}"
        );
        assert!(
            text.contains("const MORTON_GRID: f32 = 2097152.0;"),
            "{text}"
        );
        assert!(
            text.contains("const LEAF_FLAG: u32 = 2147483648u;"),
            "{text}"
        );
    }
}
