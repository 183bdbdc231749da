//! Progress bars on stderr, hidden when stderr is not a terminal or with `--quiet`: the
//! library's [`shadelab::Progress`] drawn with indicatif.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar of `total` steps labelled `what`; invisible when quiet or not a terminal.
pub fn bar(total: u64, what: &str, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new(total);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    } else if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({eta})") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
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
        self.0.set_length(total);
        self.0.set_message(what.to_string());
    }
    fn advance(&self, steps: u64) {
        self.0.inc(steps);
    }
    fn set_position(&self, done: u64) {
        self.0.set_position(done);
    }
    fn message(&self, text: &str) {
        self.0.set_message(text.to_string());
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
