//! How a frame's tree is produced — the one dispatch point over every way: a GPU builder
//! rebuilds it (LBVH, TRBVH, TRBVH with pre-splitting), a CPU reference builder builds it and
//! uploads it, or a refit keeps the topology of the tree built at the first frame and recomputes
//! its boxes (`nodes_refit`). `UpdateMode` names the choice, `TreeUpdater` carries it out; for
//! the wide layout it then converts the binary tree on the GPU (`wide::WideConverter`, pass
//! "wide"), every frame.

use std::time::Instant;

use super::lbvh::{LbvhBuilder, LBVH_PASSES};
use super::nodes_refit::{derive_refit_links, NodesRefit};
use super::treelet::{overlap_reach, RoundSchedule, TrbvhBuilder, TreeletSettings};
use super::tuning::{BuildSchedule, TuningSpace};
use super::wide::{Layout, WideCollapse, WideConverter, WideOptions, MAX_WIDE_LEAF_SIZE};
use super::{build_sbvh, build_sweep_sah, Builder, SahParams};
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, Recorder, StageTime};
use crate::scene::Triangle;
use crate::sort::context_tile_items;
use crate::{Error, Result};

/// The per-frame tree update of an animated scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpdateMode {
    /// Build a new tree every frame with this builder.
    Rebuild(Builder),
    /// Build a tree with this (GPU) builder at the first frame, then refit its boxes.
    Refit(Builder),
}

impl UpdateMode {
    /// The refit modes offered by name: over the LBVH and over the TRBVH tree of the first frame.
    pub const REFITS: &[UpdateMode] = &[
        UpdateMode::Refit(Builder::Lbvh),
        UpdateMode::Refit(Builder::Trbvh(TreeletSettings::BALANCED)),
    ];

    /// Every mode by name: each builder's rebuild, then the refits.
    pub fn all() -> Vec<UpdateMode> {
        Builder::ALL
            .iter()
            .map(|&b| UpdateMode::Rebuild(b))
            .chain(Self::REFITS.iter().copied())
            .collect()
    }

    /// `lbvh`, `trbvh`, … for rebuilds; `refit` (LBVH topology) and `refit-trbvh` for refits.
    pub fn name(self) -> &'static str {
        match self {
            UpdateMode::Rebuild(b) => b.name(),
            UpdateMode::Refit(Builder::Trbvh(_)) => "refit-trbvh",
            UpdateMode::Refit(_) => "refit",
        }
    }

    /// A longer label for reports: the treelet settings of trbvh, the topology of refits.
    pub fn label(self) -> String {
        match self {
            UpdateMode::Rebuild(b) => b.label(),
            UpdateMode::Refit(b) => format!("refit ({} topology of frame 0)", b.label()),
        }
    }

    /// A mode by name (see `name`).
    pub fn parse(name: &str) -> Result<Self> {
        let all = Self::all();
        all.iter()
            .copied()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let known: Vec<_> = all.iter().map(|m| m.name()).collect();
                Error::InvalidArgument(format!(
                    "unknown builder '{name}' (known: {})",
                    known.join(", ")
                ))
            })
    }

    /// Whether the update runs on the GPU (refits always do; rebuilds with GPU builders).
    pub fn is_gpu(self) -> bool {
        match self {
            UpdateMode::Rebuild(b) => b.is_gpu(),
            UpdateMode::Refit(_) => true,
        }
    }

    pub fn is_refit(self) -> bool {
        matches!(self, UpdateMode::Refit(_))
    }

    /// The builder that builds (rebuild) or built the topology (refit).
    pub fn builder(self) -> Builder {
        match self {
            UpdateMode::Rebuild(b) | UpdateMode::Refit(b) => b,
        }
    }

    /// The same mode with its builder's treelet settings replaced
    /// (`Builder::with_treelet_settings`).
    pub fn with_treelet_settings(self, settings: TreeletSettings) -> Self {
        match self {
            UpdateMode::Rebuild(b) => UpdateMode::Rebuild(b.with_treelet_settings(settings)),
            UpdateMode::Refit(b) => UpdateMode::Refit(b.with_treelet_settings(settings)),
        }
    }
}

