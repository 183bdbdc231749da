//! The one contract every command follows at its end: a typed report in memory, written to an
//! [`Output`] by [`CommandReport::write`].
//!
//! An `Output` says where the files go and on what terms: the path (a folder, or a render's
//! image file), whether a folder shadelab did not write may be written into (`force`), and the
//! files the run read, which are never replaced. How the files are written (whole or not at
//! all, the user's files kept) is [`AtomicDir`]'s and [`crate::io::OutputSet`]'s.
//!
//! ```
//! use shadelab::{CommandReport, Output};
//! use std::path::Path;
//!
//! /// A report of one's own, written by the same rules as every command's.
//! struct Count(usize);
//! impl CommandReport for Count {
//!     const MARKER: &'static str = "count.json";
//!     fn write_into(&self, dir: &Path) -> shadelab::Result<()> {
//!         let file = dir.join(Self::MARKER);
//!         std::fs::write(&file, format!("{{\"count\": {}}}", self.0))
//!             .map_err(|e| shadelab::Error::io(&file, e))
//!     }
//! }
//!
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-output-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! std::fs::write(dir.join("notes.txt"), "mine")?; // a folder shadelab did not write
//! assert!(Count(3).write(&Output::new(&dir)).is_err()); // refused without force
//! Count(3).write(&Output::new(&dir).force(true))?; // the whole folder, or nothing
//! assert_eq!(std::fs::read_to_string(dir.join("notes.txt"))?, "mine"); // the user's file stays
//! assert!(dir.join("count.json").is_file());
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::error::Result;
pub use crate::io::Output;
use std::path::{Path, PathBuf};

/// A command's report: what its run found, kept in memory, and the one way it is written.
pub trait CommandReport {
    /// The file that marks an output folder as this command's (written with the folder).
    const MARKER: &'static str;

    /// Writes the report's files into `dir`, a new, empty folder.
    fn write_into(&self, dir: &Path) -> Result<()>;

    /// Writes the output folder `out` whole or not at all: a folder shadelab did not write is
    /// written into only with [`Output::force`], every file this run does not write stays, and
    /// no input is replaced (see [`crate::io::AtomicDir`]). Returns the folder.
    fn write(&self, out: &Output) -> Result<PathBuf> {
        let folder = out.folder(Self::MARKER)?;
        self.write_into(folder.path())?;
        folder.commit()
    }
}
