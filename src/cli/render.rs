//! The `render` command: a still, a sequence, a GIF, a video or a sprite sheet of the scene's camera view, on
//! the renderer `--backend` chooses.

use std::time::Instant;

use super::{Backend, CliError, RenderArgs, load_scene};
use crate::export::{self, Progress, Target};
use std::sync::Arc;

use crate::frame::{FrameCache, FrameSetup, Refine};
use crate::gpu::HeadlessRenderer;
use crate::integrate::Integrator;
use crate::output::{self, Format};
use crate::reference;
use crate::scene::{DEFAULT_SCENE_NAME, Scene};

/// Refuses, before any rendering, a billboard resolution or a frame size this device cannot hold, naming
/// where the value came from.
fn check_device_limits(
    gpu: &HeadlessRenderer,
    args: &RenderArgs,
    scene: &Scene,
    name: &str,
) -> Result<(), CliError> {
    let limit = gpu.ctx.device.limits().max_texture_dimension_2d;
    let adapter = gpu.ctx.adapter_summary();
    let w = scene.billboard.resolution;
    if w > limit {
        let origin = match args.resolution {
            Some(_) => format!("--resolution {w}"),
            None => format!("{name}: [billboard] resolution = {w}"),
        };
        return Err(CliError::Usage(format!(
            "{origin} exceeds the texture limit of this GPU ({adapter}): at most {limit} texels per side"
        )));
    }
    let (width, height) = args.size;
    if (!args.brightness) && (width > limit || height > limit) {
        return Err(CliError::Usage(format!(
            "--size {width}x{height} exceeds the texture limit of this GPU ({adapter}): at most {limit} pixels per side"
        )));
    }
    Ok(())
}

