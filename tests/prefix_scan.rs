//! The GPU exclusive prefix scan (`sort::PrefixScan`, used by the collapse and pre-splitting)
//! against the CPU's exclusive scan: lengths around the block size, many blocks (more than the
//! last workgroup scans at once) with the add-back, 2D grids, the grand total, and the
//! block-local scan of several columns (each element plus its block's offset, the column totals),
//! twice in a row with the same buffers (the ticket is back at zero).

mod common;

use common::{gpu, rng};
use rand::Rng;
use treelet::gpu::constants::SCAN_BLOCK;
use treelet::gpu::{read_buffer, storage_buffer, ParamSlab, Recorder};
use treelet::sort::{scan_blocks, PrefixScan};

/// Scans `data` on the GPU; the scanned data and the total.
fn gpu_scan(scan: &mut PrefixScan, data: &[u32]) -> (Vec<u32>, u32) {
    let ctx = gpu();
    let buffer = storage_buffer(ctx, "scan data", data).expect("upload");
    scan.reserve(ctx, data.len() as u32, 1).expect("reserve");
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
fn many_blocks() {
    let mut scan = PrefixScan::new(gpu());
    let b = SCAN_BLOCK as usize;
    // 36 blocks, then b + 1 (the last workgroup scans the block totals in two tiles).
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

/// Scans `columns` columns of `len` random values block-locally on the GPU and checks every
/// element (block-local value + block offset) and every column total against the CPU.
fn check_block_local(scan: &mut PrefixScan, len: usize, columns: usize, seed: u64) {
    let ctx = gpu();
    let mut r = rng(seed);
    let data: Vec<u32> = (0..len * columns).map(|_| r.random_range(0..16)).collect();
    let buffer = storage_buffer(ctx, "scan columns", &data).expect("upload");
    scan.reserve(ctx, len as u32, columns as u32)
        .expect("reserve");
    let mut params = ParamSlab::new(ctx);
    let mut rec = Recorder::new(ctx, &mut params, None);
    {
        let mut pass = rec.pass("scan");
        scan.record_block_local(&mut pass, &buffer, len as u32, columns as u32)
            .expect("record");
    }
    rec.submit();
    let blocks = scan_blocks(len as u32) as usize;
    let local: Vec<u32> = read_buffer(ctx, &buffer, len * columns).expect("read data");
    let offsets: Vec<u32> =
        read_buffer(ctx, scan.block_offsets(), blocks * columns).expect("read offsets");
    let totals: Vec<u32> = read_buffer(ctx, scan.total(), columns).expect("read totals");
    for c in 0..columns {
        let mut sum = 0u32;
        for i in 0..len {
            let got = local[c * len + i] + offsets[c * blocks + i / SCAN_BLOCK as usize];
            assert_eq!(got, sum, "column {c}, element {i} of {len}");
            sum += data[c * len + i];
        }
        assert_eq!(totals[c], sum, "total of column {c} ({len} elements)");
    }
}

#[test]
fn block_local_columns() {
    let mut scan = PrefixScan::new(gpu());
    let b = SCAN_BLOCK as usize;
    // One block (offsets of 0), several blocks, 36 blocks; one, two and three columns; the same
    // sizes twice.
    for (i, (len, columns)) in [
        (1, 2),
        (b - 1, 2),
        (b, 1),
        (b + 1, 2),
        (3 * b + 17, 3),
        (5 * b * 7 + 3, 2),
        (3 * b + 17, 3),
        (b + 1, 2),
    ]
    .into_iter()
    .enumerate()
    {
        check_block_local(&mut scan, len, columns, 130 + i as u64);
    }
}

#[test]
fn block_local_many_blocks_and_2d_grids() {
    // b + 1 blocks (b² + 1 elements): the block totals are scanned in two tiles.
    let mut scan = PrefixScan::new(gpu());
    let b = SCAN_BLOCK as usize;
    check_block_local(&mut scan, b * b + 1, 1, 140);
    // Two columns of 5 blocks on a grid capped at 3 workgroups per dimension (10 blocks: 3 x 4).
    let mut scan = PrefixScan::new(gpu());
    scan.set_max_workgroups_per_dimension(3);
    check_block_local(&mut scan, 5 * b - 9, 2, 141);
}
