//! What frames resolved from their scenes, kept for the next ones: one cache a renderer owns (the viewer's, a
//! headless renderer's, the CPU twin's through its `FrameSetup`), with one memory bound over everything it holds
//! and explicit invalidation by what changed.
//!
//! It keeps the texels' clips and crossings (`objects::clip`), the translucent objects' voxels and tables
//! (`objects::translucent::light::prepare`), the objects' light (`objects::lit`), the particles' light
//! (`particles::light::lit_particles`) and the states the live sets' simulations reached (`scene::Simulations`).
//! Every entry is found by all it was made from, so a kept value is never stale: invalidation only frees
//! memory early. The least recently used entries go first once the bound is passed.
//!
//! A real GPU fills the translucent tables faster than the CPU: a renderer on one sets the cache's table fill
//! (`set_table_fill`, `gpu::tau_table`), which the cache calls where it would fill a table itself.

use std::sync::{Arc, Mutex};

use glam::DVec3;

use crate::background::Cancel;
use crate::field::{Palette, Sources};
use crate::geometry::{Billboard, Reach};
use crate::objects::translucent::light::{Prepared, prepare};
use crate::objects::translucent::table::Table;
use crate::objects::translucent::voxels::Voxels;
use crate::objects::{Lit, LitInputs, LitKey, Object, Tables};
use crate::particles::ParticleSet;
use crate::particles::light::{LitParticles, lit_particles};
use crate::scene::{Scene, Simulations};

/// The memory a cache holds at most by default: the viewer's orbit over a few translucent tables and a few
/// simulations' kept states (about 120 bytes a live particle) fits.
pub const DEFAULT_BUDGET: usize = 768 << 20;

/// How a texel grid's rays run: from `eye` through the `w` x `w` texels of `billboard`, as far as `reach`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rays<'a> {
    pub eye: DVec3,
    pub billboard: &'a Billboard,
    pub reach: Reach,
    pub w: u32,
}

/// What the clips (and the crossings) of a texel grid depend on.
#[derive(Clone, Debug, PartialEq)]
struct RaysKey {
    objects: Vec<Object>,
    eye: DVec3,
    billboard: Billboard,
    nu: f64,
    w: u32,
}

impl RaysKey {
    fn of(objects: &[Object], rays: Rays<'_>) -> RaysKey {
        RaysKey {
            objects: objects.to_vec(),
            eye: rays.eye,
            billboard: *rays.billboard,
            nu: rays.reach.nu,
            w: rays.w,
        }
    }
}

/// What the particles' light depends on.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticlesKey {
    pub sets: Vec<ParticleSet>,
    pub sources: Sources,
    /// The objects, which shadow the particles, their colors cleared (the light does not depend on them).
    pub objects: Vec<Object>,
    pub palette: Palette,
    pub epsilon: f64,
}

impl ParticlesKey {
    /// What `scene`'s particles are lit from.
    pub fn of(scene: &Scene) -> ParticlesKey {
        ParticlesKey {
            sets: scene.particles.clone(),
            sources: scene.sources.clone(),
            objects: (scene.objects.iter())
                .map(|o| Object {
                    color: [0.0; 3],
                    ..o.clone()
                })
                .collect(),
            palette: scene.colors.palette(),
            epsilon: scene.integration.epsilon,
        }
    }
}

/// An entry's key: what it was made from.
#[derive(Clone, Debug, PartialEq)]
enum Key {
    Clips(RaysKey),
    Crossings(RaysKey, Vec<Object>, Sources, f64),
    /// An object with its color cleared: the voxels and table depend on its shape, place and material alone.
    Translucent(Object),
    Objects(LitKey),
    Particles(ParticlesKey),
}

/// An entry's value.
#[derive(Clone)]
enum Value {
    Floats(Arc<Vec<f32>>),
    Translucent(Arc<Prepared>),
    Objects(Arc<Lit>),
    Particles(Arc<LitParticles>),
}

impl Key {
    /// The bytes a key holds on its own: a live set's particles (its frame's, which the key may alone keep).
    fn bytes(&self) -> usize {
        match self {
            Key::Particles(k) => (k.sets.iter())
                .filter_map(|s| s.live.as_ref())
                .map(|p| size_of_val(&p[..]))
                .sum(),
            _ => 0,
        }
    }
}

impl Value {
    fn bytes(&self) -> usize {
        match self {
            Value::Floats(v) => 4 * v.len(),
            Value::Translucent(p) => p.bytes(),
            Value::Objects(l) => l.bytes(),
            Value::Particles(p) => p.bytes(),
        }
    }
}

