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
    #[error("unknown {kind} '{name}'{hint} (valid: {valid})")]
    Unknown {
        /// What kind of thing was named ("stimulus", "parameter", …).
        kind: &'static str,
        /// The name given.
        name: String,
        /// The nearest valid name as words (`; did you mean 'kappas'?`), or empty.
        hint: String,
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
    /// A failure whose remedy is a setting the message names ([`crate::message::Message`]): each front
    /// end names the setting its own way (a flag, a keyword).
    #[error("{0}")]
    Setting(crate::message::Message),
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

    /// An [`Error::Unknown`] listing the valid names and naming the nearest ([`nearest_name`]).
    ///
    /// ```
    /// let e = shadelab::Error::unknown("parameter", "prior_kappa", &["prior_tilt", "kappas", "noise"]);
    /// assert_eq!(
    ///     e.to_string(),
    ///     "unknown parameter 'prior_kappa'; did you mean 'kappas'? (valid: prior_tilt, kappas, noise)"
    /// );
    /// ```
    pub fn unknown<S: AsRef<str>>(kind: &'static str, name: &str, valid: &[S]) -> Self {
        let hint = nearest_name(name, valid)
            .map(|n| format!("; did you mean '{n}'?"))
            .unwrap_or_default();
        Error::Unknown {
            kind,
            name: name.to_string(),
            hint,
            valid: valid
                .iter()
                .map(|s| s.as_ref())
                .collect::<Vec<_>>()
                .join(", "),
        }
    }

    /// Whether the error is a usage error (a bad argument rather than a failure while working):
    /// the command line exits with 2 for these and 1 for the rest. A [`Error::Setting`] is one
    /// where its remedy is to give what the picture lacks (its resolution, its target labels),
    /// not to tune a computation (a smaller λ).
    pub fn is_usage(&self) -> bool {
        use crate::message::Setting;
        match self {
            Error::Invalid(_) | Error::Unknown { .. } | Error::TooLarge(_) => true,
            Error::Setting(m) => m
                .settings()
                .any(|s| matches!(s, Setting::Ppd | Setting::Mask)),
            _ => false,
        }
    }
}

/// The valid name nearest `name`, if one is near enough to be a slip: the fewest edits
/// (insert, delete or change a letter, ignoring case and `-` against `_`) from `name`, or
/// from one of its `_`/`-`-separated words of three letters or more (`prior_kappa` →
/// `kappas`: a word of it is one letter short), at most a third of the valid name's length
/// (and at least one). Ties go to the first in `valid`.
///
/// ```
/// use shadelab::nearest_name;
/// assert_eq!(nearest_name("prior_kappa", &["prior_tilt", "kappas"]), Some("kappas"));
/// assert_eq!(nearest_name("rotaton", &["rotation", "size"]), Some("rotation"));
/// assert_eq!(nearest_name("teapot", &["sphere", "crater"]), None);
/// ```
pub fn nearest_name<'a, S: AsRef<str>>(name: &str, valid: &'a [S]) -> Option<&'a str> {
    let plain = |s: &str| s.to_lowercase().replace('-', "_");
    let name = plain(name);
    let words: Vec<&str> = std::iter::once(name.as_str())
        .chain(name.split('_').filter(|w| w.len() >= 3))
        .collect();
    valid
        .iter()
        .map(AsRef::as_ref)
        .filter_map(|v| {
            let candidate = plain(v);
            let d = words.iter().map(|w| edit_distance(w, &candidate)).min()?;
            (d <= (candidate.chars().count() / 3).max(1)).then_some((d, v))
        })
        .min_by_key(|&(d, _)| d)
        .map(|(_, v)| v)
}

/// Levenshtein distance between `a` and `b`, in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `bytes` in words: `1 byte`, `512 bytes`, `64 MiB`, `1.5 GiB`.
pub fn byte_size(bytes: u64) -> String {
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
