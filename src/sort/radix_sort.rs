//! Portable GPU LSD radix sort of (key, value) pairs: 64-bit keys as `[u32; 2]` (low word first),
//! u32 values, ascending and stable, sorting only the low `key_bits` bits.
//!
//! Method: reduce-then-scan per 8-bit digit (Satish, Harris & Garland 2009; Merrill & Grimshaw
//! 2010), no decoupled look-back and no cross-workgroup waiting of any kind, no subgroup
//! operations, at most 13 KiB of workgroup memory and 256 invocations per workgroup. Each of the
//! ceil(key_bits / 8) passes records, in one compute pass for the whole sort:
//!
//! 1. `keys_histogram.wgsl`: per tile of [`TILE_SIZE`] keys, digit counts, stored digit-major
//!    (`counts[digit * tiles + tile]`);
//! 2. `counts_scan.wgsl` once per level (blocks of 1024, block totals to the next level) and
//!    `counts_add.wgsl` once per level but the top (adds the scanned block totals back): an
//!    exclusive scan of `counts` of any length, so each (digit, tile) gets its first output slot;
//! 3. `keys_scatter.wgsl`: stable ranking of the tile (workgroup-memory emulation of match/ballot
//!    ranking, see the kernel) and the scatter to `offset[digit, tile] + rank`.
//!
//! Digits are 8 bits wide: a pass costs about as much with 4-bit digits (the scatter's cost per
//! pair barely depends on the digit width), so 8 bits halves the number of passes.
//! Passes ping-pong between the caller's buffers and internal scratch buffers, so that the result
//! ends in the caller's buffers; with an odd number of passes the input is first copied to the
//! scratch buffers (a buffer copy recorded before the compute pass), so the caller's buffers need
//! `COPY_SRC` usage besides `STORAGE`. Grids past the per-dimension workgroup limit are 2D; kernels
//! use the linear workgroup index `wid.x + wid.y * num_workgroups.x`.
//! The CPU twin [`sort_pairs_cpu`] is the same LSD radix sort on the CPU (the test oracle).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu::{
    compute_pipeline, read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext, GpuTimer,
};
use crate::{Error, Result};

/// Bits per digit: one pass per 8 key bits.
pub const RADIX_BITS: u32 = 8;
const RADIX: u32 = 1 << RADIX_BITS;
/// Pairs per workgroup (tile) of the histogram and scatter kernels (256 invocations × 8).
pub const TILE_SIZE: u32 = 2048;
/// Elements per workgroup of the scan kernels (256 invocations × 4).
const SCAN_BLOCK: u32 = 1024;

/// Parameters of one sort pass (keys_histogram.wgsl, keys_scatter.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
}
const _: () = assert!(std::mem::size_of::<SortParams>() == 16);

/// Parameters of one scan level (counts_scan.wgsl, counts_add.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ScanParams {
    len: u32,
    num_blocks: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<ScanParams>() == 16);

/// Number of passes for `key_bits` sorted bits.
fn pass_count(key_bits: u32) -> u32 {
    key_bits.div_ceil(RADIX_BITS)
}

/// Lengths of the scan levels for `len` elements: level 0 is the counts array, level i + 1 holds
/// the block totals of level i; the last level fits in one block.
fn scan_levels(len: u32) -> Vec<u32> {
    let mut levels = vec![len];
    while let Some(&last) = levels.last().filter(|&&l| l > SCAN_BLOCK) {
        levels.push(last.div_ceil(SCAN_BLOCK));
    }
    levels
}

/// Scratch buffers for sorts of up to `capacity` pairs: the ping-pong pair and the scan levels
/// (counts first, then one buffer of block totals per level, the last one holding the total).
struct Scratch {
    capacity: u32,
    keys: wgpu::Buffer,
    values: wgpu::Buffer,
    levels: Vec<wgpu::Buffer>,
}

