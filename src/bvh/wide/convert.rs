//! Binary-to-wide conversion, the CPU twin of the GPU conversion (`WideConverter`, kernels
//! `wide_nodes_emit` / `wide_nodes_finish` over `shaders/include/wide_collapse.wgsl`), after
//! Ylitie, Karras & Laine 2017 §3 with a greedy collapse in place of their SAH-optimal DP:
//! 1. children of a wide node: start from a binary node's two children and, while fewer than 8,
//!    open the internal child of the largest surface area;
//! 2. slots: child by child, the free slot of the largest Σ_a ±(centre_child − centre_node)_a
//!    (+ where bit a of the slot is set) (the paper's octant assignment, solved greedily): the
//!    traversal visits slots in ray-octant order;
//! 3. quantization: per axis the smallest exponent with origin + 255·2^e ≥ max, per child the
//!    tightest planes that still contain its box when decoded in f32 (conservative).
//!
//! Every decision uses additions, exact products and unfused products, so the GPU makes the
//! same tree on every device; only the numbering of nodes and reference blocks differs (the GPU
//! allocates them with atomics). Here nodes are numbered level by level.

use std::collections::VecDeque;

use super::node::{exponent_scale, put_byte, WideBvh, WideNode, WIDTH};
use super::optimal::OptimalCollapse;
use super::WideCollapse;
use crate::bvh::{Bvh, BvhNode, SahParams};
use crate::{Error, Result};

/// The largest leaf a wide node can hold (its count is a byte).
pub const MAX_WIDE_LEAF_SIZE: u32 = 255;

/// Fails when a leaf of `bvh` holds more than [`MAX_WIDE_LEAF_SIZE`] references (a wide node
/// counts a leaf's references in a byte).
pub fn check_leaf_sizes(bvh: &Bvh) -> Result<()> {
    match bvh.nodes.iter().find(|n| n.prim_count() > MAX_WIDE_LEAF_SIZE) {
        Some(n) => Err(Error::InvalidArgument(format!(
            "a leaf of {} references does not fit the wide layout (at most {MAX_WIDE_LEAF_SIZE}; lower --max-leaf-size)",
            n.prim_count()
        ))),
        None => Ok(()),
    }
}

/// Fails on an empty tree and on leaves too large for the layout (`check_leaf_sizes`).
fn check_convertible(bvh: &Bvh) -> Result<()> {
    if bvh.nodes.is_empty() {
        return Err(Error::InvalidArgument(
            "cannot convert an empty tree".into(),
        ));
    }
    check_leaf_sizes(bvh)
}

/// The most wide nodes the conversion by `collapse` makes from a binary tree of `leaves` leaves
/// (at least 1).
/// - Greedy: a wide node with fewer than 8 children has only leaves as children
///   (`open_children` opens internal children while a slot is free), and at least two of them
///   unless it is a root over a single leaf. With F nodes of 8 children (a of them leaves, in all)
///   and T other nodes, the N − 1 nodes below the root are the internal children: N − 1 = 8F − a,
///   with a + 2T ≤ leaves, so N = F + T = (8T + a − 1) / 7 ≤ (4 · leaves − 1) / 7. A balanced
///   tree of 16 leaves makes 9.
/// - Optimal: a wide node may leave slots free beside internal children (a child of its own can
///   cost less than two slots spent on the child's children), so only the greedy bound's first
///   argument holds: every wide node splits its 8 slots between two binary subtrees, so it has
///   at least two children; N − 1 + leaves ≥ 2N gives N ≤ leaves − 1.
pub fn max_wide_nodes(leaves: u32, collapse: WideCollapse) -> u32 {
    match collapse {
        // (4 · u32::MAX − 1) / 7 < u32::MAX.
        WideCollapse::Greedy => ((4 * u64::from(leaves)).saturating_sub(1) / 7).max(1) as u32,
        WideCollapse::Optimal => leaves.saturating_sub(1).max(1),
    }
}

