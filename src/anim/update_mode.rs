//! How an animated scene's tree follows its triangles from frame to frame: rebuilt from scratch
//! by a builder every frame, or refitted (the topology of the first frame's tree kept, only the
//! boxes recomputed; see `refit`). `TreeUpdater` runs either on the GPU, in place.

use super::RefitBuilder;
use crate::bvh::treelet::TreeletSettings;
use crate::bvh::{Builder, GpuBuilder, SahParams};
use crate::gpu::{GpuContext, StageTime};
use crate::trace::GpuScene;
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
}

/// A GPU tree update of one of the modes, rebuilding or refitting a scene's tree in place.
pub enum TreeUpdater {
    Rebuild(Box<GpuBuilder>),
    Refit(Box<RefitBuilder>),
}

impl TreeUpdater {
    /// Pipelines for `mode`, which must run on the GPU (CPU reference builders are an error).
    pub fn new(ctx: &GpuContext, mode: UpdateMode, params: &SahParams) -> Result<Self> {
        match mode {
            UpdateMode::Rebuild(b) => Ok(Self::Rebuild(Box::new(GpuBuilder::new(ctx, b, params)?))),
            UpdateMode::Refit(b) => Ok(Self::Refit(Box::new(RefitBuilder::new(ctx, b, params)?))),
        }
    }

    /// SAH parameters of the next builds (treelet builders' cost model and max leaf size).
    pub fn set_sah_params(&mut self, params: SahParams) {
        match self {
            Self::Rebuild(b) => b.set_sah_params(params),
            Self::Refit(r) => r.set_sah_params(params),
        }
    }

    /// Rebuilds or refits `scene`'s tree to its current triangles; returns the GPU stage times.
    pub fn update(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<Vec<StageTime>> {
        match self {
            Self::Rebuild(b) => b.build(ctx, scene),
            Self::Refit(r) => r.build(ctx, scene),
        }
    }

    /// Refits only: forget the captured topology (the next update builds a new tree).
    pub fn reset(&mut self) {
        if let Self::Refit(r) = self {
            r.reset();
        }
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
}
