//! The window: winit's event loop, the wgpu surface, egui-winit for input and egui-wgpu for drawing. Everything
//! the user sees is `ViewerApp::ui`; this file only runs it, presents frames, and serves the app's requests
//! (screenshots, quitting). Surface loss, minimising and device loss are recovered from without losing the
//! scene.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use super::app::{Request, ViewerApp};
use super::document::Document;
use super::presenter::{Acquired, FrameSurface, Outcome, ViewerGpu, draw_egui};
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

/// How soon a frame the surface could not give is tried again.
const SKIPPED_RETRY: Duration = Duration::from_millis(16);

/// How often an idle window looks at its file for changes made elsewhere (a stat; it draws a frame only when
/// the file changed).
const DISK_POLL: Duration = Duration::from_millis(250);

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
        next_poll: Instant::now(),
    };
    event_loop
        .run_app(&mut handler)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    handler.error.map_or(Ok(()), Err)
}

/// A window's surface, as the presenter sees it.
struct WindowSurface {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
}

impl FrameSurface for WindowSurface {
    type Frame = wgpu::SurfaceTexture;

    fn configured_size(&self) -> [u32; 2] {
        [self.config.width, self.config.height]
    }

    fn wanted_size(&self) -> [u32; 2] {
        let size = self.window.inner_size();
        [size.width, size.height]
    }

    fn configure(&mut self, device: &wgpu::Device, size: [u32; 2]) {
        [self.config.width, self.config.height] = size;
        self.surface.configure(device, &self.config);
    }

    fn acquire(&mut self) -> Acquired<wgpu::SurfaceTexture> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Acquired::Frame(t),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                Acquired::Outdated
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                Acquired::Skip
            }
            wgpu::CurrentSurfaceTexture::Validation => Acquired::Invalid,
        }
    }

    fn view(&self, frame: &wgpu::SurfaceTexture) -> wgpu::TextureView {
        frame.texture.create_view(&Default::default())
    }

    fn present(&mut self, queue: &wgpu::Queue, frame: wgpu::SurfaceTexture) {
        queue.present(frame);
    }
}

struct Gfx {
    surface: WindowSurface,
    gpu: ViewerGpu,
    egui_state: egui_winit::State,
    /// The window's title as last set.
    title: String,
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
    /// When the idle window next looks at its file.
    next_poll: Instant,
}

impl Gfx {
    fn new(event_loop: &ActiveEventLoop, window: Arc<Window>) -> Result<Self, ViewerError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        // Without a driver no backend can make a surface: say what to install rather than wgpu's "failed to
        // create surface for any enabled backend".
        let surface = match instance.create_surface(window.clone()) {
            Ok(surface) => surface,
            Err(e) => {
                let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
                let adapters = pollster::block_on(instance.enumerate_adapters(backends));
                return Err(match adapters.is_empty() {
                    true => GpuError::no_adapter(backends).into(),
                    false => ViewerError::Window(e.to_string()),
                });
            }
        };
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
        let max_texture = ctx.device.limits().max_texture_dimension_2d as usize;
        let gpu = ViewerGpu::new(ctx, config.format);
        let egui_state = egui_winit::State::new(
            gpu.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(max_texture),
        );
        Ok(Self {
            surface: WindowSurface {
                window,
                surface,
                config,
            },
            gpu,
            egui_state,
            title: String::new(),
        })
    }

    fn window(&self) -> &Window {
        &self.surface.window
    }
}

/// The window's first size, logical: 1280 x 800, shrunk to fit a monitor of `monitor` (logical) with 48 points
/// to spare across and 96 down (a taskbar, a title bar), never below 640 x 400.
pub fn fit_window(monitor: Option<(f64, f64)>) -> (f64, f64) {
    let (w, h) = (1280.0f64, 800.0f64);
    match monitor {
        Some((mw, mh)) if mw > 0.0 && mh > 0.0 => {
            (w.min(mw - 48.0).max(640.0), h.min(mh - 96.0).max(400.0))
        }
        _ => (w, h),
    }
}

