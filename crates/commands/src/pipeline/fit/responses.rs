//! Reading responses: shadelab's responses CSV, or jsPsych's data as CSV or JSON (JATOS's
//! results export too: one result per line), from a file or a lab's folder as it arrives,
//! into each participant's (rotation, answered convex) trials. Every rule about which rows
//! are fitted lives here, decided once as the rows are read: practice rows, other screens,
//! trials without a response, simulated rows (a pilot's), the same rows in two files, and
//! files of two designs.

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

/// How the data are read: the choices a lab makes about its data folder (the fit's
/// [`Config::reading`](super::Config::reading)). The defaults fit people's test trials of one
/// design.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Reading {
    /// How key presses map to judgements, for data whose `response` holds the key pressed;
    /// `None`: the rows' own `judgement`, else their `key_convex`/`key_concave`, else
    /// `response` as convex/concave/1/0.
    pub keys: Option<KeyMap>,
    /// Fit the rows whose `simulated` column is set (a pilot's, answered by the observer
    /// model) too; without it they are counted and left out, and data of only simulated rows
    /// are refused.
    pub include_simulated: bool,
    /// Pool files of different designs (another `design_hash`); without it they are refused,
    /// naming the files.
    pub mixed_designs: bool,
}

/// Trials read twice (a JATOS export beside the server's copy): a participant's rows in one
/// file the same as those in another, counted once.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Duplicate {
    /// The participant the repeated rows name (the kept rows' name where the two differ).
    pub participant: String,
    /// Rows with a rotation (practice and test) repeated.
    pub rows: usize,
    /// Where they were read first, and fitted.
    pub kept: String,
    /// Where they were read again, and left out.
    pub left_out: String,
}

/// The files whose trials carry one design's hash.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DesignFiles {
    /// The design's hash, the rows' `design_hash`.
    pub design_hash: String,
    /// The files (or JATOS results) whose trials carry it.
    pub files: Vec<String>,
}

impl std::fmt::Display for DesignFiles {
    /// `HASH in FILE, FILE`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} in {}", self.design_hash, self.files.join(", "))
    }
}

/// The trials read from responses, and what was left out of them and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Responses {
    /// Each participant's trials as (rotation in degrees, answered convex), in file order;
    /// participants in order of first appearance (without a `participant` column: the file's
    /// name when a folder is read, else one unnamed participant, ""; in a JATOS export of
    /// several results, `result N` after it).
    pub participants: Vec<(String, Vec<(f64, bool)>)>,
    /// Practice rows left out.
    pub practice_rows: usize,
    /// The columns of the (first) file.
    pub columns: Vec<String>,
    /// Rows of jsPsych data that are not bump/dimple trials (instructions, fixation, breaks,
    /// a lab's own trials), left out.
    pub other_rows: usize,
    /// Test trials without a response (`response` null or empty: a timed-out trial), left out.
    pub no_response: usize,
    /// Simulated test trials (their `simulated` column set: a pilot's) left out.
    pub simulated_left_out: usize,
    /// Simulated test trials fitted ([`Reading::include_simulated`]).
    pub simulated_fitted: usize,
    /// Participants with simulated trials fitted.
    pub simulated_participants: usize,
    /// Rows read twice and counted once.
    pub duplicates: Vec<Duplicate>,
    /// The designs the trials carry (their `design_hash`; none where the data have no such
    /// column), each with its files.
    pub designs: Vec<DesignFiles>,
    /// The files read.
    pub files: Vec<PathBuf>,
}

/// The extensions of the data files a folder is searched for.
pub const DATA_EXTENSIONS: &[&str] = &["csv", "json", "txt"];

/// Reads responses (a file, or a folder of files; at most [`io::MAX_TEXT_BYTES`] each) with
/// the default [`Reading`].
pub fn read_responses(path: &Path) -> Result<Responses> {
    read_responses_with(path, &Reading::default())
}

