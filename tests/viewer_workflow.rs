//! The viewer's first ten minutes, driven through egui_kittest like a user: looking is not editing, messages
//! that tell the truth, keys without typing paths, selection, screenshots, exports and saves that behave.

mod common;

use common::viewer::{
    click_label, differs, export_and_wait, export_sequence, harness, light_scene, undo,
};
use egui::{Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use energywave::viewer::{Request, ViewerApp};

/// Drags with the primary button from `from` by `by`, in a few moves.
fn drag(h: &mut Harness<'static, ViewerApp>, from: Pos2, by: Vec2) {
    h.hover_at(from);
    h.run();
    h.drag_at(from);
    h.run();
    for k in 1..=4 {
        h.hover_at(from + by * (k as f32 / 4.0));
        h.run();
    }
    h.drop_at(from + by);
    h.run();
}

#[test]
fn orbiting_is_not_an_edit() {
    let mut h = harness(light_scene());
    let rect = h.state().viewport_rect();
    let camera = h.state().scene().camera.clone();
    drag(
        &mut h,
        Pos2::new(rect.right() - 40.0, rect.bottom() - 40.0),
        Vec2::new(-120.0, -30.0),
    );
    assert_ne!(h.state().scene().camera, camera, "the view moved");
    assert!(!h.state().document().is_dirty());
    assert!(
        !h.state().window_title().contains('*'),
        "{}",
        h.state().window_title()
    );
    // Closing asks nothing.
    h.state_mut().request_quit();
    h.run();
    assert_eq!(h.state_mut().take_requests(), vec![Request::Quit]);
    // An edit is one, and the window's title says so.
    h.get_by_label("+ point").click();
    h.run();
    assert!(h.state().window_title().starts_with("default scene *"));
}

#[test]
fn messages_clear_at_the_next_action_and_expire() {
    let mut h = harness(light_scene());
    h.get_by_label("+ point").click();
    h.run();
    h.get_by_label("Undo").click();
    h.run();
    assert_eq!(h.state().notice().map(|n| n.0.as_str()), Some("Undone"));
    // The next edit is not "undone".
    h.get_by_label("+ line").click();
    h.run();
    assert_eq!(h.state().notice(), None);
    // A message that is not an error leaves by itself.
    h.get_by_label("Undo").click();
    h.run();
    assert!(h.state().notice().is_some());
    let steps = (energywave::viewer::app::NOTICE_SECONDS * 60.0) as usize + 30;
    for _ in 0..steps {
        h.step();
    }
    assert_eq!(h.state().notice(), None, "expired");
    // An error stays until the next action (Save with no file and no name to save to).
    h.get_by_label("Save").click();
    h.run();
    assert!(
        h.state().notice().is_some_and(|n| n.1),
        "{:?}",
        h.state().notice()
    );
    for _ in 0..steps {
        h.step();
    }
    assert!(h.state().notice().is_some_and(|n| n.1));
    h.get_by_label("+ torus").click();
    h.run();
    assert_eq!(h.state().notice(), None);
}

#[test]
fn a_fixed_file_clears_its_error_and_the_reload_prompt_fits_the_panel() {
    let dir = std::env::temp_dir().join(format!("energywave-ui-disk-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    let scene = light_scene();
    std::fs::write(&path, scene.to_toml()).unwrap();
    let mut h = harness(scene.clone());
    h.state_mut()
        .apply(energywave::viewer::Action::Open(path.clone()));
    h.run();
    let touch = |k: u64| {
        let t = std::time::SystemTime::now() + std::time::Duration::from_secs(10 * k);
        std::fs::File::options()
            .write(true)
            .open(&path)
            .unwrap()
            .set_modified(t)
            .unwrap();
    };
    // A broken file on disk: said, and the scene kept.
    std::fs::write(&path, "[camera]\neye = [0, 0\n").unwrap();
    touch(1);
    std::thread::sleep(std::time::Duration::from_millis(450));
    h.run();
    assert!(
        h.state().notice().is_some_and(|n| n.1),
        "{:?}",
        h.state().notice()
    );
    // Fixed: the error goes.
    std::fs::write(&path, scene.to_toml()).unwrap();
    touch(2);
    std::thread::sleep(std::time::Duration::from_millis(450));
    h.run();
    assert_eq!(h.state().notice(), None);
    // With unsaved edits a change on disk asks; the prompt's buttons sit inside the panel.
    h.get_by_label("+ point").click();
    h.run();
    let mut changed = scene.clone();
    changed.sources.tori.clear();
    std::fs::write(&path, changed.to_toml()).unwrap();
    touch(3);
    std::thread::sleep(std::time::Duration::from_millis(450));
    h.run();
    let panel_right = h.state().viewport_rect().left();
    for label in ["Reload", "Keep mine"] {
        let button = h.get_by_label(label);
        let r = button.rect();
        assert!(
            r.right() <= panel_right,
            "{label} ends at {} beyond {panel_right}",
            r.right()
        );
    }
    h.get_by_label("Reload").click();
    h.run();
    assert_eq!(h.state().notice(), None, "the conflict is resolved");
    assert!(h.state().scene().sources.tori.is_empty());
    assert!(!h.state().document().is_dirty());
}

#[test]
fn key_buttons_key_the_value_shown_and_the_i_key_does_too() {
    use egui::accesskit::Role;
    use energywave::animation::{Parameter, SourceKind, Value};
    let mut h = harness(light_scene());
    assert!(!h.state().scene().is_animated());
    // A still scene: keying a value gives it a timeline, with the key at frame 0.
    click_label(&mut h, "key tori[0].coefficient");
    let track = |h: &Harness<'static, ViewerApp>, p: Parameter| {
        h.state()
            .scene()
            .animation
            .as_ref()
            .and_then(|a| a.tracks.iter().find(|t| t.parameter == p).cloned())
    };
    let coefficient = Parameter::Coefficient(SourceKind::Tori, 0);
    let c0 = h.state().scene().sources.tori[0].coefficient;
    let keys = track(&h, coefficient).expect("a track").keys;
    assert_eq!(keys.len(), 1);
    assert_eq!((keys[0].frame, keys[0].value), (0.0, Value::Number(c0)));
    // At frame 40 an edit of the keyed value is a key there.
    h.get_by_role_and_label(Role::Slider, "frame")
        .set_value_accesskit(40.0);
    h.run();
    h.get_all_by_role_and_label(Role::SpinButton, "coefficient")
        .next()
        .unwrap()
        .set_value_accesskit(5.0);
    h.run();
    let frames = |h: &Harness<'static, ViewerApp>| -> Vec<f64> {
        track(h, coefficient)
            .unwrap()
            .keys
            .iter()
            .map(|k| k.frame)
            .collect()
    };
    assert_eq!(frames(&h), [0.0, 40.0]);
    // The button at a key removes it.
    click_label(&mut h, "key tori[0].coefficient");
    assert_eq!(frames(&h), [0.0]);
    // I over a field keys it, as in Blender.
    let radius = h.get_by_role_and_label(Role::SpinButton, "radius R").rect();
    h.hover_at(radius.center());
    h.run();
    h.key_press(egui::Key::I);
    h.run();
    let r = track(&h, Parameter::MajorRadius(0)).expect("keyed by I");
    assert_eq!(r.keys[0].frame, 40.0);
    assert!(h.state().history().can_undo(), "keys are edits");
}

#[test]
fn the_scrubber_gives_each_frame_pixels_of_its_own() {
    use egui::accesskit::Role;
    let mut scene = light_scene();
    scene.animation = Some(energywave::animation::Animation {
        frames: 92,
        ..Default::default()
    });
    let h = harness(scene);
    let slider = h.get_by_role_and_label(Role::Slider, "frame").rect();
    assert!(
        slider.width() >= 92.0 * 3.0,
        "the scrubber is {} wide for 92 frames",
        slider.width()
    );
}

#[test]
fn the_panel_keeps_its_width_whatever_it_shows() {
    let mut h = harness(light_scene());
    let left = h.state().viewport_rect().left();
    // Simpson with jitter shows the most rows; an animation adds key buttons everywhere.
    h.get_by_label("jitter (noise instead of bands)").click();
    h.run();
    click_label(&mut h, "key tori[0].coefficient");
    assert!(h.state().scene().is_animated());
    assert_eq!(
        h.state().viewport_rect().left(),
        left,
        "the viewport did not move"
    );
}

/// The largest difference between a screenshot of `v`'s frame (`pixels`, `size`) and the same frame rendered for
/// export at that size, its field integrated at `resolution` texels a side: under 2/255.
fn assert_is_the_export(
    v: &energywave::viewer::offscreen::OffscreenViewer,
    pixels: &[[f32; 4]],
    [w, h]: [u32; 2],
    resolution: u32,
) {
    let mut want = v.app.frame_scene();
    want.billboard.resolution = resolution;
    let frame = energywave::gpu::HeadlessRenderer::new()
        .unwrap()
        .render(&want, w, h, false)
        .unwrap();
    let mut worst = 0.0f32;
    for (p, q) in pixels.iter().zip(&frame.pixels) {
        for c in 0..3 {
            worst = worst.max((p[c] - q[c]).abs());
        }
    }
    assert!(worst < 2.0 / 255.0, "largest difference {worst}");
}

#[test]
fn a_scaled_screenshot_integrates_the_field_at_that_scale() {
    use energywave::viewer::Document;
    use energywave::viewer::offscreen::OffscreenViewer;
    let mut scene = light_scene();
    scene.billboard.resolution = 40;
    let mut v = OffscreenViewer::new(Document::new(scene, None), 480, 320).unwrap();
    v.app.view_mut().show_grid = false;
    for _ in 0..3 {
        v.frame().unwrap();
    }
    let (pixels, [w, h]) = v.screenshot(4).unwrap();
    let [vw, vh] = v.app.viewport_px();
    assert_eq!([w, h], [4 * vw, 4 * vh]);
    assert_eq!(
        v.field_values().unwrap().len(),
        160 * 160,
        "a field of 4 x 40 texels a side"
    );
    // The same frame rendered for export at that size and resolution: what the screenshot must be.
    assert_is_the_export(&v, &pixels, [w, h], 160);
}

#[test]
fn a_screenshot_taken_while_the_objects_light_is_worked_out_shows_the_whole_frame() {
    use energywave::viewer::Document;
    use energywave::viewer::offscreen::OffscreenViewer;
    let mut scene = common::shipped_scene("floor.toml");
    scene.billboard.resolution = 40;
    let mut v = OffscreenViewer::new(Document::new(scene, None), 240, 160).unwrap();
    v.app.view_mut().show_overlays = false;
    v.app.view_mut().show_grid = false;
    // One frame, which asks for the objects' light and (on this machine) draws them unshadowed meanwhile; the
    // screenshot right after it waits for the light and draws its frame again at twice the size, the field
    // integrated at twice the resolution: every try's work done, none of it lost with a try drawn again.
    v.frame().unwrap();
    let (pixels, [w, h]) = v.screenshot(2).unwrap();
    assert_is_the_export(&v, &pixels, [w, h], 80);
}

#[test]
fn screenshots_of_a_scene_without_a_file_go_to_a_stated_place() {
    let h = harness(light_scene());
    let dir = h.state().document().screenshot_dir();
    assert!(dir.is_absolute());
    assert_eq!(dir, std::env::current_dir().unwrap());
    h.get_by_label(&format!("into {}", dir.display()));
}

/// Every file under `dir`, its subfolders' too (an export stages its frames in a folder of its own), with its
/// bytes, by path.
fn files_under(dir: &std::path::Path) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(files_under(&path));
        } else if let Ok(bytes) = std::fs::read(&path) {
            out.push((path, bytes));
        }
    }
    out.sort();
    out
}

