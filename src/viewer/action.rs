//! What the user asked for, as the panels and the viewport return it: `ViewerApp::apply` carries out every
//! action in one place. An [`Edit`] changes the document's scene; [`Edit::apply`] is the whole of what an
//! edit does, and the only place the viewer writes into the scene.

use std::path::PathBuf;

use glam::DVec3;

use crate::animation::{Animation, Key, Parameter, SourceKind, Track, Value};
use crate::export::Target;
use crate::field::{Curve, Line, Point, Torus, WForm};
use crate::geometry::Camera;
use crate::integrate::{Decay, Integrator};
use crate::objects::{Object, Shape, ShapeKind};
use crate::particles::emit::EmitterShape;
use crate::particles::{Origin, ParticleSet};
use crate::scene::{Blend, DEFAULT_ALBEDO, Glare, Scene};

/// One request from the UI.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Open a scene file (asking first if there are unsaved changes).
    Open(PathBuf),
    /// Save to the document's file, or to the typed path when it has none.
    Save,
    /// Save to this path.
    SaveAs(PathBuf),
    /// Choose a scene file to open in the file dialog.
    OpenDialog,
    /// Choose where to save in the file dialog.
    SaveAsDialog,
    Undo,
    Redo,
    /// Take the file's new content from disk, dropping the edits since.
    AcceptReload,
    /// Keep the edits over the file's new content on disk.
    KeepMine,
    /// A screenshot of the viewport at the chosen scale.
    Screenshot,
    /// Place the camera to see every source.
    FrameEffect,
    /// Show or hide the overlays (grid, guides, handles) at once.
    ToggleOverlays,
    /// The camera as the file had it.
    ResetView,
    /// Render frames of the animation to files beside the UI.
    Export {
        target: Target,
        frames: std::ops::Range<u32>,
        size: (u32, u32),
        transparent: bool,
        /// With `transparent`: the objects left out, still hiding the glow.
        holdout: bool,
        /// The field of view set to frame the glow of every frame (`export::fit`).
        fit: bool,
        description: String,
    },
    /// Stop the export running (what it wrote is removed).
    CancelExport,
    /// Select a source (or none): its handles are ringed in the viewport, its entry highlighted in the panel.
    Select(Option<(SourceKind, usize)>),
    /// Select an object (or none): its handle ringed, its entry highlighted.
    SelectObject(Option<usize>),
    /// Add the glTF mesh at this path (relative to the scene file's folder, or absolute) at a point.
    AddMesh(String, DVec3),
    /// Choose a glTF file in the file dialog, to add as a mesh object at a point.
    AddMeshDialog(DVec3),
    /// Tell the user something (an error when `is_error`).
    Notify {
        text: String,
        is_error: bool,
    },
    /// Change the scene.
    Edit(Edit),
}

/// A change to the document's scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// One animatable parameter to a value as shown at the current frame: a key at that frame when the
    /// parameter is keyed (the scene's own value stays), else the scene's own value.
    Set(Parameter, Value),
    Camera(Camera),
    Integrator(Integrator),
    /// How each term's energy along the view adds up to its part of B.
    Decay(Decay),
    Tolerance(f64),
    /// Simpson's division count (even).
    Divisions(u32),
    /// Jittered sampling with a seed, or none.
    Jitter(Option<u32>),
    Resolution(u32),
    /// Whether exports keep W (`true`) or follow their pixel density.
    FixedResolution(bool),
    /// The billboard fixed at a center with a size, or placed automatically (`None`).
    Billboard(Option<(DVec3, f64)>),
    /// A new source of the kind, at a point (the camera's target).
    AddSource(SourceKind, DVec3),
    /// A copy of a source, listed right after it.
    DuplicateSource(SourceKind, usize),
    DeleteSource(SourceKind, usize),
    /// One more segment at the end of a curve, continuing it smoothly.
    AddSegment(usize),
    /// The last segment of a curve removed (a curve keeps one).
    RemoveSegment(usize),
    /// One more weight at the end of a curve's W series (the first makes a uniform series of two).
    AddWeight(usize),
    /// A curve's weight `j` removed.
    RemoveWeight(usize, usize),
    /// A curve's W series removed (uniform intensity).
    UniformWeights(usize),
    /// How curve `i`'s W series weighs its term: at its brightest point (continuous) or its nearest (the papers').
    WForm(usize, WForm),
    /// How the glow goes over the background.
    Blend(Blend),
    /// Glare on (with its settings) or off.
    Glare(Option<Glare>),
    /// A source's own color and intensity dropped, with their keys: it takes the scene's again.
    InheritLook(SourceKind, usize),
    /// A color appended to curve `i`'s color series (its last, or the curve's one color for a new series,
    /// which then starts with two: the same look until one is changed).
    AddSeriesColor(usize),
    /// Color `j` removed from curve `i`'s color series (the last removed, the curve has one color again).
    RemoveSeriesColor(usize, usize),
    /// A key of a parameter at the current frame, to a value: its track's, or a new track's (a still scene gets
    /// an animation).
    Key(Parameter, Value),
    /// A parameter's key at the current frame removed (its track with it when it was the last).
    Unkey(Parameter),
    /// The animation as a whole: timeline, pulses and keys (`None`: a still scene).
    Animation(Option<Animation>),
    /// A new object of a shape (not a mesh: `Action::AddMesh` reads its file) at a point.
    AddObject(ShapeKind, DVec3),
    /// An object appended as it is (a mesh read from its file).
    InsertObject(Object),
    /// Object `i` replaced: any of its settings edited, or moved by its handle.
    SetObject(usize, Object),
    /// A copy of object `i`, listed right after it.
    DuplicateObject(usize),
    DeleteObject(usize),
    /// A particle set appended.
    AddParticles(ParticleSet),
    /// Particle set `i` replaced: any of its settings edited.
    SetParticles(usize, ParticleSet),
    /// A copy of particle set `i`, listed right after it, with the next seed (an emitter's) so that it is not
    /// drawn over the first.
    DuplicateParticles(usize),
    DeleteParticles(usize),
    /// The particles' slices' width, in radii of the smallest particle.
    SliceWidth(f64),
}

