//! Treelet round step 2 (kernel `roots_bucket`): the treelet roots ordered by level, and each
//! level's indirect dispatch arguments.

use super::rounds::RoundParams;
use crate::gpu::kernel;

kernel!(pub ROOTS_BUCKET: RoundParams = "roots_bucket"::"main", [64, 1, 1],
    [Read, Read, ReadWrite, ReadWrite, ReadWrite, Read]);
