//! The Objects section: spheres, boxes, planes and glTF meshes standing around the effect, each with its
//! editors, Duplicate and Delete, and selection. Objects are not animated: an edit replaces the object whole
//! (`Edit::SetObject`), one undo step a settled edit like every other.

use egui::{DragValue, Ui};
use glam::DVec3;

use super::super::action::{Action, Edit};
use super::super::widgets::{ERROR_COLOR, direction, labelled, vec3};
use super::context::Context;
use super::fields::{Edits, color_field, position};
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
            if let Some(edited) = editor(ui, object) {
                out.push(Action::Edit(Edit::SetObject(i, edited)));
            }
            color_field(ui, out, "albedo", Parameter::ObjectColor(i), object.color);
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

/// The editors of one object; the object as edited when the user changed something.
fn editor(ui: &mut Ui, object: &Object) -> Option<Object> {
    let mut o = object.clone();
    let mut changed = false;
    match &mut o.shape {
        Shape::Sphere { radius, .. } => {
            changed |= length(ui, "radius", radius);
        }
        Shape::Box { size, rotation, .. } => {
            changed |= lengths(ui, "size", size);
            changed |= vec3(ui, "rotation", rotation, 0.5).0;
        }
        Shape::Plane { normal, size, .. } => {
            if let (Some(n), _) = direction(ui, "normal", *normal) {
                *normal = n;
                changed = true;
            }
            ui.horizontal(|ui| {
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
        }
        Shape::Mesh(m) => {
            ui.label(format!(
                "{} ({} triangles)",
                m.path.display(),
                m.data.triangles.len()
            ));
            changed |= vec3(ui, "rotation", &mut m.rotation, 0.5).0;
            changed |= lengths(ui, "scale", &mut m.scale);
        }
    }
    (changed && o != *object).then_some(o)
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
fn lengths(ui: &mut Ui, label: &str, v: &mut DVec3) -> bool {
    let mut edited = *v;
    let (changed, _) = vec3(ui, label, &mut edited, 0.01);
    if !changed {
        return false;
    }
    if edited.min_element() > 0.0 {
        *v = edited;
        true
    } else {
        ui.colored_label(ERROR_COLOR, format!("{label} must be positive"));
        false
    }
}
