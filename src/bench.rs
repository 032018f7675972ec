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

use crate::gpu::{FieldRenderer, GpuContext, GpuError, Specialise, map_read};
use crate::integrate::{self, Integrator};
use crate::scene::Scene;
use crate::viewer::Document;
use crate::viewer::offscreen::OffscreenViewer;

/// The equal-error reference is computed on at most this many texels per side (a subset of larger textures).
const REFERENCE_SIZE: u32 = 256;

/// The torus of paper figure 7 (R = 0.9, t = 5.1).
const TORUS_SCENE: &str = include_str!("../assets/scenes/torus_r0.9_t5.1.toml");
/// The two smoothly connected Bezier curves of paper figure 9 (b = 5.0).
const BEZIER_SCENE: &str = include_str!("../assets/scenes/bezier_b5.0.toml");
/// Every kind of source at once.
const MIXED_SCENE: &str = include_str!("../assets/scenes/mixed.toml");

/// The converged reference of the equal-error comparison: f64 Simpson with this many divisions, refined
/// (`integrate::simpson_refined`) wherever its estimated error exceeds `REFERENCE_TOLERANCE` on B.
pub const REFERENCE_DIVISIONS: u32 = 4096;
/// The reference's estimated error on B, texel by texel.
pub const REFERENCE_TOLERANCE: f64 = 1e-7;
/// How many times the reference splits an interval at most (down to a width of 2^-40).
pub const REFERENCE_MAX_DEPTH: u32 = 28;
/// The adaptive tolerances tried, cheapest first, for the equal-error comparison.
const TOLERANCES: [f64; 11] = [
    5e-2, 2e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6,
];

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
}

/// Which sections run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Sections {
    pub grid: bool,
    pub deformation: bool,
    pub equal_error: bool,
    pub viewer: bool,
}

impl Sections {
    /// Every section.
    pub const ALL: Sections = Sections {
        grid: true,
        deformation: true,
        equal_error: true,
        viewer: true,
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
        }
    }
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            quick: false,
            sections: Sections::ALL,
            equal_error_sizes: None,
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

/// Median and spread of a set of durations, in milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct Timing {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub samples: usize,
}

impl Timing {
    fn of(mut ms: Vec<f64>) -> Self {
        ms.sort_by(f64::total_cmp);
        let n = ms.len();
        let median = if n % 2 == 1 {
            ms[n / 2]
        } else {
            0.5 * (ms[n / 2 - 1] + ms[n / 2])
        };
        Self {
            median_ms: median,
            min_ms: ms[0],
            max_ms: ms[n - 1],
            samples: n,
        }
    }

    pub fn fps(&self) -> f64 {
        1e3 / self.median_ms
    }
}

/// The field pass of one frame, timed both ways.
#[derive(Clone, Debug, Serialize)]
pub struct PassTiming {
    /// GPU time of the compute pass from timestamp queries, when the adapter has them.
    pub gpu: Option<Timing>,
    /// Wall time from upload to the end of the GPU's work (submit and wait).
    pub wall: Timing,
}

impl PassTiming {
    /// The figure to report: GPU time where there is one, else wall time.
    pub fn best(&self) -> &Timing {
        self.gpu.as_ref().unwrap_or(&self.wall)
    }
}

/// One cell of the papers' grid.
#[derive(Clone, Debug, Serialize)]
pub struct GridRow {
    pub scene: String,
    pub resolution: u32,
    pub divisions: u32,
    /// The generic field pass (loops bounded by the counts in its storage buffers).
    pub ours: PassTiming,
    /// The field pass specialised to the scene's structure (`gpu::Specialise`), interleaved with the generic.
    pub specialised: PassTiming,
    pub paper_fps: Option<f64>,
    /// GPU memory held by the field pass (texture, uniform and storage buffers), bytes.
    pub field_bytes: u64,
}

/// A static scene against the same scene deforming every frame, interleaved.
#[derive(Clone, Debug, Serialize)]
pub struct DeformationRow {
    pub scene: String,
    pub resolution: u32,
    pub divisions: u32,
    pub static_scene: PassTiming,
    /// A control point (the torus's center for the torus) moves every frame.
    pub deforming: PassTiming,
}

