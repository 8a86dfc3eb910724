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
//! - **Two actors in one framing** (`MS on A and B`), film grammar's two-shot: the camera on
//!   the perpendicular bisector of their band centres (θ = π − α), on the side of the line of
//!   action it is told ([`Prepared::on_side`]), at the elevation; the size applies to both,
//!   their screen points spreading symmetrically (A left of B on the φ = 0 side) until it
//!   holds, at most [`TWO_SHOT_SCREEN_MAX`] from the centre, beyond which the size gives way
//!   ([`TwoVisual::distance_ratio`]). The camera aims between them ([`Primary::Pair`]), and
//!   actors of different heights land where it sees them, the taller higher. Written screen
//!   positions outrank the size. A profile on one of the two puts the camera on the ray from
//!   that actor along it, at their size's distance or as far as both fit; on both, or along
//!   the line through them, it is refused.
//! - **Over the shoulder** (two framings, foreground A then background B): the camera's
//!   bearing from each actor within [`PROFILE_HALF_WIDTH_RAD`] of its profile's angle (a
//!   foreground actor without one: behind them as B sees them); among those cameras, B at its
//!   screen point and, where the geometry allows, its size, else from as near as the sectors
//!   let it stand; A on the other half of the frame, where the camera sees them. No camera in
//!   both sectors is [`FramingError::ProfilesConflict`]. Primary = B.
//! - **Roll-free orientation**: the primary's aim point lands exactly at its screen point
//!   (heading and pitch from [`orient`]); a pair's aim ([`Primary::Pair`]) puts the bisector
//!   of the angle between them at the bisector of their screen points, both exact when they
//!   stand at the camera's height.
//!
//! Holding a two-actor `Visual` keeps (α, θ, φ): as the actors move apart the distances scale.
//! Re-solve each tick to keep the size exact; interpolate from the held `Visual` to a re-solved
//! one to change it smoothly.

use crate::camera::{orient, orient_fixed_pitch, Lens, Vec3};
use crate::reference::ActorPose;
use crate::toric::Toric;
use crate::{size, sphere, toric};
use dronecine_grammar::script::{Composition, Subject};
use dronecine_grammar::vocab::{Profile, Size};
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
    /// Neither: the camera aims where the bisector of the angle between the two band centres
    /// meets the line through them, at the midpoint of their screen points, so that a
    /// two-shot's errors (actors of different heights seen by a level camera) split evenly.
    Pair,
}

/// Which side of the line of action a camera stands on, for an ordered pair (A, B): the sign
/// of the vertical component of `(B − A) × (C − A)` (film grammar's line-of-action rule).
/// `Right` (negative: the camera to the right of A→B seen from above) is the toric φ = 0
/// side, from which a roll-free camera sees A screen-left of B.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Right,
    Left,
}

impl Side {
    /// The side a camera at `c_m` stands on of the line from `a_m` to `b_m` (floor
    /// coordinates); `None` on the line, or with A and B at one place.
    pub fn of(a_m: &Vec3, b_m: &Vec3, c_m: &Vec3) -> Option<Side> {
        let cross = (b_m.x - a_m.x) * (c_m.y - a_m.y) - (b_m.y - a_m.y) * (c_m.x - a_m.x);
        if !cross.is_finite() || cross == 0.0 {
            None
        } else if cross < 0.0 {
            Some(Side::Right)
        } else {
            Some(Side::Left)
        }
    }

