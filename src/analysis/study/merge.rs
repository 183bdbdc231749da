//! Merging the output folders of every shard of a study into the files one run writes.

use super::{Shard, REPORT, RESULTS, RESULTS_HEADER, SWEEP, SWEEP_HEADER};
use crate::error::{Error, Result};
use crate::io;
use serde_json::Value;
use std::path::PathBuf;

/// What a merge produces: the joined tables and what the shards' reports said.
#[derive(Debug, Clone, PartialEq)]
pub struct Merged {
    /// `results.csv`, byte-identical to an unsharded run's.
    pub results: String,
    /// `sweep.csv`, byte-identical to an unsharded run's.
    pub sweep: String,
    /// The spec the shards ran, as their reports recorded it.
    pub spec: Value,
    /// The md5 of the spec, the same in every shard.
    pub spec_md5: String,
    /// The number of grid points of the whole study.
    pub point_count: usize,
    /// Every shard and its folder, in shard order.
    pub merged_from: Vec<(Shard, PathBuf)>,
}

/// Merges the output folders of every shard of one study.
///
/// Fails, naming the folder, when one is not a study output, when they come from different
/// specs or shard counts, or when a shard is missing or given twice.
pub fn merge(dirs: &[PathBuf]) -> Result<Merged> {
    if dirs.is_empty() {
        return Err(Error::invalid("give the shard folders to merge"));
    }
    let mut shards: Vec<(Shard, &PathBuf)> = Vec::new();
    let mut spec: Option<(String, Value, usize)> = None;
    for dir in dirs {
        let path = dir.join(REPORT);
        if !path.exists() {
            return Err(Error::format(
                dir,
                format!("not a study output folder (no {REPORT} in it)"),
            ));
        }
        let report: Value = serde_json::from_slice(&io::read_bytes(&path)?)
            .map_err(|e| Error::format(&path, format!("bad study report: {e}")))?;
        let md5 = report["spec_md5"].as_str().unwrap_or_default().to_string();
        let index = report["shard"]["index"].as_u64();
        let count = report["shard"]["count"].as_u64();
        let points = report["point_count"].as_u64();
        let (Some(index), Some(count), Some(points), false) =
            (index, count, points, md5.is_empty())
        else {
            return Err(Error::format(
                &path,
                "bad study report: no spec_md5, shard or point_count",
            ));
        };
        let shard = Shard {
            index: index as usize,
            count: count as usize,
        };
        match &spec {
            None => spec = Some((md5, report["spec"].clone(), points as usize)),
            Some((m, _, _)) if *m != md5 => {
                return Err(Error::format(
                    dir,
                    format!(
                        "comes from a different study spec than {} (spec md5 {md5} vs {m})",
                        dirs[0].display()
                    ),
                ))
            }
            Some(_) => {}
        }
        if let Some((first, _)) = shards.first() {
            if first.count != shard.count {
                return Err(Error::format(
                    dir,
                    format!(
                        "is shard {}/{} but {} is one of {}",
                        shard.index,
                        shard.count,
                        dirs[0].display(),
                        first.count
                    ),
                ));
            }
        }
        if let Some((_, other)) = shards.iter().find(|(s, _)| s.index == shard.index) {
            return Err(Error::format(
                dir,
                format!(
                    "is shard {}/{}, as is {}",
                    shard.index,
                    shard.count,
                    other.display()
                ),
            ));
        }
        shards.push((shard, dir));
    }
    let count = shards[0].0.count;
    let missing: Vec<String> = (0..count)
        .filter(|i| !shards.iter().any(|(s, _)| s.index == *i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!(
            "cannot merge: shard{} {} missing",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        )));
    }
    shards.sort_by_key(|(s, _)| s.index);
    let join = |file: &str, header: &str| -> Result<String> {
        let mut rows: Vec<(usize, String)> = Vec::new();
        for (_, dir) in &shards {
            let path = dir.join(file);
            let text = String::from_utf8(io::read_bytes(&path)?)
                .map_err(|_| Error::format(&path, "not UTF-8 text"))?;
            let mut lines = text.split_inclusive('\n');
            if lines.next() != Some(header) {
                return Err(Error::format(
                    &path,
                    "unexpected header: not a study CSV of this version",
                ));
            }
            for line in lines {
                let point = line
                    .split(',')
                    .next()
                    .and_then(|p| p.parse::<usize>().ok())
                    .ok_or_else(|| {
                        Error::format(
                            &path,
                            format!("row without a point number: {}", line.trim_end()),
                        )
                    })?;
                rows.push((point, line.to_string()));
            }
        }
        // Stable: rows of one point keep their order (they all come from one shard).
        rows.sort_by_key(|(p, _)| *p);
        let mut out = String::from(header);
        for (_, line) in rows {
            out.push_str(&line);
        }
        Ok(out)
    };
    let results = join(RESULTS, RESULTS_HEADER)?;
    let sweep_csv = join(SWEEP, SWEEP_HEADER)?;
    let (md5, spec_value, point_count) = spec.unwrap_or_default();
    Ok(Merged {
        results,
        sweep: sweep_csv,
        spec: spec_value,
        spec_md5: md5,
        point_count,
        merged_from: shards.into_iter().map(|(s, d)| (s, d.clone())).collect(),
    })
}
