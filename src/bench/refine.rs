//! The field refined in image space (`frame::refine`) against the field integrated at every texel: the whole
//! field of shipped scenes at W = 256, 512 and 1024 (256 and 1024 with `--quick`), both on the field pass
//! specialised to the scene's structure (the fastest the project has), interleaved frame by frame, with the
//! share of texels the refined field integrated (read back from the GPU after the timed frames).

use serde::Serialize;

use super::timing::{FieldBench, Pass};
use super::{BenchOptions, PassTiming, load};
use crate::gpu::{GpuError, Specialise};

/// One scene at one W.
#[derive(Clone, Debug, Serialize)]
pub struct RefineRow {
    pub scene: String,
    pub resolution: u32,
    /// Every texel integrated (the field pass before the refinement).
    pub every_texel: PassTiming,
    /// Refined at the scene's tolerance.
    pub refined: PassTiming,
    /// Texels the refined field integrated, and their share of W^2.
    pub integrated: u64,
    pub share: f64,
}

/// The scenes: the default (a chain, a torus, a line), every kind of source, objects, and the papers' chains.
const SCENES: [(&str, &str); 4] = [
    ("default", include_str!("../../assets/scenes/default.toml")),
    ("mixed", include_str!("../../assets/scenes/mixed.toml")),
    ("floor", include_str!("../../assets/scenes/floor.toml")),
    (
        "bezier",
        include_str!("../../assets/scenes/bezier_b5.0.toml"),
    ),
];

pub(super) fn refine_rows(
    bench: &mut FieldBench,
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<RefineRow>, GpuError> {
    let sizes: &[u32] = if options.quick {
        &[256, 1024]
    } else {
        &[256, 512, 1024]
    };
    let mut rows = Vec::new();
    for &w in sizes {
        for (name, text) in SCENES {
            let mut scene = load(text, name);
            scene.billboard.resolution = w;
            progress(&format!("refined field: {name}, {w} x {w}"));
            // At 1024 the field integrated at every texel takes seconds a frame on a CPU rasterizer: fewer frames.
            let (warmup, frames) = match w {
                1024.. => (1, options.frames().min(3)),
                _ => (options.warmup(), options.frames()),
            };
            const PASSES: [Pass; 2] = [Pass::Field(Specialise::Blocking), Pass::Refined];
            let t = bench.interleaved_as(2, warmup, frames, |k| PASSES[k], |_, _| scene.clone())?;
            let mut t = t.into_iter();
            let (every_texel, refined) = (t.next().expect("two"), t.next().expect("two"));
            // The last frame timed was the refined one: its count.
            let (device, queue) = (&bench.ctx.device, &bench.ctx.queue);
            let integrated =
                (bench.field.integrated_texels(device, queue)?).unwrap_or(w as u64 * w as u64);
            rows.push(RefineRow {
                scene: name.to_owned(),
                resolution: w,
                every_texel,
                refined,
                integrated,
                share: integrated as f64 / (w as f64 * w as f64),
            });
        }
    }
    Ok(rows)
}
