// Rigid bodies moving through a static room (src/anim/bodies_animate.rs, CPU twin `body_triangle`): each
// body orbits a centre while bouncing and spinning about its own axis. One invocation per body
// triangle transforms its rest-pose (body-local) triangle by its body's motion at params.time and
// writes triangles[k] (the bodies are the scene's animated prefix; the room after it is static).
#include "bvh_node.wgsl"

struct BodiesParams {
    // One invocation per animated triangle.
    count: u32,
    row_pitch: u32,
    pad_a: u32,
    pad_b: u32,
    time: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// Motion of one body: orbit of `orbit_radius` around the centre at `orbit_speed` rad/s, bounce of
// `bounce_height` (|sin|) at `bounce_rate` rad/s, spin about the unit `axis` at `spin_rate` rad/s.
struct BodyMotion {
    center_x: f32,
    center_y: f32,
    center_z: f32,
    orbit_radius: f32,
    orbit_speed: f32,
    phase: f32,
    bounce_height: f32,
    bounce_rate: f32,
    axis_x: f32,
    axis_y: f32,
    axis_z: f32,
    spin_rate: f32,
}

// A triangle in its body's frame (the layout of Triangle with the body index in the first pad).
struct RestTriangle {
    v0: vec3<f32>,
    body: u32,
    v1: vec3<f32>,
    material: u32,
    v2: vec3<f32>,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: BodiesParams;
@group(0) @binding(1) var<storage, read_write> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> bodies: array<BodyMotion>;
@group(0) @binding(3) var<storage, read> rest: array<RestTriangle>;

// Rodrigues' rotation of v about the unit axis a by the angle with cosine c and sine s.
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
    let m = bodies[r.body];
    let t = params.time;
    let angle = m.phase + m.orbit_speed * t;
    let position = vec3<f32>(
        m.center_x + m.orbit_radius * cos(angle),
        m.center_y + m.bounce_height * abs(sin(m.bounce_rate * t + m.phase)),
        m.center_z + m.orbit_radius * sin(angle),
    );
    let spin = m.spin_rate * t + m.phase;
    let c = cos(spin);
    let s = sin(spin);
    let a = vec3<f32>(m.axis_x, m.axis_y, m.axis_z);
    triangles[k] = Triangle(
        position + rotate(r.v0, a, c, s),
        r.material,
        position + rotate(r.v1, a, c, s),
        0u,
        position + rotate(r.v2, a, c, s),
        0u,
    );
}
