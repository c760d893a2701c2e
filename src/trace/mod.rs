//! Ray tracing on the GPU through a BVH: the diffuse path tracer with accumulation and
//! tonemapping (`path_tracer`, kernels `paths_trace` and `image_tonemap`), batched closest-hit and
//! any-hit queries (`rays_intersect`), in the binary or the wide layout, either counting its
//! traversals' steps on request (`bvh::TraversalSteps`), PNG files (`png`), and the CPU
//! brute-force oracle they are tested against (`brute_force`). Geometry and trees come from
//! `device`.

mod brute_force;
mod image_tonemap;
mod path_tracer;
mod paths_trace;
mod png;
mod rays_intersect;

pub use brute_force::brute_force_closest_hit;
pub use image_tonemap::IMAGE_TONEMAP;
pub use path_tracer::{PathTracer, RecordedTrace, RenderSettings, TraceStats};
pub use paths_trace::{PATHS_TRACE, PATHS_TRACE_WIDE};
pub use png::save_png;
pub use rays_intersect::{
    any_hits, any_hits_wide, closest_hits, closest_hits_wide, closest_hits_with_steps,
    RAYS_INTERSECT, RAYS_INTERSECT_WIDE,
};
