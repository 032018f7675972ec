//! Every WGSL module parses and validates with naga, and every Rust mirror of a WGSL struct has the size and
//! field offsets naga's layouter gives the WGSL struct. No GPU needed.

use std::mem::{offset_of, size_of};

use energywave::gpu::layout::*;
use energywave::gpu::shaders;

fn parse_and_validate(name: &str, source: &str) -> naga::Module {
    parse_and_validate_with(name, source, &[])
}

/// `parse_and_validate`, the pipeline-overridable constants set to `constants` (the rest at their defaults)
/// before the SPIR-V is written, as wgpu does when it creates a pipeline.
fn parse_and_validate_with(name: &str, source: &str, constants: &[(&str, f64)]) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    // Every entry point also compiles to SPIR-V, as the Vulkan backend does at pipeline creation: naga's
    // front end accepts some code its SPIR-V writer cannot handle (a pointer to a struct member passed to a
    // function), which would otherwise show only on a GPU, as an invalid pipeline.
    for entry in &module.entry_points {
        let pipeline = naga::back::spv::PipelineOptions {
            shader_stage: entry.stage,
            entry_point: entry.name.clone(),
        };
        let mut values = naga::back::PipelineConstants::default();
        for &(key, value) in constants {
            values.insert(key.to_owned(), value);
        }
        let (processed, processed_info) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            Some((entry.stage, &entry.name)),
            &values,
        )
        .unwrap_or_else(|e| panic!("{name}: {}: overrides: {e}", entry.name));
        let written = std::panic::catch_unwind(|| {
            naga::back::spv::write_vec(
                &processed,
                &processed_info,
                &naga::back::spv::Options::default(),
                Some(&pipeline),
            )
        });
        match written {
            Ok(Ok(words)) => assert!(!words.is_empty(), "{name}: {}: no SPIR-V", entry.name),
            Ok(Err(e)) => panic!("{name}: {}: SPIR-V: {e}", entry.name),
            Err(_) => panic!("{name}: {}: the SPIR-V writer panicked", entry.name),
        }
    }
    module
}

#[test]
fn every_wgsl_module_validates() {
    let modules = shaders::all_modules();
    assert!(modules.len() >= 2);
    for (name, source) in modules {
        parse_and_validate(name, &source);
    }
    // Each field pass specialised to a structure (gpu::field_pass::Structure's constants), every kind present.
    for (k, (entry, _)) in shaders::FIELD_PASSES.iter().enumerate() {
        parse_and_validate_with(
            &format!("{entry} specialised"),
            &shaders::field_module_source(k),
            &[
                ("POINT_COUNT", 2.0),
                ("LINE_COUNT", 1.0),
                ("TORUS_COUNT", 1.0),
                ("CURVE_COUNT", 3.0),
                ("GAUSS_ORDER", 5.0),
                ("JITTER", 0.0),
            ],
        );
    }
    // The object pass as its pipelines are built, the brightest-point search compiled in.
    parse_and_validate_with(
        "objects with the search",
        &shaders::object_module_source(),
        &[("SEARCH", 1.0)],
    );
    // Every .wgsl file in shaders/ and its folders is part of some module, its import lines left out (no file
    // escapes validation).
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let all: String = shaders::all_modules().into_iter().map(|(_, s)| s).collect();
    for sub in [dir.clone(), dir.join("shared"), dir.join("adaptive_curves")] {
        for entry in std::fs::read_dir(sub).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "wgsl") {
                let text = std::fs::read_to_string(&path).unwrap();
                let code: String = (text.split_inclusive('\n'))
                    .filter(|l| !l.starts_with("#import "))
                    .collect();
                assert!(
                    all.contains(&code),
                    "{} is not in any validated module",
                    path.display()
                );
            }
        }
    }
}

/// (field name, byte offset in Rust) of a mirror, checked against the WGSL struct of the same name.
fn check_struct(
    module: &naga::Module,
    wgsl_name: &str,
    rust_size: usize,
    fields: &[(&str, usize)],
) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(wgsl_name))
        .unwrap_or_else(|| panic!("no WGSL struct {wgsl_name}"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{wgsl_name} is not a struct");
    };
    assert_eq!(*span as usize, rust_size, "{wgsl_name}: size");
    assert_eq!(
        layouter[handle].size as usize, rust_size,
        "{wgsl_name}: layout size"
    );
    assert_eq!(members.len(), fields.len(), "{wgsl_name}: member count");
    for (member, &(name, offset)) in members.iter().zip(fields) {
        assert_eq!(
            member.name.as_deref(),
            Some(name),
            "{wgsl_name}: member order"
        );
        assert_eq!(member.offset as usize, offset, "{wgsl_name}.{name}: offset");
    }
}

macro_rules! fields {
    ($t:ty: $($f:ident),* $(,)?) => {
        &[$((stringify!($f), offset_of!($t, $f))),*]
    };
}

