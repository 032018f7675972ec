//! How the wave lights the objects: every source is a light at the point of it that its term reads from the
//! surface (a point's position, a line's or a ring's nearest point, a curve's nearest or brightest point), of
//! the source's color, whose strength there is the source's own term of psi: `psi_i(X) = b_i W / max(eps, d)`.
//!
//! Why that falloff: the method's field is what the artist sees glow; lighting with it makes a surface exactly
//! as bright as the glow's energy at it (twice the coefficient, twice the light; the same eps keeps a surface
//! through a source finite), and a long source lights like the line light it is (1 / d) rather than a point
//! light (1 / d^2) squeezed onto its nearest point. Lambert's cosine with the direction to that point, a
//! shadow where other objects hide the source (a translucent one dims it by the light it lets through:
//! `objects::passes`), and a small ambient term so that unlit sides keep their shape:
//!
//! `L(X) = albedo * (AMBIENT + sum_i Ce_i psi_i(X) max(0, n . l_i) V_i(X))`.
//!
//! The shadow is as soft as the source is long. A line's 1 / d is the sum of inverse-square lights along it
//! (`integral ds / (d^2 + s^2) = pi / d`), so the share of the source that X sees is that sum over the points
//! X sees: `V_i(X) = integral vis(X, s) w(s) ds / integral w(s) ds`, `w = W(s) / |X - s|^2` (`visibility`).
//! A point's shadow is hard (V is 0 or 1), a line's, a ring's and a curve's soften with their extent as seen
//! from X.
//!
//! Shading is per pixel. The shadows, which need rays against every object, are worked out in f64 at the
//! vertices of the objects' triangles (`tessellate`, split where a shadow's edge crosses them) as the share
//! `S = sum_i Ce_i psi_i cos_i V_i / sum_i Ce_i psi_i cos_i` of the direct light they leave (`Shade::shadow`),
//! and interpolated; the direct light itself, which peaks sharply under a source, is evaluated at every
//! pixel's own point with its interpolated normal (`Lights::direct`; on the GPU by the field's functions in
//! `shaders/objects.wgsl`): `L(X) = albedo (AMBIENT + S direct(X))` (`shaded`), exact wherever no shadow falls.
//! Sources of negative coefficient darken what they light; their light is summed apart, with a factor of its
//! own, so that each factor is a share in 0..1 and every vertex is exact whatever the signs.

use glam::DVec3;
use rayon::prelude::*;

use super::tessellate::Surface;
use super::{Object, Shape};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::field::{Palette, Sources, brightest, curve, wseries};

/// The light every surface gets whatever the sources: a share of its albedo.
pub const AMBIENT: f64 = 0.06;

/// A source seen from a surface point: where its light comes from, its strength there (the source's term of
/// psi) and its color.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub from: DVec3,
    pub strength: f64,
    pub color: [f64; 3],
}

/// The sources' light at a surface point (`Lights::shade`), before the albedo and the ambient term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shade {
    /// Every source's light, unshadowed: `sum_i Ce_i psi_i max(0, n . l_i)` (`Lights::direct`), the sources of
    /// positive coefficient's, then the negative's.
    pub direct: Split,
    /// What of it the objects' shadows leave: each term times its source's visibility `V_i`.
    pub seen: Split,
    /// Which sources are hidden there, and how much: where the masks of neighbouring vertices differ, a
    /// shadow's edge crosses between them.
    pub mask: u64,
}

/// A light in rgb split by the sign of the sources' coefficients: the positive's (`[0]`), then the
/// negative's (`[1]`, which darken).
pub type Split = [[f64; 3]; 2];

impl Shade {
    /// The share of the direct light that the shadows leave, channel by channel, of each sign (1 where there is
    /// no such light): what the vertices carry, interpolated and multiplied by the direct light at every pixel.
    pub fn shadow(&self) -> Split {
        std::array::from_fn(|s| {
            std::array::from_fn(|c| match self.direct[s][c] != 0.0 {
                true => (self.seen[s][c] / self.direct[s][c]).clamp(0.0, 1.0),
                false => 1.0,
            })
        })
    }
}

