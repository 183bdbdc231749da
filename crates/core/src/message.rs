//! Messages that name a command's settings, so that each front end says them its own way: the
//! command line its flag (`--mask`), Python its keyword, the library plain words ("the given
//! mask"). The library never writes a flag's name, and no front end edits the library's text.
//!
//! ```
//! use shadelab::{Message, Setting};
//! let m = Message::text("use ")
//!     .setting(Setting::Lambda, "a smaller λ")
//!     .then(" to stop the divergence");
//! assert_eq!(m.to_string(), "use a smaller λ to stop the divergence");
//! let cli = m.render(|s, words| match s {
//!     Setting::Lambda => format!("{words} (--lambda)"),
//!     _ => words.to_string(),
//! });
//! assert_eq!(cli, "use a smaller λ (--lambda) to stop the divergence");
//! ```

use std::fmt;

/// A setting of a command that a message may name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Setting {
    /// The mask file (where the surface is solved for).
    Mask,
    /// The picture's resolution, pixels per degree.
    Ppd,
    /// The encoding the picture's values are decoded with.
    InputGamma,
    /// The response keys of a key-press experiment (bump, dimple).
    Keys,
    /// The smoothness weight λ.
    Lambda,
    /// The solver method (here: the Jacobi sweeps).
    JacobiMethod,
    /// Whether a fit takes simulated rows (a pilot's) too.
    IncludeSimulated,
    /// Whether a fit pools data of different designs (`design_hash`).
    MixedDesigns,
}

/// One piece of a [`Message`].
#[derive(Debug, Clone, PartialEq)]
enum Part {
    Text(String),
    Setting(Setting, String),
}

/// A line of text in which some words name a [`Setting`]; `Display` gives the library's words.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Message {
    parts: Vec<Part>,
}

impl Message {
    /// A message that starts with plain `text`.
    pub fn text(text: impl Into<String>) -> Message {
        Message::default().then(text)
    }

    /// Appends plain text.
    pub fn then(mut self, text: impl Into<String>) -> Message {
        self.parts.push(Part::Text(text.into()));
        self
    }

    /// Appends `words` that name `setting`.
    pub fn setting(mut self, setting: Setting, words: impl Into<String>) -> Message {
        self.parts.push(Part::Setting(setting, words.into()));
        self
    }

    /// The settings the message names, in order.
    pub fn settings(&self) -> impl Iterator<Item = Setting> + '_ {
        self.parts.iter().filter_map(|p| match p {
            Part::Setting(s, _) => Some(*s),
            Part::Text(_) => None,
        })
    }

    /// The message with each setting's words replaced by `name(setting, words)`.
    pub fn render(&self, name: impl Fn(Setting, &str) -> String) -> String {
        self.parts
            .iter()
            .map(|p| match p {
                Part::Text(t) => t.clone(),
                Part::Setting(s, words) => name(*s, words),
            })
            .collect()
    }
}

impl fmt::Display for Message {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render(|_, words| words.to_string()))
    }
}

impl From<String> for Message {
    fn from(text: String) -> Message {
        Message::text(text)
    }
}

/// A size written for a message with its axes named in words, height first, so that it reads
/// right whatever order the reader writes sizes in (Python and JSON (height, width), the
/// command line's `--size WxH` width first).
///
/// ```
/// use shadelab::SizeText;
/// assert_eq!(SizeText::Degrees(10.0, 14.0).to_string(), "10.0° high × 14.0° wide");
/// assert_eq!(SizeText::Degrees(3.97476, 0.25).to_string(), "3.975° high × 0.25° wide");
/// assert_eq!(SizeText::Pixels(40, 60).to_string(), "40 px high × 60 px wide");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SizeText {
    /// (height, width) in degrees of visual angle, written to three decimals at most.
    Degrees(f64, f64),
    /// (height, width) in pixels.
    Pixels(usize, usize),
}

impl std::fmt::Display for SizeText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            SizeText::Degrees(h, w) => write!(f, "{}° high × {}° wide", degrees(h), degrees(w)),
            SizeText::Pixels(h, w) => write!(f, "{h} px high × {w} px wide"),
        }
    }
}

/// `v` to three decimals at most and one at least (10.0, 3.975, 0.25).
fn degrees(v: f64) -> String {
    let text = format!("{v:.3}");
    let trimmed = text.trim_end_matches('0');
    if trimmed.ends_with('.') {
        format!("{trimmed}0")
    } else {
        trimmed.to_string()
    }
}
