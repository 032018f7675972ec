//! The Objects section: spheres, boxes, planes and glTF meshes standing around the effect, each with its
//! editors, Duplicate and Delete, and selection. Where an object stands, its albedo and the rest of its
//! transform are keyable, each with its key button; a plane's extent replaces the object whole
//! (`Edit::SetObject`), one undo step a settled edit like every other.

use egui::{DragValue, Ui};
use glam::DVec3;

use super::super::action::{Action, Edit};
use super::super::widgets::{ERROR_COLOR, labelled, vec3};
use super::context::Context;
use super::fields::{Edits, axis, color_field, position};
use super::sources::Entry;
use crate::animation::Parameter;
use crate::objects::{Object, Shape, ShapeKind};

/// The section: adding (a mesh through the file dialog), and every object's entry.
pub(super) fn objects_section(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
    let target = cx.shown.camera.target;
    ui.horizontal_wrapped(|ui| {
        ui.strong("Objects");
        for (label, kind) in [
            ("+ sphere", ShapeKind::Sphere),
            ("+ box", ShapeKind::Box),
            ("+ plane", ShapeKind::Plane),
        ] {
            if ui.button(label).clicked() {
                out.push(Action::Edit(Edit::AddObject(kind, target)));
            }
        }
        if ui
            .button("+ mesh\u{2026}")
            .on_hover_text("Choose a glTF 2.0 file (.gltf or .glb) in the file dialog")
            .clicked()
        {
            out.push(Action::AddMeshDialog(target));
        }
    });
    if cx.shown.objects.is_empty() {
        ui.weak("None: the glow alone. Objects hide the glow behind them and are lit by it.");
    }
    for (i, object) in cx.shown.objects.iter().enumerate() {
        let selected = cx.selected_object == Some(i);
        let entry = Entry {
            id: ui.make_persistent_id(("energywave.object", i)),
            title: title(object, i),
            hover: "Select: its handle is ringed in the viewport",
            selected,
            scroll: selected && cx.scroll_to_selected,
            select: Action::SelectObject((!selected).then_some(i)),
            duplicate: Edit::DuplicateObject(i),
            delete: Edit::DeleteObject(i),
        };
        entry.show(ui, out, |ui, out| {
            // Where it stands and its albedo are keyable, each with its key button.
            let label = match object.kind() {
                ShapeKind::Sphere | ShapeKind::Box => "center",
                ShapeKind::Plane => "point",
                ShapeKind::Mesh => "translation",
            };
            position(
                ui,
                out,
                label,
                Parameter::ObjectPosition(i),
                object.center(),
            );
            shape_editor(ui, out, i, object);
            let label = match object.translucent {
                Some(_) => "tint",
                None => "albedo",
            };
            color_field(ui, out, label, Parameter::ObjectColor(i), object.color);
            translucent_editor(ui, out, i, object);
        });
    }
}

fn title(object: &Object, i: usize) -> String {
    let kind = match object.kind() {
        ShapeKind::Sphere => "Sphere",
        ShapeKind::Box => "Box",
        ShapeKind::Plane => "Plane",
        ShapeKind::Mesh => "Mesh",
    };
    format!("{kind} {}", i + 1)
}

/// The editors of an object's shape: the keyable fields (`Parameter::ObjectShape`) each with its key button, as
/// `Edit::Set` (a key at this frame where the field is keyed); a plane's extent, which is not keyable, as the
/// object replaced (`Edit::SetObject`).
fn shape_editor(ui: &mut Ui, out: &mut Edits<'_>, i: usize, object: &Object) {
    use crate::animation::{ShapeField, Value};
    let key = |field| Parameter::ObjectShape(i, field);
    // A vector field and its key button on one row, `edit` giving the new value if the user changed it.
    let vector = |ui: &mut Ui,
                  out: &mut Edits<'_>,
                  field: ShapeField,
                  v: DVec3,
                  edit: &dyn Fn(&mut Ui, &mut DVec3) -> (bool, egui::Rect)| {
        ui.horizontal(|ui| {
            let mut edited = v;
            let (changed, row) = edit(ui, &mut edited);
            if changed && edited != v {
                out.push(Action::set_vector(key(field), edited));
            }
            out.key_button(ui, key(field), Value::Vector(v.to_array()), row);
        });
    };
    let rotation = |ui: &mut Ui, v: &mut DVec3| vec3(ui, "rotation", v, 0.5);
    match &object.shape {
        Shape::Sphere { radius, .. } => {
            ui.horizontal(|ui| {
                let mut r = *radius;
                let response = labelled(
                    ui,
                    "radius",
                    DragValue::new(&mut r)
                        .range(1e-3..=1e6)
                        .speed(0.01)
                        .max_decimals(4),
                );
                if response.changed() && r != *radius {
                    out.push(Action::set_number(key(ShapeField::Radius), r));
                }
                let rect = response.rect;
                out.key_button(ui, key(ShapeField::Radius), Value::Number(*radius), rect);
            });
        }
        Shape::Box {
            size, rotation: r, ..
        } => {
            vector(ui, out, ShapeField::Size, *size, &|ui, v| {
                lengths(ui, "size", v)
            });
            vector(ui, out, ShapeField::Rotation, *r, &rotation);
        }
        Shape::Plane { normal, .. } => {
            axis(ui, out, "normal", key(ShapeField::Normal), *normal);
            let mut o = object.clone();
            let mut changed = false;
            ui.horizontal(|ui| {
                let Shape::Plane { size, .. } = &mut o.shape else {
                    return;
                };
                let mut finite = size.is_some();
                if ui
                    .checkbox(&mut finite, "finite")
                    .on_hover_text("A square of this side around the point; off: the whole plane")
                    .changed()
                {
                    *size = finite.then_some(10.0);
                    changed = true;
                }
                if let Some(side) = size {
                    changed |= length(ui, "side", side);
                }
            });
            if changed && o.shape != object.shape {
                out.push(Action::Edit(Edit::SetObject(i, o)));
            }
        }
        Shape::Mesh(m) => {
            ui.label(format!(
                "{} ({} triangles)",
                m.path.display(),
                m.data.triangles.len()
            ));
            vector(ui, out, ShapeField::Rotation, m.rotation, &rotation);
            vector(ui, out, ShapeField::Scale, m.scale, &|ui, v| {
                lengths(ui, "scale", v)
            });
        }
    }
}