/// Which kinds of entry depend on what: `FrameCache::invalidate` drops those that depend on what changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changed {
    /// The objects: their clips and crossings, tables and light.
    pub objects: bool,
    /// The sources or the colors: the crossings, the objects' and particles' light, the simulations.
    pub sources: bool,
    /// The particle sets: their light and simulations.
    pub particles: bool,
}

impl Changed {
    /// Everything.
    pub const ALL: Changed = Changed {
        objects: true,
        sources: true,
        particles: true,
    };

    /// What differs between two versions of a scene (an edit): its objects, its sources or colors, its
    /// particle sets or animation.
    pub fn between(before: &Scene, after: &Scene) -> Changed {
        Changed {
            objects: before.objects != after.objects,
            sources: before.sources != after.sources
                || before.colors != after.colors
                || before.integration.epsilon != after.integration.epsilon,
            particles: before.particles != after.particles || before.animation != after.animation,
        }
    }

    fn drops(self, key: &Key) -> bool {
        match key {
            Key::Clips(_) | Key::Translucent(_) => self.objects,
            Key::Crossings(..) | Key::Objects(_) => self.objects || self.sources,
            Key::Particles(_) => self.particles || self.sources,
        }
    }

    fn any(self) -> bool {
        self.objects || self.sources || self.particles
    }
}

/// A table fill on a GPU (`set_table_fill`): the table of the voxels given, or none where it cannot (the CPU
/// fills it then).
pub type TableFill = Box<dyn Fn(&Voxels) -> Option<Table> + Send + Sync>;

/// The GPU's table fill, and whether it may be called from any thread (on GL every call holds the one context:
/// a thread of its own fills on the CPU).
struct Fill {
    fill: TableFill,
    any_thread: bool,
}

/// What frames resolved, kept (see the module's documentation).
pub struct FrameCache {
    /// Least recently used first.
    entries: Mutex<Vec<(Key, Value)>>,
    simulations: Simulations,
    budget: usize,
    fill: Option<Fill>,
}

impl Default for FrameCache {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for FrameCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameCache")
            .field("bytes", &self.bytes())
            .field("budget", &self.budget)
            .finish()
    }
}

impl FrameCache {
    /// An empty cache of `DEFAULT_BUDGET` bytes.
    pub fn new() -> Self {
        Self::with_budget(DEFAULT_BUDGET)
    }

    /// An empty cache holding at most `budget` bytes (beyond the last entry made, which is kept whatever its
    /// size until the next).
    pub fn with_budget(budget: usize) -> Self {
        FrameCache {
            entries: Mutex::new(Vec::new()),
            simulations: Simulations::new(),
            budget,
            fill: None,
        }
    }

    /// Fills the translucent tables by `fill` (a real GPU's, `gpu::tau_table`) where it gives one; where not
    /// `any_thread`, only on the thread that renders (`translucent_here`).
    pub fn set_table_fill(&mut self, fill: TableFill, any_thread: bool) {
        self.fill = Some(Fill { fill, any_thread });
    }

    /// The bytes it holds.
    pub fn bytes(&self) -> usize {
        let entries: usize = (self.entries.lock())
            .map(|e| e.iter().map(|(k, v)| k.bytes() + v.bytes()).sum())
            .unwrap_or(0);
        entries + self.simulations.bytes()
    }

    /// The memory it holds at most.
    pub fn budget(&self) -> usize {
        self.budget
    }

    /// Drops what depends on what `changed` names (an edit; opening another scene changes everything).
    pub fn invalidate(&self, changed: Changed) {
        if !changed.any() {
            return;
        }
        if let Ok(mut entries) = self.entries.lock() {
            entries.retain(|(k, _)| !changed.drops(k));
        }
        if changed.particles || changed.sources {
            self.simulations.clear();
        }
    }

    /// The live sets' simulations' kept states (`Scene::at_frame_in`).
    pub fn simulations(&self) -> &Simulations {
        &self.simulations
    }

    /// `Scene::at_frame` with the simulations' states kept here.
    pub fn scene_at(&self, scene: &Scene, frame: f64) -> Scene {
        let scene = (scene.at_frame_in(frame, &self.simulations, &Cancel::default()))
            .expect("never cancelled");
        self.trim(0);
        scene
    }

    /// The share of each texel's ray before the first of `objects` (`objects::clip::clip_fractions`), in f32;
    /// none without objects.
    pub fn clips(&self, objects: &[Object], rays: Rays<'_>) -> Option<Arc<Vec<f32>>> {
        if objects.is_empty() {
            return None;
        }
        let key = Key::Clips(RaysKey::of(objects, rays));
        self.floats(key, || {
            crate::objects::clip::clip_fractions(
                objects,
                rays.eye,
                rays.billboard,
                rays.reach,
                rays.w,
            )
        })
    }

