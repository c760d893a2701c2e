//! One way to declare and run a compute kernel. Each WGSL kernel is declared once in Rust, in the
//! module of the same name, with the `kernel!` macro: its file under `shaders/` (embedded at
//! compile time, so a wrong name does not compile), entry point, workgroup size, parameter type
//! and bindings. From the declaration the bind group layout and the pipeline are created once per
//! device (explicit layouts: no binding is inferred from what an entry point happens to use), and
//! `Pass::dispatch` binds the parameters (from the recording's parameter slab, at a dynamic
//! offset) and the buffers in declaration order. `tests/shaders.rs` checks every declaration
//! against its WGSL with naga: the parameter struct's size, every binding's kind, the workgroup
//! size, and that the WGSL declares no binding the Rust side does not.

use std::marker::PhantomData;
use std::sync::Mutex;

use bytemuck::Pod;

use super::{shader_source, GpuContext};
use crate::Result;

/// What binding `b` of a kernel's bind group 0 holds (`slots[b]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// The kernel's parameters: `var<uniform>`, always binding 0, bound at a dynamic offset into
    /// the recording's parameter slab.
    Params,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

/// A kernel's declaration without its parameter type (for tables and checks).
#[derive(Clone, Copy, Debug)]
pub struct KernelInfo {
    /// File stem: the kernel is `shaders/<name>.wgsl`.
    pub name: &'static str,
    /// The file's text before include expansion.
    pub source: &'static str,
    pub entry: &'static str,
    pub workgroup_size: [u32; 3],
    /// `slots[b]` is binding `b`; slot 0 is `Params`.
    pub slots: &'static [Slot],
    /// Size of the parameter struct in bytes.
    pub params_size: u64,
}

/// A kernel declared with parameters of type `P`.
pub struct KernelDecl<P> {
    pub info: KernelInfo,
    params: PhantomData<fn(P)>,
}

impl<P> KernelDecl<P> {
    pub const fn new(info: KernelInfo) -> Self {
        Self {
            info,
            params: PhantomData,
        }
    }
}

/// Declares a kernel constant:
/// `kernel!(pub NAME: Params = "file_stem"::"entry", [x, y, z], [Read, ReadWrite, ..]);`
/// (binding 0 is the parameters, the listed slots are bindings 1, 2, ...).
macro_rules! kernel {
    ($(#[$doc:meta])* $vis:vis $id:ident: $params:ty = $name:literal :: $entry:literal,
     [$x:expr, $y:expr, $z:expr], [$($slot:ident),* $(,)?]) => {
        $(#[$doc])*
        $vis const $id: $crate::gpu::KernelDecl<$params> =
            $crate::gpu::KernelDecl::new($crate::gpu::KernelInfo {
                name: $name,
                source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $name, ".wgsl")),
                entry: $entry,
                workgroup_size: [$x, $y, $z],
                slots: &[$crate::gpu::Slot::Params, $($crate::gpu::Slot::$slot),*],
                params_size: std::mem::size_of::<$params>() as u64,
            });
    };
}
pub(crate) use kernel;

/// The bind group layout of a declaration.
fn layout_entries(info: &KernelInfo) -> Vec<wgpu::BindGroupLayoutEntry> {
    info.slots
        .iter()
        .enumerate()
        .map(|(binding, slot)| wgpu::BindGroupLayoutEntry {
            binding: binding as u32,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: match slot {
                    Slot::Params => wgpu::BufferBindingType::Uniform,
                    Slot::Read => wgpu::BufferBindingType::Storage { read_only: true },
                    Slot::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
                },
                has_dynamic_offset: *slot == Slot::Params,
                min_binding_size: (*slot == Slot::Params)
                    .then(|| wgpu::BufferSize::new(info.params_size))
                    .flatten(),
            },
            count: None,
        })
        .collect()
}

