//! Benchmarks: the papers' speed grid (METHOD.md section 7) reproduced side by side, deformation against a
//! static scene, and whole viewer frames. Shared by `energywave bench` and `cargo bench`.
//!
//! The field pass (the work the papers timed) is timed with GPU timestamp queries where the adapter has them,
//! and always with wall time around submit and wait. Each figure is the median of several frames after
//! warm-up, with the spread (min, max). Figures that are compared with each other are measured in the same
//! process, interleaved frame by frame. Nothing here asserts a duration.

use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use crate::frame::FrameSetup;
use crate::gpu::{FieldInputs, FieldRenderer, GpuContext, GpuError, Specialise, map_read};
use crate::integrate::Integrator;
use crate::scene::Scene;

mod equal_error;
mod live;
mod particles;
mod plain;
mod refine;
mod report;
mod timing;
mod translucent;
mod viewer_frames;

pub use equal_error::*;
pub use live::*;
pub use particles::*;
pub use plain::*;
pub use refine::*;
pub use report::*;
pub use timing::*;
pub use translucent::*;
use viewer_frames::viewer_frames;
pub use viewer_frames::{OpenViewer, TimedViewer, VIEWER_SIZE};

/// The torus of paper figure 7 (R = 0.9, t = 5.1).
const TORUS_SCENE: &str = include_str!("../../assets/scenes/torus_r0.9_t5.1.toml");
/// The two smoothly connected Bezier curves of paper figure 9 (b = 5.0).
const BEZIER_SCENE: &str = include_str!("../../assets/scenes/bezier_b5.0.toml");
/// Every kind of source at once.
const MIXED_SCENE: &str = include_str!("../../assets/scenes/mixed.toml");

const RESOLUTIONS: [u32; 3] = [128, 256, 512];
const DIVISIONS: [u32; 3] = [64, 128, 256];

/// The texts' frames per second (AMD FirePro D500, OpenCL, 2016), by scene, resolution, divisions.
pub fn paper_fps(scene: &str, resolution: u32, divisions: u32) -> Option<f64> {
    let table: [[f64; 3]; 3] = match scene {
        "torus" => [
            [384.61, 168.63, 62.35],
            [116.69, 46.49, 16.85],
            [31.23, 13.49, 5.21],
        ],
        "bezier" => [
            [116.69, 60.17, 28.94],
            [34.64, 17.16, 8.31],
            [9.00, 4.40, 2.15],
        ],
        _ => return None,
    };
    let r = RESOLUTIONS.iter().position(|&x| x == resolution)?;
    let d = DIVISIONS.iter().position(|&x| x == divisions)?;
    Some(table[r][d])
}

/// How much to measure.
#[derive(Clone, Debug, Serialize)]
pub struct BenchOptions {
    /// Fewer frames, and the largest resolution left out: under two minutes on a 2-core software GPU.
    pub quick: bool,
    /// The sections to run.
    pub sections: Sections,
    /// The equal-error comparison's billboard resolutions, instead of 256 and 512 (256 with `quick`).
    pub equal_error_sizes: Option<Vec<u32>>,
    /// The name of the scene the viewer's frames are timed on (the opener loads it).
    pub viewer_scene: String,
}

/// One part of the benchmark, for `bench --only`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Section {
    /// The papers' grid of resolutions and division counts.
    Grid,
    /// The same scene static and deforming.
    Deformation,
    /// The adaptive integrator against simpson at equal error.
    EqualError,
    /// Whole viewer frames.
    Viewer,
    /// Particle sets beside paper 002_'s tables.
    Particles,
    /// The field refined in image space against the field integrated at every texel.
    Refine,
    /// Live particle sets: playing, scrubbing and rendering them.
    Live,
    /// Translucent objects: the table's precomputation, relighting, frames.
    Translucent,
}

/// Which sections run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Sections {
    pub grid: bool,
    pub deformation: bool,
    pub equal_error: bool,
    pub viewer: bool,
    pub particles: bool,
    pub live: bool,
    pub translucent: bool,
    pub refine: bool,
}

