//! Live particle sets in their scene: the simulation (`particles::live`) read from the scene's sources and keyed
//! settings at each instant, and the states it has reached kept, so that playback steps one frame from the
//! last, scrubbing back starts from a kept state a few frames before, and an export of a sequence simulates each
//! frame once. Kept states are the ones every run computes on its way (frame N is always frame 0 stepped N
//! times), so a frame is the same to the bit however it is reached.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use super::Scene;
use crate::animation::Animation;
use crate::field::Sources;
use crate::particles::live::{self, State, Timeline, World};
use crate::particles::ply::MAX_PARTICLES;
use crate::particles::{Origin, Particle, ParticleSet};

/// A live set's scene, as far as its simulation reads it: its sources, the sets (for their keyed settings) and
/// the animation. A camera move or an object's edit leaves it, and the kept states, as they were.
#[derive(Clone, PartialEq)]
struct Key {
    index: usize,
    sources: Sources,
    sets: Vec<ParticleSet>,
    animation: Option<Animation>,
}

impl Key {
    /// The sets as the simulation reads them: without their particles of a frame, and without their shutters
    /// (which only draw the particles, `particles_at`: a shutter edited keeps the states).
    fn of(scene: &Scene, index: usize) -> Key {
        let unshuttered = |set: &ParticleSet| {
            let mut set = set.unframed();
            if let Origin::Emitter(e) = &mut set.origin
                && let Some(life) = &mut e.life
            {
                life.shutter = 0.0;
            }
            set
        };
        Key {
            index,
            sources: scene.sources.clone(),
            sets: scene.particles.iter().map(unshuttered).collect(),
            animation: scene.animation.clone(),
        }
    }
}

/// The scene a key stands for, read at any frame.
struct SceneTimeline {
    index: usize,
    /// The scene without its animation and objects.
    still: Scene,
    animation: Option<Animation>,
}

impl SceneTimeline {
    fn new(scene: &Scene, key: &Key) -> SceneTimeline {
        SceneTimeline {
            index: key.index,
            still: Scene {
                sources: key.sources.clone(),
                particles: key.sets.clone(),
                objects: Vec::new(),
                animation: None,
                ..scene.clone_settings()
            },
            animation: key.animation.clone(),
        }
    }
}

impl Timeline for SceneTimeline {
    fn world(&self, frame: f64) -> World {
        let mut s = Scene {
            sources: self.still.sources.clone(),
            particles: self.still.particles.clone(),
            ..self.still.clone_settings()
        };
        if let Some(a) = &self.animation {
            a.apply(&mut s, frame);
        }
        let emitter = match s.particles.swap_remove(self.index).origin {
            Origin::Emitter(e) => e,
            Origin::File { .. } => unreachable!("only an emitter is live"),
        };
        World {
            sources: s.sources,
            emitter,
        }
    }

    fn frame_rate(&self) -> f64 {
        (self.animation.as_ref()).map_or(crate::animation::DEFAULT_FRAME_RATE, |a| a.frame_rate)
    }
}

/// States of one simulation, by frame.
struct Kept {
    key: Key,
    states: BTreeMap<u32, Arc<State>>,
    /// Frames kept: multiples of it, and the latest reached.
    stride: u32,
    latest: u32,
}

/// Particles one simulation's kept states may hold (about 240 MB); past it, fewer states are kept.
const BUDGET: usize = 2_000_000;
/// Particles every simulation's kept states may hold together; past it, the least recently used go.
const TOTAL_BUDGET: usize = 4_000_000;
/// Simulations kept (the viewer's, an export's, a test's).
const SIMULATIONS: usize = 4;
/// Frames between kept states at first.
const STRIDE: u32 = 8;

/// The states the live sets' simulations have reached, kept (a few simulations, the least recently used
/// dropped first; `BUDGET` and `TOTAL_BUDGET` bound them): owned by a renderer's frame cache
/// (`frame::FrameCache`), which counts them in its memory bound; a `Simulations` of its own simulates from the
/// start.
#[derive(Default)]
pub struct Simulations {
    kept: Mutex<Vec<Kept>>,
}

impl Simulations {
    pub fn new() -> Self {
        Self::default()
    }

    /// The particles of every live set of `scene` at `frame` as the renderers draw them, by the set's index;
    /// `None` once `cancel` is raised (the states reached so far are kept). The copies the sets' shutters add
    /// (`live::State::particles`) share the room the scene has left under `MAX_PARTICLES` evenly, so that a
    /// frame never holds more particles than a loaded scene may.
    pub fn particles_at(
        &self,
        scene: &Scene,
        frame: u32,
        cancel: &crate::background::Cancel,
    ) -> Option<Vec<(usize, Arc<Vec<Particle>>)>> {
        let mut reached = Vec::new();
        for (i, set) in scene.particles.iter().enumerate() {
            if let Some(life) = set.life() {
                let (state, timeline) = self.reached(scene, i, frame, cancel);
                if state.frame != frame {
                    return None;
                }
                reached.push((i, life.shutter, state, timeline));
            }
        }
        let still: usize = (scene.particles.iter())
            .map(|set| match &set.origin {
                Origin::File { particles, .. } => particles.len(),
                Origin::Emitter(e) if e.life.is_none() => e.count as usize,
                Origin::Emitter(_) => 0,
            })
            .sum();
        let alive: usize = reached.iter().map(|r| r.2.particles.len()).sum();
        let blurred = reached.iter().filter(|r| r.1 > 0.0).count().max(1);
        let room = MAX_PARTICLES.saturating_sub(still + alive) / blurred;
        Some(
            (reached.into_iter())
                .map(|(i, shutter, state, timeline)| {
                    (i, Arc::new(state.particles(&timeline, shutter, room)))
                })
                .collect(),
        )
    }

