//! Device creation: adapter selection (discrete GPU first, or one picked by name), explicit
//! features and limits, and a one-line description of what was chosen.

use std::collections::HashMap;
use std::sync::Mutex;

use wgpu::util::DeviceExt;

use super::kernel::{compile, CompiledKernel, KernelInfo, Overrides, Slot};
use crate::{Error, Result};

/// How to choose the adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Case-insensitive substring of the adapter name to use (also read from `TREELET_ADAPTER`).
    pub adapter: Option<String>,
    /// Time every dispatch on its own (`GpuTimer`): a profiling mode for `bench`.
    pub profile_dispatches: bool,
    /// Keys per invocation of every radix sort's tile (one of `sort::SORT_TILE_ITEMS`), instead of
    /// `sort::tile_items` of the length and device: for `bench` to compare them.
    pub sort_tile_items: Option<u32>,
    /// Workgroup width of the bottom-up climbs (one of `gpu::CLIMB_WIDTHS`) instead of the
    /// device's default (`gpu::default_climb_width`): for `bench` to compare them, and for tests to
    /// run a GPU's width on a CPU device.
    pub climb_width: Option<u32>,
}

/// An open device with what the rest of the crate needs to know about it.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Timestamp queries are available (otherwise timings read "n/a").
    pub timestamps: bool,
    /// Timers time every dispatch in a pass of its own (`GpuOptions::profile_dispatches`).
    pub profile_dispatches: bool,
    /// `GpuOptions::sort_tile_items`.
    pub sort_tile_items: Option<u32>,
    /// `GpuOptions::climb_width`.
    pub climb_width: Option<u32>,
    /// Kernels by (file, entry point, overridden constants with their values' bits), compiled
    /// once per device.
    kernels: Mutex<HashMap<KernelKey, CompiledKernel>>,
    /// The `count_limit` of kernels whose item count is known when recording (`ItemCount`):
    /// one u32, u32::MAX.
    pub(crate) no_count_limit: wgpu::Buffer,
}

