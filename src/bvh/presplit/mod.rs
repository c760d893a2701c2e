//! Triangle pre-splitting on the GPU (Karras & Aila 2013, §5): large, badly fitting triangles
//! become several references (clipped boxes of the same triangle) before the LBVH build, within a
//! budget of β·N extra references. Stages: triangle boxes → scene box (reduction) → split
//! priorities (`triangles_priority.wgsl`) → split counts under the budget by bisection
//! (`splits_budget.wgsl`) → reference offsets (exclusive scan) → recursive splitting at Morton-grid
//! planes (`triangles_split.wgsl`). The total reference count is read back between the counts and
//! the split (the LBVH stages size their dispatches from it): the one CPU round trip of a split
//! build. CPU twin: `presplit_cpu`.

mod cpu;

pub use cpu::{
    budget_scale, presplit_cpu, split_importance, split_priority, split_triangle, splits_at,
    SplitGrid, BISECTION_STEPS, MAX_SPLITS,
};

use bytemuck::{Pod, Zeroable};

use super::lbvh::{CentroidBounds, GpuAabb, TriangleBounds};
use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, read_buffer, storage_buffer_zeroed,
    uniform_buffer, GpuContext, GpuTimer,
};
use crate::sort::PrefixScan;
use crate::trace::GpuScene;
use crate::Result;

const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SplitParams {
    count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<SplitParams>() == 16);

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BudgetParams {
    count: u32,
    row_pitch: u32,
    budget: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<BudgetParams>() == 16);

/// Extra references allowed for `triangles` triangles at β = `percent` / 100.
pub fn split_budget(triangles: u32, percent: u32) -> u32 {
    (u64::from(triangles) * u64::from(percent) / 100) as u32
}

/// The grid and parameters of a per-triangle pre-splitting kernel over `n` triangles.
fn per_triangle_params(ctx: &GpuContext, n: u32) -> ((u32, u32), wgpu::Buffer) {
    let (gx, gy) = dispatch_grid(ctx, n, WORKGROUP);
    let params = uniform_buffer(
        ctx,
        "split params",
        &SplitParams {
            count: n,
            row_pitch: gx * WORKGROUP,
            _pad: [0; 2],
        },
    );
    ((gx, gy), params)
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
    tri_boxes: wgpu::Buffer,
    bounds_levels: Vec<wgpu::Buffer>,
    priorities: wgpu::Buffer,
    budget_state: wgpu::Buffer,
    ref_offsets: wgpu::Buffer,
}

/// Pipelines and scratch of the pre-splitting stage, reused per frame.
pub struct PreSplitter {
    triangle_bounds: TriangleBounds,
    scene_bounds: CentroidBounds,
    priority: wgpu::ComputePipeline,
    init_search: wgpu::ComputePipeline,
    count_splits: wgpu::ComputePipeline,
    bisect_step: wgpu::ComputePipeline,
    write_counts: wgpu::ComputePipeline,
    split: wgpu::ComputePipeline,
    scan: PrefixScan,
    scratch: Option<Scratch>,
    ref_tris: Option<wgpu::Buffer>,
}

impl PreSplitter {
    pub fn new(ctx: &GpuContext) -> Self {
        let budget = |entry| compute_pipeline(ctx, "splits_budget.wgsl", entry);
        Self {
            triangle_bounds: TriangleBounds::new(ctx),
            scene_bounds: CentroidBounds::new(ctx),
            priority: compute_pipeline(ctx, "triangles_priority.wgsl", "main"),
            init_search: budget("init_search"),
            count_splits: budget("count_splits"),
            bisect_step: budget("bisect_step"),
            write_counts: budget("write_counts"),
            split: compute_pipeline(ctx, "triangles_split.wgsl", "main"),
            scan: PrefixScan::new(ctx),
            scratch: None,
            ref_tris: None,
        }
    }

