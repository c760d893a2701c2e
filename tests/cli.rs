//! The `treelet` binary on bad input: a clear error message and a non-zero exit, never a panic.
//! And on good input: `render` writes a PNG, `bench` prints valid JSON lines.

mod common;

use common::{assert_clean_failure, run_treelet as treelet, treelet_command};
use treelet::bvh::treelet::RoundSchedule;

#[test]
fn missing_scene_file_is_a_clear_error() {
    assert_clean_failure(
        &["render", "--scene", "/no/such/file.obj"],
        "/no/such/file.obj",
    );
}

#[test]
fn unknown_scene_name_is_a_clear_error() {
    assert_clean_failure(&["bench", "--scene", "no-such-scene"], "unknown scene");
}

#[test]
fn bad_flags_are_clear_errors() {
    assert_clean_failure(&["render", "--spp", "many"], "invalid value");
    assert_clean_failure(&["render", "--no-such-flag"], "unexpected argument");
    assert_clean_failure(&["bench", "--builder", "magic"], "unknown builder");
    assert_clean_failure(&["render", "--width", "0"], "must be positive");
    assert_clean_failure(&["render", "--max-leaf-size", "0"], "max-leaf-size");
    assert_clean_failure(&["render", "--spp", "0"], "--spp");
    assert_clean_failure(&["bench", "--spp", "0"], "--spp");
}

#[test]
fn malformed_obj_is_a_clear_error() {
    let path =
        std::env::temp_dir().join(format!("treelet-cli-malformed-{}.obj", std::process::id()));
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    assert_clean_failure(
        &["render", "--scene", path.to_str().unwrap()],
        path.to_str().unwrap(),
    );
    std::fs::remove_file(&path).ok();
}

#[test]
fn render_writes_a_png() {
    let out = std::env::temp_dir().join(format!("treelet-cli-render-{}.png", std::process::id()));
    let result = treelet(&[
        "render",
        "--scene",
        "cornell",
        "--out",
        out.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "2",
    ]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let image = image::open(&out).unwrap();
    assert_eq!((image.width(), image.height()), (32, 24));
    std::fs::remove_file(&out).ok();
}

/// `treelet` without arguments and without a display (the README's main job on a headless
/// machine) renders the default scene to `treelet.png` in the working folder, its BVH built on
/// the GPU by trbvh as in the viewer.
#[test]
fn main_job_without_a_display_renders_with_the_gpu_build() {
    let folder = std::env::temp_dir().join(format!("treelet-cli-main-{}", std::process::id()));
    std::fs::create_dir_all(&folder).unwrap();
    let result = treelet_command(&[])
        .current_dir(&folder)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("RUST_LOG", "info")
        .output()
        .expect("binary runs");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.contains("trbvh n=7 r=3 build"), "{stderr}");
    let image = image::open(folder.join("treelet.png")).unwrap();
    assert_eq!((image.width(), image.height()), (640, 480));
    std::fs::remove_dir_all(&folder).ok();
}

