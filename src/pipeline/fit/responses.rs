//! Reading responses: shadelab's responses CSV, or jsPsych's data as CSV or JSON, from a file
//! or a folder, into each participant's (rotation, answered convex) trials.

use crate::error::{Error, Result};
use crate::io;
use crate::message::{Message, Setting};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The keys that mean "bump" (convex) and "dimple" (concave), compared without regard to case.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct KeyMap {
    /// The key for a bump.
    pub convex: String,
    /// The key for a dimple.
    pub concave: String,
}

impl KeyMap {
    /// Two different, non-empty keys.
    pub fn new(convex: &str, concave: &str) -> Result<KeyMap> {
        let (convex, concave) = (convex.trim().to_lowercase(), concave.trim().to_lowercase());
        if convex.is_empty() || concave.is_empty() || convex == concave {
            return Err(Error::invalid(format!(
                "the keys for bump and dimple ('{convex}', '{concave}') must be two different keys"
            )));
        }
        Ok(KeyMap { convex, concave })
    }

    /// `fj` (two single keys) or `BUMP,DIMPLE` (e.g. `arrowleft,arrowright`).
    pub fn parse(text: &str) -> Result<KeyMap> {
        match text.split_once(',') {
            Some((a, b)) => KeyMap::new(a, b),
            None => {
                let chars: Vec<char> = text.trim().chars().collect();
                match chars[..] {
                    [a, b] => KeyMap::new(&a.to_string(), &b.to_string()),
                    _ => Err(Error::invalid(format!(
                        "the keys '{text}' must be two keys, bump then dimple (fj, or f,j)"
                    ))),
                }
            }
        }
    }
}

/// The trials read from responses.
#[derive(Debug, Clone, PartialEq)]
pub struct Responses {
    /// Each participant's trials as (rotation in degrees, answered convex), in file order;
    /// participants in order of first appearance (without a `participant` column: the file's
    /// name when a folder is read, else one unnamed participant, "").
    pub participants: Vec<(String, Vec<(f64, bool)>)>,
    /// Practice rows left out.
    pub practice_rows: usize,
    /// The columns of the (first) file.
    pub columns: Vec<String>,
    /// Rows of jsPsych data that are not bump/dimple trials (instructions, fixation, breaks,
    /// a lab's own trials), left out.
    pub other_rows: usize,
    /// The files read.
    pub files: Vec<PathBuf>,
}

/// The extensions of the data files a folder is searched for.
pub const DATA_EXTENSIONS: &[&str] = &["csv", "json", "txt"];

/// Reads responses (a file, or a folder of files; at most [`io::MAX_TEXT_BYTES`] each).
pub fn read_responses(path: &Path) -> Result<Responses> {
    read_responses_with(path, None)
}

/// [`read_responses`] with a key mapping (see [`Config::keys`](super::Config::keys)).
pub fn read_responses_with(path: &Path, keys: Option<&KeyMap>) -> Result<Responses> {
    if !path.is_dir() {
        let text = read_text(path)?;
        let mut r = parse_data(&text, path, keys, "")?;
        r.files = vec![path.to_path_buf()];
        return Ok(r);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| Error::io(path, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && DATA_EXTENSIONS.contains(&io::extension(p).as_str()))
        .filter(|p| !is_design(p))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Error::format(
            path,
            "holds no data files (.csv, .json or .txt, one or more participants each)",
        ));
    }
    let mut all = Responses {
        participants: Vec::new(),
        practice_rows: 0,
        columns: Vec::new(),
        other_rows: 0,
        files: files.clone(),
    };
    for file in &files {
        let stem = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let r = parse_data(&read_text(file)?, file, keys, &stem)?;
        if all.columns.is_empty() {
            all.columns = r.columns;
        }
        all.practice_rows += r.practice_rows;
        all.other_rows += r.other_rows;
        for (who, trials) in r.participants {
            match all.participants.iter_mut().find(|(p, _)| *p == who) {
                Some((_, t)) => t.extend(trials),
                None => all.participants.push((who, trials)),
            }
        }
    }
    Ok(all)
}

