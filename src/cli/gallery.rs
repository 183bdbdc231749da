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
