//! One viewer frame, in a window or not: runs `ViewerApp::ui`, tessellates, draws with egui-wgpu into what the
//! surface hands out, and presents. What a surface or a device can do wrong is handled here, once, for the
//! window and the offscreen viewer alike: a minimised (0 x 0) surface draws nothing, a lost or outdated one is
//! reconfigured, a validation error is said in the panel, and a lost device is noticed so that the owner can
//! recreate the GPU side while the app (and so the scene) lives on.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use super::app::ViewerApp;
use super::viewport::{ViewportGpu, ViewportReport};
use crate::gpu::{GpuContext, GpuError};

/// What a surface gave when asked for the next frame.
#[derive(Debug)]
pub enum Acquired<F> {
    /// A texture to draw into (wgpu's `Success` and `Suboptimal`).
    Frame(F),
    /// The surface no longer matches the window (`Outdated`) or is gone (`Lost`): configure it again.
    Outdated,
    /// Nothing to draw into this time (`Timeout`, `Occluded`): try at the next frame.
    Skip,
    /// The surface reported a validation error (`Validation`).
    Invalid,
}

/// Where viewer frames go: a window's surface, or a texture.
pub trait FrameSurface {
    type Frame;
    /// The size the surface is configured at, in pixels (what the UI is laid out for).
    fn configured_size(&self) -> [u32; 2];
    /// The size the surface should have now (0 x 0 while minimised).
    fn wanted_size(&self) -> [u32; 2];
    /// Configures the surface at `size` (never 0 x 0).
    fn configure(&mut self, device: &wgpu::Device, size: [u32; 2]);
    fn acquire(&mut self) -> Acquired<Self::Frame>;
    fn view(&self, frame: &Self::Frame) -> wgpu::TextureView;
    fn present(&mut self, queue: &wgpu::Queue, frame: Self::Frame);
}

/// What became of a frame.
#[derive(Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Drawn and presented; `repaint_now` when the UI wants the next frame at once (an animation, a drag).
    Drawn { repaint_now: bool },
    /// The surface is 0 x 0 (a minimised window): nothing drawn, the UI not run.
    Minimised,
    /// The surface was lost or outdated and has been configured again: draw again.
    Reconfigured,
    /// The surface had nothing to draw into.
    Skipped,
    /// The device is lost: the owner must recreate the GPU side (`ViewerGpu::new`) and call `adopt`.
    DeviceLost,
}

/// A frame's outcome, what the UI asks of the platform (cursor, clipboard), and any GPU error its commands
/// raised.
pub struct Presented {
    pub outcome: Outcome,
    /// When the UI wants its next frame though nothing happens before (a delayed repaint: an export's
    /// progress, a tooltip); `None`: only on input.
    pub repaint_after: Option<std::time::Duration>,
    pub platform_output: egui::PlatformOutput,
    pub gpu_error: Option<GpuError>,
}

/// The GPU side of a viewer: device, egui's renderer with the viewport's resources, and a flag raised when the
/// device is lost. Recreated whole after a device loss; the `ViewerApp` is kept.
pub struct ViewerGpu {
    pub ctx: GpuContext,
    pub egui_ctx: egui::Context,
    pub renderer: egui_wgpu::Renderer,
    report: Arc<Mutex<ViewportReport>>,
    /// The viewer's frame cache, shared by the viewport and the app (which simulates live particles in it).
    cache: Arc<crate::frame::FrameCache>,
    device_lost: Arc<AtomicBool>,
}

impl ViewerGpu {
    /// The GPU side on `ctx`, drawing into surfaces of `format`.
    pub fn new(ctx: GpuContext, format: wgpu::TextureFormat) -> Self {
        let device_lost = Arc::new(AtomicBool::new(false));
        let flag = device_lost.clone();
        ctx.device
            .set_device_lost_callback(move |_, _| flag.store(true, Ordering::SeqCst));
        let report = Arc::new(Mutex::new(ViewportReport::default()));
        let mut renderer =
            egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        let cache = Arc::new(crate::gpu::frame_cache(&ctx.device, &ctx.queue));
        renderer.callback_resources.insert(ViewportGpu::new(
            &ctx.device,
            format,
            report.clone(),
            cache.clone(),
        ));
        Self {
            ctx,
            cache,
            egui_ctx: egui::Context::default(),
            renderer,
            report,
            device_lost,
        }
    }

    /// The viewer app on `doc`, on this GPU.
    pub fn app(&self, doc: super::Document) -> ViewerApp {
        ViewerApp::new(
            doc,
            self.ctx.adapter_summary(),
            self.max_resolution(),
            self.report.clone(),
            self.cache.clone(),
        )
    }

