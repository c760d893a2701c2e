//! The quality–speed trade-off: the crossover computation on synthetic measurements (known build
//! times and throughputs, analytically known crossovers), and `treelet tradeoff` end to end on
//! `cornell` at a tiny resolution (CSV, JSON and PNG outputs).

mod common;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use treelet::tradeoff::{best_ranges, effective_mrays, BestRange, Measurement, RAYS_RANGE};

fn m(label: &str, build_ms: f64, mrays_per_s: f64) -> Measurement {
    Measurement {
        label: label.into(),
        builder: label.into(),
        treelet_size: None,
        rounds: None,
        gpu: true,
        build_ms,
        sah: 1.0,
        mrays_per_s,
        valid: true,
    }
}

/// `(label, from, to)` with ends compared to a relative tolerance.
fn assert_ranges(actual: &[BestRange], expected: &[(&str, f64, f64)]) {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
    let ok = actual.len() == expected.len()
        && actual.iter().zip(expected).all(|(a, &(label, from, to))| {
            a.label == label && close(a.from_rays, from) && close(a.to_rays, to)
        });
    assert!(ok, "expected {expected:?}, got {actual:?}");
}

#[test]
fn effective_throughput_approaches_the_raw_one() {
    let a = m("a", 10.0, 100.0);
    // 1e6 rays at 100 Mrays/s take 10 ms: half the frame is the build.
    assert!((effective_mrays(&a, 1e6) - 50.0).abs() < 1e-9);
    assert!(effective_mrays(&a, 1e15) > 99.99);
    assert_eq!(effective_mrays(&m("free", 0.0, 7.0), 0.0), 7.0);
}

#[test]
fn unusable_or_empty_inputs_give_no_ranges() {
    assert!(best_ranges(&[], 1.0, 2.0).is_empty());
    assert!(best_ranges(&[m("zero", 1.0, 0.0)], 1.0, 2.0).is_empty());
    assert!(best_ranges(&[m("a", 1.0, 1.0)], 2.0, 2.0).is_empty());
}

#[test]
fn two_configurations_cross_where_frame_times_are_equal() {
    // 1 ms + R/100M = 21 ms + R/200M  ⇔  R = 0.02 s / (1/100M − 1/200M) = 4M rays.
    let ms = [m("fast", 1.0, 100.0), m("good", 21.0, 200.0)];
    let ranges = best_ranges(&ms, 1e6, 1e12);
    assert_ranges(&ranges, &[("fast", 1e6, 4e6), ("good", 4e6, 1e12)]);
    // At the crossover both give the same effective throughput.
    let (a, b) = (effective_mrays(&ms[0], 4e6), effective_mrays(&ms[1], 4e6));
    assert!((a - b).abs() < 1e-9 * a, "{a} vs {b}");
}

#[test]
fn three_configurations_give_two_crossovers() {
    // lbvh → trbvh at 4M (as above); trbvh → sbvh at 1 s / (1/200M − 1/250M) = 1G rays.
    let ms = [
        m("sbvh", 1021.0, 250.0),
        m("lbvh", 1.0, 100.0),
        m("trbvh", 21.0, 200.0),
    ];
    assert_ranges(
        &best_ranges(&ms, 1e6, 1e12),
        &[("lbvh", 1e6, 4e6), ("trbvh", 4e6, 1e9), ("sbvh", 1e9, 1e12)],
    );
    // A narrower interval clips the ranges at its ends.
    assert_ranges(&best_ranges(&ms, 1e7, 1e8), &[("trbvh", 1e7, 1e8)]);
}

#[test]
fn a_configuration_above_the_envelope_is_never_best() {
    // "middle" (8 ms, 110 Mrays/s) takes 44.4 ms at the 4M crossover where the others take 41 ms,
    // and overtakes "fast" only at 7.7M, where "good" is already faster; "slow" is worse than
    // "fast" everywhere.
    let ms = [
        m("fast", 1.0, 100.0),
        m("middle", 8.0, 110.0),
        m("good", 21.0, 200.0),
        m("slow", 20.0, 50.0),
    ];
    assert_ranges(
        &best_ranges(&ms, 1e6, 1e12),
        &[("fast", 1e6, 4e6), ("good", 4e6, 1e12)],
    );
}

