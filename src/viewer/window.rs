//! The window: winit's event loop, the wgpu surface, egui-winit for input and egui-wgpu for drawing. Everything
//! the user sees is `ViewerApp::ui`; this file only runs it, presents frames, and serves the app's requests
//! (screenshots, quitting). Surface loss, minimising and device loss are recovered from without losing the
//! scene.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use super::app::{Request, ViewerApp};
use super::document::Document;
use super::offscreen::draw_egui;
use super::viewport::{ViewportGpu, ViewportReport, ViewportView};
use crate::gpu::{GpuContext, GpuError, read_texture, texture_2d};
use crate::output::{self, OutputError};

/// How `energywave view` runs.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// Save the whole window (panel included) to this PNG after `frames` frames, then exit.
    pub screenshot: Option<PathBuf>,
    pub frames: u32,
}

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("cannot open a window: {0}")]
    Window(String),
    #[error("{0}")]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Output(#[from] OutputError),
}

/// Longest wait between two frames when nothing happens (keeps hot reload and the status line alive).
const IDLE_FRAME: Duration = Duration::from_millis(250);

/// Opens the window on `doc` and runs until it is closed.
pub fn run(doc: Document, options: ViewOptions) -> Result<(), ViewerError> {
    let event_loop = EventLoop::new().map_err(|e| ViewerError::Window(e.to_string()))?;
    let mut handler = Handler {
        doc: Some(doc),
        options,
        app: None,
        gfx: None,
        error: None,
        frames: 0,
        next_frame: Instant::now(),
    };
    event_loop
        .run_app(&mut handler)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    handler.error.map_or(Ok(()), Err)
}

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    device_lost: Arc<AtomicBool>,
}

struct Handler {
    /// The document until the app is created.
    doc: Option<Document>,
    options: ViewOptions,
    app: Option<ViewerApp>,
    gfx: Option<Gfx>,
    error: Option<ViewerError>,
    frames: u32,
    next_frame: Instant,
}

impl Gfx {
    fn new(
        event_loop: &ActiveEventLoop,
        window: Arc<Window>,
    ) -> Result<(Self, Arc<Mutex<ViewportReport>>), ViewerError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Window(e.to_string()))?;
        let ctx = pollster::block_on(GpuContext::with_instance(instance, Some(&surface)))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&ctx.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| {
                ViewerError::Window("the surface is not supported by the adapter".into())
            })?;
        // Colors are display values: prefer a non-sRGB format (egui does too); the blit handles sRGB ones.
        let caps = surface.get_capabilities(&ctx.adapter);
        if let Some(&format) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = format;
        }
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(&ctx.device, &config);
        let device_lost = Arc::new(AtomicBool::new(false));
        let flag = device_lost.clone();
        ctx.device
            .set_device_lost_callback(move |_, _| flag.store(true, Ordering::SeqCst));

        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let mut renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            config.format,
            egui_wgpu::RendererOptions::default(),
        );
        let report = Arc::new(Mutex::new(ViewportReport::default()));
        renderer.callback_resources.insert(ViewportGpu::new(
            &ctx.device,
            config.format,
            report.clone(),
        ));
        Ok((
            Self {
                window,
                surface,
                config,
                ctx,
                egui_ctx,
                egui_state,
                renderer,
                device_lost,
            },
            report,
        ))
    }

    fn resize(&mut self, width: u32, height: u32) {
        // A minimised window is 0 x 0: keep the old configuration and draw nothing until it comes back.
        if width == 0 || height == 0 {
            return;
        }
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&self.ctx.device, &self.config);
    }
}