    /// Records steps 1-2 and the offsets scan for the scene's triangles with `budget` extra
    /// references; `read_total` gives the reference count after submission.
    pub fn record_counts(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        budget: u32,
        timer: &mut GpuTimer,
    ) -> Result<()> {
        let n = scene.triangle_count;
        if self.scratch.as_ref().is_none_or(|s| s.capacity < n) {
            self.scratch = None;
            self.scratch = Some(Scratch {
                capacity: n,
                tri_boxes: storage_buffer_zeroed(ctx, "triangle boxes", u64::from(n) * 32)?,
                bounds_levels: CentroidBounds::level_buffers(ctx, n)?,
                priorities: storage_buffer_zeroed(ctx, "split priorities", u64::from(n) * 4)?,
                budget_state: storage_buffer_zeroed(ctx, "split budget state", 32)?,
                ref_offsets: storage_buffer_zeroed(ctx, "reference offsets", u64::from(n) * 4)?,
            });
        }
        let plan = self.scan.plan(
            ctx,
            &self.scratch.as_ref().expect("allocated").ref_offsets,
            n,
        )?;
        let s = self.scratch.as_ref().expect("allocated");
        let ((gx, gy), split_params) = per_triangle_params(ctx, n);
        let budget_params = uniform_buffer(
            ctx,
            "budget params",
            &BudgetParams {
                count: n,
                row_pitch: gx * WORKGROUP,
                budget,
                _pad: 0,
            },
        );
        let levels = CentroidBounds::level_count(n);
        let scene_box = &s.bounds_levels[levels - 1];
        let priority_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("triangles_priority"),
            layout: &self.priority.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &split_params),
                bind_entry(1, &scene.triangles),
                bind_entry(2, &s.priorities),
                bind_entry(3, &s.budget_state),
                bind_entry(6, scene_box),
            ],
        });
        let budget_group =
            |pipeline: &wgpu::ComputePipeline, with_counts: bool, with_priorities: bool| {
                let mut entries = vec![
                    bind_entry(0, &budget_params),
                    bind_entry(2, &s.budget_state),
                ];
                if with_priorities {
                    entries.push(bind_entry(1, &s.priorities));
                }
                if with_counts {
                    entries.push(bind_entry(3, &s.ref_offsets));
                }
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("splits_budget"),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &entries,
                })
            };
        let init_group = budget_group(&self.init_search, false, false);
        let count_group = budget_group(&self.count_splits, false, true);
        let step_group = budget_group(&self.bisect_step, false, false);
        let write_group = budget_group(&self.write_counts, true, true);
        encoder.clear_buffer(&s.budget_state, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("split counts"),
            timestamp_writes: timer.pass("split counts"),
        });
        self.triangle_bounds
            .record(ctx, &mut pass, &scene.triangles, n, &s.tri_boxes);
        self.scene_bounds.record(
            ctx,
            &mut pass,
            &s.tri_boxes,
            n,
            &s.bounds_levels[..levels],
            false,
        );
        pass.set_pipeline(&self.priority);
        pass.set_bind_group(0, &priority_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        pass.set_pipeline(&self.init_search);
        pass.set_bind_group(0, &init_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        for _ in 0..BISECTION_STEPS {
            pass.set_pipeline(&self.count_splits);
            pass.set_bind_group(0, &count_group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
            pass.set_pipeline(&self.bisect_step);
            pass.set_bind_group(0, &step_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        pass.set_pipeline(&self.write_counts);
        pass.set_bind_group(0, &write_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        self.scan.record(&mut pass, &plan);
        Ok(())
    }

    /// Total references after the recorded counts were submitted (triangles + splits).
    pub fn read_total(&self, ctx: &GpuContext) -> Result<u32> {
        Ok(read_buffer::<u32>(ctx, self.scan.total(), 1)?[0])
    }

    /// Records step 3: writes `total` reference boxes into `prim_boxes` and their triangles into
    /// `ref_tris()`.
    pub fn record_split(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        total: u32,
        prim_boxes: &wgpu::Buffer,
        timer: &mut GpuTimer,
    ) -> Result<()> {
        if self
            .ref_tris
            .as_ref()
            .is_none_or(|b| b.size() < u64::from(total) * 4)
        {
            self.ref_tris = Some(storage_buffer_zeroed(
                ctx,
                "reference triangles",
                u64::from(total) * 4,
            )?);
        }
        let n = scene.triangle_count;
        let s = self.scratch.as_ref().expect("record_counts first");
        let ((gx, gy), params) = per_triangle_params(ctx, n);
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("triangles_split"),
            layout: &self.split.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, &scene.triangles),
                bind_entry(2, &s.ref_offsets),
                bind_entry(3, self.scan.total()),
                bind_entry(4, prim_boxes),
                bind_entry(5, self.ref_tris.as_ref().expect("allocated above")),
                bind_entry(6, &s.bounds_levels[CentroidBounds::level_count(n) - 1]),
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("split"),
            timestamp_writes: timer.pass("split"),
        });
        pass.set_pipeline(&self.split);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        Ok(())
    }

    /// Runs the whole stage for the scene's triangles and reads its results back (tests).
    pub fn split_stages(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        budget: u32,
    ) -> Result<SplitStages> {
        let mut timer = GpuTimer::new(ctx, 2);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record_counts(ctx, &mut encoder, scene, budget, &mut timer)?;
        ctx.queue.submit([encoder.finish()]);
        let total = self.read_total(ctx)?;
        let boxes = storage_buffer_zeroed(ctx, "reference boxes", u64::from(total) * 32)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record_split(ctx, &mut encoder, scene, total, &boxes, &mut timer)?;
        ctx.queue.submit([encoder.finish()]);
        let s = self.scratch.as_ref().expect("recorded above");
        let state: Vec<u32> = read_buffer(ctx, &s.budget_state, 3)?;
        Ok(SplitStages {
            priorities: read_buffer(ctx, &s.priorities, scene.triangle_count as usize)?,
            scale: f32::from_bits(state[2]),
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
