//! Pre-splitting step 2a (kernel `splits_count`; Karras & Aila 2013, §5): one dispatch per step of
//! the budget search for the split counts, a 256-ary search of the scale E on its bit patterns
//! (`SPLIT_SEARCH_STEPS` steps of `SPLIT_SEARCH_CANDIDATES` candidates; each step counts where
//! every split first fits, and its last workgroup narrows the interval for the next; shared code
//! in `shaders/include/splits_search.wgsl`). Then `splits_assign`. CPU twin: `budget_scale` (the
//! same E by bisection) and `splits_at`.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

/// Parameters of the budget search's kernels (`splits_count`, `splits_assign`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct BudgetParams {
    pub count: u32,
    pub row_pitch: u32,
    pub budget: u32,
    /// `splits_count`: the search step.
    pub step: u32,
}
const _: () = assert!(std::mem::size_of::<BudgetParams>() == 16);

kernel!(
    /// Per triangle: the candidate at which each of its splits first fits, counted; the last
    /// workgroup narrows the interval.
    pub SPLITS_COUNT: BudgetParams = "splits_count"::"main", [256, 1, 1],
    [Read, ReadWrite, ReadWrite]
);
