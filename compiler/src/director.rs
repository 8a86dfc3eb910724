//! The director: the one evaluator of a script, stepped tick by tick.
//!
//! `Director::step(t_s, actors)` takes the time on the script's clock and the actors' poses
//! at that time and returns the next reference sample. It knows nothing of where the poses
//! come from: `compile` feeds it the script's blocking (batch), `shoot` feeds it live poses
//! from motion capture (online). Same poses in, same samples out.
//!
//! Each tick:
//! 1. advance the timeline: a shot ends → the next one starts, or, after a cut, a
//!    repositioning flight is inserted (the drone cannot jump) and the shot starts when the
//!    drone is in place — later than written unless the script pinned it, in which case a
//!    flight that does not fit is an error;
//! 2. evaluate the target: the composition solved against the live actors (a hold), the
//!    interpolation of visual parameters between two compositions (a `then` move), a path,
//!    or the repositioning trajectory;
//! 3. steer the camera toward it (`steering`), kept inside the stage and out of the actors'
//!    safety distance, and orient it so that the framing is true at the camera's actual
//!    position;
//! 4. check the sample against the profile (`feasibility`).

use crate::code::CompileCode;
use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::{Composition, Scene, Script, Shot, ShotContent, Transition};
use dronecine_grammar::vocab::Size;
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;

use crate::blocking::{min_jerk, Blocking};
use crate::camera::{orient, orient_fixed_pitch, Lens, Vec3};
use crate::feasibility::{round_up_1, Carried, Monitor};
use crate::framing::{self, FramingError};
use crate::paths::PathPlan;
use crate::reference::{ActorPose, Sample, ShotTiming};
use crate::route::{self, Keepout, Route};
use crate::steering::{self, HeadingState, Kinematics, SteerGains, SteerLimits};
use dronecine_profile::{Gimbal, Profile};

/// How far inside the profile's actor distance a framing's camera may be before
/// `compile::too_close` is told.
const TOO_CLOSE_TOLD_M: f64 = 0.01;

/// Time a repositioning flight leaves for the camera to settle on the first framing.
const SETTLE_S: f64 = 0.5;
/// A repositioning route keeps clear of where walking actors are while it flies, at this
/// many steps of its time…
const PASSING_SAMPLES: usize = 16;
/// …or more, so that no actor moves more than this between two steps…
const PASSING_STEP_M: f64 = 0.3;
/// …up to this many. A route is checked against each passing pose where the flight is then,
/// give or take a step: at 16 steps of a 12 s flight an actor walking at 2.3 m/s moves 1.7 m
/// between two, and one walking the same way behind the drone, faster than it flies, could
/// catch up with it between two checks unseen.
const PASSING_SAMPLES_MAX: usize = 128;

/// Times closer than this are the same time: the end of a shot or a flight is reached at a
/// tick that lands on it up to the rounding of the tick times.
const SAME_TIME_S: f64 = 1e-9;

/// A repositioning flight planned for the actors as they will be at its arrival has settled
/// when it arrives within this of that time (and it fits when it arrives no later than
/// this after it): a few milliseconds move a framing by millimetres.
const ARRIVAL_SETTLED_S: f64 = 0.002;
/// How many times a repositioning flight is planned again for when it arrives before the
/// search for an earlier arrival takes over: enough for an arrival that settles to settle,
/// few enough to leave the search most of [`REPOSITION_PLANS_MAX`].
const REPOSITION_ROUNDS: usize = 6;
/// The most plans of one repositioning flight, rounds and search together: bounds the work
/// of a cut (each plan solves the framing and chooses a route) and leaves the search enough
/// halvings to narrow a minute to [`SEARCH_RESOLUTION_S`].
const REPOSITION_PLANS_MAX: usize = 24;
/// The search for the earliest arrival stops when the latest arrival that does not fit and
/// the earliest that does are this close: finer than the tenth of a second diagnostics tell.
const SEARCH_RESOLUTION_S: f64 = 0.005;
/// A framing that moves no faster than this share of the horizontal speed limit when the
/// flight first planned arrives is one the drone can merge into, flying at the share of its
/// limits it plans at ([`PLANNED_SHARE`]).
const MERGEABLE_SPEED_SHARE: f64 = 0.8;
/// How far past the first plan's arrival the search for an arrival that fits goes, where
/// the framing moves slowly enough to merge into: a little later than planned is better than
/// waiting for the actors to stand.
const SEARCH_PAST_FIRST_S: f64 = 1.0;
/// A flight arriving this close after the shot's pin arrives on it (the rounding of the sum
/// of the flight's times).
const PIN_TOLERANCE_S: f64 = 1e-6;

/// A repositioning flight shorter than this…
const IN_PLACE_M: f64 = 0.03;
/// …that turns less than this…
const IN_PLACE_RAD: f64 = 0.05;
/// …from a camera slower than this takes no time: the camera is already in place, and the
/// steering closes the rest.
const IN_PLACE_MPS: f64 = 0.05;
/// A minimum-jerk flight of length `L` over `T` peaks at this many times `L/T` in speed…
const MIN_JERK_PEAK_SPEED: f64 = 1.875;
/// …and at this many times `L/T²` in acceleration.
const MIN_JERK_PEAK_ACCEL: f64 = 5.77;
/// The shortest repositioning flight: a flight of no length still takes this long, and a turn
/// that takes longer is said to set the flight's time.
const MIN_FLIGHT_S: f64 = 0.5;
/// The share of the profile's limits a repositioning flight is planned at: the rest is left
/// for the steering to follow a framing that moves during the flight.
const PLANNED_SHARE: f64 = 0.8;

/// The share of the profile's vertical speed and yaw-rate limits the reference uses: the rest
/// is left to the servo.
const SERVO_SHARE: f64 = 0.9;
/// The yaw-acceleration limit per rad/s of the profile's yaw-rate limit: the heading reaches
/// its full rate in half a second.
const YAW_ACCEL_PER_S: f64 = 2.0;
/// The separation push's gain (m/s² at half the kept distance from an actor's body): a
/// back-up to the goal kept clear of the bodies, strong enough to move a camera out.
const SEPARATION_GAIN_MPS2: f64 = 3.0;
/// The containment spring's stiffness (m/s² per metre outside the stage less its margin): a
/// back-up to the goal kept inside that box.
const CONTAINMENT_STIFFNESS_PER_S2: f64 = 4.0;

/// A path's target moving slower than this has no direction of travel to look along…
const PATH_MOVING_MPS: f64 = 1e-3;
/// …and the camera looks toward where the path is this much later instead.
const PATH_LOOK_AHEAD_S: f64 = 0.5;

/// A framing told too close is told again with the closest it came when that is this much
/// closer than first told: less is the same distance to two decimals.
const CLOSER_TOLD_M: f64 = 0.005;

/// Time step of the finite differences that give the target's velocity.
const EPS_S: f64 = 1e-3;

/// Time constant of the trend of the target's acceleration, which the steering predicts the
/// camera's velocity against ([`steering::step`]'s `trend_a`), and which it feeds forward
/// against measured actors ([`Director::actors_measured`]; against the blocking, the
/// acceleration as it is). Against live actors the difference of the target's velocity from
/// tick to tick is mostly the motion capture's noise, several times the blocking's own
/// acceleration.
const TREND_TAU_S: f64 = 0.03;

/// How a shot is flown.
#[derive(Clone, Debug)]
enum Plan {
    Hold(Composition),
    Move {
        from: Composition,
        to: Composition,
    },
    Path(PathPlan),
    /// A path not planned yet (it is planned when the drone starts toward it).
    PathPending,
}

/// Where the timeline is.
#[derive(Clone, Debug)]
enum Phase {
    NotStarted,
    Shot {
        index: usize,
        start_s: f64,
        end_s: f64,
    },
    Reposition {
        to: usize,
        start_s: f64,
        end_s: f64,
        /// Time the trajectory reaches the shot's first framing (≤ end).
        arrive_s: f64,
        from: Vec3,
        from_heading_rad: f64,
        route: Route,
    },
    Done,
}

/// The timing of one [`Director::step`].
#[derive(Clone, Copy, Debug)]
struct Tick {
    /// The time the step is given.
    t_s: f64,
    /// The script's clock: `t_s`, held at its start before 0 s.
    clock_s: f64,
    /// The time since the last step (0 on the first).
    dt_s: f64,
    /// The first step.
    first: bool,
    /// The first step of a camera the flight placed ([`Director::start_from`]): it stays
    /// where it was placed, with its heading, and is steered from the next tick.
    keep_placed: bool,
}

/// The evaluator. See the module documentation. A clone steps on as the original would,
/// bit for bit (a flight keeps one to rewind to).
#[derive(Clone)]
pub struct Director {
    shots: Vec<Shot>,
    plans: Vec<Plan>,
    names: Vec<String>,
    lens: Lens,
    gimbal: Gimbal,
    limits: SteerLimits,
    gains: SteerGains,
    /// The stage less the profile's margin: where the director keeps its target.
    stage_lo: Vec3,
    stage_hi: Vec3,
    /// The target of the last step as solved, before it was kept inside the stage.
    raw_target: Vec3,
    /// A framing failed to solve during this step (the target, or its look-ahead).
    failed_now: bool,
    /// The camera has a position: a framing (or a path) has solved at least once, or the
    /// flight said where it starts. Until then the camera is nowhere (a first framing that
    /// does not solve holds it at the origin), so nothing is checked against that position.
    placed: bool,
    /// [`Director::start_from`] placed the camera: the first step keeps it there (and its
    /// heading), and the framing is steered to, not jumped to.
    started_from: bool,
    /// The actor poses are measured (see [`Director::actors_measured`]).
    measured: bool,
    /// The turn the repositioning flight's route went at the last tick (`None` before its
    /// first, or when it does not turn).
    route_turn: Option<f64>,
    safety_m: f64,
    /// The distance kept on set ([`Safety::on_set_m`](dronecine_profile::Safety::on_set_m)).
    on_set_m: f64,
    /// How far the steering keeps the reference from the actors' bodies: `safety_m`, and on
    /// set (see [`Director::actors_measured`]) the tracking margin more. The monitor, the
    /// shots' errors and the routes judge against `safety_m`.
    keep_m: f64,
    profile_name: String,
    phase: Phase,
    state: Kinematics,
    heading: HeadingState,
    pitch_rad: f64,
    /// Last target velocity and heading target, for the acceleration and rate feed-forward.
    last_target: Option<(f64, Vec3, f64)>,
    /// The target's acceleration low-passed ([`TREND_TAU_S`]); `None` until a continuous
    /// target has given one (the first difference after a jump starts it).
    accel_trend: Option<Vec3>,
    last_t_s: f64,
    /// The visual solved for the current tick (reused to orient the camera).
    visual: Option<framing::Visual>,
    timings: Vec<ShotTiming>,
    diagnostics: Vec<Diagnostic>,
    monitor: Monitor,
    warned: Vec<bool>,
    /// By timeline index: `compile::too_close` told, and the closest that framing came
    /// (told at the end).
    closest: Vec<Option<Closest>>,
    /// By timeline index: how far inside an actor's distance the shot's framing starts where
    /// it continues (`then`) a framing already told too close, as the monitor carries a lag
    /// over ([`Carried`]).
    clearance: Vec<Carried>,
    /// Whether each two-actor framing gets its written size (`compile::size_off`).
    sizes: crate::sized::SizeWatch,
    /// Per-tick scratch: the actors extrapolated, and their body axes.
    ahead: Vec<ActorPose>,
    /// The script's blocking: where a repositioning flight will find the actors when it
    /// arrives ([`Director::arriving_into`]).
    blocking: Blocking,
    /// Per-tick scratch of a repositioning flight: the actors as they will stand when it
    /// arrives.
    arriving: Vec<ActorPose>,
    /// Scratch of a repositioning flight's plan: the actors it keeps clear of…
    keep_out: Vec<ActorPose>,
    /// …and where the walking ones are while it flies (`route::Keepout::passing`).
    passing: Vec<(f64, ActorPose)>,
    /// The velocity of the framing a repositioning flight arrives on, as of this tick.
    merge_v: Vec3,
    axes: Vec<steering::Body>,
    /// Per plan, the actors each end's composition names (by index), for the solve memo.
    framed: Vec<[Vec<usize>; 2]>,
    /// Per plan, each end's composition prepared for solving (`None` for paths).
    prepared: Vec<[Option<framing::Prepared>; 2]>,
    /// Per plan, each end's last two-actor solve: the next keeps its root, an
    /// over-the-shoulder's camera or a two-shot's θ ([`framing::Prepared::solve_near`]).
    held: Vec<[Option<framing::TwoVisual>; 2]>,
    /// The last few composition solves (see [`Solved`]), replaced round robin.
    solved: Vec<Solved>,
    /// The boxes of the last tick's blended visual, reused by the next one.
    blend_spare: Option<(Box<framing::Visual>, Box<framing::Visual>)>,
    /// The move being flown (by plan) and the way round its blend went on the last tick
    /// ([`framing::BlendWay`]): the next tick goes on the same way.
    way: Option<(usize, framing::BlendWay)>,
    next_solved: usize,
    /// What else watches the samples ([`Director::watched`]).
    watch: Option<Box<dyn Watch>>,
}

