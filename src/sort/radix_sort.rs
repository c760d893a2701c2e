//! Portable GPU LSD radix sort of (key, value) pairs: 64-bit keys as `[u32; 2]` (low word first),
//! u32 values, ascending and stable, sorting only the low `key_bits` bits.
//!
//! Method: reduce-then-scan per 4-bit digit (Satish, Harris & Garland 2009; Merrill & Grimshaw
//! 2010), no decoupled look-back and no cross-workgroup waiting of any kind, no subgroup
//! operations, 11 KiB of workgroup memory and 256 invocations per workgroup. A sort of P =
//! ceil(key_bits / 4) passes records P + 1 dispatches, in one compute pass for the whole sort:
//!
//! 1. `keys_histogram.wgsl`, once: per tile of keys (a workgroup's 256 invocations times
//!    `tile_items`, see [`tile_items`]), the 16 counts of the first pass's digit, stored
//!    digit-major (`counts[digit * tiles + tile]`);
//! 2. `keys_scatter.wgsl`, once per pass: each tile's first output slot per digit, summed by the
//!    workgroup from the counts of all tiles (16 × tiles words, which stay in cache: this replaces
//!    the scan dispatches between histogram and scatter), stable ranking within the tile by
//!    per-invocation counting (Zagha & Blelloch 1991, one "processor" per invocation; see the
//!    kernel), the scatter to `offset[digit, tile] + rank`, and the next pass's digit counts per
//!    tile of the output it writes (workgroup-memory counts per digit and output tile, added to
//!    the counts buffer with at most 512 device atomics per workgroup): the histogram dispatch the
//!    next pass would otherwise need. Three counts buffers rotate: pass p reads buffer p mod 3,
//!    adds into p + 1 (zeroed by the dispatch before) and zeroes p + 2.
//!
//! Writes: each invocation scatters the pairs it ranked. Staged writes (a round of ranked pairs
//! put in digit order in workgroup memory, then written by neighbouring invocations to
//! neighbouring slots) were built and timed on an NVIDIA H200 and lost at every size (lbvh
//! field:2000's sort 7.47 -> 9.45 ms, conference's 0.24 -> 0.33 ms; README, "On an NVIDIA H200,
//! second session"), and 1.7-3.5x on lavapipe, so they were taken out.
//!
//! Values beside the keys, or in them: where the values are small enough to fit above the sorted
//! key bits in 64, a sort can take them there, in bits it never reads as digits (`SortValues::AboveKeys`;
//! the LBVH's Morton keys with their indices, `packs_indices`): every pass but the last then
//! moves each pair as one 8-byte word, where the separate form reads and scatters 12 bytes in two
//! stores (one memory sector each on a GPU), and the last pass writes keys and values apart, as
//! the separate form leaves them.
//!
//! Digit width: 4 bits, measured about 2.5x faster on the software driver (lavapipe, 2 cores,
//! 1M pairs, 63-bit keys: about 0.14 s) than 8-bit digits ranked by workgroup-memory "ballots"
//! (match ranking with two barriers per 256 pairs): 16 counters fit in one vec4 of byte-wide
//! counters per invocation, so counting and ranking are a few vector instructions per pair with
//! three barriers per tile, which more than pays for twice the passes.
//!
//! Kernels: `keys_histogram`, `keys_scatter`.
//! Passes ping-pong between the caller's buffers and internal scratch buffers, so that the result
//! ends in the caller's buffers; with an odd number of passes the input is first copied to the
//! scratch buffers (a buffer copy recorded before the compute pass), so the caller's buffers need
//! `COPY_SRC` usage besides `STORAGE`. Grids past the per-dimension workgroup limit are 2D; kernels
//! use the linear workgroup index `wid.x + wid.y * num_workgroups.x`.
//! The CPU twin [`sort_pairs_cpu`] is the same LSD radix sort on the CPU (the test oracle).

use bytemuck::{Pod, Zeroable};

use super::keys_histogram::KEYS_HISTOGRAM;
use super::keys_scatter::KEYS_SCATTER;
pub use crate::gpu::constants::RADIX_BITS;
use crate::gpu::{
    read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext, Grid, ItemCount, Kernel,
    ParamSlab, Recorder,
};
use crate::{Error, Result};

