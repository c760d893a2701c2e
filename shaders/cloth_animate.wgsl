// A waving flag (src/anim/cloth_animate.rs, CPU twin `flag_triangle`): a grid of cols × rows cells of two
// triangles hanging from a pole, displaced by travelling waves that grow away from the pole, with
// a little sag and contraction. One invocation per flag triangle writes triangles[k] (the flag is
// the scene's animated prefix; the pole and the ground after it are static).
#include "bvh_node.wgsl"

struct FlagParams {
    // One invocation per animated triangle.
    count: u32,
    row_pitch: u32,
    pad_a: u32,
    pad_b: u32,
    time: f32,
    width: f32,
    height: f32,
    amplitude: f32,
    origin_x: f32,
    origin_y: f32,
    origin_z: f32,
    cols: u32,
    rows: u32,
    material: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: FlagParams;
@group(0) @binding(1) var<storage, read_write> triangles: array<Triangle>;

fn flag_vertex(i: u32, j: u32) -> vec3<f32> {
    let t = params.time;
    let u = f32(i) / f32(params.cols);
    let v = f32(j) / f32(params.rows);
    let wave = sin(9.0 * u - 5.0 * t + 1.3 * v) + 0.4 * sin(17.0 * u - 8.3 * t + 3.1 * v + 1.0);
    let x = u * params.width * (1.0 - 0.06 * u * (1.0 + 0.5 * sin(3.0 * t + 2.0 * v)));
    let y = v * params.height - 0.08 * params.height * u * u * (1.0 + 0.5 * sin(2.3 * t + 4.0 * u));
    let z = params.amplitude * u * wave;
    return vec3<f32>(params.origin_x + x, params.origin_y + y, params.origin_z + z);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x + gid.y * params.row_pitch;
    if k >= params.count {
        return;
    }
    let cell = k / 2u;
    let ci = cell % params.cols;
    let cj = cell / params.cols;
    let material = params.material + min(cj * 3u / params.rows, 2u);
    let p00 = flag_vertex(ci, cj);
    let p11 = flag_vertex(ci + 1u, cj + 1u);
    var tri: Triangle;
    if k % 2u == 0u {
        tri = Triangle(p00, material, flag_vertex(ci + 1u, cj), 0u, p11, 0u);
    } else {
        tri = Triangle(p00, material, p11, 0u, flag_vertex(ci, cj + 1u), 0u);
    }
    triangles[k] = tri;
}
