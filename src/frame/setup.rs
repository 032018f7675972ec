//! A frame's setup: what every renderer of one frame of a scene reads, worked out once (see `frame`).

use std::sync::{Arc, OnceLock};

use glam::DVec3;

use super::cache::{FrameCache, ParticlesKey, Rays};
use super::refine::Refine;
use crate::field::Curve;
use crate::geometry::{Billboard, Reach};
use crate::integrate::Integration;
use crate::objects::Lit;
use crate::particles::light::LitParticles;
use crate::particles::view::{GlowPlace, SmokeView, finest_radius, smoke_size};
use crate::scene::Scene;

/// One term of the field as a frame integrates it, in the order of `Sources::looks` (points, lines, tori,
/// curves).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// The term's energy color Ce_i (`Palette::color_of`).
    pub color: [f64; 3],
    /// `Ce_i - Ce`, what the field pass integrates beside B, so that the colored sum is `B Ce + sum B_i (Ce_i -
    /// Ce) = sum B_i Ce_i`: zero in the scene's color (where the blend is the papers' own to the bit), `-Ce` for a
    /// curve with a color series (the field pass adds the integral of its term times the series itself,
    /// `Colors::color_along`).
    pub tint: [f64; 3],
    /// What the term's color, or its color series, is multiplied by: its own intensity or the scene's.
    pub intensity: f64,
}

/// Where a frame's texels' rays end (`FrameSetup::front`, `FrameSetup::exit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ends {
    /// At the first opaque surface: the frame itself.
    Opaque,
    /// At the first surface of any object.
    Front,
    /// At the last translucent surface crossed, where one is.
    Exit,
}

/// What every renderer of one frame of `scene` reads (see the module's documentation).
#[derive(Debug)]
pub struct FrameSetup<'a> {
    pub scene: &'a Scene,
    pub billboard: Billboard,
    /// W: the field texture's side in texels.
    pub resolution: u32,
    /// How far every texel's ray reaches.
    pub reach: Reach,
    /// The scene's integration mapped onto the rays (`Integration::on_ray(reach.stretch)`).
    pub integration: Integration,
    pub terms: Vec<Term>,
    /// Each term's share of the tolerance (`Integration::term_tolerance`).
    pub term_tolerance: f64,
    /// Which texels of the field are integrated exactly (`refine`): by default the scene's tolerance decides
    /// (`Refine::of`); `Refine::EveryTexel` for the reference.
    pub refine: Refine,
    /// The texels' clips at `resolution`, worked out when first asked for.
    clips: OnceLock<Option<Arc<Vec<f32>>>>,
    /// Where the texels' rays end: at the first opaque surface, or (`front`, `exit`) at translucent ones.
    ends: Ends,
    /// The opaque objects.
    clip_objects: OnceLock<Vec<crate::objects::Object>>,
    /// The scene's particles and their light, worked out when first asked for.
    particles: OnceLock<Option<Arc<LitParticles>>>,
    /// The objects lit, worked out when first asked for.
    objects: OnceLock<Option<Arc<Lit>>>,
    /// Where what the frame resolves is kept: its renderer's cache.
    cache: Arc<FrameCache>,
}

impl<'a> FrameSetup<'a> {
    /// The frame of `scene` through `billboard`, at the scene's resolution, resolved through a cache of its own
    /// (a one-off frame: a renderer of many frames passes its own cache, `in_cache`).
    pub fn new(scene: &'a Scene, billboard: Billboard) -> Self {
        Self::in_cache(scene, billboard, &Arc::new(FrameCache::new()))
    }

    /// The frame of `scene` through `billboard`, at the scene's resolution, what it resolves kept in `cache`.
    pub fn in_cache(scene: &'a Scene, billboard: Billboard, cache: &Arc<FrameCache>) -> Self {
        let reach = crate::geometry::ray_reach(
            &scene.camera,
            &scene.sources,
            &billboard,
            scene.integration.decay_length,
        );
        let integration = scene.integration.on_ray(reach.stretch);
        let palette = scene.colors.palette();
        let base = scene.colors.energy_color();
        let terms = (scene.sources.looks().enumerate())
            .map(|(k, look)| {
                let color = palette.color_of(look);
                // A curve with a color series integrates its series itself: its tint is -Ce.
                let own = match scene.series_curve(k) {
                    Some(_) => [0.0; 3],
                    None => color,
                };
                Term {
                    color,
                    tint: std::array::from_fn(|j| own[j] - base[j]),
                    intensity: palette.intensity_of(look),
                }
            })
            .collect();
        FrameSetup {
            scene,
            billboard,
            resolution: scene.billboard.resolution,
            reach,
            term_tolerance: integration.term_tolerance(scene.sources.len()),
            refine: Refine::of(&scene.integration),
            integration,
            terms,
            clips: OnceLock::new(),
            ends: Ends::Opaque,
            clip_objects: OnceLock::new(),
            particles: OnceLock::new(),
            objects: OnceLock::new(),
            cache: cache.clone(),
        }
    }

