//! Refits: a tree keeps its topology and only its boxes follow moved triangles, recomputed on the
//! GPU bottom-up (kernel `nodes_refit`: a climb over parent links with the memory ordering of the
//! LBVH's `lbvh_climb`, for leaves of several triangles). Animated scenes with fixed
//! topology build their tree once, at the first frame (LBVH or TRBVH), and refit it every frame.
//!
//! Refitting the compacted tree needs its parent links and its list of leaves, which no build
//! stage keeps (the LBVH's parent links describe the tree before treelet restructuring and
//! collapse). They are derived once per topology and kept with the tree (`Tree::refit_links`):
//! the tree is read back and the parents and leaves are computed on the CPU and uploaded (O(n),
//! once; never per frame). The per-frame work is a single dispatch.
//!
//! Refitting keeps every box valid (exact unions of the triangles' coordinates) but not good:
//! when triangles move away from their neighbours of the first frame (the explosion), the boxes
//! grow and overlap and the SAH cost climbs, which the viewer's SAH plot shows next to a rebuild.

use crate::bvh::Bvh;
use crate::device::{RefitLinks, Tree};
use crate::gpu::{
    kernel, storage_buffer, storage_buffer_zeroed, GpuContext, Items, Kernel, Recorder,
};
use crate::{Error, Result};

/// Parent of the root in the uploaded parent links (the climb stops at node 0 before reading it).
const NO_PARENT: u32 = u32::MAX;

kernel!(pub NODES_REFIT: Items = "nodes_refit"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite]);

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

/// Derives `tree`'s refit links: reads the tree back, computes its parents and leaves on the CPU
/// and uploads them (O(n), once per topology; blocks until the GPU is done).
pub fn derive_refit_links(ctx: &GpuContext, tree: &Tree) -> Result<RefitLinks> {
    let bvh = tree.download(ctx)?;
    if bvh.nodes.is_empty() {
        return Err(Error::InvalidArgument("cannot refit an empty tree".into()));
    }
    let (parents, leaves) = parents_and_leaves(&bvh);
    Ok(RefitLinks {
        leaf_count: leaves.len() as u32,
        leaves: storage_buffer(ctx, "refit leaves", &leaves)?,
        parents: storage_buffer(ctx, "refit parents", &parents)?,
        arrivals: storage_buffer_zeroed(ctx, "refit arrivals", bvh.nodes.len() as u64 * 4)?,
    })
}

/// The kernel `nodes_refit`.
pub struct NodesRefit {
    kernel: Kernel<Items>,
}

impl NodesRefit {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            kernel: Kernel::climb(ctx, &NODES_REFIT),
        }
    }

    /// Records the refit of `tree`'s boxes to `triangles` through its links (pass "refit"; the
    /// arrival counters are cleared first).
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        triangles: &wgpu::Buffer,
        tree: &Tree,
        links: &RefitLinks,
    ) {
        rec.encoder().clear_buffer(&links.arrivals, 0, None);
        rec.pass("refit").dispatch_items(
            &self.kernel,
            links.leaf_count,
            &[
                triangles,
                &tree.prim_indices,
                &links.leaves,
                &links.parents,
                &tree.nodes,
                &links.arrivals,
            ],
        );
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
