//! `gallery` as a pipeline: every preset (the built-in ones of `stimuli/`, or a folder of
//! specs) rendered in memory, then written into one folder with thumbnails, a contact sheet and
//! an `index.html`; see [`GalleryReport`] for what it holds.
//!
//! ```
//! use shadelab::pipeline::gallery::{run, GalleryConfig};
//! use shadelab::{CommandReport, NoProgress, Output};
//!
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-gallery-{}", std::process::id()));
//! let mut config = GalleryConfig::builtin().unwrap();
//! config.presets.truncate(1); // the first preset only, to keep the example quick
//! let report = run(&config, &NoProgress).unwrap();
//! assert_eq!(report.presets.len(), 1);
//! assert!(report.presets[0].files.iter().any(|f| f.ends_with(".json")));
//! let folder = report.write(&Output::new(&dir)).unwrap();
//! assert!(folder.join("index.html").exists());
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

// The parts of this command's configuration and report that other modules define.
pub use crate::gallery::{Options, Preset, Rendered, THUMBNAIL_GAMMA};

use super::CommandReport;
use crate::error::Result;
use crate::gallery::{self};
use crate::progress::Progress;
use crate::visual_size::Geometry;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What to put in a gallery.
#[derive(Debug, Clone, PartialEq)]
pub struct GalleryConfig {
    /// The presets, in gallery order.
    pub presets: Vec<Preset>,
    /// The largest picture, the prefix of the docs links.
    pub options: Options,
    /// The folder the presets were read from, if any: an input, never replaced.
    pub source: Option<PathBuf>,
}

impl GalleryConfig {
    /// The built-in presets of `stimuli/`, with default options.
    pub fn builtin() -> Result<GalleryConfig> {
        Ok(GalleryConfig {
            presets: gallery::builtin_presets()?,
            options: Options::default(),
            source: None,
        })
    }

    /// Every `*.json` spec in the folder `presets`, with default options.
    pub fn from_folder(presets: &Path) -> Result<GalleryConfig> {
        Ok(GalleryConfig {
            presets: gallery::load_presets(presets)?,
            options: Options::default(),
            source: Some(presets.to_path_buf()),
        })
    }

    /// The files and folders the gallery reads, for [`Output::reads`](super::Output::reads).
    pub fn files(&self) -> Vec<PathBuf> {
        self.source.iter().cloned().collect()
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

/// A gallery rendered: every picture, in gallery order.
#[derive(Debug, Clone, Serialize)]
pub struct GalleryReport {
    /// Every picture, in gallery order.
    pub presets: Vec<GalleryEntry>,
    /// The pictures themselves.
    #[serde(skip)]
    pub rendered: Vec<Rendered>,
    /// The prefix of the docs links, if any ([`Options::docs_base`]).
    #[serde(skip)]
    pub docs_base: Option<String>,
}

/// Renders every preset (in parallel), in memory; one progress step per preset.
pub fn run(config: &GalleryConfig, progress: &dyn Progress) -> Result<GalleryReport> {
    config.validate()?;
    progress.start(config.presets.len() as u64, "gallery");
    let rendered = gallery::render(&config.presets, &config.options, &|_| progress.advance(1));
    progress.finish();
    let rendered = rendered?;
    Ok(GalleryReport {
        presets: rendered
            .iter()
            .map(|r| GalleryEntry {
                name: r.preset.name.clone(),
                stimulus: r.preset.spec.stimulus.clone(),
                geometry: r.request.geometry,
                seed: r.request.seed,
                files: r.files(),
            })
            .collect(),
        rendered,
        docs_base: config.options.docs_base.clone(),
    })
}

impl CommandReport for GalleryReport {
    /// The index page, `index.html`.
    const MARKER: &'static str = gallery::MARKER;

    /// Writes every picture with its sidecar and mask, the thumbnails, the contact sheet and
    /// the index page (see [`gallery::write_into`]); a new folder has no teaching page, so its
    /// index does not link one.
    fn write_into(&self, dir: &Path) -> Result<()> {
        gallery::write_into(dir, &self.rendered, self.docs_base.as_deref(), false)
    }

    /// As [`CommandReport::write`]; the index links the teaching page when the folder already
    /// holds it (built there by `web/build.sh GALLERY/teach`, kept as the user's).
    fn write(&self, out: &super::Output) -> Result<PathBuf> {
        let folder = out.folder(Self::MARKER)?;
        let teach = folder.target().join(gallery::TEACHING_PAGE).is_file();
        gallery::write_into(
            folder.path(),
            &self.rendered,
            self.docs_base.as_deref(),
            teach,
        )?;
        folder.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn configs_refuse_no_presets_and_twins() {
        let mut config = GalleryConfig::builtin().unwrap();
        config.validate().unwrap();
        config.presets.truncate(1);
        config.presets.push(config.presets[0].clone());
        let e = config.validate().unwrap_err().to_string();
        assert!(e.contains("two presets are called"), "{e}");
        config.presets.clear();
        assert!(config.validate().is_err());
        assert!(run(&config, &crate::progress::NoProgress).is_err());
    }
}
