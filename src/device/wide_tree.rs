//! A compressed wide BVH on the GPU (layout of `bvh::wide::WideNode`), converted from a binary
//! `Tree` by `bvh::wide::WideConverter`. `counters` holds [nodes, references, capacity
//! overflows] as the GPU wrote them; `records` the conversion's per-level records (indirect
//! dispatch arguments; even levels in the first buffer, odd in the second). The buffers grow to
//! what a conversion needs and are reused.

use crate::bvh::wide::{WideBvh, WideNode};
use crate::gpu::{indirect_buffer_zeroed, read_buffer, storage_buffer_zeroed, GpuContext};
use crate::{Error, Result};

pub struct WideTree {
    pub nodes: wgpu::Buffer,
    pub prim_indices: wgpu::Buffer,
    /// The binary node each wide node was made from (conversion scratch).
    pub sources: wgpu::Buffer,
    pub counters: wgpu::Buffer,
    pub records: [wgpu::Buffer; 2],
    /// Wide nodes `nodes` holds.
    pub capacity: u32,
}

impl WideTree {
    /// Buffers for `nodes` wide nodes, `prims` references and level records of `record_bytes`.
    pub fn new(ctx: &GpuContext, nodes: u32, prims: u32, record_bytes: u64) -> Result<Self> {
        let nodes = nodes.max(1);
        Ok(Self {
            nodes: storage_buffer_zeroed(
                ctx,
                "wide nodes",
                u64::from(nodes) * std::mem::size_of::<WideNode>() as u64,
            )?,
            prim_indices: storage_buffer_zeroed(ctx, "wide prim indices", u64::from(prims) * 4)?,
            sources: storage_buffer_zeroed(ctx, "wide sources", u64::from(nodes) * 4)?,
            counters: storage_buffer_zeroed(ctx, "wide counters", 12)?,
            records: [
                indirect_buffer_zeroed(ctx, "wide records (even levels)", record_bytes)?,
                indirect_buffer_zeroed(ctx, "wide records (odd levels)", record_bytes)?,
            ],
            capacity: nodes,
        })
    }

    /// A wide tree made on the CPU (e.g. `WideBvh::from_binary_optimal`, a reference), uploaded
    /// for tracing: its nodes, references and counts, as a conversion would leave them.
    pub fn upload(ctx: &GpuContext, wide: &WideBvh) -> Result<Self> {
        let (nodes, prims) = (wide.nodes.len() as u32, wide.prim_indices.len() as u32);
        let tree = Self::new(ctx, nodes, prims, 12)?;
        ctx.queue
            .write_buffer(&tree.nodes, 0, bytemuck::cast_slice(&wide.nodes));
        if prims > 0 {
            ctx.queue.write_buffer(
                &tree.prim_indices,
                0,
                bytemuck::cast_slice(&wide.prim_indices),
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
