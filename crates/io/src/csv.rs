//! CSV text as shadelab writes it (RFC 4180): fields quoted only when they must be.

use crate::error::{Error, Result};
use std::path::Path;

/// A CSV field, quoted when it holds a comma, quote or line break (RFC 4180); quotes inside are
/// doubled.
///
/// ```
/// use shadelab_io::csv_field;
/// assert_eq!(csv_field("bump r1c1"), "bump r1c1");
/// assert_eq!(csv_field("tilt=0,slant=45"), "\"tilt=0,slant=45\"");
/// assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
/// ```
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// Reads one record from `chars`: its fields, and whether the first field was quoted (so
/// that a blank line, one empty unquoted field, can be told apart). `line` counts the line
/// breaks passed, also those inside quoted fields. `None` at the end of the text.
fn next_record(
    chars: &mut std::iter::Peekable<std::str::Chars<'_>>,
    line: &mut usize,
    delimiter: char,
) -> std::result::Result<Option<(Vec<String>, bool)>, String> {
    if chars.peek().is_none() {
        return Ok(None);
    }
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut any_quoted = false;
    loop {
        match chars.next() {
            None => {
                fields.push(field);
                break;
            }
            Some('"') if field.is_empty() && !quoted => {
                quoted = true;
                any_quoted = true;
                loop {
                    match chars.next() {
                        None => return Err("a quoted field is never closed".into()),
                        Some('"') if chars.peek() == Some(&'"') => {
                            chars.next();
                            field.push('"');
                        }
                        Some('"') => break,
                        Some(c) => {
                            if c == '\n' {
                                *line += 1;
                            }
                            field.push(c);
                        }
                    }
                }
                match chars.peek() {
                    None | Some('\n') | Some('\r') => {}
                    Some(&c) if c == delimiter => {}
                    Some(c) => return Err(format!("'{c}' follows a closing quote")),
                }
            }
            Some('"') => return Err("a quote inside an unquoted field".into()),
            Some(c) if c == delimiter => {
                fields.push(std::mem::take(&mut field));
                quoted = false;
            }
            Some('\r') if chars.peek() == Some(&'\n') => {}
            Some('\n') => {
                fields.push(field);
                *line += 1;
                break;
            }
            Some(c) => field.push(c),
        }
    }
    Ok(Some((fields, any_quoted)))
}

/// The records of CSV text (RFC 4180: quoted fields may hold commas, doubled quotes and line
/// breaks; `\r\n` or `\n` ends a record), each with the line it starts on (1-based). Blank
/// lines are skipped. An error names the line: a quote that is never closed, a quote inside
/// an unquoted field, or text after a closing quote.
///
/// ```
/// use shadelab_io::parse_csv;
/// let rows = parse_csv("a,b\r\n1,\"x, \"\"y\"\"\"\n\n2,z\n").unwrap();
/// assert_eq!(rows[1], (2, vec!["1".to_string(), "x, \"y\"".to_string()]));
/// assert_eq!(rows[2].0, 4);
/// assert!(parse_csv("a\n\"open").unwrap_err().contains("line 2"));
/// ```
pub fn parse_csv(text: &str) -> std::result::Result<Vec<(usize, Vec<String>)>, String> {
    parse_csv_with(text, ',')
}

/// [`parse_csv`] with fields separated by `delimiter` (`;` in the CSV a European Excel saves).
pub fn parse_csv_with(
    text: &str,
    delimiter: char,
) -> std::result::Result<Vec<(usize, Vec<String>)>, String> {
    let mut rows = Vec::new();
    let mut chars = text.chars().peekable();
    let mut line = 1;
    loop {
        let start = line;
        match next_record(&mut chars, &mut line, delimiter)
            .map_err(|why| format!("line {start}: {why}"))?
        {
            None => return Ok(rows),
            Some((fields, quoted)) => {
                if !(fields.len() == 1 && fields[0].is_empty() && !quoted) {
                    rows.push((start, fields));
                }
            }
        }
    }
}

