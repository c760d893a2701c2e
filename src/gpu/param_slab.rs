//! Kernel parameters of one recording, uploaded together: each dispatch's parameter struct is
//! appended to a CPU copy of a uniform buffer at the device's offset alignment and bound at that
//! dynamic offset; before the recording is submitted, one write per chunk uploads them all. The
//! chunks (64 KiB uniform buffers) are kept and reused by the next recording, so steady-state
//! frames allocate nothing.
//!
//! A slab serves one recording at a time: a recording that resets it must come after the previous
//! one was submitted (queue writes land before the next submission, after earlier ones).

use bytemuck::Pod;

use super::GpuContext;

/// Bytes per chunk buffer (within every device's uniform binding limit).
const CHUNK_BYTES: u64 = 64 * 1024;

struct Chunk {
    buffer: wgpu::Buffer,
    bytes: Vec<u8>,
}

/// The parameter slab of a recorder (see the module documentation).
pub struct ParamSlab {
    chunks: Vec<Chunk>,
    /// The chunk being filled.
    current: usize,
    align: u64,
}

impl ParamSlab {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            chunks: Vec::new(),
            current: 0,
            align: u64::from(ctx.device.limits().min_uniform_buffer_offset_alignment).max(16),
        }
    }

    /// Starts a new recording: the space of the last one is reused.
    pub fn reset(&mut self) {
        for chunk in &mut self.chunks {
            chunk.bytes.clear();
        }
        self.current = 0;
    }

    /// Appends `params`; returns the chunk buffer to bind and the dynamic offset.
    pub fn push<P: Pod>(&mut self, ctx: &GpuContext, params: &P) -> (wgpu::Buffer, u32) {
        let data = bytemuck::bytes_of(params);
        assert!(
            data.len() as u64 <= CHUNK_BYTES,
            "parameters larger than a chunk"
        );
        loop {
            if self.current == self.chunks.len() {
                self.chunks.push(Chunk {
                    buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("kernel parameters"),
                        size: CHUNK_BYTES,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    bytes: Vec::with_capacity(CHUNK_BYTES as usize),
                });
            }
            let chunk = &mut self.chunks[self.current];
            let offset = (chunk.bytes.len() as u64).next_multiple_of(self.align);
            if offset + data.len() as u64 <= CHUNK_BYTES {
                chunk.bytes.resize(offset as usize, 0);
                chunk.bytes.extend_from_slice(data);
                return (chunk.buffer.clone(), offset as u32);
            }
            self.current += 1;
        }
    }

    /// Writes every parameter pushed since `reset` to the GPU (before the next submission).
    pub fn upload(&self, queue: &wgpu::Queue) {
        for chunk in self.chunks.iter().filter(|c| !c.bytes.is_empty()) {
            queue.write_buffer(&chunk.buffer, 0, &chunk.bytes);
        }
    }
}
