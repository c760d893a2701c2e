//! The viewer's user-adjustable settings (builder or refit mode, leaf size, node layout and the
//! wide layout's collapse, samples per frame, bounces, per-frame rebuild). Any change to them
//! restarts accumulation.

use crate::bvh::wide::{Layout, WideCollapse, MAX_WIDE_LEAF_SIZE};
use crate::bvh::SahParams;
use crate::bvh::UpdateMode;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSettings {
    /// How the tree is built: a builder rebuilding it, or a refit of the first frame's tree.
    pub builder: UpdateMode,
    pub max_leaf_size: u32,
    /// The node layout traced: the builder's binary tree, or that tree converted to the
    /// compressed 8-wide layout after every update.
    pub layout: Layout,
    /// How the wide layout's conversion collapses the binary tree.
    pub wide_collapse: WideCollapse,
    pub samples_per_frame: u32,
    /// Diffuse bounces after the primary hit (the tracer's `max_depth` is this + 1).
    pub max_bounces: u32,
    /// Rebuild the BVH every frame (GPU builders; CPU builders build once per change).
    pub rebuild_every_frame: bool,
}

// Every leaf size the panel offers fits the wide layout's leaves (a byte per slot).
const _: () = assert!(ViewSettings::MAX_LEAF_SIZE <= MAX_WIDE_LEAF_SIZE);

impl ViewSettings {
    pub const MAX_SAMPLES_PER_FRAME: u32 = 64;
    pub const MAX_BOUNCES: u32 = 16;
    pub const MAX_LEAF_SIZE: u32 = 32;

    pub fn new(builder: UpdateMode) -> Self {
        Self {
            builder,
            max_leaf_size: SahParams::default().max_leaf_size,
            layout: Layout::Binary,
            wide_collapse: WideCollapse::default(),
            samples_per_frame: 1,
            max_bounces: 3,
            rebuild_every_frame: builder.is_gpu(),
        }
    }

    /// Rays per path for the path tracer (1 = primary rays only).
    pub fn max_depth(&self) -> u32 {
        self.max_bounces + 1
    }

    pub fn sah_params(&self) -> SahParams {
        SahParams {
            max_leaf_size: self.max_leaf_size.max(1),
            ..SahParams::default()
        }
    }

    /// Whether the tree is rebuilt on every frame with these settings.
    pub fn rebuilds_every_frame(&self) -> bool {
        self.rebuild_every_frame && self.builder.is_gpu()
    }

    /// Switches builder; per-frame rebuilding defaults to on for GPU builders, off for CPU ones.
    pub fn select_builder(&mut self, builder: UpdateMode) {
        if builder != self.builder {
            self.builder = builder;
            self.rebuild_every_frame = builder.is_gpu();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::Builder;

    #[test]
    fn gpu_builders_rebuild_every_frame_by_default_cpu_ones_do_not() {
        let mut s = ViewSettings::new(UpdateMode::Rebuild(Builder::Lbvh));
        assert!(s.rebuilds_every_frame());
        s.select_builder(UpdateMode::Rebuild(Builder::Sweep));
        assert!(!s.rebuilds_every_frame());
        s.rebuild_every_frame = true;
        assert!(
            !s.rebuilds_every_frame(),
            "a CPU builder never rebuilds per frame"
        );
        s.select_builder(UpdateMode::Refit(Builder::Lbvh));
        assert!(s.rebuilds_every_frame(), "a refit runs on the GPU");
    }

    #[test]
    fn the_binary_layout_is_traced_until_another_is_chosen() {
        for mode in UpdateMode::all() {
            assert_eq!(ViewSettings::new(mode).layout, Layout::Binary);
        }
    }

    #[test]
    fn bounces_map_to_rays_per_path() {
        let mut s = ViewSettings::new(UpdateMode::Rebuild(Builder::Lbvh));
        s.max_bounces = 0;
        assert_eq!(s.max_depth(), 1);
    }
}
