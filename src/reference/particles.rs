//! Particle sets rendered by image-aligned sheet-buffer splatting, along one ray, in f64 (docs/METHOD.md section 9;
//! paper 002_): slices parallel to the image plane cut every particle into segments; within a slice the
//! segments are added (commutative: no order among them, so no color popping where particles interpenetrate),
//! and the slices are composited in order. Each segment's optical depth is the kernel integrated exactly over
//! the part of the ray the slice holds (`Particle::optical_depth`, what a pre-integrated footprint holds); a
//! slice then acts as a layer of that optical depth and of its segments' extinction-weighted color.
//!
//! [`marched`] is what it converges to as slices thin: the same medium, its extinction and color summed from
//! the kernels at every point, ray-marched in fine steps.

use glam::DVec3;

use crate::particles::view::{GlowDepths, glow_before};
use crate::particles::{Particle, Ray, Slicing, extinction, kernel};

/// What a ray through the medium gives: the light its particles scatter toward the eye, and the share of what
/// lies behind them that comes through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Composite {
    pub radiance: [f64; 3],
    pub transmittance: f64,
}

/// Light emitted along a ray in and around the medium: the energy wave's glow. `over(t0, t1)` is its integral
/// over the stretch `[t0, t1]` of the ray, unattenuated (what the field pass integrates there); it lies on
/// `[start, end]`.
pub struct Glow<'a> {
    pub over: &'a dyn Fn(f64, f64) -> [f64; 3],
    pub start: f64,
    pub end: f64,
}

impl Glow<'_> {
    /// No glow.
    pub const NONE: Glow<'static> = Glow {
        over: &|_, _| [0.0; 3],
        start: 0.0,
        end: 0.0,
    };

    /// Its integral over `[t0, t1]` clipped to where it lies.
    fn between(&self, t0: f64, t1: f64) -> DVec3 {
        let (a, b) = (t0.max(self.start), t1.min(self.end));
        if b > a {
            DVec3::from_array((self.over)(a, b))
        } else {
            DVec3::ZERO
        }
    }
}

/// `ray` through `particles` by image-aligned sheet-buffer splatting over `slicing`: each slab's segments added
/// (optical depth, and optical depth times color and times emission), then the slabs composited front to back, a
/// slab scattering `albedo` times its color times `light` at its middle on the ray (the light in-scattered
/// toward the eye there) and giving off its particles' emission, each over its opacity `1 - exp(-optical
/// depth)`.
pub fn sheet_buffer(
    particles: &[Particle],
    ray: &Ray,
    slicing: &Slicing,
    albedo: f64,
    light: impl Fn(DVec3) -> [f64; 3],
) -> Composite {
    sheet_buffer_glowing(particles, ray, slicing, albedo, light, &Glow::NONE)
}

/// [`sheet_buffer`] with the wave's `glow` along the ray as an emitter inside the medium (docs/METHOD.md section 9):
/// the glow in front of the slabs comes through whole, the glow within a slab is dimmed by what lies in front of
/// it and, spread evenly over the slab, by `(1 - exp(-tau)) / tau` of its own optical depth, the glow behind
/// them by their transmittance. Without particles it is the glow's integral itself.
pub fn sheet_buffer_glowing(
    particles: &[Particle],
    ray: &Ray,
    slicing: &Slicing,
    albedo: f64,
    light: impl Fn(DVec3) -> [f64; 3],
    glow: &Glow,
) -> Composite {
    // The sheet buffer along this ray: each slab's optical depth and its color weighed by it.
    let mut depth = vec![0.0; slicing.count as usize];
    let mut colored = vec![DVec3::ZERO; slicing.count as usize];
    let mut emitting = vec![DVec3::ZERO; slicing.count as usize];
    let facing = ray.direction.dot(slicing.axis) > 0.0 && slicing.count > 0;
    if !facing {
        return Composite {
            radiance: glow.between(f64::NEG_INFINITY, f64::INFINITY).to_array(),
            transmittance: 1.0,
        };
    }
    for p in particles {
        let Some((t_in, t_out)) = p.chord(ray) else {
            continue;
        };
        for j in slicing.slabs_between(ray, t_in, t_out) {
            let (t0, t1) = slicing.slab(ray, j);
            let tau = p.optical_depth(ray, t0.max(t_in), t1.min(t_out));
            depth[j as usize] += tau;
            colored[j as usize] += tau * DVec3::from_array(p.color);
            emitting[j as usize] += tau * DVec3::from_array(p.emission);
        }
    }
    let mut radiance = glow.between(f64::NEG_INFINITY, slicing.slab(ray, 0).0);
    let mut transmittance = 1.0;
    let slabs = depth.iter().zip(&colored).zip(&emitting);
    for (j, ((&tau, &colored), &emitting)) in (0..slicing.count).zip(slabs) {
        let (t0, t1) = slicing.slab(ray, j);
        let emitted = glow.between(t0, t1);
        if tau <= 0.0 {
            radiance += transmittance * emitted;
            continue;
        }
        let lit = DVec3::from_array(light(ray.at(0.5 * (t0 + t1))));
        let opacity = -(-tau).exp_m1();
        radiance += transmittance
            * ((albedo * colored * lit + emitting) / tau * opacity + emitted * opacity / tau);
        transmittance *= (-tau).exp();
    }
    radiance += transmittance * glow.between(slicing.slab(ray, slicing.count - 1).1, f64::INFINITY);
    Composite {
        radiance: radiance.to_array(),
        transmittance,
    }
}

