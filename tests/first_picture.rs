//! A picture at once: every shipped preset opens in the viewer (offscreen, through the window's own frame code)
//! to a first frame that shows the scene, not an empty background: close to the picture it settles to, though
//! coarse, with what takes long to work out (the objects' light and translucent tables, the particles' light)
//! prepared on a thread of its own while the frames draw stand-ins, and named in the status line until it is
//! ready. How long the first picture takes is measured by `cargo run --release --example first_picture` (and
//! printed here with `-- --nocapture`), not asserted.

mod common;

use energywave::scene::Scene;
use energywave::viewer::Document;
use energywave::viewer::offscreen::OffscreenViewer;

const SIZE: [u32; 2] = [800, 500];

/// A viewer on `scene`, its overlays (grid, guides, handles) off: the viewport shows the scene alone.
fn open(mut scene: Scene) -> OffscreenViewer {
    // A field that settles quickly on a software rasteriser; the first frame is coarse whatever W is.
    scene.billboard.resolution = scene.billboard.resolution.min(96);
    let mut v = OffscreenViewer::new(Document::new(scene, None), SIZE[0], SIZE[1])
        .expect("a GPU adapter (lavapipe in CI)");
    v.app.view_mut().show_overlays = false;
    v
}

/// The viewport's pixels (RGB, 0-255) and its size.
fn viewport(v: &OffscreenViewer) -> Vec<[f64; 3]> {
    (v.viewport_pixels().unwrap().chunks_exact(4))
        .map(|p| [p[0], p[1], p[2]].map(f64::from))
        .collect()
}

/// The mean absolute difference of two pictures of one size, per channel in 0-255.
fn mean_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = (a.iter().zip(b))
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).sum::<f64>())
        .sum();
    sum / (3 * a.len()) as f64
}

