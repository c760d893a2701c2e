//! GPU leaf collapse and compaction into the traversal layout (Karras & Aila 2013, §3): mark kept
//! nodes and output leaves (kernel `nodes_mark`), exclusive scans for new node indices and leaf
//! primitive ranges (`sort::PrefixScan`, both columns in one dispatch, block-local: the
//! compaction adds each block's offset where it reads), then write the output tree (kernel
//! `nodes_compact`: each working leaf writes its primitive, or its triangle once per leaf with
//! pre-split references, where the mark found its slot in its output leaf). Three dispatches. CPU
//! twin: `WorkingTree::collapse`.

use std::sync::OnceLock;

use super::dp::CostModel;
use super::nodes_compact::{CompactParams, NODES_COMPACT};
use super::nodes_mark::{MarkParams, HAS_REFS_OVERRIDE, NODES_MARK};
use super::rounds::TreeletState;
use crate::gpu::{flag_override, storage_buffer_zeroed, GpuContext, ItemCount, Kernel, Pass};
use crate::sort::PrefixScan;
use crate::Result;

/// Buffers of one collapse: scratch (flags, scans) and the output tree.
pub(crate) struct CollapseBuffers<'a> {
    pub flags: &'a wgpu::Buffer,
    /// Two columns of 2n - 1 words: kept flags, then output leaves' primitive counts (scanned in
    /// place, block-local).
    pub scans: &'a wgpu::Buffer,
    /// Per working leaf (n pairs): the output leaf that holds its primitive and where in its
    /// range, none for a repeated triangle (written by `nodes_mark`, read by `nodes_compact`).
    pub leaf_slots: &'a wgpu::Buffer,
    pub out_nodes: &'a wgpu::Buffer,
    pub out_prims: &'a wgpu::Buffer,
    pub tree_counts: &'a wgpu::Buffer,
    /// Triangle of each pre-split reference; None when primitives are triangles.
    pub ref_tris: Option<&'a wgpu::Buffer>,
}

pub(crate) struct Collapse {
    /// `nodes_mark` for triangles and for pre-split references (`HAS_REFS_OVERRIDE`), compiled
    /// when first used.
    mark: [OnceLock<Kernel<MarkParams>>; 2],
    compact: Kernel<CompactParams>,
    scan: PrefixScan,
    /// Bound as `ref_tris` when there are no references (the kernels then never read it).
    no_refs: wgpu::Buffer,
}

impl Collapse {
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            mark: Default::default(),
            compact: Kernel::new(ctx, &NODES_COMPACT),
            scan: PrefixScan::new(ctx),
            no_refs: storage_buffer_zeroed(ctx, "no references", 4)?,
        })
    }

    /// Grows the scan's buffers for a working tree of `n` leaves.
    pub fn reserve(&mut self, ctx: &GpuContext, n: u32) -> Result<()> {
        self.scan.reserve(ctx, 2 * n - 1, 2)
    }

    /// Records the collapse of a working tree of `n` leaves (nodes and primitive order in
    /// `state` and `prims`) into `out`. Call `reserve(n)` first.
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        count: ItemCount<'_>,
        prims: &wgpu::Buffer,
        state: &TreeletState<'_>,
        model: &CostModel,
        out: &CollapseBuffers<'_>,
    ) -> Result<()> {
        let ctx = pass.ctx();
        let n = count.capacity();
        let node_count = 2 * n - 1;
        let has_refs = out.ref_tris.is_some();
        let ref_tris = out.ref_tris.unwrap_or(&self.no_refs);
        let mark_kernel = self.mark[usize::from(has_refs)].get_or_init(|| {
            Kernel::with_overrides(
                ctx,
                &NODES_MARK,
                &[flag_override(HAS_REFS_OVERRIDE, has_refs)],
            )
        });
        let grid = mark_kernel.grid(ctx, node_count);
        let mark = MarkParams {
            leaf_count: n,
            row_pitch: grid.row_pitch,
            max_leaf_size: model.max_leaf_size,
            ct: model.ct,
            zero: 0,
            _pad: [0; 3],
        };
        pass.dispatch(
            mark_kernel,
            grid,
            &mark,
            &[
                state.nodes,
                state.parents,
                state.prim_counts,
                state.costs,
                out.flags,
                out.scans,
                prims,
                ref_tris,
                count.limit(ctx),
                out.leaf_slots,
            ],
        );
        self.scan
            .record_block_local(pass, out.scans, node_count, 2)?;
        let compact = CompactParams {
            leaf_count: n,
            row_pitch: grid.row_pitch,
            has_refs: u32::from(has_refs),
            _pad: 0,
        };
        pass.dispatch(
            &self.compact,
            grid,
            &compact,
            &[
                state.nodes,
                prims,
                out.flags,
                out.scans,
                self.scan.block_offsets(),
                out.out_nodes,
                out.out_prims,
                out.tree_counts,
                ref_tris,
                self.scan.total(),
                count.limit(ctx),
                out.leaf_slots,
            ],
        );
        Ok(())
    }
}
