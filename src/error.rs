//! The library's error type: every failure a user can cause is one of these, with its context.

use std::path::{Path, PathBuf};

/// Everything that can go wrong in shadelab, each variant carrying enough context for a
/// one-line message (`error: <file>: <problem>`).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A value given by the user is out of range or malformed (exit code 2 on the command line).
    #[error("{0}")]
    Invalid(String),
    /// A name (shape, stimulus, parameter, model, …) that shadelab does not know.
    #[error("unknown {kind} '{name}' (valid: {valid})")]
    Unknown {
        /// What kind of thing was named ("stimulus", "parameter", …).
        kind: &'static str,
        /// The name given.
        name: String,
        /// The valid names, comma separated.
        valid: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is not what was expected (corrupt, wrong shape, NaN, …).
    #[error("{}: {message}", path.display())]
    Format {
        /// The file involved.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A computation could not be carried out on valid input (e.g. an empty domain).
    #[error("{0}")]
    Compute(String),
    /// A failure whose remedy is a setting the message names ([`crate::Message`]): each front
    /// end names the setting its own way (a flag, a keyword).
    #[error("{0}")]
    Setting(crate::Message),
    /// An output would replace a file or folder that shadelab did not write (a front end may
    /// say how to allow it).
    #[error("{}: {message}", path.display())]
    NotOurs {
        /// The file or folder.
        path: PathBuf,
        /// Why it is taken for someone else's.
        message: String,
    },
    /// An image larger than the pixel limit in force (a front end may say how to raise it).
    #[error("{0}")]
    TooLarge(String),
    /// The run was stopped on request ([`crate::cancel::request`], e.g. Ctrl-C) before its
    /// outputs were committed: nothing new was written.
    #[error("interrupted")]
    Cancelled,
    /// Another run is writing the same output (its lock file is held).
    #[error("{}: {message}", path.display())]
    Locked {
        /// The output.
        path: PathBuf,
        /// Who holds it and what to do.
        message: String,
    },
}

impl Error {
    /// An [`Error::Invalid`] from anything printable.
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::Invalid(message.into())
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// An [`Error::Format`] for `path`.
    pub fn format(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Format {
            path: path.as_ref().to_path_buf(),
            message: message.into(),
        }
    }

    /// An [`Error::Unknown`] listing the valid names.
    pub fn unknown<S: AsRef<str>>(kind: &'static str, name: &str, valid: &[S]) -> Self {
        Error::Unknown {
            kind,
            name: name.to_string(),
            valid: valid
                .iter()
                .map(|s| s.as_ref())
                .collect::<Vec<_>>()
                .join(", "),
        }
    }

    /// Whether the error is a usage error (a bad argument rather than a failure while working):
    /// the command line exits with 2 for these and 1 for the rest.
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            Error::Invalid(_) | Error::Unknown { .. } | Error::TooLarge(_)
        )
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `bytes` in words: `1 byte`, `512 bytes`, `64 MiB`, `1.5 GiB`.
pub(crate) fn byte_size(bytes: u64) -> String {
    const UNITS: [(&str, u64); 3] = [("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    match UNITS.iter().find(|(_, size)| bytes >= *size) {
        Some((unit, size)) => {
            let value = bytes as f64 / *size as f64;
            format!("{} {unit}", (value * 10.0).round() / 10.0)
        }
        None if bytes == 1 => "1 byte".to_string(),
        None => format!("{bytes} bytes"),
    }
}
