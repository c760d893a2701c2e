//! Pre-splitting step 2 (kernel `splits_budget`; Karras & Aila 2013, §5): the split counts under
//! the budget, by a 16-ary search of the scale E on its bit patterns (`SPLIT_SEARCH_STEPS` steps
//! of `SPLIT_SEARCH_CANDIDATES` candidates). Four entry points, dispatched in order:
//! `init_search`, then per step `count_splits` and `narrow_search`, and last `write_counts`.
//! CPU twin: `budget_scale` (the same E by bisection) and `splits_at`.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct BudgetParams {
    pub count: u32,
    pub row_pitch: u32,
    pub budget: u32,
    pub _pad: u32,
}

kernel!(
    /// One invocation: the search interval [0, hi) with hi = (budget + 1)³ / q_max.
    pub SPLITS_INIT_SEARCH: BudgetParams = "splits_budget"::"init_search", [1, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
kernel!(
    /// Per triangle: Σ s_t at each of the step's candidates.
    pub SPLITS_COUNT: BudgetParams = "splits_budget"::"count_splits", [64, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
kernel!(
    /// One invocation: keeps the gap after the last candidate whose sum fits.
    pub SPLITS_NARROW_SEARCH: BudgetParams = "splits_budget"::"narrow_search", [1, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
kernel!(
    /// Per triangle: its reference count s_t + 1 at the final lower bound.
    pub SPLITS_WRITE_COUNTS: BudgetParams = "splits_budget"::"write_counts", [64, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
