//! The viewer's first ten minutes, driven through egui_kittest like a user: looking is not editing, messages
//! that tell the truth, keys without typing paths, selection, screenshots, exports and saves that behave.

mod common;

use common::viewer::{harness, light_scene};
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
    assert!(!h.state().window_title().contains('*'), "{}", h.state().window_title());
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
    // An error stays until the next action.
    h.get_by_label("Save As").click();
    h.run();
    assert!(h.state().notice().is_some_and(|n| n.1), "{:?}", h.state().notice());
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
    h.state_mut().apply(energywave::viewer::Action::Open(path.clone()));
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
    assert!(h.state().notice().is_some_and(|n| n.1), "{:?}", h.state().notice());
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
        assert!(r.right() <= panel_right, "{label} ends at {} beyond {panel_right}", r.right());
    }
    h.get_by_label("Reload").click();
    h.run();
    assert_eq!(h.state().notice(), None, "the conflict is resolved");
    assert!(h.state().scene().sources.tori.is_empty());
    assert!(!h.state().document().is_dirty());
}
