//! Portable multi-level exclusive prefix sum of u32s on the GPU (reduce-then-scan, no look-back):
//! `counts_scan.wgsl` scans blocks of `SCAN_BLOCK` (4096) in place and writes block totals to the next level,
//! recursively until one block remains; `counts_add.wgsl` adds the scanned totals back, top down.
//! The grand total ends in a one-element buffer. Used by the radix sort and by BVH compaction.

use bytemuck::{Pod, Zeroable};

use super::counts_add::COUNTS_ADD;
use super::counts_scan::COUNTS_SCAN;
use crate::gpu::constants::SCAN_BLOCK;
use crate::gpu::{storage_buffer_zeroed, GpuContext, Grid, Kernel, Pass};
use crate::{Error, Result};

/// Parameters of one scan level (counts_scan.wgsl, counts_add.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ScanParams {
    len: u32,
    num_blocks: u32,
    _pad: [u32; 2],
}

/// Lengths of the scan levels for `len` elements: level 0 is the data, level i + 1 holds the block
/// totals of level i; the last level fits in one block.
fn scan_levels(len: u32) -> Vec<u32> {
    let mut levels = vec![len];
    while let Some(&last) = levels.last().filter(|&&l| l > SCAN_BLOCK) {
        levels.push(last.div_ceil(SCAN_BLOCK));
    }
    levels
}

/// Kernels and level buffers (grown on demand) of the scan.
pub struct PrefixScan {
    scan: Kernel<ScanParams>,
    add: Kernel<ScanParams>,
    /// Block totals of levels 1.. and, last, the one-element grand total.
    levels: Vec<wgpu::Buffer>,
    capacity: u32,
    max_workgroups_per_dimension: u32,
}

impl PrefixScan {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            scan: Kernel::new(ctx, &COUNTS_SCAN),
            add: Kernel::new(ctx, &COUNTS_ADD),
            levels: Vec::new(),
            capacity: 0,
            max_workgroups_per_dimension: u32::MAX,
        }
    }

    /// Caps workgroups per grid dimension (so tests can take the 2D path with small inputs).
    pub fn set_max_workgroups_per_dimension(&mut self, max: u32) {
        self.max_workgroups_per_dimension = max.max(1);
    }

    /// The one-element buffer that holds the total of the last recorded scan (after `reserve`).
    pub fn total(&self) -> &wgpu::Buffer {
        self.levels.last().expect("reserve() allocates the levels")
    }

    /// Grows the level buffers for scans of up to `len` elements.
    pub fn reserve(&mut self, ctx: &GpuContext, len: u32) -> Result<()> {
        let len = len.max(1);
        if self.capacity < len {
            let mut levels = Vec::new();
            for level_len in scan_levels(len).into_iter().skip(1) {
                levels.push(storage_buffer_zeroed(
                    ctx,
                    "scan level",
                    u64::from(level_len) * 4,
                )?);
            }
            levels.push(storage_buffer_zeroed(ctx, "scan total", 4)?);
            self.levels = levels;
            self.capacity = len;
        }
        Ok(())
    }

    /// Records the exclusive scan of the first `len` u32s of `data` (in place) into `pass`; the
    /// total lands in `total()`. Call `reserve(len)` first.
    pub fn record(&self, pass: &mut Pass<'_>, data: &wgpu::Buffer, len: u32) -> Result<()> {
        let len = len.max(1);
        if data.size() < u64::from(len) * 4 || self.capacity < len {
            return Err(Error::InvalidArgument(format!(
                "scan of {len} elements on a buffer of {} bytes (levels reserved for {})",
                data.size(),
                self.capacity
            )));
        }
        let lens = scan_levels(len);
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
            _pad: [0; 2],
        };
        let grid = |level_len: u32| Grid::items_capped(level_len.div_ceil(SCAN_BLOCK), 1, max);
        for (level, &level_len) in lens.iter().enumerate() {
            pass.dispatch(
                &self.scan,
                grid(level_len),
                &params(level_len),
                &[data_of(level), sums_of(level)],
            );
        }
        for (level, &level_len) in lens.iter().enumerate().rev().skip(1) {
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
