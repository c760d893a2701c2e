//! A compressed wide BVH on the GPU (layout of `bvh::wide::WideNode`), converted from a binary
//! `Tree` by `bvh::wide::WideConverter`, with its references' triangles in order (`triangles`,
//! what the wide traversal tests). `counters` holds [nodes, references, capacity
//! overflows] as the GPU wrote them; `records` the
//! conversion's per-level records (indirect dispatch arguments; even levels in the first buffer,
//! odd in the second); `collapse` the optimal collapse's scratch, per binary node. The buffers
//! grow to what a conversion needs and are reused.

use crate::bvh::wide::{gather_triangles, WideBvh, WideNode};
use crate::gpu::constants::COLLAPSE_COST_WORDS;
use crate::gpu::{indirect_buffer_zeroed, read_buffer, storage_buffer_zeroed, GpuContext};
use crate::scene::Triangle;
use crate::{Error, Result};

pub struct WideTree {
    pub nodes: wgpu::Buffer,
    pub prim_indices: wgpu::Buffer,
    /// The triangles of `prim_indices` in order, each with its index in its `_pad1` word: what
    /// the wide traversal tests (`bvh::wide::gather_triangles`, kernel `triangles_gather`).
    pub triangles: wgpu::Buffer,
    /// Per wide node, the binary node it was made from and a word the finish's walk keeps its
    /// siblings' end in (8 bytes; conversion scratch).
    pub sources: wgpu::Buffer,
    pub counters: wgpu::Buffer,
    pub records: [wgpu::Buffer; 2],
    /// Wide nodes `nodes` holds.
    pub capacity: u32,
    pub collapse: CollapseScratch,
}

/// What the SAH-optimal collapse computes per binary node before the conversion (kernels
/// `nodes_link` and `costs_climb`): 40 bytes per node of the binary tree's buffer, allocated only
/// for that collapse.
pub struct CollapseScratch {
    pub parents: wgpu::Buffer,
    /// The climb's arrival counters.
    pub arrivals: wgpu::Buffer,
    /// C(n, 1..=7), f32 (`COLLAPSE_COST_WORDS` per node).
    pub costs: wgpu::Buffer,
    /// One word of choices per node (collapse_choices.wgsl).
    pub choices: wgpu::Buffer,
    /// Binary nodes the buffers hold.
    pub capacity: u32,
}

impl CollapseScratch {
    fn new(ctx: &GpuContext, binary_nodes: u32) -> Result<Self> {
        let n = u64::from(binary_nodes.max(1));
        Ok(Self {
            parents: storage_buffer_zeroed(ctx, "collapse parents", n * 4)?,
            arrivals: storage_buffer_zeroed(ctx, "collapse arrivals", n * 4)?,
            costs: storage_buffer_zeroed(
                ctx,
                "collapse costs",
                n * 4 * u64::from(COLLAPSE_COST_WORDS),
            )?,
            choices: storage_buffer_zeroed(ctx, "collapse choices", n * 4)?,
            capacity: binary_nodes.max(1),
        })
    }
}

impl WideTree {
    /// Buffers for `nodes` wide nodes, `prims` references, level records of `record_bytes` and
    /// the optimal collapse of a binary tree of up to `binary_nodes` nodes (1 where the
    /// conversion is greedy: its kernels bind the choices but never read them).
    pub fn new(
        ctx: &GpuContext,
        nodes: u32,
        prims: u32,
        binary_nodes: u32,
        record_bytes: u64,
    ) -> Result<Self> {
        let nodes = nodes.max(1);
        Ok(Self {
            nodes: storage_buffer_zeroed(
                ctx,
                "wide nodes",
                u64::from(nodes) * std::mem::size_of::<WideNode>() as u64,
            )?,
            prim_indices: storage_buffer_zeroed(ctx, "wide prim indices", u64::from(prims) * 4)?,
            triangles: storage_buffer_zeroed(
                ctx,
                "wide triangles",
                u64::from(prims) * std::mem::size_of::<Triangle>() as u64,
            )?,
            sources: storage_buffer_zeroed(ctx, "wide sources", u64::from(nodes) * 8)?,
            counters: storage_buffer_zeroed(ctx, "wide counters", 12)?,
            records: [
                indirect_buffer_zeroed(ctx, "wide records (even levels)", record_bytes)?,
                indirect_buffer_zeroed(ctx, "wide records (odd levels)", record_bytes)?,
            ],
            capacity: nodes,
            collapse: CollapseScratch::new(ctx, binary_nodes)?,
        })
    }

    /// A wide tree made on the CPU (e.g. by `WideBvh::from_binary_optimal`) over `triangles`,
    /// uploaded for tracing: its nodes, references, their triangles and counts, as a conversion
    /// would leave them.
    pub fn upload(ctx: &GpuContext, wide: &WideBvh, triangles: &[Triangle]) -> Result<Self> {
        let (nodes, prims) = (wide.nodes.len() as u32, wide.prim_indices.len() as u32);
        if let Some(&bad) = wide
            .prim_indices
            .iter()
            .find(|&&i| i as usize >= triangles.len())
        {
            return Err(Error::InvalidArgument(format!(
                "wide tree references triangle {bad} of {}",
                triangles.len()
            )));
        }
        let tree = Self::new(ctx, nodes, prims, 1, 12)?;
        ctx.queue
            .write_buffer(&tree.nodes, 0, bytemuck::cast_slice(&wide.nodes));
        if prims > 0 {
            ctx.queue.write_buffer(
                &tree.prim_indices,
                0,
                bytemuck::cast_slice(&wide.prim_indices),
            );
            ctx.queue.write_buffer(
                &tree.triangles,
                0,
                bytemuck::cast_slice(&gather_triangles(triangles, &wide.prim_indices)),
            );
        }
        ctx.queue
            .write_buffer(&tree.counters, 0, bytemuck::cast_slice(&[nodes, prims, 0]));
        Ok(tree)
    }

    /// (nodes, references) of the last conversion; blocks until the GPU is done. An error when
    /// the conversion ran out of room (a bug: the capacity bounds every binary tree).
    pub fn counts(&self, ctx: &GpuContext) -> Result<(u32, u32)> {
        let counters: Vec<u32> = read_buffer(ctx, &self.counters, 3)?;
        if counters[2] != 0 {
            return Err(Error::Gpu(format!(
                "the wide conversion overflowed its {} nodes",
                self.capacity
            )));
        }
        Ok((counters[0], counters[1]))
    }

    /// Reads the wide tree back (validation, export); blocks until the GPU is done.
    pub fn download(&self, ctx: &GpuContext) -> Result<WideBvh> {
        let (nodes, prims) = self.counts(ctx)?;
        Ok(WideBvh {
            nodes: read_buffer(ctx, &self.nodes, nodes as usize)?,
            prim_indices: read_buffer(ctx, &self.prim_indices, prims as usize)?,
        })
    }
}
