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
// rounds came first); and the candidates it may have made.
fn finish_entry(entry: u32, wave: u32) {
    let node = entry & NODE_MASK;
    let round = entry >> ROUND_SHIFT;
    let rounds = params.rounds;
    done[node * rounds + round] = wave;
    let next = round + 1u;
    for (var e = 1u; e < queued; e++) {
        let x = internal_node[e];
        for (var r = 0u; r <= round; r++) {
            if done[x * rounds + r] == 0u {
                done[x * rounds + r] = wave;
            }
        }
        if next < rounds && prim_counts[x] >= gamma_of(next) {
            add_candidate(x, next, wave + 1u);
        }
    }
    if node != 0u {
        let parent = parents[node];
        if prim_counts[parent] >= gamma_of(round) {
            add_candidate(parent, round, wave + 1u);
        }
    }
    if next < rounds && prim_counts[node] >= gamma_of(next) {
        add_candidate(node, next, wave + 1u);
    }
}
