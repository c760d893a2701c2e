// Raising a treelet level's indirect arguments as its roots take their slots (nodes_level.wgsl
// for the bottom-up rounds' levels, roots_phase.wgsl for a phase): both kernels declare the
// schedule buffer as atomic words (`schedule: array<atomic<u32>>`) and include
// treelet_round.wgsl, whose layout and `dispatch_args` rows treelets_optimize.wgsl reads.

// Raises level `level`'s arguments (schedule words SCHEDULE_ARGS + 3 (level − 1) ..) to cover
// `groups` workgroups: word-wise maxima of `dispatch_args`' rows, whose x times y covers any
// count that raised them.
fn raise_level_arguments(level: u32, groups: u32) {
    let args = dispatch_args(groups);
    let at = SCHEDULE_ARGS + 3u * (level - 1u);
    atomicMax(&schedule[at], args.x);
    atomicMax(&schedule[at + 1u], args.y);
    atomicMax(&schedule[at + 2u], args.z);
}
