//! WGSL sources, embedded at compile time. Kernels live in `shaders/<data>_<op>.wgsl`, shared code in
//! `shaders/include/*.wgsl`, pulled in by `#include "name.wgsl"` lines (each file once).

use super::GpuContext;

/// Shared include files: (file name, source).
const INCLUDES: &[(&str, &str)] = &[
    (
        "bvh_node.wgsl",
        include_str!("../../shaders/include/bvh_node.wgsl"),
    ),
    (
        "bvh_traverse.wgsl",
        include_str!("../../shaders/include/bvh_traverse.wgsl"),
    ),
    (
        "ray_triangle.wgsl",
        include_str!("../../shaders/include/ray_triangle.wgsl"),
    ),
    (
        "random.wgsl",
        include_str!("../../shaders/include/random.wgsl"),
    ),
    ("aabb.wgsl", include_str!("../../shaders/include/aabb.wgsl")),
    (
        "node_words.wgsl",
        include_str!("../../shaders/include/node_words.wgsl"),
    ),
    (
        "radix_digits.wgsl",
        include_str!("../../shaders/include/radix_digits.wgsl"),
    ),
    (
        "bottom_up_climb.wgsl",
        include_str!("../../shaders/include/bottom_up_climb.wgsl"),
    ),
    (
        "split_grid.wgsl",
        include_str!("../../shaders/include/split_grid.wgsl"),
    ),
    (
        "leaf_gather.wgsl",
        include_str!("../../shaders/include/leaf_gather.wgsl"),
    ),
];

/// Every compute kernel: (file name, source before include expansion).
pub const KERNELS: &[(&str, &str)] = &[
    (
        "triangles_priority.wgsl",
        include_str!("../../shaders/triangles_priority.wgsl"),
    ),
    (
        "splits_budget.wgsl",
        include_str!("../../shaders/splits_budget.wgsl"),
    ),
    (
        "triangles_split.wgsl",
        include_str!("../../shaders/triangles_split.wgsl"),
    ),
    (
        "triangles_bounds.wgsl",
        include_str!("../../shaders/triangles_bounds.wgsl"),
    ),
    (
        "treelet_optimize.wgsl",
        include_str!("../../shaders/treelet_optimize.wgsl"),
    ),
    (
        "nodes_mark.wgsl",
        include_str!("../../shaders/nodes_mark.wgsl"),
    ),
    (
        "nodes_compact.wgsl",
        include_str!("../../shaders/nodes_compact.wgsl"),
    ),
    (
        "keys_histogram.wgsl",
        include_str!("../../shaders/keys_histogram.wgsl"),
    ),
    (
        "counts_scan.wgsl",
        include_str!("../../shaders/counts_scan.wgsl"),
    ),
    (
        "counts_add.wgsl",
        include_str!("../../shaders/counts_add.wgsl"),
    ),
    (
        "keys_scatter.wgsl",
        include_str!("../../shaders/keys_scatter.wgsl"),
    ),
    (
        "centroids_reduce.wgsl",
        include_str!("../../shaders/centroids_reduce.wgsl"),
    ),
    (
        "morton_compute.wgsl",
        include_str!("../../shaders/morton_compute.wgsl"),
    ),
    (
        "lbvh_hierarchy.wgsl",
        include_str!("../../shaders/lbvh_hierarchy.wgsl"),
    ),
    (
        "bounds_refit.wgsl",
        include_str!("../../shaders/bounds_refit.wgsl"),
    ),
    (
        "rays_intersect.wgsl",
        include_str!("../../shaders/rays_intersect.wgsl"),
    ),
    (
        "paths_trace.wgsl",
        include_str!("../../shaders/paths_trace.wgsl"),
    ),
    (
        "image_tonemap.wgsl",
        include_str!("../../shaders/image_tonemap.wgsl"),
    ),
    (
        "image_display.wgsl",
        include_str!("../../shaders/image_display.wgsl"),
    ),
    (
        "cloth_animate.wgsl",
        include_str!("../../shaders/cloth_animate.wgsl"),
    ),
    (
        "bodies_animate.wgsl",
        include_str!("../../shaders/bodies_animate.wgsl"),
    ),
    (
        "debris_animate.wgsl",
        include_str!("../../shaders/debris_animate.wgsl"),
    ),
    (
        "nodes_refit.wgsl",
        include_str!("../../shaders/nodes_refit.wgsl"),
    ),
];

/// Full source of kernel `name` with its includes expanded. Panics on an unknown name: the set of
/// kernels is fixed at compile time, so that is a programming error.
pub fn shader_source(name: &str) -> String {
    let (_, source) = KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("unknown kernel {name}"));
    let mut included = Vec::new();
    expand(source, &mut included)
}

fn expand(source: &str, included: &mut Vec<&'static str>) -> String {
    let mut out = String::with_capacity(source.len());
    for line in source.lines() {
        if let Some(rest) = line.trim().strip_prefix("#include") {
            let file = rest.trim().trim_matches('"');
            let (name, text) = INCLUDES
                .iter()
                .find(|(n, _)| *n == file)
                .unwrap_or_else(|| panic!("unknown include {file}"));
            if !included.contains(name) {
                included.push(name);
                out.push_str(&expand(text, included));
            }
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// A compute pipeline for `entry` of kernel `name`, with its bind group layout derived from the
/// shader; compiled on first use and cached in the context.
pub fn compute_pipeline(ctx: &GpuContext, name: &str, entry: &str) -> wgpu::ComputePipeline {
    let key = (name.to_string(), entry.to_string());
    let mut cache = ctx.pipelines.lock().unwrap_or_else(|e| e.into_inner());
    cache
        .entry(key)
        .or_insert_with(|| create_pipeline(ctx, name, entry))
        .clone()
}

fn create_pipeline(ctx: &GpuContext, name: &str, entry: &str) -> wgpu::ComputePipeline {
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(name),
            source: wgpu::ShaderSource::Wgsl(shader_source(name).into()),
        });
    ctx.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(name),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
}