/// Runs `treelet bench` with `args`, which must succeed; its JSON lines.
fn bench_records(args: &[&str]) -> Vec<serde_json::Value> {
    let args: Vec<&str> = ["bench"].iter().chain(args).copied().collect();
    let result = treelet(&args);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let stdout = String::from_utf8(result.stdout).unwrap();
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// `bench` on field-10k with `builders`, one build and one 8 × 8 trace of 1 spp without warm-up,
/// and the `extra` options: its JSON lines. The schedule is not tuned unless `extra` says so (on a
/// GPU `bench` tunes by default, and runs compared by a test must time their own schedules).
fn quick_bench(builders: &str, extra: &[&str]) -> Vec<serde_json::Value> {
    let mut args = vec![
        "--scene",
        "field-10k",
        "--builder",
        builders,
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--repeats",
        "1",
        "--warmup-ms",
        "0",
    ];
    if !extra.contains(&"--tune-schedule") {
        args.extend_from_slice(&["--tune-schedule", "off"]);
    }
    args.extend_from_slice(extra);
    bench_records(&args)
}

/// `bench` prints one JSON line per builder, GPU builders first, each with the min/median/max of
/// its timed builds and traces, the warm-up it had and the traversal steps of its rays.
#[test]
fn bench_prints_json_lines() {
    let records = bench_records(&[
        "--scene",
        "cornell",
        "--builder",
        "sweep,lbvh",
        "--json",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "1",
        "--repeats",
        "3",
        "--warmup-ms",
        "50",
    ]);
    let builders: Vec<&str> = records
        .iter()
        .map(|r| r["builder"].as_str().unwrap())
        .collect();
    assert_eq!(builders, ["lbvh", "sweep"], "GPU builders run first");
    for record in &records {
        for key in [
            "scene",
            "builder",
            "triangles",
            "nodes",
            "leaves",
            "build_ms",
            "sah",
            "rays",
            "trace_ms",
            "mrays_per_s",
            "valid",
        ] {
            assert!(record.get(key).is_some(), "missing {key} in {record}");
        }
        assert_eq!(record["valid"], true);
        assert!(record.get("dispatch_ms").is_none(), "{record}");
        assert_eq!(record["triangles"], 36);
        assert_eq!(record["repeats"], 3);
        assert_eq!(record["warmup_ms"], 50.0);
        assert!(record["rays"].as_u64().unwrap() >= 32 * 32);
        let spread = |key: &str| {
            let s = &record[key];
            let v = |k: &str| {
                s[k].as_f64()
                    .unwrap_or_else(|| panic!("{key}.{k} in {record}"))
            };
            (v("min"), v("median"), v("max"))
        };
        let (min, median, max) = spread("build_ms_spread");
        assert!(min <= median && median <= max, "{record}");
        assert_eq!(median, record["build_ms"].as_f64().unwrap());
        if record["mrays_per_s"].is_f64() {
            let (min, median, max) = spread("mrays_per_s_spread");
            assert!(min <= median && median <= max, "{record}");
        }
        let trace_warmup = &record["trace_warmup"];
        assert!(trace_warmup["runs"].as_u64().unwrap() >= 1, "{record}");
        assert!(trace_warmup["ms"].as_f64().unwrap() >= 50.0, "{record}");
        // The traversal steps of the same rays, counted.
        let steps = &record["steps"];
        let rays = record["rays"].as_f64().unwrap();
        let nodes = steps["nodes"].as_u64().unwrap();
        assert!(
            nodes > 0 && steps["triangles"].as_u64().unwrap() > 0,
            "{record}"
        );
        assert_eq!(
            steps["nodes_per_ray"].as_f64().unwrap(),
            nodes as f64 / rays
        );
    }
    let gpu_warmup = &records[0]["build_warmup"];
    assert!(gpu_warmup["ms"].as_f64().unwrap() >= 50.0, "{gpu_warmup}");
    assert_eq!(records[0]["key_bits"], 44, "lbvh's keys: {}", records[0]);
    assert!(
        records[1]["key_bits"].is_null(),
        "a CPU builder sorts no keys"
    );
}

/// `bench --level-dispatches ... --team-below ... --climb-team-below ...` measures trbvh once per
/// combination (lbvh once) and reports each schedule; every schedule builds the same tree.
#[test]
fn bench_compares_round_schedules_on_the_same_tree() {
    let records = quick_bench(
        "lbvh,trbvh",
        &[
            "--level-dispatches",
            "0,3",
            "--team-below",
            "0,4096",
            "--climb-team-below",
            "0,16",
        ],
    );
    let schedule = |r: &serde_json::Value| {
        (
            r["builder"].as_str().unwrap().to_owned(),
            r["level_dispatches"].as_u64(),
            r["team_below"].as_u64(),
            r["climb_team_below"].as_u64(),
        )
    };
    let runs: Vec<_> = records.iter().map(schedule).collect();
    let trbvh = |d, t, c| ("trbvh".to_owned(), Some(d), Some(t), Some(c));
    assert_eq!(
        runs,
        [
            ("lbvh".to_owned(), None, None, None),
            trbvh(0, 0, 0),
            trbvh(0, 0, 16),
            trbvh(0, 4096, 0),
            trbvh(0, 4096, 16),
            trbvh(3, 0, 0),
            trbvh(3, 0, 16),
            trbvh(3, 4096, 0),
            trbvh(3, 4096, 16),
        ]
    );
    for record in &records[2..] {
        assert_eq!(record["valid"], true);
        assert_eq!(record["sah"], records[1]["sah"], "{record}");
        assert_eq!(record["nodes"], records[1]["nodes"], "{record}");
    }
}

/// `bench --treelet-dp unrolled,loop --climb-dp ...` measures trbvh once per pair of DP forms
/// (dispatched levels, climb) and reports it; all build the same tree.
#[test]
fn bench_compares_dp_forms_on_the_same_tree() {
    let records = quick_bench(
        "trbvh",
        &[
            "--treelet-dp",
            "unrolled,loop",
            "--climb-dp",
            "loop,unrolled",
        ],
    );
    let forms: Vec<_> = records
        .iter()
        .map(|r| {
            let form = |key: &str| r[key].as_str().unwrap().to_owned();
            (form("treelet_dp"), form("climb_dp"))
        })
        .collect();
    let pair = |a: &str, b: &str| (a.to_owned(), b.to_owned());
    assert_eq!(
        forms,
        [
            pair("unrolled", "loop"),
            pair("unrolled", "unrolled"),
            pair("loop", "loop"),
            pair("loop", "unrolled"),
        ]
    );
    for record in &records[1..] {
        assert_eq!(record["valid"], true);
        assert_eq!(record["sah"], records[0]["sah"]);
        assert_eq!(record["nodes"], records[0]["nodes"]);
    }
}

/// The device type a bench record names.
fn record_device(record: &serde_json::Value) -> wgpu::DeviceType {
    match record["device_type"].as_str() {
        Some("Cpu") => wgpu::DeviceType::Cpu,
        Some("DiscreteGpu") => wgpu::DeviceType::DiscreteGpu,
        Some("IntegratedGpu") => wgpu::DeviceType::IntegratedGpu,
        Some("VirtualGpu") => wgpu::DeviceType::VirtualGpu,
        Some("Other") => wgpu::DeviceType::Other,
        other => panic!("unexpected device type {other:?}"),
    }
}

/// The subtree width in effect by default on the device a bench record names (a CPU device fills
/// the list, a GPU takes fewer subtrees per workgroup).
fn default_subtree_width(record: &serde_json::Value) -> u64 {
    u64::from(RoundSchedule::default().subtree_width(record_device(record)))
}

/// The schedule a bench record's tuning kept: its last adopted trial's, or the default.
fn kept_schedule(record: &serde_json::Value) -> &str {
    record["schedule_tuning"]["trials"]
        .as_array()
        .unwrap()
        .iter()
        .rev()
        .find(|t| t["adopted"] == true)
        .map_or("default", |t| t["schedule"].as_str().unwrap())
}

/// `bench --subtree-levels 0,4,8` measures trbvh with each round's lowest levels by level and
/// per subtree of 4 and 8 levels, reports the height and the width in effect, and builds the
/// same tree with each.
#[test]
fn bench_subtree_levels_reports_each_height() {
    let records = quick_bench("trbvh", &["--subtree-levels", "0,4,8"]);
    let heights = u64_values(&records, "subtree_levels");
    assert_eq!(heights, [Some(0), Some(4), Some(8)]);
    // The width in effect with subtrees: the device type's default.
    let width = default_subtree_width(&records[0]);
    let widths = u64_values(&records, "subtree_width");
    assert_eq!(widths, [None, Some(width), Some(width)]);
    for record in &records {
        assert_eq!(record["valid"], true);
        assert_eq!(record["sah"], records[0]["sah"]);
        assert_eq!(record["nodes"], records[0]["nodes"]);
    }
}

/// `bench --last-round-size 5,7` builds trbvh once per last round's treelet size, reported in
/// `last_round_size` (the treelet size where not given) and in no other builder's record; both
/// trees are valid, and the cheaper last round's SAH is within 1 % of the rounds of one size. A
/// size out of range, or with overlapped rounds, is refused.
#[test]
fn bench_last_round_size_reports_each_size() {
    let records = quick_bench("lbvh,trbvh", &["--last-round-size", "5,7"]);
    assert_eq!(
        u64_values(&records, "last_round_size"),
        [None, Some(5), Some(7)]
    );
    assert!(records.iter().all(|r| r["valid"] == true), "{records:?}");
    assert_sah_within_1_percent(&records[1], &records[2]);
    assert_trbvh_bench_refuses(
        &["--last-round-size", "9"],
        "last round's treelet size must be 3..=8, got 9",
    );
    assert_trbvh_bench_refuses(
        &["--last-round-size", "5", "--round-overlap", "6"],
        "the overlapped treelet rounds take one treelet size",
    );
}

/// `bench --phases 0,7` builds trbvh with the bottom-up rounds and with each round in 7 phases,
/// reported in `phases` (null: bottom-up) and in no other builder's record: both trees are valid,
/// the phased one within 1 % of the bottom-up one's SAH, and the phases take no treelet levels of
/// their own (no climb). Too few phases (fewer than 3), or phases with overlapped rounds, are
/// refused; a phased preset's first-round phases go to its phased variants only. `--root-slots`
/// reports both ways for the phased rounds alone, each with the same tree.
#[test]
fn bench_phases_reports_each_count() {
    let records = quick_bench("lbvh,trbvh", &["--phases", "0,7"]);
    assert_eq!(u64_values(&records, "phases"), [None, None, Some(7)]);
    assert_eq!(
        u64_values(&records, "first_round_phases"),
        [None, None, Some(7)]
    );
    assert!(records.iter().all(|r| r["valid"] == true), "{records:?}");
    assert_sah_within_1_percent(&records[2], &records[1]);
    assert!(
        records[2]["stages_ms"]["treelets climb"].is_null(),
        "{:?}",
        records[2]
    );
    assert_trbvh_bench_refuses(&["--phases", "2"], "treelet phases must be 3..=16");
    // First-round phases apply to the phased variants of a sweep; alone they are refused.
    let records = quick_bench("trbvh", &["--phases", "0,7", "--first-round-phases", "14"]);
    assert_eq!(u64_values(&records, "phases"), [None, Some(7)]);
    assert_eq!(u64_values(&records, "first_round_phases"), [None, Some(14)]);
    assert_trbvh_bench_refuses(
        &["--first-round-phases", "14"],
        "first-round phases need phased rounds",
    );
    // The phased preset's first-round phases apply to its phased variants only.
    let records = quick_bench("trbvh", &["--preset", "phased", "--phases", "0,4"]);
    assert_eq!(u64_values(&records, "rounds"), [Some(3), Some(3)]);
    assert_eq!(u64_values(&records, "phases"), [None, Some(4)]);
    assert_eq!(u64_values(&records, "first_round_phases"), [None, Some(6)]);
    assert!(records.iter().all(|r| r["valid"] == true), "{records:?}");
    let records = quick_bench(
        "trbvh",
        &[
            "--preset",
            "phased",
            "--phases",
            "0,4",
            "--root-slots",
            "workgroup,root",
        ],
    );
    let slots: Vec<Option<&str>> = records.iter().map(|r| r["root_slots"].as_str()).collect();
    assert_eq!(slots, [None, None, Some("workgroup"), Some("root")]);
    assert_eq!(records[2]["sah"], records[3]["sah"]);
    assert_eq!(records[0]["sah"], records[1]["sah"]);
    assert_trbvh_bench_refuses(
        &["--phases", "7", "--round-overlap", "6"],
        "the phased treelet rounds take no overlap, subtrees",
    );
}

/// Record `a`'s SAH within 1 % of record `b`'s.
fn assert_sah_within_1_percent(a: &serde_json::Value, b: &serde_json::Value) {
    let (a, b) = (a["sah"].as_f64().unwrap(), b["sah"].as_f64().unwrap());
    assert!((a / b - 1.0).abs() < 0.01, "{a} against {b}");
}

/// Field `key` of each record, where it is a number.
fn u64_values(records: &[serde_json::Value], key: &str) -> Vec<Option<u64>> {
    records.iter().map(|r| r[key].as_u64()).collect()
}

/// `bench` of trbvh on the Cornell box with `extra` fails cleanly with `message`.
fn assert_trbvh_bench_refuses(extra: &[&str], message: &str) {
    let bench = ["bench", "--scene", "cornell", "--builder", "trbvh"];
    assert_clean_failure(&[&bench[..], extra].concat(), message);
}

/// `bench --round-overlap none,6,7` measures trbvh with the rounds one after another and
/// overlapped at each reach, reports the reach (null for none), and builds the same tree at
/// reaches 6 and 7 (the scene's overlapped rounds give the sequential tree); a reach below the
/// treelet size's least is refused with an error.
#[test]
fn bench_round_overlap_reports_each_reach() {
    let records = quick_bench("trbvh", &["--round-overlap", "none,6,7"]);
    let reaches = u64_values(&records, "round_overlap");
    assert_eq!(reaches, [None, Some(6), Some(7)]);
    for record in &records {
        assert_eq!(record["valid"], true);
    }
    for record in &records[1..] {
        assert_eq!(record["sah"], records[0]["sah"]);
        assert_eq!(record["nodes"], records[0]["nodes"]);
    }
    // Below treelet size − 1 two treelets of a wave could share nodes: refused.
    assert_trbvh_bench_refuses(
        &["--round-overlap", "5"],
        "round overlap reach of 5 is below 6, the least for treelets of 7 leaves",
    );
    // Overlapped rounds find their own waves: not with subtrees.
    assert_trbvh_bench_refuses(
        &["--round-overlap", "6", "--subtree-levels", "4"],
        "either overlap or take subtrees, not both",
    );
}

/// `bench --tune-schedule on` tunes the phased rounds' own schedule: their team threshold, DP
/// form and root slots (and the sort tile), never a dimension of the bottom-up rounds; no trial
/// builds another tree, and the record reports the root slots kept.
#[test]
fn bench_tunes_the_phased_rounds() {
    let records = quick_bench(
        "trbvh",
        &[
            "--preset",
            "phased",
            "--tune-schedule",
            "on",
            "--tune-pairs",
            "1",
        ],
    );
    let record = &records[0];
    let trials = record["schedule_tuning"]["trials"].as_array().unwrap();
    // The team thresholds (3), the other DP form, the other root slots and the sort tiles (2).
    assert!(trials.len() >= 7, "{trials:?}");
    let schedules: Vec<&str> = trials
        .iter()
        .map(|t| t["schedule"].as_str().unwrap())
        .collect();
    for (trial, schedule) in trials.iter().zip(&schedules) {
        assert_eq!(trial["other_tree"], false, "{trial}");
        for part in ["overlap", "subtrees", "d=", "climb"] {
            assert!(!schedule.contains(part), "{schedule}");
        }
    }
    for part in ["t=", "dp=loop", "slots="] {
        assert!(schedules.iter().any(|s| s.contains(part)), "{schedules:?}");
    }
    let kept = kept_schedule(record);
    let slots = kept.split(' ').find_map(|p| p.strip_prefix("slots="));
    let default = RoundSchedule::default()
        .root_slots(record_device(record))
        .name();
    assert_eq!(
        record["root_slots"],
        slots.unwrap_or(default),
        "{kept} {record}"
    );
    assert_eq!(record["valid"], true);
}

/// `bench --tune-schedule on` tunes lbvh's and trbvh's build schedules from the one given
/// (`--round-overlap none` stays as given): every trial is listed with both medians, no schedule
/// built another tree, lbvh tries sort tiles alone, the schedule reported is the last one kept
/// (or the one given), and the trees are the untuned ones. With auto a CPU device does not tune
/// and a GPU does.
#[test]
fn bench_tunes_the_schedule_on_request() {
    let untuned = quick_bench("lbvh,trbvh", &[]);
    assert!(untuned.iter().all(|r| r["schedule_tuning"].is_null()));
    // Auto: a CPU device does not tune, a GPU does.
    let auto = quick_bench("lbvh", &["--tune-schedule", "auto"]);
    let cpu = auto[0]["device_type"] == "Cpu";
    assert_eq!(auto[0]["schedule_tuning"].is_null(), cpu, "{}", auto[0]);
    let tuned = quick_bench(
        "lbvh,trbvh",
        &[
            "--tune-schedule",
            "on",
            "--tune-pairs",
            "1",
            "--round-overlap",
            "none",
        ],
    );
    for (record, untuned) in tuned.iter().zip(&untuned) {
        let trials = record["schedule_tuning"]["trials"].as_array().unwrap();
        let treelets = record["builder"] == "trbvh";
        // trbvh: the subtree levels (3), the DP forms (2), the team thresholds (3), the level
        // dispatches (3) and the sort tiles (2, the CPU device's default being 32) at least;
        // lbvh: the sort tiles.
        assert!(trials.len() >= if treelets { 13 } else { 2 }, "{trials:?}");
        for trial in trials {
            assert_eq!(trial["other_tree"], false, "{trial}");
            assert!(trial["kept_ms"].as_f64().unwrap() > 0.0);
            assert!(trial["candidate_ms"].as_f64().unwrap() > 0.0);
            let schedule = trial["schedule"].as_str().unwrap();
            assert!(!schedule.contains("overlap"));
            // lbvh: a tile, or back to the default one.
            let tile_only = schedule.starts_with("tile=") || schedule == "default";
            assert!(treelets || tile_only, "{schedule}");
        }
        let kept = kept_schedule(record);
        assert!(record["schedule_tuning"]["kept"].is_string());
        let parts: Vec<&str> = kept.split(' ').collect();
        let value = |key: &str| parts.iter().find_map(|p| p.strip_prefix(key));
        let tile = value("tile=").map(|t| t.parse::<u64>().unwrap());
        assert_eq!(record["sort_tile_items"].as_u64(), tile, "{kept} {record}");
        if treelets {
            let team_below = value("t=").map_or(0, |t| t.parse().unwrap());
            assert_eq!(record["team_below"], team_below, "{kept} {record}");
            let climb_team_below = value("climb-t=").map_or(0, |t| t.parse().unwrap());
            assert_eq!(
                record["climb_team_below"], climb_team_below,
                "{kept} {record}"
            );
            let dp = if parts.contains(&"dp=loop") {
                "loop"
            } else {
                "unrolled"
            };
            assert_eq!(record["treelet_dp"], dp, "{kept} {record}");
            assert!(record["round_overlap"].is_null());
            let subtrees = value("subtrees=").map_or(0, |k| k.parse().unwrap());
            assert_eq!(record["subtree_levels"], subtrees, "{kept} {record}");
            if subtrees > 0 {
                // The device type's width unless another was kept.
                let width = value("subtree-width=")
                    .map_or(default_subtree_width(record), |w| w.parse().unwrap());
                assert_eq!(record["subtree_width"], width, "{kept} {record}");
            }
        }
        assert_eq!(record["valid"], true);
        assert_eq!(record["sah"], untuned["sah"]);
        assert_eq!(record["nodes"], untuned["nodes"]);
    }
}

/// `bench --wide-level-dispatches` converts the same tree with every split of the wide levels
/// between indirect dispatches and the subtree finish (the root's dispatch and the finish
/// always run), reports the count asked for, and is refused without the wide layout.
#[test]
fn bench_wide_level_dispatches_convert_the_same_tree() {
    let records = quick_bench(
        "trbvh",
        &["--layout", "wide", "--wide-level-dispatches", "0,3,32"],
    );
    let asked = u64_values(&records, "wide_level_dispatches");
    assert_eq!(asked, [Some(0), Some(3), Some(32)]);
    let dispatches: Vec<_> = records
        .iter()
        .map(|r| r["stages_dispatches"]["wide"].as_u64().unwrap())
        .collect();
    // The root's dispatch (levels 0-2), the level dispatches after it, the finish, the copy of
    // the references' triangles.
    assert_eq!(dispatches, [3, 4, 33]);
    for record in &records {
        assert_eq!(record["valid"], true);
        for key in ["nodes", "wide_sah", "wide_levels", "sah"] {
            assert_eq!(record[key], records[0][key], "{key}");
        }
    }
    assert_clean_failure(
        &[
            "bench",
            "--scene",
            "cornell",
            "--wide-level-dispatches",
            "3",
        ],
        "applies to the wide layout",
    );
    assert_clean_failure(
        &["bench", "--layout", "wide", "--wide-level-dispatches", "33"],
        "--wide-level-dispatches",
    );
}

/// `bench --sort-tile-items` sorts in tiles of 2048, 4096 or 8192 keys; every tile builds the
/// same trees, and other values are refused.
#[test]
fn bench_sort_tiles_build_the_same_trees() {
    let run = |items: &str| quick_bench("lbvh,trbvh", &["--sort-tile-items", items]);
    let tree = |r: &serde_json::Value| (r["sah"].clone(), r["nodes"].clone(), r["valid"].clone());
    let largest = run("32");
    for items in ["8", "16"] {
        let records = run(items);
        for (record, reference) in records.iter().zip(&largest) {
            assert_eq!(record["sort_tile_items"], items.parse::<u64>().unwrap());
            assert_eq!(tree(record), tree(reference), "{record}");
        }
    }
    let refused = treelet(&["bench", "--scene", "cornell", "--sort-tile-items", "12"]);
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("must be one of [8, 16, 32]"), "{stderr}");
}

