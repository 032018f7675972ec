//! The Rendering section: the integrator and its settings, the decay, the resolution, the billboard, the
//! colors and the blend.

use egui::{DragValue, RichText, Ui};

use super::super::action::{Action, Edit};
use super::super::widgets::{labelled, vec3};
use super::context::{
    Context, PANEL_MAX_DIVISIONS, PANEL_MAX_RESOLUTION, PANEL_TOLERANCE, ViewSettings,
};
use super::fields::{Edits, color_field, number};
use crate::animation::{IntegrationSetting, Parameter};
use crate::integrate::{Decay, Integrator};
use crate::scene::{Blend, Glare, MAX_CUTOFF, MAX_GLARE_SIZE, MAX_INTENSITY, Scene, limits};

pub(super) fn render_section(
    ui: &mut Ui,
    cx: &Context,
    view: &mut ViewSettings,
    out: &mut Edits<'_>,
) {
    let scene = cx.shown;
    let i = &scene.integration;
    let edit = |out: &mut Edits<'_>, e: Edit| out.push(Action::Edit(e));
    // Set again below while the threshold is hovered or dragged.
    view.preview_glare_threshold = false;
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            egui::Grid::new("energywave.integration")
                .num_columns(2)
                .show(ui, |ui| {
                    ui.label("integrator");
                    ui.horizontal(|ui| {
                        for integrator in [Integrator::Adaptive, Integrator::Simpson] {
                            let hint = match integrator {
                                Integrator::Adaptive => "Samples where the field needs them, to a tolerance (fast, no banding)",
                                Integrator::Simpson => "The papers' n evenly spaced samples (bands at a low n)",
                            };
                            if ui
                                .selectable_label(i.integrator == integrator, integrator.name())
                                .on_hover_text(hint)
                                .clicked()
                                && i.integrator != integrator
                            {
                                edit(out, Edit::Integrator(integrator));
                            }
                        }
                    });
                    ui.end_row();
                    match i.integrator {
                        Integrator::Adaptive => {
                            let mut t = i.tolerance;
                            let r = labelled(
                                ui,
                                "tolerance",
                                DragValue::new(&mut t)
                                    .range(PANEL_TOLERANCE)
                                    .speed(1e-5)
                                    .max_decimals(7),
                            );
                            if r.changed() && t != i.tolerance {
                                edit(out, Edit::Tolerance(t));
                            }
                            ui.end_row();
                        }
                        Integrator::Simpson => {
                            let mut n = i.divisions;
                            labelled(
                                ui,
                                "divisions n",
                                DragValue::new(&mut n)
                                    .range(2..=PANEL_MAX_DIVISIONS)
                                    .speed(2),
                            );
                            // Simpson's rule needs an even count.
                            let n = (n + n % 2).clamp(2, PANEL_MAX_DIVISIONS);
                            if n != i.divisions {
                                edit(out, Edit::Divisions(n));
                            }
                            ui.end_row();
                            let mut jitter = i.jitter.is_some();
                            ui.label("");
                            if ui
                                .checkbox(&mut jitter, "jitter (noise instead of bands)")
                                .changed()
                            {
                                edit(out, Edit::Jitter(jitter.then_some(i.jitter.unwrap_or(0))));
                            }
                            ui.end_row();
                            if jitter {
                                labelled(
                                    ui,
                                    "average frames",
                                    DragValue::new(&mut view.average_frames).range(1..=1024),
                                )
                                .on_hover_text(
                                    "While the view is still, average this many jittered frames \
                                     (the noise falls as 1/\u{221a}frames); 1: none",
                                );
                                ui.end_row();
                            }
                        }
                    }
                    ui.label("decay");
                    ui.horizontal(|ui| {
                        for decay in Decay::ALL {
                            let hint = match decay {
                                Decay::Distance => "The papers': each source's energy along the view summed                                     (a long even spread outshines an intense spot)",
                                Decay::Rms => "Each source's energy along the view as its root mean square:                                     an intense spot outshines an even spread of the same energy",
                            };
                            if ui
                                .selectable_label(i.decay == decay, decay.name())
                                .on_hover_text(hint)
                                .clicked()
                                && i.decay != decay
                            {
                                edit(out, Edit::Decay(decay));
                            }
                        }
                    });
                    ui.end_row();
                    let step = 0.005 * i.decay_length;
                    let setting = |k| Parameter::Integration(k);
                    number(
                        ui,
                        out,
                        "decay length",
                        setting(IntegrationSetting::DecayLength),
                        i.decay_length,
                        |x| {
                            DragValue::new(x)
                                .range(limits::MIN_DECAY_LENGTH..=limits::MAX_DECAY_LENGTH)
                                .speed(step)
                        },
                    )
                    .on_hover_text(
                        "The depth past the billboard, in scene units, over which \u{3b6} falls from \
                         \u{3b1}/\u{3b2}\u{b2} to \u{3b1}/(1+\u{3b2})\u{b2}. Fixed in space: the look \
                         holds as the camera moves",
                    );
                    ui.end_row();
                    number(ui, out, "\u{3b1}", setting(IntegrationSetting::Alpha), i.alpha, |x| {
                        DragValue::new(x).range(0.001..=1000.0).speed(0.01)
                    });
                    ui.end_row();
                    number(ui, out, "\u{3b2}", setting(IntegrationSetting::Beta), i.beta, |x| {
                        DragValue::new(x).range(0.001..=1000.0).speed(0.01)
                    });
                    ui.end_row();
                    number(
                        ui,
                        out,
                        "\u{3b5} (clamp)",
                        setting(IntegrationSetting::Epsilon),
                        i.epsilon,
                        |x| {
                            DragValue::new(x)
                                .range(1e-6..=10.0)
                                .speed(0.001)
                                .max_decimals(6)
                        },
                    );
                    ui.end_row();
                    let top = cx.max_resolution.clamp(8, PANEL_MAX_RESOLUTION);
                    let mut w = scene.billboard.resolution;
                    let r = labelled(
                        ui,
                        "resolution W",
                        DragValue::new(&mut w).range(8..=top).speed(4),
                    );
                    if r.changed() && w != scene.billboard.resolution {
                        edit(out, Edit::Resolution(w));
                    }
                    ui.end_row();
                    ui.label("");
                    let mut fixed = scene.billboard.fixed_resolution;
                    if ui
                        .checkbox(&mut fixed, "exports too")
                        .on_hover_text(
                            "On: exports keep W whatever their size. Off: an export takes one texel per two pixels \
                             of the billboard's side in its frame (at least W), so a thin core stays smooth at \
                             1920 x 1080, as a 2x screenshot doubles W",
                        )
                        .changed()
                    {
                        edit(out, Edit::FixedResolution(fixed));
                    }
                    ui.end_row();
                });
            billboard_editor(ui, cx, out);
            color_field(ui, out, "energy Ce", Parameter::EnergyColor, scene.colors.energy);
            ui.horizontal(|ui| {
                number(
                    ui,
                    out,
                    "intensity",
                    Parameter::EnergyIntensity,
                    scene.colors.energy_intensity,
                    |x| {
                        DragValue::new(x)
                            .speed(0.02)
                            .range(0.0..=MAX_INTENSITY)
                            .max_decimals(3)
                    },
                )
                .on_hover_text("Multiplies Ce: above 1 the glow is brighter than a display color (HDR, kept in EXR exports; the viewer shows the clamp)");
            });
            color_field(
                ui,
                out,
                "background Cb",
                Parameter::BackgroundColor,
                scene.colors.background,
            );
            ui.horizontal(|ui| {
                ui.label("blend");
                for (blend, hint) in [
                    (
                        Blend::Papers,
                        "The papers' clamp((1 - B) Cb + B Ce): where B > 1 it subtracts the background, so a bright \
                         background or a lit object under a core turns dark, even black; the same as over on the \
                         papers' near-black backgrounds",
                    ),
                    (
                        Blend::Over,
                        "clamp(B Ce + (1 - min(B, 1)) Cb): the same wherever B <= 1, white-hot cores over any \
                         background, and what the transparent export composites to",
                    ),
                ] {
                    if ui
                        .selectable_label(scene.colors.blend == blend, blend.name())
                        .on_hover_text(hint)
                        .clicked()
                        && scene.colors.blend != blend
                    {
                        out.push(Action::Edit(Edit::Blend(blend)));
                    }
                }
            });
            ui.horizontal(|ui| {
                number(
                    ui,
                    out,
                    "edge cutoff",
                    Parameter::Cutoff,
                    scene.colors.cutoff,
                    |x| {
                        DragValue::new(x)
                            .speed(0.005)
                            .range(0.0..=MAX_CUTOFF)
                            .max_decimals(3)
                    },
                )
                .on_hover_text(
                    "The glow's edge: B at or below it is transparent, and the glow fades in smoothly up to twice \
                     it, so exports end in alpha 0 (sprite sheets without a hard square); 0 is the papers' \
                     glow, which never ends",
                );
            });
            if scene.colors.blend == Blend::Papers && papers_blend_darkens(scene) {
                ui.label(
                    RichText::new(
                        "papers: where B > 1 the background (and any lit object) is subtracted, so it turns \
                         dark under a bright core; \"over\" keeps it",
                    )
                    .small()
                    .weak(),
                );
            }
            view.preview_glare_threshold = glare_editor(ui, scene.glare, out);
        });
}