/// A translucent material (`objects::translucent`): the switch, the keyable extinction and index of refraction
/// with their key buttons, the voxels' resolution and an inner region, which replace the object whole
/// (`Edit::SetObject`).
fn translucent_editor(ui: &mut Ui, out: &mut Edits<'_>, i: usize, object: &Object) {
    use crate::animation::{TranslucentField, Value};
    use crate::objects::translucent::{DEFAULT_RESOLUTION, Inner, InnerShape, Translucent};
    if object.kind() == ShapeKind::Plane {
        return;
    }
    let mut o = object.clone();
    let mut on = o.translucent.is_some();
    if ui
        .checkbox(&mut on, "translucent")
        .on_hover_text(
            "Light enters it, crosses the inside and leaves elsewhere; the glow behind it shows through",
        )
        .changed()
    {
        o.translucent = on.then(|| Box::new(Translucent::default()));
        out.push(Action::Edit(Edit::SetObject(i, o)));
        return;
    }
    let Some(t) = object.translucent.as_deref() else {
        return;
    };
    let key = |field| Parameter::Translucent(i, field);
    for (field, label, value, range, hover) in [
        (
            TranslucentField::Extinction,
            "extinction",
            t.extinction,
            0.0..=1e4,
            "sigma_t, per unit of length: how far light travels inside (0: clear)",
        ),
        (
            TranslucentField::Eta,
            "eta",
            t.eta,
            0.05..=10.0,
            "The relative index of refraction: ice 1.31, glass 1.5",
        ),
    ] {
        ui.horizontal(|ui| {
            let mut x = value;
            let response = labelled(
                ui,
                label,
                DragValue::new(&mut x)
                    .range(range)
                    .speed(0.01)
                    .max_decimals(3),
            )
            .on_hover_text(hover);
            if response.changed() && x != value {
                out.push(Action::set_number(key(field), x));
            }
            out.key_button(ui, key(field), Value::Number(value), response.rect);
        });
    }
    let mut m = t.clone();
    let mut changed = false;
    ui.horizontal(|ui| {
        let mut auto = m.resolution.is_none();
        if ui
            .checkbox(&mut auto, "auto voxels")
            .on_hover_text(format!(
                "Voxels along the longest side: {DEFAULT_RESOLUTION}, or fewer where the table would not fit"
            ))
            .changed()
        {
            m.resolution = (!auto).then_some(DEFAULT_RESOLUTION);
            changed = true;
        }
        if let Some(r) = &mut m.resolution {
            changed |= labelled(ui, "voxels", DragValue::new(r).range(4..=96))
                .on_hover_text("The table grows as the fourth power: 48 takes 16 times the memory of 24")
                .changed();
        }
    });
    ui.horizontal(|ui| {
        let mut cavity = m.inner.is_some();
        if ui
            .checkbox(&mut cavity, "inner sphere")
            .on_hover_text("A region of another extinction inside, placed from the object's center: 0 for a cavity")
            .changed()
        {
            m.inner = cavity.then_some(Inner {
                shape: InnerShape::Sphere {
                    center: DVec3::ZERO,
                    radius: 0.25,
                },
                extinction: 0.0,
            });
            changed = true;
        }
        if let Some(inner) = &mut m.inner {
            if let InnerShape::Sphere { radius, .. } = &mut inner.shape {
                changed |= length(ui, "radius", radius);
            }
            changed |= labelled(
                ui,
                "extinction",
                DragValue::new(&mut inner.extinction).range(0.0..=1e4).speed(0.01),
            )
            .changed();
        }
    });
    if changed && m != *t {
        o.translucent = Some(Box::new(m));
        out.push(Action::Edit(Edit::SetObject(i, o)));
    }
}

/// A positive length.
fn length(ui: &mut Ui, label: &str, x: &mut f64) -> bool {
    ui.horizontal(|ui| {
        labelled(
            ui,
            label,
            DragValue::new(x)
                .range(1e-3..=1e6)
                .speed(0.01)
                .max_decimals(4),
        )
        .changed()
    })
    .inner
}

/// Three positive lengths (a box's sides, a mesh's scale); a zero or negative one is refused, and said so.
/// Whether they changed, and the row's rectangle.
fn lengths(ui: &mut Ui, label: &str, v: &mut DVec3) -> (bool, egui::Rect) {
    let mut edited = *v;
    let (changed, row) = vec3(ui, label, &mut edited, 0.01);
    if !changed {
        return (false, row);
    }
    if edited.min_element() > 0.0 {
        *v = edited;
        (true, row)
    } else {
        ui.colored_label(ERROR_COLOR, format!("{label} must be positive"));
        (false, row)
    }
}
