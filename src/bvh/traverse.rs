//! CPU traversal of a tree: closest hit and any hit with the watertight triangle test, the twin of
//! `shaders/include/bvh_traverse.wgsl` (same robust box test, nearer child first), and the steps
//! it takes (`TraversalSteps`, which the GPU traversals count too). Used by tests and tools that
//! trace a few rays without a GPU; the renderer traces on the GPU.

use glam::Vec3;

use super::Bvh;
use crate::geometry::{Hit, Ray, RayTriangleTest};
use crate::gpu::constants::BOX_EXIT_SLACK;
use crate::scene::Triangle;

/// The work of traversals: the internal nodes whose children's boxes they tested (a binary node's
/// two, a wide node's eight) and the triangles they tested. Exact counts of the same rays through
/// two trees compare the trees' trace cost on any device, however noisy its timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalSteps {
    pub nodes: u64,
    pub triangles: u64,
}

impl std::ops::AddAssign for TraversalSteps {
    fn add_assign(&mut self, other: Self) {
        self.nodes += other.nodes;
        self.triangles += other.triangles;
    }
}

impl std::iter::Sum for TraversalSteps {
    fn sum<I: Iterator<Item = Self>>(steps: I) -> Self {
        steps.fold(Self::default(), |mut sum, s| {
            sum += s;
            sum
        })
    }
}

/// The ray as the box test needs it (see `BoxRay` in bvh_traverse.wgsl).
struct BoxRay {
    origin: Vec3,
    /// 1 / direction, components below 1e-30 replaced by 1e-30.
    inv_dir: Vec3,
    /// 3e38 on axes the ray does not move along: their slabs become (-inf, inf), so a ray in the
    /// plane of a flat box's face still enters it.
    slab_pad: Vec3,
}

impl BoxRay {
    fn new(ray: &Ray) -> Self {
        let dir = Vec3::from(ray.dir);
        let flat = dir.abs().cmplt(Vec3::splat(1e-30));
        Self {
            origin: Vec3::from(ray.origin),
            inv_dir: Vec3::select(flat, Vec3::splat(1e-30), dir).recip(),
            slab_pad: Vec3::select(flat, Vec3::splat(3e38), Vec3::ZERO),
        }
    }

    /// Entry distance into the box of `node`, or `None` when it misses [t_min, t_max].
    fn entry(&self, bvh: &Bvh, node: u32, t_min: f32, t_max: f32) -> Option<f32> {
        let b = bvh.nodes[node as usize].bounds();
        let t0 = (b.min - self.origin) * self.inv_dir;
        let t1 = (b.max - self.origin) * self.inv_dir;
        let enter = (t0.min(t1) - self.slab_pad).max_element().max(t_min);
        let exit = (t0.max(t1) + self.slab_pad).min_element().min(t_max) * BOX_EXIT_SLACK;
        (enter <= exit).then_some(enter)
    }
}

impl Bvh {
    /// The closest hit of `ray` with `ray.t_min < t < ray.t_max` (`Hit::MISS` when none).
    pub fn closest_hit(&self, triangles: &[Triangle], ray: &Ray) -> Hit {
        self.traverse(triangles, ray, false).0
    }

    /// `closest_hit` and the steps its traversal took (those of the GPU's binary traversal).
    pub fn closest_hit_steps(&self, triangles: &[Triangle], ray: &Ray) -> (Hit, TraversalSteps) {
        self.traverse(triangles, ray, false)
    }

    /// Some hit of `ray` in its interval, not necessarily the closest (shadow rays).
    pub fn any_hit(&self, triangles: &[Triangle], ray: &Ray) -> Hit {
        self.traverse(triangles, ray, true).0
    }

    fn traverse(&self, triangles: &[Triangle], ray: &Ray, any_hit: bool) -> (Hit, TraversalSteps) {
        let mut best = Hit {
            t: ray.t_max,
            ..Hit::miss()
        };
        let mut steps = TraversalSteps::default();
        if self.nodes.is_empty() {
            return (Hit::miss(), steps);
        }
        let test = RayTriangleTest::for_ray(ray);
        let boxes = BoxRay::new(ray);
        if boxes.entry(self, 0, ray.t_min, best.t).is_none() {
            return (Hit::miss(), steps);
        }
        // Far children with their entry distances; a popped one is skipped when it starts beyond
        // the closest hit so far (by more than the rounding slack).
        let mut stack: Vec<(u32, f32)> = Vec::new();
        let mut next = Some(0);
        while let Some(index) = next.take().or_else(|| {
            while let Some((index, entry)) = stack.pop() {
                if entry <= best.t * BOX_EXIT_SLACK {
                    return Some(index);
                }
            }
            None
        }) {
            let node = self.nodes[index as usize];
            if node.is_leaf() {
                steps.triangles += u64::from(node.prim_count());
                let first = node.left_or_first as usize;
                for &tri in &self.prim_indices[first..first + node.prim_count() as usize] {
                    let [v0, v1, v2] = triangles[tri as usize].vertices();
                    if let Some((t, u, v)) = test.intersect(v0, v1, v2, ray.t_min, best.t) {
                        best = Hit { t, tri, u, v };
                    }
                }
                if any_hit && best.is_hit() {
                    break;
                }
                continue;
            }
            steps.nodes += 1;
            let (l, r) = node.children();
            let hits = [l, r].map(|c| boxes.entry(self, c, ray.t_min, best.t).map(|e| (c, e)));
            match hits {
                [Some(a), Some(b)] => {
                    let (near, far) = if b.1 < a.1 { (b, a) } else { (a, b) };
                    stack.push(far);
                    next = Some(near.0);
                }
                [Some(only), None] | [None, Some(only)] => next = Some(only.0),
                [None, None] => {}
            }
        }
        let hit = if best.is_hit() { best } else { Hit::miss() };
        (hit, steps)
    }
}
