// Products kept out of FMA contraction (which GPU compilers do and WGSL allows): XOR with a zero
// read from a uniform, which the compiler cannot see through, makes a product an opaque value, so
// it is rounded on its own before any following add. Every device then rounds like the CPU twins:
// the watertight triangle test (ray_triangle.wgsl) decides hits bit for bit, and the collapse
// (nodes_mark.wgsl) recomputes exactly the areas the treelet rounds used (Ct·A·N == C finds the
// leaves they chose); the wide conversion's decisions match its CPU twin.

// x, unchanged, but no longer a product the compiler may contract into an FMA.
fn unfused(x: f32, zero: u32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ zero);
}

// Half the surface area of the box [lo, hi] (the wide conversion's SAH unit; CPU twin: `half_area`
// in src/bvh/wide/convert.rs).
fn half_area(lo: vec3<f32>, hi: vec3<f32>, zero: u32) -> f32 {
    let e = hi - lo;
    return unfused(e.x * e.y, zero) + unfused(e.y * e.z, zero) + unfused(e.z * e.x, zero);
}

// Surface area of the box [lo, hi] (CPU twin: `surface_area` in src/bvh/treelet/dp.rs).
fn surface_area(lo: vec3<f32>, hi: vec3<f32>, zero: u32) -> f32 {
    return 2.0 * half_area(lo, hi, zero);
}
