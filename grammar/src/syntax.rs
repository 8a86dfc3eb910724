//! Syntax errors in the user's terms.
//!
//! pest reports the grammar rules it could have matched where a line stopped making sense.
//! This module turns them into a sentence ("expected a shot size such as MS or CU, found
//! `XS`"), finds the closest word the user may have meant, and names the special cases a
//! person trips on (a keyword used as a name, a unit written apart from its number).

use pest::error::{ErrorVariant, InputLocation};

use crate::code::PslCode;
use crate::rules::Rule;
use crate::vocab::{is_keyword, KEYWORDS, MOVE_NAMES, PROFILE_NAMES, SIZE_NAMES};
use dronecine_diag::suggest::{did_you_mean, or_list, shorten};
use dronecine_diag::Diagnostic;
use dronecine_diag::Span;

/// What the grammar expected, in words, with the vocabulary a misspelling is matched against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Expect {
    LineStart,
    Name,
    Profile,
    Screen,
    ScreenThird,
    And,
    Size,
    CameraAngle,
    Composition,
    Transition,
    Move,
    To,
    WalkOrTurn,
    ActorAttribute,
    PathKind,
    PathParameter,
    Duration,
    LookingAt,
    Quantity,
    Number,
    Point,
    Comma,
    CloseParen,
    X,
    Aspect,
    DroneProfile,
    QuotedFile,
    At,
    Arrow,
    Timecode,
    Event,
    Coverage,
    EndOfLine,
}

impl Expect {
    fn of(rule: Rule) -> Option<Expect> {
        use Rule as R;
        Some(match rule {
            R::line
            | R::shot
            | R::kw_stage
            | R::kw_lens
            | R::kw_drone
            | R::kw_actor
            | R::entry_index => Expect::LineStart,
            R::name | R::follow => Expect::Name,
            R::size | R::framing => Expect::Size,
            R::profile => Expect::Profile,
            R::camera_angle | R::high_angle | R::low_angle | R::eye_level => Expect::CameraAngle,
            R::screen | R::kw_screen => Expect::Screen,
            R::screen_third | R::screen_point => Expect::ScreenThird,
            R::kw_and => Expect::And,
            R::composition | R::framed_shot | R::subject => Expect::Composition,
            R::transition
            | R::cut_to
            | R::dissolve_to
            | R::then_move
            | R::kw_cut
            | R::kw_dissolve
            | R::kw_then => Expect::Transition,
            R::camera_move
            | R::kw_hold
            | R::kw_pan
            | R::kw_dolly
            | R::kw_crane
            | R::kw_track
            | R::kw_follow => Expect::Move,
            R::kw_to => Expect::To,
            R::duration | R::kw_for | R::kw_over => Expect::Duration,
            R::quantity => Expect::Quantity,
            R::count | R::number => Expect::Number,
            R::point => Expect::Point,
            R::aspect => Expect::Aspect,
            R::profile_name => Expect::DroneProfile,
            R::string => Expect::QuotedFile,
            R::actor_height | R::actor_at | R::actor_facing | R::kw_height | R::kw_facing => {
                Expect::ActorAttribute
            }
            R::walk | R::turn | R::kw_walks | R::kw_turns => Expect::WalkOrTurn,
            R::path_kind
            | R::kw_square
            | R::kw_helix
            | R::kw_orbit
            | R::waypoints
            | R::kw_waypoints => Expect::PathKind,
            R::p_side
            | R::p_center
            | R::p_altitude
            | R::p_radius
            | R::p_from_to
            | R::p_turns
            | R::p_around
            | R::p_direction
            | R::kw_side
            | R::kw_center
            | R::kw_altitude
            | R::kw_radius
            | R::kw_from
            | R::kw_around => Expect::PathParameter,
            R::looking_at | R::kw_looking => Expect::LookingAt,
            R::kw_at | R::pin => Expect::At,
            R::kw_x => Expect::X,
            R::arrow => Expect::Arrow,
            R::timecode => Expect::Timecode,
            R::event | R::kw_as | R::event_text => Expect::Event,
            R::comment | R::EOI => Expect::EndOfLine,
            R::path_shot | R::kw_path => Expect::PathKind,
            R::coverage_shot | R::kw_coverage => Expect::Coverage,
            _ => return None,
        })
    }

