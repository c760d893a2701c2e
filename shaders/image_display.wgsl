// Displays the tonemapped image (packed RGBA8 pixels, r in the low byte, as written by
// image_tonemap.wgsl) in the viewer: a fullscreen triangle drawn into the image's viewport, each
// fragment reading its pixel straight from the storage buffer (no texture, no CPU round trip).

struct DisplayParams {
    // Top-left corner of the image rectangle in framebuffer pixels.
    origin: vec2<u32>,
    // Image size in pixels (= the path tracer's resolution).
    size: vec2<u32>,
    // 1 when the render target is an sRGB format: the stored bytes are already sRGB-encoded, so
    // they are decoded here and the hardware encodes them again on write.
    decode_srgb: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: DisplayParams;
@group(0) @binding(1) var<storage, read> pixels: array<u32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // Vertices (-1,-1), (3,-1), (-1,3): one triangle covering the whole viewport.
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb_decode(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let frag = vec2<i32>(floor(position.xy)) - vec2<i32>(params.origin);
    let last = vec2<i32>(params.size) - vec2<i32>(1);
    let p = vec2<u32>(clamp(frag, vec2<i32>(0), max(last, vec2<i32>(0))));
    var color = unpack4x8unorm(pixels[p.y * params.size.x + p.x]).rgb;
    if params.decode_srgb != 0u {
        color = srgb_decode(color);
    }
    return vec4<f32>(color, 1.0);
}
