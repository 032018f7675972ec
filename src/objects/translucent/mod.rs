//! Translucent objects lit by the wave: the voxel number map of Mochida, Okamoto, Kubo and Morishima (2016),
//! docs/METHOD.md section 10.
//!
//! Light that reaches a translucent object's surface at `x_in` enters it through the Fresnel transmittance, is
//! carried through the inside, dimmed by the optical thickness `tau = integral of sigma_t` of the straight path,
//! and leaves at `x_out` through the Fresnel transmittance again:
//!
//! `L(x_out, w_out) = (1/pi) F_t(eta, w_out) sum over surface voxels k of E_k A_k exp(-tau(k, out)) / Z_k`,
//! `E_k = sum over sources of F_t(eta, w_in) max(0, N . w_in) I V` (the light as objects are lit: every source's
//! term of psi at the point, of its color, `V` its visibility past every object).
//!
//! - `voxels`: the object voxelised at the user's resolution; its surface voxels numbered, each with its share
//!   `A_k` of the surface's area `A`, its place and its normal; `sigma_t` at every voxel (zero outside and in a
//!   cavity);
//! - `table`: `tau` between every pair of surface voxels, through the voxels (a segment that leaves the object,
//!   crosses a cavity or a concave mesh's outside gathers nothing there), once an object (its shape, place and
//!   material), reused while the lights and the camera change;
//! - `light`: the irradiance of each surface voxel (the poster's irradiance map, read at the voxels themselves:
//!   the wave is not a light with one direction), the sum over the table, and what a surface point of the drawn
//!   triangles reads from the voxels near it;
//! - `reference`: the same model in f64 without voxels or table (fine surface samples, `tau` along exact
//!   segments), and the depth-map estimate it is compared with.
//!
//! The glow is seen through the objects: only opaque objects end the texels' rays, and the glow behind a
//! translucent one is dimmed by `transmittance` along the ray (`gpu::through_pass`, its f64 twin in
//! `reference::field_pass`); the medium is closed (`Medium::holds`).
//!
//! Two readings of ours, said here once. The poster's `R_d = exp(-tau)` has no unit of 1 / area: summed over the
//! surface as given, an object twice the size would glow four times as bright, and the light leaving would
//! exceed what enters. We divide by `Z(x_in) = integral over S of exp(-tau(x_in, x)) dx`, so that the light
//! entering at each point leaves over the surface, most of it where the path inside is thin (`sigma_t` sets how
//! far it travels, a cavity lets it farther): what leaves is what enters, less the exit's Fresnel reflection,
//! times the object's tint (its albedo, the share the inside does not absorb). And a source inside
//! the object lights its surface from within: each surface point gets the source's term there, dimmed by
//! `exp(-tau)` along the straight path from the source's point, and lets it out through `F_t` (no entry).

pub mod light;
pub mod reference;
pub mod table;
pub mod voxels;

pub use crate::objects::lighting::fresnel_transmittance;
use glam::{DMat3, DVec3};

use super::Object;

/// The finest voxel resolution (along the object's longest side) a translucent object gets where its file
/// gives none, coarser where its table would not fit `MAX_TABLE_BYTES`.
pub const DEFAULT_RESOLUTION: u32 = 24;

/// The finest resolution a file may ask for.
pub const MAX_RESOLUTION: u32 = 256;

/// The largest optical-thickness table an object may have (f32, its upper triangle: `N (N + 1) / 2` for `N`
/// surface voxels): 512 MiB, which a GPU's storage binding and this machine's memory both hold.
pub const MAX_TABLE_BYTES: u64 = 512 << 20;

