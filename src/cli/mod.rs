//! Command-line arguments (clap) and dispatch to the subcommands.

mod bench;
mod render;
mod render_frames;
mod tradeoff;
mod view;

use clap::{Args, Parser, Subcommand};
use treelet::bvh::treelet::TreeletSettings;
use treelet::bvh::wide::{Layout, WideCollapse};
use treelet::bvh::{Builder, SahParams, DEFAULT_SPLIT_PERCENT};
use treelet::gpu::{GpuContext, GpuOptions};
use treelet::trace::RenderSettings;
use treelet::Result;

/// The scene rendered when none is named.
pub const DEFAULT_SCENE: &str = "cornell";

#[derive(Parser, Debug)]
#[command(
    name = "treelet",
    version,
    about = "Per-frame GPU BVH construction (TRBVH) and a wgpu path tracer"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// GPU adapter to use: a case-insensitive part of its name (default: discrete GPU first; env TREELET_ADAPTER)
    #[arg(long, global = true)]
    adapter: Option<String>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to a PNG file (headless)
    Render(Box<render::RenderArgs>),
    /// Build and trace a scene, print one JSON object per builder
    Bench(Box<bench::BenchArgs>),
    /// List the built-in and shared scene names
    Scenes,
    /// Open the interactive viewer (the default when a display is available)
    View(view::ViewArgs),
    /// Measure every builder configuration and chart build time against ray throughput
    Tradeoff(tradeoff::TradeoffArgs),
}

/// Options shared by `render` and `bench`.
#[derive(Args, Debug, Clone)]
pub struct TraceArgs {
    /// Scene name (see `treelet scenes`) or path to an OBJ file
    #[arg(long, default_value = DEFAULT_SCENE)]
    scene: String,
    /// Image width in pixels
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Image height in pixels
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Samples (paths) per pixel (at least 1)
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    spp: u32,
    /// Maximum rays per path (1 = primary rays only)
    #[arg(long, default_value_t = 4)]
    max_depth: u32,
    /// Maximum primitives per leaf
    #[arg(long, default_value_t = SahParams::default().max_leaf_size)]
    max_leaf_size: u32,
    /// Treelet preset for trbvh: fast (n=5, 1 round), balanced (n=7, 3 rounds, the paper's; the
    /// default), high (n=8, 4 rounds) or phased (n=7, 3 rounds of 6, 4 and 4 phases)
    #[arg(long, value_parser = parse_preset)]
    preset: Option<TreeletSettings>,
    /// Leaves per treelet (3..=8) for trbvh, overriding the preset; `bench` takes a comma-separated list
    #[arg(long, value_delimiter = ',')]
    treelet_size: Vec<u32>,
    /// Restructuring rounds for trbvh, overriding the preset; `bench` takes a comma-separated list
    #[arg(long, value_delimiter = ',')]
    rounds: Vec<u32>,
    /// Leaves per treelet (3..=8) of the last round of trbvh, a cheaper last round (default: the
    /// treelet size; not with --round-overlap); `bench` takes a comma-separated list
    #[arg(long, value_delimiter = ',')]
    last_round_size: Vec<u32>,
    /// Each round of trbvh in P phases by depth instead of bottom-up (3..=16; below the treelet
    /// size a treelet's leaves stay within P − 1 levels of its root; 0: bottom-up, the paper's
    /// order and the default); `bench` takes a comma-separated list
    #[arg(long, value_delimiter = ',')]
    phases: Vec<u32>,
    /// Phases of the first round of phased trbvh rounds (default: --phases; 14 with --phases 7
    /// comes closest to the paper's trees); `bench` takes a comma-separated list, which applies
    /// to the phased variants only
    #[arg(long, value_delimiter = ',')]
    first_round_phases: Vec<u32>,
    /// Pre-splitting budget β of trbvh-split (extra references per triangle, 0..=1; default 0.3);
    /// `bench` takes a comma-separated list
    #[arg(long, value_delimiter = ',', value_parser = parse_split_budget)]
    split_budget: Vec<u32>,
    /// Node layout traced: binary (the builder's tree) or wide (compressed 8-wide, converted from
    /// it on the GPU); `bench` takes a comma-separated list and measures each on the same tree
    #[arg(long, value_delimiter = ',', value_parser = parse_layout, default_value = "binary")]
    layout: Vec<Layout>,
    /// How the wide layout's conversion picks a wide node's children: greedy (open the largest
    /// child until 8 slots are taken; the default) or optimal (the SAH-optimal collapse of
    /// Ylitie et al., its dynamic program on the GPU); `bench` takes a comma-separated list and
    /// measures each on the same tree
    #[arg(long, value_delimiter = ',', value_parser = parse_wide_collapse)]
    wide_collapse: Vec<WideCollapse>,
}

/// The values of a list option, or the default (None) where none is given.
fn or_default<T: Copy>(values: &[T]) -> Vec<Option<T>> {
    if values.is_empty() {
        vec![None]
    } else {
        values.iter().copied().map(Some).collect()
    }
}

