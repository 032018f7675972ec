//! The `energywave` command line: `view` (the default) and `render`.
//!
//! Exit status: 0 on success, 2 when the input is at fault (a bad scene, flag value or output path), 1 for
//! anything else. Every input is checked before any rendering starts.

mod assemble;
mod farm;
mod interrupt;
mod render;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use crate::export::{ExportError, FrameSpec};
use crate::field::WForm;
use crate::gpu::GpuError;
use crate::integrate::{Decay, Integrator};
use crate::output::{self, OutputError};
use crate::scene::{MAX_RESOLUTION, Scene, SceneError, limits};
use crate::viewer::offscreen::OffscreenViewer;
use crate::viewer::{Document, ViewOptions, ViewerError};

/// Design and render energy-wave effects (Watanabe, Abe and Konno 2016).
#[derive(Debug, Parser)]
#[command(name = "energywave", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the interactive viewer on a scene (the embedded default scene without one).
    View(ViewArgs),
    /// Render the scene's camera view to an image file.
    Render(RenderArgs),
    /// Join a rendered PNG sequence (a farm's chunks) into the GIF, sprite sheet or video one `render` makes.
    Assemble(AssembleArgs),
    /// Write the effect as a shader a game engine runs: GLSL 4.50 and ES 3.00, HLSL and MSL, with its uniforms.
    Shader(ShaderArgs),
    /// Render a sequence on a render farm: write (and submit) its jobs.
    #[command(subcommand)]
    Farm(FarmCommand),
    /// Time the field pass on the papers' grid, deformation, and whole viewer frames.
    Bench(BenchArgs),
}

#[derive(Debug, clap::Args)]
pub struct AssembleArgs {
    /// Scene file (TOML) the frames were rendered from (its frame count and rate); the embedded default scene
    /// without one.
    pub scene: Option<PathBuf>,
    /// The rendered frames: a PNG sequence, its run of # the frame number (`frames/beam_####.png`).
    #[arg(short, long)]
    pub input: PathBuf,
    /// The joined file: a .gif, a video (.mp4, .webm), or with `--sheet` a sprite sheet .png (its layout beside
    /// it as .json).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Which frames (as `render --frames`); every frame of the scene's animation by default. Missing ones are
    /// named, and nothing is written.
    #[arg(long, value_parser = FrameSpec::parse)]
    pub frames: Option<FrameSpec>,
    /// The frames' color is premultiplied by their alpha (they were rendered with `--premultiplied`).
    #[arg(long)]
    pub premultiplied: bool,
    /// Join the frames into a sprite sheet (as `render --sheet`).
    #[arg(long)]
    pub sheet: bool,
    #[command(flatten)]
    pub layout: SheetLayoutArgs,
    /// Print what is joined and where it went.
    #[arg(short, long)]
    pub verbose: bool,
}

#[derive(Debug, clap::Args)]
pub struct ShaderArgs {
    /// Scene file (TOML); the embedded default scene without one.
    pub scene: Option<PathBuf>,
    /// The folder the shader's files go into (made if needed).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The files' name stem: NAME.vert, NAME.glow.frag, NAME.hlsl, NAME.uniforms.json...
    #[arg(long, default_value = "effect")]
    pub name: String,
    /// The frame the uniforms' view is set for (the scene's camera in a WIDTHxHEIGHT picture).
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    pub size: (u32, u32),
}

#[derive(Debug, Subcommand)]
pub enum FarmCommand {
    /// Write Slurm job scripts for a sequence: a job array of chunks of frames and an assembly job after it;
    /// `--submit` queues them with sbatch.
    Slurm(SlurmArgs),
}