    /// The state of live set `index` of `scene` at `frame`: from the nearest kept state at or before it.
    pub fn state_at(&self, scene: &Scene, index: usize, frame: u32) -> Arc<State> {
        self.reached(scene, index, frame, &Default::default()).0
    }

    /// The bytes the kept states hold (their particles).
    pub fn bytes(&self) -> usize {
        let kept = self
            .kept
            .lock()
            .map(|k| k.iter().map(held).sum())
            .unwrap_or(0);
        kept * size_of::<live::LiveParticle>()
    }

    /// Drops the least recently used simulations' states until they hold at most `bytes` (the latest
    /// simulation's are kept whole).
    pub fn trim_to(&self, bytes: usize) {
        if let Ok(mut kept) = self.kept.lock() {
            let most = bytes / size_of::<live::LiveParticle>().max(1);
            while kept.len() > 1 && kept.iter().map(held).sum::<usize>() > most {
                kept.remove(0);
            }
        }
    }

    /// Drops every kept state.
    pub fn clear(&self) {
        if let Ok(mut kept) = self.kept.lock() {
            kept.clear();
        }
    }

    /// The state of live set `index` of `scene` at `frame`, and the scene as its simulation reads it; an
    /// earlier state where `cancel` stopped it.
    fn reached(
        &self,
        scene: &Scene,
        index: usize,
        frame: u32,
        cancel: &crate::background::Cancel,
    ) -> (Arc<State>, SceneTimeline) {
        let key = Key::of(scene, index);
        let timeline = SceneTimeline::new(scene, &key);
        let from = self.kept.lock().ok().and_then(|kept| {
            let k = kept.iter().find(|k| k.key == key)?;
            k.states.range(..=frame).next_back().map(|(_, s)| s.clone())
        });
        let mut state = from.unwrap_or_else(|| Arc::new(live::start(&timeline)));
        let mut reached = vec![state.clone()];
        while state.frame < frame && !cancel.stopped() {
            state = Arc::new(live::advance(&state, &timeline));
            reached.push(state.clone());
        }
        if let Ok(mut kept) = self.kept.lock() {
            let at = match kept.iter().position(|k| k.key == key) {
                Some(i) => i,
                None => {
                    if kept.len() >= SIMULATIONS {
                        kept.remove(0);
                    }
                    kept.push(Kept {
                        key,
                        states: BTreeMap::new(),
                        stride: STRIDE,
                        latest: 0,
                    });
                    kept.len() - 1
                }
            };
            // The most recently used last.
            let mut k = kept.remove(at);
            keep(&mut k, &reached);
            kept.push(k);
            while kept.len() > 1 && kept.iter().map(held).sum::<usize>() > TOTAL_BUDGET {
                kept.remove(0);
            }
        }
        (state, timeline)
    }
}

/// The particles a simulation's kept states hold.
fn held(k: &Kept) -> usize {
    k.states.values().map(|s| s.particles.len()).sum()
}

/// Keeps the states `reached` that fall on the stride, and the last one as the latest; thins the kept states
/// (doubling the stride) while they hold more particles than the budget.
fn keep(k: &mut Kept, reached: &[Arc<State>]) {
    let last = reached.last().expect("at least the state started from");
    let old_latest = k.latest;
    for s in reached {
        if s.frame.is_multiple_of(k.stride) {
            k.states.insert(s.frame, s.clone());
        }
    }
    if !old_latest.is_multiple_of(k.stride) && old_latest != last.frame {
        k.states.remove(&old_latest);
    }
    k.states.insert(last.frame, last.clone());
    k.latest = last.frame;
    while held(k) > BUDGET && k.states.len() > 1 {
        k.stride = k.stride.saturating_mul(2);
        let (stride, latest) = (k.stride, k.latest);
        k.states.retain(|&f, _| f % stride == 0 || f == latest);
        if k.stride > 1 << 20 {
            k.states.retain(|&f, _| f == latest);
        }
    }
}

impl Scene {
    /// The scene's settings with no sources, objects, particles or animation (cheap to clone).
    fn clone_settings(&self) -> Scene {
        Scene {
            camera: self.camera.clone(),
            billboard: self.billboard.clone(),
            integration: self.integration.clone(),
            colors: self.colors.clone(),
            glare: self.glare,
            sources: Sources::default(),
            objects: Vec::new(),
            particles: Vec::new(),
            slice_width: self.slice_width,
            animation: None,
        }
    }
}