/// The builder behind a mode.
enum Producer {
    Lbvh(Box<LbvhBuilder>),
    Trbvh(Box<TrbvhBuilder>),
    Cpu(Builder),
}

/// Produces a tree per frame in one of the modes (see the module documentation).
pub struct TreeUpdater {
    mode: UpdateMode,
    producer: Producer,
    /// Refit modes: the kernel; the topology's links live with the tree.
    refit: Option<NodesRefit>,
    /// Refit modes: build a new topology at the next update.
    rebuild_topology: bool,
    sah: SahParams,
    /// Wide layout: the conversion that follows every update.
    converter: Option<WideConverter>,
    /// The wide conversion's collapse and level dispatches (kept while the layout is binary).
    wide: WideOptions,
    /// The sort tile of the GPU builders (`BuildSchedule::sort_tile_items`).
    sort_tile_items: Option<u32>,
}

impl TreeUpdater {
    /// Kernels for `mode` (refits need a GPU builder for their topology).
    pub fn new(ctx: &GpuContext, mode: UpdateMode, sah: &SahParams) -> Result<Self> {
        let producer = match mode.builder() {
            Builder::Lbvh => Producer::Lbvh(Box::new(LbvhBuilder::new(ctx))),
            Builder::Trbvh(settings) | Builder::TrbvhSplit(settings) => {
                Producer::Trbvh(Box::new(TrbvhBuilder::new(ctx, settings, *sah)?))
            }
            cpu if mode.is_refit() => {
                return Err(Error::InvalidArgument(format!(
                    "refits need a GPU builder for their topology, not {}",
                    cpu.name()
                )))
            }
            cpu => Producer::Cpu(cpu),
        };
        Ok(Self {
            mode,
            producer,
            refit: mode.is_refit().then(|| NodesRefit::new(ctx)),
            rebuild_topology: true,
            sah: *sah,
            converter: None,
            wide: WideOptions::default(),
            sort_tile_items: None,
        })
    }

    /// The layout the next updates produce: binary, or binary converted to wide.
    pub fn set_layout(&mut self, ctx: &GpuContext, layout: Layout) {
        self.converter = match layout {
            Layout::Binary => None,
            Layout::Wide => {
                let mut converter = self
                    .converter
                    .take()
                    .unwrap_or_else(|| WideConverter::new(ctx, &self.sah));
                converter.set_options(self.wide);
                Some(converter)
            }
        };
    }

    /// How the wide layout's conversions collapse the binary tree (now and after a later
    /// `set_layout`).
    pub fn set_wide_collapse(&mut self, collapse: WideCollapse) {
        self.set_wide_options(WideOptions {
            collapse,
            ..self.wide
        });
    }

    /// How the wide layout's conversions collapse the binary tree and how many levels get a
    /// dispatch of their own (now and after a later `set_layout`).
    pub fn set_wide_options(&mut self, options: WideOptions) {
        self.wide = options;
        if let Some(converter) = &mut self.converter {
            converter.set_options(options);
        }
    }

    pub fn layout(&self) -> Layout {
        if self.converter.is_some() {
            Layout::Wide
        } else {
            Layout::Binary
        }
    }

    /// The wide conversion, when the layout is wide (tests fix its schedule).
    pub fn converter_mut(&mut self) -> Option<&mut WideConverter> {
        self.converter.as_mut()
    }

    pub fn mode(&self) -> UpdateMode {
        self.mode
    }

    /// How the treelet rounds of the next builds spread their work over the device (trbvh and
    /// trbvh-split; the tree does not depend on it).
    pub fn set_round_schedule(&mut self, schedule: RoundSchedule) {
        if let Producer::Trbvh(b) = &mut self.producer {
            b.set_schedule(schedule);
        }
    }

