//! How the wave lights the objects: every source is a light at the point of it that its term reads from the
//! surface (a point's position, a line's or a ring's nearest point, a curve's nearest or brightest point), of
//! the source's color, whose strength there is the source's own term of psi: `psi_i(X) = b_i W / max(eps, d)`.
//!
//! Why that falloff: the method's field is what the artist sees glow; lighting with it makes a surface exactly
//! as bright as the glow's energy at it (twice the coefficient, twice the light; the same eps keeps a surface
//! through a source finite), and a long source lights like the line light it is (1 / d) rather than a point
//! light (1 / d^2) squeezed onto its nearest point. Lambert's cosine with the direction to that point, a hard
//! shadow where another object crosses the segment to it, and a small ambient term so that unlit sides keep
//! their shape:
//!
//! `L(X) = albedo * (AMBIENT + sum_i Ce_i psi_i(X) max(0, n . l_i) [X sees its point of source i])`.
//!
//! Evaluated in f64 at the vertices of the objects' triangles (`tessellate`) and interpolated across them.

use glam::DVec3;
use rayon::prelude::*;

use super::tessellate::Surface;
use super::{Object, blocked};
use crate::field::{Sources, brightest, curve};
use crate::scene::Colors;

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

/// Every source as a light, prepared once for many surface points.
pub struct Lights<'a> {
    sources: &'a Sources,
    colors: &'a Colors,
    pieces: Vec<Vec<brightest::Piece>>,
    epsilon: f64,
}

impl<'a> Lights<'a> {
    pub fn new(sources: &'a Sources, colors: &'a Colors, epsilon: f64) -> Self {
        Lights {
            sources,
            colors,
            pieces: sources.curves.iter().map(|c| c.pieces()).collect(),
            epsilon,
        }
    }

    /// Every source's light at `x`, in the order of the field's terms.
    pub fn at(&self, x: DVec3) -> impl Iterator<Item = LightSample> + '_ {
        let s = self.sources;
        let eps = self.epsilon;
        let c = self.colors;
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

    /// The light reaching the surface point `x` of normal `n` (unit), shadows by `objects`, before the albedo.
    pub fn irradiance(&self, objects: &[Object], x: DVec3, n: DVec3) -> [f64; 3] {
        self.shade(objects, x, n).0
    }

    /// `irradiance`, and which sources an object shadows there (bit `k % 64` for term k, where the source
    /// faces the surface): where the shadows of neighbouring vertices differ, a shadow's edge crosses between
    /// them.
    pub fn shade(&self, objects: &[Object], x: DVec3, n: DVec3) -> ([f64; 3], u64) {
        let mut e = [AMBIENT; 3];
        let mut shadowed = 0u64;
        for (k, light) in self.at(x).enumerate() {
            let to = light.from - x;
            let d = to.length();
            // At the source itself the light comes from every side: full strength.
            let cosine = if d > 0.0 { n.dot(to / d).max(0.0) } else { 1.0 };
            if cosine == 0.0 || light.strength == 0.0 {
                continue;
            }
            if blocked(objects, x, light.from) {
                shadowed |= 1 << (k % 64);
                continue;
            }
            for (c, e) in e.iter_mut().enumerate() {
                *e += light.color[c] * light.strength * cosine;
            }
        }
        (e, shadowed)
    }
}

/// How many times a triangle across a shadow's edge is split in four (its vertices' shadows differ): the edge
/// then runs through triangles an eighth of the tessellation's size.
const SHADOW_REFINEMENTS: u32 = 3;

/// Lights every vertex of `surface`, splitting the triangles a shadow's edge crosses (`SHADOW_REFINEMENTS`
/// times; their edges' midpoints become vertices, lit in turn): the lit color of every vertex, the albedo of its
/// object times its irradiance (unclamped: an HDR export keeps it, the display clamps it).
pub fn light_surface(
    surface: &mut Surface,
    objects: &[Object],
    sources: &Sources,
    colors: &Colors,
    epsilon: f64,
) -> Vec<[f64; 3]> {
    let lights = Lights::new(sources, colors, epsilon);
    let shade = |s: &Surface, range: std::ops::Range<usize>| -> Vec<([f64; 3], u64)> {
        range
            .into_par_iter()
            .map(|k| lights.shade(objects, s.positions[k], s.normals[k]))
            .collect()
    };
    let mut shades = shade(surface, 0..surface.positions.len());
    for _ in 0..SHADOW_REFINEMENTS {
        let first_new = surface.positions.len();
        let mut midpoints = std::collections::HashMap::new();
        let mut indices = Vec::with_capacity(surface.indices.len());
        let old = std::mem::take(&mut surface.indices);
        for t in old.chunks_exact(3) {
            let (a, b, c) = (t[0], t[1], t[2]);
            let mask = |v: u32| shades[v as usize].1;
            if mask(a) == mask(b) && mask(b) == mask(c) {
                indices.extend_from_slice(t);
                continue;
            }
            let mut mid = |p: u32, q: u32| -> u32 {
                *midpoints.entry((p.min(q), p.max(q))).or_insert_with(|| {
                    let (p, q) = (p as usize, q as usize);
                    let position = (surface.positions[p] + surface.positions[q]) * 0.5;
                    let normal =
                        (surface.normals[p] + surface.normals[q]).normalize_or(surface.normals[p]);
                    surface.positions.push(position);
                    surface.normals.push(normal);
                    surface.object.push(surface.object[p]);
                    surface.positions.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            indices.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
        }
        surface.indices = indices;
        if surface.positions.len() == first_new {
            break;
        }
        shades.extend(shade(surface, first_new..surface.positions.len()));
    }
    (shades.iter().enumerate())
        .map(|(k, (e, _))| {
            let albedo = objects[surface.object[k] as usize].color;
            [albedo[0] * e[0], albedo[1] * e[1], albedo[2] * e[2]]
        })
        .collect()
}
