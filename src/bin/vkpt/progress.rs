//! The progress display of a render: an indicatif bar on a terminal (spp
//! done, samples/s, time left), a plain line at each quarter elsewhere (logs
//! of batch jobs), nothing with --quiet.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal as _;
use std::sync::Mutex;
use std::time::Instant;

pub struct RenderProgress {
    bar: Option<ProgressBar>,
    /// Samples per spp: the pixel count; 0 when not known (no spp shown).
    pixels: u64,
    /// An open-ended render (time limit or target error) shows no fraction.
    open_ended: bool,
    /// When tracing began: the render reports 0 samples done once its
    /// kernels are compiled and the scene is uploaded, so that samples/s
    /// and the time left are the tracing's (until then, construction time).
    start: Mutex<Instant>,
    /// Without a terminal: the last quarter printed.
    quarter: Mutex<u64>,
    enabled: bool,
}

impl RenderProgress {
    pub fn new(pixels: u64, open_ended: bool, enabled: bool) -> Self {
        let tty = std::io::stderr().is_terminal();
        let bar = (enabled && tty).then(|| {
            let template = if open_ended {
                "{spinner} {elapsed_precise} {msg}"
            } else {
                "{wide_bar} {percent:>3}% {msg}, {eta} left"
            };
            let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr_with_hz(8));
            bar.set_style(
                ProgressStyle::with_template(template)
                    .expect("the template is valid")
                    .progress_chars("=> "),
            );
            bar
        });
        RenderProgress {
            bar,
            pixels,
            open_ended,
            start: Mutex::new(Instant::now()),
            quarter: Mutex::new(0),
            enabled,
        }
    }

    /// The render's progress callback: samples done out of the total (0:
    /// tracing starts now).
    pub fn update(&self, done: u64, total: u64) {
        if done == 0 {
            *self.start.lock().expect("progress lock") = Instant::now();
            return;
        }
        if !self.enabled || total == 0 {
            return;
        }
        let elapsed = self
            .start
            .lock()
            .expect("progress lock")
            .elapsed()
            .as_secs_f64();
        let rate = done as f64 / elapsed.max(1e-9);
        let msg = match self.pixels {
            0 => format!("{}samples/s", si(rate)),
            p if self.open_ended => format!("{} spp, {}samples/s", done / p, si(rate)),
            p => format!("{}/{} spp, {}samples/s", done / p, total / p, si(rate)),
        };
        if let Some(bar) = &self.bar {
            bar.set_length(total);
            bar.set_position(done);
            bar.set_message(msg);
            return;
        }
        if self.open_ended {
            return;
        }
        let quarter = done * 4 / total;
        let mut last = self.quarter.lock().expect("progress lock");
        if quarter > *last {
            *last = quarter;
            let left = elapsed * (total - done) as f64 / done.max(1) as f64;
            eprintln!(
                "{:3.0}% {msg}, {elapsed:.1} s elapsed, {left:.1} s left",
                100.0 * done as f64 / total as f64
            );
        }
    }

    /// Prints a line above the bar (a checkpoint, a note).
    pub fn println(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.println(line),
            None => eprintln!("{line}"),
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// 1.23 M, 456.00 k, ...: a rate with an SI prefix and a trailing space.
pub fn si(x: f64) -> String {
    match x {
        x if x >= 1e9 => format!("{:.2} G", x / 1e9),
        x if x >= 1e6 => format!("{:.2} M", x / 1e6),
        x if x >= 1e3 => format!("{:.2} k", x / 1e3),
        x => format!("{x:.0} "),
    }
}
