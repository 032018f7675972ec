//! What a run measured, and its tables and JSON.

use super::*;

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
    /// A plainly written kernel specialised to the scene (`bench::plain`), its values constants of its text
    /// (`Baked::All`), interleaved with both.
    pub plain: PassTiming,
    /// The same kernel with its values read from a buffer (`Baked::Structure`): what an editor can use.
    pub plain_values: PassTiming,
    /// The plain kernels' largest difference on B from the specialised pass's, over B's largest value.
    pub plain_difference: f64,
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
    /// The camera orbits a little every frame, as the viewer draws it: the moving field, refined to 1/255
    /// (`viewer::progressive`).
    pub orbiting: Timing,
    /// The side of the moving field the viewer chose while orbiting (the full field's side if none).
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
    /// The last orbiting frame's viewport against the settled one's: the largest difference of a color channel
    /// (in 1/255), and the share of pixels with one off by more than 16/255.
    pub moving_largest_difference: u8,
    pub moving_share_over_16: f64,
    /// A point source added (a new structure: a compile starts on its thread), then frames until the picture
    /// is whole again: the longest of them, and how many.
    pub add_source_longest_frame_ms: f64,
    pub add_source_frames: u32,
    /// The scene's animation playing, where it has one.
    pub playing: Option<PlayingRow>,
}

