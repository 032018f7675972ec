//! The frame's objects and particles as its passes read them: their light resolved before the frame records
//! (renders, exports: `FrameSetup::objects`, `FrameSetup::particles`), or, in the viewer, on threads of their
//! own, each frame waiting a moment (`WAIT`) and then drawing stand-ins until the light is ready: the objects
//! with their older light (or unshadowed), the particles as last drawn (or unshadowed).

use std::sync::Arc;
use std::time::Duration;

use super::cache::ParticlesKey;
use super::setup::FrameSetup;
use crate::background::{Latest, Poll};
use crate::objects::{Lit, LitKey, Object, unshadowed};
use crate::particles::light::{LitParticles, light_particles_unshadowed};

/// How long a viewer's frame waits for the light being worked out before it draws a stand-in: a few spheres'
/// and boxes' is ready within it, translucent tables and large meshes are not.
pub const WAIT: Duration = Duration::from_millis(30);

/// A frame's objects as its passes draw them.
#[derive(Clone, Debug)]
pub struct ResolvedObjects {
    /// Their triangles and light.
    pub lit: Arc<Lit>,
    /// What the light was worked out from; none for a stand-in (the objects unshadowed, or their older light,
    /// while theirs is worked out).
    pub key: Option<LitKey>,
}

/// One frame's data: its setup, and its objects and particles resolved.
pub struct Frame<'s, 'a> {
    pub setup: &'s FrameSetup<'a>,
    /// None without objects.
    pub objects: Option<ResolvedObjects>,
    /// The particles and their light; none without particles.
    pub particles: Option<Arc<LitParticles>>,
}

impl<'s, 'a> Frame<'s, 'a> {
    /// `setup` with its objects and particles resolved before it records.
    pub fn resolved(setup: &'s FrameSetup<'a>) -> Self {
        Frame {
            setup,
            objects: (setup.objects()).map(|lit| ResolvedObjects {
                lit,
                key: Some(LitKey::of(setup.scene.lit_inputs())),
            }),
            particles: setup.particles(),
        }
    }
}

/// Where the light is worked out on threads of their own, and what the frames showed meanwhile.
struct Background {
    wait: Duration,
    objects: Latest<LitKey, Arc<Lit>>,
    particles: Latest<ParticlesKey, Option<Arc<LitParticles>>>,
    /// The last objects' light worked out whole (a color edit recolors it at once: `Lit::recolored`).
    last: Option<(LitKey, Arc<Lit>)>,
    /// The objects the last frame drew, and their light (perhaps a stand-in).
    shown: Option<(Vec<Object>, Arc<Lit>)>,
    /// The particles the last frame drew.
    shown_particles: Option<Arc<LitParticles>>,
    /// Whether the last frame drew a stand-in for the objects' light, and for the particles': until a frame
    /// draws theirs, they are being prepared, even once the work is done (the frame did not show it).
    stood_in: [bool; 2],
}

/// Resolves frames: before they record, or in the background (`in_background`).
#[derive(Default)]
pub struct Resolver {
    background: Option<Background>,
}

impl Resolver {
    /// Resolves every frame whole before it records.
    pub fn new() -> Self {
        Self::default()
    }

    /// Works out the objects' and particles' light on threads of their own from now on: a frame waits for it up
    /// to `wait` (`WAIT` in the viewer), then draws stand-ins until it is ready; `preparing` says what is.
    pub fn in_background(&mut self, wait: Duration) {
        self.background = Some(Background {
            wait,
            objects: Latest::new("energywave objects' light"),
            particles: Latest::new("energywave particles' light"),
            last: None,
            shown: None,
            shown_particles: None,
            stood_in: [false; 2],
        });
    }

    /// The frame of `setup`, its objects and particles resolved (or stood in for).
    pub fn resolve<'s, 'a>(&mut self, setup: &'s FrameSetup<'a>) -> Frame<'s, 'a> {
        let Some(bg) = &mut self.background else {
            return Frame::resolved(setup);
        };
        let objects = bg.objects_of(setup);
        bg.stood_in[0] = objects.as_ref().is_some_and(|o| o.key.is_none());
        Frame {
            setup,
            objects,
            particles: bg.particles_of(setup),
        }
    }

    /// What is being worked out on the background threads, for the status line; `None` when the frames show
    /// everything as it is.
    pub fn preparing(&self) -> Option<String> {
        let bg = self.background.as_ref()?;
        let translucent = (bg.shown.iter()).any(|(o, _)| o.iter().any(|o| o.translucent.is_some()));
        let objects = match (bg.objects.busy() || bg.stood_in[0], translucent) {
            (false, _) => None,
            (true, true) => Some("objects' light, translucent tables"),
            (true, false) => Some("objects' light"),
        };
        let parts: Vec<&str> = (objects.into_iter())
            .chain((bg.particles.busy() || bg.stood_in[1]).then_some("particles' light"))
            .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }

    /// Waits until what is being worked out is ready (a screenshot shows the scene as it is).
    pub fn wait(&self) {
        if let Some(bg) = &self.background {
            bg.objects.wait();
            bg.particles.wait();
        }
    }
}