/// The lens a scene is filmed with: its `lens` line, else the profile's camera.
pub fn scene_lens(scene: &Scene, profile: &Profile) -> Lens {
    match scene.lens {
        Some(l) => Lens::new(l.fov_x_rad, l.aspect),
        None => Lens::new(profile.camera.fov_x_rad, profile.camera.aspect),
    }
}

/// What watches a director's samples besides its own monitor (film grammar's continuity
/// checks, `dronecine-film`): told each sample, asked for a shot's findings when the
/// director's are (so `compile` and a flight report them alike). `tick` runs on the flight's
/// per-tick path: it allocates nothing.
pub trait Watch: Send {
    /// One tick: the sample, the actors at its time, and the shot being flown (`None`
    /// during a repositioning flight, and before the script's clock starts).
    fn tick(&mut self, sample: &Sample, actors: &[ActorPose], flying: Option<usize>);
    /// The findings over shot `index`, into `out`.
    fn findings(&self, index: usize, out: &mut Vec<Diagnostic>);
    /// A copy, for a director that is cloned.
    fn clone_box(&self) -> Box<dyn Watch>;
}

impl Clone for Box<dyn Watch> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// How many composition solves the director remembers: a tick solves at most two ends, for
/// the actors now and 1 ms ahead.
const SOLVED_SLOTS: usize = 8;

/// A memoised `framing::solve`: it is a pure function of the composition and of the poses of
/// the actors the composition names (and of the held solve, which for the same poses is the
/// solve itself), so while those actors stand still (and for the 1 ms look-ahead of a still
/// actor, which is the same pose) the solve is reused, bit for bit.
#[derive(Clone)]
struct Solved {
    plan: usize,
    end: usize,
    actor_count: usize,
    /// The named actors' poses, compared bit for bit.
    poses: Vec<ActorPose>,
    result: Result<framing::Visual, FramingError>,
}

impl Director {
    /// A director for a script with a scene. Diagnostics found while planning are kept and
    /// returned by [`Director::finish`].
    pub fn new(script: &Script, scene: &Scene, profile: &Profile) -> Director {
        let lens = scene_lens(scene, profile);
        let lim = &profile.limits;
        let limits = SteerLimits {
            // The reference leaves a margin under the vertical speed and yaw-rate limits for
            // the servo ([`SERVO_SHARE`]).
            speed_h_mps: lim.speed_max_mps,
            speed_v_mps: lim.vz_max_mps * SERVO_SHARE,
            accel_h_mps2: lim.accel_max_mps2,
            accel_v_mps2: lim
                .accel_max_mps2
                .min(lim.vz_max_mps / profile.model.tau_vz_s),
            jerk_mps3: lim.jerk_max_mps3,
            yaw_rate_radps: lim.yaw_rate_max_radps * SERVO_SHARE,
            yaw_accel_radps2: lim.yaw_rate_max_radps * YAW_ACCEL_PER_S,
        };
        let mut plans = Vec::with_capacity(script.timeline.len());
        let mut last_comp: Option<&Composition> = None;
        for (i, shot) in script.timeline.iter().enumerate() {
            let plan = match &shot.content {
                ShotContent::Composition(c) if script.moves_camera(i) => match last_comp {
                    Some(from) => Plan::Move {
                        from: from.clone(),
                        to: c.clone(),
                    },
                    None => Plan::Hold(c.clone()),
                },
                ShotContent::Composition(c) => Plan::Hold(c.clone()),
                ShotContent::Path(_) => Plan::PathPending,
                // A script the compiler did not expand (`crate::coverage::expand`): its
                // establishing two-shot, held.
                ShotContent::Coverage(c) => Plan::Hold(c.unexpanded()),
            };
            last_comp = match &shot.content {
                ShotContent::Composition(c) => Some(c),
                ShotContent::Path(_) | ShotContent::Coverage(_) => None,
            };
            plans.push(plan);
        }
        let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
        let framed_by = |c: &Composition| -> Vec<usize> {
            c.actors()
                .filter_map(|n| names.iter().position(|x| x == n))
                .collect()
        };
        let framed = plans
            .iter()
            .map(|plan| match plan {
                Plan::Hold(c) => [framed_by(c), Vec::new()],
                Plan::Move { from, to } => [framed_by(from), framed_by(to)],
                _ => [Vec::new(), Vec::new()],
            })
            .collect();
        // Film grammar's established side of the line, for the framings that leave it free.
        let sides = crate::line::established_sides(script, scene, &lens, &profile.camera.gimbal);
        let prepare = |c: &Composition, side: Option<framing::Side>| {
            Some(framing::Prepared::new(c, &names, &lens).on_side(side))
        };
        let side = |i: usize| sides.get(i).copied().flatten();
        let prepared = plans
            .iter()
            .enumerate()
            .map(|(i, plan)| match plan {
                Plan::Hold(c) => [prepare(c, side(i)), None],
                // A move starts from the framing of the shot before it.
                Plan::Move { from, to } => [
                    prepare(from, i.checked_sub(1).and_then(side)),
                    prepare(to, side(i)),
                ],
                _ => [None, None],
            })
            .collect();
        let held = vec![[None; 2]; plans.len()];
        let (stage_lo, stage_hi) =
            route::stage_less_margin(&scene.stage, profile.safety.stage_margin_m);
        Director {
            shots: script.timeline.clone(),
            plans,
            names,
            lens,
            gimbal: profile.camera.gimbal,
            limits,
            gains: SteerGains::default(),
            stage_lo,
            stage_hi,
            raw_target: Vec3::zeros(),
            failed_now: false,
            placed: false,
            started_from: false,
            measured: false,
            route_turn: None,
            safety_m: profile.safety.actor_distance_m,
            on_set_m: profile.safety.on_set_m(),
            keep_m: profile.safety.actor_distance_m,
            profile_name: profile.name.clone(),
            phase: Phase::NotStarted,
            state: Kinematics::default(),
            heading: HeadingState::default(),
            pitch_rad: 0.0,
            last_target: None,
            accel_trend: None,
            last_t_s: 0.0,
            visual: None,
            timings: Vec::with_capacity(script.timeline.len()),
            diagnostics: Vec::new(),
            monitor: Monitor::new(profile, scene, script.timeline.len()),
            warned: vec![false; script.timeline.len()],
            closest: vec![None; script.timeline.len()],
            clearance: vec![Carried::default(); script.timeline.len()],
            sizes: crate::sized::SizeWatch::new(script.timeline.len()),
            ahead: Vec::with_capacity(scene.actors.len()),
            blocking: Blocking::new(scene),
            arriving: Vec::with_capacity(scene.actors.len()),
            keep_out: Vec::with_capacity(2 * scene.actors.len()),
            passing: Vec::with_capacity(PASSING_SAMPLES_MAX * scene.actors.len()),
            merge_v: Vec3::zeros(),
            axes: Vec::with_capacity(scene.actors.len()),
            held,
            framed,
            prepared,
            solved: Vec::with_capacity(SOLVED_SLOTS),
            blend_spare: None,
            way: None,
            next_solved: 0,
            watch: None,
        }
    }

    pub fn lens(&self) -> &Lens {
        &self.lens
    }

    /// The diagnostics of planning and flying so far, in the order they arose (repositioning
    /// flights, framings that cannot be solved or come too close), without the monitor's
    /// limit checks, which [`Director::finish`] adds. `shoot` tells each as it arises.
    pub fn diagnostics_so_far(&self) -> &[Diagnostic] {
        &self.diagnostics
    }

    /// Whether the last shot has ended.
    pub fn finished(&self) -> bool {
        matches!(self.phase, Phase::Done)
    }

    /// The timeline as flown so far.
    pub fn timings(&self) -> &[ShotTiming] {
        &self.timings
    }

    /// Where the shots' clock `t_s` (as [`Director::step`] is given it) falls on the script's
    /// clock as written: a repositioning flight inserted before a shot holds it at the shot's
    /// start, so that it runs from 0 to the script's written end whatever the flights
    /// inserted (a progress display's position).
    pub fn written_t_s(&self, t_s: f64) -> f64 {
        match self.timings.last() {
            Some(x) => {
                x.script_start_s + (t_s - x.start_s).clamp(0.0, (x.end_s - x.start_s).max(0.0))
            }
            None => 0.0,
        }
    }

    /// Where the camera is, how it moves, and its heading, before the first step (the flight:
    /// where the approach's glide left the drone, which is a real position: the camera is
    /// placed). The camera steers from there to the first framing instead of starting on it
    /// (the flight steps it before 0 s to settle, [`Director::step`]): against live actors
    /// the framing has moved since the approach was planned, and starting on it would make
    /// the reference jump at "action!". A first framing that does not solve holds it there,
    /// instead of at the origin. No effect once stepped.
    pub fn start_from(&mut self, position_m: Vec3, velocity_mps: Vec3, heading_rad: f64) {
        if matches!(self.phase, Phase::NotStarted) {
            self.state = Kinematics {
                p: position_m,
                v: velocity_mps,
                a: Vec3::zeros(),
            };
            self.heading = HeadingState {
                heading_rad,
                rate_radps: 0.0,
            };
            self.placed = true;
            self.started_from = true;
        }
    }

    /// The actor poses it will be stepped with are measured (a motion capture's, tracked), not
    /// the script's blocking: the target's acceleration, mostly their noise differentiated, is
    /// fed forward as its trend (low-passed over 30 ms) instead of as it is (a path's, which is
    /// the path's own, as it is). On set the acceleration of a framing that follows an actor
    /// swings by metres a second squared from one tick to the next (a close framing swings
    /// with the actor's facing, whose rate is the noise of the measured heading
    /// differentiated); fed forward as it is, the steering would clip it to the drone's
    /// limits, and the clipping would carry the reference off its target, into an actor's
    /// safety distance. Against the blocking the acceleration is exact, and fed forward as it
    /// is (`compile` does not call this).
    ///
    /// The steering also keeps the profile's tracking margin more from the actors than their
    /// safety distance: it is the drone that must keep that distance, and it flies a few
    /// centimetres off its reference. A compiled reference is a perfect drone's: no margin.
    pub fn actors_measured(&mut self) {
        self.measured = true;
        self.keep_m = self.on_set_m;
        self.monitor.actors_measured();
    }

    /// What the monitor found over shot `index` (its flight there included) that is not told
    /// already: for a flight to tell when the shot is over, as `compile` tells them all at
    /// the end ([`Director::finish`]). A framing told too close is not told again as the
    /// camera coming near the actor.
    pub fn shot_findings(&self, index: usize) -> Vec<Diagnostic> {
        let mut out = Vec::new();
        self.findings_into(index, &mut out);
        out
    }

    /// [`Director::shot_findings`] of shot `index`, into `out`.
    fn findings_into(&self, index: usize, out: &mut Vec<Diagnostic>) {
        let from = out.len();
        let held_off = |k: usize| self.closest.get(k).is_some_and(Option::is_some);
        self.monitor
            .shot_diagnostics(index, &self.shots, &self.timings, held_off, out);
        let span = self.shots.get(index).map(|s| s.span);
        let told_close = (self.diagnostics.iter())
            .any(|t| t.code == CompileCode::TooClose && Some(t.span) == span);
        // (The monitor tells the camera near an actor once a shot at most.)
        let near = out[from..]
            .iter()
            .position(|d| d.code == CompileCode::TooClose);
        if let (true, Some(k)) = (told_close, near) {
            out.remove(from + k);
        }
        if let Some(w) = &self.watch {
            w.findings(index, out);
        }
        if let (Some(span), Some(Plan::Hold(comp) | Plan::Move { to: comp, .. })) =
            (span, self.plans.get(index))
        {
            let (names, lens, gimbal) = (&self.names, &self.lens, &self.gimbal);
            let stage = (&self.stage_lo, &self.stage_hi);
            out.extend((self.sizes).diagnostic(index, span, comp, names, lens, gimbal, stage));
        }
    }

    /// Whether the camera has a position: some step's framing (or path) has solved, or
    /// [`Director::start_from`] said where it is. A first framing that does not solve leaves
    /// it unplaced, its samples at the origin. The flight's pre-flight check refuses to take
    /// off for such a framing.
    pub fn placed(&self) -> bool {
        self.placed
    }

    /// Where the last [`Director::step`]'s target is as solved: its reference is kept inside
    /// the stage less its margin, this is not (the flight's pre-flight check refuses a first
    /// framing outside the stage with it).
    pub fn solved_target_m(&self) -> Vec3 {
        self.raw_target
    }

