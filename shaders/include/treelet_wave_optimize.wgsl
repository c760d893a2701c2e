// Step 2 of an overlapped rounds' wave (treelet_waves.wgsl) for one treelet: the kernels that
// optimize treelets (waves_optimize.wgsl, waves_climb.wgsl) include it after treelet_dp.wgsl and
// treelet_waves.wgsl.

// Step 2 of wave `wave` for one treelet entry: the treelet (treelet_dp.wgsl), then
// `finish_entry`.
fn optimize_entry(entry: u32, wave: u32) {
    queued = 0u;
    optimize_treelet(entry & NODE_MASK);
    finish_entry(entry, wave);
}

// What the treelet of `entry` finished in wave `wave` (the internal nodes its write-back queued,
// internal_node[1..queued], none when it kept its topology): its root, in its round; the
// internal nodes it rewrote, in its round and the ones before (their place in the sequential
// rounds came first); and the candidates it may have made: itself and the nodes it rewrote in the
// next round, its parent in its round. Nothing here waits for memory more than it must: the
// parent's link and count and the rewritten nodes' counts are loaded together up front (the root's
// count is the formation's `root_prims`), the marks are atomics whose results nobody waits for,
// and every candidate's claim (an atomicMax on `candidate_waves`, a 0 for one it does not make,
// which changes nothing) goes out before any result is read, then one atomicAdd places all it
// won. Each candidate took a load, a claim and a place one after another before.
fn finish_entry(entry: u32, wave: u32) {
    let node = entry & NODE_MASK;
    let round = entry >> ROUND_SHIFT;
    let rounds = params.rounds;
    let next = round + 1u;
    let next_wave = wave + 1u;
    // The root of the tree has no parent: its word is in bounds and unused.
    let parent = parents[node];
    let parent_count = prim_counts[parent];
    // Candidate k < MAX_TREELET: internal_node[k] in the next round (internal_node[0] is the
    // root; past `queued`, a node of an earlier treelet or 0, not a candidate); the last: the
    // parent.
    var counts: array<u32, MAX_TREELET>;
    for (var k = 1u; k < MAX_TREELET; k++) {
        counts[k] = prim_counts[internal_node[k]];
    }
    counts[0] = root_prims;
    mark_done(node, round, wave);
    for (var e = 1u; e < queued; e++) {
        for (var r = 0u; r <= round; r++) {
            mark_done(internal_node[e], r, wave);
        }
    }
    var claims: array<u32, MAX_TREELET + 1u>;
    var wanted = 0u;
    for (var k = 0u; k <= MAX_TREELET; k++) {
        let candidate = finished_candidate(k, parent, round);
        var wants = node != 0u && parent_count >= gamma_of(round);
        if k < MAX_TREELET {
            wants = (k == 0u || k < queued) && next < rounds && counts[k] >= gamma_of(next);
        }
        let slot = round_slot(candidate.x, min(candidate.y, rounds - 1u));
        claims[k] = atomicMax(&candidate_waves[slot], select(0u, next_wave, wants));
        wanted |= select(0u, 1u << k, wants);
    }
    var won = 0u;
    for (var k = 0u; k <= MAX_TREELET; k++) {
        won |= select(0u, 1u << k, ((wanted >> k) & 1u) != 0u && claims[k] < next_wave);
    }
    if won == 0u {
        return;
    }
    var at = reserve_candidates(next_wave, countOneBits(won));
    for (var k = 0u; k <= MAX_TREELET; k++) {
        if ((won >> k) & 1u) != 0u {
            let candidate = finished_candidate(k, parent, round);
            lists[at] = wave_entry(candidate.x, candidate.y);
            at++;
        }
    }
}

// Candidate k of a treelet of round `round` whose root's parent is `parent` (`finish_entry`):
// (node, round), internal_node[k] in the next round for k < MAX_TREELET, else the parent in
// `round`.
fn finished_candidate(k: u32, parent: u32, round: u32) -> vec2<u32> {
    return select(vec2<u32>(parent, round), vec2<u32>(internal_node[min(k, MAX_TREELET - 1u)], round + 1u), k < MAX_TREELET);
}