impl Background {
    fn objects_of(&mut self, setup: &FrameSetup) -> Option<ResolvedObjects> {
        let scene = setup.scene;
        if scene.objects.is_empty() {
            self.shown = None;
            return None;
        }
        let inputs = scene.lit_inputs();
        if let Some((key, lit)) = &self.last
            && key.matches(inputs)
        {
            let (key, lit) = (key.clone(), lit.clone());
            // What the frames show already, as a still view shows it frame after frame: nothing to copy.
            if !(self.shown.as_ref()).is_some_and(|(_, shown)| Arc::ptr_eq(shown, &lit)) {
                self.shown = Some((scene.objects.clone(), lit.clone()));
            }
            return Some(ResolvedObjects {
                lit,
                key: Some(key),
            });
        }
        let key = LitKey::of(inputs);
        // A color edit (a picker dragged) needs no new light: the last one, recolored, is exact.
        let recolored = (self.last.as_ref())
            .filter(|(k, _)| k.matches_but_colors(inputs))
            .map(|(_, lit)| Poll::Ready(Arc::new(Arc::new(lit.recolored(&scene.objects)))));
        let job = || {
            let cache = setup.cache().clone();
            let (objects, sources) = (scene.objects.clone(), scene.sources.clone());
            let (palette, epsilon) = (inputs.palette, inputs.epsilon);
            move |cancel: &crate::background::Cancel| {
                let inputs = crate::objects::LitInputs {
                    objects: &objects,
                    sources: &sources,
                    palette,
                    epsilon,
                };
                cache.lit_objects(inputs, false, cancel)
            }
        };
        let lit = recolored.unwrap_or_else(|| self.objects.request_within(&key, self.wait, job));
        match lit {
            Poll::Ready(lit) => {
                let lit = (*lit).clone();
                self.last = Some((key.clone(), lit.clone()));
                self.shown = Some((scene.objects.clone(), lit.clone()));
                Some(ResolvedObjects {
                    lit,
                    key: Some(key),
                })
            }
            // These objects drawn already, by older light: kept until the new light is ready, the pixels shaded
            // by the sources of now.
            Poll::Pending => match &self.shown {
                Some((objects, lit)) if objects[..] == scene.objects[..] => Some(ResolvedObjects {
                    lit: lit.clone(),
                    key: None,
                }),
                _ => {
                    let lit = Arc::new(unshadowed(inputs));
                    self.shown = Some((scene.objects.clone(), lit.clone()));
                    Some(ResolvedObjects { lit, key: None })
                }
            },
        }
    }

    fn particles_of(&mut self, setup: &FrameSetup) -> Option<Arc<LitParticles>> {
        let scene = setup.scene;
        if scene.particles.is_empty() {
            self.shown_particles = None;
            self.stood_in[1] = false;
            return None;
        }
        let key = ParticlesKey::of(scene);
        let job = || {
            let (cache, k) = (setup.cache().clone(), key.clone());
            move |cancel: &crate::background::Cancel| {
                (!cancel.stopped()).then(|| cache.lit_particles(&k))
            }
        };
        let ready = self.particles.request_within(&key, self.wait, job);
        self.stood_in[1] = matches!(ready, Poll::Pending);
        let lit = match ready {
            Poll::Ready(lit) => (*lit).clone(),
            Poll::Pending => match &self.shown_particles {
                // The particles drawn before, as they were lit.
                Some(p) => Some(p.clone()),
                // None yet: these, lit as if they shadowed nothing (a small part of the cost).
                None => {
                    let particles = crate::particles::gather(&key.sets, &key.sources);
                    let lights = crate::objects::lighting::Lights::new(
                        &key.sources,
                        key.palette,
                        key.epsilon,
                    );
                    let lights = light_particles_unshadowed(&lights, &particles);
                    (!particles.is_empty()).then(|| Arc::new(LitParticles { particles, lights }))
                }
            },
        };
        self.shown_particles = lit.clone();
        lit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn floor() -> Scene {
        crate::scene::shipped("floor.toml")
    }

    #[test]
    fn a_frame_with_a_stand_in_is_preparing_until_a_frame_shows_the_light() {
        let scene = floor();
        let setup = FrameSetup::placed(&scene, 1.5);
        let mut resolver = Resolver::new();
        resolver.in_background(Duration::ZERO);
        // Not waited for: the objects drawn unshadowed.
        let first = resolver.resolve(&setup);
        let stand_in = first.objects.unwrap();
        assert!(stand_in.key.is_none());
        assert_eq!(*stand_in.lit, unshadowed(scene.lit_inputs()));
        // The light is ready now, but the frame showed the stand-in: still being prepared.
        resolver.wait();
        assert_eq!(resolver.preparing().as_deref(), Some("objects' light"));
        // The next frame shows it, the light the frame resolves before it records.
        let second = resolver.resolve(&setup).objects.unwrap();
        assert!(second.key.is_some());
        assert_eq!(*second.lit, *setup.objects().unwrap());
        assert_eq!(resolver.preparing(), None);
        // Resolved before it records, a frame never stands in.
        let whole = Resolver::new().resolve(&setup).objects.unwrap();
        assert!(whole.key.is_some() && Arc::ptr_eq(&whole.lit, &setup.objects().unwrap()));
    }
}