/// A translucent material: how dense the inside is and how light crosses the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Translucent {
    /// The extinction coefficient `sigma_t` inside, per unit of length (0: clear).
    pub extinction: f64,
    /// The relative index of refraction of the inside to the outside (ice 1.31, glass 1.5).
    pub eta: f64,
    /// A region inside of another extinction: a cavity (0), a denser core.
    pub inner: Option<Inner>,
    /// A 3D noise that varies the extinction (ice, cloud).
    pub noise: Option<Noise>,
    /// Voxels along the object's longest side; `None` for `DEFAULT_RESOLUTION` or the finest below it whose
    /// table fits.
    pub resolution: Option<u32>,
}

impl Default for Translucent {
    fn default() -> Self {
        Translucent {
            extinction: 2.0,
            eta: 1.31,
            inner: None,
            noise: None,
            resolution: None,
        }
    }
}

/// A region inside a translucent object with an extinction of its own, placed in the object's frame
/// (`Object::frame`: its center, turned as a box or a mesh turns; a mesh's scale does not apply).
#[derive(Clone, Debug, PartialEq)]
pub struct Inner {
    pub shape: InnerShape,
    pub extinction: f64,
}

/// The shapes of an inner region, their centers relative to the object's.
#[derive(Clone, Debug, PartialEq)]
pub enum InnerShape {
    Sphere { center: DVec3, radius: f64 },
    Box { center: DVec3, size: DVec3 },
}

impl InnerShape {
    pub fn name(&self) -> &'static str {
        match self {
            InnerShape::Sphere { .. } => "sphere",
            InnerShape::Box { .. } => "box",
        }
    }

    /// Whether the point `q` of the object's frame lies inside.
    pub fn contains(&self, q: DVec3) -> bool {
        match self {
            InnerShape::Sphere { center, radius } => {
                (q - *center).length_squared() < radius * radius
            }
            InnerShape::Box { center, size } => (q - *center).abs().cmplt(*size * 0.5).all(),
        }
    }
}

/// A value noise that scales the extinction: `sigma_t (1 + amount n(x / scale))`, `n` in -1..1, at least 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Noise {
    /// The size of the noise's features, in the scene's units.
    pub scale: f64,
    /// How much it varies the extinction: 0 none, 1 from clear to twice as dense.
    pub amount: f64,
    pub seed: u64,
}

/// The extinction of a translucent object at every point of the world: 0 outside it.
#[derive(Clone, Debug)]
pub struct Medium<'a> {
    object: &'a Object,
    material: &'a Translucent,
    center: DVec3,
    /// The object's frame's rotation, transposed: world to frame.
    to_frame: DMat3,
}

