//! LBVH stage 5: bottom-up bounds (Karras 2012 §4; `shaders/bounds_refit.wgsl`): one invocation per
//! leaf climbs parent links and the second arrival at each node merges its children. The kernel
//! keeps node boxes in atomics and orders them with device-scope barriers (see the shader header);
//! the CPU twin assembles the same tree sequentially.

use bytemuck::{Pod, Zeroable};

use super::Hierarchy;
use super::Prims;
use crate::bvh::{Bvh, BvhNode};
use crate::geometry::Aabb;
use crate::gpu::{bind_entry, compute_pipeline, dispatch_grid, uniform_buffer, GpuContext};
use crate::trace::GpuScene;

const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RefitParams {
    count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<RefitParams>() == 16);

/// CPU twin: the LBVH in the node layout from the hierarchy and the sorted primitive order.
pub fn assemble_lbvh_cpu(prim_boxes: &[Aabb], hierarchy: &Hierarchy, sorted_prims: &[u32]) -> Bvh {
    let n = sorted_prims.len();
    let leaf_base = n - 1;
    let mut nodes = vec![BvhNode::leaf(Aabb::EMPTY, 0, 0); 2 * n - 1];
    for (j, &prim) in sorted_prims.iter().enumerate() {
        nodes[leaf_base + j] = BvhNode::leaf(prim_boxes[prim as usize], j as u32, 1);
    }
    // Internal boxes in post-order (children before parents), with an explicit stack.
    let mut stack = vec![(0u32, false)];
    while let Some((node, expanded)) = stack.pop() {
        if node as usize >= leaf_base {
            continue;
        }
        let (left, right) = hierarchy.children[node as usize];
        if expanded {
            let bounds = nodes[left as usize]
                .bounds()
                .union(nodes[right as usize].bounds());
            nodes[node as usize] = BvhNode::internal(bounds, left, right);
        } else {
            stack.extend([(node, true), (left, false), (right, false)]);
        }
    }
    Bvh {
        nodes,
        prim_indices: sorted_prims.to_vec(),
    }
}

pub(crate) struct BoundsRefit {
    pipeline: wgpu::ComputePipeline,
}

impl BoundsRefit {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            pipeline: compute_pipeline(ctx, "bounds_refit.wgsl", "main"),
        }
    }

    /// Records the leaf writes and the bottom-up climb into `scene.nodes`. `arrivals` must be
    /// zeroed beforehand.
    pub fn record(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        prims: &Prims<'_>,
        scene: &GpuScene,
        parents: &wgpu::Buffer,
        arrivals: &wgpu::Buffer,
    ) {
        let count = prims.count;
        let (gx, gy) = dispatch_grid(ctx, count, WORKGROUP);
        let params = uniform_buffer(
            ctx,
            "refit params",
            &RefitParams {
                count,
                row_pitch: gx * WORKGROUP,
                _pad: [0; 2],
            },
        );
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bounds_refit"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, prims.boxes),
                bind_entry(2, &scene.prim_indices),
                bind_entry(3, parents),
                bind_entry(4, &scene.nodes),
                bind_entry(5, arrivals),
            ],
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
}