/// The lit color of a surface point of `albedo`, shadow factors `shadow` (`Shade::shadow`) and direct light
/// `direct` (`Lights::direct`): `albedo (AMBIENT + shadow direct)`, each sign's part by its factor, unclamped
/// (an HDR export keeps it, the display clamps it). `shaders/objects.wgsl` shades every pixel by the same
/// formula.
pub fn shaded(albedo: [f64; 3], shadow: Split, direct: Split) -> [f64; 3] {
    std::array::from_fn(|c| {
        albedo[c] * (AMBIENT + shadow[0][c] * direct[0][c] + shadow[1][c] * direct[1][c])
    })
}

/// Lambert's cosine at `x` (normal `n`) of the light from `from`; 1 at the source itself, where the light
/// comes from every side.
fn cosine(x: DVec3, n: DVec3, from: DVec3) -> f64 {
    let to = from - x;
    let d = to.length();
    if d > 0.0 { n.dot(to / d).max(0.0) } else { 1.0 }
}

/// Every source as a light, prepared once for many surface points.
pub struct Lights {
    sources: Sources,
    palette: Palette,
    pieces: Vec<Vec<brightest::Piece>>,
    epsilon: f64,
    /// A sphere holding each term's source, where it is extended and bounded (a ring, a curve): a surface
    /// point no object can come between it and sees all of it.
    bounds: Vec<Option<(DVec3, f64)>>,
}

impl Lights {
    pub fn new(sources: &Sources, palette: Palette, epsilon: f64) -> Self {
        let points = sources.points.iter().map(|_| None);
        let lines = sources.lines.iter().map(|_| None);
        let tori = (sources.tori.iter()).map(|t| Some((t.center, t.major_radius)));
        // A Bezier chain lies in its control points' hull.
        let curves = sources.curves.iter().map(|c| {
            let lo = c
                .control_points
                .iter()
                .fold(DVec3::INFINITY, |a, &p| a.min(p));
            let hi = c
                .control_points
                .iter()
                .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
            Some(((lo + hi) * 0.5, (hi - lo).length() * 0.5))
        });
        Lights {
            sources: sources.clone(),
            palette,
            pieces: sources.curves.iter().map(|c| c.pieces()).collect(),
            epsilon,
            bounds: points.chain(lines).chain(tori).chain(curves).collect(),
        }
    }

