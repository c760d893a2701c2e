//! The diffuse path-tracing kernels (`paths_trace` through the binary BVH, `paths_trace_wide`
//! through the compressed wide BVH): their parameters and declarations. One invocation per pixel
//! traces `samples` paths through the BVH (closest hit per bounce, any hit per point light) and
//! accumulates their radiance; every ray is counted.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct TraceParams {
    pub eye: [f32; 3],
    pub seed: u32,
    pub right: [f32; 3],
    pub width: u32,
    pub up: [f32; 3],
    pub height: u32,
    pub forward: [f32; 3],
    pub max_depth: u32,
    pub sky: [f32; 3],
    pub samples: u32,
    pub light_count: u32,
    /// Always 0: keeps the triangle test's products unfused (`unfused` in unfused.wgsl).
    pub opaque_zero: u32,
    /// Which pair of `counters` this dispatch adds its rays and stack overflows to.
    pub counter_slot: u32,
    pub _pad: u32,
}

/// The pipeline-overridable constant that gives the trace kernels their shadow rays (`override
/// POINT_LIGHTS` in path_integrator.wgsl): 1 for a scene with point lights, 0 for one without,
/// whose pipeline holds no light loop and no second traversal call site (RADV: `paths_trace` 72 →
/// 60 vector registers, `paths_trace_wide` 96 → 84; README, "Kernel statistics").
pub const POINT_LIGHTS_OVERRIDE: &str = "POINT_LIGHTS";

/// The pipeline-overridable constant that makes the trace and query kernels write out their
/// traversals' steps (`override COUNT_STEPS` in ray_box.wgsl; `TraversalSteps`): 1 in the
/// pipelines of a counting trace or query, 0 (nothing counted, the same code as without it)
/// everywhere else.
pub const COUNT_STEPS_OVERRIDE: &str = "COUNT_STEPS";

kernel!(pub PATHS_TRACE: TraceParams = "paths_trace"::"main", [8, 8, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite, Read]);

kernel!(pub PATHS_TRACE_WIDE: TraceParams = "paths_trace_wide"::"main", [8, 8, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite, Read]);
