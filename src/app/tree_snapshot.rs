//! A tree's nodes read back without waiting, for its SAH cost in the panel and in the
//! rebuild-versus-refit plot: the frame's recording copies the tree's counts and node buffer
//! into a staging buffer, and the cost is computed once the GPU is done.

use crate::bvh::{sah_cost, Bvh, BvhNode, SahParams};
use crate::device::Tree;
use crate::gpu::{Readback, Recorder};
use crate::Result;

pub struct TreeSnapshot {
    readback: Readback,
    capacity: u64,
}

/// The SAH cost and leaf count of a snapshot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapshotCost {
    pub cost: f32,
    pub leaves: usize,
}

impl TreeSnapshot {
    /// Records a copy of `tree` into `reuse` when it is large enough, else into a new snapshot.
    pub fn record(rec: &mut Recorder<'_>, tree: &Tree, reuse: Option<TreeSnapshot>) -> Self {
        let capacity = 8 + tree.nodes.size();
        let mut snapshot = match reuse {
            Some(s) if s.capacity >= capacity && s.readback.is_free() => s,
            _ => Self {
                readback: Readback::new(rec.ctx, capacity),
                capacity,
            },
        };
        let encoder = rec.encoder();
        snapshot.readback.copy(encoder, &tree.counts, 0, 8);
        snapshot
            .readback
            .copy(encoder, &tree.nodes, 8, tree.nodes.size());
        snapshot
    }

    /// After the recording was submitted: starts reading.
    pub fn submitted(&mut self) {
        self.readback.start();
    }

    /// The tree's SAH cost under `params` once the copy is done (None while in flight).
    pub fn try_cost(&mut self, params: &SahParams) -> Option<Result<SnapshotCost>> {
        let bytes = self.readback.try_take()?;
        Some(bytes.map(|bytes| {
            let counts: [u32; 2] = bytemuck::pod_read_unaligned(&bytes[..8]);
            let nodes = counts[0] as usize;
            let bvh = Bvh {
                nodes: bytemuck::pod_collect_to_vec::<u8, BvhNode>(&bytes[8..8 + nodes * 32]),
                prim_indices: Vec::new(),
            };
            SnapshotCost {
                cost: sah_cost(&bvh, params),
                leaves: bvh.leaf_count(),
            }
        }))
    }
}
