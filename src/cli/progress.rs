//! Progress bars on stderr, hidden when stderr is not a terminal or with `--quiet`: the
//! library's [`shadelab::Progress`] drawn with indicatif.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// The bar of a stage counted in steps: indicatif's own estimate from the steps' rate.
const STEPS: &str = "{msg} [{bar:30}] {pos}/{len} ({eta})";

/// The bar of a stage whose work estimates its time left ([`shadelab::Progress::time_left`]):
/// the bar is the time, elapsed against elapsed plus left.
const TIMED: &str = "{msg} [{bar:30}] {prefix}";

/// Tenths of a second per unit of a timed bar's length.
const TIMED_UNITS_PER_SECOND: f64 = 10.0;

/// A progress bar of `total` steps labelled `what`; invisible when quiet or not a terminal.
pub fn bar(total: u64, what: &str, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new(total);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    } else {
        set_style(&bar, STEPS);
    }
    bar.set_message(what.to_string());
    bar
}

/// Draws `bar` with `template`.
fn set_style(bar: &ProgressBar, template: &str) {
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
}

/// `seconds` as a person reads a wait: "about 40 s left", "about 3 min 20 s left".
fn time_left_text(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0 => "finishing".to_string(),
        1..=59 => format!("about {s} s left"),
        _ => format!("about {} min {:02} s left", s / 60, s % 60),
    }
}

/// The library's progress reports drawn as one bar on stderr (hidden when quiet or not a
/// terminal), and its notes as lines above it (none when quiet).
pub struct Bar {
    bar: ProgressBar,
    quiet: bool,
}

impl Bar {
    /// A bar, hidden with `quiet`.
    pub fn new(quiet: bool) -> Bar {
        Bar {
            bar: bar(0, "", quiet),
            quiet,
        }
    }
}

impl shadelab::Progress for Bar {
    fn start(&self, total: u64, what: &str) {
        self.bar.reset();
        if !self.bar.is_hidden() {
            set_style(&self.bar, STEPS);
        }
        self.bar.set_length(total);
        self.bar.set_message(what.to_string());
    }
    fn advance(&self, steps: u64) {
        self.bar.inc(steps);
    }
    fn set_position(&self, done: u64) {
        self.bar.set_position(done);
    }
    fn time_left(&self, seconds: f64) {
        if !self.bar.is_hidden() {
            set_style(&self.bar, TIMED);
        }
        let elapsed = self.bar.elapsed().as_secs_f64();
        let units = |s: f64| (s * TIMED_UNITS_PER_SECOND).round() as u64;
        self.bar
            .set_length(units(elapsed + seconds.max(0.0)).max(1));
        self.bar.set_position(units(elapsed));
        self.bar.set_prefix(time_left_text(seconds));
    }
    fn message(&self, text: &str) {
        self.bar.set_message(text.to_string());
    }
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
    fn note(&self, line: &shadelab::Message) {
        if !self.quiet {
            // Above the bar, which is drawn again below it.
            let text = super::flags::worded(line);
            self.bar.suspend(|| super::output::stderr_line(&text));
        }
    }
}