impl Action {
    /// `Set` of a parameter to a vector.
    pub fn set_vector(parameter: Parameter, v: DVec3) -> Self {
        Action::Edit(Edit::Set(parameter, Value::Vector(v.to_array())))
    }

    /// `Set` of a parameter to a number.
    pub fn set_number(parameter: Parameter, x: f64) -> Self {
        Action::Edit(Edit::Set(parameter, Value::Number(x)))
    }

    pub fn error(text: impl Into<String>) -> Self {
        Action::Notify {
            text: text.into(),
            is_error: true,
        }
    }
}

impl Edit {
    /// Applies the edit to `scene` (the document's, with its unkeyed base values), the UI being at `frame`.
    /// An edit that names nothing (a source deleted meanwhile) does nothing.
    pub fn apply(self, scene: &mut Scene, frame: f64) {
        let s = &mut scene.sources;
        match self {
            Edit::Set(parameter, value) => {
                let track = scene
                    .animation
                    .as_mut()
                    .and_then(|a| a.tracks.iter_mut().find(|t| t.parameter == parameter));
                match track {
                    Some(track) => track.set_key(frame, value),
                    None => parameter.set(scene, value),
                }
            }
            Edit::Camera(camera) => scene.camera = camera.tidied(),
            Edit::Integrator(integrator) => {
                scene.integration.integrator = integrator;
                // Jitter belongs to simpson.
                if integrator == Integrator::Adaptive {
                    scene.integration.jitter = None;
                }
            }
            Edit::Decay(decay) => scene.integration.decay = decay,
            Edit::Tolerance(t) => scene.integration.tolerance = t,
            Edit::Divisions(n) => scene.integration.divisions = n,
            Edit::Jitter(seed) => scene.integration.jitter = seed,
            Edit::Resolution(w) => scene.billboard.resolution = w,
            Edit::FixedResolution(fixed) => scene.billboard.fixed_resolution = fixed,
            Edit::Blend(b) => scene.colors.blend = b,
            Edit::AddObject(kind, at) => {
                let shape = match kind {
                    ShapeKind::Sphere => Shape::Sphere {
                        center: at,
                        radius: 0.5,
                    },
                    ShapeKind::Box => Shape::Box {
                        center: at,
                        size: DVec3::ONE,
                        rotation: DVec3::ZERO,
                    },
                    // A floor under the point.
                    ShapeKind::Plane => Shape::Plane {
                        point: at - DVec3::Y * 1.5,
                        normal: DVec3::Y,
                        size: None,
                    },
                    ShapeKind::Mesh => return,
                };
                scene.objects.push(Object {
                    shape,
                    color: DEFAULT_ALBEDO,
                    translucent: None,
                });
            }
            Edit::InsertObject(object) => scene.objects.push(object),
            Edit::SetObject(i, object) => {
                if let Some(o) = scene.objects.get_mut(i) {
                    *o = object;
                }
            }
            Edit::DuplicateObject(i) => {
                duplicate(&mut scene.objects, i);
            }
            Edit::DeleteObject(i) => {
                remove(&mut scene.objects, i);
            }
            Edit::AddParticles(set) => {
                if set.life().is_some() && scene.animation.is_none() {
                    scene.animation = Some(Animation::default());
                }
                scene.particles.push(set.unframed());
            }
            Edit::SetParticles(i, set) => {
                if set.life().is_some() && scene.animation.is_none() {
                    scene.animation = Some(Animation::default());
                }
                if let Some(p) = scene.particles.get_mut(i) {
                    *p = set.unframed();
                }
            }
            Edit::DuplicateParticles(i) => {
                if duplicate(&mut scene.particles, i) {
                    if let Origin::Emitter(e) = &mut scene.particles[i + 1].origin {
                        e.seed = e.seed.wrapping_add(1);
                    }
                    if let Some(a) = &mut scene.animation {
                        a.particles_inserted(i + 1);
                    }
                }
            }
            Edit::DeleteParticles(i) => {
                if remove(&mut scene.particles, i)
                    && let Some(a) = &mut scene.animation
                {
                    a.particles_removed(i);
                }
            }
            Edit::SliceWidth(w) => scene.slice_width = w,
            Edit::Glare(g) => scene.glare = g,
            Edit::AddSeriesColor(i) => {
                let colors = scene.colors.clone();
                if let Some(c) = scene.sources.curves.get_mut(i) {
                    let one = c.look.color.unwrap_or(colors.energy);
                    if c.color_series.is_empty() {
                        c.color_series.push(one);
                        c.look.color = None;
                    }
                    let last = *c.color_series.last().expect("not empty");
                    c.color_series.push(last);
                }
            }
            Edit::RemoveSeriesColor(i, j) => {
                if let Some(c) = scene.sources.curves.get_mut(i)
                    && j < c.color_series.len()
                {
                    c.color_series.remove(j);
                    if c.color_series.len() == 1 {
                        c.look.color = c.color_series.pop();
                    }
                }
            }
            Edit::InheritLook(kind, i) => {
                if let Some(look) = scene.look_mut(kind, i) {
                    *look = Default::default();
                }
                if kind == SourceKind::Curves
                    && let Some(c) = scene.sources.curves.get_mut(i)
                {
                    c.color_series.clear();
                }
                if let Some(a) = &mut scene.animation {
                    a.tracks.retain(|t| {
                        !matches!(t.parameter, Parameter::SourceColor(k, j) | Parameter::Intensity(k, j) if (k, j) == (kind, i))
                            && !matches!(t.parameter, Parameter::SeriesColor(j, _) if kind == SourceKind::Curves && j == i)
                    });
                }
            }
            Edit::Billboard(fixed) => {
                scene.billboard.center = fixed.map(|(c, _)| c);
                scene.billboard.size = fixed.map(|(_, l)| l);
            }
            Edit::AddSource(kind, at) => match kind {
                SourceKind::Points => s.points.push(Point {
                    position: at,
                    coefficient: 2.0,
                    look: Default::default(),
                }),
                SourceKind::Lines => s.lines.push(Line {
                    point: at,
                    direction: DVec3::X,
                    coefficient: 0.5,
                    look: Default::default(),
                }),
                SourceKind::Tori => s.tori.push(Torus {
                    center: at,
                    axis: DVec3::Y,
                    major_radius: 1.0,
                    coefficient: 3.0,
                    look: Default::default(),
                }),
                SourceKind::Curves => s.curves.push(Curve {
                    control_points: vec![
                        at - DVec3::X * 2.0,
                        at + DVec3::Y * 1.5,
                        at + DVec3::X * 2.0,
                    ],
                    coefficient: 4.0,
                    weights: vec![],
                    look: Default::default(),
                    color_series: Vec::new(),
                    w_form: WForm::default(),
                }),
            },
            Edit::DuplicateSource(kind, i) => {
                let copied = match kind {
                    SourceKind::Points => duplicate(&mut s.points, i),
                    SourceKind::Lines => duplicate(&mut s.lines, i),
                    SourceKind::Tori => duplicate(&mut s.tori, i),
                    SourceKind::Curves => duplicate(&mut s.curves, i),
                };
                // Pulses and keys follow their sources; so do emitters (the copy has none of its own).
                if copied && let Some(a) = &mut scene.animation {
                    a.source_inserted(kind, i + 1);
                }
                if copied {
                    emitters_follow_insertion(&mut scene.particles, kind, i + 1);
                }
            }
            Edit::DeleteSource(kind, i) => {
                let removed = match kind {
                    SourceKind::Points => remove(&mut s.points, i),
                    SourceKind::Lines => remove(&mut s.lines, i),
                    SourceKind::Tori => remove(&mut s.tori, i),
                    SourceKind::Curves => remove(&mut s.curves, i),
                };
                if removed && let Some(a) = &mut scene.animation {
                    a.source_removed(kind, i);
                }
                if removed {
                    for set in emitters_follow_removal(&mut scene.particles, kind, i) {
                        if let Some(a) = &mut scene.animation {
                            a.particles_removed(set);
                        }
                    }
                }
            }
            Edit::AddSegment(c) => {
                if let Some(c) = s.curves.get_mut(c) {
                    let n = c.control_points.len();
                    let (end, before) = (c.control_points[n - 1], c.control_points[n - 2]);
                    let tangent = end - before;
                    // The new middle point on the end tangent keeps the joint smooth.
                    c.control_points.push(end + tangent);
                    c.control_points.push(
                        end + tangent * 2.0 + tangent.any_orthonormal_vector() * tangent.length(),
                    );
                }
            }
            Edit::RemoveSegment(c) => {
                if let Some(c) = s.curves.get_mut(c)
                    && c.control_points.len() > 3
                {
                    c.control_points.truncate(c.control_points.len() - 2);
                }
            }
            Edit::AddWeight(c) => {
                if let Some(c) = s.curves.get_mut(c) {
                    let last = c.weights.last().copied().unwrap_or(1.0);
                    if c.weights.is_empty() {
                        c.weights.push(1.0);
                    }
                    c.weights.push(last);
                }
            }
            Edit::RemoveWeight(c, j) => {
                if let Some(c) = s.curves.get_mut(c)
                    && j < c.weights.len()
                {
                    c.weights.remove(j);
                }
            }
            Edit::UniformWeights(c) => {
                if let Some(c) = s.curves.get_mut(c) {
                    c.weights.clear();
                }
            }
            Edit::WForm(c, form) => {
                if let Some(c) = s.curves.get_mut(c) {
                    c.w_form = form;
                }
            }
            Edit::Key(parameter, value) => {
                let a = scene.animation.get_or_insert_with(Animation::default);
                match a.tracks.iter_mut().find(|t| t.parameter == parameter) {
                    Some(track) => track.set_key(frame, value),
                    None => a.tracks.push(Track {
                        parameter,
                        keys: vec![Key { frame, value }],
                    }),
                }
            }
            Edit::Unkey(parameter) => {
                if let Some(a) = &mut scene.animation {
                    for track in a.tracks.iter_mut().filter(|t| t.parameter == parameter) {
                        track.keys.retain(|k| k.frame != frame);
                    }
                    a.tracks.retain(|t| !t.keys.is_empty());
                }
            }
            Edit::Animation(animation) => scene.animation = animation,
        }
        // Keys and pulses on what an edit removed go with it, so that the scene still saves as a valid file.
        if let Some(mut a) = scene.animation.take() {
            a.retain_valid(scene);
            scene.animation = Some(a);
        }
    }
}