#[derive(Debug, clap::Args)]
pub struct SlurmArgs {
    /// Scene file (TOML), on a file system every machine of the farm sees.
    pub scene: PathBuf,
    /// The frames: a PNG or EXR sequence, a run of # the frame number (`renders/beam_####.png`), on a shared
    /// file system.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Which frames of the scene's animation (as `render --frames`); all of them by default.
    #[arg(long, value_parser = FrameSpec::parse)]
    pub frames: Option<FrameSpec>,
    /// Frames per chunk: per array task.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub chunk_size: u32,
    /// Join the frames, once every chunk is done, into this .gif, .mp4, .webm, or sprite sheet .png.
    #[arg(long)]
    pub assemble: Option<PathBuf>,
    /// The folder the job's scripts and logs go into (default: `NAME.slurm` beside the frames, NAME the scene's
    /// file name without its extension).
    #[arg(long)]
    pub job_dir: Option<PathBuf>,
    /// One more `#SBATCH` option for both jobs, as `--sbatch=--partition=gpu` (repeat it: `--gres=gpu:1`,
    /// `--time=2:00:00`, `--account=fx`).
    #[arg(long, allow_hyphen_values = true)]
    pub sbatch: Vec<String>,
    /// Tries of a chunk that fails with status 1 (a crash, a lost device) before its task fails; status 2 (bad
    /// input) is never tried again.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub tries: u32,
    /// At most this many chunks at once.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_parallel: Option<u32>,
    /// The energywave executable the machines run (default: this one).
    #[arg(long)]
    pub executable: Option<PathBuf>,
    /// Queue the jobs with sbatch (else only write them; `submit.sh` queues them).
    #[arg(long)]
    pub submit: bool,
    /// More flags for every chunk's `render`, after `--` (`-- --size 1920x1080 --transparent`).
    #[arg(last = true)]
    pub render_args: Vec<String>,
}

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Fewer frames, 512 x 512 left out: under two minutes on a 2-core machine with a software GPU.
    #[arg(long)]
    pub quick: bool,
    /// Also write every figure, with its unit, the adapter and the settings, as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Run only these sections (comma-separated or repeated); all of them by default.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub only: Vec<crate::bench::Section>,
    /// The equal-error comparison's billboard resolutions (comma-separated), instead of 256 and 512. A real GPU
    /// is filled only by larger textures; the f64 reference costs the same at every size (a 256 x 256 subset).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(16..=16384))]
    pub equal_error_sizes: Vec<u32>,
    /// The scene the viewer's frames are timed on, instead of the embedded default scene.
    #[arg(long)]
    pub viewer_scene: Option<PathBuf>,
}

#[derive(Debug, Default, clap::Args)]
pub struct ViewArgs {
    /// Scene file (TOML).
    pub scene: Option<PathBuf>,
    /// Draw `--frames` frames, save the whole window (panel included) to this PNG, and exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// How many frames to draw before `--screenshot`.
    #[arg(long, default_value_t = 3, requires = "screenshot")]
    pub frames: u32,
}

