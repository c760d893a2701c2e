//! The compressed 8-wide node layout (Ylitie, Karras & Laine 2017, §3.1): 80-byte nodes with
//! child boxes quantized to 8 bits per plane against a per-node origin and per-axis power-of-two
//! scale, and the primitive references of the leaf children. The WGSL twin is `WideNode` in
//! `shaders/include/wide_node.wgsl`.
//!
//! Slot `s` (0..8) of a node is an internal child when bit `s` of `imask` is set, a leaf of
//! `leaf_counts` byte `s` references when that byte is not zero, and empty otherwise. Internal
//! children are the consecutive nodes from `child_base` in slot order; the references of the leaf
//! children are consecutive from `prim_base` in slot order. Root at index 0.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::geometry::Aabb;

/// Slots per node.
pub const WIDTH: usize = 8;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq, Hash)]
pub struct WideNode {
    /// Low corner of the node's box (the quantization origin), as f32 bits.
    pub origin: [u32; 3],
    /// Biased exponents (as in f32: scale 2^(e − 127)) of x, y, z in bytes 0..3, `imask` in byte 3.
    pub exponents: u32,
    /// First internal child (wide node index).
    pub child_base: u32,
    /// First reference of the leaf children.
    pub prim_base: u32,
    /// Byte per slot: references of the leaf in that slot (0: internal or empty).
    pub leaf_counts: [u32; 2],
    /// Quantized child boxes, a byte per slot: lo x, y, z, then hi x, y, z.
    pub quantized: [[u32; 2]; 6],
}
const _: () = assert!(std::mem::size_of::<WideNode>() == 80);

/// A slot's content.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    Empty,
    /// A wide node.
    Internal(u32),
    /// A leaf: `count` references from `first`.
    Leaf {
        first: u32,
        count: u32,
    },
}

/// Byte `slot` of eight bytes in two little-endian words.
pub(crate) fn slot_byte(bytes: [u32; 2], slot: usize) -> u32 {
    (bytes[slot >> 2] >> ((slot & 3) * 8)) & 0xff
}

pub(crate) fn put_byte(bytes: &mut [u32; 2], slot: usize, value: u32) {
    debug_assert!(value <= 0xff);
    bytes[slot >> 2] |= value << ((slot & 3) * 8);
}

/// 2^(e − 127) for a biased exponent e in 1..=254.
pub(crate) fn exponent_scale(biased: u32) -> f32 {
    f32::from_bits(biased << 23)
}

impl WideNode {
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(self.origin.map(f32::from_bits))
    }

    pub fn imask(&self) -> u32 {
        self.exponents >> 24
    }

    /// Biased exponent of axis `axis`.
    pub fn exponent(&self, axis: usize) -> u32 {
        (self.exponents >> (8 * axis)) & 0xff
    }

    pub fn slot(&self, slot: usize) -> Slot {
        let imask = self.imask();
        if imask >> slot & 1 != 0 {
            let rank = (imask & ((1 << slot) - 1)).count_ones();
            return Slot::Internal(self.child_base + rank);
        }
        let count = slot_byte(self.leaf_counts, slot);
        if count == 0 {
            return Slot::Empty;
        }
        let first = self.prim_base
            + (0..slot)
                .map(|s| slot_byte(self.leaf_counts, s))
                .sum::<u32>();
        Slot::Leaf { first, count }
    }

    /// The quantized (lo, hi) planes of a slot, per axis.
    pub fn quantized_box(&self, slot: usize) -> ([u32; 3], [u32; 3]) {
        let q = |plane: usize| slot_byte(self.quantized[plane], slot);
        ([q(0), q(1), q(2)], [q(3), q(4), q(5)])
    }

    /// The box of a slot as a decoder computes it in f32: origin + q · 2^(e − 127).
    pub fn slot_box(&self, slot: usize) -> Aabb {
        let (lo, hi) = self.quantized_box(slot);
        let origin = self.origin();
        let decode = |q: [u32; 3]| {
            Vec3::from_array(std::array::from_fn(|a| {
                origin[a] + q[a] as f32 * exponent_scale(self.exponent(a))
            }))
        };
        Aabb::new(decode(lo), decode(hi))
    }
}

/// A wide tree: nodes (root at 0) and the references of their leaf children.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    pub prim_indices: Vec<u32>,
}

impl WideBvh {
    /// Bytes of nodes and references.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + 4 * self.prim_indices.len()
    }

    /// Levels of the tree (1 for a root alone; 0 without nodes): the GPU conversion emits one
    /// level at a time, so this is how many of its level steps find work.
    pub fn levels(&self) -> usize {
        let mut level: Vec<u32> = if self.nodes.is_empty() {
            vec![]
        } else {
            vec![0]
        };
        let mut levels = 0;
        while !level.is_empty() {
            levels += 1;
            level = level
                .iter()
                .flat_map(|&n| {
                    let node = &self.nodes[n as usize];
                    (0..node.imask().count_ones()).map(move |k| node.child_base + k)
                })
                .collect();
        }
        levels
    }

    /// Leaf children over all nodes.
    pub fn leaf_count(&self) -> usize {
        self.nodes
            .iter()
            .map(|n| {
                (0..WIDTH)
                    .filter(|&s| slot_byte(n.leaf_counts, s) != 0)
                    .count()
            })
            .sum()
    }
}