pub(crate) fn half_area(n: &BvhNode) -> f32 {
    let e: [f32; 3] = std::array::from_fn(|a| n.max[a] - n.min[a]);
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// The smallest biased exponent e (1..=253) with lo + 255·2^(e−127) ≥ hi.
pub(crate) fn axis_exponent(lo: f32, hi: f32) -> u32 {
    let bits = (hi - lo).to_bits();
    let mut e = (bits >> 23) as i32 - 7 + i32::from(bits & 0x7f_ffff > 0x7f_0000);
    e = e.clamp(1, 253);
    while e < 253 && lo + 255.0 * exponent_scale(e as u32) < hi {
        e += 1;
    }
    e as u32
}

pub(crate) fn quantize_lo(v: f32, origin: f32, e: u32) -> u32 {
    let step = exponent_scale(e);
    let mut q = ((v - origin) * exponent_scale(254 - e))
        .floor()
        .clamp(0.0, 255.0) as u32;
    while q > 0 && origin + q as f32 * step > v {
        q -= 1;
    }
    q
}

pub(crate) fn quantize_hi(v: f32, origin: f32, e: u32) -> u32 {
    let step = exponent_scale(e);
    let mut q = ((v - origin) * exponent_scale(254 - e))
        .ceil()
        .clamp(0.0, 255.0) as u32;
    while q < 255 && origin + (q as f32) * step < v {
        q += 1;
    }
    q
}

/// The children (binary node indices) a wide node made from binary node `source` gets.
pub(crate) fn open_children(bvh: &Bvh, source: u32) -> Vec<u32> {
    let top = &bvh.nodes[source as usize];
    if top.is_leaf() {
        return vec![source];
    }
    let (l, r) = top.children();
    let mut children = vec![l, r];
    while children.len() < WIDTH {
        let mut widest = None;
        let mut widest_area = -1.0f32;
        for (j, &c) in children.iter().enumerate() {
            let n = &bvh.nodes[c as usize];
            if !n.is_leaf() {
                let a = half_area(n);
                if a > widest_area {
                    widest = Some(j);
                    widest_area = a;
                }
            }
        }
        let Some(j) = widest else { break };
        let (l, r) = bvh.nodes[children[j] as usize].children();
        children[j] = l;
        children.push(r);
    }
    children
}

/// The slot of each child: child by child, the free slot of its best score (greedy octant
/// assignment; the first of equal scores, the first free slot where none beats -3.4e38).
fn assign_slots(children: &[&BvhNode], centre: [f32; 3]) -> [usize; WIDTH] {
    let mut slot_of = [0; WIDTH];
    let mut free = [true; WIDTH];
    for (j, c) in children.iter().enumerate() {
        let d: [f32; 3] = std::array::from_fn(|a| (c.min[a] + c.max[a]) - centre[a]);
        let mut slot = free
            .iter()
            .position(|&f| f)
            .expect("a free slot for each of at most WIDTH children");
        let mut best_score = -3.4e38f32;
        for s in (0..WIDTH).filter(|&s| free[s]) {
            let signed = |a: usize| if s >> a & 1 != 0 { d[a] } else { -d[a] };
            let score = signed(0) + signed(1) + signed(2);
            if score > best_score {
                (best_score, slot) = (score, s);
            }
        }
        slot_of[j] = slot;
        free[slot] = false;
    }
    slot_of
}

impl WideBvh {
    /// Converts a binary tree (any builder's) into the wide layout, as the GPU does (the greedy
    /// collapse). Fails on a leaf of more than [`MAX_WIDE_LEAF_SIZE`] references.
    pub fn from_binary(bvh: &Bvh) -> Result<WideBvh> {
        check_convertible(bvh)?;
        Ok(Self::convert(bvh, |source| open_children(bvh, source)))
    }

    /// Converts a binary tree with the SAH-optimal collapse (`OptimalCollapse` under `params`)
    /// instead of the greedy one; slots and quantization as `from_binary`. A CPU reference: the
    /// GPU conversion is greedy.
    pub fn from_binary_optimal(bvh: &Bvh, params: &SahParams) -> Result<WideBvh> {
        check_convertible(bvh)?;
        let collapse = OptimalCollapse::new(bvh, params);
        Ok(Self::convert(bvh, |source| collapse.children(bvh, source)))
    }

    /// The conversion of a tree that `check_convertible` accepted, with the children of each
    /// wide node (binary nodes) from `children` of the binary node it is made from.
    fn convert(bvh: &Bvh, children: impl Fn(u32) -> Vec<u32>) -> WideBvh {
        let mut wide = WideBvh {
            nodes: vec![WideNode::default()],
            prim_indices: Vec::with_capacity(bvh.prim_indices.len()),
        };
        let mut queue = VecDeque::from([(0usize, 0u32)]);
        while let Some((w, source)) = queue.pop_front() {
            let children = children(source);
            let boxes: Vec<&BvhNode> = children.iter().map(|&c| &bvh.nodes[c as usize]).collect();
            let mut lo = boxes[0].min;
            let mut hi = boxes[0].max;
            for b in &boxes[1..] {
                for a in 0..3 {
                    lo[a] = lo[a].min(b.min[a]);
                    hi[a] = hi[a].max(b.max[a]);
                }
            }
            let centre: [f32; 3] = std::array::from_fn(|a| lo[a] + hi[a]);
            let slot_of = assign_slots(&boxes, centre);
            let mut in_slot = [None; WIDTH];
            for (j, &s) in slot_of.iter().take(children.len()).enumerate() {
                in_slot[s] = Some(j);
            }
            let e: [u32; 3] = std::array::from_fn(|a| axis_exponent(lo[a], hi[a]));
            let mut node = WideNode {
                origin: lo.map(f32::to_bits),
                ..WideNode::default()
            };
            let mut imask = 0;
            for (s, j) in in_slot.iter().enumerate() {
                let Some(j) = *j else { continue };
                let c = boxes[j];
                for a in 0..3 {
                    put_byte(
                        &mut node.quantized[a],
                        s,
                        quantize_lo(c.min[a], lo[a], e[a]),
                    );
                    put_byte(
                        &mut node.quantized[3 + a],
                        s,
                        quantize_hi(c.max[a], lo[a], e[a]),
                    );
                }
                if c.is_leaf() {
                    put_byte(&mut node.leaf_counts, s, c.prim_count());
                } else {
                    imask |= 1 << s;
                }
            }
            node.exponents = e[0] | e[1] << 8 | e[2] << 16 | imask << 24;
            node.prim_base = wide.prim_indices.len() as u32;
            node.child_base = if imask != 0 {
                wide.nodes.len() as u32
            } else {
                0
            };
            for j in in_slot.iter().flatten() {
                let c = boxes[*j];
                if c.is_leaf() {
                    let first = c.left_or_first as usize;
                    wide.prim_indices.extend_from_slice(
                        &bvh.prim_indices[first..first + c.prim_count() as usize],
                    );
                } else {
                    queue.push_back((wide.nodes.len(), children[*j]));
                    wide.nodes.push(WideNode::default());
                }
            }
            if node.prim_base as usize == wide.prim_indices.len() {
                node.prim_base = 0;
            }
            wide.nodes[w] = node;
        }
        wide
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::Vec3;

    /// Values spread over magnitudes and signs, with offsets far from the origin and tiny or
    /// zero extents.
    fn samples() -> Vec<(f32, f32, f32, f32)> {
        let mut state = 0x9e37_79b9_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let mut out = Vec::new();
        for scale in [1e-6f32, 1e-2, 1.0, 37.0, 1e4, 3e7] {
            for offset in [0.0f32, -5.0, 1e3, -2.5e5, 1e7] {
                for _ in 0..40 {
                    let lo = offset + scale * (next() - 0.5);
                    let hi = lo + scale * next() * next();
                    let a = lo + (hi - lo) * next();
                    let b = a + (hi - a) * next();
                    out.push((lo, hi, a.min(hi), b.min(hi)));
                }
                out.push((offset, offset, offset, offset));
            }
        }
        out
    }

    /// A binary tree of `leaves` one-reference leaves, split in halves (leaves a power of two: a
    /// balanced tree), boxes of unit cubes along x.
    fn halving_tree(leaves: u32) -> Bvh {
        fn add(nodes: &mut Vec<BvhNode>, first: u32, count: u32) -> usize {
            let index = nodes.len();
            let bounds = Aabb::new(
                Vec3::new(first as f32, 0.0, 0.0),
                Vec3::new((first + count) as f32, 1.0, 1.0),
            );
            nodes.push(BvhNode::leaf(bounds, first, 1));
            if count > 1 {
                let half = count / 2;
                let l = add(nodes, first, half) as u32;
                let r = add(nodes, first + half, count - half) as u32;
                nodes[index] = BvhNode::internal(bounds, l, r);
            }
            index
        }
        let mut nodes = Vec::new();
        add(&mut nodes, 0, leaves);
        Bvh {
            nodes,
            prim_indices: (0..leaves).collect(),
        }
    }

    #[test]
    fn wide_node_bound_holds_and_is_reached() {
        for leaves in 1..=300 {
            let wide = WideBvh::from_binary(&halving_tree(leaves)).unwrap();
            let bound = max_wide_nodes(leaves, WideCollapse::Greedy) as usize;
            assert!(
                wide.nodes.len() <= bound,
                "{leaves} leaves: {} wide nodes, bound {bound}",
                wide.nodes.len()
            );
            if leaves.is_power_of_two() && leaves.trailing_zeros() % 3 == 1 {
                // 2·8^k leaves: 8-child nodes down to nodes over two leaves.
                assert_eq!(wide.nodes.len(), bound, "{leaves} leaves");
            }
            let bvh = halving_tree(leaves);
            let optimal = WideBvh::from_binary_optimal(&bvh, &SahParams::default()).unwrap();
            assert!(optimal.nodes.len() <= max_wide_nodes(leaves, WideCollapse::Optimal) as usize);
        }
        assert_eq!(max_wide_nodes(16, WideCollapse::Greedy), 9);
        assert_eq!(
            max_wide_nodes(u32::MAX, WideCollapse::Greedy),
            2_454_267_025
        );
        assert_eq!(max_wide_nodes(16, WideCollapse::Optimal), 15);
        assert_eq!(max_wide_nodes(1, WideCollapse::Optimal), 1);
    }

    #[test]
    fn quantized_planes_contain_the_box_within_a_quantum() {
        for (lo, hi, a, b) in samples() {
            let e = axis_exponent(lo, hi);
            assert!((1..=253).contains(&e));
            let step = exponent_scale(e);
            assert!(lo + 255.0 * step >= hi, "{lo} {hi}: e {e} too small");
            if e > 1 {
                // One less would not cover the extent, exactly or as decoded.
                let smaller = exponent_scale(e - 1);
                let exact_short = 255.0 * f64::from(smaller) < f64::from(hi) - f64::from(lo);
                assert!(
                    exact_short || lo + 255.0 * smaller < hi,
                    "{lo} {hi}: e {e} not the smallest"
                );
            }
            let (qa, qb) = (quantize_lo(a, lo, e), quantize_hi(b, lo, e));
            assert!(qa <= qb && qb <= 255);
            assert!(lo + qa as f32 * step <= a, "lo plane above {a}");
            assert!(lo + qb as f32 * step >= b, "hi plane below {b}");
            // At most one quantum looser than the exact planes (plus the rounding of v − origin).
            let slack = |v: f32| 1.0001 * f64::from(step) + 2.0 * f64::from(v.abs() * f32::EPSILON);
            let plane = |q: u32| f64::from(lo) + f64::from(q) * f64::from(step);
            assert!(
                f64::from(a) - plane(qa) <= slack(a),
                "lo plane of {a} too loose"
            );
            assert!(
                plane(qb) - f64::from(b) <= slack(b),
                "hi plane of {b} too loose"
            );
        }
    }
}
