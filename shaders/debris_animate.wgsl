// An exploding mesh (src/anim/debris_animate.rs, CPU twin `debris_triangle`): from params.start on, every
// triangle flies away from the centre along its own pseudo-random ballistic path, tumbling about
// its centroid, until its centroid lands on the floor, where it stops. One invocation per mesh
// triangle reads the intact (rest) triangle and writes triangles[k] (the mesh is the scene's
// animated prefix; the floor and the crates after it are static).
#include "bvh_node.wgsl"

struct DebrisParams {
    // One invocation per animated triangle.
    count: u32,
    row_pitch: u32,
    pad_a: u32,
    pad_b: u32,
    time: f32,
    start: f32,
    speed: f32,
    gravity: f32,
    center_x: f32,
    center_y: f32,
    center_z: f32,
    floor_y: f32,
    spin: f32,
    lift: f32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: DebrisParams;
@group(0) @binding(1) var<storage, read_write> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> rest: array<Triangle>;

// Height above the floor at which a fragment's centroid comes to rest.
const REST_HEIGHT: f32 = 0.02;

fn hash(x: u32) -> u32 {
    var h = x * 0x9E3779B9u;
    h ^= h >> 16u;
    h *= 0x7FEB352Du;
    h ^= h >> 15u;
    h *= 0x846CA68Bu;
    h ^= h >> 16u;
    return h;
}

fn unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

fn rotate(v: vec3<f32>, a: vec3<f32>, c: f32, s: f32) -> vec3<f32> {
    return v * c + cross(a, v) * s + a * (dot(a, v) * (1.0 - c));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x + gid.y * params.row_pitch;
    if k >= params.count {
        return;
    }
    let r = rest[k];
    let g = (r.v0 + r.v1 + r.v2) / 3.0;
    let h1 = hash(k);
    let h2 = hash(h1 ^ 0x68E31DA4u);
    let h3 = hash(h2 ^ 0xB5297A4Du);
    let h4 = hash(h3 ^ 0x1B56C4E9u);
    let away = g - vec3<f32>(params.center_x, params.center_y, params.center_z);
    let dir = away / max(length(away), 1e-6);
    let velocity = dir * (params.speed * (0.5 + unit(h1))) + vec3<f32>(0.0, params.lift * unit(h2), 0.0);
    // Flight time until the centroid reaches its resting height above the floor.
    let drop = max(g.y - (params.floor_y + REST_HEIGHT), 0.0);
    let landing = (velocity.y + sqrt(velocity.y * velocity.y + 2.0 * params.gravity * drop)) / params.gravity;
    let s = min(max(params.time - params.start, 0.0), landing);
    let offset = velocity * s + vec3<f32>(0.0, -0.5 * params.gravity * s * s, 0.0);
    let axis = normalize(vec3<f32>(unit(h2) - 0.5, 0.6, unit(h4) - 0.5));
    let angle = params.spin * (0.5 + unit(h3)) * s;
    let c = cos(angle);
    let sn = sin(angle);
    let center = g + offset;
    triangles[k] = Triangle(
        center + rotate(r.v0 - g, axis, c, sn),
        r.material,
        center + rotate(r.v1 - g, axis, c, sn),
        0u,
        center + rotate(r.v2 - g, axis, c, sn),
        0u,
    );
}
