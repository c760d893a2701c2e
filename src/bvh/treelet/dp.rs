//! The SAH-optimal topology of one treelet by dynamic programming over all subsets of its leaves
//! (Karras & Aila 2013, §4, Algorithm 2), CPU side: used by the CPU twin of the GPU optimizer and
//! checked against brute-force enumeration in tests. Operation order and tie-breaking match
//! `shaders/include/treelet_dp.wgsl` (one invocation per treelet) and
//! `shaders/include/treelet_team.wgsl` (a team per treelet); areas agree bit for bit (the kernels
//! keep their products unfused), costs to a few ulps (the kernels may fuse Ci·A into the
//! following add).

use glam::Vec3;

use crate::bvh::SahParams;

use crate::gpu::constants::MAX_TREELET_SIZE;

/// SAH constants and the collapse limit the DP and the node costs use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    pub ci: f32,
    pub ct: f32,
    pub max_leaf_size: u32,
    /// Evaluate Ci·a + children as one fused multiply-add, as a GPU compiler may. The twin rounds
    /// the product first (false) by default; true shows how much a fusing device's trees may
    /// differ from it (the tolerances of the GPU comparisons are checked against that).
    pub fused: bool,
}

impl From<&SahParams> for CostModel {
    fn from(sah: &SahParams) -> Self {
        Self {
            ci: sah.ci,
            ct: sah.ct,
            max_leaf_size: sah.max_leaf_size,
            fused: false,
        }
    }
}

impl CostModel {
    /// Cost of a node of area `a` with `n` primitives whose children cost `children` together:
    /// min(Ci·a + children, Ct·a·n) where a leaf of n primitives is allowed.
    pub fn combine(&self, a: f32, n: u32, children: f32) -> f32 {
        let split = if self.fused {
            self.ci.mul_add(a, children)
        } else {
            self.ci * a + children
        };
        if n <= self.max_leaf_size {
            split.min(self.ct * a * n as f32)
        } else {
            split
        }
    }
}

/// Surface area with the kernel's operation order (bit-identical to the kernels').
pub fn surface_area(lo: Vec3, hi: Vec3) -> f32 {
    let e = hi - lo;
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

/// The 256 subsets of 8 treelet leaves ordered by size, then value: the order in which a team of
/// invocations processes them (`shaders/include/treelet_team.wgsl`, which binds this table). The
/// subsets of size k of the first m leaves are the first C(m, k) entries of size k.
pub fn subsets_by_size() -> Vec<u32> {
    let mut subsets: Vec<u32> = (0..1 << MAX_TREELET_SIZE).collect();
    subsets.sort_by_key(|s| (s.count_ones(), *s));
    subsets
}

/// The unordered partitions {P, S \ P} of a subset S of at least two leaves, each once: P over
/// the non-empty subsets of S without its lowest leaf, in increasing order (the order in which
/// every DP here and on the GPU evaluates them; ties keep the first P).
pub fn partitions(s: u32) -> impl Iterator<Item = u32> {
    let delta = (s - 1) & s;
    let mut p = delta.wrapping_neg() & s;
    std::iter::from_fn(move || {
        let current = p;
        p = p.wrapping_sub(delta) & s;
        (current != 0).then_some(current)
    })
}

/// One treelet leaf: its box, subtree cost and primitive count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeletLeaf {
    pub min: Vec3,
    pub max: Vec3,
    pub cost: f32,
    pub prims: u32,
}

/// DP tables over subsets of m leaves (bit i = leaf i).
#[derive(Clone, Debug)]
pub struct TreeletSolution {
    pub leaves: usize,
    pub area: Vec<f32>,
    pub cost: Vec<f32>,
    pub prims: Vec<u32>,
    /// Best partition P of each subset S (the other part is S \ P); P excludes S's lowest leaf.
    pub split: Vec<u32>,
}

impl TreeletSolution {
    pub fn full(&self) -> u32 {
        (1u32 << self.leaves) - 1
    }

    pub fn bounds(&self, leaves: &[TreeletLeaf], s: u32) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(-f32::MAX);
        for (i, leaf) in leaves.iter().enumerate() {
            if (s >> i) & 1 != 0 {
                lo = lo.min(leaf.min);
                hi = hi.max(leaf.max);
            }
        }
        (lo, hi)
    }
}

/// Optimal costs and splits for all subsets of `leaves` (2 ≤ m ≤ MAX_TREELET_SIZE).
pub fn solve_treelet(leaves: &[TreeletLeaf], model: &CostModel) -> TreeletSolution {
    let m = leaves.len();
    assert!(
        (2..=MAX_TREELET_SIZE as usize).contains(&m),
        "treelet of {m} leaves"
    );
    let full = (1u32 << m) - 1;
    let mut sol = TreeletSolution {
        leaves: m,
        area: vec![0.0; 1 << m],
        cost: vec![0.0; 1 << m],
        prims: vec![0; 1 << m],
        split: vec![0; 1 << m],
    };
    for s in 1..=full {
        let (lo, hi) = sol.bounds(leaves, s);
        sol.area[s as usize] = surface_area(lo, hi);
        sol.prims[s as usize] = (0..m)
            .filter(|i| (s >> i) & 1 != 0)
            .map(|i| leaves[i].prims)
            .sum();
        if s.count_ones() == 1 {
            sol.cost[s as usize] = leaves[s.trailing_zeros() as usize].cost;
        }
    }
    for size in 2..=m as u32 {
        for s in 3..=full {
            if s.count_ones() != size {
                continue;
            }
            let mut best = f32::MAX;
            let mut best_p = 0;
            for p in partitions(s) {
                let c = sol.cost[p as usize] + sol.cost[(s ^ p) as usize];
                if c < best {
                    best = c;
                    best_p = p;
                }
            }
            sol.cost[s as usize] = model.combine(sol.area[s as usize], sol.prims[s as usize], best);
            sol.split[s as usize] = best_p;
        }
    }
    sol
}