    /// The visual held at the last [`Director::step`]: in a hold, once its first
    /// `SETTLE_S` are past; `None` during a move, a path, a repositioning flight or a
    /// settle.
    fn held_visual(&self) -> Option<&framing::Visual> {
        let Phase::Shot { index, start_s, .. } = self.phase else {
            return None;
        };
        if !matches!(self.plans.get(index), Some(Plan::Hold(_)))
            || self.last_t_s < start_s + SETTLE_S
        {
            return None;
        }
        self.visual.as_ref()
    }

    /// The framing held at the last [`Director::step`] with the lens and gimbal that aim it
    /// ([`Held`]), or `None` outside holds (as [`Director::hold_targets`]). Owned, and
    /// allocating nothing (a hold's visual is one or two actors', never a blend): a flight
    /// that steps the director on another thread sends it back each tick.
    pub fn held(&self) -> Option<Held> {
        let v = self.held_visual()?;
        (!matches!(v, framing::Visual::Blend { .. })).then(|| Held {
            visual: v.clone(),
            lens: self.lens,
            gimbal: self.gimbal,
        })
    }

    /// The framing held at the last [`Director::step`]: each framed actor's aim point and the
    /// screen point the script puts it at, for a camera at `camera_m` (cleared and filled
    /// into `out`, allocating nothing once it has room for two). Returns false, with `out`
    /// empty, outside holds: during a move, a path, a repositioning flight, or the first
    /// `SETTLE_S` of a shot. `compile` measures its framing with it (a flight with
    /// [`Held::targets_into`], the same targets).
    pub fn hold_targets(
        &self,
        actors: &[ActorPose],
        camera_m: &Vec3,
        out: &mut Vec<framing::ScreenTarget>,
    ) -> bool {
        out.clear();
        match self.held_visual() {
            Some(v) => hold_targets(v, &self.lens, &self.gimbal, actors, camera_m, out),
            None => false,
        }
    }

    /// Whether a path shot is being flown (its target is the path's, not a framing's).
    fn on_path(&self) -> bool {
        matches!(self.phase, Phase::Shot { index, .. }
            if matches!(self.plans.get(index), Some(Plan::Path(_))))
    }

    /// The visual of a one-actor hold being flown this tick, if that is what it is.
    fn held_one_actor(&self) -> Option<&framing::Visual> {
        let Phase::Shot { index, .. } = self.phase else {
            return None;
        };
        match (self.plans.get(index), &self.visual) {
            (Some(Plan::Hold(_)), Some(v @ framing::Visual::One(_))) => Some(v),
            _ => None,
        }
    }

    /// Index of the shot being flown (or flown to), for the sample's `shot` field.
    fn shot_index(&self) -> usize {
        match self.phase {
            Phase::Shot { index, .. } => index,
            Phase::Reposition { to, .. } => to,
            Phase::NotStarted => 0,
            Phase::Done => self.shots.len().saturating_sub(1),
        }
    }

    fn actor_index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// One tick: the sample at `t_s` given the actors' poses at `t_s` (one per actor of the
    /// scene, in declaration order).
    ///
    /// Before 0 s the script's clock is held at its start: the camera, placed by
    /// [`Director::start_from`], steers to the first framing as the actors stand, which a
    /// flight does while the drone settles before "action!" (`compile` starts at 0 s).
    pub fn step(&mut self, t_s: f64, actors: &[ActorPose]) -> Sample {
        let tick = self.start_tick(t_s, actors);
        let (target, v_t) = self.target_and_velocity(tick.clock_s, actors);
        let (a_t, trend) = self.target_acceleration(t_s, v_t);
        let goal = self.goal(target, v_t, a_t, trend, actors);
        self.steer_position(&tick, &goal, v_t, &trend);
        let heading_target = self.steer_orientation(&tick, actors);
        self.last_target = (!self.failed_now).then_some((t_s, v_t, heading_target));
        self.last_t_s = t_s;
        let sample = self.sample_and_record(t_s, &goal, actors);
        if let Some(w) = self.watch.as_mut() {
            let flying = match self.phase {
                Phase::Shot { index, .. } if t_s >= 0.0 => Some(index),
                _ => None,
            };
            w.tick(&sample, actors, flying);
        }
        sample
    }

    /// The director with `watch` told every sample and asked for each shot's findings
    /// ([`Watch`]).
    pub fn watched(mut self, watch: Box<dyn Watch>) -> Director {
        self.watch = Some(watch);
        self
    }

    /// Starts the timeline on the first step and advances it to `t_s`: the tick's timing.
    fn start_tick(&mut self, t_s: f64, actors: &[ActorPose]) -> Tick {
        let clock_s = t_s.max(0.0);
        let first = matches!(self.phase, Phase::NotStarted);
        if first {
            if self.shots.is_empty() {
                // Nothing to direct: done at once, the camera where it is. (`compile` and
                // the flight refuse such a script before it comes here.)
                self.phase = Phase::Done;
            } else {
                self.begin_shot(0, 0.0, actors);
            }
        }
        let dt = if first { 0.0 } else { t_s - self.last_t_s };
        // The first step of a camera the flight placed: it stays where it was placed, with
        // its heading, and is steered from the next tick.
        let keep_placed = first && self.started_from;
        let continuous = self.advance(clock_s, actors);
        if !continuous {
            self.last_target = None;
        }
        Tick {
            t_s,
            clock_s,
            dt_s: dt,
            first,
            keep_placed,
        }
    }

    /// The target at `clock_s` and its velocity (a forward difference with the actors
    /// extrapolated); no velocity where a framing did not solve, now or a moment ahead.
    fn target_and_velocity(&mut self, clock_s: f64, actors: &[ActorPose]) -> (Vec3, Vec3) {
        // A blend's two boxes are kept for the next tick's blend (no allocation per tick).
        if let Some(framing::Visual::Blend { from, to, .. }) = self.visual.take() {
            self.blend_spare = Some((from, to));
        }
        self.failed_now = false;
        let target = self.target(clock_s, actors, true);
        let v_t = match self.held_one_actor() {
            // A one-actor hold moves rigidly with its actor: the exact velocity, no second
            // solve.
            Some(v) => framing::velocity_mps(v, actors, &self.lens, &self.gimbal),
            None => {
                // Reused buffers: the sampling loop allocates nothing per tick.
                let mut ahead = std::mem::take(&mut self.ahead);
                ahead.clear();
                ahead.extend(actors.iter().map(|a| extrapolate(a, EPS_S)));
                let target_ahead = if self.hold_stands_still(actors, &ahead) {
                    // The same solve against the same poses: the same target, bit for bit.
                    target
                } else {
                    self.target(clock_s + EPS_S, &ahead, false)
                };
                self.ahead = ahead;
                (target_ahead - target) / EPS_S
            }
        };
        // A framing that did not solve, now or a moment ahead, holds the camera: no
        // feed-forward (its look-ahead difference would be the jump between where the camera
        // is and a framing solved a millisecond later, hundreds of metres a second, enough to
        // carry the reference through the stage's wall). Nor on the tick after, whose
        // difference would start from the hold.
        let v_t = if self.failed_now { Vec3::zeros() } else { v_t };
        (target, v_t)
    }

    /// The target's acceleration at `t_s` from its velocity `v_t` (fed forward), and that
    /// low-passed (its trend, which the camera's velocity is predicted against).
    fn target_acceleration(&mut self, t_s: f64, v_t: Vec3) -> (Vec3, Vec3) {
        match self.last_target {
            Some((t0, v0, _)) if t_s > t0 && !self.failed_now => {
                let a_t = (v_t - v0) / (t_s - t0);
                let trend = match self.accel_trend {
                    Some(a) => a + (a_t - a) * ((t_s - t0) / (TREND_TAU_S + t_s - t0)),
                    None => a_t,
                };
                self.accel_trend = Some(trend);
                (a_t, trend)
            }
            _ => {
                self.accel_trend = None;
                (Vec3::zeros(), Vec3::zeros())
            }
        }
    }

    /// The goal the camera is steered to: the target as solved, kept inside the stage less
    /// its margin and out of the actors' safety distance.
    fn goal(
        &mut self,
        target: Vec3,
        v_t: Vec3,
        a_t: Vec3,
        trend: Vec3,
        actors: &[ActorPose],
    ) -> Kinematics {
        // The target is kept inside the stage less its margin: containment's spring alone
        // would let a framing near a wall (or a solve that jumps there, or beyond, against
        // live actors) take the reference to the wall, where a few centimetres of tracking
        // error land the drone (the stage failsafe). The monitor sees the target as solved:
        // a framing beyond the stage is still compile's error, and the pre-flight check's.
        // Nor does the target come inside an actor's safety distance: a framing that would
        // put the camera there (a live actor walking into it, a path or route grazing) is
        // held at that distance, on the line from the actor's body to the framing, until the
        // framing clears. The monitor and the shot's error still see the framing as solved.
        self.raw_target = target;
        let goal = Kinematics {
            p: target,
            v: v_t,
            a: if self.measured && !self.on_path() {
                trend
            } else {
                a_t
            },
        };
        self.axes.clear();
        self.axes.extend(actors.iter().map(steering::Body::from));
        let bodies = steering::Bodies {
            axes: &self.axes,
            clear_m: self.keep_m,
        };
        let (lo, hi) = (&self.stage_lo, &self.stage_hi);
        contained(
            steering::kept_clear(contained(goal, lo, hi), bodies),
            lo,
            hi,
        )
    }

    /// Moves the camera toward `goal` over the tick (its velocity `v_t` as the target's,
    /// `trend` the trend of its acceleration), or puts it on the goal where the tick starts
    /// the camera framed.
    fn steer_position(&mut self, tick: &Tick, goal: &Kinematics, v_t: Vec3, trend: &Vec3) {
        let target = goal.p;
        if tick.keep_placed {
            // Where the flight placed it, moving as it did: steered from the next tick.
        } else if tick.first || tick.dt_s <= 0.0 || !self.placed {
            // The first shot starts framed: on its target, moving with it (never faster than
            // the camera may fly: live actors' velocities are estimates). So does a first
            // framing that solves only after a few ticks: the camera was never anywhere else.
            self.state = Kinematics {
                p: target,
                v: steering::truncate_hv(v_t, self.limits.speed_h_mps, self.limits.speed_v_mps),
                a: Vec3::zeros(),
            };
        } else {
            // A tick longer than the steering's step is steered in sub-steps toward the goal
            // as it moved during the tick, so the camera is the same at any rate.
            let bodies = steering::Bodies {
                axes: &self.axes,
                clear_m: self.keep_m,
            };
            let (axes, safety_m) = (&self.axes, self.keep_m);
            let (lo, hi) = (&self.stage_lo, &self.stage_hi);
            self.state = steering::advance(
                &self.state,
                goal,
                trend,
                |p| {
                    steering::separation(p, axes, safety_m, SEPARATION_GAIN_MPS2)
                        + steering::containment(p, lo, hi, CONTAINMENT_STIFFNESS_PER_S2)
                },
                (lo, hi),
                bodies,
                &self.limits,
                &self.gains,
                tick.dt_s,
            );
        }
    }

    /// Turns the camera toward the heading and pitch that frame the shot from the camera's
    /// actual position; returns the heading it turns toward.
    fn steer_orientation(&mut self, tick: &Tick, actors: &[ActorPose]) -> f64 {
        let t_s = tick.t_s;
        let (heading_target, pitch_target) = self.look(tick.clock_s, actors, &self.state.p.clone());
        let heading_rate_target = match self.last_target {
            Some((t0, _, h0)) if t_s > t0 => wrap_angle_rad(heading_target - h0) / (t_s - t0),
            _ => 0.0,
        };
        if tick.keep_placed {
            // With the heading the flight placed it at.
        } else if tick.first || tick.dt_s <= 0.0 {
            self.heading = HeadingState {
                heading_rad: heading_target,
                rate_radps: 0.0,
            };
        } else {
            self.heading = steering::advance_heading(
                &self.heading,
                heading_target,
                heading_rate_target,
                &self.limits,
                &self.gains,
                tick.dt_s,
            );
        }
        self.pitch_rad = match self.gimbal {
            // A gimbal turns the camera at its rate: the pitch goes toward the one that
            // frames the shot no faster.
            Gimbal::Pitch { rate_radps, .. }
                if !tick.first && tick.dt_s > 0.0 && self.pitch_rad.is_finite() =>
            {
                let most = rate_radps * tick.dt_s;
                self.pitch_rad + (pitch_target - self.pitch_rad).clamp(-most, most)
            }
            _ => pitch_target,
        };
        heading_target
    }

