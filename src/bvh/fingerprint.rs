//! A tree's fingerprint, computed on the GPU (kernel `words_hash`): 128-bit hashes of its buffers'
//! words, read back in a few bytes instead of the whole tree. The schedule tuning compares every
//! trial's tree with the starting schedule's by it (`bvh::tuning`); at millions of triangles a
//! read-back of the tree per trial cost more than the trial.
//!
//! The binary tree is hashed word by word in order (nodes, references, counts): two fingerprints
//! are equal when the trees are equal bit for bit, and differ otherwise but with probability
//! 2^-128 per accidental difference. The wide layout is hashed as the multiset of its nodes'
//! contents without the two words that hold other nodes' and references' numbers (`child_base`,
//! `prim_base`), since its conversion numbers wide nodes by atomics (two conversions of one binary
//! tree may order them differently), its references as a multiset (each present, none twice),
//! plus its node and reference counts.
//!
//! CPU twin: [`words_hash_cpu`], the same sums, which the GPU's equal exactly (they wrap, so the
//! workgroups' order does not matter).

use bytemuck::{Pod, Zeroable};

use crate::bvh::wide::{WideBvh, WideNode};
use crate::bvh::{Bvh, BvhNode};
use crate::device::Tree;
use crate::gpu::{
    kernel, read_buffer, storage_buffer_zeroed, GpuContext, Kernel, ParamSlab, Recorder,
};
use crate::Result;

/// Parameters of `words_hash.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct HashParams {
    /// Invocations (words / `HASH_ITEMS`, rounded up).
    pub count: u32,
    pub row_pitch: u32,
    /// Words hashed (from the first).
    pub words: u32,
    /// Words per record: the key of a word that is not `positional` is its position in its record.
    pub stride: u32,
    /// Bit p set: the words at position p of their record are left out (stride ≤ 32).
    pub skipped: u32,
    /// 1: a word's key is its index, so the words' order counts.
    pub positional: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<HashParams>() == 32);

/// Words per invocation of `words_hash.wgsl` (`ITEMS` there).
const HASH_ITEMS: u32 = 16;

kernel!(pub WORDS_HASH: HashParams = "words_hash"::"main", [256, 1, 1], [Read, ReadWrite]);

/// What is hashed of a buffer of u32 words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WordsHash {
    /// Words hashed (from the first).
    pub count: u32,
    /// See `HashParams`.
    pub stride: u32,
    pub skipped: u32,
    pub positional: bool,
}

impl WordsHash {
    /// The first `count` words in order.
    pub fn in_order(count: u32) -> Self {
        Self {
            count,
            stride: 1,
            skipped: 0,
            positional: true,
        }
    }

    /// `records` records of `stride` words as a multiset, without the positions in `skipped`.
    pub fn records(records: u32, stride: u32, skipped: u32) -> Self {
        assert!((1..=32).contains(&stride), "records of 1..=32 words");
        Self {
            count: records * stride,
            stride,
            skipped,
            positional: false,
        }
    }
}

/// `pcg_hash` of `random.wgsl` (Jarzynski & Olano 2020), a bijection of u32.
fn pcg_hash(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The seeds of the four sums (as in `words_hash.wgsl`).
const SEEDS: [u32; 4] = [0x243f_6a88, 0x85a3_08d3, 0x1319_8a2e, 0x0370_7344];

/// CPU twin of the kernel: the four sums over `words[..what.count]`.
pub fn words_hash_cpu(words: &[u32], what: WordsHash) -> [u32; 4] {
    let mut sums = [0u32; 4];
    for (i, &w) in words.iter().enumerate().take(what.count as usize) {
        let position = i as u32 % what.stride;
        if (what.skipped >> position) & 1 != 0 {
            continue;
        }
        let key = if what.positional { i as u32 } else { position };
        for (sum, seed) in sums.iter_mut().zip(SEEDS) {
            *sum = sum.wrapping_add(pcg_hash(
                pcg_hash(w ^ seed).wrapping_add(key.wrapping_mul(0x9e37_79b9)),
            ));
        }
    }
    sums
}

/// The kernel and the buffer its sums land in.
pub struct WordsHasher {
    kernel: Kernel<HashParams>,
    sums: wgpu::Buffer,
    slab: ParamSlab,
}

impl WordsHasher {
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            kernel: Kernel::new(ctx, &WORDS_HASH),
            sums: storage_buffer_zeroed(ctx, "words hash", 16)?,
            slab: ParamSlab::new(ctx),
        })
    }

    /// The four sums over `buffer`'s words as `what` says; blocks until the GPU is done.
    pub fn hash(
        &mut self,
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
        what: WordsHash,
    ) -> Result<[u32; 4]> {
        let mut rec = Recorder::new(ctx, &mut self.slab, None);
        rec.encoder().clear_buffer(&self.sums, 0, None);
        if what.count > 0 {
            let invocations = what.count.div_ceil(HASH_ITEMS);
            let grid = self.kernel.grid(ctx, invocations);
            let params = HashParams {
                count: invocations,
                row_pitch: grid.row_pitch,
                words: what.count,
                stride: what.stride,
                skipped: what.skipped,
                positional: u32::from(what.positional),
                _pad: [0; 2],
            };
            rec.pass("words hash")
                .dispatch(&self.kernel, grid, &params, &[buffer, &self.sums]);
        }
        rec.submit();
        let sums: Vec<u32> = read_buffer(ctx, &self.sums, 4)?;
        Ok([sums[0], sums[1], sums[2], sums[3]])
    }
}