const RADIX: u32 = 1 << RADIX_BITS;
/// Invocations per workgroup of the sort's kernels (`radix_digits.wgsl`).
const SORT_WORKGROUP: u32 = 256;
/// Keys per invocation a sort may use (`tile_items`): tiles of 2048, 4096 or 8192 keys.
pub const SORT_TILE_ITEMS: [u32; 3] = [8, 16, 32];

/// `items` if it is one of `SORT_TILE_ITEMS`, else a clear error.
pub fn check_tile_items(items: u32) -> Result<u32> {
    crate::error::one_of("sort tile items", items, &SORT_TILE_ITEMS)
}

/// The tile a sort of `len` keys takes on `ctx` unless it is fixed (`RadixSort::set_tile_items`):
/// the context's `sort_tile_items`, else `tile_items`.
pub fn context_tile_items(ctx: &GpuContext, len: u32) -> u32 {
    ctx.sort_tile_items
        .unwrap_or_else(|| tile_items(len, ctx.info.device_type))
}

/// Keys per invocation (a tile is 256 times as many keys) for `len` keys on a device of
/// `device` type. Each scatter workgroup sums 16 counts per tile, so the work of finding the
/// offsets grows with the square of the tile count; smaller tiles give more workgroups.
/// - On a GPU, the smallest tile with at most `GPU_TILES` tiles. On an H200 more workgroups paid
///   at both ends measured (`scripts/gpu-profile.sh`, lbvh sort stage): conference's 331k keys
///   0.27 ms in 162 tiles of 2048 keys, 0.29 ms in 81, 0.45 ms in 41; field:2000's 8.7M keys
///   7.3 ms in 2128 tiles of 4096, 10.3 ms in 1064 of 8192.
/// - On a CPU device (lavapipe), where every invocation is a SIMD lane of few cores, the largest
///   (tiles of 2048 cost lavapipe's sort about half again).
pub fn tile_items(len: u32, device: wgpu::DeviceType) -> u32 {
    const GPU_TILES: u32 = 2560;
    match device {
        wgpu::DeviceType::Cpu => SORT_TILE_ITEMS[2],
        _ => SORT_TILE_ITEMS
            .into_iter()
            .find(|&items| len.div_ceil(SORT_WORKGROUP * items) <= GPU_TILES)
            .unwrap_or(SORT_TILE_ITEMS[2]),
    }
}

/// Where a sort's values are (`RadixSort::record`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortValues {
    /// In a values buffer of their own, moved beside the keys.
    Apart,
    /// Above the key bits in the keys' words, moved with them (`packs_indices`), and written to
    /// the values buffer by the last pass.
    AboveKeys,
}

/// Where a pass finds and leaves the values (`pairs` of `SortParams`; the constants `PAIRS_*` of
/// keys_scatter.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
enum Pairs {
    /// In the values buffers, moved beside the keys.
    Separate = 0,
    /// Above the key bits, moved with the keys.
    Packed = 1,
    /// Above the key bits, written to the values buffer (the keys keep their key bits alone).
    Unpack = 2,
}

/// Parameters of one sort pass (keys_histogram.wgsl, keys_scatter.wgsl): its digit, `bits` bits
/// from bit `shift`, the next pass's digit (`next_bits` = 0 after the last pass) and where the
/// values are (`Pairs`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
    next_shift: u32,
    next_bits: u32,
    pairs: u32,
    /// The sorted bits, above which packed values sit.
    key_bits: u32,
}
const _: () = assert!(std::mem::size_of::<SortParams>() == 32);

impl SortParams {
    /// Pass `pass` of a sort of `len` pairs in `num_tiles` tiles by the low `key_bits` bits,
    /// with values as `packed` says (`SortValues::AboveKeys`): above the key bits, unpacked by the last
    /// pass.
    fn pass(len: u32, num_tiles: u32, key_bits: u32, pass: u32, packed: bool) -> Self {
        let shift = pass * RADIX_BITS;
        let next_shift = shift + RADIX_BITS;
        let pairs = match (packed, pass + 1 == pass_count(key_bits)) {
            (false, _) => Pairs::Separate,
            (true, false) => Pairs::Packed,
            (true, true) => Pairs::Unpack,
        };
        Self {
            n: len,
            num_tiles,
            shift,
            bits: RADIX_BITS.min(key_bits - shift),
            next_shift,
            next_bits: RADIX_BITS.min(key_bits.saturating_sub(next_shift)),
            pairs: pairs as u32,
            key_bits,
        }
    }
}