/// The pipeline and bind group layout of a kernel on one device (cached in the context).
#[derive(Clone)]
pub(crate) struct CompiledKernel {
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

/// Values of a kernel's pipeline-overridable constants (WGSL `override`), by name.
pub type Overrides<'a> = &'a [(&'static str, f64)];

/// A boolean pipeline-overridable constant (`override NAME: u32`, 0 or 1) set to `on`: the
/// variants of a kernel whose modes are compiled apart.
pub(crate) fn flag_override(name: &'static str, on: bool) -> (&'static str, f64) {
    (name, f64::from(u8::from(on)))
}

/// The value `overrides` gives the integer constant `name`, if any.
pub(crate) fn override_value(overrides: Overrides, name: &str) -> Option<u32> {
    overrides
        .iter()
        .find(|(n, _)| *n == name)
        .map(|&(_, value)| value as u32)
}

/// The constant that sets a kernel's workgroup width where its WGSL declares
/// `override WORKGROUP_WIDTH: u32 = <the declaration's width>;` and
/// `@workgroup_size(WORKGROUP_WIDTH)`. A kernel compiled with it overridden covers its items
/// with workgroups of that width (`Kernel::grid`).
pub const WORKGROUP_WIDTH_OVERRIDE: &str = "WORKGROUP_WIDTH";

/// Workgroup widths the bottom-up climbs can run with (`GpuOptions::climb_width`).
pub const CLIMB_WIDTHS: [u32; 6] = [8, 16, 32, 64, 128, 256];

/// `width` if it is one of `CLIMB_WIDTHS`, else a clear error.
pub fn check_climb_width(width: u32) -> Result<u32> {
    crate::error::one_of("climb width", width, &CLIMB_WIDTHS)
}

/// The climb width on a device of this type: 64 on GPUs (two warps; a barrier is cheap there);
/// on a CPU device its SIMD width, 8 (lavapipe's subgroup size with 256-bit vectors). The climbs
/// step their loop together, a barrier per step, and a CPU device runs a workgroup as SIMD
/// batches that switch at every barrier: one batch per workgroup switches none (lavapipe,
/// conference: `lbvh_climb` about 70 -> 55 ms, the first round's `nodes_level` 82 -> 72 ms).
pub fn default_climb_width(device: wgpu::DeviceType) -> u32 {
    match device {
        wgpu::DeviceType::Cpu => 8,
        _ => 64,
    }
}

pub(crate) fn compile(ctx: &GpuContext, info: &KernelInfo, overrides: Overrides) -> CompiledKernel {
    let layout = ctx
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(info.name),
            entries: &layout_entries(info),
        });
    let pipeline_layout = ctx
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(info.name),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(info.name),
            source: wgpu::ShaderSource::Wgsl(shader_source(info.source, overrides).into()),
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(info.name),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(info.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: overrides,
                ..Default::default()
            },
            cache: None,
        });
    CompiledKernel { pipeline, layout }
}

/// Bind groups kept per kernel: a few buffer sets recur every frame (ping-pong buffers, levels).
const BIND_GROUP_CACHE: usize = 8;

/// A kernel ready to dispatch on one device (see `Pass::dispatch`).
pub struct Kernel<P> {
    pub(crate) info: &'static KernelInfo,
    pub(crate) compiled: CompiledKernel,
    /// Invocations per workgroup along x: the declaration's, or `WORKGROUP_WIDTH_OVERRIDE`'s.
    width: u32,
    /// Bind groups by bound buffers (parameter slab chunk first), most recent last.
    bind_groups: Mutex<Vec<(Vec<wgpu::Buffer>, wgpu::BindGroup)>>,
    params: PhantomData<fn(P)>,
}

impl<P: Pod> Kernel<P> {
    /// The kernel of `decl` on `ctx`'s device (compiled on first use per device).
    pub fn new(ctx: &GpuContext, decl: &'static KernelDecl<P>) -> Self {
        Self::with_overrides(ctx, decl, &[])
    }