/// The same medium ray-marched in `steps` equal steps over the particles' span on `ray`: at each step's middle
/// the extinction and the extinction-weighted color summed from the kernels, the step a layer of them. What
/// [`sheet_buffer`] converges to as its slabs thin.
pub fn marched(
    particles: &[Particle],
    ray: &Ray,
    albedo: f64,
    light: impl Fn(DVec3) -> [f64; 3],
    steps: u32,
) -> Composite {
    marched_glowing(
        particles,
        ray,
        albedo,
        light,
        (&|_| [0.0; 3], 0.0, 0.0),
        steps,
    )
}

/// [`marched`] with a glow along the ray, `(density, start, end)`: its light per unit length at t, on
/// `[start, end]`, emitted at each step's middle and dimmed by the medium in front and, over the step, by its
/// own layer; the particles' own emission alike, summed from their kernels. What [`sheet_buffer_glowing`]
/// converges to.
pub fn marched_glowing(
    particles: &[Particle],
    ray: &Ray,
    albedo: f64,
    light: impl Fn(DVec3) -> [f64; 3],
    (glow, glow_start, glow_end): (&dyn Fn(f64) -> [f64; 3], f64, f64),
    steps: u32,
) -> Composite {
    let chords = particles.iter().filter_map(|p| p.chord(ray));
    let (mut start, mut end) = chords.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
        (a.min(c.0.max(0.0)), b.max(c.1))
    });
    if glow_end > glow_start {
        (start, end) = (start.min(glow_start), end.max(glow_end));
    }
    let (mut radiance, mut transmittance) = (DVec3::ZERO, 1.0);
    if end <= start {
        return Composite {
            radiance: [0.0; 3],
            transmittance,
        };
    }
    let dt = (end - start) / steps as f64;
    for k in 0..steps {
        let t = start + (k as f64 + 0.5) * dt;
        let x = ray.at(t);
        let emitted = if (glow_start..glow_end).contains(&t) {
            DVec3::from_array(glow(t)) * dt
        } else {
            DVec3::ZERO
        };
        let sigma = extinction(particles, x);
        if sigma <= 0.0 {
            radiance += transmittance * emitted;
            continue;
        }
        let weighed = |of: &dyn Fn(&Particle) -> [f64; 3]| -> DVec3 {
            (particles.iter())
                .map(|p| {
                    p.density
                        * kernel((x - p.position).length() / p.radius)
                        * DVec3::from_array(of(p))
                })
                .sum::<DVec3>()
                / sigma
        };
        let (color, emission) = (weighed(&|p| p.color), weighed(&|p| p.emission));
        let lit = DVec3::from_array(light(x));
        let opacity = -(-sigma * dt).exp_m1();
        radiance += transmittance
            * ((albedo * color * lit + emission) * opacity + emitted * opacity / (sigma * dt));
        transmittance *= (-sigma * dt).exp();
    }
    Composite {
        radiance: radiance.to_array(),
        transmittance,
    }
}