impl TraceArgs {
    /// Every combination of the requested treelet sizes, rounds, last rounds' sizes, phases and
    /// first rounds' phases (the preset's where not given).
    fn treelet_variants(&self) -> Vec<TreeletSettings> {
        let preset = self.preset.unwrap_or(TreeletSettings::BALANCED);
        let mut variants = Vec::new();
        for treelet_size in or_default(&self.treelet_size) {
            for rounds in or_default(&self.rounds) {
                for last_round_size in or_default(&self.last_round_size) {
                    for phases in or_default(&self.phases) {
                        let phases = phases.map_or(preset.phases, |p| (p > 0).then_some(p));
                        // The bottom-up variant of a sweep with phased ones once, without
                        // first-round phases (only phased rounds take them; alone, the settings
                        // refuse them).
                        let firsts = if phases.is_none() && self.phases.iter().any(|&p| p > 0) {
                            vec![None]
                        } else {
                            or_default(&self.first_round_phases)
                        };
                        for first_round_phases in firsts {
                            variants.push(TreeletSettings {
                                treelet_size: treelet_size.unwrap_or(preset.treelet_size),
                                rounds: rounds.unwrap_or(preset.rounds),
                                split_percent: 0,
                                last_round_size: last_round_size.or(preset.last_round_size),
                                phases,
                                // The preset's apply to phased rounds only (given ones
                                // without them are refused).
                                first_round_phases: first_round_phases
                                    .or(phases.and(preset.first_round_phases)),
                            });
                        }
                    }
                }
            }
        }
        variants
    }

    /// Fails when a treelet option is given but no builder in `builders` has treelets, or a split
    /// budget but none pre-splits: such an option would be silently ignored.
    fn check_options_apply(&self, builders: &[Builder]) -> Result<()> {
        refuse_treelet_options(
            builders,
            &[
                ("--treelet-size", !self.treelet_size.is_empty()),
                ("--phases", !self.phases.is_empty()),
                ("--first-round-phases", !self.first_round_phases.is_empty()),
                ("--rounds", !self.rounds.is_empty()),
                ("--last-round-size", !self.last_round_size.is_empty()),
                ("--preset", self.preset.is_some()),
            ],
        )?;
        let splits = builders.iter().any(|b| matches!(b, Builder::TrbvhSplit(_)));
        if !self.split_budget.is_empty() && !splits {
            return Err(treelet::Error::InvalidArgument(format!(
                "--split-budget does not apply to builder {}: only trbvh-split pre-splits",
                builder_names(builders)
            )));
        }
        Ok(())
    }

    /// The builders to run: `builders`, with trbvh expanded into every treelet variant and
    /// trbvh-split also into every split budget. Fails on options that apply to none of them.
    fn builder_variants(&self, builders: &[Builder]) -> Result<Vec<Builder>> {
        self.check_options_apply(builders)?;
        let budgets = if self.split_budget.is_empty() {
            vec![DEFAULT_SPLIT_PERCENT]
        } else {
            self.split_budget.clone()
        };
        Ok(builders
            .iter()
            .flat_map(|&b| match b {
                Builder::Trbvh(_) => self
                    .treelet_variants()
                    .into_iter()
                    .map(|s| b.with_treelet_settings(s))
                    .collect::<Vec<_>>(),
                Builder::TrbvhSplit(_) => self
                    .treelet_variants()
                    .into_iter()
                    .flat_map(|s| {
                        budgets.iter().map(move |&split_percent| {
                            // β = 0 is trbvh itself (no pre-splitting).
                            let settings = TreeletSettings { split_percent, ..s };
                            if split_percent == 0 {
                                Builder::Trbvh(settings)
                            } else {
                                b.with_treelet_settings(settings)
                            }
                        })
                    })
                    .collect(),
                other => vec![other],
            })
            .collect())
    }

    /// The settings of a tracer of `layout`.
    fn render_settings(&self, layout: Layout) -> RenderSettings {
        RenderSettings {
            width: self.width,
            height: self.height,
            max_depth: self.max_depth,
            layout,
            ..RenderSettings::default()
        }
    }

    /// The wide collapses asked for (the default when none was); refused without the wide
    /// layout, to which they apply.
    fn wide_collapses(&self) -> Result<Vec<WideCollapse>> {
        if self.wide_collapse.is_empty() {
            return Ok(vec![WideCollapse::default()]);
        }
        if !self.layout.contains(&Layout::Wide) {
            return Err(treelet::Error::InvalidArgument(
                "--wide-collapse applies to the wide layout (add --layout wide)".into(),
            ));
        }
        Ok(self.wide_collapse.clone())
    }

    /// The one wide collapse of commands that trace one tree (`render`).
    fn single_wide_collapse(&self) -> Result<WideCollapse> {
        match self.wide_collapses()?[..] {
            [collapse] => Ok(collapse),
            _ => Err(treelet::Error::InvalidArgument(
                "this command takes one --wide-collapse".into(),
            )),
        }
    }