impl Scratch {
    fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        let n = u64::from(capacity);
        let mut levels = Vec::new();
        for len in scan_levels(capacity.div_ceil(TILE_SIZE) * RADIX) {
            levels.push(storage_buffer_zeroed(
                ctx,
                "sort scan level",
                u64::from(len) * 4,
            )?);
        }
        levels.push(storage_buffer_zeroed(ctx, "sort scan total", 4)?);
        Ok(Self {
            capacity,
            keys: storage_buffer_zeroed(ctx, "sort scratch keys", n * 8)?,
            values: storage_buffer_zeroed(ctx, "sort scratch values", n * 4)?,
            levels,
        })
    }
}

/// The GPU radix sort: pipelines created once per device, scratch buffers grown on demand.
pub struct RadixSort {
    histogram: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    add: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    scratch: Option<Scratch>,
    max_workgroups_per_dimension: u32,
}

/// A bind group entry binding `size` bytes of `buffer` from `offset`.
fn bind_range(
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

impl RadixSort {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            histogram: compute_pipeline(ctx, "keys_histogram.wgsl", "main"),
            scan: compute_pipeline(ctx, "counts_scan.wgsl", "main"),
            add: compute_pipeline(ctx, "counts_add.wgsl", "main"),
            scatter: compute_pipeline(ctx, "keys_scatter.wgsl", "main"),
            scratch: None,
            max_workgroups_per_dimension: u32::MAX,
        }
    }

    /// Caps the workgroups per grid dimension below the device limit (at least 1), so that small
    /// inputs already take the 2D-grid path that inputs past 65,535 workgroups need (tests).
    pub fn with_max_workgroups_per_dimension(mut self, max: u32) -> Self {
        self.max_workgroups_per_dimension = max.max(1);
        self
    }

    /// Workgroup grid for `groups` workgroups: 1D up to the per-dimension limit, then 2D.
    fn grid(&self, ctx: &GpuContext, groups: u32) -> Result<(u32, u32)> {
        let max = self
            .max_workgroups_per_dimension
            .min(ctx.device.limits().max_compute_workgroups_per_dimension);
        if groups <= max {
            return Ok((groups, 1));
        }
        let y = groups.div_ceil(max);
        if y > max {
            return Err(Error::SceneTooLarge(format!(
                "radix sort needs {groups} workgroups, more than a {max}x{max} grid"
            )));
        }
        Ok((groups.div_ceil(y), y))
    }

    /// Records the sort of the first `len` pairs of `keys` (`[u32; 2]` each, low word first) and
    /// `values` (u32 each) by the low `key_bits` (1..=64) bits of the key, ascending and stable,
    /// into `encoder`; nothing is submitted. The sorted pairs end in `keys` and `values`, which need
    /// `STORAGE | COPY_SRC` usage. Internal scratch buffers grow to `len` on demand; several sorts
    /// may be recorded into one encoder.
    ///
    /// Everything is one compute pass; with a timer it is the single timestamped pass "sort"
    /// (one timer slot per call, also for `len` ≤ 1 where the pass is empty). The pass holds
    /// ceil(key_bits / 8) × (2 + 2 × levels − 1) dispatches, levels = scan levels of the
    /// len / 256 counts (1 up to 8,192 pairs, 2 up to 8.4 M pairs, then 3).
    #[allow(clippy::too_many_arguments)]
    pub fn sort(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
        len: u32,
        key_bits: u32,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        if !(1..=64).contains(&key_bits) {
            return Err(Error::InvalidArgument(format!(
                "radix sort key_bits must be 1..=64, got {key_bits}"
            )));
        }
        let (key_bytes, value_bytes) = (u64::from(len) * 8, u64::from(len) * 4);
        if keys.size() < key_bytes || values.size() < value_bytes {
            return Err(Error::InvalidArgument(format!(
                "radix sort of {len} pairs needs {key_bytes} key bytes and {value_bytes} value bytes, \
                 the buffers hold {} and {}",
                keys.size(),
                values.size()
            )));
        }
        let timestamp_writes = timer.and_then(|t| t.pass("sort"));
        if len <= 1 {
            if timestamp_writes.is_some() {
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("sort"),
                    timestamp_writes,
                });
            }
            return Ok(());
        }
        if self.scratch.as_ref().is_none_or(|s| s.capacity < len) {
            // Drop the old buffers first so that peak memory holds one set.
            self.scratch = None;
            self.scratch = Some(Scratch::new(ctx, len)?);
        }
        let scratch = self.scratch.as_ref().expect("scratch allocated above");

        let passes = pass_count(key_bits);
        let num_tiles = len.div_ceil(TILE_SIZE);
        let levels = scan_levels(num_tiles * RADIX);
        let tile_grid = self.grid(ctx, num_tiles)?;
        let level_grids = levels
            .iter()
            .map(|&l| self.grid(ctx, l.div_ceil(SCAN_BLOCK)))
            .collect::<Result<Vec<_>>>()?;

        // One parameter slot per pass, then one per scan level, at uniform-offset alignment: every
        // dispatch keeps its own parameters however many sorts are recorded before the submit.
        let stride = u64::from(ctx.device.limits().min_uniform_buffer_offset_alignment).max(16);
        let slots = passes as usize + levels.len();
        let mut bytes = vec![0u8; slots * stride as usize];
        for pass in 0..passes {
            let shift = pass * RADIX_BITS;
            let params = SortParams {
                n: len,
                num_tiles,
                shift,
                bits: RADIX_BITS.min(key_bits - shift),
            };
            let at = pass as usize * stride as usize;
            bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&params));
        }
        for (level, &level_len) in levels.iter().enumerate() {
            let params = ScanParams {
                len: level_len,
                num_blocks: level_len.div_ceil(SCAN_BLOCK),
                _pad: [0; 2],
            };
            let at = (passes as usize + level) * stride as usize;
            bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&params));
        }
        let params = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sort params"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let pass_params = |pass: u32| bind_range(0, &params, u64::from(pass) * stride, 16);
        let level_params =
            |level: usize| bind_range(0, &params, (passes as usize + level) as u64 * stride, 16);
        let level_bytes = |level: usize| u64::from(levels.get(level).copied().unwrap_or(1)) * 4;

        let scan_groups: Vec<wgpu::BindGroup> = (0..levels.len())
            .map(|level| {
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("counts_scan"),
                    layout: &self.scan.get_bind_group_layout(0),
                    entries: &[
                        level_params(level),
                        bind_range(1, &scratch.levels[level], 0, level_bytes(level)),
                        bind_range(2, &scratch.levels[level + 1], 0, level_bytes(level + 1)),
                    ],
                })
            })
            .collect();
        let add_groups: Vec<wgpu::BindGroup> = (0..levels.len() - 1)
            .map(|level| {
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("counts_add"),
                    layout: &self.add.get_bind_group_layout(0),
                    entries: &[
                        level_params(level),
                        bind_range(1, &scratch.levels[level], 0, level_bytes(level)),
                        bind_range(2, &scratch.levels[level + 1], 0, level_bytes(level + 1)),
                    ],
                })
            })
            .collect();

        // Pass p reads `src` and writes `dst`; the last pass writes the caller's buffers.
        let (mut src, mut dst) = ((keys, values), (&scratch.keys, &scratch.values));
        if passes % 2 == 1 {
            encoder.copy_buffer_to_buffer(keys, 0, &scratch.keys, 0, key_bytes);
            encoder.copy_buffer_to_buffer(values, 0, &scratch.values, 0, value_bytes);
            std::mem::swap(&mut src, &mut dst);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("sort"),
            timestamp_writes,
        });
        for p in 0..passes {
            let histogram = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("keys_histogram"),
                layout: &self.histogram.get_bind_group_layout(0),
                entries: &[
                    pass_params(p),
                    bind_range(1, src.0, 0, key_bytes),
                    bind_range(2, &scratch.levels[0], 0, level_bytes(0)),
                ],
            });
            let scatter = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("keys_scatter"),
                layout: &self.scatter.get_bind_group_layout(0),
                entries: &[
                    pass_params(p),
                    bind_range(1, src.0, 0, key_bytes),
                    bind_range(2, src.1, 0, value_bytes),
                    bind_range(3, &scratch.levels[0], 0, level_bytes(0)),
                    bind_range(4, dst.0, 0, key_bytes),
                    bind_range(5, dst.1, 0, value_bytes),
                ],
            });
            pass.set_pipeline(&self.histogram);
            pass.set_bind_group(0, &histogram, &[]);
            pass.dispatch_workgroups(tile_grid.0, tile_grid.1, 1);
            pass.set_pipeline(&self.scan);
            for (group, grid) in scan_groups.iter().zip(&level_grids) {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(grid.0, grid.1, 1);
            }
            pass.set_pipeline(&self.add);
            for (group, grid) in add_groups.iter().zip(&level_grids).rev() {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(grid.0, grid.1, 1);
            }
            pass.set_pipeline(&self.scatter);
            pass.set_bind_group(0, &scatter, &[]);
            pass.dispatch_workgroups(tile_grid.0, tile_grid.1, 1);
            std::mem::swap(&mut src, &mut dst);
        }
        Ok(())
    }

    /// Uploads the pairs, sorts them by the low `key_bits` bits of the keys, submits and reads the
    /// result back (tests and benchmarks).
    pub fn sort_pairs(
        &mut self,
        ctx: &GpuContext,
        keys: &[[u32; 2]],
        values: &[u32],
        key_bits: u32,
    ) -> Result<(Vec<[u32; 2]>, Vec<u32>)> {
        if keys.len() != values.len() {
            return Err(Error::InvalidArgument(format!(
                "{} keys but {} values",
                keys.len(),
                values.len()
            )));
        }
        let len = u32::try_from(keys.len())
            .map_err(|_| Error::InvalidArgument(format!("{} pairs to sort", keys.len())))?;
        let key_buffer = storage_buffer(ctx, "sort keys", keys)?;
        let value_buffer = storage_buffer(ctx, "sort values", values)?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("sort pairs"),
            });
        self.sort(
            ctx,
            &mut encoder,
            &key_buffer,
            &value_buffer,
            len,
            key_bits,
            None,
        )?;
        ctx.queue.submit([encoder.finish()]);
        Ok((
            read_buffer(ctx, &key_buffer, keys.len())?,
            read_buffer(ctx, &value_buffer, values.len())?,
        ))
    }
}