    /// The sample at `t_s`, recorded by the monitor (with the `goal` it was steered to) once
    /// the camera is placed.
    fn sample_and_record(&mut self, t_s: f64, goal: &Kinematics, actors: &[ActorPose]) -> Sample {
        let sample = Sample {
            t_s,
            position_m: self.state.p.into(),
            velocity_mps: self.state.v.into(),
            acceleration_mps2: self.state.a.into(),
            heading_rad: self.heading.heading_rad,
            heading_rate_radps: self.heading.rate_radps,
            camera_pitch_rad: self.pitch_rad,
            shot: self.shot_index(),
        };
        // (After the last shot, the target is where the camera is: no placing.)
        self.placed |= !self.failed_now && !matches!(self.phase, Phase::Done);
        if self.placed {
            let in_shot = matches!(self.phase, Phase::Shot { .. });
            self.monitor
                .record(&sample, goal, &self.raw_target, actors, in_shot);
        }
        sample
    }

    /// Whether the target 1 ms ahead is the target now: in a hold (which depends on the
    /// poses of the actors it frames, not on the time) whose framed actors extrapolate to
    /// their own poses, bit for bit (they stand still).
    fn hold_stands_still(&self, actors: &[ActorPose], ahead: &[ActorPose]) -> bool {
        let Phase::Shot { index, .. } = self.phase else {
            return false;
        };
        matches!(self.plans.get(index), Some(Plan::Hold(_)))
            && self.framed[index][0].iter().all(
                |&i| matches!((actors.get(i), ahead.get(i)), (Some(a), Some(b)) if a.same_bits(b)),
            )
    }

    /// Advance the phase to `t_s`. Returns false when the target jumps (a new segment that
    /// does not continue the previous one), so the feed-forward history is dropped.
    fn advance(&mut self, t_s: f64, actors: &[ActorPose]) -> bool {
        let mut continuous = true;
        loop {
            match self.phase.clone() {
                Phase::Shot { index, end_s, .. } if t_s >= end_s - SAME_TIME_S => {
                    if let Some(last) = self.timings.last_mut() {
                        last.end_s = end_s;
                    }
                    let next = index + 1;
                    if next >= self.shots.len() {
                        // The last sample sits exactly on the end; the one after is done.
                        if t_s > end_s + SAME_TIME_S {
                            self.phase = Phase::Done;
                        }
                        return continuous;
                    }
                    let is_move = matches!(self.shots[next].transition, Transition::Move { .. });
                    if is_move && !self.shots[next].pinned {
                        self.begin_shot(next, end_s, actors);
                    } else {
                        self.begin_reposition(next, end_s, t_s, actors);
                        continuous = false;
                    }
                }
                Phase::Reposition { to, end_s, .. } if t_s >= end_s - SAME_TIME_S => {
                    self.begin_shot(to, end_s, actors);
                    continuous = false;
                }
                _ => return continuous,
            }
        }
    }

    fn begin_shot(&mut self, index: usize, start_s: f64, actors: &[ActorPose]) {
        let duration = self.shots[index].end_s - self.shots[index].start_s;
        if matches!(self.plans[index], Plan::PathPending) {
            // The camera's position when the path starts (the origin before the first tick).
            self.begin_shot_plan_only(index, actors);
        }
        // A shot that continues the one before (`then`) starts from the two-actor solve that
        // one ended on: a fresh solve could take the other root (the one nearest the symmetric
        // θ, or the other camera of an over-the-shoulder) while the held one had kept its
        // own, and the framing would step at the boundary.
        let continues = matches!(self.shots[index].transition, Transition::Move { .. });
        if continues && index > 0 && self.held[index][0].is_none() {
            let last_end = match self.plans[index - 1] {
                Plan::Move { .. } => 1,
                _ => 0,
            };
            self.held[index][0] = self.held[index - 1][last_end];
        }
        let reposition = match self.phase {
            Phase::Reposition { start_s, end_s, .. } => Some((start_s, end_s)),
            _ => None,
        };
        self.timings.push(ShotTiming {
            index,
            script_start_s: self.shots[index].start_s,
            start_s,
            end_s: start_s + duration,
            reposition,
        });
        self.phase = Phase::Shot {
            index,
            start_s,
            end_s: start_s + duration,
        };
    }

    /// Plan the flight from where the camera is to shot `to`'s first framing.
    ///
    /// That framing is where the actors will be when the drone arrives, and when it arrives
    /// depends on how far it flies. The flight is planned to the framing with the actors as
    /// they stand now, then again to where the blocking will have taken them by the time that
    /// flight arrives, until the arrival settles (to 2 ms; halfway steps after the first
    /// round, as an actor walking toward where the drone comes from shortens the flight the
    /// later it arrives). Where it does not settle, the earliest arrival the drone can make
    /// is searched among those planned, the ends of the actors' movements, and halfway between
    /// one that does not fit and one that does: at most a second past the first plan's
    /// arrival while the framing then moves slower than the drone can merge into it (else
    /// the flight arrives then, as soon as the drone can fly that way at its full limits, or
    /// as planned when that way is another, round an actor who walks across the first one,
    /// and then the search goes as far as that arrival: waiting for the actor to pass can be
    /// sooner), without a bound where it sweeps by faster (an actor turning round at the
    /// size's distance). A flight that arrives while the framing moves merges into it
    /// ([`route::merge_m_per_mps`]).
    ///
    /// Planned to the actors as they stand when it sets off, a flight during which an actor
    /// walks or turns would arrive where the framing was, and the shot would start off it, by
    /// metres.
    ///
    /// `actors` are the poses at `actors_s` (the tick's time, at or after `now_s`).
    fn begin_reposition(&mut self, to: usize, now_s: f64, actors_s: f64, actors: &[ActorPose]) {
        if matches!(self.plans[to], Plan::PathPending) {
            self.begin_shot_plan_only(to, actors);
        }
        let arrival = {
            let shot = &self.shots[to];
            Arrival {
                now_s,
                written_s: if shot.pinned { shot.start_s } else { now_s },
                pinned: shot.pinned,
            }
        };
        let flight = self.search_arrival(to, actors_s, actors, &arrival);
        let RepositionFlight {
            route,
            needed,
            needed_full,
            flown,
            ..
        } = flight;
        let from = self.state.p;
        let needed = arrival.needed_for_pin(needed, needed_full);
        let arrive = now_s + needed;
        let end = self.reposition_end_s(to, &arrival, needed, needed_full, &flown);
        if end <= now_s + SAME_TIME_S {
            self.begin_shot(to, now_s, actors);
            return;
        }
        if !arrival.pinned && needed > 0.0 {
            self.tell_reposition(to, needed, end, &flown);
        }
        self.route_turn = None;
        self.phase = Phase::Reposition {
            to,
            start_s: now_s,
            end_s: end,
            arrive_s: (arrive - SETTLE_S).max(now_s).min(end),
            from,
            from_heading_rad: self.heading.heading_rad,
            route,
        };
    }

    /// The repositioning flight to shot `to` (see [`Director::begin_reposition`]): planned
    /// again for when it arrives until the arrival settles, else the earliest arrival that
    /// fits found by the search.
    fn search_arrival(
        &mut self,
        to: usize,
        actors_s: f64,
        actors: &[ActorPose],
        arrival: &Arrival,
    ) -> RepositionFlight {
        let now_s = arrival.now_s;
        let flight = self.plan_reposition(to, now_s, actors_s, now_s, actors);
        let mut search = ArrivalSearch {
            first: flight.clone(),
            flight,
            best: None,
            short_s: now_s,
            round: 0,
            after_s: now_s,
            searching: false,
            on_time: None,
            limit_s: f64::INFINITY,
        };
        for _ in 0..REPOSITION_PLANS_MAX {
            if arrival.settled(&search.flight) && !search.searching {
                break;
            }
            if search.round >= REPOSITION_ROUNDS && !search.searching && search.on_time.is_none() {
                if let Some((on_time, limit_s)) =
                    self.on_time_flight(to, actors_s, actors, arrival, &search.first)
                {
                    search.on_time = Some(on_time);
                    search.limit_s = limit_s;
                }
            }
            search.record(arrival);
            match self.next_arrival(to, actors_s, actors, arrival, &mut search) {
                NextArrival::Plan(at_s) => {
                    search.flight = self.plan_reposition(to, now_s, actors_s, at_s, actors);
                }
                NextArrival::Take(there) => search.flight = there,
                NextArrival::Stop => break,
            }
        }
        search.into_flight(arrival)
    }

    /// When the rounds did not settle: where the framing moves no faster than the drone can
    /// merge into it when the flight first planned (`first`) arrives, the flight that
    /// arrives then, to where the framing will be (it may start the shot a little behind,
    /// where the actors took the framing further than the flight was planned for), and how
    /// late the search may go (a second past that arrival, or as late as a flight another
    /// way arrives); `None` where the framing moves faster.
    fn on_time_flight(
        &mut self,
        to: usize,
        actors_s: f64,
        actors: &[ActorPose],
        arrival: &Arrival,
        first: &RepositionFlight,
    ) -> Option<(RepositionFlight, f64)> {
        // Unbounded, the search would wait for the actors to stand, and a shot after an
        // actor's walk would start seconds later than needed, past a pin that follows it.
        let a0 = arrival.at_s(first.needed);
        let plan = self.plan_reposition(to, arrival.now_s, actors_s, a0, actors);
        if plan.goal_speed_mps <= MERGEABLE_SPEED_SHARE * self.limits.speed_h_mps {
            let mut limit_s = a0 + SEARCH_PAST_FIRST_S;
            // In the first plan's time, the goal where the framing will be then; but another
            // way (round an actor who walks across the first plan's way then) takes the time
            // it needs: a way several times as long, flown in the first plan's time, would
            // ask more speed than the drone has.
            let needed = if plan.way == first.way {
                plan.needed.min(first.needed).max(plan.needed_full)
            } else {
                // That way arrives later: any flight that arrives before it is looked for
                // (waiting for the actor to pass, the short way).
                limit_s = limit_s.max(arrival.at_s(plan.needed));
                plan.needed
            };
            Some((RepositionFlight { needed, ..plan }, limit_s))
        } else {
            None
        }
    }

    /// The next arrival the search plans for: again for when the last flight arrives (the
    /// rounds), halfway between the latest that does not fit and the earliest that does, or
    /// when an actor's movement ends; or a flight found that fits, or the end of the search.
    fn next_arrival(
        &mut self,
        to: usize,
        actors_s: f64,
        actors: &[ActorPose],
        arrival: &Arrival,
        search: &mut ArrivalSearch,
    ) -> NextArrival {
        if search.round < REPOSITION_ROUNDS && !search.searching {
            // Planned again for when it arrives; halfway after the first round (an actor
            // walking toward where the drone comes from shortens the flight the later it
            // arrives, and the rounds would swing).
            search.round += 1;
            let next = arrival.at_s(search.flight.needed);
            NextArrival::Plan(if search.round == 1 {
                next
            } else {
                (search.flight.at_s + next) / 2.0
            })
        } else if let Some(b) = &search.best {
            // Between the latest that does not fit and the earliest that does.
            search.searching = true;
            if b.at_s - search.short_s < SEARCH_RESOLUTION_S {
                return NextArrival::Stop;
            }
            NextArrival::Plan((search.short_s + b.at_s) / 2.0)
        } else if let Some(end_s) = self
            .blocking
            .next_movement_end_after(search.after_s)
            .filter(|&e| e <= search.limit_s)
        {
            // The framing sweeps by faster than the drone can meet it (an actor turning
            // round at the size's distance): the drone arrives when a movement ends, or
            // later while the actors stand as they do then, and the earliest such arrival
            // is looked for.
            search.searching = true;
            search.after_s = end_s;
            let there = self.plan_reposition(to, arrival.now_s, actors_s, end_s, actors);
            if arrival.fits(&there) {
                return NextArrival::Take(there);
            }
            NextArrival::Plan(arrival.at_s(there.needed))
        } else {
            NextArrival::Stop
        }
    }

    /// When a repositioning flight to shot `to` that takes `needed` s (`needed_full` at the
    /// profile's full limits) ends: when it arrives, or at the shot's pin; a flight that
    /// cannot make its pin even at the full limits is an error, and arrives when it can.
    fn reposition_end_s(
        &mut self,
        to: usize,
        arrival: &Arrival,
        needed: f64,
        needed_full: f64,
        flown: &Flown,
    ) -> f64 {
        let (now_s, written) = (arrival.now_s, arrival.written_s);
        let shot = &self.shots[to];
        let arrive = now_s + needed;
        if arrival.pinned {
            if arrive > written + PIN_TOLERANCE_S {
                // Late even at the full limits: by how much, and the pin that it would make.
                let soonest = now_s + needed_full;
                let late = soonest - written;
                self.diagnostics.push(
                    Diagnostic::error(
                        CompileCode::CutTooShort,
                        shot.span,
                        format!(
                            "the drone needs {needed:.1} s to fly to this shot's first framing \
                             ({flown}; {needed_full:.1} s at its full limits), but the shot is \
                             pinned to start at {:.1} s, {:.1} s after the previous shot ends",
                            written,
                            (written - now_s).max(0.0)
                        ),
                    )
                    .with_label(format!("{late:.1} s too early for {}", self.profile_name))
                    .with_help(format!(
                        "pin the shot at `at {}s` or later, or shorten the shot before it by \
                         {late:.1} s",
                        round_up_1(soonest)
                    )),
                );
                arrive
            } else {
                written
            }
        } else {
            arrive
        }
    }

