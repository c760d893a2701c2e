//! TRBVH: treelet restructuring of an LBVH on the GPU (Karras & Aila 2013, "Fast Parallel
//! Construction of High-Quality Bounding Volume Hierarchies", §3-4), then leaf collapse and
//! compaction into the traversal layout.
//!
//! Per build, all in one submission: the GPU LBVH (`bvh::lbvh`), `rounds` restructuring rounds
//! (γ = treelet size, doubling each round), the collapse. Each part has a CPU twin
//! (`build_trbvh_cpu`) that produces the identical tree, used as the test oracle.

mod collapse;
mod cpu;
mod dp;
mod optimize;

pub use cpu::WorkingTree;
pub use dp::{
    solve_treelet, surface_area, CostModel, TreeletLeaf, TreeletSolution, MAX_TREELET_SIZE,
};

use collapse::{Collapse, CollapseBuffers};
use optimize::{Round, TreeletOptimizer, TreeletState};

use super::lbvh::{build_lbvh_from_boxes_cpu, prim_boxes_cpu, LbvhBuilder};
use super::presplit::{presplit_cpu, split_budget, PreSplitter};
use super::{Bvh, BvhNode, SahParams};
use crate::geometry::Aabb;
use crate::gpu::{read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, StageTime};
use crate::scene::Triangle;
use crate::trace::GpuScene;
use crate::{Error, Result};

/// Largest leaf the GPU collapse may create (its gather stack holds a leaf's subtree).
pub const MAX_GPU_LEAF_SIZE: u32 = 32;

/// Treelet optimizer settings (presets as named constants; the paper's setting is `BALANCED`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TreeletSettings {
    /// Leaves per treelet, 3..=8 (the paper uses 7).
    pub treelet_size: u32,
    /// Restructuring rounds (γ = treelet_size, doubled each round); 0 = LBVH + collapse only.
    pub rounds: u32,
    /// Triangle pre-splitting budget β in percent of the triangle count (0 disables; §5 of the
    /// paper, which uses 30).
    pub split_percent: u32,
}

impl TreeletSettings {
    /// Quick: small treelets, one round.
    pub const FAST: Self = Self {
        treelet_size: 5,
        rounds: 1,
        split_percent: 0,
    };
    /// The paper's reference setting: treelets of 7 leaves, 3 rounds.
    pub const BALANCED: Self = Self {
        treelet_size: 7,
        rounds: 3,
        split_percent: 0,
    };
    /// Largest treelets the kernel supports, more rounds.
    pub const HIGH_QUALITY: Self = Self {
        treelet_size: 8,
        rounds: 4,
        split_percent: 0,
    };

    /// A preset by name: `fast`, `balanced` or `high`.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "fast" => Ok(Self::FAST),
            "balanced" => Ok(Self::BALANCED),
            "high" => Ok(Self::HIGH_QUALITY),
            _ => Err(Error::InvalidArgument(format!(
                "unknown treelet preset '{name}' (known: fast, balanced, high)"
            ))),
        }
    }

    /// Checks the settings together with the SAH parameters (whose max leaf size the collapse uses).
    pub fn validate(&self, sah: &SahParams) -> Result<()> {
        if !(3..=MAX_TREELET_SIZE).contains(&self.treelet_size) {
            return Err(Error::InvalidArgument(format!(
                "treelet size must be 3..={MAX_TREELET_SIZE}, got {}",
                self.treelet_size
            )));
        }
        if !(1..=MAX_GPU_LEAF_SIZE).contains(&sah.max_leaf_size) {
            return Err(Error::InvalidArgument(format!(
                "max leaf size must be 1..={MAX_GPU_LEAF_SIZE} for the GPU treelet builder, got {}",
                sah.max_leaf_size
            )));
        }
        if self.split_percent > 100 {
            return Err(Error::InvalidArgument(format!(
                "split budget must be 0..=1 (0..=100 %), got {} %",
                self.split_percent
            )));
        }
        if self.rounds > 16 {
            return Err(Error::InvalidArgument(format!(
                "at most 16 rounds, got {}",
                self.rounds
            )));
        }
        Ok(())
    }

    /// γ of each round; a single cost-only pass (no treelets) when `rounds` is 0.
    fn gammas(&self) -> Vec<u32> {
        if self.rounds == 0 {
            return vec![u32::MAX];
        }
        (0..self.rounds)
            .map(|r| self.treelet_size.saturating_mul(1 << r))
            .collect()
    }
}

impl Default for TreeletSettings {
    fn default() -> Self {
        Self::BALANCED
    }
}

/// CPU twin of the whole GPU TRBVH build.
pub fn build_trbvh_cpu(triangles: &[Triangle], settings: &TreeletSettings, sah: &SahParams) -> Bvh {
    optimize_cpu(triangles, settings, sah).collapse(&CostModel::from(sah), None)
}

