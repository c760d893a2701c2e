//! GPU plumbing: device and adapter selection (`context`), storage buffers and read-back
//! (`buffers`), WGSL sources with includes and pipeline creation (`shaders`), timestamp-query
//! timing (`timer`), and warm-up plans and min/median/max of repeated timings (`spread`).

mod buffers;
mod context;
mod shaders;
mod spread;
mod timer;

pub use buffers::{
    bind_entry, dispatch_grid, read_buffer, storage_buffer, storage_buffer_zeroed, uniform_buffer,
};
pub use context::{GpuContext, GpuOptions};
pub use shaders::{compute_pipeline, shader_source, KERNELS};
pub use spread::{Spread, Timing, Warmup};
pub use timer::{aggregate_stages, GpuTimer, StageTime};