/// [`read_responses`] as `reading` says (see [`Config::reading`](super::Config::reading)).
pub fn read_responses_with(path: &Path, reading: &Reading) -> Result<Responses> {
    if !path.is_dir() {
        let text = read_text(path)?;
        return parse_data(&text, path, reading, "");
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
    let mut read = Vec::new();
    for file in &files {
        let stem = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        read.push(file_chunks(&read_text(file)?, file, reading, &stem)?);
    }
    gather(read, files, path, reading)
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
    String::from_utf8(bytes).map_err(|_| {
        Error::format(
            path,
            "not UTF-8 text (a spreadsheet can save it as 'CSV UTF-8')",
        )
    })
}

/// Parses the text of a responses CSV with the default [`Reading`]; `path` names it in
/// errors, which give the line.
pub fn parse_responses(text: &str, path: &Path) -> Result<Responses> {
    parse_data(text, path, &Reading::default(), "")
}

/// Parses responses as CSV (comma- or semicolon-separated), or as JSON when the text starts
/// with `[` or `{`: jsPsych's (an array of row objects), or JATOS's results export (one such
/// result per line); `participant` names the rows without a `participant` column.
pub fn parse_data(
    text: &str,
    path: &Path,
    reading: &Reading,
    participant: &str,
) -> Result<Responses> {
    let chunks = file_chunks(text, path, reading, participant)?;
    gather(vec![chunks], vec![path.to_path_buf()], path, reading)
}

type Rows = Vec<(usize, Vec<String>)>;

/// One table of rows: a file, or one result of a JATOS export.
struct Table {
    /// Where the rows are, in words: the file, with `(result N)` in a JATOS export.
    source: String,
    columns: Vec<String>,
    rows: Rows,
    /// What a row is called in errors, with what comes before its number: `line`, `row`,
    /// `result 2, row`.
    unit: String,
    /// A semicolon-separated CSV, whose numbers may have a decimal comma.
    decimal_comma: bool,
    /// The participant of rows without a `participant` column.
    participant: String,
}

/// One participant's rows in one table, with what was left out of them.
#[derive(Default)]
struct Chunk {
    participant: String,
    source: String,
    trials: Vec<(f64, bool)>,
    /// Every row with a rotation, as (rotation, block, response, rt): two tables with the same
    /// list hold the same rows.
    rows: Vec<[String; 4]>,
    /// Test rows (fitted or left out for want of a response, or as simulated).
    test_rows: usize,
    practice: usize,
    other: usize,
    no_response: usize,
    simulated_left_out: usize,
    simulated_fitted: usize,
    designs: Vec<String>,
}

/// The rows of one file, by participant and table.
fn file_chunks(
    text: &str,
    path: &Path,
    reading: &Reading,
    participant: &str,
) -> Result<(Vec<String>, Vec<Chunk>)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let tables = tables(text, path, participant)?;
    let lenient = tables.len() > 1;
    let mut chunks = Vec::new();
    for t in &tables {
        chunks.extend(interpret(t, path, reading, lenient)?);
    }
    let count = |f: fn(&Chunk) -> usize| chunks.iter().map(f).sum::<usize>();
    if count(|c| c.test_rows) == 0 {
        return Err(Error::format(
            path,
            if count(|c| c.practice) > 0 {
                "no test trials (only practice rows)"
            } else if count(|c| c.other) > 0 {
                "no bump/dimple trials (no row has a rotation_deg)"
            } else {
                "no trials after the header"
            },
        ));
    }
    Ok((tables[0].columns.clone(), chunks))
}

