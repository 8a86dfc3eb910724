//! The resolved script: plain serde data, every check passed, units in the field names.
//!
//! This is the contract between the language front end and the compiler. Angles are in
//! radians wrapped to (−π, π], lengths in metres, times in seconds on the script's clock
//! (the first shot starts at 0). Actors are referred to by name; every name used here is
//! declared in `Scene::actors` (or, for a film annotation, listed in `cast`). Spans point
//! into the source so that later stages can report errors on the line that caused them.

use serde::{Deserialize, Serialize};

use crate::vocab::{CameraAngle, MoveKind, Profile, ScreenThird, Size};
use dronecine_diag::Span;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Script {
    /// The physical set-up; `None` for a film annotation (subtitle-timed lines only), which
    /// can be checked but not compiled or flown.
    pub scene: Option<Scene>,
    /// Every actor name, in order of declaration (or of first use in an annotation).
    pub cast: Vec<String>,
    pub timeline: Vec<Shot>,
    /// End of the last shot.
    pub duration_s: f64,
}

impl Script {
    pub fn is_annotation(&self) -> bool {
        self.scene.is_none()
    }

    /// [`moves_camera`] of this script's shot `index`.
    pub fn moves_camera(&self, index: usize) -> bool {
        moves_camera(&self.timeline, index)
    }
}

/// Whether shot `index` of `timeline` is a camera move: a `then … to` another composition than
/// the framing before it, which it reaches over its duration, the visual parameters
/// interpolated. `hold` is one of those moves: `then hold to MS on A` after another framing
/// moves there as `then dolly to` does (a step to it at once would leave the drone metres off
/// its framing, flying a straight line to it through whatever stands between).
/// `then hold for` and a `then hold to` the same composition hold the framing; so does a
/// `then` after a path, which has no framing to move from.
pub fn moves_camera(timeline: &[Shot], index: usize) -> bool {
    let Some(shot) = timeline.get(index) else {
        return false;
    };
    let Transition::Move { kind, .. } = &shot.transition else {
        return false;
    };
    let before = index.checked_sub(1).and_then(|i| timeline.get(i));
    match (before.map(|b| &b.content), &shot.content) {
        (Some(ShotContent::Composition(from)), ShotContent::Composition(to)) => {
            then_moves(*kind, from, to)
        }
        _ => false,
    }
}

/// The rule of [`moves_camera`] for a `then` of `kind` from the composition `from` to `to`
/// (the resolver asks it too, for the duration keyword, before the timeline exists).
pub fn then_moves(kind: MoveKind, from: &Composition, to: &Composition) -> bool {
    kind != MoveKind::Hold || from != to
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    pub stage: Stage,
    /// `None`: the drone profile's lens.
    pub lens: Option<Lens>,
    /// `None`: the default drone.
    pub drone: Option<DroneRef>,
    pub actors: Vec<Actor>,
    /// Actor movements sorted by start time.
    pub blocking: Vec<Movement>,
}

/// The flight volume: x ∈ [−x/2, x/2], y ∈ [−y/2, y/2], z ∈ [0, z], origin at the centre of
/// the floor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    pub size_m: [f64; 3],
}

impl Stage {
    pub fn min_m(&self) -> [f64; 3] {
        [-self.size_m[0] / 2.0, -self.size_m[1] / 2.0, 0.0]
    }

    pub fn max_m(&self) -> [f64; 3] {
        [self.size_m[0] / 2.0, self.size_m[1] / 2.0, self.size_m[2]]
    }

    /// Whether a floor point lies inside the stage (borders included).
    pub fn contains_xy(&self, p: [f64; 2]) -> bool {
        let (lo, hi) = (self.min_m(), self.max_m());
        (0..2).all(|i| p[i] >= lo[i] - 1e-9 && p[i] <= hi[i] + 1e-9)
    }

