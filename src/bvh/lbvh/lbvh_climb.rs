//! LBVH stages 4-5 in one bottom-up climb (kernel `lbvh_climb`): the hierarchy of Karras 2012
//! (§4, Figure 4: the binary radix tree over the sorted keys, internal nodes 0..n-2 with the root
//! at 0, leaf j at node n-1+j, duplicate keys ordered by index), found bottom-up as in Apetrei
//! 2014, and the bounds (Karras 2012 §4), one invocation per leaf. The kernel keeps node data in
//! atomics and orders it with device-scope barriers (see the shader header). CPU twin: Karras's
//! top-down emission (`hierarchy_cpu`, a different algorithm for the same tree and numbering) and
//! a post-order assembly of the boxes (`assemble_lbvh_cpu`).

use crate::bvh::{Bvh, BvhNode};
use crate::geometry::Aabb;
use crate::gpu::{kernel, ItemCount, Items, Kernel, Pass};

kernel!(pub LBVH_CLIMB: Items = "lbvh_climb"::"main", [64, 1, 1],
    [Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, Read]);

/// Children (left, right) of each internal node and the parent of every node (root: u32::MAX).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Hierarchy {
    pub children: Vec<(u32, u32)>,
    pub parents: Vec<u32>,
}

/// CPU twin of the climb's hierarchy: Karras's top-down emission over the sorted keys, one
/// internal node at a time.
pub fn hierarchy_cpu(sorted_keys: &[u64]) -> Hierarchy {
    let n = sorted_keys.len();
    let delta = |i: i64, j: i64| -> i64 {
        if j < 0 || j >= n as i64 {
            return -1;
        }
        let x = sorted_keys[i as usize] ^ sorted_keys[j as usize];
        if x != 0 {
            i64::from(x.leading_zeros())
        } else {
            64 + i64::from((i as u32 ^ j as u32).leading_zeros())
        }
    };
    let mut children = vec![(0, 0); n.saturating_sub(1)];
    let mut parents = vec![u32::MAX; (2 * n).saturating_sub(1)];
    for (index, child) in children.iter_mut().enumerate() {
        let i = index as i64;
        let d = if delta(i, i + 1) > delta(i, i - 1) {
            1
        } else {
            -1
        };
        let delta_min = delta(i, i - d);
        let mut l_max = 2;
        while delta(i, i + l_max * d) > delta_min {
            l_max *= 2;
        }
        let mut l = 0;
        let mut t = l_max / 2;
        while t >= 1 {
            if delta(i, i + (l + t) * d) > delta_min {
                l += t;
            }
            t /= 2;
        }
        let j = i + l * d;
        let delta_node = delta(i, j);
        let (mut s, mut t) = (0, l);
        loop {
            t = (t + 1) / 2;
            if delta(i, i + (s + t) * d) > delta_node {
                s += t;
            }
            if t <= 1 {
                break;
            }
        }
        let gamma = i + s * d + d.min(0);
        let leaf_base = n as u32 - 1;
        let left = if i.min(j) == gamma {
            leaf_base + gamma as u32
        } else {
            gamma as u32
        };
        let right = if i.max(j) == gamma + 1 {
            leaf_base + gamma as u32 + 1
        } else {
            gamma as u32 + 1
        };
        *child = (left, right);
        parents[left as usize] = index as u32;
        parents[right as usize] = index as u32;
    }
    Hierarchy { children, parents }
}

/// CPU twin of the climb's bounds: the LBVH in the node layout from the hierarchy and the sorted
/// primitive order.
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

/// The kernel `lbvh_climb`.
pub(crate) struct LbvhClimb {
    kernel: Kernel<Items>,
}

/// The buffers of one climb.
pub(crate) struct ClimbBuffers<'a> {
    /// The sorted keys and the primitive of each leaf.
    pub keys: &'a wgpu::Buffer,
    pub order: &'a wgpu::Buffer,
    pub prim_boxes: &'a wgpu::Buffer,
    pub nodes: &'a wgpu::Buffer,
    pub parents: &'a wgpu::Buffer,
    /// One word per split, zero (and zero again after the climb).
    pub arrivals: &'a wgpu::Buffer,
}

impl LbvhClimb {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::climb(ctx, &LBVH_CLIMB),
        }
    }

    /// Records the hierarchy and bounds of `count` sorted leaves into `nodes` and `parents`.
    pub fn record(&self, pass: &mut Pass<'_>, count: ItemCount<'_>, b: &ClimbBuffers<'_>) {
        pass.dispatch_counted(
            &self.kernel,
            count,
            &[
                b.keys,
                b.prim_boxes,
                b.order,
                b.nodes,
                b.parents,
                b.arrivals,
            ],
        );
    }
}