/// Splits one CSV record (a line without its line break) into its fields, undoing
/// [`csv_field`]: a quoted field may hold commas and doubled quotes. Fails, saying why, on a
/// quote that is not closed, a quote inside an unquoted field or text after a closing quote.
///
/// ```
/// use shadelab_io::csv_record;
/// assert_eq!(csv_record("3,\"tilt=0,slant=45\",x").unwrap(), ["3", "tilt=0,slant=45", "x"]);
/// assert_eq!(csv_record("a,\"b\"\"c\",").unwrap(), ["a", "b\"c", ""]);
/// assert!(csv_record("a,\"b").is_err());
/// ```
pub fn csv_record(line: &str) -> std::result::Result<Vec<String>, String> {
    let mut chars = line.chars().peekable();
    let mut lines = 1;
    match next_record(&mut chars, &mut lines, ',')? {
        None => Ok(vec![String::new()]),
        Some(_) if chars.peek().is_some() => Err("a line break inside the record".into()),
        Some((fields, _)) => Ok(fields),
    }
}

/// The field separator of a table's header line: `;` when the line has a semicolon and no
/// comma outside quotes (the CSV a European Excel saves, whose decimal separator is the
/// comma), else `,`.
///
/// ```
/// use shadelab_io::csv_delimiter;
/// assert_eq!(csv_delimiter("\"a;b\",c"), ',');
/// assert_eq!(csv_delimiter("rotation_deg;response;\"a,b\""), ';');
/// ```
pub fn csv_delimiter(header: &str) -> char {
    let (mut commas, mut semicolons, mut quoted) = (0, 0, false);
    for c in header.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => commas += 1,
            ';' if !quoted => semicolons += 1,
            _ => {}
        }
    }
    if semicolons > 0 && commas == 0 {
        ';'
    } else {
        ','
    }
}

/// Refuses CSV text that holds a NaN or an infinity in any field, naming the line and the
/// column (from the header line): shadelab never writes one into a file, so finding one is an
/// internal error, reported instead of written. Records that do not parse are left alone.
pub(crate) fn check_csv_finite(path: &Path, text: &str) -> Result<()> {
    let mut lines = text.lines();
    let header = lines.next().map(csv_record).and_then(|r| r.ok());
    for (n, line) in lines.enumerate() {
        let Ok(fields) = csv_record(line) else {
            continue;
        };
        for (k, field) in fields.iter().enumerate() {
            let value = field.trim().parse::<f64>();
            if value.is_ok_and(|v| !v.is_finite()) {
                let column = header
                    .as_ref()
                    .and_then(|h| h.get(k))
                    .map_or_else(|| format!("{}", k + 1), |c| format!("'{c}'"));
                return Err(Error::Compute(format!(
                    "internal error: {} line {}, column {column}, would be '{field}': shadelab \
                     writes no NaN or infinity into a file (please report this)",
                    path.display(),
                    n + 2
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip_and_non_finite_numbers_are_refused() {
        let fields = ["1", "tilt=0,slant=45", "a\"b", "", "two\nlines?"];
        let line: Vec<String> = fields[..4].iter().map(|f| csv_field(f)).collect();
        assert_eq!(csv_record(&line.join(",")).unwrap(), fields[..4]);
        for bad in ["\"open", "\"a\"b", "a\"b"] {
            assert!(csv_record(bad).is_err(), "{bad}");
        }
        let p = Path::new("out/t.csv");
        assert!(check_csv_finite(p, "a,b\n1,2.5\n\"NaN stimulus\",3\n").is_ok());
        for (text, column) in [
            ("a,b\n1,2\n3,NaN\n", "'b'"),
            ("a,b\n1,-inf\n", "'b'"),
            ("a\n1,inf\n", "2"),
        ] {
            let e = check_csv_finite(p, text).unwrap_err().to_string();
            assert!(
                e.starts_with("internal error: out/t.csv line ") && e.contains(column),
                "{e}"
            );
        }
    }

    #[test]
    fn fields_are_quoted_when_needed() {
        assert_eq!(csv_field("bump r1c1"), "bump r1c1");
        assert_eq!(
            csv_field("light=tilt=0,slant=45"),
            "\"light=tilt=0,slant=45\""
        );
        assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
    }
}