/// The source index an emitter is placed around, where it is of `kind`.
fn emitter_source(set: &mut ParticleSet, kind: SourceKind) -> Option<&mut usize> {
    let Origin::Emitter(e) = &mut set.origin else {
        return None;
    };
    match (&mut e.shape, kind) {
        (EmitterShape::Curve { curve, .. }, SourceKind::Curves) => Some(curve),
        (EmitterShape::Torus { torus, .. }, SourceKind::Tori) => Some(torus),
        _ => None,
    }
}

/// After source `i` of `kind` is removed: the emitters placed around it go with it, and those around a later
/// one of its kind follow it down the list (so that the scene still saves as a valid file). The indices the
/// removed sets had, from the last, for their keys to follow.
fn emitters_follow_removal(sets: &mut Vec<ParticleSet>, kind: SourceKind, i: usize) -> Vec<usize> {
    let mut removed = Vec::new();
    let mut at = 0;
    sets.retain_mut(|set| {
        let keep = match emitter_source(set, kind) {
            Some(index) if *index == i => false,
            Some(index) if *index > i => {
                *index -= 1;
                true
            }
            _ => true,
        };
        if !keep {
            removed.push(at);
        }
        at += 1;
        keep
    });
    removed.reverse();
    removed
}

/// After a source of `kind` is inserted at `i`: the emitters around it and the later ones follow it up the list.
fn emitters_follow_insertion(sets: &mut [ParticleSet], kind: SourceKind, i: usize) {
    for set in sets {
        if let Some(index) = emitter_source(set, kind)
            && *index >= i
        {
            *index += 1;
        }
    }
}

