//! The WGSL sources, embedded in the binary, and their composition into modules. A file names the files it uses
//! by `#import path` lines (paths under `shaders/`); `compose` makes a module of an entry file: every file it
//! imports, directly or not, once each, depth first in the order named, then the file itself without its import
//! lines. Which files make up a module is written in the files themselves. The parts several passes share live in
//! `shaders/shared/`, each the f32 twin of one Rust module and named after it (`shared/curve.wgsl` of
//! `crate::field::curve`); the constants both twins use are generated from the Rust side (`shared_constants`) and
//! imported as `shared/constants.wgsl`. A new pass is a file in `shaders/` that imports what it uses, listed in
//! `FILES`.

use std::collections::BTreeSet;

/// The billboard pass.
pub const BILLBOARD_PASS: &str = include_str!("../../shaders/billboard.wgsl");
/// The glare pass (`gpu::glare_pass`).
pub const GLARE_PASS: &str = include_str!("../../shaders/glare.wgsl");
/// The glow seen through translucent objects (`gpu::through_pass`).
pub const THROUGH_PASS: &str = include_str!("../../shaders/through.wgsl");
/// The optical-thickness table of a translucent object (`gpu::tau_table`).
pub const TAU_TABLE_PASS: &str = include_str!("../../shaders/tau_table.wgsl");
/// The smooth upsampling of the viewer's low-resolution preview field.
/// The running mean of jittered frames.
pub const AVERAGE_PASS: &str = include_str!("../../shaders/average.wgsl");
/// The viewer's ground grid.
pub const GRID_PASS: &str = include_str!("../../shaders/grid.wgsl");
/// The viewer's copy of its offscreen viewport into egui's frame.
pub const BLIT_PASS: &str = include_str!("../../shaders/blit.wgsl");

/// The generated file of the constants both twins use (`shared_constants`), imported like any other.
pub const CONSTANTS: &str = "shared/constants.wgsl";

/// Every WGSL file but the generated one, by its path under `shaders/`.
pub const FILES: [(&str, &str); 26] = [
    (
        "shared/field.wgsl",
        include_str!("../../shaders/shared/field.wgsl"),
    ),
    (
        "shared/cubic.wgsl",
        include_str!("../../shaders/shared/cubic.wgsl"),
    ),
    (
        "shared/curve.wgsl",
        include_str!("../../shaders/shared/curve.wgsl"),
    ),
    (
        "shared/field_pass.wgsl",
        include_str!("../../shaders/shared/field_pass.wgsl"),
    ),
    (
        "shared/field_params.wgsl",
        include_str!("../../shaders/shared/field_params.wgsl"),
    ),
    (
        "shared/decay.wgsl",
        include_str!("../../shaders/shared/decay.wgsl"),
    ),
    (
        "shared/wseries.wgsl",
        include_str!("../../shaders/shared/wseries.wgsl"),
    ),
    (
        "shared/brightest.wgsl",
        include_str!("../../shaders/shared/brightest.wgsl"),
    ),
    (
        "shared/adaptive.wgsl",
        include_str!("../../shaders/shared/adaptive.wgsl"),
    ),
    (
        "adaptive_curves/kinks.wgsl",
        include_str!("../../shaders/adaptive_curves/kinks.wgsl"),
    ),
    (
        "adaptive_curves/scan.wgsl",
        include_str!("../../shaders/adaptive_curves/scan.wgsl"),
    ),
    ("simpson.wgsl", include_str!("../../shaders/simpson.wgsl")),
    (
        "engine/globals.wgsl",
        include_str!("../../shaders/engine/globals.wgsl"),
    ),
    (
        "engine/effect.wgsl",
        include_str!("../../shaders/engine/effect.wgsl"),
    ),
    (
        "adaptive_smooth.wgsl",
        include_str!("../../shaders/adaptive_smooth.wgsl"),
    ),
    (
        "adaptive_curves.wgsl",
        include_str!("../../shaders/adaptive_curves.wgsl"),
    ),
    ("objects.wgsl", include_str!("../../shaders/objects.wgsl")),
    ("refine.wgsl", include_str!("../../shaders/refine.wgsl")),
    (
        "particles.wgsl",
        include_str!("../../shaders/particles.wgsl"),
    ),
    ("billboard.wgsl", BILLBOARD_PASS),
    ("glare.wgsl", GLARE_PASS),
    ("through.wgsl", THROUGH_PASS),
    ("tau_table.wgsl", TAU_TABLE_PASS),
    ("average.wgsl", AVERAGE_PASS),
    ("grid.wgsl", GRID_PASS),
    ("blit.wgsl", BLIT_PASS),
];

