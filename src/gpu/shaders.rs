//! The WGSL sources, embedded in the binary. WGSL has no include: each field pass's module is assembled here
//! from shared parts (the constants generated from the f64 twin, `field_common.wgsl` with the source structs
//! and distance functions, `field_pass.wgsl` with the bindings, then the pass's own file), so each part lives in
//! one place and each pass's module carries only its own code.

/// Shared structs and functions of the field.
pub const FIELD_COMMON: &str = include_str!("../../shaders/field_common.wgsl");
/// What every field pass shares: parameters, bindings, the structure's constants, the texel's ray.
pub const FIELD_PASS: &str = include_str!("../../shaders/field_pass.wgsl");
/// The papers' integrator, Simpson's rule (entry point `integrate`).
pub const SIMPSON_PASS: &str = include_str!("../../shaders/simpson.wgsl");
/// The adaptive integrator's parts shared by its two passes.
pub const ADAPTIVE_COMMON: &str = include_str!("../../shaders/adaptive.wgsl");
/// The adaptive integrator's pass for points, lines and tori (entry point `integrate_adaptive`).
pub const ADAPTIVE_SMOOTH_PASS: &str = include_str!("../../shaders/adaptive_smooth.wgsl");
/// The adaptive integrator's pass for curve chains (entry point `integrate_adaptive_curves`).
pub const ADAPTIVE_CURVES_PASS: &str = include_str!("../../shaders/adaptive_curves.wgsl");

/// The field passes: each entry point with the files of its module after the shared parts, in the order
/// `gpu::field_pass` indexes its pipelines.
pub const FIELD_PASSES: [(&str, &[&str]); 3] = [
    ("integrate", &[SIMPSON_PASS]),
    (
        "integrate_adaptive",
        &[ADAPTIVE_COMMON, ADAPTIVE_SMOOTH_PASS],
    ),
    (
        "integrate_adaptive_curves",
        &[ADAPTIVE_COMMON, ADAPTIVE_CURVES_PASS],
    ),
];

/// The complete source of field pass `k`'s module (`FIELD_PASSES`): the constants it shares with its f64
/// twin, generated from the twin's definitions (`shared_constants`), the common parts and the pass.
pub fn field_module_source(k: usize) -> String {
    let mut source = format!("{}\n{FIELD_COMMON}\n{FIELD_PASS}", shared_constants());
    for part in FIELD_PASSES[k].1 {
        source.push('\n');
        source.push_str(part);
    }
    source
}

/// The billboard pass.
pub const BILLBOARD_PASS: &str = include_str!("../../shaders/billboard.wgsl");
/// The glare pass (`gpu::glare_pass`).
pub const GLARE_PASS: &str = include_str!("../../shaders/glare.wgsl");

/// The smooth upsampling of the viewer's low-resolution preview field.
pub const UPSAMPLE_PASS: &str = include_str!("../../shaders/upsample.wgsl");

/// The running mean of jittered frames.
pub const AVERAGE_PASS: &str = include_str!("../../shaders/average.wgsl");

/// The viewer's ground grid.
pub const GRID_PASS: &str = include_str!("../../shaders/grid.wgsl");
/// The scene's objects, lit at every pixel (`object_module_source` is its module).
pub const OBJECT_PASS: &str = include_str!("../../shaders/objects.wgsl");

/// The object pass's module: the field's shared parts, as a field pass has them (its fragment shader evaluates
/// every source's term at the pixel's surface point with the field's own functions), then `objects.wgsl`.
pub fn object_module_source() -> String {
    format!(
        "{}\n{FIELD_COMMON}\n{FIELD_PASS}\n{OBJECT_PASS}",
        shared_constants()
    )
}
/// The viewer's copy of its offscreen viewport into egui's frame.
pub const BLIT_PASS: &str = include_str!("../../shaders/blit.wgsl");

/// Newton steps the adaptive curves pass takes from the last node's nearest point (GPU only: the f64 twin solves
/// every node in closed form); `gpu::field_pass` counts them in its iteration budget.
pub const TRACK_NEWTON: u32 = 2;

