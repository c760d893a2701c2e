// Parameters of a kernel with one invocation per item (Rust twin `gpu::Items`): `count` items on
// a grid of `row_pitch` invocations per row (2D past the per-dimension workgroup limit); the
// invocation's item is `gid.x + gid.y * row_pitch`.

struct Items {
    count: u32,
    row_pitch: u32,
    pad0: u32,
    pad1: u32,
}
