// Boxes as the reduction kernels exchange them (32 bytes, the layout of a BvhNode's bounds).

struct Aabb {
    min: vec3<f32>,
    pad0: u32,
    max: vec3<f32>,
    pad1: u32,
}

const F32_MAX: f32 = 3.40282347e38;

fn empty_aabb() -> Aabb {
    return Aabb(vec3<f32>(F32_MAX), 0u, vec3<f32>(-F32_MAX), 0u);
}

fn triangle_min(t: Triangle) -> vec3<f32> {
    return min(t.v0, min(t.v1, t.v2));
}

fn triangle_max(t: Triangle) -> vec3<f32> {
    return max(t.v0, max(t.v1, t.v2));
}