#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML); the embedded default scene without one.
    pub scene: Option<PathBuf>,
    /// Output: an image, .png (8-bit) or .exr (32-bit float), by extension; for an animation also a sequence
    /// (name_####.png), a .gif, a --sheet, or a video, .mp4 (H.264) or .webm (VP9), through ffmpeg.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Which renderer integrates the field: `gpu` (WGSL compute, f32) or `cpu` (the f64 reference, on every
    /// core).
    #[arg(long, value_enum, default_value_t = Backend::Gpu)]
    pub backend: Backend,
    /// Export the glow over a transparent background, alpha = min(B, 1), for compositing: a PNG with straight
    /// color (or premultiplied with `--premultiplied`), an EXR associated (premultiplied, the OpenEXR convention)
    /// and unclamped. Composited "over" a background in display values (not scene-linear) it is the viewer's blend
    /// wherever B <= 1.
    #[arg(long, conflicts_with = "brightness")]
    pub transparent: bool,
    /// With `--transparent`, write a PNG's color premultiplied by its alpha, for engines' premultiplied blend
    /// modes (Unity URP "Premultiply", Godot `BLEND_MODE_PREMULT_ALPHA`). An EXR is associated either way.
    #[arg(long, requires = "transparent")]
    pub premultiplied: bool,
    /// With `--transparent`, leave the scene's objects out of the picture while they still hide the glow: the
    /// glow alone, alpha 0 and no glow wherever an object hides it, for layering over a render of the same scene
    /// (and camera) made elsewhere.
    #[arg(long, requires = "transparent")]
    pub holdout: bool,
    /// Frame the effect: set the camera's field of view (eye and target kept) so that the whole glow, down to
    /// its edge (`colors.cutoff`), lies inside every frame exported with a small margin. For sprite sheets
    /// and sequences whose cells must end in alpha 0 all round; the scene needs a cutoff above 0.
    #[arg(long)]
    pub fit: bool,
    /// Write the billboard's brightness B itself (W x W, before the blend, unclamped, rows from the top) as a
    /// float EXR (R = G = B = brightness) instead of the composed frame.
    #[arg(long)]
    pub brightness: bool,
    /// Fix the billboard's resolution W (texels per side). Without it, and unless the scene fixes W
    /// (`[billboard] resolution`), W follows the frame's pixel density: one texel per two pixels of the
    /// billboard's side in the frame (at least the scene's W, at most 4096 and the GPU's limit), so a thin core stays
    /// smooth at 1920x1080 as at 512x512.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_RESOLUTION as i64))]
    pub resolution: Option<u32>,
    /// Override the scene's Simpson division count n (even).
    #[arg(long, value_parser = parse_divisions)]
    pub divisions: Option<u32>,
    /// Override the scene's integrator: `adaptive` (samples where the field needs them; the default) or
    /// `simpson` (the papers' n evenly spaced samples).
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<Integrator>,
    /// Override the adaptive integrator's tolerance: the error allowed on B, shared between the sources (default 1e-4).
    #[arg(long, value_parser = parse_tolerance)]
    pub tolerance: Option<f64>,
    /// Override the scene's decay: `distance` (the papers': each source's energy along the view summed) or `rms`
    /// (its root mean square along the view: an even spread of moderate energy does not outshine a single intense
    /// spot).
    #[arg(long, value_parser = parse_decay)]
    pub decay: Option<Decay>,
    /// Override every curve's W form: `continuous` (its W series read at the chain's brightest point: no seam) or
    /// `nearest` (the papers': at the nearest point).
    #[arg(long, value_parser = parse_w_form)]
    pub w_form: Option<WForm>,
    /// Jitter the simpson integrator's samples with this seed: each texel's samples are shifted by a random
    /// fraction of a step, so a low n gives fine noise instead of bands.
    #[arg(long, value_name = "SEED")]
    pub jitter: Option<u32>,
    /// Integrate the field at every texel (the reference), rather than refined in image space: predicted from
    /// coarser texels where the detail stays within an eighth of the tolerance, integrated elsewhere. Slower,
    /// and within half the tolerance of the refined render.
    #[arg(long)]
    pub every_texel: bool,
    /// Print the adapter, what is rendered and how long it took.
    #[arg(short, long)]
    pub verbose: bool,
    /// Frames of the scene's animation: `A..B` (A to B-1, so `0..50` and `50..100` split an export between
    /// two machines), `A..=B` or `A-B` (A to B, as render farm managers write a chunk), `A..`, `..B`, or one
    /// frame `A`. Default: every frame for a sequence (an
    /// output such as `dir/name_####.png`), a `.gif` or `--sheet`; frame 0 for a single image.
    #[arg(long, value_parser = FrameSpec::parse)]
    pub frames: Option<FrameSpec>,
    /// Write the frames as one sprite sheet (a flipbook grid, row-major from the top-left) to the `.png`
    /// output, with its layout as JSON beside it (same name, `.json`).
    #[arg(long, conflicts_with = "brightness")]
    pub sheet: bool,
    #[command(flatten)]
    pub layout: SheetLayoutArgs,
}

/// A sprite sheet's layout, for `render --sheet` and `assemble --sheet` alike.
#[derive(Debug, Default, clap::Args)]
pub struct SheetLayoutArgs {
    /// Columns of the sprite sheet (default: as square as it gets).
    #[arg(long, requires = "sheet")]
    pub columns: Option<u32>,
    /// Transparent pixels between the sheet's cells, so that mipmaps do not bleed one frame into the next.
    #[arg(long, default_value_t = 0, requires = "sheet")]
    pub padding: u32,
    /// Round the sheet's width and height up to powers of two (for engines and GPUs that want them).
    #[arg(long, requires = "sheet")]
    pub power_of_two: bool,
}

impl SheetLayoutArgs {
    /// The layout, where `sheet` asks for a sheet.
    pub fn options(&self, sheet: bool) -> Option<crate::export::SheetOptions> {
        sheet.then_some(crate::export::SheetOptions {
            columns: self.columns,
            padding: self.padding,
            power_of_two: self.power_of_two,
        })
    }
}

/// The renderer behind `render`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// The GPU: any adapter wgpu finds (a real GPU first, else Mesa's lavapipe, else Mesa's GL).
    Gpu,
    /// The f64 CPU reference.
    Cpu,
}