/// Glare on or off, and its threshold, size and strength. Whether the threshold is hovered or dragged (the
/// viewport then previews it).
fn glare_editor(ui: &mut Ui, glare: Option<Glare>, out: &mut Edits<'_>) -> bool {
    let mut on = glare.is_some();
    if ui
        .checkbox(&mut on, "glare (fog glow)")
        .on_hover_text("The glow brighter than the threshold blurred and added back, in the billboard's plane; off is the papers' look")
        .changed()
    {
        out.push(Action::Edit(Edit::Glare(on.then(Glare::default))));
    }
    let Some(g) = glare else { return false };
    let mut next = g;
    let mut previewed = false;
    ui.horizontal(|ui| {
        let threshold = labelled(
            ui,
            "threshold",
            DragValue::new(&mut next.threshold)
                .range(0.0..=100.0)
                .speed(0.02)
                .max_decimals(3),
        )
        .on_hover_text(
            "B above which the glow glares (1: only what blows out). While this is hovered or dragged the \
             viewport dims the glow that does not glare",
        );
        previewed = threshold.hovered() || threshold.dragged() || threshold.has_focus();
        labelled(
            ui,
            "size",
            DragValue::new(&mut next.size)
                .range(0.001..=MAX_GLARE_SIZE)
                .speed(0.001)
                .max_decimals(3),
        )
        .on_hover_text("The blur's width, a fraction of the billboard's side");
        labelled(
            ui,
            "strength",
            DragValue::new(&mut next.strength)
                .range(0.0..=MAX_INTENSITY)
                .speed(0.02)
                .max_decimals(3),
        );
    });
    if next != g {
        out.push(Action::Edit(Edit::Glare(Some(next))));
    }
    previewed
}

