//! The 3D viewport on the GPU: the ground grid behind the energy wave, drawn by the same `SceneRenderer` as
//! headless rendering into an offscreen frame that an egui paint callback copies into the window. Because it is an egui-wgpu callback, the window and the UI tests draw it
//! through the same code.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::progressive::{FrameBudget, MOVING_TOLERANCE, PREVIEW_TOLERANCE, Pacing, Plan, Work};
use crate::frame::refine::SHARE;
use crate::frame::{FrameCache, FrameSetup, Refine};
use crate::gpu::{
    BlitPass, Brightness, FieldInputs, FieldRenderer, FrameTargets, Gpu, GpuError, GridPass,
    SceneRenderer, Specialise, Target, checked, layers_of, read_frame,
};
use crate::integrate::Integrator;
use crate::scene::Scene;

/// Format of the offscreen viewport: half floats, so the blend and the grid keep more than 8 bits.
pub const VIEWPORT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

use crate::gpu::grid_pass::gpu_data::GridVertex;

/// What one viewport frame shows.
#[derive(Clone, Debug)]
pub struct ViewportView {
    pub scene: Scene,
    /// Size in physical pixels.
    pub size: [u32; 2],
    pub show_grid: bool,
    /// With a jittered integrator: how many frames to average while the scene stays the same (1: none).
    pub average_frames: u32,
    /// Whether a moving view may show the moving field while the full one is refined (`progressive`); the
    /// viewer's screen does, screenshots never.
    pub progressive: bool,
    /// How the moving field and the refining bands are chosen (`progressive::Pacing`).
    pub pacing: Pacing,
    /// While the panel edits the glare's threshold: that threshold, the glow at or below it dimmed.
    pub threshold_preview: Option<f64>,
}

/// What the GPU side reports back to the UI.
#[derive(Clone, Debug, Default)]
pub struct ViewportReport {
    /// The last GPU error, cleared by the next good frame.
    pub error: Option<String>,
    /// How many times the field texture has been rendered.
    pub field_renders: u64,
    /// While jittered frames are averaged: how many the picture holds, and the most it will hold.
    pub averaged: Option<(u32, u32)>,
    /// While the view moves, until the full field is whole again: the side of the moving field's coarse grid.
    pub preview: Option<u32>,
    /// And the moving field's side (W, or less where the machine is slow), while it shows.
    pub moving_side: Option<u32>,
    /// The frame just recorded made the picture whole after a coarse one (the UI, drawn before it, still
    /// said otherwise).
    pub refined: bool,
    /// What is being worked out on a thread of its own (`SceneRenderer::preparing`), the frames drawing
    /// stand-ins meanwhile.
    pub preparing: Option<String>,
    /// The frame just recorded showed what was being prepared, now ready (the UI still said otherwise).
    pub prepared: bool,
}

impl ViewportReport {
    /// Whether the viewport wants another frame: to add to its average, to refine a coarse picture, or to let
    /// the UI show that the picture is whole. While something is being prepared the UI asks for frames itself,
    /// a few a second (`settled` is false).
    pub fn wants_frame(&self) -> bool {
        self.averaged.is_some_and(|(k, most)| k < most)
            || self.preview.is_some()
            || self.refined
            || self.prepared
    }

    /// Whether the picture shows the scene as it is, whole: nothing to refine, average or prepare.
    pub fn settled(&self) -> bool {
        !self.wants_frame() && self.preparing.is_none()
    }
}

/// The viewport's pipelines and GPU state, kept in egui-wgpu's callback resources.
pub struct ViewportGpu {
    scene_renderer: SceneRenderer,
    grid: GridPass,
    blit: BlitPass,
    targets: Option<(FrameTargets, wgpu::BindGroup)>,
    report: Arc<Mutex<ViewportReport>>,
    /// The field of a moving view (refined at a looser tolerance, `progressive`), and what frames cost.
    preview: FieldRenderer,
    budget: FrameBudget,
    /// The field inputs of the last frame, and whether it showed the moving field (the side of its coarse grid
    /// and its tolerance).
    last_inputs: Option<FieldInputs>,
    showing_preview: Option<(u32, Option<u32>)>,
    /// The side of the moving field's texture (its W over the budget's divisor).
    preview_side: u32,
    /// What the frame in `targets` shows besides the field's texels: while neither changes, it is shown again
    /// as it is, not composed anew (a still view costs the copy into the window alone).
    composed: Option<Composed>,
    /// Whether the scene's field pipelines are being compiled on a thread of their own (its frames drawn by
    /// Simpson's rule meanwhile: `stand_in`).
    compiling: bool,
    /// Whether the last frame was still: its field's texels and what it composed the same as the frame's
    /// before. The first still frame composes anyway, so that the frame budget measures what an idle frame
    /// costs; the next ones show it again.
    still: bool,
}