    /// Every source's light at `x`, in the order of the field's terms.
    pub fn at(&self, x: DVec3) -> impl Iterator<Item = LightSample> + '_ {
        let s = &self.sources;
        let eps = self.epsilon;
        let c = &self.palette;
        let points = s.points.iter().map(move |p| LightSample {
            from: p.position,
            strength: p.field(x, eps),
            color: c.color_of(&p.look),
        });
        let lines = s.lines.iter().map(move |l| LightSample {
            from: l.point + l.direction * (x - l.point).dot(l.direction),
            strength: l.field(x, eps),
            color: c.color_of(&l.look),
        });
        let tori = s.tori.iter().map(move |t| {
            let q = x - t.center;
            let across = q - t.axis * q.dot(t.axis);
            // On the axis every point of the ring is nearest: any will do.
            let radial = across
                .try_normalize()
                .unwrap_or_else(|| t.axis.any_orthonormal_vector());
            LightSample {
                from: t.center + radial * t.major_radius,
                strength: t.field(x, eps),
                color: c.color_of(&t.look),
            }
        });
        let curves = s.curves.iter().zip(&self.pieces).map(move |(k, pieces)| {
            let seen = k.point_seen(pieces, x, eps);
            LightSample {
                from: curve::chain_frame(&k.control_points, seen.t).0,
                strength: k.term_at(seen, eps),
                color: c.color_along(k, seen.t),
            }
        });
        points.chain(lines).chain(tori).chain(curves)
    }

    /// The light reaching the surface point `x` of normal `n` (unit), shadows by `objects`, before the albedo:
    /// `AMBIENT + sum_i Ce_i psi_i max(0, n . l_i) V_i`.
    pub fn irradiance(&self, objects: &[Object], x: DVec3, n: DVec3) -> [f64; 3] {
        let seen = self.shade(objects, x, n).seen;
        std::array::from_fn(|c| AMBIENT + seen[0][c] + seen[1][c])
    }

    /// Every source's direct light at `x` on a surface of normal `n` (unit, or zero for none), no shadows, no
    /// ambient: `sum_i Ce_i psi_i max(0, n . l_i)`, what the object pass evaluates at every pixel; the sources
    /// of positive coefficient apart from the negative's.
    pub fn direct(&self, x: DVec3, n: DVec3) -> Split {
        let mut e = [[0.0; 3]; 2];
        for light in self.at(x) {
            let lambert = light.strength * cosine(x, n, light.from);
            let e = &mut e[(lambert < 0.0) as usize];
            for (c, e) in e.iter_mut().enumerate() {
                *e += light.color[c] * lambert;
            }
        }
        e
    }

    /// The direct light at `x` (normal `n`) with and without the shadows of `objects`, and which sources they
    /// hide there.
    pub fn shade(&self, objects: &[Object], x: DVec3, n: DVec3) -> Shade {
        let mut out = Shade {
            direct: [[0.0; 3]; 2],
            seen: [[0.0; 3]; 2],
            mask: 0,
        };
        for (k, light) in self.at(x).enumerate() {
            let lambert = light.strength * cosine(x, n, light.from);
            if lambert == 0.0 {
                continue;
            }
            let seen = self.visibility(objects, x, n, k, light.from);
            if seen < 1.0 {
                // The shadow's signature: which sources are hidden, and how much, in eighths, so that a
                // triangle across a penumbra is refined as one across a hard edge.
                let level = (8.0 * (1.0 - seen)).ceil() as u64;
                out.mask = out.mask.rotate_left(5) ^ (level << (k % 8 * 4)) ^ (k as u64 + 1);
            }
            let sign = (lambert < 0.0) as usize;
            for c in 0..3 {
                out.direct[sign][c] += light.color[c] * lambert;
                out.seen[sign][c] += light.color[c] * lambert * seen;
            }
        }
        out
    }

    /// The share `V` of term `k`'s source that `x` (on a surface of normal `n`) sees past `objects` (1 unhidden,
    /// 0 in full shadow): the inverse-square weights of its points that reach `x` over those of all its points
    /// above the surface's tangent plane (the module's formula; the cosine with the nearest point accounts for
    /// the horizon, so a sphere does not shadow itself), each point's light stopped by an opaque object and
    /// dimmed by the translucent ones it crosses (`objects::passes`), by `SOFT_SAMPLES` stratified samples of the
    /// source, after `PROBES` of them agree or not. A point's light comes from `nearest` alone.
    pub fn visibility(
        &self,
        objects: &[Object],
        x: DVec3,
        n: DVec3,
        k: usize,
        nearest: DVec3,
    ) -> f64 {
        self.share_past(objects, x, Some(n), k, nearest)
    }

    /// The share of term `k`'s light that reaches `x` (a point in a medium, on no surface) past `objects`:
    /// `visibility` over all of the source's points (no horizon). What lights a particle.
    pub fn passing(&self, objects: &[Object], x: DVec3, k: usize, nearest: DVec3) -> f64 {
        self.share_past(objects, x, None, k, nearest)
    }

    fn share_past(
        &self,
        objects: &[Object],
        x: DVec3,
        horizon: Option<DVec3>,
        k: usize,
        nearest: DVec3,
    ) -> f64 {
        if objects.is_empty() {
            return 1.0;
        }
        if let Some(Some(bound)) = self.bounds.get(k)
            && !objects.iter().any(|o| may_come_between(o, x, *bound))
        {
            return 1.0;
        }
        let above = |points: Vec<(DVec3, f64)>| -> Vec<(DVec3, f64)> {
            match horizon {
                Some(n) => (points.into_iter())
                    .filter(|(p, _)| n.dot(*p - x) > 0.0)
                    .collect(),
                None => points,
            }
        };
        let samples = |count: usize| self.extent_samples(x, k, count).map(above);
        let near = super::passes(objects, nearest, x);
        let Some(probes) = samples(PROBES) else {
            return near;
        };
        // All alike, and the nearest point too: no penumbra here (a shadow narrower than the probes' spacing
        // slips through, as a hard shadow's edge between vertices did). A probe of no weight (a curve's weight
        // series at 0 there) decides nothing.
        let agree = |&(p, w): &(DVec3, f64)| {
            w == 0.0 || (super::passes(objects, p, x) - near).abs() <= 1e-12
        };
        if probes.iter().all(agree) {
            return near;
        }
        let all = samples(SOFT_SAMPLES).expect("an extended source");
        let (s, t) = all.iter().fold((0.0, 0.0), |(s, t), &(p, w)| {
            (s + w * super::passes(objects, p, x), t + w)
        });
        match t > 0.0 {
            true => s / t,
            // Nothing of it above the horizon: the nearest point decides (its cosine is about 0 anyway).
            false => near,
        }
    }

    /// `n` stratified points of term `k`'s source with their weights `W / |x - p|^2` (times the measure of the
    /// stratum), or `None` for a point, which has no extent.
    fn extent_samples(&self, x: DVec3, k: usize, n: usize) -> Option<Vec<(DVec3, f64)>> {
        let s = &self.sources;
        let mut k = k;
        if k < s.points.len() {
            return None;
        }
        k -= s.points.len();
        if let Some(l) = s.lines.get(k) {
            // s = d tan(theta): the weight ds / (d^2 + s^2) is d theta / d, uniform in theta.
            let foot = l.point + l.direction * (x - l.point).dot(l.direction);
            let d = (x - foot).length().max(self.epsilon);
            return Some(
                (0..n)
                    .map(|j| {
                        let theta = -FRAC_PI_2 + (j as f64 + 0.5) * PI / n as f64;
                        (foot + l.direction * d * theta.tan(), 1.0)
                    })
                    .collect(),
            );
        }
        k -= s.lines.len();
        if let Some(t) = s.tori.get(k) {
            let e1 = t.axis.any_orthonormal_vector();
            let e2 = t.axis.cross(e1);
            return Some(
                (0..n)
                    .map(|j| {
                        let a = (j as f64 + 0.5) * TAU / n as f64;
                        let p = t.center + t.major_radius * (a.cos() * e1 + a.sin() * e2);
                        (
                            p,
                            1.0 / (x - p).length_squared().max(self.epsilon * self.epsilon),
                        )
                    })
                    .collect(),
            );
        }
        k -= s.tori.len();
        let c = s.curves.get(k)?;
        let h = 0.25 / n as f64;
        Some(
            (0..n)
                .map(|j| {
                    let t = (j as f64 + 0.5) / n as f64;
                    let p = curve::chain_frame(&c.control_points, t).0;
                    let speed = (curve::chain_frame(&c.control_points, t + h).0
                        - curve::chain_frame(&c.control_points, t - h).0)
                        .length()
                        / (2.0 * h);
                    let w = if c.weights.is_empty() {
                        1.0
                    } else {
                        wseries::evaluate(&c.weights, t).max(0.0)
                    };
                    (
                        p,
                        w * speed / (x - p).length_squared().max(self.epsilon * self.epsilon),
                    )
                })
                .collect(),
        )
    }
}