/// An f32 WGSL literal of `v`: the shortest decimal that reads back as `v as f32`.
fn f32_literal(v: f64) -> String {
    let s = format!("{:?}", v as f32);
    if s.contains(['.', 'e']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// The WGSL declarations of every constant the field pass shares with its f64 twin, written from the twin's
/// own definitions, so that neither side mirrors the other by hand: the adaptive integrator's scan, jump,
/// kink, panel and refinement settings (`integrate::adaptive`), the curves' degeneracy threshold
/// (`crate::field::curve`), the Newton steps the iteration budget counts on (`TRACK_NEWTON`), and the
/// Gauss-Kronrod table with the function that finds a pair in it.
pub fn shared_constants() -> String {
    use crate::field::brightest as b;
    use crate::integrate::adaptive as a;
    use std::fmt::Write;
    let integers: [(&str, u64); 20] = [
        ("SCAN", a::SCAN as u64),
        ("BRIGHT_SCAN", a::BRIGHT_SCAN as u64),
        ("CUT_BISECTIONS", a::CUT_BISECTIONS as u64),
        ("KINK_ROUNDS", a::KINK_ROUNDS as u64),
        ("MAX_KINKS", a::MAX_KINKS as u64),
        ("MAX_GAUSS_PANELS", a::MAX_GAUSS_PANELS as u64),
        ("MAX_DEPTH", a::MAX_DEPTH as u64),
        ("MAX_REFINEMENTS", a::MAX_REFINEMENTS as u64),
        ("COARSE_ORDER", a::COARSE_ORDER as u64),
        ("COARSE_REFINEMENTS", a::COARSE_REFINEMENTS as u64),
        ("MAX_PEAKS", a::MAX_PEAKS as u64),
        ("PEAK_NEWTON", a::PEAK_NEWTON as u64),
        ("SWITCH_ROUNDS", a::SWITCH_ROUNDS as u64),
        ("RING_NEWTON", a::RING_NEWTON as u64),
        ("POLE_SERIES_TERMS_F32", a::POLE_SERIES_TERMS_F32 as u64),
        ("TRACK_NEWTON", TRACK_NEWTON as u64),
        ("ROOT_LEVELS", b::ROOT_LEVELS as u64),
        ("ROOT_VISITS", b::ROOT_VISITS as u64),
        ("ROOT_NEWTON", b::ROOT_NEWTON as u64),
        ("KRONROD_ROWS", a::KRONROD.len() as u64),
    ];
    let reals: [(&str, f64); 17] = [
        ("JUMP", a::JUMP),
        ("PARAM_JUMP", a::PARAM_JUMP),
        ("END_SNAP", a::END_SNAP),
        ("KINK_BRACKET", a::KINK_BRACKET),
        ("FINE_KINK_BRACKET", a::FINE_KINK_BRACKET),
        ("KINK_PROBE", a::KINK_PROBE),
        ("U_PANEL", a::U_PANEL),
        ("PEAK_SETTLED", a::PEAK_SETTLED),
        ("CUT_MERGE", a::CUT_MERGE),
        ("SINGULAR_MERGE", a::SINGULAR_MERGE),
        ("SWITCH_INSET", a::SWITCH_INSET),
        ("MAX_WIDTH", a::MAX_WIDTH),
        ("MIN_AXIS_WIDTH", a::MIN_AXIS_WIDTH),
        ("RING_STEP", a::RING_STEP),
        ("DEGENERATE", crate::field::curve::DEGENERATE),
        ("CLOSED_FORM_CONDITION", a::CLOSED_FORM_CONDITION),
        ("POLE_SERIES_REACH", a::POLE_SERIES_REACH),
    ];
    let mut s = String::from(
        "// Generated by gpu::shaders::shared_constants from the definitions both twins use (src/integrate/adaptive.rs,\n\
         // src/field/curve.rs, src/gpu/shaders.rs): the WGSL files use these and do not declare them.\n",
    );
    for (name, v) in integers {
        writeln!(s, "const {name}: u32 = {v}u;").expect("a String takes writes");
    }
    for (name, v) in reals {
        writeln!(s, "const {name}: f32 = {};", f32_literal(v)).expect("a String takes writes");
    }
    // The table (twin of integrate::adaptive::KRONROD): each pair's n + 1 rows, (node x >= 0, Kronrod weight, Gauss
    // weight), the first at x = 0.
    writeln!(
        s,
        "const KRONROD: array<vec3<f32>, KRONROD_ROWS> = array<vec3<f32>, KRONROD_ROWS>("
    )
    .expect("a String takes writes");
    for (x, k, g) in a::KRONROD {
        let row = [x, k, g].map(f32_literal).join(", ");
        writeln!(s, "    vec3<f32>({row}),").expect("a String takes writes");
    }
    s.push_str(");\n");
    s.push_str(
        "// The first row of the Gauss-Kronrod pair of `order` in KRONROD (the last pair for any other order).\n\
         fn kronrod_start(order: u32) -> u32 {\n    switch order {\n",
    );
    let last = a::KRONROD_ORDERS.len() - 1;
    for (k, n) in a::KRONROD_ORDERS.iter().enumerate().take(last) {
        let start = a::KRONROD_START[k];
        writeln!(s, "        case {n}u: {{ return {start}u; }}").expect("a String takes writes");
    }
    writeln!(
        s,
        "        default: {{ return {}u; }}\n    }}\n}}",
        a::KRONROD_START[last]
    )
    .expect("a String takes writes");
    s
}

/// Every shader module the program builds, by name: what the validation tests check.
pub fn all_modules() -> Vec<(&'static str, String)> {
    vec![
        (
            "simpson.wgsl (with field_common.wgsl and field_pass.wgsl)",
            field_module_source(0),
        ),
        (
            "adaptive_smooth.wgsl (with field_common.wgsl, field_pass.wgsl and adaptive.wgsl)",
            field_module_source(1),
        ),
        (
            "adaptive_curves.wgsl (with field_common.wgsl, field_pass.wgsl and adaptive.wgsl)",
            field_module_source(2),
        ),
        ("billboard.wgsl", BILLBOARD_PASS.to_string()),
        ("glare.wgsl", GLARE_PASS.to_string()),
        ("average.wgsl", AVERAGE_PASS.to_string()),
        ("upsample.wgsl", UPSAMPLE_PASS.to_string()),
        ("grid.wgsl", GRID_PASS.to_string()),
        (
            "objects.wgsl (with field_common.wgsl and field_pass.wgsl)",
            object_module_source(),
        ),
        ("blit.wgsl", BLIT_PASS.to_string()),
    ]
}
