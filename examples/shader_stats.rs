//! What a GPU driver's compiler makes of each kernel, without running anything: registers,
//! spills, private (scratch) memory, code size and occupancy as the driver reports them through
//! `VK_KHR_pipeline_executable_properties`. The kernels go through naga to SPIR-V with the options
//! wgpu's Vulkan backend uses (index bounds checks that clamp, buffer accesses unchecked where the
//! device has robust buffer access 2, loops bounded, workgroup memory zeroed by the driver), and
//! each becomes a compute pipeline of its declared bindings (`treelet::kernels::ALL`).
//!
//! A machine without a GPU still has a real GPU compiler: Mesa's RADV with a null device
//! (`RADV_FORCE_FAMILY`) compiles for an AMD GPU, and `scripts/shader-stats.sh` runs this example
//! that way. On a lent NVIDIA GPU the same example reports NVIDIA's compiler (the tool library's
//! `.gpu/run.sh` does not pack examples: build it there or add it to the pack). Register
//! pressure and spills are a property of the code, so they can be compared before and after a
//! change where timings cannot.
//!
//! Arguments: kernel names or substrings (default: every kernel), and overridable constants as
//! `NAME=value` (default `TREELET_SIZE=7`, the treelet kernels' only constant without a default).
//!
//! ```text
//! bash scripts/shader-stats.sh wide_nodes paths_trace TREELET_SIZE=8
//! ```
use std::collections::BTreeMap;
use std::ffi::CStr;

use ash::vk;
use treelet::gpu::constants::{MAX_TREELET_SIZE, MIN_TREELET_SIZE};
use treelet::gpu::{shader_source, KernelInfo, Slot};

/// A kernel in SPIR-V as wgpu's Vulkan backend would hand it to the driver.
fn spirv(info: &KernelInfo, overrides: &[(&'static str, f64)]) -> Result<Vec<u32>, String> {
    let source = shader_source(info.source, overrides);
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    let module_info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(&source))?;
    // Only the constants this kernel declares (naga refuses unknown ones).
    let constants: naga::back::PipelineConstants = overrides
        .iter()
        .filter(|(name, _)| {
            module
                .overrides
                .iter()
                .any(|(_, o)| o.name.as_deref() == Some(*name))
        })
        .map(|&(name, value)| (name.to_string(), value))
        .collect();
    let (module, module_info) = naga::back::pipeline_constants::process_overrides(
        &module,
        &module_info,
        Some((naga::ShaderStage::Compute, info.entry)),
        &constants,
    )
    .map_err(|e| e.to_string())?;
    let options = naga::back::spv::Options {
        lang_version: (1, 5),
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: naga::proc::BoundsCheckPolicy::Restrict,
            buffer: naga::proc::BoundsCheckPolicy::Unchecked,
            image_load: naga::proc::BoundsCheckPolicy::Unchecked,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        zero_initialize_workgroup_memory:
            naga::back::spv::ZeroInitializeWorkgroupMemoryMode::Native,
        force_loop_bounding: true,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: info.entry.to_string(),
    };
    naga::back::spv::write_vec(&module, &module_info, &options, Some(&pipeline))
        .map_err(|e| e.to_string())
}

/// One statistic's value as text.
fn value_text(stat: &vk::PipelineExecutableStatisticKHR) -> String {
    // SAFETY: the union member read is the one `format` names.
    unsafe {
        match stat.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => (stat.value.b32 != 0).to_string(),
            vk::PipelineExecutableStatisticFormatKHR::INT64 => stat.value.i64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::UINT64 => stat.value.u64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => format!("{:.2}", stat.value.f64),
            _ => "?".into(),
        }
    }
}

/// A device to compile on. Never destroyed: the process ends after the report (and Mesa's null
/// device crashes in vkDestroyDevice).
struct Driver {
    device: ash::Device,
    executables: ash::khr::pipeline_executable_properties::Device,
    name: String,
}

impl Driver {
    /// The first GPU (not a CPU device) with pipeline executable statistics.
    fn open() -> Result<Self, String> {
        // SAFETY: plain Vulkan setup; every handle outlives its uses (the process ends after).
        unsafe {
            let entry = ash::Entry::load().map_err(|e| format!("no Vulkan loader: {e}"))?;
            let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
            let instance = entry
                .create_instance(
                    &vk::InstanceCreateInfo::default().application_info(&app),
                    None,
                )
                .map_err(|e| format!("vkCreateInstance: {e}"))?;
            let extension = ash::khr::pipeline_executable_properties::NAME;
            for physical in instance
                .enumerate_physical_devices()
                .map_err(|e| e.to_string())?
            {
                let properties = instance.get_physical_device_properties(physical);
                let has_stats = instance
                    .enumerate_device_extension_properties(physical)
                    .unwrap_or_default()
                    .iter()
                    .any(|e| e.extension_name_as_c_str() == Ok(extension));
                if properties.device_type == vk::PhysicalDeviceType::CPU || !has_stats {
                    continue;
                }
                let name = properties
                    .device_name_as_c_str()
                    .map_or("?".into(), |n| n.to_string_lossy().into_owned());
                let priorities = [1.0];
                let queues = [vk::DeviceQueueCreateInfo::default()
                    .queue_family_index(0)
                    .queue_priorities(&priorities)];
                let extensions = [extension.as_ptr()];
                let mut stats =
                    vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
                        .pipeline_executable_info(true);
                let device = instance
                    .create_device(
                        physical,
                        &vk::DeviceCreateInfo::default()
                            .queue_create_infos(&queues)
                            .enabled_extension_names(&extensions)
                            .push_next(&mut stats),
                        None,
                    )
                    .map_err(|e| format!("vkCreateDevice on {name}: {e}"))?;
                let executables =
                    ash::khr::pipeline_executable_properties::Device::new(&instance, &device);
                return Ok(Self {
                    device,
                    executables,
                    name,
                });
            }
            Err(
                "no GPU with VK_KHR_pipeline_executable_properties (without one, run \
                 scripts/shader-stats.sh, which compiles on Mesa's RADV with a null device)"
                    .into(),
            )
        }
    }

