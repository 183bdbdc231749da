//! Display files: shadelab's display JSON, a PsychoPy monitor file or a photometer's CSV, read
//! into a [`Display`] (see docs/display.md).

use crate::display::{Calibration, Display, GammaModel, Quantise, Response};
use crate::error::{Error, Result};
use serde_json::Value;
use std::path::Path;

/// Reads a display file: shadelab's display JSON (see docs/display.md), a PsychoPy
/// monitor file (`~/.psychopy3/monitors/NAME.json`: the gamma grid of the calibration
/// PsychoPy's `Monitor(NAME)` loads, the last by name)
/// or a photometer's CSV (`code,luminance`, 8, 10 or 16 bits by its top code).
pub fn read_display(path: &Path) -> Result<Display> {
    let bytes = super::read_capped(path, super::MAX_TEXT_BYTES)?;
    let text = String::from_utf8(bytes).map_err(|_| Error::format(path, "not UTF-8 text"))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if super::extension(path) == "csv" {
        let rows = read_table(&text).map_err(|m| Error::format(path, m))?;
        let top = rows.last().map(|r| r.0).unwrap_or(0);
        let bits = bits_of_top(top).map_err(|m| Error::format(path, m))?;
        return Display::new(name, bits, Response::Table(rows), Quantise::Plain)
            .map_err(|e| Error::format(path, e.to_string()));
    }
    let value: Value = serde_json::from_str(&text)
        .map_err(|e| Error::format(path, format!("invalid JSON ({e})")))?;
    from_json(path, &name, &value).map_err(|e| match e {
        Error::Invalid(m) => Error::format(path, m),
        other => other,
    })
}

/// The display a JSON value describes, as [`read_display`] reads a file (the Python module's
/// dicts): relative file names in it resolve against `folder`.
pub fn display_from_value(value: &Value, folder: &Path) -> Result<Display> {
    from_json(&folder.join("display.json"), "display", value)
}

/// The bit depth whose top code is `top`.
fn bits_of_top(top: u32) -> std::result::Result<u8, String> {
    match top {
        255 => Ok(8),
        1023 => Ok(10),
        65535 => Ok(16),
        other => Err(format!(
            "the table's last code is {other}; it must be the top code (255, 1023 or 65535)"
        )),
    }
}

/// A photometer's CSV: a header, then `code,luminance` rows.
fn read_table(text: &str) -> std::result::Result<Vec<(u32, f64)>, String> {
    let rows = super::parse_csv(text)?;
    let mut out = Vec::new();
    for (i, (line, fields)) in rows.iter().enumerate() {
        if fields.len() != 2 {
            return Err(format!(
                "line {line}: {} fields; a photometer table has two (code, luminance in cd/m²)",
                fields.len()
            ));
        }
        let code = fields[0].trim().parse::<u32>();
        let lum = fields[1].trim().parse::<f64>();
        match (code, lum) {
            (Ok(c), Ok(l)) if l.is_finite() && l >= 0.0 => out.push((c, l)),
            _ if i == 0 => {} // the header
            _ => {
                return Err(format!(
                    "line {line}: '{}','{}' is not a code and a luminance >= 0",
                    fields[0], fields[1]
                ))
            }
        }
    }
    if out.len() < 2 {
        return Err("a photometer table needs at least two rows (code 0 and the top code)".into());
    }
    Ok(out)
}