    /// How each texel's ray crosses the translucent objects among `objects` (`objects::clip::crossings`), in
    /// f32; none without translucent objects.
    pub fn crossings(
        &self,
        (objects, opaque): (&[Object], &[Object]),
        (sources, epsilon): (&Sources, f64),
        rays: Rays<'_>,
    ) -> Option<Arc<Vec<f32>>> {
        if !objects.iter().any(|o| o.translucent.is_some()) {
            return None;
        }
        let key = Key::Crossings(
            RaysKey::of(objects, rays),
            opaque.to_vec(),
            sources.clone(),
            epsilon,
        );
        self.floats(key, || {
            crate::objects::clip::crossings(
                objects,
                opaque,
                (sources, epsilon),
                rays.eye,
                rays.billboard,
                rays.reach,
                rays.w,
            )
        })
    }

    /// `object`'s voxels and table, the table filled by the GPU where the cache has a fill for this thread
    /// (`here`: the thread that renders); none for an opaque object.
    fn translucent_on(&self, object: &Object, here: bool) -> Option<Arc<Prepared>> {
        object.translucent.as_ref()?;
        let key = Key::Translucent(Object {
            color: [0.0; 3],
            ..object.clone()
        });
        let value = self.kept(key, || {
            let gpu = self.fill.as_ref().filter(|f| here || f.any_thread);
            let fill = |v: &Voxels| gpu.and_then(|f| (f.fill)(v));
            prepare(object, &fill).map(|p| Value::Translucent(Arc::new(p)))
        })?;
        match value {
            Value::Translucent(p) => Some(p),
            _ => None,
        }
    }

    /// `object`'s voxels and table, on the thread that renders (the GPU fills the table where it can).
    pub fn translucent_here(&self, object: &Object) -> Option<Arc<Prepared>> {
        self.translucent_on(object, true)
    }

    /// The objects lit (`objects::lit`), their tables from here; none without objects. Made on the thread that
    /// renders (`here`) or on one of its own, which stops between the objects once `cancel` is raised (then
    /// none).
    pub fn lit_objects(
        &self,
        inputs: LitInputs<'_>,
        here: bool,
        cancel: &Cancel,
    ) -> Option<Arc<Lit>> {
        if inputs.objects.is_empty() {
            return None;
        }
        let key = Key::Objects(LitKey::of(inputs));
        let value = self.kept(key, || {
            // The tables first (the longest part), each a step that a newer request can stop after.
            for o in inputs.objects.iter().filter(|o| o.translucent.is_some()) {
                if cancel.stopped() {
                    return None;
                }
                self.translucent_on(o, here);
            }
            if cancel.stopped() {
                return None;
            }
            let tables = Here { cache: self, here };
            Some(Value::Objects(Arc::new(crate::objects::lit(
                inputs, &tables,
            ))))
        })?;
        match value {
            Value::Objects(l) => Some(l),
            _ => None,
        }
    }

    /// The particles of `key`'s sets lit by its sources (`particles::light::lit_particles`); none without
    /// particles.
    pub fn lit_particles(&self, key: &ParticlesKey) -> Option<Arc<LitParticles>> {
        if key.sets.is_empty() {
            return None;
        }
        let value = self.kept(Key::Particles(key.clone()), || {
            let lit = lit_particles(
                &key.sets,
                (&key.sources, &key.objects),
                key.palette,
                key.epsilon,
            )?;
            Some(Value::Particles(Arc::new(lit)))
        })?;
        match value {
            Value::Particles(p) => Some(p),
            _ => None,
        }
    }

    /// What `make` gives for `key` (in f64), in f32, kept.
    fn floats(&self, key: Key, make: impl FnOnce() -> Option<Vec<f64>>) -> Option<Arc<Vec<f32>>> {
        let value = self.kept(key, || {
            let v: Vec<f32> = make()?.into_iter().map(|c| c as f32).collect();
            Some(Value::Floats(Arc::new(v)))
        })?;
        match value {
            Value::Floats(v) => Some(v),
            _ => None,
        }
    }

    /// The value kept for `key` (now the most recently used), else what `make` gives, kept.
    fn kept(&self, key: Key, make: impl FnOnce() -> Option<Value>) -> Option<Value> {
        if let Ok(mut entries) = self.entries.lock()
            && let Some(at) = entries.iter().position(|(k, _)| *k == key)
        {
            let entry = entries.remove(at);
            let value = entry.1.clone();
            entries.push(entry);
            return Some(value);
        }
        let value = make()?;
        let bytes = key.bytes() + value.bytes();
        if let Ok(mut entries) = self.entries.lock() {
            entries.retain(|(k, _)| *k != key);
            entries.push((key, value.clone()));
        }
        self.trim(bytes);
        Some(value)
    }

