//! Merging the output folders of every shard of a study into the files one run writes.

use super::{Shard, REPORT, RESULTS, RESULTS_HEADER, SWEEP, SWEEP_HEADER};
use crate::error::{Error, Result};
use crate::io;
use serde_json::Value;
use std::path::{Path, PathBuf};

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

/// What a column of a study CSV holds, as a merge checks it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Column {
    /// The grid point's number.
    Point,
    /// Any text (a name, parameters, a token).
    Text,
    /// A finite number.
    Number,
    /// `true` or `false`.
    Flag,
}

use Column::{Flag, Number, Point, Text};

/// The columns of `results.csv` ([`RESULTS_HEADER`]).
const RESULTS_COLUMNS: [Column; 11] = [
    Point, Text, Text, Number, Number, Number, Number, Number, Text, Number, Number,
];

/// The columns of `sweep.csv` ([`SWEEP_HEADER`]).
const SWEEP_COLUMNS: [Column; 11] = [
    Point, Text, Text, Number, Number, Text, Number, Number, Number, Number, Flag,
];

/// The header and columns of the study CSV named `file` ([`RESULTS`] or [`SWEEP`]).
fn layout(file: &str) -> (&'static str, &'static [Column]) {
    if file == SWEEP {
        (SWEEP_HEADER, &SWEEP_COLUMNS)
    } else {
        (RESULTS_HEADER, &RESULTS_COLUMNS)
    }
}

/// The rows of one shard's study CSV (`results.csv` or `sweep.csv`, as the name of `path`
/// says), each with its point, after checking the header and every row: whole (a line break
/// at its end), as many fields as the header, numbers that parse and are finite, and a point
/// of the study's `point_count` that `shard` runs. Errors name `path` and the line.
///
/// ```
/// use shadelab_analysis::analysis::study::{merge::shard_rows, Shard, SWEEP_HEADER};
/// use std::path::Path;
/// let path = Path::new("s1/sweep.csv");
/// let row = "1,bumps,rows=1,30,0,bump,1,0.1,0.2,0.3,true\n";
/// let shard = Shard { index: 1, count: 2 };
/// let rows = shard_rows(format!("{SWEEP_HEADER}{row}").as_bytes(), path, shard, 4)?;
/// assert_eq!(rows, [(1, row.to_string())]);
/// let cut = format!("{SWEEP_HEADER}{}", &row[..20]);
/// let e = shard_rows(cut.as_bytes(), path, shard, 4).unwrap_err().to_string();
/// assert_eq!(e, "s1/sweep.csv: line 2: the row is truncated (the file ends inside it)");
/// let other = Shard { index: 0, count: 2 };
/// let e = shard_rows(format!("{SWEEP_HEADER}{row}").as_bytes(), path, other, 4).unwrap_err();
/// assert!(e.to_string().ends_with("point 1 belongs to shard 1/2, not to this shard 0/2"));
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn shard_rows(
    bytes: &[u8],
    path: &Path,
    shard: Shard,
    point_count: usize,
) -> Result<Vec<(usize, String)>> {
    let file = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let (header, columns) = layout(file);
    let text = std::str::from_utf8(bytes).map_err(|_| Error::format(path, "not UTF-8 text"))?;
    let mut lines = text.split_inclusive('\n');
    if lines.next() != Some(header) {
        return Err(Error::format(
            path,
            "unexpected header: not a study CSV of this version",
        ));
    }
    lines
        .enumerate()
        .map(|(n, line)| {
            check_row(line, columns, shard, point_count)
                .map(|point| (point, line.to_string()))
                .map_err(|why| Error::format(path, format!("line {}: {why}", n + 2)))
        })
        .collect()
}

/// Checks one row (with its line break) of a shard's CSV against `columns`: whole, with as
/// many fields, numbers that parse and are finite, and a point of the study that `shard`
/// runs; gives its point, or why not.
fn check_row(
    line: &str,
    columns: &[Column],
    shard: Shard,
    point_count: usize,
) -> std::result::Result<usize, String> {
    let Some(record) = line.strip_suffix('\n') else {
        return Err("the row is truncated (the file ends inside it)".into());
    };
    let fields = io::csv_record(record).map_err(|why| format!("not a CSV row ({why})"))?;
    if fields.len() != columns.len() {
        return Err(format!(
            "{} fields where the header has {} (a truncated or foreign row)",
            fields.len(),
            columns.len()
        ));
    }
    let mut point = None;
    for (k, (field, column)) in fields.iter().zip(columns).enumerate() {
        let ok = match column {
            Point => {
                let p: usize = field
                    .parse()
                    .map_err(|_| format!("'{field}' is not a point number"))?;
                if p >= point_count {
                    return Err(format!(
                        "point {p} is not in the study (it has {point_count} points)"
                    ));
                }
                if !shard.runs(p) {
                    return Err(format!(
                        "point {p} belongs to shard {}/{}, not to this shard {}/{}",
                        p % shard.count,
                        shard.count,
                        shard.index,
                        shard.count
                    ));
                }
                point = Some(p);
                true
            }
            Text => true,
            Number => field.parse::<f64>().is_ok_and(f64::is_finite),
            Flag => field == "true" || field == "false",
        };
        if !ok {
            let want = if *column == Flag {
                "true or false"
            } else {
                "a finite number"
            };
            return Err(format!("field {} is '{field}', not {want}", k + 1));
        }
    }
    point.ok_or_else(|| "no point number".to_string())
}

/// Merges the output folders of every shard of one study.
///
/// Fails, naming the folder, when one is not a study output, when they come from different
/// specs or shard counts, or when a shard is missing or given twice; fails, naming the file
/// and line, on a row that is truncated, has another number of fields than the header, holds
/// a number that does not parse or is not finite, or names a point that is not the study's or
/// not its shard's (a point appearing twice); and on a point no shard has rows for.
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
    let point_count = spec.as_ref().map_or(0, |(_, _, n)| *n);
    let join = |file: &str| -> Result<String> {
        let mut rows: Vec<(usize, String)> = Vec::new();
        for (shard, dir) in &shards {
            let path = dir.join(file);
            rows.extend(shard_rows(
                &io::read_bytes(&path)?,
                &path,
                *shard,
                point_count,
            )?);
        }
        let missing: Vec<String> = (0..point_count)
            .filter(|p| !rows.iter().any(|(q, _)| q == p))
            .map(|p| p.to_string())
            .collect();
        if let Some(first) = missing.first() {
            return Err(Error::invalid(format!(
                "cannot merge: no shard's {file} has rows for point{} {} (of {point_count}; \
                 shard {}/{count} runs point {first})",
                if missing.len() > 1 { "s" } else { "" },
                missing.join(", "),
                first.parse::<usize>().unwrap_or(0) % count,
            )));
        }
        // Stable: rows of one point keep their order (they all come from one shard).
        rows.sort_by_key(|(p, _)| *p);
        let mut out = String::from(layout(file).0);
        for (_, line) in rows {
            out.push_str(&line);
        }
        Ok(out)
    };
    let results = join(RESULTS)?;
    let sweep_csv = join(SWEEP)?;
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