/// The file's tables: one for a CSV or a JSON document, one per line for JATOS's results
/// export (a JSON result per line).
fn tables(text: &str, path: &Path, participant: &str) -> Result<Vec<Table>> {
    use serde_json::Value;
    let source = path.display().to_string();
    if !text.trim_start().starts_with(['[', '{']) {
        let (columns, rows, delimiter) = csv_table(text, path)?;
        return Ok(vec![Table {
            source,
            columns,
            rows,
            unit: "line".into(),
            decimal_comma: delimiter == ';',
            participant: participant.into(),
        }]);
    }
    let whole = match serde_json::from_str::<Value>(text) {
        Ok(v) => {
            let (columns, rows) = json_table(&v, path, "row")?;
            if columns.is_empty() {
                return Err(Error::format(path, "empty: no trials"));
            }
            return Ok(vec![Table {
                source,
                columns,
                rows,
                unit: "row".into(),
                decimal_comma: false,
                participant: participant.into(),
            }]);
        }
        Err(e) => e,
    };
    // JATOS's results export: each result's data (jsPsych's JSON) on a line of its own.
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| (i + 1, l))
        .collect();
    if lines.len() < 2 || serde_json::from_str::<Value>(lines[0].1).is_err() {
        return Err(Error::format(path, format!("not JSON: {whole}")));
    }
    let mut out = Vec::new();
    for (k, (line, text)) in lines.iter().enumerate() {
        let v: Value = serde_json::from_str(text).map_err(|e| {
            Error::format(
                path,
                format!(
                    "line {line}: not JSON ({e}); a JATOS results export holds one result, \
                     jsPsych's JSON, on each line"
                ),
            )
        })?;
        let unit = format!("result {} (line {line}), row", k + 1);
        let (columns, rows) = json_table(&v, path, &unit)?;
        out.push(Table {
            source: format!("{source} (result {})", k + 1),
            columns,
            rows,
            unit,
            decimal_comma: false,
            participant: if participant.is_empty() {
                format!("result {}", k + 1)
            } else {
                format!("{participant} result {}", k + 1)
            },
        });
    }
    Ok(out)
}

fn csv_table(text: &str, path: &Path) -> Result<(Vec<String>, Rows, char)> {
    let delimiter = io::csv_delimiter(text.lines().next().unwrap_or(""));
    let read_as = if delimiter == ';' {
        " (read as a semicolon-separated CSV)"
    } else {
        ""
    };
    let rows = io::parse_csv_with(text, delimiter)
        .map_err(|m| Error::format(path, format!("{m}{read_as}")))?;
    let Some(((_, header), rows)) = rows.split_first() else {
        return Err(Error::format(path, "empty: no header and no trials"));
    };
    let columns: Vec<String> = header.iter().map(|h| h.trim().to_string()).collect();
    for (line, row) in rows {
        if row.len() != columns.len() {
            return Err(Error::format(
                path,
                format!(
                    "line {line}: {} fields where the header has {}{read_as}",
                    row.len(),
                    columns.len()
                ),
            ));
        }
    }
    Ok((columns, rows.to_vec(), delimiter))
}

