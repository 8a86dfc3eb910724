//! Diagnostics: stable codes, spans, messages in the user's terms, a help line with the fix.
//!
//! A `Diagnostic` is plain data; `render` turns a file's diagnostics into the text a person
//! reads (miette's graphical report, quoting the source) and `to_json` into the records a
//! tool reads. Codes are a public contract: never rename one, add new ones at the end.

use std::fmt;
use std::sync::Arc;

use serde::Serialize;

use crate::span::{LineIndex, Span};

macro_rules! codes {
    ($($variant:ident => $code:literal: $doc:literal,)*) => {
        /// Stable diagnostic codes.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Code {
            $(#[doc = $doc] $variant,)*
        }

        impl Code {
            pub const ALL: &'static [Code] = &[$(Code::$variant,)*];

            pub fn as_str(self) -> &'static str {
                match self { $(Code::$variant => $code,)* }
            }

            /// One sentence on what the code means.
            pub fn explain(self) -> &'static str {
                match self { $(Code::$variant => $doc,)* }
            }
        }
    };
}

codes! {
    Syntax => "psl::syntax": "The line does not follow the grammar of PSL.",
    KeywordAsName => "psl::keyword_as_name": "A keyword (a size, a profile, `on`, `to`, …) stands where a name is needed.",
    UnitSpace => "psl::unit_space": "A unit is separated from its number by a space.",
    MissingUnit => "psl::missing_unit": "A number needs a unit (`m`, `s` or `deg`).",
    WrongUnit => "psl::wrong_unit": "A number has a unit other than the one this place needs.",
    OutOfRange => "psl::out_of_range": "A number is not finite or lies outside the range that makes sense here.",
    NonPositiveDuration => "psl::nonpositive_duration": "A duration is zero or negative.",
    MissingDuration => "psl::missing_duration": "A shot or movement has no duration.",
    DurationKeyword => "psl::duration_keyword": "`for` holds a composition, `over` times a move; the other one was written.",
    UnknownActor => "psl::unknown_actor": "An actor is used but never declared.",
    DuplicateActor => "psl::duplicate_actor": "An actor is declared twice.",
    ActorFramedTwice => "psl::actor_framed_twice": "One actor appears in two framings of one composition.",
    TwoShotSameActor => "psl::two_shot_same_actor": "The actors of a two-shot are the same actor.",
    TooManyActors => "psl::too_many_actors": "A composition frames more actors than a drone can (two).",
    MissingAttribute => "psl::missing_attribute": "An actor declaration lacks its height or position.",
    DuplicateAttribute => "psl::duplicate_attribute": "An attribute or path parameter is given twice.",
    MissingStage => "psl::missing_stage": "A scene has no `stage` line.",
    DuplicateSetting => "psl::duplicate_setting": "`stage`, `lens` or `drone` is set twice.",
    SetupAfterShots => "psl::setup_after_shots": "A scene set-up line comes after the first shot.",
    OutsideStage => "psl::outside_stage": "A position lies outside the stage volume.",
    OverlappingMovement => "psl::overlapping_movement": "Two movements of one actor overlap in time.",
    ThenWithoutShot => "psl::then_without_shot": "A `then` line has no shot before it to continue.",
    ThenAfterPath => "psl::then_after_path": "A `then` move follows a path, which has no composition to move from.",
    ThenToPath => "psl::then_to_path": "A `then` move leads into a path; paths start after a cut.",
    PinnedStartOverlaps => "psl::pinned_start_overlaps": "A shot pinned with `at Ns` starts before the previous shot ends.",
    UnknownDrone => "psl::unknown_drone": "The drone profile name is not a built-in profile.",
    FileNotFound => "psl::file_not_found": "A file named in the script cannot be read.",
    BadWaypoints => "psl::bad_waypoints": "A waypoints file has a line that is not three numbers x, y, z.",
    MissingPathParameter => "psl::missing_path_parameter": "A path lacks a parameter its shape needs.",
    UnexpectedPathParameter => "psl::unexpected_path_parameter": "A path has a parameter its shape does not take.",
    BadTimecode => "psl::bad_timecode": "A subtitle timecode is malformed or out of range.",
    TimecodeOrder => "psl::timecode_order": "A timed entry ends before it starts or overlaps the previous one.",
    MixedTiming => "psl::mixed_timing": "Timed (subtitle) entries and untimed shots are mixed in one file.",
    DurationInTimedEntry => "psl::duration_in_timed_entry": "A timed entry also gives a duration.",
    EmptyScript => "psl::empty_script": "The script has no shots.",
    BadAspect => "psl::bad_aspect": "A lens aspect ratio is not two positive numbers.",
    InvalidUtf8 => "psl::invalid_utf8": "The file is not UTF-8 text.",
    Internal => "psl::internal": "The parser met a case it does not handle; please report it.",
    ProfileSyntax => "profile::syntax": "A drone profile is not valid TOML.",
    ProfileBadValue => "profile::bad_value": "A drone profile value has the wrong type or lies outside its range.",
    ProfileUnknownKey => "profile::unknown_key": "A drone profile has a key dronecine does not know.",
    ProfileMissingKey => "profile::missing_key": "A drone profile lacks a required key.",
    ProfileNotFound => "profile::not_found": "The drone profile file cannot be read.",
    NoScene => "compile::no_scene": "The script is a film annotation without a scene set-up; it cannot be flown.",
    TooClose => "compile::too_close": "A framing puts the camera inside an actor's safety distance.",
    Infeasible => "compile::infeasible": "The reference exceeds a limit of the drone profile (speed, acceleration, tilt, vertical speed, yaw rate).",
    LeavesStage => "compile::leaves_stage": "The reference leaves the stage volume.",
    CutTooShort => "compile::cut_too_short": "A cut to a pinned shot leaves too little time for the drone to fly to its first framing.",
    Reposition => "compile::reposition": "A cut needs a repositioning flight, inserted before the shot.",
    AngleNotRendered => "compile::angle_not_rendered": "The drone has no gimbal; the camera angle comes from altitude alone or not at all.",
    Unframeable => "compile::unframeable": "No roll-free camera orientation puts the actors at the requested screen positions.",
    FramingOff => "compile::framing_off": "A hold's actors land away from the screen points the script gives them.",
    ActorsOverlap => "psl::actors_overlap": "Two actors start in the same place.",
    ActorsCollide => "compile::actors_collide": "The blocking walks two actors into each other.",
    RigSyntax => "rig::syntax": "A rig file is not valid TOML.",
    RigBadValue => "rig::bad_value": "A rig file value has the wrong type or range, or gives two things one rigid body.",
    RigUnknownKey => "rig::unknown_key": "A rig file has a key dronecine does not know.",
    RigMissingKey => "rig::missing_key": "A rig file lacks a required key.",
    SizeOff => "compile::size_off": "An over-the-shoulder hold frames an actor two or more sizes from the one the script names.",
    ProfileOff => "compile::profile_off": "An over-the-shoulder hold sees an actor from a side far from the profile the script names.",
    InMargin => "compile::in_margin": "A framing puts the camera inside the stage's safety margin: the drone is held at the margin, off its framing.",
    BeyondReach => "compile::beyond_reach": "An over-the-shoulder's background size is just out of reach where the actors stand: the actor is framed a little larger.",
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
    pub fn error(code: Code, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            code,
            severity: Severity::Error,
            message: message.into(),
            span,
            label: None,
            help: None,
            related: Vec::new(),
        }
    }

    pub fn warning(code: Code, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, span, message)
        }
    }

    pub(crate) fn internal(span: Span, what: String) -> Diagnostic {
        Diagnostic::error(
            Code::Internal,
            span,
            format!("internal parser error: {what}"),
        )
        .with_help("this is a bug in dronecine; please report it with the script that caused it")
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
}