/// `bench --climb-width` runs the bottom-up climbs at that workgroup width (the JSON says which
/// ran); every width builds the same trees, and other values are refused.
#[test]
fn bench_climb_widths_build_the_same_trees() {
    let run = |width: &str| quick_bench("lbvh,trbvh", &["--climb-width", width]);
    let tree = |r: &serde_json::Value| (r["sah"].clone(), r["nodes"].clone(), r["valid"].clone());
    let default = quick_bench("lbvh,trbvh", &[]);
    for width in ["8", "64", "256"] {
        for (record, reference) in run(width).iter().zip(&default) {
            assert_eq!(record["climb_width"], width.parse::<u64>().unwrap());
            assert_eq!(tree(record), tree(reference), "{record}");
        }
    }
    let refused = treelet(&["bench", "--scene", "cornell", "--climb-width", "48"]);
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("must be one of [8, 16, 32, 64, 128, 256]"),
        "{stderr}"
    );
}

/// `bench --wide-collapse optimal,greedy` converts the same tree both ways on the GPU (greedy by
/// default): valid trees, the optimal one of the optimal SAH with fewer nodes and two more
/// dispatches in the wide stage; a collapse without the wide layout is refused, and so is an
/// unknown one.
#[test]
fn bench_converts_by_both_wide_collapses() {
    let default = quick_bench("trbvh", &["--layout", "wide"]);
    let both = quick_bench(
        "trbvh",
        &["--layout", "wide", "--wide-collapse", "optimal,greedy"],
    );
    let (optimal, greedy) = (&both[0], &both[1]);
    assert_eq!(default[0]["wide_collapse"], "greedy");
    assert_eq!(optimal["wide_collapse"], "optimal");
    assert_eq!(greedy["wide_collapse"], "greedy");
    for run in [optimal, greedy] {
        assert_eq!(run["valid"], true);
        assert_eq!(run["wide_sah_optimal"], optimal["wide_sah_optimal"]);
        assert!(run["wide_levels"].as_u64() > Some(1), "{run}");
    }
    assert!(default[0]["wide_levels"].as_u64() > Some(1));
    assert_eq!(optimal["wide_sah"], optimal["wide_sah_optimal"]);
    assert!(greedy["wide_sah"].as_f64() > optimal["wide_sah"].as_f64());
    assert!(optimal["nodes"].as_u64() < greedy["nodes"].as_u64());
    let wide_dispatches =
        |run: &serde_json::Value| run["stages_dispatches"]["wide"].as_u64().unwrap();
    assert_eq!(wide_dispatches(optimal), wide_dispatches(greedy) + 2);
    assert_clean_failure(
        &["bench", "--scene", "cornell", "--wide-collapse", "greedy"],
        "applies to the wide layout",
    );
    assert_clean_failure(
        &["bench", "--scene", "cornell", "--wide-collapse", "best"],
        "unknown wide collapse 'best'",
    );
}