    /// Compiles `code` as a pipeline of `info`'s bindings and returns each executable's
    /// statistics (name, value).
    fn statistics(&self, info: &KernelInfo, code: &[u32]) -> Result<Vec<(String, String)>, String> {
        // SAFETY: as in `open`; the objects made here are destroyed before returning.
        unsafe {
            let bindings: Vec<vk::DescriptorSetLayoutBinding> = info
                .slots
                .iter()
                .enumerate()
                .map(|(b, slot)| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b as u32)
                        .descriptor_type(match slot {
                            Slot::Params => vk::DescriptorType::UNIFORM_BUFFER_DYNAMIC,
                            Slot::Read | Slot::ReadWrite => vk::DescriptorType::STORAGE_BUFFER,
                        })
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            let d = &self.device;
            let set_layout = d
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .map_err(|e| e.to_string())?;
            let set_layouts = [set_layout];
            let layout = d
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts),
                    None,
                )
                .map_err(|e| e.to_string())?;
            let module = d
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None)
                .map_err(|e| e.to_string())?;
            let entry = std::ffi::CString::new(info.entry).map_err(|e| e.to_string())?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(&entry);
            let create = vk::ComputePipelineCreateInfo::default()
                .flags(vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR)
                .stage(stage)
                .layout(layout);
            let pipeline = d
                .create_compute_pipelines(vk::PipelineCache::null(), &[create], None)
                .map_err(|(_, e)| format!("vkCreateComputePipelines: {e}"))?[0];
            let mut out = Vec::new();
            let executables = self
                .executables
                .get_pipeline_executable_properties(
                    &vk::PipelineInfoKHR::default().pipeline(pipeline),
                )
                .map_err(|e| e.to_string())?;
            for (index, executable) in executables.iter().enumerate() {
                let which = vk::PipelineExecutableInfoKHR::default()
                    .pipeline(pipeline)
                    .executable_index(index as u32);
                let stats = self
                    .executables
                    .get_pipeline_executable_statistics(&which)
                    .map_err(|e| e.to_string())?;
                let prefix = if executables.len() > 1 {
                    format!(
                        "{}: ",
                        executable
                            .name_as_c_str()
                            .map_or("?".into(), CStr::to_string_lossy)
                    )
                } else {
                    String::new()
                };
                for stat in &stats {
                    let name = stat
                        .name_as_c_str()
                        .map_or("?".into(), CStr::to_string_lossy);
                    out.push((format!("{prefix}{name}"), value_text(stat)));
                }
            }
            d.destroy_pipeline(pipeline, None);
            d.destroy_shader_module(module, None);
            d.destroy_pipeline_layout(layout, None);
            d.destroy_descriptor_set_layout(set_layout, None);
            Ok(out)
        }
    }
}

fn main() {
    let mut filters = Vec::new();
    let mut overrides: BTreeMap<&'static str, f64> = BTreeMap::from([("TREELET_SIZE", 7.0)]);
    for arg in std::env::args().skip(1) {
        match arg.split_once('=') {
            Some((name, value)) => match value.parse::<f64>() {
                Ok(value) => {
                    overrides.insert(String::leak(name.to_string()), value);
                }
                Err(_) => {
                    eprintln!("error: {arg}: the value of an overridable constant is a number");
                    std::process::exit(2);
                }
            },
            None => filters.push(arg),
        }
    }
    let sizes = f64::from(MIN_TREELET_SIZE)..=f64::from(MAX_TREELET_SIZE);
    if !sizes.contains(&overrides["TREELET_SIZE"]) {
        eprintln!("error: TREELET_SIZE must be {MIN_TREELET_SIZE}..={MAX_TREELET_SIZE}");
        std::process::exit(2);
    }
    let overrides: Vec<(&'static str, f64)> = overrides.into_iter().collect();
    let driver = match Driver::open() {
        Ok(driver) => driver,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let kernels: Vec<_> = treelet::kernels::ALL
        .iter()
        .filter(|info| filters.is_empty() || filters.iter().any(|f| info.name.contains(f.as_str())))
        .collect();
    if kernels.is_empty() {
        eprintln!("error: no kernel's name contains any of {filters:?}");
        std::process::exit(2);
    }
    println!("# {} {overrides:?}", driver.name);
    let mut failed = false;
    for info in kernels {
        let stats = spirv(info, &overrides).and_then(|code| driver.statistics(info, &code));
        match stats {
            Ok(stats) => {
                let fields: Vec<String> = stats
                    .iter()
                    .map(|(name, value)| format!("{name}={value}"))
                    .collect();
                println!("{}: {}", info.name, fields.join(", "));
            }
            Err(e) => {
                failed = true;
                println!("{}: error: {e}", info.name);
            }
        }
    }
    if failed {
        std::process::exit(1);
    }
}
