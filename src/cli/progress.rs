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
        self.bar.set_length(total);
        self.bar.set_message(what.to_string());
    }
    fn advance(&self, steps: u64) {
        self.bar.inc(steps);
    }
    fn set_position(&self, done: u64) {
        self.bar.set_position(done);
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