#[test]
fn an_export_can_be_cancelled_and_leaves_the_folder_as_it_was() {
    let dir = std::env::temp_dir().join(format!("energywave-ui-cancel-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // An earlier export of the same names: a cancelled export leaves every byte of it.
    for k in 0..3 {
        std::fs::write(
            dir.join(format!("frame_{k:04}.png")),
            format!("earlier {k}"),
        )
        .unwrap();
    }
    let earlier = files_under(&dir);
    let mut scene = light_scene();
    scene.animation = Some(energywave::animation::Animation {
        frames: 400,
        ..Default::default()
    });
    let mut h = harness(scene);
    h.get_by_label("Export").click_accesskit();
    h.run();
    {
        let form = h.state_mut().animation_form_mut();
        form.export_path = dir.join("frame_####.png").display().to_string();
        form.size = [160, 120];
    }
    h.run();
    h.get_by_label("Export 400 frames").click_accesskit();
    h.run();
    assert!(h.state().is_exporting(), "{:?}", h.state().notice());
    // Let a few frames land (beside the destination, until the last is written), then stop.
    let start = std::time::Instant::now();
    while files_under(&dir).len() < earlier.len() + 2 && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(
        files_under(&dir).len() >= earlier.len() + 2,
        "frames are being written"
    );
    h.get_by_label("Cancel").click_accesskit();
    h.run();
    while h.state().is_exporting() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
    }
    assert_eq!(
        h.state().notice().map(|n| n.0.as_str()),
        Some("Export cancelled: nothing written")
    );
    assert_eq!(
        files_under(&dir),
        earlier,
        "the frames written are gone, the earlier ones whole"
    );
}

#[test]
fn the_holdout_checkbox_leaves_the_objects_out_of_an_export() {
    // A bright point behind a sphere standing before the billboard, two frames exported as a transparent PNG
    // sequence through the panel: with "holdout" ticked the sphere's middle pixel is transparent (left out, the
    // glow it hides still hidden), without it opaque; the glow beside it shows in both.
    let dir = std::env::temp_dir().join(format!("energywave-ui-holdout-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = energywave::scene::Scene::parse(
        "[camera]\neye = [0.0, 0.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 30.0\n\
         [billboard]\nresolution = 32\n[integration]\nintegrator = \"simpson\"\ndivisions = 32\n\
         [animation]\nframes = 2\n\
         [[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.5\n\
         [[objects]]\nshape = \"sphere\"\ncenter = [0.0, 0.0, 4.0]\nradius = 0.5\n",
        std::path::Path::new("sphere.toml"),
    )
    .unwrap();
    let mut h = harness(scene);
    h.get_by_label("Export").click_accesskit();
    h.run();
    let (w, ht) = (64u32, 48u32);
    let export = |h: &mut egui_kittest::Harness<'static, energywave::viewer::ViewerApp>,
                  name: &str| {
        export_sequence(h, (&dir, name), [w, ht], "Export 2 frames", 0)
    };
    h.get_by_label("transparent").click_accesskit();
    h.run();
    let drawn = export(&mut h, "drawn");
    h.get_by_label("holdout").click_accesskit();
    h.run();
    assert!(h.state_mut().animation_form_mut().holdout, "ticked");
    let held = export(&mut h, "held");
    let (middle, beside) = ((w / 2, ht / 2), (w / 2 + w / 5, ht / 2));
    assert_eq!(
        drawn.get_pixel(middle.0, middle.1)[3],
        255,
        "the sphere drawn"
    );
    assert_eq!(
        held.get_pixel(middle.0, middle.1).0,
        [0, 0, 0, 0],
        "held out"
    );
    for image in [&drawn, &held] {
        assert!(
            image.get_pixel(beside.0, beside.1)[3] > 40,
            "the glow beside it"
        );
    }
}

#[test]
fn the_fit_checkbox_frames_the_whole_glow_in_an_export() {
    // A point's glow seen through a narrow field of view fills the frame: exported transparent as it is, the
    // border is glow; with "fit" ticked the field of view widens for the export alone, the border is alpha 0
    // all round and the glow is whole in the middle, and the scene's own camera is untouched.
    let dir = std::env::temp_dir().join(format!("energywave-ui-fit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = energywave::scene::Scene::parse(
        "[camera]\neye = [0.0, 0.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 8.0\n\
         [billboard]\nresolution = 32\n[integration]\nintegrator = \"simpson\"\ndivisions = 32\n\
         [animation]\nframes = 2\n[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.5\n",
        std::path::Path::new("point.toml"),
    )
    .unwrap();
    let mut h = harness(scene);
    h.get_by_label("Export").click_accesskit();
    h.run();
    let (w, ht) = (64u32, 48u32);
    let export = |h: &mut egui_kittest::Harness<'static, energywave::viewer::ViewerApp>,
                  name: &str| {
        export_sequence(h, (&dir, name), [w, ht], "Export 2 frames", 1)
    };
    let border = |image: &image::RgbaImage| -> u8 {
        (image.enumerate_pixels())
            .filter(|(x, y, _)| *x == 0 || *y == 0 || *x == w - 1 || *y == ht - 1)
            .map(|(_, _, p)| p[3])
            .max()
            .unwrap()
    };
    h.get_by_label("transparent").click_accesskit();
    h.run();
    let narrow = export(&mut h, "narrow");
    assert!(border(&narrow) > 100, "the glow fills the narrow frame");
    h.get_by_label("fit").click_accesskit();
    h.run();
    assert!(h.state_mut().animation_form_mut().fit, "ticked");
    let fitted = export(&mut h, "fitted");
    assert_eq!(border(&fitted), 0, "the fitted frame ends in alpha 0");
    assert!(
        fitted.get_pixel(w / 2, ht / 2)[3] > 200,
        "the glow in the middle"
    );
    assert_eq!(h.state().document().scene.camera.fov_y_degrees, 8.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_save_keeps_the_files_comments_and_layout() {
    use egui::accesskit::Role;
    use egui_kittest::kittest::NodeT;
    let dir = std::env::temp_dir().join(format!("energywave-ui-save-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ring.toml");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml"),
    )
    .unwrap();
    std::fs::write(&path, &text).unwrap();
    let mut h = harness(light_scene());
    h.state_mut()
        .apply(energywave::viewer::Action::Open(path.clone()));
    h.run();
    // Orbit, then one edit in the panel, then Ctrl+S.
    let rect = h.state().viewport_rect();
    drag(
        &mut h,
        Pos2::new(rect.right() - 40.0, rect.bottom() - 40.0),
        Vec2::new(-60.0, 0.0),
    );
    let radius = h.get_by_role_and_label(Role::SpinButton, "radius R");
    assert_eq!(radius.accesskit_node().numeric_value(), Some(1.3));
    radius.set_value_accesskit(0.97);
    h.run();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    h.run();
    assert!(!h.state().document().is_dirty());
    let saved = std::fs::read_to_string(&path).unwrap();
    assert!(saved.starts_with("# The default scene"), "{saved}");
    assert!(saved.contains("major_radius = 0.97\n"));
    // The axis typed [1.0, 0.25, 0.0] stays as typed; the orbit moved the eye, and the decay the file derived
    // from it is written out so that the look stays.
    assert!(saved.contains("axis = [1.0, 0.25, 0.0]\n"));
    assert!(saved.contains("decay_length = "));
    // Every other line as it was: the lines gone and the lines new are those three.
    let removed: Vec<&str> = text
        .lines()
        .filter(|l| !saved.lines().any(|m| m == *l))
        .collect();
    let added: Vec<&str> = saved
        .lines()
        .filter(|l| !text.lines().any(|m| m == *l))
        .collect();
    assert_eq!(removed, ["eye = [2.0, 4.5, 14.0]", "major_radius = 1.3"]);
    assert_eq!(added.len(), 3, "{added:?}");
    assert!(added[0].starts_with("eye = ") && added[1].starts_with("decay_length = "));
    assert_eq!(added[2], "major_radius = 0.97");
    assert_eq!(
        energywave::scene::Scene::load(&path).unwrap(),
        *h.state().scene()
    );
}

/// Clicks (press and release, no move) at `at`.
fn click(h: &mut Harness<'static, ViewerApp>, at: Pos2) {
    h.hover_at(at);
    h.run();
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: egui::Modifiers::NONE,
    });
    h.run();
}

#[test]
fn clicking_a_handle_selects_its_source_and_shows_its_entry() {
    use energywave::animation::SourceKind;
    use energywave::viewer::handles::{self, HandleId};
    let mut scene = light_scene();
    // Twelve points: the last one's entry is far below the panel's fold.
    for k in 0..12 {
        scene.sources.points.push(energywave::field::Point {
            position: glam::DVec3::new(-2.2 + 0.4 * k as f64, 2.0, 0.0),
            coefficient: 0.5,
            look: Default::default(),
        });
    }
    let mut h = harness(scene);
    let rect = h.state().viewport_rect();
    let p = handles::get(h.state().scene(), HandleId::Point(11)).unwrap();
    let at = handles::to_screen(&h.state().scene().camera, rect, p).unwrap();
    assert!(
        h.get_by_label("Point 12").rect().top() > 700.0,
        "below the fold at first"
    );
    click(&mut h, at);
    assert_eq!(h.state().selection(), Some((SourceKind::Points, 11)));
    h.run();
    let entry = h.get_by_label("Point 12").rect();
    assert!(
        entry.top() >= 0.0 && entry.bottom() <= 700.0,
        "scrolled to: {entry:?}"
    );
    // A click on nothing clears it; a click on an entry's name selects that source. (The top-right corner
    // holds the Overlays button.)
    click(&mut h, Pos2::new(rect.left() + 10.0, rect.top() + 10.0));
    assert_eq!(h.state().selection(), None);
    h.get_by_label("Torus 1").click();
    h.run();
    assert_eq!(h.state().selection(), Some((SourceKind::Tori, 0)));
    // Deleting the selected source clears the selection.
    let torus_delete = h.get_all_by_label("Delete").nth(12).unwrap();
    torus_delete.click();
    h.run();
    assert!(h.state().scene().sources.tori.is_empty());
    assert_eq!(h.state().selection(), None);
}

#[test]
fn a_second_click_on_overlapping_handles_picks_the_next() {
    use energywave::animation::SourceKind;
    use energywave::viewer::handles;
    // The default scene's torus is centred on the curve's middle control point.
    let mut h = harness(light_scene());
    let rect = h.state().viewport_rect();
    let scene = h.state().scene().clone();
    let at = handles::to_screen(&scene.camera, rect, scene.sources.tori[0].center).unwrap();
    click(&mut h, at);
    let first = h.state().selection();
    click(&mut h, at);
    let second = h.state().selection();
    let both = [first, second];
    assert!(both.contains(&Some((SourceKind::Tori, 0))), "{both:?}");
    assert!(both.contains(&Some((SourceKind::Curves, 0))), "{both:?}");
    click(&mut h, at);
    assert_eq!(h.state().selection(), first, "round again");
}

#[test]
fn a_torus_radius_and_axis_and_a_line_direction_have_handles() {
    use energywave::viewer::handles::{self, HandleId};
    let mut scene = light_scene();
    scene.sources.lines.push(energywave::field::Line {
        point: glam::DVec3::new(0.0, 2.5, 0.0),
        direction: glam::DVec3::X,
        coefficient: 0.3,
        look: Default::default(),
    });
    let mut h = harness(scene);
    let rect = h.state().viewport_rect();
    let grab = |h: &Harness<'static, ViewerApp>, id| {
        let s = h.state().scene();
        handles::to_screen(&s.camera, rect, handles::get(s, id).unwrap()).unwrap()
    };
    let before = h.state().scene().clone();
    // The radius handle dragged outward widens the ring.
    let at = grab(&h, HandleId::TorusRadius(0));
    let center = grab(&h, HandleId::TorusCenter(0));
    drag(&mut h, at, (at - center).normalized() * 30.0);
    let t = &h.state().scene().sources.tori[0];
    assert!(
        t.major_radius > before.sources.tori[0].major_radius * 1.1,
        "{}",
        t.major_radius
    );
    assert_eq!(t.center, before.sources.tori[0].center);
    // The axis handle turns the ring.
    let at = grab(&h, HandleId::TorusAxis(0));
    drag(&mut h, at, Vec2::new(25.0, 10.0));
    let axis = h.state().scene().sources.tori[0].axis;
    assert!(
        axis.dot(before.sources.tori[0].axis.normalize()) < 0.999,
        "{axis}"
    );
    assert!((axis.length() - 1.0).abs() < 1e-9);
    // The line's direction handle turns the line about its point.
    let at = grab(&h, HandleId::LineDirection(0));
    drag(&mut h, at, Vec2::new(0.0, -40.0));
    let l = &h.state().scene().sources.lines[0];
    assert!(l.direction.y > 0.1, "{}", l.direction);
    assert_eq!(l.point, before.sources.lines[0].point);
    assert!(h.state().history().can_undo());
}

/// A file dropped onto the window, as egui-winit hands it over.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn files_open_and_save_through_the_dialog_by_dropping_and_from_the_recent_list() {
    let dir = std::env::temp_dir().join(format!("energywave-ui-files-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("shots")).unwrap();
    let mut ring = light_scene();
    ring.sources.curves.clear();
    std::fs::write(dir.join("ring.toml"), ring.to_toml()).unwrap();
    std::fs::write(dir.join("notes.txt"), "not a scene").unwrap();
    let mut h = harness(light_scene());
    h.state_mut()
        .set_recent(energywave::viewer::recent::RecentFiles::load(
            dir.join("recent.txt"),
        ));
    // Open through the dialog: it starts beside the typed path, lists the folder's scenes, a click picks one.
    *h.state_mut().path_input_mut() = dir.join("shots").display().to_string();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    h.run();
    assert!(h.state().file_dialog().is_some());
    h.get_by_label("Up").click();
    h.run();
    assert!(
        h.query_by_label("notes.txt").is_none(),
        "only scene files are listed"
    );
    h.get_by_label("ring.toml").click();
    h.run();
    h.get_by_label("Open").click();
    h.run();
    assert!(h.state().file_dialog().is_none());
    assert_eq!(*h.state().scene(), ring);
    // Save As through the dialog, a new name: `.toml` is added.
    h.get_by_label("+ point").click();
    h.run();
    h.get_by_label("Save As\u{2026}").click();
    h.run();
    let name = h.get_by_label("name");
    name.focus();
    h.run();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.get_by_label("name").type_text("ring with a point");
    h.run();
    // The dialog's Save (the panel has one too, behind the dialog).
    h.get_all_by_label("Save").last().unwrap().click();
    h.run();
    let saved = dir.join("ring with a point.toml");
    assert!(saved.is_file(), "{:?}", h.state().notice());
    assert!(!h.state().document().is_dirty());
    // Dropping a scene onto the window opens it (asking first when there are unsaved changes).
    h.get_by_label("+ torus").click();
    h.run();
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(dir.join("ring.toml"))));
    h.run();
    assert!(
        h.query_by_label("Unsaved changes").is_some(),
        "the prompt covers a drop"
    );
    h.get_by_label("Discard").click();
    h.run();
    assert_eq!(*h.state().scene(), ring);
    // A file that is not a scene is refused, and said so.
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(dir.join("notes.txt"))));
    h.run();
    assert!(
        h.state()
            .notice()
            .is_some_and(|n| n.1 && n.0.contains("notes.txt"))
    );
    // The recent list, newest first, kept in its file; a click opens.
    let recent = h.state().recent_files().to_vec();
    assert_eq!(recent[0], dir.join("ring.toml"));
    assert_eq!(recent[1], saved);
    assert_eq!(
        energywave::viewer::recent::RecentFiles::load(dir.join("recent.txt")).files(),
        recent.as_slice()
    );
    h.get_by_label("Recent").click();
    h.run();
    h.get_by_label("ring with a point.toml").click();
    h.run();
    assert_eq!(h.state().document().path(), Some(saved.as_path()));
    assert_eq!(h.state().scene().sources.points.len(), 1);
}