#[test]
fn rust_mirrors_match_the_wgsl_layouts() {
    let field = parse_and_validate("simpson", &shaders::field_module_source(0));
    check_struct(
        &field,
        "FieldParams",
        size_of::<FieldParams>(),
        fields!(FieldParams: center, size, right, resolution, up, divisions, eye, nu, alpha, beta, epsilon,
            point_count, line_count, torus_count, curve_count, integrator, term_tolerance, jitter, seed, gauss_order,
            layers, search, decay, stretch, clipped, pad0, pad1, pad2),
    );
    check_struct(
        &field,
        "Chunk",
        size_of::<Chunk>(),
        fields!(Chunk: first, count, accumulate, pipeline, row_offset, term, stage, listed),
    );
    let refine = parse_and_validate("refine", &shaders::compose("refine.wgsl"));
    check_struct(
        &refine,
        "Level",
        size_of::<Level>(),
        fields!(Level: resolution, layers, level, coarsest, tolerance, slot, measured_top, pad1),
    );
    check_struct(
        &field,
        "PointSource",
        size_of::<PointSource>(),
        fields!(PointSource: position, coefficient),
    );
    check_struct(
        &field,
        "LineSource",
        size_of::<LineSource>(),
        fields!(LineSource: point, coefficient, direction, pad0),
    );
    check_struct(
        &field,
        "TorusSource",
        size_of::<TorusSource>(),
        fields!(TorusSource: center, major_radius, axis, coefficient),
    );
    check_struct(
        &field,
        "CurveSource",
        size_of::<CurveSource>(),
        fields!(CurveSource: first_segment, segment_count, first_weight, weight_count, coefficient, first_color, color_count,
            first_piece, piece_count, pad0, pad1, pad2),
    );
    check_struct(
        &field,
        "CurvePiece",
        size_of::<CurvePiece>(),
        fields!(CurvePiece: c2, s2, c1, s1, c0, s0, center, radius, t0, t1, weight_max, zero_end),
    );
    check_struct(
        &field,
        "CurveSegment",
        size_of::<CurveSegment>(),
        fields!(CurveSegment: c2, pad0, c1, pad1, c0, pad2),
    );
    let through = parse_and_validate("through", shaders::THROUGH_PASS);
    check_struct(
        &through,
        "ThroughParams",
        size_of::<energywave::gpu::through_pass::gpu_data::ThroughParams>(),
        fields!(energywave::gpu::through_pass::gpu_data::ThroughParams: resolution, layers, pad1, pad2),
    );
    let tau = parse_and_validate("tau_table", shaders::TAU_TABLE_PASS);
    check_struct(
        &tau,
        "TauParams",
        size_of::<energywave::gpu::tau_table::gpu_data::TauParams>(),
        fields!(energywave::gpu::tau_table::gpu_data::TauParams: origin, side, dims, n, k0, rows, base, pad0),
    );
    let grid = parse_and_validate("grid", shaders::GRID_PASS);
    check_struct(
        &grid,
        "GridParams",
        size_of::<energywave::gpu::grid_pass::gpu_data::GridParams>(),
        fields!(energywave::gpu::grid_pass::gpu_data::GridParams: view_proj),
    );
    let objects = parse_and_validate("objects", &shaders::object_module_source());
    check_struct(
        &objects,
        "ObjectParams",
        size_of::<energywave::gpu::object_pass::gpu_data::ObjectParams>(),
        fields!(energywave::gpu::object_pass::gpu_data::ObjectParams: view_proj, energy, ambient, eye, pad0),
    );
    let particles = parse_and_validate("particles", &shaders::compose("particles.wgsl"));
    {
        use energywave::gpu::particle_pass::gpu_data::{SmokeChunk, SmokeParams, SmokeParticle};
        check_struct(
            &particles,
            "SmokeParams",
            size_of::<SmokeParams>(),
            fields!(SmokeParams: eye, tan_half, forward, aspect, right, near, up, width, size, tiles_x, chunk,
                frame, objects, pad0, depth_near, depth_far, pad1, pad2, bb_center, bb_size, bb_right, glass_w, bb_up,
                glass_offset, bb_normal, pad4),
        );
        check_struct(
            &particles,
            "SmokeParticle",
            size_of::<SmokeParticle>(),
            fields!(SmokeParticle: position, radius, color, density, diag_r, off_r, diag_g, off_g, diag_b, off_b),
        );
        check_struct(
            &particles,
            "SmokeChunk",
            size_of::<SmokeChunk>(),
            fields!(SmokeChunk: index, last, pad0, pad1),
        );
    }
    let billboard = parse_and_validate("billboard", shaders::BILLBOARD_PASS);
    check_struct(
        &billboard,
        "BillboardParams",
        size_of::<BillboardParams>(),
        fields!(BillboardParams: view_proj, center, size, right, resolution, up, mode, energy, near, far, nu, cutoff, edge),
    );
    let average = parse_and_validate("average", shaders::AVERAGE_PASS);
    check_struct(
        &average,
        "AverageParams",
        size_of::<AverageParams>(),
        fields!(AverageParams: weight, pad0, pad1, pad2),
    );
}