/// `bench --profile-dispatches` times every dispatch on its own: `dispatch_ms` lists them in
/// order, as many per stage as the stage's dispatch count, each a declared kernel, and the
/// stage times are their sums.
#[test]
fn bench_profiles_every_dispatch() {
    let records = quick_bench("lbvh,trbvh,trbvh-split", &["--profile-dispatches"]);
    let declared: Vec<&str> = treelet::kernels::ALL.iter().map(|k| k.name).collect();
    for record in &records {
        assert_eq!(record["valid"], true);
        let dispatches = record["dispatch_ms"].as_array().expect("dispatch_ms");
        assert_eq!(
            dispatches.len() as u64,
            record["dispatches"].as_u64().unwrap(),
            "{record}"
        );
        let kernels: Vec<&str> = dispatches
            .iter()
            .map(|d| d["kernel"].as_str().unwrap())
            .collect();
        for kernel in &kernels {
            assert!(declared.contains(kernel), "{kernel} in {record}");
        }
        assert_eq!(kernels[0], "triangles_bounds", "{record}");
        let morton = kernels.iter().position(|&k| k == "morton_compute").unwrap();
        assert_eq!(kernels[morton + 1], "keys_histogram", "{record}");
        for (stage, count) in record["stages_dispatches"].as_object().unwrap() {
            let of_stage: Vec<&serde_json::Value> = dispatches
                .iter()
                .filter(|d| d["stage"] == stage.as_str())
                .collect();
            assert_eq!(of_stage.len() as u64, count.as_u64().unwrap(), "{stage}");
            if let Some(total) = record["stages_ms"][stage].as_f64() {
                let sum: f64 = of_stage.iter().map(|d| d["ms"].as_f64().unwrap()).sum();
                assert!(
                    (sum - total).abs() <= 1e-9 * total.max(1.0),
                    "{stage}: {sum} vs {total}"
                );
            }
        }
        if record["builder"] != "lbvh" {
            for kernel in [
                "nodes_level",
                "treelets_optimize",
                "treelets_climb",
                "nodes_mark",
                "counts_scan",
                "nodes_compact",
            ] {
                assert!(kernels.contains(&kernel), "{kernel} in {record}");
            }
        }
    }
}

