//! SIGINT, SIGTERM and SIGHUP during an export: a scheduler stopping a chunk (a time limit, a cancel, a
//! pre-emption sends SIGTERM, then SIGKILL some seconds later) or Ctrl-C. The export stops after the frame it is
//! on and removes what it wrote, so a stopped chunk leaves no file behind, and exits with status 1 (try again);
//! a second signal ends the process at once.

use std::sync::atomic::{AtomicBool, Ordering};

static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the handler (once; a second call is a no-op).
pub fn watch() {
    let _ = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\nenergywave: stopping after this frame; nothing of this export is kept");
    });
}

/// Whether a signal asked the export to stop.
pub fn asked() -> bool {
    STOP.load(Ordering::SeqCst)
}