/// Whether `object` may cross a segment from `x` to a point of the sphere `(c, r)`: conservatively, by a sphere
/// holding the object (every such segment lies within `r` of the segment from `x` to `c`), or, for an infinite
/// plane, whether the sphere reaches the plane's other side from `x` (from a point on the plane, no segment
/// crosses it). A mesh always may.
fn may_come_between(object: &Object, x: DVec3, (c, r): (DVec3, f64)) -> bool {
    let holding = match &object.shape {
        Shape::Sphere { center, radius } => (*center, *radius),
        Shape::Box { center, size, .. } => (*center, size.length() * 0.5),
        Shape::Plane {
            point,
            size: Some(side),
            ..
        } => (*point, side * std::f64::consts::FRAC_1_SQRT_2),
        Shape::Plane {
            point,
            normal,
            size: None,
        } => {
            let side = normal.dot(x - *point);
            let scale = 1.0 + x.abs().max_element();
            return side.abs() > 1e-9 * scale && normal.dot(c - *point) * side.signum() < r;
        }
        Shape::Mesh(_) => return true,
    };
    let (o, rho) = holding;
    let along = c - x;
    let t = ((o - x).dot(along) / along.length_squared().max(1e-300)).clamp(0.0, 1.0);
    (x + along * t - o).length() <= rho + r
}

/// Samples of an extended source first tried: where they agree with each other and with its nearest point,
/// the whole source is taken as seen (or hidden).
const PROBES: usize = 8;

/// Samples of an extended source where the probes disagree (a penumbra): its visibility to about 1/32.
const SOFT_SAMPLES: usize = 32;

/// How many times a triangle across a shadow's edge is split in four (its vertices' shadows differ): the edge
/// then runs through triangles an eighth of the tessellation's size.
const SHADOW_REFINEMENTS: u32 = 3;

