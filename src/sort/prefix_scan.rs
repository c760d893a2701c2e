//! Portable multi-level exclusive prefix sum of u32s on the GPU (reduce-then-scan, no look-back):
//! `counts_scan.wgsl` scans blocks of `SCAN_BLOCK` (4096) in place and writes block totals to the
//! next level, recursively until one block remains; `counts_add.wgsl` adds the scanned totals back,
//! top down. The grand total ends in the `total()` buffer. Several equal-length arrays stored back
//! to back ("columns") are scanned independently by the same dispatches. A consumer that can add
//! a block's offset itself skips the last add-back (`record_block_local`): BVH compaction (two
//! columns) and pre-splitting read their scans that way; `record` gives the plain scan.

use bytemuck::{Pod, Zeroable};

use super::counts_add::COUNTS_ADD;
use super::counts_scan::COUNTS_SCAN;
use crate::gpu::constants::SCAN_BLOCK;
use crate::gpu::{storage_buffer_zeroed, GpuContext, Grid, Kernel, Pass};
use crate::{Error, Result};

/// Parameters of one scan level (WGSL twin in `shaders/include/scan_blocks.wgsl`).
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

/// Lengths (per column) of the scan levels for `len` elements: level 0 is the data, level i + 1
/// holds the block totals of level i; the last level fits in one block. At least `min_levels`.
fn scan_levels(len: u32, min_levels: usize) -> Vec<u32> {
    let mut levels = vec![len];
    while let Some(&last) = levels
        .last()
        .filter(|&&l| l > SCAN_BLOCK || levels.len() < min_levels)
    {
        levels.push(last.div_ceil(SCAN_BLOCK));
    }
    levels
}

/// The blocks of `len` elements: where a block-local scan's offsets of a column start.
pub fn scan_blocks(len: u32) -> u32 {
    len.max(1).div_ceil(SCAN_BLOCK)
}

/// Kernels and level buffers (grown on demand) of the scan.
pub struct PrefixScan {
    scan: Kernel<ScanParams>,
    add: Kernel<ScanParams>,
    /// Block totals of levels 1.. (at least level 1) and, last, the grand totals (one per column).
    levels: Vec<wgpu::Buffer>,
    /// Elements per column and columns the levels are sized for.
    capacity: (u32, u32),
    max_workgroups_per_dimension: u32,
}

impl PrefixScan {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            scan: Kernel::new(ctx, &COUNTS_SCAN),
            add: Kernel::new(ctx, &COUNTS_ADD),
            levels: Vec::new(),
            capacity: (0, 0),
            max_workgroups_per_dimension: u32::MAX,
        }
    }

    /// Caps workgroups per grid dimension (so tests can take the 2D path with small inputs).
    pub fn set_max_workgroups_per_dimension(&mut self, max: u32) {
        self.max_workgroups_per_dimension = max.max(1);
    }

    /// The grand totals (one u32 per column) of the last recorded scan (after `reserve`).
    pub fn total(&self) -> &wgpu::Buffer {
        self.levels.last().expect("reserve() allocates the levels")
    }

    /// After `record_block_local`: the exclusive scan of each column's block totals, column c's
    /// at `c * scan_blocks(len)`.
    pub fn block_offsets(&self) -> &wgpu::Buffer {
        &self.levels[0]
    }

    /// Grows the level buffers for scans of up to `columns` columns of `len` elements.
    pub fn reserve(&mut self, ctx: &GpuContext, len: u32, columns: u32) -> Result<()> {
        let len = len.max(1);
        let columns = columns.max(1);
        if self.capacity.0 < len || self.capacity.1 < columns {
            let len = len.max(self.capacity.0);
            let columns = columns.max(self.capacity.1);
            let mut levels = Vec::new();
            for level_len in scan_levels(len, 2).into_iter().skip(1) {
                levels.push(storage_buffer_zeroed(
                    ctx,
                    "scan level",
                    u64::from(level_len) * u64::from(columns) * 4,
                )?);
            }
            levels.push(storage_buffer_zeroed(
                ctx,
                "scan totals",
                u64::from(columns) * 4,
            )?);
            self.levels = levels;
            self.capacity = (len, columns);
        }
        Ok(())
    }

    /// Records the exclusive scan of the first `len` u32s of `data` (in place) into `pass`; the
    /// total lands in `total()`. Call `reserve(len, 1)` first.
    pub fn record(&self, pass: &mut Pass<'_>, data: &wgpu::Buffer, len: u32) -> Result<()> {
        self.record_levels(pass, data, len, 1, 1, 0)
    }

    /// Records the exclusive scans of `columns` arrays of `len` u32s stored back to back in
    /// `data`, each on its own, but leaves out the add-back into `data` itself: element i of
    /// column c's scan is then `data[c·len + i] + block_offsets()[c·scan_blocks(len) + i /
    /// SCAN_BLOCK]`, and the column's total is `total()[c]`. One dispatch fewer than `record`
    /// per scan, for a consumer that adds the offset where it reads. Call `reserve(len, columns)`
    /// first.
    pub fn record_block_local(
        &self,
        pass: &mut Pass<'_>,
        data: &wgpu::Buffer,
        len: u32,
        columns: u32,
    ) -> Result<()> {
        self.record_levels(pass, data, len, columns, 2, 1)
    }

    /// The scan of `columns` columns with at least `min_levels` levels, the add-backs stopping at
    /// level `lowest_add`.
    fn record_levels(
        &self,
        pass: &mut Pass<'_>,
        data: &wgpu::Buffer,
        len: u32,
        columns: u32,
        min_levels: usize,
        lowest_add: usize,
    ) -> Result<()> {
        let len = len.max(1);
        let elements = u64::from(len) * u64::from(columns);
        if data.size() < elements * 4 || self.capacity.0 < len || self.capacity.1 < columns {
            return Err(Error::InvalidArgument(format!(
                "scan of {columns} × {len} elements on a buffer of {} bytes (levels reserved for \
                 {} × {})",
                data.size(),
                self.capacity.1,
                self.capacity.0
            )));
        }
        let lens = scan_levels(len, min_levels);
        let max = self.max_workgroups_per_dimension.min(
            pass.ctx()
                .device
                .limits()
                .max_compute_workgroups_per_dimension,
        );
        // Level i's data, and where its block totals go: level i + 1's data, or the grand total
        // at the top level (the level buffers may be sized for more levels than `len` needs).
        let data_of = |level: usize| {
            if level == 0 {
                data
            } else {
                &self.levels[level - 1]
            }
        };
        let sums_of = |level: usize| {
            if level + 1 == lens.len() {
                self.total()
            } else {
                &self.levels[level]
            }
        };
        let params = |level_len: u32| ScanParams {
            len: level_len,
            num_blocks: level_len.div_ceil(SCAN_BLOCK),
            columns,
            _pad: 0,
        };
        let grid =
            |level_len: u32| Grid::items_capped(level_len.div_ceil(SCAN_BLOCK) * columns, 1, max);
        for (level, &level_len) in lens.iter().enumerate() {
            pass.dispatch(
                &self.scan,
                grid(level_len),
                &params(level_len),
                &[data_of(level), sums_of(level)],
            );
        }
        for (level, &level_len) in lens.iter().enumerate().rev().skip(1) {
            if level < lowest_add {
                break;
            }
            pass.dispatch(
                &self.add,
                grid(level_len),
                &params(level_len),
                &[data_of(level), sums_of(level)],
            );
        }
        Ok(())
    }
}
