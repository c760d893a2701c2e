//! What optimizing a round's lowest K treelet levels per subtree (`RoundSchedule::subtree_levels`,
//! kernel `subtrees_optimize`) asks of a GPU, counted on the CPU twin's trees (trbvh (7,3) from
//! the LBVH of 32-bit keys, each round's tree before it runs): per scene, round, K and subtree
//! width (`RoundSchedule::subtree_width`), the warp steps (a warp of 32 invocations optimizing
//! up to 32 treelets side by side) that the K levels take dispatched one by one, and that the
//! subtrees take: in all (throughput), in how many workgroups (one warp each), and the most in one
//! workgroup (its chain of dependent steps: latency; the levels' chain is K, one per dispatch).
//! The packing is the kernel's: cut roots bucketed by level, `subtrees_per_workgroup` of them per
//! workgroup, each depth of the workgroup's list in steps of 32.
//!
//! ```text
//! cargo run --release --example subtree_schedule -- conference,sibenik 4,6,8 32,1024
//! ```
use treelet::bvh::lbvh::{build_lbvh_from_boxes_cpu, prim_boxes_cpu, TRBVH_KEY_BITS};
use treelet::bvh::treelet::{CostModel, TreeletSettings, WorkingTree, SUBTREE_LIST};
use treelet::bvh::SahParams;
use treelet::scene::load_scene;

/// Invocations of a `subtrees_optimize` workgroup, and of a warp.
const WARP: usize = 32;

/// `subtrees_per_workgroup` of treelet_round.wgsl.
fn subtrees_per_workgroup(level: u32, width: u32) -> usize {
    let bound = (SUBTREE_LIST / ((1 << level) - 1)).min(WARP as u32);
    bound.min((width >> (level - 1)).max(1)) as usize
}

fn main() -> treelet::Result<()> {
    let mut args = std::env::args().skip(1);
    let scenes = args.next().unwrap_or_else(|| "sibenik".into());
    let list = |text: Option<String>, default: &str| -> Vec<u32> {
        text.unwrap_or_else(|| default.into())
            .split(',')
            .filter_map(|v| v.parse().ok())
            .collect()
    };
    let heights = list(args.next(), "4,6,8");
    let widths = list(args.next(), "32,1024");
    let settings = TreeletSettings::BALANCED;
    let model = CostModel::from(&SahParams::default());
    println!(
        "scene            round  K  width  levels' warp steps  subtrees' warp steps  workgroups  \
         most in one"
    );
    for name in scenes.split(',') {
        let scene = load_scene(name)?;
        let boxes = prim_boxes_cpu(&scene.triangles);
        let (lbvh, parents) = build_lbvh_from_boxes_cpu(&boxes, TRBVH_KEY_BITS);
        let mut tree = WorkingTree::from_lbvh(lbvh, parents);
        for (round, &gamma) in settings.gammas().iter().enumerate() {
            let (leaves, levels) = tree.treelet_levels(gamma);
            let is_root = |node: u32| leaves[node as usize] >= gamma;
            for &k in &heights {
                let level_warps: usize = (1..=k)
                    .map(|l| levels.iter().filter(|&&x| x == l).count().div_ceil(WARP))
                    .sum();
                // The cut roots of each level: of level K at most, the parent above K.
                let mut cuts = vec![Vec::new(); k as usize + 1];
                for (node, &level) in levels.iter().enumerate() {
                    let parent = tree.parents[node] as usize;
                    if level != 0 && level <= k && (node == 0 || levels[parent] > k) {
                        cuts[level as usize].push(node as u32);
                    }
                }
                for &width in &widths {
                    let (mut warps, mut workgroups, mut most) = (0, 0, 0);
                    for level in 1..=k {
                        let per = subtrees_per_workgroup(level, width);
                        for group in cuts[level as usize].chunks(per) {
                            workgroups += 1;
                            let (mut depth, mut steps) = (group.to_vec(), 0);
                            while !depth.is_empty() {
                                steps += depth.len().div_ceil(WARP);
                                depth = depth
                                    .iter()
                                    .flat_map(|&d| {
                                        let (l, r) = tree.nodes[d as usize].children();
                                        [l, r]
                                    })
                                    .filter(|&c| is_root(c))
                                    .collect();
                            }
                            warps += steps;
                            most = usize::max(most, steps);
                        }
                    }
                    println!(
                        "{name:16} {:5} {k:2} {width:6} {level_warps:19} {warps:21} \
                         {workgroups:11} {most:12}",
                        round + 1
                    );
                }
            }
            tree.optimize_round(&model, settings.treelet_size, gamma);
        }
    }
    Ok(())
}