pub fn to_json(file: &str, src: &str, diagnostics: &[Diagnostic]) -> Vec<JsonDiagnostic> {
    let index = LineIndex::new(src);
    diagnostics
        .iter()
        .map(|d| {
            let (line, column) = index.line_col(src, d.span.start);
            let (end_line, end_column) = index.line_col(src, d.span.end);
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
            }
        })
        .collect()
}

/// Lines longer than this are shown as a window around the span, not whole.
const MAX_SHOWN_LINE: usize = 400;

/// Render diagnostics the way a person reads them: message, code, the quoted source with the
/// span underlined, and the help line. Plain text (no colour) unless `color` is set.
pub fn render(
    file: &str,
    src: &str,
    diagnostics: &[Diagnostic],
    color: bool,
    width: usize,
) -> String {
    let theme = if color {
        miette::GraphicalTheme::unicode()
    } else {
        miette::GraphicalTheme::unicode_nocolor()
    };
    let handler = miette::GraphicalReportHandler::new_themed(theme)
        .with_width(width)
        .with_context_lines(1);
    let shown = Arc::new(display_safe(src));
    let index = LineIndex::new(src);
    let mut out = String::new();
    for d in diagnostics {
        let report = windowed(file, &shown, &index, d);
        if handler.render_report(&mut out, &report).is_err() {
            out.push_str(&format!("{}: {} [{}]\n", file, d.message, d.code));
        }
    }
    out
}

/// A diagnostic with its source, as miette wants it.
struct Report {
    diagnostic: Diagnostic,
    source: miette::NamedSource<Arc<String>>,
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
        Some(&self.source)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let d = &self.diagnostic;
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
fn windowed(file: &str, shown: &Arc<String>, index: &LineIndex, d: &Diagnostic) -> Report {
    let src = shown.as_str();
    let (line, col) = index.line_col(src, d.span.start);
    let line_span = index.line_span(src, line);
    let related_elsewhere = d
        .related
        .iter()
        .any(|r| r.span.start < line_span.start || r.span.end > line_span.end);
    if line_span.len() <= MAX_SHOWN_LINE || related_elsewhere {
        return Report {
            diagnostic: d.clone(),
            source: miette::NamedSource::new(file, Arc::clone(shown)),
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
        source: miette::NamedSource::new(format!("{file}:{line}:{col}"), Arc::new(text)),
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

    #[test]
    fn codes_are_unique_and_namespaced() {
        let mut seen = std::collections::HashSet::new();
        for c in Code::ALL {
            let namespaced = ["psl::", "profile::", "compile::", "rig::"]
                .iter()
                .any(|ns| c.as_str().starts_with(ns));
            assert!(namespaced, "{c}");
            assert!(seen.insert(c.as_str()), "duplicate code {c}");
            assert!(!c.explain().is_empty());
        }
    }

    #[test]
    fn display_safe_keeps_byte_offsets() {
        let s = "a\u{0}b\u{1b}[31m\u{85}c";
        assert_eq!(display_safe(s).len(), s.len());
        assert!(!display_safe(s).contains('\u{1b}'));
    }

    #[test]
    fn long_lines_render_as_a_window() {
        let mut src = "x".repeat(100_000);
        src.push_str(" oops");
        let d = Diagnostic::error(Code::Syntax, Span::new(100_001, 100_005), "bad");
        let out = render("f.psl", &src, &[d], false, 100);
        assert!(out.len() < 2_000, "rendered {} bytes", out.len());
        assert!(out.contains("oops"));
        assert!(out.contains("f.psl:1:100002"));
    }
}