    /// Tells the `needed` s repositioning flight inserted before shot `to`, which now starts
    /// at `end` s.
    fn tell_reposition(&mut self, to: usize, needed: f64, end: f64, flown: &Flown) {
        let shot = &self.shots[to];
        let flight = format!("a {needed:.1} s repositioning flight ({flown}) is inserted before");
        // Between a coverage's parts its holds are split for its flights (`crate::coverage`):
        // a part starts late only as the coverage does, and no pin or gap is the fix.
        let (message, label, help) = match shot.coverage.as_ref().filter(|p| p.part > 1) {
            Some(part) => (
                format!("{flight} {part}: it starts at {end:.1} s"),
                "the drone flies between the coverage's shots",
                "a single drone cannot jump between framings: the coverage's shots are held for \
                 what its flights leave of its duration, and a longer coverage holds them longer",
            ),
            None => (
                format!(
                    "{flight} this shot: it starts at {end:.1} s instead of {:.1} s",
                    shot.start_s
                ),
                "the drone flies here first",
                "a single drone cannot jump between framings; pin the shot (`at Ns cut to …`) or \
                 leave a gap to keep it on the script's clock",
            ),
        };
        self.diagnostics.push(
            Diagnostic::warning(CompileCode::Reposition, shot.span, message)
                .with_label(label)
                .with_help(help),
        );
    }

    /// A repositioning flight setting off at `start_s` from where the camera is now to shot
    /// `to`'s first framing with the actors (`actors`, their poses at `actors_s`) where the
    /// blocking will have taken them at `at_s` (when it arrives): its route, and how long it
    /// takes.
    fn plan_reposition(
        &mut self,
        to: usize,
        start_s: f64,
        actors_s: f64,
        at_s: f64,
        actors: &[ActorPose],
    ) -> RepositionFlight {
        // Each plan solves from the same held two-actor solve (the flight's own solves start
        // from it too): else the plans of one search would each start from the last one's
        // root, and which root the goal takes would depend on the order they were planned in.
        let held = self.held[to][0];
        let mut arriving = std::mem::take(&mut self.arriving);
        self.arriving_into(actors, actors_s, at_s, &mut arriving);
        let goal = self.shot_target(to, 0.0, &arriving, false);
        let (goal_heading, _) = self.look_for(to, 0.0, &arriving, &goal, false);
        let pivot = self.pivot(to, &arriving);
        // How the framing moves on arrival (the flight arrives moving with it).
        let (moving, goal_v) =
            self.arrival_velocity(to, actors, actors_s, at_s, &goal, &mut arriving);
        // The route keeps clear of the actors where they stand, where they will be, and where
        // they pass in between: a route clear of a walking actor's two ends could cross their
        // way while they walked it.
        let mut keep_out = std::mem::take(&mut self.keep_out);
        let mut passing = std::mem::take(&mut self.passing);
        keep_out.clear();
        passing.clear();
        keep_out.extend_from_slice(actors);
        if moving {
            keep_out.extend_from_slice(&arriving);
        }
        if moving && at_s > actors_s {
            // On the flight's clock: it sets off at `start_s` (at or before `actors_s`) and
            // arrives at `at_s`. Sampled at `PASSING_SAMPLES` steps, and again finer where an
            // actor moved more than `PASSING_STEP_M` in one.
            let step_m = self.passing_into(
                actors,
                actors_s,
                start_s,
                at_s,
                PASSING_SAMPLES,
                &mut arriving,
                &mut passing,
            );
            if step_m > PASSING_STEP_M {
                let steps = (PASSING_SAMPLES as f64 * step_m / PASSING_STEP_M).ceil();
                let steps = (steps as usize).min(PASSING_SAMPLES_MAX);
                passing.clear();
                self.passing_into(
                    actors,
                    actors_s,
                    start_s,
                    at_s,
                    steps,
                    &mut arriving,
                    &mut passing,
                );
            }
        }
        self.arriving = arriving;
        self.held[to][0] = held;
        let from = self.state.p;
        let keep = Keepout {
            lo: self.stage_lo,
            hi: self.stage_hi,
            actors: &keep_out,
            passing: &passing,
            safety_m: self.safety_m,
            // The flight's merge as `target` flies it: over the time from `start_s` to `at_s`.
            merge: (goal_v != Vec3::zeros() && at_s > start_s).then_some(route::Merge {
                arrive_v: goal_v,
                duration_s: at_s - start_s,
                limits: &self.limits,
            }),
        };
        let route = route::choose(&from, &goal, pivot, &keep);
        self.keep_out = keep_out;
        self.passing = passing;
        let path_len = route.length(&from, &goal);
        let dz = (goal.z - from.z).abs();
        let dh = wrap_angle_rad(goal_heading - self.heading.heading_rad).abs();
        let speed = self.state.v.norm();
        let in_place = path_len < IN_PLACE_M && dh < IN_PLACE_RAD && speed < IN_PLACE_MPS;
        let (needed, needed_full, turn_sets_time) = if in_place {
            (0.0, 0.0, false)
        } else {
            // A min-jerk flight peaks at 1.875·L/T in speed and 5.77·L/T² in
            // acceleration; keep both under the share `m` of the limits ([`PLANNED_SHARE`]
            // as planned), plus the time to stop from the current speed and half a second to
            // settle.
            let l = &self.limits;
            let t_stop = speed / l.accel_h_mps2;
            let flight_s = |m: f64| {
                let t_speed = MIN_JERK_PEAK_SPEED * path_len / (m * l.speed_h_mps);
                let t_accel = (MIN_JERK_PEAK_ACCEL * path_len / (m * l.accel_h_mps2)).sqrt();
                let t_vz = MIN_JERK_PEAK_SPEED * dz / (m * l.speed_v_mps);
                let t_yaw = MIN_JERK_PEAK_SPEED * dh / (m * l.yaw_rate_radps);
                let t0 = t_speed.max(t_accel).max(t_vz).max(t_yaw).max(MIN_FLIGHT_S);
                // The flight may curve round the pivot: measure its peaks (centripetal
                // acceleration included) and stretch it until they fit (to the share
                // [`route::FIT_SHARE`] of the limits it is given: these, scaled to make that
                // the share `m`).
                let k = m / route::FIT_SHARE;
                let scaled = SteerLimits {
                    speed_h_mps: l.speed_h_mps * k,
                    speed_v_mps: l.speed_v_mps * k,
                    accel_h_mps2: l.accel_h_mps2 * k,
                    accel_v_mps2: l.accel_v_mps2 * k,
                    ..*l
                };
                let t_fly = route.fit_duration_arriving(&from, &goal, &goal_v, t0, &scaled);
                (
                    t_fly + t_stop + SETTLE_S,
                    t_yaw > MIN_FLIGHT_S && t_yaw >= t0,
                )
            };
            let (needed, turn_sets_time) = flight_s(PLANNED_SHARE);
            (needed, flight_s(1.0).0, turn_sets_time)
        };
        RepositionFlight {
            at_s,
            route,
            way: Way::of(&route, pivot),
            needed,
            needed_full,
            goal_speed_mps: goal_v.norm(),
            flown: Flown {
                path_m: path_len,
                turn_rad: dh,
                turn_sets_time,
            },
        }
    }

    /// The poses of the actors who move during a flight that sets off at `start_s` and
    /// arrives at `at_s`, at `steps` steps of the time from `actors_s` (where `actors` are)
    /// to `at_s`, each with its fraction of the flight's time, appended to `passing` in time
    /// order (`scratch` is overwritten). Returns the most an actor moved in one step, on the
    /// floor.
    #[allow(clippy::too_many_arguments)]
    fn passing_into(
        &self,
        actors: &[ActorPose],
        actors_s: f64,
        start_s: f64,
        at_s: f64,
        steps: usize,
        scratch: &mut Vec<ActorPose>,
        passing: &mut Vec<(f64, ActorPose)>,
    ) -> f64 {
        // The most the blocking takes an actor on the floor from `t0_s` to `t1_s` (a live pose
        // moves as the blocking does: `arriving_into`).
        let moved_m = |t0_s: f64, t1_s: f64| {
            (0..actors.len().min(self.blocking.len()))
                .map(|i| {
                    let (a, b) = (self.blocking.pose(i, t0_s), self.blocking.pose(i, t1_s));
                    let (dx, dy) = (
                        b.position_m[0] - a.position_m[0],
                        b.position_m[1] - a.position_m[1],
                    );
                    (dx * dx + dy * dy).sqrt()
                })
                .fold(0.0, f64::max)
        };
        let mut step_m: f64 = 0.0;
        let mut before_s = actors_s;
        for k in 1..steps {
            let t_s = actors_s + (at_s - actors_s) * k as f64 / steps as f64;
            self.arriving_into(actors, actors_s, t_s, scratch);
            let u = (t_s - start_s) / (at_s - start_s);
            passing.extend(
                scratch
                    .iter()
                    .zip(actors)
                    .filter(|(then, now)| !then.same_bits(now))
                    .map(|(then, _)| (u, *then)),
            );
            step_m = step_m.max(moved_m(before_s, t_s));
            before_s = t_s;
        }
        // The last step, to the arrival (its poses are not passing ones: they stand at the
        // goal, kept out of as such).
        step_m.max(moved_m(before_s, at_s))
    }

    /// The actors as they will stand at `at_s`, from their poses `actors` at `now_s`: each
    /// moved on by what the script's blocking does between the two times (its walks'
    /// displacement, its turns' rotation, the velocities at `at_s`), into `out`. Against the
    /// blocking itself (`compile`) that is the blocking at `at_s`, bit for bit; on set the
    /// actor's deviation from the blocking is carried along. An actor whom the blocking has
    /// at the same pose at both times is its pose now, bit for bit.
    /// Returns whether any actor moves between the two times.
    fn arriving_into(
        &self,
        actors: &[ActorPose],
        now_s: f64,
        at_s: f64,
        out: &mut Vec<ActorPose>,
    ) -> bool {
        let mut moving = false;
        out.clear();
        out.extend(actors.iter().enumerate().map(|(i, a)| {
            if i >= self.blocking.len() {
                return *a;
            }
            let (p0, p1) = (self.blocking.pose(i, now_s), self.blocking.pose(i, at_s));
            if p0.same_bits(&p1) {
                return *a;
            }
            moving = true;
            if a.same_bits(&p0) {
                // On its mark (as in `compile`): the blocking's pose then.
                return ActorPose {
                    height_m: a.height_m,
                    ..p1
                };
            }
            // `then + (live − planned now)`: exact when the live pose is the planned one.
            let on = |then: [f64; 3], live: [f64; 3], planned: [f64; 3]| {
                [0, 1, 2].map(|k| then[k] + (live[k] - planned[k]))
            };
            ActorPose {
                position_m: on(p1.position_m, a.position_m, p0.position_m),
                velocity_mps: on(p1.velocity_mps, a.velocity_mps, p0.velocity_mps),
                facing_rad: wrap_angle_rad(
                    p1.facing_rad + wrap_angle_rad(a.facing_rad - p0.facing_rad),
                ),
                facing_rate_radps: p1.facing_rate_radps
                    + (a.facing_rate_radps - p0.facing_rate_radps),
                height_m: a.height_m,
            }
        }));
        moving
    }

    /// How shot `to`'s first framing moves at `at_s`, where it is `goal` (a forward difference
    /// over 1 ms, the actors from `actors` at `actors_s` as [`Director::arriving_into`] has
    /// them, written into `scratch`), and whether any actor moves between the two times.
    fn arrival_velocity(
        &mut self,
        to: usize,
        actors: &[ActorPose],
        actors_s: f64,
        at_s: f64,
        goal: &Vec3,
        scratch: &mut Vec<ActorPose>,
    ) -> (bool, Vec3) {
        if !self.arriving_into(actors, actors_s, at_s + EPS_S, scratch) {
            return (false, Vec3::zeros());
        }
        let after = self.solve_live(to, |d| d.shot_target(to, 0.0, scratch, false));
        (true, (after - goal) / EPS_S)
    }

    /// `solve` (a solve of shot `to`'s first framing against the actors as they are now,
    /// during a repositioning flight), leaving the held two-actor solve as it was: the flight
    /// holds the one of its goal, which the shot starts from.
    fn solve_live<R>(&mut self, to: usize, solve: impl FnOnce(&mut Director) -> R) -> R {
        let held = self.held[to][0];
        let r = solve(self);
        self.held[to][0] = held;
        r
    }

