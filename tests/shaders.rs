//! Every WGSL kernel against its one Rust declaration (`kernel!`), checked with naga, so that a
//! mismatch fails `cargo test` without any GPU: the source (with includes and the generated
//! constants) parses and validates; the entry point exists with the declared workgroup size; every
//! declared binding exists in group 0 with the declared kind (the parameters as `var<uniform>` of
//! exactly the declared size, `var<storage, read>` or `read_write`); and the WGSL declares no
//! binding the Rust side does not. Every shader file is declared.

use treelet::gpu::{shader_source, KernelInfo, Slot, WORKGROUP_WIDTH_OVERRIDE};

fn parse(name: &str, source: &str) -> naga::Module {
    let source = shader_source(source, &[]);
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    module
}

/// The slot kind of a global variable, if it is a buffer binding.
fn slot_of(space: naga::AddressSpace) -> Option<Slot> {
    match space {
        naga::AddressSpace::Uniform => Some(Slot::Params),
        naga::AddressSpace::Storage { access } if access.contains(naga::StorageAccess::STORE) => {
            Some(Slot::ReadWrite)
        }
        naga::AddressSpace::Storage { .. } => Some(Slot::Read),
        _ => None,
    }
}

/// The entry point's workgroup size, an overridable dimension at its default value (a workgroup
/// width set by `gpu::WORKGROUP_WIDTH_OVERRIDE`, declared in Rust by its default).
fn workgroup_size(module: &naga::Module, entry: &naga::EntryPoint) -> [u32; 3] {
    let mut size = entry.workgroup_size;
    for (dim, expr) in entry.workgroup_size_overrides.iter().flatten().enumerate() {
        let Some(expr) = expr else { continue };
        let naga::Expression::Override(o) = module.global_expressions[*expr] else {
            panic!("workgroup size {dim}: not an override");
        };
        assert_eq!(
            module.overrides[o].name.as_deref(),
            Some(WORKGROUP_WIDTH_OVERRIDE),
            "workgroup size {dim}: the override's name"
        );
        let init = module.overrides[o]
            .init
            .expect("the override has a default");
        let naga::Expression::Literal(naga::Literal::U32(value)) = module.global_expressions[init]
        else {
            panic!("workgroup size {dim}: the default is not a u32 literal");
        };
        size[dim] = value;
    }
    size
}

fn check(info: &KernelInfo) {
    let who = format!("{}::{}", info.name, info.entry);
    let module = parse(&who, info.source);
    let entry = module
        .entry_points
        .iter()
        .find(|e| e.name == info.entry)
        .unwrap_or_else(|| panic!("{who}: no such entry point"));
    assert_eq!(entry.stage, naga::ShaderStage::Compute, "{who}: stage");
    assert_eq!(
        workgroup_size(&module, entry),
        info.workgroup_size,
        "{who}: workgroup size"
    );
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layouts");
    let mut declared = vec![false; info.slots.len()];
    for (_, var) in module.global_variables.iter() {
        let Some(binding) = &var.binding else {
            continue;
        };
        assert_eq!(binding.group, 0, "{who}: {:?} is not in group 0", var.name);
        let b = binding.binding as usize;
        let name = var.name.as_deref().unwrap_or("?");
        let Some(&slot) = info.slots.get(b) else {
            panic!("{who}: binding {b} ({name}) is not declared in Rust");
        };
        assert_eq!(
            slot_of(var.space),
            Some(slot),
            "{who}: binding {b} ({name}) is {:?} in WGSL, {slot:?} in Rust",
            var.space
        );
        if slot == Slot::Params {
            let size = u64::from(layouter[var.ty].size);
            assert_eq!(
                size, info.params_size,
                "{who}: the WGSL parameters ({name}) are {size} bytes, the Rust struct {}",
                info.params_size
            );
        }
        declared[b] = true;
    }
    if let Some(b) = declared.iter().position(|d| !d) {
        panic!("{who}: binding {b} is declared in Rust but not in the WGSL");
    }
}

#[test]
fn every_kernel_matches_its_declaration() {
    assert!(!treelet::kernels::ALL.is_empty());
    for info in treelet::kernels::ALL {
        check(info);
    }
}

#[cfg(feature = "app")]
#[test]
fn the_render_shader_validates() {
    parse("image_display", treelet::app::DISPLAY_SHADER);
}

#[test]
fn every_shader_file_is_declared() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "wgsl") {
            let stem = path.file_stem().unwrap().to_str().unwrap();
            assert!(
                stem == "image_display" || treelet::kernels::ALL.iter().any(|k| k.name == stem),
                "shaders/{stem}.wgsl has no kernel! declaration in treelet::kernels::ALL"
            );
        }
    }
}

/// Every file in `shaders/include` is known to the include expansion (which embeds them at
/// compile time) and expands to WGSL that parses on its own or with the includes it names.
#[test]
fn every_include_file_is_embedded() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/include");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let expanded = std::panic::catch_unwind(|| {
            treelet::gpu::shader_source(&format!("#include \"{name}\"\n"), &[])
        });
        assert!(
            expanded.is_ok_and(|text| !text.trim().is_empty()),
            "shaders/include/{name} is not in gpu::shaders' include table"
        );
    }
}

/// The checks catch what they claim to: a declaration with one binding too many, a wrong kind,
/// a wrong parameter size or a wrong workgroup size fails.
#[test]
fn mismatched_declarations_fail() {
    let good = treelet::bvh::lbvh::MORTON_COMPUTE.info;
    use Slot::{Params, Read, ReadWrite};
    assert_eq!(good.slots, [Params, Read, Read, ReadWrite, ReadWrite, Read]);
    let variants = [
        // A binding missing, one of the wrong kind, one too many.
        KernelInfo {
            slots: &[Params, Read, Read, ReadWrite, ReadWrite],
            ..good
        },
        KernelInfo {
            slots: &[Params, Read, Read, ReadWrite, Read, Read],
            ..good
        },
        KernelInfo {
            slots: &[Params, Read, Read, ReadWrite, ReadWrite, Read, Read],
            ..good
        },
        KernelInfo {
            params_size: 32,
            ..good
        },
        KernelInfo {
            workgroup_size: [32, 1, 1],
            ..good
        },
    ];
    check(&good);
    for variant in variants {
        let caught = std::panic::catch_unwind(|| check(&variant)).is_err();
        assert!(caught, "{variant:?} passed the check");
    }
}
