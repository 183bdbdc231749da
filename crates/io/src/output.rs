//! Where a command writes, and on what terms: an output path, whether a folder shadelab did not
//! write may be written into, and the files the run read (never replaced). How the files are
//! written is [`AtomicDir`]'s; the command contract that writes a report through an `Output` is
//! `shadelab::CommandReport`.

use crate::error::Result;
use crate::AtomicDir;
use std::path::{Path, PathBuf};

/// Where a command writes, and on what terms.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Output {
    path: PathBuf,
    force: bool,
    inputs: Vec<PathBuf>,
}

impl Output {
    /// Writing to `path` (an output folder; for a render, its image file), refusing a folder
    /// shadelab did not write, reading nothing.
    pub fn new(path: impl Into<PathBuf>) -> Output {
        Output {
            path: path.into(),
            force: false,
            inputs: Vec::new(),
        }
    }

    /// With `force`, an existing folder shadelab did not write is written into (its files that
    /// the run does not write stay).
    pub fn force(mut self, force: bool) -> Output {
        self.force = force;
        self
    }

    /// Names the files the run read, so that the output never replaces one of them.
    pub fn reads<P: Into<PathBuf>>(mut self, inputs: impl IntoIterator<Item = P>) -> Output {
        self.inputs.extend(inputs.into_iter().map(Into::into));
        self
    }

    /// The output's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether a folder shadelab did not write may be written into.
    pub fn forced(&self) -> bool {
        self.force
    }

    /// The files the run read.
    pub fn inputs(&self) -> &[PathBuf] {
        &self.inputs
    }

    /// Starts the output folder with `marker` as the file that marks it as the command's
    /// (checked against a folder that exists, and against the inputs): the one place a
    /// command's folder is claimed.
    pub fn folder(&self, marker: &str) -> Result<AtomicDir> {
        AtomicDir::create(&self.path, marker, self.force)?.reads(&self.inputs)
    }

    /// Fails now, before the long part of a run, when the folder could not be written with
    /// `marker` (a folder that is not shadelab's, a lock held by another run, an input in the
    /// way); nothing is left behind.
    pub fn check(&self, marker: &str) -> Result<()> {
        self.folder(marker).map(drop)
    }
}
