//! The command line's errors: a subcommand's error with its exit status, and how a library
//! error becomes one line of text with the flag that remedies it.

use super::flags;

/// An error from a subcommand, with whether it is a usage error (exit 2).
#[derive(Debug)]
pub struct CliError {
    pub(super) error: anyhow::Error,
    pub(super) usage: bool,
}

impl<E: Into<anyhow::Error>> From<E> for CliError {
    fn from(e: E) -> Self {
        let error: anyhow::Error = e.into();
        let usage = error.chain().any(|c| {
            c.downcast_ref::<shadelab::Error>()
                .is_some_and(|e| e.is_usage())
        });
        CliError { error, usage }
    }
}

impl CliError {
    /// A usage error (exit 2) from a message.
    pub fn usage(message: impl Into<String>) -> Self {
        CliError {
            error: anyhow::anyhow!(message.into()),
            usage: true,
        }
    }
}

/// The result of a subcommand.
pub type CliResult = Result<(), CliError>;

/// The exit status of a run stopped by a signal (128 + SIGINT, as shells report it).
pub(super) const INTERRUPTED: u8 = 130;

/// Whether the library stopped on request.
pub(super) fn cancelled(error: &anyhow::Error) -> bool {
    error.chain().any(|c| {
        matches!(
            c.downcast_ref::<shadelab::Error>(),
            Some(shadelab::Error::Cancelled)
        )
    })
}

/// What the command line adds to a library error that a flag can remedy.
pub(super) fn hint(error: &anyhow::Error) -> &'static str {
    match error
        .chain()
        .find_map(|c| c.downcast_ref::<shadelab::Error>())
    {
        Some(shadelab::Error::NotOurs { path, .. }) if path.is_dir() => {
            "; use --force to write into it (every file shadelab did not write stays)"
        }
        Some(shadelab::Error::NotOurs { .. }) => "; use --force to replace it",
        Some(shadelab::Error::TooLarge(_)) => " (--max-pixels)",
        _ => "",
    }
}

/// The error and its causes on one line, each cause once: library errors already name their
/// cause (`file: No such file or directory`), so a cause whose text is shown is not repeated.
pub(super) fn one_line(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        // A message that names settings names them by their flags.
        let part = match cause.downcast_ref::<shadelab::Error>() {
            Some(shadelab::Error::Setting(message)) => flags::worded(message),
            _ => cause.to_string(),
        };
        if !text.contains(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
    }
    text.replace('\n', " ")
}
