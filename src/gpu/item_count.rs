//! How many items a recorded stage works on: a number known when recording, or one that an
//! earlier stage of the same recording computes on the GPU (the reference count of
//! pre-splitting), so that nothing is read back in between. Dispatches are sized for the count's
//! capacity, and the kernels that accept a GPU count work on `min(params.count, count_limit[0])`
//! items: a known count is the parameter, with a limit buffer holding u32::MAX; a GPU count
//! binds its buffer as the limit, with its capacity as the parameter.

use super::GpuContext;

#[derive(Clone, Copy, Debug)]
pub enum ItemCount<'a> {
    /// Known when recording.
    Known(u32),
    /// `buffer[0]` (a u32 written earlier in the recording), at most `capacity`.
    OnGpu {
        buffer: &'a wgpu::Buffer,
        capacity: u32,
    },
}

impl<'a> ItemCount<'a> {
    /// The most items there can be: what dispatches and buffers are sized for.
    pub fn capacity(self) -> u32 {
        match self {
            ItemCount::Known(n) => n,
            ItemCount::OnGpu { capacity, .. } => capacity,
        }
    }

    /// The count, when it is known on the CPU.
    pub fn known(self) -> Option<u32> {
        match self {
            ItemCount::Known(n) => Some(n),
            ItemCount::OnGpu { .. } => None,
        }
    }

    /// The buffer to bind as the kernels' `count_limit`.
    pub fn limit(self, ctx: &'a GpuContext) -> &'a wgpu::Buffer {
        match self {
            ItemCount::Known(_) => &ctx.no_count_limit,
            ItemCount::OnGpu { buffer, .. } => buffer,
        }
    }
}
