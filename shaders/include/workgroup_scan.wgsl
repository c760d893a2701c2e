// A workgroup of 256 invocations' exclusive prefix sum of one u32 each (counts_scan.wgsl's block
// and block-total scans, splits_count.wgsl's narrowing of the budget search). The including
// kernel has 256 invocations and calls `workgroup_scan` from every one of them.

// GROUPS² = 256.
const GROUPS: u32 = 16u;

var<workgroup> partial: array<u32, 256>;
var<workgroup> group_totals: array<u32, GROUPS>;

// The workgroup's exclusive scan of the invocations' `total`s: (this invocation's prefix, the
// sum of all). Every invocation calls it. Three barriers (a Hillis-Steele scan takes two per
// step, 16 for 256 invocations, and a barrier is what a workgroup pays most for on a CPU
// device): GROUPS invocations each scan a group of GROUPS totals serially, then every invocation
// adds the totals of the groups before its own.
fn workgroup_scan(lid: u32, total: u32) -> vec2<u32> {
    partial[lid] = total;
    workgroupBarrier();
    if lid < GROUPS {
        var run = 0u;
        for (var k = 0u; k < GROUPS; k++) {
            let x = partial[lid * GROUPS + k];
            partial[lid * GROUPS + k] = run;
            run += x;
        }
        group_totals[lid] = run;
    }
    workgroupBarrier();
    var before = partial[lid];
    var all = 0u;
    for (var g = 0u; g < GROUPS; g++) {
        let t = group_totals[g];
        before += select(0u, t, g < lid / GROUPS);
        all += t;
    }
    // Before `partial` is written again.
    workgroupBarrier();
    return vec2<u32>(before, all);
}