/// What a composed viewport frame depends on besides the field's texels.
#[derive(Clone, Debug, PartialEq)]
struct Composed {
    scene: Scene,
    size: [u32; 2],
    show_grid: bool,
    threshold_preview: Option<f64>,
}

impl Composed {
    fn of(view: &ViewportView, size: [u32; 2]) -> Self {
        Composed {
            scene: view.scene.clone(),
            size,
            show_grid: view.show_grid,
            threshold_preview: view.threshold_preview,
        }
    }

    /// Whether a frame of `view` at `size` shows what this one does.
    fn shows(&self, view: &ViewportView, size: [u32; 2]) -> bool {
        self.size == size
            && self.show_grid == view.show_grid
            && self.threshold_preview == view.threshold_preview
            && self.scene == view.scene
    }
}

impl ViewportGpu {
    /// The brightness texture the viewport shows now (after its first frame): the moving field while the view
    /// moves, else the full one.
    pub fn field_texture(&self) -> Option<&wgpu::Texture> {
        match self.showing_preview {
            Some(_) => self.preview.texture(),
            None => self.scene_renderer.field().texture(),
        }
    }

    /// Pipelines for a frame of `target_format` (egui's); `report` is shared with the UI, and `cache` (the
    /// viewer's frame cache, `gpu::frame_cache`) with the app, which simulates its live particles in it.
    pub fn new(
        device: &wgpu::Device,
        target_format: wgpu::TextureFormat,
        report: Arc<Mutex<ViewportReport>>,
        cache: Arc<FrameCache>,
    ) -> Self {
        // The viewer's frames never wait on a compile: a structure compiles on its own thread once the picture
        // is whole (`integrate`), so it takes no core from the frames that move or refine.
        let mut scene_renderer = SceneRenderer::with_cache(device, cache);
        scene_renderer
            .field_mut()
            .set_specialise(Specialise::IfReady);
        // Nor on the objects' or particles' light: the first frame shows the scene at once, with stand-ins
        // until they are ready.
        scene_renderer.prepare_in_background(crate::frame::resolve::WAIT);
        let shaders = scene_renderer.field().shaders();
        Self {
            scene_renderer,
            grid: GridPass::new(device),
            blit: BlitPass::new(device, target_format),
            targets: None,
            report,
            // Generic: a moving field's few texels gain little from a compile of their own; the full field's
            // shaders, so that the first frames compile each generic pipeline once.
            preview: FieldRenderer::with_shaders(device, shaders),
            budget: FrameBudget::default(),
            last_inputs: None,
            showing_preview: None,
            preview_side: 0,
            composed: None,
            still: false,
            compiling: false,
        }
    }

    /// Records one viewport frame into `encoder`: the field pass when the scene changed, the background and
    /// grid, the billboard over them. Keeps its targets for `paint`.
    pub fn record(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewportView,
    ) -> Result<(), GpuError> {
        let device = gpu.device;
        let size = [view.size[0].max(1), view.size[1].max(1)];
        if self.targets.as_ref().is_none_or(|(t, _)| t.size != size) {
            let targets = FrameTargets::new(device, size);
            let bind_group =
                self.blit
                    .bind_group(device, &targets.color_view, &targets.depth_value_view);
            self.targets = Some((targets, bind_group));
            self.composed = None;
        }
        let (targets, bind_group) = self.targets.take().expect("created above");
        let shown = self.composed.take();
        let result = self.record_into(gpu, encoder, view, &targets, view.progressive, shown);
        self.targets = Some((targets, bind_group));
        result
    }

