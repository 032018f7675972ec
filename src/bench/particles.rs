//! Particle sets beside paper 002_'s tables: two particles, the 500-particle cloud lit, and 50,000 lit, each
//! in a frame of the default beam at W = 256 (a 512 x 512 frame, its smoke image 256 x 256). What particles
//! cost lies in three places, each timed: lighting them (CPU, once per edit of the particles or the sources:
//! `particles::light`), planning a view's slices and each tile's particles (CPU, once per camera move:
//! `particles::view`), and the frame itself: the smoke splatted and laid over it, timed on a view whose field
//! and plan are made (a renderer with the particles and one without, interleaved frame by frame, the
//! difference theirs). A frame whose view moved pays the plan and the splatting (`added_ms`) besides the field,
//! whose own time dwarfs and blurs them on this machine. The paper's "unlit" is ours without the lighting step.

use std::time::Instant;

use serde::Serialize;

use super::Timing;
use crate::frame::FrameSetup;
use crate::gpu::{GpuError, HeadlessRenderer};
use crate::objects::lighting::Lights;
use crate::particles::light::light_particles;
use crate::scene::Scene;

/// One case: its particles, and where the time goes.
#[derive(Clone, Debug, Serialize)]
pub struct ParticleRow {
    pub case: String,
    pub particles: usize,
    /// Lighting every particle through the others (CPU, per edit).
    pub light: Timing,
    /// The view's slices, tile lists and glow depths (CPU, per camera move).
    pub plan: Timing,
    /// The entries (a particle in a tile) the plan holds.
    pub entries: usize,
    /// A frame of a view already planned (its field integrated before) with the particles, and the same frame
    /// without them: the difference is the splatting and the compositing.
    pub frame: Timing,
    pub bare: Timing,
    /// The paper's figures (GeForce FX 5600, 2003): its method unlit and lit, ms.
    pub paper_unlit_ms: Option<f64>,
    pub paper_lit_ms: Option<f64>,
}

impl ParticleRow {
    /// What the particles add to a frame whose view moved (its plan and its splatting; the lighting of an edit
    /// not included: it is paid once per edit of the particles or the sources, never per frame).
    pub fn added_ms(&self) -> f64 {
        self.plan.median_ms + self.frame.median_ms - self.bare.median_ms
    }
}

/// The default beam with a particle set of `count` particles in a cloud around it.
fn case(count: u32, radius: &str) -> Scene {
    let text = format!(
        "{}\n[[particles]]\nemitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 2.5\ncount = {count}\n\
         particle_radius = {radius}\ndensity = [1.0, 2.0]\ncolor = [0.6, 0.6, 0.65]\nseed = 1\nnoise = 0.5\n",
        crate::scene::DEFAULT_SCENE_TOML
    );
    Scene::parse(&text, std::path::Path::new("bench particles")).expect("a valid scene")
}

/// The cases, timed; `frames` frames each after `warmup`.
pub fn particle_rows(warmup: usize, frames: usize) -> Result<Vec<ParticleRow>, GpuError> {
    // A renderer each, so that neither reuses the other's field (each orbiting frame integrates it anew).
    let (mut gpu, mut gpu_bare) = (HeadlessRenderer::new()?, HeadlessRenderer::new()?);
    let cases = [
        ("two particles", case(2, "0.8"), Some(43.1), None),
        (
            "500 particles",
            case(500, "[0.2, 0.4]"),
            Some(58.1),
            Some(286.0),
        ),
        ("50,000 particles", case(50_000, "[0.04, 0.08]"), None, None),
    ];
    let (w, h) = (512, 512);
    let mut rows = Vec::new();
    for (name, mut scene, paper_unlit_ms, paper_lit_ms) in cases {
        scene.billboard.resolution = 256;
        scene.billboard.fixed_resolution = true;
        let particles = crate::particles::gather(&scene.particles, &scene.sources);
        let lights = Lights::new(
            &scene.sources,
            scene.colors.palette(),
            scene.integration.epsilon,
        );
        let light = Timing::of(
            (0..frames.max(3))
                .map(|_| {
                    let t = Instant::now();
                    std::hint::black_box(light_particles(&lights, &particles));
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        );
        let setup = FrameSetup::placed(&scene, w as f64 / h as f64);
        let mut entries = 0;
        let plan = Timing::of(
            (0..frames.max(3))
                .map(|_| {
                    let t = Instant::now();
                    let view = setup.smoke_view(&particles, [w, h], 256);
                    entries = view.tile_lists(&particles).0.len();
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        );
        let bare = Scene {
            particles: Vec::new(),
            ..scene.clone()
        };
        // The same view every frame: each renderer keeps its field and the plan, and the smoke is splatted and
        // laid over the frame anew (what a frame pays besides the plan).
        let (mut with, mut without) = (Vec::new(), Vec::new());
        for k in 0..warmup + frames {
            let t = Instant::now();
            // Splatted anew as a moved view's frame is (a frame of the same view lays the last image again).
            gpu.splat_again();
            gpu.render(&scene, w, h, false)?;
            let a = t.elapsed().as_secs_f64() * 1e3;
            let t = Instant::now();
            gpu_bare.render(&bare, w, h, false)?;
            let b = t.elapsed().as_secs_f64() * 1e3;
            if k >= warmup {
                with.push(a);
                without.push(b);
            }
        }
        rows.push(ParticleRow {
            case: name.to_owned(),
            particles: particles.len(),
            light,
            plan,
            entries,
            frame: Timing::of(with),
            bare: Timing::of(without),
            paper_unlit_ms,
            paper_lit_ms,
        });
    }
    Ok(rows)
}