    fn begin_shot_plan_only(&mut self, index: usize, actors: &[ActorPose]) {
        let shot = &self.shots[index];
        if let ShotContent::Path(path) = &shot.content {
            let plan = PathPlan::new(
                &path.shape,
                shot.end_s - shot.start_s,
                self.limits.accel_h_mps2,
                self.state.p,
                |n| self.names.iter().position(|x| x == n),
                actors,
            );
            self.plans[index] = Plan::Path(plan);
        }
    }

    /// The point repositioning flights turn around: the actors the next shot frames (or all
    /// actors).
    fn pivot(&self, to: usize, actors: &[ActorPose]) -> Option<Vec3> {
        let idx: Vec<usize> = match &self.shots[to].content {
            ShotContent::Composition(c) => c.actors().filter_map(|n| self.actor_index(n)).collect(),
            ShotContent::Coverage(c) => [&c.a, &c.b]
                .into_iter()
                .filter_map(|n| self.actor_index(n))
                .collect(),
            ShotContent::Path(_) => (0..actors.len()).collect(),
        };
        if idx.is_empty() {
            return None;
        }
        let mut c = Vec3::zeros();
        for &i in &idx {
            c += Vec3::from(actors[i].position_m);
        }
        Some(c / idx.len() as f64)
    }

    /// The camera target at `t_s`.
    fn target(&mut self, t_s: f64, actors: &[ActorPose], keep: bool) -> Vec3 {
        match self.phase.clone() {
            Phase::Shot { index, start_s, .. } => {
                self.shot_target(index, t_s - start_s, actors, keep)
            }
            Phase::Reposition {
                to,
                start_s,
                arrive_s,
                from,
                route,
                ..
            } => {
                let u = if arrive_s > start_s {
                    (t_s - start_s) / (arrive_s - start_s)
                } else {
                    1.0
                };
                let (s, _, _) = min_jerk(u);
                if u >= 1.0 {
                    // Arrived: on the framing as it is, until the shot starts.
                    let goal = self.shot_target(to, 0.0, actors, false);
                    return route.at(&from, &goal, s);
                }
                // The flight's goal: the shot's first framing as it will be when the flight
                // arrives, and how it moves then.
                let mut arriving = std::mem::take(&mut self.arriving);
                self.arriving_into(actors, t_s, arrive_s, &mut arriving);
                let goal = self.shot_target(to, 0.0, &arriving, false);
                // Round the way it went at the last tick (`Route::at_turning`).
                let (on_route, turn) = route.at_turning(&from, &goal, s, self.route_turn);
                if keep {
                    self.route_turn = turn;
                }
                // The framing's velocity on arrival: solved with the tick's target, reused by
                // its look-ahead (whose change of it over 1 ms the feed-forward does not need).
                if keep {
                    (_, self.merge_v) =
                        self.arrival_velocity(to, actors, t_s, arrive_s, &goal, &mut arriving);
                }
                let v = self.merge_v;
                let p = if v == Vec3::zeros() {
                    on_route
                } else {
                    let duration_s = arrive_s - start_s;
                    on_route + v * route::merge_m_per_mps(u, duration_s, v.norm(), &self.limits)
                };
                self.arriving = arriving;
                p
            }
            Phase::NotStarted | Phase::Done => self.state.p,
        }
    }

    /// The composition of end `end` of plan `index` (0: the hold or the move's start, 1: the
    /// move's end); `None` for paths.
    fn composition(&self, index: usize, end: usize) -> Option<&Composition> {
        match (&self.plans[index], end) {
            (Plan::Hold(c), _)
            | (Plan::Move { from: c, .. }, 0)
            | (Plan::Move { to: c, .. }, _) => Some(c),
            _ => None,
        }
    }

    /// `framing::solve` of end `end` (0: the hold or the move's start, 1: the move's end) of
    /// plan `index`, memoised (see [`Solved`]).
    fn solve_end(
        &mut self,
        index: usize,
        end: usize,
        actors: &[ActorPose],
    ) -> Result<framing::Visual, FramingError> {
        let framed = &self.framed[index][end];
        let known = framed.iter().all(|&i| i < actors.len());
        let hit = if known {
            self.solved.iter().position(|m| {
                m.plan == index
                    && m.end == end
                    && m.actor_count == actors.len()
                    && m.poses.len() == framed.len()
                    && framed
                        .iter()
                        .zip(&m.poses)
                        .all(|(&i, p)| actors[i].same_bits(p))
            })
        } else {
            None
        };
        if let Some(k) = hit {
            return self.solved[k].result.clone();
        }
        // Only compositions are solved (shot_ends).
        let Some(comp) = self.composition(index, end) else {
            return Err(FramingError::Unsupported {
                framings: 0,
                subjects: 0,
            });
        };
        let near = self.held[index][end].map(framing::Visual::Two);
        let result = match &self.prepared[index][end] {
            Some(prepared) => {
                let (lens, gimbal) = (&self.lens, &self.gimbal);
                prepared.solve_near(comp, actors, lens, gimbal, near.as_ref(), self.safety_m)
            }
            None => framing::solve(comp, &self.names, actors, &self.lens, &self.gimbal),
        };
        if let Ok(framing::Visual::Two(t)) = &result {
            self.held[index][end] = Some(*t);
        }
        if known {
            // A full memo reuses the oldest slot and its pose buffer: no allocation per tick.
            let slot = if self.solved.len() < SOLVED_SLOTS {
                self.solved.push(Solved {
                    plan: index,
                    end,
                    actor_count: actors.len(),
                    poses: Vec::with_capacity(framed.len()),
                    result: result.clone(),
                });
                self.solved.len() - 1
            } else {
                let k = self.next_solved;
                self.next_solved = (self.next_solved + 1) % SOLVED_SLOTS;
                let entry = &mut self.solved[k];
                entry.plan = index;
                entry.end = end;
                entry.actor_count = actors.len();
                entry.result = result.clone();
                k
            };
            let framed = &self.framed[index][end];
            let poses = &mut self.solved[slot].poses;
            poses.clear();
            poses.extend(framed.iter().map(|&i| actors[i]));
        }
        result
    }

    /// The solved ends of shot `index` at `into_s` seconds into it: the hold's visual, or the
    /// move's two ends and how far along it is (None for paths).
    #[allow(clippy::type_complexity)]
    fn shot_ends(
        &mut self,
        index: usize,
        into_s: f64,
        actors: &[ActorPose],
    ) -> Option<Result<(framing::Visual, Option<(framing::Visual, f64)>), FramingError>> {
        let duration = self.shots[index].end_s - self.shots[index].start_s;
        match &self.plans[index] {
            Plan::Hold(_) => Some(self.solve_end(index, 0, actors).map(|v| (v, None))),
            Plan::Move { .. } => {
                let (s, _, _) = min_jerk(into_s / duration);
                let a = self.solve_end(index, 0, actors);
                let b = self.solve_end(index, 1, actors);
                Some(match (a, b) {
                    (Ok(a), Ok(b)) => Ok((a, Some((b, s)))),
                    (Err(e), _) | (_, Err(e)) => Err(e),
                })
            }
            _ => None,
        }
    }

    /// The visual parameters of shot `index` at `into_s` seconds into it (None for paths).
    fn shot_visual(
        &mut self,
        index: usize,
        into_s: f64,
        actors: &[ActorPose],
    ) -> Option<Result<framing::Visual, FramingError>> {
        self.shot_ends(index, into_s, actors).map(|r| {
            r.map(|(a, b)| match b {
                None => a,
                Some((b, s)) => framing::interpolate(&a, &b, s),
            })
        })
    }

    /// The target of shot `index` at `into_s` seconds into it. With `keep`, the solved visual
    /// is kept for orienting the camera this tick, and the framing is checked against the
    /// actors' safety distance.
    fn shot_target(&mut self, index: usize, into_s: f64, actors: &[ActorPose], keep: bool) -> Vec3 {
        match self.shot_ends(index, into_s, actors) {
            Some(Ok((a, b))) => {
                let p = match &b {
                    None => framing::position_m(&a, actors, &self.lens, &self.gimbal),
                    Some((b, s)) => {
                        let last = match self.way {
                            Some((plan, way)) if plan == index => way,
                            _ => framing::BlendWay::default(),
                        };
                        let (lens, gimbal) = (&self.lens, &self.gimbal);
                        let (p, way) =
                            framing::position_between_way_m(&a, b, *s, actors, lens, gimbal, &last);
                        if keep {
                            self.way = Some((index, way));
                        }
                        p
                    }
                };
                if keep {
                    self.check_clearance(index, into_s, &p, actors);
                    self.check_reach(index, 0, &a, actors);
                    if let Some((b, _)) = &b {
                        self.check_reach(index, 1, b, actors);
                    }
                    self.visual = Some(match b {
                        None => a,
                        Some((b, s)) => {
                            framing::interpolate_reusing(&a, &b, s, &mut self.blend_spare)
                        }
                    });
                }
                p
            }
            Some(Err(e)) => self.fail(index, e, actors),
            None => match &self.plans[index] {
                Plan::Path(plan) => plan.at(into_s, actors).p,
                _ => self.state.p,
            },
        }
    }

    /// A framing whose camera position is inside an actor's safety distance: an error on the
    /// shot (once, when it first is: a flight tells it then), with the size to use instead.
    /// The closest it comes to that actor is followed to the end ([`Director::finish`] tells
    /// it): an actor who walks through the camera's spot comes much closer than when the
    /// error is first told.
    fn check_clearance(&mut self, index: usize, into_s: f64, p: &Vec3, actors: &[ActorPose]) {
        if let Some(c) = self.closest[index].as_mut() {
            if let Some(a) = actors.get(c.actor) {
                let d = framing::body_axis_distance_m(p, a);
                if d < c.closest_m {
                    (c.closest_m, c.closest_s) = (d, into_s);
                }
            }
            return;
        }
        let nearest_m = actors
            .iter()
            .map(|a| framing::body_axis_distance_m(p, a))
            .fold(f64::INFINITY, f64::min);
        // A shot that continues a framing told too close starts there: that shot's error.
        // While it comes out from there it is told only for coming nearer than it started.
        let continues_told = index > 0
            && (self.closest[index - 1].is_some()
                || self.clearance[index - 1].entry() > TOO_CLOSE_TOLD_M)
            && matches!(self.shots[index].transition, Transition::Move { .. })
            && !self.shots[index].pinned;
        let deepest_m = self.safety_m - nearest_m;
        let left_m = if continues_told { deepest_m } else { 0.0 };
        self.clearance[index].see(left_m, deepest_m, TOO_CLOSE_TOLD_M);
        if deepest_m <= TOO_CLOSE_TOLD_M {
            return;
        }
        let carried = self.clearance[index];
        for (i, a) in actors.iter().enumerate() {
            let d = framing::body_axis_distance_m(p, a);
            let intrusion_m = self.safety_m - d;
            if intrusion_m > TOO_CLOSE_TOLD_M && !carried.holds(intrusion_m, TOO_CLOSE_TOLD_M) {
                self.closest[index] = Some(Closest {
                    diagnostic: self.diagnostics.len(),
                    actor: i,
                    first_m: d,
                    first_s: into_s,
                    closest_m: d,
                    closest_s: into_s,
                });
                let name = self.names.get(i).map(String::as_str).unwrap_or("an actor");
                self.diagnostics.push(
                    Diagnostic::error(
                        CompileCode::TooClose,
                        self.shots[index].span,
                        format!(
                            "this framing puts the camera {d:.2} m from {name} ({:.1} s into \
                             the shot); {} keeps {:.2} m from actors: the camera is held at \
                             that distance, off its framing",
                            into_s.max(0.0),
                            self.profile_name,
                            self.safety_m
                        ),
                    )
                    .with_label(format!("too close to {name}"))
                    .with_help(
                        "use a wider size (MS → MLS → FS), a longer lens (`lens …`), or move the \
                         actors apart",
                    ),
                );
                return;
            }
        }
    }

    /// Tells once per shot that an over-the-shoulder's background actor is framed larger than
    /// written, its size just out of the toric circle's reach where the actors stand
    /// (`framing::OVER_SHOULDER_REACH`): the help says how much further apart they would have
    /// to stand.
    /// A two-actor end of shot `index` as solved this tick: how far its camera stands from
    /// the written size's distance ([`crate::sized::SizeWatch`]).
    fn check_reach(&mut self, index: usize, end: usize, v: &framing::Visual, actors: &[ActorPose]) {
        let framing::Visual::Two(t) = v else {
            return;
        };
        let comp = match (&self.plans[index], end) {
            (Plan::Hold(c), _)
            | (Plan::Move { from: c, .. }, 0)
            | (Plan::Move { to: c, .. }, _) => c,
            _ => return,
        };
        self.sizes.see(index, comp, t, actors);
    }

