//! GPU leaf collapse and compaction into the traversal layout (Karras & Aila 2013, §3): mark kept
//! nodes and output leaves (`shaders/nodes_mark.wgsl`), exclusive scans for new node indices and
//! leaf primitive ranges (`sort::PrefixScan`), then write the output tree
//! (`shaders/nodes_compact.wgsl`). CPU twin: `WorkingTree::collapse`.

use bytemuck::{Pod, Zeroable};

use super::dp::CostModel;
use super::optimize::TreeletState;
use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, storage_buffer_zeroed, uniform_buffer, GpuContext,
};
use crate::sort::PrefixScan;
use crate::trace::GpuScene;
use crate::Result;

const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CollapseParams {
    node_count: u32,
    row_pitch: u32,
    max_leaf_size: u32,
    ct: f32,
    /// Always 0: keeps the kernel's products unfused (see `unfused` in the shader).
    zero: u32,
    /// 1 when the primitives are pre-split references mapped through `ref_tris`.
    has_refs: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<CollapseParams>() == 32);

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CompactParams {
    node_count: u32,
    row_pitch: u32,
    has_refs: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<CompactParams>() == 16);

/// Buffers of one collapse: scratch (flags, scans) and the output tree.
pub(crate) struct CollapseBuffers<'a> {
    pub flags: &'a wgpu::Buffer,
    pub kept_scan: &'a wgpu::Buffer,
    pub leaf_prim_scan: &'a wgpu::Buffer,
    pub out_nodes: &'a wgpu::Buffer,
    pub out_prims: &'a wgpu::Buffer,
    pub tree_counts: &'a wgpu::Buffer,
    /// Triangle of each pre-split reference; None when primitives are triangles.
    pub ref_tris: Option<&'a wgpu::Buffer>,
}

pub(crate) struct Collapse {
    mark: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    scan: PrefixScan,
    /// Bound as `ref_tris` when there are no references (the kernels then never read it).
    no_refs: wgpu::Buffer,
}

impl Collapse {
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            mark: compute_pipeline(ctx, "nodes_mark.wgsl", "main"),
            compact: compute_pipeline(ctx, "nodes_compact.wgsl", "main"),
            scan: PrefixScan::new(ctx),
            no_refs: storage_buffer_zeroed(ctx, "no references", 4)?,
        })
    }

    /// Records the collapse of the working tree in `scene` into `out`.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        scene: &GpuScene,
        state: &TreeletState<'_>,
        model: &CostModel,
        out: &CollapseBuffers<'_>,
    ) -> Result<()> {
        let n = scene.prim_count;
        let node_count = 2 * n - 1;
        let has_refs = u32::from(out.ref_tris.is_some());
        let ref_tris = out.ref_tris.unwrap_or(&self.no_refs);
        let (gx, gy) = dispatch_grid(ctx, node_count, WORKGROUP);
        let mark_params = uniform_buffer(
            ctx,
            "collapse params",
            &CollapseParams {
                node_count,
                row_pitch: gx * WORKGROUP,
                max_leaf_size: model.max_leaf_size,
                ct: model.ct,
                zero: 0,
                has_refs,
                _pad: [0; 2],
            },
        );
        let mark = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("nodes_mark"),
            layout: &self.mark.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &mark_params),
                bind_entry(1, &scene.nodes),
                bind_entry(2, state.parents),
                bind_entry(3, state.prim_counts),
                bind_entry(4, state.costs),
                bind_entry(5, out.flags),
                bind_entry(6, out.kept_scan),
                bind_entry(7, out.leaf_prim_scan),
                bind_entry(8, &scene.prim_indices),
                bind_entry(9, ref_tris),
            ],
        });
        let kept_plan = self.scan.plan(ctx, out.kept_scan, node_count)?;
        let leaf_plan = self.scan.plan(ctx, out.leaf_prim_scan, node_count)?;
        let compact_params = uniform_buffer(
            ctx,
            "compact params",
            &CompactParams {
                node_count,
                row_pitch: gx * WORKGROUP,
                has_refs,
                _pad: 0,
            },
        );
        let compact = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("nodes_compact"),
            layout: &self.compact.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &compact_params),
                bind_entry(1, &scene.nodes),
                bind_entry(2, &scene.prim_indices),
                bind_entry(4, out.flags),
                bind_entry(5, out.kept_scan),
                bind_entry(6, out.leaf_prim_scan),
                bind_entry(7, out.out_nodes),
                bind_entry(8, out.out_prims),
                bind_entry(9, out.tree_counts),
                bind_entry(10, ref_tris),
                bind_entry(11, self.scan.total()),
            ],
        });
        pass.set_pipeline(&self.mark);
        pass.set_bind_group(0, &mark, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        self.scan.record(pass, &kept_plan);
        self.scan.record(pass, &leaf_plan);
        pass.set_pipeline(&self.compact);
        pass.set_bind_group(0, &compact, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        Ok(())
    }
}
