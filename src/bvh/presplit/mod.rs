//! Triangle pre-splitting on the GPU (Karras & Aila 2013, §5): large, badly fitting triangles
//! become several references (clipped boxes of the same triangle) before the LBVH build, within a
//! budget of β·N extra references. Stages: triangle boxes → scene box (reduction) → split
//! priorities (`triangles_priority.wgsl`) → split counts under the budget by a 256-ary search
//! (`splits_count.wgsl` per step, then `splits_assign.wgsl`) → reference offsets (exclusive
//! scan) → recursive splitting at Morton-grid planes (`triangles_split.wgsl`: a triangle per
//! invocation; `references_split.wgsl`: a reference per invocation for the triangles of more than
//! `SPLIT_INLINE_PIECES` references). The reference count stays on the GPU: the LBVH stages after
//! it are sized for N + β·N references and read the count (`gpu::ItemCount`). CPU twin:
//! `presplit_cpu`.

mod cpu;
mod references_split;
mod splits_assign;
mod splits_count;
mod triangles_priority;
mod triangles_split;

pub use cpu::{
    budget_scale, presplit_cpu, split_importance, split_priority, split_triangle, splits_at,
    SplitGrid,
};
pub use references_split::REFERENCES_SPLIT;
pub use splits_assign::SPLITS_ASSIGN;
pub use splits_count::SPLITS_COUNT;
pub use triangles_priority::TRIANGLES_PRIORITY;
pub use triangles_split::TRIANGLES_SPLIT;

use splits_count::BudgetParams;

use super::lbvh::{CentroidsReduce, TriangleBoundsOutput, TrianglesBounds};
use crate::device::Geometry;
use crate::geometry::GpuAabb;
use crate::gpu::constants::{
    SPLIT_COUNT_ITEMS, SPLIT_HEAVY_WORD, SPLIT_INLINE_PIECES, SPLIT_SCALE_WORD, SPLIT_SEARCH_STEPS,
};
use crate::gpu::{
    grow_storage_buffer, read_buffer, storage_buffer_zeroed, GpuContext, Items, Kernel, ParamSlab,
    Recorder,
};
use crate::sort::PrefixScan;
use crate::Result;

/// Extra references allowed for `triangles` triangles at β = `percent` / 100.
pub fn split_budget(triangles: u32, percent: u32) -> u32 {
    (u64::from(triangles) * u64::from(percent) / 100) as u32
}

/// One run of the stage read back (tests): each triangle's priority q, the budget scale E the
/// search found (split counts are `splits_at(E, q)`), and the references: boxes and triangles.
#[derive(Clone, Debug)]
pub struct SplitStages {
    pub priorities: Vec<f32>,
    pub scale: f32,
    pub boxes: Vec<GpuAabb>,
    pub ref_tris: Vec<u32>,
}

struct Scratch {
    capacity: u32,
    /// The scene box, as the reduction's box words.
    scene_box: wgpu::Buffer,
    /// Bound in the place of triangle boxes, which the scene box needs none of.
    no_boxes: wgpu::Buffer,
    priorities: wgpu::Buffer,
    budget_state: wgpu::Buffer,
    ref_offsets: wgpu::Buffer,
    /// The references of triangles of more than `SPLIT_INLINE_PIECES` references (room for
    /// `heavy_capacity(budget)` of them).
    heavy_refs: wgpu::Buffer,
}

/// Kernels and scratch of the pre-splitting stage, reused per frame.
pub struct PreSplitter {
    triangle_bounds: TrianglesBounds,
    priority: Kernel<Items>,
    count_splits: Kernel<BudgetParams>,
    assign_splits: Kernel<BudgetParams>,
    split: Kernel<Items>,
    split_references: Kernel<Items>,
    scan: PrefixScan,
    scratch: Option<Scratch>,
    ref_tris: Option<wgpu::Buffer>,
}