    /// The cache what this frame resolves is kept in.
    pub fn cache(&self) -> &Arc<FrameCache> {
        &self.cache
    }

    /// The texel grid of `w` x `w` texels over this frame's billboard.
    fn rays(&self, w: u32) -> Rays<'_> {
        Rays {
            eye: self.eye(),
            billboard: &self.billboard,
            reach: self.reach,
            w,
        }
    }

    /// This frame with the translucent objects ending the texels' rays as the opaque ones do: the glow in front
    /// of them, which the glow inside and behind them, seen through them, is blended with (`crossings_at`).
    pub fn front(&self) -> FrameSetup<'a> {
        self.with_ends(Ends::Front)
    }

    /// This frame with the texels' rays that cross translucent objects ending at the last surface of one they
    /// cross: the glow up to there, in front of and inside them (`crossings_at`).
    pub fn exit(&self) -> FrameSetup<'a> {
        self.with_ends(Ends::Exit)
    }

    fn with_ends(&self, ends: Ends) -> FrameSetup<'a> {
        let mut f = FrameSetup::in_cache(self.scene, self.billboard, &self.cache);
        f.resolution = self.resolution;
        f.refine = self.refine;
        f.ends = ends;
        f
    }

    /// Whether the scene has translucent objects, through which the glow is seen.
    pub fn translucent(&self) -> bool {
        self.ends == Ends::Opaque && self.scene.objects.iter().any(|o| o.translucent.is_some())
    }

    /// The opaque objects, which end the texels' rays (every object does in the `front` frame).
    pub fn clip_objects(&self) -> &[crate::objects::Object] {
        match self.ends {
            Ends::Front => &self.scene.objects,
            _ => self.clip_objects.get_or_init(|| {
                (self.scene.objects.iter())
                    .filter(|o| o.translucent.is_none())
                    .cloned()
                    .collect()
            }),
        }
    }

    /// The `front` and `exit` frames' clips, where the texel's ray crosses a translucent object (its first
    /// surface of any object, its last translucent surface), else 0: the blend (`crossings_at`) does not read
    /// their glow where the ray crosses none, so those texels integrate nothing and these fields cost only the
    /// translucent objects' texels.
    fn crossing_clips_at(&self, w: u32) -> Option<Arc<Vec<f32>>> {
        let all = self.cache.clips(&self.scene.objects, self.rays(w));
        let Some(x) = self.with_ends(Ends::Opaque).crossings_at(w) else {
            return all;
        };
        let crossed = |k: usize| x[3 * k + 1] < 1.0 || x[3 * k + 2] < 1.0;
        Some(Arc::new(
            (0..x.len() / 3)
                .map(|k| match (crossed(k), self.ends) {
                    (false, _) => 0.0,
                    (true, Ends::Exit) => x[3 * k],
                    (true, _) => all.as_ref().map_or(1.0, |a| a[k]),
                })
                .collect(),
        ))
    }

    /// The clips at `w` texels a side up to the first surface of any object, opaque or translucent: what the
    /// billboard matches each pixel's own surface against (`clips_at` without translucent objects).
    pub fn surface_clips_at(&self, w: u32) -> Option<Arc<Vec<f32>>> {
        match self.translucent() {
            true => self.cache.clips(&self.scene.objects, self.rays(w)),
            false => self.clips_at(w),
        }
    }

    /// How each texel's ray crosses the translucent objects, at `w` texels a side, three numbers a texel
    /// (`objects::clip::crossings`: the exit's clip, the shares of the glow inside and behind that reach the
    /// eye); none without translucent objects. The glow a texel shows is
    /// `B_front + inside (B_exit - B_front) + behind (B - B_exit)`.
    pub fn crossings_at(&self, w: u32) -> Option<Arc<Vec<f32>>> {
        if !self.translucent() {
            return None;
        }
        self.cache.crossings(
            (&self.scene.objects, self.clip_objects()),
            (&self.scene.sources, self.integration.epsilon),
            self.rays(w),
        )
    }

    /// The frame of `scene` in a picture of `aspect` (width / height), its billboard placed as the scene says
    /// (`Scene::place_billboard`).
    pub fn placed(scene: &'a Scene, aspect: f64) -> Self {
        FrameSetup::new(scene, scene.place_billboard(aspect))
    }

    /// `placed`, what it resolves kept in `cache`.
    pub fn placed_in(scene: &'a Scene, aspect: f64, cache: &Arc<FrameCache>) -> Self {
        FrameSetup::in_cache(scene, scene.place_billboard(aspect), cache)
    }

    /// The eye every ray leaves from.
    pub fn eye(&self) -> DVec3 {
        self.scene.camera.eye
    }

    /// The index of the first curve's term (`Sources::first_curve`).
    pub fn first_curve(&self) -> usize {
        self.scene.sources.first_curve()
    }

    /// Term `k` when it is a curve with a color series.
    pub fn series_curve(&self, k: usize) -> Option<&'a Curve> {
        self.scene.series_curve(k)
    }

    /// The share of each texel's ray before the first surface of the scene's objects, at `resolution`, in f32 as
    /// the GPU passes read it (`objects::clip`); none without objects.
    pub fn clips(&self) -> Option<Arc<Vec<f32>>> {
        self.clips
            .get_or_init(|| self.clips_at(self.resolution))
            .clone()
    }

    /// The scene's particles, each with the light it scatters (`particles::light`); none without particles.
    pub fn particles(&self) -> Option<Arc<LitParticles>> {
        self.particles
            .get_or_init(|| {
                (!self.scene.particles.is_empty())
                    .then(|| self.cache.lit_particles(&ParticlesKey::of(self.scene)))
                    .flatten()
            })
            .clone()
    }

    /// The scene's objects tessellated and lit (`objects::lit`), their translucent tables filled where the
    /// renderer's cache fills them; none without objects.
    pub fn objects(&self) -> Option<Arc<Lit>> {
        self.objects
            .get_or_init(|| {
                let inputs = self.scene.lit_inputs();
                (self.cache).lit_objects(inputs, true, &Default::default())
            })
            .clone()
    }

    /// The smoke of this frame of `frame` pixels over a field of `resolution` texels a side: its camera, its
    /// slices, its glow placed by its sources. A field coarser than the scene's (the viewer's while the view
    /// moves) gets a coarser image and slices as much wider, up to four times; large particles a coarser image
    /// (`smoke_size`).
    pub fn smoke_view(
        &self,
        particles: &[crate::particles::Particle],
        frame: [u32; 2],
        resolution: u32,
    ) -> SmokeView {
        let setup = self;
        let scene = setup.scene;
        let coarser = (setup.resolution as f64 / resolution.max(1) as f64).clamp(1.0, 4.0);
        SmokeView::new(
            particles,
            &scene.camera,
            smoke_size(
                frame,
                resolution,
                finest_radius(particles, &scene.camera, frame[1]),
            ),
            scene.slice_width * coarser,
            &setup.glow_place(),
        )
    }

    /// What places the glow along this frame's rays (`SmokeView`'s depths): its sources and the field pass's
    /// reach and decay along each ray.
    pub fn glow_place(&self) -> GlowPlace<'_> {
        GlowPlace {
            sources: &self.scene.sources,
            epsilon: self.scene.integration.epsilon,
            billboard: &self.billboard,
            nu: self.reach.nu,
            alpha: self.integration.alpha,
            beta: self.integration.beta,
        }
    }

    /// The clips of a texture of `w` x `w` texels over the same billboard (a coarse field's, while the view
    /// moves).
    pub fn clips_at(&self, w: u32) -> Option<Arc<Vec<f32>>> {
        if w == self.resolution
            && let Some(clips) = self.clips.get()
        {
            return clips.clone();
        }
        if self.ends != Ends::Opaque {
            return self.crossing_clips_at(w);
        }
        self.cache.clips(self.clip_objects(), self.rays(w))
    }
}
