// Boxes as the reduction kernels exchange them (32 bytes, the layout of a BvhNode's bounds).

#include "constants.wgsl"

struct Aabb {
    min: vec3<f32>,
    pad0: u32,
    max: vec3<f32>,
    pad1: u32,
}