    /// `shown`: what the frame `targets` hold shows, where they hold one (then, if the field's texels and it
    /// stay the same, the frame is left as it is).
    fn record_into(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewportView,
        targets: &FrameTargets,
        progressive: bool,
        shown: Option<Composed>,
    ) -> Result<(), GpuError> {
        let [width, height] = targets.size;
        let aspect = width as f64 / height as f64;
        let setup = self.scene_renderer.setup(&view.scene, aspect);
        let inputs = FieldInputs::of(&setup);
        // While the scene's field pipelines compile on a thread of their own (the adaptive integrator's take
        // half a second and more on a software rasteriser), its frames are drawn by Simpson's rule, whose
        // pipeline compiles in a tenth of that: no frame waits on the compile. Not for screenshots (not
        // `progressive`), nor on GL, where nothing compiles off this thread.
        let main = self.scene_renderer.field();
        self.compiling = progressive
            && view.scene.integration.integrator == Integrator::Adaptive
            && !main.compiled_for(&inputs)
            && main.compile_for_in_background(&inputs);
        let simpson;
        let (setup, inputs) = match self.compiling {
            false => (setup, inputs),
            true => {
                simpson = stand_in(&view.scene);
                let setup = self.scene_renderer.setup(&simpson, aspect);
                let inputs = FieldInputs::of(&setup);
                (setup, inputs)
            }
        };
        let result = self.integrate(gpu, encoder, view, (&setup, inputs), progressive);
        let unchanged = shown.as_ref().is_some_and(|c| c.shows(view, targets.size));
        let still = matches!(&result, Ok(Brightness { fresh: false, .. })) && unchanged;
        let again = still && self.still;
        self.still = still;
        let result = if again {
            if progressive {
                self.budget.frame_shown_again();
            }
            Ok(())
        } else {
            self.compose(gpu, encoder, view, &setup, targets, result)
        };
        let preparing = match (self.compiling, self.scene_renderer.preparing()) {
            (true, Some(what)) => Some(format!("shaders, {what}")),
            (true, None) => Some("shaders".into()),
            (false, what) => what,
        };
        if result.is_ok() {
            // The scene is copied only when what the frame shows changed; a frame with stand-ins is composed
            // again, until what they stand for is ready.
            self.composed = match (unchanged, &preparing) {
                (_, Some(_)) => None,
                (true, None) => shown,
                (false, None) => Some(Composed::of(view, targets.size)),
            };
        }
        if let Ok(mut r) = self.report.lock() {
            r.error = result.as_ref().err().map(|e| e.to_string());
            r.field_renders =
                self.scene_renderer.field().dispatch_count() + self.preview.dispatch_count();
            r.averaged = self.scene_renderer.field().averaged_frames();
            r.refined = r.preview.is_some() && self.showing_preview.is_none();
            r.preview = self.showing_preview.map(|(side, _)| side);
            r.moving_side = self.showing_preview.and_then(|(_, side)| side);
            r.prepared = r.preparing.is_some() && preparing.is_none();
            r.preparing = preparing;
        }
        result
    }

    /// Composes the frame into `targets` over the brightness `integrate` gave: the frame's passes, the grid
    /// among them.
    fn compose(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewportView,
        setup: &FrameSetup,
        targets: &FrameTargets,
        brightness: Result<Brightness, GpuError>,
    ) -> Result<(), GpuError> {
        let vertices = if view.show_grid {
            grid_vertices(&view.scene)
        } else {
            Vec::new()
        };
        self.grid.upload(gpu.device, gpu.queue, vertices);
        self.scene_renderer
            .set_threshold_preview(view.threshold_preview);
        let target = Target {
            targets,
            transparent: false,
        };
        let brightness = brightness?;
        (self.scene_renderer).compose(
            gpu,
            encoder,
            setup,
            target,
            brightness,
            &mut [&mut self.grid],
        )
    }

