//! The interactive viewer (`treelet view`, and `treelet` on a display): a winit window with a wgpu
//! surface, an egui side panel, and the path-traced image filling the rest of the window. Every
//! frame runs animate → build BVH (GPU, in place) → trace → display, accumulating samples while
//! nothing changes.
//!
//! Files: `options` (what the command line asks for), `window_app` (the winit application: window,
//! surface, device, egui, drawing and presenting), `surface` (swap-chain configuration), `viewer`
//! (the per-frame pipeline and its state), `frame_builder` (per-frame BVH rebuilds with any
//! builder), `sah_reference` (the CPU sweep-SAH anchor, in a background thread), `camera_control`
//! (orbit, zoom, fly), `display` (the image's render pipeline), `panel` (the egui side panel),
//! `settings`, `stats`, and `screenshot` (whole-window PNG capture).

mod camera_control;
mod display;
mod frame_builder;
mod options;
mod panel;
mod sah_reference;
mod screenshot;
mod settings;
mod stats;
mod surface;
mod viewer;
mod window_app;

pub use options::ViewerOptions;
pub use window_app::run;