/// Frames until the picture is whole and nothing is being prepared.
fn settle(v: &mut OffscreenViewer) {
    for _ in 0..2000 {
        if v.app.report().settled() {
            return;
        }
        v.frame().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    panic!("the viewer never settled: {:?}", v.app.report());
}

#[test]
fn every_shipped_preset_opens_to_a_picture_of_the_scene_in_its_first_frame() {
    let mut presets = common::shipped();
    presets.push(("(embedded default)".into(), Scene::default_scene()));
    let mut failures = Vec::new();
    for (name, scene) in presets {
        let background = scene.colors.background.map(|c| c * 255.0);
        let mut v = open(scene);
        let start = std::time::Instant::now();
        v.frame().unwrap();
        let first_seconds = start.elapsed().as_secs_f64();
        let first = viewport(&v);
        let first_report = v.app.report();
        settle(&mut v);
        // The size the viewport settles at (the first frame lays the UI out) shows the settled picture.
        v.frame().unwrap();
        let settled = viewport(&v);
        let empty = vec![background; settled.len()];
        let away = mean_difference(&settled, &empty);
        eprintln!(
            "{name}: first frame {:.0} ms{}",
            first_seconds * 1e3,
            (first_report.preparing.as_ref()).map_or(String::new(), |p| format!(", preparing {p}"))
        );
        if away < 1.0 {
            failures.push(format!(
                "{name}: the settled picture is the background ({away:.2}/255 off it)"
            ));
            continue;
        }
        if first.len() != settled.len() {
            failures.push(format!(
                "{name}: the first frame's viewport has {} pixels, the settled one {}",
                first.len(),
                settled.len()
            ));
            continue;
        }
        // Not empty: much nearer the scene's picture than the background is.
        let off = mean_difference(&first, &settled);
        if off > 0.35 * away {
            failures.push(format!(
                "{name}: the first frame is {off:.2}/255 off the settled picture, which is {away:.2}/255 off the \
                 empty background"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The translucent preset's tables take seconds on a CPU: its first frame does not wait for them, shows the cube
/// with a stand-in light and says what is being prepared; once ready, the picture is the one a render that waits
/// gives, and the note is gone.
#[test]
fn a_translucent_preset_draws_at_once_and_its_tables_arrive_later() {
    let mut v = open(common::shipped_scene("translucent_cavity.toml"));
    v.frame().unwrap();
    let first = v.app.report();
    let what = first
        .preparing
        .expect("the first frame says what is being prepared");
    assert!(what.contains("translucent tables"), "{what}");
    let (off, _) = settled_against_waited(&mut v);
    assert!(v.app.report().preparing.is_none());
    assert!(
        off < 1.0,
        "the settled viewport is {off:.2}/255 off a render that waited"
    );
}

/// Settles `v`, then compares its viewport with the viewport rendered again with every preparation waited for
/// (a screenshot's path): the mean difference, and the waited picture.
fn settled_against_waited(v: &mut OffscreenViewer) -> (f64, Vec<[f64; 3]>) {
    settle(v);
    v.frame().unwrap();
    let shown = viewport(v);
    let waited: Vec<[f64; 3]> = (v.viewport_image().unwrap().iter())
        .map(|p| [0, 1, 2].map(|c| (p[c].clamp(0.0, 1.0) as f64 * 255.0).round()))
        .collect();
    (mean_difference(&shown, &waited), waited)
}

/// An edit while the objects' light is being worked out starts it anew for the edited scene, and what is shown
/// once settled is the edited scene's light, not the first request's.
#[test]
fn an_edit_while_preparing_is_what_gets_prepared() {
    let mut v = open(common::shipped_scene("translucent_cavity.toml"));
    v.frame().unwrap();
    assert!(v.app.report().preparing.is_some());
    // A clearer cube: more of the ring's light reaches the far faces.
    fn extinction(v: &mut OffscreenViewer) -> &mut f64 {
        let objects = &mut v.app.scene_mut().objects;
        let t = objects.iter_mut().find_map(|o| o.translucent.as_mut());
        &mut t.expect("the preset's cube is translucent").extinction
    }
    let before = *extinction(&mut v);
    *extinction(&mut v) = 0.25 * before;
    v.frame().unwrap();
    let (off, edited) = settled_against_waited(&mut v);
    assert!(
        off < 1.0,
        "the settled viewport is {off:.2}/255 off the edited scene's render"
    );
    // And the edit shows: the scene before it renders otherwise.
    *extinction(&mut v) = before;
    let (_, unedited) = settled_against_waited(&mut v);
    let edit = mean_difference(&edited, &unedited);
    assert!(
        edit > 3.0 * off.max(0.3),
        "the edit changes the picture by {edit:.2}/255"
    );
}

/// A scrub far into a dense live set (10,000 particles alive) shows the frame at once, with the particles last
/// simulated, while the simulation runs on a thread of its own; a second scrub before it ends cancels it; once
/// done, the frame shown is the scene simulated up to the frame asked for last, exactly.
#[test]
fn a_scrub_into_a_dense_live_set_does_not_wait_for_its_simulation() {
    let text = format!(
        "{}\n[[particles]]\nemitter = \"box\"\ncenter = [0.0, -1.0, 0.0]\nsize = [5.0, 0.5, 2.0]\n\
         particle_radius = [0.04, 0.08]\ndensity = [2.0, 4.0]\ncolor = [0.7, 0.7, 0.75]\nseed = 1\n\n\
         [particles.life]\nrate = 5000.0\nlifetime = 2.0\nspeed = [0.5, 1.0]\ndirection = [0.0, 1.0, 0.0]\n\
         cone = 40.0\nacceleration = [0.0, -0.5, 0.0]\ndrag = 0.5\n\n[particles.life.turbulence]\nscale = 0.8\n\
         strength = 0.5\nspeed = 1.0\n\n[animation]\nframe_rate = 30.0\nframes = 200\n",
        energywave::scene::DEFAULT_SCENE_TOML
    );
    let scene = Scene::parse(&text, std::path::Path::new("dense live set")).unwrap();
    let mut v = open(scene.clone());
    v.frame().unwrap();
    let at_start = v.app.frame_scene().particles[0].live.clone();
    v.app.seek(190);
    let shown = v.app.frame_scene();
    assert_eq!(
        v.app.preparing(),
        Some("particle simulation"),
        "190 frames of 10,000 particles are simulated on a thread of their own"
    );
    assert_eq!(
        shown.particles[0].live, at_start,
        "the particles last simulated are shown meanwhile"
    );
    // The scene's other animated parts are at the frame asked for at once.
    assert_eq!(shown.sources, scene.at_frame(190.0).sources);
    v.app.seek(120);
    for _ in 0..3000 {
        v.frame().unwrap();
        if v.app.preparing().is_none() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(v.app.preparing().is_none(), "the simulation ends");
    let shown = v.app.frame_scene();
    let want = scene.at_frame(120.0);
    assert!(want.particles[0].live.as_ref().unwrap().len() > 5000);
    assert_eq!(shown.particles[0].live, want.particles[0].live);
}
