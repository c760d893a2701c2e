//! CPU twin of the GPU treelet pipeline: the working tree (Karras layout with parent links,
//! primitive counts and SAH costs), one restructuring round (Karras & Aila 2013, §3-4) processed in
//! post-order exactly as the GPU's bottom-up climb processes it, and the leaf collapse with
//! compaction. Same float operations in the same order as the kernels. Also the rounds overlapped
//! in waves (`optimize_overlapped`, the twin of the GPU's `RoundSchedule::overlap`): how far a
//! round can run ahead of the one before without changing the trees.

use glam::Vec3;

use super::dp::{solve_treelet, surface_area, CostModel, TreeletLeaf};
use crate::bvh::{Bvh, BvhNode};

/// The tree the optimizer rewrites in place: LBVH layout (internal 0..n-2, leaf j at n-1+j with
/// one primitive `prims[j]`), parents, and per-node primitive counts and costs.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkingTree {
    pub nodes: Vec<BvhNode>,
    pub parents: Vec<u32>,
    pub prims: Vec<u32>,
    pub prim_counts: Vec<u32>,
    pub costs: Vec<f32>,
}

impl WorkingTree {
    /// Wraps an LBVH (`lbvh.nodes`, `lbvh.prim_indices` in Morton order) and its parent links.
    pub fn from_lbvh(lbvh: Bvh, parents: Vec<u32>) -> Self {
        let count = lbvh.nodes.len();
        Self {
            nodes: lbvh.nodes,
            parents,
            prims: lbvh.prim_indices,
            prim_counts: vec![0; count],
            costs: vec![0.0; count],
        }
    }

    fn area(&self, node: u32) -> f32 {
        let n = &self.nodes[node as usize];
        surface_area(Vec3::from(n.min), Vec3::from(n.max))
    }

    /// Internal nodes in post-order (children before parents).
    fn post_order(&self) -> Vec<u32> {
        let mut order = Vec::new();
        let mut stack = vec![(0u32, false)];
        while let Some((node, expanded)) = stack.pop() {
            let n = self.nodes[node as usize];
            if n.is_leaf() {
                continue;
            }
            if expanded {
                order.push(node);
            } else {
                let (l, r) = n.children();
                stack.extend([(node, true), (r, false), (l, false)]);
            }
        }
        order
    }

    /// Leaves below each node and each node's treelet level for smallest root `gamma` (0 below
    /// gamma leaves, else one more than its children's highest: the levels the GPU rounds
    /// process one by one, `nodes_level.wgsl`), from the topology alone.
    pub fn treelet_levels(&self, gamma: u32) -> (Vec<u32>, Vec<u32>) {
        let count = self.nodes.len();
        let mut leaves: Vec<u32> = self.nodes.iter().map(|n| u32::from(n.is_leaf())).collect();
        let mut levels = vec![0u32; count];
        for node in self.post_order() {
            let (l, r) = self.nodes[node as usize].children();
            let (l, r, i) = (l as usize, r as usize, node as usize);
            leaves[i] = leaves[l] + leaves[r];
            if leaves[i] >= gamma {
                let of = |c: usize| if leaves[c] >= gamma { levels[c] } else { 0 };
                levels[i] = 1 + of(l).max(of(r));
            }
        }
        (leaves, levels)
    }

    /// One restructuring round: every node gets its primitive count and cost; nodes with at least
    /// `gamma` primitives root a treelet of up to `treelet_size` leaves that is replaced by its
    /// SAH-optimal topology when that is cheaper.
    pub fn optimize_round(&mut self, model: &CostModel, treelet_size: u32, gamma: u32) {
        self.leaf_costs(model);
        for node in self.post_order() {
            self.finish_node(node, model);
            if self.prim_counts[node as usize] >= gamma {
                self.optimize_treelet(node, model, treelet_size, u32::MAX);
            }
        }
    }

    /// Every leaf's count (1) and cost (Ct·A).
    fn leaf_costs(&mut self, model: &CostModel) {
        for (i, n) in self.nodes.iter().enumerate() {
            if n.is_leaf() {
                self.prim_counts[i] = 1;
                self.costs[i] = model.ct * surface_area(Vec3::from(n.min), Vec3::from(n.max));
            }
        }
    }

    /// An internal node's count and cost from its children's.
    fn finish_node(&mut self, node: u32, model: &CostModel) {
        let (l, r) = self.nodes[node as usize].children();
        let prims = self.prim_counts[l as usize] + self.prim_counts[r as usize];
        self.prim_counts[node as usize] = prims;
        self.costs[node as usize] = model.combine(
            self.area(node),
            prims,
            self.costs[l as usize] + self.costs[r as usize],
        );
    }