    fn describe(self) -> &'static str {
        match self {
            Expect::LineStart => "a shot, a set-up line (`stage`, `lens`, `drone`, `actor`), a movement (`at 6s A walks …`) or a comment",
            Expect::Name => "an actor name",
            Expect::Size => "a shot size such as MS or CU",
            Expect::Profile => "a profile angle such as front or 34left",
            Expect::CameraAngle => "a camera angle (`high angle`, `low angle`, `eye level`)",
            Expect::Screen => "a screen position such as `screen left`",
            Expect::ScreenThird => "`left`, `center`, `right` or a point `(x, y)`",
            Expect::And => "`and`",
            Expect::Composition => "a composition such as `MS on A front`",
            Expect::Transition => "`cut to`, `dissolve to` or `then … to`",
            Expect::Move => "a camera move (`hold`, `pan`, `dolly`, `crane`, `track`, `follow A`)",
            Expect::To => "`to`",
            Expect::Duration => "a duration such as `for 4s`",
            Expect::Quantity => "a number with its unit, such as `4s` or `1.5m`",
            Expect::Number => "a number",
            Expect::Point => "a point such as `(1, 2.5)`",
            Expect::Comma => "`,`",
            Expect::CloseParen => "`)`",
            Expect::X => "`x`",
            Expect::Aspect => "an aspect ratio such as `16:9`",
            Expect::DroneProfile => "a drone profile name such as `ardrone2` or a quoted file name",
            Expect::QuotedFile => "a quoted file name such as \"path.csv\"",
            Expect::ActorAttribute => "`height 1.80m`, `at (0, 0)` or `facing 0deg`",
            Expect::WalkOrTurn => "`walks to (x, y)` or `turns to 90deg`",
            Expect::PathKind => "a path shape (`square`, `helix`, `orbit`, `waypoints \"file.csv\"`)",
            Expect::PathParameter => "a path parameter such as `side 2m` or `radius 1.5m`",
            Expect::LookingAt => "`looking at A`",
            Expect::At => "`at`",
            Expect::Arrow => "`-->`",
            Expect::Timecode => "a timecode such as `00:01:03`",
            Expect::Event => "`as` and what happens",
            Expect::Coverage => "a coverage such as `coverage A and B for 24s`",
            Expect::EndOfLine => "the end of the line",
        }
    }

    /// Words a misspelling of this expectation is compared with (two lists, to share the
    /// vocabulary's own tables).
    fn words(self) -> [&'static [&'static str]; 2] {
        const STATEMENT_STARTS: &[&str] = &[
            "stage", "lens", "drone", "actor", "at", "cut", "dissolve", "then", "path", "high",
            "low", "eye", "coverage",
        ];
        const ANGLE_STARTS: &[&str] = &["high", "low", "eye"];
        let one: &'static [&'static str] = match self {
            Expect::LineStart => return [STATEMENT_STARTS, SIZE_NAMES],
            Expect::Composition => return [ANGLE_STARTS, SIZE_NAMES],
            Expect::Size => SIZE_NAMES,
            Expect::Profile => PROFILE_NAMES,
            Expect::CameraAngle => &["high", "low", "eye", "angle", "level"],
            Expect::Screen => &["screen"],
            Expect::ScreenThird => &["left", "center", "right"],
            Expect::And => &["and"],
            Expect::Transition => &["cut", "dissolve", "then"],
            Expect::Move => MOVE_NAMES,
            Expect::To => &["to"],
            Expect::Duration => &["for", "over"],
            Expect::X => &["x"],
            Expect::ActorAttribute => &["height", "at", "facing"],
            Expect::WalkOrTurn => &["walks", "turns"],
            Expect::PathKind => &["path", "square", "helix", "orbit", "waypoints"],
            Expect::PathParameter => &[
                "side",
                "center",
                "altitude",
                "radius",
                "from",
                "turns",
                "around",
                "clockwise",
                "counterclockwise",
            ],
            Expect::LookingAt => &["looking"],
            Expect::At => &["at"],
            Expect::Event => &["as"],
            Expect::Coverage => &["coverage"],
            _ => &[],
        };
        [one, &[]]
    }
}