    /// How the next builds spread over the device (`BuildSchedule`; the tree does not depend
    /// on it): the treelet rounds' schedule (trbvh, trbvh-split), the sort's tile (GPU
    /// builders), the wide conversion's level dispatches (kept while the layout is binary).
    pub fn set_build_schedule(&mut self, schedule: BuildSchedule) -> Result<()> {
        match &mut self.producer {
            Producer::Lbvh(b) => b.set_sort_tile_items(schedule.sort_tile_items)?,
            Producer::Trbvh(b) => b.set_sort_tile_items(schedule.sort_tile_items)?,
            Producer::Cpu(_) => {}
        }
        self.sort_tile_items = schedule.sort_tile_items;
        self.set_round_schedule(schedule.rounds);
        self.set_wide_options(WideOptions {
            level_dispatches: schedule.wide_level_dispatches,
            ..self.wide
        });
        Ok(())
    }

    pub fn build_schedule(&self) -> BuildSchedule {
        BuildSchedule {
            rounds: match &self.producer {
                Producer::Trbvh(b) => b.schedule(),
                _ => RoundSchedule::default(),
            },
            sort_tile_items: self.sort_tile_items,
            wide_level_dispatches: self.wide.level_dispatches,
        }
    }

    /// Whether a schedule tuning applies: a GPU builder's rebuilds (not a CPU builder's, not a
    /// refit's, whose topology is built once).
    pub fn is_tunable(&self) -> bool {
        !matches!(self.producer, Producer::Cpu(_)) && !self.mode.is_refit()
    }

    /// What a schedule tuning (`tune_schedule`) may vary in this updater's builds over
    /// `triangles` triangles, with the defaults those builds take on this device (None where
    /// `is_tunable` is false).
    pub fn tuning_space(&self, ctx: &GpuContext, triangles: u32) -> Option<TuningSpace> {
        if !self.is_tunable() {
            return None;
        }
        let device = ctx.info.device_type;
        // The stages' sizes (the references of pre-splitting where the builder splits) and the
        // treelet rounds' level dispatches (none for the phased rounds).
        let phased = matches!(&self.producer, Producer::Trbvh(b) if b.settings.phases.is_some());
        let (prims, round_levels, round_levels_vary, overlap_reach) = match &self.producer {
            // The phased rounds take no level schedule (their own dimensions: `phased`).
            Producer::Trbvh(b) if b.settings.phases.is_some() => {
                (b.leaf_capacity(triangles), None, false, 0)
            }
            Producer::Trbvh(b) => {
                let prims = b.leaf_capacity(triangles);
                let size = b.settings.treelet_size;
                let levels = RoundSchedule::default_level_dispatches(prims, size, device);
                // Each round's default (a cost-only pass has no levels).
                let vary = b.settings.gammas().iter().any(|&gamma| {
                    gamma != u32::MAX
                        && RoundSchedule::default_level_dispatches(prims, gamma, device) != levels
                });
                let reach = if b.settings.one_treelet_size() {
                    overlap_reach(size)
                } else {
                    0
                };
                (prims, Some(levels), vary, reach)
            }
            _ => (triangles, None, false, 0),
        };
        Some(TuningSpace {
            round_levels,
            phased,
            root_slots: RoundSchedule::default().root_slots(device),
            round_levels_vary,
            overlap_reach,
            subtree_width: RoundSchedule::default().subtree_width(device),
            sort_tile_items: context_tile_items(ctx, prims),
            wide_levels: self
                .converter
                .is_some()
                .then(|| WideConverter::level_dispatches(prims)),
        })
    }

    /// SAH parameters of the next builds (treelet builders' cost model and max leaf size; CPU
    /// builders' too).
    pub fn set_sah_params(&mut self, sah: SahParams) {
        self.sah = sah;
        if let Producer::Trbvh(b) = &mut self.producer {
            b.sah = sah;
        }
    }

    /// Timestamped passes one update records at most (the size of a timer for it).
    pub fn pass_count(&self) -> u32 {
        match &self.producer {
            Producer::Lbvh(_) => LBVH_PASSES,
            Producer::Trbvh(b) => b.pass_count(),
            Producer::Cpu(_) => 0,
        }
        .max(1)
            + u32::from(self.converter.is_some())
    }

    /// Refits: the next update builds a new topology (after the animation looped, or a setting
    /// changed).
    pub fn reset(&mut self) {
        self.rebuild_topology = true;
    }

