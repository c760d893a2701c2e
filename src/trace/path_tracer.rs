//! The progressive diffuse path tracer (`shaders/paths_trace.wgsl`) and its tonemapping pass
//! (`shaders/image_tonemap.wgsl`). Every traced ray is counted on the GPU; trace time comes from
//! timestamp queries, so Mrays/s = rays / GPU trace time.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::GpuScene;
use crate::gpu::{
    bind_entry, compute_pipeline, read_buffer, storage_buffer_zeroed, uniform_buffer, GpuContext,
    GpuTimer,
};
use crate::scene::Camera;
use crate::{Error, Result};

/// Image size and path settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Rays per path at most (1 = primary rays only).
    pub max_depth: u32,
    pub exposure: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            max_depth: 4,
            exposure: 1.0,
        }
    }
}

/// What one `trace` call did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceStats {
    pub rays: u64,
    /// GPU time of the trace dispatches (None without timestamp queries).
    pub trace_ms: Option<f64>,
    /// Wall-clock time including submission and waiting.
    pub wall_ms: f64,
    pub samples: u32,
}

impl TraceStats {
    pub fn mrays_per_s(&self) -> Option<f64> {
        self.trace_ms
            .filter(|&ms| ms > 0.0)
            .map(|ms| self.rays as f64 / (ms * 1e3))
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TraceParams {
    eye: [f32; 3],
    seed: u32,
    right: [f32; 3],
    width: u32,
    up: [f32; 3],
    height: u32,
    forward: [f32; 3],
    max_depth: u32,
    sky: [f32; 3],
    samples: u32,
    light_count: u32,
    /// Always 0: keeps the triangle test's products unfused (`opaque` in ray_triangle.wgsl).
    opaque_zero: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<TraceParams>() == 96);

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TonemapParams {
    width: u32,
    height: u32,
    exposure: f32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<TonemapParams>() == 16);

/// Rays counted by one dispatch must fit the kernel's u32 counter.
const MAX_RAYS_PER_DISPATCH: u64 = 1 << 31;

pub struct PathTracer {
    settings: RenderSettings,
    trace_pipeline: wgpu::ComputePipeline,
    tonemap_pipeline: wgpu::ComputePipeline,
    trace_params: wgpu::Buffer,
    tonemap_params: wgpu::Buffer,
    accum: wgpu::Buffer,
    pixels: wgpu::Buffer,
    counters: wgpu::Buffer,
    samples_done: u32,
}

impl PathTracer {
    pub fn new(ctx: &GpuContext, settings: RenderSettings) -> Result<Self> {
        if settings.width == 0 || settings.height == 0 || settings.max_depth == 0 {
            return Err(Error::InvalidArgument(format!(
                "image size {}x{} and max depth {} must be positive",
                settings.width, settings.height, settings.max_depth
            )));
        }
        let pixel_count = u64::from(settings.width) * u64::from(settings.height);
        let max_dim = ctx.device.limits().max_compute_workgroups_per_dimension * 8;
        if settings.width > max_dim || settings.height > max_dim {
            return Err(Error::InvalidArgument(format!(
                "image size {}x{} exceeds this device's limit of {max_dim} pixels per side",
                settings.width, settings.height
            )));
        }
        Ok(Self {
            settings,
            trace_pipeline: compute_pipeline(ctx, "paths_trace.wgsl", "main"),
            tonemap_pipeline: compute_pipeline(ctx, "image_tonemap.wgsl", "main"),
            trace_params: uniform_buffer(ctx, "trace params", &TraceParams::zeroed()),
            tonemap_params: uniform_buffer(
                ctx,
                "tonemap params",
                &TonemapParams {
                    width: settings.width,
                    height: settings.height,
                    exposure: settings.exposure,
                    _pad: 0,
                },
            ),
            accum: storage_buffer_zeroed(ctx, "accumulation", pixel_count * 16)?,
            pixels: storage_buffer_zeroed(ctx, "pixels", pixel_count * 4)?,
            counters: storage_buffer_zeroed(ctx, "trace counters", 8)?,
            samples_done: 0,
        })
    }

    pub fn settings(&self) -> RenderSettings {
        self.settings
    }

    /// Samples per pixel accumulated since the last reset.
    pub fn samples_done(&self) -> u32 {
        self.samples_done
    }

    /// Starts accumulation over (after a camera, scene or setting change).
    pub fn reset(&mut self, ctx: &GpuContext) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.accum, 0, None);
        ctx.queue.submit([encoder.finish()]);
        self.samples_done = 0;
    }

