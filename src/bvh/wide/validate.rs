//! Structural validation of a wide tree (the checks of `bvh::validate`, for the layout of
//! `wide/node.rs`): from the root, every internal slot's child index is in range and no node is
//! reached twice or left unreached; every node has a child; leaf ranges lie inside
//! `prim_indices`, which every leaf uses exactly once; triangle ids are in range and each
//! triangle is referenced exactly once (relaxed mode: at least once, once per leaf at most);
//! quantization frames hold no NaN and exponents are in range. Boxes: every slot's box, decoded
//! in f32 as a traversal does, contains what lies beneath it, with zero tolerance: the triangles
//! of a leaf and the union of all triangles below an internal child (relaxed mode: a leaf's box
//! overlaps its triangles, which it bounds only in part, and an internal child's box contains
//! the child's origin and overlaps every box of the child's own slots).

use super::node::{Slot, WideBvh, WIDTH};
use crate::bvh::validate::{overlaps, ReferenceLedger, References};
use crate::bvh::{ValidationError, ValidationStats};
use crate::geometry::Aabb;
use crate::scene::Triangle;

/// Checks a wide tree against the triangles it was built over (each referenced once).
pub fn validate_wide(
    wide: &WideBvh,
    triangles: &[Triangle],
) -> Result<ValidationStats, ValidationError> {
    validate_mode(wide, triangles, References::Single)
}

/// [`validate_wide`] for trees of split triangles (see the module documentation).
pub fn validate_wide_with_references(
    wide: &WideBvh,
    triangles: &[Triangle],
) -> Result<ValidationStats, ValidationError> {
    validate_mode(wide, triangles, References::Multiple)
}

fn validate_mode(
    wide: &WideBvh,
    triangles: &[Triangle],
    mode: References,
) -> Result<ValidationStats, ValidationError> {
    let nodes = &wide.nodes;
    if nodes.is_empty() {
        return Err(ValidationError::Empty);
    }
    let mut stats = ValidationStats {
        nodes: nodes.len(),
        leaves: 0,
        max_depth: 0,
        max_leaf_size: 0,
    };
    let mut seen = vec![false; nodes.len()];
    let mut references = ReferenceLedger::new(&wide.prim_indices, triangles, mode);
    let mut leaf_id = 0usize;
    // Nodes in the order reached (parents before children), for the bottom-up box check.
    let mut order = Vec::with_capacity(nodes.len());
    seen[0] = true;
    let mut stack = vec![(0usize, 0usize)];
    while let Some((index, depth)) = stack.pop() {
        order.push(index);
        stats.max_depth = stats.max_depth.max(depth);
        let node = &nodes[index];
        let origin = node.origin();
        if origin.is_nan() || (0..3).any(|a| !(1..=254).contains(&node.exponent(a))) {
            return Err(ValidationError::BadQuantizationFrame { node: index });
        }
        let mut children = 0;
        for slot in 0..WIDTH {
            match node.slot(slot) {
                Slot::Empty => {}
                Slot::Internal(child) => {
                    children += 1;
                    let child = child as usize;
                    if child >= nodes.len() {
                        return Err(ValidationError::ChildOutOfRange {
                            node: index,
                            child,
                            node_count: nodes.len(),
                        });
                    }
                    if std::mem::replace(&mut seen[child], true) {
                        return Err(ValidationError::NodeReachedTwice { node: index, child });
                    }
                    stack.push((child, depth + 1));
                }
                Slot::Leaf { first, count } => {
                    children += 1;
                    leaf_id += 1;
                    let (first, count) = (first as usize, count as usize);
                    let misfit = |_| ValidationError::SlotNotContaining { node: index, slot };
                    references.leaf(
                        index,
                        leaf_id,
                        (first, count),
                        &node.slot_box(slot),
                        misfit,
                    )?;
                    stats.leaves += 1;
                    stats.max_leaf_size = stats.max_leaf_size.max(count);
                }
            }
        }
        if children == 0 {
            return Err(ValidationError::EmptyWideNode { node: index });
        }
    }
    if let Some(node) = seen.iter().position(|&s| !s) {
        return Err(ValidationError::UnreachableNode { node });
    }
    references.finish()?;
    check_internal_boxes(wide, triangles, mode, &order)?;
    Ok(stats)
}

/// Internal slots against their subtrees, children before parents.
fn check_internal_boxes(
    wide: &WideBvh,
    triangles: &[Triangle],
    mode: References,
    order: &[usize],
) -> Result<(), ValidationError> {
    // The exact bounds of each node's triangles (single mode).
    let mut bounds = vec![Aabb::EMPTY; wide.nodes.len()];
    for &index in order.iter().rev() {
        let node = &wide.nodes[index];
        let mut total = Aabb::EMPTY;
        for slot in 0..WIDTH {
            let slot_box = node.slot_box(slot);
            match node.slot(slot) {
                Slot::Empty => {}
                Slot::Leaf { first, count } => {
                    for &t in &wide.prim_indices[first as usize..(first + count) as usize] {
                        total = total.union(triangles[t as usize].bounds());
                    }
                }
                Slot::Internal(child) => {
                    let child_node = &wide.nodes[child as usize];
                    let fits = match mode {
                        References::Single => slot_box.contains(&bounds[child as usize], 0.0),
                        References::Multiple => {
                            slot_box.min.cmple(child_node.origin()).all()
                                && (0..WIDTH).all(|s| {
                                    matches!(child_node.slot(s), Slot::Empty)
                                        || overlaps(&slot_box, &child_node.slot_box(s))
                                })
                        }
                    };
                    if !fits {
                        return Err(ValidationError::SlotNotContaining { node: index, slot });
                    }
                    total = total.union(bounds[child as usize]);
                }
            }
        }
        bounds[index] = total;
    }
    Ok(())
}