/// Each vertex's light (`light_surface`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexLights {
    /// The albedo: its object's color times its tint.
    pub albedo: Vec<[f64; 3]>,
    /// The share of the direct light the shadows leave, of either sign (`Shade::shadow`).
    pub shadow: Vec<Split>,
    /// The lit color there (`shaded`): what the per-pixel shading gives at the vertex itself (a translucent
    /// object's seen head on).
    pub colors: Vec<[f64; 3]>,
    /// A translucent object's vertex: the light it scatters out before the exit's Fresnel and its tint
    /// (`translucent::light::Scattered::at`); zero on an opaque one.
    pub subsurface: Vec<[f64; 3]>,
    /// A translucent object's relative index of refraction; 0 on an opaque one.
    pub eta: Vec<f64>,
}

/// Lights every vertex of `surface` by `lights`, splitting the triangles a shadow's edge crosses
/// (`SHADOW_REFINEMENTS` times; their edges' midpoints become vertices, lit in turn). `scattered(o, x, n)` is
/// the light translucent object `o` scatters out at its surface point `x` of normal `n`
/// (`translucent::light::Scattered::at`), read at its vertices.
pub fn light_surface(
    surface: &mut Surface,
    objects: &[Object],
    lights: &Lights,
    scattered: &(dyn Fn(usize, DVec3, DVec3) -> [f64; 3] + Sync),
) -> VertexLights {
    let shade = |s: &Surface, range: std::ops::Range<usize>| -> Vec<Shade> {
        range
            .into_par_iter()
            .map(|k| lights.shade(objects, s.positions[k], s.normals[k]))
            .collect()
    };
    let mut shades = shade(surface, 0..surface.positions.len());
    for _ in 0..SHADOW_REFINEMENTS {
        let first_new = surface.positions.len();
        let old = std::mem::take(&mut surface.indices);
        // The edges of the triangles a shadow's edge crosses (their vertices' masks differ), by place: every
        // triangle that has one is split there too (in two or three where it has one or two), so that no vertex
        // lies on another triangle's edge, a T-junction, which the rasterizer shows as a crack of background.
        let mask = |v: u32| shades[v as usize].mask;
        let mut split = std::collections::HashSet::new();
        for t in old.chunks_exact(3) {
            if mask(t[0]) != mask(t[1]) || mask(t[1]) != mask(t[2]) {
                for k in 0..3 {
                    split.insert(edge_key(&surface.positions, t[k], t[(k + 1) % 3]));
                }
            }
        }
        if split.is_empty() {
            surface.indices = old;
            break;
        }
        let mut midpoints = std::collections::HashMap::new();
        let mut indices = Vec::with_capacity(old.len() * 2);
        for t in old.chunks_exact(3) {
            let cut: [bool; 3] = std::array::from_fn(|k| {
                split.contains(&edge_key(&surface.positions, t[k], t[(k + 1) % 3]))
            });
            let mut mid = |p: u32, q: u32| midpoint(surface, &mut midpoints, p, q);
            // The triangle turned so that its corners start at `r`: the winding kept.
            let turned = |r: usize| (t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
            match cut.iter().filter(|&&c| c).count() {
                0 => indices.extend_from_slice(t),
                1 => {
                    let (a, b, c) = turned(cut.iter().position(|&c| c).unwrap());
                    let m = mid(a, b);
                    indices.extend_from_slice(&[a, m, c, m, b, c]);
                }
                2 => {
                    // The uncut edge last, from c to a.
                    let (a, b, c) = turned((cut.iter().position(|&c| !c).unwrap() + 1) % 3);
                    let (ab, bc) = (mid(a, b), mid(b, c));
                    indices.extend_from_slice(&[ab, b, bc, a, ab, bc, a, bc, c]);
                }
                _ => {
                    let (a, b, c) = turned(0);
                    let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                    indices.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
                }
            }
        }
        surface.indices = indices;
        shades.extend(shade(surface, first_new..surface.positions.len()));
    }
    let albedo: Vec<[f64; 3]> = (0..shades.len())
        .map(|k| {
            let color = objects[surface.object[k] as usize].color;
            std::array::from_fn(|c| color[c] * surface.tint[k][c])
        })
        .collect();
    let shadow: Vec<Split> = shades.iter().map(Shade::shadow).collect();
    let eta: Vec<f64> = (surface.object.iter())
        .map(|&o| {
            objects[o as usize]
                .translucent
                .as_ref()
                .map_or(0.0, |t| t.eta)
        })
        .collect();
    let subsurface: Vec<[f64; 3]> = (0..shades.len())
        .into_par_iter()
        .map(|k| match eta[k] > 0.0 {
            true => scattered(
                surface.object[k] as usize,
                surface.positions[k],
                surface.normals[k],
            ),
            false => [0.0; 3],
        })
        .collect();
    let colors = (0..shades.len())
        .map(|k| match eta[k] > 0.0 {
            true => shaded_translucent(albedo[k], subsurface[k], eta[k], 1.0),
            false => shaded(albedo[k], shadow[k], shades[k].direct),
        })
        .collect();
    VertexLights {
        albedo,
        shadow,
        colors,
        subsurface,
        eta,
    }
}

/// The light of `surface`'s vertices before the shadows and the translucent objects' light are worked out: every
/// vertex in the whole direct light (the shader shades each pixel by the sources all the same), no light carried
/// through a translucent object (it shows its ambient part). What the viewer draws for the moment it works out
/// `light_surface` on a thread of its own.
pub fn unshadowed(surface: &Surface, objects: &[Object]) -> VertexLights {
    let n = surface.positions.len();
    let albedo: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            let color = objects[surface.object[k] as usize].color;
            std::array::from_fn(|c| color[c] * surface.tint[k][c])
        })
        .collect();
    let eta: Vec<f64> = (surface.object.iter())
        .map(|&o| (objects[o as usize].translucent.as_ref()).map_or(0.0, |t| t.eta))
        .collect();
    let colors = (0..n)
        .map(|k| match eta[k] > 0.0 {
            true => shaded_translucent(albedo[k], [0.0; 3], eta[k], 1.0),
            false => std::array::from_fn(|c| albedo[k][c] * AMBIENT),
        })
        .collect();
    VertexLights {
        albedo,
        shadow: vec![[[1.0; 3]; 2]; n],
        colors,
        subsurface: vec![[0.0; 3]; n],
        eta,
    }
}

