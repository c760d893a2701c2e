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
mod prim_bounds;
mod refit;

pub use centroid_bounds::centroid_bounds_cpu;
pub use hierarchy::{hierarchy_cpu, Hierarchy};
pub use morton::{morton_key, morton_keys_cpu, MORTON_BITS};
pub use prim_bounds::{prim_boxes_cpu, GpuAabb};
pub use refit::assemble_lbvh_cpu;

pub use centroid_bounds::CentroidBounds;
use hierarchy::HierarchyEmission;
use morton::MortonKeys;
pub use prim_bounds::TriangleBounds;
use refit::BoundsRefit;

use super::{Bvh, BvhNode};
use crate::geometry::Aabb;
use crate::gpu::{read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, StageTime};
use crate::scene::Triangle;
use crate::sort::{sort_pairs_cpu, RadixSort};
use crate::trace::GpuScene;
use crate::{Error, Result};

/// CPU twin of the whole GPU LBVH pipeline over triangles.
pub fn build_lbvh_cpu(triangles: &[Triangle]) -> Bvh {
    build_lbvh_from_boxes_cpu(&prim_boxes_cpu(triangles)).0
}

/// CPU twin of the LBVH stages over primitive boxes: the tree and its parent links.
pub fn build_lbvh_from_boxes_cpu(prim_boxes: &[Aabb]) -> (Bvh, Vec<u32>) {
    if prim_boxes.is_empty() {
        return (Bvh::default(), Vec::new());
    }
    let bounds = centroid_bounds_cpu(prim_boxes);
    let keys = morton_keys_cpu(prim_boxes, &bounds);
    let values: Vec<u32> = (0..prim_boxes.len() as u32).collect();
    let (sorted_keys, sorted_prims) = sort_pairs_cpu(&keys, &values, MORTON_BITS);
    let hierarchy = hierarchy_cpu(&sorted_keys);
    let bvh = assemble_lbvh_cpu(prim_boxes, &hierarchy, &sorted_prims);
    (bvh, hierarchy.parents)
}

/// The primitives a build runs over: `count` boxes (`GpuAabb`) in `boxes`.
pub(crate) struct Prims<'a> {
    pub boxes: &'a wgpu::Buffer,
    pub count: u32,
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
    prim_boxes: wgpu::Buffer,
    bounds_levels: Vec<wgpu::Buffer>,
    keys: wgpu::Buffer,
    parents: wgpu::Buffer,
    arrivals: wgpu::Buffer,
}

/// The GPU LBVH builder: pipelines and scratch space, reused across frames.
pub struct LbvhBuilder {
    triangle_bounds: TriangleBounds,
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
            triangle_bounds: TriangleBounds::new(ctx),
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

    /// Records a whole build over the scene's triangles into `encoder` (5 timestamped passes);
    /// returns the primitive count. Later stages (treelet optimization) append to the encoder.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &mut GpuScene,
        timer: &mut GpuTimer,
    ) -> Result<u32> {
        let n = scene.triangle_count;
        self.prepare(ctx, scene, n)?;
        self.record_keys(ctx, encoder, scene, n, true, timer);
        self.record_tree(ctx, encoder, scene, n, timer)?;
        Ok(n)
    }

    /// Records a build over `count` primitive boxes already written to `prim_boxes()` (by the
    /// pre-splitting stage, after `reserve(count)`); returns `count`.
    pub fn record_prims(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &mut GpuScene,
        count: u32,
        timer: &mut GpuTimer,
    ) -> Result<u32> {
        self.prepare(ctx, scene, count)?;
        self.record_keys(ctx, encoder, scene, count, false, timer);
        self.record_tree(ctx, encoder, scene, count, timer)?;
        Ok(count)
    }

    /// Grows the scratch space to hold `capacity` primitives.
    pub fn reserve(&mut self, ctx: &GpuContext, capacity: u32) -> Result<()> {
        if capacity == 0 {
            return Err(Error::InvalidArgument(
                "cannot build a BVH over zero primitives".into(),
            ));
        }
        if self.scratch.as_ref().is_none_or(|s| s.capacity < capacity) {
            let n = u64::from(capacity);
            self.scratch = None;
            self.scratch = Some(Scratch {
                capacity,
                prim_boxes: storage_buffer_zeroed(ctx, "prim boxes", n * 32)?,
                bounds_levels: CentroidBounds::level_buffers(ctx, capacity)?,
                keys: storage_buffer_zeroed(ctx, "morton keys", n * 8)?,
                parents: storage_buffer_zeroed(ctx, "parents", (2 * n - 1) * 4)?,
                arrivals: storage_buffer_zeroed(ctx, "arrival counters", n * 4)?,
            });
        }
        Ok(())
    }

    /// The primitive boxes the build reads (`GpuAabb` each); valid after `reserve`.
    pub fn prim_boxes(&self) -> Option<&wgpu::Buffer> {
        self.scratch.as_ref().map(|s| &s.prim_boxes)
    }

    /// Parent links of the last build's nodes (root: unspecified), for passes that climb the tree.
    pub fn parents(&self) -> Option<&wgpu::Buffer> {
        self.scratch.as_ref().map(|s| &s.parents)
    }

    /// Like `build`, but in two submissions with every intermediate buffer read back.
    pub fn build_stages(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<LbvhStages> {
        let n = scene.triangle_count;
        self.prepare(ctx, scene, n)?;
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.record_keys(ctx, &mut encoder, scene, n, true, &mut timer);
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

    /// Sizes scratch and output buffers for `n` primitives.
    fn prepare(&mut self, ctx: &GpuContext, scene: &mut GpuScene, n: u32) -> Result<()> {
        self.reserve(ctx, n)?;
        let node_bytes = u64::from(2 * n - 1) * std::mem::size_of::<BvhNode>() as u64;
        if scene.nodes.size() < node_bytes {
            scene.nodes = storage_buffer_zeroed(ctx, "bvh nodes", node_bytes)?;
        }
        if scene.prim_indices.size() < u64::from(n) * 4 {
            scene.prim_indices = storage_buffer_zeroed(ctx, "prim indices", u64::from(n) * 4)?;
        }
        scene.node_count = 2 * n - 1;
        scene.prim_count = n;
        Ok(())
    }

    /// Stages 0-2: primitive boxes of the triangles (when `from_triangles`), centroid bounds and
    /// Morton keys (values = identity permutation).
    fn record_keys(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        n: u32,
        from_triangles: bool,
        timer: &mut GpuTimer,
    ) {
        let scratch = self.scratch.as_ref().expect("prepared");
        let prims = Prims {
            boxes: &scratch.prim_boxes,
            count: n,
        };
        // The level buffers are sized for the capacity; reduce over exactly the levels n needs.
        let levels = CentroidBounds::level_count(n);
        let bounds_levels = &scratch.bounds_levels[..levels];
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("centroid bounds"),
                timestamp_writes: timer.pass("bounds"),
            });
            if from_triangles {
                self.triangle_bounds.record(
                    ctx,
                    &mut pass,
                    &scene.triangles,
                    n,
                    &scratch.prim_boxes,
                );
            }
            self.bounds
                .record(ctx, &mut pass, &scratch.prim_boxes, n, bounds_levels, true);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("morton keys"),
            timestamp_writes: timer.pass("morton"),
        });
        self.morton.record(
            ctx,
            &mut pass,
            &prims,
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
        let prims = Prims {
            boxes: &scratch.prim_boxes,
            count: n,
        };
        self.refit.record(
            ctx,
            &mut pass,
            &prims,
            scene,
            &scratch.parents,
            &scratch.arrivals,
        );
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