/// One-shot [`RadixSort::sort_pairs`] (creates the pipelines; keep a [`RadixSort`] to sort often).
pub fn sort_pairs(
    ctx: &GpuContext,
    keys: &[[u32; 2]],
    values: &[u32],
    key_bits: u32,
) -> Result<(Vec<[u32; 2]>, Vec<u32>)> {
    RadixSort::new(ctx).sort_pairs(ctx, keys, values, key_bits)
}

/// CPU twin of the GPU sort: an LSD radix sort with the same 8-bit digits (counting sort per
/// digit, stable), sorting by the low `key_bits` bits. Panics unless `key_bits` is in 1..=64 and
/// the slices have equal lengths.
pub fn sort_pairs_cpu(keys: &[u64], values: &[u32], key_bits: u32) -> (Vec<u64>, Vec<u32>) {
    assert!(
        (1..=64).contains(&key_bits),
        "key_bits must be 1..=64, got {key_bits}"
    );
    assert_eq!(keys.len(), values.len(), "keys and values differ in length");
    let (mut keys, mut values) = (keys.to_vec(), values.to_vec());
    let (mut keys_out, mut values_out) = (vec![0u64; keys.len()], vec![0u32; values.len()]);
    for pass in 0..pass_count(key_bits) {
        let shift = pass * RADIX_BITS;
        let mask = (1u64 << RADIX_BITS.min(key_bits - shift)) - 1;
        let digit = |key: u64| ((key >> shift) & mask) as usize;
        let mut offsets = [0usize; RADIX as usize];
        for &key in &keys {
            offsets[digit(key)] += 1;
        }
        let mut sum = 0;
        for offset in &mut offsets {
            (*offset, sum) = (sum, sum + *offset);
        }
        for (&key, &value) in keys.iter().zip(&values) {
            let slot = &mut offsets[digit(key)];
            keys_out[*slot] = key;
            values_out[*slot] = value;
            *slot += 1;
        }
        std::mem::swap(&mut keys, &mut keys_out);
        std::mem::swap(&mut values, &mut values_out);
    }
    (keys, values)
}
