//! GPU LBVH construction (Karras 2012, "Maximizing Parallelism in the Construction of BVHs, Octrees,
//! and k-d Trees"), every stage a WGSL kernel: centroid bounds → Morton keys → radix sort →
//! hierarchy and bounds in one bottom-up climb (Apetrei 2014). Each stage has a CPU twin; `build_lbvh_cpu` chains them
//! into the reference tree (tests compare each GPU stage with its twin fed the GPU's own input).
//!
//! Output layout (the project's `BvhNode` layout): internal nodes 0..n-2 (root 0), leaf j at node
//! n-1+j holding `prim_indices[j]`, the primitives in Morton order.

mod centroids_reduce;
mod lbvh_climb;
mod morton_compute;
mod triangles_bounds;

pub use centroids_reduce::{box_of_words, centroid_bounds_cpu, CentroidsReduce, CENTROIDS_REDUCE};
pub use lbvh_climb::{assemble_lbvh_cpu, hierarchy_cpu, Hierarchy, LBVH_CLIMB};
pub use morton_compute::{
    morton_key, morton_keys_cpu, KeyWidth, LBVH_KEY_BITS, LBVH_PACKED_KEY_BITS, MORTON_BITS,
    MORTON_COMPUTE, TRBVH_KEY_BITS,
};
pub use triangles_bounds::{
    prim_boxes_cpu, TriangleBoundsOutput, TrianglesBounds, TRIANGLES_BOUNDS,
};

use lbvh_climb::{ClimbBuffers, LbvhClimb};
use morton_compute::MortonCompute;

use super::Bvh;
use crate::device::{Geometry, Tree};
use crate::geometry::Aabb;
use crate::gpu::{
    read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, ItemCount, ParamSlab, Recorder,
    StageTime,
};
use crate::scene::Triangle;
use crate::sort::{sort_pairs_cpu, RadixSort, SortValues};
use crate::{Error, Result};

/// What an LBVH is built over.
#[derive(Clone, Copy, Debug)]
pub enum LbvhInput<'a> {
    /// The first `count` triangles of a triangle buffer (`scene::Triangle` each).
    Triangles {
        buffer: &'a wgpu::Buffer,
        count: u32,
    },
    /// The primitive boxes already written to `LbvhBuilder::prim_boxes` (by the pre-splitting
    /// stage, which computes their count on the GPU).
    PrimBoxes(ItemCount<'a>),
}

impl<'a> LbvhInput<'a> {
    fn count(self) -> ItemCount<'a> {
        match self {
            LbvhInput::Triangles { count, .. } => ItemCount::Known(count),
            LbvhInput::PrimBoxes(count) => count,
        }
    }
}

/// CPU twin of the whole GPU LBVH pipeline over triangles (the `lbvh` builder's key width,
/// `KeyWidth::LBVH`).
pub fn build_lbvh_cpu(triangles: &[Triangle]) -> Bvh {
    let key_bits = KeyWidth::LBVH.bits(triangles.len() as u32);
    build_lbvh_from_boxes_cpu(&prim_boxes_cpu(triangles), key_bits).0
}

