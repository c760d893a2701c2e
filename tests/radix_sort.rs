//! The GPU radix sort (`sort::RadixSort`) and its CPU twin against `sort_unstable` on
//! (key, value) pairs with values 0..n: equal results mean sorted by key and stable. Sorts whose
//! values fit above the key bits run with them there too (`SortValues::AboveKeys`).

mod common;

use common::{gpu, rng};
use rand::Rng;
use treelet::gpu::{ItemCount, ParamSlab, Recorder};
use treelet::sort::{packs_indices, sort_pairs_cpu, RadixSort, SortValues, SORT_TILE_ITEMS};

/// The largest tile: 256 invocations of 32 keys.
const SORT_TILE: usize = 256 * 32;

fn split(key: u64) -> [u32; 2] {
    [key as u32, (key >> 32) as u32]
}

fn join(key: [u32; 2]) -> u64 {
    u64::from(key[0]) | (u64::from(key[1]) << 32)
}

/// Keys below 2^key_bits.
fn random_keys(n: usize, key_bits: u32, seed: u64) -> Vec<u64> {
    let mut r = rng(seed);
    let mask = u64::MAX >> (64 - key_bits);
    (0..n).map(|_| r.random::<u64>() & mask).collect()
}

/// Expected result: pairs (key, index) sorted by (key & mask, index), i.e. stably by masked key.
fn expected(keys: &[u64], key_bits: u32) -> (Vec<u64>, Vec<u32>) {
    let mask = u64::MAX >> (64 - key_bits);
    let mut pairs: Vec<(u64, u32, u64)> = keys
        .iter()
        .enumerate()
        .map(|(i, &k)| (k & mask, i as u32, k))
        .collect();
    pairs.sort_unstable();
    pairs.into_iter().map(|(_, v, k)| (k, v)).unzip()
}

/// The low `key_bits` bits.
fn low_bits(key: u64, key_bits: u32) -> u64 {
    key & (u64::MAX >> (64 - key_bits))
}

/// Sorts with the GPU and the CPU twin and compares both with `expected`; where the values fit
/// above the key bits, also with them there (`SortValues::AboveKeys`), whose sorted keys are the key
/// bits alone.
fn check(sorter: &mut RadixSort, keys: &[u64], key_bits: u32) {
    if packs_indices(key_bits, keys.len() as u32) {
        let values: Vec<u32> = (0..keys.len() as u32).collect();
        let (want_keys, want_values) = expected(keys, key_bits);
        let gpu_keys: Vec<[u32; 2]> = keys.iter().map(|&k| split(k)).collect();
        let (got_keys, got_values) = sorter
            .sort_pairs(gpu(), &gpu_keys, &values, key_bits, SortValues::AboveKeys)
            .unwrap();
        let want_keys: Vec<[u32; 2]> = want_keys
            .iter()
            .map(|&k| split(low_bits(k, key_bits)))
            .collect();
        assert!(
            got_keys == want_keys && got_values == want_values,
            "packed GPU sort of n = {} with key_bits = {key_bits}",
            keys.len()
        );
    }
    let values: Vec<u32> = (0..keys.len() as u32).collect();
    let (want_keys, want_values) = expected(keys, key_bits);
    let (cpu_keys, cpu_values) = sort_pairs_cpu(keys, &values, key_bits);
    assert!(
        cpu_keys == want_keys && cpu_values == want_values,
        "CPU twin, n = {}",
        keys.len()
    );
    let gpu_keys: Vec<[u32; 2]> = keys.iter().map(|&k| split(k)).collect();
    let (got_keys, got_values) = sorter
        .sort_pairs(gpu(), &gpu_keys, &values, key_bits, SortValues::Apart)
        .unwrap();
    let got_keys: Vec<u64> = got_keys.into_iter().map(join).collect();
    if let Some(i) =
        (0..keys.len()).find(|&i| got_keys[i] != want_keys[i] || got_values[i] != want_values[i])
    {
        panic!(
            "GPU sort of n = {} with key_bits = {key_bits}: first difference at {i}: ({:#x}, {}) instead of ({:#x}, {})",
            keys.len(),
            got_keys[i],
            got_values[i],
            want_keys[i],
            want_values[i]
        );
    }
}

