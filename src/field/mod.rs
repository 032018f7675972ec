//! The energy field psi: sources, their distance functions and the sum (METHOD.md section 1, thesis 3.1-3.28).
//!
//! This is the f64 reference the GPU passes are checked against; `shaders/shared/field.wgsl` and the field
//! passes mirror it in f32, function for function.

pub mod brightest;
pub mod cubic;
pub mod curve;
pub mod wseries;

pub use brightest::WForm;

use glam::DVec3;

/// How a source's glow is colored: its energy color Ce_i and that color's intensity. Not part of psi (the field
/// and its integrals ignore it): the field pass integrates, beside B = sum B_i, the colored sum sum B_i Ce_i
/// (METHOD.md section 4), and the blend puts that over the background. `None` takes the scene's
/// (`colors.energy`, `colors.energy_intensity`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Look {
    /// Display values in [0, 1], as an artist picks them.
    pub color: Option<[f64; 3]>,
    /// A multiplier of the color, at least 0: above 1 the glow is brighter than a display color can be (HDR),
    /// clamped on screen and kept unclamped in EXR exports.
    pub intensity: Option<f64>,
}

/// The scene's energy color and intensity, which a source without its own look takes: what a source's energy
/// color Ce_i is made of besides its look (`scene::Colors::palette`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Palette {
    pub energy: [f64; 3],
    pub energy_intensity: f64,
}

impl Palette {
    /// A source's energy color Ce_i: its own color and intensity, each the scene's where it has none.
    pub fn color_of(&self, look: &Look) -> [f64; 3] {
        let intensity = self.intensity_of(look);
        look.color.unwrap_or(self.energy).map(|c| c * intensity)
    }

    /// The intensity a source's color (or color series) is multiplied by: its own, or the scene's without one.
    pub fn intensity_of(&self, look: &Look) -> f64 {
        look.intensity.unwrap_or(self.energy_intensity)
    }

    /// A curve's energy color at chain parameter `t`: its color series there times its intensity, or its one
    /// color (`color_of`) without a series.
    pub fn color_along(&self, curve: &Curve, t: f64) -> [f64; 3] {
        if curve.color_series.is_empty() {
            return self.color_of(&curve.look);
        }
        let intensity = self.intensity_of(&curve.look);
        wseries::evaluate_colors(&curve.color_series, t).map(|c| c * intensity)
    }
}

/// A point source (thesis 3.2): `S(P) = 1 / max(eps, |P - M|)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub position: DVec3,
    pub coefficient: f64,
    pub look: Look,
}

/// An infinite line through `point` with unit `direction` (thesis 3.3).
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub point: DVec3,
    /// Unit length (the scene loader normalises it).
    pub direction: DVec3,
    pub coefficient: f64,
    pub look: Look,
}

/// A torus-shaped source: the circle of radius `major_radius` around `center` in the plane normal to `axis`
/// (thesis 3.7, generalised from the origin and the z axis).
#[derive(Clone, Debug, PartialEq)]
pub struct Torus {
    pub center: DVec3,
    /// Unit length (the scene loader normalises it).
    pub axis: DVec3,
    pub major_radius: f64,
    pub coefficient: f64,
    pub look: Look,
}

/// A chain of quadratic Bezier segments (`2k + 1` control points) with its W series (thesis 3.8-3.27).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub control_points: Vec<DVec3>,
    pub coefficient: f64,
    /// The W series; empty means all weights 1.
    pub weights: Vec<f64>,
    pub look: Look,
    /// The color series: the glow's color along the chain, a quadratic B-spline of colors over the chain
    /// parameter t* of the nearest point, like the W series (display values in [0, 1], times the look's
    /// intensity); empty means the look's one color.
    pub color_series: Vec<[f64; 3]>,
    /// How the W series weighs the term: at the chain's brightest point seen from P (continuous, the default)
    /// or at the nearest point (the papers').
    pub w_form: WForm,
}

/// Every source of a scene, by kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sources {
    pub points: Vec<Point>,
    pub lines: Vec<Line>,
    pub tori: Vec<Torus>,
    pub curves: Vec<Curve>,
}

/// `1 / max(eps, distance)`: the falloff shared by every kind of source.
pub fn falloff(distance: f64, eps: f64) -> f64 {
    1.0 / distance.max(eps)
}

