//! From a PSL composition to a camera placement: the public API the timeline calls every tick.
//!
//! - [`solve`] turns a [`Composition`] and the actors' current poses into a [`Visual`]: the
//!   composition's visual parameters expressed relative to the actors (sphere coordinates
//!   about one actor, toric coordinates about a pair), so that holding a `Visual` while the
//!   actors move keeps the framing, and a transition interpolates parameters, not positions.
//! - [`place`] turns a `Visual` and the actors' poses into a camera position, heading and
//!   pitch, with [`Flags`] for what the drone cannot render.
//! - [`interpolate`] blends two `Visual`s for a camera move.
//! - [`screen_targets`] gives each framed actor's world point and requested screen point (the
//!   framing-error metric); [`body_axis_distances_m`] the camera's distance to each actor's
//!   body axis (safety); [`velocity_mps`] the feed-forward camera velocity of a held `Visual`.
//!
//! Conventions:
//! - **Aim points.** Each framed actor has a band (its size, [`size`]) `[bottom, top]` above
//!   the feet; the band centre M is the aim point of the sphere and torus. A requested screen
//!   point `(x, y)` means: the band spans the frame height with its centre at `(x, y)`
//!   (default `y = 0`: the band fills the frame; its ends land at `y ± 1`).
//! - **One actor** (`MS on A 34left screen right`): `C = M + d·û(h + θ, φ)`, θ the profile
//!   azimuth (default front), φ the camera-angle elevation ([`sphere::elevation_rad`]), d the
//!   exact distance of [`size::exact_distance_m`] (the band subtends the angle between the
//!   rays through `(x, y ± 1)`).
//!   The camera aims the band's *bisector point* Q (the point of the band seen halfway between
//!   its ends, [`size::bisector_point`]) at [`size::band_aim_screen`]; Q lands there exactly,
//!   and for `x = 0` the band's top and bottom land exactly on `y ± 1` whatever the elevation.
//!   (Q = M for a level camera with `y = 0`.) Off-centre (`x ≠ 0`) with a pitched camera a
//!   vertical band is seen slightly slanted: its ends land within about 0.02 of `(x, y ± 1)`.
//! - **Fixed-pitch camera** (`Gimbal::None`): the camera is level; it stays on the sphere's
//!   vertical half-plane θ at horizontal distance `d = h·Sy·√(1 + x'²)` (h the half band,
//!   `x' = x/Sx`) and at the altitude `M_z − y·h` that puts M at `y`: the band then spans
//!   `[y − 1, y + 1]` exactly at any `x`. A non-zero elevation cannot be rendered:
//!   [`Flags::angle_not_rendered`].
//! - **Two actors in one framing** (`MS on A and B`): A at x = −1/3, B at +1/3 unless screen
//!   positions say otherwise; α from the two screen points; φ = elevation on the φ = 0 side
//!   (A left) or π − elevation on the far side (A right); θ so that the *nearer* actor has its
//!   size (toric distance constraints, both actors tried, the root nearest the symmetric
//!   θ = π − α kept). If the first subject has a profile, the vantage formula gives (θ, φ)
//!   instead and the size is not kept. Primary actor (aimed exactly) = the sized actor, or the
//!   first subject when a profile was used.
//! - **Over the shoulder** (two framings, foreground then background): toric pair (A =
//!   foreground, B = background); θ ∈ the two roots of the background distance constraint, so
//!   the background actor's size is exact; φ (and the root) minimise the angle between C − A
//!   and the foreground's profile direction (or, without one, C − B and the background's
//!   profile direction; without either, φ = elevation on the side of the screen order and the
//!   root nearer the foreground actor). Screens are exact up to the roll-free error below; the
//!   profile holds as well as the torus allows. Primary = background actor. Held tick after
//!   tick ([`Prepared::solve_near`], as the director solves), the framing keeps its root until
//!   the other frames the profile [`BRANCH_KEEP_RAD`] better: two roots that miss it alike
//!   would otherwise trade places across the stage from one tick to the next.
//! - **Two-actor orientation** (no roll): the primary's aim point lands exactly at its
//!   screen point (heading and pitch from [`orient`]); the other actor lands exactly too when
//!   both aim points are at the camera's height (equal heights and φ = 0 or π, e.g. eye-level
//!   two-shots of equal-height actors, any θ); otherwise it lands off by the roll-free error
//!   (≈ 0.28 in screen y at φ = 20°, θ = (π − α)/2 with a 43° lens). Default screen y's are 0.
//!   With a pitch gimbal at eye level, a two-shot in one framing turns φ (about AB) to where
//!   the other actor lands exactly too, within the gimbal's range (`both_exact`): a written
//!   camera angle keeps its φ and the error.
//! - **Default screens** follow the side: when no screen x is given and the profile puts the
//!   camera across the line of action, the defaults swap (A right, B left) so a roll-free
//!   camera can show them; explicit screens that a roll-free camera cannot show from the
//!   profile's side are an error ([`FramingError::ScreenSideConflict`]).
//!
//! Holding a two-actor `Visual` keeps (α, θ, φ): as the actors move apart the distances scale.
//! Re-solve each tick to keep the size exact; interpolate from the held `Visual` to a re-solved
//! one to change it smoothly.

use crate::camera::{orient, orient_fixed_pitch, Lens, Vec3};
use crate::reference::ActorPose;
use crate::toric::Toric;
use crate::{size, sphere, toric};
use dronecine_grammar::script::{Composition, Subject};
use dronecine_grammar::vocab::Size;
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;
use dronecine_profile::Gimbal;
use std::f64::consts::{FRAC_PI_2, PI};

/// The visual parameters of a composition solved against actor poses.
#[derive(Clone, Debug, PartialEq)]
pub enum Visual {
    One(OneVisual),
    Two(TwoVisual),
    /// A camera move between two visuals that cannot be blended without the actors' poses
    /// (different actors, one ↔ two actors, two-actor toric interpolation). [`place`]
    /// evaluates it against the current poses (see [`interpolate`]).
    Blend {
        from: Box<Visual>,
        to: Box<Visual>,
        s: f64,
    },
}

/// One actor on the sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OneVisual {
    /// Index into the actors slice.
    pub actor: usize,
    /// From the band centre to the camera (horizontal for a fixed-pitch camera).
    pub distance_m: f64,
    /// θ, relative to the actor's facing, counter-clockwise, in (−π, π].
    pub azimuth_rad: f64,
    /// φ, the requested camera-angle elevation (not rendered by a fixed-pitch camera).
    pub elevation_rad: f64,
    /// Requested screen point of the band centre.
    pub screen: [f64; 2],
    /// Framed band `[bottom, top]` above the actor's feet.
    pub band_m: [f64; 2],
}

/// Which actor of a pair the roll-free camera aims exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primary {
    A,
    B,
}

/// Two actors on the torus: A and B are the toric pair (A the first subject, or the
/// foreground actor of an over-the-shoulder composition).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoVisual {
    pub a: usize,
    pub b: usize,
    /// (α, θ, φ) about the aim points (band centres) of A and B.
    pub toric: Toric,
    pub screen_a: [f64; 2],
    pub screen_b: [f64; 2],
    pub band_a_m: [f64; 2],
    pub band_b_m: [f64; 2],
    pub primary: Primary,
    /// The requested camera-angle elevation (for the fixed-pitch flag).
    pub elevation_rad: f64,
    pub over_shoulder: bool,
    /// 1, or for an over-the-shoulder whose sized (primary, background) actor's size was out
    /// of the toric circle's reach, how far out (its size's distance over the circle's
    /// diameter, at most [`OVER_SHOULDER_REACH`]): the actor is framed that much larger.
    pub stretch: f64,
}

/// What [`place`] could not render exactly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flags {
    /// A non-level camera angle asked of a fixed-pitch camera: rendered level.
    pub angle_not_rendered: bool,
    /// The pitch left the gimbal's range and was clamped (the aim point lands off its y).
    pub pitch_clamped: bool,
    /// No roll-free orientation puts the aim point at its screen point (nearly straight above
    /// or below): clamped by [`orient`].
    pub orientation_clamped: bool,
    /// The geometry is degenerate (actors coincide or are vertically aligned, or an actor
    /// index is out of range): a fallback placement.
    pub degenerate: bool,
}

impl Flags {
    fn union(self, o: Flags) -> Flags {
        Flags {
            angle_not_rendered: self.angle_not_rendered || o.angle_not_rendered,
            pitch_clamped: self.pitch_clamped || o.pitch_clamped,
            orientation_clamped: self.orientation_clamped || o.orientation_clamped,
            degenerate: self.degenerate || o.degenerate,
        }
    }

    pub fn any(&self) -> bool {
        self.angle_not_rendered || self.pitch_clamped || self.orientation_clamped || self.degenerate
    }
}

/// A camera placement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub position_m: Vec3,
    /// Counter-clockwise from +x, wrapped to (−π, π].
    pub heading_rad: f64,
    /// Up positive; 0 for a fixed-pitch camera.
    pub pitch_rad: f64,
    pub flags: Flags,
}

/// An actor's world point and where it should land on screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenTarget {
    pub actor: usize,
    pub point_m: Vec3,
    pub screen: [f64; 2],
}