/// Whether `len` pairs whose values are indices below `len` fit keys of `key_bits` bits with the
/// values above them in 64 bits (`SortValues::AboveKeys`).
pub fn packs_indices(key_bits: u32, len: u32) -> bool {
    fits_above_keys(len.saturating_sub(1), key_bits)
}

/// Whether `value` fits above keys of `key_bits` (1..=63) bits in 64 bits.
fn fits_above_keys(value: u32, key_bits: u32) -> bool {
    (1..64).contains(&key_bits) && u64::from(value) >> (64 - key_bits) == 0
}

/// The keys' low `key_bits` (1..=63) bits with the values above them (`SortValues::AboveKeys`),
/// or an error where a value does not fit.
fn pack_values(keys: &[[u32; 2]], values: &[u32], key_bits: u32) -> Result<Vec<[u32; 2]>> {
    if !(1..64).contains(&key_bits) || !values.iter().all(|&v| fits_above_keys(v, key_bits)) {
        return Err(Error::InvalidArgument(format!(
            "values above keys of {key_bits} bits do not fit in 64 bits"
        )));
    }
    Ok(keys
        .iter()
        .zip(values)
        .map(|(k, &v)| {
            let key = (u64::from(k[0]) | (u64::from(k[1]) << 32)) & (u64::MAX >> (64 - key_bits));
            let word = key | (u64::from(v) << key_bits);
            [word as u32, (word >> 32) as u32]
        })
        .collect())
}

/// Number of passes for `key_bits` sorted bits.
fn pass_count(key_bits: u32) -> u32 {
    key_bits.div_ceil(RADIX_BITS)
}

/// Scratch buffers for sorts of up to `capacity` pairs: the ping-pong pair and the three
/// rotating digit-count buffers.
struct Scratch {
    capacity: u32,
    keys: wgpu::Buffer,
    values: wgpu::Buffer,
    counts: [wgpu::Buffer; 3],
}

impl Scratch {
    fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        let n = u64::from(capacity);
        Ok(Self {
            capacity,
            keys: storage_buffer_zeroed(ctx, "sort scratch keys", n * 8)?,
            values: storage_buffer_zeroed(ctx, "sort scratch values", n * 4)?,
            counts: [
                Self::counts(ctx, capacity)?,
                Self::counts(ctx, capacity)?,
                Self::counts(ctx, capacity)?,
            ],
        })
    }

    /// Digit counts for the most tiles: those of the smallest tile.
    fn counts(ctx: &GpuContext, capacity: u32) -> Result<wgpu::Buffer> {
        let tiles = capacity.div_ceil(SORT_WORKGROUP * SORT_TILE_ITEMS[0]);
        storage_buffer_zeroed(ctx, "sort digit counts", u64::from(tiles * RADIX) * 4)
    }
}

/// The kernels of one tile size (`SORT_TILE_ITEMS`, the WGSL override `TILE_ITEMS`).
struct TileKernels {
    histogram: Kernel<SortParams>,
    scatter: Kernel<SortParams>,
}

impl TileKernels {
    /// The kernels of tile size `SORT_TILE_ITEMS[variant]`.
    fn new(ctx: &GpuContext, variant: usize) -> Self {
        Self {
            histogram: Kernel::with_overrides(ctx, &KEYS_HISTOGRAM, &tile_override(variant)),
            scatter: Kernel::with_overrides(ctx, &KEYS_SCATTER, &tile_override(variant)),
        }
    }
}