/// A failure of a command, with its exit status.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("{0}")]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Viewer(#[from] ViewerError),
    #[error("{0}")]
    Usage(String),
    #[error("{0}")]
    Unavailable(String),
    #[error("{0}")]
    Export(#[from] ExportError),
}

impl CliError {
    /// 2 when the input is at fault, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Scene(SceneError::Read { .. }) => 2,
            CliError::Scene(_) | CliError::Usage(_) => 2,
            CliError::Output(e) if e.is_input_error() => 2,
            CliError::Gpu(e) if e.is_input_error() => 2,
            CliError::Viewer(ViewerError::Output(e)) if e.is_input_error() => 2,
            CliError::Export(e) if e.is_input_error() => 2,
            CliError::Export(_) => 1,
            CliError::Output(_)
            | CliError::Gpu(_)
            | CliError::Viewer(_)
            | CliError::Unavailable(_) => 1,
        }
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let err = || {
        format!(
            "{s:?} is not a frame size: use WIDTHxHEIGHT with each between 1 and {MAX_RESOLUTION}, for example 1280x720"
        )
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let w: u32 = w.trim().parse().map_err(|_| err())?;
    let h: u32 = h.trim().parse().map_err(|_| err())?;
    if !(1..=MAX_RESOLUTION).contains(&w) || !(1..=MAX_RESOLUTION).contains(&h) {
        return Err(err());
    }
    Ok((w, h))
}

fn parse_divisions(s: &str) -> Result<u32, String> {
    let n = s.parse::<u32>().map_err(|_| {
        format!(
            "{s:?}: {}",
            limits::divisions(0).expect_err("0 is not a count")
        )
    })?;
    limits::divisions(n).map_err(|rule| format!("{s:?}: {rule}"))
}

fn parse_integrator(s: &str) -> Result<Integrator, String> {
    match s {
        "adaptive" => Ok(Integrator::Adaptive),
        "simpson" => Ok(Integrator::Simpson),
        _ => Err(format!(
            "{s:?} is not an integrator: use adaptive (the default) or simpson (the papers' evenly spaced samples)"
        )),
    }
}

fn parse_decay(s: &str) -> Result<Decay, String> {
    Decay::ALL.into_iter().find(|d| d.name() == s).ok_or_else(|| {
        format!("{s:?} is not a decay: use distance (the papers', the default) or rms (a spot is not outshone by an even spread)")
    })
}

fn parse_w_form(s: &str) -> Result<WForm, String> {
    WForm::ALL.into_iter().find(|f| f.name() == s).ok_or_else(|| {
        format!("{s:?} is not a W form: use continuous (the chain's brightest point, the default) or nearest (the papers')")
    })
}

fn parse_tolerance(s: &str) -> Result<f64, String> {
    let t = s.parse::<f64>().unwrap_or(f64::NAN);
    limits::tolerance(t).map_err(|rule| format!("{s:?}: {rule}"))
}

/// Parses the arguments, runs the command, prints any error and returns the exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("energywave: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        None => view(&ViewArgs::default()),
        Some(Command::View(args)) => view(&args),
        Some(Command::Render(args)) => render::render(&args),
        Some(Command::Assemble(args)) => assemble::assemble(&args),
        Some(Command::Shader(args)) => shader(&args),
        Some(Command::Farm(FarmCommand::Slurm(args))) => farm::slurm(&args),
        Some(Command::Bench(args)) => bench(&args),
    }
}