impl<'a> Medium<'a> {
    /// `object`'s medium; `None` where it is opaque.
    pub fn of(object: &'a Object) -> Option<Medium<'a>> {
        let material = object.translucent.as_deref()?;
        let (center, rotation) = object.frame();
        Some(Medium {
            object,
            material,
            center,
            to_frame: rotation.transpose(),
        })
    }

    pub fn material(&self) -> &Translucent {
        self.material
    }

    pub fn object(&self) -> &Object {
        self.object
    }

    /// `sigma_t` at `p`.
    pub fn extinction(&self, p: DVec3) -> f64 {
        if !self.object.contains(p) {
            return 0.0;
        }
        self.inside(p)
    }

    /// Whether `p` lies inside the object or on its surface (within `reach`): the medium is closed, so that a
    /// path running along a face, from an entry point to an exit point on the same face, runs through it (as
    /// the light does, just under the surface), not outside.
    pub fn holds(&self, p: DVec3, reach: f64) -> bool {
        self.object.contains(p)
            || DVec3::AXES.iter().any(|a| {
                self.object.contains(p + *a * reach) || self.object.contains(p - *a * reach)
            })
    }

    /// `sigma_t` at `p`, known to be inside the object.
    pub fn inside(&self, p: DVec3) -> f64 {
        let m = self.material;
        let base = match &m.inner {
            Some(inner) if inner.shape.contains(self.to_frame * (p - self.center)) => {
                inner.extinction
            }
            _ => m.extinction,
        };
        match &m.noise {
            Some(n) if base > 0.0 => {
                let (v, _) = crate::noise::noise_with_gradient(p / n.scale, n.seed);
                base * (1.0 + n.amount * v).max(0.0)
            }
            _ => base,
        }
    }

    /// Where along `from + t (to - from)`, t in (0, 1), the object's surface and its inner region's are crossed,
    /// in order: between two of them the medium is one (where it has no noise).
    pub fn crossings(&self, from: DVec3, to: DVec3) -> Vec<f64> {
        let d = to - from;
        let mut out = Vec::new();
        let mut t = 0.0;
        while let Some(next) = self.object.hit(from, d, t, 1.0) {
            out.push(next);
            t = next + 1e-12;
            if out.len() > 10_000 {
                break;
            }
        }
        if let Some(inner) = &self.material.inner {
            let o = self.to_frame * (from - self.center);
            let dd = self.to_frame * d;
            let mut t = 0.0;
            for _ in 0..2 {
                let hit = match &inner.shape {
                    InnerShape::Sphere { center, radius } => {
                        super::sphere_hit(o - *center, dd, *radius, t)
                    }
                    InnerShape::Box { center, size } => {
                        super::box_hit(o - *center, dd, *size * 0.5, t)
                    }
                };
                match hit {
                    Some(x) if x < 1.0 => {
                        out.push(x);
                        t = x + 1e-12;
                    }
                    _ => break,
                }
            }
        }
        out.sort_by(f64::total_cmp);
        out
    }

    /// The optical thickness of the segment `from -> to`, exactly where the medium is piecewise uniform (between
    /// the surfaces `crossings` finds, each piece's extinction read at its middle, the medium closed: `holds`),
    /// and by `steps_per_piece` midpoint samples a piece where a noise varies it: the oracle the voxel table is
    /// checked against.
    pub fn optical_thickness(&self, from: DVec3, to: DVec3, steps_per_piece: usize) -> f64 {
        let length = (to - from).length();
        if length == 0.0 {
            return 0.0;
        }
        let mut cuts = vec![0.0];
        cuts.extend(self.crossings(from, to));
        cuts.push(1.0);
        let at = |t: f64| from + (to - from) * t;
        let mut tau = 0.0;
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b <= a {
                continue;
            }
            let mid = at(0.5 * (a + b));
            let reach = 1e-9 * (1.0 + mid.abs().max_element());
            if !self.holds(mid, reach) {
                continue;
            }
            if self.material.noise.is_none() {
                tau += self.inside(mid) * (b - a) * length;
            } else {
                let n = steps_per_piece.max(1);
                let h = (b - a) / n as f64;
                let sum: f64 = (0..n)
                    .map(|i| self.inside(at(a + (i as f64 + 0.5) * h)))
                    .sum();
                tau += sum * h * length;
            }
        }
        tau
    }
}

/// The outward unit normal of `object`'s surface at its point `p` (a sphere's, a box's face's, a mesh's
/// triangle's nearest `p` along `dir`, the ray that met it there).
fn normal_at(object: &Object, p: DVec3, dir: DVec3) -> DVec3 {
    match &object.shape {
        super::Shape::Sphere { center, .. } => (p - *center).normalize_or(DVec3::Y),
        super::Shape::Box {
            center,
            size,
            rotation,
        } => {
            let r = super::rotation_matrix(*rotation);
            let q = r.transpose() * (p - *center);
            let scaled = q / (*size * 0.5);
            let axis = scaled.abs().max_position();
            let mut n = DVec3::ZERO;
            n[axis] = scaled[axis].signum();
            r * n
        }
        super::Shape::Plane { normal, .. } => *normal,
        super::Shape::Mesh(m) => {
            let (inverse, forward) = m.inverse();
            let o = inverse * (p - m.translation);
            let d = inverse * dir;
            // The triangle the ray meets nearest p: from a little before it.
            // A little before it, by the direction's unit (the segment's length must not move it).
            match m
                .data
                .hit_triangle(o - d * (1e-6 / d.length()), d, 0.0, f64::INFINITY)
            {
                Some((_, k)) => {
                    let t = &m.data.triangles[k];
                    let n = forward.inverse().transpose() * (t[1] - t[0]).cross(t[2] - t[0]);
                    n.normalize_or(DVec3::Y)
                }
                None => -dir.normalize_or(DVec3::Y),
            }
        }
    }
}

