//! The progressive diffuse path tracer (kernel `paths_trace`) and its tonemapping (kernel
//! `image_tonemap`). Traces are recorded into the frame's recording; every traced ray is counted
//! on the GPU, and trace time comes from timestamp queries, so Mrays/s = rays / GPU trace time.

use std::sync::OnceLock;

use glam::Vec3;

use super::image_tonemap::{TonemapParams, IMAGE_TONEMAP};
use super::paths_trace::{
    TraceParams, COUNT_STEPS_OVERRIDE, PATHS_TRACE, PATHS_TRACE_WIDE, POINT_LIGHTS_OVERRIDE,
};
use crate::bvh::wide::Layout;
use crate::bvh::TraversalSteps;
use crate::device::{Geometry, Tree};
use crate::gpu::constants::{MAX_TRACE_DISPATCHES, TRACE_STEPS_AT};
use crate::gpu::{
    flag_override, read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, Grid, Kernel,
    ParamSlab, Recorder,
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
    /// The node layout traced (the wide one needs a tree converted by the update).
    pub layout: Layout,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            max_depth: 4,
            exposure: 1.0,
            layout: Layout::Binary,
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
    /// The traversal steps of all its rays, where the tracer counted them (`set_count_steps`).
    pub steps: Option<TraversalSteps>,
}

impl TraceStats {
    pub fn mrays_per_s(&self) -> Option<f64> {
        self.trace_ms
            .filter(|&ms| ms > 0.0)
            .map(|ms| self.rays as f64 / (ms * 1e3))
    }
}

/// Rays counted by one dispatch must fit the kernel's u32 counter.
const MAX_RAYS_PER_DISPATCH: u64 = 1 << 31;
/// Rays of one workgroup in one dispatch must fit its tally's high 25 bits (`TALLY_SHIFT` in
/// path_integrator.wgsl).
const MAX_WORKGROUP_RAYS: u64 = 1 << 25;
/// Pixels (invocations) per workgroup of the trace kernels: 8 x 8 (`WORKGROUP_INVOCATIONS` in
/// path_integrator.wgsl).
const WORKGROUP_PIXELS: u64 = 64;

/// The dispatches of one recorded trace: their count and the samples they add.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordedTrace {
    pub dispatches: u32,
    pub samples: u32,
    /// Whether its dispatches counted their traversal steps.
    pub counts_steps: bool,
}

impl RecordedTrace {
    /// The traversal steps of its dispatches from the tracer's counters read back whole (the
    /// words from `TRACE_STEPS_AT` on hold each dispatch's two 64-bit counts).
    pub fn steps(&self, counters: &[u32]) -> TraversalSteps {
        let count = |low: usize| u64::from(counters[low]) | u64::from(counters[low + 1]) << 32;
        (0..self.dispatches as usize)
            .map(|d| {
                let at = TRACE_STEPS_AT as usize + 4 * d;
                TraversalSteps {
                    nodes: count(at),
                    triangles: count(at + 2),
                }
            })
            .sum()
    }

    /// (rays, stack overflows) from the tracer's counters as read back after the submission.
    pub fn totals(&self, counters: &[u32]) -> (u64, u64) {
        counters
            .chunks_exact(2)
            .take(self.dispatches as usize)
            .fold((0, 0), |(r, o), c| {
                (r + u64::from(c[0]), o + u64::from(c[1]))
            })
    }
}

