//! How far a treelet round can run ahead of the one before (Karras & Aila 2013, §4: rounds of
//! bottom-up restructuring), measured on the CPU twin: `WorkingTree::optimize_overlapped` with each
//! reach, against the sequential rounds (`None`), from the LBVH of 32-bit keys that trbvh builds.
//! Prints per scene and reach the waves (the chain of dependent steps a GPU schedule would have),
//! how many of them optimize more than 128 treelets (a GPU would dispatch those; the climb's
//! workgroup takes the rest), the SAH of the collapsed tree and whether the working tree is the
//! sequential one.
//!
//! ```text
//! cargo run --release --example rounds_overlap -- conference,sibenik 6,4,2 [balanced|high]
//! ```
use treelet::bvh::lbvh::{build_lbvh_from_boxes_cpu, prim_boxes_cpu, TRBVH_KEY_BITS};
use treelet::bvh::treelet::{CostModel, TreeletSettings, WorkingTree};
use treelet::bvh::{sah_cost, SahParams};
use treelet::scene::load_scene;

fn main() -> treelet::Result<()> {
    let mut args = std::env::args().skip(1);
    let scenes = args.next().unwrap_or_else(|| "cornell,field-10k".into());
    let reaches: Vec<u32> = args
        .next()
        .unwrap_or_else(|| "6,4".into())
        .split(',')
        .filter_map(|r| r.parse().ok())
        .collect();
    let settings = TreeletSettings::preset(&args.next().unwrap_or_else(|| "balanced".into()))?;
    let sah = SahParams::default();
    let model = CostModel::from(&sah);
    let gammas = settings.gammas();
    println!("scene            reach  waves  >128  SAH          vs sequential  same tree");
    let wide = |sizes: &[u32]| sizes.iter().filter(|&&n| n > 128).count();
    for name in scenes.split(',') {
        let scene = load_scene(name)?;
        let boxes = prim_boxes_cpu(&scene.triangles);
        let (lbvh, parents) = build_lbvh_from_boxes_cpu(&boxes, TRBVH_KEY_BITS);
        let start = WorkingTree::from_lbvh(lbvh, parents);
        let mut sequential = start.clone();
        let chain = sequential.optimize_overlapped(&model, settings.treelet_size, &gammas, None);
        let sequential_sah = sah_cost(&sequential.collapse(&model, None), &sah);
        println!(
            "{name:16} {:>5}  {:5}  {:4}  {sequential_sah:.6}",
            "none",
            chain.len(),
            wide(&chain)
        );
        for &reach in &reaches {
            let mut tree = start.clone();
            let waves =
                tree.optimize_overlapped(&model, settings.treelet_size, &gammas, Some(reach));
            let cost = sah_cost(&tree.collapse(&model, None), &sah);
            println!(
                "{name:16} {reach:5}  {:5}  {:4}  {cost:.6}  {:+12.4} %  {}",
                waves.len(),
                wide(&waves),
                100.0 * (cost / sequential_sah - 1.0),
                tree.nodes == sequential.nodes
            );
        }
    }
    Ok(())
}