#[test]
fn the_blend_is_chosen_in_the_panel_and_is_an_undo_step() {
    use common::viewer::{mean_abs_difference, viewport_pixels};
    use energywave::scene::Blend;
    let mut scene = light_scene();
    scene.colors.background = [0.0, 0.7, 0.1];
    scene.colors.blend = Blend::Papers;
    let mut h = harness(scene);
    let papers = viewport_pixels(&mut h);
    h.get_by_label("over").click();
    h.run();
    assert_eq!(h.state().scene().colors.blend, Blend::Over);
    let over = viewport_pixels(&mut h);
    assert!(
        mean_abs_difference(&papers, &over) > 0.05,
        "the core no longer subtracts the green"
    );
    undo(&mut h);
    assert_eq!(h.state().scene().colors.blend, Blend::Papers);
}

#[test]
fn the_viewer_exports_a_video_and_a_padded_sheet() {
    use energywave::viewer::animation_panel::ExportKind;
    let dir = std::env::temp_dir().join(format!("energywave-ui-video-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut scene = light_scene();
    scene.billboard.resolution = 24;
    scene.animation = Some(energywave::animation::Animation {
        frames: 8,
        ..Default::default()
    });
    let mut h = harness(scene);
    h.get_by_label("Export").click_accesskit();
    h.run();
    let export = |h: &mut Harness<'static, ViewerApp>| export_and_wait(h, "Export 8 frames");
    // H.264 has no alpha: a transparent MP4 is refused, and said so.
    {
        let form = h.state_mut().animation_form_mut();
        form.export_kind = ExportKind::Video;
        form.transparent = true;
        form.export_path = dir.join("glow.mp4").display().to_string();
        form.size = [64, 48];
    }
    h.run();
    let notice = export(&mut h);
    assert!(
        notice
            .as_ref()
            .is_some_and(|(t, e)| *e && t.contains(".webm")),
        "{notice:?}"
    );
    h.state_mut().animation_form_mut().transparent = false;
    h.run();
    let notice = export(&mut h);
    assert!(
        notice
            .as_ref()
            .is_some_and(|(t, e)| !e && t.starts_with("Exported")),
        "{notice:?}"
    );
    let probe = std::process::Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            "stream=nb_read_frames,width,height",
            "-of",
            "csv=p=0",
        ])
        .arg(dir.join("glow.mp4"))
        .output()
        .expect("ffprobe runs");
    assert_eq!(String::from_utf8_lossy(&probe.stdout).trim(), "64,48,8");
    // A sheet with padding and power-of-two sides.
    {
        let form = h.state_mut().animation_form_mut();
        form.export_kind = ExportKind::Sheet;
        form.export_path = dir.join("sheet.png").display().to_string();
        form.sheet.padding = 2;
        form.sheet.power_of_two = true;
    }
    h.run();
    export(&mut h);
    let sheet = image::open(dir.join("sheet.png")).unwrap();
    // 8 frames of 64 x 48 in 3 columns and 3 rows, 2 between: 196 x 148, up to 256 x 256.
    assert_eq!((sheet.width(), sheet.height()), (256, 256));
}