pub(super) fn render(args: &RenderArgs) -> Result<(), CliError> {
    super::interrupt::watch();
    let target = Target::for_output(&args.output, args.layout.options(args.sheet))?;
    let alpha = output::Alpha::of(args.transparent, args.premultiplied);
    let format = match &target {
        Target::Single { format, .. } | Target::Sequence { format, .. } => *format,
        Target::Gif { .. } | Target::Sheet { .. } | Target::Video { .. } => Format::Png,
    };
    if let Target::Video { container, .. } = &target {
        if args.transparent && *container == export::video::Container::Mp4 {
            return Err(CliError::Usage(format!(
                "{}: H.264 in MP4 has no alpha, so it cannot carry alpha = min(B, 1); write a .webm (VP9 \
                 with alpha) or a PNG sequence (name_####.png) with --transparent instead",
                args.output.display()
            )));
        }
        if args.premultiplied {
            return Err(CliError::Usage(format!(
                "{}: --premultiplied is for PNG; a video's alpha is straight",
                args.output.display()
            )));
        }
    }
    if args.transparent && matches!(target, Target::Gif { .. }) {
        return Err(CliError::Usage(format!(
            "{}: a GIF has no partial transparency, so it cannot carry alpha = min(B, 1); export a PNG \
             sequence (name_####.png) or a --sheet with --transparent instead",
            args.output.display()
        )));
    }
    if args.brightness && matches!(target, Target::Gif { .. } | Target::Video { .. }) {
        return Err(CliError::Usage(format!(
            "{}: --brightness writes floating-point EXR; give an .exr output (name_####.exr for frames)",
            args.output.display()
        )));
    }
    if args.brightness && format != Format::Exr {
        return Err(CliError::Usage(format!(
            "{}: --brightness writes unclamped floating-point values; give an .exr output",
            args.output.display()
        )));
    }
    let mut scene = load_scene(args.scene.as_deref())?;
    if let Some(w) = args.resolution {
        scene.billboard.resolution = w;
    }
    if let Some(n) = args.divisions {
        scene.integration.divisions = n;
    }
    if let Some(integrator) = args.integrator {
        scene.integration.integrator = integrator;
    }
    if let Some(t) = args.tolerance {
        scene.integration.tolerance = t;
    }
    if let Some(decay) = args.decay {
        scene.integration.decay = decay;
    }
    if let Some(form) = args.w_form {
        scene
            .sources
            .curves
            .iter_mut()
            .for_each(|c| c.w_form = form);
    }
    if let Some(seed) = args.jitter {
        if scene.integration.integrator != Integrator::Simpson {
            return Err(CliError::Usage(format!(
                "--jitter {seed}: jitter shifts the simpson integrator's evenly spaced samples; add --integrator simpson (the adaptive integrator does not band)"
            )));
        }
        scene.integration.jitter = Some(seed);
    }
    let frames = export::frames_to_render(args.frames.as_ref(), &target, scene.frame_count())?;
    if args.fit {
        scene.camera.fov_y_degrees =
            // Over the whole animation, whichever frames this command renders: the chunks of an export split
            // between machines frame the effect alike.
            export::fit::fit_field_of_view(&scene, 0..scene.frame_count(), args.size).map_err(|e| {
                let name = args
                    .scene
                    .as_ref()
                    .map_or(DEFAULT_SCENE_NAME.to_owned(), |p| p.display().to_string());
                CliError::Usage(format!("{name}: --fit: {e}"))
            })?;
    }
    if target.is_multi_frame() {
        return render_frames(args, &scene, &target, frames);
    }
    if frames.len() != 1 {
        return Err(CliError::Usage(format!(
            "{}: --frames asks for {} frames, but the output is one image: name it with a run of # for a \
             sequence (name_####.png), use .gif, or add --sheet",
            args.output.display(),
            frames.len()
        )));
    }
    let (width, height) = args.size;
    let hdr = target.is_exr();
    let mut renderer = Renderer::new(args, hdr)?;
    follow_pixel_density(&mut scene, args, &renderer);
    let scene = renderer.cache().scene_at(&scene, frames.start as f64);
    specialise(&mut renderer, &scene);
    let setup = renderer.setup(&scene, (width, height));
    let billboard = setup.billboard;
    let name = args
        .scene
        .as_ref()
        .map_or(DEFAULT_SCENE_NAME.to_owned(), |p| p.display().to_string());
    if args.verbose {
        eprintln!(
            "{name}: {} sources; billboard {}x{} texels, center {:.4}, side {:.4}; integrator {} (n = {}, tolerance {:e}), decay length {:.4} (rays span {:.3} of it); backend {:?}",
            scene.sources.len(),
            scene.billboard.resolution,
            scene.billboard.resolution,
            billboard.center,
            billboard.size,
            scene.integration.integrator.name(),
            scene.integration.divisions,
            scene.integration.tolerance,
            scene.integration.decay_length,
            setup.reach.stretch,
            args.backend,
        );
    }
    if let Renderer::Gpu(gpu) = &renderer {
        if args.verbose {
            eprintln!("adapter: {}", gpu.ctx.adapter_summary());
        }
        check_device_limits(gpu, args, &scene, &name)?;
    }
    let start = Instant::now();
    // A signal during the render (a scheduler stopping the job): nothing written.
    let stopped = || match super::interrupt::asked() {
        true => Err(CliError::Export(export::ExportError::Cancelled)),
        false => Ok(()),
    };
    if args.brightness {
        let values = renderer.brightness(&setup)?;
        stopped()?;
        output::write_brightness_exr(&args.output, scene.billboard.resolution, &values)?;
    } else {
        let pixels = renderer.compose(&scene, (width, height), backdrop(args), hdr)?;
        stopped()?;
        output::write_rgba(&args.output, width, height, &pixels, alpha)?;
    }
    if args.verbose {
        eprintln!(
            "{} and readback: {:.1} ms",
            renderer.name(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }
    if args.verbose {
        eprintln!("wrote {}", args.output.display());
    }
    Ok(())
}

/// Unless `--resolution` or the scene fixes W, the billboard takes the texels the frame's size needs
/// (`Scene::resolution_for`, within the device's limit) at the animation's first frame, whichever frames are
/// rendered: frame N has the same W in a whole export and in any chunk of it. A B-only EXR (`--brightness`,
/// W x W whatever the size) keeps the scene's.
fn follow_pixel_density(scene: &mut Scene, args: &RenderArgs, renderer: &Renderer) {
    if args.resolution.is_some() || args.brightness {
        return;
    }
    scene.billboard.resolution =
        (renderer.cache().scene_at(scene, 0.0)).resolution_for(args.size, renderer.texture_limit());
}

/// An animation of more than a few frames gets the GPU's pipelines specialised to its structure (they pay for
/// their compile after a few frames), decided by the animation's length, not by how many frames this command
/// renders: the specialised and the generic pass differ in their last bits, and frame N must come out the same
/// in a whole export and in any chunk of it, down to the byte.
fn specialise(renderer: &mut Renderer, scene: &Scene) {
    if let Renderer::Gpu(gpu) = renderer
        && scene.frame_count() > 4
    {
        gpu.set_specialise(crate::gpu::Specialise::Blocking);
    }
}

/// Where the command's pictures are made, chosen once from `--backend`: the GPU, set up for the command's
/// holdout and HDR, or the CPU twin.
enum Renderer {
    Gpu(Box<HeadlessRenderer>),
    /// The CPU twin, with its frame cache and, where not the scene's, which texels it integrates.
    Cpu(Arc<FrameCache>, Option<Refine>),
}

impl Renderer {
    /// The renderer `--backend` names; `hdr` (an EXR) keeps the opaque blend's values above 1.
    fn new(args: &RenderArgs, hdr: bool) -> Result<Renderer, CliError> {
        let refine = args.every_texel.then_some(Refine::EveryTexel);
        Ok(match args.backend {
            Backend::Gpu => {
                let mut gpu = HeadlessRenderer::new()?;
                gpu.set_holdout(args.holdout);
                gpu.set_unclamped(hdr);
                gpu.set_refine(refine);
                Renderer::Gpu(Box::new(gpu))
            }
            Backend::Cpu => Renderer::Cpu(Arc::new(FrameCache::new()), refine),
        })
    }

    /// What its timings are called.
    fn name(&self) -> &'static str {
        match self {
            Renderer::Gpu(_) => "gpu render",
            Renderer::Cpu(..) => "cpu render",
        }
    }

    /// The largest texture side it makes: the device's limit, or what the CPU twin allows W.
    fn texture_limit(&self) -> u32 {
        match self {
            Renderer::Gpu(gpu) => gpu.ctx.device.limits().max_texture_dimension_2d,
            Renderer::Cpu(..) => crate::scene::MAX_AUTO_RESOLUTION,
        }
    }

    /// The cache its frames are resolved through.
    fn cache(&self) -> &Arc<FrameCache> {
        match self {
            Renderer::Gpu(gpu) => gpu.cache(),
            Renderer::Cpu(cache, _) => cache,
        }
    }

    /// The frame of `scene` in a picture of `size`, resolved through its cache.
    fn setup<'a>(&self, scene: &'a Scene, (width, height): (u32, u32)) -> FrameSetup<'a> {
        match self {
            Renderer::Gpu(gpu) => gpu.setup(scene, width as f64 / height as f64),
            Renderer::Cpu(cache, refine) => {
                let mut setup = FrameSetup::placed_in(scene, width as f64 / height as f64, cache);
                if let Some(refine) = refine {
                    setup.refine = *refine;
                }
                setup
            }
        }
    }

    /// B over the frame's W x W texels, rows from the top, before the blend.
    fn brightness(&mut self, setup: &FrameSetup) -> Result<Vec<f64>, CliError> {
        Ok(match self {
            Renderer::Gpu(gpu) => (gpu.brightness(setup)?.iter()).map(|&b| b as f64).collect(),
            Renderer::Cpu(..) => reference::render_brightness(setup).values,
        })
    }

    /// The composed frame of `scene` (RGBA display values, rows from the top); with `hdr` (an EXR) the opaque
    /// blend is not clamped above 1 (the GPU was set up for it).
    fn compose(
        &mut self,
        scene: &Scene,
        (width, height): (u32, u32),
        backdrop: reference::Backdrop,
        hdr: bool,
    ) -> Result<Vec<[f64; 4]>, CliError> {
        let transparent = backdrop != reference::Backdrop::Opaque;
        Ok(match self {
            Renderer::Gpu(gpu) => {
                let frame = gpu.render(scene, width, height, transparent)?;
                frame.pixels.iter().map(|p| p.map(|c| c as f64)).collect()
            }
            Renderer::Cpu(..) => {
                let setup = self.setup(scene, (width, height));
                let texture = reference::render_brightness(&setup);
                let compose = match hdr {
                    true => reference::compose_frame_unclamped,
                    false => reference::compose_frame_over,
                };
                compose(&setup, &texture, (width, height), backdrop)
            }
        })
    }
}