impl Handler {
    fn create(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewerError> {
        let window = match &self.gfx {
            Some(gfx) => gfx.surface.window.clone(),
            None => {
                // 1280 x 800, or what fits the monitor with room for its panels and the title bar.
                let monitor = event_loop
                    .primary_monitor()
                    .or_else(|| event_loop.available_monitors().next())
                    .map(|m| {
                        let size = m.size().to_logical::<f64>(m.scale_factor());
                        (size.width, size.height)
                    });
                let (w, h) = fit_window(monitor);
                let attributes = Window::default_attributes()
                    .with_title("energywave")
                    .with_inner_size(LogicalSize::new(w, h));
                Arc::new(
                    event_loop
                        .create_window(attributes)
                        .map_err(|e| ViewerError::Window(e.to_string()))?,
                )
            }
        };
        self.gfx = None;
        let gfx = Gfx::new(event_loop, window)?;
        match (&mut self.app, self.doc.take()) {
            (Some(app), _) => gfx.gpu.adopt(app),
            (None, Some(doc)) => {
                let mut recent = super::recent::RecentFiles::for_user();
                if let Some(path) = doc.path() {
                    recent.add(path);
                }
                let mut app = gfx.gpu.app(doc);
                app.set_recent(recent);
                self.app = Some(app);
            }
            (None, None) => unreachable!("the document is kept until the app exists"),
        }
        gfx.window().request_redraw();
        self.gfx = Some(gfx);
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewerError) {
        self.error = Some(error);
        event_loop.exit();
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let (Some(gfx), Some(app)) = (&mut self.gfx, &mut self.app) else {
            return;
        };
        let raw_input = gfx.egui_state.take_egui_input(&gfx.surface.window);
        // The screenshot is of the Nth frame drawn.
        let capture = self
            .options
            .screenshot
            .clone()
            .filter(|_| self.frames + 1 >= self.options.frames.max(1));
        let mut captured = None;
        let format = gfx.surface.config.format;
        let presented = gfx
            .gpu
            .frame(app, raw_input, &mut gfx.surface, |gpu, jobs, screen| {
                if let Some(path) = &capture {
                    captured = Some(capture_window(gpu, format, jobs, screen, path));
                }
            });
        let repaint_now = match presented.outcome {
            Outcome::Drawn { repaint_now } => {
                self.frames += 1;
                repaint_now
            }
            Outcome::DeviceLost => {
                if let Err(e) = self.create(event_loop) {
                    self.fail(event_loop, e);
                }
                return;
            }
            Outcome::Reconfigured => true,
            // A minimised window draws again when it is restored (a resize event).
            Outcome::Minimised => false,
            // No frame to draw into this time (a timeout, an occluded window): try again shortly.
            Outcome::Skipped => {
                self.next_frame = Instant::now() + SKIPPED_RETRY;
                return;
            }
        };
        gfx.egui_state
            .handle_platform_output(&gfx.surface.window, presented.platform_output);
        let title = app.window_title();
        if title != gfx.title {
            gfx.surface.window.set_title(&title);
            gfx.title = title;
        }
        if let Some(e) = presented.gpu_error {
            app.notify(format!("GPU error: {e}"), true);
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
                    let result = save_viewport(&mut gfx.gpu, app, &path, scale);
                    match result {
                        Ok(()) => {
                            app.notify(format!("Screenshot saved: {}", path.display()), false)
                        }
                        Err(e) => app.notify(format!("Screenshot failed: {e}"), true),
                    }
                }
            }
        }
        let now = repaint_now || self.options.screenshot.is_some();
        // Idle is idle: the next frame comes with input, with a repaint the UI asked for after a delay, or
        // when the file changes on disk.
        self.next_frame = match (now, presented.repaint_after) {
            (true, _) => Instant::now(),
            (false, Some(delay)) => Instant::now() + delay,
            (false, None) => Instant::now() + Duration::from_secs(3600),
        };
        if now {
            gfx.window().request_redraw();
        }
    }
}