/// One pixel of a frame's smoke, as the GPU pass renders it (`gpu::particle_pass`, docs/METHOD.md section 9): the
/// sheet buffer along `ray` over `slicing`, each segment scattering its particle's color times the light that
/// particle scatters back along the ray (`lights[k]`, `particles::light`) and giving off its emission, the slabs
/// whose front lies at or past `until` (the depth along the view axis of the first object on the ray; infinite
/// for none) left out and the slab it lies in cut there (the smoke in front of a surface integrated up to the
/// surface itself), and those past where the light through the pixel falls below
/// `particles::TRANSMITTANCE_CUTOFF`. The glow lies along the ray as `glow` places it (`particles::view`), up to
/// `until`; the smoke past a translucent surface the ray meets first (`glass`) is seen through the objects. The
/// pixel is returned as the two images the frame composes, the front one over the glow and the back one under it
/// ([`SmokeLayers::images`]).
pub fn smoke_pixel(
    particles: &[Particle],
    lights: &[crate::particles::light::ParticleLight],
    ray: &Ray,
    slicing: &Slicing,
    (until, glass): (f64, Option<Glass>),
    glow: &GlowDepths,
) -> [Composite; 2] {
    smoke_layers(particles, lights, ray, slicing, (until, glass), glow).images()
}

/// A translucent surface a pixel's ray meets first: its depth along the view axis, and the light the translucent
/// objects let through to what lies behind them on the ray (`objects::clip::crossings`' share behind: the Fresnel
/// transmittance at every surface crossed, `exp(-tau)` between).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    pub depth: f64,
    pub behind: f64,
}

/// The smoke along a pixel's ray with the glow spread through its slabs (docs/METHOD.md section 9): what the frame
/// of the glow `B` (the field's integral along the ray, of color `Ce`) over what lies behind, `X`, is,
/// `S - B occluded + B seen Ce + (1 - B) transmittance X` before the billboard's clamp, linear in B so that the
/// smoke is worked out once for every field the viewer refines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmokeLayers {
    /// The light the smoke scatters and gives off toward the eye, each slab's dimmed by the slabs in front.
    pub radiance: DVec3,
    /// Each slab's share of `radiance` times the share of the glow in front of it: what the glow's blend
    /// covers (the method's `(1 - B)` over what lies behind the glow).
    pub occluded: DVec3,
    /// The share of the glow that comes through the smoke: each part of it dimmed by the slabs in front, and
    /// within its own slab by `(1 - exp(-tau)) / tau` (at least `transmittance` and `SEEN_FLOOR`).
    pub seen: f64,
    /// The light through all of the smoke.
    pub transmittance: f64,
}

/// The least share of the glow a pixel's front image passes (`SmokeLayers::images`): the back image is divided
/// by it (a glow seen less than this is off by at most this share of it).
pub const SEEN_FLOOR: f64 = 1e-4;

impl SmokeLayers {
    /// The two images the frame composes as before the glow was spread, front over `blend(B, back over X)`:
    /// front `(radiance - occluded, seen)`, back `(occluded / seen, transmittance / seen)`. Front over back is
    /// the whole smoke, and with all of the glow at one depth they are the slabs in front of it and those behind.
    pub fn images(&self) -> [Composite; 2] {
        let seen = self.seen.max(self.transmittance).max(SEEN_FLOOR);
        [
            Composite {
                radiance: (self.radiance - self.occluded).to_array(),
                transmittance: seen,
            },
            Composite {
                radiance: (self.occluded / seen).to_array(),
                transmittance: self.transmittance / seen,
            },
        ]
    }
}

/// `1 - (1 - exp(-tau)) / tau`: the share of a light spread evenly through a slab of optical depth `tau` that the
/// slab itself holds back (a series where it cancels).
pub fn held_within(tau: f64) -> f64 {
    if tau < 1e-3 {
        tau * (0.5 - tau / 6.0)
    } else {
        1.0 + (-tau).exp_m1() / tau
    }
}