    /// Records this frame's field work and returns the view of the W x W brightness to show: the full field
    /// when it shows the scene (or, with `progressive` off, always: it is integrated whole now), else what the
    /// frame budget allows (`progressive::FrameBudget::plan`): the whole field refined at a looser tolerance
    /// while the view moves, and levels (or bands) of the full one once it holds still.
    fn integrate(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewportView,
        (setup, inputs): (&FrameSetup, FieldInputs),
        progressive: bool,
    ) -> Result<Brightness, GpuError> {
        let (device, queue) = (gpu.device, gpu.queue);
        let scene = setup.scene;
        let moved = self.last_inputs.as_ref() != Some(&inputs);
        self.last_inputs = Some(inputs.clone());
        let now = Instant::now();
        if progressive {
            self.budget.frame_started(now);
        }
        let w = scene.billboard.resolution;
        let texels = w as u64 * w as u64;
        let main = self.scene_renderer.field_mut();
        main.set_average_frames(view.average_frames);
        let plan = if !progressive || main.shows(&inputs) {
            Plan::Full
        } else if !moved && main.holds(&inputs) {
            // Refining already: the next band, whatever the estimates say now (a whole field's remaining bands
            // in one frame would be the long frame the bands are there to avoid).
            Plan::Refine {
                band_rows: main.band_layout().1,
                bands: 1,
            }
        } else {
            self.budget.plan_paced(view.pacing, moved, w)
        };
        let mut work = Work::Nothing;
        let mut preview = None;
        match plan {
            Plan::Full => {
                main.set_band_rows(0);
                main.prepare(device, queue, &inputs)?;
                if checked(device, || main.encode_timed(encoder, None))? {
                    work = Work::Full { texels };
                }
            }
            Plan::Preview {
                resolution,
                divisor,
            } => {
                // The whole field, refined from a coarse grid within the moving tolerance: the cores where they
                // are and sharp, the objects' silhouettes integrated exactly (`frame::refine`).
                let mut moving = scene.clone();
                let i = &mut moving.integration;
                i.tolerance = i.tolerance.max(PREVIEW_TOLERANCE);
                let side = (w / divisor).max(resolution).min(w);
                let mut at = FrameSetup::in_cache(&moving, setup.billboard, setup.cache());
                at.resolution = side;
                at.refine = Refine::Coarse {
                    threshold: SHARE * MOVING_TOLERANCE,
                    side: resolution,
                };
                self.preview_side = side;
                self.preview.prepare(device, queue, &FieldInputs::of(&at))?;
                checked(device, || self.preview.encode(encoder))?;
                work = Work::Preview {
                    texels: resolution as u64 * resolution as u64,
                };
                preview = Some((resolution, Some(side)));
            }
            Plan::Refine { band_rows, bands } => {
                if !main.holds(&inputs) {
                    main.set_band_rows(band_rows);
                    main.prepare(device, queue, &inputs)?;
                }
                let (_, height) = main.band_layout();
                let complete = checked(device, || main.encode_bands(encoder, bands, None))?;
                work = Work::Full {
                    texels: (bands * height).min(w) as u64 * w as u64,
                };
                // Until the full field is whole, the last moving one (of these same inputs) stays.
                if !complete && self.preview.view().is_some() {
                    preview = Some(self.showing_preview.map_or((w, None), |(r, _)| (r, None)));
                }
            }
        }
        if progressive {
            self.budget.frame_did(now, work);
        }
        let main = self.scene_renderer.field_mut();
        if preview.is_none() && !main.pending() {
            main.compile_in_background();
        }
        // Whether the texels shown changed: work this frame, or another texture shown.
        let fresh = !matches!(work, Work::Nothing) || preview != self.showing_preview;
        self.showing_preview = preview;
        let shown = match preview {
            Some(_) => self.preview.view().map(|v| (v, self.preview_side)),
            None => self.scene_renderer.field().view().map(|v| (v, w)),
        };
        let (view, resolution) = shown.expect("a field was integrated above");
        Ok(Brightness {
            view: view.clone(),
            resolution,
            layers: layers_of(scene),
            fresh,
            undimmed: false,
        })
    }

    /// How long a frame waits for what is prepared on other threads before it draws stand-ins (`WAIT` by
    /// default; a test that checks what a frame shows after an edit waits as long as it takes).
    pub fn set_preparation_wait(&mut self, wait: std::time::Duration) {
        self.scene_renderer.prepare_in_background(wait);
    }

