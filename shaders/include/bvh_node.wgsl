// GPU twins of the Rust structs in src/bvh/node.rs, src/scene/mod.rs and src/geometry/ray.rs.

#include "constants.wgsl"

// Internal: left_or_first = left child, right_or_count = right child.
// Leaf: left_or_first = first prim_indices entry, right_or_count = LEAF_FLAG | count.
struct BvhNode {
    min: vec3<f32>,
    left_or_first: u32,
    max: vec3<f32>,
    right_or_count: u32,
}

struct Triangle {
    v0: vec3<f32>,
    material: u32,
    v1: vec3<f32>,
    pad1: u32,
    v2: vec3<f32>,
    pad2: u32,
}

struct Material {
    albedo: vec3<f32>,
    pad0: f32,
    emission: vec3<f32>,
    pad1: f32,
}

struct Ray {
    origin: vec3<f32>,
    t_min: f32,
    dir: vec3<f32>,
    t_max: f32,
}

struct Hit {
    t: f32,
    tri: u32,
    u: f32,
    v: f32,
}
