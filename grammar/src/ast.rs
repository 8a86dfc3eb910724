//! The typed syntax tree of a script, with a byte span on every node.
//!
//! The tree borrows its text from the source (`'a`) and keeps every literal as written, so
//! that the formatter can print numbers and names exactly as the author did. Values are
//! parsed (`Quantity::value`) but not checked: units, ranges and references are the
//! semantic pass's job (`resolve.rs`).

use crate::vocab::{CameraAngle, MoveKind, Profile, ScreenThird, Size};
use dronecine_diag::Span;

/// A whole script: one entry per source line, blank and comment lines included.
#[derive(Clone, Debug, PartialEq)]
pub struct File<'a> {
    /// The whole source text.
    pub source: &'a str,
    pub lines: Vec<Line<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Line<'a> {
    /// 1-based line number.
    pub number: usize,
    /// The line without its line break.
    pub span: Span,
    pub statement: Option<Statement<'a>>,
    /// A trailing or whole-line comment, `#` included.
    pub comment: Option<Text<'a>>,
    /// The line did not parse; a diagnostic says why.
    pub error: bool,
}

/// A piece of source text.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Text<'a> {
    pub text: &'a str,
    pub span: Span,
}

/// A number with its unit as written: `4s`, `1.80m`, `2` (no unit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantity<'a> {
    pub value: f64,
    pub number: &'a str,
    pub unit: Option<Text<'a>>,
    pub span: Span,
}