/// jsPsych's JSON (`jsPsych.data.get().json()`, as JATOS stores it): an array of objects,
/// or an object with such an array under `trials` or `data`. Rows are named `{unit} N`.
fn json_table(v: &serde_json::Value, path: &Path, unit: &str) -> Result<(Vec<String>, Rows)> {
    use serde_json::Value;
    let array = match v {
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
            return Err(Error::format(
                path,
                format!("{unit} {}: not an object", i + 1),
            ));
        };
        for k in o.keys() {
            if !columns.contains(k) {
                columns.push(k.clone());
            }
        }
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

/// A number as written in a cell: `.` or, in a semicolon-separated CSV, `,` before the
/// decimals.
fn number(cell: &str, decimal_comma: bool) -> Option<f64> {
    let cell = cell.trim();
    let parsed = if decimal_comma && !cell.contains('.') {
        cell.replacen(',', ".", 1).parse()
    } else {
        cell.parse()
    };
    parsed.ok().filter(|x: &f64| x.is_finite())
}

/// A cell that holds nothing: empty, or jsPsych's `null`.
fn blank(cell: &str) -> bool {
    cell.is_empty() || cell.eq_ignore_ascii_case("null")
}

/// The rows of one table, by participant, in order of first appearance.
fn interpret(t: &Table, path: &Path, reading: &Reading, lenient: bool) -> Result<Vec<Chunk>> {
    let (columns, unit) = (&t.columns, t.unit.as_str());
    let find = |name: &str| columns.iter().position(|c| c.eq_ignore_ascii_case(name));
    let participant = find("participant");
    let who_of = |row: &[String]| {
        participant
            .map(|p| row[p].trim().to_string())
            .filter(|p| !p.is_empty())
            .unwrap_or_else(|| t.participant.clone())
    };
    let mut chunks: Vec<Chunk> = Vec::new();
    fn chunk<'a>(chunks: &'a mut Vec<Chunk>, who: String, t: &Table) -> &'a mut Chunk {
        let i = match chunks.iter().position(|c| c.participant == who) {
            Some(i) => i,
            None => {
                chunks.push(Chunk {
                    participant: who,
                    source: t.source.clone(),
                    ..Chunk::default()
                });
                chunks.len() - 1
            }
        };
        &mut chunks[i]
    }
    let (rotation, response) = match (find("rotation_deg"), find("response")) {
        (Some(r), Some(s)) => (r, s),
        // Another component's result in a JATOS export (a questionnaire, a consent form).
        _ if lenient => {
            for (_, row) in &t.rows {
                chunk(&mut chunks, who_of(row), t).other += 1;
            }
            return Ok(chunks);
        }
        (r, _) => {
            let name = if r.is_none() {
                "rotation_deg"
            } else {
                "response"
            };
            return Err(Error::format(
                path,
                format!(
                    "{}no '{name}' column (the data need rotation_deg and response)",
                    if unit == "line" { "line 1: " } else { "" }
                ),
            ));
        }
    };
    let block = find("block");
    let (judgement, key_convex, key_concave) =
        (find("judgement"), find("key_convex"), find("key_concave"));
    let (simulated, design_hash) = (find("simulated"), find("design_hash"));
    let rt = find("rt").or_else(|| find("rt_ms"));
    // jsPsych's data hold a row per screen; only those with a rotation are trials.
    let jspsych = find("trial_type").is_some();
    let keys = reading.keys.as_ref();
    for (line, row) in &t.rows {
        let cell = |i: usize| row[i].trim();
        let c = chunk(&mut chunks, who_of(row), t);
        if jspsych && blank(cell(rotation)) {
            c.other += 1;
            continue;
        }
        let same = |i: Option<usize>| {
            i.map(&cell)
                .filter(|v| !blank(v))
                .map(|v| match number(v, t.decimal_comma) {
                    Some(x) => x.to_string(),
                    None => v.to_lowercase(),
                })
                .unwrap_or_default()
        };
        c.rows
            .push([Some(rotation), block, Some(response), rt].map(same));
        if let Some(b) = block {
            match cell(b).to_ascii_lowercase().as_str() {
                "test" => {}
                "practice" => {
                    c.practice += 1;
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
        c.test_rows += 1;
        let theta = number(cell(rotation), t.decimal_comma).ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "{unit} {line}: rotation_deg '{}' is not a finite number of degrees",
                    row[rotation]
                ),
            )
        })?;
        if let Some(h) = design_hash.map(cell).filter(|h| !blank(h)) {
            if !c.designs.iter().any(|d| d == h) {
                c.designs.push(h.to_string());
            }
        }
        let is_simulated = simulated.map(cell).is_some_and(|s| {
            !(blank(s) || ["0", "false", "no"].contains(&s.to_ascii_lowercase().as_str()))
        });
        if is_simulated && !reading.include_simulated {
            c.simulated_left_out += 1;
            continue;
        }
        let pressed = cell(response).to_lowercase();
        let judged = judgement.map(cell).filter(|j| !blank(j));
        if blank(&pressed) && judged.is_none() {
            c.no_response += 1;
            continue;
        }
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
        } else if let Some(j) = judged {
            match j.to_ascii_lowercase().as_str() {
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
        if is_simulated {
            c.simulated_fitted += 1;
        }
        c.trials.push((theta, convex));
    }
    Ok(chunks)
}

