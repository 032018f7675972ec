//! The viewer's interface, driven through egui_kittest like a user: the real `ViewerApp::ui`, rendered by
//! egui-wgpu on the same GPU passes as the window (lavapipe in CI).

mod common;

use common::viewer::{
    click_first, differs, export_and_wait, harness, light_scene, mean_abs_difference, undo,
    viewport_pixels,
};
use egui::accesskit::Role;
use egui::{Key, Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use energywave::integrate::Integrator;
use energywave::scene::Scene;
use energywave::viewer::ViewerApp;
use energywave::viewer::handles::{self, HandleId};

#[test]
fn the_viewport_shows_the_glow_not_a_flat_image() {
    let mut h = harness(light_scene());
    let pixels = viewport_pixels(&mut h);
    let luma: Vec<u32> = pixels
        .iter()
        .map(|p| (p[0] as u32 + p[1] as u32 + p[2] as u32) / 3)
        .collect();
    let bright = luma.iter().filter(|&&l| l > 230).count();
    let dark = luma.iter().filter(|&&l| l < 120).count();
    assert!(
        bright > 200,
        "the blown-out core is visible ({bright} bright pixels)"
    );
    assert!(
        dark > pixels.len() / 20,
        "the glow fades into the background ({dark} dark pixels)"
    );
    assert!(
        h.state().report().error.is_none(),
        "{:?}",
        h.state().report().error
    );
}

#[test]
fn editing_a_value_changes_the_scene_and_the_image() {
    let mut h = harness(light_scene());
    let before = viewport_pixels(&mut h);
    let renders = h.state().report().field_renders;
    h.get_by_role_and_label(Role::SpinButton, "radius R")
        .set_value_accesskit(2.4);
    h.run();
    assert_eq!(h.state().scene().sources.tori[0].major_radius, 2.4);
    let after = viewport_pixels(&mut h);
    assert!(
        h.state().report().field_renders > renders,
        "the field was rendered again"
    );
    let diff = mean_abs_difference(&before, &after);
    assert!(diff > 2.0, "the image changed (mean difference {diff})");
    // Colors change the image without touching the field (once a coarse field shown while editing is refined).
    for _ in 0..100 {
        if h.state().report().settled() {
            break;
        }
        h.step();
        viewport_pixels(&mut h);
    }
    assert!(h.state().report().settled(), "the picture is whole");
    let after = viewport_pixels(&mut h);
    let renders = h.state().report().field_renders;
    h.state_mut().scene_mut().colors.energy = [1.0, 0.3, 0.1];
    h.run();
    let warm = viewport_pixels(&mut h);
    assert!(mean_abs_difference(&after, &warm) > 2.0);
    assert_eq!(h.state().report().field_renders, renders);
}

#[test]
fn sources_can_be_added_duplicated_and_deleted() {
    let mut h = harness(light_scene());
    let count = |h: &Harness<'static, ViewerApp>| {
        let s = &h.state().scene().sources;
        (s.points.len(), s.lines.len(), s.tori.len(), s.curves.len())
    };
    assert_eq!(count(&h), (0, 0, 1, 1));
    h.get_by_label("+ point").click();
    h.run();
    h.get_by_label("+ line").click();
    h.run();
    assert_eq!(count(&h), (1, 1, 1, 1));
    // The first Duplicate button belongs to the first source listed, the point (scrolled to: the Rendering
    // section's rows push the sources' editors down).
    let first = |h: &mut Harness<'static, ViewerApp>, label: &str| {
        h.get_all_by_label(label).next().unwrap().scroll_to_me();
        h.run();
        h.get_all_by_label(label).next().unwrap().click();
        h.run();
    };
    first(&mut h, "Duplicate");
    assert_eq!(count(&h), (2, 1, 1, 1));
    first(&mut h, "Delete");
    first(&mut h, "Delete");
    assert_eq!(count(&h), (0, 1, 1, 1));
    h.get_by_label("+ curve").click();
    h.run();
    assert_eq!(count(&h), (0, 1, 1, 2));
    assert!(h.state().document().is_dirty() && h.state().document().title().ends_with('*'));
}

#[test]
fn undo_and_redo_restore_the_state() {
    let mut h = harness(light_scene());
    let original = h.state().scene().clone();
    h.get_by_role_and_label(Role::SpinButton, "divisions n")
        .set_value_accesskit(64.0);
    h.run();
    h.get_by_label("+ point").click();
    h.run();
    let edited = h.state().scene().clone();
    assert_eq!(
        (edited.integration.divisions, edited.sources.points.len()),
        (64, 1)
    );
    undo(&mut h);
    assert_eq!(h.state().scene().sources.points.len(), 0);
    assert_eq!(h.state().scene().integration.divisions, 64);
    undo(&mut h);
    assert_eq!(*h.state().scene(), original);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(*h.state().scene(), edited);
}

