//! Portable exclusive prefix sum of u32s on the GPU (reduce-then-scan, no look-back and no
//! workgroup waiting for another): `counts_scan.wgsl` scans blocks of `SCAN_BLOCK` (4096) in place
//! and stores their totals, and the workgroup that finishes last scans those totals into block
//! offsets (`block_offsets()`) and the grand total (`total()`), all in one dispatch;
//! `counts_add.wgsl` adds the offsets back. Several equal-length arrays stored back to back
//! ("columns") are scanned independently by the same dispatches. A consumer that can add a
//! block's offset itself skips the add-back (`record_block_local`, one dispatch): BVH compaction
//! (two columns) and pre-splitting read their scans that way; `record` gives the plain scan.

use bytemuck::{Pod, Zeroable};

use super::counts_add::COUNTS_ADD;
use super::counts_scan::COUNTS_SCAN;
use crate::gpu::constants::SCAN_BLOCK;
use crate::gpu::{storage_buffer_zeroed, GpuContext, Grid, Kernel, Pass};
use crate::{Error, Result};

/// Parameters of a scan dispatch (WGSL twin in `shaders/include/scan_blocks.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ScanParams {
    /// Elements per column.
    len: u32,
    /// Blocks per column.
    num_blocks: u32,
    columns: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<ScanParams>() == 16);

impl ScanParams {
    fn new(len: u32, columns: u32) -> Self {
        Self {
            len,
            num_blocks: scan_blocks(len),
            columns,
            _pad: 0,
        }
    }
}

/// The blocks of `len` elements: where a block-local scan's offsets of a column start.
pub fn scan_blocks(len: u32) -> u32 {
    len.max(1).div_ceil(SCAN_BLOCK)
}

/// The scan's buffers besides the data.
struct ScanBuffers {
    /// Per column, the block totals, then their exclusive scan (the block offsets).
    block_sums: wgpu::Buffer,
    /// The grand total of each column.
    totals: wgpu::Buffer,
    /// Workgroups finished so far (one word, zero between dispatches).
    ticket: wgpu::Buffer,
}

/// Kernels and buffers (grown on demand) of the scan.
pub struct PrefixScan {
    scan: Kernel<ScanParams>,
    add: Kernel<ScanParams>,
    buffers: Option<ScanBuffers>,
    /// Elements per column and columns the buffers are sized for.
    capacity: (u32, u32),
    max_workgroups_per_dimension: u32,
}

impl PrefixScan {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            scan: Kernel::new(ctx, &COUNTS_SCAN),
            add: Kernel::new(ctx, &COUNTS_ADD),
            buffers: None,
            capacity: (0, 0),
            max_workgroups_per_dimension: u32::MAX,
        }
    }

    /// Caps workgroups per grid dimension (so tests can take the 2D path with small inputs).
    pub fn set_max_workgroups_per_dimension(&mut self, max: u32) {
        self.max_workgroups_per_dimension = max.max(1);
    }

    fn buffers(&self) -> &ScanBuffers {
        self.buffers
            .as_ref()
            .expect("reserve() allocates the buffers")
    }

    /// The grand totals (one u32 per column) of the last recorded scan (after `reserve`).
    pub fn total(&self) -> &wgpu::Buffer {
        &self.buffers().totals
    }

    /// After `record_block_local`: the exclusive scan of each column's block totals, column c's
    /// at `c * scan_blocks(len)`.
    pub fn block_offsets(&self) -> &wgpu::Buffer {
        &self.buffers().block_sums
    }

    /// Grows the buffers for scans of up to `columns` columns of `len` elements.
    pub fn reserve(&mut self, ctx: &GpuContext, len: u32, columns: u32) -> Result<()> {
        let len = len.max(1);
        let columns = columns.max(1);
        if self.capacity.0 < len || self.capacity.1 < columns {
            let len = len.max(self.capacity.0);
            let columns = columns.max(self.capacity.1);
            // Release the old buffers before allocating the new ones.
            self.buffers = None;
            self.buffers = Some(ScanBuffers {
                block_sums: storage_buffer_zeroed(
                    ctx,
                    "scan block sums",
                    u64::from(scan_blocks(len)) * u64::from(columns) * 4,
                )?,
                totals: storage_buffer_zeroed(ctx, "scan totals", u64::from(columns) * 4)?,
                ticket: storage_buffer_zeroed(ctx, "scan ticket", 4)?,
            });
            self.capacity = (len, columns);
        }
        Ok(())
    }

    /// Records the exclusive scan of the first `len` u32s of `data` (in place) into `pass`; the
    /// total lands in `total()`. Two dispatches (one up to `SCAN_BLOCK` elements). Call
    /// `reserve(len, 1)` first.
    pub fn record(&self, pass: &mut Pass<'_>, data: &wgpu::Buffer, len: u32) -> Result<()> {
        let grid = self.record_scan(pass, data, len, 1)?;
        if len > SCAN_BLOCK {
            pass.dispatch(
                &self.add,
                grid,
                &ScanParams::new(len, 1),
                &[data, &self.buffers().block_sums],
            );
        }
        Ok(())
    }

    /// Records the exclusive scans of `columns` arrays of `len` u32s stored back to back in
    /// `data`, each on its own, but leaves out the add-back into `data` itself: element i of
    /// column c's scan is then `data[c·len + i] + block_offsets()[c·scan_blocks(len) + i /
    /// SCAN_BLOCK]`, and the column's total is `total()[c]`. One dispatch, for a consumer that
    /// adds the offset where it reads. Call `reserve(len, columns)` first.
    pub fn record_block_local(
        &self,
        pass: &mut Pass<'_>,
        data: &wgpu::Buffer,
        len: u32,
        columns: u32,
    ) -> Result<()> {
        self.record_scan(pass, data, len, columns).map(|_| ())
    }

    /// The block scans with the block offsets and totals (one dispatch); its grid.
    fn record_scan(
        &self,
        pass: &mut Pass<'_>,
        data: &wgpu::Buffer,
        len: u32,
        columns: u32,
    ) -> Result<Grid> {
        let len = len.max(1);
        let elements = u64::from(len) * u64::from(columns);
        if data.size() < elements * 4 || self.capacity.0 < len || self.capacity.1 < columns {
            return Err(Error::InvalidArgument(format!(
                "scan of {columns} × {len} elements on a buffer of {} bytes (buffers reserved \
                 for {} × {})",
                data.size(),
                self.capacity.1,
                self.capacity.0
            )));
        }
        let max = self.max_workgroups_per_dimension.min(
            pass.ctx()
                .device
                .limits()
                .max_compute_workgroups_per_dimension,
        );
        let grid = Grid::items_capped(scan_blocks(len) * columns, 1, max);
        let buffers = self.buffers();
        pass.dispatch(
            &self.scan,
            grid,
            &ScanParams::new(len, columns),
            &[data, &buffers.block_sums, &buffers.totals, &buffers.ticket],
        );
        Ok(grid)
    }
}
