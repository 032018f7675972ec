//! Live particle sets: what playing, scrubbing and rendering them costs. Two steady sets around the default beam
//! (10,000 and 100,000 particles alive: a rate times a two-second life, thrown, pulled down, dragged and swirled
//! by a turbulence) and the shipped `pulse_sparks.toml`, each at W = 256 in a 512 x 512 frame. Timed: a frame of
//! playback on the CPU (the simulation stepped one frame from the last and its particles drawn up:
//! `Scene::at_frame`), a frame back while scrubbing (from the kept state at or before it), the same frame from
//! scratch (no kept state), and the frame rendered (lighting, plan, field, smoke) beside the same frame without
//! its particles, interleaved frame by frame.

use std::time::Instant;

use serde::Serialize;

use super::Timing;
use crate::gpu::{GpuError, HeadlessRenderer};
use crate::scene::Scene;

/// One case.
#[derive(Clone, Debug, Serialize)]
pub struct LiveRow {
    pub case: String,
    /// Particles alive at the frames timed (their median).
    pub alive: usize,
    /// A frame of playback on the CPU: the simulation stepped one frame and the particles drawn up.
    pub step: Timing,
    /// A frame back while scrubbing backwards one frame at a time.
    pub scrub_back: Timing,
    /// The last frame timed, from frame 0 with nothing kept.
    pub scratch_ms: f64,
    /// The frame scene rendered (its particles lit, planned and splatted, and the field), and the same frame
    /// without its particles.
    pub frame: Timing,
    pub bare: Timing,
    /// The scene's frame rate: a frame of playback in real time has `1000 / frame_rate` ms.
    pub frame_rate: f64,
}

/// The default beam with a live box of particles around it: `rate` a second, living two seconds.
fn steady(rate: f64) -> Scene {
    let text = format!(
        "{}\n[[particles]]\nemitter = \"box\"\ncenter = [0.0, -1.0, 0.0]\nsize = [5.0, 0.5, 2.0]\n\
         particle_radius = [0.04, 0.08]\ndensity = [2.0, 4.0]\ncolor = [0.7, 0.7, 0.75]\nseed = 1\n\n\
         [particles.life]\nrate = {rate}\nlifetime = 2.0\nspeed = [0.5, 1.0]\ndirection = [0.0, 1.0, 0.0]\n\
         cone = 40.0\nacceleration = [0.0, -0.5, 0.0]\ndrag = 0.5\n\n[particles.life.turbulence]\nscale = 0.8\n\
         strength = 0.5\nspeed = 1.0\n\n[animation]\nframe_rate = 30.0\nframes = 200\n",
        crate::scene::DEFAULT_SCENE_TOML
    );
    Scene::parse(&text, std::path::Path::new("bench live")).expect("a valid scene")
}

/// The scene with a key no particle reads: another simulation, which keeps nothing of the first one's states.
fn unkept(scene: &Scene, round: usize) -> Scene {
    let mut s = scene.clone();
    if let Some(a) = &mut s.animation {
        a.tracks.push(crate::animation::Track {
            parameter: crate::animation::Parameter::Cutoff,
            keys: vec![crate::animation::Key {
                frame: round as f64,
                value: crate::animation::Value::Number(scene.colors.cutoff),
            }],
        });
    }
    s
}

/// The cases, `frames` frames each from frame `start` (after `warmup` frames).
pub fn live_rows(warmup: usize, frames: usize) -> Result<Vec<LiveRow>, GpuError> {
    let (mut gpu, mut gpu_bare) = (HeadlessRenderer::new()?, HeadlessRenderer::new()?);
    let sparks = Scene::parse(
        include_str!("../../assets/scenes/pulse_sparks.toml"),
        std::path::Path::new("pulse_sparks.toml"),
    )
    .expect("the shipped preset is valid");
    let cases = [
        ("pulse_sparks.toml", sparks, 30u32),
        ("10,000 alive", steady(5_000.0), 70),
        ("100,000 alive", steady(50_000.0), 70),
    ];
    let (w, h) = (512, 512);
    let mut rows = Vec::new();
    for (round, (name, mut scene, start)) in cases.into_iter().enumerate() {
        scene.billboard.resolution = 256;
        scene.billboard.fixed_resolution = true;
        let scene = unkept(&scene, round);
        let frame_rate = scene.animation.as_ref().map_or(30.0, |a| a.frame_rate);
        // The states reached are kept in a frame cache, as the viewer's and an export's renderer keep them.
        let cache = crate::frame::FrameCache::new();
        // Up to the first frame timed, then one frame at a time as playback steps.
        std::hint::black_box(cache.scene_at(&scene, start as f64));
        let (mut step, mut rendered, mut bare, mut alive) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let last = start + (warmup + frames) as u32;
        for f in start + 1..=last {
            let t = Instant::now();
            let at = cache.scene_at(&scene, f as f64);
            let s = t.elapsed().as_secs_f64() * 1e3;
            let t = Instant::now();
            gpu.render(&at, w, h, false)?;
            let r = t.elapsed().as_secs_f64() * 1e3;
            let without = Scene {
                particles: Vec::new(),
                ..at.clone()
            };
            let t = Instant::now();
            gpu_bare.render(&without, w, h, false)?;
            let b = t.elapsed().as_secs_f64() * 1e3;
            if f > start + warmup as u32 {
                step.push(s);
                rendered.push(r);
                bare.push(b);
                alive.push(at.particles[0].live.as_ref().map_or(0, |p| p.len()));
            }
        }
        let scrub_back = (1..=frames.max(8) as u32)
            .map(|k| {
                let t = Instant::now();
                std::hint::black_box(cache.scene_at(&scene, (last - k) as f64));
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        // From scratch: `Scene::at_frame` keeps no state (and the key differs from any kept).
        let fresh = unkept(&scene, 100 + round);
        let t = Instant::now();
        std::hint::black_box(fresh.at_frame(last as f64));
        let scratch_ms = t.elapsed().as_secs_f64() * 1e3;
        alive.sort_unstable();
        rows.push(LiveRow {
            case: name.to_owned(),
            alive: alive[alive.len() / 2],
            step: Timing::of(step),
            scrub_back: Timing::of(scrub_back),
            scratch_ms,
            frame: Timing::of(rendered),
            bare: Timing::of(bare),
            frame_rate,
        });
    }
    Ok(rows)
}
