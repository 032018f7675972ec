//! The viewer under egui_kittest, as the UI test files drive it: a harness around the real `ViewerApp::ui` on our
//! own GPU device (lavapipe in CI), rendered by egui-wgpu.

use std::sync::{Arc, Mutex};

use egui::Vec2;
use egui_kittest::kittest::Queryable;
use egui_kittest::{Harness, wgpu::WgpuTestRenderer};
use energywave::gpu::GpuContext;
use energywave::integrate::Integrator;
use energywave::scene::Scene;
use energywave::viewer::viewport::{ViewportGpu, ViewportReport};
use energywave::viewer::{Document, ViewerApp};

pub const SIZE: Vec2 = Vec2::new(1000.0, 700.0);
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// As long as anything the harness's viewer prepares takes.
pub const PREPARATION_WAIT: std::time::Duration = std::time::Duration::from_secs(600);

/// The default scene at a resolution and division count that render quickly on a software rasteriser.
pub fn light_scene() -> Scene {
    let mut s = Scene::default_scene();
    s.billboard.resolution = 96;
    s.integration.integrator = Integrator::Simpson;
    s.integration.divisions = 64;
    s
}

/// A harness around a viewer on `scene`, its renderer on our own device with the viewport installed.
pub fn harness(scene: Scene) -> Harness<'static, ViewerApp> {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let report = Arc::new(Mutex::new(ViewportReport::default()));
    let mut renderer =
        egui_wgpu::Renderer::new(&ctx.device, FORMAT, egui_wgpu::RendererOptions::PREDICTABLE);
    // The UI tests check what a frame shows after an edit: its frames wait for what the viewer prepares on
    // other threads (a window's frames wait a moment, then draw stand-ins: tests/first_picture.rs).
    let cache = Arc::new(energywave::gpu::frame_cache(&ctx.device, &ctx.queue));
    let mut viewport = ViewportGpu::new(&ctx.device, FORMAT, report.clone(), cache.clone());
    viewport.set_preparation_wait(PREPARATION_WAIT);
    renderer.callback_resources.insert(viewport);
    let mut app = ViewerApp::new(
        Document::new(scene, None),
        ctx.adapter_summary(),
        ctx.device.limits().max_texture_dimension_2d,
        report,
        cache,
    );
    app.set_preparation_wait(PREPARATION_WAIT);
    let render_state = egui_wgpu::RenderState {
        available_adapters: vec![ctx.adapter.clone()],
        adapter: ctx.adapter,
        instance: ctx.instance,
        device: ctx.device,
        queue: ctx.queue,
        target_format: FORMAT,
        renderer: Arc::new(egui::mutex::RwLock::new(renderer)),
    };
    let mut h = Harness::builder()
        .with_size(SIZE)
        .renderer(WgpuTestRenderer::from_render_state(render_state))
        .build_ui_state(|ui, app: &mut ViewerApp| app.ui(ui), app);
    h.run();
    h
}

/// Scrolls to the widget labelled `label` and clicks it, a frame after each (as a user reaches a control in the
/// panel).
pub fn click_label(h: &mut Harness<'static, ViewerApp>, label: &str) {
    h.get_by_label(label).scroll_to_me();
    h.run();
    h.get_by_label(label).click();
    h.run();
}

/// Scrolls to the first widget labelled `label` (of several: a section's button that others share) and clicks
/// it, a frame after each.
pub fn click_first(h: &mut Harness<'static, ViewerApp>, label: &str) {
    h.get_all_by_label(label).next().unwrap().scroll_to_me();
    h.run();
    h.get_all_by_label(label).next().unwrap().click();
    h.run();
}

/// Undoes the last edit with the keyboard (Ctrl+Z, Cmd+Z on macOS), a frame after.
pub fn undo(h: &mut Harness<'static, ViewerApp>) {
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run();
}

/// Whether two viewport pictures differ visibly: a mean absolute difference above 0.001 (`mean_abs_difference`).
pub fn differs(a: &[[u8; 4]], b: &[[u8; 4]]) -> bool {
    mean_abs_difference(a, b) > 0.001
}

/// The viewport's pixels of a rendered frame, as an average color and the image.
pub fn viewport_pixels(h: &mut Harness<'static, ViewerApp>) -> Vec<[u8; 4]> {
    let rect = h.state().viewport_rect();
    let image = h.render().expect("the frame renders");
    let ppp = image.width() as f32 / SIZE.x;
    let mut v = Vec::new();
    for y in (rect.top() * ppp) as u32..(rect.bottom() * ppp) as u32 {
        for x in (rect.left() * ppp) as u32..(rect.right() * ppp) as u32 {
            v.push(image.get_pixel(x, y).0);
        }
    }
    v
}

pub fn mean_abs_difference(a: &[[u8; 4]], b: &[[u8; 4]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p[c] as f64 - q[c] as f64).abs())
                .sum::<f64>()
        })
        .sum();
    sum / (a.len() * 3) as f64
}

/// Clicks the Export section's button `label` ("Export 5 frames") and steps the viewer until the export, on its
/// thread, has ended (two minutes at most); returns the notice it left.
pub fn export_and_wait(h: &mut Harness<'static, ViewerApp>, label: &str) -> Option<(String, bool)> {
    egui_kittest::kittest::Queryable::get_by_label(h, label).click_accesskit();
    h.run();
    let start = std::time::Instant::now();
    while h.state().is_exporting() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
    }
    h.state().notice().cloned()
}

/// Exports through the panel (its Export section open) as a PNG sequence `dir/name_##.png` of `width` x
/// `height` by clicking `button`; checks that the notice says it was exported, and reads frame `frame` back.
pub fn export_sequence(
    h: &mut Harness<'static, ViewerApp>,
    (dir, name): (&std::path::Path, &str),
    [width, height]: [u32; 2],
    button: &str,
    frame: u32,
) -> image::RgbaImage {
    {
        let form = h.state_mut().animation_form_mut();
        form.export_path = dir.join(format!("{name}_##.png")).display().to_string();
        form.size = [width, height];
    }
    h.run();
    let notice = export_and_wait(h, button);
    assert!(
        notice
            .as_ref()
            .is_some_and(|(t, e)| !e && t.starts_with("Exported")),
        "{notice:?}"
    );
    image::open(dir.join(format!("{name}_{frame:02}.png")))
        .unwrap()
        .to_rgba8()
}

/// The viewport as the viewer last presented it (RGBA, 0..1), cropped out of its window `width` pixels wide.
pub fn shown_viewport(
    v: &energywave::viewer::offscreen::OffscreenViewer,
    width: usize,
) -> Vec<[f32; 4]> {
    let window = v.frame_image().unwrap();
    let rect = v.app.viewport_rect();
    let [vw, vh] = v.app.viewport_px();
    let (x0, y0) = (rect.left().round() as usize, rect.top().round() as usize);
    let mut out = Vec::with_capacity((vw * vh) as usize);
    for y in y0..y0 + vh as usize {
        for x in x0..x0 + vw as usize {
            let at = 4 * (y * width + x);
            out.push(std::array::from_fn(|c| window[at + c] as f32 / 255.0));
        }
    }
    out
}