impl Sections {
    /// Every section.
    pub const ALL: Sections = Sections {
        grid: true,
        deformation: true,
        equal_error: true,
        viewer: true,
        particles: true,
        live: true,
        translucent: true,
        refine: true,
    };

    /// Only those listed; every section for an empty list.
    pub fn only(list: &[Section]) -> Sections {
        if list.is_empty() {
            return Sections::ALL;
        }
        Sections {
            grid: list.contains(&Section::Grid),
            deformation: list.contains(&Section::Deformation),
            equal_error: list.contains(&Section::EqualError),
            viewer: list.contains(&Section::Viewer),
            particles: list.contains(&Section::Particles),
            live: list.contains(&Section::Live),
            translucent: list.contains(&Section::Translucent),
            refine: list.contains(&Section::Refine),
        }
    }
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            quick: false,
            sections: Sections::ALL,
            equal_error_sizes: None,
            viewer_scene: "default".into(),
        }
    }
}

impl BenchOptions {
    fn warmup(&self) -> usize {
        if self.quick { 1 } else { 2 }
    }
    fn frames(&self) -> usize {
        if self.quick { 3 } else { 7 }
    }
    fn resolutions(&self) -> &'static [u32] {
        if self.quick {
            &RESOLUTIONS[..2]
        } else {
            &RESOLUTIONS
        }
    }
}

fn load(text: &str, name: &str) -> Scene {
    Scene::parse(text, Path::new(name)).expect("the benchmark scenes are valid (held by tests)")
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores, {}", std::env::consts::OS)
}

/// A scene moved a little for round `round`: the deforming variant.
fn deformed(base: &Scene, round: usize) -> Scene {
    let mut s = base.clone();
    let wobble = DVec3::new(
        0.0,
        0.05 * (round as f64 * 0.7).sin(),
        0.05 * (round as f64 * 0.7).cos(),
    );
    if let Some(c) = s.sources.curves.first_mut() {
        c.control_points[1] += wobble;
    } else if let Some(t) = s.sources.tori.first_mut() {
        t.center += wobble;
    }
    s
}

