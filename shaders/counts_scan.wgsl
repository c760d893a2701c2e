// Exclusive prefix sum of `sort::PrefixScan` in one dispatch (reduce-then-scan, no waiting): each
// workgroup scans its block of SCAN_BLOCK = 4096 u32s of `data` in place (16 consecutive per
// invocation, then a scan of the 256 invocation totals in workgroup memory: workgroup_scan.wgsl) and
// stores the block's total in `block_sums`; the workgroup that finishes last (a ticket counter,
// as in Merrill & Grimshaw's reduce-then-scan, but without any workgroup waiting for another)
// scans the block totals of every column in place, 4096 at a time with a carry, which leaves
// each block's offset there, and stores each column's grand total. A consumer adds a block's
// offset where it reads, or counts_add.wgsl adds it back. Every column of `data` is scanned on
// its own (scan_blocks.wgsl).
#include "scan_blocks.wgsl"
#include "workgroup_scan.wgsl"

const WORKGROUP: u32 = 256u;
const ITEMS: u32 = SCAN_BLOCK / WORKGROUP;

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
// Per column, num_blocks block totals; after the dispatch their exclusive scan (block offsets).
@group(0) @binding(2) var<storage, read_write> block_sums: array<atomic<u32>>;
// The grand total of each column.
@group(0) @binding(3) var<storage, read_write> totals: array<u32>;
// Workgroups finished so far; zero before and after the dispatch.
@group(0) @binding(4) var<storage, read_write> ticket: array<atomic<u32>>;

var<workgroup> is_last: u32;

// Element i of the column starting at `start`.
fn load(start: u32, i: u32) -> u32 {
    if i < params.len {
        return data[start + i];
    }
    return 0u;
}

fn store(start: u32, i: u32, x: u32) {
    if i < params.len {
        data[start + i] = x;
    }
}

// The last workgroup: every column's block totals scanned in place, SCAN_BLOCK at a time.
fn scan_block_sums(lid: u32) {
    for (var column = 0u; column < params.columns; column++) {
        let start = column * params.num_blocks;
        var carry = 0u;
        for (var first = 0u; first < params.num_blocks; first += SCAN_BLOCK) {
            let base = first + lid * ITEMS;
            let count = min(params.num_blocks - min(base, params.num_blocks), ITEMS);
            var total = 0u;
            for (var i = 0u; i < count; i++) {
                total += atomicLoad(&block_sums[start + base + i]);
            }
            let scanned = workgroup_scan(lid, total);
            var before = carry + scanned.x;
            for (var i = 0u; i < count; i++) {
                let x = atomicLoad(&block_sums[start + base + i]);
                atomicStore(&block_sums[start + base + i], before);
                before += x;
            }
            carry += scanned.y;
        }
        if lid == 0u {
            totals[column] = carry;
        }
    }
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let b = scan_block(wid, nwg);
    if b.exists {
        let base = b.first + lid * ITEMS;
        var total = 0u;
        for (var i = 0u; i < ITEMS; i++) {
            total += load(b.start, base + i);
        }
        let scanned = workgroup_scan(lid, total);
        var before = scanned.x;
        for (var i = 0u; i < ITEMS; i++) {
            let x = load(b.start, base + i);
            store(b.start, base + i, before);
            before += x;
        }
        if lid == 0u {
            atomicStore(&block_sums[b.id], scanned.y);
        }
    }
    // Release: the block's total is stored before the ticket is taken.
    storageBarrier();
    if lid == 0u {
        is_last = u32(atomicAdd(&ticket[0], 1u) + 1u == nwg.x * nwg.y);
    }
    if workgroupUniformLoad(&is_last) == 0u {
        return;
    }
    // Acquire: every block's total is visible.
    storageBarrier();
    scan_block_sums(lid);
    if lid == 0u {
        atomicStore(&ticket[0], 0u);
    }
}
