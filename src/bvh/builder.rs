//! The builders a user can choose by name, and one entry point that builds a scene's tree with any
//! of them (through `TreeUpdater`, the one dispatch point over builders) into GPU buffers ready to
//! trace, with timings.

use std::time::Instant;

use super::lbvh::{KeyWidth, TRBVH_KEY_BITS};
use super::treelet::{RoundSchedule, TreeletSettings};
use super::tuning::{tune_updater, TunedSchedule, TuningOptions};
use super::update::{TreeUpdater, UpdateMode};
use super::wide::{check_leaf_sizes, Layout, WideConverter, WideOptions};
use super::{build_sbvh, build_sweep_sah, Bvh, SahParams};
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, GpuTimer, ParamSlab, Recorder, StageTime, Timing, Warmup};
use crate::scene::Scene;
use crate::{Error, Result};

/// A BVH construction method, selectable by name on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// CPU full-sweep SAH (greedy top-down): the quality reference.
    Sweep,
    /// CPU SBVH (Stich et al. 2009): object + spatial splits, the reference for split-aware
    /// builders; a triangle may be referenced by several leaves.
    Sbvh,
    /// GPU LBVH (Karras 2012): Morton order, one primitive per leaf.
    Lbvh,
    /// GPU TRBVH (Karras & Aila 2013): LBVH + treelet restructuring rounds + leaf collapse.
    Trbvh(TreeletSettings),
    /// GPU TRBVH over pre-split triangles (paper §5; `split_percent` of the settings).
    TrbvhSplit(TreeletSettings),
}

/// The pre-splitting budget of `trbvh-split` when none is given: β = 0.3, as in the paper.
pub const DEFAULT_SPLIT_PERCENT: u32 = 30;

/// Build timings. For GPU builders `build_ms` is the sum of the GPU stage times (timestamp
/// queries; wall-clock time where the device has none) of the median timed build, `builds_ms`
/// every timed build's; for CPU builders (timed once, no warm-up) it is CPU time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildReport {
    pub build_ms: f64,
    pub wall_ms: f64,
    pub stages: Vec<StageTime>,
    pub builds_ms: Vec<f64>,
    pub warmup: Warmup,
    /// GPU builders built with a tuned schedule: the tuning (its schedule is the one timed).
    pub tuned: Option<TunedSchedule>,
}

