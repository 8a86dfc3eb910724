//! Diagnostics for the files a person writes (a script, a drone profile, a rig file): a
//! stable code, a span into the text, a message in the user's terms, a help line with the fix.
//!
//! A [`Diagnostic`] is plain data; [`render`] turns a file's diagnostics into the text a person
//! reads (miette's graphical report, quoting the source) and [`to_json`] into the records a
//! tool reads. Each crate owns its codes, declared with [`codes!`] under its own namespace
//! (`psl::`, `profile::`, `compile::`, `rig::`, `preflight::`). Codes are a public contract:
//! never rename one.

use std::fmt;
use std::sync::Arc;

use serde::Serialize;

pub mod docs;
pub mod span;
pub mod suggest;
#[cfg(feature = "toml")]
pub mod toml;

pub use span::{LineIndex, Span};

/// A stable diagnostic code: its name (`psl::syntax`) and one sentence on what it means.
/// Two codes are the same code when their names are. Codes sort in the order their crate
/// declares them (diagnostics at one place are listed in that order).
#[derive(Clone, Copy, Debug)]
pub struct Code {
    name: &'static str,
    explain: &'static str,
    index: u16,
}

impl Code {
    /// A code named `name` (`namespace::snake_case`), meaning `explain`, declared `index`-th
    /// in its crate's list.
    pub const fn new(name: &'static str, explain: &'static str, index: u16) -> Code {
        Code {
            name,
            explain,
            index,
        }
    }

    pub fn as_str(self) -> &'static str {
        self.name
    }

    /// One sentence on what the code means.
    pub fn explain(self) -> &'static str {
        self.explain
    }

    /// The part before `::`: which crate's code it is.
    pub fn namespace(self) -> &'static str {
        self.name.split("::").next().unwrap_or(self.name)
    }
}

impl PartialEq for Code {
    fn eq(&self, other: &Code) -> bool {
        self.name == other.name
    }
}

impl Eq for Code {}

impl std::hash::Hash for Code {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        self.name.hash(h);
    }
}

impl PartialOrd for Code {
    fn partial_cmp(&self, other: &Code) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Code {
    fn cmp(&self, other: &Code) -> std::cmp::Ordering {
        (self.index, self.name).cmp(&(other.index, other.name))
    }
}

/// Declares a crate's diagnostic codes: an enum with one variant per code, its `ALL` list,
/// and the conversion into [`Code`] (which a [`Diagnostic`] holds, and compares equal to the
/// variant).
///
/// ```
/// dronecine_diag::codes! {
///     /// The example's codes.
///     pub enum ExampleCode {
///         Oops => "example::oops": "Something went wrong.",
///     }
/// }
/// let code: dronecine_diag::Code = ExampleCode::Oops.into();
/// assert_eq!(code.as_str(), "example::oops");
/// assert!(code == ExampleCode::Oops);
/// ```
#[macro_export]
macro_rules! codes {
    ($(#[$meta:meta])* $vis:vis enum $name:ident {
        $($variant:ident => $code:literal: $doc:literal,)*
    }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        $vis enum $name {
            $(#[doc = $doc] $variant,)*
        }

        impl $name {
            /// Every code, in the order declared.
            pub const ALL: &'static [$name] = &[$($name::$variant,)*];

            /// The code a diagnostic carries.
            pub const fn code(self) -> $crate::Code {
                match self {
                    $($name::$variant => $crate::Code::new($code, $doc, self as u16),)*
                }
            }

            pub fn as_str(self) -> &'static str {
                self.code().as_str()
            }

            /// One sentence on what the code means.
            pub fn explain(self) -> &'static str {
                self.code().explain()
            }
        }

        impl ::core::convert::From<$name> for $crate::Code {
            fn from(c: $name) -> $crate::Code {
                c.code()
            }
        }

        impl ::core::cmp::PartialEq<$name> for $crate::Code {
            fn eq(&self, other: &$name) -> bool {
                *self == other.code()
            }
        }

        impl ::core::fmt::Display for $name {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                f.write_str(self.as_str())
            }
        }
    };
}

