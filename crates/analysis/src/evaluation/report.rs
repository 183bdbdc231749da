//! The evaluation as a Markdown table.

use super::case::CaseResult;
use super::Config;
use crate::error::Result;
use crate::io;
use crate::io::{BitDepth, Output};
use crate::progress::Progress;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The file that marks an output folder as written by the evaluation.
pub const MARKER: &str = "evaluation.json";

/// Writes `evaluation.md` (the table, with the version, commit and command) and
/// `evaluation.json` (every number and parameter) into `dir`.
pub fn write_summary(
    dir: &Path,
    config: &Config,
    results: &[CaseResult],
    commit: &str,
    command: &[String],
    seconds: f64,
) -> Result<()> {
    let table = markdown_table(results);
    let text = format!(
        "# shadelab evaluation\n\nshadelab {} at commit {commit}\n\n`{}`\n\n{table}",
        io::PROGRAM_VERSION,
        command.join(" ")
    );
    io::write_text(&dir.join("evaluation.md"), &text)?;
    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "commit": commit,
        "command": command,
        "data": config.data.display().to_string(),
        "conventions": io::conventions_json(),
        "parameters": config.describe(),
        "cases": results,
        "seconds": seconds,
    });
    io::write_json(&dir.join(MARKER), &report)
}

/// Where and how [`run_into`] records an evaluation: the output folder (none: the results
/// only) and the commit and command line the summary names.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// The output folder: the summary (`evaluation.md`, `evaluation.json`) and a picture per
    /// row; `None` writes nothing. The data folder is never written into.
    pub out: Option<Output>,
    /// The commit of the program that ran, as the summary states it.
    pub commit: String,
    /// The command line (or call) that ran, as the summary states it.
    pub command: Vec<String>,
}

/// Runs the evaluation ([`super::run`]) and, with an output folder, writes it whole or not at
/// all: the folder is claimed before the work (a folder that may not be replaced fails at
/// once, and the data folder is never written into), each row's picture and the summary
/// ([`write_summary`]) go into it, and it replaces the old one only when everything is
/// written. Returns the results and the folder written.
pub fn run_into(
    config: &Config,
    record: &Record,
    progress: &dyn Progress,
) -> Result<(Vec<CaseResult>, Option<PathBuf>)> {
    let started = Instant::now();
    let folder = match &record.out {
        Some(out) => Some(out.clone().reads([&config.data]).folder(MARKER)?),
        None => None,
    };
    let dir = folder.as_ref().map(|f| f.path().to_path_buf());
    let results = super::run(
        config,
        dir.is_some(),
        progress,
        &mut |name, image| match &dir {
            Some(dir) => io::write_rgb(&dir.join(name), image, BitDepth::Eight, None),
            None => Ok(()),
        },
    )?;
    let written = match folder {
        Some(folder) => {
            let seconds = started.elapsed().as_secs_f64();
            write_summary(
                folder.path(),
                config,
                &results,
                &record.commit,
                &record.command,
                seconds,
            )?;
            Some(folder.commit()?)
        }
        None => None,
    };
    Ok((results, written))
}

/// The table's header: what each column means is in docs/evaluation.md.
const HEADER: &str = "| set | object | light | boundary | method | mean error | median error | depth error (RMS after scale+offset fit) | residual | seconds |\n|---|---|---|---|---|---:|---:|---:|---:|---:|\n";

/// One Markdown table row per case and method: normal errors in degrees on the object's mask, the depth
/// error in pixels and as a percentage of the true depth range, the shading residual
/// mean |R(n) − I| in units of the albedo, and the seconds spent solving and integrating;
/// "—" where there is no truth to compare with.
pub fn markdown_table(results: &[CaseResult]) -> String {
    let mut text = String::from(HEADER);
    for r in results {
        let (mean, median) = match &r.normal_error {
            Some(e) => (
                format!("{:.2}°", e.mean_deg),
                format!("{:.2}°", e.median_deg),
            ),
            None => ("—".into(), "—".into()),
        };
        let depth = match &r.depth_error {
            Some(d) => format!("{:.2} px ({:.1} %)", d.rms_px, d.rms_percent_of_range),
            None => "—".into(),
        };
        let flag = match (r.converged, r.globalised) {
            (false, _) => " (not converged)",
            (true, true) => " (energy descent)",
            (true, false) => "",
        };
        text.push_str(&format!(
            "| {} | {} | {} | {} | {} | {mean} | {median} | {depth} | {:.3} | {:.2}{flag} |\n",
            r.set, r.object, r.light_label, r.boundary, r.method, r.residual, r.seconds
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluation::case::Albedo;
    use crate::evaluation::metrics::AngularError;

    #[test]
    fn rows_show_dashes_where_there_is_no_truth() {
        let row = CaseResult {
            set: "beethoven",
            object: "beethoven".into(),
            light_label: "image0".into(),
            light: [0.0, 0.0, 1.0],
            tilt_deg: 0.0,
            slant_deg: 0.0,
            boundary: "occluding",
            limb: None,
            albedo: Albedo::known(),
            normal_error: None,
            depth_error: None,
            residual: 0.0123,
            width: 10,
            height: 10,
            domain_pixels: 50,
            method: "multigrid".into(),
            globalised: false,
            iterations: 3,
            converged: true,
            seconds: 0.5,
        };
        let mut with_truth = row.clone();
        with_truth.normal_error = Some(AngularError {
            mean_deg: 3.14567,
            median_deg: 2.5,
            p90_deg: 6.0,
            pixels: 50,
        });
        let table = markdown_table(&[row, with_truth]);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 4);
        assert_eq!(
            lines[2],
            "| beethoven | beethoven | image0 | occluding | multigrid | — | — | — | 0.012 | 0.50 |"
        );
        assert!(lines[3].contains("| 3.15° | 2.50° | — |"), "{}", lines[3]);
    }
}
