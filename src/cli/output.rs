//! Where every command prints: results on stdout (a short table, or with `--json` the typed
//! report as one JSON document), chatter and progress on stderr (silenced by `--quiet`, which
//! never hides results), warnings on stderr always. A closed stdout (`| head -c1`) ends the
//! output quietly; any other write error (a full disk, `> /dev/full`) is a one-line error.

use super::{CliError, CliResult, Global};
use serde::Serialize;
use std::io::Write;

/// The printer of one command.
#[derive(Debug, Clone, Copy)]
pub struct Output {
    /// No chatter on stderr.
    pub quiet: bool,
    /// Results as JSON.
    pub json: bool,
}

impl Output {
    /// The printer the global flags ask for.
    pub fn new(global: &Global) -> Output {
        Output {
            quiet: global.quiet,
            json: global.json,
        }
    }

    /// A line of chatter ("wrote X", what was read): stderr, unless quiet.
    pub fn note(&self, line: impl std::fmt::Display) {
        if !self.quiet {
            stderr_line(&line.to_string());
        }
    }

    /// The chatter line that ends a command which wrote `target`: "wrote TARGET (S s)".
    pub fn wrote(&self, target: &std::path::Path, seconds: f64) {
        self.note(format!("wrote {} ({seconds:.2} s)", target.display()));
    }

    /// A warning: stderr, even when quiet.
    pub fn warn(&self, line: impl std::fmt::Display) {
        stderr_line(&format!("warning: {line}"));
    }

    /// The results: `text` on stdout, or `report` as one JSON document with `--json`.
    pub fn results(&self, text: &str, report: &impl Serialize) -> CliResult {
        if self.json {
            let json = serde_json::to_string_pretty(report).map_err(|e| {
                CliError::from(shadelab::Error::Compute(format!(
                    "cannot serialise the report: {e}"
                )))
            })?;
            print_stdout(&(json + "\n"))
        } else if text.is_empty() || text.ends_with('\n') {
            print_stdout(text)
        } else {
            print_stdout(&format!("{text}\n"))
        }
    }
}

/// Prints `text` on stdout; a closed pipe (`| head`) ends the output quietly, any other error
/// (a full disk) is an error naming standard output.
pub fn print_stdout(text: &str) -> CliResult {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(CliError::from(shadelab::Error::io("standard output", e)))
        }
        _ => Ok(()),
    }
}

/// Writes a line on stderr; a closed stderr is ignored (never a panic).
pub fn stderr_line(line: &str) {
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "{line}");
}
