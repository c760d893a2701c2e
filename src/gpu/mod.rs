//! GPU plumbing: device and adapter selection (`context`), storage buffers and blocking read-back
//! (`buffers`), reads that do not wait (`readback`), WGSL sources with includes (`shaders`) and
//! the numbers they share with Rust (`constants`), kernel declarations and dispatch (`kernel`),
//! recordings of GPU work executed later (`recorder`) with their kernel parameters
//! (`param_slab`), item counts known when recording or computed on the GPU (`item_count`),
//! timestamp-query timing (`timer`), and warm-up plans and min/median/max of repeated timings
//! (`spread`).

mod buffers;
pub mod constants;
mod context;
mod item_count;
mod kernel;
mod param_slab;
mod readback;
mod recorder;
mod shaders;
mod spread;
mod timer;

pub use buffers::{
    bind_entry, grow_storage_buffer, indirect_buffer_zeroed, read_buffer, storage_buffer,
    storage_buffer_zeroed, uniform_buffer,
};
pub use context::{instance_flags, GpuContext, GpuOptions};
pub use item_count::ItemCount;
pub use kernel::{
    check_climb_width, default_climb_width, Grid, Items, Kernel, KernelDecl, KernelInfo, Overrides,
    Slot, CLIMB_WIDTHS, WORKGROUP_WIDTH_OVERRIDE,
};
pub(crate) use kernel::{flag_override, kernel, override_value};
pub use param_slab::ParamSlab;
pub use readback::Readback;
pub use recorder::{Pass, Recorder};
pub use shaders::shader_source;
pub use spread::{Spread, Timing, Warmup};
pub use timer::{aggregate_stages, GpuTimer, StageTime, TimedPass};