/// The color of a translucent object's surface point of `albedo` (its tint), scattered light `subsurface`
/// (`VertexLights::subsurface`) and index `eta`, seen at `cos_view` to its normal: what leaves through the
/// exit's Fresnel, `albedo F_t(eta, w_out) (AMBIENT + subsurface)` (the ambient light as it scatters through
/// too). `shaders/objects.wgsl` shades every pixel of a translucent object by the same formula.
pub fn shaded_translucent(
    albedo: [f64; 3],
    subsurface: [f64; 3],
    eta: f64,
    cos_view: f64,
) -> [f64; 3] {
    let t = fresnel_transmittance(eta, cos_view);
    std::array::from_fn(|c| albedo[c] * t * (AMBIENT + subsurface[c]))
}

/// An edge by the places of its ends (to 1e-9, in either order): where two grids meet (a box's faces, a
/// sphere's seam) their edges are one, though their vertices are not.
fn edge_key(positions: &[DVec3], p: u32, q: u32) -> ([i64; 3], [i64; 3]) {
    let place = |v: u32| {
        (positions[v as usize] * 1e9)
            .round()
            .to_array()
            .map(|x| x as i64)
    };
    let (a, b) = (place(p), place(q));
    if a <= b { (a, b) } else { (b, a) }
}

/// The vertex halfway along the edge `p`-`q` of `surface` (made once an edge, lit in turn).
fn midpoint(
    surface: &mut Surface,
    midpoints: &mut std::collections::HashMap<(u32, u32), u32>,
    p: u32,
    q: u32,
) -> u32 {
    *midpoints.entry((p.min(q), p.max(q))).or_insert_with(|| {
        let (p, q) = (p as usize, q as usize);
        let position = (surface.positions[p] + surface.positions[q]) * 0.5;
        let normal = (surface.normals[p] + surface.normals[q]).normalize_or(surface.normals[p]);
        surface.positions.push(position);
        surface.normals.push(normal);
        surface.object.push(surface.object[p]);
        surface.tint.push(surface.tint[p]);
        surface.positions.len() as u32 - 1
    })
}

/// The unpolarised Fresnel transmittance `F_t = 1 - F_r` of light crossing, at `cos_outside` (the cosine of its
/// angle to the normal on the outside), into or out of a medium of relative index `eta`: the Fresnel equations,
/// exact (`1 - F_r` with `F_r` the mean of the s and p reflectances), 0 past the critical angle where `eta < 1`.
pub fn fresnel_transmittance(eta: f64, cos_outside: f64) -> f64 {
    let c = cos_outside.abs().min(1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 0.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    let r = 0.5 * (rs * rs + rp * rp);
    (1.0 - r).clamp(0.0, 1.0)
}