    /// Record a framing failure once per shot and hold position this tick. The plan is
    /// kept: the next tick solves again, against the actors as they are then (on set, live
    /// poses that miss a solvable framing by a few centimetres for a moment must not cost
    /// the rest of the shot).
    fn fail(&mut self, index: usize, e: framing::FramingError, actors: &[ActorPose]) -> Vec3 {
        self.failed_now = true;
        if !self.warned[index] {
            self.warned[index] = true;
            let mut d = framing_diagnostic(&e, self.shots[index].span);
            if let FramingError::ProfilesConflict { .. } = e {
                if let Some(help) = self.profiles_that_frame(index, actors) {
                    d.help = Some(help);
                }
            }
            self.diagnostics.push(d);
        }
        self.state.p
    }

    /// For an over-the-shoulder whose two profiles leave no camera: the background
    /// profiles that frame with the foreground's as the actors stand, in words.
    fn profiles_that_frame(&self, index: usize, actors: &[ActorPose]) -> Option<String> {
        let Some(Plan::Hold(comp) | Plan::Move { to: comp, .. }) = self.plans.get(index) else {
            return None;
        };
        let [fg, bg] = comp.framings.as_slice() else {
            return None;
        };
        let (a, b) = (&fg.subjects.first()?.actor, &bg.subjects.first()?.actor);
        let works = |clear_screens: bool| -> Vec<&str> {
            dronecine_grammar::vocab::Profile::ALL
                .into_iter()
                .filter(|p| {
                    let mut c = comp.clone();
                    c.framings[1].subjects[0].profile = Some(*p);
                    if clear_screens {
                        for f in &mut c.framings {
                            for s in &mut f.subjects {
                                s.screen_x = None;
                                s.screen_y = None;
                            }
                        }
                    }
                    framing::solve(&c, &self.names, actors, &self.lens, &self.gimbal).is_ok()
                })
                .map(|p| p.as_str())
                .collect()
        };
        let fg_profile = fg.subjects[0].profile.map_or("", |p| p.as_str());
        let (as_written, unscreened) = (works(false), works(true));
        Some(if !as_written.is_empty() {
            format!(
                "with {a} {fg_profile}, the camera sees {b} from {}: the profiles of an \
                 over-the-shoulder name the same side of the line between them",
                as_written.join(", ")
            )
        } else if !unscreened.is_empty() {
            format!(
                "with {a} {fg_profile}, the camera sees {b} from {} once the screen positions \
                 are left out: the ones written put the two in the order the other side of the \
                 line shows",
                unscreened.join(", ")
            )
        } else {
            format!(
                "no profile of {b} frames with {a} {fg_profile} as they stand: choose {a}'s \
                 profile on the side {b} faces (the camera behind {a}, looking at {b})"
            )
        })
    }

    /// Heading and pitch that frame the current shot from `position`.
    fn look(&mut self, t_s: f64, actors: &[ActorPose], position: &Vec3) -> (f64, f64) {
        match self.phase.clone() {
            Phase::Shot { index, start_s, .. } => {
                self.look_for(index, t_s - start_s, actors, position, true)
            }
            Phase::Reposition {
                to,
                start_s,
                arrive_s,
                from_heading_rad,
                ..
            } => {
                let u = if arrive_s > start_s {
                    (t_s - start_s) / (arrive_s - start_s)
                } else {
                    1.0
                };
                let (s, _, _) = min_jerk(u);
                // As the target does: toward the framing as it will be on arrival, then the
                // framing as it is.
                let mut arriving = std::mem::take(&mut self.arriving);
                if u < 1.0 {
                    self.arriving_into(actors, t_s, arrive_s, &mut arriving);
                } else {
                    arriving.clear();
                    arriving.extend_from_slice(actors);
                }
                let (h1, p1) = self.look_for(to, 0.0, &arriving, position, false);
                self.arriving = arriving;
                (
                    wrap_angle_rad(from_heading_rad + s * wrap_angle_rad(h1 - from_heading_rad)),
                    p1 * s,
                )
            }
            _ => (self.heading.heading_rad, self.pitch_rad),
        }
    }

    fn look_for(
        &mut self,
        index: usize,
        into_s: f64,
        actors: &[ActorPose],
        position: &Vec3,
        cached: bool,
    ) -> (f64, f64) {
        let duration = self.shots[index].end_s - self.shots[index].start_s;
        let visual = match &self.plans[index] {
            Plan::Hold(_) | Plan::Move { .. } => match (cached, self.visual.take()) {
                // The tick's visual: used, then put back below.
                (true, Some(v)) => Some((v, true)),
                (_, kept) => {
                    self.visual = kept;
                    self.shot_visual(index, into_s, actors)
                        .and_then(Result::ok)
                        .map(|v| (v, false))
                }
            },
            Plan::Path(plan) => {
                let looking_at = match &self.shots[index].content {
                    ShotContent::Path(p) => p.looking_at.clone(),
                    _ => None,
                };
                return match looking_at.and_then(|n| self.actor_index(&n)) {
                    Some(i) => {
                        let aim = look_at_point(&actors[i]);
                        self.orient_to(position, &aim, [0.0, 0.0])
                    }
                    None => {
                        // Along the path: the target's direction of travel.
                        let a = plan.at(into_s, actors);
                        let v = if dronecine_math::norm_xy(a.v.x, a.v.y) > PATH_MOVING_MPS {
                            a.v
                        } else {
                            plan.at((into_s + PATH_LOOK_AHEAD_S).min(duration), actors)
                                .p
                                - a.p
                        };
                        if dronecine_math::norm_xy(v.x, v.y) > 1e-6 {
                            (math::atan2(v.y, v.x), 0.0)
                        } else {
                            (self.heading.heading_rad, 0.0)
                        }
                    }
                };
            }
            Plan::PathPending => None,
        };
        match visual {
            Some((v, kept)) => {
                let (h, p, _) =
                    framing::orient_visual(&v, actors, &self.lens, &self.gimbal, position);
                if kept {
                    self.visual = Some(v);
                }
                (h, p)
            }
            None => (self.heading.heading_rad, self.pitch_rad),
        }
    }

    fn orient_to(&self, position: &Vec3, aim: &Vec3, screen: [f64; 2]) -> (f64, f64) {
        match self.gimbal {
            Gimbal::None => (
                orient_fixed_pitch(&self.lens, position, aim, screen[0], 0.0),
                0.0,
            ),
            Gimbal::Pitch {
                min_rad, max_rad, ..
            } => {
                let o = orient(&self.lens, position, aim, screen);
                (o.heading_rad, o.pitch_rad.clamp(min_rad, max_rad))
            }
        }
    }

    /// Diagnostics from planning and flying (repositions, cuts that do not fit, framings
    /// that cannot be solved, limits exceeded), in source order.
    pub fn finish(mut self) -> (Vec<ShotTiming>, Vec<Diagnostic>) {
        // The monitor's, shot by shot, as a flight tells them (a framing told too close is
        // not told again as the camera coming near the actor).
        let mut found = Vec::new();
        for i in 0..self.shots.len() {
            self.findings_into(i, &mut found);
        }
        let mut diags = std::mem::take(&mut self.diagnostics);
        // A framing too close: the closest it came, when it came closer than first told.
        for c in self.closest.iter().flatten() {
            if c.closest_m > c.first_m - CLOSER_TOLD_M {
                continue;
            }
            let name = self.names.get(c.actor).map_or("an actor", String::as_str);
            if let Some(d) = diags.get_mut(c.diagnostic) {
                d.message = format!(
                    "this framing puts the camera {:.2} m from {name} at the closest, {:.1} s \
                     into the shot (too close from {:.1} s); {} keeps {:.2} m from actors: the \
                     camera is held at that distance, off its framing",
                    c.closest_m,
                    c.closest_s.max(0.0),
                    c.first_s.max(0.0),
                    self.profile_name,
                    self.safety_m
                );
            }
        }
        diags.append(&mut found);
        diags.sort_by_key(|d| (d.span.start, d.span.end, d.code));
        (self.timings, diags)
    }
}

/// A shot's framing too close to an actor: where it was first told and the closest it came.
#[derive(Clone, Copy, Debug)]
struct Closest {
    /// Its diagnostic's index in the director's list.
    diagnostic: usize,
    actor: usize,
    /// The distance and the time into the shot when first told.
    first_m: f64,
    first_s: f64,
    closest_m: f64,
    closest_s: f64,
}

/// `goal` held inside the box `[lo, hi]`: on an axis where its position is outside, the
/// position is put on the box's face and the velocity and acceleration that would carry it
/// further out are dropped.
fn contained(mut goal: Kinematics, lo: &Vec3, hi: &Vec3) -> Kinematics {
    for i in 0..3 {
        let p = goal.p[i];
        if p < lo[i] {
            goal.p[i] = lo[i];
            goal.v[i] = goal.v[i].max(0.0);
            goal.a[i] = goal.a[i].max(0.0);
        } else if p > hi[i] {
            goal.p[i] = hi[i];
            goal.v[i] = goal.v[i].min(0.0);
            goal.a[i] = goal.a[i].min(0.0);
        }
    }
    goal
}

/// A held framing and the lens and gimbal that aim it ([`Director::held`]): the aim of
/// the hold from where the drone is, and the same framing targets as
/// [`Director::hold_targets`] at the step it was taken from, bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct Held {
    visual: framing::Visual,
    lens: Lens,
    gimbal: Gimbal,
}

impl Held {
    /// The heading and camera pitch that frame the hold from a camera at `camera_m` — on
    /// set, where the drone really is rather than where it should be (`shoot` aims the
    /// camera with it, so a position error does not also become a framing error); `None`
    /// when they are not finite.
    pub fn orientation(&self, actors: &[ActorPose], camera_m: &Vec3) -> Option<(f64, f64)> {
        let (v, lens) = (&self.visual, &self.lens);
        if matches!(self.gimbal, Gimbal::None) {
            // A level camera: a two-actor hold's heading is the balanced one, and aiming the
            // primary (below) would only give the pitch, which is 0.
            if let Some(h) = framing::balanced_heading(v, actors, lens, camera_m, 0.0) {
                return Some((h, 0.0));
            }
        }
        let (heading, pitch, _) = framing::orient_visual(v, actors, lens, &self.gimbal, camera_m);
        // Two actors: balance their screen-x errors rather than aim the primary exactly.
        let heading =
            framing::balanced_heading(v, actors, lens, camera_m, pitch).unwrap_or(heading);
        (heading.is_finite() && pitch.is_finite()).then_some((heading, pitch))
    }

    /// [`Director::hold_targets`] of the step it was taken from.
    pub fn targets_into(
        &self,
        actors: &[ActorPose],
        camera_m: &Vec3,
        out: &mut Vec<framing::ScreenTarget>,
    ) -> bool {
        out.clear();
        hold_targets(
            &self.visual,
            &self.lens,
            &self.gimbal,
            actors,
            camera_m,
            out,
        )
    }
}

/// Each framed actor's aim point and screen point of held visual `v` ([`Director::hold_targets`]).
fn hold_targets(
    v: &framing::Visual,
    lens: &Lens,
    gimbal: &Gimbal,
    actors: &[ActorPose],
    camera_m: &Vec3,
    out: &mut Vec<framing::ScreenTarget>,
) -> bool {
    framing::screen_targets_into(v, actors, lens, gimbal, camera_m, out);
    !out.is_empty()
}

/// An actor moved on by its velocity and turn rate over `dt_s`.
pub fn extrapolate(a: &ActorPose, dt_s: f64) -> ActorPose {
    ActorPose {
        position_m: [
            a.position_m[0] + a.velocity_mps[0] * dt_s,
            a.position_m[1] + a.velocity_mps[1] * dt_s,
            a.position_m[2] + a.velocity_mps[2] * dt_s,
        ],
        facing_rad: wrap_angle_rad(a.facing_rad + a.facing_rate_radps * dt_s),
        ..*a
    }
}

/// The point `looking at A` aims at: the centre of A's medium-shot band.
pub fn look_at_point(actor: &ActorPose) -> Vec3 {
    let (bottom, top) = crate::size::band(Size::MS, actor.height_m);
    Vec3::new(
        actor.position_m[0],
        actor.position_m[1],
        actor.position_m[2] + (bottom + top) / 2.0,
    )
}