/// The share of light that crosses the translucent objects among `objects` along the segment `from -> to`
/// (a texel's ray from the eye to where its glow ends, or a light's path to what it lights): at every surface it
/// crosses, the Fresnel transmittance at its angle there, and `exp(-tau)` wherever it lies in a medium
/// (`Medium::optical_thickness`), an end inside one included. 1 where it meets none.
pub fn transmittance(objects: &[Object], from: DVec3, to: DVec3) -> f64 {
    let d = to - from;
    let mut t = 1.0;
    for o in objects {
        let Some(medium) = Medium::of(o) else {
            continue;
        };
        let hits = {
            let mut out = Vec::new();
            let mut at = 0.0;
            while let Some(next) = o.hit(from, d, at, 1.0) {
                out.push(next);
                at = next + 1e-12;
                if out.len() > 10_000 {
                    break;
                }
            }
            out
        };
        // Crossing no surface, the segment lies wholly outside or wholly inside (an end in the medium: a light
        // or a point lit inside it): its medium dims it there too.
        if hits.is_empty() && !medium.holds(from + d * 0.5, 1e-9 * (1.0 + to.abs().max_element())) {
            continue;
        }
        let eta = medium.material().eta;
        for &h in &hits {
            let p = from + d * h;
            let cos = normal_at(o, p, d).dot(d.normalize()).abs();
            t *= fresnel_transmittance(eta, cos);
        }
        t *= (-medium.optical_thickness(from, to, 64)).exp();
    }
    t
}

/// The translucent objects along a ray `eye + t d`, `t` in `(0, end)`, found once: `transmittance` from the eye
/// to any point of the ray, read off them, is the function's to rounding (the same surfaces, the same pieces,
/// each piece's extinction read where the function reads it), at the cost of a walk instead of every object's
/// surfaces and medium found again; an object whose medium a noise varies is sampled at each point as the
/// function samples it. A texel's crossing reads it at 17 points.
struct Along<'a> {
    /// Each surface crossed: its `t`, its Fresnel transmittance, in no order.
    surfaces: Vec<(f64, f64)>,
    /// Each piece of medium between two surfaces of one object: from `t`, to `t`, `sigma_t |d|` (its optical
    /// thickness per unit of `t`).
    pieces: Vec<[f64; 3]>,
    /// The objects whose medium varies within its pieces (a noise): each point's transmittance through them is
    /// `transmittance`'s own, the factors of the objects apart.
    sampled: Vec<&'a Object>,
    eye: DVec3,
    d: DVec3,
}