#[test]
fn invalid_entries_are_refused() {
    let mut h = harness(light_scene());
    let limit = h.state().max_resolution();
    h.get_by_role_and_label(Role::SpinButton, "divisions n")
        .set_value_accesskit(201.0);
    h.run();
    let n = h.state().scene().integration.divisions;
    assert!(
        n % 2 == 0 && (200..=202).contains(&n),
        "odd division counts are refused: {n}"
    );
    h.get_by_role_and_label(Role::SpinButton, "radius R")
        .set_value_accesskit(-3.0);
    h.run();
    assert!(h.state().scene().sources.tori[0].major_radius > 0.0);
    h.get_by_role_and_label(Role::SpinButton, "decay length")
        .set_value_accesskit(0.0);
    h.run();
    assert!(h.state().scene().integration.decay_length > 0.0);
    h.get_by_role_and_label(Role::SpinButton, "\u{3b5} (clamp)")
        .set_value_accesskit(0.0);
    h.run();
    assert!(h.state().scene().integration.epsilon > 0.0);
    h.get_by_role_and_label(Role::SpinButton, "resolution W")
        .set_value_accesskit(1e9);
    h.run();
    let w = h.state().scene().billboard.resolution;
    assert!(
        w <= limit && w <= energywave::viewer::panel::PANEL_MAX_RESOLUTION,
        "{w}"
    );
    // Back to a resolution that renders quickly here.
    h.get_by_role_and_label(Role::SpinButton, "resolution W")
        .set_value_accesskit(64.0);
    h.run();
    // Whatever was typed, the scene still validates as a file would, and renders without a GPU error.
    let text = h.state().scene().to_toml();
    Scene::parse(&text, std::path::Path::new("after-edits.toml")).unwrap();
    viewport_pixels(&mut h);
    assert!(
        h.state().report().error.is_none(),
        "{:?}",
        h.state().report().error
    );
}

#[test]
fn dragging_a_control_point_bends_the_curve() {
    let mut h = harness(light_scene());
    let id = HandleId::Control { curve: 0, index: 3 };
    let before_point = handles::get(h.state().scene(), id).unwrap();
    let rect = h.state().viewport_rect();
    let start = handles::to_screen(&h.state().scene().camera, rect, before_point).unwrap();
    let end = start + Vec2::new(60.0, -80.0);
    let before = viewport_pixels(&mut h);
    h.hover_at(start);
    h.run();
    h.drag_at(start);
    h.run();
    for k in 1..=6 {
        h.hover_at(start + (end - start) * (k as f32 / 6.0));
        h.run();
    }
    h.drop_at(end);
    h.run();
    let moved = handles::get(h.state().scene(), id).unwrap();
    let landed = handles::to_screen(&h.state().scene().camera, rect, moved).unwrap();
    assert!(
        landed.distance(end) < 3.0,
        "the handle follows the pointer: {landed:?} vs {end:?}"
    );
    assert_eq!(
        h.state().scene().camera,
        light_scene().camera,
        "dragging a handle does not orbit"
    );
    let after = viewport_pixels(&mut h);
    assert!(
        mean_abs_difference(&before, &after) > 1.0,
        "the glow moved with the curve"
    );
    // One drag, one undo step.
    undo(&mut h);
    assert_eq!(handles::get(h.state().scene(), id), Some(before_point));

    // The rest of the movement and the release arriving in one frame (as when a frame is slow) are applied.
    h.hover_at(start);
    h.run();
    h.drag_at(start);
    h.run();
    h.hover_at(start + Vec2::new(10.0, 0.0));
    h.run();
    h.hover_at(start + (end - start) * 0.5);
    h.hover_at(end);
    h.drop_at(end);
    h.run();
    let moved = handles::get(h.state().scene(), id).unwrap();
    let landed = handles::to_screen(&h.state().scene().camera, rect, moved).unwrap();
    assert!(
        landed.distance(end) < 3.0,
        "batched movement is applied: {landed:?} vs {end:?}"
    );
}

#[test]
fn dragging_empty_space_orbits_and_the_wheel_zooms() {
    let mut h = harness(light_scene());
    let rect = h.state().viewport_rect();
    let camera = h.state().scene().camera.clone();
    let start = Pos2::new(rect.right() - 40.0, rect.bottom() - 40.0);
    h.hover_at(start);
    h.run();
    h.drag_at(start);
    h.run();
    h.hover_at(start - Vec2::new(120.0, 30.0));
    h.run();
    h.drop_at(start - Vec2::new(120.0, 30.0));
    h.run();
    let orbited = h.state().scene().camera.clone();
    assert_ne!(orbited.eye, camera.eye);
    assert_eq!(orbited.target, camera.target);
    // Kept, to the millionth of it navigation rounds the camera to.
    assert!(
        ((orbited.eye - orbited.target).length() - (camera.eye - camera.target).length()).abs()
            < 1e-5
    );
    assert!(
        !h.state().history().can_undo(),
        "navigation is not an undo step"
    );
    h.hover_at(rect.center());
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: Vec2::new(0.0, 120.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Wheel,
        modifiers: Modifiers::NONE,
    });
    h.run();
    let zoomed = &h.state().scene().camera;
    assert!((zoomed.eye - zoomed.target).length() < (orbited.eye - orbited.target).length());
}

