//! Staying in frame (`film::out_of_frame`): a framed actor must stay inside the frame —
//! their head and, for the sizes that show them, their feet within a tenth of the frame's
//! height of its top and bottom edges, the centre of their band (their screen point) inside
//! the frame — through a hold, a move and a path `looking at` them. Reported once per shot
//! with when, how far, and why.

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_compiler::size;
use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::{Composition, PathShape};
use dronecine_profile::Gimbal;

use crate::code::FilmCode;

/// How far past the frame's top or bottom edge a band's end may land (screen units: the
/// frame is 2 high), a tenth of the frame's height.
pub const EDGE_SLACK: f64 = 0.2;
/// The first seconds of a shot, while the camera settles on its framing, are not judged.
pub const SETTLE_S: f64 = 0.5;

/// An actor that must stay in frame, and the band of them that must.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kept {
    pub actor: usize,
    /// Bottom and top above the feet, metres.
    pub band_m: [f64; 2],
}

/// Where an actor left the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    Above,
    Below,
    Left,
    Right,
    /// Behind the camera.
    Behind,
}

/// A shot's time out of frame: from the first tick out to the last, how many ticks, and the
/// worst (the actor, the edge, how far past it in screen units).
#[derive(Clone, Copy, Debug, Default)]
pub struct Out {
    pub first_s: Option<f64>,
    pub last_s: f64,
    pub ticks_out: u64,
    pub ticks: u64,
    pub worst: Option<(usize, Edge, f64)>,
    /// The height above the floor of the worst actor's band centre then, metres.
    pub worst_centre_m: f64,
    /// Whether the camera's pitch was at the end of its gimbal's range at the worst tick.
    pub worst_clamped: bool,
}

/// The actors a composition keeps in frame: a single's actor, both actors of a two-shot,
/// the background actor of an over-the-shoulder (the foreground one is framed at the frame's
/// edge by design), each with its size's band.
pub fn kept(c: &Composition, names: &[String], heights_m: &[f64]) -> [Option<Kept>; 2] {
    let of = |actor: &str, size| {
        let i = names.iter().position(|n| n == actor)?;
        let (b, t) = size::band(size, *heights_m.get(i)?);
        Some(Kept {
            actor: i,
            band_m: [b, t],
        })
    };
    match c.framings.as_slice() {
        [f] => [
            f.subjects.first().and_then(|s| of(&s.actor, f.size)),
            f.subjects.get(1).and_then(|s| of(&s.actor, f.size)),
        ],
        [_, bg] => [
            bg.subjects.first().and_then(|s| of(&s.actor, bg.size)),
            None,
        ],
        _ => [None, None],
    }
}

/// The altitudes a path flies between, metres (`None` for one without a written altitude).
pub fn path_altitude_m(shape: &PathShape) -> Option<(f64, f64)> {
    match shape {
        PathShape::Square { altitude_m, .. } | PathShape::Orbit { altitude_m, .. } => {
            Some((*altitude_m, *altitude_m))
        }
        PathShape::Helix { from_m, to_m, .. } => Some((from_m.min(*to_m), from_m.max(*to_m))),
        PathShape::Waypoints { points_m, .. } => {
            let zs = points_m.iter().map(|p| p[2]);
            let lo = zs.clone().fold(f64::INFINITY, f64::min);
            let hi = zs.fold(f64::NEG_INFINITY, f64::max);
            lo.is_finite().then_some((lo, hi))
        }
    }
}

/// How far past the frame an actor lands seen from `camera`, and where; `None` when in
/// frame. The head is judged when the band reaches it, the feet when the band does.
fn outside(
    camera: &CameraPose,
    lens: &Lens,
    pose: &ActorPose,
    band_m: [f64; 2],
) -> Option<(Edge, f64)> {
    let feet = Vec3::from(pose.position_m);
    let up = |h: f64| feet + Vec3::new(0.0, 0.0, h);
    let frame = camera.frame();
    let centre = frame.project(lens, &up((band_m[0] + band_m[1]) / 2.0));
    let Some(centre) = centre else {
        return Some((Edge::Behind, f64::INFINITY));
    };
    let head_m = pose.height_m;
    let top = (band_m[1] >= head_m)
        .then(|| frame.project(lens, &up(head_m)))
        .flatten();
    let bottom = (band_m[0] <= 0.0)
        .then(|| frame.project(lens, &up(0.0)))
        .flatten();
    let mut worst: Option<(Edge, f64)> = None;
    let mut consider = |edge: Edge, past: f64| {
        if past > 0.0 && worst.is_none_or(|w| past > w.1) {
            worst = Some((edge, past));
        }
    };
    if let Some(t) = top {
        consider(Edge::Above, t[1] - 1.0 - EDGE_SLACK);
    }
    if let Some(b) = bottom {
        consider(Edge::Below, -1.0 - EDGE_SLACK - b[1]);
    }
    consider(Edge::Right, centre[0] - 1.0);
    consider(Edge::Left, -1.0 - centre[0]);
    consider(Edge::Above, centre[1] - 1.0);
    consider(Edge::Below, -1.0 - centre[1]);
    worst
}