    /// The rounds of `gammas` overlapped in waves (the GPU's `RoundSchedule::overlap`, module
    /// `waves`, follows the same rule). In each wave, round r optimizes every root Q of at least
    /// γ_r primitives whose children of at least γ_r are done in round r (so round 1 its roots
    /// of treelet level w in wave w) and, for r > 1, which with its ancestors up to `reach`
    /// levels up is done in round r − 1 (`None`: all of them, so each round waits for the whole
    /// round before: the sequential rounds, one wave per treelet level). A wave's treelets are
    /// disjoint when `reach` is at least `treelet_size` − 1 (the levels a treelet reaches below
    /// its root; `overlap_reach`), so their order does not matter; with less they can share
    /// nodes, and this twin gives the result of processing them by (round, node). Internal nodes a treelet
    /// rewrites count as done in its round and the ones before (their sequential visit came
    /// first). Returns the treelets optimized in each wave: as many waves as a GPU schedule would
    /// have dependent steps. Counts and costs are computed afresh before and after.
    ///
    /// Not exact in general: a write-back can lift a treelet leaf to just below its root, so the
    /// next ancestor's treelet may reach a node that round r already optimized. On the shared
    /// scenes, reach 6 gives the sequential trees exactly (`examples/rounds_overlap.rs`).
    pub fn optimize_overlapped(
        &mut self,
        model: &CostModel,
        treelet_size: u32,
        gammas: &[u32],
        reach: Option<u32>,
    ) -> Vec<u32> {
        let count = self.nodes.len();
        self.leaf_costs(model);
        let order = self.post_order();
        let mut waves = Waves {
            gammas,
            reach,
            done: vec![0; count * gammas.len()],
        };
        for &node in &order {
            self.finish_node(node, model);
        }
        let mut sizes = Vec::new();
        loop {
            let wave = sizes.len() as u32 + 1;
            let mut ops = Vec::new();
            for &node in &order {
                for round in 0..gammas.len() {
                    if waves.ready(self, node, round, wave) {
                        ops.push((round, node));
                    }
                }
            }
            if ops.is_empty() {
                break;
            }
            sizes.push(ops.len() as u32);
            ops.sort_unstable();
            for (round, node) in ops {
                self.finish_node(node, model);
                for x in self.optimize_treelet(node, model, treelet_size, u32::MAX) {
                    for r in 0..=round {
                        waves.mark(x, r, wave);
                    }
                }
                waves.mark(node, round, wave);
            }
        }
        for node in order {
            for (round, &gamma) in gammas.iter().enumerate() {
                assert!(
                    self.prim_counts[node as usize] < gamma || waves.is_done(node, round, u32::MAX),
                    "overlapped rounds stalled after {} waves: node {node}, round {round}",
                    sizes.len()
                );
            }
        }
        self.leaf_costs(model);
        for node in self.post_order() {
            self.finish_node(node, model);
        }
        sizes
    }

    /// The rounds of `rounds` (treelet size, γ, phases P) each in P phases by depth (the GPU's
    /// `TreeletSettings::phases`, module `phases`): counts and costs once, then per round and phase
    /// k every root (an internal node of at least γ primitives) at depth ≡ P − 1 − k (mod P) in
    /// the tree the phases before left, its cost first recomputed from its children's. Roots of
    /// one phase lie at least P levels apart and a treelet's leaves at most P − 1 below its root
    /// (the formation expands no leaf that deep; with P at least the treelet size it never
    /// reaches it), so their treelets are disjoint and their order does not matter. Costs are
    /// not refreshed otherwise: a node above a treelet that lowered its cost keeps its own until
    /// its turn as a root (a node that is no root keeps it, as the collapse reads it; on the
    /// shared scenes the refreshed costs give the same SAH to four places).
    pub fn optimize_phased(&mut self, model: &CostModel, rounds: &[(u32, u32, u32)]) {
        self.leaf_costs(model);
        for node in self.post_order() {
            self.finish_node(node, model);
        }
        for &(treelet_size, gamma, phases) in rounds {
            for k in 0..phases {
                for root in self.phase_roots(gamma, phases, phases - 1 - k) {
                    self.finish_node(root, model);
                    self.optimize_treelet(root, model, treelet_size, phases - 1);
                }
            }
        }
    }

