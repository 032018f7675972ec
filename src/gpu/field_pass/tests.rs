use super::*;
use crate::field::{Curve, Point, Torus};
use crate::integrate::Integrator;
use crate::scene::Scene;
use glam::DVec3;

/// The value the field module declares for `const NAME: TYPE = VALUE;`, as f64.
fn shader_constant(name: &str) -> f64 {
    let source = crate::gpu::shaders::field_module_source(2);
    let start = format!("const {name}: ");
    let line = source
        .lines()
        .find(|l| l.trim_start().starts_with(&start))
        .unwrap_or_else(|| panic!("the field module declares {name}"));
    let value = line
        .split('=')
        .nth(1)
        .expect("a value")
        .trim()
        .trim_end_matches(';');
    value
        .trim_end_matches('u')
        .parse()
        .unwrap_or_else(|e| panic!("{name} = {value}: {e}"))
}

#[test]
fn the_constants_shared_with_the_twin_are_generated_from_it_and_declared_once() {
    // Mirrored by hand they drifted apart once (8 panels on the CPU against 4 on the GPU, unnoticed): now the
    // module's declarations are written from the twin's definitions, and no WGSL file declares them again.
    use crate::gpu::shaders;
    use crate::integrate::adaptive as a;
    let shared: &[(&str, f64)] = &[
        ("SCAN", a::SCAN as f64),
        ("SUB_SCAN", a::SUB_SCAN as f64),
        ("EXACT_SAMPLES", a::EXACT_SAMPLES as f64),
        ("MINIMA", a::MINIMA as f64),
        ("RIVAL_MARGIN", a::RIVAL_MARGIN),
        ("EXACT_SLACK", a::EXACT_SLACK),
        ("JUMP", a::JUMP),
        ("PARAM_JUMP", a::PARAM_JUMP),
        ("SUSPECT_MISS", a::SUSPECT_MISS),
        ("END_SNAP", a::END_SNAP),
        ("KINK_ROUNDS", a::KINK_ROUNDS as f64),
        ("KINK_BRACKET", a::KINK_BRACKET),
        ("FINE_KINK_BRACKET", a::FINE_KINK_BRACKET),
        ("KINK_PROBE", a::KINK_PROBE),
        ("MAX_KINKS", a::MAX_KINKS as f64),
        ("U_PANEL", a::U_PANEL),
        ("MAX_GAUSS_PANELS", a::MAX_GAUSS_PANELS as f64),
        ("MAX_DEPTH", a::MAX_DEPTH as f64),
        ("MAX_REFINEMENTS", a::MAX_REFINEMENTS as f64),
        ("COARSE_ORDER", a::COARSE_ORDER as f64),
        ("COARSE_REFINEMENTS", a::COARSE_REFINEMENTS as f64),
        ("MAX_PEAKS", a::MAX_PEAKS as f64),
        ("PEAK_NEWTON", a::PEAK_NEWTON as f64),
        ("PEAK_SETTLED", a::PEAK_SETTLED),
        ("CUT_MERGE", a::CUT_MERGE),
        ("SINGULAR_MERGE", a::SINGULAR_MERGE),
        ("SWITCH_ROUNDS", a::SWITCH_ROUNDS as f64),
        ("SWITCH_INSET", a::SWITCH_INSET),
        ("MAX_WIDTH", a::MAX_WIDTH),
        ("MIN_AXIS_WIDTH", a::MIN_AXIS_WIDTH),
        ("RING_NEWTON", a::RING_NEWTON as f64),
        ("RING_STEP", a::RING_STEP),
        ("DEGENERATE", crate::field::curve::DEGENERATE),
        ("CLOSED_FORM_CONDITION", a::CLOSED_FORM_CONDITION),
        ("TRACK_NEWTON", TRACK_NEWTON as f64),
        ("KRONROD_ROWS", a::KRONROD.len() as f64),
    ];
    let module = shaders::field_module_source(2);
    for &(name, want) in shared {
        let got = shader_constant(name);
        assert!(
            (got - want).abs() <= 1e-7 * want.abs(),
            "{name}: the shader declares {got}, the f64 twin {want}"
        );
        let declaration = format!("const {name}: ");
        assert_eq!(
            module.matches(&declaration).count(),
            1,
            "{name} declared once"
        );
        for (file, text) in shaders::FILES {
            assert!(
                !text.contains(&declaration),
                "{file} declares {name} by hand"
            );
        }
    }
    // The Gauss-Kronrod table, row by row, and where each pair starts.
    let rows: Vec<&str> = module
        .lines()
        .skip_while(|l| !l.starts_with("const KRONROD: "))
        .skip(1)
        .take_while(|l| l.trim_start().starts_with("vec3<f32>("))
        .collect();
    assert_eq!(rows.len(), a::KRONROD.len());
    for (row, (x, k, g)) in rows.iter().zip(a::KRONROD) {
        let values: Vec<f32> = row
            .trim()
            .trim_start_matches("vec3<f32>(")
            .trim_end_matches("),")
            .split(", ")
            .map(|v| v.parse().expect("a number"))
            .collect();
        assert_eq!(values, [x as f32, k as f32, g as f32], "{row}");
    }
    for (k, n) in a::KRONROD_ORDERS
        .iter()
        .enumerate()
        .take(a::KRONROD_ORDERS.len() - 1)
    {
        let case = format!("case {n}u: {{ return {}u; }}", a::KRONROD_START[k]);
        assert!(module.contains(&case), "kronrod_start: {case}");
    }
}

