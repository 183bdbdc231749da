//! `study run` and `study merge` as pipelines: a study (or one shard of it) run into the tables
//! `results.csv` and `sweep.csv` with a report `study.json`, and the shards' folders merged into
//! exactly the files one run writes. See [`crate::analysis::study`] for the spec and the grid.
//!
//! ```
//! use shadelab_analysis::analysis::study::{Shard, StudySpec};
//! use shadelab::pipeline::study::{run, StudyRunConfig};
//! use shadelab::NoProgress;
//!
//! let spec: StudySpec = serde_json::from_str(
//!     r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": 1},
//!         "visual_size": [2, 2], "ppd": 12}], "tilts": "0:360:90"}"#,
//! )
//! .unwrap();
//! let config = StudyRunConfig::new(spec, Shard::WHOLE, 1 << 20).unwrap();
//! assert_eq!(config.point_count(), 1);
//! let report = run(&config, &NoProgress).unwrap();
//! assert_eq!(report.points, vec![0]);
//! // One sweep row per assumed tilt (4) and token (1), after the header.
//! assert_eq!(report.sweep.lines().count(), 1 + 4);
//! ```

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::study::grid::Point;
pub use crate::analysis::study::{PriorGrid, Shard, StimulusEntry, Study, StudyOutput, StudySpec};

use super::CommandReport;
use crate::analysis::study::{self, REPORT, RESULTS, SWEEP};
use crate::error::{Error, Result};
use crate::io::{self, Stamp};
use crate::progress::Progress;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run a study: the checked spec with its grid, and the shard to run.
#[derive(Debug, Clone)]
pub struct StudyRunConfig {
    /// The checked study.
    pub study: Study,
    /// Which part of it to run ([`Shard::WHOLE`] for all).
    pub shard: Shard,
}

impl StudyRunConfig {
    /// Checks `spec` (pictures of at most `max_pixels` pixels) and expands its grid.
    pub fn new(spec: StudySpec, shard: Shard, max_pixels: usize) -> Result<StudyRunConfig> {
        Ok(StudyRunConfig {
            study: Study::new_with_max_pixels(spec, max_pixels)?,
            shard,
        })
    }

    /// Reads and checks the spec file `path` (errors name the file).
    pub fn load(path: &Path, shard: Shard, max_pixels: usize) -> Result<StudyRunConfig> {
        Ok(StudyRunConfig {
            study: Study::load_with_max_pixels(path, max_pixels)?,
            shard,
        })
    }

    /// How many grid points the shard runs.
    pub fn point_count(&self) -> usize {
        self.study.shard_points(self.shard).len()
    }
}

/// What a study run did: the content of `study.json`, with the two tables beside it.
#[derive(Debug, Clone, Serialize)]
pub struct StudyRunReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The spec as given.
    pub spec: StudySpec,
    /// The md5 of the spec's canonical JSON: shards of one study share it.
    pub spec_md5: String,
    /// The shard run.
    pub shard: Shard,
    /// The number of grid points of the whole study.
    pub point_count: usize,
    /// The points this run ran.
    pub points: Vec<usize>,
    /// What each table holds.
    pub files: BTreeMap<&'static str, &'static str>,
    /// The time the run took.
    pub seconds: f64,
    /// `results.csv`: the observer's P(convex) per point × prior × rotation × token.
    #[serde(skip)]
    pub results: String,
    /// `sweep.csv`: the prior sweep per point × assumed tilt × token.
    #[serde(skip)]
    pub sweep: String,
}

/// Runs the config's shard of its study (in parallel), one progress step per grid point.
pub fn run(config: &StudyRunConfig, progress: &dyn Progress) -> Result<StudyRunReport> {
    let started = Instant::now();
    let study = &config.study;
    progress.start(config.point_count() as u64, "study");
    let output = study.run(config.shard, &|| progress.advance(1));
    progress.finish();
    let output = output?;
    Ok(StudyRunReport {
        stamp: Stamp::of("study run"),
        spec: study.spec.clone(),
        spec_md5: study.spec_md5.clone(),
        shard: config.shard,
        point_count: study.points.len(),
        points: output.points,
        files: BTreeMap::from([
            (RESULTS, "observer: P(convex) per point × prior × rotation × token"),
            (
                SWEEP,
                "prior sweep: convexity, residual e_R, smoothness e_S per point × assumed tilt × token",
            ),
        ]),
        seconds: started.elapsed().as_secs_f64(),
        results: output.results,
        sweep: output.sweep,
    })
}

impl CommandReport for StudyRunReport {
    const MARKER: &'static str = REPORT;

    /// Writes `results.csv`, `sweep.csv` and the report, `study.json`.
    fn write_into(&self, dir: &Path) -> Result<()> {
        write_study_files(dir, &self.results, &self.sweep, self)
    }
}

/// How to merge a study's shards: their output folders, and where the merge goes.
#[derive(Debug, Clone)]
pub struct StudyMergeConfig {
    /// Every shard's output folder, any order.
    pub dirs: Vec<PathBuf>,
}

