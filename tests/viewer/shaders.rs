//! Every WGSL shader parses and validates with naga (no GPU needed), as the program embeds it.

fn validate(name: &str, source: &str) {
    let module =
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {e:?}"));
}

#[test]
fn all_shaders_validate() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let globals = std::fs::read_to_string(dir.join("globals.wgsl")).expect("shaders/globals.wgsl");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("shaders/ exists") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "wgsl") {
            continue;
        }
        let source = std::fs::read_to_string(&path).expect("readable");
        // A render shader reads the shared uniforms, which the renderer puts in front of it.
        let whole = if source.contains("globals.") { format!("{globals}{source}") } else { source };
        validate(&path.display().to_string(), &whole);
        count += 1;
    }
    assert!(count >= 4, "expected the globals, surface, line and compute shaders, found {count}");
    // The sources the program embeds.
    validate("SURFACE_WGSL", tissue_viewer::render::gpu::SURFACE_WGSL);
    validate("LINES_WGSL", tissue_viewer::render::gpu::LINES_WGSL);
    validate("EXPLICIT_STEP_WGSL", tissue_gpu::explicit::EXPLICIT_STEP_WGSL);
    assert_eq!(tissue_viewer::render::gpu::SURFACE_WGSL.matches("struct Globals").count(), 1);
}