/// Why a composition has no camera placement.
#[derive(Clone, Debug, PartialEq)]
pub enum FramingError {
    /// An actor name not in the names slice (or without a pose).
    UnknownActor(String),
    /// The same actor framed twice.
    SameActor(String),
    /// A shape of composition this module does not frame (no subject, three actors, …).
    Unsupported { framings: usize, subjects: usize },
    /// Field of view outside (0, π) or aspect not positive.
    InvalidLens,
    /// An actor pose with a non-positive height or non-finite values.
    InvalidActor(usize),
    /// A screen coordinate that is not finite.
    InvalidScreen,
    /// The two actors coincide or stand vertically aligned: no toric frame.
    ActorsCoincide,
    /// The two requested screen points coincide (α = 0).
    ScreensCoincide,
    /// The profile puts the camera on the side from which a roll-free camera shows the two
    /// actors in the other order than the explicit screen positions ask.
    ScreenSideConflict,
    /// The profile's vantage direction cannot see both actors at the requested angle
    /// (∠(AB, u) ≥ π − α).
    ProfileUnreachable,
    /// No point of the torus frames the sized actor at this size.
    SizeUnreachable { size: Size },
}

impl std::fmt::Display for FramingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FramingError::UnknownActor(n) => write!(f, "unknown actor `{n}`"),
            FramingError::SameActor(n) => write!(f, "actor `{n}` is framed twice"),
            FramingError::Unsupported { framings, subjects } => write!(
                f,
                "cannot frame {subjects} subject(s) in {framings} framing(s): one actor, two \
                 actors in one framing, or two framings of one actor each"
            ),
            FramingError::InvalidLens => f.write_str("invalid lens"),
            FramingError::InvalidActor(i) => write!(f, "invalid pose for actor #{i}"),
            FramingError::InvalidScreen => f.write_str("screen position is not finite"),
            FramingError::ActorsCoincide => {
                f.write_str("the two actors stand at the same place: no two-shot geometry")
            }
            FramingError::ScreensCoincide => {
                f.write_str("the two actors are asked at the same screen position")
            }
            FramingError::ScreenSideConflict => f.write_str(
                "the profile puts the camera on the side where the actors appear in the other \
                 screen order",
            ),
            FramingError::ProfileUnreachable => {
                f.write_str("no camera on this profile sees both actors at their screen positions")
            }
            FramingError::SizeUnreachable { size } => write!(
                f,
                "no camera position frames the nearer actor as {} with both actors at their \
                 screen positions",
                size.as_str()
            ),
        }
    }
}

impl std::error::Error for FramingError {}

// ---------------------------------------------------------------------------------------------
// Small geometry helpers.

fn feet(p: &ActorPose) -> Vec3 {
    Vec3::new(p.position_m[0], p.position_m[1], p.position_m[2])
}

fn band_point(p: &ActorPose, h_m: f64) -> Vec3 {
    feet(p) + Vec3::new(0.0, 0.0, h_m)
}

/// The centre of a band `band_m` (metres above the feet) of actor `p`: a framing's aim point.
pub(crate) fn band_centre(p: &ActorPose, band_m: [f64; 2]) -> Vec3 {
    band_point(p, (band_m[0] + band_m[1]) / 2.0)
}

fn lerp(a: f64, b: f64, s: f64) -> f64 {
    a + (b - a) * s
}

fn lerp2(a: [f64; 2], b: [f64; 2], s: f64) -> [f64; 2] {
    [lerp(a[0], b[0], s), lerp(a[1], b[1], s)]
}

fn lerp_angle(a: f64, b: f64, s: f64) -> f64 {
    wrap_angle_rad(a + wrap_angle_rad(b - a) * s)
}

fn fixed_pitch(gimbal: &Gimbal) -> bool {
    matches!(gimbal, Gimbal::None)
}

/// Distance from the band centre that frames a band of half height `half_m` with its centre at
/// `screen`: the exact variant of [`size::exact_distance_m`] for a gimbal camera at
/// `elevation_rad`; for a fixed-pitch camera the horizontal distance `h·Sy·√(1 + x'²)`.
fn band_distance_m(
    lens: &Lens,
    half_m: f64,
    screen: [f64; 2],
    elevation_rad: f64,
    level: bool,
) -> Option<f64> {
    if level {
        let sx = lens.sx();
        let xp = screen[0] / sx;
        return (half_m > 0.0).then(|| half_m * sx * lens.aspect() * (1.0 + xp * xp).sqrt());
    }
    size::exact_distance_m(
        half_m,
        math::sin(elevation_rad),
        size::band_angle_rad(lens, screen),
    )
}