/// [`smoke_pixel`]'s smoke before it is made the two images. Past a translucent surface (`glass`, docs/METHOD.md
/// section 10) the slabs are seen through the objects: a particle's part is cut at the surface as at an opaque
/// one, and the slabs past it add their light dimmed by the light the objects let through and by the slabs in
/// front (and among themselves), covered by the glow as the surface is, dimming neither the surface (drawn in
/// front of them) nor the glow (the see-through pass's, worked out without the smoke).
pub fn smoke_layers(
    particles: &[Particle],
    lights: &[crate::particles::light::ParticleLight],
    ray: &Ray,
    slicing: &Slicing,
    (until, glass): (f64, Option<Glass>),
    glow: &GlowDepths,
) -> SmokeLayers {
    let (glass_at, behind) = glass.map_or((f64::INFINITY, 1.0), |g| (g.depth, g.behind));
    let mut depth = vec![0.0; slicing.count as usize];
    let mut colored = vec![DVec3::ZERO; slicing.count as usize];
    let toward_eye = -ray.direction;
    let along = ray.direction.dot(slicing.axis);
    // The surface ends the smoke where it lies, inside its slab (the slab's part in front of it kept); a
    // translucent one cuts the slab it lies in there.
    let t_of = |d: f64| {
        if along > 0.0 {
            d / along
        } else {
            f64::INFINITY
        }
    };
    let (t_until, t_glass) = (t_of(until), t_of(glass_at));
    for (p, light) in particles.iter().zip(lights) {
        let Some((t_in, t_out)) = p.chord(ray) else {
            continue;
        };
        let lit = DVec3::from_array(p.color) * DVec3::from_array(light.toward(toward_eye))
            + DVec3::from_array(p.emission);
        for j in slicing.slabs_between(ray, t_in, t_out) {
            let (t0, t1) = slicing.slab(ray, j);
            let (a, mut b) = (t0.max(t_in), t1.min(t_out).min(t_until));
            if slicing.near + j as f64 * slicing.width < glass_at {
                b = b.min(t_glass);
            }
            if b <= a {
                continue;
            }
            let tau = p.optical_depth(ray, a, b);
            depth[j as usize] += tau;
            colored[j as usize] += tau * lit;
        }
    }
    // The glow's share in front of a depth, of the glow up to the surface (the field pass integrates no further);
    // all of it in front where none lies before the surface.
    let whole = if until.is_finite() {
        glow_before(glow, until)
    } else {
        1.0
    };
    let before = |d: f64| {
        if whole > 0.0 {
            (glow_before(glow, d.min(until)) / whole).min(1.0)
        } else {
            1.0
        }
    };
    let mut layers = SmokeLayers {
        radiance: DVec3::ZERO,
        occluded: DVec3::ZERO,
        seen: 1.0,
        transmittance: 1.0,
    };
    // The light through the slabs past the translucent surface, among themselves.
    let mut glassed = 1.0;
    for (j, (&tau, &colored)) in depth.iter().zip(&colored).enumerate() {
        let front = slicing.near + j as f64 * slicing.width;
        if front >= until || along <= 0.0 {
            break;
        }
        if tau <= 0.0 {
            continue;
        }
        if front >= glass_at {
            let light = layers.transmittance * glassed * behind * colored / tau * -(-tau).exp_m1();
            layers.radiance += light;
            layers.occluded += light;
            glassed *= (-tau).exp();
            if glassed < crate::particles::TRANSMITTANCE_CUTOFF {
                break;
            }
            continue;
        }
        let (f0, f1) = (before(front), before(front + slicing.width));
        let t = layers.transmittance;
        let opacity = -(-tau).exp_m1();
        let light = t * colored / tau * opacity;
        layers.radiance += light;
        layers.occluded += light * 0.5 * (f0 + f1);
        // The glow behind the slab loses its opacity; the glow within it, spread evenly, what it holds back.
        layers.seen -= t * ((1.0 - f1) * opacity + (f1 - f0) * held_within(tau));
        layers.transmittance *= (-tau).exp();
        if layers.transmittance < crate::particles::TRANSMITTANCE_CUTOFF {
            break;
        }
    }
    // No less than the light through all of it (rounding), nor than the floor the back image is divided by.
    layers.seen = layers.seen.max(layers.transmittance).max(SEEN_FLOOR);
    layers
}

/// A frame's smoke as the GPU pass renders it (`gpu::particle_pass`): the image over its plan, each pixel's smoke
/// (`smoke_layers`), and the frame it lies over.
pub struct SmokeImage {
    pub view: crate::particles::view::SmokeView,
    pub pixels: Vec<SmokeLayers>,
    frame: [u32; 2],
}

