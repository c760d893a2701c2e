//! What the command line asks of the viewer: the first scene and builder, the adapter, the window
//! size, and the automation flags used by scripts (screenshot after N frames, then exit).

use std::path::PathBuf;

use crate::anim::UpdateMode;
use crate::gpu::GpuOptions;

#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// Scene name (see the scene and animation registries), path to an OBJ file, or a folder of
    /// frame OBJs (an OBJ sequence).
    pub scene: String,
    pub builder: UpdateMode,
    pub gpu: GpuOptions,
    /// Inner size of the window in physical pixels.
    pub window_size: (u32, u32),
    /// Write a PNG of the whole window (image and panel) after `exit_after_frames` frames.
    pub screenshot: Option<PathBuf>,
    /// Exit (status 0) after this many presented frames.
    pub exit_after_frames: Option<u64>,
}