/// A compiled kernel's cache key: file, entry point, and the overridden constants.
type KernelKey = (&'static str, &'static str, Vec<(&'static str, u64)>);

/// Preference order of adapter types: discrete GPUs first, software rasterizers last.
fn type_rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The flags of every wgpu instance treelet opens: wgpu's for the build type and its environment
/// variables (`WGPU_VALIDATION`, ...), but without wgpu's validation of indirect dispatch
/// arguments unless `WGPU_VALIDATION_INDIRECT_CALL=1` asks for it. That validation runs a
/// dispatch of its own before each indirect dispatch, between two barriers, and rebinds the pass's
/// pipeline and bind groups, while every indirect argument of the crate comes from its own kernels
/// within the limit it guards (at most 65535 workgroups per dimension: `nodes_level.wgsl` and
/// `treelet_waves.wgsl` spread a larger count over y, `wide_nodes_emit.wgsl` caps x and strides).
/// A treelet build dispatches each level indirectly, so it would otherwise run twice as many
/// dispatches there.
pub fn instance_flags() -> wgpu::InstanceFlags {
    (wgpu::InstanceFlags::from_build_config() - wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL)
        .with_env()
}

impl GpuContext {
    /// Opens a device without a window (headless rendering, benchmarks, tests).
    pub fn new(options: &GpuOptions) -> Result<Self> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.flags = instance_flags();
        Self::with_instance(wgpu::Instance::new(descriptor), options, None)
    }

    /// Opens a device on `instance`, able to present to `surface` when given.
    pub fn with_instance(
        instance: wgpu::Instance,
        options: &GpuOptions,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self> {
        let adapter = pollster::block_on(Self::select_adapter(&instance, options, surface))?;
        let info = adapter.get_info();
        // Timestamps for the stage and dispatch timings; no kernel uses another optional feature.
        let wanted =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let features = adapter.features() & wanted;
        let required_limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("treelet"),
            required_features: features,
            required_limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::Gpu(format!("cannot open device on {}: {e}", info.name)))?;
        log::info!(
            "adapter: {} ({:?}, {:?}), driver {} {}",
            info.name,
            info.device_type,
            info.backend,
            info.driver,
            info.driver_info
        );
        if let Some(items) = options.sort_tile_items {
            crate::sort::check_tile_items(items)?;
        }
        if let Some(width) = options.climb_width {
            super::kernel::check_climb_width(width)?;
        }
        Ok(Self {
            profile_dispatches: options.profile_dispatches,
            sort_tile_items: options.sort_tile_items,
            climb_width: options.climb_width,
            ..Self::from_device(adapter, device, queue)?
        })
    }

    /// The limits a device needs for every kernel of the crate: wgpu's defaults, with as many
    /// storage buffers per shader stage as the kernel with the most bindings has. (Larger scenes
    /// need larger `max_storage_buffer_binding_size` and `max_buffer_size`; buffers are checked
    /// against the device's limits when created.)
    pub fn required_limits() -> wgpu::Limits {
        let storage_buffers = crate::kernels::ALL
            .iter()
            .map(|k| k.slots.iter().filter(|s| **s != Slot::Params).count() as u32)
            .max()
            .unwrap_or(0);
        wgpu::Limits {
            max_storage_buffers_per_shader_stage: storage_buffers,
            ..wgpu::Limits::default()
        }
    }

    /// Wraps a device the caller opened (e.g. a renderer that shares its buffers with the
    /// builders: see `device::Geometry::from_buffer`). Fails with a clear error when the device's
    /// limits are below `required_limits`. Timestamps are used when the device has the
    /// `TIMESTAMP_QUERY` and `TIMESTAMP_QUERY_INSIDE_ENCODERS` features.
    pub fn from_device(
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self> {
        let info = adapter.get_info();
        let mut short = Vec::new();
        Self::required_limits().check_limits_with_fail_fn(
            &device.limits(),
            false,
            |name, needed, allowed| short.push(format!("{name} is {allowed}, needs {needed}")),
        );
        if !short.is_empty() {
            return Err(Error::Gpu(format!(
                "the device's limits are too low for treelet's kernels ({}); request \
                 GpuContext::required_limits() when opening it",
                short.join(", ")
            )));
        }
        let timestamps = device.features().contains(
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        );
        let no_count_limit = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("no count limit"),
            contents: bytemuck::bytes_of(&u32::MAX),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Ok(Self {
            no_count_limit,
            adapter,
            device,
            queue,
            timestamps,
            profile_dispatches: false,
            sort_tile_items: None,
            climb_width: None,
            info,
            kernels: Mutex::default(),
        })
    }

    async fn select_adapter(
        instance: &wgpu::Instance,
        options: &GpuOptions,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<wgpu::Adapter> {
        let wanted_name = options
            .adapter
            .clone()
            .or_else(|| std::env::var("TREELET_ADAPTER").ok())
            .map(|s| s.to_lowercase());
        let mut adapters: Vec<wgpu::Adapter> = instance
            .enumerate_adapters(wgpu::Backends::all())
            .await
            .into_iter()
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .collect();
        if adapters.is_empty() {
            return Err(Error::Gpu(
                "no GPU adapter found: install a Vulkan driver (on Debian/Ubuntu run scripts/install-deps.sh, which installs Mesa's software driver)".into(),
            ));
        }
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        if let Some(wanted) = wanted_name {
            return adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
                .ok_or_else(|| {
                    Error::Gpu(format!(
                        "no adapter matches '{wanted}'; available: {}",
                        names.join(", ")
                    ))
                });
        }
        adapters.sort_by_key(|a| {
            let info = a.get_info();
            // Vulkan before other backends on the same device: it is what the project is tested on.
            (
                type_rank(info.device_type),
                info.backend != wgpu::Backend::Vulkan,
            )
        });
        Ok(adapters.swap_remove(0))
    }

    /// "name (backend, driver)" for logs, JSON and the viewer.
    pub fn adapter_description(&self) -> String {
        format!(
            "{} ({:?}, {} {})",
            self.info.name, self.info.backend, self.info.driver, self.info.driver_info
        )
    }

    /// The pipeline and bind group layout of a kernel, compiled on first use.
    pub(crate) fn compiled_kernel(
        &self,
        info: &'static KernelInfo,
        overrides: Overrides,
    ) -> CompiledKernel {
        let key = (
            info.name,
            info.entry,
            overrides.iter().map(|&(n, v)| (n, v.to_bits())).collect(),
        );
        let mut kernels = self.kernels.lock().unwrap_or_else(|e| e.into_inner());
        kernels
            .entry(key)
            .or_insert_with(|| compile(self, info, overrides))
            .clone()
    }

    /// Workgroup width of the bottom-up climbs: `GpuOptions::climb_width`, else the device's
    /// default (`gpu::default_climb_width`).
    pub fn climb_width(&self) -> u32 {
        self.climb_width
            .unwrap_or_else(|| super::default_climb_width(self.info.device_type))
    }

    /// Largest storage buffer binding this device accepts, in bytes.
    pub fn max_storage_binding(&self) -> u64 {
        self.device.limits().max_storage_buffer_binding_size
    }
}

#[cfg(test)]
mod tests {
    use super::instance_flags;

    /// wgpu's indirect validation is off unless its environment variable asks for it (set to
    /// anything but "0"); wgpu's other flags for the build type are kept.
    #[test]
    fn indirect_validation_only_on_request() {
        let asked = std::env::var("WGPU_VALIDATION_INDIRECT_CALL").is_ok_and(|v| v != "0");
        let flags = instance_flags();
        assert_eq!(
            flags.contains(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL),
            asked
        );
        let others = wgpu::InstanceFlags::from_build_config().with_env()
            - wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL;
        assert_eq!(
            flags - wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL,
            others
        );
    }
}