/// Minimise a 1-D function on [lo, hi]: dense sampling, then golden-section refinement.
fn minimise(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> (f64, f64) {
    let n = 96;
    let step = (hi - lo) / n as f64;
    let mut best = (lo, f(lo));
    for i in 1..=n {
        let x = lo + step * i as f64;
        let v = f(x);
        if v < best.1 {
            best = (x, v);
        }
    }
    let (mut a, mut b) = ((best.0 - step).max(lo), (best.0 + step).min(hi));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..60 {
        let c = b - g * (b - a);
        let d = a + g * (b - a);
        if f(c) < f(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let x = (a + b) / 2.0;
    let v = f(x);
    if v < best.1 {
        (x, v)
    } else {
        best
    }
}

// ---------------------------------------------------------------------------------------------
// solve

fn check_lens(lens: &Lens) -> Result<(), FramingError> {
    if lens.fov_x_rad() > 0.0
        && lens.fov_x_rad() < PI
        && lens.aspect() > 0.0
        && lens.aspect().is_finite()
    {
        Ok(())
    } else {
        Err(FramingError::InvalidLens)
    }
}

/// The index of actor `name` in `names` (the first that matches), found once per composition
/// ([`Prepared`]).
fn name_index<S: AsRef<str>>(name: &str, names: &[S]) -> Option<usize> {
    names.iter().position(|n| n.as_ref() == name)
}

/// The subject's actor, found at `index` by [`name_index`], with a pose a solve can use.
fn lookup(name: &str, index: Option<usize>, actors: &[ActorPose]) -> Result<usize, FramingError> {
    let i = index
        .filter(|i| *i < actors.len())
        .ok_or_else(|| FramingError::UnknownActor(name.to_string()))?;
    let p = &actors[i];
    let finite = p.position_m.iter().all(|v| v.is_finite())
        && p.velocity_mps.iter().all(|v| v.is_finite())
        && p.facing_rad.is_finite()
        && p.facing_rate_radps.is_finite();
    if !(finite && p.height_m > 0.0 && p.height_m.is_finite()) {
        return Err(FramingError::InvalidActor(i));
    }
    Ok(i)
}

fn check_screen(s: &Subject) -> Result<(), FramingError> {
    if s.screen_x.is_some_and(|v| !v.is_finite()) || s.screen_y.is_some_and(|v| !v.is_finite()) {
        return Err(FramingError::InvalidScreen);
    }
    Ok(())
}

/// Solve a composition against the actors' poses. `names[i]` names `actors[i]`.
///
/// Accepted shapes: one framing of one actor; one framing of two actors; two framings of one
/// actor each (over the shoulder, foreground first). See the module documentation for the
/// defaults and for what is exact.
///
/// The same as [`Prepared::new`] then [`Prepared::solve`]; a caller that solves one
/// composition every tick prepares it once.
pub fn solve<S: AsRef<str>>(
    comp: &Composition,
    names: &[S],
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
) -> Result<Visual, FramingError> {
    Prepared::new(comp, names, lens).solve(comp, actors, lens, gimbal)
}

/// What a solve of one composition needs that does not depend on the actors' poses: the
/// subjects' indices among the scene's names, the camera angle's elevation and, for two
/// actors, the angle α between their screen points (an `acos` and two rays a solve would
/// otherwise repeat). Built for one composition, names list and lens; [`Prepared::solve`]
/// gives exactly what [`solve`] gives.
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// Each subject's index in `names`, in the order of the composition's framings.
    indices: [Option<usize>; 2],
    elevation: f64,
    /// α of the two subjects' screen points (NaN for one subject or non-finite screens).
    alpha: f64,
}

impl Prepared {
    pub fn new<S: AsRef<str>>(comp: &Composition, names: &[S], lens: &Lens) -> Prepared {
        let mut subjects = comp.framings.iter().flat_map(|f| f.subjects.iter());
        let (sa, sb) = (subjects.next(), subjects.next());
        let alpha = match (sa, sb) {
            (Some(sa), Some(sb)) => {
                let (screen_a, screen_b) = pair_screens(sa, sb);
                toric::alpha_from_screens(lens, screen_a, screen_b)
            }
            _ => f64::NAN,
        };
        Prepared {
            indices: [
                sa.and_then(|s| name_index(&s.actor, names)),
                sb.and_then(|s| name_index(&s.actor, names)),
            ],
            elevation: sphere::elevation_rad(comp.camera_angle),
            alpha,
        }
    }

    /// Solve `comp` against the actors' poses: `comp` and `lens` must be those this was
    /// prepared with (the director keeps one per composition end of its plans).
    pub fn solve(
        &self,
        comp: &Composition,
        actors: &[ActorPose],
        lens: &Lens,
        gimbal: &Gimbal,
    ) -> Result<Visual, FramingError> {
        self.solve_near(comp, actors, lens, gimbal, None, 0.0)
    }

    /// [`Prepared::solve`] for a framing held tick after tick, `near` the visual it was solved
    /// at last. An over-the-shoulder has up to two cameras that frame the background actor at
    /// its size, and the solve keeps the one nearer the profile written; as live actors move,
    /// the two can come to frame it equally badly, and a choice made afresh would then flip
    /// from one to the other, across the stage in one tick. With `near`, the root nearer the
    /// last solve is kept while the other frames the profile less than [`BRANCH_KEEP_RAD`]
    /// better. And of the two, one whose camera comes within `clear_m` of an actor's body axis
    /// is not chosen while the other is clear (a foreground actor walking toward the other
    /// brings one camera onto their own shoulder: 0.00 m from them, the other 2 m away framing
    /// the profile as well). Without `near` and with `clear_m` 0, or for other compositions, as
    /// `solve`.
    pub fn solve_near(
        &self,
        comp: &Composition,
        actors: &[ActorPose],
        lens: &Lens,
        gimbal: &Gimbal,
        near: Option<&Visual>,
        clear_m: f64,
    ) -> Result<Visual, FramingError> {
        check_lens(lens)?;
        let subjects: usize = comp.framings.iter().map(|f| f.subjects.len()).sum();
        let unsupported = FramingError::Unsupported {
            framings: comp.framings.len(),
            subjects,
        };
        let elevation = self.elevation;
        let level = fixed_pitch(gimbal);
        // The two actors of a two-actor composition: screens checked, names found, distinct.
        let pair_of = |sa: &Subject, sb: &Subject, sizes: (Size, Size)| {
            check_screen(sa)?;
            check_screen(sb)?;
            let (a, b) = (
                lookup(&sa.actor, self.indices[0], actors)?,
                lookup(&sb.actor, self.indices[1], actors)?,
            );
            if a == b {
                return Err(FramingError::SameActor(sa.actor.clone()));
            }
            Pair::new(a, b, sa, sb, sizes, actors, elevation, level, self.alpha)
        };
        match comp.framings.as_slice() {
            [f] if f.subjects.len() == 1 => {
                let s = &f.subjects[0];
                check_screen(s)?;
                let i = lookup(&s.actor, self.indices[0], actors)?;
                solve_one(i, s, f.size, &actors[i], elevation, level, lens).map(Visual::One)
            }
            [f] if f.subjects.len() == 2 => {
                let (sa, sb) = (&f.subjects[0], &f.subjects[1]);
                let pair = pair_of(sa, sb, (f.size, f.size))?;
                let near = match near {
                    Some(Visual::Two(t)) if !t.over_shoulder && (t.a, t.b) == (pair.a, pair.b) => {
                        Some((t.toric.theta_rad, t.toric.phi_rad))
                    }
                    _ => None,
                };
                solve_together(pair, sa, f.size, actors, lens, gimbal, near).map(Visual::Two)
            }
            [fg, bg] if fg.subjects.len() == 1 && bg.subjects.len() == 1 => {
                let (sa, sb) = (&fg.subjects[0], &bg.subjects[0]);
                let pair = pair_of(sa, sb, (fg.size, bg.size))?;
                let near = match near {
                    Some(Visual::Two(t)) if t.over_shoulder => {
                        Some((t.toric.theta_rad, t.toric.phi_rad))
                    }
                    _ => None,
                };
                solve_over_shoulder(pair, sa, sb, bg.size, actors, lens, near, clear_m)
                    .map(Visual::Two)
            }
            _ => Err(unsupported),
        }
    }
}

/// The two subjects' screen points: A at x = −1/3 and B at +1/3 unless written (one written
/// x puts the other on the other side), y = 0 unless written.
fn pair_screens(sa: &Subject, sb: &Subject) -> ([f64; 2], [f64; 2]) {
    let third = 1.0 / 3.0;
    let (xa, xb) = match (sa.screen_x, sb.screen_x) {
        (Some(xa), Some(xb)) => (xa, xb),
        (Some(xa), None) => (xa, if xa > 0.0 { -third } else { third }),
        (None, Some(xb)) => (if xb < 0.0 { third } else { -third }, xb),
        (None, None) => (-third, third),
    };
    (
        [xa, sa.screen_y.unwrap_or(0.0)],
        [xb, sb.screen_y.unwrap_or(0.0)],
    )
}

fn solve_one(
    actor: usize,
    s: &Subject,
    size_: Size,
    pose: &ActorPose,
    elevation: f64,
    level: bool,
    lens: &Lens,
) -> Result<OneVisual, FramingError> {
    let (bottom, top) = size::band(size_, pose.height_m);
    let screen = [s.screen_x.unwrap_or(0.0), s.screen_y.unwrap_or(0.0)];
    let e = if level { 0.0 } else { elevation };
    let distance_m = band_distance_m(lens, (top - bottom) / 2.0, screen, e, level)
        .ok_or(FramingError::InvalidActor(actor))?;
    Ok(OneVisual {
        actor,
        distance_m,
        azimuth_rad: s.profile.map_or(0.0, |p| p.azimuth_rad()),
        elevation_rad: elevation,
        screen,
        band_m: [bottom, top],
    })
}

/// The common set-up of a two-actor solve: bands, aim points, screens, α (from [`Prepared`]).
struct Pair {
    a: usize,
    b: usize,
    band_a: [f64; 2],
    band_b: [f64; 2],
    ma: Vec3,
    mb: Vec3,
    screen_a: [f64; 2],
    screen_b: [f64; 2],
    /// Some screen x was written: the screen order is fixed.
    order_fixed: bool,
    alpha: f64,
    /// Elevation used for the geometry (0 for a fixed-pitch camera).
    e: f64,
    elevation: f64,
    level: bool,
}

impl Pair {
    #[allow(clippy::too_many_arguments)]
    fn new(
        a: usize,
        b: usize,
        sa: &Subject,
        sb: &Subject,
        sizes: (Size, Size),
        actors: &[ActorPose],
        elevation: f64,
        level: bool,
        alpha: f64,
    ) -> Result<Pair, FramingError> {
        let (pa, pb) = (&actors[a], &actors[b]);
        let (ba, ta) = size::band(sizes.0, pa.height_m);
        let (bb, tb) = size::band(sizes.1, pb.height_m);
        let band_a = [ba, ta];
        let band_b = [bb, tb];
        let ma = band_centre(pa, band_a);
        let mb = band_centre(pb, band_b);
        toric::frame(&ma, &mb).map_err(|_| FramingError::ActorsCoincide)?;
        let (screen_a, screen_b) = pair_screens(sa, sb);
        if alpha.is_nan() || alpha <= 1e-9 {
            return Err(FramingError::ScreensCoincide);
        }
        Ok(Pair {
            a,
            b,
            band_a,
            band_b,
            ma,
            mb,
            screen_a,
            screen_b,
            order_fixed: sa.screen_x.is_some() || sb.screen_x.is_some(),
            alpha,
            e: if level { 0.0 } else { elevation },
            elevation,
            level,
        })
    }

    fn a_left(&self) -> bool {
        self.screen_a[0] <= self.screen_b[0]
    }

    /// Mirror the screen x's (α does not change).
    fn mirror(&mut self) {
        self.screen_a[0] = -self.screen_a[0];
        self.screen_b[0] = -self.screen_b[0];
    }

    /// Make the screen order agree with the side φ: swap defaults, or fail on explicit ones.
    fn agree_with_side(&mut self, phi: f64) -> Result<(), FramingError> {
        let near_side = math::cos(phi) >= 0.0;
        if near_side != self.a_left() {
            if self.order_fixed {
                return Err(FramingError::ScreenSideConflict);
            }
            self.mirror();
        }
        Ok(())
    }

    fn ab(&self) -> f64 {
        (self.mb - self.ma).norm()
    }

    fn visual(&self, toric: Toric, primary: Primary, over_shoulder: bool) -> TwoVisual {
        TwoVisual {
            a: self.a,
            b: self.b,
            toric,
            screen_a: self.screen_a,
            screen_b: self.screen_b,
            band_a_m: self.band_a,
            band_b_m: self.band_b,
            primary,
            elevation_rad: self.elevation,
            over_shoulder,
            stretch: 1.0,
        }
    }

    /// The over-the-shoulder visual at (θ, φ), B (the background) sized, `stretch` as
    /// [`TwoVisual::stretch`].
    fn over_shoulder_visual(&self, theta: f64, phi: f64, stretch: f64) -> TwoVisual {
        let toric = Toric {
            alpha_rad: self.alpha,
            theta_rad: theta,
            phi_rad: phi,
        };
        TwoVisual {
            stretch,
            ..self.visual(toric, Primary::B, true)
        }
    }

    fn distance_a(&self, lens: &Lens) -> Option<f64> {
        band_distance_m(
            lens,
            (self.band_a[1] - self.band_a[0]) / 2.0,
            self.screen_a,
            self.e,
            self.level,
        )
    }

    fn distance_b(&self, lens: &Lens) -> Option<f64> {
        band_distance_m(
            lens,
            (self.band_b[1] - self.band_b[0]) / 2.0,
            self.screen_b,
            self.e,
            self.level,
        )
    }

    /// Refine θ so the sized actor's distance uses the camera's actual elevation seen from
    /// that actor (the exact variant of the size distance depends on it; φ turns about AB,
    /// so the elevation is not φ): a few fixed-point steps, each keeping the root nearest
    /// the previous θ.
    fn refine_theta(&self, lens: &Lens, theta: f64, phi: f64, sized: Primary) -> f64 {
        if self.level {
            return theta;
        }
        let (m, band, screen) = match sized {
            Primary::A => (self.ma, self.band_a, self.screen_a),
            Primary::B => (self.mb, self.band_b, self.screen_b),
        };
        let mut theta = theta;
        for _ in 0..6 {
            let v = Toric {
                alpha_rad: self.alpha,
                theta_rad: theta,
                phi_rad: phi,
            };
            let Ok(c) = toric::position(&self.ma, &self.mb, &v) else {
                break;
            };
            let to_c = c - m;
            let elevation = math::atan2(to_c.z, to_c.xy().norm());
            let Some(d) =
                band_distance_m(lens, (band[1] - band[0]) / 2.0, screen, elevation, false)
            else {
                break;
            };
            let roots = match sized {
                Primary::A => toric::theta_for_distance_to_a(self.alpha, self.ab(), d),
                Primary::B => toric::theta_for_distance_to_b(self.alpha, self.ab(), d),
            };
            match roots
                .into_iter()
                .min_by(|x, y| (x - theta).abs().total_cmp(&(y - theta).abs()))
            {
                // A fixed point, bit for bit: the remaining steps would repeat this one.
                Some(t) if t.to_bits() == theta.to_bits() => break,
                Some(t) => theta = t,
                None => break,
            }
        }
        theta
    }

    /// φ on the side of the screen order, at the requested elevation.
    fn side_phi(&self) -> f64 {
        if self.a_left() {
            self.e
        } else {
            wrap_angle_rad(PI - self.e)
        }
    }
}

/// How much nearer the symmetric θ the second subject's root must be to win over the
/// first's (radians of θ).
const TIE_MARGIN_RAD: f64 = 0.02;

/// A two-shot: a camera on the toric surface of the screen points where the nearer actor is at
/// the size, at the elevation. Of the up to four such θ, the one nearest the symmetric
/// θ = π − α; held tick after tick (`near_theta_rad`, the last solve's θ), the one nearest the
/// last: unheld, as actors walk, another root would come to be nearer the symmetric θ and the
/// camera would cross the arc at once. A held two-shot still jumps when the nearer actor
/// changes (at θ = π − α) between actors whose sizes are at different distances (different
/// heights): the size moves to the other actor, and its distance with it. The profile-vantage
/// two-shot has one camera, and no choice to hold.
///
/// With a pitch gimbal at eye level, φ is the one nearest the side's (held: nearest the last
/// solve's) at which both actors land on their screen points ([`both_exact`]); `near` is the
/// last solve's (θ, φ).
fn solve_together(
    mut pair: Pair,
    sa: &Subject,
    size_: Size,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    near: Option<(f64, f64)>,
) -> Result<TwoVisual, FramingError> {
    let near_theta_rad = near.map(|n| n.0);
    if let Some(profile) = sa.profile {
        // Vantage from A: (θ, φ) exact, the size follows.
        let u = sphere::direction(actors[pair.a].facing_rad, profile.azimuth_rad(), pair.e);
        let c = toric::vantage_position(&pair.ma, &pair.mb, pair.alpha, &u)
            .ok_or(FramingError::ProfileUnreachable)?;
        let t =
            toric::inverse(&pair.ma, &pair.mb, &c).map_err(|_| FramingError::ProfileUnreachable)?;
        pair.agree_with_side(t.phi_rad)?;
        let toric = Toric {
            alpha_rad: pair.alpha,
            ..t
        };
        return Ok(pair.visual(toric, Primary::A, false));
    }
    let phi = pair.side_phi();
    let ab = pair.ab();
    let r = toric::radius_m(ab, pair.alpha);
    let alpha = pair.alpha;
    let dist_a = |th: f64| 2.0 * r * math::sin(alpha + th / 2.0);
    let dist_b = |th: f64| 2.0 * r * math::sin(th / 2.0);
    // At most two roots each: on the stack (this runs every tick).
    let mut candidates = [(0.0, Primary::A); 4];
    let mut count = 0;
    // A root for A's distance is at that distance (to rounding, far below the 1e-9 margin):
    // only the other actor's distance is computed.
    if let Some(d) = pair.distance_a(lens) {
        for th in toric::theta_for_distance_to_a_on(alpha, r, d) {
            if d <= dist_b(th) + 1e-9 {
                candidates[count] = (th, Primary::A);
                count += 1;
            }
        }
    }
    if let Some(d) = pair.distance_b(lens) {
        for th in toric::theta_for_distance_to_b_on(alpha, r, d) {
            if d <= dist_a(th) + 1e-9 {
                candidates[count] = (th, Primary::B);
                count += 1;
            }
        }
    }
    let candidates = &candidates[..count];
    // The root nearest the symmetric θ = π − α; on a near tie (equal sizes and heights give
    // mirror-image roots) the first subject keeps its size, so that the choice does not
    // flicker with noise on live actors' poses.
    let symmetric = PI - alpha;
    let key = |c: &(f64, Primary)| match near_theta_rad {
        Some(last) if last.is_finite() => (c.0 - last).abs(),
        _ => {
            (c.0 - symmetric).abs()
                + if matches!(c.1, Primary::B) {
                    TIE_MARGIN_RAD
                } else {
                    0.0
                }
        }
    };
    let (theta, primary) = candidates
        .iter()
        .copied()
        .min_by(|x, y| key(x).total_cmp(&key(y)))
        .ok_or(FramingError::SizeUnreachable { size: size_ })?;
    let refined = pair.refine_theta(lens, theta, phi, primary);
    let (theta, phi) = match gimbal {
        Gimbal::Pitch {
            min_rad, max_rad, ..
        } if pair.elevation == 0.0 => {
            // Held, from the last solve's φ when it is on this side.
            let start = near
                .map(|n| n.1)
                .filter(|last| last.is_finite() && math::cos(last - phi) > 0.0)
                .unwrap_or(phi);
            both_exact(&pair, lens, theta, start, primary, (*min_rad, *max_rad))
                .unwrap_or((refined, phi))
        }
        _ => (refined, phi),
    };
    Ok(pair.visual(
        Toric {
            alpha_rad: alpha,
            theta_rad: theta,
            phi_rad: phi,
        },
        primary,
        false,
    ))
}

/// How far from its start [`both_exact`] looks for φ, each way (radians): short of a quarter
/// turn, so that the camera stays on its side of the line of action.
const BOTH_EXACT_REACH_RAD: f64 = 1.4;

/// The step of [`both_exact`]'s search for a change of sign (radians of φ).
const BOTH_EXACT_STEP_RAD: f64 = 0.02;

/// A roll-free camera on a pitch gimbal puts two points at different heights on their screen
/// points when the plane through the camera and the two points holds the camera's right axis
/// (horizontal: every plane holds a horizontal direction) at the tilt of the camera's pitch.
/// The torus gives the angle between the two actors; turning about AB (φ) turns that plane;
/// θ keeps the sized actor's size. So: the φ nearest `start` at which the camera that aims
/// the primary exactly puts the other actor on its screen point too, with its θ refined for
/// the size (from the root `theta0`), and a pitch inside the gimbal's range `pitch_range`.
/// `None` when no such φ lies within [`BOTH_EXACT_REACH_RAD`] of `start`.
///
/// The other actor's miss is measured as the signed angle, about the primary's ray, from
/// where it is asked to where it lands: both rays are α from the primary's, so it is one
/// number, and zero only where the actor lands exactly.
fn both_exact(
    pair: &Pair,
    lens: &Lens,
    theta0: f64,
    start: f64,
    primary: Primary,
    pitch_range: (f64, f64),
) -> Option<(f64, f64)> {
    let (aimed, aimed_screen, other, other_screen) = match primary {
        Primary::A => (pair.ma, pair.screen_a, pair.mb, pair.screen_b),
        Primary::B => (pair.mb, pair.screen_b, pair.ma, pair.screen_a),
    };
    let u = lens.ray(aimed_screen).normalize();
    let w = lens.ray(other_screen).normalize();
    // (miss, θ, pitch) at φ.
    let miss = |phi: f64| -> Option<(f64, f64, f64)> {
        let theta = pair.refine_theta(lens, theta0, phi, primary);
        let toric = Toric {
            alpha_rad: pair.alpha,
            theta_rad: theta,
            phi_rad: phi,
        };
        let c = toric::position(&pair.ma, &pair.mb, &toric).ok()?;
        let o = orient(lens, &c, &aimed, aimed_screen);
        if o.clamped {
            return None;
        }
        let camera = crate::camera::CameraPose {
            position_m: c,
            heading_rad: o.heading_rad,
            pitch_rad: o.pitch_rad,
        };
        let v = camera.to_camera(&other).normalize();
        let m = u.dot(&w.cross(&v));
        m.is_finite().then_some((m, theta, o.pitch_rad))
    };
    let in_range = |(_, theta, pitch): (f64, f64, f64), phi: f64| {
        (pitch >= pitch_range.0 && pitch <= pitch_range.1).then_some((theta, wrap_angle_rad(phi)))
    };
    let at = miss(start)?;
    // The nearest change of sign, stepping out both ways.
    let mut bracket = None;
    let mut last = [(start, at); 2];
    if at.0 != 0.0 {
        let steps = (BOTH_EXACT_REACH_RAD / BOTH_EXACT_STEP_RAD) as usize;
        'out: for k in 1..=steps {
            for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
                let phi = start + sign * BOTH_EXACT_STEP_RAD * k as f64;
                let Some(here) = miss(phi) else {
                    continue;
                };
                let (phi0, before) = last[side];
                if (before.0 < 0.0) != (here.0 < 0.0) || here.0 == 0.0 {
                    bracket = Some(((phi0, before), (phi, here)));
                    break 'out;
                }
                last[side] = (phi, here);
            }
        }
    }
    let ((mut a, mut fa), (mut b, mut fb)) = match bracket {
        Some(((a, fa), (b, fb))) => ((a, fa.0), (b, fb.0)),
        None if at.0 == 0.0 => return in_range(at, start),
        None => return None,
    };
    // Regula falsi (Illinois: the end kept twice has its value halved); the miss is smooth
    // in φ. The answer is the point evaluated with the smallest miss.
    let mut best = if fa.abs() <= fb.abs() {
        (a, miss(a)?)
    } else {
        (b, miss(b)?)
    };
    let mut kept = 0i8;
    for _ in 0..60 {
        if best.1 .0 == 0.0 || (b - a).abs() < 1e-13 {
            break;
        }
        let mut phi = (a * fb - b * fa) / (fb - fa);
        if !(phi > a.min(b) && phi < a.max(b)) {
            phi = (a + b) / 2.0;
        }
        let here = miss(phi)?;
        if here.0.abs() < best.1 .0.abs() {
            best = (phi, here);
        }
        if (here.0 < 0.0) == (fa < 0.0) {
            (a, fa) = (phi, here.0);
            if kept == 1 {
                fb /= 2.0;
            }
            kept = 1;
        } else {
            (b, fb) = (phi, here.0);
            if kept == -1 {
                fa /= 2.0;
            }
            kept = -1;
        }
    }
    in_range(best.1, best.0)
}