/// A scene of `points` points, one torus and curves of the given segment counts.
fn scene(points: usize, curves: &[usize], integrator: Integrator) -> Packed {
    let mut s = Scene::default_scene();
    s.sources.points = (0..points)
        .map(|i| Point {
            position: DVec3::new(i as f64, 0.0, 0.0),
            coefficient: 1.0,
            look: Default::default(),
        })
        .collect();
    s.sources.lines.clear();
    s.sources.tori = vec![Torus {
        center: DVec3::ZERO,
        axis: DVec3::Z,
        major_radius: 1.0,
        coefficient: 1.0,
        look: Default::default(),
    }];
    s.sources.curves = curves
        .iter()
        .map(|&k| Curve {
            control_points: (0..=2 * k)
                .map(|i| DVec3::new(i as f64, 1.0, 0.0))
                .collect(),
            coefficient: 1.0,
            weights: vec![1.0],
            look: Default::default(),
            color_series: Vec::new(),
            w_form: crate::field::WForm::Nearest,
        })
        .collect();
    s.integration.integrator = integrator;
    pack(&crate::frame::FrameSetup::placed(&s, 1.0))
}

/// Every term exactly once, in order; the first dispatch writes and the others add.
fn check_cover(p: &Packed, terms: u32) {
    let mut next = 0;
    for (k, c) in p.chunks.iter().enumerate() {
        assert_eq!(c.first, next, "chunk {k} starts where the last ended");
        assert!(c.count > 0 || terms == 0);
        assert_eq!(c.accumulate, (k > 0) as u32);
        next += c.count;
    }
    assert_eq!(next, terms);
}

#[test]
fn adaptive_dispatches_run_points_lines_and_tori_apart_from_curves_within_the_budget() {
    let p = scene(2, &[1, 2, 40], Integrator::Adaptive);
    check_cover(&p, 6);
    for c in &p.chunks {
        let last = c.first + c.count;
        // Points and the torus (terms 0..3) on the smooth terms' pipeline, curves on their own.
        let want = if last <= 3 {
            ADAPTIVE_SMOOTH
        } else {
            assert!(c.first >= 3, "a dispatch mixes the two families: {c:?}");
            ADAPTIVE_CURVES
        };
        assert_eq!(c.pipeline, want, "{c:?}");
        // A dispatch of several curves stays within the budget.
        if c.pipeline == ADAPTIVE_CURVES && c.count > 1 {
            let cost: u64 = (c.first..last)
                .map(|t| p.curves[(t - 3) as usize].segment_count)
                .map(|k| adaptive_curve_iterations(p.params.gauss_order, curve_iterations(k, 0)))
                .sum();
            assert!(cost <= ITERATION_BUDGET, "{c:?} costs {cost}");
        }
    }
    // The 40-segment chain costs more than the budget alone: it has a dispatch of its own.
    assert!(p.chunks.iter().any(|c| c.first == 5 && c.count == 1));
    assert!(p.chunks.len() >= 3);
}

#[test]
fn simpson_dispatches_are_ranges_of_samples_on_its_pipeline() {
    let p = scene(1, &[2], Integrator::Simpson);
    check_cover(&p, p.params.divisions + 1);
    assert!(p.chunks.iter().all(|c| c.pipeline == SIMPSON));
}

#[test]
fn a_scene_without_sources_still_writes_the_texture() {
    let mut p = scene(0, &[], Integrator::Adaptive);
    p.params.torus_count = 0;
    p.tori.clear();
    let chunks = plan_chunks(&p);
    assert_eq!(chunks.len(), 1);
    assert_eq!((chunks[0].count, chunks[0].accumulate), (0, 0));
}

#[test]
fn the_search_flag_says_whether_no_some_or_every_curve_reads_its_brightest_point() {
    // 2 lets a pass drop the nearest point's code: it must be set only where every curve has pieces.
    let mut s = Scene::default_scene();
    let continuous = s.sources.curves[0].clone();
    assert!(continuous.searches());
    let search = |s: &Scene| {
        pack(&crate::frame::FrameSetup::placed(s, 1.0))
            .params
            .search
    };
    assert_eq!(search(&s), 2);
    let mut uniform = continuous.clone();
    uniform.weights = vec![0.7; 5];
    s.sources.curves = vec![continuous.clone(), uniform.clone()];
    assert_eq!(search(&s), 1);
    s.sources.curves = vec![uniform];
    assert_eq!(search(&s), 0);
    s.sources.curves.clear();
    assert_eq!(search(&s), 0);
}