    pub fn contains(&self, p: [f64; 3]) -> bool {
        let (lo, hi) = (self.min_m(), self.max_m());
        (0..3).all(|i| p[i] >= lo[i] - 1e-9 && p[i] <= hi[i] + 1e-9)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lens {
    /// Horizontal field of view.
    pub fov_x_rad: f64,
    /// Frame width over height (16:9 unless written).
    pub aspect: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DroneRef {
    Builtin {
        name: String,
    },
    /// Relative to the script's directory, as written.
    File {
        path: String,
    },
}

/// Two actors closer than this, centre to centre, are in one place: two bodies cannot stand
/// closer. Declared start positions are checked against it here (`psl::actors_overlap`), the
/// blocking's walks by the compiler (`compile::actors_collide`).
pub const ACTORS_MIN_APART_M: f64 = 0.3;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Actor {
    pub name: String,
    pub height_m: f64,
    /// Start position on the floor.
    pub position_m: [f64; 2],
    /// Start facing, counter-clockwise from +x.
    pub facing_rad: f64,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Movement {
    pub actor: String,
    pub start_s: f64,
    pub end_s: f64,
    pub action: Action,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Action {
    Walk { to_m: [f64; 2] },
    Turn { to_rad: f64 },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Shot {
    pub start_s: f64,
    pub end_s: f64,
    /// The start was fixed by `at Ns` or a timecode rather than by the previous shot's end.
    pub pinned: bool,
    pub transition: Transition,
    pub content: ShotContent,
    pub span: Span,
    /// The coverage this shot is a part of, when the compiler expanded it from a `coverage`
    /// line (whose span it carries).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<CoveragePart>,
}

impl Shot {
    /// How a report or a preview names the shot: its line of `source` (the script's text),
    /// or, for a part of an expanded coverage, which part it is and what it frames (`part
    /// 2/5 of the coverage of Rick and Ilsa: MS on Rick 34backright MS on Ilsa 34left`).
    pub fn label(&self, source: &str) -> String {
        let line = source
            .get(self.span.start..self.span.end)
            .unwrap_or("")
            .trim();
        match (&self.coverage, &self.content) {
            (Some(part), ShotContent::Composition(c)) => format!("{part}: {c}"),
            _ => line.to_string(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Transition {
    /// A new shot: `cut to`, or a composition line without a transition.
    Cut,
    Dissolve,
    /// `then [as EVENT] MOVE to …` (and `then hold for …`).
    Move {
        #[serde(rename = "move")]
        kind: MoveKind,
        /// The actor of `follow A`.
        follow: Option<String>,
        event: Option<String>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ShotContent {
    Composition(Composition),
    Path(Path),
    /// `coverage A and B for Ns`: the compiler expands it into [`COVERAGE_PARTS`] shots of
    /// compositions before it flies the script.
    Coverage(Coverage),
}

impl ShotContent {
    /// The composition the shot frames: its own, or an unexpanded coverage's
    /// ([`Coverage::unexpanded`]); `None` for a path.
    pub fn framed(&self) -> Option<std::borrow::Cow<'_, Composition>> {
        match self {
            ShotContent::Composition(c) => Some(std::borrow::Cow::Borrowed(c)),
            ShotContent::Coverage(c) => Some(std::borrow::Cow::Owned(c.unexpanded())),
            ShotContent::Path(_) => None,
        }
    }
}

/// The shots a coverage expands into: an establishing two-shot, an over-the-shoulder over
/// each actor's shoulder, a single on each.
pub const COVERAGE_PARTS: usize = 5;

/// The shortest hold of a shot of a coverage: a cut shorter than this does not read.
pub const COVERAGE_MIN_HOLD_S: f64 = 1.5;

/// The shortest repositioning flight the compiler expects between two shots of a coverage:
/// the AR.Drone's flight between its two singles, 0.3 m apart and turned 57°, takes 2.0 s
/// (`shots/coverage.psl`); most take twice as long.
pub const COVERAGE_MIN_FLIGHT_S: f64 = 2.0;

/// The shortest coverage the language accepts (`psl::coverage_too_short`): every part held
/// [`COVERAGE_MIN_HOLD_S`], with a flight of [`COVERAGE_MIN_FLIGHT_S`] between two parts.
pub const COVERAGE_MIN_S: f64 = COVERAGE_PARTS as f64 * COVERAGE_MIN_HOLD_S
    + (COVERAGE_PARTS - 1) as f64 * COVERAGE_MIN_FLIGHT_S;

/// The coverage of a pair of actors (`coverage [SIZE on] A and B`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coverage {
    pub a: String,
    pub b: String,
    /// The establishing two-shot's size; `None`: the compiler chooses the tightest that holds.
    pub size: Option<Size>,
}

impl Coverage {
    /// The size of the establishing two-shot of a coverage framed as written, unexpanded.
    pub const UNEXPANDED_SIZE: Size = Size::FS;

    /// What a coverage frames when a compiler does not expand it: its establishing two-shot
    /// for the whole duration, at the size written (else [`Coverage::UNEXPANDED_SIZE`]).
    pub fn unexpanded(&self) -> Composition {
        self.two_shot(self.size.unwrap_or(Coverage::UNEXPANDED_SIZE))
    }

    /// The establishing two-shot, `SIZE on A and B`.
    pub fn two_shot(&self, size: Size) -> Composition {
        let subject = |actor: &str| Subject {
            actor: actor.to_string(),
            profile: None,
            screen_x: None,
            screen_y: None,
        };
        Composition {
            camera_angle: CameraAngle::EyeLevel,
            framings: vec![Framing {
                size,
                subjects: vec![subject(&self.a), subject(&self.b)],
            }],
        }
    }
}

/// Which shot of which coverage an expanded shot is.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoveragePart {
    /// From 1.
    pub part: usize,
    pub parts: usize,
    pub a: String,
    pub b: String,
}

impl std::fmt::Display for CoveragePart {
    /// `part 2/5 of the coverage of A and B`: the words every caption and label use.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "part {}/{} of the coverage of {} and {}",
            self.part, self.parts, self.a, self.b
        )
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Composition {
    pub camera_angle: CameraAngle,
    /// One or more framings; several make an over-the-shoulder composition.
    pub framings: Vec<Framing>,
}

impl std::fmt::Display for Composition {
    /// The composition as PSL text (`MS on Rick 34backright MS on Ilsa 34left screen right`),
    /// which the parser resolves to it again: a screen x at a third is written as the third,
    /// any other point as `screen (x, y)`, each number in the shortest form that reads back
    /// to the same value. (PSL writes a screen y with its x only: a subject with a y and no x,
    /// which no line resolves to, is written with x = 0.)
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.camera_angle != CameraAngle::EyeLevel {
            write!(f, "{} ", self.camera_angle.as_str())?;
        }
        for (i, framing) in self.framings.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{} on ", framing.size.as_str())?;
            for (j, s) in framing.subjects.iter().enumerate() {
                if j > 0 {
                    f.write_str(" and ")?;
                }
                f.write_str(&s.actor)?;
                if let Some(p) = s.profile {
                    write!(f, " {}", p.as_str())?;
                }
                let third = [ScreenThird::Left, ScreenThird::Center, ScreenThird::Right]
                    .into_iter()
                    .find(|t| Some(t.screen_x()) == s.screen_x);
                match (s.screen_x, s.screen_y, third) {
                    (None, None, _) => {}
                    (Some(_), None, Some(t)) => write!(f, " screen {}", t.as_str())?,
                    (x, y, _) => write!(f, " screen ({}, {})", x.unwrap_or(0.0), y.unwrap_or(0.0))?,
                }
            }
        }
        Ok(())
    }
}

impl Composition {
    /// Every actor of the composition, in order.
    pub fn actors(&self) -> impl Iterator<Item = &str> {
        self.framings
            .iter()
            .flat_map(|f| f.subjects.iter().map(|s| s.actor.as_str()))
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Framing {
    pub size: Size,
    pub subjects: Vec<Subject>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Subject {
    pub actor: String,
    /// `None`: the compiler chooses (front for one actor; the toric default for two).
    pub profile: Option<Profile>,
    /// Requested screen x in [−1, 1]; `None`: the default placement (the centre for one
    /// actor; for two, the thirds at −1/3 and +1/3, or the other side of a written one).
    pub screen_x: Option<f64>,
    /// Requested screen y in [−1, 1]; `None`: from the shot size.
    pub screen_y: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Path {
    pub shape: PathShape,
    /// The camera looks at this actor; `None`: along the path.
    pub looking_at: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PathShape {
    Square {
        side_m: f64,
        center_m: [f64; 2],
        altitude_m: f64,
        clockwise: bool,
    },
    Helix {
        radius_m: f64,
        center_m: [f64; 2],
        from_m: f64,
        to_m: f64,
        turns: f64,
        clockwise: bool,
    },
    Orbit {
        center: OrbitCenter,
        radius_m: f64,
        altitude_m: f64,
        turns: f64,
        clockwise: bool,
    },
    Waypoints {
        file: String,
        points_m: Vec<[f64; 3]>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum OrbitCenter {
    Point {
        at_m: [f64; 2],
    },
    /// Around an actor, following them as they move.
    Actor {
        name: String,
    },
}