/// The command that prints what `code` means, with an example and the fix (its entry in
/// `docs/diagnostics.md`): `dronecine explain psl::unknown_actor`.
pub fn explain_command(code: Code) -> String {
    format!("dronecine explain {code}")
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for Code {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
}

/// A second place a diagnostic points at ("first declared here").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Related {
    pub span: Span,
    pub message: String,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnostic {
    pub code: Code,
    pub severity: Severity,
    pub message: String,
    pub span: Span,
    /// Short text under the span; the message is used when absent.
    pub label: Option<String>,
    pub help: Option<String>,
    pub related: Vec<Related>,
}

impl Diagnostic {
    pub fn error(code: impl Into<Code>, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            code: code.into(),
            severity: Severity::Error,
            message: message.into(),
            span,
            label: None,
            help: None,
            related: Vec::new(),
        }
    }

    pub fn warning(code: impl Into<Code>, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, span, message)
        }
    }

    pub fn with_label(mut self, label: impl Into<String>) -> Diagnostic {
        self.label = Some(label.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Diagnostic {
        self.help = Some(help.into());
        self
    }

    pub fn with_related(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.related.push(Related {
            span,
            message: message.into(),
        });
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// Decode a file's bytes as UTF-8. On failure, returns a display copy of the text (invalid
/// bytes replaced by U+FFFD) and a diagnostic for each invalid sequence (at most ten), with
/// spans into that copy, each with `code` and `help`.
pub fn decode_utf8<'a>(
    bytes: &'a [u8],
    code: impl Into<Code>,
    help: &str,
) -> Result<&'a str, (String, Vec<Diagnostic>)> {
    let code = code.into();
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
                        code,
                        Span::new(at, at + '\u{fffd}'.len_utf8()),
                        format!("the file is not UTF-8 text: invalid byte {}", hex.join(" ")),
                    )
                    .with_label("not UTF-8")
                    .with_help(help),
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

/// One diagnostic as a tool reads it: 1-based lines and columns (columns count characters).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JsonDiagnostic {
    pub file: String,
    pub code: &'static str,
    pub severity: Severity,
    pub message: String,
    pub line: usize,
    pub column: usize,
    pub end_line: usize,
    pub end_column: usize,
    pub help: Option<String>,
    /// The command that explains the code ([`explain_command`]).
    pub explain: String,
}

pub fn to_json(file: &str, src: &str, diagnostics: &[Diagnostic]) -> Vec<JsonDiagnostic> {
    let index = LineIndex::new(src);
    diagnostics
        .iter()
        .map(|d| {
            let place = |offset: usize| match d.span.is_placed() {
                true => index.line_col(src, offset),
                false => (0, 0),
            };
            let (line, column) = place(d.span.start);
            let (end_line, end_column) = place(d.span.end);
            JsonDiagnostic {
                file: file.to_string(),
                code: d.code.as_str(),
                severity: d.severity,
                message: d.message.clone(),
                line,
                column,
                end_line,
                end_column,
                help: d.help.clone(),
                explain: explain_command(d.code),
            }
        })
        .collect()
}

/// Lines longer than this are shown as a window around the span, not whole.
const MAX_SHOWN_LINE: usize = 400;

/// How many of one file's diagnostics [`render`] quotes in full; one line after them counts
/// the rest. A file with thousands of mistakes is fixed from its first ones, and a screen of
/// quotes is all a person reads.
pub const MAX_RENDERED: usize = 100;

/// Render diagnostics the way a person reads them: message, code, the quoted source with the
/// span underlined, the help line, and the command that explains the code
/// ([`explain_command`]). Plain text (no colour) unless `color` is set. The first
/// [`MAX_RENDERED`] are rendered, in the order given; a last line counts the others.
pub fn render(
    file: &str,
    src: &str,
    diagnostics: &[Diagnostic],
    color: bool,
    width: usize,
) -> String {
    render_listed(file, src, diagnostics, color, width, None)
}

/// [`render`], whose line counting the diagnostics not shown names `lister`, a command that
/// lists every one (`dronecine check --format json FILE`).
pub fn render_listed(
    file: &str,
    src: &str,
    diagnostics: &[Diagnostic],
    color: bool,
    width: usize,
    lister: Option<&str>,
) -> String {
    let theme = if color {
        miette::GraphicalTheme::unicode()
    } else {
        miette::GraphicalTheme::unicode_nocolor()
    };
    let handler = miette::GraphicalReportHandler::new_themed(theme)
        .with_width(width)
        .with_word_splitter(textwrap::WordSplitter::NoHyphenation)
        .with_context_lines(1);
    let shown = Lines::new(Arc::new(display_safe(src)));
    let index = LineIndex::new(src);
    let (rendered, rest) = diagnostics.split_at(diagnostics.len().min(MAX_RENDERED));
    let mut out = String::new();
    for d in rendered {
        let report = windowed(file, &shown, &index, d);
        if handler.render_report(&mut out, &report).is_err() {
            out.push_str(&format!("{}: {} [{}]\n", file, d.message, d.code));
        }
        out.push_str(&format!("  more: `{}`\n", explain_command(d.code)));
    }
    if !rest.is_empty() {
        out.push_str(&not_shown(file, rest, lister));
    }
    out
}