fn duplicate<T: Clone>(items: &mut Vec<T>, i: usize) -> bool {
    let Some(copy) = items.get(i).cloned() else {
        return false;
    };
    items.insert(i + 1, copy);
    true
}

fn remove<T>(items: &mut Vec<T>, i: usize) -> bool {
    if i < items.len() {
        items.remove(i);
        true
    } else {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default scene with the torus's radius keyed at frames 0 (1.0) and 20 (2.0).
    fn keyed() -> Scene {
        let mut s = Scene::default_scene();
        s.animation = Some(Animation {
            tracks: vec![Track {
                parameter: Parameter::MajorRadius(0),
                keys: vec![
                    Key {
                        frame: 0.0,
                        value: Value::Number(1.0),
                    },
                    Key {
                        frame: 20.0,
                        value: Value::Number(2.0),
                    },
                ],
            }],
            ..Animation::default()
        });
        s
    }

    #[test]
    fn a_keyed_value_edited_becomes_a_key_and_an_unkeyed_one_the_base_value() {
        let mut s = keyed();
        let base = s.sources.tori[0].major_radius;
        Edit::Set(Parameter::MajorRadius(0), Value::Number(2.4)).apply(&mut s, 10.0);
        assert_eq!(s.sources.tori[0].major_radius, base, "the base value stays");
        assert_eq!(s.at_frame(10.0).sources.tori[0].major_radius, 2.4);
        assert_eq!(s.animation.as_ref().unwrap().tracks[0].keys.len(), 3);
        Edit::Set(
            Parameter::Coefficient(SourceKind::Tori, 0),
            Value::Number(7.0),
        )
        .apply(&mut s, 10.0);
        assert_eq!(s.sources.tori[0].coefficient, 7.0);
        assert_eq!(
            s.animation.as_ref().unwrap().tracks.len(),
            1,
            "no track made"
        );
    }

    #[test]
    fn keys_follow_their_sources_and_go_with_them() {
        let mut s = keyed();
        Edit::DuplicateSource(SourceKind::Tori, 0).apply(&mut s, 0.0);
        assert_eq!(s.sources.tori.len(), 2);
        Edit::DeleteSource(SourceKind::Tori, 0).apply(&mut s, 0.0);
        // The copy, now first, carries no keys: the track went with the source it keyed.
        assert!(s.animation.as_ref().unwrap().tracks.is_empty());
        // A weight's key goes when the weight does, and the scene still saves as a valid file.
        let mut s = Scene::default_scene();
        let weights = s.sources.curves[0].weights.len();
        assert!(weights > 2);
        s.animation = Some(Animation {
            tracks: vec![Track {
                parameter: Parameter::Weight(0, weights - 1),
                keys: vec![Key {
                    frame: 0.0,
                    value: Value::Number(0.5),
                }],
            }],
            ..Animation::default()
        });
        Edit::RemoveWeight(0, 0).apply(&mut s, 0.0);
        assert!(s.animation.as_ref().unwrap().tracks.is_empty());
        Scene::parse(&s.to_toml(), std::path::Path::new("edited.toml")).expect("valid");
    }

    #[test]
    fn edits_that_name_nothing_do_nothing() {
        let s0 = Scene::default_scene();
        for edit in [
            Edit::DeleteSource(SourceKind::Points, 3),
            Edit::DuplicateSource(SourceKind::Lines, 0),
            Edit::AddSegment(5),
            Edit::RemoveWeight(0, 99),
            Edit::Set(Parameter::MajorRadius(9), Value::Number(1.0)),
        ] {
            let mut s = s0.clone();
            edit.clone().apply(&mut s, 0.0);
            assert_eq!(s, s0, "{edit:?}");
        }
        // A curve keeps its last segment.
        let mut s = s0.clone();
        let n = s.sources.curves[0].control_points.len();
        for _ in 0..n {
            Edit::RemoveSegment(0).apply(&mut s, 0.0);
        }
        assert_eq!(s.sources.curves[0].control_points.len(), 3);
        Edit::AddSegment(0).apply(&mut s, 0.0);
        assert_eq!(s.sources.curves[0].control_points.len(), 5);
    }

    #[test]
    fn choosing_adaptive_drops_the_jitter() {
        let mut s = Scene::default_scene();
        Edit::Integrator(Integrator::Simpson).apply(&mut s, 0.0);
        Edit::Jitter(Some(3)).apply(&mut s, 0.0);
        assert_eq!(s.integration.jitter, Some(3));
        Edit::Integrator(Integrator::Adaptive).apply(&mut s, 0.0);
        assert_eq!(s.integration.jitter, None);
    }
}
