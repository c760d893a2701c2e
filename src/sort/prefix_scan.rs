//! Portable multi-level exclusive prefix sum of u32s on the GPU (reduce-then-scan, no look-back):
//! `counts_scan.wgsl` scans blocks of 1024 in place and writes block totals to the next level,
//! recursively until one block remains; `counts_add.wgsl` adds the scanned totals back, top down.
//! The grand total ends in a one-element buffer. Used by the radix sort and by BVH compaction.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu::{compute_pipeline, storage_buffer_zeroed, GpuContext};
use crate::{Error, Result};

/// Elements per workgroup of the scan kernels (256 invocations × 4).
pub const SCAN_BLOCK: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ScanParams {
    len: u32,
    num_blocks: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<ScanParams>() == 16);

/// Lengths of the scan levels for `len` elements: level 0 is the data, level i + 1 holds the block
/// totals of level i; the last level fits in one block.
fn scan_levels(len: u32) -> Vec<u32> {
    let mut levels = vec![len];
    while let Some(&last) = levels.last().filter(|&&l| l > SCAN_BLOCK) {
        levels.push(last.div_ceil(SCAN_BLOCK));
    }
    levels
}

/// A bind group entry binding `size` bytes of `buffer` from `offset`.
pub(crate) fn bind_range(
    binding: u32,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset,
            size: wgpu::BufferSize::new(size),
        }),
    }
}

/// Workgroup grid for `groups` workgroups, capped at `max` per dimension: 1D, then 2D.
pub(crate) fn capped_grid(groups: u32, max: u32) -> Result<(u32, u32)> {
    if groups <= max {
        return Ok((groups, 1));
    }
    let y = groups.div_ceil(max);
    if y > max {
        return Err(Error::SceneTooLarge(format!(
            "{groups} workgroups do not fit a {max}x{max} grid"
        )));
    }
    Ok((groups.div_ceil(y), y))
}

/// Pipelines and level buffers (grown on demand) of the scan.
pub struct PrefixScan {
    scan: wgpu::ComputePipeline,
    add: wgpu::ComputePipeline,
    /// Block totals of levels 1.. and, last, the one-element grand total.
    levels: Vec<wgpu::Buffer>,
    capacity: u32,
    max_workgroups_per_dimension: u32,
}

/// A scan of one buffer, ready to record any number of times.
pub struct ScanPlan {
    groups: Vec<(wgpu::BindGroup, (u32, u32))>,
    add_groups: Vec<(wgpu::BindGroup, (u32, u32))>,
}

impl PrefixScan {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            scan: compute_pipeline(ctx, "counts_scan.wgsl", "main"),
            add: compute_pipeline(ctx, "counts_add.wgsl", "main"),
            levels: Vec::new(),
            capacity: 0,
            max_workgroups_per_dimension: u32::MAX,
        }
    }

    /// Caps workgroups per grid dimension (so tests can take the 2D path with small inputs).
    pub fn set_max_workgroups_per_dimension(&mut self, max: u32) {
        self.max_workgroups_per_dimension = max.max(1);
    }

    /// The one-element buffer that holds the total of the last recorded scan.
    pub fn total(&self) -> &wgpu::Buffer {
        self.levels.last().expect("plan() allocates the levels")
    }

    /// Prepares the exclusive scan of the first `len` u32s of `data` (in place).
    pub fn plan(&mut self, ctx: &GpuContext, data: &wgpu::Buffer, len: u32) -> Result<ScanPlan> {
        let len = len.max(1);
        if data.size() < u64::from(len) * 4 {
            return Err(Error::InvalidArgument(format!(
                "scan of {len} elements on a buffer of {} bytes",
                data.size()
            )));
        }
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
        let lens = scan_levels(len);
        let max = self
            .max_workgroups_per_dimension
            .min(ctx.device.limits().max_compute_workgroups_per_dimension);
        let stride = u64::from(ctx.device.limits().min_uniform_buffer_offset_alignment).max(16);
        let mut bytes = vec![0u8; lens.len() * stride as usize];
        for (level, &level_len) in lens.iter().enumerate() {
            let params = ScanParams {
                len: level_len,
                num_blocks: level_len.div_ceil(SCAN_BLOCK),
                _pad: [0; 2],
            };
            let at = level * stride as usize;
            bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&params));
        }
        let params = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scan params"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            });
        // Level i's data, and where its block totals go: level i + 1's data, or the grand total
        // at the top level (the level buffers may be sized for more levels than `len` needs).
        let total = self.levels.last().expect("levels allocated above");
        let data_of = |level: usize| {
            if level == 0 {
                data
            } else {
                &self.levels[level - 1]
            }
        };
        let sums_of = |level: usize| {
            if level + 1 == lens.len() {
                total
            } else {
                &self.levels[level]
            }
        };
        let level_bytes = |level: usize| u64::from(lens.get(level).copied().unwrap_or(1)) * 4;
        let group = |pipeline: &wgpu::ComputePipeline, level: usize| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("prefix scan"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    bind_range(0, &params, level as u64 * stride, 16),
                    bind_range(1, data_of(level), 0, level_bytes(level)),
                    bind_range(2, sums_of(level), 0, level_bytes(level + 1)),
                ],
            })
        };
        let mut groups = Vec::new();
        let mut add_groups = Vec::new();
        for (level, &level_len) in lens.iter().enumerate() {
            let grid = capped_grid(level_len.div_ceil(SCAN_BLOCK), max)?;
            groups.push((group(&self.scan, level), grid));
            if level + 1 < lens.len() {
                add_groups.push((group(&self.add, level), grid));
            }
        }
        Ok(ScanPlan { groups, add_groups })
    }

    /// Records a prepared scan into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, plan: &ScanPlan) {
        pass.set_pipeline(&self.scan);
        for (group, grid) in &plan.groups {
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        }
        pass.set_pipeline(&self.add);
        for (group, grid) in plan.add_groups.iter().rev() {
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        }
    }
}