#[test]
fn lengths_around_tiles_and_blocks() {
    let mut sorter = RadixSort::new(gpu());
    for (i, n) in [
        0, 1, 2, 255, 256, 257, 1000, 2047, 2048, 2049, 4097, 100_000,
    ]
    .into_iter()
    .enumerate()
    {
        check(&mut sorter, &random_keys(n, 63, 10 + i as u64), 63);
    }
}

#[test]
fn two_dimensional_grids() {
    // Capped at 8 workgroups per dimension, 100,000 pairs need 13 tiles (a 7x2 grid, one
    // workgroup idle) and 65,537 pairs 9 tiles (5x2, one idle): the path that more than
    // 65,535 tiles of pairs take under a real device limit.
    let mut sorter = RadixSort::new(gpu())
        .with_max_workgroups_per_dimension(8)
        .with_tile_items(32)
        .unwrap();
    for (n, bits, seed) in [(100_000, 40, 20), (8 * SORT_TILE + 1, 17, 21)] {
        assert!(n > 8 * SORT_TILE);
        check(&mut sorter, &random_keys(n, bits, seed), bits);
    }
}

/// Every tile size sorts the same (tiles of 2048, 4096 and 8192 pairs): lengths around tile
/// boundaries, many tiles, a 2D grid, odd pass counts; the GPU's choice by length is one of them.
#[test]
fn every_tile_size() {
    for items in SORT_TILE_ITEMS {
        let tile = 256 * items as usize;
        let mut sorter = RadixSort::new(gpu()).with_tile_items(items).unwrap();
        for (n, bits, seed) in [
            (tile - 1, 32, 70),
            (tile, 20, 71),
            (tile + 1, 12, 72),
            (37 * tile + 5, 44, 73),
        ] {
            check(
                &mut sorter,
                &random_keys(n, bits, seed + u64::from(items)),
                bits,
            );
        }
        let mut sorter = RadixSort::new(gpu())
            .with_max_workgroups_per_dimension(4)
            .with_tile_items(items)
            .unwrap();
        check(&mut sorter, &random_keys(9 * tile + 3, 24, 80), 24);
    }
    for n in [1000, 331_179, 1_100_000, 8_400_000] {
        assert!(
            SORT_TILE_ITEMS.contains(&treelet::sort::tile_items(n, wgpu::DeviceType::DiscreteGpu))
        );
    }
    assert_eq!(
        treelet::sort::tile_items(331_179, wgpu::DeviceType::Cpu),
        32
    );
    assert!(RadixSort::new(gpu()).with_tile_items(12).is_err());
}

#[test]
fn many_tiles_and_an_odd_pass_count() {
    // 2,200,000 pairs give 269 tiles of 8192: each scatter workgroup sums 16 × 269 digit counts
    // for its offsets, in stripes of 17 and 16 tiles. 12-bit keys: three passes, so also the copy
    // to the scratch buffers that odd pass counts start with.
    let mut sorter = RadixSort::new(gpu()).with_tile_items(32).unwrap();
    check(&mut sorter, &random_keys(2_200_000, 12, 22), 12);
}

#[test]
fn duplicate_keys() {
    let mut sorter = RadixSort::new(gpu());
    let mut r = rng(30);
    let distinct: Vec<u64> = (0..16).map(|_| r.random()).collect();
    let keys: Vec<u64> = (0..50_000)
        .map(|_| distinct[r.random_range(0..16)])
        .collect();
    check(&mut sorter, &keys, 64);
    check(&mut sorter, &vec![0x1234_5678_9abc_def0; 10_000], 64);
    check(&mut sorter, &vec![0; 5000], 63);
    check(&mut sorter, &vec![u64::MAX; 5000], 64);
}