    /// The one layout of commands that trace one (`render`).
    fn single_layout(&self) -> Result<Layout> {
        match self.layout[..] {
            [layout] => Ok(layout),
            _ => Err(treelet::Error::InvalidArgument(
                "this command takes one --layout".into(),
            )),
        }
    }

    fn sah_params(&self) -> Result<SahParams> {
        if self.max_leaf_size == 0 {
            return Err(treelet::Error::InvalidArgument(
                "--max-leaf-size must be at least 1".into(),
            ));
        }
        Ok(SahParams {
            max_leaf_size: self.max_leaf_size,
            ..SahParams::default()
        })
    }
}

/// The names of `builders`, comma-separated (error messages).
fn builder_names(builders: &[Builder]) -> String {
    let names: Vec<_> = builders.iter().map(|b| b.name()).collect();
    names.join(", ")
}

/// `--tune-schedule` of `bench`, `view` and `render --frames`: tune a GPU builder's build
/// schedule (auto: on GPUs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum TuneSchedule {
    Auto,
    On,
    Off,
}

impl TuneSchedule {
    /// On or off as asked; None for auto.
    pub(crate) fn forced(self) -> Option<bool> {
        match self {
            TuneSchedule::Auto => None,
            TuneSchedule::On => Some(true),
            TuneSchedule::Off => Some(false),
        }
    }
}

/// Fails when one of the treelet `options` (flag, given) is given but no builder in `builders`
/// has treelets: the option would be silently ignored.
fn refuse_treelet_options(builders: &[Builder], options: &[(&str, bool)]) -> Result<()> {
    let has_treelets = builders.iter().any(|b| b.treelet_settings().is_some());
    match options.iter().find(|(_, given)| *given) {
        Some((flag, _)) if !has_treelets => Err(treelet::Error::InvalidArgument(format!(
            "{flag} does not apply to builder {}: only trbvh and trbvh-split have treelets",
            builder_names(builders)
        ))),
        _ => Ok(()),
    }
}

/// β as a fraction (e.g. 0.3) to whole percent.
fn parse_split_budget(text: &str) -> std::result::Result<u32, String> {
    let beta: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if !(0.0..=1.0).contains(&beta) {
        return Err(format!("split budget must be between 0 and 1, got {text}"));
    }
    Ok((beta * 100.0).round() as u32)
}

fn parse_layout(name: &str) -> std::result::Result<Layout, String> {
    Layout::parse(name).map_err(|e| e.to_string())
}

fn parse_wide_collapse(name: &str) -> std::result::Result<WideCollapse, String> {
    WideCollapse::parse(name).map_err(|e| e.to_string())
}

fn parse_preset(name: &str) -> std::result::Result<TreeletSettings, String> {
    TreeletSettings::preset(name).map_err(|e| e.to_string())
}

fn parse_builder(name: &str) -> std::result::Result<Builder, String> {
    Builder::parse(name).map_err(|e| e.to_string())
}

/// A builder name, or `refit` / `refit-trbvh` (animated scenes).
fn parse_update_mode(name: &str) -> std::result::Result<treelet::bvh::UpdateMode, String> {
    treelet::bvh::UpdateMode::parse(name).map_err(|e| e.to_string())
}

pub fn run(cli: Cli) -> Result<()> {
    let adapter = cli.adapter.clone();
    let gpu_with = |profile_dispatches, sort_tile_items, climb_width| {
        GpuContext::new(&GpuOptions {
            adapter: adapter.clone(),
            profile_dispatches,
            sort_tile_items,
            climb_width,
        })
    };
    let gpu = || gpu_with(false, None, None);
    match cli.command.unwrap_or_else(default_command) {
        Command::Render(args) => render::run(&gpu()?, &args),
        Command::Bench(args) => bench::run(
            &gpu_with(
                args.profile_dispatches,
                args.sort_tile_items,
                args.climb_width,
            )?,
            &args,
        ),
        Command::Scenes => {
            for entry in treelet::scene::SCENES {
                println!("{:<16} {}", entry.name, entry.description);
            }
            for entry in treelet::anim::ANIMATIONS {
                println!("{:<16} [animated] {}", entry.name, entry.description);
            }
            Ok(())
        }
        Command::View(args) => view::run(cli.adapter.clone(), args),
        Command::Tradeoff(args) => tradeoff::run(&gpu()?, &args),
    }
}

/// What `treelet` without arguments does: open the viewer when a display is available (DISPLAY or
/// WAYLAND_DISPLAY set), otherwise render the default scene to `treelet.png` with the viewer's
/// builder, trbvh on the GPU (`render` alone builds with the CPU's sweep, a reference).
fn default_command() -> Command {
    let has_display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()));
    let args: &[&str] = if has_display {
        &["treelet", "view"]
    } else {
        log::info!("no display (DISPLAY and WAYLAND_DISPLAY unset): rendering to treelet.png instead of opening the viewer");
        &["treelet", "render", "--builder", "trbvh"]
    };
    Cli::parse_from(args)
        .command
        .expect("the default command parses")
}