/// Runs the sections `options` asks for, reporting progress through `progress`; `open_viewer` opens the
/// viewer whose frames the viewer section times.
pub fn run(
    options: BenchOptions,
    open_viewer: OpenViewer,
    mut progress: impl FnMut(&str),
) -> Result<Report, GpuError> {
    let start = Instant::now();
    let mut bench = FieldBench::new()?;
    let adapter = bench.ctx.adapter_summary();
    progress(&format!("adapter: {adapter}"));
    let scenes = [
        ("torus", load(TORUS_SCENE, "torus_r0.9_t5.1.toml")),
        ("bezier", load(BEZIER_SCENE, "bezier_b5.0.toml")),
    ];

    let timestamp_queries = bench.queries.is_some();
    // The papers' grid: every cell of a resolution interleaved, frame by frame.
    let mut grid = Vec::new();
    let resolutions = if options.sections.grid {
        options.resolutions()
    } else {
        &[]
    };
    for &resolution in resolutions {
        let cells: Vec<(&str, Scene)> = scenes
            .iter()
            .flat_map(|(name, base)| {
                DIVISIONS.iter().map(move |&n| {
                    let mut s = base.clone();
                    s.integration.integrator = Integrator::Simpson;
                    s.billboard.resolution = resolution;
                    s.integration.divisions = n;
                    (*name, s)
                })
            })
            .collect();
        progress(&format!(
            "grid: {resolution} x {resolution}, {} cells",
            cells.len()
        ));
        // Each cell four times, interleaved: the generic pass, the specialised one, and a plain kernel
        // specialised to the scene with its values constant and with them read from a buffer.
        const PASSES: [Pass; 4] = [
            Pass::Field(Specialise::Off),
            Pass::Field(Specialise::Blocking),
            Pass::Plain(Baked::All),
            Pass::Plain(Baked::Structure),
        ];
        let timings = bench.interleaved_as(
            PASSES.len() * cells.len(),
            options.warmup(),
            options.frames(),
            |k| PASSES[k % PASSES.len()],
            |k, _| cells[k / PASSES.len()].1.clone(),
        )?;
        let field_bytes = bench.field.gpu_bytes();
        let mut timings = timings.into_iter();
        for (name, s) in &cells {
            let mut next = || timings.next().expect("one a pass");
            let (generic, specialised, plain, plain_values) = (next(), next(), next(), next());
            // How far the plain kernels' B lies from our specialised pass's, relative to B's largest value.
            bench.field.set_specialise(Specialise::Blocking);
            let ours = bench.brightness(s)?;
            let largest = ours.iter().fold(0.0f32, |m, b| m.max(b.abs()));
            let mut off = 0.0f32;
            for baked in [Baked::All, Baked::Structure] {
                let theirs = bench.plain.brightness(&bench.ctx, s, baked)?;
                off = (ours.iter().zip(&theirs)).fold(off, |m, (a, b)| m.max((a - b).abs()));
            }
            grid.push(GridRow {
                scene: name.to_string(),
                resolution,
                divisions: s.integration.divisions,
                ours: generic,
                specialised,
                plain,
                plain_values,
                plain_difference: (off / largest.max(f32::MIN_POSITIVE)) as f64,
                paper_fps: paper_fps(name, resolution, s.integration.divisions),
                field_bytes,
            });
        }
    }

    // Deformation costs nothing extra: the same scene static and moving, interleaved.
    let mut deformation = Vec::new();
    let deforming: &[_] = if options.sections.deformation {
        &scenes
    } else {
        &[]
    };
    for (name, base) in deforming {
        let mut base = base.clone();
        base.integration.integrator = Integrator::Simpson;
        base.billboard.resolution = 256;
        base.integration.divisions = 128;
        progress(&format!("deformation: {name}, 256 x 256, n = 128"));
        let t = bench.interleaved(2, options.warmup(), options.frames(), |k, round| {
            if k == 0 {
                base.clone()
            } else {
                deformed(&base, round)
            }
        })?;
        let mut t = t.into_iter();
        deformation.push(DeformationRow {
            scene: name.to_string(),
            resolution: 256,
            divisions: 128,
            static_scene: t.next().expect("two variants"),
            deforming: t.next().expect("two variants"),
        });
    }
    let equal_error = if options.sections.equal_error {
        equal_error(&mut bench, &options, &mut progress)?
    } else {
        Vec::new()
    };
    let refine = if options.sections.refine {
        refine_rows(&mut bench, &options, &mut progress)?
    } else {
        Vec::new()
    };
    let compile = (bench.field.compile_times().iter())
        .map(|(structure, ms)| CompileTime {
            structure: format!("{structure:?}"),
            ms: *ms,
        })
        .collect();
    drop(bench);
    let viewer = if options.sections.viewer {
        Some(viewer_frames(&options, open_viewer, &mut progress)?)
    } else {
        None
    };
    let particles = if options.sections.particles {
        progress("particle sets: two, 500 and 50,000 particles around the default beam");
        particle_rows(options.warmup(), options.frames())?
    } else {
        Vec::new()
    };
    let live = if options.sections.live {
        progress(
            "live particle sets: the sparks preset, 10,000 and 100,000 alive around the default beam",
        );
        live_rows(options.warmup(), options.frames())?
    } else {
        Vec::new()
    };
    let translucent = if options.sections.translucent {
        progress(
            "translucent objects: the table at 32, 64 and 128 voxels a side; frames at 1280 x 720",
        );
        Some(translucent_rows(
            options.warmup(),
            options.frames(),
            options.quick,
        )?)
    } else {
        None
    };

    Ok(Report {
        adapter,
        timestamp_queries,
        machine: machine(),
        warmup_frames: options.warmup(),
        options,
        warmup_seconds: WARMUP_SECONDS,
        grid,
        deformation,
        viewer,
        equal_error,
        particles,
        live,
        translucent,
        refine,
        compile,
        total_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Whole viewer frames at 1280 x 720 on the default scene (or another): idle (settled), orbiting and dragging a control point
/// as the viewer draws them (a coarse field while moving), orbiting with the whole field every frame, and the
/// time from the last move to the full picture.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_table_is_complete_and_read_by_row_and_column() {
        assert_eq!(paper_fps("torus", 128, 64), Some(384.61));
        assert_eq!(paper_fps("torus", 512, 256), Some(5.21));
        assert_eq!(paper_fps("bezier", 256, 128), Some(17.16));
        assert_eq!(paper_fps("bezier", 512, 64), Some(9.00));
        assert_eq!(paper_fps("torus", 1024, 64), None);
        // Both benchmark scenes are the papers' settings.
        let t = load(TORUS_SCENE, "t");
        assert_eq!(
            (
                t.sources.tori[0].major_radius,
                t.sources.tori[0].coefficient
            ),
            (0.9, 5.1)
        );
        let b = load(BEZIER_SCENE, "b");
        assert_eq!(b.sources.curves[0].coefficient, 5.0);
    }

    #[test]
    fn render_errors_take_b_unclamped_and_count_the_picture_clamped() {
        // 4 x 4 texels, stride 2: texels (0,0), (2,0), (0,2), (2,2) are compared.
        let mut values = vec![0.5f32; 16];
        values[0] = 0.51; // 0.01 off
        values[2] = 1.25; // B > 1 against 1.2: off by 0.05, though both clamp to 1 in the picture
        values[10] = 0.5 + 0.5 / 255.0; // under 1/255
        values[1] = 100.0; // not sampled
        let reference = [0.5, 1.2, 0.5, 0.5];
        let e = RenderError::of(&values, 4, 2, &reference);
        assert!((e.max_abs - 0.05).abs() < 1e-6, "{e:?}");
        assert_eq!(e.share_over_1_255, 0.25);
        assert!(e.no_larger_than(&RenderError {
            max_abs: 0.06,
            share_over_1_255: 0.25
        }));
        assert!(!e.no_larger_than(&RenderError {
            max_abs: 0.06,
            share_over_1_255: 0.2
        }));
        assert!(!e.no_larger_than(&RenderError {
            max_abs: 0.02,
            share_over_1_255: 0.25
        }));
    }

    #[test]
    fn timings_take_the_median_and_the_spread() {
        let t = Timing::of(vec![5.0, 1.0, 3.0]);
        assert_eq!(
            (t.median_ms, t.min_ms, t.max_ms, t.samples),
            (3.0, 1.0, 5.0, 3)
        );
        let t = Timing::of(vec![4.0, 1.0, 3.0, 2.0]);
        assert_eq!(t.median_ms, 2.5);
        assert_eq!(t.fps(), 400.0);
    }

    fn pass(ms: f64) -> PassTiming {
        PassTiming {
            gpu: Some(Timing::of(vec![ms, ms * 0.9, ms * 1.1])),
            wall: Timing::of(vec![ms * 1.2]),
        }
    }

    #[test]
    fn the_report_puts_our_figures_beside_the_papers() {
        let report = Report {
            adapter: "test adapter".into(),
            timestamp_queries: true,
            machine: "test machine".into(),
            options: BenchOptions {
                quick: true,
                ..Default::default()
            },
            warmup_frames: 1,
            warmup_seconds: WARMUP_SECONDS,
            grid: vec![GridRow {
                scene: "torus".into(),
                resolution: 256,
                divisions: 128,
                ours: pass(20.0),
                specialised: pass(15.0),
                plain: pass(12.0),
                plain_values: pass(14.0),
                plain_difference: 3e-6,
                paper_fps: paper_fps("torus", 256, 128),
                field_bytes: 262_144 + 1024,
            }],
            deformation: vec![DeformationRow {
                scene: "bezier".into(),
                resolution: 256,
                divisions: 128,
                static_scene: pass(10.0),
                deforming: pass(11.0),
            }],
            viewer: Some(ViewerFrameRow {
                width: 1280,
                height: 720,
                scene: "default".into(),
                idle: Timing::of(vec![16.0]),
                orbiting: Timing::of(vec![40.0]),
                orbiting_resolution: 48,
                orbiting_full_field: Timing::of(vec![200.0]),
                dragging: Timing::of(vec![41.0]),
                dragging_resolution: 48,
                refine_ms: 450.0,
                refine_frames: 8,
                refine_longest_frame_ms: 60.0,
                moving_largest_difference: 40,
                moving_share_over_16: 0.01,
                add_source_longest_frame_ms: 70.0,
                add_source_frames: 9,
                playing: Some(PlayingRow {
                    frame_rate: 25.0,
                    frame: Timing::of(vec![44.0]),
                    side: 32,
                    full_field: Timing::of(vec![400.0]),
                }),
            }),
            particles: vec![ParticleRow {
                case: "500 particles".into(),
                particles: 500,
                light: Timing::of(vec![3.0]),
                plan: Timing::of(vec![2.0]),
                entries: 4000,
                frame: Timing::of(vec![60.0]),
                bare: Timing::of(vec![50.0]),
                paper_unlit_ms: Some(58.1),
                paper_lit_ms: Some(286.0),
            }],
            live: vec![LiveRow {
                case: "10,000 alive".into(),
                alive: 10_000,
                step: Timing::of(vec![40.0]),
                scrub_back: Timing::of(vec![120.0]),
                scratch_ms: 3000.0,
                frame: Timing::of(vec![900.0]),
                bare: Timing::of(vec![70.0]),
                frame_rate: 30.0,
            }],
            translucent: Some((
                vec![TranslucentRow {
                    case: "cube with a cavity".into(),
                    resolution: 64,
                    surface_voxels: 24_576,
                    table_mb: 1208.0,
                    precompute_ms: None,
                    relight_ms: None,
                    table_cpu_ms: None,
                    table_gpu_ms: None,
                }],
                TranslucentFrames {
                    still: Timing::of(vec![90.0]),
                    orbit: Timing::of(vec![700.0]),
                    opaque_orbit: Timing::of(vec![400.0]),
                },
            )),
            equal_error: vec![EqualErrorRow {
                scene: "mixed".into(),
                resolution: 256,
                error_stride: 1,
                reference: "f64 CPU, Simpson n = 4096".into(),
                simpson_divisions: 200,
                pipelines: "specialised".into(),
                simpson: pass(30.0),
                simpson_error: RenderError {
                    max_abs: 0.02,
                    share_over_1_255: 0.001,
                },
                adaptive_tolerance: 1e-4,
                adaptive: pass(5.0),
                adaptive_error: RenderError {
                    max_abs: 0.003,
                    share_over_1_255: 0.0,
                },
                equal_error: true,
                speedup: 6.0,
                tried: vec![],
                at_target: AtTargetRow {
                    target_max_abs: 1e-4,
                    simpson_divisions: 1600,
                    simpson_reached: true,
                    simpson: pass(240.0),
                    simpson_error: RenderError {
                        max_abs: 9e-5,
                        share_over_1_255: 0.0,
                    },
                    adaptive_tolerance: 1e-5,
                    adaptive_reached: false,
                    adaptive: pass(12.0),
                    adaptive_error: RenderError {
                        max_abs: 2e-4,
                        share_over_1_255: 0.0,
                    },
                    speedup: 20.0,
                    tried_divisions: vec![],
                },
            }],
            refine: vec![
                RefineRow {
                    scene: "default".into(),
                    resolution: 256,
                    every_texel: pass(1000.0),
                    refined: pass(250.0),
                    integrated: 16384,
                    share: 0.25,
                },
                RefineRow {
                    scene: "default".into(),
                    resolution: 1024,
                    every_texel: pass(16000.0),
                    refined: pass(1000.0),
                    integrated: 104858,
                    share: 0.1,
                },
            ],
            compile: vec![CompileTime {
                structure: "torus".into(),
                ms: 280.0,
            }],
            total_seconds: 3.0,
        };
        let table = report.table();
        // Generic 20 ms, specialised 15 ms (1.33x): 66.67 FPS against the papers' 46.49, ratio 1.434; GPU time is
        // preferred to wall time.
        assert!(
            table.contains("20.00")
                && table.contains("15.00")
                && table.contains("1.33")
                && table.contains("66.67")
                && table.contains("46.49")
                && table.contains("1.434"),
            "{table}"
        );
        assert!(table.contains("compiled torus in 280 ms"), "{table}");
        // At a fixed error: simpson n = 1600 reached it, the adaptive pass did not (marked).
        assert!(
            table.contains("1600") && table.contains("2.0e-4!") && table.contains("20.00x"),
            "{table}"
        );
        assert!(table.contains("ratio 1.100"), "{table}");
        assert!(table.contains("test adapter") && table.contains("GPU timestamps"));
        let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        assert_eq!(json["adapter"], "test adapter");
        assert_eq!(json["grid"][0]["ours"]["gpu"]["median_ms"], 20.0);
        assert_eq!(json["grid"][0]["specialised"]["gpu"]["median_ms"], 15.0);
        assert_eq!(json["grid"][0]["plain"]["gpu"]["median_ms"], 12.0);
        // Ours at 15 ms against the plain kernel's 12: 1.25 times its time.
        assert!(table.contains("12.00") && table.contains("1.25"), "{table}");
        assert_eq!(json["compile"][0]["ms"], 280.0);
        assert!(
            table.contains("6.00x") && table.contains("2.0e-2 0.100%"),
            "{table}"
        );
        assert_eq!(json["equal_error"][0]["speedup"], 6.0);
        assert_eq!(json["equal_error"][0]["adaptive_error"]["max_abs"], 0.003);
        assert_eq!(json["grid"][0]["paper_fps"], 46.49);
        assert_eq!(json["grid"][0]["field_bytes"], 263_168);
        assert_eq!(
            json["deformation"][0]["deforming"]["wall"]["median_ms"],
            13.2
        );
        assert_eq!(json["viewer"]["orbiting"]["median_ms"], 40.0);
        // Playing at 25 frames a second (40 ms a frame): the whole field takes 10 times that.
        assert!(
            table.contains("animation playing at 25 frames a second (40.0 ms a frame): 44.0 ms")
                && table.contains("field 32^2 shown")
                && table.contains("400.0 ms (10.00x"),
            "{table}"
        );
        assert_eq!(json["viewer"]["playing"]["side"], 32);
        assert!(
            table.contains("500 particles") && table.contains("286.0"),
            "{table}"
        );
        assert_eq!(json["particles"][0]["frame"]["median_ms"], 60.0);
        assert_eq!(json["live"][0]["scrub_back"]["median_ms"], 120.0);
        assert!(
            table.contains("live particle sets") && table.contains("10,000 alive"),
            "{table}"
        );
        assert_eq!(json["translucent"][0][0]["surface_voxels"], 24_576);
        assert_eq!(json["translucent"][1]["orbit"]["median_ms"], 700.0);
        // The refined field: its speedup, its share, each W against 256.
        assert_eq!(json["refine"][1]["share"], 0.1);
        assert!(
            table.contains("refined in image space")
                && table.contains("4.00x")
                && table.contains("16.00x"),
            "{table}"
        );
        assert!(
            table.contains("translucent objects") && table.contains("refused"),
            "{table}"
        );
        assert_eq!(json["options"]["quick"], true);
        // A run of some sections prints only theirs.
        let only = Report {
            grid: Vec::new(),
            deformation: Vec::new(),
            viewer: None,
            particles: Vec::new(),
            live: Vec::new(),
            translucent: None,
            refine: Vec::new(),
            ..report
        };
        let table = only.table();
        assert!(
            table.contains("speedup") && table.contains("6.00x"),
            "{table}"
        );
        for absent in [
            "paper FPS",
            "deformation",
            "viewer frame",
            "--quick",
            "particle sets",
            "alive",
            "refined in image space",
        ] {
            assert!(!table.contains(absent), "{absent}: {table}");
        }
    }

    #[test]
    fn the_deforming_variant_moves_a_source_every_frame() {
        let b = load(BEZIER_SCENE, "b");
        assert_ne!(
            deformed(&b, 1).sources.curves[0].control_points[1],
            deformed(&b, 2).sources.curves[0].control_points[1]
        );
        let t = load(TORUS_SCENE, "t");
        assert_ne!(
            deformed(&t, 1).sources.tori[0].center,
            deformed(&t, 2).sources.tori[0].center
        );
    }
}
