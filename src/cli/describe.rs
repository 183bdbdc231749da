//! `shadelab list` and `shadelab describe NAME`.

use super::output::Output;
use super::{CliResult, Global};
use shadelab::pipeline::render::{describe, list as all};
use std::fmt::Write;

/// Arguments of `describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The stimulus or surface to describe.
    pub name: String,
}

/// Prints one line per stimulus: its name and what it shows.
pub fn list(global: &Global) -> CliResult {
    let all = all();
    let mut text = String::new();
    for s in &all {
        let _ = writeln!(text, "{:<18} {}", s.name, s.summary);
    }
    Output::new(global).results(&text, &all)
}

/// Prints a stimulus's parameters with defaults and ranges.
pub fn run(args: Args, global: &Global) -> CliResult {
    let d = describe(&args.name)?;
    let mut text = String::new();
    let _ = writeln!(text, "{} — {}", d.name, d.summary);
    let _ = writeln!(
        text,
        "default size: {} at {} ppd",
        shadelab::SizeText::Degrees(d.default_visual_size.0, d.default_visual_size.1),
        d.default_ppd
    );
    let _ = writeln!(text, "parameters (--set key=value):");
    for p in &d.params {
        let _ = writeln!(
            text,
            "  {:<18} default {:<14} range {:<28} {}",
            p.name,
            p.default.to_string(),
            p.range,
            p.doc
        );
    }
    if !d.stimupy_names.is_empty() {
        let _ = writeln!(text, "stimupy's names, also accepted:");
        for (theirs, ours) in &d.stimupy_names {
            let _ = writeln!(text, "  {theirs:<18} = {ours}");
        }
    }
    Output::new(global).results(&text, &d)
}
