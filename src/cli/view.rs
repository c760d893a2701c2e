//! `treelet view`: the interactive viewer (see `treelet::app`), with automation flags for scripts
//! (`--screenshot out.png --exit-after-frames N`).

use std::path::PathBuf;

use clap::Args;
use treelet::anim::DEFAULT_ANIMATION;
use treelet::app::ViewerOptions;
use treelet::bvh::UpdateMode;
use treelet::gpu::GpuOptions;
use treelet::Result;

use super::{parse_update_mode, TuneSchedule};

#[derive(Args, Debug)]
pub struct ViewArgs {
    /// Scene name (see `treelet scenes`; animated ones play), path to an OBJ file, or a folder of
    /// frame OBJs (an OBJ sequence)
    #[arg(long, default_value = DEFAULT_ANIMATION)]
    scene: String,
    /// BVH builder (GPU builders are rebuilt every frame); for animated scenes also `refit` or
    /// `refit-trbvh` (the first frame's tree, refitted every frame). Default: trbvh on a GPU, lbvh
    /// on a software rasterizer
    #[arg(long, value_parser = parse_update_mode)]
    builder: Option<UpdateMode>,
    /// Window width in pixels
    #[arg(long, default_value_t = 1280, value_parser = clap::value_parser!(u32).range(1..))]
    width: u32,
    /// Window height in pixels
    #[arg(long, default_value_t = 800, value_parser = clap::value_parser!(u32).range(1..))]
    height: u32,
    /// Write a PNG of the whole window (image and panel) after --exit-after-frames frames
    #[arg(long, requires = "exit_after_frames")]
    screenshot: Option<PathBuf>,
    /// Tune a GPU builder's build schedule on this device and scene (every schedule builds the
    /// same tree; the panel's "Tune schedule" does it at any time): auto (on GPUs, after a few
    /// seconds of frames, once per builder), on (at once, also on CPU devices, where it takes
    /// long) or off
    #[arg(long, value_enum, default_value_t = TuneSchedule::Auto)]
    tune_schedule: TuneSchedule,
    /// Exit after rendering this many frames
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    exit_after_frames: Option<u64>,
}

pub fn run(adapter: Option<String>, args: ViewArgs) -> Result<()> {
    treelet::app::run(ViewerOptions {
        scene: args.scene,
        builder: args.builder,
        gpu: GpuOptions {
            adapter,
            profile_dispatches: false,
            sort_tile_items: None,
            climb_width: None,
        },
        window_size: (args.width, args.height),
        screenshot: args.screenshot,
        exit_after_frames: args.exit_after_frames,
        tune_schedule: args.tune_schedule.forced(),
    })
}
