//! What the phased treelet rounds (`TreeletSettings::phases`: each round in P phases by depth
//! instead of bottom-up) cost in tree quality, measured on the CPU twin
//! (`WorkingTree::optimize_phased`, whose trees the GPU builds exactly) from the LBVH of 32-bit
//! keys that trbvh builds: per scene, rounds, P and the first round's P, the SAH of the collapsed
//! tree against the paper's bottom-up rounds (7 leaves, 3 rounds), and the dependent steps a GPU
//! takes (the phases, against the bottom-up rounds' treelet levels, each waiting for the one
//! below).
//!
//! Arguments: scenes, phases P, rounds, the first round's phases (default: P), treelet sizes
//! (default: 7; below P a treelet's leaves stay within P − 1 levels of its root).
//!
//! ```text
//! cargo run --release --example phased_rounds -- conference,sibenik 7,14 3,4 [14] [7]
//! cargo run --release --example phased_rounds -- conference,sibenik 4 4 5,6 6,7
//! ```
use treelet::bvh::lbvh::{build_lbvh_from_boxes_cpu, prim_boxes_cpu, TRBVH_KEY_BITS};
use treelet::bvh::treelet::{optimize_lbvh_cpu, CostModel, TreeletSettings, WorkingTree};
use treelet::bvh::{sah_cost, SahParams};
use treelet::scene::load_scene;

/// The comma-separated numbers of `text`, or of `default` without it.
fn numbers(text: Option<String>, default: &str) -> Vec<u32> {
    text.unwrap_or_else(|| default.into())
        .split(',')
        .filter_map(|v| v.parse().ok())
        .collect()
}

fn main() -> treelet::Result<()> {
    let mut args = std::env::args().skip(1);
    let scenes = args.next().unwrap_or_else(|| "cornell,field-10k".into());
    let phase_counts = numbers(args.next(), "7");
    let round_counts = numbers(args.next(), "3,4");
    // The first round's phases: as the others' where not given.
    let first_counts: Vec<Option<u32>> = match args.next() {
        Some(text) => numbers(Some(text), "").into_iter().map(Some).collect(),
        None => vec![None],
    };
    let sizes = numbers(args.next(), "7");
    let sah = SahParams::default();
    let model = CostModel::from(&sah);
    let paper = TreeletSettings::BALANCED;
    println!("scene            size  rounds  phases  first  SAH          vs bottom-up  steps");
    for name in scenes.split(',') {
        let scene = load_scene(name)?;
        let (lbvh, parents) =
            build_lbvh_from_boxes_cpu(&prim_boxes_cpu(&scene.triangles), TRBVH_KEY_BITS);
        let lbvh = WorkingTree::from_lbvh(lbvh, parents);
        // The bottom-up rounds, each round's treelet levels counted on the tree it starts from.
        let mut tree = lbvh.clone();
        let mut levels = 0;
        for (round, &gamma) in paper.gammas().iter().enumerate() {
            levels += tree.treelet_levels(gamma).1.into_iter().max().unwrap_or(0);
            tree.optimize_round(&model, paper.round_size(round), gamma);
        }
        let reference = sah_cost(&tree.collapse(&model, None), &sah);
        println!(
            "{name:16} {:4}  {:6}  {:>6}  {:>5}  {reference:<11.4}  {:>12}  {levels:5}",
            paper.treelet_size, paper.rounds, "-", "-", "-"
        );
        for &treelet_size in &sizes {
            for &rounds in &round_counts {
                for &phases in &phase_counts {
                    for &first_round_phases in &first_counts {
                        let settings = TreeletSettings {
                            treelet_size,
                            rounds,
                            phases: Some(phases),
                            first_round_phases,
                            ..paper
                        };
                        let first = settings.round_phases(0).unwrap_or(phases);
                        let row = format!(
                            "{name:16} {treelet_size:4}  {rounds:6}  {phases:6}  {first:5}"
                        );
                        if let Err(error) = settings.validate(&sah) {
                            println!("{row}  {error}");
                            continue;
                        }
                        let phased = optimize_lbvh_cpu(lbvh.clone(), &settings, &model);
                        let cost = sah_cost(&phased.collapse(&model, None), &sah);
                        println!(
                            "{row}  {cost:<11.4}  {:>+11.2}%  {:5}",
                            (cost / reference - 1.0) * 100.0,
                            first + (rounds - 1) * phases
                        );
                    }
                }
            }
        }
    }
    Ok(())
}
