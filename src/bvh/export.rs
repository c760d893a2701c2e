//! The BVH file formats written by `treelet bench --export-bvh` (and read back by `read_bvh` /
//! `read_wide_bvh`), so users and external tools can load built trees. Both share one header; all
//! values little-endian:
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `[u8; 8]` | magic: `TRLTBVH1` binary, `TRLTCWB1` compressed wide |
//! | 8 | u32 | node count N |
//! | 12 | u32 | primitive reference count P |
//! | 16 | u32 | triangle count of the scene |
//! | 20 | u32 | reserved (0) |
//! | 24 | N × S bytes | nodes, root first: S = 32 in the `BvhNode` layout, 80 in the `WideNode` layout |
//! | 24 + S·N | P × u32 | `prim_indices` (triangle ids) |

use std::io::{Read, Write};
use std::path::Path;

use super::wide::{WideBvh, WideNode};
use super::{Bvh, BvhNode};
use crate::{Error, Result};

pub const BVH_MAGIC: &[u8; 8] = b"TRLTBVH1";
pub const WIDE_BVH_MAGIC: &[u8; 8] = b"TRLTCWB1";
const HEADER_BYTES: usize = 24;

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `bvh` (over a scene of `triangle_count` triangles) to `path`.
pub fn write_bvh(path: &Path, bvh: &Bvh, triangle_count: u32) -> Result<()> {
    let nodes: &[u32] = bytemuck::cast_slice(&bvh.nodes);
    let counts = [bvh.nodes.len() as u32, bvh.prim_indices.len() as u32];
    write_file(
        path,
        BVH_MAGIC,
        counts,
        triangle_count,
        nodes,
        &bvh.prim_indices,
    )
}

/// Writes a wide tree (over a scene of `triangle_count` triangles) to `path`.
pub fn write_wide_bvh(path: &Path, wide: &WideBvh, triangle_count: u32) -> Result<()> {
    let nodes: &[u32] = bytemuck::cast_slice(&wide.nodes);
    let counts = [wide.nodes.len() as u32, wide.prim_indices.len() as u32];
    write_file(
        path,
        WIDE_BVH_MAGIC,
        counts,
        triangle_count,
        nodes,
        &wide.prim_indices,
    )
}

fn write_file(
    path: &Path,
    magic: &[u8; 8],
    [node_count, prim_count]: [u32; 2],
    triangle_count: u32,
    nodes: &[u32],
    prims: &[u32],
) -> Result<()> {
    let mut bytes = Vec::with_capacity(HEADER_BYTES + 4 * (nodes.len() + prims.len()));
    bytes.extend_from_slice(magic);
    for word in [node_count, prim_count, triangle_count, 0]
        .iter()
        .chain(nodes)
        .chain(prims)
    {
        bytes.extend_from_slice(&word.to_le_bytes());
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
    let (nodes, prim_indices, triangles) = read_file(path, BVH_MAGIC, 32, "binary")?;
    let nodes = bytemuck::cast_slice::<u32, BvhNode>(&nodes).to_vec();
    Ok((
        Bvh {
            nodes,
            prim_indices,
        },
        triangles,
    ))
}

/// Reads a file written by `write_wide_bvh`: the wide tree and the scene's triangle count.
pub fn read_wide_bvh(path: &Path) -> Result<(WideBvh, u32)> {
    let (nodes, prim_indices, triangles) = read_file(path, WIDE_BVH_MAGIC, 80, "wide")?;
    let nodes = bytemuck::cast_slice::<u32, WideNode>(&nodes).to_vec();
    Ok((
        WideBvh {
            nodes,
            prim_indices,
        },
        triangles,
    ))
}

/// (node words, references, triangle count) of a file with `magic` and nodes of `node_bytes`.
fn read_file(
    path: &Path,
    magic: &[u8; 8],
    node_bytes: usize,
    kind: &str,
) -> Result<(Vec<u32>, Vec<u32>, u32)> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| io_error(path, e))?;
    let bad = |message: String| Error::InvalidArgument(format!("{}: {message}", path.display()));
    if bytes.len() < HEADER_BYTES || &bytes[..8] != magic {
        return Err(bad(format!(
            "not a treelet BVH file of the {kind} layout (bad magic or too short)"
        )));
    }
    let words: Vec<u32> = bytes[8..]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let (nodes, prims, triangles) = (words[0] as usize, words[1] as usize, words[2]);
    let node_words = node_bytes / 4;
    let body = &words[4..];
    if (bytes.len() - 8) % 4 != 0
        || nodes
            .checked_mul(node_words)
            .and_then(|n| n.checked_add(prims))
            != Some(body.len())
    {
        return Err(bad("size does not match the header's counts".into()));
    }
    Ok((
        body[..nodes * node_words].to_vec(),
        body[nodes * node_words..].to_vec(),
        triangles,
    ))
}