/// The text of the embedded file at `path` (under `shaders/`), the generated constants included.
pub fn file(path: &str) -> Option<String> {
    if path == CONSTANTS {
        return Some(shared_constants());
    }
    FILES
        .iter()
        .find(|(p, _)| *p == path)
        .map(|(_, text)| text.to_string())
}

/// The path an import line names, if `line` is one (`#import path`).
fn import_of(line: &str) -> Option<&str> {
    line.strip_prefix("#import ").map(str::trim)
}

/// The module of `entry`, its imports read by `lookup`: each file once, those it imports before it (depth first,
/// in the order named), the import lines left out, the parts joined by a line break. An import of a file
/// `lookup` does not know, or a circle of imports, is an error naming the files.
pub fn compose_with(
    entry: &str,
    lookup: &dyn Fn(&str) -> Option<String>,
) -> Result<String, String> {
    fn visit(
        path: &str,
        lookup: &dyn Fn(&str) -> Option<String>,
        open: &mut Vec<String>,
        done: &mut BTreeSet<String>,
        parts: &mut Vec<String>,
    ) -> Result<(), String> {
        if done.contains(path) {
            return Ok(());
        }
        if let Some(at) = open.iter().position(|p| p == path) {
            let mut circle = open[at..].to_vec();
            circle.push(path.to_owned());
            return Err(format!("a circle of imports: {}", circle.join(" -> ")));
        }
        let text = lookup(path).ok_or_else(|| match open.last() {
            Some(by) => format!("{by} imports {path}, which does not exist"),
            None => format!("no shader file {path}"),
        })?;
        open.push(path.to_owned());
        for import in text.lines().filter_map(import_of) {
            visit(import, lookup, open, done, parts)?;
        }
        open.pop();
        done.insert(path.to_owned());
        parts.push(
            text.split_inclusive('\n')
                .filter(|line| import_of(line).is_none())
                .collect(),
        );
        Ok(())
    }
    let mut parts = Vec::new();
    visit(
        entry,
        lookup,
        &mut Vec::new(),
        &mut BTreeSet::new(),
        &mut parts,
    )?;
    Ok(parts.join("\n"))
}

/// The module of the embedded entry file `entry` (`compose_with` over `file`). The files are part of the
/// program, and every module is composed by the tests (`all_modules`): a failure here is a bug in them.
pub fn compose(entry: &str) -> String {
    compose_with(entry, &file).unwrap_or_else(|e| panic!("shaders/{entry}: {e}"))
}

/// The field passes: each entry point and its file, in the order `gpu::field_pass` indexes its pipelines.
pub const FIELD_PASSES: [(&str, &str); 3] = [
    ("integrate", "simpson.wgsl"),
    ("integrate_adaptive", "adaptive_smooth.wgsl"),
    ("integrate_adaptive_curves", "adaptive_curves.wgsl"),
];

/// The complete source of field pass `k`'s module (`FIELD_PASSES`).
pub fn field_module_source(k: usize) -> String {
    compose(FIELD_PASSES[k].1)
}

