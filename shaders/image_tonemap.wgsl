// Accumulated radiance -> display pixels: average, exposure, ACES filmic curve (Narkowicz fit),
// sRGB encoding, packed RGBA8 (r in the low byte).

struct TonemapParams {
    width: u32,
    height: u32,
    exposure: f32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: TonemapParams;
@group(0) @binding(1) var<storage, read> accum: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> pixels: array<u32>;

fn aces(x: vec3<f32>) -> vec3<f32> {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let pixel = gid.y * params.width + gid.x;
    let a = accum[pixel];
    let color = srgb_encode(aces(a.rgb / max(a.w, 1.0) * params.exposure));
    let bytes = vec4<u32>(round(vec4<f32>(color, 1.0) * 255.0));
    pixels[pixel] = bytes.x | (bytes.y << 8u) | (bytes.z << 16u) | (bytes.w << 24u);
}