/// `shader`: the effect for game engines (`crate::engine`).
fn shader(args: &ShaderArgs) -> Result<(), CliError> {
    let scene = load_scene(args.scene.as_deref())?;
    let name = &args.name;
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return Err(CliError::Usage(format!(
            "--name {name:?}: letters, digits, - and _ only (it names the files)"
        )));
    }
    let (w, h) = args.size;
    let input = |e: crate::engine::EngineError| match e.is_input_error() {
        true if matches!(e, crate::engine::EngineError::Folder { .. }) => {
            CliError::Usage(format!("--output {e}"))
        }
        true => CliError::Usage(format!(
            "{}: {e}",
            args.scene
                .as_ref()
                .map_or("the default scene".into(), |p| p.display().to_string())
        )),
        false => CliError::Unavailable(e.to_string()),
    };
    let effect = crate::engine::EffectShader::of(&scene, w as f64 / h as f64).map_err(input)?;
    let (written, warning) = effect.write(&args.output, name).map_err(input)?;
    if let Some(w) = warning {
        eprintln!("warning: {w}");
    }
    for path in &written {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// Loads the scene file, or the embedded default scene.
pub fn load_scene(path: Option<&Path>) -> Result<Scene, SceneError> {
    match path {
        Some(p) => Scene::load(p),
        None => Ok(Scene::default_scene()),
    }
}

fn view(args: &ViewArgs) -> Result<(), CliError> {
    // The scene and the screenshot path are checked first, so bad input is reported the same way with or
    // without a display.
    let scene = load_scene(args.scene.as_deref())?;
    if let Some(path) = &args.screenshot {
        output::check_destination(path)?;
    }
    let has_display = std::env::var_os("DISPLAY").is_some_and(|v| !v.is_empty())
        || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|v| !v.is_empty());
    if !has_display {
        let scene_arg = args
            .scene
            .as_ref()
            .map_or(String::new(), |p| format!(" {}", p.display()));
        return Err(CliError::Unavailable(format!(
            "no display found (neither DISPLAY nor WAYLAND_DISPLAY is set), so the viewer cannot open a window.\n\
             Render the scene to an image instead:\n  energywave render{scene_arg} --output frame.png"
        )));
    }
    let doc = Document::new(scene, args.scene.clone());
    let options = ViewOptions {
        screenshot: args.screenshot.clone(),
        frames: args.frames,
    };
    crate::viewer::run(doc, options)?;
    Ok(())
}

fn bench(args: &BenchArgs) -> Result<(), CliError> {
    if let Some(path) = &args.json {
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        if !dir.is_dir() || path.is_dir() {
            return Err(CliError::Usage(format!(
                "{}: cannot write the JSON report there (the directory does not exist, or it is a directory)",
                path.display()
            )));
        }
    }
    let viewer_scene = match &args.viewer_scene {
        Some(path) => Some((Scene::load(path)?, path.display().to_string())),
        None => None,
    };
    let (scene, label) = viewer_scene.unwrap_or_else(|| (Scene::default_scene(), "default".into()));
    let report = crate::bench::run(
        crate::bench::BenchOptions {
            quick: args.quick,
            sections: crate::bench::Sections::only(&args.only),
            equal_error_sizes: (!args.equal_error_sizes.is_empty())
                .then(|| args.equal_error_sizes.clone()),
            viewer_scene: label,
        },
        &mut || bench_viewer_on(scene.clone()),
        |p| eprintln!("{p}"),
    )?;
    print!("{}", report.table());
    if let Some(path) = &args.json {
        output::write_atomically(path, report.to_json().as_bytes())?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The viewer the bench times: the real one, drawn offscreen at the bench's size, on the default scene.
pub fn bench_viewer() -> Result<Box<dyn crate::bench::TimedViewer>, crate::gpu::GpuError> {
    bench_viewer_on(Scene::default_scene())
}

/// `bench_viewer` on `scene`.
pub fn bench_viewer_on(
    scene: Scene,
) -> Result<Box<dyn crate::bench::TimedViewer>, crate::gpu::GpuError> {
    let [w, h] = crate::bench::VIEWER_SIZE;
    let doc = Document::new(scene, None);
    Ok(Box::new(OffscreenViewer::new(doc, w, h)?))
}

impl crate::bench::TimedViewer for OffscreenViewer {
    fn frame(&mut self) -> Result<(), crate::gpu::GpuError> {
        OffscreenViewer::frame(self).map(|_| ())
    }

    fn wants_frame(&self) -> bool {
        !self.app.report().settled()
    }

    fn preview(&self) -> Option<u32> {
        // The moving field's own side (the budget may make it smaller than W), not its coarse start's.
        let report = self.app.report();
        report.preview.and(report.moving_side)
    }

    fn scene_mut(&mut self) -> &mut Scene {
        self.app.scene_mut()
    }

    fn step_animation(&mut self) -> Option<f64> {
        self.app.step_animation()
    }

    fn orbit(&mut self, yaw: f64) {
        crate::viewer::navigation::orbit(&mut self.app.scene_mut().camera, yaw, 0.0);
    }

    fn set_progressive(&mut self, on: bool) {
        self.app.view_mut().progressive = on;
    }

    fn viewport(&self) -> Result<Vec<u8>, crate::gpu::GpuError> {
        self.viewport_pixels()
    }
}
