//! `shadelab list` and `shadelab describe NAME`.

use super::CliResult;
use shadelab::pipeline::render::{describe, list as all};

/// Arguments of `describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The stimulus or surface to describe.
    pub name: String,
}

/// Prints one line per stimulus: its name and what it shows.
pub fn list() -> CliResult {
    for s in all() {
        println!("{:<18} {}", s.name, s.summary);
    }
    Ok(())
}

/// Prints a stimulus's parameters with defaults and ranges.
pub fn run(args: Args) -> CliResult {
    let d = describe(&args.name)?;
    println!("{} — {}", d.name, d.summary);
    println!(
        "default size: {}x{} deg (width x height) at {} ppd",
        d.default_visual_size.1, d.default_visual_size.0, d.default_ppd
    );
    println!("parameters (--set key=value):");
    for p in &d.params {
        println!(
            "  {:<18} default {:<14} range {:<28} {}",
            p.name,
            p.default.to_string(),
            p.range,
            p.doc
        );
    }
    Ok(())
}