/// Renders `frames` of the scene's animation into a sequence, a GIF or a sprite sheet, one renderer for all of
/// them, with a progress bar on stderr.
fn render_frames(
    args: &RenderArgs,
    scene: &Scene,
    target: &Target,
    frames: std::ops::Range<u32>,
) -> Result<(), CliError> {
    let (width, height) = args.size;
    let hdr = target.is_exr();
    let frame_rate = scene
        .animation
        .as_ref()
        .map_or(crate::animation::DEFAULT_FRAME_RATE, |a| a.frame_rate);
    // A sheet too large for image tools is refused before the GPU starts; one past what mobile GPUs load is
    // said.
    if let Target::Sheet { path, options } = target {
        let layout = export::sheet_grid(path, width, height, frames.clone(), options, frame_rate)?;
        if let Some(warning) = export::sheet::mobile_warning(&layout) {
            eprintln!("warning: {}: {warning}", path.display());
        }
    }
    let mut renderer = Renderer::new(args, hdr)?;
    let mut scene = scene.clone();
    follow_pixel_density(&mut scene, args, &renderer);
    let scene = &scene;
    specialise(&mut renderer, scene);
    if args.verbose {
        if let Renderer::Gpu(gpu) = &renderer {
            eprintln!("adapter: {}", gpu.ctx.adapter_summary());
        }
        eprintln!(
            "frames {}..{} of {} at {frame_rate} frames/s, {width}x{height}, billboard {}x{}, n = {}",
            frames.start,
            frames.end,
            scene.frame_count(),
            scene.billboard.resolution,
            scene.billboard.resolution,
            scene.integration.divisions,
        );
    }
    let start = Instant::now();
    let mut progress = Progress::new(frames.len() as u32);
    let written = if args.brightness {
        // Only an .exr sequence gets here (checked above): B of each frame, before the blend.
        let Target::Sequence { pattern, .. } = target else {
            return Err(CliError::Usage(format!(
                "{}: --brightness writes one EXR per frame: name it name_####.exr",
                args.output.display()
            )));
        };
        // Staged as every other sequence: the frames are written beside the destination and moved in once all
        // are whole, so a failure or a signal on the way leaves an earlier sequence of the same names as it was.
        let mut staged =
            export::staged::Staged::beside(&export::frame_path(pattern, frames.start))?;
        for frame in frames.clone() {
            let at = renderer.cache().scene_at(scene, frame as f64);
            let values = renderer.brightness(&renderer.setup(&at, (width, height)))?;
            let path = staged.stage(&export::frame_path(pattern, frame));
            output::write_brightness_exr(&path, at.billboard.resolution, &values)?;
            progress.frame_done(frame);
            if super::interrupt::asked() {
                return Err(export::ExportError::Cancelled.into());
            }
        }
        staged.commit()?
    } else {
        export::export_frames(
            scene,
            target,
            frames.clone(),
            (width, height),
            output::Alpha::of(args.transparent, args.premultiplied),
            |frame| {
                let at = renderer.cache().scene_at(scene, frame as f64);
                renderer.compose(&at, (width, height), backdrop(args), hdr)
            },
            |_, frame| {
                progress.frame_done(frame);
                match super::interrupt::asked() {
                    true => std::ops::ControlFlow::Break(()),
                    false => std::ops::ControlFlow::Continue(()),
                }
            },
        )?
    };
    if args.verbose {
        let seconds = start.elapsed().as_secs_f64();
        eprintln!(
            "{} frames in {seconds:.2} s ({:.1} ms per frame)",
            frames.len(),
            seconds * 1e3 / frames.len().max(1) as f64
        );
        for path in written.iter().take(3) {
            eprintln!("wrote {}", path.display());
        }
        if written.len() > 3 {
            eprintln!("... and {} more", written.len() - 3);
        }
    }
    Ok(())
}

/// What lies behind the glow in the command's pictures.
fn backdrop(args: &RenderArgs) -> reference::Backdrop {
    match (args.transparent, args.holdout) {
        (false, _) => reference::Backdrop::Opaque,
        (true, false) => reference::Backdrop::Transparent,
        (true, true) => reference::Backdrop::Holdout,
    }
}