/// A shadelab experiment's `design.json` (not data).
pub(super) fn is_design(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n == crate::pipeline::experiment::MARKER)
        && io::read_bytes(path)
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .is_some_and(|v| v["program"] == "shadelab" && v["trials"].is_array())
}

fn read_text(path: &Path) -> Result<String> {
    let bytes = io::read_bytes(path)?;
    String::from_utf8(bytes).map_err(|_| Error::format(path, "not UTF-8 text"))
}

/// Parses the text of a responses CSV; `path` names it in errors, which give the line.
pub fn parse_responses(text: &str, path: &Path) -> Result<Responses> {
    parse_data(text, path, None, "")
}

/// Parses responses as CSV, or as JSON (jsPsych's: an array of row objects) when the text
/// starts with `[`; `participant` names the rows without a `participant` column.
pub fn parse_data(
    text: &str,
    path: &Path,
    keys: Option<&KeyMap>,
    participant: &str,
) -> Result<Responses> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (columns, rows, unit) = if text.trim_start().starts_with(['[', '{']) {
        let (c, r) = json_table(text, path)?;
        (c, r, "row")
    } else {
        let (c, r) = csv_table(text, path)?;
        (c, r, "line")
    };
    interpret(columns, rows, path, keys, participant, unit)
}

type Rows = Vec<(usize, Vec<String>)>;

fn csv_table(text: &str, path: &Path) -> Result<(Vec<String>, Rows)> {
    let rows = io::parse_csv(text).map_err(|m| Error::format(path, m))?;
    let Some(((_, header), rows)) = rows.split_first() else {
        return Err(Error::format(path, "empty: no header and no trials"));
    };
    let columns: Vec<String> = header.iter().map(|h| h.trim().to_string()).collect();
    for (line, row) in rows {
        if row.len() != columns.len() {
            return Err(Error::format(
                path,
                format!(
                    "line {line}: {} fields where the header has {}",
                    row.len(),
                    columns.len()
                ),
            ));
        }
    }
    Ok((columns, rows.to_vec()))
}

/// jsPsych's JSON (`jsPsych.data.get().json()`, as JATOS stores it): an array of objects,
/// or an object with such an array under `trials` or `data`.
fn json_table(text: &str, path: &Path) -> Result<(Vec<String>, Rows)> {
    use serde_json::Value;
    let v: Value =
        serde_json::from_str(text).map_err(|e| Error::format(path, format!("not JSON: {e}")))?;
    let array = match &v {
        Value::Array(a) => a,
        Value::Object(o) => match o.get("trials").or_else(|| o.get("data")) {
            Some(Value::Array(a)) => a,
            _ => {
                return Err(Error::format(
                    path,
                    "JSON without an array of trials (jsPsych's data: [{...}, ...])",
                ))
            }
        },
        _ => return Err(Error::format(path, "JSON that is not an array of trials")),
    };
    let mut columns: Vec<String> = Vec::new();
    for (i, row) in array.iter().enumerate() {
        let Value::Object(o) = row else {
            return Err(Error::format(path, format!("row {}: not an object", i + 1)));
        };
        for k in o.keys() {
            if !columns.contains(k) {
                columns.push(k.clone());
            }
        }
    }
    if columns.is_empty() {
        return Err(Error::format(path, "empty: no trials"));
    }
    let rows = array
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let cells = columns
                .iter()
                .map(|c| match row.get(c) {
                    None | Some(Value::Null) => String::new(),
                    Some(Value::String(s)) => s.clone(),
                    Some(other) => other.to_string(),
                })
                .collect();
            (i + 1, cells)
        })
        .collect();
    Ok((columns, rows))
}