impl StudyMergeConfig {
    /// Checks that `out`, the merge's output folder, is
    /// none of them: replacing one of its own inputs would lose that shard if anything went
    /// wrong later.
    pub fn new(dirs: Vec<PathBuf>, out: &Path) -> Result<StudyMergeConfig> {
        if let Ok(target) = std::fs::canonicalize(out) {
            if let Some(dir) = dirs
                .iter()
                .find(|d| std::fs::canonicalize(d).ok().as_ref() == Some(&target))
            {
                return Err(Error::invalid(format!(
                    "{} is one of the shard folders being merged ({}); choose another folder",
                    out.display(),
                    dir.display()
                )));
            }
        }
        Ok(StudyMergeConfig { dirs })
    }
}

/// One shard folder of a merge.
#[derive(Debug, Clone, Serialize)]
pub struct MergedShard {
    /// The folder, as given.
    pub folder: String,
    /// The shard it holds.
    pub shard: Shard,
}

/// What a merge did: the content of the merged `study.json`, with the two tables beside it.
#[derive(Debug, Clone, Serialize)]
pub struct StudyMergeReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The spec, as the shards recorded it.
    pub spec: Value,
    /// The md5 of the spec.
    pub spec_md5: String,
    /// Always [`Shard::WHOLE`]: the merge is the whole study.
    pub shard: Shard,
    /// The number of grid points of the study.
    pub point_count: usize,
    /// The shard folders merged, in shard order.
    pub merged_from: Vec<MergedShard>,
    /// The merged `results.csv`, identical to an unsharded run's.
    #[serde(skip)]
    pub results: String,
    /// The merged `sweep.csv`, identical to an unsharded run's.
    #[serde(skip)]
    pub sweep: String,
}

/// Merges the shards' folders (see [`study::merge()`] for what is refused).
pub fn merge(config: &StudyMergeConfig, progress: &dyn Progress) -> Result<StudyMergeReport> {
    progress.start(config.dirs.len() as u64, "merge");
    let merged = study::merge(&config.dirs);
    progress.finish();
    let merged = merged?;
    Ok(StudyMergeReport {
        stamp: Stamp::of("study merge"),
        spec: merged.spec,
        spec_md5: merged.spec_md5,
        shard: Shard::WHOLE,
        point_count: merged.point_count,
        merged_from: merged
            .merged_from
            .into_iter()
            .map(|(shard, dir)| MergedShard {
                folder: dir.display().to_string(),
                shard,
            })
            .collect(),
        results: merged.results,
        sweep: merged.sweep,
    })
}

impl CommandReport for StudyMergeReport {
    const MARKER: &'static str = REPORT;

    /// Writes `results.csv`, `sweep.csv` and the report, `study.json`.
    fn write_into(&self, dir: &Path) -> Result<()> {
        write_study_files(dir, &self.results, &self.sweep, self)
    }
}

/// The three files of a study folder.
fn write_study_files(
    dir: &Path,
    results: &str,
    sweep: &str,
    report: &impl Serialize,
) -> Result<()> {
    io::write_text(&dir.join(RESULTS), results)?;
    io::write_text(&dir.join(SWEEP), sweep)?;
    let value = serde_json::to_value(report)
        .map_err(|e| Error::Compute(format!("cannot serialise the study report: {e}")))?;
    io::write_json(&dir.join(REPORT), &value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    fn spec() -> StudySpec {
        serde_json::from_str(
            r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": 1,
                "pattern": ["bumps", "dimples"]}, "visual_size": [2, 2], "ppd": 10}],
                "tilts": "0:360:90", "slants": [30, 45]}"#,
        )
        .unwrap()
    }

    #[test]
    fn shards_written_and_merged_give_the_whole_run() {
        let dir =
            std::env::temp_dir().join(format!("shadelab-pipeline-study-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let whole = run(
            &StudyRunConfig::new(spec(), Shard::WHOLE, 1 << 20).unwrap(),
            &NoProgress,
        )
        .unwrap();
        assert_eq!(whole.points, vec![0, 1, 2, 3]);
        let mut dirs = Vec::new();
        for index in [1, 0] {
            let config = StudyRunConfig::new(spec(), Shard { index, count: 2 }, 1 << 20).unwrap();
            assert_eq!(config.point_count(), 2);
            let report = run(&config, &NoProgress).unwrap();
            let out = dir.join(format!("s{index}"));
            assert_eq!(report.write(&super::super::Output::new(&out)).unwrap(), out);
            dirs.push(out);
        }
        let out = dir.join("merged");
        let merged = merge(
            &StudyMergeConfig::new(dirs.clone(), &out).unwrap(),
            &NoProgress,
        )
        .unwrap();
        assert_eq!(
            (merged.results.as_str(), merged.sweep.as_str()),
            (whole.results.as_str(), whole.sweep.as_str())
        );
        assert_eq!(merged.spec_md5, whole.spec_md5);
        assert_eq!(merged.merged_from[0].shard.index, 0);
        merged.write(&super::super::Output::new(&out)).unwrap();
        let report: Value =
            serde_json::from_slice(&std::fs::read(out.join(REPORT)).unwrap()).unwrap();
        assert_eq!(report["command"], "study merge");
        assert_eq!(report["point_count"], 4);
        assert_eq!(
            std::fs::read_to_string(out.join(RESULTS)).unwrap(),
            whole.results
        );
        // The merge may not write over one of its own shards.
        let e = StudyMergeConfig::new(dirs.clone(), &dirs[1])
            .unwrap_err()
            .to_string();
        assert!(e.contains("one of the shard folders"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
