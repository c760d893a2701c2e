//! The BVH file format written by `treelet bench --export-bvh` (and read back by `read_bvh`), so
//! users and external tools can load built trees. All values little-endian:
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `[u8; 8]` | magic `TRLTBVH1` |
//! | 8 | u32 | node count N |
//! | 12 | u32 | primitive reference count P |
//! | 16 | u32 | triangle count of the scene |
//! | 20 | u32 | reserved (0) |
//! | 24 | N × 32 bytes | nodes in the `BvhNode` layout (root first) |
//! | 24 + 32N | P × u32 | `prim_indices` (triangle ids) |

use std::io::{Read, Write};
use std::path::Path;

use super::{Bvh, BvhNode};
use crate::{Error, Result};

pub const BVH_MAGIC: &[u8; 8] = b"TRLTBVH1";
const HEADER_BYTES: usize = 24;

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `bvh` (over a scene of `triangle_count` triangles) to `path`.
pub fn write_bvh(path: &Path, bvh: &Bvh, triangle_count: u32) -> Result<()> {
    let mut bytes =
        Vec::with_capacity(HEADER_BYTES + bvh.nodes.len() * 32 + bvh.prim_indices.len() * 4);
    bytes.extend_from_slice(BVH_MAGIC);
    for value in [
        bvh.nodes.len() as u32,
        bvh.prim_indices.len() as u32,
        triangle_count,
        0,
    ] {
        bytes.extend_from_slice(&value.to_le_bytes());
    }
    for node in &bvh.nodes {
        for word in bytemuck::cast_slice::<BvhNode, u32>(std::slice::from_ref(node)) {
            bytes.extend_from_slice(&word.to_le_bytes());
        }
    }
    for prim in &bvh.prim_indices {
        bytes.extend_from_slice(&prim.to_le_bytes());
    }
    let write_error = |e: std::io::Error| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut file = std::fs::File::create(path).map_err(write_error)?;
    file.write_all(&bytes).map_err(write_error)
}

/// Reads a file written by `write_bvh`: the tree and the scene's triangle count.
pub fn read_bvh(path: &Path) -> Result<(Bvh, u32)> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| io_error(path, e))?;
    let bad = |message: &str| Error::InvalidArgument(format!("{}: {message}", path.display()));
    if bytes.len() < HEADER_BYTES || &bytes[..8] != BVH_MAGIC {
        return Err(bad("not a treelet BVH file (bad magic or too short)"));
    }
    let words: Vec<u32> = bytes[8..]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let (nodes, prims, triangles) = (words[0] as usize, words[1] as usize, words[2]);
    let body = &words[4..];
    if body.len() != nodes * 8 + prims {
        return Err(bad("size does not match the header's counts"));
    }
    Ok((
        Bvh {
            nodes: bytemuck::cast_slice::<u32, BvhNode>(&body[..nodes * 8]).to_vec(),
            prim_indices: body[nodes * 8..].to_vec(),
        },
        triangles,
    ))
}