/// Renders the viewport alone at `scale` times its size (its field at `scale` times the resolution) and saves it
/// to `path`.
fn save_viewport(
    gpu: &mut ViewerGpu,
    app: &ViewerApp,
    path: &std::path::Path,
    scale: u32,
) -> Result<(), ViewerError> {
    let (pixels, [w, h]) = gpu.screenshot(app, scale)?;
    let pixels: Vec<[f64; 4]> = pixels.iter().map(|p| p.map(|c| c as f64)).collect();
    output::write_rgba(path, w, h, &pixels, output::Alpha::Opaque)?;
    Ok(())
}

/// Draws the same frame into an offscreen texture and saves it: the whole window, panel included.
fn capture_window(
    gpu: &ViewerGpu,
    format: wgpu::TextureFormat,
    paint_jobs: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
    path: &std::path::Path,
) -> Result<(), ViewerError> {
    let (device, queue) = (&gpu.ctx.device, &gpu.ctx.queue);
    let [width, height] = screen.size_in_pixels;
    let texture = texture_2d(
        device,
        "energywave.window.capture",
        [width, height],
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("energywave.window.capture.encoder"),
    });
    draw_egui(
        &gpu.renderer,
        &mut encoder,
        &texture.create_view(&Default::default()),
        paint_jobs,
        screen,
    );
    queue.submit([encoder.finish()]);
    let bytes = read_texture(device, queue, &texture, 4)?;
    let bgra = matches!(
        format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let pixels: Vec<[f64; 4]> = bytes
        .chunks_exact(4)
        .map(|p| {
            let (r, b) = if bgra { (p[2], p[0]) } else { (p[0], p[2]) };
            [r, p[1], b, 255].map(|c| c as f64 / 255.0)
        })
        .collect();
    output::write_rgba(path, width, height, &pixels, output::Alpha::Opaque)?;
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
        let response = gfx.egui_state.on_window_event(&gfx.surface.window, &event);
        // egui-winit answers every event with "repaint", a redraw too: drawn, the frame itself says whether it
        // wants the next one (`redraw`), or every frame would ask for another and the idle viewer would spin.
        let drawn = matches!(event, WindowEvent::RedrawRequested);
        match event {
            WindowEvent::CloseRequested => {
                if let Some(app) = &mut self.app {
                    app.request_quit();
                }
                gfx.window().request_redraw();
            }
            WindowEvent::Resized(_) => {
                gfx.gpu.resize(&mut gfx.surface);
                gfx.window().request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
        if response.repaint
            && !drawn
            && let Some(gfx) = &self.gfx
        {
            gfx.window().request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let (Some(gfx), Some(app)) = (&self.gfx, &self.app) else {
            return;
        };
        let now = Instant::now();
        if now >= self.next_poll {
            self.next_poll = now + DISK_POLL;
            if app.document().changed_on_disk() {
                self.next_frame = now;
            }
        }
        if now >= self.next_frame {
            gfx.window().request_redraw();
            self.next_frame = now + Duration::from_secs(3600);
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(self.next_frame.min(self.next_poll)));
    }
}

#[cfg(test)]
mod tests {
    use super::fit_window;

    #[test]
    fn the_window_fits_the_monitor_with_room_for_its_panels() {
        assert_eq!(fit_window(None), (1280.0, 800.0));
        assert_eq!(fit_window(Some((2560.0, 1440.0))), (1280.0, 800.0));
        // A 1280 x 800 screen keeps the status line in view.
        assert_eq!(fit_window(Some((1280.0, 800.0))), (1232.0, 704.0));
        assert_eq!(fit_window(Some((300.0, 200.0))), (640.0, 400.0));
    }
}