#[test]
fn a_source_gets_its_own_color_in_the_panel_keyed_and_undone() {
    use common::viewer::{mean_abs_difference, viewport_pixels};
    use energywave::animation::{Parameter, SourceKind};
    let mut scene = light_scene();
    let red = [1.0, 0.2, 0.1];
    scene.sources.tori[0].look.color = Some(red);
    let energy = scene.colors.energy;
    let mut h = harness(scene);
    let reddish = viewport_pixels(&mut h);
    let redness =
        |p: &[[u8; 4]]| p.iter().map(|q| q[0] as f64 - q[2] as f64).sum::<f64>() / p.len() as f64;
    // The torus (the first source in the panel) in its own red: the view is redder than blue in the mean.
    assert!(redness(&reddish) > 0.0, "{}", redness(&reddish));
    // Back to the scene's color: the glow all light blue.
    h.get_all_by_label("own color")
        .next()
        .unwrap()
        .scroll_to_me();
    h.run();
    h.get_all_by_label("own color").next().unwrap().click();
    h.run();
    assert_eq!(h.state().scene().sources.tori[0].look, Default::default());
    let blue = viewport_pixels(&mut h);
    assert!(redness(&blue) < redness(&reddish) - 5.0);
    assert!(mean_abs_difference(&reddish, &blue) > 0.02);
    undo(&mut h);
    assert_eq!(h.state().scene().sources.tori[0].look.color, Some(red));
    // Its color keyed, then its own color dropped: the keys go with it.
    click_label(&mut h, "key tori[0].color");
    let keyed = h.state().scene().animation.as_ref().is_some_and(|a| {
        (a.tracks.iter()).any(|t| t.parameter == Parameter::SourceColor(SourceKind::Tori, 0))
    });
    assert!(keyed, "the torus's color is keyed");
    h.get_all_by_label("own color")
        .next()
        .unwrap()
        .scroll_to_me();
    h.run();
    h.get_all_by_label("own color").next().unwrap().click();
    h.run();
    let scene = h.state().scene();
    assert_eq!(scene.sources.tori[0].look, Default::default());
    assert!(scene.animation.as_ref().is_none_or(|a| a.tracks.is_empty()));
    // A color of its own again starts from the scene's.
    h.get_all_by_label("own color")
        .next()
        .unwrap()
        .scroll_to_me();
    h.run();
    h.get_all_by_label("own color").next().unwrap().click();
    h.run();
    assert_eq!(h.state().scene().sources.tori[0].look.color, Some(energy));
}