/// The line after the rendered diagnostics that counts the others, by severity:
/// "… 49900 more errors and 1 more warning in `x.psl` not shown", then what lists them.
fn not_shown(file: &str, rest: &[Diagnostic], lister: Option<&str>) -> String {
    let errors = rest.iter().filter(|d| d.is_error()).count();
    let counts: Vec<String> = [(errors, "error"), (rest.len() - errors, "warning")]
        .into_iter()
        .filter(|&(n, _)| n > 0)
        .map(|(n, what)| format!("{n} more {what}{}", if n == 1 { "" } else { "s" }))
        .collect();
    let mut line = format!("… {} in `{file}` not shown", counts.join(" and "));
    if let Some(lister) = lister {
        line.push_str(&format!("; `{lister}` lists every one"));
    }
    line.push('\n');
    line
}

/// A text with its line starts, the source miette quotes. miette's own reading of a text
/// walks it from its first byte to the span; this one starts a few lines before the span
/// (found in the line starts), so that a diagnostic costs what its own lines cost, not what
/// the text before it does.
#[derive(Clone)]
struct Lines {
    text: Arc<String>,
    /// Where each line starts, with miette's line breaks: `\n`, `\r\n` and a lone `\r`.
    starts: Arc<Vec<usize>>,
}

impl Lines {
    fn new(text: Arc<String>) -> Lines {
        let mut starts = vec![0];
        let mut bytes = text.bytes().enumerate().peekable();
        while let Some((i, b)) = bytes.next() {
            let next = match b {
                b'\r' if bytes.next_if(|&(_, n)| n == b'\n').is_some() => i + 2,
                b'\r' | b'\n' => i + 1,
                _ => continue,
            };
            starts.push(next);
        }
        Lines {
            text,
            starts: Arc::new(starts),
        }
    }
}

impl miette::SourceCode for Lines {
    /// miette's reading of the text from the start of a line above the span's context: what
    /// it reads there is what it reads from the text's first byte (the same bytes, the same
    /// lines kept for context), with offsets and line numbers shifted by what is skipped.
    fn read_span<'a>(
        &'a self,
        span: &miette::SourceSpan,
        before: usize,
        after: usize,
    ) -> Result<Box<dyn miette::SpanContents<'a> + 'a>, miette::MietteError> {
        let line = self.starts.partition_point(|&s| s <= span.offset()) - 1;
        // One line more than the context: an empty span at the very start of what miette
        // reads is read as ending there, not as the line it starts.
        let first = line.saturating_sub(before + 1);
        let base = self.starts[first];
        let local = miette::SourceSpan::new((span.offset() - base).into(), span.len());
        let read =
            <str as miette::SourceCode>::read_span(&self.text[base..], &local, before, after)?;
        let at = miette::SourceSpan::new((read.span().offset() + base).into(), read.span().len());
        Ok(Box::new(miette::MietteSpanContents::new(
            read.data(),
            at,
            read.line() + first,
            read.column(),
            read.line_count() + first,
        )))
    }
}

/// A diagnostic with its source, as miette wants it.
struct Report {
    diagnostic: Diagnostic,
    source: miette::NamedSource<Lines>,
}

impl fmt::Debug for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.diagnostic, f)
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.diagnostic.message)
    }
}

impl std::error::Error for Report {}

impl miette::Diagnostic for Report {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        Some(Box::new(self.diagnostic.code.as_str()))
    }

    fn severity(&self) -> Option<miette::Severity> {
        Some(match self.diagnostic.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        })
    }

    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.diagnostic
            .help
            .as_ref()
            .map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.diagnostic
            .span
            .is_placed()
            .then_some(&self.source as &dyn miette::SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let d = &self.diagnostic;
        if !d.span.is_placed() {
            return None;
        }
        let main = miette::LabeledSpan::new_primary_with_span(
            Some(d.label.clone().unwrap_or_else(|| d.message.clone())),
            (d.span.start, d.span.len()),
        );
        let rest = d.related.iter().map(|r| {
            miette::LabeledSpan::new_with_span(
                Some(r.message.clone()),
                (r.span.start, r.span.len()),
            )
        });
        Some(Box::new(std::iter::once(main).chain(rest)))
    }
}

