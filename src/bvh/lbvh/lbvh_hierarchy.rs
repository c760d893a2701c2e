//! LBVH stage 4: hierarchy emission, one invocation per internal node (Karras 2012 §4, Figure 4;
//! kernel `lbvh_hierarchy`), and its CPU twin. Internal nodes are 0..n-2 (root 0), leaf j is
//! node n-1+j; duplicate keys are ordered by index in every δ evaluation.

use crate::gpu::{kernel, Grid, ItemCount, Items, Kernel, Pass};

kernel!(pub LBVH_HIERARCHY: Items = "lbvh_hierarchy"::"main", [64, 1, 1], [Read, ReadWrite, ReadWrite, Read]);

/// Children (left, right) of each internal node and the parent of every node (root: u32::MAX).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Hierarchy {
    pub children: Vec<(u32, u32)>,
    pub parents: Vec<u32>,
}

/// CPU twin of the hierarchy kernel over sorted keys.
pub fn hierarchy_cpu(sorted_keys: &[u64]) -> Hierarchy {
    let n = sorted_keys.len();
    let delta = |i: i64, j: i64| -> i64 {
        if j < 0 || j >= n as i64 {
            return -1;
        }
        let x = sorted_keys[i as usize] ^ sorted_keys[j as usize];
        if x != 0 {
            i64::from(x.leading_zeros())
        } else {
            64 + i64::from((i as u32 ^ j as u32).leading_zeros())
        }
    };
    let mut children = vec![(0, 0); n.saturating_sub(1)];
    let mut parents = vec![u32::MAX; (2 * n).saturating_sub(1)];
    for (index, child) in children.iter_mut().enumerate() {
        let i = index as i64;
        let d = if delta(i, i + 1) > delta(i, i - 1) {
            1
        } else {
            -1
        };
        let delta_min = delta(i, i - d);
        let mut l_max = 2;
        while delta(i, i + l_max * d) > delta_min {
            l_max *= 2;
        }
        let mut l = 0;
        let mut t = l_max / 2;
        while t >= 1 {
            if delta(i, i + (l + t) * d) > delta_min {
                l += t;
            }
            t /= 2;
        }
        let j = i + l * d;
        let delta_node = delta(i, j);
        let (mut s, mut t) = (0, l);
        loop {
            t = (t + 1) / 2;
            if delta(i, i + (s + t) * d) > delta_node {
                s += t;
            }
            if t <= 1 {
                break;
            }
        }
        let gamma = i + s * d + d.min(0);
        let leaf_base = n as u32 - 1;
        let left = if i.min(j) == gamma {
            leaf_base + gamma as u32
        } else {
            gamma as u32
        };
        let right = if i.max(j) == gamma + 1 {
            leaf_base + gamma as u32 + 1
        } else {
            gamma as u32 + 1
        };
        *child = (left, right);
        parents[left as usize] = index as u32;
        parents[right as usize] = index as u32;
    }
    Hierarchy { children, parents }
}

/// The kernel `lbvh_hierarchy`.
pub(crate) struct LbvhHierarchy {
    kernel: Kernel<Items>,
}

impl LbvhHierarchy {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &LBVH_HIERARCHY),
        }
    }

    /// Records the emission over `count` sorted keys (n-1 invocations; nothing for n < 2).
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        keys: &wgpu::Buffer,
        count: ItemCount<'_>,
        nodes: &wgpu::Buffer,
        parents: &wgpu::Buffer,
    ) {
        let capacity = count.capacity();
        if capacity < 2 {
            return;
        }
        let ctx = pass.ctx();
        let grid: Grid = self.kernel.grid(ctx, capacity - 1);
        pass.dispatch(
            &self.kernel,
            grid,
            &Items::new(capacity, grid),
            &[keys, nodes, parents, count.limit(ctx)],
        );
    }
}