#[test]
fn key_widths() {
    let mut sorter = RadixSort::new(gpu());
    // No pair, and one: packed, the passes run to unpack it.
    check(&mut sorter, &random_keys(0, 32, 46), 32);
    check(&mut sorter, &random_keys(1, 32, 47), 32);
    check(&mut sorter, &random_keys(2, 32, 48), 32);
    check(&mut sorter, &random_keys(30_000, 64, 40), 64);
    check(&mut sorter, &random_keys(30_000, 30, 41), 30);
    // Odd pass counts (the input is copied to the scratch buffers first) and sub-byte digits.
    check(&mut sorter, &random_keys(30_000, 1, 42), 1);
    check(&mut sorter, &random_keys(30_000, 20, 43), 20);
    // Bits above key_bits are ignored (stably): 64-bit keys sorted by their low 30 and 8 bits.
    check(&mut sorter, &random_keys(30_000, 64, 44), 30);
    check(&mut sorter, &random_keys(30_000, 64, 45), 8);
}

#[test]
fn scratch_reuse_and_growth() {
    let mut sorter = RadixSort::new(gpu());
    check(&mut sorter, &random_keys(50_000, 63, 50), 63);
    check(&mut sorter, &random_keys(50_000, 63, 51), 63);
    check(&mut sorter, &random_keys(3000, 63, 52), 63);
    check(&mut sorter, &random_keys(70_000, 63, 53), 63);
}

#[test]
fn two_sorts_in_one_submission() {
    let ctx = gpu();
    let mut sorter = RadixSort::new(ctx);
    // 16 passes, then 3 (which start with a copy to the scratch buffers), then a no-op, all
    // recorded into one recording with one timer slot each.
    let a = random_keys(20_000, 63, 60);
    let b = random_keys(30_000, 11, 61);
    let upload = |keys: &[u64]| {
        let split_keys: Vec<[u32; 2]> = keys.iter().map(|&k| split(k)).collect();
        let values: Vec<u32> = (0..keys.len() as u32).collect();
        (
            treelet::gpu::storage_buffer(ctx, "keys", &split_keys).unwrap(),
            treelet::gpu::storage_buffer(ctx, "values", &values).unwrap(),
        )
    };
    let (ka, va) = upload(&a);
    let (kb, vb) = upload(&b);
    let (k1, v1) = upload(&[42]);
    let mut timer = treelet::gpu::GpuTimer::new(ctx, 3);
    let mut params = ParamSlab::new(ctx);
    let mut rec = Recorder::new(ctx, &mut params, Some(&mut timer));
    sorter
        .record(
            &mut rec,
            &ka,
            &va,
            ItemCount::Known(a.len() as u32),
            63,
            SortValues::Apart,
        )
        .unwrap();
    sorter
        .record(
            &mut rec,
            &kb,
            &vb,
            ItemCount::Known(b.len() as u32),
            11,
            SortValues::Apart,
        )
        .unwrap();
    sorter
        .record(
            &mut rec,
            &k1,
            &v1,
            ItemCount::Known(1),
            63,
            SortValues::Apart,
        )
        .unwrap();
    rec.submit();
    for (keys, kbuf, vbuf, bits) in [(&a, &ka, &va, 63), (&b, &kb, &vb, 11)] {
        let got_keys: Vec<[u32; 2]> = treelet::gpu::read_buffer(ctx, kbuf, keys.len()).unwrap();
        let got_values: Vec<u32> = treelet::gpu::read_buffer(ctx, vbuf, keys.len()).unwrap();
        let got_keys: Vec<u64> = got_keys.into_iter().map(join).collect();
        assert!(
            (got_keys, got_values) == expected(keys, bits),
            "sort of {} pairs",
            keys.len()
        );
    }
    let times = timer.read(ctx).unwrap();
    assert_eq!(
        times.iter().map(|t| t.label.as_str()).collect::<Vec<_>>(),
        ["sort", "sort", "sort"]
    );
}