/// Distance from `p` to a line (thesis 3.3): `sqrt(|P-M|^2 - ((P-M).D)^2)`, computed as the length of the
/// part of `P - M` across the line. The difference of squares loses to rounding what the two have in common:
/// in f32 (the shader's twin) a point 20 units along the line and 0.01 from it came out a quarter off in d^2.
pub fn line_distance(p: DVec3, point: DVec3, direction: DVec3) -> f64 {
    let d = p - point;
    (d - direction * d.dot(direction)).length()
}

/// Distance from `p` to the major circle of a torus (thesis 3.7 in the torus's own frame):
/// `sqrt((rho - R)^2 + z^2)`, `z` along the axis and `rho` the distance from the axis.
pub fn torus_distance(p: DVec3, center: DVec3, axis: DVec3, major_radius: f64) -> f64 {
    let q = p - center;
    let z = q.dot(axis);
    let rho = (q.length_squared() - z * z).max(0.0).sqrt();
    let dr = rho - major_radius;
    (dr * dr + z * z).sqrt()
}

impl Point {
    /// This source's term of psi, coefficient included.
    pub fn field(&self, p: DVec3, eps: f64) -> f64 {
        self.coefficient * falloff((p - self.position).length(), eps)
    }
}

impl Line {
    /// This source's term of psi, coefficient included.
    pub fn field(&self, p: DVec3, eps: f64) -> f64 {
        self.coefficient * falloff(line_distance(p, self.point, self.direction), eps)
    }
}

impl Torus {
    /// This source's term of psi, coefficient included.
    pub fn field(&self, p: DVec3, eps: f64) -> f64 {
        self.coefficient
            * falloff(
                torus_distance(p, self.center, self.axis, self.major_radius),
                eps,
            )
    }
}

impl Curve {
    /// Whether the term reads its chain at the brightest point (`brightest`): the continuous form of a W series
    /// that varies. Elsewhere both forms read the nearest point (with a uniform W they are the same term).
    pub fn searches(&self) -> bool {
        self.w_form == WForm::Continuous && !brightest::uniform(&self.weights)
    }

    /// What `point_seen` needs: the chain's pieces where the term searches for its brightest point, else none.
    pub fn pieces(&self) -> Vec<brightest::Piece> {
        if self.searches() {
            brightest::pieces(&self.control_points, &self.weights)
        } else {
            Vec::new()
        }
    }

    /// The point of the chain the term reads at `p`, with `pieces` from `pieces`: the brightest point in the
    /// continuous form, else the nearest. The term is `b Sw(t) falloff(distance)` at it.
    pub fn point_seen(&self, pieces: &[brightest::Piece], p: DVec3, eps: f64) -> curve::Nearest {
        if pieces.is_empty() {
            curve::nearest_on_chain(&self.control_points, p)
        } else {
            brightest::brightest(pieces, p, eps)
        }
    }

    /// This source's term of psi: `b Sw(t) / max(eps, |P - C(t)|)` at the point `point_seen` reads (t* the nearest
    /// point in the papers' form, `b Sw(t*) / max(eps, L(P))`).
    pub fn field(&self, p: DVec3, eps: f64) -> f64 {
        self.term_at(self.point_seen(&self.pieces(), p, eps), eps)
    }

    /// The term at the point `seen` it reads.
    pub fn term_at(&self, seen: curve::Nearest, eps: f64) -> f64 {
        self.coefficient * wseries::evaluate(&self.weights, seen.t) * falloff(seen.distance, eps)
    }
}

/// A scene's sources with what their terms need worked out once (the curves' pieces): for evaluating psi at
/// many points.
pub struct Field<'a> {
    pub sources: &'a Sources,
    pieces: Vec<Vec<brightest::Piece>>,
}

impl Field<'_> {
    /// psi(P), the sum of every source's term (thesis 3.28).
    pub fn psi(&self, p: DVec3, eps: f64) -> f64 {
        let s = self.sources;
        s.points.iter().map(|x| x.field(p, eps)).sum::<f64>()
            + s.lines.iter().map(|x| x.field(p, eps)).sum::<f64>()
            + s.tori.iter().map(|x| x.field(p, eps)).sum::<f64>()
            + (0..s.curves.len())
                .map(|i| self.curve(i, p, eps))
                .sum::<f64>()
    }

    /// Curve `i`'s term at `p`.
    pub fn curve(&self, i: usize, p: DVec3, eps: f64) -> f64 {
        let c = &self.sources.curves[i];
        c.term_at(c.point_seen(&self.pieces[i], p, eps), eps)
    }

    /// Term `k` of psi(P) alone, in the order of `Sources::looks`; 0 past the last.
    pub fn term(&self, k: usize, p: DVec3, eps: f64) -> f64 {
        let s = self.sources;
        let smooth = s.first_curve();
        if k < smooth {
            s.term(k, p, eps)
        } else if k - smooth < s.curves.len() {
            self.curve(k - smooth, p, eps)
        } else {
            0.0
        }
    }
}

