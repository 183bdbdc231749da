//! `gallery` as a pipeline: every preset (the built-in ones of `stimuli/`, or a folder of
//! specs) rendered into one folder with thumbnails, a contact sheet and an `index.html`. The
//! folder is the output, so `run` writes it (whole or not at all); see [`crate::gallery`] for
//! what it holds.
//!
//! ```
//! use shadelab::pipeline::gallery::{run, GalleryConfig};
//! use shadelab::NoProgress;
//!
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-gallery-{}", std::process::id()));
//! let mut config = GalleryConfig::builtin(&dir).unwrap();
//! config.presets.truncate(1); // the first preset only, to keep the example quick
//! let report = run(&config, &NoProgress).unwrap();
//! assert_eq!(report.presets.len(), 1);
//! assert!(report.index.exists());
//! assert!(report.presets[0].files.iter().any(|f| f.ends_with(".json")));
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

use crate::error::Result;
use crate::gallery::{self, Options, Preset};
use crate::progress::Progress;
use crate::visual_size::Geometry;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What to put in a gallery and where.
#[derive(Debug, Clone, PartialEq)]
pub struct GalleryConfig {
    /// The presets, in gallery order.
    pub presets: Vec<Preset>,
    /// The output folder.
    pub out: PathBuf,
    /// Replacing a foreign folder, the largest picture, the prefix of the docs links.
    pub options: Options,
}

impl GalleryConfig {
    /// The built-in presets of `stimuli/`, into `out`, with default options.
    pub fn builtin(out: impl Into<PathBuf>) -> Result<GalleryConfig> {
        Ok(GalleryConfig {
            presets: gallery::builtin_presets()?,
            out: out.into(),
            options: Options::default(),
        })
    }

    /// Every `*.json` spec in the folder `presets`, into `out`, with default options.
    pub fn from_folder(presets: &Path, out: impl Into<PathBuf>) -> Result<GalleryConfig> {
        Ok(GalleryConfig {
            presets: gallery::load_presets(presets)?,
            out: out.into(),
            options: Options {
                inputs: vec![presets.to_path_buf()],
                ..Options::default()
            },
        })
    }

    /// Checks that there is at least one preset and that their names are distinct.
    pub fn validate(&self) -> Result<()> {
        gallery::check_presets(&self.presets)
    }
}

/// One picture of a gallery.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GalleryEntry {
    /// The preset's name, which names its files.
    pub name: String,
    /// The stimulus it renders.
    pub stimulus: String,
    /// Its size in pixels and degrees.
    pub geometry: Geometry,
    /// Its seed.
    pub seed: u64,
    /// The names of its files in the folder (image, sidecar, mask, ...).
    pub files: Vec<String>,
}

/// What a gallery run wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GalleryReport {
    /// The gallery folder.
    pub folder: PathBuf,
    /// Its index page.
    pub index: PathBuf,
    /// Every picture, in gallery order.
    pub presets: Vec<GalleryEntry>,
}

/// Renders every preset (in parallel) and writes the gallery folder; one progress step per
/// preset.
pub fn run(config: &GalleryConfig, progress: &dyn Progress) -> Result<GalleryReport> {
    config.validate()?;
    progress.start(config.presets.len() as u64, "gallery");
    let report = gallery::build(&config.presets, &config.out, &config.options, &|_| {
        progress.advance(1)
    });
    progress.finish();
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn configs_refuse_no_presets_and_twins() {
        let mut config = GalleryConfig::builtin("g").unwrap();
        config.validate().unwrap();
        config.presets.truncate(1);
        config.presets.push(config.presets[0].clone());
        let e = config.validate().unwrap_err().to_string();
        assert!(e.contains("two presets are called"), "{e}");
        config.presets.clear();
        assert!(config.validate().is_err());
        assert!(run(&config, &crate::progress::NoProgress).is_err());
        assert!(!Path::new("g").exists());
    }
}