/// One tick of a shot that started at `start_s`.
pub fn see(
    out: &mut Out,
    kept: &[Option<Kept>; 2],
    sample: &Sample,
    start_s: f64,
    actors: &[ActorPose],
    (lens, gimbal): (&Lens, &Gimbal),
) {
    if sample.t_s < start_s + SETTLE_S {
        return;
    }
    let camera = CameraPose {
        position_m: Vec3::from(sample.position_m),
        heading_rad: sample.heading_rad,
        pitch_rad: sample.camera_pitch_rad,
    };
    let mut any = false;
    for k in kept.iter().flatten() {
        let Some(pose) = actors.get(k.actor) else {
            continue;
        };
        out.ticks += 1;
        if let Some((edge, past)) = outside(&camera, lens, pose, k.band_m) {
            any = true;
            if out.worst.is_none_or(|w| past > w.2) {
                out.worst = Some((k.actor, edge, past));
                out.worst_centre_m = pose.position_m[2] + (k.band_m[0] + k.band_m[1]) / 2.0;
                out.worst_clamped = at_range_end(gimbal, sample.camera_pitch_rad);
            }
        }
    }
    if any {
        out.first_s.get_or_insert(sample.t_s);
        out.last_s = sample.t_s;
        out.ticks_out += 1;
    }
}

/// Whether `pitch_rad` is at an end of the gimbal's range.
fn at_range_end(gimbal: &Gimbal, pitch_rad: f64) -> bool {
    match gimbal {
        Gimbal::None => false,
        Gimbal::Pitch {
            min_rad, max_rad, ..
        } => (pitch_rad - min_rad).abs() < 1e-6 || (pitch_rad - max_rad).abs() < 1e-6,
    }
}

/// What the warning needs of its shot.
pub struct Context<'a> {
    pub span: Span,
    pub start_s: f64,
    pub duration_s: f64,
    pub names: &'a [String],
    pub lens: &'a Lens,
    pub gimbal: &'a Gimbal,
    pub path_altitude_m: Option<(f64, f64)>,
}

/// The shot's warning, if an actor it frames was out of frame.
pub fn diagnostic(out: &Out, cx: Context<'_>) -> Option<Diagnostic> {
    let first = out.first_s?;
    let (actor, edge, past) = out.worst?;
    let who = cx.names.get(actor).map_or("an actor", String::as_str);
    let (from, to) = (first - cx.start_s, out.last_s - cx.start_s);
    let level = matches!(cx.gimbal, Gimbal::None);
    let vertical = matches!(edge, Edge::Above | Edge::Below);
    let (where_, cause, help) = match (edge, vertical, level, cx.path_altitude_m) {
        (Edge::Behind, ..) => (
            "behind the camera".to_string(),
            "the camera turns away from them".to_string(),
            "aim the shot at them, or shorten the move".to_string(),
        ),
        (_, true, true, Some((lo, hi))) => (
            edge_words(edge),
            format!(
                "the camera is level and cannot tilt, and the path flies at {} where {who} \
                 is framed at {:.1} m",
                altitude_words(lo, hi),
                out.worst_centre_m
            ),
            "fly the path nearer their height, farther from them, or with a drone that has a \
             gimbal (a profile with `gimbal = { … }`)"
                .to_string(),
        ),
        (_, true, true, None) => (
            edge_words(edge),
            "the camera is level and cannot tilt: the drone's altitude alone frames them"
                .to_string(),
            "frame them looser, or fly a drone with a gimbal (a profile with `gimbal = { … }`)"
                .to_string(),
        ),
        (_, true, false, _) if out.worst_clamped => (
            edge_words(edge),
            "the gimbal cannot pitch the camera far enough".to_string(),
            "frame them looser, or fly the camera nearer their height".to_string(),
        ),
        (_, true, false, Some((lo, hi))) => (
            edge_words(edge),
            format!(
                "the path passes too near {who} at {} for the camera to take all of them in",
                altitude_words(lo, hi)
            ),
            "fly the path farther from them".to_string(),
        ),
        (_, true, false, None) => (
            edge_words(edge),
            "the framing leaves no room (a two-shot's size is for their mean height: the \
             taller is framed tighter)"
                .to_string(),
            "write a looser size".to_string(),
        ),
        (_, false, ..) => (
            edge_words(edge),
            format!(
                "the lens ({:.0}° across) is too narrow for the framing",
                cx.lens.fov_x_rad().to_degrees()
            ),
            "frame them looser, or bring their screen positions nearer the centre".to_string(),
        ),
    };
    let share = if out.ticks > 0 {
        100.0 * out.ticks_out as f64 / (out.ticks as f64).max(1.0)
    } else {
        0.0
    };
    let past_words = if past.is_finite() {
        format!(
            "; at worst {:.0}% of the frame's height past it",
            past / 2.0 * 100.0
        )
    } else {
        String::new()
    };
    Some(
        Diagnostic::warning(
            FilmCode::OutOfFrame,
            cx.span,
            format!(
                "{who} leaves the frame {where_} from {from:.1} s to {to:.1} s into this {:.1} s \
                 shot ({share:.0}% of it{past_words}): {cause}",
                cx.duration_s
            ),
        )
        .with_label(format!("{who} out of frame"))
        .with_help(help),
    )
}

fn edge_words(edge: Edge) -> String {
    match edge {
        Edge::Above => "above its top",
        Edge::Below => "below its bottom",
        Edge::Left => "past its left edge",
        Edge::Right => "past its right edge",
        Edge::Behind => "behind the camera",
    }
    .to_string()
}

fn altitude_words(lo: f64, hi: f64) -> String {
    if (hi - lo).abs() < 1e-6 {
        format!("{lo:.1} m")
    } else {
        format!("{lo:.1} to {hi:.1} m")
    }
}