/// CPU twin of the LBVH stages over primitive boxes with keys of `key_bits` (1..=48) bits: the
/// tree and its parent links.
pub fn build_lbvh_from_boxes_cpu(prim_boxes: &[Aabb], key_bits: u32) -> (Bvh, Vec<u32>) {
    if prim_boxes.is_empty() {
        return (Bvh::default(), Vec::new());
    }
    let bounds = centroid_bounds_cpu(prim_boxes);
    let keys = morton_keys_cpu(prim_boxes, &bounds, key_bits);
    let values: Vec<u32> = (0..prim_boxes.len() as u32).collect();
    let (sorted_keys, sorted_prims) = sort_pairs_cpu(&keys, &values, key_bits);
    let hierarchy = hierarchy_cpu(&sorted_keys);
    let bvh = assemble_lbvh_cpu(prim_boxes, &hierarchy, &sorted_prims);
    (bvh, hierarchy.parents)
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

/// Scratch buffers sized for up to `capacity` primitives.
struct Scratch {
    capacity: u32,
    prim_boxes: wgpu::Buffer,
    /// The centroid bounds, as the reduction's box words.
    centroid_box: wgpu::Buffer,
    keys: wgpu::Buffer,
    parents: wgpu::Buffer,
    arrivals: wgpu::Buffer,
}

/// The GPU LBVH builder: kernels and scratch space, reused across frames.
pub struct LbvhBuilder {
    triangles_bounds: TrianglesBounds,
    centroids: CentroidsReduce,
    morton: MortonCompute,
    sort: RadixSort,
    climb: LbvhClimb,
    scratch: Option<Scratch>,
    /// Parameters of the builds this builder records and submits itself (`build`).
    params: ParamSlab,
}

/// Timestamped passes one build records (bounds, morton, sort, hierarchy).
pub const LBVH_PASSES: u32 = 4;

impl LbvhBuilder {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            triangles_bounds: TrianglesBounds::new(ctx),
            centroids: CentroidsReduce::new(ctx),
            morton: MortonCompute::new(ctx, KeyWidth::LBVH),
            sort: RadixSort::new(ctx),
            climb: LbvhClimb::new(ctx),
            scratch: None,
            params: ParamSlab::new(ctx),
        }
    }

    /// Keys of `key_bits` (1..=48) bits at every count instead of `KeyWidth::LBVH`: the high
    /// bits of the full key.
    pub fn with_key_bits(mut self, key_bits: u32) -> Result<Self> {
        if !(1..=MORTON_BITS).contains(&key_bits) {
            return Err(Error::InvalidArgument(format!(
                "Morton key bits must be 1..={MORTON_BITS}, got {key_bits}"
            )));
        }
        self.morton.width = KeyWidth::fixed(key_bits);
        Ok(self)
    }

    /// The radix sort's tile in the next builds (`RadixSort::set_tile_items`; the same tree for
    /// every tile).
    pub fn set_sort_tile_items(&mut self, items: Option<u32>) -> Result<()> {
        self.sort.set_tile_items(items)
    }

    /// Builds `geometry`'s tree into `tree` in one submission and waits; returns the per-stage
    /// GPU times.
    pub fn build(
        &mut self,
        ctx: &GpuContext,
        geometry: &Geometry,
        tree: &mut Tree,
    ) -> Result<Vec<StageTime>> {
        let mut timer = GpuTimer::new(ctx, LBVH_PASSES);
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let result = {
            let mut rec = Recorder::new(ctx, &mut params, Some(&mut timer));
            let result = self.record(&mut rec, geometry, tree);
            rec.submit();
            result
        };
        self.params = params;
        result?;
        timer.read(ctx)
    }

    /// Records a whole build over `geometry`'s triangles into `tree` (4 timestamped passes),
    /// grown as needed: internal nodes 0..n-2, leaf j at node n-1+j.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        tree: &mut Tree,
    ) -> Result<()> {
        let n = geometry.triangle_count;
        self.reserve(rec.ctx, n)?;
        tree.reserve(rec.ctx, 2 * n - 1, n)?;
        let input = LbvhInput::Triangles {
            buffer: &geometry.triangles,
            count: n,
        };
        self.record_into(rec, input, &tree.nodes, &tree.prim_indices)?;
        rec.ctx
            .queue
            .write_buffer(&tree.counts, 0, bytemuck::cast_slice(&[2 * n - 1, n]));
        Ok(())
    }

    /// Records a build over `input`'s n primitives into `nodes` (2n − 1) and `order` (the
    /// primitive of each leaf, n); with primitive boxes as the input, after
    /// `reserve(count.capacity())`.
    pub fn record_into(
        &mut self,
        rec: &mut Recorder<'_>,
        input: LbvhInput<'_>,
        nodes: &wgpu::Buffer,
        order: &wgpu::Buffer,
    ) -> Result<()> {
        self.record_sorted_into(rec, input, order)?;
        self.record_climb(rec, input.count(), nodes, order);
        Ok(())
    }

    /// Like `record_into` without the tree: the sorted keys (`keys()`) and the sorted primitive
    /// order in `order`, for a caller that builds the hierarchy and boxes in a bottom-up climb of
    /// its own (the treelet rounds' first schedule does, with its counts and costs, from
    /// `keys()` and `prim_boxes()` into `parents()`).
    pub fn record_sorted_into(
        &mut self,
        rec: &mut Recorder<'_>,
        input: LbvhInput<'_>,
        order: &wgpu::Buffer,
    ) -> Result<()> {
        self.reserve(rec.ctx, input.count().capacity())?;
        self.record_keys(rec, input, order);
        self.record_sort(rec, input.count(), order)
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
                centroid_box: CentroidsReduce::box_buffer(ctx)?,
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

    /// The sorted Morton keys of the last build (`[u32; 2]` each, low word first); valid after
    /// `reserve`.
    pub fn keys(&self) -> Option<&wgpu::Buffer> {
        self.scratch.as_ref().map(|s| &s.keys)
    }

    /// Like `build`, but in two submissions with every intermediate buffer read back (tests).
    pub fn build_stages(&mut self, ctx: &GpuContext, geometry: &Geometry) -> Result<LbvhStages> {
        let n = geometry.triangle_count;
        let mut tree = Tree::empty(ctx)?;
        self.reserve(ctx, n)?;
        tree.reserve(ctx, 2 * n - 1, n)?;
        let mut params = ParamSlab::new(ctx);
        let mut rec = Recorder::new(ctx, &mut params, None);
        let input = LbvhInput::Triangles {
            buffer: &geometry.triangles,
            count: n,
        };
        self.record_keys(&mut rec, input, &tree.prim_indices);
        rec.submit();
        let scratch = self.scratch.as_ref().expect("reserved");
        let box_words: Vec<u32> = read_buffer(ctx, &scratch.centroid_box, 8)?;
        // Keys that pack the indices hold them above their bits: the sorted primitives show
        // whether they were right.
        let key_mask = if self.morton.packs_indices(n) {
            u64::MAX >> (64 - self.morton.key_bits(n))
        } else {
            u64::MAX
        };
        let keys = read_keys(ctx, &scratch.keys, n)?
            .into_iter()
            .map(|k| k & key_mask)
            .collect();
        let mut rec = Recorder::new(ctx, &mut params, None);
        self.record_sort(&mut rec, input.count(), &tree.prim_indices)?;
        self.record_climb(&mut rec, input.count(), &tree.nodes, &tree.prim_indices);
        rec.submit();
        let scratch = self.scratch.as_ref().expect("reserved");
        let sorted_prims: Vec<u32> = read_buffer(ctx, &tree.prim_indices, n as usize)?;
        Ok(LbvhStages {
            centroid_bounds: box_of_words(&box_words),
            keys,
            sorted_keys: read_keys(ctx, &scratch.keys, n)?,
            parents: read_buffer(ctx, &scratch.parents, 2 * n as usize - 1)?,
            bvh: Bvh {
                nodes: read_buffer(ctx, &tree.nodes, 2 * n as usize - 1)?,
                prim_indices: sorted_prims.clone(),
            },
            sorted_prims,
        })
    }

    /// Stages 0-2: primitive boxes of the triangles (for triangle input), centroid bounds, and
    /// Morton keys with the identity permutation in `order` (the values the sort reorders).
    fn record_keys(&self, rec: &mut Recorder<'_>, input: LbvhInput<'_>, order: &wgpu::Buffer) {
        let count = input.count();
        let scratch = self.scratch.as_ref().expect("reserved");
        rec.encoder().clear_buffer(&scratch.centroid_box, 0, None);
        {
            let mut pass = rec.pass("bounds");
            match input {
                LbvhInput::Triangles { buffer, count } => self.triangles_bounds.record(
                    &mut pass,
                    buffer,
                    count,
                    TriangleBoundsOutput::LbvhInput(&scratch.prim_boxes),
                    &scratch.centroid_box,
                ),
                LbvhInput::PrimBoxes(count) => self.centroids.record(
                    &mut pass,
                    &scratch.prim_boxes,
                    count,
                    &scratch.centroid_box,
                ),
            }
        }
        let mut pass = rec.pass("morton");
        self.morton.record(
            &mut pass,
            &scratch.prim_boxes,
            count,
            &scratch.centroid_box,
            &scratch.keys,
            order,
        );
    }

    /// Stage 3: the sort of the keys, with the leaves' primitives in `order`.
    fn record_sort(
        &mut self,
        rec: &mut Recorder<'_>,
        count: ItemCount<'_>,
        order: &wgpu::Buffer,
    ) -> Result<()> {
        let scratch = self.scratch.as_ref().expect("reserved");
        let key_bits = self.morton.key_bits(count.capacity());
        let values_at = if self.morton.packs_indices(count.capacity()) {
            SortValues::AboveKeys
        } else {
            SortValues::Apart
        };
        self.sort
            .record(rec, &scratch.keys, order, count, key_bits, values_at)
    }

    /// Stages 4-5: hierarchy and bounds into `nodes` in one climb (pass "hierarchy"). The
    /// arrival words are zero from their allocation, and every climb leaves them zero.
    fn record_climb(
        &self,
        rec: &mut Recorder<'_>,
        count: ItemCount<'_>,
        nodes: &wgpu::Buffer,
        order: &wgpu::Buffer,
    ) {
        let scratch = self.scratch.as_ref().expect("reserved");
        self.climb.record(
            &mut rec.pass("hierarchy"),
            count,
            &ClimbBuffers {
                keys: &scratch.keys,
                order,
                prim_boxes: &scratch.prim_boxes,
                nodes,
                parents: &scratch.parents,
                arrivals: &scratch.arrivals,
            },
        );
    }
}

fn read_keys(ctx: &GpuContext, keys: &wgpu::Buffer, n: u32) -> Result<Vec<u64>> {
    let words: Vec<[u32; 2]> = read_buffer(ctx, keys, n as usize)?;
    Ok(words
        .iter()
        .map(|&[lo, hi]| u64::from(lo) | (u64::from(hi) << 32))
        .collect())
}
