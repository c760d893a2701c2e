//! Command-line arguments (clap) and dispatch to the subcommands.

mod bench;
mod render;

use clap::{Args, Parser, Subcommand};
use treelet::bvh::{Builder, SahParams};
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
    Render(render::RenderArgs),
    /// Build and trace a scene, print one JSON object per builder
    Bench(bench::BenchArgs),
    /// List the built-in and shared scene names
    Scenes,
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
    /// Samples (paths) per pixel
    #[arg(long, default_value_t = 16)]
    spp: u32,
    /// Maximum rays per path (1 = primary rays only)
    #[arg(long, default_value_t = 4)]
    max_depth: u32,
    /// Maximum primitives per leaf
    #[arg(long, default_value_t = SahParams::default().max_leaf_size)]
    max_leaf_size: u32,
}

impl TraceArgs {
    fn render_settings(&self) -> RenderSettings {
        RenderSettings {
            width: self.width,
            height: self.height,
            max_depth: self.max_depth,
            ..RenderSettings::default()
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

fn parse_builder(name: &str) -> std::result::Result<Builder, String> {
    Builder::parse(name).map_err(|e| e.to_string())
}

pub fn run(cli: Cli) -> Result<()> {
    let gpu = || {
        GpuContext::new(&GpuOptions {
            adapter: cli.adapter.clone(),
        })
    };
    match cli.command.unwrap_or_else(default_command) {
        Command::Render(args) => render::run(&gpu()?, &args),
        Command::Bench(args) => bench::run(&gpu()?, &args),
        Command::Scenes => {
            for entry in treelet::scene::SCENES {
                println!("{:<16} {}", entry.name, entry.description);
            }
            Ok(())
        }
    }
}

/// What `treelet` without arguments does: render the default scene to `treelet.png`.
fn default_command() -> Command {
    Cli::parse_from(["treelet", "render"])
        .command
        .expect("`render` parses as a command")
}
