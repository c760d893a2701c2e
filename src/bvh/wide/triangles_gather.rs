//! The wide layout's references and the copy of their triangles in reference order (kernel
//! `triangles_gather`, the last dispatch of the conversion's pass "wide"): each reference, which
//! the conversion left as a position in the binary tree's references, becomes its triangle's
//! index; and the wide traversal tests a leaf's triangles from consecutive words of
//! `WideTree::triangles`, each carrying its triangle's index, instead of loading a reference's
//! index and then its triangle (one dependent load fewer per triangle test; Ylitie et al. 2017
//! store the triangles in leaf order too). CPU twin of the copy: `gather_triangles`.

use crate::gpu::kernel;
use crate::scene::Triangle;

kernel!(pub TRIANGLES_GATHER: crate::gpu::Items = "triangles_gather"::"main", [64, 1, 1],
    [Read, Read, ReadWrite, Read, ReadWrite]);

/// The triangles of `prim_indices` in order, each with its index in `_pad1` (as the kernel writes
/// them; uploaded CPU-made wide trees take these).
pub fn gather_triangles(triangles: &[Triangle], prim_indices: &[u32]) -> Vec<Triangle> {
    prim_indices
        .iter()
        .map(|&i| Triangle {
            _pad1: i,
            ..triangles[i as usize]
        })
        .collect()
}