/// The usual form of a statement, by its first word, for the help line.
fn form_of(first_word: &str) -> Option<&'static str> {
    Some(match first_word {
        "stage" => "stage 8m x 6m x 3m",
        "lens" => "lens 84deg (or `lens 84deg 4:3`)",
        "drone" => "drone ardrone2 (or `drone \"profiles/mine.toml\"`)",
        "actor" => "actor A height 1.80m at (0, 0) facing 0deg",
        "path" => "path square side 2m center (0, 0) altitude 1.5m for 20s",
        "then" => "then dolly to MS on A 34backright over 6s",
        "cut" => "cut to MS on A front for 4s",
        "dissolve" => "dissolve to MS on A front for 4s",
        "at" => "at 6s A walks to (1, 1.5) over 4s",
        "coverage" => "coverage A and B for 24s (or `coverage FS on A and B for 24s`)",
        _ => return None,
    })
}

/// Convert a pest error on one line (starting at byte `offset` of the file) to a diagnostic.
pub fn diagnostic(err: &pest::error::Error<Rule>, line: &str, offset: usize) -> Diagnostic {
    let pos = match err.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    }
    .min(line.len());
    let mut expected: Vec<Expect> = match &err.variant {
        ErrorVariant::ParsingError { positives, .. } => {
            positives.iter().filter_map(|r| Expect::of(*r)).collect()
        }
        ErrorVariant::CustomError { .. } => Vec::new(),
    };
    // Inside a point the grammar's literals ("," and ")") are not rules; name them by context.
    if expected.is_empty() {
        expected.push(match line[..pos].trim_end().chars().last() {
            Some('(') => Expect::Quantity,
            _ if line[..pos].contains('(') && !line[..pos].contains(')') => {
                if line[..pos].matches(',').count() == 0 {
                    Expect::Comma
                } else {
                    Expect::CloseParen
                }
            }
            _ => Expect::EndOfLine,
        });
    }
    if expected.contains(&Expect::LineStart) {
        expected.retain(|e| *e == Expect::LineStart);
    }
    expected.sort();
    expected.dedup();

    // Point at the next token, past any blanks pest stopped in front of.
    let pos = pos + (line[pos..].len() - line[pos..].trim_start_matches([' ', '\t']).len());
    let (found, found_len) = token_at(line, pos);
    let span = Span::new(offset + pos, offset + pos + found_len);
    let found_text = match found {
        Found::End => "the end of the line".to_string(),
        Found::Word(w) => format!("`{}`", shorten(w)),
        Found::Char(c) => format!("`{}`", c.escape_debug()),
    };
    let first_word = line.split_whitespace().next().unwrap_or("");

    // A unit written apart from its number: `for 4 s`.
    if let Found::Word(w) = found {
        if matches!(w, "s" | "m" | "deg" | "sec" | "cm") && line[..pos].ends_with([' ', '\t']) {
            let before = line[..pos].trim_end();
            if before.ends_with(|c: char| c.is_ascii_digit() || c == '.') {
                let num_start = before
                    .rfind(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
                    .map(|i| i + 1)
                    .unwrap_or(0);
                let number = &before[num_start..];
                return Diagnostic::error(
                    PslCode::UnitSpace,
                    Span::new(offset + num_start, span.end),
                    format!("the unit `{w}` is written apart from its number"),
                )
                .with_label("number and unit must touch")
                .with_help(format!("write `{number}{w}`"));
            }
        }
    }

    // A keyword where a name belongs.
    if expected.contains(&Expect::Name) {
        if let Found::Word(w) = found {
            if is_keyword(w) {
                let (message, help) = if first_word == "actor" {
                    (
                        format!("`{w}` is a keyword and cannot name an actor"),
                        "choose another name: sizes, profiles and words such as `on`, `and`, `to` are reserved"
                            .to_string(),
                    )
                } else {
                    (
                        format!("expected an actor name, found the keyword `{w}`"),
                        "write the actor's name here, e.g. `MS on A front`; keywords cannot be names".to_string(),
                    )
                };
                return Diagnostic::error(PslCode::KeywordAsName, span, message)
                    .with_label("a keyword, not a name")
                    .with_help(help);
            }
        }
    }

    let described: Vec<&str> = expected.iter().map(|e| e.describe()).collect();
    let expected_text = match described.len() {
        0 => "something else".to_string(),
        1 => described[0].to_string(),
        n if n <= 5 => format!("{} or {}", described[..n - 1].join(", "), described[n - 1]),
        _ => format!("{}, or …", described[..4].join(", ")),
    };
    let message = format!("expected {expected_text}, found {found_text}");
    let label = match found {
        Found::End => "the line ends here".to_string(),
        _ => format!("expected {}", short_expected(&expected)),
    };

    let mut help = None;
    if let Found::Word(w) = found {
        let words: Vec<&str> = expected
            .iter()
            .flat_map(|e| e.words().into_iter().flatten().copied())
            .collect();
        let same_case_folded = words.iter().find(|c| c.eq_ignore_ascii_case(w) && **c != w);
        help = match same_case_folded {
            Some(c) if c.chars().all(|ch| ch.is_ascii_uppercase()) => {
                Some(format!("size codes are upper case: write `{c}`"))
            }
            Some(c) => Some(format!("keywords are lower case: write `{c}`")),
            None => did_you_mean(w, words.iter().copied()),
        };
        if help.is_none() && expected == [Expect::EndOfLine] {
            help = Some(format!(
                "remove `{}`, or start a comment with `#`",
                shorten(w)
            ));
        }
        if help.is_none() && expected.contains(&Expect::LineStart) {
            if let Some(s) = did_you_mean(w, KEYWORDS.iter().copied()) {
                help = Some(s);
            } else if w.chars().next().is_some_and(|c| c.is_alphabetic()) {
                help = Some("a shot starts with a size, e.g. `MS on A front for 4s`; a set-up line with `stage`, `lens`, `drone` or `actor`".to_string());
            }
        }
    }
    if help.is_none() {
        help = form_of(first_word).map(|f| format!("the form is `{f}`"));
    }
    if help.is_none() && expected.contains(&Expect::LineStart) {
        help =
            Some("a shot looks like `MS on A front for 4s`; comments start with `#`".to_string());
    }
    let mut d = Diagnostic::error(PslCode::Syntax, span, message).with_label(label);
    d.help = help;
    d
}

