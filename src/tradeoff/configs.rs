//! The builder configurations a trade-off study compares, derived from `Builder::ALL` by name so
//! that builders added later (e.g. `sbvh`, `trbvh-split`) join the study without changes here:
//! `trbvh` is swept over treelet sizes × rounds (and takes part with two phased rounds' settings),
//! `trbvh-split` over split budgets β (the paper's n = 7, 3 rounds), and every other builder in `Builder::ALL` takes part once with its listed
//! settings. GPU builders come first, then the CPU references.

use crate::bvh::treelet::TreeletSettings;
use crate::bvh::Builder;

/// Treelet sizes (leaves per treelet) swept for `trbvh`.
pub const TREELET_SIZES: [u32; 3] = [5, 7, 8];
/// Restructuring rounds swept for `trbvh`.
pub const ROUNDS: [u32; 3] = [1, 2, 3];
/// Pre-splitting budgets β (percent) swept for `trbvh-split`.
pub const SPLIT_PERCENTS: [u32; 3] = [10, 30, 50];
/// The phased rounds `trbvh` also takes part with (`TreeletSettings::phases`), 7 leaves, 3
/// rounds: 14, 7 and 7 phases (28), within 0.35 % of the paper's SAH on the shared scenes, and
/// 6, 4 and 4 (14, the later rounds' treelets with their leaves within 3 levels of their roots),
/// within 0.9 %.
pub const PHASED: [TreeletSettings; 2] = [
    TreeletSettings {
        phases: Some(7),
        first_round_phases: Some(14),
        ..TreeletSettings::BALANCED
    },
    TreeletSettings::PHASED,
];

/// The configurations to measure. `quick` keeps one `trbvh` setting (`TreeletSettings::FAST`)
/// and `trbvh-split` with its listed budget instead of the sweeps, for tests and previews.
pub fn configurations(quick: bool) -> Vec<Builder> {
    let all = Builder::ALL
        .iter()
        .flat_map(|&builder| variants(builder, quick));
    let (gpu, cpu): (Vec<Builder>, Vec<Builder>) = all.partition(|b| b.is_gpu());
    gpu.into_iter().chain(cpu).collect()
}

fn variants(builder: Builder, quick: bool) -> Vec<Builder> {
    if builder.name() == "trbvh-split" && !quick {
        return SPLIT_PERCENTS
            .iter()
            .map(|&split_percent| {
                builder.with_treelet_settings(TreeletSettings {
                    split_percent,
                    ..TreeletSettings::BALANCED
                })
            })
            .collect();
    }
    if builder.name() != "trbvh" {
        return vec![builder];
    }
    if quick {
        return vec![builder.with_treelet_settings(TreeletSettings::FAST)];
    }
    TREELET_SIZES
        .iter()
        .flat_map(|&treelet_size| {
            ROUNDS.iter().map(move |&rounds| {
                builder.with_treelet_settings(TreeletSettings {
                    treelet_size,
                    rounds,
                    split_percent: 0,
                    last_round_size: None,
                    phases: None,
                    first_round_phases: None,
                })
            })
        })
        .chain(PHASED.map(|phased| builder.with_treelet_settings(phased)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builder_takes_part_and_trbvh_is_swept() {
        let configs = configurations(false);
        for builder in Builder::ALL {
            assert!(
                configs.iter().any(|c| c.name() == builder.name()),
                "{} missing",
                builder.name()
            );
        }
        let trbvh = configs.iter().filter(|c| c.name() == "trbvh").count();
        assert_eq!(trbvh, TREELET_SIZES.len() * ROUNDS.len() + PHASED.len());
        let split = configs.iter().filter(|c| c.name() == "trbvh-split").count();
        if Builder::ALL.iter().any(|b| b.name() == "trbvh-split") {
            assert_eq!(split, SPLIT_PERCENTS.len());
        }
        let labels: std::collections::HashSet<String> = configs.iter().map(|c| c.label()).collect();
        assert_eq!(labels.len(), configs.len(), "labels are unique");
        let first_cpu = configs.iter().position(|c| !c.is_gpu());
        assert!(first_cpu.is_none_or(|i| configs[i..].iter().all(|c| !c.is_gpu())));
    }

    #[test]
    fn quick_keeps_one_trbvh_setting() {
        let configs = configurations(true);
        let trbvh: Vec<_> = configs.iter().filter(|c| c.name() == "trbvh").collect();
        assert_eq!(trbvh.len(), 1);
        assert_eq!(trbvh[0].label(), "trbvh n=5 r=1");
    }
}