/// Whole viewer frames (UI, viewport, field when it changes), wall time, no display.
#[derive(Clone, Debug, Serialize)]
pub struct ViewerFrameRow {
    pub width: u32,
    pub height: u32,
    pub scene: String,
    /// Nothing changes: the field is not integrated again.
    pub idle: Timing,
    /// The camera orbits a little every frame, as the viewer draws it: a coarse field while moving
    /// (`viewer::progressive`).
    pub orbiting: Timing,
    /// The side of the coarse field the viewer chose while orbiting (the full field's side if none).
    pub orbiting_resolution: u32,
    /// The same orbit with the whole field integrated every frame (progressive refinement off): the baseline.
    pub orbiting_full_field: Timing,
    /// A control point of the curve dragged a little every frame, as the viewer draws it.
    pub dragging: Timing,
    pub dragging_resolution: u32,
    /// From the last moving frame to the full-quality picture: milliseconds, frames, and the longest of them.
    pub refine_ms: f64,
    pub refine_frames: u32,
    pub refine_longest_frame_ms: f64,
    /// A point source added (a new structure: a compile starts on its thread), then frames until the picture
    /// is whole again: the longest of them, and how many.
    pub add_source_longest_frame_ms: f64,
    pub add_source_frames: u32,
}

/// The error of a brightness texture against the converged reference: the largest on B itself (the tolerance's
/// promise, B > 1 included: exports keep it), and the share of texels whose picture changes, on B clamped to
/// [0, 1] as the blend shows it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RenderError {
    /// Largest |B - B_ref|, unclamped.
    pub max_abs: f64,
    /// Share of texels off by more than 1/255 on B clamped to [0, 1].
    pub share_over_1_255: f64,
}

impl RenderError {
    /// The error of `values` (every `stride`-th texel of a W x W texture, rows and columns) against
    /// `reference` (those texels only).
    pub fn of(values: &[f32], w: u32, stride: u32, reference: &[f64]) -> Self {
        let mut max_abs: f64 = 0.0;
        let mut over = 0usize;
        let texels = (0..w).step_by(stride as usize).flat_map(|j| {
            (0..w)
                .step_by(stride as usize)
                .map(move |i| (j * w + i) as usize)
        });
        for (k, r) in texels.zip(reference) {
            let b = values[k] as f64;
            max_abs = max_abs.max((b - r).abs());
            let shown = b.clamp(0.0, 1.0) - r.clamp(0.0, 1.0);
            over += (shown.abs() > 1.0 / 255.0) as usize;
        }
        Self {
            max_abs,
            share_over_1_255: over as f64 / reference.len().max(1) as f64,
        }
    }

    /// True when no figure of `self` is larger than `other`'s.
    pub fn no_larger_than(&self, other: &RenderError) -> bool {
        self.max_abs <= other.max_abs && self.share_over_1_255 <= other.share_over_1_255
    }
}

/// The papers' integrator at n = 200 against the adaptive one at the cheapest tolerance whose error is no
/// larger, both against the converged reference.
#[derive(Clone, Debug, Serialize)]
pub struct EqualErrorRow {
    pub scene: String,
    pub resolution: u32,
    /// Every how many texels (in each direction) the error is computed.
    pub error_stride: u32,
    pub reference: String,
    pub simpson_divisions: u32,
    /// Which field pass times both integrators: the fastest the project has, specialised to the structure.
    pub pipelines: String,
    pub simpson: PassTiming,
    pub simpson_error: RenderError,
    pub adaptive_tolerance: f64,
    pub adaptive: PassTiming,
    pub adaptive_error: RenderError,
    /// Whether some tried tolerance reached the error of `simpson` (else the finest tried is shown).
    pub equal_error: bool,
    /// Median time of `simpson` over median time of `adaptive` (GPU timestamps where available).
    pub speedup: f64,
    /// Every tolerance tried, with its error.
    pub tried: Vec<(f64, RenderError)>,
}

