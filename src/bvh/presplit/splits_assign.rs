//! Pre-splitting step 2b (kernel `splits_assign`; Karras & Aila 2013, §5): after the budget
//! search (`splits_count`), each triangle's reference count s_t + 1 at the scale found, the input
//! of the reference offsets scan. CPU twin: `budget_scale` and `splits_at`.

use super::splits_count::BudgetParams;
use crate::gpu::kernel;

kernel!(
    /// Per triangle: its reference count s_t + 1 at the final lower bound.
    pub SPLITS_ASSIGN: BudgetParams = "splits_assign"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