    /// Copies the last recorded frame into egui's render pass (whose viewport egui has set to the callback's
    /// rectangle).
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'static>) {
        if let Some((_, bind_group)) = &self.targets {
            self.blit.draw(pass, bind_group);
        }
    }

    /// Renders the viewport alone at `size` pixels and reads it back (RGBA display values, rows from the top):
    /// screenshots, at any scale, through the same passes as the screen.
    pub fn render_image(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        view: &ViewportView,
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let limit = device.limits().max_texture_dimension_2d;
        if view.size[0] > limit || view.size[1] > limit {
            return Err(GpuError::FrameTooLarge {
                width: view.size[0],
                height: view.size[1],
                limit,
            });
        }
        let targets = FrameTargets::new(device, view.size);
        // A screenshot shows the scene as it is: what is being prepared is waited for (twice at most: a request
        // the frame itself made, then one a change made meanwhile would have), then the frame drawn again. Each
        // try is submitted: the passes count what they recorded as done (the field, its glare), so a try's work
        // must run even when the next try draws the frame again.
        for tries in 0.. {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("energywave.viewport.screenshot"),
            });
            let gpu = Gpu { device, queue };
            let result = self.record_into(gpu, &mut encoder, view, &targets, false, None);
            // The frame composed is the screenshot's, not the one the window's targets hold.
            self.composed = None;
            result?;
            queue.submit([encoder.finish()]);
            if self.scene_renderer.preparing().is_none() || tries == 2 {
                break;
            }
            self.scene_renderer.wait_prepared();
        }
        read_frame(device, queue, &targets)
    }
}

/// `scene` integrated by Simpson's rule at its division count (the papers' 200 by default), the rest as it is:
/// what a frame shows while the adaptive integrator's pipelines compile.
fn stand_in(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.integration.integrator = Integrator::Simpson;
    s.integration.divisions = s.integration.divisions.min(64);
    s.integration.jitter = None;
    s
}

/// The ground grid (the plane y = 0) and the axes, scaled to the scene: ten steps each way, the step a power
/// of ten near a fifth of the effect's size; the x axis red, y green, z blue.
pub fn grid_vertices(scene: &Scene) -> Vec<GridVertex> {
    let extent = scene
        .sources
        .bounds()
        .map_or(1.0, |(lo, hi)| (hi - lo).max_element())
        .max(1e-3);
    let step = 10f64.powf((extent / 5.0).log10().round()) as f32;
    let n = 10;
    let half = step * n as f32;
    let grid = [0.55, 0.55, 0.6, 0.22];
    let mut v = Vec::with_capacity(4 * (2 * n as usize + 1) + 6);
    let mut line = |a: [f32; 3], b: [f32; 3], color: [f32; 4]| {
        v.push(GridVertex { position: a, color });
        v.push(GridVertex { position: b, color });
    };
    for k in -n..=n {
        let t = k as f32 * step;
        if k != 0 {
            line([t, 0.0, -half], [t, 0.0, half], grid);
            line([-half, 0.0, t], [half, 0.0, t], grid);
        }
    }
    line([-half, 0.0, 0.0], [half, 0.0, 0.0], [0.9, 0.25, 0.25, 0.8]);
    line([0.0, 0.0, -half], [0.0, 0.0, half], [0.25, 0.45, 0.95, 0.8]);
    line(
        [0.0, 0.0, 0.0],
        [0.0, step * 2.0, 0.0],
        [0.3, 0.85, 0.3, 0.8],
    );
    v
}

/// The egui paint callback that draws the viewport.
pub struct ViewportCallback(pub ViewportView);

impl egui_wgpu::CallbackTrait for ViewportCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(gpu) = resources.get_mut::<ViewportGpu>() {
            // Errors are reported through the shared report; the frame shows the last good texture.
            let _ = gpu.record(Gpu { device, queue }, encoder, &self.0);
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        if let Some(gpu) = resources.get::<ViewportGpu>() {
            gpu.paint(pass);
        }
    }
}