    /// Traces `samples` more paths per pixel and accumulates them. Blocks until the GPU is done.
    pub fn trace(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
        sky: Vec3,
        samples: u32,
    ) -> Result<TraceStats> {
        let s = self.settings;
        // Each path vertex traces its bounce ray and one shadow ray per light.
        let rays_per_sample = u64::from(s.width)
            * u64::from(s.height)
            * u64::from(s.max_depth)
            * (1 + u64::from(scene.light_count));
        let per_dispatch =
            (MAX_RAYS_PER_DISPATCH / rays_per_sample).clamp(1, u64::from(samples.max(1))) as u32;
        let layout = self.trace_pipeline.get_bind_group_layout(0);
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("paths_trace"),
            layout: &layout,
            entries: &[
                bind_entry(0, &self.trace_params),
                bind_entry(1, &scene.triangles),
                bind_entry(2, &scene.materials),
                bind_entry(3, &scene.nodes),
                bind_entry(4, &scene.prim_indices),
                bind_entry(5, &self.accum),
                bind_entry(6, &self.counters),
                bind_entry(7, &scene.lights),
            ],
        });
        let mut stats = TraceStats::default();
        let mut timer = GpuTimer::new(ctx, 1);
        let start = std::time::Instant::now();
        let mut remaining = samples;
        while remaining > 0 {
            let batch = remaining.min(per_dispatch);
            let params = self.params(camera, sky, scene.light_count, batch);
            ctx.queue
                .write_buffer(&self.trace_params, 0, bytemuck::bytes_of(&params));
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&self.counters, 0, None);
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("paths_trace"),
                    timestamp_writes: timer.pass("trace"),
                });
                pass.set_pipeline(&self.trace_pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(s.width.div_ceil(8), s.height.div_ceil(8), 1);
            }
            timer.resolve(&mut encoder);
            ctx.queue.submit([encoder.finish()]);
            let counters: Vec<u32> = read_buffer(ctx, &self.counters, 2)?;
            if counters[1] > 0 {
                return Err(Error::Gpu(format!(
                    "{} paths overflowed the traversal stack (tree deeper than the kernel supports)",
                    counters[1]
                )));
            }
            stats.rays += u64::from(counters[0]);
            let times = timer.read(ctx)?;
            stats.trace_ms = match (stats.trace_ms, times[0].ms) {
                (Some(total), Some(ms)) => Some(total + ms),
                (None, Some(ms)) if stats.samples == 0 => Some(ms),
                _ => None,
            };
            stats.samples += batch;
            self.samples_done += batch;
            remaining -= batch;
        }
        stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(stats)
    }

    fn params(&self, camera: &Camera, sky: Vec3, light_count: u32, samples: u32) -> TraceParams {
        let s = self.settings;
        let forward = (camera.target - camera.eye).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let half_height = (0.5 * camera.fov_y_degrees.to_radians()).tan();
        let half_width = half_height * s.width as f32 / s.height as f32;
        TraceParams {
            eye: camera.eye.to_array(),
            seed: self.samples_done,
            right: (right * half_width).to_array(),
            width: s.width,
            up: (up * half_height).to_array(),
            height: s.height,
            forward: forward.to_array(),
            max_depth: s.max_depth,
            sky: sky.to_array(),
            samples,
            light_count,
            opaque_zero: 0,
            _pad: [0; 2],
        }
    }

    /// The tonemapped image: `width * height` packed RGBA8 pixels (r in the low byte), row 0 at
    /// the top, written by `tonemap`.
    pub fn pixels(&self) -> &wgpu::Buffer {
        &self.pixels
    }

    /// Records the tonemap dispatch (accumulation -> `pixels`) into `encoder`, without reading
    /// anything back: the viewer displays `pixels` straight from the GPU.
    pub fn tonemap(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        let s = self.settings;
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("image_tonemap"),
            layout: &self.tonemap_pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &self.tonemap_params),
                bind_entry(1, &self.accum),
                bind_entry(2, &self.pixels),
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("image_tonemap"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.tonemap_pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(s.width.div_ceil(8), s.height.div_ceil(8), 1);
    }

    /// Tonemaps the accumulated image and reads it back.
    pub fn read_image(&self, ctx: &GpuContext) -> Result<image::RgbaImage> {
        let s = self.settings;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.tonemap(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let pixels: Vec<u32> = read_buffer(ctx, &self.pixels, (s.width * s.height) as usize)?;
        image::RgbaImage::from_raw(s.width, s.height, bytemuck::cast_slice(&pixels).to_vec())
            .ok_or_else(|| Error::Gpu("pixel buffer has the wrong size".into()))
    }
}
