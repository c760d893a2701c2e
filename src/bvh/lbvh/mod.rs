//! GPU LBVH construction (Karras 2012, "Maximizing Parallelism in the Construction of BVHs, Octrees,
//! and k-d Trees"), every stage a WGSL kernel: centroid bounds → Morton keys → radix sort →
//! hierarchy emission → bottom-up bounds. Each stage has a CPU twin; `build_lbvh_cpu` chains them
//! into the reference tree that the GPU output must equal bit for bit.
//!
//! Output layout (the project's `BvhNode` layout): internal nodes 0..n-2 (root 0), leaf j at node
//! n-1+j holding `prim_indices[j]`, the primitives in Morton order.

mod centroid_bounds;
mod hierarchy;
mod morton;
mod refit;

pub use centroid_bounds::centroid_bounds_cpu;
pub use hierarchy::{hierarchy_cpu, Hierarchy};
pub use morton::{morton_key, morton_keys_cpu, MORTON_BITS};
pub use refit::assemble_lbvh_cpu;

use centroid_bounds::CentroidBounds;
use hierarchy::HierarchyEmission;
use morton::MortonKeys;
use refit::BoundsRefit;

use super::{Bvh, BvhNode};
use crate::geometry::Aabb;
use crate::gpu::{read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, StageTime};
use crate::scene::Triangle;
use crate::sort::{sort_pairs_cpu, RadixSort};
use crate::trace::GpuScene;
use crate::{Error, Result};

/// CPU twin of the whole GPU LBVH pipeline.
pub fn build_lbvh_cpu(triangles: &[Triangle]) -> Bvh {
    if triangles.is_empty() {
        return Bvh::default();
    }
    let bounds = centroid_bounds_cpu(triangles);
    let keys = morton_keys_cpu(triangles, &bounds);
    let values: Vec<u32> = (0..triangles.len() as u32).collect();
    let (sorted_keys, sorted_prims) = sort_pairs_cpu(&keys, &values, MORTON_BITS);
    assemble_lbvh_cpu(triangles, &hierarchy_cpu(&sorted_keys), &sorted_prims)
}

/// Intermediate results of one GPU build, read back for stage-by-stage comparison in tests.
#[derive(Clone, Debug)]
pub struct LbvhStages {
    pub centroid_bounds: Aabb,
    pub keys: Vec<u64>,
    pub sorted_keys: Vec<u64>,
    pub sorted_prims: Vec<u32>,
    pub parents: Vec<u32>,
    pub bvh: Bvh,
}

/// Scratch buffers sized for up to `capacity` triangles.
struct Scratch {
    capacity: u32,
    bounds_levels: Vec<wgpu::Buffer>,
    keys: wgpu::Buffer,
    parents: wgpu::Buffer,
    arrivals: wgpu::Buffer,
}

/// The GPU LBVH builder: pipelines and scratch space, reused across frames.
pub struct LbvhBuilder {
    bounds: CentroidBounds,
    morton: MortonKeys,
    sort: RadixSort,
    hierarchy: HierarchyEmission,
    refit: BoundsRefit,
    scratch: Option<Scratch>,
}

/// Timestamped passes one build records (bounds, morton, sort, hierarchy, refit).
const TIMER_CAPACITY: u32 = 5;