/// How much farther than the toric circle allows an over-the-shoulder's background actor may
/// be asked to be framed (its size's distance over the circle's diameter) and still be framed,
/// from the circle's farthest point: up to this, the background actor is framed a little
/// larger than written (by at most this factor) with both actors on their screen points,
/// instead of the composition failing. A shot written at the edge of reach against its
/// blocking (as `scene.psl`'s reverse shot is) comes out of reach against live actors, who
/// stand a few centimetres closer at moments; without this allowance the drone would hold the
/// camera, unframed, for part of the shot.
pub const OVER_SHOULDER_REACH: f64 = 1.15;

/// How much nearer its profile (radians) the other root of an over-the-shoulder must frame
/// before a held framing leaves its own (see [`Prepared::solve_near`]).
pub const BRANCH_KEEP_RAD: f64 = 0.35;

/// `near`: the (θ, φ) this composition was solved at last (a hold, solved again each tick);
/// `clear_m`: how far from each actor's body axis a root's camera must be to be preferred
/// (see [`Prepared::solve_near`]).
#[allow(clippy::too_many_arguments)]
fn solve_over_shoulder(
    mut pair: Pair,
    sa: &Subject,
    sb: &Subject,
    bg_size: Size,
    actors: &[ActorPose],
    lens: &Lens,
    near: Option<(f64, f64)>,
    clear_m: f64,
) -> Result<TwoVisual, FramingError> {
    let ab = pair.ab();
    let alpha = pair.alpha;
    let d = pair
        .distance_b(lens)
        .ok_or(FramingError::SizeUnreachable { size: bg_size })?;
    let mut thetas = toric::theta_for_distance_to_b(alpha, ab, d);
    let mut stretch = 1.0;
    if thetas.is_empty() {
        // Just out of reach: framed from the farthest point of the circle instead.
        let farthest = 2.0 * toric::radius_m(ab, alpha);
        if d <= farthest * OVER_SHOULDER_REACH {
            thetas = toric::theta_for_distance_to_b(alpha, ab, farthest * (1.0 - 1e-12));
            stretch = d / farthest;
        }
    }
    if thetas.is_empty() {
        return Err(FramingError::SizeUnreachable { size: bg_size });
    }
    // The direction to match: the foreground's profile seen from A, else the background's seen
    // from B.
    let target = match (sa.profile, sb.profile) {
        (Some(p), _) => Some((
            pair.ma,
            sphere::direction(actors[pair.a].facing_rad, p.azimuth_rad(), pair.e),
        )),
        (None, Some(p)) => Some((
            pair.mb,
            sphere::direction(actors[pair.b].facing_rad, p.azimuth_rad(), pair.e),
        )),
        (None, None) => None,
    };
    let Some((origin, u)) = target else {
        // No profile: the side of the screen order, the root nearer the foreground actor.
        let phi = pair.side_phi();
        let theta = pair.refine_theta(lens, thetas[thetas.len() - 1], phi, Primary::B);
        return Ok(pair.over_shoulder_visual(theta, phi, stretch));
    };
    let (ma, mb) = (pair.ma, pair.mb);
    let cost = |theta: f64, phi: f64| -> f64 {
        match toric::position(
            &ma,
            &mb,
            &Toric {
                alpha_rad: alpha,
                theta_rad: theta,
                phi_rad: phi,
            },
        ) {
            Ok(c) => crate::camera::angle(&(c - origin), &u),
            Err(_) => f64::INFINITY,
        }
    };
    let (lo, hi) = if !pair.order_fixed {
        (-PI, PI)
    } else if pair.a_left() {
        (-FRAC_PI_2, FRAC_PI_2)
    } else {
        (FRAC_PI_2, 3.0 * FRAC_PI_2)
    };
    // Each root with its best φ (at most two: on the stack, this runs every tick), and the
    // best of them (the first on a tie).
    let mut found = [(f64::NAN, f64::NAN, f64::INFINITY); 2];
    let mut count = 0;
    for &th in thetas.iter().take(found.len()) {
        let (phi, v) = minimise(|phi| cost(th, phi), lo, hi);
        found[count] = (th, phi, v);
        count += 1;
    }
    let mut roots: &[(f64, f64, f64)] = &found[..count];
    // A root whose camera stands inside an actor's distance gives way to one that does not.
    if clear_m > 0.0 && count == 2 {
        let (a, b) = (&actors[pair.a], &actors[pair.b]);
        let clear = |r: &(f64, f64, f64)| {
            toric::position(
                &ma,
                &mb,
                &Toric {
                    alpha_rad: alpha,
                    theta_rad: r.0,
                    phi_rad: r.1,
                },
            )
            .is_ok_and(|c| {
                body_axis_distance_m(&c, a) >= clear_m && body_axis_distance_m(&c, b) >= clear_m
            })
        };
        match (clear(&roots[0]), clear(&roots[1])) {
            (true, false) => roots = &roots[..1],
            (false, true) => roots = &roots[1..],
            _ => {}
        }
    }
    let mut best = (f64::NAN, f64::NAN, f64::INFINITY);
    for &r in roots {
        if r.2 < best.2 {
            best = r;
        }
    }
    // A held framing keeps its root while the other is not clearly better.
    let (theta, phi, _) = match near {
        Some((theta0, phi0)) => {
            let apart =
                |r: &(f64, f64, f64)| (r.0 - theta0).abs() + wrap_angle_rad(r.1 - phi0).abs();
            let held = roots
                .iter()
                .copied()
                .min_by(|x, y| apart(x).total_cmp(&apart(y)))
                .unwrap_or(best);
            if held.2 <= best.2 + BRANCH_KEEP_RAD {
                held
            } else {
                best
            }
        }
        None => best,
    };
    let phi = wrap_angle_rad(phi);
    pair.agree_with_side(phi)?;
    let theta = pair.refine_theta(lens, theta, phi, Primary::B);
    Ok(pair.over_shoulder_visual(theta, phi, stretch))
}