    /// Drops the least recently used entries, then the simulations' oldest states, until what is held fits the
    /// budget (the newest entry, of `newest` bytes, always stays).
    fn trim(&self, newest: usize) {
        let held = |e: &[(Key, Value)]| {
            (e.iter())
                .map(|(k, v)| k.bytes() + v.bytes())
                .sum::<usize>()
        };
        if let Ok(mut entries) = self.entries.lock() {
            let simulated = self.simulations.bytes();
            while entries.len() > 1 && held(&entries) + simulated > self.budget {
                entries.remove(0);
            }
        }
        let entries = self.entries.lock().map(|e| held(&e)).unwrap_or(newest);
        if entries + self.simulations.bytes() > self.budget {
            self.simulations
                .trim_to(self.budget.saturating_sub(entries));
        }
    }
}

/// The cache as the objects' lighting reads the tables, on the thread that renders or not.
struct Here<'a> {
    cache: &'a FrameCache,
    here: bool,
}

impl Tables for Here<'_> {
    fn translucent(&self, object: &Object) -> Option<Arc<Prepared>> {
        self.cache.translucent_on(object, self.here)
    }
}

impl Tables for FrameCache {
    fn translucent(&self, object: &Object) -> Option<Arc<Prepared>> {
        self.translucent_here(object)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Billboard;

    fn scene_with_sphere() -> Scene {
        crate::scene::shipped("floor.toml")
    }

    fn rays(billboard: &Billboard, w: u32) -> Rays<'_> {
        Rays {
            eye: DVec3::new(3.6, 2.4, 6.8),
            billboard,
            reach: Reach {
                nu: 3.0,
                stretch: 1.0,
            },
            w,
        }
    }

    #[test]
    fn a_kept_value_is_the_one_made_and_the_bound_holds() {
        let scene = scene_with_sphere();
        let billboard = scene.place_billboard(1.0);
        // Room for about two grids of 32 x 32 clips.
        let cache = FrameCache::with_budget(2 * 4 * 32 * 32 + 100);
        let a = cache.clips(&scene.objects, rays(&billboard, 32)).unwrap();
        let again = cache.clips(&scene.objects, rays(&billboard, 32)).unwrap();
        assert!(Arc::ptr_eq(&a, &again), "the same grid is made once");
        let direct = crate::objects::clip::clip_fractions(
            &scene.objects,
            DVec3::new(3.6, 2.4, 6.8),
            &billboard,
            rays(&billboard, 32).reach,
            32,
        )
        .unwrap();
        assert_eq!(*a, direct.iter().map(|&c| c as f32).collect::<Vec<_>>());
        assert!(a.iter().any(|&c| c < 1.0) && a.contains(&1.0));
        // Two more grids: the least recently used goes, the bound holds.
        cache.clips(&scene.objects, rays(&billboard, 31)).unwrap();
        cache.clips(&scene.objects, rays(&billboard, 30)).unwrap();
        assert!(cache.bytes() <= cache.budget(), "{} bytes", cache.bytes());
        let made_again = cache.clips(&scene.objects, rays(&billboard, 32)).unwrap();
        assert!(!Arc::ptr_eq(&a, &made_again) && *a == *made_again);
    }

    #[test]
    fn invalidation_drops_what_depends_on_what_changed() {
        let scene = scene_with_sphere();
        let billboard = scene.place_billboard(1.0);
        let cache = FrameCache::new();
        let a = cache.clips(&scene.objects, rays(&billboard, 16)).unwrap();
        cache.invalidate(Changed {
            sources: true,
            particles: true,
            ..Default::default()
        });
        let kept = cache.clips(&scene.objects, rays(&billboard, 16)).unwrap();
        assert!(Arc::ptr_eq(&a, &kept), "a source's edit leaves the clips");
        let mut moved = scene.clone();
        if let crate::objects::Shape::Sphere { center, .. } = &mut moved.objects[1].shape {
            center.x += 0.1;
        }
        let changed = Changed::between(&scene, &moved);
        assert_eq!(
            changed,
            Changed {
                objects: true,
                ..Default::default()
            }
        );
        cache.invalidate(changed);
        assert_eq!(cache.bytes(), 0);
        let made = cache.clips(&scene.objects, rays(&billboard, 16)).unwrap();
        assert!(!Arc::ptr_eq(&a, &made) && *a == *made);
    }
}