impl SmokeImage {
    /// The smoke of `setup`'s frame of `frame` pixels over a field of `resolution` texels a side, none without
    /// particles; `until(x, y)` is the depth along the view axis of the first opaque object on the ray of frame
    /// pixel `(x, y)` (infinite for none), which ends the rays of the smoke's pixels that fall in it, and the
    /// translucent surface the ray meets first, where one does.
    pub fn of(
        setup: &crate::frame::FrameSetup,
        frame: [u32; 2],
        resolution: u32,
        until: impl Fn(u32, u32) -> (f64, Option<Glass>) + Sync,
    ) -> Option<SmokeImage> {
        use rayon::prelude::*;
        let lit = setup.particles()?;
        let view = setup.smoke_view(&lit.particles, frame, resolution);
        let [w, h] = view.size;
        let pixels = (0..w * h)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % w, k / w);
                let at = |c: u32, n: u32, f: u32| {
                    (((c as f64 + 0.5) * f as f64 / n as f64) as u32).min(f - 1)
                };
                let ends = until(at(x, w, frame[0]), at(y, h, frame[1]));
                smoke_layers(
                    &lit.particles,
                    &lit.lights,
                    &view.ray(x, y),
                    &view.slicing,
                    ends,
                    &view.glow_at(x, y),
                )
            })
            .collect();
        Some(SmokeImage {
            view,
            pixels,
            frame,
        })
    }

    /// The front and back images at frame pixel `(x, y)`, `[radiance, transmittance]` each, as the GPU's draw
    /// makes them: the smoke's sums bilinear between the smoke's pixel centers, then made the two images
    /// ([`SmokeLayers::images`]; filtered after, the back image's division by the glow's share would carry a
    /// dense pixel's light onto its neighbours).
    pub fn at(&self, x: u32, y: u32) -> [[f64; 4]; 2] {
        let [w, h] = self.view.size;
        let g = [
            (x as f64 + 0.5) * w as f64 / self.frame[0] as f64 - 0.5,
            (y as f64 + 0.5) * h as f64 / self.frame[1] as f64 - 0.5,
        ];
        let i0 = [g[0].floor(), g[1].floor()];
        let f = [g[0] - i0[0], g[1] - i0[1]];
        let px = |dx: f64, dy: f64| {
            let cx = (i0[0] + dx).clamp(0.0, w as f64 - 1.0) as u32;
            let cy = (i0[1] + dy).clamp(0.0, h as f64 - 1.0) as u32;
            self.pixels[(cy * w + cx) as usize]
        };
        let mix = |a: SmokeLayers, b: SmokeLayers, t: f64| SmokeLayers {
            radiance: a.radiance.lerp(b.radiance, t),
            occluded: a.occluded.lerp(b.occluded, t),
            seen: a.seen + (b.seen - a.seen) * t,
            transmittance: a.transmittance + (b.transmittance - a.transmittance) * t,
        };
        let top = mix(px(0.0, 0.0), px(1.0, 0.0), f[0]);
        let bottom = mix(px(0.0, 1.0), px(1.0, 1.0), f[0]);
        mix(top, bottom, f[1]).images().map(|c| {
            let [r, g, b] = c.radiance;
            [r, g, b, c.transmittance]
        })
    }
}

/// `smoke` ([radiance, transmittance]) laid over `under` (RGBA, premultiplied), as the GPU's premultiplied blend.
pub fn smoke_over(smoke: [f64; 4], under: [f64; 4]) -> [f64; 4] {
    let t = smoke[3];
    [
        smoke[0] + t * under[0],
        smoke[1] + t * under[1],
        smoke[2] + t * under[2],
        (1.0 - t) + t * under[3],
    ]
}

/// The medium of [`smoke_pixel`] ray-marched in `steps` equal steps over the particles' span on `ray`: at each
/// step's middle the extinction and, weighed by it, each particle's color times the light it scatters back
/// along the ray (`lights`) plus its emission, the step a layer of them. What `smoke_pixel`'s two images, the front one over the
/// back, converge to as its slabs thin.
pub fn marched_lit(
    particles: &[Particle],
    lights: &[crate::particles::light::ParticleLight],
    ray: &Ray,
    steps: u32,
) -> Composite {
    let toward_eye = -ray.direction;
    let lit: Vec<DVec3> = (particles.iter().zip(lights))
        .map(|(p, l)| {
            DVec3::from_array(p.color) * DVec3::from_array(l.toward(toward_eye))
                + DVec3::from_array(p.emission)
        })
        .collect();
    let chords = particles.iter().filter_map(|p| p.chord(ray));
    let (start, end) = chords.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
        (a.min(c.0.max(0.0)), b.max(c.1))
    });
    let (mut radiance, mut transmittance) = (DVec3::ZERO, 1.0);
    if end > start {
        let dt = (end - start) / steps as f64;
        for k in 0..steps {
            let x = ray.at(start + (k as f64 + 0.5) * dt);
            let (mut sigma, mut colored) = (0.0, DVec3::ZERO);
            for (p, c) in particles.iter().zip(&lit) {
                let s = p.density * kernel((x - p.position).length() / p.radius);
                sigma += s;
                colored += s * *c;
            }
            if sigma > 0.0 {
                let opacity = -(-sigma * dt).exp_m1();
                radiance += transmittance * colored / sigma * opacity;
                transmittance *= (-sigma * dt).exp();
            }
        }
    }
    Composite {
        radiance: radiance.to_array(),
        transmittance,
    }
}