#[test]
fn a_curve_gets_a_color_series_in_the_panel_and_loses_it_again() {
    use energywave::animation::Parameter;
    let scene = light_scene();
    let energy = scene.colors.energy;
    let mut h = harness(scene);
    click_label(&mut h, "+ color series");
    // Two colors, both the curve's one color: the same look until one changes.
    assert_eq!(
        h.state().scene().sources.curves[0].color_series,
        [energy, energy]
    );
    assert!(h.state().scene().tinted());
    click_label(&mut h, "+ color");
    assert_eq!(h.state().scene().sources.curves[0].color_series.len(), 3);
    // A control color keyed, then removed with it.
    h.get_by_label("key curves[0].color_series[2]")
        .scroll_to_me();
    h.run();
    h.get_by_label("key curves[0].color_series[2]").click();
    h.run();
    let keyed =
        |h: &Harness<'static, ViewerApp>| {
            h.state().scene().animation.as_ref().is_some_and(|a| {
                (a.tracks.iter()).any(|t| t.parameter == Parameter::SeriesColor(0, 2))
            })
        };
    assert!(keyed(&h));
    click_label(&mut h, "remove c2");
    assert_eq!(h.state().scene().sources.curves[0].color_series.len(), 2);
    assert!(!keyed(&h), "a key of a removed color goes with it");
    // Down to one color: the curve has that one color again, and no series.
    click_label(&mut h, "remove c1");
    let curve = &h.state().scene().sources.curves[0];
    assert!(curve.color_series.is_empty());
    assert_eq!(curve.look.color, Some(energy));
    // Undo brings the series back.
    undo(&mut h);
    assert_eq!(h.state().scene().sources.curves[0].color_series.len(), 2);
}

