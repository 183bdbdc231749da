//! CSV text as shadelab writes it (RFC 4180): fields quoted only when they must be.

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

/// The records of CSV text (RFC 4180: quoted fields may hold commas, doubled quotes and line
/// breaks; `\r\n` or `\n` ends a record), each with the line it starts on (1-based). Blank
/// lines are skipped. An error names the line: a quote that is never closed, or text after a
/// closing quote.
///
/// ```
/// use shadelab::io::parse_csv;
/// let rows = parse_csv("a,b\r\n1,\"x, \"\"y\"\"\"\n\n2,z\n").unwrap();
/// assert_eq!(rows[1], (2, vec!["1".to_string(), "x, \"y\"".to_string()]));
/// assert_eq!(rows[2].0, 4);
/// assert!(parse_csv("a\n\"open").unwrap_err().contains("line 2"));
/// ```
pub fn parse_csv(text: &str) -> Result<Vec<(usize, Vec<String>)>, String> {
    let mut rows = Vec::new();
    let mut chars = text.chars().peekable();
    let mut line = 1;
    while chars.peek().is_some() {
        let start = line;
        let mut fields = Vec::new();
        let mut field = String::new();
        let mut quoted_field = false;
        loop {
            match chars.next() {
                None => {
                    fields.push(std::mem::take(&mut field));
                    break;
                }
                Some('"') if field.is_empty() && !quoted_field => {
                    quoted_field = true;
                    loop {
                        match chars.next() {
                            None => {
                                return Err(format!("line {start}: a quoted field is never closed"))
                            }
                            Some('"') if chars.peek() == Some(&'"') => {
                                chars.next();
                                field.push('"');
                            }
                            Some('"') => break,
                            Some(c) => {
                                if c == '\n' {
                                    line += 1;
                                }
                                field.push(c);
                            }
                        }
                    }
                    match chars.peek() {
                        None | Some(',') | Some('\n') | Some('\r') => {}
                        Some(_) => return Err(format!("line {line}: text after a closing quote")),
                    }
                }
                Some(',') => {
                    fields.push(std::mem::take(&mut field));
                    quoted_field = false;
                }
                Some('\r') if chars.peek() == Some(&'\n') => {}
                Some('\n') => {
                    fields.push(std::mem::take(&mut field));
                    line += 1;
                    break;
                }
                Some(c) => field.push(c),
            }
        }
        if !(fields.len() == 1 && fields[0].is_empty() && !quoted_field) {
            rows.push((start, fields));
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

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