    /// The internal nodes of at least `gamma` primitives whose depth is ≡ `residue` (mod
    /// `phases`), by index (the GPU kernel `roots_phase` finds them by walking up to the root).
    fn phase_roots(&self, gamma: u32, phases: u32, residue: u32) -> Vec<u32> {
        let mut roots = Vec::new();
        let mut stack = vec![(0u32, 0u32)];
        while let Some((node, depth)) = stack.pop() {
            let n = self.nodes[node as usize];
            if n.is_leaf() {
                continue;
            }
            if self.prim_counts[node as usize] >= gamma && depth % phases == residue {
                roots.push(node);
            }
            let (l, r) = n.children();
            stack.extend([(l, depth + 1), (r, depth + 1)]);
        }
        roots.sort_unstable();
        roots
    }

    /// Optimizes the treelet at `root` of up to `treelet_size` leaves, none deeper than
    /// `max_leaf_depth` levels below the root (fewer leaves where that stops the formation);
    /// returns the internal nodes it rewrote (none when the topology is kept).
    fn optimize_treelet(
        &mut self,
        root: u32,
        model: &CostModel,
        treelet_size: u32,
        max_leaf_depth: u32,
    ) -> Vec<u32> {
        let (l, r) = self.nodes[root as usize].children();
        let mut leaves = vec![l, r];
        let mut depths = vec![1, 1];
        let mut internal = vec![root];
        while (leaves.len() as u32) < treelet_size {
            let mut best = None;
            let mut best_area = -1.0;
            for (i, &node) in leaves.iter().enumerate() {
                if !self.nodes[node as usize].is_leaf() && depths[i] < max_leaf_depth {
                    let a = self.area(node);
                    if a > best_area {
                        best_area = a;
                        best = Some(i);
                    }
                }
            }
            let Some(best) = best else { break };
            let expanded = leaves[best];
            let (cl, cr) = self.nodes[expanded as usize].children();
            leaves[best] = cl;
            leaves.push(cr);
            depths[best] += 1;
            depths.push(depths[best]);
            internal.push(expanded);
        }
        if leaves.len() < 3 {
            return Vec::new();
        }
        let treelet: Vec<TreeletLeaf> = leaves
            .iter()
            .map(|&node| {
                let n = self.nodes[node as usize];
                TreeletLeaf {
                    min: Vec3::from(n.min),
                    max: Vec3::from(n.max),
                    cost: self.costs[node as usize],
                    prims: self.prim_counts[node as usize],
                }
            })
            .collect();
        let sol = solve_treelet(&treelet, model);
        if sol.cost[sol.full() as usize] >= self.costs[root as usize] {
            return Vec::new();
        }
        // Write back breadth-first, left = P, right = S \ P, reusing internal nodes in order.
        let mut queue = std::collections::VecDeque::from([(sol.full(), root)]);
        let mut next_internal = 1;
        while let Some((s, node)) = queue.pop_front() {
            let p = sol.split[s as usize];
            let mut child = [0u32; 2];
            for (k, part) in [p, s ^ p].into_iter().enumerate() {
                child[k] = if part.count_ones() == 1 {
                    leaves[part.trailing_zeros() as usize]
                } else {
                    let c = internal[next_internal];
                    next_internal += 1;
                    queue.push_back((part, c));
                    c
                };
                self.parents[child[k] as usize] = node;
            }
            let (lo, hi) = sol.bounds(&treelet, s);
            self.nodes[node as usize] = BvhNode {
                min: lo.to_array(),
                left_or_first: child[0],
                max: hi.to_array(),
                right_or_count: child[1],
            };
            self.prim_counts[node as usize] = sol.prims[s as usize];
            self.costs[node as usize] = sol.cost[s as usize];
        }
        internal.split_off(1)
    }

    /// Whether `node` becomes (or is inside) a leaf: a leaf already, or Ct·A·N <= C with
    /// N <= max leaf size (the kernel `nodes_mark.wgsl`).
    fn collapses(&self, node: u32, model: &CostModel) -> bool {
        let n = self.prim_counts[node as usize];
        self.nodes[node as usize].is_leaf()
            || (n <= model.max_leaf_size
                && model.ct * self.area(node) * n as f32 <= self.costs[node as usize])
    }

