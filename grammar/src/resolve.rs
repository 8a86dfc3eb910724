//! The semantic pass: from the syntax tree to a checked `Script`.
//!
//! Every check reports into one list, so a file's mistakes all come out in one run; a
//! `Script` is returned only when none of them is an error. What is checked: units and
//! ranges of every number, actors declared once and referenced only when declared, at most
//! one appearance of an actor per composition, durations > 0, positions inside the stage,
//! blocking that does not overlap, a timeline whose pinned starts and timecodes are in order,
//! and the parameters each path shape needs.

use std::collections::HashMap;
use std::path::Path as FsPath;

use crate::ast::{self, DurationKeyword, PathValue, Quantity, ShotBody, Statement, TransitionKind};
use crate::code::PslCode;
use crate::script::*;
use crate::vocab::{CameraAngle, MoveKind};
use dronecine_diag::suggest::{did_you_mean, shorten};
use dronecine_diag::Diagnostic;
use dronecine_diag::Span;
use dronecine_math::wrap_angle_rad;

/// What the semantic pass needs from outside the script.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options<'o> {
    /// Names of the built-in drone profiles; when empty, `drone NAME` is not checked.
    pub known_drones: &'o [&'o str],
    /// The script's directory, against which `drone "…"` and `path waypoints "…"` are
    /// resolved; `None` leaves files unread (and waypoint lists empty).
    pub base_dir: Option<&'o FsPath>,
}

/// Longest time the language accepts anywhere: a day.
const MAX_TIME_S: f64 = 86_400.0;
const EPS_S: f64 = 1e-9;

/// Shortest duration the language accepts: one control period at the fastest rate dronecine
/// flies (`shoot --rate` takes up to 1000 Hz). A shorter shot or movement has no tick of its
/// own.
pub const MIN_DURATION_S: f64 = 0.001;

/// Smallest size of a number other than 0: a non-zero digit within nine after the point, as
/// nine digits before it bound the largest. Smaller numbers (subnormals among them) are slips
/// of the keyboard, and no later stage is built for them.
pub const MIN_MAGNITUDE: f64 = 1e-9;

/// Shortest path length (side, radius, altitude): a drone holds its place to centimetres.
pub const MIN_PATH_LENGTH_M: f64 = 0.01;

/// Resolve a parsed file. Returns the script when no diagnostic is an error.
pub fn resolve<'a>(file: &ast::File<'a>, opts: &Options<'_>) -> (Option<Script>, Vec<Diagnostic>) {
    let mut failed_lines = Vec::new();
    let mut failed_actors = Vec::new();
    let mut failed_stage = false;
    for line in file.lines.iter().filter(|l| l.error) {
        failed_lines.push(line.span.start);
        let text = file
            .source
            .get(line.span.start..line.span.end)
            .unwrap_or("");
        let mut words = text.split_whitespace();
        match words.next() {
            Some("stage") => failed_stage = true,
            Some("actor") => failed_actors.extend(words.next()),
            _ => {}
        }
    }
    let mut r = Resolver {
        opts,
        diags: Vec::new(),
        failed_lines,
        failed_actors,
        failed_stage,
    };
    let script = r.run(file);
    let ok = !r.diags.iter().any(Diagnostic::is_error);
    (if ok { Some(script) } else { None }, r.diags)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Dim {
    Length,
    Time,
    Angle,
}

impl Dim {
    fn unit(self) -> &'static str {
        match self {
            Dim::Length => "m",
            Dim::Time => "s",
            Dim::Angle => "deg",
        }
    }

    fn noun(self) -> &'static str {
        match self {
            Dim::Length => "a length in metres",
            Dim::Time => "a time in seconds",
            Dim::Angle => "an angle in degrees",
        }
    }

    /// Units a user may write instead, with the factor to ours.
    fn unit_factor(unit: &str) -> Option<(Dim, f64)> {
        Some(match unit {
            "m" | "meter" | "meters" | "metre" | "metres" => (Dim::Length, 1.0),
            "cm" => (Dim::Length, 0.01),
            "mm" => (Dim::Length, 0.001),
            "km" => (Dim::Length, 1000.0),
            "ft" => (Dim::Length, 0.3048),
            "in" => (Dim::Length, 0.0254),
            "s" | "sec" | "secs" | "second" | "seconds" => (Dim::Time, 1.0),
            "ms" => (Dim::Time, 0.001),
            "min" | "mins" | "minute" | "minutes" => (Dim::Time, 60.0),
            "h" => (Dim::Time, 3600.0),
            "deg" | "degree" | "degrees" | "degs" => (Dim::Angle, 1.0),
            "rad" => (Dim::Angle, 180.0 / std::f64::consts::PI),
            _ => return None,
        })
    }
}

/// A resolved shot body before it is placed on the clock.
struct Pending {
    transition: Transition,
    content: Option<ShotContent>,
    duration_s: Option<f64>,
    /// A camera move (`script::moves_camera`): timed with `over`.
    is_move: bool,
}

/// Where the shots placed so far end, and the line of the last one.
#[derive(Clone, Copy)]
struct Clock {
    now_s: f64,
    last: Option<Span>,
}

/// Where a shot goes on the clock: its start, whether that start is pinned, and how long it
/// lasts (`None` when that is unknown or wrong, and the shot is left off the timeline).
struct Placement {
    start_s: f64,
    pinned: bool,
    duration_s: Option<f64>,
}

struct Resolver<'o, 'a> {
    opts: &'o Options<'o>,
    diags: Vec<Diagnostic>,
    /// Start offsets of the lines that failed to parse: a `then` after one of them may be
    /// continuing it, so no "nothing to continue" error is reported.
    failed_lines: Vec<usize>,
    /// Names on `actor` lines that failed to parse: not reported again as unknown.
    failed_actors: Vec<&'a str>,
    /// A `stage` line failed to parse: no "missing stage" error.
    failed_stage: bool,
}