/// A composition that cannot be framed, on its shot's line.
fn framing_diagnostic(e: &FramingError, span: Span) -> Diagnostic {
    let help = match e {
        FramingError::SizeUnreachable { .. } => {
            "use a wider size, move the actors apart, or put them closer together on screen"
        }
        FramingError::ProfileUnreachable | FramingError::ScreenSideConflict => {
            "drop the profile angle, or swap the actors' screen positions"
        }
        FramingError::ScreensCoincide => "give the two actors different screen positions",
        FramingError::TwoProfiles => {
            "write the profile on one of the two actors: the camera sees that one from that side"
        }
        FramingError::ProfileBlocked { .. } => {
            "choose a profile that sees the two side by side (a three-quarter or side profile), \
             or write an over-the-shoulder as two framings"
        }
        FramingError::ProfilesConflict { .. } => {
            "the profiles of an over-the-shoulder name the same side of the line between the actors"
        }
        FramingError::ActorsCoincide => {
            "the two actors stand at the same place here: frame one of them, or change the blocking"
        }
        _ => "frame one actor, two actors in one framing, or two framings of one actor each",
    };
    Diagnostic::error(
        CompileCode::Unframeable,
        span,
        format!("this composition cannot be framed: {e}"),
    )
    .with_label("no camera position gives this framing")
    .with_help(help)
}

/// A planned repositioning flight ([`Director::plan_reposition`]).
#[derive(Clone)]
struct RepositionFlight {
    /// When the flight was taken to arrive: the actors where the blocking puts them then.
    at_s: f64,
    route: Route,
    way: Way,
    /// Its duration, settling included.
    needed: f64,
    /// The same at the profile's full limits instead of [`PLANNED_SHARE`] of them: the
    /// shortest it can take.
    needed_full: f64,
    /// How fast the framing moves when it arrives.
    goal_speed_mps: f64,
    flown: Flown,
}

/// When a repositioning flight that sets off at `now_s` arrives and may end, for a flight of
/// a given duration.
#[derive(Clone, Copy, Debug)]
struct Arrival {
    now_s: f64,
    /// When the shot is pinned to start, or `now_s` when it is not pinned.
    written_s: f64,
    pinned: bool,
}

impl Arrival {
    /// When a flight that takes `needed` s reaches the framing (see
    /// `Phase::Reposition::arrive_s`).
    fn at_s(&self, needed: f64) -> f64 {
        let end = (self.now_s + needed).max(self.written_s);
        (self.now_s + needed - SETTLE_S).max(self.now_s).min(end)
    }

    /// Whether flight `f`, planned for the actors as they are at `f.at_s`, arrives then.
    fn settled(&self, f: &RepositionFlight) -> bool {
        (self.at_s(f.needed) - f.at_s).abs() < ARRIVAL_SETTLED_S
    }

    /// Whether flight `f`, planned for `f.at_s`, is there by then (it flies slower, or waits).
    fn fits(&self, f: &RepositionFlight) -> bool {
        self.at_s(f.needed) <= f.at_s + ARRIVAL_SETTLED_S
    }

    /// The duration of a flight that takes `needed` s as planned and `needed_full` s at the
    /// profile's full limits: late for its pin as planned, in time at its full limits, it is
    /// flown in the time there is.
    fn needed_for_pin(&self, needed: f64, needed_full: f64) -> f64 {
        let (now_s, written) = (self.now_s, self.written_s);
        if self.pinned
            && now_s + needed > written + PIN_TOLERANCE_S
            && now_s + needed_full <= written + PIN_TOLERANCE_S
        {
            written - now_s
        } else {
            needed
        }
    }
}

/// Where the search for a repositioning flight's arrival is ([`Director::search_arrival`]).
struct ArrivalSearch {
    /// The flight planned last.
    flight: RepositionFlight,
    /// The arrival as first planned: to the framing as it is now.
    first: RepositionFlight,
    /// The earliest arrival found that fits…
    best: Option<RepositionFlight>,
    /// …and the latest before it that does not.
    short_s: f64,
    /// How many times the flight was planned again for when it arrives.
    round: usize,
    /// The end of the actors' movements the search last planned for.
    after_s: f64,
    /// Past the rounds: a fit found, an earlier one is looked for.
    searching: bool,
    /// Where the framing when first planned moves no faster than the drone can merge into
    /// it: the flight that arrives then…
    on_time: Option<RepositionFlight>,
    /// …and how much later than that a search may go.
    limit_s: f64,
}

impl ArrivalSearch {
    /// Keeps the flight planned last as the earliest that fits, or its time as the latest
    /// that does not fit before that.
    fn record(&mut self, arrival: &Arrival) {
        if arrival.fits(&self.flight) {
            if self.best.as_ref().is_none_or(|b| self.flight.at_s < b.at_s) {
                self.best = Some(self.flight.clone());
            }
        } else if self.best.as_ref().is_none_or(|b| self.flight.at_s < b.at_s) {
            self.short_s = self.short_s.max(self.flight.at_s);
        }
    }

    /// The flight the search comes to: the one planned last where it settled, else the
    /// earliest that fits within the search's bound (or the one on time), flown in the time
    /// it has.
    fn into_flight(self, arrival: &Arrival) -> RepositionFlight {
        let ArrivalSearch {
            mut flight,
            mut best,
            searching,
            on_time,
            limit_s,
            ..
        } = self;
        if !arrival.settled(&flight) || searching {
            if searching
                && arrival.fits(&flight)
                && best.as_ref().is_none_or(|b| flight.at_s < b.at_s)
            {
                best = Some(flight.clone());
            }
            let best = match (best, on_time) {
                (Some(b), _) if b.at_s <= limit_s => Some(b),
                (_, on_time) => on_time,
            };
            if let Some(b) = best {
                // Early: it flies there in the time it has (or waits, pinned).
                let early_s = if arrival.fits(&b) {
                    b.at_s - arrival.at_s(b.needed)
                } else {
                    0.0
                };
                flight = RepositionFlight {
                    needed: b.needed + early_s.max(0.0),
                    ..b
                };
            }
        }
        flight
    }
}

/// What the search for a repositioning flight's arrival does next.
enum NextArrival {
    /// Plan a flight for this arrival.
    Plan(f64),
    /// Take this flight, planned already.
    Take(RepositionFlight),
    /// Stop: the search is over.
    Stop,
}

/// Which way a repositioning flight goes: the way it goes unless something is in it (round
/// the next shot's actors the short way, or straight when there are none to turn round), or
/// another of the route's shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Way {
    Usual,
    Straight,
    ShortArc,
    LongArc,
}

impl Way {
    fn of(route: &Route, pivot: Option<Vec3>) -> Way {
        match route {
            r if *r == route::usual(pivot) => Way::Usual,
            Route::Straight => Way::Straight,
            Route::Around {
                long_way: false, ..
            } => Way::ShortArc,
            Route::Around { long_way: true, .. } => Way::LongArc,
        }
    }
}

/// A repositioning flight in words, for its diagnostics: the length of its route and, when the
/// camera turns visibly or the turn sets the flight's time, the turn ("0.4 m and a 165°
/// turn"): a short flight that needs seconds is a turn at the yaw-rate limit, and the
/// distance alone does not say so. Formatted only when a diagnostic is written (a flight's
/// loop allocates nothing for a repositioning it does not tell).
#[derive(Clone)]
struct Flown {
    path_m: f64,
    turn_rad: f64,
    /// The turn at the yaw-rate limit takes longer than the flight's other bounds (a slow
    /// yaw profile's small turn too).
    turn_sets_time: bool,
}

impl Flown {
    /// Smaller turns are mentioned only when they set the time: at the ardrone2's 100°/s such
    /// a turn fits in the half second that every repositioning flight takes at least.
    const TURN_TOLD_DEG: f64 = 15.0;
    /// Turns smaller than this are never mentioned: they round to no turn at all.
    const TURN_NEVER_TOLD_DEG: f64 = 0.5;
    /// A flight shorter than this is a turn on the spot: its length rounds to nothing.
    const ON_THE_SPOT_M: f64 = 0.05;
}

impl std::fmt::Display for Flown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let deg = self.turn_rad.abs().to_degrees();
        if (deg < Self::TURN_TOLD_DEG && !self.turn_sets_time) || deg < Self::TURN_NEVER_TOLD_DEG {
            write!(f, "{:.1} m", self.path_m)
        } else if self.path_m < Self::ON_THE_SPOT_M {
            write!(f, "a {deg:.0}° turn on the spot")
        } else {
            write!(f, "{:.1} m and a {deg:.0}° turn", self.path_m)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repositioning_flight_in_words_names_a_turn_that_counts() {
        let words = |path_m: f64, turn_deg: f64, turn_sets_time: bool| {
            Flown {
                path_m,
                turn_rad: turn_deg.to_radians(),
                turn_sets_time,
            }
            .to_string()
        };
        assert_eq!(words(2.345, 14.9, false), "2.3 m");
        assert_eq!(words(2.345, -14.9, false), "2.3 m", "either way round");
        assert_eq!(words(0.4, 154.2, true), "0.4 m and a 154° turn");
        assert_eq!(words(0.4, -154.2, false), "0.4 m and a 154° turn");
        assert_eq!(words(0.01, 90.0, true), "a 90° turn on the spot");
        // A small turn that sets the time (a slow yaw): told.
        assert_eq!(words(0.2, 12.0, true), "0.2 m and a 12° turn");
        assert_eq!(words(0.2, 0.2, true), "0.2 m");
    }

    /// Where a repositioning flight will find the actors: against the blocking itself, the
    /// blocking at the arrival, bit for bit; on set, the live pose carried along by what the
    /// blocking does in between (an actor a little off its mark stays as far off it); an
    /// actor who stands still, the live pose itself.
    #[test]
    fn the_actors_on_arrival_follow_the_blocking_from_where_they_are() {
        let text = "stage 10m x 8m x 3m\ndrone ardrone2\n\
                    actor A height 1.80m at (-2, 0) facing 0deg\n\
                    actor B height 1.70m at (2, 1) facing 180deg\n\
                    at 2s A walks to (1, -1) over 4s\n\
                    at 6s A turns to 170deg over 1s\n\
                    MS on A for 10s\n";
        let opts = dronecine_grammar::Options {
            known_drones: dronecine_profile::BUILTIN_NAMES,
            base_dir: None,
        };
        let script = dronecine_grammar::check(text, &opts).script.unwrap();
        let scene = script.scene.as_ref().unwrap();
        let director = Director::new(&script, scene, &Profile::builtin("ardrone2").unwrap());
        let blocking = Blocking::new(scene);
        let mut out = Vec::new();
        // Exact against the blocking.
        let now = blocking.poses(2.5);
        assert!(director.arriving_into(&now, 2.5, 7.0, &mut out));
        let then = blocking.poses(7.0);
        assert!(out[0].same_bits(&then[0]), "{:?} {:?}", out[0], then[0]);
        assert!(out[1].same_bits(&now[1]), "B stands");
        // Off the mark by (0.1, −0.2) m and 0.05 rad: as far off at the arrival.
        let mut live = now.clone();
        live[0].position_m[0] += 0.1;
        live[0].position_m[1] -= 0.2;
        live[0].facing_rad += 0.05;
        director.arriving_into(&live, 2.5, 7.0, &mut out);
        assert!((out[0].position_m[0] - (then[0].position_m[0] + 0.1)).abs() < 1e-12);
        assert!((out[0].position_m[1] - (then[0].position_m[1] - 0.2)).abs() < 1e-12);
        let facing_off = wrap_angle_rad(out[0].facing_rad - then[0].facing_rad);
        assert!((facing_off - 0.05).abs() < 1e-12, "{facing_off}");
        // Nothing moves between 7 s and 9 s: the live poses, and no movement.
        let late = blocking.poses(7.0);
        assert!(!director.arriving_into(&late, 7.0, 9.0, &mut out));
        assert!(out.iter().zip(&late).all(|(a, b)| a.same_bits(b)));
    }

    fn goal(p: [f64; 3], v: [f64; 3]) -> Kinematics {
        Kinematics {
            p: Vec3::from(p),
            v: Vec3::from(v),
            a: Vec3::from(v),
        }
    }

    #[test]
    fn a_target_outside_the_margin_is_kept_on_its_edge() {
        // The stage 8 × 6 × 3 m less a 0.3 m margin.
        let (lo, hi) = (Vec3::new(-3.7, -2.7, 0.3), Vec3::new(3.7, 2.7, 2.7));
        let contain = |g| contained(g, &lo, &hi);
        // Inside: untouched.
        let g = goal([1.0, 2.0, 1.5], [0.3, 0.4, -0.1]);
        assert_eq!(contain(g).p, g.p);
        assert_eq!(contain(g).v, g.v);
        // In the margin along y (and below the floor's margin): on the edge, no outward
        // motion; the inward motion and the other axes kept.
        let c = contain(goal([1.0, 2.9, 0.1], [0.3, 0.4, 0.2]));
        assert_eq!(c.p, Vec3::new(1.0, 2.7, 0.3));
        assert_eq!(c.v, Vec3::new(0.3, 0.0, 0.2));
        let c = contain(goal([1.0, 2.9, 1.0], [0.3, -0.4, 0.0]));
        assert_eq!(c.v.y, -0.4, "moving back in");
        // Beyond the wall too.
        let c = contain(goal([4.5, 2.9, 1.0], [0.0; 3]));
        assert_eq!(c.p, Vec3::new(3.7, 2.7, 1.0));
    }
}