/// CPU twin of the whole GPU TRBVH build with triangle pre-splitting (`settings.split_percent`).
pub fn build_trbvh_split_cpu(
    triangles: &[Triangle],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> Bvh {
    let budget = split_budget(triangles.len() as u32, settings.split_percent);
    if budget == 0 {
        return build_trbvh_cpu(triangles, settings, sah);
    }
    let (boxes, ref_tris) = presplit_cpu(triangles, budget);
    optimize_prims_cpu(&boxes, settings, sah).collapse(&CostModel::from(sah), Some(&ref_tris))
}

/// CPU twin up to the end of the rounds (the working tree before the collapse).
pub fn optimize_cpu(
    triangles: &[Triangle],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> WorkingTree {
    optimize_prims_cpu(&prim_boxes_cpu(triangles), settings, sah)
}

/// CPU twin of the rounds over primitive boxes (pre-split references or triangle boxes).
pub fn optimize_prims_cpu(
    prim_boxes: &[Aabb],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> WorkingTree {
    let (lbvh, parents) = build_lbvh_from_boxes_cpu(prim_boxes);
    optimize_lbvh_cpu(
        WorkingTree::from_lbvh(lbvh, parents),
        settings,
        &CostModel::from(sah),
    )
}

/// CPU twin of the rounds over a given LBVH (e.g. the GPU's own, read back).
pub fn optimize_lbvh_cpu(
    mut tree: WorkingTree,
    settings: &TreeletSettings,
    model: &CostModel,
) -> WorkingTree {
    for gamma in settings.gammas() {
        tree.optimize_round(model, settings.treelet_size, gamma);
    }
    tree
}

/// Scratch space for up to `capacity` triangles.
struct Scratch {
    capacity: u32,
    prim_counts: wgpu::Buffer,
    costs: wgpu::Buffer,
    arrivals: wgpu::Buffer,
    flags: wgpu::Buffer,
    kept_scan: wgpu::Buffer,
    leaf_prim_scan: wgpu::Buffer,
    out_nodes: wgpu::Buffer,
    out_prims: wgpu::Buffer,
    tree_counts: wgpu::Buffer,
}

impl Scratch {
    fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        let nodes = u64::from(2 * capacity - 1);
        Ok(Self {
            capacity,
            prim_counts: storage_buffer_zeroed(ctx, "treelet prim counts", nodes * 4)?,
            costs: storage_buffer_zeroed(ctx, "treelet costs", nodes * 4)?,
            arrivals: storage_buffer_zeroed(ctx, "treelet arrivals", u64::from(capacity) * 4)?,
            flags: storage_buffer_zeroed(ctx, "collapse flags", nodes * 4)?,
            kept_scan: storage_buffer_zeroed(ctx, "collapse kept scan", nodes * 4)?,
            leaf_prim_scan: storage_buffer_zeroed(ctx, "collapse leaf scan", nodes * 4)?,
            out_nodes: storage_buffer_zeroed(
                ctx,
                "bvh nodes",
                nodes * std::mem::size_of::<BvhNode>() as u64,
            )?,
            out_prims: storage_buffer_zeroed(ctx, "prim indices", u64::from(capacity) * 4)?,
            tree_counts: storage_buffer_zeroed(ctx, "tree counts", 8)?,
        })
    }
}

/// A GPU build's intermediate trees, read back for comparison in tests: the LBVH the rounds start
/// from (costs and counts not yet set), the working tree after the rounds, the collapsed tree.
#[derive(Clone, Debug)]
pub struct TrbvhStages {
    pub lbvh: WorkingTree,
    pub working: WorkingTree,
    pub bvh: Bvh,
}

/// The trees around the rounds of one build: the LBVH before them and the working tree after.
type RoundTrees = (WorkingTree, WorkingTree);

/// GPU TRBVH builder: LBVH + treelet rounds + collapse, pipelines and scratch reused per frame.
pub struct TrbvhBuilder {
    lbvh: LbvhBuilder,
    presplit: Option<PreSplitter>,
    optimizer: TreeletOptimizer,
    collapse: Collapse,
    scratch: Option<Scratch>,
    pub settings: TreeletSettings,
    pub sah: SahParams,
}

impl TrbvhBuilder {
    pub fn new(ctx: &GpuContext, settings: TreeletSettings, sah: SahParams) -> Result<Self> {
        settings.validate(&sah)?;
        Ok(Self {
            lbvh: LbvhBuilder::new(ctx),
            presplit: None,
            optimizer: TreeletOptimizer::new(ctx),
            collapse: Collapse::new(ctx)?,
            scratch: None,
            settings,
            sah,
        })
    }

    /// Builds the optimized tree of `scene` into its `nodes`/`prim_indices`; returns stage times.
    pub fn build(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<Vec<StageTime>> {
        self.build_inner(ctx, scene, false)
            .map(|(stages, _)| stages)
    }

    /// Like `build`, in two submissions, reading back the LBVH before the rounds and the working
    /// tree after them (tests).
    pub fn build_stages(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<TrbvhStages> {
        let (_, trees) = self.build_inner(ctx, scene, true)?;
        let (lbvh, working) = trees.expect("requested");
        Ok(TrbvhStages {
            lbvh,
            working,
            bvh: scene.download_bvh(ctx)?,
        })
    }

    fn build_inner(
        &mut self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        read_trees: bool,
    ) -> Result<(Vec<StageTime>, Option<RoundTrees>)> {
        self.settings.validate(&self.sah)?;
        let gammas = self.settings.gammas();
        let mut timer = GpuTimer::new(ctx, 8 + gammas.len() as u32);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let budget = split_budget(scene.triangle_count, self.settings.split_percent);
        let n = if budget == 0 {
            self.lbvh.record(ctx, &mut encoder, scene, &mut timer)?
        } else {
            // Split counts, then (after reading the reference count back) the split and the LBVH
            // over the references.
            let splitter = self.presplit.get_or_insert_with(|| PreSplitter::new(ctx));
            splitter.record_counts(ctx, &mut encoder, scene, budget, &mut timer)?;
            ctx.queue.submit([encoder.finish()]);
            let total = splitter.read_total(ctx)?;
            encoder = ctx.device.create_command_encoder(&Default::default());
            self.lbvh.reserve(ctx, total)?;
            let prim_boxes = self.lbvh.prim_boxes().expect("reserved");
            splitter.record_split(ctx, &mut encoder, scene, total, prim_boxes, &mut timer)?;
            self.lbvh
                .record_prims(ctx, &mut encoder, scene, total, &mut timer)?
        };
        if self.scratch.as_ref().is_none_or(|s| s.capacity < n) {
            self.scratch = None;
            self.scratch = Some(Scratch::new(ctx, n)?);
        }
        let scratch = self.scratch.as_mut().expect("allocated above");
        // The output buffers swap with the scene's each build, so they may come from a smaller scene.
        let node_bytes = u64::from(2 * n - 1) * std::mem::size_of::<BvhNode>() as u64;
        if scratch.out_nodes.size() < node_bytes {
            scratch.out_nodes = storage_buffer_zeroed(ctx, "bvh nodes", node_bytes)?;
        }
        if scratch.out_prims.size() < u64::from(n) * 4 {
            scratch.out_prims = storage_buffer_zeroed(ctx, "prim indices", u64::from(n) * 4)?;
        }
        let scratch = &*scratch;
        let parents = self.lbvh.parents().expect("recorded above");
        let read_tree = |ctx: &GpuContext| -> Result<WorkingTree> {
            let count = (2 * n - 1) as usize;
            Ok(WorkingTree {
                nodes: read_buffer(ctx, &scene.nodes, count)?,
                parents: read_buffer(ctx, parents, count)?,
                prims: read_buffer(ctx, &scene.prim_indices, n as usize)?,
                prim_counts: read_buffer(ctx, &scratch.prim_counts, count)?,
                costs: read_buffer(ctx, &scratch.costs, count)?,
            })
        };
        let lbvh = if read_trees {
            ctx.queue.submit([encoder.finish()]);
            encoder = ctx.device.create_command_encoder(&Default::default());
            let tree = read_tree(ctx)?;
            Some(WorkingTree::from_lbvh(
                Bvh {
                    nodes: tree.nodes,
                    prim_indices: tree.prims,
                },
                tree.parents,
            ))
        } else {
            None
        };
        let state = TreeletState {
            parents,
            prim_counts: &scratch.prim_counts,
            costs: &scratch.costs,
            arrivals: &scratch.arrivals,
        };
        let model = CostModel::from(&self.sah);
        for gamma in gammas {
            encoder.clear_buffer(&scratch.arrivals, 0, None);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("treelet round"),
                timestamp_writes: timer.pass("treelets"),
            });
            let round = Round {
                model,
                treelet_size: self.settings.treelet_size,
                gamma,
            };
            self.optimizer.record(ctx, &mut pass, scene, &state, &round);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("collapse"),
                timestamp_writes: timer.pass("collapse"),
            });
            let out = CollapseBuffers {
                flags: &scratch.flags,
                kept_scan: &scratch.kept_scan,
                leaf_prim_scan: &scratch.leaf_prim_scan,
                out_nodes: &scratch.out_nodes,
                out_prims: &scratch.out_prims,
                tree_counts: &scratch.tree_counts,
                ref_tris: if budget == 0 {
                    None
                } else {
                    self.presplit.as_ref().and_then(PreSplitter::ref_tris)
                },
            };
            self.collapse
                .record(ctx, &mut pass, scene, &state, &model, &out)?;
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let stages = timer.read(ctx)?;
        let trees = match lbvh {
            Some(lbvh) => Some((lbvh, read_tree(ctx)?)),
            None => None,
        };
        let counts: Vec<u32> = read_buffer(ctx, &scratch.tree_counts, 2)?;
        // The compacted tree becomes the scene's; the working buffers become next build's output.
        let scratch = self.scratch.as_mut().expect("allocated above");
        std::mem::swap(&mut scene.nodes, &mut scratch.out_nodes);
        std::mem::swap(&mut scene.prim_indices, &mut scratch.out_prims);
        scene.node_count = counts[0];
        scene.prim_count = counts[1];
        Ok((stages, trees))
    }
}