    /// Updates `tree` to `geometry` (whose triangles, on the CPU, are `triangles`: CPU builders
    /// read them). GPU builders and refits record their passes into `rec`; a CPU builder builds
    /// the tree now and replaces `tree` by its upload, and returns its CPU time. A refit of a tree
    /// without refit links builds the topology first and derives them (flushing `rec` and reading
    /// the tree back: once per topology, not per frame).
    /// With the wide layout the binary tree is then converted (`tree.wide`); with the binary
    /// layout `tree.wide` is dropped.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        triangles: &[Triangle],
        tree: &mut Tree,
    ) -> Result<Option<StageTime>> {
        if self.converter.is_some() && self.sah.max_leaf_size > MAX_WIDE_LEAF_SIZE {
            return Err(Error::InvalidArgument(format!(
                "leaves of up to {} triangles do not fit the wide layout (at most {MAX_WIDE_LEAF_SIZE})",
                self.sah.max_leaf_size
            )));
        }
        let cpu_time = self.record_binary(rec, geometry, triangles, tree)?;
        match &self.converter {
            Some(converter) => converter.record(rec, geometry, tree)?,
            None => tree.wide = None,
        }
        Ok(cpu_time)
    }

    fn record_binary(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        triangles: &[Triangle],
        tree: &mut Tree,
    ) -> Result<Option<StageTime>> {
        if let Some(refit) = &self.refit {
            if !self.rebuild_topology {
                if let Some(links) = &tree.refit_links {
                    refit.record(rec, &geometry.triangles, tree, links);
                    return Ok(None);
                }
            }
        }
        let cpu_time = match &mut self.producer {
            Producer::Lbvh(b) => {
                b.record(rec, geometry, tree)?;
                None
            }
            Producer::Trbvh(b) => {
                b.record(rec, geometry, tree)?;
                None
            }
            Producer::Cpu(builder) => {
                let start = Instant::now();
                let bvh = match builder {
                    Builder::Sbvh => build_sbvh(triangles, &self.sah),
                    _ => build_sweep_sah(triangles, &self.sah),
                };
                let ms = start.elapsed().as_secs_f64() * 1e3;
                *tree = Tree::upload(rec.ctx, &bvh)?;
                Some(StageTime::cpu(format!("cpu {}", builder.name()), ms))
            }
        };
        if self.refit.is_some() {
            rec.flush();
            tree.refit_links = Some(derive_refit_links(rec.ctx, tree)?);
            self.rebuild_topology = false;
        }
        Ok(cpu_time)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_parse_by_name() {
        assert_eq!(
            UpdateMode::parse("lbvh").unwrap(),
            UpdateMode::Rebuild(Builder::Lbvh)
        );
        assert_eq!(
            UpdateMode::parse("refit").unwrap(),
            UpdateMode::Refit(Builder::Lbvh)
        );
        assert!(UpdateMode::parse("refit-trbvh").unwrap().is_refit());
        let e = UpdateMode::parse("magic").unwrap_err().to_string();
        assert!(e.contains("unknown builder") && e.contains("refit"), "{e}");
        for mode in UpdateMode::all() {
            assert_eq!(UpdateMode::parse(mode.name()).unwrap().name(), mode.name());
        }
    }

    #[test]
    fn treelet_settings_change_the_builder_not_the_mode() {
        let phased = TreeletSettings::PHASED;
        assert!(phased.validate(&SahParams::default()).is_ok());
        assert_eq!(
            UpdateMode::Refit(Builder::Trbvh(TreeletSettings::BALANCED))
                .with_treelet_settings(phased),
            UpdateMode::Refit(Builder::Trbvh(phased))
        );
        let split = TreeletSettings {
            split_percent: 30,
            ..phased
        };
        assert_eq!(
            UpdateMode::Rebuild(Builder::TrbvhSplit(TreeletSettings::BALANCED))
                .with_treelet_settings(split),
            UpdateMode::Rebuild(Builder::TrbvhSplit(split))
        );
        assert_eq!(
            UpdateMode::Rebuild(Builder::Lbvh).with_treelet_settings(phased),
            UpdateMode::Rebuild(Builder::Lbvh)
        );
    }
}