    /// The primitives under `node` depth-first, left first. With pre-split references
    /// (`ref_tris[r]` = triangle of reference r) they become triangle ids, each kept once (first
    /// occurrence): a leaf references a triangle at most once.
    fn gather(&self, node: u32, ref_tris: Option<&[u32]>) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack = vec![node];
        while let Some(x) = stack.pop() {
            let w = self.nodes[x as usize];
            if w.is_leaf() {
                let first = w.left_or_first as usize;
                for &p in &self.prims[first..first + w.prim_count() as usize] {
                    match ref_tris {
                        Some(tris) => {
                            let t = tris[p as usize];
                            if !out.contains(&t) {
                                out.push(t);
                            }
                        }
                        None => out.push(p),
                    }
                }
            } else {
                stack.extend([w.right_or_count, w.left_or_first]);
            }
        }
        out
    }

    /// Collapse and compaction (the kernels `nodes_mark.wgsl` + scans + `nodes_compact.wgsl`):
    /// kept nodes keep their relative order, output leaves gather their subtree's primitives
    /// depth-first, left first (mapped to unique triangle ids when `ref_tris` is given).
    pub fn collapse(&self, model: &CostModel, ref_tris: Option<&[u32]>) -> Bvh {
        let count = self.nodes.len();
        let mut kept = vec![false; count];
        let mut leaf_prims: Vec<Option<Vec<u32>>> = vec![None; count];
        for i in 0..count as u32 {
            let mut x = i;
            let mut keep = true;
            while x != 0 {
                x = self.parents[x as usize];
                if self.collapses(x, model) {
                    keep = false;
                    break;
                }
            }
            kept[i as usize] = keep;
            if keep && self.collapses(i, model) {
                leaf_prims[i as usize] = Some(self.gather(i, ref_tris));
            }
        }
        let mut new_index = vec![0u32; count];
        let mut leaf_first = vec![0u32; count];
        let (mut nodes_out, mut prims_out) = (0u32, 0u32);
        for i in 0..count {
            new_index[i] = nodes_out;
            leaf_first[i] = prims_out;
            nodes_out += u32::from(kept[i]);
            prims_out += leaf_prims[i].as_ref().map_or(0, |p| p.len() as u32);
        }
        let mut nodes = vec![BvhNode::leaf(crate::geometry::Aabb::EMPTY, 0, 0); nodes_out as usize];
        let mut prim_indices = Vec::with_capacity(prims_out as usize);
        for i in 0..count {
            if !kept[i] {
                continue;
            }
            let n = self.nodes[i];
            nodes[new_index[i] as usize] = match &leaf_prims[i] {
                Some(prims) => {
                    prim_indices.extend_from_slice(prims);
                    BvhNode::leaf(n.bounds(), leaf_first[i], prims.len() as u32)
                }
                None => {
                    let (l, r) = n.children();
                    BvhNode::internal(n.bounds(), new_index[l as usize], new_index[r as usize])
                }
            };
        }
        Bvh {
            nodes,
            prim_indices,
        }
    }
}

/// The schedule of `WorkingTree::optimize_overlapped`.
struct Waves<'a> {
    gammas: &'a [u32],
    reach: Option<u32>,
    /// The wave in which each node was done in each round (0: not yet), node-major.
    done: Vec<u32>,
}

impl Waves<'_> {
    /// Whether `node` was done in `round` before wave `wave`.
    fn is_done(&self, node: u32, round: usize, wave: u32) -> bool {
        let d = self.done[node as usize * self.gammas.len() + round];
        d != 0 && d < wave
    }

    /// Records `node` as done in `round` in wave `wave`, unless it was already.
    fn mark(&mut self, node: u32, round: usize, wave: u32) {
        let d = &mut self.done[node as usize * self.gammas.len() + round];
        if *d == 0 {
            *d = wave;
        }
    }

    /// Whether wave `wave` optimizes `node` in `round` (see `optimize_overlapped`).
    fn ready(&self, tree: &WorkingTree, node: u32, round: usize, wave: u32) -> bool {
        let gamma = self.gammas[round];
        let n = tree.nodes[node as usize];
        if n.is_leaf()
            || self.done[node as usize * self.gammas.len() + round] != 0
            || tree.prim_counts[node as usize] < gamma
        {
            return false;
        }
        let (l, r) = n.children();
        let children_done = [l, r].into_iter().all(|c| {
            tree.nodes[c as usize].is_leaf()
                || tree.prim_counts[c as usize] < gamma
                || self.is_done(c, round, wave)
        });
        if round == 0 {
            return children_done;
        }
        let mut x = node;
        let mut up = 0;
        loop {
            if !self.is_done(x, round - 1, wave) {
                return false;
            }
            if x == 0 || self.reach.is_some_and(|reach| up >= reach) {
                return children_done;
            }
            x = tree.parents[x as usize];
            up += 1;
        }
    }
}