    /// The same side seen from the pair taken in the other order.
    pub fn swapped(self) -> Side {
        match self {
            Side::Right => Side::Left,
            Side::Left => Side::Right,
        }
    }
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
    /// The camera's distance from the sized actor's band centre (both actors' for a
    /// symmetric two-shot) over the distance the written size asks: 1 when the size holds,
    /// above 1 when the camera had to stand farther (the actors too far apart for the size
    /// in one frame; an over-the-shoulder's background actor out of the size's reach from
    /// behind the foreground actor), the sized actor then framed that much smaller.
    pub distance_ratio: f64,
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
    /// A two-shot with a profile on both actors: it has one vantage.
    TwoProfiles,
    /// A two-shot's profile looks along the line through the two actors: one would stand in
    /// front of the other, or behind the camera.
    ProfileBlocked { profile: Profile },
    /// No camera stands in both over-the-shoulder sectors: the foreground actor's profile
    /// (behind them, without one) and the background actor's.
    ProfilesConflict {
        foreground: Option<Profile>,
        background: Option<Profile>,
    },
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
            FramingError::TwoProfiles => {
                f.write_str("a two-shot is seen from one side: it takes one profile, not two")
            }
            FramingError::ProfileBlocked { profile } => write!(
                f,
                "from the {} side the camera looks along the line through the two actors: one \
                 stands in front of the other",
                profile.as_str()
            ),
            FramingError::ProfilesConflict {
                foreground,
                background,
            } => {
                let fg = foreground.map_or("behind the foreground actor".to_string(), |p| {
                    format!("the foreground actor's {}", p.as_str())
                });
                let bg = background.map_or("the background actor in frame".to_string(), |p| {
                    format!("the background actor's {}", p.as_str())
                });
                write!(f, "no camera stands both on {fg} side and on {bg} side")
            }
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
    /// The side of the line of action a two-actor framing that leaves it free stands on
    /// (the first subject as A), set by [`Prepared::on_side`].
    side: Option<Side>,
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
            side: None,
        }
    }

    /// The same, with a two-actor framing whose side of the line of action its profiles and
    /// screen positions leave free put on `side` (the line from the first subject to the
    /// second): film grammar's established side, which the compiler gives each shot.
    pub fn on_side(self, side: Option<Side>) -> Prepared {
        Prepared { side, ..self }
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
    /// from one to the other, across the stage in one tick. With `near`, each camera's cost
    /// grows with its bearing's turn from the last solve's (`HOLD_WEIGHT_M_PER_RAD`), so the
    /// one held is not given up for one that frames only as well. And of the two, one whose camera comes within `clear_m` of an actor's body axis
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
                        Some(t.toric)
                    }
                    _ => None,
                };
                solve_together(pair, sa, sb, actors, lens, gimbal, near, self.side).map(Visual::Two)
            }
            [fg, bg] if fg.subjects.len() == 1 && bg.subjects.len() == 1 => {
                let (sa, sb) = (&fg.subjects[0], &bg.subjects[0]);
                let pair = pair_of(sa, sb, (fg.size, bg.size))?;
                let near = match near {
                    Some(Visual::Two(t)) if t.over_shoulder => Some(t.toric),
                    _ => None,
                };
                let side = self.side;
                solve_over_shoulder(pair, sa, sb, actors, lens, gimbal, near, clear_m, side)
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
#[derive(Clone, Debug)]
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
            distance_ratio: 1.0,
        }
    }

    /// The distance both actors' size asks of a camera that sees A at `screen_a` and B at
    /// `screen_b`: the mean of the two (they differ for actors of different heights).
    fn asked_distance(&self, lens: &Lens, screen_a: [f64; 2], screen_b: [f64; 2]) -> f64 {
        let d = |band: [f64; 2], screen| {
            band_distance_m(lens, (band[1] - band[0]) / 2.0, screen, self.e, self.level)
                .unwrap_or(f64::NAN)
        };
        (d(self.band_a, screen_a) + d(self.band_b, screen_b)) / 2.0
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

/// The widest a two-shot puts its actors on screen (|x| of their band centres): past it the
/// size gives way, the camera standing back until they fit.
pub const TWO_SHOT_SCREEN_MAX: f64 = 0.8;

/// A two-actor framing in one framing (`MS on A and B`), as film grammar reads it:
/// - no profile: a symmetric two-shot ([`symmetric_two_shot`]);
/// - a profile on one of the two: the camera sees that actor from that side
///   ([`two_shot_from`]);
/// - a profile on both: refused, a two-shot has one vantage.
#[allow(clippy::too_many_arguments)]
fn solve_together(
    pair: Pair,
    sa: &Subject,
    sb: &Subject,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    near: Option<Toric>,
    side: Option<Side>,
) -> Result<TwoVisual, FramingError> {
    match (sa.profile, sb.profile) {
        (Some(_), Some(_)) => Err(FramingError::TwoProfiles),
        (Some(p), None) => two_shot_from(pair, Primary::A, p, actors, lens),
        (None, Some(p)) => two_shot_from(pair, Primary::B, p, actors, lens),
        (None, None) => symmetric_two_shot(pair, lens, gimbal, near, side),
    }
}

/// A two-shot with no profile: the camera on the perpendicular bisector of the two band
/// centres (θ = π − α, equally far from both), on `side` of the line (else the held one,
/// else A screen-left), at the written elevation, aimed between them ([`Primary::Pair`]).
/// The size applies to both: without written screen positions the actors' screen points
/// move apart or together symmetrically until the camera's distance is the one their size
/// asks (the mean of the two, for actors of different heights), up to
/// [`TWO_SHOT_SCREEN_MAX`], beyond which the size gives way ([`TwoVisual::distance_ratio`]);
/// their screen points are then where that camera sees them, so that actors of different
/// heights stand as they are, the taller higher in the frame (no roll-free camera puts two
/// points at different heights on one screen line from equal distances). Written screen
/// positions hold and the size follows; for actors of different heights their roll-free
/// error splits evenly between the two.
fn symmetric_two_shot(
    mut pair: Pair,
    lens: &Lens,
    gimbal: &Gimbal,
    near: Option<Toric>,
    side: Option<Side>,
) -> Result<TwoVisual, FramingError> {
    let right = match (side, near) {
        (Some(s), _) => s == Side::Right,
        (None, Some(t)) if t.phi_rad.is_finite() => math::cos(t.phi_rad) >= 0.0,
        _ => true,
    };
    if !pair.order_fixed && right != pair.a_left() {
        pair.mirror();
    }
    let ratio = if pair.order_fixed {
        let asked = pair.asked_distance(lens, pair.screen_a, pair.screen_b);
        symmetric_distance(pair.ab(), pair.alpha) / asked
    } else {
        let (x, ratio) = spread_for_size(&pair, lens);
        let sign = if pair.a_left() { 1.0 } else { -1.0 };
        pair.screen_a[0] = -sign * x;
        pair.screen_b[0] = sign * x;
        pair.alpha = toric::alpha_from_screens(lens, pair.screen_a, pair.screen_b);
        ratio
    };
    if !(pair.alpha > 1e-9 && pair.alpha < PI) {
        return Err(FramingError::ScreensCoincide);
    }
    let toric = Toric {
        alpha_rad: pair.alpha,
        theta_rad: PI - pair.alpha,
        phi_rad: pair.side_phi(),
    };
    let mut visual = TwoVisual {
        distance_ratio: ratio,
        ..pair.visual(toric, Primary::Pair, false)
    };
    if !pair.order_fixed {
        as_seen(&mut visual, &pair, lens, gimbal);
    }
    Ok(visual)
}

/// Puts a symmetric two-shot's screen points where its camera, aimed between the two, sees
/// their band centres (the same angle between them: only heights move them off the line).
/// The gimbal's range is not applied here, `place` applies it.
fn as_seen(v: &mut TwoVisual, pair: &Pair, lens: &Lens, gimbal: &Gimbal) {
    let Ok(mut c) = toric::position(&pair.ma, &pair.mb, &v.toric) else {
        return;
    };
    let (da, db) = ((pair.ma - c).norm(), (pair.mb - c).norm());
    let share = if da + db > 0.0 { da / (da + db) } else { 0.5 };
    let target = pair.ma + (pair.mb - pair.ma) * share;
    // The camera the composition asks for (a gimbal's pitch unclamped: a pitch out of its
    // range shows as an error on these points, not in them).
    let (heading, pitch) = if fixed_pitch(gimbal) {
        c.z = target.z;
        (orient_fixed_pitch(lens, &c, &target, 0.0, 0.0), 0.0)
    } else {
        let o = orient(lens, &c, &target, [0.0, 0.0]);
        (o.heading_rad, o.pitch_rad)
    };
    let camera = crate::camera::CameraPose {
        position_m: c,
        heading_rad: heading,
        pitch_rad: pitch,
    };
    if let (Some(a), Some(b)) = (
        camera.project(lens, &pair.ma),
        camera.project(lens, &pair.mb),
    ) {
        v.screen_a = a;
        v.screen_b = b;
    }
}

/// The camera's distance from each band centre on the bisector of a pair `ab_m` apart seen
/// under α: `|AB| / (2 sin(α/2))`.
fn symmetric_distance(ab_m: f64, alpha_rad: f64) -> f64 {
    ab_m / (2.0 * math::sin(alpha_rad / 2.0))
}

/// Where a symmetric two-shot's size's distance and its widest spread's meet, the camera's
/// distance blends from one to the other over this share of the size's distance (a smooth
/// maximum): as the actors walk apart the camera starts to stand back smoothly, with no step
/// in its acceleration for the drone to follow, framing at most half this share looser
/// where the two meet.
pub const SPREAD_BLEND: f64 = 0.1;

/// The widest screen half-spread the size's root is looked for up to (rays 176° apart).
const SPREAD_ROOT_MAX: f64 = 30.0;

/// The screen half-spread x (A and B at ∓x) of a symmetric two-shot, and the ratio of the
/// camera's distance to the one the pair's size asks: the size's distance (where the
/// bisector distance, falling as x grows, meets the asked distance, growing: one root, found
/// by regula falsi from the level camera's closed form `x = (|AB|/2)/(h·aspect)`), or the
/// distance at [`TWO_SHOT_SCREEN_MAX`] when that is farther, the two blended over
/// [`SPREAD_BLEND`]; x from the distance in closed form, `x = Sx·tan(asin(|AB|/2d))`.
fn spread_for_size(pair: &Pair, lens: &Lens) -> (f64, f64) {
    let ab = pair.ab();
    let at = |x: f64| {
        let (sa, sb) = ([-x, 0.0], [x, 0.0]);
        let alpha = toric::alpha_from_screens(lens, sa, sb);
        let asked = pair.asked_distance(lens, sa, sb);
        (symmetric_distance(ab, alpha), asked)
    };
    let gap = |x: f64| {
        let (d, asked) = at(x);
        d - asked
    };
    let half = ((pair.band_a[1] - pair.band_a[0]) + (pair.band_b[1] - pair.band_b[0])) / 4.0;
    let guess = (ab / 2.0) / (half * lens.aspect());
    let (mut a, mut b) = (1e-6, SPREAD_ROOT_MAX);
    let (mut fa, mut fb) = (gap(a), gap(b));
    if guess > a && guess < b {
        let fg = gap(guess);
        if fg > 0.0 {
            (a, fa) = (guess, fg);
        } else {
            (b, fb) = (guess, fg);
        }
    }
    let mut kept = 0i8;
    for _ in 0..80 {
        if (b - a).abs() < 1e-12 || fa == 0.0 || fb == 0.0 {
            break;
        }
        let mut x = (a * fb - b * fa) / (fb - fa);
        if !(x > a.min(b) && x < a.max(b)) {
            x = (a + b) / 2.0;
        }
        let fx = gap(x);
        if (fx > 0.0) == (fa > 0.0) {
            (a, fa) = (x, fx);
            if kept == 1 {
                fb /= 2.0;
            }
            kept = 1;
        } else {
            (b, fb) = (x, fx);
            if kept == -1 {
                fa /= 2.0;
            }
            kept = -1;
        }
    }
    let root = if fa.abs() < fb.abs() { a } else { b };
    let d_size = at(root).0;
    let d_fit = at(TWO_SHOT_SCREEN_MAX).0;
    let d = smooth_max(d_size, d_fit, SPREAD_BLEND * d_size);
    let half_angle = math::asin((ab / (2.0 * d)).min(1.0));
    (lens.sx() * math::tan(half_angle), d / d_size)
}

/// A smooth maximum of `a` and `b`: `(a + b + √((a − b)² + w²))/2`, at most `w/2` above the
/// larger, where they meet.
fn smooth_max(a: f64, b: f64, w: f64) -> f64 {
    (a + b + ((a - b) * (a - b) + w * w).sqrt()) / 2.0
}

/// Directions a two-shot's profile may not look along: within this of the line to the
/// other actor, one actor stands in front of the other (or behind the camera).
pub const PROFILE_BLOCKED_RAD: f64 = 0.35;

/// A two-shot with a profile on one actor X (`which`): the camera on the ray from X's band
/// centre along the profile (at the written elevation; level for a fixed-pitch camera), at
/// the distance X's size asks, or farther until both actors fit within
/// [`TWO_SHOT_SCREEN_MAX`] of the centre with the camera aimed between them
/// ([`Primary::Pair`]). Refused when the profile looks along the line through the two
/// ([`FramingError::ProfileBlocked`]).
fn two_shot_from(
    mut pair: Pair,
    which: Primary,
    profile: Profile,
    actors: &[ActorPose],
    lens: &Lens,
) -> Result<TwoVisual, FramingError> {
    let (x_actor, mx, my, band) = match which {
        Primary::B => (pair.b, pair.mb, pair.ma, pair.band_b),
        _ => (pair.a, pair.ma, pair.mb, pair.band_a),
    };
    let u = sphere::direction(actors[x_actor].facing_rad, profile.azimuth_rad(), pair.e);
    let to_other = my - mx;
    let gamma = crate::camera::angle(
        &Vec3::new(u.x, u.y, 0.0),
        &Vec3::new(to_other.x, to_other.y, 0.0),
    );
    if !(gamma > PROFILE_BLOCKED_RAD && gamma < PI - PROFILE_BLOCKED_RAD) {
        return Err(FramingError::ProfileBlocked { profile });
    }
    // The half angle the two subtend at a camera r along u, and the spread it puts them at.
    let half_angle =
        |r: f64| crate::camera::angle(&(mx - (mx + u * r)), &(my - (mx + u * r))) / 2.0;
    let spread = |r: f64| lens.sx() * math::tan(half_angle(r));
    let half = (band[1] - band[0]) / 2.0;
    // The size's distance depends on the screen x; two fixed-point steps settle it.
    let mut r = band_distance_m(lens, half, [0.0, 0.0], pair.e, pair.level).unwrap_or(1.0);
    for _ in 0..2 {
        let x = spread(r).min(TWO_SHOT_SCREEN_MAX);
        r = band_distance_m(lens, half, [x, 0.0], pair.e, pair.level).unwrap_or(r);
    }
    let asked = r;
    if !(spread(r) <= TWO_SHOT_SCREEN_MAX) {
        // Farther along u the angle between them shrinks: bisect for the widest spread.
        let (mut lo, mut hi) = (r, r * 2.0);
        while spread(hi) > TWO_SHOT_SCREEN_MAX && hi < 1e4 {
            lo = hi;
            hi *= 2.0;
        }
        for _ in 0..60 {
            let mid = (lo + hi) / 2.0;
            if spread(mid) > TWO_SHOT_SCREEN_MAX {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        r = hi;
    }
    let c = mx + u * r;
    let t = toric::inverse(&pair.ma, &pair.mb, &c).map_err(|_| FramingError::ActorsCoincide)?;
    let x = spread(r);
    let a_left = Side::of(&pair.ma, &pair.mb, &c) != Some(Side::Left);
    if pair.order_fixed && a_left != pair.a_left() {
        return Err(FramingError::ScreenSideConflict);
    }
    pair.screen_a = [if a_left { -x } else { x }, 0.0];
    pair.screen_b = [if a_left { x } else { -x }, 0.0];
    pair.alpha = t.alpha_rad;
    Ok(TwoVisual {
        distance_ratio: r / asked,
        ..pair.visual(t, Primary::Pair, false)
    })
}

/// Half-width of the bearings a profile names, about its angle: film grammar's ±22.5°
/// (each of the eight profiles a 45° sector), less a margin for live actors and rounding.
pub const PROFILE_HALF_WIDTH_RAD: f64 = 20.0 * PI / 180.0;

/// Without a profile on the foreground actor, an over-the-shoulder camera stands behind
/// them: within this of the line from the background actor through the foreground one.
pub const BEHIND_HALF_WIDTH_RAD: f64 = PI / 3.0;

/// The weight (metres per radian) of a profile's deviation from its angle against the
/// background actor's size (metres of camera distance) in the over-the-shoulder's choice:
/// small, the size comes first and the profiles only choose among cameras that keep it.
const PROFILE_WEIGHT_M_PER_RAD: f64 = 0.05;

/// The weight (metres per radian) of a held over-the-shoulder's bearing from its last: a
/// camera that frames as well elsewhere does not take its place.
const HOLD_WEIGHT_M_PER_RAD: f64 = 0.02;

/// How far from the frame's centre an over-the-shoulder's foreground actor is asked to be at
/// least, on the other half from the background actor (screen units).
const OTS_FOREGROUND_GAP: f64 = 0.05;

/// The farthest an over-the-shoulder's camera stands from the background actor, in multiples
/// of its size's distance or of the actors' separation (the larger): where the two sectors
/// meet only farther away, no camera frames the composition.
const OTS_REACH: f64 = 4.0;

/// The bearings from the background actor the over-the-shoulder's search samples (across
/// a profile's sector, or the whole turn), before it refines the best.
const OTS_SAMPLES: usize = 48;

/// The horizontal bearings (a wedge with its apex at an actor's feet) a camera's bearing
/// from that actor must lie in.
#[derive(Clone, Copy, Debug)]
struct Wedge {
    apex: [f64; 2],
    centre_rad: f64,
    half_rad: f64,
}

impl Wedge {
    /// The wedge of a written profile, or `None`.
    fn of_profile(p: &ActorPose, profile: Option<Profile>) -> Option<Wedge> {
        profile.map(|pr| Wedge {
            apex: [p.position_m[0], p.position_m[1]],
            centre_rad: wrap_angle_rad(p.facing_rad + pr.azimuth_rad()),
            half_rad: PROFILE_HALF_WIDTH_RAD,
        })
    }

    /// How far the bearing of `q` from the apex is from the wedge's centre.
    fn deviation(&self, q: [f64; 2]) -> f64 {
        let b = math::atan2(q[1] - self.apex[1], q[0] - self.apex[0]);
        wrap_angle_rad(b - self.centre_rad).abs()
    }

    /// The range of `r ≥ 0` for which `q + r·w` lies in the wedge (its two half-planes:
    /// the wedge is narrower than a half turn), or `None`.
    fn ray_interval(&self, q: [f64; 2], w: [f64; 2]) -> Option<(f64, f64)> {
        let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
        let (lo, hi) = (
            self.centre_rad - self.half_rad,
            self.centre_rad + self.half_rad,
        );
        let (e_lo, e_hi) = (
            [math::cos(lo), math::sin(lo)],
            [math::cos(hi), math::sin(hi)],
        );
        let d = [q[0] - self.apex[0], q[1] - self.apex[1]];
        let (mut r0, mut r1) = (0.0f64, f64::INFINITY);
        // cross(e_lo, d + r w) ≥ 0 and cross(d + r w, e_hi) ≥ 0.
        for (c0, c1) in [
            (cross(e_lo, d), cross(e_lo, w)),
            (-cross(e_hi, d), -cross(e_hi, w)),
        ] {
            if c1.abs() < 1e-15 {
                if c0 < 0.0 {
                    return None;
                }
            } else if c1 > 0.0 {
                r0 = r0.max(-c0 / c1);
            } else {
                r1 = r1.min(-c0 / c1);
            }
        }
        (r0 <= r1).then_some((r0, r1))
    }
}

/// One camera of the over-the-shoulder's search: its bearing and horizontal distance from
/// the background actor, which side of the line it stands on, and its cost.
#[derive(Clone, Copy, Debug)]
struct OtsCandidate {
    bearing_rad: f64,
    r_m: f64,
    side: Side,
    cost: f64,
}

/// An over-the-shoulder composition (`SIZE on A PROFILE_A SIZE on B PROFILE_B`, A the
/// foreground actor), as film grammar defines it: the camera's bearing from A within
/// [`PROFILE_HALF_WIDTH_RAD`] of PROFILE_A's angle (without one, behind A as B sees them,
/// within [`BEHIND_HALF_WIDTH_RAD`]), and from B within that of PROFILE_B's; then, among
/// those cameras, B framed at its size and screen point where the geometry allows and
/// otherwise from as near the size's distance as they allow ([`TwoVisual::distance_ratio`]),
/// the profiles as near their angles as the size leaves, A on the other half of the frame,
/// every camera at least `clear_m` from both actors' body axes. A's screen point and size
/// follow from where the camera is. No camera in both sectors is
/// [`FramingError::ProfilesConflict`].
///
/// Held (`near`: the last solve's toric coordinates), the search prefers the camera nearest
/// the last.
/// `side`: the side of the line the camera must stand on when the profiles leave it free.
#[allow(clippy::too_many_arguments)]
fn solve_over_shoulder(
    pair: Pair,
    sa: &Subject,
    sb: &Subject,
    actors: &[ActorPose],
    lens: &Lens,
    gimbal: &Gimbal,
    near: Option<Toric>,
    clear_m: f64,
    side: Option<Side>,
) -> Result<TwoVisual, FramingError> {
    let (pa, pb) = (&actors[pair.a], &actors[pair.b]);
    let a_xy = [pa.position_m[0], pa.position_m[1]];
    let b_xy = [pb.position_m[0], pb.position_m[1]];
    let behind = math::atan2(a_xy[1] - b_xy[1], a_xy[0] - b_xy[0]);
    let wedge_a = Wedge::of_profile(pa, sa.profile).unwrap_or(Wedge {
        apex: a_xy,
        centre_rad: behind,
        half_rad: BEHIND_HALF_WIDTH_RAD,
    });
    let wedge_b = Wedge::of_profile(pb, sb.profile);
    // The side the written screen order or the hint fixes, if any.
    let fixed_side = if pair.order_fixed {
        Some(if pair.a_left() {
            Side::Right
        } else {
            Side::Left
        })
    } else {
        side
    };
    let last = near.and_then(|t| {
        let c = toric::position(&pair.ma, &pair.mb, &t).ok()?;
        Some(math::atan2(c.y - b_xy[1], c.x - b_xy[0]))
    });
    let search = OtsSearch {
        pair: &pair,
        a: pa,
        b: pb,
        wedge_a,
        wedge_b,
        lens,
        gimbal,
        clear_m,
        fixed_side,
        last,
    };
    let best = search.best().ok_or(FramingError::ProfilesConflict {
        foreground: sa.profile,
        background: sb.profile,
    })?;
    search.visual(&best)
}

/// The over-the-shoulder's search ([`solve_over_shoulder`]).
struct OtsSearch<'a> {
    pair: &'a Pair,
    a: &'a ActorPose,
    b: &'a ActorPose,
    wedge_a: Wedge,
    wedge_b: Option<Wedge>,
    lens: &'a Lens,
    gimbal: &'a Gimbal,
    clear_m: f64,
    fixed_side: Option<Side>,
    last: Option<f64>,
}

impl OtsSearch<'_> {
    fn b_xy(&self) -> [f64; 2] {
        [self.b.position_m[0], self.b.position_m[1]]
    }

    /// B's screen point for a camera on `side`: as written, or the third away from A.
    fn screen_b(&self, side: Side) -> [f64; 2] {
        let s = self.pair.screen_b;
        if self.pair.order_fixed {
            return s;
        }
        let x = s[0].abs().max(1e-3);
        [if side == Side::Right { x } else { -x }, s[1]]
    }

    /// The horizontal distance from B at which B has its size, at B's screen point.
    fn asked_r(&self, screen: [f64; 2]) -> Option<f64> {
        let p = self.pair;
        let d = band_distance_m(
            self.lens,
            (p.band_b[1] - p.band_b[0]) / 2.0,
            screen,
            p.e,
            p.level,
        )?;
        Some(if p.level { d } else { d * math::cos(p.e) })
    }

    /// The best camera on the ray from B at `bearing`, if the ray meets A's wedge.
    fn along(&self, bearing: f64) -> Option<OtsCandidate> {
        let b = self.b_xy();
        let w = [math::cos(bearing), math::sin(bearing)];
        let (r0, r1) = self.wedge_a.ray_interval(b, w)?;
        let probe = [b[0] + w[0] * (r0 + 1.0), b[1] + w[1] * (r0 + 1.0)];
        let side = Side::of(
            &Vec3::new(self.a.position_m[0], self.a.position_m[1], 0.0),
            &Vec3::new(b[0], b[1], 0.0),
            &Vec3::new(probe[0], probe[1], 0.0),
        )?;
        if self.fixed_side.is_some_and(|s| s != side) {
            return None;
        }
        let screen = self.screen_b(side);
        let asked = self.asked_r(screen)?;
        let r0 = r0.max(self.clear_m);
        // Sectors that meet only far away (nearly parallel) frame nothing the shot names.
        let ab = math::hypot(self.a.position_m[0] - b[0], self.a.position_m[1] - b[1]);
        if r0 > r1 || r0 > OTS_REACH * asked.max(ab) {
            return None;
        }
        let mut r = asked.clamp(r0, r1);
        r = self.clear_of_a(b, w, r, r1)?;
        let c = [b[0] + w[0] * r, b[1] + w[1] * r];
        let mut cost = (r - asked).abs();
        cost += PROFILE_WEIGHT_M_PER_RAD
            * (self.wedge_a.deviation(c) + self.wedge_b.map_or(0.0, |wb| wb.deviation(c)));
        if let Some(l) = self.last {
            cost += HOLD_WEIGHT_M_PER_RAD * wrap_angle_rad(bearing - l).abs();
        }
        if !self.a_on_other_half(c, screen) {
            cost += 100.0;
        }
        Some(OtsCandidate {
            bearing_rad: bearing,
            r_m: r,
            side,
            cost,
        })
    }

    /// `r`, or farther along the ray (up to `r_max`) until the camera is `clear_m` from A's
    /// feet; `None` when no such camera is left.
    fn clear_of_a(&self, b: [f64; 2], w: [f64; 2], r: f64, r_max: f64) -> Option<f64> {
        let a = [self.a.position_m[0], self.a.position_m[1]];
        let d = [b[0] - a[0], b[1] - a[1]];
        let at = |r: f64| math::hypot(d[0] + w[0] * r, d[1] + w[1] * r);
        if at(r) >= self.clear_m {
            return Some(r);
        }
        // |d + r w|² = clear²: the far root.
        let bq = d[0] * w[0] + d[1] * w[1];
        let cq = d[0] * d[0] + d[1] * d[1] - self.clear_m * self.clear_m;
        let far = -bq + (bq * bq - cq).max(0.0).sqrt();
        (far <= r_max).then_some(far)
    }

    /// Whether A lands on the other half of the frame from B, inside it, for a level camera
    /// at `c` that puts B at `screen`.
    fn a_on_other_half(&self, c: [f64; 2], screen: [f64; 2]) -> bool {
        let b = self.b_xy();
        let bearing_b = math::atan2(b[1] - c[1], b[0] - c[0]);
        let bearing_a = math::atan2(self.a.position_m[1] - c[1], self.a.position_m[0] - c[0]);
        let sx = self.lens.sx();
        let heading = bearing_b + math::atan(screen[0] / sx);
        let off = wrap_angle_rad(heading - bearing_a);
        let x_a = sx * math::tan(off);
        off.abs() < FRAC_PI_2 && x_a.abs() <= 1.0 && x_a * screen[0] < 0.0
    }

    /// The bearings the search samples: across B's sector, or the whole turn.
    fn range(&self) -> (f64, f64) {
        match &self.wedge_b {
            Some(w) => (w.centre_rad - w.half_rad, w.centre_rad + w.half_rad),
            None => (-PI, PI),
        }
    }

    /// The cheapest camera: sampled, then refined by golden section about the best sample.
    fn best(&self) -> Option<OtsCandidate> {
        let (lo, hi) = self.range();
        let step = (hi - lo) / OTS_SAMPLES as f64;
        let mut best: Option<OtsCandidate> = None;
        let mut keep = |c: Option<OtsCandidate>| {
            if let Some(c) = c {
                if best.is_none_or(|b| c.cost < b.cost) {
                    best = Some(c);
                }
            }
        };
        for i in 0..=OTS_SAMPLES {
            keep(self.along(lo + step * i as f64));
        }
        let found = best?;
        let cost = |x: f64| self.along(x).map_or(f64::INFINITY, |c| c.cost);
        let (mut a, mut b) = (found.bearing_rad - step, found.bearing_rad + step);
        if self.wedge_b.is_some() {
            (a, b) = (a.max(lo), b.min(hi));
        }
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..40 {
            let c = b - g * (b - a);
            let d = a + g * (b - a);
            if cost(c) < cost(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let refined = self.along((a + b) / 2.0);
        Some(match refined {
            Some(r) if r.cost < found.cost => r,
            _ => found,
        })
    }

    /// The visual of the chosen camera: its toric coordinates about the band centres, B's
    /// screen point as asked (the side's third by default), A's where the camera sees it.
    fn visual(&self, best: &OtsCandidate) -> Result<TwoVisual, FramingError> {
        let mut pair = self.pair.clone();
        let b = self.b_xy();
        let screen_b = self.screen_b(best.side);
        let (w0, w1) = (math::cos(best.bearing_rad), math::sin(best.bearing_rad));
        let mb = pair.mb;
        let z = if pair.level {
            mb.z
        } else {
            mb.z + best.r_m * math::tan(pair.e)
        };
        let mut c = Vec3::new(b[0] + w0 * best.r_m, b[1] + w1 * best.r_m, z);
        let asked = self.asked_r(screen_b).unwrap_or(best.r_m);
        pair.screen_b = screen_b;
        if pair.level {
            // The altitude that puts B's band centre at its screen y (place_two's rule).
            let xp = screen_b[0] / self.lens.sx();
            let depth = best.r_m / (1.0 + xp * xp).sqrt();
            c.z = mb.z - screen_b[1] * depth / self.lens.sy();
        }
        let (heading, pitch, _) = aim(self.lens, self.gimbal, &c, &mb, screen_b);
        let camera = crate::camera::CameraPose {
            position_m: c,
            heading_rad: heading,
            pitch_rad: pitch,
        };
        // The foreground actor is asked where the camera sees them, on the other half of the
        // frame from B: a camera that cannot show them there misses it, and says so.
        let other_half = if screen_b[0] >= 0.0 {
            (-1.0, -OTS_FOREGROUND_GAP)
        } else {
            (OTS_FOREGROUND_GAP, 1.0)
        };
        let seen = camera
            .project(self.lens, &pair.ma)
            .unwrap_or([-screen_b[0], 0.0]);
        pair.screen_a = [
            seen[0].clamp(other_half.0, other_half.1),
            seen[1].clamp(-1.0, 1.0),
        ];
        let t = toric::inverse(&pair.ma, &pair.mb, &c).map_err(|_| FramingError::ActorsCoincide)?;
        pair.alpha = t.alpha_rad;
        Ok(TwoVisual {
            distance_ratio: best.r_m / asked,
            ..pair.visual(t, Primary::B, true)
        })
    }
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
        Visual::Two(t) => primary_target(t, actors, lens, c),
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

/// The point a two-actor visual aims exactly from a camera at `c`, and its screen point:
/// the primary's band centre, or for [`Primary::Pair`] the point where the bisector of the
/// angle at `c` between the two band centres meets the line through them (the angle
/// bisector theorem: it divides AB as |CA| to |CB|), at the screen point of the bisector of
/// their two screen points' rays: the angle between the rays is the angle between the
/// actors, so both land on their points when the two split it evenly.
fn primary_target(t: &TwoVisual, actors: &[ActorPose], lens: &Lens, c: &Vec3) -> (Vec3, [f64; 2]) {
    let ma = band_centre(&actors[t.a], t.band_a_m);
    let mb = band_centre(&actors[t.b], t.band_b_m);
    match t.primary {
        Primary::A => (ma, t.screen_a),
        Primary::B => (mb, t.screen_b),
        Primary::Pair => {
            let (da, db) = ((ma - c).norm(), (mb - c).norm());
            let share = if da + db > 0.0 { da / (da + db) } else { 0.5 };
            let ray = lens.ray(t.screen_a).normalize() + lens.ray(t.screen_b).normalize();
            let screen = if ray.y > 0.0 {
                [ray.x * lens.sx() / ray.y, ray.z * lens.sy() / ray.y]
            } else {
                lerp2(t.screen_a, t.screen_b, 0.5)
            };
            (ma + (mb - ma) * share, screen)
        }
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
                Primary::B => (t.b, t.band_b_m, t.screen_b),
                _ => (t.a, t.band_a_m, t.screen_a),
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
        let (target, screen) = primary_target(t, actors, lens, &c);
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
            Primary::Pair => Primary::Pair,
        },
        elevation_rad: t.elevation_rad,
        over_shoulder: t.over_shoulder,
        distance_ratio: t.distance_ratio,
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
