//! Small GPU-to-CPU copies that are read without waiting, for statistics shown a frame or two
//! late: a recording copies buffers into the readback's staging buffer, the owner submits and
//! calls `start`, and `try_take` returns the bytes once the GPU is done (the device must be
//! polled, e.g. `device.poll(PollType::Poll)` once per frame). A readback still in flight is busy
//! (`is_free`); owners keep a few and skip a frame's statistics when all are busy.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use super::GpuContext;
use crate::{Error, Result};

const IDLE: u8 = 0;
const RECORDED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

pub struct Readback {
    staging: wgpu::Buffer,
    state: Arc<AtomicU8>,
}

impl Readback {
    /// A readback of up to `size` bytes.
    pub fn new(ctx: &GpuContext, size: u64) -> Self {
        Self {
            staging: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: size.max(4).next_multiple_of(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(IDLE)),
        }
    }

    /// Whether nothing is in flight (copies may be recorded).
    pub fn is_free(&self) -> bool {
        self.state.load(Ordering::Acquire) == IDLE
    }

    /// Records a copy of `size` bytes of `source` to byte `offset` of the staging buffer.
    pub fn copy(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) {
        debug_assert!(self.is_free() || self.state.load(Ordering::Acquire) == RECORDED);
        encoder.copy_buffer_to_buffer(source, 0, &self.staging, offset, size);
        self.state.store(RECORDED, Ordering::Release);
    }

    /// After the recording with the copies was submitted: starts mapping.
    pub fn start(&mut self) {
        if self.state.load(Ordering::Acquire) != RECORDED {
            return;
        }
        self.state.store(MAPPING, Ordering::Release);
        let state = self.state.clone();
        self.staging
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |result| {
                let done = if result.is_ok() { MAPPED } else { FAILED };
                state.store(done, Ordering::Release);
            });
    }

    /// The staging buffer's bytes once the copies are done (then the readback is free again);
    /// None while in flight or idle.
    pub fn try_take(&mut self) -> Option<Result<Vec<u8>>> {
        match self.state.load(Ordering::Acquire) {
            MAPPED => {
                let bytes = self
                    .staging
                    .slice(..)
                    .get_mapped_range()
                    .map(|view| view.to_vec())
                    .map_err(|e| Error::Gpu(format!("readback map range failed: {e:?}")));
                self.staging.unmap();
                self.state.store(IDLE, Ordering::Release);
                Some(bytes)
            }
            FAILED => {
                self.state.store(IDLE, Ordering::Release);
                Some(Err(Error::Gpu("readback mapping failed".into())))
            }
            _ => None,
        }
    }
}
