//! The viewer drawn into a texture instead of a window: the same `ViewerApp::ui` and the same frame code
//! (`presenter`) as `window.rs`, for timing whole viewer frames and for stress tests without a display. The
//! texture stands in for a window's surface, so tests can make it minimised, lost or outdated, and lose the
//! device, exactly where a window would.

use std::collections::VecDeque;

use super::app::ViewerApp;
use super::document::Document;
use super::presenter::{Acquired, FrameSurface, Outcome, ViewerGpu};
use super::viewport::{ViewportGpu, ViewportView};
use crate::gpu::{GpuContext, GpuError, texture_2d};

/// Format of the offscreen frame (what a window's surface would typically be).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// What the texture surface answers instead of a frame, once, in order (set by tests).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceFault {
    Outdated,
    Lost,
    Timeout,
    Occluded,
    Validation,
}

/// A texture standing in for a window's surface.
pub struct TextureSurface {
    texture: Option<wgpu::Texture>,
    configured: [u32; 2],
    wanted: [u32; 2],
    /// Answers for the next acquisitions, before frames are handed out again.
    pub faults: VecDeque<SurfaceFault>,
    /// How many times the surface has been configured.
    pub configures: u32,
    /// How many frames have been presented.
    pub presented: u64,
}

impl FrameSurface for TextureSurface {
    type Frame = wgpu::Texture;

    fn configured_size(&self) -> [u32; 2] {
        self.configured
    }

    fn wanted_size(&self) -> [u32; 2] {
        self.wanted
    }

    fn configure(&mut self, device: &wgpu::Device, size: [u32; 2]) {
        self.texture = Some(texture_2d(
            device,
            "energywave.offscreen.frame",
            size,
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        ));
        self.configured = size;
        self.configures += 1;
    }

    fn acquire(&mut self) -> Acquired<wgpu::Texture> {
        match self.faults.pop_front() {
            Some(SurfaceFault::Outdated | SurfaceFault::Lost) => Acquired::Outdated,
            Some(SurfaceFault::Timeout | SurfaceFault::Occluded) => Acquired::Skip,
            Some(SurfaceFault::Validation) => Acquired::Invalid,
            None => match &self.texture {
                Some(t) => Acquired::Frame(t.clone()),
                None => Acquired::Outdated,
            },
        }
    }

    fn view(&self, frame: &wgpu::Texture) -> wgpu::TextureView {
        frame.create_view(&Default::default())
    }

    fn present(&mut self, _queue: &wgpu::Queue, _frame: wgpu::Texture) {
        self.presented += 1;
    }
}

/// A viewer without a window.
pub struct OffscreenViewer {
    pub app: ViewerApp,
    pub gpu: ViewerGpu,
    pub surface: TextureSurface,
    /// How many times the GPU side has been recreated after a device loss.
    pub recoveries: u32,
    /// Frames run so far: the UI's clock, a 60 Hz frame each, so that its animations end as in a window.
    frames: u64,
}

impl OffscreenViewer {
    /// A viewer on `doc`, `width` x `height` pixels, on its own GPU context.
    pub fn new(doc: Document, width: u32, height: u32) -> Result<Self, GpuError> {
        let gpu = ViewerGpu::new(GpuContext::new()?, FORMAT);
        let app = gpu.app(doc);
        let mut surface = TextureSurface {
            texture: None,
            configured: [0, 0],
            wanted: [width, height],
            faults: VecDeque::new(),
            configures: 0,
            presented: 0,
        };
        surface.configure(&gpu.ctx.device, [width, height]);
        Ok(Self {
            app,
            gpu,
            surface,
            recoveries: 0,
            frames: 0,
        })
    }