/// Fixed or automatic placement of the billboard; a fixed one's center and size.
pub(super) fn billboard_editor(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
    let scene = cx.shown;
    let b = &scene.billboard;
    let mut fixed = b.center.is_some();
    if ui
        .checkbox(&mut fixed, "fixed billboard (else placed automatically)")
        .changed()
    {
        let placement = fixed.then(|| {
            // Fixed where it is now.
            let mut automatic = scene.clone();
            (automatic.billboard.center, automatic.billboard.size) = (None, None);
            let placed = automatic.place_billboard(cx.aspect);
            (placed.center, placed.size)
        });
        out.push(Action::Edit(Edit::Billboard(placement)));
    }
    if let (Some(center), Some(size)) = (b.center, b.size) {
        let mut c = center;
        // The billboard must not contain the eye.
        if vec3(ui, "center", &mut c, 0.05).0 && (c - scene.camera.eye).length() > 1e-6 {
            out.push(Action::Edit(Edit::Billboard(Some((c, size)))));
        }
        ui.horizontal(|ui| {
            let mut l = size;
            let r = labelled(
                ui,
                "size l",
                DragValue::new(&mut l).range(1e-3..=1e5).speed(0.05),
            );
            if r.changed() && l != size {
                out.push(Action::Edit(Edit::Billboard(Some((center, l)))));
            }
        });
    }
}

/// Whether the papers' blend visibly darkens this scene where B > 1: a background brighter than the papers'
/// near-black ones, or objects, which the glow lights and the blend then subtracts.
pub(crate) fn papers_blend_darkens(scene: &Scene) -> bool {
    !scene.objects.is_empty() || scene.colors.background.iter().any(|&c| c > 0.05)
}
