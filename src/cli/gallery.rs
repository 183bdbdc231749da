//! `shadelab gallery --out DIR`: every preset rendered, with an index page.

use super::{progress, CliResult, Global};
use shadelab::gallery;
use std::path::PathBuf;

/// Arguments of `gallery`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (written whole, or not at all): images, sidecars, masks, thumbnails, index.html.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// A folder of stimulus specs (*.json) to use instead of the built-in presets of stimuli/.
    #[arg(long, value_name = "DIR")]
    pub presets: Option<PathBuf>,
    /// Prefix of the links from each picture to its explanation in docs/: the default suits a gallery one level below the repository root (README's `gallery/`); elsewhere give the repository's path or a URL of its files (e.g. https://github.com/OWNER/shadelab/blob/main/).
    #[arg(long, value_name = "PREFIX", default_value = gallery::DOCS_BASE)]
    pub docs_base: String,
}

/// Runs `gallery`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let presets = match &args.presets {
        Some(dir) => gallery::load_presets(dir)?,
        None => gallery::builtin_presets()?,
    };
    let bar = progress::bar(presets.len() as u64, "gallery", global.quiet);
    let options = gallery::Options {
        force: global.force,
        max_pixels: global.max_pixels,
        docs_base: args.docs_base,
    };
    let dir = gallery::build(&presets, &args.out, &options, &|_| bar.inc(1))?;
    bar.finish_and_clear();
    if !global.quiet {
        eprintln!(
            "wrote {} ({} stimuli; open {})",
            dir.display(),
            presets.len(),
            dir.join(gallery::MARKER).display()
        );
    }
    Ok(())
}
