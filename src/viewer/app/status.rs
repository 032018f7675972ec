//! The status line: frame time, adapter, resolution and integrator, the file, and the messages for the user
//! (which clear at the next action, and expire unless they are errors); the window's title.

use super::*;

/// The color of the note of what is being prepared.
const PREPARING: Color32 = Color32::from_rgb(240, 200, 90);

/// How often the status line looks again while something is being prepared.
const PREPARING_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// The color of an error notice.
const ERROR_NOTICE: Color32 = Color32::from_rgb(255, 110, 90);

impl ViewerApp {
    pub fn notify(&mut self, text: impl Into<String>, is_error: bool) {
        self.notice = Some(Notice {
            message: (text.into(), is_error),
            at: self.now,
            from_disk: false,
        });
    }

    /// A message about the file on disk (cleared when the file is fine again).
    pub(super) fn notify_disk(&mut self, text: impl Into<String>, is_error: bool) {
        self.notify(text, is_error);
        if let Some(n) = &mut self.notice {
            n.from_disk = true;
        }
    }

    /// The window's title: the file's name, `*` with unsaved changes, and the program's.
    pub fn window_title(&self) -> String {
        format!("{} \u{2014} energywave", self.doc.title())
    }

    /// Drops a message whose time is up or whose cause is gone, and asks for a frame when the one shown will
    /// expire.
    pub(super) fn expire_notice(&mut self, ctx: &egui::Context) {
        let Some(n) = &self.notice else {
            return;
        };
        let disk_fine = self.doc.disk_error.is_none() && self.doc.pending_reload.is_none();
        let left = NOTICE_SECONDS - (self.now - n.at);
        if (n.from_disk && disk_fine) || (!n.message.1 && left <= 0.0) {
            self.notice = None;
        } else if !n.message.1 {
            ctx.request_repaint_after(std::time::Duration::from_secs_f64(left));
        }
    }

    /// Median frame time in seconds over the last frames.
    pub fn frame_time(&self) -> Option<f64> {
        if self.frame_times.is_empty() {
            return None;
        }
        let mut v: Vec<f64> = self.frame_times.iter().copied().collect();
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    /// The status line: frame time, what is being prepared, adapter, billboard and integrator, the file, and a
    /// notice; an error notice
    /// whole beneath it.
    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            match self.frame_time() {
                Some(t) if t > 0.0 => {
                    ui.monospace(format!("{:6.1} ms  {:5.1} FPS", t * 1e3, 1.0 / t))
                }
                _ => ui.monospace("   -- ms     -- FPS"),
            };
            let preparing = match (self.preparing(), self.report().preparing) {
                (Some(a), Some(b)) => Some(format!("{a}, {b}")),
                (a, b) => a.map(String::from).or(b),
            };
            if let Some(what) = preparing {
                ui.separator();
                ui.label(egui::RichText::new(format!("preparing {what}\u{2026}")).color(PREPARING))
                    .on_hover_text(
                        "Worked out on a thread of its own: until it is ready the picture shows the objects \
                         unshadowed (or with their light before the edit) and the particles as they were; \
                         the next edit starts it anew",
                    );
                // The frames that pick it up when it is ready (the viewer draws none of its own when idle).
                ui.ctx().request_repaint_after(PREPARING_POLL);
            }
            ui.separator();
            ui.label(&self.adapter);
            ui.separator();
            let w = self.doc.scene.billboard.resolution;
            let i = &self.doc.scene.integration;
            let integrator = match i.integrator {
                Integrator::Adaptive => format!("adaptive, tolerance {:e}", i.tolerance),
                Integrator::Simpson if i.jitter.is_some() => {
                    let averaged = match self.report().averaged {
                        Some((k, most)) => format!(", mean of {k}/{most} frames"),
                        None => String::new(),
                    };
                    format!("simpson, n = {}, jittered{averaged}", i.divisions)
                }
                Integrator::Simpson => format!("simpson, n = {}", i.divisions),
            };
            // What is on screen: the moving field (its side where the machine made it smaller), the still field
            // being refined, or the still field whole.
            let report = self.report();
            let shown = match (report.preview, report.moving_side) {
                (Some(_), Some(side)) if side >= w => "moving: within 1/255".to_owned(),
                (Some(_), Some(side)) => format!("moving: {side}\u{d7}{side} within 1/255"),
                (Some(_), None) => "refining".to_owned(),
                (None, _) => "still".to_owned(),
            };
            ui.label(format!("billboard {w}\u{d7}{w} ({shown}), {integrator}"))
                .on_hover_text(
                    "While the view moves, the field refined in image space to a step of the 8-bit \
                     picture, integrated exactly at the cores and at objects' edges (at a smaller side \
                     where the machine cannot keep the frame rate); once it holds still, refined to the \
                     scene's tolerance (View: fast preview)",
                );
            ui.separator();
            ui.label(self.doc.title());
            if let Some((text, false)) = self.notice() {
                ui.separator();
                // One line, cut to the bar's width; the whole message on hover.
                let first_line = text.lines().next().unwrap_or_default();
                let color = ui.visuals().weak_text_color();
                let more = first_line.len() < text.len();
                let shown = if more {
                    format!("{first_line} \u{2026}")
                } else {
                    first_line.to_owned()
                };
                ui.add(egui::Label::new(egui::RichText::new(shown).color(color)).truncate())
                    .on_hover_text(text.as_str());
            }
        });
        // An error is read whole: wrapped, in a box over the viewport's bottom right, just above the status
        // line (nothing moves to make room for it).
        if let Some((text, true)) = self.notice() {
            let above = ui.max_rect().height() + 6.0;
            egui::Area::new(egui::Id::unique("energywave.error_notice"))
                .anchor(egui::Align2::RIGHT_BOTTOM, egui::vec2(-8.0, -above))
                .interactable(false)
                .show(ui.ctx(), |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.set_max_width(560.0);
                        ui.add(
                            egui::Label::new(
                                egui::RichText::new(text.as_str()).color(ERROR_NOTICE),
                            )
                            .wrap(),
                        );
                    });
                });
        }
    }
}
