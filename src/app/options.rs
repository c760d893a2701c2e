//! What the command line asks of the viewer: the first scene and builder, the adapter, the window
//! size, the schedule tuning, and the automation flags used by scripts (screenshot after N
//! frames, then exit).

use std::path::PathBuf;

use crate::bvh::treelet::TreeletSettings;
use crate::bvh::Builder;
use crate::bvh::UpdateMode;
use crate::gpu::GpuOptions;

#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// Scene name (see the scene and animation registries), path to an OBJ file, or a folder of
    /// frame OBJs (an OBJ sequence).
    pub scene: String,
    /// How the tree is made each frame; None: `default_update_mode` for the adapter.
    pub builder: Option<UpdateMode>,
    pub gpu: GpuOptions,
    /// Inner size of the window in physical pixels.
    pub window_size: (u32, u32),
    /// Write a PNG of the whole window (image and panel) after `exit_after_frames` frames.
    pub screenshot: Option<PathBuf>,
    /// Exit (status 0) after this many presented frames.
    pub exit_after_frames: Option<u64>,
    /// Tune a GPU builder's build schedule: at its first frame (true), only on request (false), or
    /// None: on a GPU after a few seconds of frames.
    pub tune_schedule: Option<bool>,
}

/// The viewer's builder when none is asked for: the paper's (trbvh, balanced) on a GPU; lbvh on a
/// software rasterizer, where a treelet build of a default scene takes seconds per frame.
pub fn default_update_mode(device: wgpu::DeviceType) -> UpdateMode {
    match device {
        wgpu::DeviceType::Cpu => UpdateMode::Rebuild(Builder::Lbvh),
        _ => UpdateMode::Rebuild(Builder::Trbvh(TreeletSettings::BALANCED)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpus_open_with_the_papers_builder() {
        for device in [
            wgpu::DeviceType::DiscreteGpu,
            wgpu::DeviceType::IntegratedGpu,
            wgpu::DeviceType::VirtualGpu,
            wgpu::DeviceType::Other,
        ] {
            assert_eq!(
                default_update_mode(device),
                UpdateMode::Rebuild(Builder::Trbvh(TreeletSettings::BALANCED))
            );
        }
        assert_eq!(
            default_update_mode(wgpu::DeviceType::Cpu),
            UpdateMode::Rebuild(Builder::Lbvh)
        );
    }
}
