// The choices of the SAH-optimal wide collapse (Ylitie, Karras & Laine 2017, §3.1), one word per
// binary node n, written by costs_climb.wgsl and read by wide_collapse.wgsl (CPU twin:
// `OptimalCollapse`, src/bvh/wide/optimal.rs). C(n, i) is the least cost of n's subtree spread
// over at most i slots of the wide node above it. For i in 2..=7, bits 3(i − 2)..3(i − 2) + 3
// hold C(n, i)'s choice: 0 = i − 1 slots do as well, k = k slots for the left child and i − k
// for the right. Bits 18..21 hold the k of n made a wide node itself (its 8 slots split).
// C(n, 8) is never asked for: a parent gives a child at most 7 slots (the COLLAPSE_COST_WORDS
// costs per node, constants.wgsl).

const CHOICE_WIDE_SHIFT: u32 = 18u;

// C(n, slots)'s choice, slots in 2..=7.
fn slots_choice(choice_word: u32, slots: u32) -> u32 {
    return (choice_word >> (3u * (slots - 2u))) & 7u;
}

// The left child's slots when n is a wide node of its own.
fn wide_split(choice_word: u32) -> u32 {
    return (choice_word >> CHOICE_WIDE_SHIFT) & 7u;
}
