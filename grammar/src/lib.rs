//! The PSL shot language of dronecine: grammar, syntax tree, semantic pass, diagnostics and
//! formatter.
//!
//! Pipeline: `parser::parse` (pest, line by line) → `ast::File` (typed, spans everywhere) →
//! `resolve::resolve` (every check) → `script::Script` (plain serde data for the compiler).
//! Every stage reports into `Vec<Diagnostic>`; nothing here panics on any input, and all the
//! mistakes of a file come out together. See `psl.pest` for the grammar, `vocab.rs` for the
//! words and the angle conventions, and `docs/language.md` for the language itself.
//!
//! The grammar knows nothing of drones: a script names a drone profile, and the caller says
//! which names exist ([`Options`]).

pub mod ast;
pub mod code;
pub mod format;
pub mod parser;
pub mod reference;
pub mod resolve;
pub mod rules;
pub mod script;
mod syntax;
pub mod vocab;

pub use code::PslCode;
pub use resolve::Options;
pub use script::Script;

use dronecine_diag::Diagnostic;

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
    dronecine_diag::decode_utf8(
        bytes,
        PslCode::InvalidUtf8,
        "save the script as UTF-8 text (a .psl file is plain text, not a binary)",
    )
}