/// Build the report for one diagnostic. Spans on a very long line are shown in a window cut
/// out of that line (the file name then carries the true line and column).
fn windowed(file: &str, shown: &Lines, index: &LineIndex, d: &Diagnostic) -> Report {
    let src = shown.text.as_str();
    if !d.span.is_placed() {
        return Report {
            diagnostic: d.clone(),
            source: miette::NamedSource::new(file, shown.clone()),
        };
    }
    let (line, col) = index.line_col(src, d.span.start);
    let line_span = index.line_span(src, line);
    let related_elsewhere = d
        .related
        .iter()
        .any(|r| r.span.start < line_span.start || r.span.end > line_span.end);
    if line_span.len() <= MAX_SHOWN_LINE || related_elsewhere {
        return Report {
            diagnostic: d.clone(),
            source: miette::NamedSource::new(file, shown.clone()),
        };
    }
    let lo = floor_char(src, d.span.start.saturating_sub(60).max(line_span.start));
    let hi = ceil_char(
        src,
        (d.span.start + 60)
            .max(d.span.end.min(d.span.start + 120))
            .min(line_span.end),
    );
    let prefix = if lo > line_span.start { "…" } else { "" };
    let suffix = if hi < line_span.end { "…" } else { "" };
    let text = format!("{prefix}{}{suffix}", &src[lo..hi]);
    let shift = |o: usize| o.clamp(lo, hi) - lo + prefix.len();
    let mut diagnostic = d.clone();
    diagnostic.span = Span::new(shift(d.span.start), shift(d.span.end.min(hi)));
    diagnostic.related.clear();
    Report {
        diagnostic,
        source: miette::NamedSource::new(
            format!("{file}:{line}:{col}"),
            Lines::new(Arc::new(text)),
        ),
    }
}