// ---------------------------------------------------------------------------------------------
// place

fn valid_indices(v: &Visual, n: usize) -> bool {
    match v {
        Visual::One(o) => o.actor < n,
        Visual::Two(t) => t.a < n && t.b < n,
        Visual::Blend { from, to, .. } => valid_indices(from, n) && valid_indices(to, n),
    }
}

/// Aim `target` at `screen` from `c` with the camera the gimbal allows.
fn aim(
    lens: &Lens,
    gimbal: &Gimbal,
    c: &Vec3,
    target: &Vec3,
    screen: [f64; 2],
) -> (f64, f64, Flags) {
    let mut flags = Flags::default();
    match gimbal {
        Gimbal::None => (
            orient_fixed_pitch(lens, c, target, screen[0], 0.0),
            0.0,
            flags,
        ),
        Gimbal::Pitch {
            min_rad, max_rad, ..
        } => {
            let o = orient(lens, c, target, screen);
            flags.orientation_clamped = o.clamped;
            let (lo, hi) = (min_rad.min(*max_rad), max_rad.max(*min_rad));
            if o.pitch_rad < lo || o.pitch_rad > hi {
                flags.pitch_clamped = true;
                let p = o.pitch_rad.clamp(lo, hi);
                (orient_fixed_pitch(lens, c, target, screen[0], p), p, flags)
            } else {
                (o.heading_rad, o.pitch_rad, flags)
            }
        }
    }
}

/// The world point a visual aims exactly from `c`, and its screen point: one actor, the band's
/// bisector point at [`size::band_aim_screen`] (the band centre at its screen point for a
/// fixed-pitch camera); two actors, the primary's band centre; a blend, the two ends' targets
/// interpolated (point and screen), which keeps the orientation continuous along the move
/// (and exact for an actor that is the aimed one at both ends).
fn aim_target(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    c: &Vec3,
) -> (Vec3, [f64; 2]) {
    match v {
        Visual::One(o) => {
            let p = &actors[o.actor];
            if fixed_pitch(gimbal) {
                (band_centre(p, o.band_m), o.screen)
            } else {
                let q = size::bisector_point(
                    c,
                    &band_point(p, o.band_m[1]),
                    &band_point(p, o.band_m[0]),
                );
                (q, size::band_aim_screen(lens, o.screen))
            }
        }
        Visual::Two(t) => primary_target(t, actors),
        Visual::Blend { from, to, s } => {
            let (p0, s0) = aim_target(from, actors, lens, gimbal, c);
            let (p1, s1) = aim_target(to, actors, lens, gimbal, c);
            (p0 + (p1 - p0) * *s, lerp2(s0, s1, *s))
        }
    }
}