/// The converged f64 reference of B (`REFERENCE_DIVISIONS`, `REFERENCE_TOLERANCE`) for every `stride`-th
/// texel of `scene`'s billboard (rows, then columns), and how it was reached.
pub fn converged_reference(scene: &Scene, stride: u32) -> (Vec<f64>, ReferenceStats) {
    let s = scene;
    let w = s.billboard.resolution;
    let billboard = s.place_billboard(1.0);
    let reach = s.ray_reach(&billboard);
    let plane = (billboard.center - s.camera.eye).dot(-billboard.normal);
    let texels: Vec<(u32, u32)> = (0..w)
        .step_by(stride as usize)
        .flat_map(|j| (0..w).step_by(stride as usize).map(move |i| (i, j)))
        .collect();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = texels.len().div_ceil(threads).max(1);
    let mut out = vec![(0.0, 0); texels.len()];
    std::thread::scope(|scope| {
        for (ts, os) in texels.chunks(chunk).zip(out.chunks_mut(chunk)) {
            let (s, billboard) = (&s, &billboard);
            scope.spawn(move || {
                for (&(i, j), o) in ts.iter().zip(os) {
                    // In the scene's own terms, not the integrators' normalised s: sigma is the depth past
                    // the billboard in decay lengths, zeta(sigma) = alpha / (sigma + beta)^2, and the ray
                    // ends at sigma = reach.stretch.
                    let p = billboard.texel_center(i, j, w);
                    let i = &s.integration;
                    let per_depth = (p - s.camera.eye) / plane;
                    let span = reach.stretch;
                    let f = |t: f64| {
                        let sigma = t * span;
                        s.sources
                            .psi(p + per_depth * (sigma * i.decay_length), i.epsilon)
                            * integrate::zeta(sigma, i.alpha, i.beta)
                            * span
                    };
                    *o = integrate::simpson_refined(
                        f,
                        REFERENCE_DIVISIONS,
                        REFERENCE_TOLERANCE,
                        REFERENCE_MAX_DEPTH,
                    );
                }
            });
        }
    });
    // Without refinement, a texel spends the n + 1 samples and 2 more a pair of intervals, to check them.
    let unrefined = 2 * REFERENCE_DIVISIONS as u64 + 1;
    let stats = ReferenceStats {
        refined_share: out.iter().filter(|(_, e)| *e > unrefined).count() as f64
            / out.len().max(1) as f64,
        mean_evaluations: out.iter().map(|(_, e)| *e as f64).sum::<f64>() / out.len().max(1) as f64,
        max_evaluations: out.iter().map(|(_, e)| *e).max().unwrap_or(0),
    };
    (out.into_iter().map(|(b, _)| b).collect(), stats)
}

/// How the converged reference of one render was reached.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ReferenceStats {
    /// Share of texels refined beyond the uniform `REFERENCE_DIVISIONS` (and its check).
    pub refined_share: f64,
    /// Evaluations of the integrand a texel, on average and at most.
    pub mean_evaluations: f64,
    pub max_evaluations: u64,
}

impl std::fmt::Display for ReferenceStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "f64 CPU, Simpson n = {REFERENCE_DIVISIONS} refined to an estimated {REFERENCE_TOLERANCE:e} on B ({:.1}% of texels refined; {:.0} evaluations a texel on average, {} at most)",
            100.0 * self.refined_share,
            self.mean_evaluations,
            self.max_evaluations,
        )
    }
}

/// Everything one run measured.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub adapter: String,
    pub timestamp_queries: bool,
    pub machine: String,
    pub options: BenchOptions,
    /// Warm-up before each timed set: at least this many frames and `warmup_seconds`.
    pub warmup_frames: usize,
    pub warmup_seconds: f64,
    pub grid: Vec<GridRow>,
    pub deformation: Vec<DeformationRow>,
    pub viewer: Option<ViewerFrameRow>,
    pub equal_error: Vec<EqualErrorRow>,
    /// What each structure's specialised pipelines took to compile, in milliseconds.
    pub compile: Vec<CompileTime>,
    pub total_seconds: f64,
}

/// The compile of one structure's specialised pipelines.
#[derive(Clone, Debug, Serialize)]
pub struct CompileTime {
    pub structure: String,
    pub ms: f64,
}