#[test]
fn glare_is_turned_on_in_the_panel_and_is_an_undo_step() {
    use common::viewer::viewport_pixels;
    let mut h = harness(light_scene());
    let plain = viewport_pixels(&mut h);
    click_label(&mut h, "glare (fog glow)");
    assert_eq!(
        h.state().scene().glare,
        Some(energywave::scene::Glare::default())
    );
    let glared = viewport_pixels(&mut h);
    assert!(differs(&plain, &glared), "the glow glares");
    undo(&mut h);
    assert_eq!(h.state().scene().glare, None);
}

#[test]
fn the_w_form_is_switched_in_the_panel_and_is_an_undo_step() {
    use common::viewer::viewport_pixels;
    use energywave::field::WForm;
    let mut h = harness(light_scene());
    assert_eq!(
        h.state().scene().sources.curves[0].w_form,
        WForm::Continuous
    );
    let continuous = viewport_pixels(&mut h);
    click_label(&mut h, "continuous (no seam)");
    assert_eq!(h.state().scene().sources.curves[0].w_form, WForm::Nearest);
    let nearest = viewport_pixels(&mut h);
    assert!(
        differs(&continuous, &nearest),
        "the papers' form shows another glow"
    );
    undo(&mut h);
    assert_eq!(
        h.state().scene().sources.curves[0].w_form,
        WForm::Continuous
    );
    // A curve without a W series offers no choice: both forms are one term there.
    h.state_mut().scene_mut().sources.curves[0].weights.clear();
    h.run();
    assert!(h.query_by_label("continuous (no seam)").is_none());
}