impl<'a> Along<'a> {
    fn of(objects: &'a [Object], eye: DVec3, d: DVec3, end: f64) -> Along<'a> {
        let (mut surfaces, mut pieces, mut sampled) = (Vec::new(), Vec::new(), Vec::new());
        let (dir, length) = (d.normalize(), d.length());
        for o in objects {
            let Some(medium) = Medium::of(o) else {
                continue;
            };
            if medium.material().noise.is_some() {
                sampled.push(o);
                continue;
            }
            let from = surfaces.len();
            let mut at = 0.0;
            while let Some(t) = o.hit(eye, d, at, end) {
                let cos = normal_at(o, eye + d * t, d).dot(dir).abs();
                surfaces.push((t, fresnel_transmittance(medium.material().eta, cos)));
                at = t + 1e-12 * end;
                if surfaces.len() - from > 10_000 {
                    break;
                }
            }
            let to = eye + d * end;
            let mut cuts = vec![0.0];
            cuts.extend(medium.crossings(eye, to).into_iter().map(|c| c * end));
            cuts.push(end);
            for w in cuts.windows(2) {
                let (a, b) = (w[0], w[1]);
                if b <= a {
                    continue;
                }
                let mid = eye + d * (0.5 * (a + b));
                let reach = 1e-9 * (1.0 + mid.abs().max_element());
                if medium.holds(mid, reach) {
                    pieces.push([a, b, medium.inside(mid) * length]);
                }
            }
        }
        Along {
            surfaces,
            pieces,
            sampled,
            eye,
            d,
        }
    }

    /// `transmittance` from the eye to `eye + t d`, `t` in `(0, end]`.
    fn transmittance(&self, t: f64) -> f64 {
        let fresnel: f64 = (self.surfaces.iter())
            .filter(|s| s.0 < t)
            .map(|s| s.1)
            .product();
        let tau: f64 = (self.pieces.iter())
            .filter(|p| p[0] < t)
            .map(|p| (p[1].min(t) - p[0]) * p[2])
            .sum();
        let sampled: f64 = (self.sampled.iter())
            .map(|o| transmittance(std::slice::from_ref(*o), self.eye, self.eye + self.d * t))
            .product();
        fresnel * (-tau).exp() * sampled
    }
}

/// How a texel's ray crosses the translucent objects: the ray `eye + t (s - eye)`, its glow from the billboard
/// (`t = 1`) to where it ends (`end`: the first opaque surface, or the ray's end).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// `t` of the last translucent surface crossed before `end`.
    pub exit: f64,
    /// The share of the glow between the first translucent surface (or the billboard, if later) and `exit` that
    /// reaches the eye: the transmittance along the ray averaged over that stretch, weighted by `|psi|` there
    /// (`CROSSING_SAMPLES` midpoints), so that a source inside an object is dimmed by the path from where it
    /// glows, not by the whole crossing.
    pub inside: f64,
    /// The share of the glow past `exit` that reaches the eye (`transmittance` to `end`).
    pub behind: f64,
}

/// Samples of the glow inside the translucent objects along a texel's ray (`Crossing::inside`).
pub const CROSSING_SAMPLES: usize = 16;

/// How the texel ray from `eye` through `s` crosses the translucent objects among `objects` before `end`;
/// `psi` the field, which weighs the glow inside. `None` where it crosses none.
pub fn crossing(
    objects: &[Object],
    eye: DVec3,
    s: DVec3,
    end: f64,
    psi: &dyn Fn(DVec3) -> f64,
) -> Option<Crossing> {
    let d = s - eye;
    let (mut first, mut exit) = (f64::INFINITY, f64::NEG_INFINITY);
    for o in objects.iter().filter(|o| o.translucent.is_some()) {
        let mut at = 0.0;
        let mut n = 0;
        while let Some(t) = o.hit(eye, d, at, end) {
            first = first.min(t);
            exit = exit.max(t);
            at = t + 1e-12 * (1.0 + t);
            n += 1;
            if n > 10_000 {
                break;
            }
        }
    }
    if !exit.is_finite() {
        return None;
    }
    let at = |t: f64| eye + d * t;
    // The surfaces and pieces along the ray found once, the transmittance to each sample read off them.
    let along = Along::of(objects, eye, d, end);
    let through = |t: f64| along.transmittance(t);
    let behind = through(end);
    let (a, b) = (first.max(1.0), exit);
    let inside = if b > a {
        let h = (b - a) / CROSSING_SAMPLES as f64;
        let (mut sum, mut weight) = (0.0, 0.0);
        for i in 0..CROSSING_SAMPLES {
            let t = a + (i as f64 + 0.5) * h;
            let w = psi(at(t)).abs();
            sum += w * through(t);
            weight += w;
        }
        match weight > 0.0 {
            true => sum / weight,
            false => through(0.5 * (a + b)),
        }
    } else {
        behind
    };
    Some(Crossing {
        exit,
        inside,
        behind,
    })
}
