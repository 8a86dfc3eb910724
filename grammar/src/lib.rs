//! The PSL shot language of dronecine: grammar, syntax tree, semantic pass, diagnostics and
//! formatter.
//!
//! Pipeline: `parser::parse` (pest, line by line) → `ast::File` (typed, spans everywhere) →
//! `resolve::resolve` (every check) → `script::Script` (plain serde data for the compiler).
//! Every stage reports into `Vec<Diagnostic>`; nothing here panics on any input, and all the
//! mistakes of a file come out together. See `psl.pest` for the grammar and `vocab.rs` for
//! the words and the angle conventions of psl.md §3.

pub mod ast;
pub mod diag;
pub mod fast;
pub mod format;
pub mod parser;
pub mod resolve;
pub mod script;
pub mod span;
pub mod suggest;
mod syntax;
pub mod vocab;

pub use diag::{Code, Diagnostic, Severity};
pub use resolve::Options;
pub use script::Script;
pub use span::{LineIndex, Span};

/// The outcome of checking a script.
#[derive(Clone, Debug)]
pub struct Checked {
    /// The resolved script, when no diagnostic is an error.
    pub script: Option<Script>,
    /// Errors and warnings, in source order.
    pub diagnostics: Vec<Diagnostic>,
}

impl Checked {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Parse and resolve a script.
pub fn check(src: &str, opts: &Options<'_>) -> Checked {
    let (file, mut diagnostics) = parser::parse(src);
    let (script, semantic) = resolve::resolve(&file, opts);
    let syntax_failed = diagnostics.iter().any(Diagnostic::is_error);
    diagnostics.extend(semantic);
    diagnostics.sort_by_key(|d| (d.span.start, d.span.end));
    Checked {
        script: if syntax_failed { None } else { script },
        diagnostics,
    }
}

/// The canonical form of a script, or the syntax errors that prevent formatting it.
pub fn format(src: &str) -> Result<String, Vec<Diagnostic>> {
    let (file, diagnostics) = parser::parse(src);
    if diagnostics.iter().any(Diagnostic::is_error) {
        return Err(diagnostics);
    }
    Ok(format::format_file(&file))
}

/// Decode a file's bytes as UTF-8. On failure, returns a display copy of the text (invalid
/// bytes replaced by U+FFFD) and a diagnostic for each invalid sequence (at most ten), with
/// spans into that copy.
pub fn decode(bytes: &[u8]) -> Result<&str, (String, Vec<Diagnostic>)> {
    if let Ok(s) = std::str::from_utf8(bytes) {
        return Ok(s);
    }
    let mut text = String::with_capacity(bytes.len() + 16);
    let mut diagnostics = Vec::new();
    let mut invalid = 0usize;
    for chunk in bytes.utf8_chunks() {
        text.push_str(chunk.valid());
        if !chunk.invalid().is_empty() {
            invalid += 1;
            let at = text.len();
            text.push('\u{fffd}');
            if diagnostics.len() < 10 {
                let hex: Vec<String> = chunk
                    .invalid()
                    .iter()
                    .map(|b| format!("0x{b:02X}"))
                    .collect();
                diagnostics.push(
                    Diagnostic::error(
                        Code::InvalidUtf8,
                        Span::new(at, at + '\u{fffd}'.len_utf8()),
                        format!("the file is not UTF-8 text: invalid byte {}", hex.join(" ")),
                    )
                    .with_label("not UTF-8")
                    .with_help(
                        "save the script as UTF-8 text (a .psl file is plain text, not a binary)",
                    ),
                );
            }
        }
    }
    if invalid > 10 {
        if let Some(last) = diagnostics.last_mut() {
            last.message
                .push_str(&format!(" (and {} more invalid sequences)", invalid - 10));
        }
    }
    Err((text, diagnostics))
}
