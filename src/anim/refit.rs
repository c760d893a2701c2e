//! Refit-only tree updates for animated scenes with fixed topology: the tree is built once, at the
//! first frame, by a GPU builder (LBVH by default, TRBVH on request), and every later frame only
//! recomputes its boxes on the GPU, bottom-up (`shaders/nodes_refit.wgsl`, the climb and memory
//! ordering of the LBVH's `bounds_refit.wgsl`, generalized to leaves of several triangles).
//!
//! Refitting the compacted tree needs its parent links and its list of leaves, which no build
//! stage keeps (the LBVH's parent links describe the tree before treelet restructuring and
//! collapse). They are derived once per topology, when the tree is built: the tree is read back
//! and the parents and leaves are computed on the CPU and uploaded (O(n), once; never per frame).
//! The per-frame work is a single dispatch.
//!
//! Refitting keeps every box valid (exact unions of the triangles' coordinates) but not good:
//! when triangles move away from their neighbours of the first frame (the explosion), the boxes
//! grow and overlap and the SAH cost climbs, which the viewer's SAH plot shows next to a rebuild.

use bytemuck::{Pod, Zeroable};

use crate::bvh::{Builder, Bvh, GpuBuilder, SahParams};
use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, storage_buffer, storage_buffer_zeroed,
    uniform_buffer, GpuContext, GpuTimer, StageTime,
};
use crate::trace::GpuScene;
use crate::{Error, Result};

const WORKGROUP: u32 = 64;

/// Parent of the root in the uploaded parent links (the climb stops at node 0 before reading it).
const NO_PARENT: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RefitParams {
    leaf_count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<RefitParams>() == 16);

/// Parent links (root: `NO_PARENT`) and leaf node indices of `bvh`, whose root is node 0.
pub fn parents_and_leaves(bvh: &Bvh) -> (Vec<u32>, Vec<u32>) {
    let mut parents = vec![NO_PARENT; bvh.nodes.len()];
    let mut leaves = Vec::new();
    for (i, node) in bvh.nodes.iter().enumerate() {
        if node.is_leaf() {
            leaves.push(i as u32);
        } else {
            let (left, right) = node.children();
            for child in [left, right] {
                if let Some(p) = parents.get_mut(child as usize) {
                    *p = i as u32;
                }
            }
        }
    }
    (parents, leaves)
}

/// The tree a refit updates, and the buffers its refits need.
struct Topology {
    /// The scene buffers the topology was captured from (a refit applies only to them).
    nodes: wgpu::Buffer,
    prim_indices: wgpu::Buffer,
    triangles: wgpu::Buffer,
    node_count: u32,
    bind_group: wgpu::BindGroup,
    arrivals: wgpu::Buffer,
    grid: (u32, u32),
}

/// Builds a scene's tree once with `topology_builder`, then refits its boxes on every call.
pub struct RefitBuilder {
    builder: GpuBuilder,
    pipeline: wgpu::ComputePipeline,
    topology: Option<Topology>,
}

impl RefitBuilder {
    /// Refits of the trees `topology_builder` (a GPU builder) builds.
    pub fn new(ctx: &GpuContext, topology_builder: Builder, params: &SahParams) -> Result<Self> {
        Ok(Self {
            builder: GpuBuilder::new(ctx, topology_builder, params)?,
            pipeline: compute_pipeline(ctx, "nodes_refit.wgsl", "main"),
            topology: None,
        })
    }

    /// SAH parameters of the next topology build.
    pub fn set_sah_params(&mut self, params: SahParams) {
        self.builder.set_sah_params(params);
    }

    /// Forgets the topology: the next `build` builds a new tree.
    pub fn reset(&mut self) {
        self.topology = None;
    }

    /// Whether the next `build` of `scene` is a refit (its tree is the captured one).
    pub fn refits(&self, scene: &GpuScene) -> bool {
        self.topology.as_ref().is_some_and(|t| {
            t.nodes == scene.nodes
                && t.prim_indices == scene.prim_indices
                && t.triangles == scene.triangles
                && t.node_count == scene.node_count
        })
    }

    /// Refits `scene`'s tree to its current triangles, or builds it (and captures its topology)
    /// when it is not the tree of the last build. Returns the GPU stage times ("refit" for a refit,
    /// the builder's stages for a build).
    pub fn build(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<Vec<StageTime>> {
        if !self.refits(scene) {
            self.topology = None;
            let stages = self.builder.build(ctx, scene)?;
            self.topology = Some(self.capture(ctx, scene)?);
            return Ok(stages);
        }
        let topology = self.topology.as_ref().expect("checked by refits");
        let mut timer = GpuTimer::new(ctx, 1);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&topology.arrivals, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("nodes refit"),
                timestamp_writes: timer.pass("refit"),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &topology.bind_group, &[]);
            pass.dispatch_workgroups(topology.grid.0, topology.grid.1, 1);
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        timer.read(ctx)
    }

    /// Reads the freshly built tree back and uploads its parent links and leaves.
    fn capture(&self, ctx: &GpuContext, scene: &GpuScene) -> Result<Topology> {
        let bvh = scene.download_bvh(ctx)?;
        if bvh.nodes.is_empty() {
            return Err(Error::InvalidArgument("cannot refit an empty tree".into()));
        }
        let (parents, leaves) = parents_and_leaves(&bvh);
        let leaf_count = leaves.len() as u32;
        let grid = dispatch_grid(ctx, leaf_count, WORKGROUP);
        let params = uniform_buffer(
            ctx,
            "refit params",
            &RefitParams {
                leaf_count,
                row_pitch: grid.0 * WORKGROUP,
                _pad: [0; 2],
            },
        );
        let leaves = storage_buffer(ctx, "refit leaves", &leaves)?;
        let parents = storage_buffer(ctx, "refit parents", &parents)?;
        let arrivals =
            storage_buffer_zeroed(ctx, "refit arrivals", u64::from(scene.node_count) * 4)?;
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("nodes_refit"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, &scene.triangles),
                bind_entry(2, &scene.prim_indices),
                bind_entry(3, &leaves),
                bind_entry(4, &parents),
                bind_entry(5, &scene.nodes),
                bind_entry(6, &arrivals),
            ],
        });
        Ok(Topology {
            nodes: scene.nodes.clone(),
            prim_indices: scene.prim_indices.clone(),
            triangles: scene.triangles.clone(),
            node_count: scene.node_count,
            bind_group,
            arrivals,
            grid,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhNode;
    use crate::geometry::Aabb;

    #[test]
    fn parents_and_leaves_of_a_small_tree() {
        let b = Aabb::EMPTY;
        let bvh = Bvh {
            nodes: vec![
                BvhNode::internal(b, 1, 2),
                BvhNode::leaf(b, 0, 2),
                BvhNode::internal(b, 3, 4),
                BvhNode::leaf(b, 2, 1),
                BvhNode::leaf(b, 3, 1),
            ],
            prim_indices: vec![0, 1, 2, 3],
        };
        let (parents, leaves) = parents_and_leaves(&bvh);
        assert_eq!(parents, vec![NO_PARENT, 0, 0, 2, 2]);
        assert_eq!(leaves, vec![1, 3, 4]);
    }
}