/// Times the field pass on one context: timestamp queries if available, else wall time only.
struct FieldBench {
    ctx: GpuContext,
    field: FieldRenderer,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
}

impl FieldBench {
    fn new() -> Result<Self, GpuError> {
        let ctx = GpuContext::new()?;
        let field = FieldRenderer::new(&ctx.device);
        let queries = ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| {
                let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("energywave.bench.timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("energywave.bench.resolve"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("energywave.bench.read"),
                    size: 16,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                });
                (set, resolve, read)
            });
        Ok(Self {
            ctx,
            field,
            queries,
        })
    }

    /// Integrates the field of `scene` once (forced, even if unchanged): (GPU ms, wall ms).
    fn frame(&mut self, scene: &Scene) -> Result<(Option<f64>, f64), GpuError> {
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let start = Instant::now();
        self.field.invalidate();
        let billboard = scene.place_billboard(1.0);
        self.field.prepare(device, queue, scene, &billboard)?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.bench.encoder"),
        });
        let writes = self
            .queries
            .as_ref()
            .map(|(set, _, _)| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            });
        self.field.encode_timed(&mut encoder, writes);
        if let Some((set, resolve, read)) = &self.queries {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
        }
        self.ctx.checked(|| queue.submit([encoder.finish()]))?;
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let wall = start.elapsed().as_secs_f64() * 1e3;
        let gpu = match &self.queries {
            Some((_, _, read)) => {
                let ticks: [u64; 2] = bytemuck::pod_read_unaligned(&map_read(device, read)?[..16]);
                let period = queue.get_timestamp_period() as f64;
                Some(ticks[1].saturating_sub(ticks[0]) as f64 * period * 1e-6)
            }
            None => None,
        };
        Ok((gpu, wall))
    }

    /// The brightness texture of `scene`, integrated on the GPU and read back.
    fn brightness(&mut self, scene: &Scene) -> Result<Vec<f32>, GpuError> {
        self.frame(scene)?;
        let texture = self.field.texture().expect("integrated above");
        let bytes = self.ctx.read_texture(texture, 4)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// Times `scenes` interleaved frame by frame (so that drift of a shared, noisy machine hits them alike):
    /// at least `warmup` untimed rounds and `WARMUP_SECONDS`, then `frames` timed ones. `next(k, i)` gives scene
    /// `k` for round `i`.
    fn interleaved(
        &mut self,
        count: usize,
        warmup: usize,
        frames: usize,
        next: impl FnMut(usize, usize) -> Scene,
    ) -> Result<Vec<PassTiming>, GpuError> {
        self.interleaved_as(count, warmup, frames, |_| Specialise::Blocking, next)
    }

    /// `interleaved`, scene `k` drawn by the pipelines `mode(k)` chooses (compiled in the warm-up).
    fn interleaved_as(
        &mut self,
        count: usize,
        warmup: usize,
        frames: usize,
        mode: impl Fn(usize) -> Specialise,
        mut next: impl FnMut(usize, usize) -> Scene,
    ) -> Result<Vec<PassTiming>, GpuError> {
        let mut gpu = vec![Vec::new(); count];
        let mut wall = vec![Vec::new(); count];
        let start = Instant::now();
        let mut round = 0;
        while round < warmup || warming(start, round) {
            for k in 0..count {
                self.field.set_specialise(mode(k));
                self.frame(&next(k, round))?;
            }
            round += 1;
        }
        for round in round..round + frames {
            for k in 0..count {
                self.field.set_specialise(mode(k));
                let (g, w) = self.frame(&next(k, round))?;
                wall[k].push(w);
                if let Some(g) = g {
                    gpu[k].push(g);
                }
            }
        }
        Ok((0..count)
            .map(|k| PassTiming {
                gpu: (!gpu[k].is_empty()).then(|| Timing::of(gpu[k].clone())),
                wall: Timing::of(wall[k].clone()),
            })
            .collect())
    }
}