/// The override of tile size `SORT_TILE_ITEMS[variant]`.
fn tile_override(variant: usize) -> [(&'static str, f64); 1] {
    [("TILE_ITEMS", f64::from(SORT_TILE_ITEMS[variant]))]
}

/// The GPU radix sort: kernels created per tile size when first used, scratch buffers grown on
/// demand.
pub struct RadixSort {
    kernels: [Option<TileKernels>; 3],
    scratch: Option<Scratch>,
    max_workgroups_per_dimension: u32,
    /// Keys per invocation of every sort (one of `SORT_TILE_ITEMS`); None: the context's
    /// `sort_tile_items`, else `tile_items` of the length and device.
    fixed_tile_items: Option<u32>,
    /// Parameters of the sorts `sort_pairs` records and submits itself.
    params: ParamSlab,
}

impl RadixSort {
    pub fn new(ctx: &GpuContext) -> Self {
        // The largest tile, which every CPU device and the largest inputs use, compiled up front.
        let mut kernels = [None, None, None];
        kernels[2] = Some(TileKernels::new(ctx, 2));
        Self {
            kernels,
            scratch: None,
            max_workgroups_per_dimension: u32::MAX,
            fixed_tile_items: None,
            params: ParamSlab::new(ctx),
        }
    }

    /// Sorts in tiles of 256 × `items` keys (one of `SORT_TILE_ITEMS`) whatever the length and
    /// device (tests; the result is the same for every tile).
    pub fn with_tile_items(mut self, items: u32) -> Result<Self> {
        self.set_tile_items(Some(items))?;
        Ok(self)
    }

    /// The tile of the next sorts: 256 × `items` keys (one of `SORT_TILE_ITEMS`), or None: the
    /// context's `sort_tile_items`, else `tile_items` of the length and device.
    pub fn set_tile_items(&mut self, items: Option<u32>) -> Result<()> {
        self.fixed_tile_items = items.map(check_tile_items).transpose()?;
        Ok(())
    }

    /// Caps the workgroups per grid dimension below the device limit (at least 1), so that small
    /// inputs already take the 2D-grid path that inputs past 65,535 workgroups need (tests).
    pub fn with_max_workgroups_per_dimension(mut self, max: u32) -> Self {
        self.max_workgroups_per_dimension = max.max(1);
        self
    }

    /// Records the sort of the first `len` pairs of `keys` (`[u32; 2]` each, low word first) and
    /// their values by the low `key_bits` (1..=64) bits of the key, ascending and stable; nothing
    /// is submitted. The values are u32 each, where `values_at` says:
    /// - `SortValues::Apart`: in `values`;
    /// - `SortValues::AboveKeys`: in the keys (1..=63 key bits), `keys[i]` holding key | value <<
    ///   key_bits, the values below 2^(64 − key_bits) (`packs_indices`; `values` is not read).
    ///   The passes move each pair as one word, and the sorted pairs end as with `Apart`: the
    ///   keys in `keys`, the bits above `key_bits` cleared, and the values in `values`. Pairs past
    ///   a count computed on the GPU are left as they are (packed); one pair runs the passes too,
    ///   which unpack it.
    ///
    /// `len` may be a count computed on the GPU earlier in the recording: the passes are sized for
    /// its capacity, and the pairs past the count are left as they are. The sorted pairs end in
    /// `keys` and `values`, which need `STORAGE | COPY_SRC` usage. Internal scratch buffers grow
    /// to the capacity on demand; several sorts may be recorded into one recording.
    ///
    /// Everything is one compute pass, named "sort" (timestamped when the recording has a timer;
    /// also for `len` ≤ 1, where the pass is empty). The pass holds ceil(key_bits / 4) + 1
    /// dispatches.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
        len: ItemCount<'_>,
        key_bits: u32,
        values_at: SortValues,
    ) -> Result<()> {
        let packed = values_at == SortValues::AboveKeys;
        if packed && key_bits >= 64 {
            return Err(Error::InvalidArgument(format!(
                "a radix sort with the values above the keys sorts at most 63 key bits, got \
                 {key_bits}"
            )));
        }
        if !(1..=64).contains(&key_bits) {
            return Err(Error::InvalidArgument(format!(
                "radix sort key_bits must be 1..=64, got {key_bits}"
            )));
        }
        let limit = len.limit(rec.ctx);
        let len = len.capacity();
        let (key_bytes, value_bytes) = (u64::from(len) * 8, u64::from(len) * 4);
        if keys.size() < key_bytes || values.size() < value_bytes {
            return Err(Error::InvalidArgument(format!(
                "radix sort of {len} pairs needs {key_bytes} key bytes and {value_bytes} value bytes, \
                 the buffers hold {} and {}",
                keys.size(),
                values.size()
            )));
        }
        // One pair is sorted, but a packed one needs the passes to unpack it.
        if len == 0 || (len == 1 && !packed) {
            rec.pass("sort");
            return Ok(());
        }
        let ctx = rec.ctx;
        if self.scratch.as_ref().is_none_or(|s| s.capacity < len) {
            // Release the old buffers before allocating the new ones.
            self.scratch = None;
            self.scratch = Some(Scratch::new(ctx, len)?);
        }
        let scratch = self.scratch.as_ref().expect("scratch allocated above");
        let passes = pass_count(key_bits);
        let items = self
            .fixed_tile_items
            .unwrap_or_else(|| context_tile_items(ctx, len));
        let variant = SORT_TILE_ITEMS
            .iter()
            .position(|&i| i == items)
            .expect("a tile size of SORT_TILE_ITEMS");
        let kernels = &*self.kernels[variant].get_or_insert_with(|| TileKernels::new(ctx, variant));
        let num_tiles = len.div_ceil(SORT_WORKGROUP * items);
        let max = self
            .max_workgroups_per_dimension
            .min(ctx.device.limits().max_compute_workgroups_per_dimension);
        let tile_grid = Grid::items_capped(num_tiles, 1, max);

        // Pass p reads `src` and writes `dst`; the last pass writes the caller's buffers.
        let (mut src, mut dst) = ((keys, values), (&scratch.keys, &scratch.values));
        if passes % 2 == 1 {
            rec.encoder()
                .copy_buffer_to_buffer(keys, 0, &scratch.keys, 0, key_bytes);
            if !packed {
                rec.encoder()
                    .copy_buffer_to_buffer(values, 0, &scratch.values, 0, value_bytes);
            }
            std::mem::swap(&mut src, &mut dst);
        }
        let mut pass = rec.pass("sort");
        let counts = &scratch.counts;
        pass.dispatch(
            &kernels.histogram,
            tile_grid,
            &SortParams::pass(len, num_tiles, key_bits, 0, packed),
            &[src.0, &counts[0], &counts[1], limit],
        );
        for p in 0..passes {
            let rotation = p as usize;
            pass.dispatch(
                &kernels.scatter,
                tile_grid,
                &SortParams::pass(len, num_tiles, key_bits, p, packed),
                &[
                    src.0,
                    src.1,
                    &counts[rotation % 3],
                    dst.0,
                    dst.1,
                    &counts[(rotation + 1) % 3],
                    &counts[(rotation + 2) % 3],
                    limit,
                ],
            );
            std::mem::swap(&mut src, &mut dst);
        }
        Ok(())
    }

    /// Uploads the pairs, sorts them by the low `key_bits` bits of the keys, submits and reads the
    /// result back (tests and benchmarks). With `SortValues::AboveKeys` the values are uploaded
    /// above the low `key_bits` (1..=63) bits of the keys, whose own bits there are dropped; that
    /// fails when a value does not fit.
    pub fn sort_pairs(
        &mut self,
        ctx: &GpuContext,
        keys: &[[u32; 2]],
        values: &[u32],
        key_bits: u32,
        values_at: SortValues,
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
        // Packed, the values buffer only receives the sorted values: it starts with words no value
        // has, so that each must come from the keys.
        let (key_buffer, value_buffer) = match values_at {
            SortValues::Apart => (
                storage_buffer(ctx, "sort keys", keys)?,
                storage_buffer(ctx, "sort values", values)?,
            ),
            SortValues::AboveKeys => (
                storage_buffer(ctx, "sort keys", &pack_values(keys, values, key_bits)?)?,
                storage_buffer(ctx, "sort values", &vec![u32::MAX; keys.len().max(1)])?,
            ),
        };
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let result = {
            let mut rec = Recorder::new(ctx, &mut params, None);
            let count = ItemCount::Known(len);
            let result = self.record(
                &mut rec,
                &key_buffer,
                &value_buffer,
                count,
                key_bits,
                values_at,
            );
            rec.submit();
            result
        };
        self.params = params;
        result?;
        Ok((
            read_buffer(ctx, &key_buffer, keys.len())?,
            read_buffer(ctx, &value_buffer, values.len())?,
        ))
    }
}

/// CPU twin of the GPU sort: an LSD radix sort with the same 4-bit digits (counting sort per
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
