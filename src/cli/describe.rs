//! `shadelab list` and `shadelab describe NAME`.

use super::CliResult;
use shadelab::stimulus;

/// Arguments of `describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The stimulus or surface to describe.
    pub name: String,
}

/// Prints one line per stimulus: its name and what it shows.
pub fn list() -> CliResult {
    for s in stimulus::all() {
        let info = s.info();
        println!("{:<18} {}", info.name, info.summary);
    }
    Ok(())
}

/// Prints a stimulus's parameters with defaults and ranges.
pub fn run(args: Args) -> CliResult {
    let s = stimulus::find(&args.name)?;
    let info = s.info();
    println!("{} — {}", info.name, info.summary);
    println!(
        "default size: {}x{} deg at {} ppd",
        info.default_visual_size.0, info.default_visual_size.1, info.default_ppd
    );
    println!("parameters (--set key=value):");
    for p in &info.params {
        println!(
            "  {:<18} default {:<14} range {:<28} {}",
            p.name,
            p.default.to_string(),
            p.range_text(),
            p.doc
        );
    }
    Ok(())
}