impl Handler {
    fn create(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewerError> {
        let window = match &self.gfx {
            Some(gfx) => gfx.window.clone(),
            None => {
                let attributes = Window::default_attributes()
                    .with_title("energywave")
                    .with_inner_size(LogicalSize::new(1280.0, 800.0));
                Arc::new(
                    event_loop
                        .create_window(attributes)
                        .map_err(|e| ViewerError::Window(e.to_string()))?,
                )
            }
        };
        self.gfx = None;
        let (gfx, report) = Gfx::new(event_loop, window)?;
        let adapter = gfx.ctx.adapter_summary();
        let max_resolution = gfx.ctx.device.limits().max_texture_dimension_2d;
        match (&mut self.app, self.doc.take()) {
            (Some(app), _) => {
                app.set_gpu(adapter, max_resolution, report);
                app.notify("The GPU device was lost and has been recreated", true);
            }
            (None, Some(doc)) => {
                self.app = Some(ViewerApp::new(doc, adapter, max_resolution, report))
            }
            (None, None) => unreachable!("the document is kept until the app exists"),
        }
        gfx.window.request_redraw();
        self.gfx = Some(gfx);
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewerError) {
        self.error = Some(error);
        event_loop.exit();
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        if self
            .gfx
            .as_ref()
            .is_some_and(|g| g.device_lost.load(Ordering::SeqCst))
        {
            if let Err(e) = self.create(event_loop) {
                self.fail(event_loop, e);
            }
            return;
        }
        let (Some(gfx), Some(app)) = (&mut self.gfx, &mut self.app) else {
            return;
        };
        let size = gfx.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return;
        }
        let raw_input = gfx.egui_state.take_egui_input(&gfx.window);
        let output = gfx.egui_ctx.run_ui(raw_input, |ui| app.ui(ui));
        gfx.egui_state
            .handle_platform_output(&gfx.window, output.platform_output.clone());
        let repaint_now = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .is_some_and(|v| v.repaint_delay.is_zero());
        let paint_jobs = gfx
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [gfx.config.width, gfx.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        let (device, queue) = (&gfx.ctx.device, &gfx.ctx.queue);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                gfx.renderer.update_texture(device, queue, *id, delta);
            }
        }
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(device, &gfx.config);
                gfx.window.request_redraw();
                return;
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => return,
            wgpu::CurrentSurfaceTexture::Validation => {
                app.notify(
                    "The window surface reported a validation error; reconfiguring",
                    true,
                );
                gfx.surface.configure(device, &gfx.config);
                return;
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.window.encoder"),
        });
        let mut buffers =
            gfx.renderer
                .update_buffers(device, queue, &mut encoder, &paint_jobs, &screen);
        draw_egui(&gfx.renderer, &mut encoder, &view, &paint_jobs, &screen);
        buffers.push(encoder.finish());
        queue.submit(buffers);

        self.frames += 1;
        let capture = self
            .options
            .screenshot
            .clone()
            .filter(|_| self.frames >= self.options.frames.max(1));
        let captured = capture.map(|path| capture_window(gfx, &paint_jobs, &screen, &path));
        queue.present(frame);
        for id in &output.textures_delta.free {
            gfx.renderer.free_texture(id);
        }
        match captured {
            Some(Ok(())) => {
                event_loop.exit();
                return;
            }
            Some(Err(e)) => {
                self.fail(event_loop, e);
                return;
            }
            None => {}
        }
        for request in app.take_requests() {
            match request {
                Request::Quit => event_loop.exit(),
                Request::Screenshot { path, scale } => {
                    let [w, h] = app.viewport_px;
                    let view = ViewportView {
                        scene: app.frame_scene(),
                        size: [w.max(1) * scale, h.max(1) * scale],
                        show_grid: app.show_grid,
                    };
                    let result = match gfx.renderer.callback_resources.get_mut::<ViewportGpu>() {
                        Some(vp) => vp
                            .render_image(device, queue, &view)
                            .map_err(ViewerError::from)
                            .and_then(|pixels| {
                                let pixels: Vec<[f64; 4]> =
                                    pixels.iter().map(|p| p.map(|c| c as f64)).collect();
                                output::write_rgba(
                                    &path,
                                    view.size[0],
                                    view.size[1],
                                    &pixels,
                                    false,
                                )
                                .map_err(ViewerError::from)
                            }),
                        None => Err(ViewerError::Window(
                            "the viewport is not initialised".into(),
                        )),
                    };
                    match result {
                        Ok(()) => {
                            app.notify(format!("Screenshot saved: {}", path.display()), false)
                        }
                        Err(e) => app.notify(format!("Screenshot failed: {e}"), true),
                    }
                }
            }
        }
        self.next_frame = Instant::now()
            + if repaint_now || self.options.screenshot.is_some() {
                Duration::ZERO
            } else {
                IDLE_FRAME
            };
        if repaint_now || self.options.screenshot.is_some() {
            gfx.window.request_redraw();
        }
    }
}

/// Draws the same frame into an offscreen texture and saves it: the whole window, panel included.
fn capture_window(
    gfx: &Gfx,
    paint_jobs: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
    path: &std::path::Path,
) -> Result<(), ViewerError> {
    let (device, queue) = (&gfx.ctx.device, &gfx.ctx.queue);
    let [width, height] = screen.size_in_pixels;
    let texture = texture_2d(
        device,
        "energywave.window.capture",
        [width, height],
        gfx.config.format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("energywave.window.capture.encoder"),
    });
    draw_egui(
        &gfx.renderer,
        &mut encoder,
        &texture.create_view(&Default::default()),
        paint_jobs,
        screen,
    );
    queue.submit([encoder.finish()]);
    let bytes = read_texture(device, queue, &texture, 4)?;
    let bgra = matches!(
        gfx.config.format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let pixels: Vec<[f64; 4]> = bytes
        .chunks_exact(4)
        .map(|p| {
            let (r, b) = if bgra { (p[2], p[0]) } else { (p[0], p[2]) };
            [r, p[1], b, 255].map(|c| c as f64 / 255.0)
        })
        .collect();
    output::write_rgba(path, width, height, &pixels, false)?;
    Ok(())
}

impl ApplicationHandler for Handler {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.create(event_loop)
        {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = &mut self.gfx else { return };
        let response = gfx.egui_state.on_window_event(&gfx.window, &event);
        match event {
            WindowEvent::CloseRequested => {
                if let Some(app) = &mut self.app {
                    app.request_quit();
                }
                gfx.window.request_redraw();
            }
            WindowEvent::Resized(size) => {
                gfx.resize(size.width, size.height);
                gfx.window.request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
        if response.repaint
            && let Some(gfx) = &self.gfx
        {
            gfx.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(gfx) = &self.gfx else { return };
        if Instant::now() >= self.next_frame {
            gfx.window.request_redraw();
            self.next_frame = Instant::now() + IDLE_FRAME;
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(self.next_frame));
    }
}