/// Least time spent warming up before anything is timed. A real GPU idles at a fraction of its clock and only
/// reaches full speed after a moment of steady work: an H200 timed after two warm-up frames that followed a
/// few seconds of CPU work (the equal-error reference) ran at its idle clock, 345 of 1980 MHz, about 5.7 times
/// slower than in the grid section just before. On lavapipe the warm-up frames alone take longer than this.
pub const WARMUP_SECONDS: f64 = 0.5;
/// Most warm-up rounds, whatever the time: a pass of a few microseconds reaches `WARMUP_SECONDS` in well under this.
const MAX_WARMUP_ROUNDS: usize = 100_000;

/// Whether warm-up that began at `start` and has run `rounds` rounds should go on.
fn warming(start: Instant, rounds: usize) -> bool {
    rounds < MAX_WARMUP_ROUNDS && start.elapsed().as_secs_f64() < WARMUP_SECONDS
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

/// Runs the benchmarks, reporting progress through `progress`.
pub fn run(options: BenchOptions, mut progress: impl FnMut(&str)) -> Result<Report, GpuError> {
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
        // Each cell twice, the generic pass and the specialised one, interleaved.
        let mode = |k: usize| [Specialise::Off, Specialise::Blocking][k % 2];
        let timings = bench.interleaved_as(
            2 * cells.len(),
            options.warmup(),
            options.frames(),
            mode,
            |k, _| cells[k / 2].1.clone(),
        )?;
        let field_bytes = bench.field.gpu_bytes();
        let mut timings = timings.into_iter();
        for (name, s) in &cells {
            let (generic, specialised) =
                (timings.next().expect("two"), timings.next().expect("two"));
            grid.push(GridRow {
                scene: name.to_string(),
                resolution,
                divisions: s.integration.divisions,
                ours: generic,
                specialised,
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
    let compile = (bench.field.compile_times().iter())
        .map(|(structure, ms)| CompileTime {
            structure: format!("{structure:?}"),
            ms: *ms,
        })
        .collect();
    drop(bench);
    let viewer = if options.sections.viewer {
        Some(viewer_frames(&options, &mut progress)?)
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
        compile,
        total_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Whole viewer frames at 1280 x 720 on the default scene: idle (settled), orbiting and dragging a control point
/// as the viewer draws them (a coarse field while moving), orbiting with the whole field every frame, and the
/// time from the last move to the full picture.
fn viewer_frames(
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<ViewerFrameRow, GpuError> {
    progress("viewer: 1280 x 720, default scene");
    let mut viewer = OffscreenViewer::new(Document::new(Scene::default_scene(), None), 1280, 720)?;
    let timed = |viewer: &mut OffscreenViewer| -> Result<f64, GpuError> {
        let t = Instant::now();
        viewer.frame()?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    // Until the picture is whole and nothing asks for another frame.
    let settle = |viewer: &mut OffscreenViewer| -> Result<(f64, u32, f64), GpuError> {
        let (start, mut frames, mut longest) = (Instant::now(), 0, 0.0f64);
        while viewer.app.report().wants_frame() && frames < 1000 {
            longest = longest.max(timed(viewer)?);
            frames += 1;
        }
        Ok((start.elapsed().as_secs_f64() * 1e3, frames, longest))
    };
    let start = Instant::now();
    let mut rounds = 0;
    while rounds < options.warmup() || warming(start, rounds) {
        viewer.frame()?;
        rounds += 1;
    }
    settle(&mut viewer)?;
    let frames = options.frames().max(3);
    let mut idle = Vec::new();
    for _ in 0..frames {
        idle.push(timed(&mut viewer)?);
    }
    // A gesture: several frames in a row, each moving the view, timed once the frame budget has adapted.
    let gesture = |viewer: &mut OffscreenViewer,
                   step: &dyn Fn(&mut Scene)|
     -> Result<(Vec<f64>, u32), GpuError> {
        let (mut ms, mut resolution) = (Vec::new(), 0);
        for k in 0..frames + 4 {
            step(&mut viewer.app.doc.scene);
            let t = timed(viewer)?;
            if k >= 4 {
                ms.push(t);
                resolution = (viewer.app.report().preview)
                    .unwrap_or(viewer.app.doc.scene.billboard.resolution);
            }
        }
        Ok((ms, resolution))
    };
    let orbit = |s: &mut Scene| crate::viewer::navigation::orbit(&mut s.camera, 0.01, 0.0);
    let (orbiting, orbiting_resolution) = gesture(&mut viewer, &orbit)?;
    let (refine_ms, refine_frames, refine_longest_frame_ms) = settle(&mut viewer)?;
    let drag = |s: &mut Scene| {
        if let Some(p) = s
            .sources
            .curves
            .first_mut()
            .and_then(|c| c.control_points.get_mut(1))
        {
            p.y += 0.01;
        }
    };
    let (dragging, dragging_resolution) = gesture(&mut viewer, &drag)?;
    settle(&mut viewer)?;
    viewer
        .app
        .doc
        .scene
        .sources
        .points
        .push(crate::field::Point {
            position: glam::DVec3::new(0.5, 1.0, 0.0),
            coefficient: 1.0,
        });
    let first = timed(&mut viewer)?;
    let (_, added_frames, added_longest) = settle(&mut viewer)?;
    viewer.app.doc.scene.sources.points.pop();
    settle(&mut viewer)?;
    viewer.app.progressive = false;
    let (orbiting_full_field, _) = gesture(&mut viewer, &orbit)?;
    viewer.app.progressive = true;
    Ok(ViewerFrameRow {
        width: 1280,
        height: 720,
        scene: "default".into(),
        idle: Timing::of(idle),
        orbiting: Timing::of(orbiting),
        orbiting_resolution,
        orbiting_full_field: Timing::of(orbiting_full_field),
        dragging: Timing::of(dragging),
        dragging_resolution,
        refine_ms,
        refine_frames,
        refine_longest_frame_ms,
        add_source_longest_frame_ms: first.max(added_longest),
        add_source_frames: added_frames + 1,
    })
}

/// The equal-error comparison: on the torus, Bezier and mixed scenes at 256 and 512 (256 only with --quick),
/// the errors of simpson (n = 200) and of the adaptive integrator at each tolerance against the converged
/// reference, then the two timed interleaved at the cheapest tolerance whose error is no larger.
fn equal_error(
    bench: &mut FieldBench,
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<EqualErrorRow>, GpuError> {
    let scenes = [
        ("torus", load(TORUS_SCENE, "torus_r0.9_t5.1.toml")),
        ("bezier", load(BEZIER_SCENE, "bezier_b5.0.toml")),
        ("mixed", load(MIXED_SCENE, "mixed.toml")),
    ];
    let resolutions: &[u32] = match (&options.equal_error_sizes, options.quick) {
        (Some(sizes), _) => sizes,
        (None, true) => &[256],
        (None, false) => &[256, 512],
    };
    let mut rows = Vec::new();
    for &resolution in resolutions {
        for (name, base) in &scenes {
            // The f64 reference is the slow part: above 256, every (W / 256)-th texel in each direction, so
            // that it costs the same at every size.
            let stride = (resolution / REFERENCE_SIZE).max(1);
            let mut simpson = base.clone();
            simpson.billboard.resolution = resolution;
            simpson.integration.integrator = Integrator::Simpson;
            simpson.integration.jitter = None;
            simpson.integration.divisions = 200;
            progress(&format!(
                "equal error: {name}, {resolution} x {resolution}: f64 reference (n = {REFERENCE_DIVISIONS} and more)"
            ));
            let (reference, reference_stats) = converged_reference(&simpson, stride);
            let simpson_error =
                RenderError::of(&bench.brightness(&simpson)?, resolution, stride, &reference);
            let mut adaptive = simpson.clone();
            adaptive.integration.integrator = Integrator::Adaptive;
            let mut tried = Vec::new();
            let mut chosen = None;
            for &tolerance in &TOLERANCES {
                adaptive.integration.tolerance = tolerance;
                let error = RenderError::of(
                    &bench.brightness(&adaptive)?,
                    resolution,
                    stride,
                    &reference,
                );
                tried.push((tolerance, error));
                if error.no_larger_than(&simpson_error) {
                    chosen = Some(tolerance);
                    break;
                }
            }
            let equal = chosen.is_some();
            let tolerance = chosen.unwrap_or(TOLERANCES[TOLERANCES.len() - 1]);
            adaptive.integration.tolerance = tolerance;
            let adaptive_error = tried.last().expect("a tolerance was tried").1;
            progress(&format!(
                "equal error: {name}, {resolution} x {resolution}: timing simpson n = 200 against adaptive tolerance {tolerance:e}"
            ));
            let t = bench.interleaved(2, options.warmup(), options.frames(), |k, _| {
                if k == 0 {
                    simpson.clone()
                } else {
                    adaptive.clone()
                }
            })?;
            let mut t = t.into_iter();
            let (ts, ta) = (t.next().expect("two"), t.next().expect("two"));
            let speedup = ts.best().median_ms / ta.best().median_ms;
            rows.push(EqualErrorRow {
                scene: name.to_string(),
                resolution,
                error_stride: stride,
                reference: reference_stats.to_string(),
                simpson_divisions: 200,
                pipelines: "specialised to the scene's structure (gpu::Specialise::Blocking)"
                    .into(),
                simpson: ts,
                simpson_error,
                adaptive_tolerance: tolerance,
                adaptive: ta,
                adaptive_error,
                equal_error: equal,
                speedup,
                tried,
            });
        }
    }
    Ok(rows)
}

impl Report {
    /// The papers' grid beside their figures.
    fn grid_table(&self, s: &mut String) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "\n{:<7} {:>5} {:>4} {:>11} {:>15} {:>8} {:>9} {:>10} {:>8} {:>10}",
            "scene",
            "W",
            "n",
            "generic ms",
            "specialised ms",
            "speedup",
            "FPS",
            "paper FPS",
            "ratio",
            "field MiB"
        );
        for r in &self.grid {
            let (g, t) = (r.ours.best(), r.specialised.best());
            let paper = r.paper_fps.map_or("-".to_owned(), |p| format!("{p:.2}"));
            let ratio = r
                .paper_fps
                .map_or("-".to_owned(), |p| format!("{:.3}", t.fps() / p));
            let _ = writeln!(
                s,
                "{:<7} {:>5} {:>4} {:>11.2} {:>15.2} {:>8.2} {:>9.2} {:>10} {:>8} {:>10.2}",
                r.scene,
                r.resolution,
                r.divisions,
                g.median_ms,
                t.median_ms,
                g.median_ms / t.median_ms,
                t.fps(),
                paper,
                ratio,
                r.field_bytes as f64 / (1024.0 * 1024.0)
            );
        }
        let _ = writeln!(
            s,
            "(FPS and the ratio to the papers' 2016 GPU are the specialised pass's; medians, min..max in the JSON)"
        );
        for c in &self.compile {
            let _ = writeln!(s, "compiled {} in {:.0} ms", c.structure, c.ms);
        }
        if self.options.quick {
            let _ = writeln!(
                s,
                "(--quick: 512 x 512 left out; run without --quick for the whole grid)"
            );
        }
    }

    /// The report as a human-readable table.
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let source = if self.timestamp_queries {
            "GPU timestamps"
        } else {
            "wall time (no timestamp queries)"
        };
        let _ = writeln!(s, "adapter: {}", self.adapter);
        let _ = writeln!(s, "machine: {}", self.machine);
        let _ = writeln!(
            s,
            "field pass only, {source}; median of {} frames after at least {} warm-up frames and {} s (min..max)",
            self.options.frames(),
            self.warmup_frames,
            self.warmup_seconds
        );
        if !self.grid.is_empty() {
            self.grid_table(&mut s);
        }
        if !self.deformation.is_empty() {
            let _ = writeln!(
                s,
                "\ndeformation (interleaved with the static scene; GPU ms where available, wall ms):"
            );
        }
        for d in &self.deformation {
            let (a, b) = (d.static_scene.best(), d.deforming.best());
            let _ = writeln!(
                s,
                "{:<7} {}x{} n={}: static {:.2} ms, deforming {:.2} ms (ratio {:.3}); wall {:.2} vs {:.2} ms",
                d.scene,
                d.resolution,
                d.resolution,
                d.divisions,
                a.median_ms,
                b.median_ms,
                b.median_ms / a.median_ms,
                d.static_scene.wall.median_ms,
                d.deforming.wall.median_ms
            );
        }
        if let Some(v) = &self.viewer {
            let _ = writeln!(
                s,
                "\nviewer frame {}x{} ({} scene, UI + viewport, wall): idle {:.1} ms ({:.1} FPS); orbiting {:.1} ms ({:.1} FPS, {:.2}x idle, field {}^2 while moving); dragging a control point {:.1} ms ({:.1} FPS, {:.2}x idle, field {}^2); orbiting with the whole field every frame {:.1} ms ({:.1} FPS, {:.2}x idle); full picture {:.0} ms after the last move ({} frames, longest {:.1} ms); a source added: longest frame {:.1} ms of {}",
                v.width,
                v.height,
                v.scene,
                v.idle.median_ms,
                v.idle.fps(),
                v.orbiting.median_ms,
                v.orbiting.fps(),
                v.orbiting.median_ms / v.idle.median_ms,
                v.orbiting_resolution,
                v.dragging.median_ms,
                v.dragging.fps(),
                v.dragging.median_ms / v.idle.median_ms,
                v.dragging_resolution,
                v.orbiting_full_field.median_ms,
                v.orbiting_full_field.fps(),
                v.orbiting_full_field.median_ms / v.idle.median_ms,
                v.refine_ms,
                v.refine_frames,
                v.refine_longest_frame_ms,
                v.add_source_longest_frame_ms,
                v.add_source_frames,
            );
        }
        if !self.equal_error.is_empty() {
            let _ = writeln!(
                s,
                "\nequal error: simpson n = 200 against adaptive at the cheapest tolerance with no larger error; error vs the converged reference (max |dB| on B, share of texels off by > 1/255 on B clamped to [0, 1])"
            );
            let _ = writeln!(
                s,
                "{:<7} {:>4} {:>11} {:>20} {:>9} {:>11} {:>20} {:>8}",
                "scene",
                "W",
                "simpson ms",
                "simpson error",
                "tol",
                "adaptive ms",
                "adaptive error",
                "speedup"
            );
            for r in &self.equal_error {
                let e = |e: &RenderError| {
                    format!("{:.1e} {:.3}%", e.max_abs, 100.0 * e.share_over_1_255)
                };
                let _ = writeln!(
                    s,
                    "{:<7} {:>4} {:>11.2} {:>20} {:>9.0e} {:>11.2} {:>20} {:>7.2}x{}",
                    r.scene,
                    r.resolution,
                    r.simpson.best().median_ms,
                    e(&r.simpson_error),
                    r.adaptive_tolerance,
                    r.adaptive.best().median_ms,
                    e(&r.adaptive_error),
                    r.speedup,
                    if r.equal_error { "" } else { " (error larger)" }
                );
            }
        }
        let _ = writeln!(s, "\ntotal: {:.0} s", self.total_seconds);
        s
    }

    /// The report as JSON: every figure with its unit in its name, the adapter and the settings.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }
}

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
                add_source_longest_frame_ms: 70.0,
                add_source_frames: 9,
            }),
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
            }],
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
        assert!(table.contains("ratio 1.100"), "{table}");
        assert!(table.contains("test adapter") && table.contains("GPU timestamps"));
        let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        assert_eq!(json["adapter"], "test adapter");
        assert_eq!(json["grid"][0]["ours"]["gpu"]["median_ms"], 20.0);
        assert_eq!(json["grid"][0]["specialised"]["gpu"]["median_ms"], 15.0);
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
        assert_eq!(json["options"]["quick"], true);
        // A run of some sections prints only theirs.
        let only = Report {
            grid: Vec::new(),
            deformation: Vec::new(),
            viewer: None,
            ..report
        };
        let table = only.table();
        assert!(
            table.contains("speedup") && table.contains("6.00x"),
            "{table}"
        );
        for absent in ["paper FPS", "deformation", "viewer frame", "--quick"] {
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