/// The object pass's module (`objects.wgsl`, which imports the field's parts: its fragment shader evaluates every
/// source's term at the pixel's surface point with the field's own functions).
pub fn object_module_source() -> String {
    compose("objects.wgsl")
}

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
    let integers: [(&str, u64); 23] = [
        ("SCAN", a::SCAN as u64),
        ("EXACT_SAMPLES", a::EXACT_SAMPLES as u64),
        ("SUB_SCAN", a::SUB_SCAN as u64),
        ("MINIMA", a::MINIMA as u64),
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
    let reals: [(&str, f64); 20] = [
        ("JUMP", a::JUMP),
        ("RIVAL_MARGIN", a::RIVAL_MARGIN),
        ("EXACT_SLACK", a::EXACT_SLACK),
        ("PARAM_JUMP", a::PARAM_JUMP),
        ("SUSPECT_MISS", a::SUSPECT_MISS),
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

/// Every shader module the program builds, by its entry file (every file no other imports): what the validation
/// tests check.
pub fn all_modules() -> Vec<(&'static str, String)> {
    let imported: BTreeSet<&str> = FILES
        .iter()
        .flat_map(|(_, text)| text.lines().filter_map(import_of))
        .collect();
    // The effect shader for game engines is composed for each scene's structure, and validated there (the
    // engine module, which comes after this one).
    FILES
        .iter()
        .filter(|(path, _)| !imported.contains(path) && !path.starts_with("engine/"))
        .map(|(path, _)| (*path, compose(path)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_under_shaders_is_embedded_and_every_module_composes() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let mut on_disk = Vec::new();
        let mut folders = vec![String::new()];
        while let Some(sub) = folders.pop() {
            for entry in std::fs::read_dir(dir.join(&sub)).unwrap() {
                let entry = entry.unwrap();
                let name = entry.file_name().into_string().unwrap();
                let path = if sub.is_empty() {
                    name
                } else {
                    format!("{sub}/{name}")
                };
                if entry.file_type().unwrap().is_dir() {
                    folders.push(path);
                } else if path.ends_with(".wgsl") {
                    on_disk.push(path);
                }
            }
        }
        on_disk.sort();
        let mut listed: Vec<String> = FILES.iter().map(|(p, _)| p.to_string()).collect();
        listed.sort();
        assert_eq!(on_disk, listed, "FILES lists every file under shaders/");
        for (path, text) in FILES {
            for import in text.lines().filter_map(import_of) {
                // The effect's structure is written for each scene (the engine module's STRUCTURE).
                assert!(
                    file(import).is_some() || import == "engine/structure.wgsl",
                    "{path} imports {import}, which does not exist"
                );
            }
        }
        let entries: Vec<&str> = all_modules().iter().map(|(p, _)| *p).collect();
        assert_eq!(
            entries,
            [
                "simpson.wgsl",
                "adaptive_smooth.wgsl",
                "adaptive_curves.wgsl",
                "objects.wgsl",
                "refine.wgsl",
                "particles.wgsl",
                "billboard.wgsl",
                "glare.wgsl",
                "through.wgsl",
                "tau_table.wgsl",
                "average.wgsl",
                "grid.wgsl",
                "blit.wgsl"
            ]
        );
    }

    #[test]
    fn imports_come_first_once_each_and_circles_are_refused() {
        let files = |p: &str| -> Option<String> {
            Some(
                match p {
                    "a" => "#import b\n#import c\nA\n",
                    "b" => "#import c\nB\n",
                    "c" => "C\n",
                    "x" => "#import y\nX\n",
                    "y" => "#import x\nY\n",
                    "z" => "#import nowhere\nZ\n",
                    _ => return None,
                }
                .to_owned(),
            )
        };
        assert_eq!(compose_with("a", &files).unwrap(), "C\n\nB\n\nA\n");
        assert_eq!(
            compose_with("x", &files).unwrap_err(),
            "a circle of imports: x -> y -> x"
        );
        assert_eq!(
            compose_with("z", &files).unwrap_err(),
            "z imports nowhere, which does not exist"
        );
        // The field passes' parts come in the order they depend on one another, the constants first.
        let curves = field_module_source(2);
        let at = |needle: &str| curves.find(needle).unwrap_or_else(|| panic!("{needle}"));
        assert!(
            at("const KRONROD: ") < at("struct PointSource")
                && at("struct PointSource") < at("struct Roots")
        );
        assert!(
            at("fn segment_at(") < at("struct FieldParams")
                && at("struct FieldParams") < at("fn wseries_knot(")
        );
        assert!(
            at("fn curve_search(") < at("struct Peak {")
                && at("struct Peak {") < at("struct ChainSample")
        );
        assert!(!curves.contains("#import"));
    }
}
