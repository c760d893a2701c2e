//! Storage/uniform buffer creation, dispatch sizing (2D grids past 65,535 workgroups) and
//! blocking read-back for headless use and tests.

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use super::GpuContext;
use crate::{Error, Result};

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A storage buffer holding `data` (at least 4 bytes, so empty arrays still bind).
pub fn storage_buffer<T: Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> Result<wgpu::Buffer> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    check_binding_size(ctx, label, bytes.len() as u64)?;
    if bytes.is_empty() {
        return storage_buffer_zeroed(ctx, label, 4);
    }
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: STORAGE,
        }))
}

/// A zero-filled storage buffer of `size` bytes that also holds indirect dispatch arguments.
pub fn indirect_buffer_zeroed(ctx: &GpuContext, label: &str, size: u64) -> Result<wgpu::Buffer> {
    check_binding_size(ctx, label, size)?;
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4).next_multiple_of(4),
        usage: STORAGE | wgpu::BufferUsages::INDIRECT,
        mapped_at_creation: false,
    }))
}

/// A zero-filled storage buffer of `size` bytes.
pub fn storage_buffer_zeroed(ctx: &GpuContext, label: &str, size: u64) -> Result<wgpu::Buffer> {
    check_binding_size(ctx, label, size)?;
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4).next_multiple_of(4),
        usage: STORAGE,
        mapped_at_creation: false,
    }))
}

/// Makes `slot` a zero-filled storage buffer of at least `size` bytes: kept if it is one already,
/// else replaced (the old one dropped first, so both are never held at once; its contents are
/// not kept).
pub fn grow_storage_buffer(
    ctx: &GpuContext,
    slot: &mut Option<wgpu::Buffer>,
    label: &str,
    size: u64,
) -> Result<()> {
    if slot.as_ref().is_none_or(|buffer| buffer.size() < size) {
        *slot = None;
        *slot = Some(storage_buffer_zeroed(ctx, label, size)?);
    }
    Ok(())
}

/// A uniform buffer holding `value`, updatable with `queue.write_buffer`.
pub fn uniform_buffer<T: Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(value),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        })
}

fn check_binding_size(ctx: &GpuContext, label: &str, size: u64) -> Result<()> {
    let max = ctx.max_storage_binding();
    if size > max {
        return Err(Error::SceneTooLarge(format!(
            "buffer '{label}' needs {size} bytes but this device binds at most {max} bytes per storage buffer"
        )));
    }
    Ok(())
}

/// Copies `buffer` (its first `count` elements) back to the CPU; blocks until done.
pub fn read_buffer<T: Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<T>> {
    let size = (count * std::mem::size_of::<T>()) as u64;
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("device poll failed: {e}")))?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("map callback lost: {e}")))?
        .map_err(|e| Error::Gpu(format!("buffer map failed: {e}")))?;
    let data = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("buffer map range failed: {e:?}")))?;
        bytemuck::pod_collect_to_vec::<u8, T>(&view)
    };
    staging.unmap();
    Ok(data)
}

/// A bind group entry binding the whole of `buffer`.
pub fn bind_entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}
