//! Ray tracing on the GPU through a BVH: scene upload (`gpu_scene`), the diffuse path tracer with
//! accumulation and tonemapping (`path_tracer`), PNG files (`png`), batched closest-hit and any-hit queries (`ray_query`), and the
//! CPU brute-force oracle they are tested against (`brute_force`).

mod brute_force;
mod gpu_scene;
mod path_tracer;
mod png;
mod ray_query;

pub use brute_force::brute_force_closest_hit;
pub use gpu_scene::GpuScene;
pub use path_tracer::{PathTracer, RenderSettings, TraceStats};
pub use png::save_png;
pub use ray_query::{any_hits, closest_hits};
