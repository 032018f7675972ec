//! The viewer drawn into a texture instead of a window: the same `ViewerApp::ui`, egui tessellation and
//! egui-wgpu drawing as `window.rs`, for timing whole viewer frames without a display.

use std::sync::{Arc, Mutex};

use super::app::ViewerApp;
use super::document::Document;
use super::viewport::{ViewportGpu, ViewportReport};
use crate::gpu::{GpuContext, GpuError, texture_2d};

/// Format of the offscreen frame (what a window's surface would typically be).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Draws `paint_jobs` with egui-wgpu into `view`, cleared first: the window's last step.
pub fn draw_egui(
    renderer: &egui_wgpu::Renderer,
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    paint_jobs: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
) {
    let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("energywave.egui.pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    renderer.render(&mut pass.forget_lifetime(), paint_jobs, screen);
}

/// A viewer without a window.
pub struct OffscreenViewer {
    pub app: ViewerApp,
    ctx: GpuContext,
    egui_ctx: egui::Context,
    renderer: egui_wgpu::Renderer,
    target: wgpu::Texture,
    size: [u32; 2],
}

impl OffscreenViewer {
    /// A viewer on `doc`, `width` x `height` pixels, on its own GPU context.
    pub fn new(doc: Document, width: u32, height: u32) -> Result<Self, GpuError> {
        let ctx = GpuContext::new()?;
        let report = Arc::new(Mutex::new(ViewportReport::default()));
        let mut renderer =
            egui_wgpu::Renderer::new(&ctx.device, FORMAT, egui_wgpu::RendererOptions::default());
        renderer
            .callback_resources
            .insert(ViewportGpu::new(&ctx.device, FORMAT, report.clone()));
        let app = ViewerApp::new(
            doc,
            ctx.adapter_summary(),
            ctx.device.limits().max_texture_dimension_2d,
            report,
        );
        let target = texture_2d(
            &ctx.device,
            "energywave.offscreen.frame",
            [width, height],
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        Ok(Self {
            app,
            ctx,
            egui_ctx: egui::Context::default(),
            renderer,
            target,
            size: [width, height],
        })
    }

    /// Runs the UI once and draws it, waiting until the GPU has finished.
    pub fn frame(&mut self) -> Result<(), GpuError> {
        let [w, h] = self.size;
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(w as f32, h as f32),
            )),
            ..Default::default()
        };
        let app = &mut self.app;
        let output = self.egui_ctx.run_ui(input, |ui| app.ui(ui));
        let jobs = self
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: self.size,
            pixels_per_point: output.pixels_per_point,
        };
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.renderer.update_texture(device, queue, *id, delta);
            }
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.offscreen.encoder"),
        });
        let mut buffers = self
            .renderer
            .update_buffers(device, queue, &mut encoder, &jobs, &screen);
        draw_egui(
            &self.renderer,
            &mut encoder,
            &self.target.create_view(&Default::default()),
            &jobs,
            &screen,
        );
        buffers.push(encoder.finish());
        self.ctx.checked(|| queue.submit(buffers))?;
        for id in &output.textures_delta.free {
            self.renderer.free_texture(id);
        }
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        match self.app.report().error {
            Some(e) => Err(GpuError::Validation(e)),
            None => Ok(()),
        }
    }

    /// The viewport alone at its last size, rendered again and read back (RGBA).
    pub fn viewport_image(&mut self) -> Result<Vec<[f32; 4]>, GpuError> {
        let view = super::viewport::ViewportView {
            scene: self.app.frame_scene(),
            size: [
                self.app.viewport_px[0].max(1),
                self.app.viewport_px[1].max(1),
            ],
            show_grid: self.app.show_grid,
        };
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        match self.renderer.callback_resources.get_mut::<ViewportGpu>() {
            Some(vp) => vp.render_image(device, queue, &view),
            None => Err(GpuError::Validation("the viewport is not installed".into())),
        }
    }

    /// How many times the field has been integrated.
    pub fn field_renders(&self) -> u64 {
        self.app.report().field_renders
    }
}
