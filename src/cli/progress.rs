//! Progress on standard error: spinners for opaque steps, bars for counted steps, and the
//! notes and warnings of a run (repairs, estimated errors), all through one place so that a
//! note never tears a bar apart.
//!
//! `--progress auto` (the default) draws indicatif spinners and bars when standard error is a
//! terminal and nothing otherwise, so pipes, files and CI logs stay clean. `--progress always`
//! does the same on a terminal and writes one plain line per finished step elsewhere (for a
//! log: `wfem … 2> log`); `--progress never` draws nothing. Notes and warnings are printed in
//! every mode.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// When progress is shown (`wfem --progress …`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProgressMode {
    /// Bars on a terminal, nothing otherwise.
    #[default]
    Auto,
    /// Bars on a terminal, one line per finished step otherwise.
    Always,
    /// No progress (notes and warnings are still printed).
    Never,
}

/// How this process draws: indicatif on a terminal, plain lines, or nothing.
enum Sink {
    Bars(MultiProgress),
    Lines,
    Hidden,
}

static SINK: OnceLock<Sink> = OnceLock::new();

/// Sets the mode for the whole run (first call wins; later calls are ignored).
pub fn set_mode(mode: ProgressMode) {
    let _ = SINK.set(sink_for(mode));
}

fn sink_for(mode: ProgressMode) -> Sink {
    let terminal = std::io::stderr().is_terminal();
    match (mode, terminal) {
        (ProgressMode::Never, _) => Sink::Hidden,
        (_, true) => Sink::Bars(MultiProgress::with_draw_target(ProgressDrawTarget::stderr())),
        (ProgressMode::Always, false) => Sink::Lines,
        (ProgressMode::Auto, false) => Sink::Hidden,
    }
}

fn sink() -> &'static Sink {
    SINK.get_or_init(|| sink_for(ProgressMode::Auto))
}

/// Steps shorter than this leave no line behind on a terminal.
const PERSIST_AFTER: Duration = Duration::from_secs(1);

fn seconds(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 10.0 {
        format!("{s:.2} s")
    } else if s < 120.0 {
        format!("{s:.1} s")
    } else {
        format!("{}m{:02}s", d.as_secs() / 60, d.as_secs() % 60)
    }
}

/// Writes one line on standard error. Unlike `eprintln!`, a closed standard error (e.g.
/// `wfem … 2>&- `, or a pipe whose reader quit) is ignored instead of panicking.
pub fn stderr_line(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// Prints a line on standard error (`wfem: …`), above any bar being drawn.
pub fn note(text: &str) {
    let line = format!("wfem: {text}");
    match sink() {
        Sink::Bars(multi) => multi.suspend(|| stderr_line(&line)),
        Sink::Lines | Sink::Hidden => stderr_line(&line),
    }
}

/// Prints a warning on standard error (`wfem: warning: …`), above any bar being drawn.
pub fn warn(text: &str) {
    note(&format!("warning: {text}"));
}

/// One step of a run: a spinner with the elapsed time while it lasts (for a library call that
/// is one opaque step), or a bar over `len` units (per t, per shape).
pub struct Step {
    bar: Option<ProgressBar>,
    label: String,
    start: Instant,
    finished: bool,
}

/// Starts a spinner for an opaque step, e.g. `step("factorizing (B + γtL)")`.
pub fn step(label: impl Into<String>) -> Step {
    start(
        label.into(),
        ProgressBar::new_spinner,
        "{spinner} {msg} [{elapsed_precise}]",
    )
}

/// Starts a bar over `len` units, e.g. `bar(3, "K_t f")` for three diffusion times.
pub fn bar(len: usize, label: impl Into<String>) -> Step {
    start(
        label.into(),
        || ProgressBar::new(len as u64),
        "{msg} [{bar:30}] {pos}/{len} [{elapsed_precise}, eta {eta}]",
    )
}

/// A step drawn (on a terminal) by the indicatif bar `new` with `template`.
fn start(label: String, new: impl FnOnce() -> ProgressBar, template: &str) -> Step {
    let bar = match sink() {
        Sink::Bars(multi) => {
            let bar = multi.add(new());
            let style = ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style.progress_chars("=> "));
            bar.set_message(label.clone());
            bar.enable_steady_tick(Duration::from_millis(120));
            Some(bar)
        }
        Sink::Lines | Sink::Hidden => None,
    };
    Step {
        bar,
        label,
        start: Instant::now(),
        finished: false,
    }
}

impl Step {
    /// Shows what the current unit of a bar is (e.g. `t = 0.01`).
    pub fn set_detail(&self, detail: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{}: {detail}", self.label));
        }
    }

    /// Counts one unit of a bar as done; in `--progress always` mode off a terminal, writes
    /// `detail` as its own line.
    pub fn inc(&self, detail: &str) {
        match &self.bar {
            Some(bar) => bar.inc(1),
            None => {
                if matches!(sink(), Sink::Lines) {
                    stderr_line(&format!(
                        "wfem: {}: {detail} [{}]",
                        self.label,
                        seconds(self.start.elapsed())
                    ));
                }
            }
        }
    }

    /// Counts `k` units of a bar as done at once (one line for them off a terminal).
    pub fn inc_by(&self, k: usize, detail: &str) {
        match &self.bar {
            Some(bar) => bar.inc(k as u64),
            None if k > 0 => self.inc(detail),
            None => {}
        }
    }

    /// Ends the step: the spinner disappears (leaving `label (time)` when it took a while),
    /// or one line `label … done` is written in `--progress always` mode off a terminal.
    pub fn done(mut self) {
        self.finish();
    }

    fn finish(&mut self) {
        if self.finished {
            return;
        }
        self.finished = true;
        let elapsed = self.start.elapsed();
        match (&self.bar, sink()) {
            (Some(bar), Sink::Bars(multi)) => {
                bar.finish_and_clear();
                multi.remove(bar);
                if elapsed >= PERSIST_AFTER {
                    let _ = multi.println(format!("  {} ({})", self.label, seconds(elapsed)));
                }
            }
            (_, Sink::Lines) => stderr_line(&format!("wfem: {} … done ({})", self.label, seconds(elapsed))),
            _ => {}
        }
    }
}

impl Drop for Step {
    /// A step abandoned by an error disappears without a "done" line.
    fn drop(&mut self) {
        if !self.finished {
            if let Some(bar) = &self.bar {
                bar.finish_and_clear();
                if let Sink::Bars(multi) = sink() {
                    multi.remove(bar);
                }
            }
        }
    }
}

/// Runs `work` as one opaque step with a spinner.
pub fn run<T, E>(label: impl Into<String>, work: impl FnOnce() -> Result<T, E>) -> Result<T, E> {
    let s = step(label);
    let out = work()?;
    s.done();
    Ok(out)
}