#[test]
fn ties_resolve_without_empty_ranges() {
    // Identical configurations: the one listed first wins everywhere.
    let twins = [m("first", 5.0, 100.0), m("second", 5.0, 100.0)];
    assert_ranges(&best_ranges(&twins, 1e6, 1e12), &[("first", 1e6, 1e12)]);
    // Equal at the start of the interval: the flatter one is best from there on.
    let at_start = [m("steep", 0.0, 100.0), m("flat", 5.0, 200.0)];
    assert_ranges(&best_ranges(&at_start, 1e6, 1e12), &[("flat", 1e6, 1e12)]);
    // Three lines through one point (2M rays, 20 ms): the middle slope's range would be empty.
    let three = [m("a", 0.0, 100.0), m("b", 10.0, 200.0), m("c", 15.0, 400.0)];
    assert_ranges(
        &best_ranges(&three, 1e6, 1e12),
        &[("a", 1e6, 2e6), ("c", 2e6, 1e12)],
    );
    // A crossover exactly at the end of the interval changes nothing inside it.
    let at_end = [m("fast", 1.0, 100.0), m("good", 21.0, 200.0)];
    assert_ranges(&best_ranges(&at_end, 1e6, 4e6), &[("fast", 1e6, 4e6)]);
}

#[test]
fn unusable_measurements_are_ignored() {
    let ms = [
        m("no-throughput", 0.0, 0.0),
        m("nan", f64::NAN, 10.0),
        m("ok", 3.0, 10.0),
    ];
    assert_ranges(&best_ranges(&ms, 1e6, 1e12), &[("ok", 1e6, 1e12)]);
}

#[test]
fn ranges_match_a_brute_force_search() {
    let mut rng = Pcg64::seed_from_u64(7);
    for case in 0..200 {
        let ms: Vec<Measurement> = (0..rng.random_range(1..8))
            .map(|i| {
                m(
                    &format!("c{i}"),
                    10f64.powf(rng.random_range(-2.0..4.0)),
                    10f64.powf(rng.random_range(0.0..3.0)),
                )
            })
            .collect();
        let (lo, hi) = RAYS_RANGE;
        let ranges = best_ranges(&ms, lo, hi);
        assert!(!ranges.is_empty());
        assert_eq!(ranges[0].from_rays, lo);
        assert_eq!(ranges.last().unwrap().to_rays, hi);
        for pair in ranges.windows(2) {
            assert_eq!(pair[0].to_rays, pair[1].from_rays, "case {case}: gap");
            assert_ne!(pair[0].label, pair[1].label, "case {case}: split range");
        }
        for r in &ranges {
            assert!(r.from_rays < r.to_rays, "case {case}: empty range {r:?}");
            // In the middle of each range (log scale) its configuration is the fastest.
            let mid = (r.from_rays * r.to_rays).sqrt();
            let time = |m: &Measurement| m.build_ms * 1e-3 + mid / (m.mrays_per_s * 1e6);
            let winner = ms.iter().find(|m| m.label == r.label).unwrap();
            let best = ms.iter().map(time).fold(f64::INFINITY, f64::min);
            assert!(
                time(winner) <= best * (1.0 + 1e-12),
                "case {case}: {} not best at {mid:e}: {ms:?}",
                r.label
            );
        }
    }
}

/// `treelet tradeoff` end to end (the command line needs feature "app").
#[cfg(feature = "app")]
mod command_line {
    use std::path::{Path, PathBuf};

    use super::common::run_treelet as treelet;

