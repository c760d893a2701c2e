//! A BVH on the GPU in the project's node layout (`BvhNode`, root at 0) with its primitive
//! references. `counts` holds [nodes, references] as the GPU wrote them: GPU builders compact on
//! the GPU, so the CPU learns the sizes only by reading them (`Tree::counts`), off the per-frame
//! path. The buffers grow to what a build needs and are reused by the next build.

use super::WideTree;
use crate::bvh::{Bvh, BvhNode};
use crate::gpu::{read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext};
use crate::{Error, Result};

pub struct Tree {
    pub nodes: wgpu::Buffer,
    pub prim_indices: wgpu::Buffer,
    /// [node count, reference count].
    pub counts: wgpu::Buffer,
    /// What a refit of this tree needs (derived once per topology, dropped by every build).
    pub refit_links: Option<RefitLinks>,
    /// The tree in the compressed wide layout, when a conversion made it (see
    /// `bvh::wide::WideConverter`); builds keep its buffers for the next conversion.
    pub wide: Option<WideTree>,
}

/// A tree's parent links and leaves, for refits (see `bvh::derive_refit_links`).
pub struct RefitLinks {
    pub parents: wgpu::Buffer,
    pub leaves: wgpu::Buffer,
    pub leaf_count: u32,
    /// The refit's arrival counters, one per node.
    pub arrivals: wgpu::Buffer,
}

impl Tree {
    /// A tree with room for nothing yet: builders grow it.
    pub fn empty(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            nodes: storage_buffer_zeroed(ctx, "bvh nodes", std::mem::size_of::<BvhNode>() as u64)?,
            prim_indices: storage_buffer_zeroed(ctx, "prim indices", 4)?,
            counts: storage_buffer_zeroed(ctx, "tree counts", 8)?,
            refit_links: None,
            wide: None,
        })
    }

    /// Uploads a CPU-built tree.
    pub fn upload(ctx: &GpuContext, bvh: &Bvh) -> Result<Self> {
        if bvh.nodes.is_empty() {
            return Err(Error::InvalidArgument("cannot upload an empty tree".into()));
        }
        let counts = [bvh.nodes.len() as u32, bvh.prim_indices.len() as u32];
        Ok(Self {
            nodes: storage_buffer(ctx, "bvh nodes", &bvh.nodes)?,
            prim_indices: storage_buffer(ctx, "prim indices", &bvh.prim_indices)?,
            counts: storage_buffer(ctx, "tree counts", &counts)?,
            refit_links: None,
            wide: None,
        })
    }

    /// Prepares the tree for a new build of `nodes` nodes and `prims` references: grows the
    /// buffers (contents are lost when a buffer grows) and drops the refit links of the old
    /// topology.
    pub fn reserve(&mut self, ctx: &GpuContext, nodes: u32, prims: u32) -> Result<()> {
        self.refit_links = None;
        let node_bytes = u64::from(nodes) * std::mem::size_of::<BvhNode>() as u64;
        if self.nodes.size() < node_bytes {
            self.nodes = storage_buffer_zeroed(ctx, "bvh nodes", node_bytes)?;
        }
        if self.prim_indices.size() < u64::from(prims) * 4 {
            self.prim_indices = storage_buffer_zeroed(ctx, "prim indices", u64::from(prims) * 4)?;
        }
        Ok(())
    }

    /// (nodes, references) of the last build; blocks until the GPU is done.
    pub fn counts(&self, ctx: &GpuContext) -> Result<(u32, u32)> {
        let counts: Vec<u32> = read_buffer(ctx, &self.counts, 2)?;
        Ok((counts[0], counts[1]))
    }

    /// Reads the tree back (validation, SAH, export); blocks until the GPU is done.
    pub fn download(&self, ctx: &GpuContext) -> Result<Bvh> {
        let (nodes, prims) = self.counts(ctx)?;
        Ok(Bvh {
            nodes: read_buffer(ctx, &self.nodes, nodes as usize)?,
            prim_indices: read_buffer(ctx, &self.prim_indices, prims as usize)?,
        })
    }
}
