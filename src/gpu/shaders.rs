//! WGSL sources, embedded at compile time. Kernels live in `shaders/<data>_<op>.wgsl` (declared
//! with `kernel!`), shared code in `shaders/include/*.wgsl`, pulled in by `#include "name.wgsl"`
//! lines (each file once), the shared constants in the generated `constants.wgsl` and the
//! written-out treelet DP in the generated `treelet_dp_unrolled.wgsl` (`bvh::treelet::dp_unrolled`).

use super::Overrides;

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
        "box_words.wgsl",
        include_str!("../../shaders/include/box_words.wgsl"),
    ),
    (
        "box_reduce.wgsl",
        include_str!("../../shaders/include/box_reduce.wgsl"),
    ),
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
        "radix_climb.wgsl",
        include_str!("../../shaders/include/radix_climb.wgsl"),
    ),
    (
        "split_grid.wgsl",
        include_str!("../../shaders/include/split_grid.wgsl"),
    ),
    (
        "scan_blocks.wgsl",
        include_str!("../../shaders/include/scan_blocks.wgsl"),
    ),
    (
        "workgroup_scan.wgsl",
        include_str!("../../shaders/include/workgroup_scan.wgsl"),
    ),
    (
        "splits_search.wgsl",
        include_str!("../../shaders/include/splits_search.wgsl"),
    ),
    (
        "items.wgsl",
        include_str!("../../shaders/include/items.wgsl"),
    ),
    (
        "treelet_waves.wgsl",
        include_str!("../../shaders/include/treelet_waves.wgsl"),
    ),
    (
        "treelet_wave_optimize.wgsl",
        include_str!("../../shaders/include/treelet_wave_optimize.wgsl"),
    ),
    (
        "treelet_round.wgsl",
        include_str!("../../shaders/include/treelet_round.wgsl"),
    ),
    (
        "treelet_arguments.wgsl",
        include_str!("../../shaders/include/treelet_arguments.wgsl"),
    ),
    (
        "treelet_roots.wgsl",
        include_str!("../../shaders/include/treelet_roots.wgsl"),
    ),
    (
        "treelet_wave_bindings.wgsl",
        include_str!("../../shaders/include/treelet_wave_bindings.wgsl"),
    ),
    (
        "unfused.wgsl",
        include_str!("../../shaders/include/unfused.wgsl"),
    ),
    (
        "ray_box.wgsl",
        include_str!("../../shaders/include/ray_box.wgsl"),
    ),
    (
        "wide_node.wgsl",
        include_str!("../../shaders/include/wide_node.wgsl"),
    ),
    (
        "wide_traverse.wgsl",
        include_str!("../../shaders/include/wide_traverse.wgsl"),
    ),
    (
        "wide_collapse.wgsl",
        include_str!("../../shaders/include/wide_collapse.wgsl"),
    ),
    (
        "ray_queries.wgsl",
        include_str!("../../shaders/include/ray_queries.wgsl"),
    ),
    (
        "path_integrator.wgsl",
        include_str!("../../shaders/include/path_integrator.wgsl"),
    ),
    (
        "collapse_choices.wgsl",
        include_str!("../../shaders/include/collapse_choices.wgsl"),
    ),
    (
        "treelet_dp.wgsl",
        include_str!("../../shaders/include/treelet_dp.wgsl"),
    ),
    (
        "treelet_team.wgsl",
        include_str!("../../shaders/include/treelet_team.wgsl"),
    ),
    (
        "triangle_pieces.wgsl",
        include_str!("../../shaders/include/triangle_pieces.wgsl"),
    ),
];

/// The text of a generated include for a pipeline's override values.
type Generate = fn(Overrides) -> String;

/// Generated include files: (file name, how its text is generated).
const GENERATED: &[(&str, Generate)] = &[
    ("constants.wgsl", |_| super::constants::wgsl()),
    (
        "treelet_dp_unrolled.wgsl",
        crate::bvh::treelet::dp_unrolled::wgsl_for,
    ),
];

/// `source` with its includes expanded (each file once) for a pipeline with these override
/// values; `GENERATED` includes are generated for them (`constants.wgsl`, and
/// `treelet_dp_unrolled.wgsl` for the override `TREELET_SIZE`). Panics on an unknown include:
/// the set is fixed at compile time, and `tests/shaders.rs` expands every kernel.
pub fn shader_source(source: &str, overrides: Overrides) -> String {
    let mut included = Vec::new();
    expand(source, overrides, &mut included)
}

fn expand(source: &str, overrides: Overrides, included: &mut Vec<String>) -> String {
    let mut out = String::with_capacity(source.len());
    for line in source.lines() {
        if let Some(rest) = line.trim().strip_prefix("#include") {
            let file = rest.trim().trim_matches('"');
            if included.iter().any(|f| f == file) {
                continue;
            }
            included.push(file.to_string());
            if let Some((_, generate)) = GENERATED.iter().find(|(n, _)| *n == file) {
                out.push_str(&generate(overrides));
            } else {
                let (_, text) = INCLUDES
                    .iter()
                    .find(|(n, _)| *n == file)
                    .unwrap_or_else(|| panic!("unknown include {file}"));
                out.push_str(&expand(text, overrides, included));
            }
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}