/// Heading and pitch for a visual seen from a camera at `c` (not necessarily where [`place`]
/// puts it): the aimed point lands exactly where the visual asks.
pub fn orient_visual(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    c: &Vec3,
) -> (f64, f64, Flags) {
    let (target, screen) = aim_target(v, actors, lens, gimbal, c);
    aim(lens, gimbal, c, &target, screen)
}

/// For a two-actor visual seen from `c` with camera pitch `pitch_rad`: the heading halfway
/// between the two that put each actor's aim point at its screen x — the screen-x errors of
/// the two actors then balance, where [`orient_visual`] puts all of it on the secondary.
/// `None` for a one-actor visual or bad indices.
pub fn balanced_heading(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    c: &Vec3,
    pitch_rad: f64,
) -> Option<f64> {
    let Visual::Two(t) = v else {
        return None;
    };
    if !valid_indices(v, actors.len()) {
        return None;
    }
    let ha = orient_fixed_pitch(
        lens,
        c,
        &band_centre(&actors[t.a], t.band_a_m),
        t.screen_a[0],
        pitch_rad,
    );
    let hb = orient_fixed_pitch(
        lens,
        c,
        &band_centre(&actors[t.b], t.band_b_m),
        t.screen_b[0],
        pitch_rad,
    );
    let h = wrap_angle_rad(ha + wrap_angle_rad(hb - ha) / 2.0);
    h.is_finite().then_some(h)
}

fn primary_target(t: &TwoVisual, actors: &[ActorPose]) -> (Vec3, [f64; 2]) {
    match t.primary {
        Primary::A => (band_centre(&actors[t.a], t.band_a_m), t.screen_a),
        Primary::B => (band_centre(&actors[t.b], t.band_b_m), t.screen_b),
    }
}

/// Place the camera for a visual against the actors' current poses.
pub fn place(v: &Visual, actors: &[ActorPose], lens: &Lens, gimbal: &Gimbal) -> Placement {
    place_impl(v, actors, lens, gimbal, true)
}

/// The camera position [`place`] gives, without the orientation (the position never depends
/// on it): what the director needs for its target, at a fraction of the cost.
pub fn position_m(v: &Visual, actors: &[ActorPose], lens: &Lens, gimbal: &Gimbal) -> Vec3 {
    place_impl(v, actors, lens, gimbal, false).position_m
}

/// Which way round a move's blend goes, carried from one tick to the next. Each angle a
/// [`Visual::Blend`] interpolates — the cylindrical blend's angle about the actors, or the
/// toric blend's yaw about each of the two actors — goes the short way round on the move's
/// first tick ([`BlendWay::default`]) and from then on the way nearest the last tick's
/// ([`toric::nearest_turn_rad`]). When an end swings through the opposite side (an actor
/// turning round during the move), the short way changes side, and the camera's target would
/// cross the actors in one tick, which no drone flies. The director keeps one per move.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BlendWay {
    /// The cylindrical blend's turn about the actors' centroid.
    about_centre_rad: Option<f64>,
    /// The toric blend's turns about actor A and about actor B.
    about_pair_rad: [Option<f64>; 2],
}

/// `position_m(&interpolate(a, b, s), …)`, bit for bit, without building the blend.
pub fn position_between_m(
    a: &Visual,
    b: &Visual,
    s: f64,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
) -> Vec3 {
    position_between_way_m(a, b, s, actors, lens, gimbal, &BlendWay::default()).0
}

/// [`position_between_m`] going round the way nearest `way` (the last tick's); also returns
/// the way it went, for the next tick. With `BlendWay::default()` it is
/// [`position_between_m`], bit for bit; so it is whenever the short way is the nearest.
pub fn position_between_way_m(
    a: &Visual,
    b: &Visual,
    s: f64,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    way: &BlendWay,
) -> (Vec3, BlendWay) {
    let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
    if s == 0.0 {
        return (position_m(a, actors, lens, gimbal), *way);
    }
    if s == 1.0 {
        return (position_m(b, actors, lens, gimbal), *way);
    }
    if let (Visual::One(x), Visual::One(y)) = (a, b) {
        if x.actor == y.actor {
            let v = Visual::One(lerp_one(x, y, s));
            return (position_m(&v, actors, lens, gimbal), *way);
        }
    }
    if !(valid_indices(a, actors.len()) && valid_indices(b, actors.len())) {
        return (Vec3::zeros(), *way);
    }
    let (p, way) = place_blend(a, b, s, None, actors, lens, gimbal, way);
    (p.position_m, way)
}

/// [`place`], with the orientation (and its flags) only when `orient`.
fn place_impl(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    orient: bool,
) -> Placement {
    if !valid_indices(v, actors.len()) {
        return Placement {
            position_m: Vec3::zeros(),
            heading_rad: 0.0,
            pitch_rad: 0.0,
            flags: Flags {
                degenerate: true,
                ..Flags::default()
            },
        };
    }
    match v {
        Visual::One(o) => place_one(o, actors, lens, gimbal, orient),
        Visual::Two(t) => place_two(t, actors, lens, gimbal, orient),
        Visual::Blend { from, to, s } => {
            let short = BlendWay::default();
            place_blend(
                from,
                to,
                *s,
                orient.then_some(v),
                actors,
                lens,
                gimbal,
                &short,
            )
            .0
        }
    }
}

/// A camera at `c` oriented for `whole` (the blend being placed), or not oriented at all.
fn oriented(
    c: Vec3,
    whole: Option<&Visual>,
    flags: Flags,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
) -> Placement {
    let (heading_rad, pitch_rad, f) = match whole {
        Some(v) => orient_visual(v, actors, lens, gimbal, &c),
        None => (0.0, 0.0, Flags::default()),
    };
    Placement {
        position_m: c,
        heading_rad,
        pitch_rad,
        flags: f.union(flags),
    }
}

/// The placement of `Visual::Blend { from, to, s }` (indices already checked), oriented for
/// `whole` when given, going round the way nearest `way`; and the way it went.
#[allow(clippy::too_many_arguments)]
fn place_blend(
    from: &Visual,
    to: &Visual,
    s: f64,
    whole: Option<&Visual>,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    way: &BlendWay,
) -> (Placement, BlendWay) {
    let orient = whole.is_some();
    let p0 = place_impl(from, actors, lens, gimbal, orient);
    let p1 = place_impl(to, actors, lens, gimbal, orient);
    let flags = p0.flags.union(p1.flags);
    if let Some((mut c, turns)) = toric_blend_position(from, to, s, actors, way) {
        if fixed_pitch(gimbal) {
            // Level camera: blend the ends' altitude corrections (place_two).
            let correction = |p: &Placement, v: &Visual| match v {
                Visual::Two(t) => toric::position(
                    &band_centre(&actors[t.a], t.band_a_m),
                    &band_centre(&actors[t.b], t.band_b_m),
                    &t.toric,
                )
                .map_or(0.0, |c| p.position_m.z - c.z),
                _ => 0.0,
            };
            c.z += lerp(correction(&p0, from), correction(&p1, to), s);
        }
        let way = BlendWay {
            about_pair_rad: turns.map(Some),
            ..*way
        };
        return (oriented(c, whole, flags, actors, lens, gimbal), way);
    }
    // Cylindrical blend about the actors involved.
    let centre = blend_centre(from, to, s, actors);
    let cyl = |p: &Vec3| {
        let d = p - centre;
        (
            dronecine_math::norm_xy(d.x, d.y),
            math::atan2(d.y, d.x),
            d.z,
        )
    };
    let (r0, a0, z0) = cyl(&p0.position_m);
    let (r1, a1, z1) = cyl(&p1.position_m);
    let turn = toric::nearest_turn_rad(wrap_angle_rad(a1 - a0), way.about_centre_rad);
    let (r, a, z) = (
        lerp(r0, r1, s),
        wrap_angle_rad(a0 + turn * s),
        lerp(z0, z1, s),
    );
    let c = centre + Vec3::new(r * math::cos(a), r * math::sin(a), z);
    let way = BlendWay {
        about_centre_rad: Some(turn),
        ..*way
    };
    (oriented(c, whole, flags, actors, lens, gimbal), way)
}

/// The aim points of a one- or two-actor visual, on the stack (`None` for a blend).
fn simple_aim_points(v: &Visual, actors: &[ActorPose]) -> Option<([(usize, Vec3); 2], usize)> {
    match v {
        Visual::One(o) => Some((
            [
                (o.actor, band_centre(&actors[o.actor], o.band_m)),
                (usize::MAX, Vec3::zeros()),
            ],
            1,
        )),
        Visual::Two(t) => Some((
            [
                (t.a, band_centre(&actors[t.a], t.band_a_m)),
                (t.b, band_centre(&actors[t.b], t.band_b_m)),
            ],
            2,
        )),
        Visual::Blend { .. } => None,
    }
}