    /// The kernel of `decl` with its pipeline-overridable constants set (compiled on first use
    /// per device and values; the driver compiles the values in, as it does constants).
    pub fn with_overrides(
        ctx: &GpuContext,
        decl: &'static KernelDecl<P>,
        overrides: Overrides,
    ) -> Self {
        let width = override_value(overrides, WORKGROUP_WIDTH_OVERRIDE)
            .unwrap_or(decl.info.workgroup_size[0]);
        Self {
            info: &decl.info,
            compiled: ctx.compiled_kernel(&decl.info, overrides),
            width,
            bind_groups: Mutex::default(),
            params: PhantomData,
        }
    }

    /// A bottom-up climb's kernel (its WGSL sets `@workgroup_size(WORKGROUP_WIDTH)`) at
    /// `ctx.climb_width()`; at the declared width it is the plain kernel.
    pub fn climb(ctx: &GpuContext, decl: &'static KernelDecl<P>) -> Self {
        let width = ctx.climb_width();
        if width == decl.info.workgroup_size[0] {
            Self::new(ctx, decl)
        } else {
            Self::with_overrides(ctx, decl, &[(WORKGROUP_WIDTH_OVERRIDE, f64::from(width))])
        }
    }

    /// The grid that covers `items` invocations along x (2D past the per-dimension limit).
    pub fn grid(&self, ctx: &GpuContext, items: u32) -> Grid {
        Grid::items(ctx, items, self.width)
    }

    /// The bind group over `buffers` (parameter chunk first), cached.
    pub(crate) fn bind_group(
        &self,
        ctx: &GpuContext,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        assert_eq!(
            buffers.len(),
            self.info.slots.len(),
            "{}::{}: {} buffers for {} bindings",
            self.info.name,
            self.info.entry,
            buffers.len() - 1,
            self.info.slots.len() - 1
        );
        let mut cache = self.bind_groups.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, group)) = cache
            .iter()
            .find(|(key, _)| key.iter().eq(buffers.iter().copied()))
        {
            return group.clone();
        }
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: binding as u32,
                resource: if binding == 0 {
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset: 0,
                        size: wgpu::BufferSize::new(self.info.params_size),
                    })
                } else {
                    buffer.as_entire_binding()
                },
            })
            .collect();
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.info.name),
            layout: &self.compiled.layout,
            entries: &entries,
        });
        if cache.len() == BIND_GROUP_CACHE {
            cache.remove(0);
        }
        cache.push((buffers.iter().map(|&b| b.clone()).collect(), group.clone()));
        group
    }
}

/// Parameters of a kernel with one invocation per item (WGSL twin `Items` in
/// `shaders/include/items.wgsl`): the item count and the invocations per grid row.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, bytemuck::Zeroable, PartialEq, Eq)]
pub struct Items {
    pub count: u32,
    pub row_pitch: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<Items>() == 16);

impl Items {
    pub fn new(count: u32, grid: Grid) -> Self {
        Self {
            count,
            row_pitch: grid.row_pitch,
            _pad: [0; 2],
        }
    }
}

/// A dispatch's workgroup grid, and the invocations per grid row (`row_pitch`): kernels compute
/// their linear index as `gid.x + gid.y * row_pitch`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    pub groups: [u32; 3],
    pub row_pitch: u32,
}

impl Grid {
    /// `items` invocations in workgroups of `workgroup_size`: 1D up to the device's
    /// per-dimension limit, then 2D (at least one workgroup).
    pub fn items(ctx: &GpuContext, items: u32, workgroup_size: u32) -> Self {
        let max = ctx.device.limits().max_compute_workgroups_per_dimension;
        Self::items_capped(items, workgroup_size, max)
    }

    /// `items` invocations, at most `max` workgroups per dimension.
    pub fn items_capped(items: u32, workgroup_size: u32, max: u32) -> Self {
        let groups = items.div_ceil(workgroup_size).max(1);
        let (x, y) = if groups <= max {
            (groups, 1)
        } else {
            let y = groups.div_ceil(max);
            (groups.div_ceil(y), y)
        };
        Self {
            groups: [x, y, 1],
            row_pitch: x * workgroup_size,
        }
    }

    /// An explicit grid of workgroups (x, y).
    pub fn workgroups(x: u32, y: u32) -> Self {
        Self {
            groups: [x, y, 1],
            row_pitch: 0,
        }
    }
}
