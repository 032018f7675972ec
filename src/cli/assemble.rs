//! The `assemble` command: a rendered PNG sequence (the chunks of a farm) joined into the GIF, sprite sheet or
//! video that one `render` of the same frames makes, byte for byte.

use super::{AssembleArgs, CliError, load_scene};
use crate::export::assemble::{self, Frames};
use crate::export::{self, Progress, Target};

pub(super) fn assemble(args: &AssembleArgs) -> Result<(), CliError> {
    super::interrupt::watch();
    let target = Target::for_output(&args.output, args.layout.options(args.sheet))?;
    let scene = load_scene(args.scene.as_deref())?;
    let range = export::frames_to_render(args.frames.as_ref(), &target, scene.frame_count())?;
    let frame_rate = scene
        .animation
        .as_ref()
        .map_or(crate::animation::DEFAULT_FRAME_RATE, |a| a.frame_rate);
    let frames = Frames {
        pattern: args.input.clone(),
        range: range.clone(),
        premultiplied: args.premultiplied,
    };
    // A sheet too large for image tools is refused before any frame is read; one past what mobile GPUs load
    // is said.
    if let Target::Sheet { path, options } = &target {
        let found = frames.check()?;
        let layout = export::sheet_grid(
            path,
            found.width,
            found.height,
            range.clone(),
            options,
            frame_rate,
        )?;
        if let Some(warning) = export::sheet::mobile_warning(&layout) {
            eprintln!("warning: {}: {warning}", path.display());
        }
    }
    let mut progress = Progress::new(range.len() as u32);
    let written = assemble::assemble(&frames, &target, frame_rate, |_, frame| {
        progress.frame_done(frame);
        match super::interrupt::asked() {
            true => std::ops::ControlFlow::Break(()),
            false => std::ops::ControlFlow::Continue(()),
        }
    })?;
    if args.verbose {
        eprintln!(
            "joined frames {}..={} of {}",
            range.start,
            range.end - 1,
            args.input.display()
        );
        for path in &written {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}
