//! A progress bar for multi-frame exports on stderr: one line redrawn with `\r` on a terminal; on anything
//! else (a log, a pipe, a CI job) a plain line now and then, so that logs stay readable.

use std::io::{IsTerminal, Write};
use std::time::Instant;

/// Counts finished frames and reports them on stderr.
pub struct Progress {
    total: u32,
    done: u32,
    start: Instant,
    terminal: bool,
    /// Last tenth reported on a non-terminal.
    last_tenth: u32,
}

impl Progress {
    /// A bar for `total` frames; silent when there is only one.
    pub fn new(total: u32) -> Self {
        Self {
            total,
            done: 0,
            start: Instant::now(),
            terminal: std::io::stderr().is_terminal(),
            last_tenth: 0,
        }
    }

    /// One more frame is done (`frame` is its number in the animation).
    pub fn frame_done(&mut self, frame: u32) {
        self.done += 1;
        if self.total <= 1 {
            return;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        let per_frame = elapsed / self.done as f64;
        let left = per_frame * (self.total - self.done) as f64;
        let line = render_line(self.done, self.total, frame, per_frame, left);
        let mut err = std::io::stderr().lock();
        if self.terminal {
            // Erase to the end of the line: the previous line may have been longer.
            let _ = write!(err, "\r{line}\x1b[K");
            if self.done == self.total {
                let _ = writeln!(err);
            }
            let _ = err.flush();
        } else {
            let tenth = self.done * 10 / self.total;
            if tenth > self.last_tenth || self.done == self.total || self.total <= 10 {
                self.last_tenth = tenth;
                let _ = writeln!(err, "{line}");
            }
        }
    }
}

/// `[#########...........]  45/100 frames (frame 44)  0.31 s/frame, 17 s left`
pub fn render_line(done: u32, total: u32, frame: u32, per_frame: f64, left: f64) -> String {
    const WIDTH: u32 = 24;
    let filled = (done as u64 * WIDTH as u64 / total.max(1) as u64) as usize;
    let bar: String = "#".repeat(filled) + &".".repeat(WIDTH as usize - filled);
    let digits = total.to_string().len();
    format!(
        "[{bar}] {done:>digits$}/{total} frames (frame {frame})  {per_frame:.2} s/frame, {left:.0} s left"
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_bar_fills_in_proportion() {
        let l = super::render_line(6, 24, 5, 0.5, 9.0);
        assert!(l.starts_with("[######..................]"), "{l}");
        assert!(l.contains(" 6/24 frames (frame 5)"), "{l}");
        let l = super::render_line(24, 24, 23, 0.5, 0.0);
        assert!(l.starts_with(&format!("[{}]", "#".repeat(24))), "{l}");
    }
}