#[test]
fn invalid_arguments_are_errors() {
    let ctx = gpu();
    let mut sorter = RadixSort::new(ctx);
    let apart = SortValues::Apart;
    assert!(sorter.sort_pairs(ctx, &[[0, 0]], &[0], 0, apart).is_err());
    assert!(sorter.sort_pairs(ctx, &[[0, 0]], &[0], 65, apart).is_err());
    assert!(sorter
        .sort_pairs(ctx, &[[0, 0]], &[0, 1], 8, apart)
        .is_err());
    // Values must fit above the key bits.
    let above = SortValues::AboveKeys;
    assert!(sorter.sort_pairs(ctx, &[[0, 0]], &[0], 64, above).is_err());
    assert!(sorter
        .sort_pairs(ctx, &[[0, 0], [0, 0]], &[0, 1 << 20], 44, above)
        .is_err());
}

#[test]
fn cpu_twin_matches_sort_unstable() {
    for (n, bits, seed) in [
        (0, 64, 70),
        (1, 64, 71),
        (1000, 64, 72),
        (100_000, 63, 73),
        (10_000, 30, 74),
        (5000, 3, 75),
    ] {
        let keys = random_keys(n, bits, seed);
        let values: Vec<u32> = (0..n as u32).collect();
        assert_eq!(sort_pairs_cpu(&keys, &values, bits), expected(&keys, bits));
    }
}

/// A pair count computed on the GPU (here written by a buffer copy in the same recording): the
/// passes are sized for the capacity, the first `count` pairs end sorted and the pairs past them
/// are left as they are; also with the values above the key bits (where they fit), whose
/// pairs past the count stay packed.
#[test]
fn a_count_on_the_gpu_sorts_only_its_pairs() {
    let ctx = gpu();
    let mut sorter = RadixSort::new(ctx);
    for (capacity, count, bits) in [
        (40_000usize, 29_999usize, 63),
        (9000, 8192, 32),
        (9000, 7000, 44),
        (5, 2, 63),
    ] {
        let keys = random_keys(capacity, bits, capacity as u64);
        let values: Vec<u32> = (0..capacity as u32).collect();
        for packed in [false, true] {
            if packed && !packs_indices(bits, capacity as u32) {
                continue;
            }
            let split_keys: Vec<[u32; 2]> = keys
                .iter()
                .zip(&values)
                .map(|(&k, &v)| {
                    if packed {
                        split(low_bits(k, bits) | (u64::from(v) << bits))
                    } else {
                        split(k)
                    }
                })
                .collect();
            // Packed, the values buffer starts with other words: past the count they stay.
            let start_values: Vec<u32> = if packed {
                values.iter().map(|v| !v).collect()
            } else {
                values.clone()
            };
            let kbuf = treelet::gpu::storage_buffer(ctx, "keys", &split_keys).unwrap();
            let vbuf = treelet::gpu::storage_buffer(ctx, "values", &start_values).unwrap();
            let source =
                treelet::gpu::storage_buffer(ctx, "count source", &[count as u32]).unwrap();
            let count_buffer = treelet::gpu::storage_buffer(ctx, "count", &[0u32]).unwrap();
            let mut params = ParamSlab::new(ctx);
            let mut rec = Recorder::new(ctx, &mut params, None);
            rec.encoder()
                .copy_buffer_to_buffer(&source, 0, &count_buffer, 0, 4);
            let len = ItemCount::OnGpu {
                buffer: &count_buffer,
                capacity: capacity as u32,
            };
            let values_at = if packed {
                SortValues::AboveKeys
            } else {
                SortValues::Apart
            };
            sorter
                .record(&mut rec, &kbuf, &vbuf, len, bits, values_at)
                .unwrap();
            rec.submit();
            let got_keys: Vec<[u32; 2]> = treelet::gpu::read_buffer(ctx, &kbuf, capacity).unwrap();
            let got_values: Vec<u32> = treelet::gpu::read_buffer(ctx, &vbuf, capacity).unwrap();
            let (want_keys, want_values) = expected(&keys[..count], bits);
            let want_keys: Vec<[u32; 2]> = want_keys.into_iter().map(split).collect();
            assert!(
                got_keys[..count] == want_keys[..] && got_values[..count] == want_values[..],
                "{count} of {capacity} pairs (packed: {packed})"
            );
            assert!(
                got_keys[count..] == split_keys[count..]
                    && got_values[count..] == start_values[count..],
                "pairs past the count moved ({count} of {capacity}, packed: {packed})"
            );
        }
    }
}
