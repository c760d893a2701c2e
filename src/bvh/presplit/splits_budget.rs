//! Pre-splitting step 2 (kernel `splits_budget`; Karras & Aila 2013, §5): the split counts under
//! the budget, by a 16-ary search of the scale E on its bit patterns (`SPLIT_SEARCH_STEPS` steps
//! of `SPLIT_SEARCH_CANDIDATES` candidates, each step's sums kept, so that every workgroup replays
//! the interval). Two entry points, dispatched in order: per step `count_splits`, and last
//! `write_counts`.
//! CPU twin: `budget_scale` (the same E by bisection) and `splits_at`.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct BudgetParams {
    pub count: u32,
    pub row_pitch: u32,
    pub budget: u32,
    /// `count_splits`: the search step.
    pub step: u32,
}

kernel!(
    /// Per triangle: Σ s_t at each of the step's candidates (the interval replayed from the
    /// sums of the steps before).
    pub SPLITS_COUNT: BudgetParams = "splits_budget"::"count_splits", [64, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
kernel!(
    /// Per triangle: its reference count s_t + 1 at the final lower bound.
    pub SPLITS_WRITE_COUNTS: BudgetParams = "splits_budget"::"write_counts", [64, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