/// A display from JSON: a PsychoPy monitor file (calibrations holding a `gammaGrid`) or
/// shadelab's display JSON.
fn from_json(path: &Path, stem: &str, value: &Value) -> Result<Display> {
    let bad = |m: String| Error::invalid(m);
    let Value::Object(map) = value else {
        return Err(bad("a display file is a JSON object".into()));
    };
    // PsychoPy's monitor file: {calibration name: {gammaGrid, linearizeMethod, calibDate, ...}}.
    if map
        .values()
        .any(|v| v.get("gammaGrid").is_some() || v.get("calibDate").is_some())
    {
        return psychopy_monitor(stem, map, None, 8, Quantise::Plain);
    }
    const KEYS: [&str; 12] = [
        "name",
        "bit_depth",
        "quantise",
        "gamma",
        "black_cd_m2",
        "white_cd_m2",
        "b",
        "equation",
        "table",
        "psychopy_monitor",
        "calibration",
        "channel_weights",
    ];
    if let Some(k) = map.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(bad(format!(
            "unknown key '{k}' (valid: {})",
            KEYS.join(", ")
        )));
    }
    let name = map
        .get("name")
        .and_then(Value::as_str)
        .unwrap_or(stem)
        .to_string();
    let bits = match map.get("bit_depth") {
        None => 8,
        Some(v) => match v.as_u64() {
            Some(b @ (8 | 10 | 16)) => b as u8,
            _ => return Err(bad(format!("bit_depth {v} is not 8, 10 or 16"))),
        },
    };
    let quantise = match map.get("quantise").map(|v| v.as_str()) {
        None | Some(Some("plain")) => Quantise::Plain,
        Some(Some("bit-stealing")) => Quantise::BitStealing,
        Some(Some("dither")) => Quantise::Dither,
        Some(_) => {
            return Err(bad(format!(
                "quantise {} is not plain, bit-stealing or dither",
                map["quantise"]
            )))
        }
    };
    let number = |key: &str| -> Result<Option<f64>> {
        match map.get(key) {
            None => Ok(None),
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| bad(format!("{key} {v} is not a number"))),
        }
    };
    let sources = ["gamma", "table", "psychopy_monitor"]
        .iter()
        .filter(|k| map.contains_key(**k))
        .count();
    if sources != 1 {
        return Err(bad(
            "a display says its response once: \"gamma\" (with black_cd_m2, white_cd_m2), \
             \"table\" (a photometer CSV) or \"psychopy_monitor\" (a PsychoPy monitor file)"
                .into(),
        ));
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    let display = if let Some(file) = map.get("psychopy_monitor") {
        let file = file
            .as_str()
            .ok_or_else(|| bad("psychopy_monitor must be a file name".into()))?;
        let monitor_path = folder.join(file);
        let bytes = super::read_capped(&monitor_path, super::MAX_TEXT_BYTES)?;
        let monitor: Value = serde_json::from_slice(&bytes)
            .map_err(|e| Error::format(&monitor_path, format!("invalid JSON ({e})")))?;
        let Value::Object(calibs) = &monitor else {
            return Err(Error::format(&monitor_path, "not a PsychoPy monitor file"));
        };
        let calibration = map.get("calibration").and_then(Value::as_str);
        psychopy_monitor(&name, calibs, calibration, bits, quantise)
            .map_err(|e| Error::format(&monitor_path, e.to_string()))?
    } else if let Some(file) = map.get("table") {
        let file = file
            .as_str()
            .ok_or_else(|| bad("table must be a CSV file name".into()))?;
        let table_path = folder.join(file);
        let bytes = super::read_capped(&table_path, super::MAX_TEXT_BYTES)?;
        let text =
            String::from_utf8(bytes).map_err(|_| Error::format(&table_path, "not UTF-8 text"))?;
        let rows = read_table(&text).map_err(|m| Error::format(&table_path, m))?;
        Display::new(name, bits, Response::Table(rows), quantise)
            .map_err(|e| Error::format(&table_path, e.to_string()))?
    } else {
        let need = |key: &str| -> Result<f64> {
            number(key)?.ok_or_else(|| bad(format!("a gamma model needs {key}")))
        };
        let model = GammaModel {
            equation: match map.get("equation") {
                None => 1,
                Some(v) => v
                    .as_u64()
                    .filter(|e| matches!(e, 1 | 2 | 4))
                    .map(|e| e as u8)
                    .ok_or_else(|| bad(format!("equation {v} is not 1, 2 or 4")))?,
            },
            black: need("black_cd_m2")?,
            white: need("white_cd_m2")?,
            gamma: need("gamma")?,
            b: number("b")?.unwrap_or(0.0),
        };
        Display::new(name, bits, Response::Gamma(model), quantise)?
    };
    match map.get("channel_weights") {
        None => Ok(display),
        Some(v) => {
            let w: Vec<f64> = v
                .as_array()
                .map(|a| a.iter().filter_map(Value::as_f64).collect())
                .unwrap_or_default();
            match w.as_slice() {
                [r, g, b] => display.with_channel_weights([*r, *g, *b]),
                _ => Err(bad(format!("channel_weights {v} is not three numbers"))),
            }
        }
    }
}