    /// Resizes the "window" (0 x 0 is a minimised one), as a window's resize event does.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.surface.wanted = [width, height];
        self.gpu.resize(&mut self.surface);
    }

    /// Destroys the device under the viewer, as a driver reset or an unplugged GPU would.
    pub fn lose_device(&self) {
        self.gpu.ctx.device.destroy();
    }

    /// Runs the UI once and draws it, waiting until the GPU has finished. A lost device is recreated here, as
    /// the window does, and the frame reported as `DeviceLost`.
    pub fn frame(&mut self) -> Result<Outcome, GpuError> {
        let [w, h] = self.surface.configured_size();
        self.frames += 1;
        let input = egui::RawInput {
            time: Some(self.frames as f64 / 60.0),
            predicted_dt: 1.0 / 60.0,
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(w as f32, h as f32),
            )),
            ..Default::default()
        };
        let presented = self
            .gpu
            .frame(&mut self.app, input, &mut self.surface, |_, _, _| {});
        let outcome = presented.outcome;
        if let Some(e) = presented.gpu_error {
            return Err(e);
        }
        if outcome == Outcome::DeviceLost {
            self.gpu = ViewerGpu::new(GpuContext::new()?, FORMAT);
            self.gpu.adopt(&mut self.app);
            let size = self.surface.configured_size();
            self.surface.configure(&self.gpu.ctx.device, size);
            self.recoveries += 1;
            return Ok(outcome);
        }
        self.gpu
            .ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        self.gpu.ctx.check_uncaptured()?;
        match self.app.report().error {
            Some(e) => Err(GpuError::Validation(e)),
            None => Ok(outcome),
        }
    }

    /// The viewport alone at its last size, rendered again and read back (RGBA).
    pub fn viewport_image(&mut self) -> Result<Vec<[f32; 4]>, GpuError> {
        let view = ViewportView {
            progressive: false,
            ..self.app.viewport_view()
        };
        let (device, queue) = (&self.gpu.ctx.device, &self.gpu.ctx.queue);
        match self
            .gpu
            .renderer
            .callback_resources
            .get_mut::<ViewportGpu>()
        {
            Some(vp) => vp.render_image(device, queue, &view),
            None => Err(GpuError::Validation("the viewport is not installed".into())),
        }
    }

    /// A screenshot as the window takes it (`ViewerGpu::screenshot`): RGBA and its size.
    pub fn screenshot(&mut self, scale: u32) -> Result<(Vec<[f32; 4]>, [u32; 2]), GpuError> {
        self.gpu.screenshot(&self.app, scale)
    }

    /// The last presented frame, read back (RGBA8).
    pub fn frame_image(&self) -> Result<Vec<u8>, GpuError> {
        match &self.surface.texture {
            Some(t) => self.gpu.ctx.read_texture(t, 4),
            None => Err(GpuError::Readback("the surface is not configured".into())),
        }
    }

    /// The viewport's part of the last presented frame (RGBA8, rows from the top).
    pub fn viewport_pixels(&self) -> Result<Vec<u8>, GpuError> {
        let image = self.frame_image()?;
        let width = self.surface.configured_size()[0] as usize;
        let rect = self.app.viewport_rect();
        let [w, h] = self.app.viewport_px();
        let (x0, y0) = (rect.min.x.round() as usize, rect.min.y.round() as usize);
        Ok((y0..y0 + h as usize)
            .flat_map(|y| {
                let row = 4 * (y * width + x0);
                image[row..row + 4 * w as usize].iter().copied()
            })
            .collect())
    }

    /// The brightness texture B the viewport shows now, read back (W x W, rows from the top): B itself, before
    /// the blend's clamp, where a non-finite value would hide in a clamped pixel.
    pub fn field_values(&mut self) -> Result<Vec<f32>, GpuError> {
        let ctx = &self.gpu.ctx;
        match self
            .gpu
            .renderer
            .callback_resources
            .get::<ViewportGpu>()
            .and_then(|vp| vp.field_texture())
        {
            Some(t) => Ok(bytemuck::cast_slice(&ctx.read_texture(t, 4)?).to_vec()),
            None => Err(GpuError::Validation(
                "the field has not been rendered".into(),
            )),
        }
    }

    /// How many times the field has been integrated.
    pub fn field_renders(&self) -> u64 {
        self.app.report().field_renders
    }
}