impl PreSplitter {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            triangle_bounds: TrianglesBounds::new(ctx),
            priority: Kernel::new(ctx, &TRIANGLES_PRIORITY),
            count_splits: Kernel::new(ctx, &SPLITS_COUNT),
            assign_splits: Kernel::new(ctx, &SPLITS_ASSIGN),
            split: Kernel::new(ctx, &TRIANGLES_SPLIT),
            split_references: Kernel::new(ctx, &REFERENCES_SPLIT),
            scan: PrefixScan::new(ctx),
            scratch: None,
            ref_tris: None,
        }
    }

    /// References there can be for `triangles` triangles with `budget` extra ones.
    pub fn capacity(triangles: u32, budget: u32) -> u32 {
        triangles.saturating_add(budget)
    }

    /// References there can be of triangles of more than `SPLIT_INLINE_PIECES` references with
    /// `budget` extra ones: such a triangle's R references are at most (1 + 1/I)·(R − 1) for I =
    /// SPLIT_INLINE_PIECES, and the R − 1 of all triangles add up to at most the budget.
    pub fn heavy_capacity(budget: u32) -> u32 {
        budget.saturating_add(budget / SPLIT_INLINE_PIECES)
    }

    /// Records the whole stage for `geometry`'s triangles with `budget` extra references (passes
    /// "split counts" and "split"): the reference boxes into `prim_boxes` (room for
    /// `capacity(n, budget)` boxes) and their triangles into `ref_tris()`. The reference count is
    /// computed on the GPU and stays there: `total()` holds it after the recording ran.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        budget: u32,
        prim_boxes: &wgpu::Buffer,
    ) -> Result<()> {
        let ctx = rec.ctx;
        let n = geometry.triangle_count;
        let capacity = Self::capacity(n, budget);
        let heavy_capacity = Self::heavy_capacity(budget);
        let heavy_bytes = u64::from(heavy_capacity.max(1)) * 4;
        if self
            .scratch
            .as_ref()
            .is_none_or(|s| s.capacity < n || s.heavy_refs.size() < heavy_bytes)
        {
            self.scratch = None;
            self.scratch = Some(Scratch {
                capacity: n,
                scene_box: CentroidsReduce::box_buffer(ctx)?,
                no_boxes: storage_buffer_zeroed(ctx, "no triangle boxes", 32)?,
                priorities: storage_buffer_zeroed(ctx, "split priorities", u64::from(n) * 4)?,
                budget_state: storage_buffer_zeroed(
                    ctx,
                    "split budget state",
                    u64::from(SPLIT_HEAVY_WORD + 1) * 4,
                )?,
                ref_offsets: storage_buffer_zeroed(ctx, "reference offsets", u64::from(n) * 4)?,
                heavy_refs: storage_buffer_zeroed(
                    ctx,
                    "references split one per invocation",
                    heavy_bytes,
                )?,
            });
        }
        let ref_tris = u64::from(capacity) * 4;
        grow_storage_buffer(ctx, &mut self.ref_tris, "reference triangles", ref_tris)?;
        self.scan.reserve(ctx, n, 1)?;
        let s = self.scratch.as_ref().expect("allocated");
        let ref_tris = self.ref_tris.as_ref().expect("allocated");
        let scene_box = &s.scene_box;
        let grid = self.priority.grid(ctx, n);
        let mut budget_params = BudgetParams {
            count: n,
            row_pitch: grid.row_pitch,
            budget,
            step: 0,
        };
        let budget_buffers = [&s.priorities, &s.budget_state, &s.ref_offsets];
        rec.encoder().clear_buffer(&s.budget_state, 0, None);
        rec.encoder().clear_buffer(scene_box, 0, None);
        {
            let mut pass = rec.pass("split counts");
            self.triangle_bounds.record(
                &mut pass,
                &geometry.triangles,
                n,
                TriangleBoundsOutput::SceneBox(&s.no_boxes),
                scene_box,
            );
            pass.dispatch(
                &self.priority,
                grid,
                &Items::new(n, grid),
                &[
                    &geometry.triangles,
                    &s.priorities,
                    &s.budget_state,
                    scene_box,
                ],
            );
            // SPLIT_COUNT_ITEMS triangles per invocation (the kernel reads no row pitch).
            let count_grid = self.count_splits.grid(ctx, n.div_ceil(SPLIT_COUNT_ITEMS));
            for step in 0..SPLIT_SEARCH_STEPS {
                budget_params.step = step;
                pass.dispatch(
                    &self.count_splits,
                    count_grid,
                    &budget_params,
                    &budget_buffers,
                );
            }
            pass.dispatch(&self.assign_splits, grid, &budget_params, &budget_buffers);
            self.scan
                .record_block_local(&mut pass, &s.ref_offsets, n, 1)?;
        }
        let mut pass = rec.pass("split");
        let split_buffers = [
            &geometry.triangles,
            &s.ref_offsets,
            self.scan.block_offsets(),
            self.scan.total(),
            prim_boxes,
            ref_tris,
            scene_box,
            &s.budget_state,
            &s.heavy_refs,
        ];
        pass.dispatch_items(&self.split, n, &split_buffers);
        // Over the most entries there can be; those past the count written return.
        let heavy_grid = self.split_references.grid(ctx, heavy_capacity);
        pass.dispatch(
            &self.split_references,
            heavy_grid,
            &Items::new(n, heavy_grid),
            &split_buffers,
        );
        Ok(())
    }

    /// The reference count of the last recorded stage (triangles + splits; one u32), written on
    /// the GPU.
    pub fn total(&self) -> &wgpu::Buffer {
        self.scan.total()
    }

    /// Runs the whole stage for `geometry`'s triangles and reads its results back (tests).
    pub fn split_stages(
        &mut self,
        ctx: &GpuContext,
        geometry: &Geometry,
        budget: u32,
    ) -> Result<SplitStages> {
        let capacity = Self::capacity(geometry.triangle_count, budget);
        let boxes = storage_buffer_zeroed(ctx, "reference boxes", u64::from(capacity) * 32)?;
        let mut params = ParamSlab::new(ctx);
        let mut rec = Recorder::new(ctx, &mut params, None);
        self.record(&mut rec, geometry, budget, &boxes)?;
        rec.submit();
        let total = read_buffer::<u32>(ctx, self.total(), 1)?[0];
        let s = self.scratch.as_ref().expect("recorded above");
        let state: Vec<u32> = read_buffer(ctx, &s.budget_state, SPLIT_SCALE_WORD as usize + 1)?;
        Ok(SplitStages {
            priorities: read_buffer(ctx, &s.priorities, geometry.triangle_count as usize)?,
            scale: f32::from_bits(state[SPLIT_SCALE_WORD as usize]),
            boxes: read_buffer(ctx, &boxes, total as usize)?,
            ref_tris: read_buffer(
                ctx,
                self.ref_tris.as_ref().expect("split recorded"),
                total as usize,
            )?,
        })
    }

    /// The triangle of each reference of the last split.
    pub fn ref_tris(&self) -> Option<&wgpu::Buffer> {
        self.ref_tris.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::PreSplitter;
    use crate::gpu::constants::{MAX_SPLITS, SPLIT_INLINE_PIECES};

    #[test]
    fn heavy_capacity_holds_the_most_references_a_budget_allows() {
        // most[b]: the most references triangles of more than SPLIT_INLINE_PIECES references can
        // have when their extra references (R - 1 each) add up to at most b (a knapsack).
        let budgets = 300usize;
        let mut most = vec![0u32; budgets + 1];
        for b in 0..=budgets {
            for r in SPLIT_INLINE_PIECES + 1..=MAX_SPLITS + 1 {
                let extra = (r - 1) as usize;
                if extra <= b {
                    most[b] = most[b].max(most[b - extra] + r);
                }
            }
            assert!(
                most[b] <= PreSplitter::heavy_capacity(b as u32),
                "budget {b}: {} references, capacity {}",
                most[b],
                PreSplitter::heavy_capacity(b as u32)
            );
        }
        // The bound is reached: budgets of whole triangles of SPLIT_INLINE_PIECES + 1 references.
        let b = 10 * SPLIT_INLINE_PIECES;
        assert_eq!(most[b as usize], PreSplitter::heavy_capacity(b));
    }
}