/// An animation playing in the viewer, each frame showing the next frame of it (the viewer keeping up with its
/// rate).
#[derive(Clone, Debug, Serialize)]
pub struct PlayingRow {
    /// The animation's frames a second.
    pub frame_rate: f64,
    /// A frame as the viewer draws it while playing (the field of each animation frame new).
    pub frame: Timing,
    /// The side of the field it shows (the full field's side where that fits).
    pub side: u32,
    /// A frame with the whole field integrated (progressive refinement off): what showing it at full quality costs.
    pub full_field: Timing,
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
    /// Particle sets beside paper 002_'s tables.
    pub particles: Vec<super::ParticleRow>,
    /// Live particle sets: playback, scrubbing and rendering.
    pub live: Vec<super::LiveRow>,
    /// Translucent objects: the table per resolution, and frames.
    pub translucent: Option<(Vec<super::TranslucentRow>, super::TranslucentFrames)>,
    /// The field refined in image space against every texel integrated.
    pub refine: Vec<super::RefineRow>,
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

impl Report {
    /// The papers' grid beside their figures.
    pub(super) fn grid_table(&self, s: &mut String) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "\n{:<7} {:>5} {:>4} {:>11} {:>15} {:>8} {:>9} {:>11} {:>10} {:>11} {:>9} {:>9} {:>10} {:>8} {:>10}",
            "scene",
            "W",
            "n",
            "generic ms",
            "specialised ms",
            "speedup",
            "plain ms",
            "spec/plain",
            "buffered ms",
            "spec/buff",
            "plain off",
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
                "{:<7} {:>5} {:>4} {:>11.2} {:>15.2} {:>8.2} {:>9.2} {:>11.2} {:>10.2} {:>11.2} {:>9.1e} {:>9.2} {:>10} {:>8} {:>10.2}",
                r.scene,
                r.resolution,
                r.divisions,
                g.median_ms,
                t.median_ms,
                g.median_ms / t.median_ms,
                r.plain.best().median_ms,
                t.median_ms / r.plain.best().median_ms,
                r.plain_values.best().median_ms,
                t.median_ms / r.plain_values.best().median_ms,
                r.plain_difference,
                t.fps(),
                paper,
                ratio,
                r.field_bytes as f64 / (1024.0 * 1024.0)
            );
        }
        let _ = writeln!(
            s,
            "(FPS and the ratio to the papers' 2016 GPU are the specialised pass's; spec/plain: its time over a plainly \
             written kernel specialised to the scene (bench::plain, its values constants), spec/buff: over that \
             kernel with its values read from a buffer, plain off: their largest difference on B over B's largest; \
             medians, min..max in the JSON)"
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
                "\nviewer frame {}x{} ({} scene, UI + viewport, wall): idle {:.1} ms ({:.1} FPS); orbiting {:.1} ms ({:.1} FPS, {:.2}x idle, field {}^2 while moving); dragging a control point {:.1} ms ({:.1} FPS, {:.2}x idle, field {}^2); orbiting with the whole field every frame {:.1} ms ({:.1} FPS, {:.2}x idle); full picture {:.0} ms after the last move ({} frames, longest {:.1} ms; the last moving frame off it by up to {}/255, {:.2} % of pixels by more than 16/255); a source added: longest frame {:.1} ms of {}",
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
                v.moving_largest_difference,
                100.0 * v.moving_share_over_16,
                v.add_source_longest_frame_ms,
                v.add_source_frames,
            );
            if let Some(p) = &v.playing {
                let _ = writeln!(
                    s,
                    "animation playing at {:.0} frames a second ({:.1} ms a frame): {:.1} ms a viewer frame, field {}^2 shown; the whole field every frame {:.1} ms ({:.2}x the animation's frame time)",
                    p.frame_rate,
                    1e3 / p.frame_rate,
                    p.frame.median_ms,
                    p.side,
                    p.full_field.median_ms,
                    p.full_field.median_ms * p.frame_rate / 1e3,
                );
            }
        }
        if !self.particles.is_empty() {
            let _ = writeln!(
                s,
                "\nparticle sets around the default beam, W = 256, 512 x 512 (wall ms, median (min..max)): light per edit, plan per view, frame of a planned view with and without them; added = plan + frame - bare, per moved view; the paper's on its 2003 GPU"
            );
            let _ = writeln!(
                s,
                "{:<17} {:>9} {:>9} {:>10} {:>9} {:>15} {:>15} {:>9} {:>13} {:>11}",
                "case",
                "particles",
                "light ms",
                "entries",
                "plan ms",
                "frame ms",
                "bare frame ms",
                "added ms",
                "paper unlit",
                "paper lit"
            );
            let paper = |x: Option<f64>| x.map_or("-".to_owned(), |v| format!("{v:.1}"));
            for r in &self.particles {
                let _ = writeln!(
                    s,
                    "{:<17} {:>9} {:>9.1} {:>10} {:>9.1} {:>15} {:>15} {:>9.1} {:>13} {:>11}",
                    r.case,
                    r.particles,
                    r.light.median_ms,
                    r.entries,
                    r.plan.median_ms,
                    format!(
                        "{:.1} ({:.0}..{:.0})",
                        r.frame.median_ms, r.frame.min_ms, r.frame.max_ms
                    ),
                    format!(
                        "{:.1} ({:.0}..{:.0})",
                        r.bare.median_ms, r.bare.min_ms, r.bare.max_ms
                    ),
                    r.added_ms(),
                    paper(r.paper_unlit_ms),
                    paper(r.paper_lit_ms),
                );
            }
        }
        if !self.live.is_empty() {
            let _ = writeln!(
                s,
                "\nlive particle sets, W = 256, 512 x 512 (wall ms, median (min..max)): a frame of playback on the CPU (simulation stepped one frame, particles drawn up), a frame back while scrubbing, the last frame from scratch, the frame rendered (light, plan, field, smoke) and without its particles"
            );
            let _ = writeln!(
                s,
                "{:<18} {:>8} {:>16} {:>16} {:>11} {:>18} {:>16} {:>10}",
                "case",
                "alive",
                "step ms",
                "scrub back ms",
                "scratch ms",
                "frame ms",
                "bare ms",
                "budget ms"
            );
            let t = |x: &super::Timing| {
                format!("{:.1} ({:.0}..{:.0})", x.median_ms, x.min_ms, x.max_ms)
            };
            for r in &self.live {
                let _ = writeln!(
                    s,
                    "{:<18} {:>8} {:>16} {:>16} {:>11.0} {:>18} {:>16} {:>10.1}",
                    r.case,
                    r.alive,
                    t(&r.step),
                    t(&r.scrub_back),
                    r.scratch_ms,
                    t(&r.frame),
                    t(&r.bare),
                    1e3 / r.frame_rate,
                );
            }
        }
        if let Some((rows, frames)) = &self.translucent {
            let _ = writeln!(
                s,
                "\ntranslucent objects: the voxel number map's table (surface voxels N, N (N + 1) / 2 f32), its precomputation (voxels, table, spread) and a relight (irradiance and the sum over the table), wall ms; refused past {} MiB",
                crate::objects::translucent::MAX_TABLE_BYTES >> 20
            );
            let _ = writeln!(
                s,
                "{:<30} {:>6} {:>10} {:>10} {:>14} {:>11} {:>13} {:>13}",
                "object",
                "voxels",
                "surface",
                "table MB",
                "precompute ms",
                "relight ms",
                "table CPU ms",
                "table GPU ms"
            );
            let ms = |x: Option<f64>| x.map_or("refused".to_owned(), |x| format!("{x:.0}"));
            for r in rows {
                let _ = writeln!(
                    s,
                    "{:<30} {:>6} {:>10} {:>10.1} {:>14} {:>11} {:>13} {:>13}",
                    r.case,
                    r.resolution,
                    r.surface_voxels,
                    r.table_mb,
                    ms(r.precompute_ms),
                    ms(r.relight_ms),
                    ms(r.table_cpu_ms),
                    ms(r.table_gpu_ms),
                );
            }
            let t = |x: &super::Timing| {
                format!("{:.1} ({:.0}..{:.0})", x.median_ms, x.min_ms, x.max_ms)
            };
            let _ = writeln!(
                s,
                "frames of translucent_cavity.toml at 1280 x 720 (wall ms, median (min..max)): still {}, orbiting {}, orbiting with the cube opaque {}",
                t(&frames.still),
                t(&frames.orbit),
                t(&frames.opaque_orbit)
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
            let _ = writeln!(
                s,
                "\nat a fixed error: the cheapest simpson n and the loosest adaptive tolerance with max |dB| <= {:.0e} on B",
                super::equal_error::TARGET_ERROR
            );
            let _ = writeln!(
                s,
                "{:<7} {:>4} {:>6} {:>11} {:>20} {:>9} {:>11} {:>20} {:>8}",
                "scene",
                "W",
                "n",
                "simpson ms",
                "simpson error",
                "tol",
                "adaptive ms",
                "adaptive error",
                "speedup"
            );
            for r in &self.equal_error {
                let a = &r.at_target;
                let e = |e: &RenderError, reached: bool| {
                    format!(
                        "{:.1e}{} {:.3}%",
                        e.max_abs,
                        if reached { "" } else { "!" },
                        100.0 * e.share_over_1_255
                    )
                };
                let _ = writeln!(
                    s,
                    "{:<7} {:>4} {:>6} {:>11.2} {:>20} {:>9.0e} {:>11.2} {:>20} {:>7.2}x",
                    r.scene,
                    r.resolution,
                    a.simpson_divisions,
                    a.simpson.best().median_ms,
                    e(&a.simpson_error, a.simpson_reached),
                    a.adaptive_tolerance,
                    a.adaptive.best().median_ms,
                    e(&a.adaptive_error, a.adaptive_reached),
                    a.speedup,
                );
            }
            let _ = writeln!(s, "(! : the target not reached; the finest tried shown)");
        }
        if !self.refine.is_empty() {
            self.refine_table(&mut s);
        }
        let _ = writeln!(s, "\ntotal: {:.0} s", self.total_seconds);
        s
    }

    /// The refined field beside every texel integrated, and each W's time against W = 256's.
    fn refine_table(&self, s: &mut String) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "\nthe whole field refined in image space (the scene's tolerance) against every texel integrated, both on the specialised pass; ms, median (min..max), GPU time where available, then wall"
        );
        let _ = writeln!(
            s,
            "{:<8} {:>5} {:>24} {:>24} {:>8} {:>10} {:>12} {:>12} {:>14}",
            "scene",
            "W",
            "every texel ms",
            "refined ms",
            "speedup",
            "integrated",
            "every / 256",
            "refined / 256",
            "wall every/ref"
        );
        let t =
            |t: &super::Timing| format!("{:.1} ({:.1}..{:.1})", t.median_ms, t.min_ms, t.max_ms);
        for r in &self.refine {
            let base = (self.refine.iter()).find(|b| b.scene == r.scene && b.resolution == 256);
            let ratio = |f: &dyn Fn(&super::RefineRow) -> f64| {
                base.map_or("-".to_owned(), |b| format!("{:.2}x", f(r) / f(b)))
            };
            let (e, f) = (r.every_texel.best(), r.refined.best());
            let _ = writeln!(
                s,
                "{:<8} {:>5} {:>24} {:>24} {:>7.2}x {:>9.1}% {:>12} {:>12} {:>7.0}/{:<6.0}",
                r.scene,
                r.resolution,
                t(e),
                t(f),
                e.median_ms / f.median_ms,
                100.0 * r.share,
                ratio(&|r| r.every_texel.best().median_ms),
                ratio(&|r| r.refined.best().median_ms),
                r.every_texel.wall.median_ms,
                r.refined.wall.median_ms,
            );
        }
    }

    /// The report as JSON: every figure with its unit in its name, the adapter and the settings.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }
}