/// The files' rows together: the same rows in two places counted once, designs kept apart
/// unless `reading` pools them, what was left out summed, and data with nothing to fit
/// refused, saying why. `what` names the data in errors.
fn gather(
    read: Vec<(Vec<String>, Vec<Chunk>)>,
    files: Vec<PathBuf>,
    what: &Path,
    reading: &Reading,
) -> Result<Responses> {
    let columns = read.first().map(|r| r.0.clone()).unwrap_or_default();
    let mut kept: Vec<Chunk> = Vec::new();
    let mut duplicates = Vec::new();
    for c in read.into_iter().flat_map(|r| r.1) {
        let first = (!c.rows.is_empty())
            .then(|| {
                kept.iter()
                    .find(|k| k.source != c.source && k.rows == c.rows)
            })
            .flatten();
        match first {
            Some(k) => duplicates.push(Duplicate {
                participant: k.participant.clone(),
                rows: c.rows.len(),
                kept: k.source.clone(),
                left_out: c.source.clone(),
            }),
            None => kept.push(c),
        }
    }
    let mut designs: Vec<DesignFiles> = Vec::new();
    for c in &kept {
        for h in &c.designs {
            match designs.iter_mut().find(|d| d.design_hash == *h) {
                Some(d) if d.files.contains(&c.source) => {}
                Some(d) => d.files.push(c.source.clone()),
                None => designs.push(DesignFiles {
                    design_hash: h.clone(),
                    files: vec![c.source.clone()],
                }),
            }
        }
    }
    if designs.len() > 1 && !reading.mixed_designs {
        let each: Vec<String> = designs.iter().map(DesignFiles::to_string).collect();
        return Err(Error::Setting(
            Message::text(format!(
                "{}: trials of {} designs (another design_hash): {}; fit each design alone, or \
                 pool them with ",
                what.display(),
                designs.len(),
                each.join("; ")
            ))
            .setting(Setting::MixedDesigns, "mixed designs allowed"),
        ));
    }
    let count = |f: fn(&Chunk) -> usize| kept.iter().map(f).sum::<usize>();
    let mut participants: Vec<(String, Vec<(f64, bool)>)> = Vec::new();
    for c in &kept {
        if c.trials.is_empty() {
            continue;
        }
        match participants.iter_mut().find(|(p, _)| *p == c.participant) {
            Some((_, t)) => t.extend(c.trials.iter().copied()),
            None => participants.push((c.participant.clone(), c.trials.clone())),
        }
    }
    let (simulated_left_out, no_response) =
        (count(|c| c.simulated_left_out), count(|c| c.no_response));
    let simulated_participants = participants
        .iter()
        .filter(|(p, _)| {
            kept.iter()
                .any(|c| c.participant == *p && c.simulated_fitted > 0)
        })
        .count();
    if participants.is_empty() {
        if simulated_left_out > 0 {
            return Err(Error::Setting(
                Message::text(format!(
                    "{}: every trial with a response is simulated ({simulated_left_out} trials \
                     whose 'simulated' column is set: a pilot's, not people's); to fit them \
                     anyway give ",
                    what.display()
                ))
                .setting(Setting::IncludeSimulated, "simulated trials included"),
            ));
        }
        return Err(Error::format(
            what,
            format!("no trial has a response ({no_response} without one: timed out)"),
        ));
    }
    Ok(Responses {
        participants,
        practice_rows: count(|c| c.practice),
        columns,
        other_rows: count(|c| c.other),
        no_response,
        simulated_left_out,
        simulated_fitted: count(|c| c.simulated_fitted),
        simulated_participants,
        duplicates,
        designs,
        files,
    })
}
