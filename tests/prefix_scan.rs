//! The GPU exclusive prefix scan (`sort::PrefixScan`, used by the radix sort, the collapse and
//! pre-splitting) against the CPU's exclusive scan: lengths around the block size, two and three
//! levels with their add-backs, 2D grids, and the grand total.

mod common;

use common::{gpu, rng};
use rand::Rng;
use treelet::gpu::constants::SCAN_BLOCK;
use treelet::gpu::{read_buffer, storage_buffer, ParamSlab, Recorder};
use treelet::sort::PrefixScan;

/// Scans `data` on the GPU; the scanned data and the total.
fn gpu_scan(scan: &mut PrefixScan, data: &[u32]) -> (Vec<u32>, u32) {
    let ctx = gpu();
    let buffer = storage_buffer(ctx, "scan data", data).expect("upload");
    scan.reserve(ctx, data.len() as u32).expect("reserve");
    let mut params = ParamSlab::new(ctx);
    let mut rec = Recorder::new(ctx, &mut params, None);
    {
        let mut pass = rec.pass("scan");
        scan.record(&mut pass, &buffer, data.len() as u32)
            .expect("record");
    }
    rec.submit();
    let total: Vec<u32> = read_buffer(ctx, scan.total(), 1).expect("read total");
    (
        read_buffer(ctx, &buffer, data.len()).expect("read"),
        total[0],
    )
}

fn check(scan: &mut PrefixScan, n: usize, seed: u64) {
    let mut r = rng(seed);
    let data: Vec<u32> = (0..n).map(|_| r.random_range(0..16)).collect();
    let (got, total) = gpu_scan(scan, &data);
    let mut sum = 0u32;
    for (i, (&x, &g)) in data.iter().zip(&got).enumerate() {
        assert_eq!(g, sum, "element {i} of {n}");
        sum += x;
    }
    assert_eq!(total, sum, "total of {n}");
}

#[test]
fn lengths_around_blocks() {
    let mut scan = PrefixScan::new(gpu());
    let b = SCAN_BLOCK as usize;
    for (i, n) in [1, 2, 255, 256, 257, b - 1, b, b + 1, 3 * b + 17]
        .into_iter()
        .enumerate()
    {
        check(&mut scan, n, 100 + i as u64);
    }
}

#[test]
fn two_and_three_levels() {
    let mut scan = PrefixScan::new(gpu());
    let b = SCAN_BLOCK as usize;
    // Two levels (block totals scanned once more), then three (b² + 1 elements).
    check(&mut scan, 5 * b * 7 + 3, 110);
    check(&mut scan, b * b + 1, 111);
}

#[test]
fn two_dimensional_grids() {
    // Capped at 2 workgroups per dimension: 5 blocks need a 3x2 grid with one workgroup idle.
    let mut scan = PrefixScan::new(gpu());
    scan.set_max_workgroups_per_dimension(2);
    check(&mut scan, 5 * SCAN_BLOCK as usize - 9, 120);
}
