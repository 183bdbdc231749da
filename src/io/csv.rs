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
