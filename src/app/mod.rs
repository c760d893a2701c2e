//! The interactive viewer (`treelet view`, and `treelet` on a display): a winit window with a wgpu
//! surface, an egui side panel, and the path-traced image filling the rest of the window. Every
//! frame runs animate → build BVH (GPU, in place) → trace → display, accumulating samples while
//! nothing changes (animated scenes change every frame while they play).
//!
//! Files: `options` (what the command line asks for), `window_app` (the winit application: window,
//! surface, device, egui, drawing and presenting), `surface` (swap-chain configuration), `viewer`
//! (the per-frame pipeline and its state, recorded into one submission per frame),
//! `frame_readback` and `tree_snapshot` (statistics and trees read back without waiting),
//! `animated_scene` (an animated scene's clock, animate step and the
//! rebuild-versus-refit comparison), `playback` (the animation clock and its controls), `companion`
//! (the second tree of the comparison), `sah_history` (its SAH-over-time plot), `sah_reference`
//! (the CPU sweep-SAH anchor, in a background thread), `camera_control` (orbit, zoom, fly),
//! `display` (the image's render pipeline), `panel` (the egui side panel), `settings`, `stats`,
//! `screenshot` (whole-window PNG capture), and `tradeoff_panel` (the quality–speed trade-off
//! window: builders measured on request, effective Mrays/s plotted).

mod animated_scene;
mod camera_control;
mod companion;
mod display;
mod frame_readback;
mod options;
mod panel;
mod playback;
mod sah_history;
mod sah_reference;
mod screenshot;
mod settings;
mod stats;
mod surface;
mod tradeoff_panel;
mod tree_snapshot;
mod viewer;
mod window_app;

pub use display::DISPLAY_SHADER;
pub use options::{default_update_mode, ViewerOptions};
pub use window_app::run;