/// The display a PsychoPy monitor file describes: the calibration named, else the one
/// PsychoPy's `Monitor(name)` loads (`Monitor.__init__` calls `setCurrent(-1)`: the last of
/// `sorted(calibs)`, by name, whatever its `calibDate`); its `gammaGrid` row 0 (luminance:
/// minLum, maxLum, gamma, a, b, k) and its `linearizeMethod`; the guns' maxLum (rows 1–3)
/// give bit-stealing its channel weights. The display records which calibration it is.
fn psychopy_monitor(
    name: &str,
    calibs: &serde_json::Map<String, Value>,
    wanted: Option<&str>,
    bits: u8,
    quantise: Quantise,
) -> Result<Display> {
    let bad = |m: String| Error::invalid(m);
    // Python sorts str by code point, as Rust orders UTF-8 by bytes.
    let mut all: Vec<String> = calibs.keys().cloned().collect();
    all.sort();
    let listed = || {
        all.iter()
            .map(|n| format!("'{n}'"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (label, calib) = match wanted {
        Some(w) => calibs.get_key_value(w).ok_or_else(|| {
            bad(format!(
                "no calibration '{w}' in the monitor file (it holds {})",
                listed()
            ))
        })?,
        None => all
            .last()
            .and_then(|n| calibs.get_key_value(n))
            .ok_or_else(|| bad("the monitor file holds no calibration".into()))?,
    };
    if calib.get("gammaGrid").is_none() {
        return Err(bad(if wanted.is_none() && all.len() > 1 {
            format!(
                "calibration '{label}', the one PsychoPy's Monitor loads (the last by name), has \
                 no gammaGrid; name one that has as the display's calibration \
                 ({{\"psychopy_monitor\": FILE, \"calibration\": NAME}}; the file holds {})",
                listed()
            )
        } else {
            format!("calibration '{label}' has no gammaGrid")
        }));
    }
    let grid = calib.get("gammaGrid").cloned().unwrap_or(Value::Null);
    // json_tricks writes arrays as {"__ndarray__": [...], "dtype": ..., "shape": ...}.
    let grid = grid.get("__ndarray__").cloned().unwrap_or(grid);
    let rows: Vec<Vec<f64>> = grid
        .as_array()
        .map(|rows| {
            rows.iter()
                .map(|r| {
                    r.as_array()
                        .map(|r| r.iter().filter_map(Value::as_f64).collect())
                        .unwrap_or_default()
                })
                .collect()
        })
        .unwrap_or_default();
    if rows.len() != 4 || rows.iter().any(|r| r.len() < 3) {
        return Err(bad(format!(
            "calibration '{label}': its gammaGrid is not 4 rows of [minLum, maxLum, gamma, a, b, k]"
        )));
    }
    let equation = match calib.get("linearizeMethod").and_then(Value::as_u64) {
        None => 1,
        Some(m @ (1 | 2 | 4)) => m as u8,
        Some(m) => {
            return Err(bad(format!(
                "calibration '{label}': linearizeMethod {m} is not a fitted gamma (1, 2 or 4); \
                 give a photometer table instead"
            )))
        }
    };
    // PsychoPy takes minLum from gun row 1 (calibTools.linearizeLums).
    let model = GammaModel {
        equation,
        black: rows[1][0],
        white: rows[0][1],
        gamma: rows[0][2],
        b: rows[0].get(4).copied().unwrap_or(0.0),
    };
    let display = Display::new(
        format!("{name} ({label})"),
        bits,
        Response::Gamma(model),
        quantise,
    )
    .map_err(|e| bad(format!("calibration '{label}': {e}")))?;
    let display = display.with_calibration(Calibration {
        name: label.clone(),
        named: wanted.is_some(),
        all: all.clone(),
    });
    let guns = [rows[1][1], rows[2][1], rows[3][1]];
    let total: f64 = guns.iter().sum();
    if guns.iter().all(|g| g.is_finite() && *g > 0.0) {
        display.with_channel_weights(guns.map(|g| g / total))
    } else {
        Ok(display)
    }
}