#[test]
fn the_decay_is_chosen_in_the_panel_and_is_an_undo_step() {
    use common::viewer::viewport_pixels;
    use energywave::integrate::Decay;
    let mut h = harness(light_scene());
    let distance = viewport_pixels(&mut h);
    click_label(&mut h, "rms");
    assert_eq!(h.state().scene().integration.decay, Decay::Rms);
    let rms = viewport_pixels(&mut h);
    assert!(differs(&distance, &rms), "the rms decay shows another glow");
    undo(&mut h);
    assert_eq!(h.state().scene().integration.decay, Decay::Distance);
}

#[test]
fn what_is_added_is_selected_and_another_file_starts_with_nothing_selected() {
    use energywave::animation::SourceKind;
    let mut h = harness(light_scene());
    click_label(&mut h, "+ sphere");
    let objects = h.state().scene().objects.len();
    assert_eq!(h.state().selected_object(), Some(objects - 1));
    // Its place and albedo are keyable from its entry.
    let last = objects - 1;
    assert!(
        h.query_by_label(&format!("key objects[{last}].position"))
            .is_some()
    );
    assert!(
        h.query_by_label(&format!("key objects[{last}].color"))
            .is_some()
    );
    // And its radius: keyed at this frame with the value shown.
    h.get_by_label(&format!("key objects[{last}].radius"))
        .click_accesskit();
    h.run();
    let keyed = (h.state().document().scene.animation.as_ref())
        .and_then(|a| {
            a.tracks.iter().find(|t| {
                t.parameter
                    == energywave::animation::Parameter::ObjectShape(
                        last,
                        energywave::animation::ShapeField::Radius,
                    )
            })
        })
        .map(|t| t.keys.clone());
    assert_eq!(
        keyed.map(|k| k.iter().map(|k| k.value).collect::<Vec<_>>()),
        Some(vec![energywave::animation::Value::Number(0.5)])
    );
    click_label(&mut h, "+ point");
    let points = h.state().scene().sources.points.len();
    assert_eq!(
        h.state().selection(),
        Some((SourceKind::Points, points - 1))
    );
    assert_eq!(h.state().selected_object(), None);
    // Saved, then another file opened: nothing of the first stays selected.
    let dir = std::env::temp_dir().join(format!("energywave-select-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let saved = dir.join("first.toml");
    h.state_mut()
        .apply(energywave::viewer::action::Action::SaveAs(saved.clone()));
    h.run();
    let floor = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/floor.toml");
    h.state_mut()
        .apply(energywave::viewer::action::Action::Open(floor));
    h.run();
    assert_eq!(h.state().selection(), None);
    assert_eq!(h.state().selected_object(), None);
    // A saved camera reads as numbers, not float noise, after an orbit.
    let rect = h.state().viewport_rect();
    drag(
        &mut h,
        Pos2::new(rect.right() - 60.0, rect.bottom() - 60.0),
        Vec2::new(-97.0, -23.0),
    );
    let orbited = dir.join("orbited.toml");
    h.state_mut()
        .apply(energywave::viewer::action::Action::SaveAs(orbited.clone()));
    h.run();
    let text = std::fs::read_to_string(&orbited).unwrap();
    let eye = text.lines().find(|l| l.starts_with("eye = ")).unwrap();
    assert_ne!(eye, "eye = [3.6, 2.4, 6.8]", "the view was orbited");
    for number in eye
        .trim_start_matches("eye = [")
        .trim_end_matches(']')
        .split(',')
    {
        let decimals = number.trim().split('.').nth(1).map_or(0, str::len);
        assert!(decimals <= 7, "{eye}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_quick_click_on_the_scrubber_seeks_there() {
    use egui::accesskit::Role;
    let mut scene = light_scene();
    scene.animation = Some(energywave::animation::Animation {
        frames: 61,
        ..Default::default()
    });
    let mut h = harness(scene);
    let rail = h.get_by_role_and_label(Role::Slider, "frame").rect();
    // Pressed and released within one frame, three quarters along the rail.
    let at = Pos2::new(rail.left() + rail.width() * 0.75, rail.center().y);
    h.drag_at(at);
    h.drop_at(at);
    h.run();
    let frame = h.state().playback().frame;
    assert!((40..=50).contains(&frame), "{frame}");
}

#[test]
fn opening_the_view_section_leaves_the_panel_and_its_buttons_in_place() {
    let mut h = harness(light_scene());
    let left = h.state().viewport_rect().left();
    let undo = h.get_by_label("Undo").rect();
    let redo = h.get_by_label("Redo").rect();
    assert_eq!(undo.top(), redo.top(), "Undo and Redo share a row");
    h.get_by_label("View").click();
    h.run();
    assert!(
        h.query_by_label("Reset view").is_some(),
        "the section opened"
    );
    assert_eq!(
        h.state().viewport_rect().left(),
        left,
        "the panel kept its width"
    );
    assert_eq!(h.get_by_label("Undo").rect(), undo);
    assert_eq!(h.get_by_label("Redo").rect(), redo);
}

#[test]
fn an_error_is_shown_whole_and_the_color_pickers_glyphs_exist() {
    let mut h = harness(light_scene());
    let long = format!(
        "/a/long/folder/{}/model.glb: the file is not glTF: it ends before its header says",
        "deeper/".repeat(12)
    );
    h.state_mut()
        .apply(energywave::viewer::action::Action::Notify {
            text: long.clone(),
            is_error: true,
        });
    h.run();
    assert!(
        h.query_by_label(&long).is_some(),
        "the whole message is a label"
    );
    // The color picker's copy button (egui's) has its glyph in the fonts we ship.
    let has = h
        .ctx
        .fonts_mut(|f| f.has_glyph(&egui::FontId::proportional(14.0), '\u{1f4cb}'));
    assert!(has);
}
