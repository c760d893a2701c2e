//! The `treelet` binary on bad input: a clear error message and a non-zero exit, never a panic.
//! And on good input: `render` writes a PNG, `bench` prints valid JSON lines.

mod common;

use common::{assert_clean_failure, run_treelet as treelet};

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

#[test]
fn bench_prints_json_lines() {
    let result = treelet(&[
        "bench", "--scene", "cornell", "--json", "--width", "32", "--height", "32", "--spp", "1",
    ]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let stdout = String::from_utf8(result.stdout).unwrap();
    let record: serde_json::Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
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
    assert_eq!(record["triangles"], 36);
    assert!(record["rays"].as_u64().unwrap() >= 32 * 32);
}