/// The centroid of [`aim_points`] of `Visual::Blend { from, to, s }`, summed in the same
/// order (so bit for bit the same), without allocating for one- and two-actor ends.
fn blend_centre(from: &Visual, to: &Visual, s: f64, actors: &[ActorPose]) -> Vec3 {
    let (Some((p0, n0)), Some((p1, n1))) = (
        simple_aim_points(from, actors),
        simple_aim_points(to, actors),
    ) else {
        let v = Visual::Blend {
            from: Box::new(from.clone()),
            to: Box::new(to.clone()),
            s,
        };
        let points = aim_points(&v, actors);
        let sum = points.iter().fold(Vec3::zeros(), |acc, (_, p)| acc + p);
        return sum / points.len().max(1) as f64;
    };
    let (p0, p1) = (&p0[..n0], &p1[..n1]);
    let mut out = [(usize::MAX, Vec3::zeros()); 4];
    let mut n = 0;
    for (i, p) in p0 {
        out[n] = match p1.iter().find(|(j, _)| j == i) {
            Some((_, q)) => (*i, p + (q - p) * s),
            None => (*i, *p),
        };
        n += 1;
    }
    for (j, q) in p1 {
        if !out[..n].iter().any(|(i, _)| i == j) {
            out[n] = (*j, *q);
            n += 1;
        }
    }
    let sum = out[..n].iter().fold(Vec3::zeros(), |acc, (_, p)| acc + p);
    sum / n.max(1) as f64
}

fn place_one(
    o: &OneVisual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    orient: bool,
) -> Placement {
    let p = &actors[o.actor];
    let m = band_centre(p, o.band_m);
    let mut flags = Flags::default();
    let c = if fixed_pitch(gimbal) {
        flags.angle_not_rendered = o.elevation_rad.abs() > 1e-9;
        let horizontal = sphere::position(
            &m,
            p.facing_rad,
            &sphere::Spherical {
                distance_m: o.distance_m,
                azimuth_rad: o.azimuth_rad,
                elevation_rad: 0.0,
            },
        );
        let sx = lens.sx();
        let xp = o.screen[0] / sx;
        let depth = o.distance_m / (1.0 + xp * xp).sqrt();
        Vec3::new(
            horizontal.x,
            horizontal.y,
            m.z - o.screen[1] * depth / (sx * lens.aspect()),
        )
    } else {
        sphere::position(
            &m,
            p.facing_rad,
            &sphere::Spherical {
                distance_m: o.distance_m,
                azimuth_rad: o.azimuth_rad,
                elevation_rad: o.elevation_rad,
            },
        )
    };
    let (heading_rad, pitch_rad, f) = if orient {
        orient_visual(&Visual::One(*o), actors, lens, gimbal, &c)
    } else {
        (0.0, 0.0, Flags::default())
    };
    Placement {
        position_m: c,
        heading_rad,
        pitch_rad,
        flags: flags.union(f),
    }
}

fn place_two(
    t: &TwoVisual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    orient: bool,
) -> Placement {
    let ma = band_centre(&actors[t.a], t.band_a_m);
    let mb = band_centre(&actors[t.b], t.band_b_m);
    let mut c = match toric::position(&ma, &mb, &t.toric) {
        Ok(c) => c,
        Err(_) => {
            // Degenerate pair: frame the primary alone, from the front.
            let (actor, band, screen) = match t.primary {
                Primary::A => (t.a, t.band_a_m, t.screen_a),
                Primary::B => (t.b, t.band_b_m, t.screen_b),
            };
            let level = fixed_pitch(gimbal);
            let e = if level { 0.0 } else { t.elevation_rad };
            let d =
                band_distance_m(lens, (band[1] - band[0]) / 2.0, screen, e, level).unwrap_or(1.0);
            let one = OneVisual {
                actor,
                distance_m: d,
                azimuth_rad: 0.0,
                elevation_rad: t.elevation_rad,
                screen,
                band_m: band,
            };
            let mut p = place_one(&one, actors, lens, gimbal, orient);
            p.flags.degenerate = true;
            return p;
        }
    };
    let mut flags = Flags::default();
    if fixed_pitch(gimbal) {
        flags.angle_not_rendered = t.elevation_rad.abs() > 1e-9;
        // Level camera: the altitude puts the primary's aim point at its screen y.
        let (target, screen) = primary_target(t, actors);
        let rho = (target - c).xy().norm();
        let sx = lens.sx();
        let xp = screen[0] / sx;
        let depth = rho / (1.0 + xp * xp).sqrt();
        c.z = target.z - screen[1] * depth / (sx * lens.aspect());
    }
    let (heading_rad, pitch_rad, f) = if orient {
        orient_visual(&Visual::Two(*t), actors, lens, gimbal, &c)
    } else {
        (0.0, 0.0, Flags::default())
    };
    Placement {
        position_m: c,
        heading_rad,
        pitch_rad,
        flags: flags.union(f),
    }
}

/// Swap the roles of A and B in a two-actor visual (same camera position):
/// θ' = 2(π − α) − θ, φ' = π − φ.
pub fn swap_pair(t: &TwoVisual) -> TwoVisual {
    TwoVisual {
        a: t.b,
        b: t.a,
        toric: Toric {
            alpha_rad: t.toric.alpha_rad,
            theta_rad: 2.0 * (PI - t.toric.alpha_rad) - t.toric.theta_rad,
            phi_rad: wrap_angle_rad(PI - t.toric.phi_rad),
        },
        screen_a: t.screen_b,
        screen_b: t.screen_a,
        band_a_m: t.band_b_m,
        band_b_m: t.band_a_m,
        primary: match t.primary {
            Primary::A => Primary::B,
            Primary::B => Primary::A,
        },
        elevation_rad: t.elevation_rad,
        over_shoulder: t.over_shoulder,
        stretch: t.stretch,
    }
}

/// The position of a blend of two two-actor visuals of the same pair (in either order): the
/// toric interpolation ([`toric::interpolate`]) against the current poses, about the aim points
/// of the interpolated bands (the midpoint of the two candidates is used as is: it is near, not
/// on, the torus of the interpolated α, and never collapses onto an actor the way a projection
/// onto the torus does when the move crosses the line of action). `None` for any other blend.
fn toric_blend_position(
    from: &Visual,
    to: &Visual,
    s: f64,
    actors: &[ActorPose],
    way: &BlendWay,
) -> Option<(Vec3, [f64; 2])> {
    let (Visual::Two(t0), Visual::Two(t1)) = (from, to) else {
        return None;
    };
    let t1 = if (t1.a, t1.b) == (t0.a, t0.b) {
        *t1
    } else if (t1.b, t1.a) == (t0.a, t0.b) {
        swap_pair(t1)
    } else {
        return None;
    };
    let ma = band_centre(&actors[t0.a], lerp2(t0.band_a_m, t1.band_a_m, s));
    let mb = band_centre(&actors[t0.b], lerp2(t0.band_b_m, t1.band_b_m, s));
    let c0 = toric::position(&ma, &mb, &t0.toric).ok()?;
    let c1 = toric::position(&ma, &mb, &t1.toric).ok()?;
    Some(toric::interpolate(
        &ma,
        &mb,
        &c0,
        &c1,
        t0.toric.alpha_rad,
        t1.toric.alpha_rad,
        s,
        way.about_pair_rad,
    ))
}

// ---------------------------------------------------------------------------------------------
// interpolate

/// Blend two visuals at `s` ∈ [0, 1] (clamped; `s = 0` and `s = 1` return the inputs).
///
/// - Same single actor: linear in distance, band, elevation and screen, azimuth the short way
///   round (wrapped).
/// - Otherwise a [`Visual::Blend`], evaluated by [`place`] against the current poses:
///   - two visuals of the same pair (in either order): the position is the toric
///     interpolation (per-actor yaw/elevation/distance, pulled toward the torus of the linearly
///     interpolated α, midpoint of the two candidates), about the aim points of the linearly
///     interpolated bands;
///   - anything else (different actors, one ↔ two actors): both ends are placed and the
///     position is interpolated in cylindrical coordinates (radius, angle the short way,
///     height) about the centroid of the aim points of every actor involved.
///
///   In both cases the camera aims the interpolation of the two ends' aimed points at the
///   interpolation of their screen points (continuous; exact for an actor aimed at both ends),
///   and the flags are those of both ends plus the blend's own.
pub fn interpolate(a: &Visual, b: &Visual, s: f64) -> Visual {
    interpolate_reusing(a, b, s, &mut None)
}

/// [`interpolate`], building a blend in the two boxes of `spare` when it holds some (taken):
/// the same visual, without allocating once a blend has been made.
pub fn interpolate_reusing(
    a: &Visual,
    b: &Visual,
    s: f64,
    spare: &mut Option<(Box<Visual>, Box<Visual>)>,
) -> Visual {
    let v = interpolate_shortcut(a, b, s);
    match v {
        Ok(v) => v,
        Err(s) => {
            let (mut from, mut to) = match spare.take() {
                Some(boxes) => boxes,
                None => (Box::new(a.clone()), Box::new(b.clone())),
            };
            (*from).clone_from(a);
            (*to).clone_from(b);
            Visual::Blend { from, to, s }
        }
    }
}

/// The cases of [`interpolate`] that need no blend (`Ok`), or the clamped `s` of a blend.
fn interpolate_shortcut(a: &Visual, b: &Visual, s: f64) -> Result<Visual, f64> {
    let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
    if s == 0.0 {
        return Ok(a.clone());
    }
    if s == 1.0 {
        return Ok(b.clone());
    }
    match (a, b) {
        (Visual::One(x), Visual::One(y)) if x.actor == y.actor => {
            Ok(Visual::One(lerp_one(x, y, s)))
        }
        _ => Err(s),
    }
}

