// The treelet rounds overlapped in waves (Karras & Aila 2013, §4's rounds, run ahead of each
// other; GPU twin of the CPU's `WorkingTree::optimize_overlapped`, whose rule it follows exactly).
// In wave w, round r (from 0) optimizes every root Q of at least γ_r = treelet size · 2^r
// primitives that is not done in round r, whose children of at least γ_r are done in round r and,
// for r > 0, which with its ancestors up to `params.reach` levels up is done in round r − 1 (done:
// before wave w). A wave has two steps: `find_candidate` (waves_find.wgsl, or the climb's first
// phase) sorts the wave's candidates into its treelets and the ones still waiting for their
// ancestors (kept for the next wave); `optimize_entry` (treelet_wave_optimize.wgsl, for
// waves_optimize.wgsl and the climb's second phase) optimizes a treelet and adds the candidates
// it may have made ready: its parent in its round, itself and the internal nodes it rewrote in
// the next round. Every root the rule makes ready is a candidate of
// its wave (a candidate is dropped only while a condition fails that an optimized treelet will
// make true, which adds it again), and a wave's treelets are disjoint subtrees, so the waves
// optimize what the CPU twin's do. Entries are `node | round << ROUND_SHIFT`.
// The including kernel declares `params: RoundParams` (treelet_round.wgsl), `nodes`, `parents`,
// `prim_counts`, `done: array<atomic<u32>>` (per node and round, node-major: 0 while not done,
// else the complement of the wave that did it; `mark_done`), `candidate_waves:
// array<atomic<u32>>` (the last wave each node and round was
// made a candidate of), `lists: array<u32>` (the candidates of odd and even waves, `params.rounds *
// params.count` entries each, then the wave's treelets) and `wave_state: array<atomic<u32>>`.

const ROUND_SHIFT: u32 = 28u;
const NODE_MASK: u32 = (1u << ROUND_SHIFT) - 1u;

// Words of `wave_state`: the wave's treelets, the candidates of even and odd waves, the tickets
// of the find and optimize dispatches, and 1 once a wave found no treelet (the rounds are done:
// the dispatches left return at once). The indirect arguments of each dispatch are in a buffer of
// their own, which the dispatch before writes (a dispatch cannot write its own).
const OPS_COUNT: u32 = 0u;
const CANDIDATE_COUNT: u32 = 1u;
const FIND_TICKET: u32 = 3u;
const OPTIMIZE_TICKET: u32 = 4u;
const STOPPED: u32 = 5u;

// What `find_candidate` does with a candidate.
const DROP: u32 = 0u;
const READY: u32 = 1u;
const WAITING: u32 = 2u;

// The invocations of a wave dispatch's workgroup (each takes one entry).
const WAVE_WORKGROUP: u32 = 32u;

var<workgroup> state_value: u32;

// Word `word` of the wave state, loaded once for the workgroup (every invocation calls it; two
// calls need a barrier between them, as the value is shared).
fn state_word(lid: u32, word: u32) -> u32 {
    if lid == 0u {
        state_value = atomicLoad(&wave_state[word]);
    }
    return workgroupUniformLoad(&state_value);
}

// Whether a wave before found no treelet (every invocation calls it).
fn rounds_stopped(lid: u32) -> bool {
    return state_word(lid, STOPPED) != 0u;
}

var<workgroup> state_pair: vec2<u32>;

// The start of a wave's dispatch: whether a wave before found no treelet (x, as rounds_stopped)
// and word `word` of the wave state (y), loaded together once for the workgroup (every invocation
// calls it, once): one round trip to memory, where the two calls of state_word took two.
fn stopped_and_state_word(lid: u32, word: u32) -> vec2<u32> {
    if lid == 0u {
        state_pair = vec2<u32>(atomicLoad(&wave_state[STOPPED]), atomicLoad(&wave_state[word]));
    }
    return workgroupUniformLoad(&state_pair);
}

// The end of wave `wave`: its candidates (which its first step read) and its treelets, counted
// no more.
fn end_wave(wave: u32) {
    atomicStore(&wave_state[CANDIDATE_COUNT + (wave & 1u)], 0u);
    atomicStore(&wave_state[OPS_COUNT], 0u);
}

var<workgroup> is_last: u32;

// Whether this workgroup is the last of its dispatch of `groups` to finish, by the ticket at word
// `ticket` of the wave state (which the last one resets). Every invocation calls it after its
// stores: the barriers release them before the ticket is taken and, in the last workgroup,
// acquire every other workgroup's.
fn last_workgroup(lid: u32, groups: u32, ticket: u32) -> bool {
    storageBarrier();
    if lid == 0u {
        is_last = u32(atomicAdd(&wave_state[ticket], 1u) + 1u == groups);
    }
    if workgroupUniformLoad(&is_last) == 0u {
        return false;
    }
    storageBarrier();
    if lid == 0u {
        atomicStore(&wave_state[ticket], 0u);
    }
    return true;
}

fn gamma_of(round: u32) -> u32 {
    return params.gamma << round;
}

fn candidates_base(wave: u32) -> u32 {
    return (wave & 1u) * params.rounds * params.count;
}

