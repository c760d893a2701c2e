//! The one BVH node layout every builder outputs and the tracer consumes.
//!
//! A tree is an array of 32-byte nodes with the root at index 0, plus an array of primitive
//! references (`prim_indices`, triangle ids). Each node stores its own bounds and either
//! - internal: `left_or_first` = index of the left child, `right_or_count` = index of the right child
//!   (children may sit anywhere in the array: GPU builders emit Karras' layout directly), or
//! - leaf: `left_or_first` = first entry in `prim_indices`, `right_or_count` = `LEAF_FLAG | count`.
//!
//! The WGSL twin is `BvhNode` in `shaders/include/bvh_node.wgsl`.

use crate::geometry::Aabb;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Set in `right_or_count` of leaf nodes.
pub use crate::gpu::constants::LEAF_FLAG;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub right_or_count: u32,
}
const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

impl BvhNode {
    pub fn internal(bounds: Aabb, left: u32, right: u32) -> Self {
        debug_assert!(right & LEAF_FLAG == 0);
        Self {
            min: bounds.min.to_array(),
            left_or_first: left,
            max: bounds.max.to_array(),
            right_or_count: right,
        }
    }

    pub fn leaf(bounds: Aabb, first: u32, count: u32) -> Self {
        Self {
            min: bounds.min.to_array(),
            left_or_first: first,
            max: bounds.max.to_array(),
            right_or_count: LEAF_FLAG | count,
        }
    }

    pub fn is_leaf(&self) -> bool {
        self.right_or_count & LEAF_FLAG != 0
    }

    /// Number of primitives of a leaf (0 for internal nodes).
    pub fn prim_count(&self) -> u32 {
        if self.is_leaf() {
            self.right_or_count & !LEAF_FLAG
        } else {
            0
        }
    }

    /// (left, right) child indices of an internal node.
    pub fn children(&self) -> (u32, u32) {
        (self.left_or_first, self.right_or_count)
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from(self.min), Vec3::from(self.max))
    }
}

/// A built tree: nodes (root at 0) and the primitive references the leaves point into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub prim_indices: Vec<u32>,
}

impl Bvh {
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }
}