    /// Hands this (recreated) GPU side to an existing app, which keeps its scene, history and camera.
    pub fn adopt(&self, app: &mut ViewerApp) {
        app.set_gpu(
            self.ctx.adapter_summary(),
            self.max_resolution(),
            self.report.clone(),
            self.cache.clone(),
        );
        app.notify(
            "The GPU device was lost and has been recreated; the scene is unchanged",
            true,
        );
    }

    /// The viewport alone at `scale` times its size, its field integrated at `scale` times the resolution
    /// (`ViewerApp::screenshot_view`): RGBA and its size.
    pub fn screenshot(
        &mut self,
        app: &ViewerApp,
        scale: u32,
    ) -> Result<(Vec<[f32; 4]>, [u32; 2]), GpuError> {
        let view = app.screenshot_view(scale);
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let vp = self
            .renderer
            .callback_resources
            .get_mut::<super::viewport::ViewportGpu>()
            .ok_or_else(|| GpuError::Validation("the viewport is not installed".into()))?;
        Ok((vp.render_image(device, queue, &view)?, view.size))
    }

    pub fn max_resolution(&self) -> u32 {
        self.ctx.device.limits().max_texture_dimension_2d
    }

    pub fn is_device_lost(&self) -> bool {
        self.device_lost.load(Ordering::SeqCst)
    }

    /// Resizes `surface` to the size it wants; a 0 x 0 size (minimised) keeps the old configuration.
    pub fn resize<S: FrameSurface>(&self, surface: &mut S) {
        let size = surface.wanted_size();
        if size[0] > 0 && size[1] > 0 && size != surface.configured_size() {
            surface.configure(&self.ctx.device, size);
        }
    }

    /// One frame: the UI on `input`, drawn into `surface` and presented. `before_present` sees the tessellated
    /// frame before it is presented (the window's screenshot of itself draws it a second time there).
    pub fn frame<S: FrameSurface>(
        &mut self,
        app: &mut ViewerApp,
        input: egui::RawInput,
        surface: &mut S,
        before_present: impl FnOnce(&Self, &[egui::ClippedPrimitive], &egui_wgpu::ScreenDescriptor),
    ) -> Presented {
        let early = |outcome| Presented {
            outcome,
            repaint_after: None,
            platform_output: Default::default(),
            gpu_error: None,
        };
        // wgpu reports a loss (or a `destroy`) from its maintenance: run it, without waiting, before using the
        // device (egui-wgpu panics when a buffer cannot be mapped on a dead device).
        let _ = self.ctx.device.poll(wgpu::PollType::Poll);
        if self.is_device_lost() {
            return early(Outcome::DeviceLost);
        }
        let wanted = surface.wanted_size();
        if wanted[0] == 0 || wanted[1] == 0 {
            return early(Outcome::Minimised);
        }
        // Acquire first: a frame that cannot be drawn must not consume the UI's input.
        let frame = match surface.acquire() {
            Acquired::Frame(frame) => frame,
            Acquired::Outdated => {
                surface.configure(&self.ctx.device, wanted);
                return early(Outcome::Reconfigured);
            }
            Acquired::Skip => return early(Outcome::Skipped),
            Acquired::Invalid => {
                app.notify(
                    "The window surface reported a validation error; it has been reconfigured",
                    true,
                );
                surface.configure(&self.ctx.device, wanted);
                return early(Outcome::Reconfigured);
            }
        };
        let output = self.egui_ctx.run_ui(input, |ui| app.ui(ui));
        let delay = (output.viewport_output.get(&egui::ViewportId::ROOT))
            .map_or(std::time::Duration::MAX, |v| v.repaint_delay);
        let ui_repaint_now = delay.is_zero();
        // egui asks for no repaint with a delay of Duration::MAX.
        let repaint_after = (delay < std::time::Duration::from_secs(3600)).then_some(delay);
        let jobs = self
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: surface.configured_size(),
            pixels_per_point: output.pixels_per_point,
        };
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.renderer.update_texture(device, queue, *id, delta);
            }
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.viewer.encoder"),
        });
        let mut buffers = self
            .renderer
            .update_buffers(device, queue, &mut encoder, &jobs, &screen);
        // The viewport (recorded just now, by `update_buffers`) may want the next frame for its average.
        let repaint_now = ui_repaint_now || self.report.lock().is_ok_and(|r| r.wants_frame());
        draw_egui(
            &self.renderer,
            &mut encoder,
            &surface.view(&frame),
            &jobs,
            &screen,
        );
        buffers.push(encoder.finish());
        let gpu_error = self.ctx.checked(|| queue.submit(buffers)).err();
        before_present(self, &jobs, &screen);
        surface.present(&self.ctx.queue, frame);
        for id in &output.textures_delta.free {
            self.renderer.free_texture(id);
        }
        Presented {
            outcome: Outcome::Drawn { repaint_now },
            repaint_after,
            platform_output: output.platform_output,
            gpu_error,
        }
    }
}

/// Draws `paint_jobs` with egui-wgpu into `view`, cleared first.
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
