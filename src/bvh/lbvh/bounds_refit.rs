//! LBVH stage 5: bottom-up bounds (Karras 2012 §4; kernel `bounds_refit`): one invocation per
//! leaf climbs parent links and the second arrival at each node merges its children. The kernel
//! keeps node boxes in atomics and orders them with device-scope barriers (see the shader header);
//! the CPU twin assembles the same tree sequentially.

use super::Hierarchy;
use crate::bvh::{Bvh, BvhNode};
use crate::geometry::Aabb;
use crate::gpu::{kernel, ItemCount, Items, Kernel, Pass};

kernel!(pub BOUNDS_REFIT: Items = "bounds_refit"::"main", [64, 1, 1], [Read, Read, Read, ReadWrite, ReadWrite, Read]);

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

/// The kernel `bounds_refit`.
pub(crate) struct BoundsRefit {
    kernel: Kernel<Items>,
}

impl BoundsRefit {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &BOUNDS_REFIT),
        }
    }

    /// Records the leaf writes and the bottom-up climb over `count` leaves into `nodes`.
    /// `arrivals` must be zeroed beforehand.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: ItemCount<'_>,
        order: &wgpu::Buffer,
        parents: &wgpu::Buffer,
        nodes: &wgpu::Buffer,
        arrivals: &wgpu::Buffer,
    ) {
        pass.dispatch_counted(
            &self.kernel,
            count,
            &[prim_boxes, order, parents, nodes, arrivals],
        );
    }
}
