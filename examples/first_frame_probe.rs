use energywave::gpu::GpuContext;
use energywave::scene::Scene;
use energywave::viewer::{Document, offscreen::OffscreenViewer, presenter::ViewerGpu};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    for path in &args {
        let t0 = Instant::now();
        let scene = if path == "default" {
            Scene::default_scene()
        } else {
            Scene::load(std::path::Path::new(path)).unwrap()
        };
        let t_load = t0.elapsed().as_secs_f64();
        let ctx = GpuContext::new().unwrap();
        let t_ctx = t0.elapsed().as_secs_f64();
        let gpu = ViewerGpu::new(ctx, wgpu::TextureFormat::Rgba8Unorm);
        let t_gpu = t0.elapsed().as_secs_f64();
        drop(gpu);
        let mut v = OffscreenViewer::new(Document::new(scene.clone(), None), 1280, 800).unwrap();
        let t_new = t0.elapsed().as_secs_f64();
        v.app.view_mut().show_overlays = false;
        let mut times = vec![];
        for _ in 0..4 {
            let s = Instant::now();
            v.frame().unwrap();
            times.push(s.elapsed().as_secs_f64());
        }
        let px = v.viewport_pixels().unwrap();
        let bg = scene.colors.background.map(|c| (c * 255.0).round() as i32);
        let lit = px
            .chunks(4)
            .filter(|p| (0..3).any(|i| (p[i] as i32 - bg[i]).abs() > 3))
            .count();
        println!(
            "{path}: load {:.2} ctx {:.2} viewergpu {:.2} offscreen-new(incl ctx) {:.2} frames {:?} lit px {lit}/{}",
            t_load,
            t_ctx - t_load,
            t_gpu - t_ctx,
            t_new - t_gpu,
            times
                .iter()
                .map(|t| (t * 1000.0).round() / 1000.0)
                .collect::<Vec<_>>(),
            px.len() / 4
        );
    }
}