pub struct PathTracer {
    settings: RenderSettings,
    /// The trace kernels per layout (binary, wide), whether the scene has point lights and
    /// whether they count steps, compiled when first used (`trace_kernel`).
    trace: [[[OnceLock<Kernel<TraceParams>>; 2]; 2]; 2],
    /// Whether traces count their traversal steps (`set_count_steps`).
    count_steps: bool,
    tonemap: Kernel<TonemapParams>,
    accum: wgpu::Buffer,
    pixels: wgpu::Buffer,
    /// Per dispatch of the last recorded trace: [rays, stack overflows]; from `TRACE_STEPS_AT`,
    /// per dispatch its traversal steps where counted (nodes, triangles: 64 bits each).
    counters: wgpu::Buffer,
    samples_done: u32,
    /// Parameters of what this tracer records and submits itself (`trace`, `read_image`).
    params: ParamSlab,
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
            trace: Default::default(),
            count_steps: false,
            tonemap: Kernel::new(ctx, &IMAGE_TONEMAP),
            accum: storage_buffer_zeroed(ctx, "accumulation", pixel_count * 16)?,
            pixels: storage_buffer_zeroed(ctx, "pixels", pixel_count * 4)?,
            counters: storage_buffer_zeroed(ctx, "trace counters", Self::COUNTER_WORDS * 4)?,
            samples_done: 0,
            params: ParamSlab::new(ctx),
        })
    }

    /// Words of the counters: a pair per dispatch, then four per dispatch for the steps.
    const COUNTER_WORDS: u64 = TRACE_STEPS_AT as u64 + 4 * MAX_TRACE_DISPATCHES as u64;

    pub fn settings(&self) -> RenderSettings {
        self.settings
    }

    /// Whether the traces recorded from now on count their traversal steps (`TraceStats::steps`;
    /// a pipeline of their own, which adds its counts with a few atomics per pixel: for
    /// measurements, not for timed traces).
    pub fn set_count_steps(&mut self, count: bool) {
        self.count_steps = count;
    }

    /// Samples per pixel accumulated since the last reset.
    pub fn samples_done(&self) -> u32 {
        self.samples_done
    }

    /// Starts accumulation over (after a camera, scene or setting change): the next recorded
    /// trace clears the accumulation first.
    pub fn reset(&mut self) {
        self.samples_done = 0;
    }

    /// The trace kernel of `layout`, with shadow rays where the scene has point lights (without,
    /// a pipeline that holds no light loop: `POINT_LIGHTS_OVERRIDE`).
    fn trace_kernel(&self, ctx: &GpuContext, layout: Layout, lights: bool) -> &Kernel<TraceParams> {
        let (decl, by_layout) = match layout {
            Layout::Binary => (&PATHS_TRACE, &self.trace[0]),
            Layout::Wide => (&PATHS_TRACE_WIDE, &self.trace[1]),
        };
        let count = self.count_steps;
        by_layout[usize::from(lights)][usize::from(count)].get_or_init(|| {
            Kernel::with_overrides(
                ctx,
                decl,
                &[
                    flag_override(POINT_LIGHTS_OVERRIDE, lights),
                    flag_override(COUNT_STEPS_OVERRIDE, count),
                ],
            )
        })
    }

    /// The counters of the last recorded trace (see `RecordedTrace::totals`).
    pub fn counters(&self) -> &wgpu::Buffer {
        &self.counters
    }

    /// Records `samples` more paths per pixel through `tree` in the settings' layout (pass
    /// "trace"), accumulating. An error when the wide layout is asked for and the tree has none.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        tree: &Tree,
        camera: &Camera,
        sky: Vec3,
        samples: u32,
    ) -> Result<RecordedTrace> {
        let s = self.settings;
        // Each path vertex traces its bounce ray and one shadow ray per light.
        let rays_per_path = u64::from(s.max_depth) * (1 + u64::from(geometry.light_count));
        let workgroup_rays_per_sample = WORKGROUP_PIXELS * rays_per_path;
        if workgroup_rays_per_sample >= MAX_WORKGROUP_RAYS {
            return Err(Error::InvalidArgument(format!(
                "max depth {} with {} point lights: at most {} rays per path",
                s.max_depth,
                geometry.light_count,
                (MAX_WORKGROUP_RAYS - 1) / WORKGROUP_PIXELS
            )));
        }
        let rays_per_sample = u64::from(s.width) * u64::from(s.height) * rays_per_path;
        let per_dispatch = (MAX_RAYS_PER_DISPATCH / rays_per_sample)
            .min((MAX_WORKGROUP_RAYS - 1) / workgroup_rays_per_sample)
            .clamp(1, u64::from(samples.max(1))) as u32;
        let dispatches = samples.div_ceil(per_dispatch);
        if dispatches > MAX_TRACE_DISPATCHES {
            return Err(Error::InvalidArgument(format!(
                "{samples} samples of {}x{} pixels in one trace: at most {} per call",
                s.width,
                s.height,
                per_dispatch * MAX_TRACE_DISPATCHES
            )));
        }
        // What the leaves' references are tested through: the binary tree's indices into the
        // triangles, the wide tree's copies of its references' triangles.
        let (nodes, leaf_data) = match s.layout {
            Layout::Binary => (&tree.nodes, &tree.prim_indices),
            Layout::Wide => {
                let wide = tree.wide.as_ref().ok_or_else(|| {
                    Error::InvalidArgument(
                        "the wide layout was asked for, but the tree was not converted".into(),
                    )
                })?;
                (&wide.nodes, &wide.triangles)
            }
        };
        let kernel = self.trace_kernel(rec.ctx, s.layout, geometry.light_count > 0);
        if self.samples_done == 0 {
            rec.encoder().clear_buffer(&self.accum, 0, None);
        }
        rec.encoder().clear_buffer(&self.counters, 0, None);
        let grid = Grid::workgroups(s.width.div_ceil(8), s.height.div_ceil(8));
        let mut pass = rec.pass("trace");
        let mut remaining = samples;
        for slot in 0..dispatches {
            let batch = remaining.min(per_dispatch);
            let params = self.params(camera, sky, geometry.light_count, batch, slot);
            pass.dispatch(
                kernel,
                grid,
                &params,
                &[
                    &geometry.triangles,
                    &geometry.materials,
                    nodes,
                    leaf_data,
                    &self.accum,
                    &self.counters,
                    &geometry.lights,
                ],
            );
            remaining -= batch;
        }
        // The dispatches' batches add up to `samples`.
        self.samples_done += samples;
        Ok(RecordedTrace {
            dispatches,
            samples,
            counts_steps: self.count_steps,
        })
    }

    /// Traces `samples` more paths per pixel and accumulates them; blocks until the GPU is done
    /// and reads the ray count and the GPU time back.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &mut self,
        ctx: &GpuContext,
        geometry: &Geometry,
        tree: &Tree,
        camera: &Camera,
        sky: Vec3,
        samples: u32,
    ) -> Result<TraceStats> {
        let start = std::time::Instant::now();
        let mut timer = GpuTimer::new(ctx, 1);
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let recorded = {
            let mut rec = Recorder::new(ctx, &mut params, Some(&mut timer));
            let recorded = self.record(&mut rec, geometry, tree, camera, sky, samples);
            rec.submit();
            recorded
        };
        self.params = params;
        let recorded = recorded?;
        let times = timer.read(ctx)?;
        let trace_ms = times.first().and_then(|t| t.ms);
        self.read_stats(ctx, recorded, trace_ms, start.elapsed().as_secs_f64() * 1e3)
    }

    /// The statistics of a recorded trace after its submission (blocks to read the counters):
    /// an error when paths overflowed the traversal stack.
    pub fn read_stats(
        &self,
        ctx: &GpuContext,
        recorded: RecordedTrace,
        trace_ms: Option<f64>,
        wall_ms: f64,
    ) -> Result<TraceStats> {
        let words = if recorded.counts_steps {
            Self::COUNTER_WORDS as usize
        } else {
            2 * recorded.dispatches as usize
        };
        let counters: Vec<u32> = read_buffer(ctx, &self.counters, words)?;
        let (rays, overflows) = recorded.totals(&counters);
        if overflows > 0 {
            return Err(Error::Gpu(format!(
                "{overflows} paths overflowed the traversal stack (tree deeper than the kernel supports)"
            )));
        }
        Ok(TraceStats {
            rays,
            trace_ms,
            wall_ms,
            samples: recorded.samples,
            steps: recorded.counts_steps.then(|| recorded.steps(&counters)),
        })
    }

    fn params(
        &self,
        camera: &Camera,
        sky: Vec3,
        light_count: u32,
        samples: u32,
        counter_slot: u32,
    ) -> TraceParams {
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
            counter_slot,
            _pad: 0,
        }
    }
    /// The tonemapped image: `width * height` packed RGBA8 pixels (r in the low byte), row 0 at
    /// the top, written by `record_tonemap`.
    pub fn pixels(&self) -> &wgpu::Buffer {
        &self.pixels
    }

    /// Records the tonemap (accumulation -> `pixels`, pass "tonemap"), without reading anything
    /// back: the viewer displays `pixels` straight from the GPU.
    pub fn record_tonemap(&self, rec: &mut Recorder<'_>) {
        let s = self.settings;
        let params = TonemapParams {
            width: s.width,
            height: s.height,
            exposure: s.exposure,
            _pad: 0,
        };
        let grid = Grid::workgroups(s.width.div_ceil(8), s.height.div_ceil(8));
        rec.pass("tonemap")
            .dispatch(&self.tonemap, grid, &params, &[&self.accum, &self.pixels]);
    }

    /// Tonemaps the accumulated image and reads it back.
    pub fn read_image(&mut self, ctx: &GpuContext) -> Result<image::RgbaImage> {
        let s = self.settings;
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let mut rec = Recorder::new(ctx, &mut params, None);
        self.record_tonemap(&mut rec);
        rec.submit();
        self.params = params;
        let pixels: Vec<u32> = read_buffer(ctx, &self.pixels, (s.width * s.height) as usize)?;
        image::RgbaImage::from_raw(s.width, s.height, bytemuck::cast_slice(&pixels).to_vec())
            .ok_or_else(|| Error::Gpu("pixel buffer has the wrong size".into()))
    }
}
