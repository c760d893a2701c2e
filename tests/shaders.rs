//! Every WGSL kernel, with its includes expanded, parses and validates with naga: a broken shader
//! fails `cargo test` without any GPU.

use treelet::gpu::{shader_source, KERNELS};

#[test]
fn every_kernel_validates_with_naga() {
    assert!(!KERNELS.is_empty());
    for (name, _) in KERNELS {
        let source = shader_source(name);
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    }
}

#[test]
fn every_shader_file_is_registered() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "wgsl") {
            let file = path.file_name().unwrap().to_str().unwrap();
            assert!(
                KERNELS.iter().any(|(n, _)| *n == file),
                "{file} is not listed in gpu::shaders::KERNELS"
            );
        }
    }
}