fn ops_base() -> u32 {
    return 2u * params.rounds * params.count;
}

// Where (node, round) is in the node-major arrays of a word per node and round (`done`,
// `candidate_waves`).
fn round_slot(node: u32, round: u32) -> u32 {
    return node * params.rounds + round;
}

// The done word of `node` in `round`: 0 while not done, else the complement of the wave that did
// it (`mark_done`).
fn done_in(node: u32, round: u32) -> u32 {
    return atomicLoad(&done[round_slot(node, round)]);
}

// Whether a node whose done word (of some round) is `d` was done in that round before wave
// `wave`.
fn done_before(d: u32, wave: u32) -> bool {
    return d != 0u && ~d < wave;
}

// Marks `node` done in `round` by wave `wave` unless a wave before did (done words only grow
// earlier: every mark is of the current wave, and a node is marked once per wave). One atomicMax
// of the wave's complement keeps the earliest wave and waits for nothing; a load of the word and
// a store where it was 0 waited for a round trip to memory per node and round.
fn mark_done(node: u32, round: u32, wave: u32) {
    atomicMax(&done[round_slot(node, round)], ~wave);
}

// The entry of (node, round) in the lists.
fn wave_entry(node: u32, round: u32) -> u32 {
    return node | (round << ROUND_SHIFT);
}

// The first of `n` consecutive places reserved in wave `wave`'s candidate list.
fn reserve_candidates(wave: u32, n: u32) -> u32 {
    return candidates_base(wave) + atomicAdd(&wave_state[CANDIDATE_COUNT + (wave & 1u)], n);
}

// Makes (node, round) a candidate of wave `wave`, once (its claim on `candidate_waves`).
fn add_candidate(node: u32, round: u32, wave: u32) {
    if atomicMax(&candidate_waves[round_slot(node, round)], wave) < wave {
        lists[reserve_candidates(wave, 1u)] = wave_entry(node, round);
    }
}

// Whether a child (its right word, count and done word of the candidate's round) keeps its
// parent from being a candidate of that round in wave `wave`: an internal node of at least
// `gamma` primitives not done in the round before the wave.
fn child_blocks(right: u32, count: u32, done_word: u32, gamma: u32, wave: u32) -> bool {
    return (right & LEAF_FLAG) == 0u && count >= gamma && !done_before(done_word, wave);
}

// A candidate of wave `wave`: READY (optimized in this wave), WAITING (only an ancestor within
// the reach is not done in the round before: a candidate of the next wave) or DROP. What a step
// tests about a node is loaded at once: the node, its count, its done words and its parent link,
// then both children's words, then per step up an ancestor's done word with its parent link. A
// chain of conditions (`||`, a loop with early returns, a parent link and then its done word)
// waited for one round trip to memory after another.
fn candidate_state(node: u32, round: u32, wave: u32) -> u32 {
    let gamma = gamma_of(round);
    // Round r − 1 (round 0's own word for r = 0, unused).
    let previous = max(round, 1u) - 1u;
    let n = nodes[node];
    let count = prim_counts[node];
    let done_now = done_in(node, round);
    let done_previous = done_in(node, previous);
    var parent = parents[node];
    if done_now != 0u || (n.right_or_count & LEAF_FLAG) != 0u || count < gamma {
        return DROP;
    }
    if round > 0u && !done_before(done_previous, wave) {
        return DROP;
    }
    let left = n.left_or_first;
    let right = n.right_or_count;
    let left_right = nodes[left].right_or_count;
    let right_right = nodes[right].right_or_count;
    let left_count = prim_counts[left];
    let right_count = prim_counts[right];
    let left_done = done_in(left, round);
    let right_done = done_in(right, round);
    let left_blocks = child_blocks(left_right, left_count, left_done, gamma, wave);
    let right_blocks = child_blocks(right_right, right_count, right_done, gamma, wave);
    if left_blocks || right_blocks {
        return DROP;
    }
    if round == 0u {
        return READY;
    }
    // x with its done word of round r − 1 and its parent link (past the root: the root's own
    // word, in bounds and unused).
    var x = node;
    var done_x = done_previous;
    var up = 0u;
    var state = READY;
    loop {
        if !done_before(done_x, wave) {
            state = WAITING;
            break;
        }
        if x == 0u || up >= params.reach {
            break;
        }
        x = parent;
        done_x = done_in(x, previous);
        parent = parents[x];
        up++;
    }
    return state;
}

// Step 1 of wave `wave` for one candidate entry.
fn find_candidate(entry: u32, wave: u32) {
    let node = entry & NODE_MASK;
    let round = entry >> ROUND_SHIFT;
    let state = candidate_state(node, round, wave);
    if state == READY {
        let slot = atomicAdd(&wave_state[OPS_COUNT], 1u);
        lists[ops_base() + slot] = entry;
    } else if state == WAITING {
        add_candidate(node, round, wave + 1u);
    }
}

// The indirect arguments (x, y, z) of a dispatch over `items` entries, `per_group` per workgroup.
fn wave_args(items: u32, per_group: u32) -> vec3<u32> {
    return dispatch_args((items + per_group - 1u) / per_group);
}