impl Builder {
    pub const ALL: &[Builder] = &[
        Builder::Sweep,
        Builder::Sbvh,
        Builder::Lbvh,
        Builder::Trbvh(TreeletSettings::BALANCED),
        Builder::TrbvhSplit(TreeletSettings {
            split_percent: DEFAULT_SPLIT_PERCENT,
            ..TreeletSettings::BALANCED
        }),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Builder::Sweep => "sweep",
            Builder::Sbvh => "sbvh",
            Builder::Lbvh => "lbvh",
            Builder::Trbvh(_) => "trbvh",
            Builder::TrbvhSplit(_) => "trbvh-split",
        }
    }

    /// Whether the builder runs on the GPU (the per-frame path) rather than as a CPU reference.
    pub fn is_gpu(self) -> bool {
        matches!(
            self,
            Builder::Lbvh | Builder::Trbvh(_) | Builder::TrbvhSplit(_)
        )
    }

    /// The Morton key bits a GPU builder sorts for `prims` primitives (its references, for
    /// `trbvh-split`): `lbvh` 44, narrowed past 2^20 primitives (`KeyWidth::LBVH`), the treelet
    /// builders 32; None for the CPU builders.
    pub fn morton_key_bits(self, prims: u32) -> Option<u32> {
        match self {
            Builder::Lbvh => Some(KeyWidth::LBVH.bits(prims)),
            Builder::Trbvh(_) | Builder::TrbvhSplit(_) => Some(TRBVH_KEY_BITS),
            Builder::Sweep | Builder::Sbvh => None,
        }
    }

    /// Whether the builder may reference a triangle from several leaves (spatial splits): its
    /// trees are checked with [`super::validate_with_references`] instead of [`super::validate`].
    pub fn duplicates_references(self) -> bool {
        matches!(self, Builder::Sbvh | Builder::TrbvhSplit(_))
    }

    /// The same builder with other treelet settings (no effect on builders without treelets;
    /// `trbvh` never splits, `trbvh-split` always does).
    pub fn with_treelet_settings(self, settings: TreeletSettings) -> Self {
        match self {
            Builder::Trbvh(_) => Builder::Trbvh(TreeletSettings {
                split_percent: 0,
                ..settings
            }),
            Builder::TrbvhSplit(_) => Builder::TrbvhSplit(TreeletSettings {
                split_percent: settings.split_percent.max(1),
                ..settings
            }),
            other => other,
        }
    }

    /// The treelet settings of treelet builders.
    pub fn treelet_settings(self) -> Option<TreeletSettings> {
        match self {
            Builder::Trbvh(s) | Builder::TrbvhSplit(s) => Some(s),
            _ => None,
        }
    }

    /// "trbvh n=7 r=3" style label for reports ("trbvh n=7 r=3 last=5" with a last round of
    /// other treelets).
    pub fn label(self) -> String {
        let last = |s: TreeletSettings| {
            let last = match s.last_round_treelets() {
                Some(size) if !s.one_treelet_size() => format!(" last={size}"),
                _ => String::new(),
            };
            match (s.phases, s.round_phases(0)) {
                (Some(phases), Some(first)) if first != phases => {
                    format!("{last} p={first},{phases}")
                }
                (Some(phases), _) => format!("{last} p={phases}"),
                _ => last,
            }
        };
        match self {
            Builder::Trbvh(s) => format!("trbvh n={} r={}{}", s.treelet_size, s.rounds, last(s)),
            Builder::TrbvhSplit(s) => format!(
                "trbvh-split n={} r={}{} b={:.2}",
                s.treelet_size,
                s.rounds,
                last(s),
                f64::from(s.split_percent) / 100.0
            ),
            other => other.name().to_string(),
        }
    }

    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|b| b.name() == name)
            .ok_or_else(|| {
                let known: Vec<_> = Self::ALL.iter().map(|b| b.name()).collect();
                Error::InvalidArgument(format!(
                    "unknown builder '{name}' (known: {})",
                    known.join(", ")
                ))
            })
    }

    /// Uploads `scene` and builds its tree in `layout`, ready to trace. GPU builders run the
    /// untimed warm-up builds of `timing` (pipeline compilation, GPU clocks) and then
    /// `timing.repeats` timed builds, each submitted and waited for, reporting the one with the
    /// median time; the wide layout's conversion is one of their stages ("wide"). CPU builders
    /// are timed once, and their upload is converted once on the GPU (timed as "wide").
    /// `wide` sets the wide conversion (its collapse and level dispatches); `schedule` spreads the
    /// treelet rounds over the device (trbvh, trbvh-split); with `tuning`, GPU builders tune their
    /// build schedule from these after the warm-up (`tune_schedule`) and time the one they keep.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        self,
        ctx: &GpuContext,
        scene: &Scene,
        params: &SahParams,
        timing: &Timing,
        layout: Layout,
        wide: WideOptions,
        schedule: RoundSchedule,
        tuning: Option<&TuningOptions>,
    ) -> Result<(Geometry, Tree, BuildReport)> {
        let geometry = Geometry::upload(ctx, scene)?;
        match self {
            Builder::Sweep => {
                let converter = wide_converter(ctx, params, layout, wide);
                cpu_build(ctx, geometry, "cpu sweep", converter, || {
                    build_sweep_sah(&scene.triangles, params)
                })
            }
            Builder::Sbvh => {
                let converter = wide_converter(ctx, params, layout, wide);
                cpu_build(ctx, geometry, "cpu sbvh", converter, || {
                    build_sbvh(&scene.triangles, params)
                })
            }
            Builder::Lbvh | Builder::Trbvh(_) | Builder::TrbvhSplit(_) => {
                let mut tree = Tree::empty(ctx)?;
                let mut updater = TreeUpdater::new(ctx, UpdateMode::Rebuild(self), params)?;
                updater.set_wide_options(wide);
                updater.set_layout(ctx, layout);
                updater.set_round_schedule(schedule);
                let mut slab = ParamSlab::new(ctx);
                let triangles = &scene.triangles;
                // One build, submitted (timed by `timer` where given); the updater and the tree
                // are passed in, so that the tuning can use them between builds.
                let mut build_once = |updater: &mut TreeUpdater,
                                      tree: &mut Tree,
                                      timer: Option<&mut GpuTimer>|
                 -> Result<()> {
                    let mut rec = Recorder::new(ctx, &mut slab, timer);
                    let result = updater.record(&mut rec, &geometry, triangles, tree);
                    rec.submit();
                    result.map(drop)
                };
                let warmup = timing.warm_up(|| {
                    build_once(&mut updater, &mut tree, None)?;
                    ctx.device
                        .poll(wgpu::PollType::wait_indefinitely())
                        .map_err(|e| Error::Gpu(format!("device poll failed: {e}")))
                        .map(drop)
                })?;
                let tuned = match tuning {
                    Some(options) => tune_updater(
                        ctx,
                        &mut updater,
                        &geometry,
                        triangles,
                        &mut tree,
                        options,
                        0.0,
                    )?,
                    None => None,
                };
                let passes = updater.pass_count();
                let mut reports = Vec::new();
                for _ in 0..timing.repeats.max(1) {
                    let mut timer = GpuTimer::new(ctx, passes);
                    let start = Instant::now();
                    build_once(&mut updater, &mut tree, Some(&mut timer))?;
                    let stages = timer.read(ctx)?;
                    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                    let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
                    reports.push(BuildReport {
                        build_ms: gpu_ms.unwrap_or(wall_ms),
                        wall_ms,
                        stages,
                        ..BuildReport::default()
                    });
                }
                let builds_ms: Vec<f64> = reports.iter().map(|r| r.build_ms).collect();
                reports.sort_by(|a, b| a.build_ms.total_cmp(&b.build_ms));
                let median = reports.swap_remove(reports.len() / 2);
                Ok((
                    geometry,
                    tree,
                    BuildReport {
                        builds_ms,
                        warmup,
                        tuned,
                        ..median
                    },
                ))
            }
        }
    }
}