    fn out_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("treelet-tradeoff-{name}-{}", std::process::id()));
        std::fs::remove_dir_all(&dir).ok();
        dir
    }

    #[test]
    fn tradeoff_writes_csv_json_and_charts() {
        let dir = out_dir("cornell");
        let out = treelet(&[
            "tradeoff",
            "--scene",
            "cornell",
            "--out",
            dir.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "1",
            "--repeats",
            "1",
            "--quick",
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "tradeoff failed: {stderr}");

        let csv = std::fs::read_to_string(dir.join("tradeoff-cornell.csv")).unwrap();
        let mut lines = csv.lines();
        assert_eq!(
            lines.next().unwrap(),
            "label,builder,treelet_size,rounds,build_ms,sah,mrays_per_s,best_from_rays,best_to_rays"
        );
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        for row in &rows {
            assert_eq!(row.len(), 9, "{row:?}");
            for value in &row[4..7] {
                let v: f64 = value.parse().unwrap();
                assert!(v.is_finite() && v >= 0.0, "{row:?}");
            }
        }
        let labels: Vec<&str> = rows.iter().map(|r| r[0]).collect();
        for expected in ["lbvh", "trbvh n=5 r=1", "sweep"] {
            assert!(labels.contains(&expected), "{expected} missing: {labels:?}");
        }
        let trbvh = rows.iter().find(|r| r[0] == "trbvh n=5 r=1").unwrap();
        assert_eq!((trbvh[1], trbvh[2], trbvh[3]), ("trbvh", "5", "1"));
        assert!(
            rows.iter().any(|r| !r[7].is_empty() && !r[8].is_empty()),
            "some configuration is best somewhere"
        );

        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join("tradeoff-cornell.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(json["scene"], "cornell");
        assert!(json["triangles"].as_u64().unwrap() > 0);
        assert!(!json["adapter"].as_str().unwrap().is_empty());
        let measurements = json["measurements"].as_array().unwrap();
        assert_eq!(measurements.len(), rows.len());
        assert!(measurements.iter().all(|m| m["valid"] == true));
        let rays = json["curves"]["rays"].as_array().unwrap();
        assert_eq!(rays.len(), 61);
        assert_eq!(rays[0].as_f64().unwrap(), 1e6);
        let series = json["curves"]["series"].as_array().unwrap();
        assert_eq!(series.len(), rows.len());
        for (s, label) in series.iter().zip(&labels) {
            assert_eq!(s["label"], *label);
            assert_eq!(s["effective_mrays"].as_array().unwrap().len(), rays.len());
        }
        let ranges = json["best_ranges"].as_array().unwrap();
        assert_eq!(ranges[0]["from_rays"].as_f64().unwrap(), 1e6);
        assert_eq!(ranges.last().unwrap()["to_rays"].as_f64().unwrap(), 1e12);
        // Among GPU builders only, every winner is a GPU configuration.
        let gpu_labels: Vec<&str> = measurements
            .iter()
            .filter(|m| m["gpu"] == true)
            .map(|m| m["label"].as_str().unwrap())
            .collect();
        let gpu_ranges = json["best_ranges_gpu_only"].as_array().unwrap();
        assert!(!gpu_ranges.is_empty());
        for r in gpu_ranges {
            assert!(gpu_labels.contains(&r["label"].as_str().unwrap()), "{r}");
        }
        assert!(!json["pareto_front"].as_array().unwrap().is_empty());

        let size = (
            json["charts"]["width"].as_u64().unwrap() as u32,
            json["charts"]["height"].as_u64().unwrap() as u32,
        );
        for key in ["throughput", "pareto"] {
            let file = json["charts"][key].as_str().unwrap();
            assert_eq!(file, format!("tradeoff-cornell-{key}.png"));
            assert_chart(&dir.join(file), size);
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The PNG decodes to an image of `size` with something drawn on it.
    fn assert_chart(path: &Path, size: (u32, u32)) {
        let image = image::open(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .to_rgb8();
        assert_eq!(image.dimensions(), size, "{}", path.display());
        assert!(size.0 > 0 && size.1 > 0);
        let colours: std::collections::HashSet<[u8; 3]> = image.pixels().map(|p| p.0).collect();
        assert!(
            colours.len() > 16,
            "{} has only {} colours",
            path.display(),
            colours.len()
        );
    }

    #[test]
    fn tradeoff_bad_flags_are_clear_errors() {
        for (args, expected) in [
            (vec!["tradeoff", "--spp", "0"], "--spp"),
            (
                vec!["tradeoff", "--scene", "no-such-scene"],
                "unknown scene",
            ),
            (vec!["tradeoff", "--width", "0"], "must be positive"),
            (vec!["tradeoff", "--repeats", "x"], "invalid value"),
        ] {
            super::common::assert_clean_failure(&args, expected);
        }
    }
}