fn interpret(
    columns: Vec<String>,
    rows: Rows,
    path: &Path,
    keys: Option<&KeyMap>,
    default_participant: &str,
    unit: &str,
) -> Result<Responses> {
    let find = |name: &str| columns.iter().position(|c| c.eq_ignore_ascii_case(name));
    let need = |name: &str| {
        find(name).ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "{}no '{name}' column (the data need rotation_deg and response)",
                    if unit == "line" { "line 1: " } else { "" }
                ),
            )
        })
    };
    let (rotation, response) = (need("rotation_deg")?, need("response")?);
    let (block, participant) = (find("block"), find("participant"));
    let (judgement, key_convex, key_concave) =
        (find("judgement"), find("key_convex"), find("key_concave"));
    // jsPsych's data hold a row per screen; only those with a rotation are trials.
    let jspsych = find("trial_type").is_some();
    let mut participants: Vec<(String, Vec<(f64, bool)>)> = Vec::new();
    let (mut practice_rows, mut other_rows) = (0, 0);
    for (line, row) in &rows {
        let cell = |i: usize| row[i].trim();
        if jspsych && matches!(cell(rotation), "" | "null") {
            other_rows += 1;
            continue;
        }
        if let Some(b) = block {
            match cell(b).to_ascii_lowercase().as_str() {
                "test" => {}
                "practice" => {
                    practice_rows += 1;
                    continue;
                }
                other => {
                    return Err(Error::format(
                        path,
                        format!("{unit} {line}: block '{other}' is not 'test' or 'practice'"),
                    ))
                }
            }
        }
        let theta: f64 = cell(rotation)
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!(
                        "{unit} {line}: rotation_deg '{}' is not a finite number of degrees",
                        row[rotation]
                    ),
                )
            })?;
        let pressed = cell(response).to_lowercase();
        let row_keys = match (key_convex, key_concave) {
            (Some(a), Some(b)) if !cell(a).is_empty() && !cell(b).is_empty() => {
                Some((cell(a).to_lowercase(), cell(b).to_lowercase()))
            }
            _ => None,
        };
        let convex = if let Some(k) = keys {
            if pressed == k.convex {
                true
            } else if pressed == k.concave {
                false
            } else {
                return Err(Error::format(
                    path,
                    format!(
                        "{unit} {line}: response '{pressed}' is neither the bump key '{}' nor the dimple key '{}'",
                        k.convex, k.concave
                    ),
                ));
            }
        } else if let Some(j) = judgement.filter(|&j| !cell(j).is_empty()) {
            match cell(j).to_ascii_lowercase().as_str() {
                "convex" => true,
                "concave" => false,
                other => {
                    return Err(Error::format(
                        path,
                        format!("{unit} {line}: judgement '{other}' is not convex or concave"),
                    ))
                }
            }
        } else if let Some((kc, _)) = row_keys.filter(|(kc, kd)| pressed == *kc || pressed == *kd) {
            pressed == kc
        } else {
            match pressed.as_str() {
                "convex" | "1" => true,
                "concave" | "0" => false,
                other => {
                    return Err(Error::Setting(
                        Message::text(format!(
                            "{}: {unit} {line}: unknown response '{other}' (valid: convex, \
                             concave, 1, 0; for key presses give ",
                            path.display()
                        ))
                        .setting(Setting::Keys, "the keys for bump and dimple")
                        .then(")"),
                    ))
                }
            }
        };
        let who = participant
            .map(|p| cell(p).to_string())
            .filter(|p| !p.is_empty())
            .unwrap_or_else(|| default_participant.to_string());
        match participants.iter_mut().find(|(p, _)| *p == who) {
            Some((_, trials)) => trials.push((theta, convex)),
            None => participants.push((who, vec![(theta, convex)])),
        }
    }
    if participants.is_empty() {
        return Err(Error::format(
            path,
            if practice_rows > 0 {
                "no test trials (only practice rows)"
            } else if other_rows > 0 {
                "no bump/dimple trials (no row has a rotation_deg)"
            } else {
                "no trials after the header"
            },
        ));
    }
    Ok(Responses {
        participants,
        practice_rows,
        columns,
        other_rows,
        files: Vec::new(),
    })
}