impl Sources {
    /// The sources prepared for evaluating psi at many points.
    pub fn field(&self) -> Field<'_> {
        Field {
            sources: self,
            pieces: self.curves.iter().map(Curve::pieces).collect(),
        }
    }

    /// psi(P), the sum of every source's term (thesis 3.28).
    pub fn psi(&self, p: DVec3, eps: f64) -> f64 {
        self.points.iter().map(|s| s.field(p, eps)).sum::<f64>()
            + self.lines.iter().map(|s| s.field(p, eps)).sum::<f64>()
            + self.tori.iter().map(|s| s.field(p, eps)).sum::<f64>()
            + self.curves.iter().map(|s| s.field(p, eps)).sum::<f64>()
    }

    /// Every source's look, in the order of the field pass's terms: points, lines, tori, curves.
    pub fn looks(&self) -> impl Iterator<Item = &Look> {
        (self.points.iter().map(|s| &s.look))
            .chain(self.lines.iter().map(|s| &s.look))
            .chain(self.tori.iter().map(|s| &s.look))
            .chain(self.curves.iter().map(|s| &s.look))
    }

    /// Term `k` of psi(P) alone, in the order of `looks` (points, lines, tori, curves); 0 past the last.
    pub fn term(&self, k: usize, p: DVec3, eps: f64) -> f64 {
        let (n_p, n_l, n_t) = (self.points.len(), self.lines.len(), self.tori.len());
        if k < n_p {
            self.points[k].field(p, eps)
        } else if k < n_p + n_l {
            self.lines[k - n_p].field(p, eps)
        } else if k < n_p + n_l + n_t {
            self.tori[k - n_p - n_l].field(p, eps)
        } else {
            self.curves
                .get(k - n_p - n_l - n_t)
                .map_or(0.0, |c| c.field(p, eps))
        }
    }

    /// The coefficient of term `k`, in the order of `looks`; 0 past the last.
    pub fn coefficient(&self, k: usize) -> f64 {
        let (n_p, n_l, n_t) = (self.points.len(), self.lines.len(), self.tori.len());
        if k < n_p {
            self.points[k].coefficient
        } else if k < n_p + n_l {
            self.lines[k - n_p].coefficient
        } else if k < n_p + n_l + n_t {
            self.tori[k - n_p - n_l].coefficient
        } else {
            self.curves
                .get(k - n_p - n_l - n_t)
                .map_or(0.0, |c| c.coefficient)
        }
    }

    /// The index of the first curve's term, in the order of `looks`: the number of points, lines and tori,
    /// whose terms come first.
    pub fn first_curve(&self) -> usize {
        self.points.len() + self.lines.len() + self.tori.len()
    }

    /// Total number of sources.
    pub fn len(&self) -> usize {
        self.points.len() + self.lines.len() + self.tori.len() + self.curves.len()
    }

    /// True when there is no source at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// An axis-aligned box holding every bounded source (points, torus circles, curve control hulls) and the
    /// anchor point of every line, or `None` without sources.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut add = |p: DVec3, half: DVec3| {
            lo = lo.min(p - half);
            hi = hi.max(p + half);
        };
        self.points
            .iter()
            .for_each(|s| add(s.position, DVec3::ZERO));
        self.lines.iter().for_each(|s| add(s.point, DVec3::ZERO));
        for t in &self.tori {
            // The circle's extent along each world axis e is R sqrt(1 - (a.e)^2).
            add(
                t.center,
                t.major_radius * (DVec3::ONE - t.axis * t.axis).max(DVec3::ZERO).powf(0.5),
            );
        }
        // A Bezier curve lies in the convex hull of its control points.
        self.curves
            .iter()
            .flat_map(|c| &c.control_points)
            .for_each(|&p| add(p, DVec3::ZERO));
        (!self.is_empty()).then_some((lo, hi))
    }
}
