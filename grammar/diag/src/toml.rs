//! Small pieces shared by the readers of the project's TOML files (the drone profile, the
//! mocap rig): spans into the text, what a value is in words, and a TOML
//! error's place, so that each file's diagnostics read alike.

use crate::suggest;
use crate::Span;
use toml::de::DeValue;

/// A span from a byte range of the parsed text (never reversed).
pub fn span(r: std::ops::Range<usize>) -> Span {
    Span::new(r.start, r.end.max(r.start))
}

/// An empty span just after the last non-blank text of the file: where a missing key goes.
pub fn eof_span(src: &str) -> Span {
    let end = src.trim_end().len();
    Span::new(end, end)
}

/// What a value is, for "must be a number, found …": `the text "12 deg"`, `a list`, ….
pub fn kind_of(v: &DeValue<'_>) -> String {
    match v {
        DeValue::String(s) => format!("the text \"{}\"", suggest::shorten(s)),
        DeValue::Integer(_) => "an integer".to_string(),
        DeValue::Float(_) => "a number".to_string(),
        DeValue::Boolean(b) => format!("`{b}`"),
        DeValue::Datetime(_) => "a date".to_string(),
        DeValue::Array(_) => "a list".to_string(),
        DeValue::Table(_) => "a table".to_string(),
    }
}

/// Where a TOML error points in `src` (its range shifted by `offset` when the error comes
/// from parsing a piece of `src` that starts there), on character boundaries; the end of the
/// text when the error has no place.
pub fn error_span(src: &str, e: &toml::de::Error, offset: usize) -> Span {
    match e.span() {
        Some(r) if r.start + offset <= src.len() => {
            let mut start = r.start + offset;
            let mut end = (r.end + offset).clamp(start, src.len());
            while !src.is_char_boundary(start) {
                start -= 1;
            }
            while !src.is_char_boundary(end) {
                end += 1;
            }
            Span::new(start, end)
        }
        _ => eof_span(src),
    }
}

/// A number as TOML wrote it (`_` separators, hexadecimal, octal and binary integers
/// included), or `None` for a value that is not a number.
pub fn number(v: &DeValue<'_>) -> Option<f64> {
    match v {
        DeValue::Integer(i) => {
            let digits = i.as_str().replace('_', "");
            i64::from_str_radix(&digits, i.radix())
                .ok()
                .map(|n| n as f64)
                .or_else(|| digits.parse::<f64>().ok())
        }
        DeValue::Float(f) => f.as_str().replace('_', "").parse::<f64>().ok(),
        _ => None,
    }
}