impl LbvhBuilder {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            bounds: CentroidBounds::new(ctx),
            morton: MortonKeys::new(ctx),
            sort: RadixSort::new(ctx),
            hierarchy: HierarchyEmission::new(ctx),
            refit: BoundsRefit::new(ctx),
            scratch: None,
        }
    }

    /// Builds the tree of `scene`'s triangles into `scene.nodes`/`scene.prim_indices` in one
    /// submission; returns the per-stage GPU times.
    pub fn build(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<Vec<StageTime>> {
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record(ctx, &mut encoder, scene, &mut timer)?;
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        timer.read(ctx)
    }

    /// Records a whole build into `encoder` (5 timestamped passes); returns the triangle count.
    /// Later stages (treelet optimization) append to the same encoder.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &mut GpuScene,
        timer: &mut GpuTimer,
    ) -> Result<u32> {
        let n = self.prepare(ctx, scene)?;
        self.record_keys(ctx, encoder, scene, n, timer);
        self.record_tree(ctx, encoder, scene, n, timer)?;
        Ok(n)
    }

    /// Parent links of the last build's nodes (root: unspecified), for passes that climb the tree.
    pub fn parents(&self) -> Option<&wgpu::Buffer> {
        self.scratch.as_ref().map(|s| &s.parents)
    }

    /// Like `build`, but in two submissions with every intermediate buffer read back.
    pub fn build_stages(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<LbvhStages> {
        let n = self.prepare(ctx, scene)?;
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record_keys(ctx, &mut encoder, scene, n, &mut timer);
        ctx.queue.submit([encoder.finish()]);
        let scratch = self.scratch.as_ref().expect("prepared");
        let bounds_node: Vec<BvhNode> =
            read_buffer(ctx, scratch.bounds_levels.last().expect("one level"), 1)?;
        let keys = read_keys(ctx, &scratch.keys, n)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record_tree(ctx, &mut encoder, scene, n, &mut timer)?;
        ctx.queue.submit([encoder.finish()]);
        let scratch = self.scratch.as_ref().expect("prepared");
        Ok(LbvhStages {
            centroid_bounds: bounds_node[0].bounds(),
            keys,
            sorted_keys: read_keys(ctx, &scratch.keys, n)?,
            sorted_prims: read_buffer(ctx, &scene.prim_indices, n as usize)?,
            parents: read_buffer(ctx, &scratch.parents, 2 * n as usize - 1)?,
            bvh: scene.download_bvh(ctx)?,
        })
    }

    /// Sizes scratch and output buffers for the scene; returns the triangle count.
    fn prepare(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<u32> {
        let n = scene.triangle_count;
        if n == 0 {
            return Err(Error::InvalidArgument(
                "cannot build a BVH over zero triangles".into(),
            ));
        }
        let node_bytes = u64::from(2 * n - 1) * std::mem::size_of::<BvhNode>() as u64;
        if scene.nodes.size() < node_bytes {
            scene.nodes = storage_buffer_zeroed(ctx, "bvh nodes", node_bytes)?;
        }
        if scene.prim_indices.size() < u64::from(n) * 4 {
            scene.prim_indices = storage_buffer_zeroed(ctx, "prim indices", u64::from(n) * 4)?;
        }
        if self.scratch.as_ref().is_none_or(|s| s.capacity < n) {
            self.scratch = Some(Scratch {
                capacity: n,
                bounds_levels: CentroidBounds::level_buffers(ctx, n)?,
                keys: storage_buffer_zeroed(ctx, "morton keys", u64::from(n) * 8)?,
                parents: storage_buffer_zeroed(ctx, "parents", u64::from(2 * n - 1) * 4)?,
                arrivals: storage_buffer_zeroed(ctx, "arrival counters", u64::from(n) * 4)?,
            });
        }
        scene.node_count = 2 * n - 1;
        scene.prim_count = n;
        Ok(n)
    }

    /// Stages 1-2: centroid bounds and Morton keys (values = identity permutation).
    fn record_keys(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        n: u32,
        timer: &mut GpuTimer,
    ) {
        let scratch = self.scratch.as_ref().expect("prepared");
        // The level buffers are sized for the capacity; reduce over exactly the levels n needs.
        let levels = CentroidBounds::level_count(n);
        let bounds_levels = &scratch.bounds_levels[..levels];
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("centroid bounds"),
                timestamp_writes: timer.pass("bounds"),
            });
            self.bounds
                .record(ctx, &mut pass, &scene.triangles, n, bounds_levels);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("morton keys"),
            timestamp_writes: timer.pass("morton"),
        });
        self.morton.record(
            ctx,
            &mut pass,
            scene,
            &bounds_levels[levels - 1],
            &scratch.keys,
        );
    }

    /// Stages 3-5: sort, hierarchy emission, bottom-up bounds.
    fn record_tree(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        n: u32,
        timer: &mut GpuTimer,
    ) -> Result<()> {
        let scratch = self.scratch.as_ref().expect("prepared");
        self.sort.sort(
            ctx,
            encoder,
            &scratch.keys,
            &scene.prim_indices,
            n,
            MORTON_BITS,
            Some(&mut *timer),
        )?;
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("lbvh hierarchy"),
                timestamp_writes: timer.pass("hierarchy"),
            });
            self.hierarchy.record(
                ctx,
                &mut pass,
                &scratch.keys,
                n,
                &scene.nodes,
                &scratch.parents,
            );
        }
        encoder.clear_buffer(&scratch.arrivals, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bounds refit"),
            timestamp_writes: timer.pass("refit"),
        });
        self.refit
            .record(ctx, &mut pass, scene, &scratch.parents, &scratch.arrivals);
        Ok(())
    }
}

fn read_keys(ctx: &GpuContext, keys: &wgpu::Buffer, n: u32) -> Result<Vec<u64>> {
    let words: Vec<[u32; 2]> = read_buffer(ctx, keys, n as usize)?;
    Ok(words
        .iter()
        .map(|&[lo, hi]| u64::from(lo) | (u64::from(hi) << 32))
        .collect())
}