/// The wide conversion of `layout` (none for the binary layout).
fn wide_converter(
    ctx: &GpuContext,
    params: &SahParams,
    layout: Layout,
    wide: WideOptions,
) -> Option<WideConverter> {
    (layout == Layout::Wide).then(|| {
        let mut converter = WideConverter::new(ctx, params);
        converter.set_options(wide);
        converter
    })
}

/// Runs a CPU builder once (timed, CPU time) and uploads its tree; with a `converter` (the wide
/// layout) the upload is converted on the GPU (its time added as stage "wide").
fn cpu_build(
    ctx: &GpuContext,
    geometry: Geometry,
    label: &str,
    converter: Option<WideConverter>,
    build: impl FnOnce() -> Bvh,
) -> Result<(Geometry, Tree, BuildReport)> {
    let start = Instant::now();
    let bvh = build();
    let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut tree = Tree::upload(ctx, &bvh)?;
    let mut stages = vec![StageTime::cpu(label, cpu_ms)];
    if let Some(converter) = converter {
        check_leaf_sizes(&bvh)?;
        let mut timer = GpuTimer::new(ctx, 1);
        let mut slab = ParamSlab::new(ctx);
        let mut rec = Recorder::new(ctx, &mut slab, Some(&mut timer));
        converter.record(&mut rec, &geometry, &mut tree)?;
        rec.submit();
        stages.extend(timer.read(ctx)?);
    }
    let build_ms = stages.iter().filter_map(|s| s.ms).sum();
    let report = BuildReport {
        build_ms,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        stages,
        builds_ms: vec![build_ms],
        warmup: Warmup::default(),
        tuned: None,
    };
    Ok((geometry, tree, report))
}
