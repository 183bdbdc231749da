//! `shadelab gallery --out DIR`: every preset rendered, with an index page.

use super::progress::Bar;
use super::{CliResult, Global};
use shadelab::pipeline::gallery::{self, run as build, GalleryConfig, GalleryReport};
use shadelab::CommandReport;
use std::path::PathBuf;

/// Arguments of `gallery`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file): images, sidecars, masks, thumbnails, index.html.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// A folder of stimulus specs (*.json) to use instead of the built-in presets of stimuli/.
    #[arg(long, value_name = "DIR")]
    pub presets: Option<PathBuf>,
    /// Also link each picture to its explanation in shadelab's docs/, with this prefix: a URL of the repository's files (e.g. https://github.com/OWNER/shadelab/blob/main/), or ../ for a gallery one level below a checkout. Without it no link leaves the folder; each picture carries its explanation.
    #[arg(long, value_name = "URL")]
    pub docs_base: Option<String>,
}

/// Runs `gallery`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let mut config = match &args.presets {
        Some(dir) => GalleryConfig::from_folder(dir)?,
        None => GalleryConfig::builtin()?,
    };
    config.options = gallery::Options {
        max_pixels: global.max_pixels,
        docs_base: args.docs_base,
    };
    let dest = super::destination::<GalleryReport>(&args.out, global, config.files())?;
    let report = build(&config, &Bar::new(global.quiet))?;
    let folder = report.write(&dest)?;
    let index = folder.join(GalleryReport::MARKER);
    let out = super::output::Output::new(global);
    out.note(format!(
        "wrote {} ({} stimuli; open {})",
        folder.display(),
        report.presets.len(),
        index.display()
    ));
    // The folder is the result; with --json, where it is and what it holds.
    let json = serde_json::json!({ "folder": folder, "index": index, "presets": report.presets });
    out.results("", &json)
}
