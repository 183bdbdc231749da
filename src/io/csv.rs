//! CSV text as shadelab writes it (RFC 4180): fields quoted only when they must be.

use crate::error::{Error, Result};
use std::path::Path;

/// A CSV field, quoted when it holds a comma, quote or line break (RFC 4180); quotes inside are
/// doubled.
///
/// ```
/// use shadelab::io::csv_field;
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

/// Splits one CSV record (a line without its line break) into its fields, undoing
/// [`csv_field`]: a quoted field may hold commas and doubled quotes. Fails, saying why, on a
/// quote that is not closed or text after a closing quote.
///
/// ```
/// use shadelab::io::csv_record;
/// assert_eq!(csv_record("3,\"tilt=0,slant=45\",x").unwrap(), ["3", "tilt=0,slant=45", "x"]);
/// assert_eq!(csv_record("a,\"b\"\"c\",").unwrap(), ["a", "b\"c", ""]);
/// assert!(csv_record("a,\"b").is_err());
/// ```
pub fn csv_record(line: &str) -> std::result::Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        let mut field = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next() {
                    Some('"') if chars.peek() == Some(&'"') => {
                        chars.next();
                        field.push('"');
                    }
                    Some('"') => break,
                    Some(c) => field.push(c),
                    None => return Err("a quoted field is not closed".into()),
                }
            }
            match chars.next() {
                Some(',') => fields.push(field),
                None => {
                    fields.push(field);
                    return Ok(fields);
                }
                Some(c) => return Err(format!("'{c}' follows a closing quote")),
            }
        } else {
            loop {
                match chars.next() {
                    Some(',') => break,
                    Some('"') => return Err("a quote inside an unquoted field".into()),
                    Some(c) => field.push(c),
                    None => {
                        fields.push(field);
                        return Ok(fields);
                    }
                }
            }
            fields.push(field);
        }
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