fn fmt_num(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    // A small number that rounds to 0 is shown in full, not as the 0 it is not.
    let r = if r == 0.0 && v != 0.0 { v } else { r };
    let s = format!("{r}");
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

impl<'o, 'a> Resolver<'o, 'a> {
    fn err(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }

    // -----------------------------------------------------------------------------------
    // Numbers

    /// A number of the given dimension, in our unit (radians for angles). `unit_optional`:
    /// a bare number is taken in our unit (coordinates).
    fn quantity(
        &mut self,
        q: &Quantity<'_>,
        dim: Dim,
        what: &str,
        unit_optional: bool,
    ) -> Option<f64> {
        let value = self.measure(q, dim, what, unit_optional)?;
        self.not_tiny(q, what)?;
        Some(if dim == Dim::Angle {
            value.to_radians()
        } else {
            value
        })
    }

    /// [`Self::quantity`] before its conversion to radians and its check against numbers
    /// too close to 0: the unit and the largest size.
    fn measure(
        &mut self,
        q: &Quantity<'_>,
        dim: Dim,
        what: &str,
        unit_optional: bool,
    ) -> Option<f64> {
        match q.unit {
            None if !unit_optional => {
                self.err(
                    Diagnostic::error(
                        PslCode::MissingUnit,
                        q.span,
                        format!("{what} `{}` has no unit", q.number),
                    )
                    .with_label(format!("{} needed", dim.noun()))
                    .with_help(format!("write `{}{}`", q.number, dim.unit())),
                );
                return None;
            }
            None => {}
            Some(u) if u.text == dim.unit() => {}
            Some(u) => {
                let mut d = Diagnostic::error(
                    PslCode::WrongUnit,
                    u.span,
                    match Dim::unit_factor(u.text) {
                        Some((d, _)) if d != dim => {
                            format!("{what} must be {}, not `{}`", dim.noun(), u.text)
                        }
                        Some(_) => format!(
                            "{what} is written in `{}`; dronecine uses `{}`",
                            u.text,
                            dim.unit()
                        ),
                        None => format!("unknown unit `{}` in {what}", u.text),
                    },
                )
                .with_label(format!("expected `{}`", dim.unit()));
                d.help = Some(match Dim::unit_factor(u.text) {
                    Some((d, f)) if d == dim => {
                        format!("write `{}{}`", fmt_num(q.value * f), dim.unit())
                    }
                    _ => format!("write `{}{}`", q.number, dim.unit()),
                });
                self.err(d);
                return None;
            }
        }
        if !q.value.is_finite() || q.value.abs() > 1e9 {
            self.err(
                Diagnostic::error(
                    PslCode::OutOfRange,
                    q.span,
                    format!("{what} `{}` is too large", shorten(q.number)),
                )
                .with_help("write a number of at most nine digits before the point"),
            );
            return None;
        }
        Some(q.value)
    }

    /// Refuse a number other than 0 smaller in size than [`MIN_MAGNITUDE`].
    fn not_tiny(&mut self, q: &Quantity<'_>, what: &str) -> Option<()> {
        if q.value != 0.0 && q.value.abs() < MIN_MAGNITUDE {
            self.err(
                Diagnostic::error(
                    PslCode::OutOfRange,
                    q.span,
                    format!("{what} `{}` is too small", shorten(q.number)),
                )
                .with_help(
                    "write 0 where 0 is meant, or a number with a non-zero digit within nine after the point",
                ),
            );
            return None;
        }
        Some(())
    }

    /// A unitless number (turns, screen coordinates).
    fn plain(&mut self, q: &Quantity<'_>, what: &str) -> Option<f64> {
        if let Some(u) = q.unit {
            self.err(
                Diagnostic::error(
                    PslCode::WrongUnit,
                    u.span,
                    format!("{what} has no unit, found `{}`", u.text),
                )
                .with_help(format!("write `{}`", q.number)),
            );
            return None;
        }
        if !q.value.is_finite() || q.value.abs() > 1e9 {
            self.err(
                Diagnostic::error(
                    PslCode::OutOfRange,
                    q.span,
                    format!("{what} `{}` is too large", shorten(q.number)),
                )
                .with_help("write a number of at most nine digits before the point"),
            );
            return None;
        }
        self.not_tiny(q, what)?;
        Some(q.value)
    }

    /// Check `v` against `bounds` and report with the range.
    fn range(&mut self, v: f64, span: Span, what: &str, bounds: Bounds) -> Option<f64> {
        let Bounds {
            lo,
            open_lo,
            hi,
            unit,
        } = bounds;
        let below = if open_lo { v <= lo } else { v < lo };
        if below || v > hi {
            let lo_txt = if open_lo {
                format!("more than {}{unit}", fmt_num(lo))
            } else {
                format!("at least {}{unit}", fmt_num(lo))
            };
            self.err(
                Diagnostic::error(
                    PslCode::OutOfRange,
                    span,
                    format!(
                        "{what} is {}{unit}; it must be {lo_txt} and at most {}{unit}",
                        fmt_num(v),
                        fmt_num(hi)
                    ),
                )
                .with_help(format!(
                    "choose a value between {}{unit} and {}{unit}",
                    fmt_num(lo),
                    fmt_num(hi)
                )),
            );
            return None;
        }
        Some(v)
    }

    fn time(&mut self, q: &Quantity<'_>, what: &str) -> Option<f64> {
        let v = self.quantity(q, Dim::Time, what, false)?;
        self.range(v, q.span, what, Bounds::closed(0.0, MAX_TIME_S, "s"))
    }

    fn duration(&mut self, d: &ast::Duration<'_>) -> Option<f64> {
        let v = self.measure(&d.value, Dim::Time, "the duration", false)?;
        if v <= 0.0 {
            self.err(
                Diagnostic::error(
                    PslCode::NonPositiveDuration,
                    d.value.span,
                    format!(
                        "a duration must be more than 0s, found `{}`",
                        d.value.number.to_string() + "s"
                    ),
                )
                .with_label("not a positive duration")
                .with_help("give it a positive length such as `for 4s`"),
            );
            return None;
        }
        if v < MIN_DURATION_S {
            self.err(
                Diagnostic::error(
                    PslCode::TooShort,
                    d.value.span,
                    format!(
                        "the duration `{}s` is shorter than 1 ms, one control period at the \
                         fastest rate",
                        shorten(d.value.number)
                    ),
                )
                .with_label("shorter than one tick")
                .with_help(
                    "make it at least `0.001s`, one tick at 1000 Hz (a shot on film lasts \
                     seconds, such as `4s`)",
                ),
            );
            return None;
        }
        self.range(
            v,
            d.value.span,
            "the duration",
            Bounds::above(0.0, MAX_TIME_S, "s"),
        )
    }

    fn point(&mut self, p: &ast::Point<'_>, what: &str) -> Option<[f64; 2]> {
        let x = self.quantity(&p.x, Dim::Length, what, true);
        let y = self.quantity(&p.y, Dim::Length, what, true);
        Some([x?, y?])
    }

    fn inside(&mut self, stage: Option<&Stage>, p: [f64; 2], span: Span, what: &str) {
        let Some(stage) = stage else { return };
        if !stage.contains_xy(p) {
            let (lo, hi) = (stage.min_m(), stage.max_m());
            self.err(
                Diagnostic::error(
                    PslCode::OutsideStage,
                    span,
                    format!("{what} ({}, {}) lies outside the stage", fmt_num(p[0]), fmt_num(p[1])),
                )
                .with_label("outside the stage")
                .with_help(format!(
                    "the stage spans x from {} to {} and y from {} to {}; move the point inside or enlarge the stage",
                    fmt_num(lo[0]),
                    fmt_num(hi[0]),
                    fmt_num(lo[1]),
                    fmt_num(hi[1])
                )),
            );
        }
    }

    fn inside_height(&mut self, stage: Option<&Stage>, z: f64, span: Span, what: &str) {
        let Some(stage) = stage else { return };
        if z < 0.0 || z > stage.size_m[2] + 1e-9 {
            self.err(
                Diagnostic::error(
                    PslCode::OutsideStage,
                    span,
                    format!("{what} {}m is outside the stage's height", fmt_num(z)),
                )
                .with_help(format!(
                    "the stage is {}m high; choose a height from 0m to {}m",
                    fmt_num(stage.size_m[2]),
                    fmt_num(stage.size_m[2])
                )),
            );
        }
    }

    fn actor_ref(
        &mut self,
        name: &ast::Text<'_>,
        declared: &HashMap<&str, Span>,
        annotation: bool,
    ) -> bool {
        if annotation || declared.contains_key(name.text) {
            return true;
        }
        if self.failed_actors.contains(&name.text) {
            return false;
        }
        let mut d = Diagnostic::error(
            PslCode::UnknownActor,
            name.span,
            format!("unknown actor `{}`", name.text),
        )
        .with_label("not declared");
        // Candidates in declaration order, so that the suggestion is the same on every run.
        let mut names: Vec<(&str, Span)> = declared.iter().map(|(n, s)| (*n, *s)).collect();
        names.sort_by_key(|(_, s)| s.start);
        d.help = Some(
            match did_you_mean(name.text, names.iter().map(|(n, _)| *n)) {
                Some(s) => s,
                None => format!(
                    "declare it before the shots: `actor {} height 1.75m at (0, 0) facing 0deg`",
                    name.text
                ),
            },
        );
        self.err(d);
        false
    }

    // -----------------------------------------------------------------------------------
    // The pass

    fn run(&mut self, file: &ast::File<'_>) -> Script {
        let statements: Vec<&Statement<'_>> = file
            .lines
            .iter()
            .filter_map(|l| l.statement.as_ref())
            .collect();
        let any_syntax_error = file.lines.iter().any(|l| l.error);

        let has_timed = statements.iter().any(|s| matches!(s, Statement::Timed(_)));
        let has_scene_lines = statements.iter().any(|s| !matches!(s, Statement::Timed(_)));
        let annotation = has_timed && !has_scene_lines;

        self.setup_after_shots(&statements);

        // Settings.
        let stage = self.stage(&statements);
        let lens = self.lens(&statements);
        let drone = self.drone(&statements);

        let (declared, actors) = self.actors(&statements, stage.as_ref());
        self.actors_apart(&actors);

        // Blocking.
        let blocking = self.blocking(&statements, &declared, stage.as_ref());

        // Timeline.
        let mut cast: Vec<String> = actors.iter().map(|a| a.name.clone()).collect();
        let timeline = self.timeline(
            &statements,
            &declared,
            stage.as_ref(),
            annotation,
            &mut cast,
        );

        let duration_s = timeline.last().map(|s| s.end_s).unwrap_or(0.0);
        if timeline.is_empty() && !any_syntax_error && !self.diags.iter().any(Diagnostic::is_error)
        {
            self.empty_script(&statements, &actors);
        }

        let scene = if annotation || statements.is_empty() {
            None
        } else {
            match stage {
                Some(stage) => Some(Scene {
                    stage,
                    lens,
                    drone,
                    actors,
                    blocking,
                }),
                None => {
                    self.missing_stage(&statements);
                    None
                }
            }
        };

        Script {
            scene,
            cast,
            timeline,
            duration_s,
        }
    }

    /// Report every scene set-up line (stage, lens, drone, actor) that comes after the first
    /// shot.
    fn setup_after_shots(&mut self, statements: &[&Statement<'_>]) {
        let mut seen_shot: Option<Span> = None;
        for s in statements {
            match s {
                Statement::Shot(sh) => {
                    seen_shot.get_or_insert(sh.span);
                }
                Statement::Timed(t) => {
                    seen_shot.get_or_insert(t.span);
                }
                Statement::Stage(_)
                | Statement::Lens(_)
                | Statement::Drone(_)
                | Statement::Actor(_) => {
                    if let Some(first) = seen_shot {
                        let what = match s {
                            Statement::Stage(_) => "stage",
                            Statement::Lens(_) => "lens",
                            Statement::Drone(_) => "drone",
                            _ => "actor",
                        };
                        self.err(
                            Diagnostic::error(
                                PslCode::SetupAfterShots,
                                s.span(),
                                format!("`{what}` comes after the first shot"),
                            )
                            .with_label("scene set-up")
                            .with_related(first, "the first shot")
                            .with_help("move the scene set-up (stage, lens, drone, actors) above the first shot"),
                        );
                    }
                }
                Statement::Blocking(_) => {}
            }
        }
    }

    /// The actors declared (each name once, with where), and those that resolved.
    fn actors<'s>(
        &mut self,
        statements: &[&'s Statement<'_>],
        stage: Option<&Stage>,
    ) -> (HashMap<&'s str, Span>, Vec<Actor>) {
        let mut declared: HashMap<&str, Span> = HashMap::new();
        let mut actors = Vec::new();
        for s in statements {
            if let Statement::Actor(a) = s {
                if let Some(first) = declared.get(a.name.text) {
                    self.err(
                        Diagnostic::error(
                            PslCode::DuplicateActor,
                            a.name.span,
                            format!("actor `{}` is declared twice", a.name.text),
                        )
                        .with_label("declared again here")
                        .with_related(*first, "first declared here")
                        .with_help("remove one declaration, or give the second actor another name"),
                    );
                    continue;
                }
                declared.insert(a.name.text, a.name.span);
                if let Some(actor) = self.actor(a, stage) {
                    actors.push(actor);
                }
            }
        }
        (declared, actors)
    }

    /// Two actors on one spot: no one stands there, and no framing can tell them apart.
    fn actors_apart(&mut self, actors: &[Actor]) {
        for (j, b) in actors.iter().enumerate() {
            let apart_m = |a: &Actor| {
                let (dx, dy) = (
                    a.position_m[0] - b.position_m[0],
                    a.position_m[1] - b.position_m[1],
                );
                (dx * dx + dy * dy).sqrt()
            };
            let near = actors[..j]
                .iter()
                .map(|a| (a, apart_m(a)))
                .find(|&(_, d)| d < ACTORS_MIN_APART_M);
            if let Some((a, d)) = near {
                self.err(
                    Diagnostic::error(
                        PslCode::ActorsOverlap,
                        b.span,
                        format!(
                            "`{}` starts {d:.2} m from `{}`: two actors cannot stand in one place",
                            b.name, a.name
                        ),
                    )
                    .with_label(format!("on `{}`'s spot", a.name))
                    .with_related(a.span, format!("`{}` stands here", a.name))
                    .with_help(format!(
                        "move one of them: two actors stand at least {ACTORS_MIN_APART_M} m apart \
                         (centre to centre)"
                    )),
                );
            }
        }
    }

    /// Warn of a script without shots, where the first shot would go: after the last line.
    fn empty_script(&mut self, statements: &[&Statement<'_>], actors: &[Actor]) {
        let end = statements.last().map_or(0, |s| s.span().end);
        let actor = actors.first().map_or("A", |a| a.name.as_str());
        self.err(
            Diagnostic::warning(
                PslCode::EmptyScript,
                Span::new(end, end),
                "the script has no shots",
            )
            .with_help(format!("add a shot such as `MS on {actor} front for 4s`")),
        );
    }

    /// Report a scene without a stage, unless its `stage` line is there and failed to parse.
    fn missing_stage(&mut self, statements: &[&Statement<'_>]) {
        if !self.failed_stage && !statements.iter().any(|s| matches!(s, Statement::Stage(_))) {
            let first = statements.first().map(|s| s.span()).unwrap_or_default();
            self.err(
                Diagnostic::error(PslCode::MissingStage, first, "the scene has no stage")
                    .with_label("a scene needs a stage before its shots")
                    .with_help("add the flight volume above the shots, e.g. `stage 8m x 6m x 3m`"),
            );
        }
    }

    fn first_of<'s, 'b, T>(
        &mut self,
        statements: &'s [&'s Statement<'b>],
        pick: impl Fn(&'s Statement<'b>) -> Option<&'s T>,
        span_of: impl Fn(&T) -> Span,
        what: &str,
    ) -> Option<&'s T> {
        let mut found: Option<&T> = None;
        for s in statements {
            if let Some(x) = pick(s) {
                match found {
                    None => found = Some(x),
                    Some(first) => self.err(
                        Diagnostic::error(
                            PslCode::DuplicateSetting,
                            span_of(x),
                            format!("`{what}` is set twice"),
                        )
                        .with_label("set again here")
                        .with_related(span_of(first), "first set here")
                        .with_help(format!("keep one `{what}` line")),
                    ),
                }
            }
        }
        found
    }

    fn stage(&mut self, statements: &[&Statement<'_>]) -> Option<Stage> {
        let st = self.first_of(
            statements,
            |s| match s {
                Statement::Stage(x) => Some(x),
                _ => None,
            },
            |x| x.span,
            "stage",
        )?;
        let mut size = [0.0; 3];
        let mut ok = true;
        for (i, (q, axis)) in [(&st.x, "x"), (&st.y, "y"), (&st.z, "z")]
            .into_iter()
            .enumerate()
        {
            let what = format!("the stage's {axis} size");
            match self
                .quantity(q, Dim::Length, &what, false)
                .and_then(|v| self.range(v, q.span, &what, Bounds::above(0.0, 1000.0, "m")))
            {
                Some(v) => size[i] = v,
                None => ok = false,
            }
        }
        ok.then_some(Stage { size_m: size })
    }

    fn lens(&mut self, statements: &[&Statement<'_>]) -> Option<Lens> {
        let l = self.first_of(
            statements,
            |s| match s {
                Statement::Lens(x) => Some(x),
                _ => None,
            },
            |x| x.span,
            "lens",
        )?;
        let fov = self
            .quantity(&l.fov, Dim::Angle, "the lens's field of view", false)
            .and_then(|v| {
                self.range(
                    v.to_degrees(),
                    l.fov.span,
                    "the lens's field of view",
                    Bounds::closed(1.0, 170.0, "deg"),
                )
            })
            .map(f64::to_radians);
        let aspect = match &l.aspect {
            None => Some(16.0 / 9.0),
            Some(a) => {
                let mut parts = a
                    .text
                    .splitn(2, ':')
                    .map(|p| p.parse::<f64>().unwrap_or(f64::NAN));
                let (w, h) = (
                    parts.next().unwrap_or(f64::NAN),
                    parts.next().unwrap_or(f64::NAN),
                );
                let ratio = w / h;
                if w > 0.0 && h > 0.0 && ratio.is_finite() && (0.25..=4.0).contains(&ratio) {
                    Some(ratio)
                } else {
                    self.err(
                        Diagnostic::error(
                            PslCode::BadAspect,
                            a.span,
                            format!("`{}` is not a usable aspect ratio", a.text),
                        )
                        .with_help(
                            "write width:height with positive numbers, e.g. `16:9` or `4:3`",
                        ),
                    );
                    None
                }
            }
        };
        Some(Lens {
            fov_x_rad: fov?,
            aspect: aspect?,
        })
    }

    fn drone(&mut self, statements: &[&Statement<'_>]) -> Option<DroneRef> {
        let d = self.first_of(
            statements,
            |s| match s {
                Statement::Drone(x) => Some(x),
                _ => None,
            },
            |x| x.span,
            "drone",
        )?;
        match &d.target {
            ast::DroneTarget::Builtin(name) => {
                let known = self.opts.known_drones;
                if !known.is_empty() && !known.contains(&name.text) {
                    let mut diag = Diagnostic::error(
                        PslCode::UnknownDrone,
                        name.span,
                        format!("unknown drone profile `{}`", name.text),
                    )
                    .with_label("not a built-in profile");
                    let list = dronecine_diag::suggest::or_list(known);
                    diag.help = Some(match did_you_mean(name.text, known.iter().copied()) {
                        Some(s) => format!("{s} (built-in profiles: {list}; or give a file: `drone \"mine.toml\"`)"),
                        None => format!("built-in profiles are {list}; for your own, write `drone \"profiles/mine.toml\"`"),
                    });
                    self.err(diag);
                    return None;
                }
                Some(DroneRef::Builtin {
                    name: name.text.to_string(),
                })
            }
            ast::DroneTarget::File(path) => {
                if let Some(base) = self.opts.base_dir {
                    let full = base.join(path.text);
                    if !full.is_file() {
                        let folder = full.is_dir();
                        self.err(
                            Diagnostic::error(
                                PslCode::FileNotFound,
                                path.span,
                                if folder {
                                    format!("`{}` is a folder, not a drone profile file", path.text)
                                } else {
                                    format!("drone profile file `{}` not found", path.text)
                                },
                            )
                            .with_label(format!("looked in {}", full.display()))
                            .with_help(if folder {
                                "name the profile's TOML file inside it, as `drone \"profiles/mine.toml\"`"
                            } else {
                                "file names are relative to the script's folder; check the name"
                            }),
                        );
                        return None;
                    }
                }
                Some(DroneRef::File {
                    path: path.text.to_string(),
                })
            }
        }
    }

    fn actor(&mut self, a: &ast::ActorDecl<'_>, stage: Option<&Stage>) -> Option<Actor> {
        let mut height = None;
        let mut position = None;
        let mut facing = None;
        let mut ok = true;
        let mut seen: HashMap<&str, Span> = HashMap::new();
        for attr in &a.attrs {
            let key = match attr {
                ast::ActorAttr::Height(..) => "height",
                ast::ActorAttr::At(..) => "at",
                ast::ActorAttr::Facing(..) => "facing",
            };
            if let Some(first) = seen.insert(key, attr.span()) {
                self.err(
                    Diagnostic::error(
                        PslCode::DuplicateAttribute,
                        attr.span(),
                        format!("`{key}` is given twice for `{}`", a.name.text),
                    )
                    .with_related(first, "first given here")
                    .with_help(format!("keep one `{key}`")),
                );
                ok = false;
                continue;
            }
            match attr {
                ast::ActorAttr::Height(_, q) => {
                    height = self
                        .quantity(q, Dim::Length, "the actor's height", false)
                        .and_then(|v| {
                            self.range(
                                v,
                                q.span,
                                "the actor's height",
                                Bounds::closed(0.2, 3.0, "m"),
                            )
                        });
                    ok &= height.is_some();
                }
                ast::ActorAttr::At(_, p) => {
                    position = self.point(p, "a position");
                    if let Some(pos) = position {
                        self.inside(
                            stage,
                            pos,
                            p.span,
                            &format!("the start position of `{}`", a.name.text),
                        );
                    }
                    ok &= position.is_some();
                }
                ast::ActorAttr::Facing(_, q) => {
                    facing = self.quantity(q, Dim::Angle, "the facing angle", false);
                    ok &= facing.is_some();
                }
            }
        }
        for (key, value, fix) in [
            (
                "height",
                height.is_some() || seen.contains_key("height"),
                "height 1.75m",
            ),
            (
                "position",
                position.is_some() || seen.contains_key("at"),
                "at (0, 0)",
            ),
        ] {
            if !value {
                self.err(
                    Diagnostic::error(
                        PslCode::MissingAttribute,
                        a.name.span,
                        format!("actor `{}` has no {key}", a.name.text),
                    )
                    .with_label(format!("{key} missing"))
                    .with_help(format!(
                        "add `{fix}`: `actor {} height 1.75m at (0, 0) facing 0deg`",
                        a.name.text
                    )),
                );
                ok = false;
            }
        }
        if !ok {
            return None;
        }
        Some(Actor {
            name: a.name.text.to_string(),
            height_m: height?,
            position_m: position?,
            facing_rad: wrap_angle_rad(facing.unwrap_or(0.0)),
            span: a.span,
        })
    }

    fn blocking(
        &mut self,
        statements: &[&Statement<'_>],
        declared: &HashMap<&str, Span>,
        stage: Option<&Stage>,
    ) -> Vec<Movement> {
        let mut moves: Vec<Movement> = Vec::new();
        for s in statements {
            let Statement::Blocking(b) = s else { continue };
            let known = self.actor_ref(&b.actor, declared, false);
            let start = self.time(&b.at, "the start time");
            let action = match &b.action {
                ast::Action::Walk(_, p) => self.point(p, "a position").map(|to| {
                    self.inside(
                        stage,
                        to,
                        p.span,
                        &format!("the walk target of `{}`", b.actor.text),
                    );
                    Action::Walk { to_m: to }
                }),
                ast::Action::Turn(_, q) => {
                    self.quantity(q, Dim::Angle, "the angle", false)
                        .map(|a| Action::Turn {
                            to_rad: wrap_angle_rad(a),
                        })
                }
            };
            let dur = match &b.duration {
                None => {
                    self.err(
                        Diagnostic::error(
                            PslCode::MissingDuration,
                            Span::new(b.span.end, b.span.end),
                            "this movement has no duration",
                        )
                        .with_label("add how long it takes")
                        .with_help("end the line with `over 4s`"),
                    );
                    None
                }
                Some(d) => {
                    if d.keyword == DurationKeyword::For {
                        self.err(
                            Diagnostic::warning(
                                PslCode::DurationKeyword,
                                d.span,
                                "a movement is timed with `over`",
                            )
                            .with_help(format!(
                                "write `over {}{}`",
                                d.value.number,
                                d.value.unit.map(|u| u.text).unwrap_or("s")
                            )),
                        );
                    }
                    self.duration(d)
                }
            };
            if let (true, Some(start), Some(action), Some(dur)) = (known, start, action, dur) {
                moves.push(Movement {
                    actor: b.actor.text.to_string(),
                    start_s: start,
                    end_s: start + dur,
                    action,
                    span: b.span,
                });
            }
        }
        // Overlaps, per actor, in time order.
        moves.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        let mut last_end: HashMap<&str, (f64, Span)> = HashMap::new();
        let mut overlapping = Vec::new();
        for m in &moves {
            if let Some(&(end, span)) = last_end.get(m.actor.as_str()) {
                if m.start_s < end - EPS_S {
                    overlapping.push(
                        Diagnostic::error(
                            PslCode::OverlappingMovement,
                            m.span,
                            format!(
                                "`{}` is still moving until {}s when this movement starts at {}s",
                                m.actor,
                                fmt_num(end),
                                fmt_num(m.start_s)
                            ),
                        )
                        .with_label("overlaps the previous movement")
                        .with_related(span, "this movement is not over yet")
                        .with_help(format!(
                            "start it `at {}s` or later, or shorten the previous one",
                            fmt_num(end)
                        )),
                    );
                    continue;
                }
            }
            last_end.insert(m.actor.as_str(), (m.end_s, m.span));
        }
        let bad = !overlapping.is_empty();
        self.diags.extend(overlapping);
        if bad {
            moves.clear();
        }
        moves
    }

    fn timeline(
        &mut self,
        statements: &[&Statement<'_>],
        declared: &HashMap<&str, Span>,
        stage: Option<&Stage>,
        annotation: bool,
        cast: &mut Vec<String>,
    ) -> Vec<Shot> {
        let mut timeline: Vec<Shot> = Vec::new();
        let mut clock = Clock {
            now_s: 0.0,
            last: None,
        };
        // What a `then` continues: the previous shot's content, if it resolved.
        let mut prev: Option<(Span, Option<ShotContent>)> = None;
        let mut first_untimed: Option<Span> = None;
        let mut first_timed: Option<Span> = None;

        for s in statements {
            let (span, body, pin, timecodes) = match s {
                Statement::Shot(sh) => {
                    first_untimed.get_or_insert(sh.span);
                    if let Some(t) = first_timed {
                        self.mixed(sh.span, t);
                    }
                    (sh.span, &sh.body, sh.pin.as_ref(), None)
                }
                Statement::Timed(t) => {
                    first_timed.get_or_insert(t.span);
                    if let Some(u) = first_untimed {
                        self.mixed(t.span, u);
                    }
                    (t.span, &t.body, None, Some(t))
                }
                _ => continue,
            };

            let pending = self.shot_body(body, prev.as_ref(), declared, stage, annotation, cast);
            let content_ok = pending.content.is_some();

            // Place it on the clock.
            let placed = if let Some(t) = timecodes {
                self.place_timed(t, body, clock)
            } else if let Some(p) = pin {
                self.place_pinned(p, clock, pending.duration_s)
            } else {
                if body.duration().is_none() {
                    self.missing_shot_duration(body, pending.is_move);
                }
                Placement {
                    start_s: clock.now_s,
                    pinned: false,
                    duration_s: pending.duration_s,
                }
            };

            if let Some(d) = placed.duration_s {
                let end = placed.start_s + d;
                if content_ok {
                    timeline.push(Shot {
                        start_s: placed.start_s,
                        end_s: end,
                        pinned: placed.pinned,
                        transition: pending.transition,
                        content: pending.content.clone().expect("checked above"),
                        span,
                        coverage: None,
                    });
                }
                clock.now_s = end;
            }
            clock.last = Some(span);
            prev = Some((span, pending.content));
        }
        timeline
    }

    /// Place a timed (subtitle) entry on the clock by its timecodes: it starts at the first
    /// and lasts until the second.
    fn place_timed(
        &mut self,
        t: &ast::TimedEntry<'_>,
        body: &ShotBody<'_>,
        clock: Clock,
    ) -> Placement {
        let mut placed = Placement {
            start_s: clock.now_s,
            pinned: false,
            duration_s: None,
        };
        if let Some(d) = body.duration() {
            self.err(
                Diagnostic::error(
                    PslCode::DurationInTimedEntry,
                    d.span,
                    "a timed entry takes its duration from its timecodes",
                )
                .with_help("remove the duration, or change the timecodes"),
            );
        }
        let a = self.timecode(&t.start);
        let b = self.timecode(&t.end);
        let (Some(a), Some(b)) = (a, b) else {
            return placed;
        };
        if b <= a {
            self.err(
                Diagnostic::error(
                    PslCode::TimecodeOrder,
                    t.start.span.to(t.end.span),
                    format!(
                        "this entry ends at {} before it starts at {}",
                        t.end.text, t.start.text
                    ),
                )
                .with_help("the second timecode is the end; it must come after the first"),
            );
            return placed;
        }
        if a < clock.now_s - EPS_S {
            let mut d = Diagnostic::error(
                PslCode::TimecodeOrder,
                t.start.span,
                format!(
                    "this entry starts at {} while the previous one runs until {}s",
                    t.start.text,
                    fmt_num(clock.now_s)
                ),
            )
            .with_help("entries must follow each other in time; fix either timecode");
            if let Some(p) = clock.last {
                d = d.with_related(p, "the previous entry");
            }
            self.err(d);
        }
        placed.start_s = a;
        placed.pinned = true;
        placed.duration_s = Some(b - a);
        placed
    }

    /// Place a shot pinned with `at` on the clock: at its time, unless the shots before it
    /// run past it.
    fn place_pinned(
        &mut self,
        p: &Quantity<'_>,
        clock: Clock,
        duration_s: Option<f64>,
    ) -> Placement {
        let mut placed = Placement {
            start_s: clock.now_s,
            pinned: false,
            duration_s,
        };
        if let Some(at) = self.time(p, "the start time") {
            if at < clock.now_s - EPS_S {
                let mut d = Diagnostic::error(
                    PslCode::PinnedStartOverlaps,
                    p.span,
                    format!(
                        "this shot is pinned at {}s but the shots before it run until {}s",
                        fmt_num(at),
                        fmt_num(clock.now_s)
                    ),
                )
                .with_label("starts too early")
                .with_help(format!(
                    "pin it `at {}s` or later, or shorten the shots before it",
                    fmt_num(clock.now_s)
                ));
                if let Some(p) = clock.last {
                    d = d.with_related(p, "the previous shot");
                }
                self.err(d);
            } else {
                placed.start_s = at;
                placed.pinned = true;
            }
        }
        placed
    }

    /// Report a shot without a duration, at the end of its line.
    fn missing_shot_duration(&mut self, body: &ShotBody<'_>, is_move: bool) {
        let end = body.span().end;
        self.err(
            Diagnostic::error(
                PslCode::MissingDuration,
                Span::new(end, end),
                "this shot has no duration",
            )
            .with_label("add how long it lasts")
            .with_help(if is_move {
                "end the line with `over 6s`: how long the move takes"
            } else {
                "end the line with `for 4s`: how long the shot lasts"
            }),
        );
    }

    fn mixed(&mut self, span: Span, other: Span) {
        self.err(
            Diagnostic::error(
                PslCode::MixedTiming,
                span,
                "timed (subtitle) entries and untimed shots are mixed",
            )
            .with_related(other, "the first entry of the other kind")
            .with_help(
                "write every shot with `for`/`over` durations, or every shot with timecodes",
            ),
        );
    }

    /// `[h]h:mm:ss[,mmm]` or `mm:ss[,mmm]` in seconds; 60 seconds is tolerated.
    fn timecode(&mut self, t: &ast::Text<'_>) -> Option<f64> {
        let (main, frac) = match t.text.find([',', '.']) {
            Some(i) => (&t.text[..i], Some(&t.text[i + 1..])),
            None => (t.text, None),
        };
        let fields: Vec<&str> = main.split(':').collect();
        let nums: Vec<Option<u64>> = fields
            .iter()
            .map(|f| if f.len() <= 6 { f.parse().ok() } else { None })
            .collect();
        let bad = |this: &mut Self, why: &str| {
            this.err(
                Diagnostic::error(
                    PslCode::BadTimecode,
                    t.span,
                    format!("timecode `{}` {why}", t.text),
                )
                .with_help("write hours:minutes:seconds, e.g. `00:01:03` or `00:01:03,500`"),
            );
            None
        };
        let (h, m, s) = match nums.as_slice() {
            [Some(h), Some(m), Some(s)] => (*h, *m, *s),
            [Some(m), Some(s)] => (0, *m, *s),
            _ => return bad(self, "is not hours:minutes:seconds"),
        };
        if m > 59 {
            return bad(self, "has more than 59 minutes");
        }
        if s > 60 {
            return bad(self, "has more than 60 seconds");
        }
        let frac_s = match frac {
            None => 0.0,
            Some(f) if !f.is_empty() && f.len() <= 3 => {
                f.parse::<f64>().unwrap_or(0.0) / 10f64.powi(f.len() as i32)
            }
            Some(_) => return bad(self, "has more than three digits of milliseconds"),
        };
        let at_s = (h * 3600 + m * 60 + s) as f64 + frac_s;
        if at_s > MAX_TIME_S {
            self.err(
                Diagnostic::error(
                    PslCode::BadTimecode,
                    t.span,
                    format!("timecode `{}` is past 24:00:00", t.text),
                )
                .with_label("more than a day")
                .with_help("a script runs at most a day: write a timecode up to `24:00:00`"),
            );
            return None;
        }
        Some(at_s)
    }

    fn shot_body(
        &mut self,
        body: &ShotBody<'_>,
        prev: Option<&(Span, Option<ShotContent>)>,
        declared: &HashMap<&str, Span>,
        stage: Option<&Stage>,
        annotation: bool,
        cast: &mut Vec<String>,
    ) -> Pending {
        match body {
            ShotBody::Framed(f) => {
                let transition = match &f.transition {
                    None => Transition::Cut,
                    Some(t) => match &t.kind {
                        TransitionKind::Cut => Transition::Cut,
                        TransitionKind::Dissolve => Transition::Dissolve,
                        TransitionKind::Move {
                            event,
                            kind,
                            follow,
                        } => {
                            self.continues(t.span, prev);
                            let follow = follow.as_ref().and_then(|n| {
                                self.actor_ref(n, declared, annotation)
                                    .then(|| n.text.to_string())
                            });
                            Transition::Move {
                                kind: *kind,
                                follow,
                                event: event.map(|e| event_text(&e)),
                            }
                        }
                    },
                };
                let content = self
                    .composition(&f.composition, declared, annotation, cast)
                    .map(ShotContent::Composition);
                // A move, as `script::moves_camera` tells it: `then hold to` another
                // composition than the one before moves there, as every `then … to` does.
                // (Without both compositions the line is an error already; its keyword is
                // judged by the move's kind alone.)
                let is_move = match (&transition, prev, &content) {
                    (
                        Transition::Move { kind, .. },
                        Some((_, Some(ShotContent::Composition(from)))),
                        Some(ShotContent::Composition(to)),
                    ) => crate::script::then_moves(*kind, from, to),
                    (Transition::Move { kind, .. }, _, _) => *kind != MoveKind::Hold,
                    _ => false,
                };
                let duration_s = f.duration.as_ref().and_then(|d| {
                    if is_move && d.keyword == DurationKeyword::For {
                        self.err(
                            Diagnostic::warning(
                                PslCode::DurationKeyword,
                                d.span,
                                "a camera move is timed with `over`",
                            )
                            .with_label("`for` holds a composition")
                            .with_help(format!(
                                "write `over {}`: the move takes that long",
                                quantity_text(&d.value)
                            )),
                        );
                    } else if !is_move && d.keyword == DurationKeyword::Over {
                        self.err(
                            Diagnostic::warning(
                                PslCode::DurationKeyword,
                                d.span,
                                "a held composition is timed with `for`",
                            )
                            .with_label("`over` times a camera move")
                            .with_help(format!("write `for {}`", quantity_text(&d.value))),
                        );
                    }
                    self.duration(d)
                });
                Pending {
                    transition,
                    content,
                    duration_s,
                    is_move,
                }
            }
            ShotBody::Hold(h) => {
                let content = self
                    .continues(h.span, prev)
                    .cloned()
                    .map(ShotContent::Composition);
                let duration_s = h.duration.as_ref().and_then(|d| self.duration(d));
                Pending {
                    transition: Transition::Move {
                        kind: MoveKind::Hold,
                        follow: None,
                        event: h.event.map(|e| event_text(&e)),
                    },
                    content,
                    duration_s,
                    is_move: false,
                }
            }
            ShotBody::Coverage(c) => self.coverage(c, declared, annotation),
            ShotBody::Path(p) => {
                if let Some(t) = &p.transition {
                    if matches!(t.kind, TransitionKind::Move { .. }) {
                        self.err(
                            Diagnostic::error(
                                PslCode::ThenToPath,
                                t.span,
                                "a `then` move cannot lead into a path",
                            )
                            .with_label("moves end on a composition")
                            .with_help("start the path with `cut to path …` (or just `path …`)"),
                        );
                    }
                }
                let content = self.path(p, declared, stage).map(ShotContent::Path);
                let duration_s = p.duration.as_ref().and_then(|d| self.duration(d));
                Pending {
                    transition: match p.transition.as_ref().map(|t| &t.kind) {
                        Some(TransitionKind::Dissolve) => Transition::Dissolve,
                        _ => Transition::Cut,
                    },
                    content,
                    duration_s,
                    is_move: false,
                }
            }
        }
    }

    /// A `coverage` line: its actors declared and distinct, a cut or a dissolve into it, and
    /// a duration the classic pattern fits in, written with `for`.
    fn coverage(
        &mut self,
        c: &ast::CoverageShot<'_>,
        declared: &HashMap<&str, Span>,
        annotation: bool,
    ) -> Pending {
        let transition = match c.transition.as_ref().map(|t| (t.span, &t.kind)) {
            Some((span, TransitionKind::Move { .. })) => {
                self.err(
                    Diagnostic::error(
                        PslCode::ThenToCoverage,
                        span,
                        "a `then` move cannot lead into a coverage: a coverage is a set of cuts",
                    )
                    .with_label("moves end on a composition")
                    .with_help(
                        "start the coverage with `cut to coverage …` (or just `coverage …`)",
                    ),
                );
                Transition::Cut
            }
            Some((_, TransitionKind::Dissolve)) => Transition::Dissolve,
            _ => Transition::Cut,
        };
        let a_known = self.actor_ref(&c.a, declared, annotation);
        let b_known = self.actor_ref(&c.b, declared, annotation);
        let distinct = c.a.text != c.b.text;
        if !distinct {
            self.err(
                Diagnostic::error(
                    PslCode::TwoShotSameActor,
                    c.b.span,
                    format!("`{}` is covered twice in one coverage", c.b.text),
                )
                .with_label("the same actor again")
                .with_related(c.a.span, "first here")
                .with_help("a coverage frames two different actors: name the other actor here"),
            );
        }
        let duration_s = c.duration.as_ref().and_then(|d| {
            if d.keyword == DurationKeyword::Over {
                self.err(
                    Diagnostic::warning(
                        PslCode::DurationKeyword,
                        d.span,
                        "a coverage is timed with `for`: it is a set of held shots",
                    )
                    .with_label("`over` times a camera move")
                    .with_help(format!("write `for {}`", quantity_text(&d.value))),
                );
            }
            let v = self.duration(d)?;
            if v < COVERAGE_MIN_S {
                self.err(
                    Diagnostic::error(
                        PslCode::CoverageTooShort,
                        d.value.span,
                        format!(
                            "a coverage of {}s is too short for its {COVERAGE_PARTS} shots",
                            fmt_num(v)
                        ),
                    )
                    .with_label(format!("at least {}s", fmt_num(COVERAGE_MIN_S)))
                    .with_help(format!(
                        "give it at least `for {}s`: {COVERAGE_PARTS} shots of at least {}s \
                         each and a repositioning flight of about {}s between two; or write the \
                         shots themselves",
                        fmt_num(COVERAGE_MIN_S),
                        fmt_num(COVERAGE_MIN_HOLD_S),
                        fmt_num(COVERAGE_MIN_FLIGHT_S)
                    )),
                );
                return None;
            }
            Some(v)
        });
        let content = (a_known && b_known && distinct).then(|| {
            ShotContent::Coverage(Coverage {
                a: c.a.text.to_string(),
                b: c.b.text.to_string(),
                size: c.size.map(|(_, s)| s),
            })
        });
        Pending {
            transition,
            content,
            duration_s,
            is_move: false,
        }
    }

    /// Check that a `then` line has a composition to continue; return it.
    fn continues<'p>(
        &mut self,
        span: Span,
        prev: Option<&'p (Span, Option<ShotContent>)>,
    ) -> Option<&'p Composition> {
        match prev {
            None if self.failed_lines.iter().any(|&l| l < span.start) => None,
            None => {
                self.err(
                    Diagnostic::error(PslCode::ThenWithoutShot, span, "`then` continues a shot, but no shot comes before it")
                        .with_help("start with a composition such as `MS on A front for 4s`, or write `cut to`"),
                );
                None
            }
            Some((pspan, Some(ShotContent::Path(_)))) => {
                self.err(
                    Diagnostic::error(
                        PslCode::ThenAfterPath,
                        span,
                        "`then` cannot continue a path: a path has no composition to move from",
                    )
                    .with_related(*pspan, "the path")
                    .with_help("write `cut to` and the composition instead"),
                );
                None
            }
            Some((cspan, Some(ShotContent::Coverage(_)))) => {
                self.err(
                    Diagnostic::error(
                        PslCode::ThenAfterCoverage,
                        span,
                        "`then` cannot continue a coverage: it ends on a single the compiler \
                         chooses",
                    )
                    .with_related(*cspan, "the coverage")
                    .with_help("write `cut to` and the composition instead"),
                );
                None
            }
            Some((_, Some(ShotContent::Composition(c)))) => Some(c),
            // The previous shot had errors of its own, already reported.
            Some((_, None)) => None,
        }
    }

    fn composition(
        &mut self,
        c: &ast::Composition<'_>,
        declared: &HashMap<&str, Span>,
        annotation: bool,
        cast: &mut Vec<String>,
    ) -> Option<Composition> {
        let mut ok = true;
        let mut framings = Vec::new();
        // actor -> (framing index, span)
        let mut seen: HashMap<&str, (usize, Span)> = HashMap::new();
        let mut distinct = 0usize;
        for (fi, f) in c.framings.iter().enumerate() {
            let mut subjects = Vec::new();
            for s in &f.subjects {
                let name = s.actor.text;
                if let Some(&(ffi, first)) = seen.get(name) {
                    let d = if ffi == fi {
                        Diagnostic::error(
                            PslCode::TwoShotSameActor,
                            s.actor.span,
                            format!("`{name}` is framed twice in one framing"),
                        )
                        .with_label("the same actor again")
                        .with_related(first, "first here")
                        .with_help(
                            "a two-shot frames two different actors: name the other actor here",
                        )
                    } else {
                        Diagnostic::error(
                            PslCode::ActorFramedTwice,
                            s.actor.span,
                            format!("`{name}` appears in two framings of one composition"),
                        )
                        .with_label("framed again")
                        .with_related(first, "already framed here")
                        .with_help("an actor appears once per composition; remove one framing or frame another actor")
                    };
                    self.err(d);
                    ok = false;
                    continue;
                }
                seen.insert(name, (fi, s.actor.span));
                distinct += 1;
                if annotation {
                    if !cast.iter().any(|c| c == name) {
                        cast.push(name.to_string());
                    }
                } else if !self.actor_ref(&s.actor, declared, false) {
                    ok = false;
                }
                let (mut sx, mut sy) = (None, None);
                if let Some(screen) = &s.screen {
                    match &screen.position {
                        ast::ScreenPosition::Third(t) => sx = Some(t.screen_x()),
                        ast::ScreenPosition::Point(x, y) => {
                            for (q, slot, axis) in [(x, &mut sx, "x"), (y, &mut sy, "y")] {
                                let what = format!("screen {axis}");
                                match self.plain(q, &what).and_then(|v| {
                                    self.range(v, q.span, &what, Bounds::closed(-1.0, 1.0, ""))
                                }) {
                                    Some(v) => *slot = Some(v),
                                    None => ok = false,
                                }
                            }
                        }
                    }
                }
                subjects.push(Subject {
                    actor: name.to_string(),
                    profile: s.profile.map(|(_, p)| p),
                    screen_x: sx,
                    screen_y: sy,
                });
            }
            framings.push(Framing {
                size: f.size.1,
                subjects,
            });
        }
        if !annotation && distinct > 2 {
            self.err(
                Diagnostic::error(
                    PslCode::TooManyActors,
                    c.span,
                    format!(
                        "this composition frames {distinct} actors; a drone frames at most two"
                    ),
                )
                .with_help("frame one or two actors per composition (cut between them for more)"),
            );
            ok = false;
        }
        ok.then(|| Composition {
            camera_angle: c.angle.map(|(_, a)| a).unwrap_or(CameraAngle::EyeLevel),
            framings,
        })
    }

    fn path(
        &mut self,
        p: &ast::PathShot<'_>,
        declared: &HashMap<&str, Span>,
        stage: Option<&Stage>,
    ) -> Option<Path> {
        let kind = &p.kind.1;
        let (given, mut ok) = self.path_params(p);
        ok &= self.unexpected_path_params(p);
        let params = PathParams {
            given,
            kind_span: p.kind.0,
            shape_name: kind.name(),
            span: p.span,
        };
        let clockwise = matches!(
            params.given.get("clockwise"),
            Some((_, PathValue::Clockwise(true)))
        );
        let looking_at = match params.given.get("looking at").copied() {
            Some((_, PathValue::LookingAt(n))) => {
                if self.actor_ref(n, declared, false) {
                    Some(n.text.to_string())
                } else {
                    ok = false;
                    None
                }
            }
            _ => None,
        };

        let shape = match kind {
            ast::PathKind::Square => {
                let (shape, corners_inside) = self.square(&params, stage, clockwise);
                ok &= corners_inside;
                shape
            }
            ast::PathKind::Helix => self.helix(&params, stage, clockwise),
            ast::PathKind::Orbit => self.orbit(&params, declared, stage, clockwise),
            ast::PathKind::Waypoints(file) => {
                self.waypoints(file, stage)
                    .map(|points_m| PathShape::Waypoints {
                        file: file.text.to_string(),
                        points_m,
                    })
            }
        };
        if !ok {
            return None;
        }
        Some(Path {
            shape: shape?,
            looking_at,
        })
    }

    /// A path's parameters by keyword, each given once (a second one is reported), and
    /// whether none was given twice.
    fn path_params<'p, 'v>(
        &mut self,
        p: &'p ast::PathShot<'v>,
    ) -> (HashMap<&'static str, (Span, &'p PathValue<'v>)>, bool) {
        let mut ok = true;
        let mut given: HashMap<&'static str, (Span, &PathValue<'_>)> = HashMap::new();
        for param in &p.params {
            let key = param.value.keyword();
            if let Some((first, _)) = given.get(key) {
                self.err(
                    Diagnostic::error(
                        PslCode::DuplicateAttribute,
                        param.span,
                        format!("`{key}` is given twice"),
                    )
                    .with_related(*first, "first given here")
                    .with_help(format!("keep one `{key}`")),
                );
                ok = false;
                continue;
            }
            given.insert(key, (param.span, &param.value));
        }
        (given, ok)
    }

    /// Report every parameter that the path's shape does not take; whether there was none.
    fn unexpected_path_params(&mut self, p: &ast::PathShot<'_>) -> bool {
        let kind = &p.kind.1;
        let shape_name = kind.name();
        let mut ok = true;
        let accepted: &[&str] = match kind {
            ast::PathKind::Square => &["side", "center", "altitude", "clockwise", "looking at"],
            ast::PathKind::Helix => &[
                "radius",
                "center",
                "from",
                "turns",
                "clockwise",
                "looking at",
            ],
            ast::PathKind::Orbit => &[
                "around",
                "center",
                "radius",
                "altitude",
                "turns",
                "clockwise",
                "looking at",
            ],
            ast::PathKind::Waypoints(_) => &["looking at"],
        };
        for param in &p.params {
            let key = param.value.keyword();
            if !accepted.contains(&key) {
                let shown: Vec<&str> = accepted
                    .iter()
                    .copied()
                    .filter(|k| *k != "clockwise")
                    .collect();
                self.err(
                    Diagnostic::error(
                        PslCode::UnexpectedPathParameter,
                        param.span,
                        format!("a {shape_name} path takes no `{key}`"),
                    )
                    .with_label("not a parameter of this shape")
                    .with_help(format!(
                        "a {shape_name} path takes {}",
                        dronecine_diag::suggest::or_list(&shown)
                    )),
                );
                ok = false;
            }
        }
        ok
    }

    /// A square path from its side, altitude and centre, and whether its corners lie inside
    /// the stage.
    fn square(
        &mut self,
        params: &PathParams<'_, '_>,
        stage: Option<&Stage>,
        clockwise: bool,
    ) -> (Option<PathShape>, bool) {
        let has =
            params.need(self, "side", "side 2m") & params.need(self, "altitude", "altitude 1.5m");
        let side = params.length(self, "side", "the side", true);
        let alt = params.length(self, "altitude", "the altitude", true);
        let c = params.center(self);
        let mut corners_inside = true;
        let shape = match (has, side, alt, c) {
            (true, Some(side), Some(alt), Some(c)) => {
                let h = side / 2.0;
                let corners = [[c[0] - h, c[1] - h], [c[0] + h, c[1] + h]];
                if corners
                    .iter()
                    .any(|p| stage.is_some_and(|s| !s.contains_xy(*p)))
                {
                    self.inside(stage, corners[0], params.span, "a corner of the square");
                    self.inside(stage, corners[1], params.span, "a corner of the square");
                    corners_inside = false;
                }
                self.inside_height(stage, alt, params.given["altitude"].0, "the altitude");
                Some(PathShape::Square {
                    side_m: side,
                    center_m: c,
                    altitude_m: alt,
                    clockwise,
                })
            }
            _ => None,
        };
        (shape, corners_inside)
    }

    /// A helix path from its radius, centre, turns and heights.
    fn helix(
        &mut self,
        params: &PathParams<'_, '_>,
        stage: Option<&Stage>,
        clockwise: bool,
    ) -> Option<PathShape> {
        let has = params.need(self, "radius", "radius 1.5m")
            & params.need(self, "from", "from 1m to 2.5m");
        let radius = params.length(self, "radius", "the radius", true);
        let c = params.center(self);
        let t = params.turns(self);
        let from_to = match params.given.get("from").copied() {
            Some((span, PathValue::FromTo(a, b))) => {
                let a = self.quantity(a, Dim::Length, "the start height", false);
                let b = self.quantity(b, Dim::Length, "the end height", false);
                if let (Some(a), Some(b)) = (a, b) {
                    self.inside_height(stage, a, span, "the start height");
                    self.inside_height(stage, b, span, "the end height");
                }
                a.zip(b)
            }
            _ => None,
        };
        match (has, radius, c, t, from_to) {
            (true, Some(r), Some(c), Some(t), Some((a, b))) => {
                self.circle_inside(stage, c, r, params.span, "helix");
                Some(PathShape::Helix {
                    radius_m: r,
                    center_m: c,
                    from_m: a,
                    to_m: b,
                    turns: t,
                    clockwise,
                })
            }
            _ => None,
        }
    }

    /// An orbit path from its radius, altitude, turns and what it goes round: an actor or a
    /// fixed centre.
    fn orbit(
        &mut self,
        params: &PathParams<'_, '_>,
        declared: &HashMap<&str, Span>,
        stage: Option<&Stage>,
        clockwise: bool,
    ) -> Option<PathShape> {
        let given = &params.given;
        let has = params.need(self, "radius", "radius 2m")
            & params.need(self, "altitude", "altitude 1.5m");
        let radius = params.length(self, "radius", "the radius", true);
        let alt = params.length(self, "altitude", "the altitude", true);
        let t = params.turns(self);
        let center = match (given.get("around").copied(), given.get("center").copied()) {
            (Some((_, PathValue::Around(n))), None) => {
                self.actor_ref(n, declared, false)
                    .then(|| OrbitCenter::Actor {
                        name: n.text.to_string(),
                    })
            }
            (None, Some((_, PathValue::Center(pt)))) => self.point(pt, "the centre").map(|at| {
                if let Some(r) = radius {
                    self.circle_inside(stage, at, r, params.span, "orbit");
                }
                OrbitCenter::Point { at_m: at }
            }),
            (Some((a, _)), Some((c, _))) => {
                self.err(
                    Diagnostic::error(PslCode::UnexpectedPathParameter, c, "an orbit goes `around` an actor or about a `center`, not both")
                        .with_related(a, "`around` given here")
                        .with_help("remove `center (x, y)` to orbit the actor, or `around` to orbit a fixed point"),
                );
                None
            }
            _ => {
                self.err(
                    Diagnostic::error(
                        PslCode::MissingPathParameter,
                        params.kind_span,
                        "an orbit needs `around A` or `center (x, y)`",
                    )
                    .with_label("what to orbit?")
                    .with_help(
                        "add `around A` to circle an actor, or `center (0, 0)` for a fixed point",
                    ),
                );
                None
            }
        };
        if let Some(alt) = alt {
            self.inside_height(stage, alt, given["altitude"].0, "the altitude");
        }
        match (has, radius, alt, t, center) {
            (true, Some(r), Some(alt), Some(t), Some(center)) => Some(PathShape::Orbit {
                center,
                radius_m: r,
                altitude_m: alt,
                turns: t,
                clockwise,
            }),
            _ => None,
        }
    }

    fn circle_inside(
        &mut self,
        stage: Option<&Stage>,
        c: [f64; 2],
        r: f64,
        span: Span,
        what: &str,
    ) {
        let Some(stage) = stage else { return };
        let (lo, hi) = (stage.min_m(), stage.max_m());
        if c[0] - r < lo[0] - 1e-9
            || c[0] + r > hi[0] + 1e-9
            || c[1] - r < lo[1] - 1e-9
            || c[1] + r > hi[1] + 1e-9
        {
            self.err(
                Diagnostic::error(
                    PslCode::OutsideStage,
                    span,
                    format!("the {what} (radius {}m about ({}, {})) leaves the stage", fmt_num(r), fmt_num(c[0]), fmt_num(c[1])),
                )
                .with_help(format!(
                    "the stage spans x from {} to {} and y from {} to {}; shrink the radius or move the centre",
                    fmt_num(lo[0]),
                    fmt_num(hi[0]),
                    fmt_num(lo[1]),
                    fmt_num(hi[1])
                )),
            );
        }
    }

    /// Read a waypoints CSV: one `x, y, z` per line in metres; `#` comments and one header
    /// line allowed.
    fn waypoints(&mut self, file: &ast::Text<'_>, stage: Option<&Stage>) -> Option<Vec<[f64; 3]>> {
        let Some(base) = self.opts.base_dir else {
            return Some(Vec::new());
        };
        let path = base.join(file.text);
        let text = match std::fs::read(&path) {
            Ok(bytes) => {
                match String::from_utf8(bytes) {
                    Ok(t) => t,
                    Err(_) => {
                        self.err(
                        Diagnostic::error(PslCode::BadWaypoints, file.span, format!("`{}` is not UTF-8 text", file.text))
                            .with_help("save the waypoints as a plain-text CSV: x, y, z in metres per line"),
                    );
                        return None;
                    }
                }
            }
            Err(e) => {
                self.err(
                    Diagnostic::error(
                        PslCode::FileNotFound,
                        file.span,
                        format!("cannot read waypoints file `{}`: {e}", file.text),
                    )
                    .with_label(format!("looked for {}", path.display()))
                    .with_help("file names are relative to the script's folder; check the name"),
                );
                return None;
            }
        };
        let mut points = Vec::new();
        let mut header_allowed = true;
        for (i, line) in text.lines().enumerate() {
            let l = line.trim();
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = l.split(',').map(str::trim).collect();
            let nums: Vec<Option<f64>> = fields
                .iter()
                .map(|f| f.parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect();
            if nums.iter().all(Option::is_none) && header_allowed {
                header_allowed = false;
                continue;
            }
            header_allowed = false;
            match nums.as_slice() {
                [Some(x), Some(y), Some(z)] => {
                    let p = [*x, *y, *z];
                    let tiny = p.iter().position(|v| *v != 0.0 && v.abs() < MIN_MAGNITUDE);
                    if let Some(k) = tiny {
                        self.err(
                            Diagnostic::error(
                                PslCode::OutOfRange,
                                file.span,
                                format!(
                                    "`{}` line {}: `{}` is too small",
                                    file.text,
                                    i + 1,
                                    shorten(fields[k])
                                ),
                            )
                            .with_help(
                                "write 0 where 0 is meant, or a number with a non-zero digit within nine after the point",
                            ),
                        );
                        return None;
                    }
                    if stage.is_some_and(|s| !s.contains(p)) {
                        self.err(
                            Diagnostic::error(
                                PslCode::OutsideStage,
                                file.span,
                                format!(
                                    "`{}` line {}: waypoint ({}, {}, {}) is outside the stage",
                                    file.text,
                                    i + 1,
                                    x,
                                    y,
                                    z
                                ),
                            )
                            .with_help("move the waypoint inside the stage or enlarge the stage"),
                        );
                        return None;
                    }
                    points.push(p);
                }
                _ => {
                    self.err(
                        Diagnostic::error(
                            PslCode::BadWaypoints,
                            file.span,
                            format!(
                                "`{}` line {}: expected three numbers x, y, z, found `{}`",
                                file.text,
                                i + 1,
                                shorten(l)
                            ),
                        )
                        .with_help("write one waypoint per line as `x, y, z` in metres"),
                    );
                    return None;
                }
            }
        }
        if points.len() < 2 {
            self.err(
                Diagnostic::error(
                    PslCode::BadWaypoints,
                    file.span,
                    format!(
                        "`{}` has {} waypoint(s); a path needs at least 2",
                        file.text,
                        points.len()
                    ),
                )
                .with_help("add waypoints, one `x, y, z` per line"),
            );
            return None;
        }
        Some(points)
    }
}

/// A path's parameters by keyword, with what their shape's checks report against: the
/// shape's name and keyword, and the path's line.
struct PathParams<'p, 'v> {
    given: HashMap<&'static str, (Span, &'p PathValue<'v>)>,
    kind_span: Span,
    shape_name: &'static str,
    span: Span,
}

impl PathParams<'_, '_> {
    /// Whether `key` is given; if not, report it missing with `example`.
    fn need(&self, r: &mut Resolver<'_, '_>, key: &str, example: &str) -> bool {
        if self.given.contains_key(key) {
            return true;
        }
        let shape_name = self.shape_name;
        r.err(
            Diagnostic::error(
                PslCode::MissingPathParameter,
                self.kind_span,
                format!("a {shape_name} path needs `{key}`"),
            )
            .with_label(format!("`{key}` missing"))
            .with_help(format!("add `{example}`")),
        );
        false
    }

    /// The length given as `key` in metres, if given and valid; `positive`: from
    /// [`MIN_PATH_LENGTH_M`] to 1000 m.
    fn length(
        &self,
        r: &mut Resolver<'_, '_>,
        key: &str,
        what: &str,
        positive: bool,
    ) -> Option<f64> {
        let Some((_, PathValue::Side(q) | PathValue::Altitude(q) | PathValue::Radius(q))) =
            self.given.get(key).copied()
        else {
            return None;
        };
        let v = r.quantity(q, Dim::Length, what, false)?;
        if positive {
            r.range(
                v,
                q.span,
                what,
                Bounds::closed(MIN_PATH_LENGTH_M, 1000.0, "m"),
            )
        } else {
            Some(v)
        }
    }

    /// The `center` given, or the stage's centre (0, 0).
    fn center(&self, r: &mut Resolver<'_, '_>) -> Option<[f64; 2]> {
        match self.given.get("center").copied() {
            Some((_, PathValue::Center(pt))) => r.point(pt, "the centre"),
            _ => Some([0.0, 0.0]),
        }
    }

    /// The number of `turns` given, or 1.
    fn turns(&self, r: &mut Resolver<'_, '_>) -> Option<f64> {
        match self.given.get("turns").copied() {
            Some((_, PathValue::Turns(q))) => r.plain(q, "the number of turns").and_then(|v| {
                r.range(
                    v,
                    q.span,
                    "the number of turns",
                    Bounds::above(0.0, 100.0, ""),
                )
            }),
            _ => Some(1.0),
        }
    }
}

/// The event as plain text: a quoted event verbatim, free words joined by single spaces.
fn event_text(e: &ast::Event<'_>) -> String {
    if e.quoted {
        e.text.to_string()
    } else {
        e.text.split_whitespace().collect::<Vec<_>>().join(" ")
    }
}

fn quantity_text(q: &Quantity<'_>) -> String {
    format!("{}{}", q.number, q.unit.map(|u| u.text).unwrap_or("s"))
}

/// The accepted range of a number, for [`Resolver::range`]'s check and its message.
#[derive(Clone, Copy)]
struct Bounds {
    lo: f64,
    /// `lo < v` instead of `lo <= v`.
    open_lo: bool,
    hi: f64,
    unit: &'static str,
}

impl Bounds {
    /// `lo <= v <= hi`.
    fn closed(lo: f64, hi: f64, unit: &'static str) -> Bounds {
        Bounds {
            lo,
            open_lo: false,
            hi,
            unit,
        }
    }

    /// `lo < v <= hi`.
    fn above(lo: f64, hi: f64, unit: &'static str) -> Bounds {
        Bounds {
            lo,
            open_lo: true,
            hi,
            unit,
        }
    }
}