fn short_expected(expected: &[Expect]) -> String {
    let names: Vec<&str> = expected
        .iter()
        .map(|e| match e {
            Expect::LineStart => "a statement",
            Expect::Name => "name",
            Expect::Size => "size",
            Expect::Profile => "profile",
            Expect::CameraAngle => "camera angle",
            Expect::Screen => "screen",
            Expect::ScreenThird => "third",
            Expect::And => "and",
            Expect::Composition => "composition",
            Expect::Transition => "transition",
            Expect::Move => "move",
            Expect::To => "to",
            Expect::Duration => "duration",
            Expect::Quantity => "number+unit",
            Expect::Number => "number",
            Expect::Point => "point",
            Expect::Comma => ",",
            Expect::CloseParen => ")",
            Expect::X => "x",
            Expect::Aspect => "aspect",
            Expect::DroneProfile => "profile",
            Expect::QuotedFile => "file",
            Expect::ActorAttribute => "attribute",
            Expect::WalkOrTurn => "walks/turns",
            Expect::PathKind => "path shape",
            Expect::PathParameter => "path parameter",
            Expect::LookingAt => "looking at",
            Expect::At => "at",
            Expect::Arrow => "-->",
            Expect::Timecode => "timecode",
            Expect::Event => "as",
            Expect::Coverage => "coverage",
            Expect::EndOfLine => "end of line",
        })
        .collect();
    if names.len() > 4 {
        format!("{}, …", names[..4].join(", "))
    } else {
        or_list(&names).replace('`', "")
    }
}

#[derive(Clone, Copy, Debug)]
enum Found<'a> {
    End,
    Word(&'a str),
    Char(char),
}

/// The token at `pos`: a word (letters, digits, `_`, `-`, `.`), one other character, or the
/// end of the line; with its length in bytes (at least one character, zero at the end).
fn token_at(line: &str, pos: usize) -> (Found<'_>, usize) {
    let rest = &line[pos..];
    let Some(c) = rest.chars().next() else {
        return (Found::End, 0);
    };
    if c.is_alphanumeric() || c == '_' {
        let len = rest
            .find(|ch: char| !(ch.is_alphanumeric() || ch == '_' || ch == '-' || ch == '.'))
            .unwrap_or(rest.len());
        (Found::Word(&rest[..len]), len)
    } else {
        (Found::Char(c), c.len_utf8())
    }
}
