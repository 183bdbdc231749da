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
/// terminal).
pub struct Bar(ProgressBar);

impl Bar {
    /// A bar, hidden with `quiet`.
    pub fn new(quiet: bool) -> Bar {
        Bar(bar(0, "", quiet))
    }
}

impl shadelab::Progress for Bar {
    fn start(&self, total: u64, what: &str) {
        self.0.reset();
        if !self.0.is_hidden() {
            set_style(&self.0, STEPS);
        }
        self.0.set_length(total);
        self.0.set_message(what.to_string());
    }
    fn advance(&self, steps: u64) {
        self.0.inc(steps);
    }
    fn set_position(&self, done: u64) {
        self.0.set_position(done);
    }
    fn time_left(&self, seconds: f64) {
        if !self.0.is_hidden() {
            set_style(&self.0, TIMED);
        }
        let elapsed = self.0.elapsed().as_secs_f64();
        let units = |s: f64| (s * TIMED_UNITS_PER_SECOND).round() as u64;
        self.0.set_length(units(elapsed + seconds.max(0.0)).max(1));
        self.0.set_position(units(elapsed));
        self.0.set_prefix(time_left_text(seconds));
    }
    fn message(&self, text: &str) {
        self.0.set_message(text.to_string());
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
