//! The viewport's input: orbit, pan and zoom, handles dragged, and the selection a click on a handle makes
//! (the handle in front first, the next under it on a second click), kept on its source as sources renumber.

use super::*;

impl ViewerApp {
    /// The 3D view with its handles: navigation and handle drags come back as edits.
    pub(super) fn viewport(&mut self, ui: &mut egui::Ui) -> Vec<Action> {
        let mut out = Vec::new();
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        self.viewport_rect = rect;
        self.viewport_px = [
            (rect.width() * ppp).round() as u32,
            (rect.height() * ppp).round() as u32,
        ];
        if self.viewport_px[0] == 0 || self.viewport_px[1] == 0 {
            return out;
        }
        let view = self.viewport_view();
        // Handles and navigation work on the scene as shown; their edits apply after this frame's view.
        let shown = view.scene.clone();
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            rect,
            ViewportCallback(view),
        ));

        // Handles first: a press on a handle drags it, anywhere else navigates.
        let show_handles = self.view.show_handles && self.view.show_overlays;
        let pointer = response.hover_pos().or(response.interact_pointer_pos());
        let dragged_handle = match &self.gesture {
            Some(Gesture::Handle { id, .. }) => Some(*id),
            _ => None,
        };
        self.hovered = match (show_handles, pointer) {
            (true, Some(p)) if dragged_handle.is_none() => handles::pick(&shown, rect, p),
            _ => self.hovered,
        };
        if show_handles
            && response.clicked()
            && let Some(at) = response.interact_pointer_pos()
        {
            // A click selects the source of the handle in front; a second click on the same spot goes on to
            // the next handle under it; a click on nothing clears the selection.
            let under = handles::pick_all(&shown, rect, at);
            let next = match self.picked {
                Some((last, spot)) if spot.distance(at) <= 4.0 => under
                    .iter()
                    .position(|&h| h == last)
                    .map(|k| under[(k + 1) % under.len()]),
                _ => None,
            }
            .or(under.first().copied());
            self.picked = next.map(|h| (h, at));
            self.selection = next.and_then(HandleId::source);
            self.selected_object = next.and_then(HandleId::object);
            self.scroll_to_selection = next.is_some();
        }
        if response.drag_started() {
            // A drag is only recognised once the pointer has moved: start from where the button went down.
            let press = ui
                .input(|i| i.pointer.press_origin())
                .or(response.interact_pointer_pos())
                .unwrap_or(rect.center());
            let camera = shown.camera.clone();
            // The handle picked last if it is under the press (so that cycling then dragging drags it), else the
            // one in front.
            let under = if show_handles {
                handles::pick_all(&shown, rect, press)
            } else {
                Vec::new()
            };
            let handle = match self.picked {
                Some((h, _)) if under.contains(&h) => Some(h),
                _ => under.first().copied(),
            };
            if response.dragged_by(PointerButton::Primary)
                && let Some(id) = handle
            {
                self.selection = id.source();
                self.selected_object = id.object();
                self.scroll_to_selection = true;
            }
            self.gesture = if response.dragged_by(PointerButton::Primary) {
                Some(
                    match handle.and_then(|id| handles::get(&shown, id).map(|p| (id, p))) {
                        Some((id, start)) => Gesture::Handle { id, start, press },
                        None => Gesture::Orbit {
                            start: camera,
                            press,
                        },
                    },
                )
            } else {
                Some(Gesture::Pan {
                    start: camera,
                    press,
                })
            };
        }
        let latest = ui.input(|i| i.pointer.latest_pos());
        if let (Some(gesture), Some(now)) = (&self.gesture, latest) {
            match gesture {
                Gesture::Handle { id, start, press } => {
                    let q = handles::drag_in_view_plane(
                        &shown.camera,
                        rect.height(),
                        *start,
                        now - *press,
                    );
                    if handles::get(&shown, *id) != Some(q) {
                        if let Some((parameter, value)) = handles::edit(&shown, *id, q) {
                            out.push(Action::Edit(Edit::Set(parameter, value)));
                        } else if let Some(edit) = handles::object_edit(&shown, *id, q) {
                            out.push(Action::Edit(edit));
                        }
                    }
                }
                Gesture::Orbit { start, press } => {
                    let d = now - *press;
                    let mut camera = start.clone();
                    // About a full turn across a typical viewport's width.
                    navigation::orbit(&mut camera, d.x as f64 * 0.0065, d.y as f64 * 0.0065);
                    if camera != shown.camera {
                        out.push(Action::Edit(Edit::Camera(camera)));
                    }
                }
                Gesture::Pan { start, press } => {
                    let d = now - *press;
                    let mut camera = start.clone();
                    navigation::pan(&mut camera, d.x as f64, d.y as f64, rect.height() as f64);
                    if camera != shown.camera {
                        out.push(Action::Edit(Edit::Camera(camera)));
                    }
                }
            }
        }
        if self.gesture.is_some() && !ui.input(|i| i.pointer.any_down()) {
            self.gesture = None;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let toward = pointer.map(|p| handles::screen_ray(&shown.camera, rect, p));
                let mut camera = shown.camera.clone();
                let floor = navigation::dolly_floor(&shown.sources);
                navigation::zoom_or_dolly(
                    &mut camera,
                    (-scroll as f64 * 0.003).exp(),
                    toward,
                    floor,
                );
                out.push(Action::Edit(Edit::Camera(camera)));
            }
        }

        let painter = ui.painter_at(rect);
        if show_handles {
            handles::draw(
                &painter,
                rect,
                &shown,
                dragged_handle.or(self.hovered),
                self.selection,
                self.selected_object,
            );
        }
        if let Some(error) = self.report().error {
            painter.text(
                rect.left_top() + egui::vec2(8.0, 8.0),
                egui::Align2::LEFT_TOP,
                format!("GPU error: {error}"),
                egui::FontId::proportional(13.0),
                Color32::from_rgb(255, 110, 90),
            );
        }
        // Blender's overlays button, in the viewport's top-right corner.
        let button = egui::Rect::from_min_size(
            rect.right_top() + egui::vec2(-92.0, 6.0),
            egui::vec2(86.0, 20.0),
        );
        if ui
            .put(
                button,
                egui::Button::selectable(self.view.show_overlays, "Overlays"),
            )
            .on_hover_text("Show or hide the grid, guides and handles (Shift+Alt+Z)")
            .clicked()
        {
            out.push(Action::ToggleOverlays);
        }
        out
    }

    /// The selection follows its source or object when an edit renumbers them (and goes with it).
    pub(super) fn follow_renumbering(&mut self, edit: &Edit) {
        if let Some(j) = self.selected_object {
            self.selected_object = match *edit {
                Edit::DeleteObject(i) if i == j => None,
                Edit::DeleteObject(i) if i < j => Some(j - 1),
                Edit::DuplicateObject(i) if i < j => Some(j + 1),
                _ => Some(j),
            };
        }
        let Some((kind, j)) = self.selection else {
            return;
        };
        self.selection = match *edit {
            Edit::DeleteSource(k, i) if k == kind && i == j => None,
            Edit::DeleteSource(k, i) if k == kind && i < j => Some((kind, j - 1)),
            Edit::DuplicateSource(k, i) if k == kind && i < j => Some((kind, j + 1)),
            _ => self.selection,
        };
    }

    /// Drops a selection whose source is gone (an undo, a reload, another file).
    pub(super) fn check_selection(&mut self) {
        if self.selected_object >= Some(self.doc.scene.objects.len()) {
            self.selected_object = None;
        }
        let s = &self.doc.scene.sources;
        if let Some((kind, i)) = self.selection {
            let count = match kind {
                SourceKind::Points => s.points.len(),
                SourceKind::Lines => s.lines.len(),
                SourceKind::Tori => s.tori.len(),
                SourceKind::Curves => s.curves.len(),
            };
            if i >= count {
                self.selection = None;
            }
        }
    }
}