/// `(x, y)`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point<'a> {
    pub x: Quantity<'a>,
    pub y: Quantity<'a>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Statement<'a> {
    Stage(Stage<'a>),
    Lens(Lens<'a>),
    Drone(Drone<'a>),
    Actor(ActorDecl<'a>),
    Blocking(Blocking<'a>),
    Shot(Shot<'a>),
    Timed(TimedEntry<'a>),
}

impl Statement<'_> {
    pub fn span(&self) -> Span {
        match self {
            Statement::Stage(s) => s.span,
            Statement::Lens(s) => s.span,
            Statement::Drone(s) => s.span,
            Statement::Actor(s) => s.span,
            Statement::Blocking(s) => s.span,
            Statement::Shot(s) => s.span,
            Statement::Timed(s) => s.span,
        }
    }
}

/// `stage 8m x 6m x 3m`
#[derive(Clone, Debug, PartialEq)]
pub struct Stage<'a> {
    pub span: Span,
    pub x: Quantity<'a>,
    pub y: Quantity<'a>,
    pub z: Quantity<'a>,
}

/// `lens 84deg [4:3]`
#[derive(Clone, Debug, PartialEq)]
pub struct Lens<'a> {
    pub span: Span,
    pub fov: Quantity<'a>,
    pub aspect: Option<Text<'a>>,
}

/// `drone ardrone2` or `drone "profiles/mine.toml"`
#[derive(Clone, Debug, PartialEq)]
pub struct Drone<'a> {
    pub span: Span,
    pub target: DroneTarget<'a>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum DroneTarget<'a> {
    Builtin(Text<'a>),
    /// The file name without its quotes.
    File(Text<'a>),
}

/// `actor A height 1.80m at (0, 0) facing 0deg`
#[derive(Clone, Debug, PartialEq)]
pub struct ActorDecl<'a> {
    pub span: Span,
    pub name: Text<'a>,
    pub attrs: Vec<ActorAttr<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ActorAttr<'a> {
    Height(Span, Quantity<'a>),
    At(Span, Point<'a>),
    Facing(Span, Quantity<'a>),
}

impl ActorAttr<'_> {
    pub fn span(&self) -> Span {
        match self {
            ActorAttr::Height(s, _) | ActorAttr::At(s, _) | ActorAttr::Facing(s, _) => *s,
        }
    }
}

/// `at 6s A walks to (1, 1.5) over 4s`, `at 12s B turns to 90deg over 1s`
#[derive(Clone, Debug, PartialEq)]
pub struct Blocking<'a> {
    pub span: Span,
    pub at: Quantity<'a>,
    pub actor: Text<'a>,
    pub action: Action<'a>,
    pub duration: Option<Duration<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Action<'a> {
    Walk(Span, Point<'a>),
    Turn(Span, Quantity<'a>),
}

/// `for 4s` or `over 6s`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Duration<'a> {
    pub span: Span,
    pub keyword: DurationKeyword,
    pub value: Quantity<'a>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DurationKeyword {
    For,
    Over,
}

impl DurationKeyword {
    pub fn as_str(self) -> &'static str {
        match self {
            DurationKeyword::For => "for",
            DurationKeyword::Over => "over",
        }
    }
}

/// A shot line, optionally pinned on the clock (`at 30s …`).
#[derive(Clone, Debug, PartialEq)]
pub struct Shot<'a> {
    pub span: Span,
    pub pin: Option<Quantity<'a>>,
    pub body: ShotBody<'a>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ShotBody<'a> {
    Framed(FramedShot<'a>),
    Hold(HoldShot<'a>),
    Path(PathShot<'a>),
    Coverage(CoverageShot<'a>),
}

impl ShotBody<'_> {
    pub fn span(&self) -> Span {
        match self {
            ShotBody::Framed(s) => s.span,
            ShotBody::Hold(s) => s.span,
            ShotBody::Path(s) => s.span,
            ShotBody::Coverage(s) => s.span,
        }
    }

    pub fn duration(&self) -> Option<&Duration<'_>> {
        match self {
            ShotBody::Framed(s) => s.duration.as_ref(),
            ShotBody::Hold(s) => s.duration.as_ref(),
            ShotBody::Path(s) => s.duration.as_ref(),
            ShotBody::Coverage(s) => s.duration.as_ref(),
        }
    }
}

/// `[transition] coverage [SIZE [on]] A and B [duration]`
#[derive(Clone, Debug, PartialEq)]
pub struct CoverageShot<'a> {
    pub span: Span,
    pub transition: Option<Transition<'a>>,
    /// The establishing two-shot's size, if written.
    pub size: Option<(Span, Size)>,
    pub a: Text<'a>,
    pub b: Text<'a>,
    pub duration: Option<Duration<'a>>,
}

/// `[transition] composition [duration]`
#[derive(Clone, Debug, PartialEq)]
pub struct FramedShot<'a> {
    pub span: Span,
    pub transition: Option<Transition<'a>>,
    pub composition: Composition<'a>,
    pub duration: Option<Duration<'a>>,
}

/// `then [as EVENT] hold for Ns`
#[derive(Clone, Debug, PartialEq)]
pub struct HoldShot<'a> {
    pub span: Span,
    pub event: Option<Event<'a>>,
    pub duration: Option<Duration<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Transition<'a> {
    pub span: Span,
    pub kind: TransitionKind<'a>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum TransitionKind<'a> {
    Cut,
    Dissolve,
    /// `then [as EVENT] MOVE to`
    Move {
        event: Option<Event<'a>>,
        kind: MoveKind,
        /// The actor of `follow A`.
        follow: Option<Text<'a>>,
    },
}

/// `as Bob sits down` or `as "Bob sits down"`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event<'a> {
    pub span: Span,
    /// The text without quotes.
    pub text: &'a str,
    pub quoted: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Composition<'a> {
    pub span: Span,
    pub angle: Option<(Span, CameraAngle)>,
    pub framings: Vec<Framing<'a>>,
}

/// `SIZE [on] SUBJECT (and SUBJECT)*`
#[derive(Clone, Debug, PartialEq)]
pub struct Framing<'a> {
    pub span: Span,
    pub size: (Span, Size),
    pub subjects: Vec<Subject<'a>>,
}

/// `NAME [profile] [screen …]`
#[derive(Clone, Debug, PartialEq)]
pub struct Subject<'a> {
    pub span: Span,
    pub actor: Text<'a>,
    pub profile: Option<(Span, Profile)>,
    pub screen: Option<Screen<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Screen<'a> {
    pub span: Span,
    pub position: ScreenPosition<'a>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ScreenPosition<'a> {
    Third(ScreenThird),
    Point(Quantity<'a>, Quantity<'a>),
}

/// `path KIND PARAM* [duration] [looking at A]`
#[derive(Clone, Debug, PartialEq)]
pub struct PathShot<'a> {
    pub span: Span,
    pub transition: Option<Transition<'a>>,
    pub kind: (Span, PathKind<'a>),
    /// Parameters in source order, `looking at` included wherever it was written.
    pub params: Vec<PathParam<'a>>,
    pub duration: Option<Duration<'a>>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum PathKind<'a> {
    Square,
    Helix,
    Orbit,
    /// The CSV file name, without quotes.
    Waypoints(Text<'a>),
}

impl PathKind<'_> {
    pub fn name(&self) -> &'static str {
        match self {
            PathKind::Square => "square",
            PathKind::Helix => "helix",
            PathKind::Orbit => "orbit",
            PathKind::Waypoints(_) => "waypoints",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct PathParam<'a> {
    pub span: Span,
    pub value: PathValue<'a>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum PathValue<'a> {
    Side(Quantity<'a>),
    Center(Point<'a>),
    Altitude(Quantity<'a>),
    Radius(Quantity<'a>),
    FromTo(Quantity<'a>, Quantity<'a>),
    Turns(Quantity<'a>),
    Around(Text<'a>),
    Clockwise(bool),
    LookingAt(Text<'a>),
}

impl PathValue<'_> {
    /// The keyword that introduces the parameter, as the user writes it.
    pub fn keyword(&self) -> &'static str {
        match self {
            PathValue::Side(_) => "side",
            PathValue::Center(_) => "center",
            PathValue::Altitude(_) => "altitude",
            PathValue::Radius(_) => "radius",
            PathValue::FromTo(..) => "from",
            PathValue::Turns(_) => "turns",
            PathValue::Around(_) => "around",
            PathValue::Clockwise(_) => "clockwise",
            PathValue::LookingAt(_) => "looking at",
        }
    }
}

/// `12 00:01:03 --> 00:01:09  cut to low angle MCU Bob 34right`
#[derive(Clone, Debug, PartialEq)]
pub struct TimedEntry<'a> {
    pub span: Span,
    pub index: Text<'a>,
    pub start: Text<'a>,
    pub end: Text<'a>,
    /// A framed shot or a hold; its duration, if written, conflicts with the timecodes.
    pub body: ShotBody<'a>,
}