/// Two one-actor visuals of the same actor blended at `s`.
fn lerp_one(x: &OneVisual, y: &OneVisual, s: f64) -> OneVisual {
    OneVisual {
        actor: x.actor,
        distance_m: lerp(x.distance_m, y.distance_m, s),
        azimuth_rad: lerp_angle(x.azimuth_rad, y.azimuth_rad, s),
        elevation_rad: lerp(x.elevation_rad, y.elevation_rad, s),
        screen: lerp2(x.screen, y.screen, s),
        band_m: lerp2(x.band_m, y.band_m, s),
    }
}

// ---------------------------------------------------------------------------------------------
// Metrics and safety

/// The aim point (band centre) of every actor a visual frames, by actor index; for a blend,
/// actors present at both ends have their points interpolated.
pub fn aim_points(v: &Visual, actors: &[ActorPose]) -> Vec<(usize, Vec3)> {
    if !valid_indices(v, actors.len()) {
        return Vec::new();
    }
    match v {
        Visual::One(o) => vec![(o.actor, band_centre(&actors[o.actor], o.band_m))],
        Visual::Two(t) => vec![
            (t.a, band_centre(&actors[t.a], t.band_a_m)),
            (t.b, band_centre(&actors[t.b], t.band_b_m)),
        ],
        Visual::Blend { from, to, s } => {
            let p0 = aim_points(from, actors);
            let p1 = aim_points(to, actors);
            let mut out: Vec<(usize, Vec3)> = Vec::new();
            for (i, p) in &p0 {
                match p1.iter().find(|(j, _)| j == i) {
                    Some((_, q)) => out.push((*i, p + (q - p) * *s)),
                    None => out.push((*i, *p)),
                }
            }
            for (j, q) in &p1 {
                if !out.iter().any(|(i, _)| i == j) {
                    out.push((*j, *q));
                }
            }
            out
        }
    }
}

/// Each framed actor's world point and requested screen point, for a camera at `camera_m`
/// (the metric: project `point_m` through the placed camera and compare with `screen`).
///
/// One actor: the band's bisector point seen from the camera and [`size::band_aim_screen`]
/// (for a fixed-pitch camera the band centre at the requested screen point: both land
/// exactly). Two actors: the band centres at their screen points. Blend: actors at both ends
/// interpolated (point and screen), an actor at one end only listed while that end dominates
/// (s < 0.5 for `from`).
pub fn screen_targets(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    camera_m: &Vec3,
) -> Vec<ScreenTarget> {
    let mut out = Vec::new();
    screen_targets_into(v, actors, lens, gimbal, camera_m, &mut out);
    out
}

/// [`screen_targets`] into a reused buffer (cleared first): a `One` or `Two` visual (a hold)
/// allocates nothing once `out` has room for two targets.
pub fn screen_targets_into(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    camera_m: &Vec3,
    out: &mut Vec<ScreenTarget>,
) {
    out.clear();
    if !valid_indices(v, actors.len()) {
        return;
    }
    let targets = match v {
        Visual::One(o) => {
            let p = &actors[o.actor];
            if fixed_pitch(gimbal) {
                out.push(ScreenTarget {
                    actor: o.actor,
                    point_m: band_centre(p, o.band_m),
                    screen: o.screen,
                });
            } else {
                out.push(ScreenTarget {
                    actor: o.actor,
                    point_m: size::bisector_point(
                        camera_m,
                        &band_point(p, o.band_m[1]),
                        &band_point(p, o.band_m[0]),
                    ),
                    screen: size::band_aim_screen(lens, o.screen),
                });
            }
            return;
        }
        Visual::Two(t) => {
            out.push(ScreenTarget {
                actor: t.a,
                point_m: band_centre(&actors[t.a], t.band_a_m),
                screen: t.screen_a,
            });
            out.push(ScreenTarget {
                actor: t.b,
                point_m: band_centre(&actors[t.b], t.band_b_m),
                screen: t.screen_b,
            });
            return;
        }
        Visual::Blend { from, to, s } => {
            let t0 = screen_targets(from, actors, lens, gimbal, camera_m);
            let t1 = screen_targets(to, actors, lens, gimbal, camera_m);
            let mut blend = Vec::new();
            for x in &t0 {
                match t1.iter().find(|y| y.actor == x.actor) {
                    Some(y) => blend.push(ScreenTarget {
                        actor: x.actor,
                        point_m: x.point_m + (y.point_m - x.point_m) * *s,
                        screen: lerp2(x.screen, y.screen, *s),
                    }),
                    None if *s < 0.5 => blend.push(*x),
                    None => {}
                }
            }
            if *s >= 0.5 {
                for y in &t1 {
                    if !t0.iter().any(|x| x.actor == y.actor) {
                        blend.push(*y);
                    }
                }
            }
            blend
        }
    };
    out.extend(targets);
}

/// Distance from a point to an actor's body axis (the vertical segment feet → head).
pub fn body_axis_distance_m(point_m: &Vec3, actor: &ActorPose) -> f64 {
    crate::steering::Body::from(actor).distance_m(point_m)
}

/// [`body_axis_distance_m`] for every actor, in the actors' order.
pub fn body_axis_distances_m(point_m: &Vec3, actors: &[ActorPose]) -> Vec<f64> {
    actors
        .iter()
        .map(|a| body_axis_distance_m(point_m, a))
        .collect()
}

/// How fast a two-shot's θ turns while the actors walk with their velocities, for a visual
/// whose θ is a root of its sized actor's distance constraint with a level camera (a
/// two-actor framing without profile: what [`solve`] gives each tick). From θ = θ₀ + 2s·β',
/// β' = arccos(ρ), ρ = d·sin α/|AB| (θ₀ = π − 2α when A has the size, π when B has it; s = ±1
/// the root): `dθ/dt = 2s·ρ/(|AB|·√(1 − ρ²)) · d|AB|/dt`. α, φ, the bands and the screens
/// do not change while the actors keep their heights, so this and the actors' velocities
/// give the held framing's motion without solving again. `None` when it does not apply:
/// another visual, a gimbal (θ is then refined against the elevation), a θ that is not that
/// root (a profile's vantage), or a root near the tangent (ρ > 0.999).
pub fn two_shot_theta_rate(
    v: &Visual,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
) -> Option<f64> {
    let Visual::Two(t) = v else {
        return None;
    };
    if !fixed_pitch(gimbal) || t.over_shoulder || !valid_indices(v, actors.len()) {
        return None;
    }
    let (pa, pb) = (&actors[t.a], &actors[t.b]);
    let ab_m = band_centre(pb, t.band_b_m) - band_centre(pa, t.band_a_m);
    let ab = ab_m.norm();
    let alpha = t.toric.alpha_rad;
    let (band, screen, theta0) = match t.primary {
        Primary::A => (t.band_a_m, t.screen_a, PI - 2.0 * alpha),
        Primary::B => (t.band_b_m, t.screen_b, PI),
    };
    let d = band_distance_m(lens, (band[1] - band[0]) / 2.0, screen, 0.0, true)?;
    let ratio = d / (2.0 * toric::radius_m(ab, alpha));
    if !(ratio < 0.999 && ratio > 0.0) {
        return None;
    }
    let theta = t.toric.theta_rad;
    let s = if theta >= theta0 { 1.0 } else { -1.0 };
    if (theta0 + s * 2.0 * math::acos(ratio) - theta).abs() > 1e-9 {
        return None;
    }
    let relative_mps = Vec3::from(pb.velocity_mps) - Vec3::from(pa.velocity_mps);
    let ab_rate_mps = ab_m.dot(&relative_mps) / ab;
    Some(s * 2.0 * ratio / (ab * (1.0 - ratio * ratio).sqrt()) * ab_rate_mps)
}

/// Feed-forward velocity of [`place`]'s position for a held visual while the actors move with
/// their velocities and turn rates: the sphere's formula (`Ṗ + d·∂û/∂θ·ḣ`,
/// [`sphere::velocity`]) for one actor, the exact derivative of the placement (central
/// difference of the smooth map, actors extrapolated ±1 ms) otherwise.
pub fn velocity_mps(v: &Visual, actors: &[ActorPose], lens: &Lens, gimbal: &Gimbal) -> Vec3 {
    if !valid_indices(v, actors.len()) {
        return Vec3::zeros();
    }
    if let Visual::One(o) = v {
        let p = &actors[o.actor];
        let e = if fixed_pitch(gimbal) {
            0.0
        } else {
            o.elevation_rad
        };
        return sphere::velocity(
            p.facing_rad,
            &sphere::Spherical {
                distance_m: o.distance_m,
                azimuth_rad: o.azimuth_rad,
                elevation_rad: e,
            },
            &sphere::Rates {
                aim_velocity_mps: Vec3::from(p.velocity_mps),
                facing_rate_radps: p.facing_rate_radps,
                distance_rate_mps: 0.0,
                azimuth_rate_radps: 0.0,
                elevation_rate_radps: 0.0,
            },
        );
    }
    let dt = 1e-3;
    let shifted = |k: f64| -> Vec<ActorPose> {
        actors
            .iter()
            .map(|a| ActorPose {
                position_m: [
                    a.position_m[0] + a.velocity_mps[0] * k,
                    a.position_m[1] + a.velocity_mps[1] * k,
                    a.position_m[2] + a.velocity_mps[2] * k,
                ],
                facing_rad: wrap_angle_rad(a.facing_rad + a.facing_rate_radps * k),
                ..*a
            })
            .collect()
    };
    let p1 = place(v, &shifted(dt), lens, gimbal).position_m;
    let p0 = place(v, &shifted(-dt), lens, gimbal).position_m;
    (p1 - p0) / (2.0 * dt)
}