fn floor_char(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn ceil_char(s: &str, mut i: usize) -> usize {
    while i < s.len() && !s.is_char_boundary(i) {
        i += 1;
    }
    i
}

/// Replace control characters (which would drive the terminal) by printable ones of the same
/// byte length, so that spans keep pointing at the same text.
fn display_safe(src: &str) -> String {
    src.chars()
        .map(|c| match c {
            '\n' | '\t' => c,
            '\r' => ' ',
            c if (c as u32) < 0x20 || c as u32 == 0x7f => '?',
            c if (0x80..0xa0).contains(&(c as u32)) => '¿',
            c => c,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    crate::codes! {
        enum TestCode {
            First => "test::first": "The first.",
            Second => "test::second": "The second.",
        }
    }

    #[test]
    fn a_crates_codes_convert_and_compare_by_name() {
        assert_eq!(TestCode::ALL, &[TestCode::First, TestCode::Second]);
        let c: Code = TestCode::Second.into();
        assert_eq!((c.as_str(), c.explain()), ("test::second", "The second."));
        assert_eq!(c.namespace(), "test");
        assert_eq!(TestCode::First.explain(), "The first.");
        assert!(c == TestCode::Second && c != TestCode::First);
        assert_eq!(c, Code::new("test::second", "another sentence", 7));
        assert!(Code::from(TestCode::First) < c, "in the order declared");
        let d = Diagnostic::warning(TestCode::First, Span::new(0, 1), "m");
        assert!(d.code == TestCode::First && !d.is_error());
        assert_eq!(serde_json::to_string(&d.code).unwrap(), "\"test::first\"");
    }

    #[test]
    fn display_safe_keeps_byte_offsets() {
        let s = "a\u{0}b\u{1b}[31m\u{85}c";
        assert_eq!(display_safe(s).len(), s.len());
        assert!(!display_safe(s).contains('\u{1b}'));
    }

    #[test]
    fn a_diagnostic_without_a_place_is_rendered_without_a_quote() {
        let d = Diagnostic::error(TestCode::Second, Span::NOWHERE, "the battery is flat")
            .with_help("charge it");
        let out = render(
            "x.psl",
            "stage 8m x 6m x 3m\n",
            std::slice::from_ref(&d),
            false,
            100,
        );
        assert!(
            out.contains("the battery is flat") && out.contains("charge it"),
            "{out}"
        );
        assert!(
            out.ends_with("\n  more: `dronecine explain test::second`\n"),
            "{out}"
        );
        assert!(!out.contains("stage"), "{out}");
        let json = to_json("x.psl", "stage 8m x 6m x 3m\n", &[d]);
        assert_eq!((json[0].line, json[0].column), (0, 0));
        assert_eq!(json[0].explain, "dronecine explain test::second");
    }

    #[test]
    fn lines_read_what_miette_reads_from_the_whole_text() {
        use miette::SourceCode;
        let texts = [
            "",
            "a",
            "\n",
            "ab\ncd\n",
            "one\ntwo\n\n\nfive\nsix",
            "x\r\ny\rz\n\r\n\rlast",
            "é\nßx\n\n日本\n",
        ];
        for text in texts {
            let lines = Lines::new(Arc::new(text.to_string()));
            for start in 0..=text.len() {
                for len in 0..=text.len() - start {
                    for (before, after) in [(0, 0), (1, 1), (2, 0), (0, 2), (3, 3)] {
                        let span = miette::SourceSpan::new(start.into(), len);
                        let whole = text.read_span(&span, before, after);
                        let read = lines.read_span(&span, before, after);
                        let at = format!("{text:?} at {start}+{len}, context {before}/{after}");
                        match (whole, read) {
                            (Ok(w), Ok(r)) => assert_eq!(
                                (w.data(), w.span(), w.line(), w.column(), w.line_count()),
                                (r.data(), r.span(), r.line(), r.column(), r.line_count()),
                                "{at}"
                            ),
                            (Err(_), Err(_)) => {}
                            (w, r) => panic!("{at}: {:?} / {:?}", w.is_ok(), r.is_ok()),
                        }
                    }
                }
            }
        }
    }

    /// A script of `n` lines, each with a diagnostic: errors, and a warning every `warn_every`.
    fn numbered(n: usize, warn_every: usize) -> (String, Vec<Diagnostic>) {
        let mut src = String::new();
        let mut diagnostics = Vec::new();
        for i in 0..n {
            let at = src.len();
            src.push_str(&format!("MS on Nobody{i} for 4s\n"));
            let span = Span::new(at + 6, at + 12 + i.to_string().len());
            diagnostics.push(match i % warn_every == warn_every - 1 {
                true => Diagnostic::warning(TestCode::Second, span, format!("warning {i}")),
                false => Diagnostic::error(TestCode::First, span, format!("error {i}")),
            });
        }
        (src, diagnostics)
    }

    #[test]
    fn many_diagnostics_render_the_first_ones_and_count_the_rest() {
        let (src, diagnostics) = numbered(250, 5);
        let out = render_listed(
            "f.psl",
            &src,
            &diagnostics,
            false,
            100,
            Some("dronecine check --format json f.psl"),
        );
        let quoted = out.lines().filter(|l| l.starts_with("test::")).count();
        assert_eq!(quoted, MAX_RENDERED, "{out}");
        assert!(
            out.contains("× error 98") && out.contains("⚠ warning 99"),
            "{out}"
        );
        assert!(!out.contains("error 100"), "{out}");
        // Of the 150 left out (lines 101 to 250), every fifth is a warning.
        assert!(
            out.ends_with(
                "\n… 120 more errors and 30 more warnings in `f.psl` not shown; \
                 `dronecine check --format json f.psl` lists every one\n"
            ),
            "{out}"
        );
        let out = render("f.psl", &src, &diagnostics[..MAX_RENDERED + 1], false, 100);
        assert!(
            out.ends_with("\n… 1 more error in `f.psl` not shown\n"),
            "{out}"
        );
        let out = render("f.psl", &src, &diagnostics[..MAX_RENDERED], false, 100);
        assert!(!out.contains("not shown"), "{out}");
        let (src, diagnostics) = numbered(MAX_RENDERED + 2, 1);
        let out = render("f.psl", &src, &diagnostics, false, 100);
        assert!(
            out.ends_with("\n… 2 more warnings in `f.psl` not shown\n"),
            "{out}"
        );
    }

    #[test]
    fn a_diagnostic_deep_in_a_file_is_quoted_with_its_line_numbers() {
        let (src, diagnostics) = numbered(50_000, 7);
        let out = render("f.psl", &src, &diagnostics[49_990..49_991], false, 100);
        let expected = "test::first

  × error 49990
       ╭─[f.psl:49991:7]
 49990 │ MS on Nobody49989 for 4s
 49991 │ MS on Nobody49990 for 4s
       ·       ─────┬─────
       ·            ╰── error 49990
 49992 │ MS on Nobody49991 for 4s
       ╰────
  more: `dronecine explain test::first`
";
        assert_eq!(out, expected);
    }

    #[test]
    fn long_lines_render_as_a_window() {
        let mut src = "x".repeat(100_000);
        src.push_str(" oops");
        let d = Diagnostic::error(TestCode::First, Span::new(100_001, 100_005), "bad");
        let out = render("f.psl", &src, &[d], false, 100);
        assert!(out.len() < 2_000, "rendered {} bytes", out.len());
        assert!(out.contains("oops"));
        assert!(out.contains("f.psl:1:100002"));
    }
}