#[test]
fn the_w_series_editor_shapes_the_glow() {
    let mut h = harness(light_scene());
    let before = viewport_pixels(&mut h);
    h.get_by_role_and_label(Role::Slider, "w1")
        .set_value_accesskit(0.0);
    h.run();
    assert_eq!(h.state().scene().sources.curves[0].weights[1], 0.0);
    // Below the panel's fold: pressed through accessibility, as a screen reader would.
    h.get_by_label("+ weight").click_accesskit();
    h.run();
    assert_eq!(h.state().scene().sources.curves[0].weights.len(), 6);
    let after = viewport_pixels(&mut h);
    let diff = mean_abs_difference(&before, &after);
    assert!(diff > 0.3, "the glow changed: mean difference {diff}");
    h.get_by_label("uniform").click_accesskit();
    h.run();
    assert!(h.state().scene().sources.curves[0].weights.is_empty());
}

#[test]
fn unsaved_changes_are_not_lost_without_asking() {
    use energywave::viewer::Request;
    let mut h = harness(light_scene());
    // Clean: quitting needs no question.
    h.state_mut().request_quit();
    h.run();
    assert_eq!(h.state_mut().take_requests(), vec![Request::Quit]);
    // Dirty: a prompt; Cancel keeps everything.
    h.get_by_label("+ point").click();
    h.run();
    h.state_mut().request_quit();
    h.run();
    h.get_by_label("Cancel").click();
    h.run();
    assert!(h.state_mut().take_requests().is_empty());
    assert_eq!(h.state().scene().sources.points.len(), 1);
    // Opening another file asks too; Discard goes ahead.
    let dir = std::env::temp_dir().join(format!("energywave-ui-open-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let other = dir.join("other.toml");
    let mut other_scene = light_scene();
    other_scene.sources.curves.clear();
    std::fs::write(&other, other_scene.to_toml()).unwrap();
    // The file dialog opens beside the typed path, with its name picked.
    *h.state_mut().path_input_mut() = other.display().to_string();
    h.get_by_label("Open\u{2026}").click();
    h.run();
    h.get_by_label("Open").click();
    h.run();
    assert!(
        h.query_by_label("Unsaved changes").is_some(),
        "the prompt is shown"
    );
    h.get_by_label("Discard").click();
    h.run();
    assert_eq!(*h.state().scene(), other_scene);
    assert!(!h.state().document().is_dirty());
    assert!(
        !h.state().history().can_undo(),
        "a new document starts a new history"
    );
    // Saving clears the mark; the file holds the edits.
    h.get_by_label("+ torus").click();
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run();
    assert!(!h.state().document().is_dirty());
    assert_eq!(
        energywave::scene::Scene::load(&other)
            .unwrap()
            .sources
            .tori
            .len(),
        other_scene.sources.tori.len() + 1
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The travelling-pulse preset, light enough for a software rasteriser.
fn pulse_scene() -> Scene {
    let mut s = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes/pulse_travelling.toml"),
    )
    .unwrap();
    s.billboard.resolution = 64;
    s.integration.divisions = 48;
    s
}

fn repaints_continuously(h: &Harness<'static, ViewerApp>) -> bool {
    h.output()
        .viewport_output
        .get(&egui::ViewportId::ROOT)
        .is_some_and(|v| v.repaint_delay.is_zero())
}

#[test]
fn the_animated_preset_plays_steps_scrubs_loops_and_edits_while_paused() {
    let mut h = harness(pulse_scene());
    assert_eq!(h.state().playback().frame, 0);
    assert!(!repaints_continuously(&h), "paused: no continuous repaint");
    // The preset's loop starts 46 frames into eq. 5.1's run: frame 0 has the pulse halfway along the curve,
    // frame 40 (the thesis's 86) near its end, so the two pictures differ.
    let halfway = viewport_pixels(&mut h);
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(40.0);
    h.run();
    assert_eq!(h.state().playback().frame, 40);
    let near_end = viewport_pixels(&mut h);
    assert!(
        mean_abs_difference(&halfway, &near_end) > 5.0,
        "the pulse moves"
    );
    // What is drawn is the scene at that frame: eq. 5.1 at the thesis's frame 86, w_6 with
    // theta = (86 - 42) pi / 25 and w_2 past its lit span (theta > 2 pi), 0.
    let w = h.state().frame_scene().sources.curves[0].weights.clone();
    let theta = 44.0 * std::f64::consts::PI / 25.0;
    assert!((w[6] - ((-theta.cos() + 0.8) / 1.5).clamp(0.0, 1.0)).abs() < 1e-12);
    assert_eq!(w[2], 0.0);

    // Step forward and back.
    h.get_by_label("Step >").click();
    h.run();
    assert_eq!(h.state().playback().frame, 41);
    h.get_by_label("< Step").click();
    h.get_by_label("< Step").click();
    h.run();
    assert_eq!(h.state().playback().frame, 39);

    // Play: frames advance with time and the viewer repaints continuously, only while playing.
    h.get_by_label("Play").click();
    h.step();
    h.step();
    h.step();
    assert!(h.state().playback().playing);
    assert!(h.state().playback().frame > 39, "frames advance");
    assert!(repaints_continuously(&h));
    h.get_by_label("Pause").click();
    h.run();
    let paused_at = h.state().playback().frame;
    h.run();
    assert_eq!(h.state().playback().frame, paused_at);
    assert!(!repaints_continuously(&h));

    // Looping wraps past the last frame; without it playback stops there.
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(90.0);
    h.run();
    h.key_press(Key::Space);
    h.step();
    h.step();
    assert!(h.state().playback().frame < 90, "wrapped to the start");
    h.key_press(Key::Space);
    h.run();
    h.get_by_label("loop").click();
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(90.0);
    h.run();
    h.key_press(Key::Space);
    h.step();
    h.step();
    h.run();
    assert_eq!(h.state().playback().frame, 91);
    assert!(!h.state().playback().playing, "stopped on the last frame");

    // Playback is not a document edit.
    assert!(!h.state().history().can_undo());
    assert!(!h.state().document().is_dirty());

    // An edit while paused: the pulse's width; it is an undo step, and undo leaves the frame alone.
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(40.0);
    h.run();
    let before = viewport_pixels(&mut h);
    h.get_by_role_and_label(Role::SpinButton, "width (frames)")
        .set_value_accesskit(20.0);
    h.run();
    let pulse = |h: &Harness<'static, ViewerApp>| {
        h.state().scene().animation.as_ref().unwrap().pulses[0]
            .pulse
            .clone()
    };
    assert_eq!(pulse(&h).width, 20.0);
    let after = viewport_pixels(&mut h);
    assert!(mean_abs_difference(&before, &after) > 2.0, "the edit shows");
    undo(&mut h);
    assert_eq!(pulse(&h).width, 50.0);
    assert_eq!(h.state().playback().frame, 40);
    assert!(h.state().report().error.is_none());
}

#[test]
fn a_still_scene_can_be_animated_with_a_key() {
    let mut h = harness(light_scene());
    assert!(
        h.query_by_label("Play").is_none(),
        "no transport for a still scene"
    );
    h.get_by_label("Animate").click_accesskit();
    h.run();
    assert!(h.state().scene().is_animated());
    // Key the torus's coefficient at frame 0 (the path typed in the Animation section), then at frame 50.
    h.state_mut().animation_form_mut().new_track = "tori[0].coefficient".into();
    h.get_by_label("key at frame 0").click_accesskit();
    h.run();
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(50.0);
    h.run();
    // Both the track's button and the one beside the typed path key the track at the current frame.
    h.state_mut().animation_form_mut().new_track = "tori[0].coefficient".into();
    for button in h.get_all_by_label("key at frame 50") {
        button.click_accesskit();
    }
    h.run();
    let a = h.state().scene().animation.clone().unwrap();
    assert_eq!(h.state().playback().frame, 50, "{:?}", h.state().notice());
    assert_eq!(a.tracks.len(), 1, "{:?}", h.state().notice());
    let frames: Vec<f64> = a.tracks[0].keys.iter().map(|k| k.frame).collect();
    assert_eq!(frames, [0.0, 50.0]);
    assert!(h.state().history().can_undo(), "keys are document edits");
}

#[test]
fn the_viewer_exports_a_sprite_sheet_beside_the_ui() {
    let dir = std::env::temp_dir().join(format!("energywave-viewer-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut scene = pulse_scene();
    scene.billboard.resolution = 24;
    scene.integration.divisions = 24;
    scene.animation.as_mut().unwrap().frames = 5;
    let mut h = harness(scene);
    h.get_by_label("Export").click_accesskit();
    h.run();
    {
        let form = h.state_mut().animation_form_mut();
        form.export_kind = energywave::viewer::animation_panel::ExportKind::Sheet;
        form.export_path = dir.join("sheet.png").display().to_string();
        form.size = [20, 16];
    }
    h.run();
    let notice = export_and_wait(&mut h, "Export 5 frames");
    assert!(
        notice
            .as_ref()
            .is_some_and(|(t, e)| !e && t.starts_with("Exported")),
        "{notice:?}"
    );
    let sheet = image::open(dir.join("sheet.png")).unwrap();
    // Five frames: three columns, two rows.
    assert_eq!((sheet.width(), sheet.height()), (60, 32));
    assert!(dir.join("sheet.json").is_file());
}

#[test]
fn editing_a_keyed_value_while_paused_sets_a_key_at_that_frame() {
    let mut scene = light_scene();
    let text = format!(
        "{}\n[animation]\nframes = 30\n[[animation.tracks]]\nparameter = \"tori[0].major_radius\"\nkeys = [{{ frame = 0, value = 1.0 }}, {{ frame = 20, value = 2.0 }}]\n",
        scene.to_toml()
    );
    scene = Scene::parse(&text, std::path::Path::new("keyed.toml")).unwrap();
    let base = scene.sources.tori[0].major_radius;
    let mut h = harness(scene);
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(10.0);
    h.run();
    // The panel shows the keyed value at frame 10, 1.5 (by hand: halfway from 1 to 2), not the base value.
    assert_eq!(
        h.get_by_role_and_label(Role::SpinButton, "radius R")
            .accesskit_node()
            .numeric_value(),
        Some(1.5)
    );
    assert!(
        !h.state().document().is_dirty(),
        "showing keyed values is not an edit"
    );
    h.get_by_role_and_label(Role::SpinButton, "radius R")
        .set_value_accesskit(2.4);
    h.run();
    let scene = h.state().scene().clone();
    let keys: Vec<(f64, f64)> = scene.animation.as_ref().unwrap().tracks[0]
        .keys
        .iter()
        .map(|k| match k.value {
            energywave::animation::Value::Number(x) => (k.frame, x),
            _ => panic!("a number"),
        })
        .collect();
    assert_eq!(keys, [(0.0, 1.0), (10.0, 2.4), (20.0, 2.0)]);
    assert_eq!(
        scene.sources.tori[0].major_radius, base,
        "the base value stays"
    );
    assert_eq!(scene.at_frame(10.0).sources.tori[0].major_radius, 2.4);
    // The new key is an undo step.
    undo(&mut h);
    assert_eq!(
        h.state().scene().animation.as_ref().unwrap().tracks[0]
            .keys
            .len(),
        2
    );
}

#[test]
fn the_integrator_switch_shows_each_integrators_settings_and_is_undoable() {
    let mut h = harness(light_scene());
    assert!(h.query_by_label("tolerance").is_none());
    h.get_by_role_and_label(Role::SpinButton, "divisions n");
    let simpson = viewport_pixels(&mut h);
    h.get_by_label("adaptive").click();
    h.run();
    assert_eq!(
        h.state().scene().integration.integrator,
        Integrator::Adaptive
    );
    assert!(h.query_by_label("divisions n").is_none());
    h.get_by_role_and_label(Role::SpinButton, "tolerance")
        .set_value_accesskit(0.001);
    h.run();
    assert_eq!(h.state().scene().integration.tolerance, 0.001);
    // Both integrate the same field: the picture barely changes (n = 64 against a converged one).
    let adaptive = viewport_pixels(&mut h);
    let d = mean_abs_difference(&simpson, &adaptive);
    assert!(d < 3.0, "mean difference {d}");
    undo(&mut h);
    undo(&mut h);
    assert_eq!(
        h.state().scene().integration.integrator,
        Integrator::Simpson
    );
    // Jitter belongs to simpson.
    h.get_by_label("jitter (noise instead of bands)").click();
    h.run();
    assert_eq!(h.state().scene().integration.jitter, Some(0));
}

#[test]
fn objects_can_be_added_edited_moved_by_their_handle_deleted_and_undone() {
    use energywave::objects::Shape;
    let mut h = harness(light_scene());
    let before = viewport_pixels(&mut h);
    let click = click_first;
    click(&mut h, "+ sphere");
    click(&mut h, "+ plane");
    assert_eq!(h.state().scene().objects.len(), 2);
    // The sphere at the camera's target hides the glow behind it and shows (the image changes).
    let with = viewport_pixels(&mut h);
    assert!(
        mean_abs_difference(&before, &with) > 1.0,
        "the objects show"
    );
    // Its radius edited in the panel.
    let radius = h.get_by_role_and_label(Role::SpinButton, "radius");
    radius.set_value_accesskit(0.9);
    h.run();
    assert!(
        matches!(h.state().scene().objects[0].shape, Shape::Sphere { radius, .. } if radius == 0.9)
    );
    // Dragged by its handle at its center (put clear of the torus's center, which the camera's target shares):
    // it follows the pointer, one undo step.
    let away = h.state().scene().objects[0].moved_to(glam::DVec3::new(1.6, -1.1, 0.4));
    h.state_mut().scene_mut().objects[0] = away;
    h.run();
    let id = HandleId::Object(0);
    let at = handles::get(h.state().scene(), id).unwrap();
    let rect = h.state().viewport_rect();
    let start = handles::to_screen(&h.state().scene().camera, rect, at).unwrap();
    let end = start + Vec2::new(40.0, 30.0);
    h.hover_at(start);
    h.run();
    h.drag_at(start);
    h.run();
    for k in 1..=4 {
        h.hover_at(start + (end - start) * (k as f32 / 4.0));
        h.run();
    }
    h.drop_at(end);
    h.run();
    let moved = handles::get(h.state().scene(), id).unwrap();
    let landed = handles::to_screen(&h.state().scene().camera, rect, moved).unwrap();
    assert!(landed.distance(end) < 3.0, "{landed:?} vs {end:?}");
    assert_eq!(h.state().selected_object(), Some(0), "dragging selects it");
    undo(&mut h);
    assert_eq!(handles::get(h.state().scene(), id), Some(at));
    // Deleted (the plane is the second entry's Delete, after the sources'), and undone.
    let deletes = h.get_all_by_label("Delete").count();
    h.get_all_by_label("Delete")
        .nth(deletes - 1)
        .unwrap()
        .scroll_to_me();
    h.run();
    h.get_all_by_label("Delete")
        .nth(deletes - 1)
        .unwrap()
        .click();
    h.run();
    assert_eq!(h.state().scene().objects.len(), 1);
    undo(&mut h);
    assert_eq!(h.state().scene().objects.len(), 2);
    // Saved and read back with its objects.
    let text = h.state().scene().to_toml();
    let back = Scene::parse(&text, std::path::Path::new("s.toml")).unwrap();
    assert_eq!(back.objects, h.state().scene().objects);
    assert!(
        h.state().report().error.is_none(),
        "{:?}",
        h.state().report().error
    );
}

/// A set's emission edited in the panel (its color and intensity keyable like its albedo): the smoke glows by
/// itself in the viewport, brighter than it was, and one undo takes it back.
#[test]
fn a_sets_emission_is_edited_in_the_panel_and_glows_in_the_viewport() {
    let mut h = harness(light_scene());
    click_first(&mut h, "+ smoke");
    assert_eq!(h.state().scene().particles[0].emission.intensity, 0.0);
    let before = viewport_pixels(&mut h);
    h.get_by_role_and_label(Role::SpinButton, "emission intensity")
        .set_value_accesskit(4.0);
    h.run();
    assert_eq!(h.state().scene().particles[0].emission.intensity, 4.0);
    let glowing = viewport_pixels(&mut h);
    let brightness = |p: &[[u8; 4]]| {
        p.iter()
            .map(|c| c[0] as f64 + c[1] as f64 + c[2] as f64)
            .sum::<f64>()
    };
    // Brighter, and visibly so where the smoke is (as much as the smoke itself shows in its own test).
    let d = mean_abs_difference(&before, &glowing);
    assert!(
        brightness(&glowing) > brightness(&before) && d > 1.0,
        "the smoke glows: {} against {}, {d} apart",
        brightness(&glowing),
        brightness(&before)
    );
    assert!(
        h.get_all_by_label("key particles[0].emission_intensity")
            .count()
            == 1
    );
    undo(&mut h);
    assert_eq!(h.state().scene().particles[0].emission.intensity, 0.0);
    assert!(
        !differs(&viewport_pixels(&mut h), &before),
        "undone, the picture is as it was"
    );
}

#[test]
fn particle_sets_can_be_added_edited_deleted_and_undone_and_show_in_the_viewport() {
    use energywave::particles::Origin;
    let mut h = harness(light_scene());
    let before = viewport_pixels(&mut h);
    let click = click_first;
    click(&mut h, "+ smoke");
    assert_eq!(h.state().scene().particles.len(), 1);
    // A cloud at the camera's target: it shows (the image changes).
    let with = viewport_pixels(&mut h);
    let d = mean_abs_difference(&before, &with);
    assert!(d > 1.0, "the smoke shows: {d}");
    // Its count and the slices' width edited in the panel, each one undo step.
    h.get_by_role_and_label(Role::SpinButton, "count")
        .set_value_accesskit(120.0);
    h.run();
    let Origin::Emitter(e) = &h.state().scene().particles[0].origin else {
        panic!("an emitter");
    };
    assert_eq!(e.count, 120);
    h.get_by_role_and_label(Role::SpinButton, "slices")
        .set_value_accesskit(0.25);
    h.run();
    assert_eq!(h.state().scene().slice_width, 0.25);
    undo(&mut h);
    assert_eq!(h.state().scene().slice_width, 0.5);
    // Duplicated with the next seed (the set's is the last Duplicate of the panel, after the sources').
    let last = h.get_all_by_label("Duplicate").count() - 1;
    h.get_all_by_label("Duplicate")
        .nth(last)
        .unwrap()
        .scroll_to_me();
    h.run();
    h.get_all_by_label("Duplicate").nth(last).unwrap().click();
    h.run();
    let sets = &h.state().scene().particles;
    assert_eq!(sets.len(), 2);
    assert_ne!(sets[0], sets[1]);
    // Dust around the ring; saved and read back with every set.
    click(&mut h, "+ ring dust");
    assert_eq!(h.state().scene().particles.len(), 3);
    let text = h.state().scene().to_toml();
    let back = Scene::parse(&text, std::path::Path::new("s.toml")).unwrap();
    assert_eq!(back.particles, h.state().scene().particles);
    undo(&mut h);
    undo(&mut h);
    assert_eq!(h.state().scene().particles.len(), 1);
    // Deleting the torus the ring dust follows takes the dust with it: the scene still saves as a valid file.
    click(&mut h, "+ ring dust");
    assert_eq!(h.state().scene().particles.len(), 2);
    h.state_mut()
        .apply(energywave::viewer::action::Action::Edit(
            energywave::viewer::action::Edit::DeleteSource(
                energywave::animation::SourceKind::Tori,
                0,
            ),
        ));
    h.run();
    assert!(h.state().scene().sources.tori.is_empty());
    assert_eq!(h.state().scene().particles.len(), 1);
    let text = h.state().scene().to_toml();
    Scene::parse(&text, std::path::Path::new("s.toml")).unwrap();
    assert!(
        h.state().report().error.is_none(),
        "{:?}",
        h.state().report().error
    );
}

#[test]
fn hovering_the_glare_threshold_previews_what_glares() {
    let mut scene = light_scene();
    // The default scene's B is above 0.5 nearly everywhere in frame: a threshold that leaves the cores.
    scene.glare = Some(energywave::scene::Glare {
        threshold: 2.0,
        ..Default::default()
    });
    let mut h = harness(scene);
    let plain = viewport_pixels(&mut h);
    h.get_by_role_and_label(Role::SpinButton, "threshold")
        .hover();
    h.run();
    assert!(h.state().view().preview_glare_threshold);
    let previewed = viewport_pixels(&mut h);
    // The glow at or below the threshold is dimmed to a quarter; the cores that glare are kept.
    let luma = |p: &[u8; 4]| (p[0] as u32 + p[1] as u32 + p[2] as u32) / 3;
    let dimmed = plain
        .iter()
        .zip(&previewed)
        .filter(|(a, b)| luma(a) > 40 && luma(b) * 2 < luma(a))
        .count();
    let kept = plain
        .iter()
        .zip(&previewed)
        .filter(|(a, b)| luma(a) > 240 && luma(b) > 240)
        .count();
    let glowing = plain.iter().filter(|a| luma(a) > 40).count();
    assert!(
        dimmed > glowing / 4,
        "{dimmed} of {glowing} glowing pixels dimmed"
    );
    assert!(kept > 100, "{kept} glaring pixels kept");
    // Away from it, the picture is the plain one again.
    h.hover_at(Pos2::new(2.0, 2.0));
    h.run();
    assert!(!h.state().view().preview_glare_threshold);
    let again = viewport_pixels(&mut h);
    assert!(mean_abs_difference(&plain, &again) < 0.5);
}

#[test]
fn overlays_toggle_by_button_and_key_and_the_guides_let_the_glow_through() {
    let mut scene = light_scene();
    // A dimmer beam, its core not blown out, so the guide on it shows as it is.
    scene.sources.curves[0].coefficient = 1.0;
    let mut h = harness(scene);
    // The guides and handles alone (the grid has its own switch).
    h.state_mut().view_mut().show_grid = false;
    h.run();
    let with = viewport_pixels(&mut h);
    h.get_by_label("Overlays").click();
    h.run();
    assert!(!h.state().view().show_overlays);
    let without = viewport_pixels(&mut h);
    // The grid, guides and handles are gone, and nothing else changed: only few pixels differ.
    let differ = with
        .iter()
        .zip(&without)
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 2))
        .count();
    assert!(differ > 200, "the overlays drew something: {differ}");
    // The guides are thin and translucent: over the glow they shift a pixel by well under half its value
    // (they were a crisp white line on the beam's core).
    let luma = |p: &[u8; 4]| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0;
    let on_glow: Vec<f64> = with
        .iter()
        .zip(&without)
        .filter(|(_, b)| luma(b) > 60.0 && luma(b) < 200.0)
        .map(|(a, b)| (luma(a) - luma(b)).abs())
        .collect();
    // The handles (a few discs) are opaque; the guides (long lines) are most of what changed.
    let mut changed: Vec<f64> = on_glow.into_iter().filter(|&d| d > 2.0).collect();
    changed.sort_by(f64::total_cmp);
    let typical = changed[changed.len() * 3 / 4];
    // Measured: 18 now, 70 with the old opaque white guides.
    assert!(
        typical < 40.0,
        "a guide changes the glow under it by {typical} (75th percentile)"
    );
    // Shift+Alt+Z brings them back, as in Blender.
    h.key_press_modifiers(Modifiers::SHIFT | Modifiers::ALT, Key::Z);
    h.run();
    assert!(h.state().view().show_overlays);
    assert!(mean_abs_difference(&with, &viewport_pixels(&mut h)) < 0.5);
}

#[test]
fn a_live_set_is_added_edited_keyed_and_played_in_the_viewer() {
    use energywave::animation::{Parameter, ParticleField};
    let mut h = harness(light_scene());
    assert!(h.state().scene().animation.is_none());
    let click = click_first;
    click(&mut h, "+ fountain");
    // A live set needs a timeline: the still scene got one.
    assert_eq!(h.state().scene().particles.len(), 1);
    assert!(h.state().scene().particles[0].life().is_some());
    assert!(h.state().scene().animation.is_some());
    let first = viewport_pixels(&mut h);
    // Its rate edited in the panel, one undo step; then keyed at frame 0 by its key button.
    h.get_by_role_and_label(Role::SpinButton, "rate /s")
        .set_value_accesskit(450.0);
    h.run();
    assert_eq!(h.state().scene().particles[0].life().unwrap().rate, 450.0);
    undo(&mut h);
    assert_eq!(h.state().scene().particles[0].life().unwrap().rate, 200.0);
    click(&mut h, "key particles[0].rate");
    let keyed = Parameter::Particles(0, ParticleField::Rate);
    assert!(
        h.state()
            .scene()
            .animation
            .as_ref()
            .unwrap()
            .track(&keyed)
            .is_some()
    );
    // Twenty frames on, the fountain has risen: the viewport shows the scene at that frame, particles included.
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(20.0);
    h.run();
    assert_eq!(h.state().playback().frame, 20);
    let later = viewport_pixels(&mut h);
    let d = mean_abs_difference(&first, &later);
    assert!(d > 0.5, "the particles show: {d}");
    let shown = h.state().frame_scene();
    let expected = h.state().scene().at_frame(20.0);
    assert_eq!(shown.particles, expected.particles);
    assert!(shown.particles[0].live.as_ref().unwrap().len() > 100);
    // Motion blur: the shutter opened in the panel draws each moving particle as copies along its path.
    let sharp = shown.particles[0].live.as_ref().unwrap().len();
    h.get_by_role_and_label(Role::Slider, "shutter")
        .set_value_accesskit(1.0);
    h.run();
    assert_eq!(h.state().scene().particles[0].life().unwrap().shutter, 1.0);
    let blurred = h.state().frame_scene().particles[0]
        .live
        .as_ref()
        .unwrap()
        .len();
    assert!(blurred > sharp, "{blurred} copies of {sharp} particles");
    // Turbulence switched on; saved and read back whole.
    click(&mut h, "turbulence");
    assert!(
        h.state().scene().particles[0]
            .life()
            .unwrap()
            .turbulence
            .is_some()
    );
    let text = h.state().scene().to_toml();
    let back = Scene::parse(&text, std::path::Path::new("s.toml")).unwrap();
    assert_eq!(back.particles, h.state().scene().particles);
    assert!(
        h.state().report().error.is_none(),
        "{:?}",
        h.state().report().error
    );
}

#[test]
fn an_object_made_translucent_in_the_panel_lets_the_glow_through_and_undoes() {
    let mut h = harness(light_scene());
    click_first(&mut h, "+ sphere");
    let opaque = viewport_pixels(&mut h);
    assert!(h.state().scene().objects[0].translucent.is_none());
    common::viewer::click_label(&mut h, "translucent");
    let t = h.state().scene().objects[0].translucent.clone();
    assert!(t.is_some(), "the switch makes it translucent");
    // Its extinction edited: one undo step like every edit.
    let extinction = h.get_by_role_and_label(Role::SpinButton, "extinction");
    extinction.set_value_accesskit(0.5);
    h.run();
    let t = h.state().scene().objects[0].translucent.clone().unwrap();
    assert_eq!(t.extinction, 0.5);
    // The glow behind the sphere shows through it now: the picture changes.
    let clear = viewport_pixels(&mut h);
    let changed = (opaque.iter().zip(&clear))
        .filter(|(p, q)| (0..3).any(|c| (p[c] as i32 - q[c] as i32).abs() > 16))
        .count();
    assert!(
        changed * 100 > opaque.len(),
        "the glow shows through: {changed} pixels changed"
    );
    undo(&mut h);
    assert_eq!(
        h.state().scene().objects[0]
            .translucent
            .as_ref()
            .unwrap()
            .extinction,
        energywave::objects::translucent::Translucent::default().extinction
    );
    undo(&mut h);
    assert!(h.state().scene().objects[0].translucent.is_none());
}