/// Words per wide node, and the positions of `child_base` and `prim_base` among them.
const WIDE_NODE_WORDS: u32 = (std::mem::size_of::<WideNode>() / 4) as u32;
const WIDE_NUMBERING_WORDS: u32 = (1 << 4) | (1 << 5);
const _: () = assert!(std::mem::offset_of!(WideNode, child_base) == 16);
const _: () = assert!(std::mem::offset_of!(WideNode, prim_base) == 20);

/// What is hashed of a binary tree of `nodes` nodes and `prims` references: the node words in
/// order, then the references in order.
fn binary_parts(nodes: u32, prims: u32) -> [WordsHash; 2] {
    let node_words = nodes * (std::mem::size_of::<BvhNode>() / 4) as u32;
    [WordsHash::in_order(node_words), WordsHash::in_order(prims)]
}

/// What is hashed of a wide layout of `nodes` nodes and `prims` references: the nodes as a
/// multiset without their numbering words, then the references as a multiset.
fn wide_parts(nodes: u32, prims: u32) -> [WordsHash; 2] {
    [
        WordsHash::records(nodes, WIDE_NODE_WORDS, WIDE_NUMBERING_WORDS),
        WordsHash::records(prims, 1, 0),
    ]
}

/// A tree's fingerprint (see the module header).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeFingerprint {
    /// Node and reference counts, and the hashes of the nodes and of the references.
    pub binary: ([u32; 2], [u32; 4], [u32; 4]),
    /// The same for the wide layout, when the tree has one (its nodes and its references as
    /// multisets).
    pub wide: Option<([u32; 2], [u32; 4], [u32; 4])>,
}

impl TreeFingerprint {
    /// `tree`'s fingerprint; blocks until the GPU is done.
    pub fn of(ctx: &GpuContext, hasher: &mut WordsHasher, tree: &Tree) -> Result<Self> {
        let (nodes, prims) = tree.counts(ctx)?;
        let [node_words, prim_words] = binary_parts(nodes, prims);
        let binary = (
            [nodes, prims],
            hasher.hash(ctx, &tree.nodes, node_words)?,
            hasher.hash(ctx, &tree.prim_indices, prim_words)?,
        );
        let wide = match &tree.wide {
            Some(wide) => {
                let (nodes, prims) = wide.counts(ctx)?;
                let [node_words, prim_words] = wide_parts(nodes, prims);
                Some((
                    [nodes, prims],
                    hasher.hash(ctx, &wide.nodes, node_words)?,
                    hasher.hash(ctx, &wide.prim_indices, prim_words)?,
                ))
            }
            None => None,
        };
        Ok(Self { binary, wide })
    }

    /// CPU twin of [`TreeFingerprint::of`] for trees read back or built on the CPU.
    pub fn of_cpu(bvh: &Bvh, wide: Option<&WideBvh>) -> Self {
        let counts = [bvh.nodes.len() as u32, bvh.prim_indices.len() as u32];
        let [node_words, prim_words] = binary_parts(counts[0], counts[1]);
        let binary = (
            counts,
            words_hash_cpu(bytemuck::cast_slice(&bvh.nodes), node_words),
            words_hash_cpu(&bvh.prim_indices, prim_words),
        );
        let wide = wide.map(|wide| {
            let counts = [wide.nodes.len() as u32, wide.prim_indices.len() as u32];
            let [node_words, prim_words] = wide_parts(counts[0], counts[1]);
            (
                counts,
                words_hash_cpu(bytemuck::cast_slice(&wide.nodes), node_words),
                words_hash_cpu(&wide.prim_indices, prim_words),
            )
        });
        Self { binary, wide }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_counts_in_order_and_not_between_records() {
        let words: Vec<u32> = (0..40).map(|i| i * 7 + 3).collect();
        let mut swapped = words.clone();
        swapped.swap(3, 17);
        let in_order = WordsHash::in_order(40);
        assert_ne!(
            words_hash_cpu(&words, in_order),
            words_hash_cpu(&swapped, in_order)
        );
        // Records of 4 words: swapping records 1 and 6 keeps the multiset.
        let mut records = words.clone();
        for k in 0..4 {
            records.swap(4 + k, 24 + k);
        }
        let multiset = WordsHash::records(10, 4, 0);
        assert_eq!(
            words_hash_cpu(&words, multiset),
            words_hash_cpu(&records, multiset)
        );
        assert_ne!(
            words_hash_cpu(&words, multiset),
            words_hash_cpu(&swapped, multiset)
        );
        // A skipped position may differ; another may not.
        let mut renumbered = words.clone();
        renumbered[5] ^= 1;
        let skip_1 = WordsHash::records(10, 4, 1 << 1);
        assert_eq!(
            words_hash_cpu(&words, skip_1),
            words_hash_cpu(&renumbered, skip_1)
        );
        renumbered[6] ^= 1;
        assert_ne!(
            words_hash_cpu(&words, skip_1),
            words_hash_cpu(&renumbered, skip_1)
        );
        // Words past the count are not hashed.
        let mut tail = words.clone();
        tail[39] = 0;
        assert_eq!(
            words_hash_cpu(&words, WordsHash::in_order(39)),
            words_hash_cpu(&tail, WordsHash::in_order(39))
        );
    }
}