/// A fresh temporary path named `stem` with `extension`.
fn temp_path(stem: &str, extension: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!(
        "treelet-cli-{stem}-{}.{extension}",
        std::process::id()
    ))
}

#[test]
fn an_aff_file_given_by_path_renders() {
    let aff = temp_path("scene", "aff");
    std::fs::write(
        &aff,
        "v\nfrom 0 0 3\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 32 24\n\
         f 0.8 0.5 0.2 1 0 0 0 1\n\
         p 4\n -1 -1 0\n 1 -1 0\n 1 1 0\n -1 1 0\n",
    )
    .unwrap();
    let out = temp_path("aff-render", "png");
    let args = ["--width", "16", "--height", "12", "--spp", "1"];
    for command in ["render", "bench"] {
        let mut full = vec![command, "--scene", aff.to_str().unwrap()];
        full.extend(args);
        if command == "render" {
            full.extend(["--out", out.to_str().unwrap()]);
        } else {
            full.extend(["--repeats", "1", "--warmup-ms", "0"]);
        }
        let result = treelet(&full);
        assert!(
            result.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
    }
    assert!(image::open(&out).is_ok());
    std::fs::remove_file(&out).ok();
    std::fs::remove_file(&aff).ok();
    assert_clean_failure(
        &["render", "--scene", "/no/such/scene.aff"],
        "/no/such/scene.aff",
    );
}

#[test]
fn writing_into_a_missing_folder_says_cannot_write() {
    assert_clean_failure(
        &[
            "render",
            "--out",
            "/nonexistent/dir/x.png",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "1",
        ],
        "cannot write /nonexistent/dir/x.png",
    );
}

#[test]
fn overflowing_triangles_are_reported_as_such() {
    let obj = temp_path("overflow", "obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -3e38 0 0\nv 3e38 0 0\nv 0 3e38 0\nf 1 2 3\nf 4 5 6\n",
    )
    .unwrap();
    let out = temp_path("overflow", "png");
    let result = treelet(&[
        "render",
        "--scene",
        obj.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(
        stderr.contains("0 triangle(s) with non-finite coordinates, 1 with coordinates so large"),
        "{stderr}"
    );
    std::fs::remove_file(&obj).ok();
    std::fs::remove_file(&out).ok();
}

#[test]
fn options_of_other_builders_are_refused() {
    let cases: [(&[&str], &str); 15] = [
        (
            &["render", "--builder", "sweep", "--treelet-size", "99"],
            "--treelet-size does not apply to builder sweep",
        ),
        (
            &["bench", "--builder", "lbvh,sbvh", "--rounds", "2"],
            "--rounds does not apply to builder lbvh, sbvh",
        ),
        (
            &["render", "--builder", "lbvh", "--preset", "fast"],
            "--preset does not apply",
        ),
        (
            &["bench", "--builder", "lbvh", "--team-below", "64"],
            "--team-below does not apply to builder lbvh: only trbvh and trbvh-split have treelets",
        ),
        (
            &["bench", "--builder", "lbvh", "--last-round-size", "5"],
            "--last-round-size does not apply to builder lbvh",
        ),
        (
            &["bench", "--builder", "lbvh", "--phases", "7"],
            "--phases does not apply to builder lbvh",
        ),
        (
            &["bench", "--builder", "sbvh", "--climb-team-below", "8"],
            "--climb-team-below does not apply to builder sbvh",
        ),
        (
            &["bench", "--builder", "lbvh", "--treelet-dp", "loop"],
            "--treelet-dp does not apply to builder lbvh",
        ),
        (
            &["bench", "--builder", "trbvh", "--treelet-dp", "recursive"],
            "invalid value 'recursive' for '--treelet-dp",
        ),
        (
            &["bench", "--builder", "sweep", "--climb-dp", "loop"],
            "--climb-dp does not apply to builder sweep",
        ),
        (
            &["bench", "--builder", "lbvh", "--round-overlap", "6"],
            "--round-overlap does not apply to builder lbvh",
        ),
        (
            &["bench", "--builder", "trbvh", "--round-overlap", "far"],
            "'far' is neither a number of levels nor none",
        ),
        (
            &["bench", "--builder", "sweep,sbvh", "--tune-schedule", "on"],
            "--tune-schedule on does not apply to builder sweep, sbvh: only GPU builders",
        ),
        (
            &["bench", "--builder", "trbvh", "--tune-pairs", "0"],
            "invalid value '0' for '--tune-pairs",
        ),
        (
            &["bench", "--builder", "trbvh", "--split-budget", "0.3"],
            "--split-budget does not apply to builder trbvh",
        ),
    ];
    for (args, message) in cases {
        assert_clean_failure(args, message);
    }
}

/// `bench --export-bvh` writes each builder's tree; `bvh::read_bvh` reads it back as a valid tree
/// over the scene's triangles, and refuses files that are not one.
#[test]
fn exported_trees_read_back_as_valid_trees() {
    let dir = temp_path("export", "d");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("tree.bvh");
    quick_bench(
        "sweep,trbvh-split",
        &["--export-bvh", file.to_str().unwrap()],
    );
    let scene = treelet::scene::load_scene("field-10k").unwrap();
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert_eq!(files.len(), 2, "{files:?}");
    for path in &files {
        let (bvh, triangle_count) = treelet::bvh::read_bvh(path).unwrap();
        assert_eq!(triangle_count as usize, scene.triangles.len());
        // The split builder's leaves bound pieces of triangles (references), not whole ones.
        let split = path.to_string_lossy().contains("split");
        let valid = if split {
            treelet::bvh::validate_with_references(&bvh, &scene.triangles)
        } else {
            treelet::bvh::validate(&bvh, &scene.triangles)
        };
        valid.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
    let garbage = dir.join("garbage.bvh");
    // A header promising 5 nodes and 3 references, followed by nothing.
    let header: Vec<u8> = [5u32, 3, 10, 0]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect();
    std::fs::write(&garbage, [&b"TRLTBVH1"[..], &header].concat()).unwrap();
    let e = treelet::bvh::read_bvh(&garbage).unwrap_err().to_string();
    assert!(e.contains("does not match"), "{e}");
    std::fs::write(&garbage, b"not a tree at all, just some words").unwrap();
    let e = treelet::bvh::read_bvh(&garbage).unwrap_err().to_string();
    assert!(e.contains("not a treelet BVH file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
