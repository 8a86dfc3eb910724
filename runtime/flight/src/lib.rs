//! The flight loop behind `dronecine shoot`: pre-flight checks, take-off, the approach to the
//! first framing, the shots with the online director, the flight back over the take-off spot,
//! landing, and the report.
//!
//! One tick, at the loop's rate on the backend's [`Clock`]:
//! 1. wait for the tick time (the simulator advances its world; a wall clock sleeps);
//! 2. read the newest mocap frame: the drone's measured pose, the actors' poses (smoothed into
//!    [`ActorPose`]s with velocity and turn rate for the director);
//! 3. the reference: during the shots the online [`Director`] re-solves the framing against
//!    the live actor poses (the same evaluator `compile` runs in batch);
//! 4. the controller's tick, then the command (or a failsafe's) to the drone;
//! 5. metrics, the flight record to the [`FlightSink`], progress to the [`Observer`].
//!
//! The loop knows the backend only through the traits of `backend.rs`, and allocates nothing
//! per tick once started (events, which are rare, allocate their message).
//!
//! Replay rule (see `replay.rs`): the controller is reset once, with the first logged tick's
//! measurement at `t_s − dt_s`, and then given every logged [`TickInput`] in order.
//!
//! Failsafes (each logged as an event): a controller fault (NaN, time not increasing) →
//! hover for that tick; the drone's body not tracked for `mocap_hover_s` → hover, for
//! `mocap_land_s` → land; an actor's body not tracked as long, during the approach, the
//! shots or the flight back to the take-off spot, the same (the drone cannot keep clear of an
//! actor it does not see; an actor tracked again before the landing lets it fly on); the
//! drone outside the stage → land; battery below `battery_land_percent` → land; no telemetry
//! for `link_lost_s` → land; Ctrl-C → land, a second Ctrl-C → emergency motor cut.

mod ahead;
pub mod replay;
pub mod report;

use std::io;

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::director::{Director, Held};
use dronecine_compiler::framing::ScreenTarget;
use dronecine_compiler::route::{self, Keepout, Route};
use dronecine_compiler::steering::{self, Bodies, Body, Kinematics, SteerLimits};
use dronecine_compiler::CompileCode;
use dronecine_diag::{Diagnostic, LineIndex};
use dronecine_grammar::script::{Scene, Script};
use dronecine_profile::Profile;
use serde::Serialize;

use crate::ahead::{direct, Ahead, AheadStart, DirectedTick, Directing};
use crate::report::{Counts, FlightReport, Metrics};
use dronecine_backend::frames::Command;
use dronecine_backend::{
    BackendError, Backends, BodyPose, Clock, Drone, FlightState, Mocap, MocapFrame,
};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_math::wrap_angle_rad;
use dronecine_mcap::record::{Event, FlightSink, FramingRecord, Phase, TickRecord};
use dronecine_servo::control::{Controller, Measurement, Reference, TickInput};

/// What a progress display shows, offered every tick.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub t_s: f64,
    pub phase: Phase,
    pub shot: Option<usize>,
    pub shots: usize,
    /// Where the shots are on the script's clock as written (0 before they start, held at a
    /// shot's start during a repositioning flight inserted before it, the script's end after
    /// the last: [`Director::written_t_s`]).
    pub script_t_s: f64,
    /// Script duration as written.
    pub script_duration_s: f64,
    /// Distance from the measured position to the reference, when measured.
    pub position_error_m: Option<f64>,
}

pub trait Observer {
    fn progress(&mut self, progress: &Progress);
    fn event(&mut self, _event: &Event) {}
}

pub struct NoObserver;

impl Observer for NoObserver {
    fn progress(&mut self, _: &Progress) {}
}

/// Thresholds of the failsafes and the pre-flight checks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Safety {
    /// The drone, or an actor during the approach, the shots or the flight back, not tracked
    /// this long → hover.
    pub mocap_hover_s: f64,
    /// The drone, or an actor during the approach, the shots or the flight back, not tracked
    /// this long → land.
    pub mocap_land_s: f64,
    /// Below this, no take-off, and a flying drone lands.
    pub battery_land_percent: f64,
    /// Pre-flight: the first mocap frame must arrive within this.
    pub mocap_wait_s: f64,
    pub take_off_timeout_s: f64,
    pub landing_timeout_s: f64,
    /// No telemetry from the drone for this long → land.
    pub link_lost_s: f64,
}

impl Default for Safety {
    fn default() -> Self {
        Safety {
            mocap_hover_s: 0.5,
            mocap_land_s: 2.0,
            battery_land_percent: 15.0,
            mocap_wait_s: 2.0,
            take_off_timeout_s: 10.0,
            landing_timeout_s: 15.0,
            link_lost_s: 1.0,
        }
    }
}

pub struct FlightSetup<'a> {
    pub script: &'a Script,
    /// The script's text (shot labels in the report).
    pub source: &'a str,
    pub scene: &'a Scene,
    pub profile: &'a Profile,
    /// Control rate.
    pub rate_hz: f64,
    pub safety: Safety,
    /// Interrupts (Ctrl-C) counted by the caller's signal handler: the first lands the
    /// drone, the second cuts the motors.
    pub interrupts: Option<&'a std::sync::atomic::AtomicU32>,
}

#[derive(Debug)]
pub enum FlightError {
    /// A pre-flight check failed: the drone never took off.
    Preflight(String),
    Backend(BackendError),
    /// The flight log could not be written; the drone was landed.
    Log(io::Error),
}

impl std::fmt::Display for FlightError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FlightError::Preflight(m) => write!(f, "pre-flight check failed: {m}"),
            FlightError::Backend(e) => write!(f, "drone backend: {e}"),
            FlightError::Log(e) => write!(
                f,
                "the flight log could not be written ({e}): the drone was landed"
            ),
        }
    }
}

impl std::error::Error for FlightError {}

impl From<BackendError> for FlightError {
    fn from(e: BackendError) -> Self {
        FlightError::Backend(e)
    }
}

/// Actor poses from the mocap, smoothed by an α-β tracker per actor: the director wants a
/// velocity and a turn rate (feed-forward), which raw differences of a noisy position would
/// make jumpy.
///
/// Positions: the steady-state gains of the Kalman filter of a body whose acceleration is
/// white ([`TRACK_ACTOR_ACCEL_MPS2`]) measured with noise ([`TRACK_POSITION_NOISE_M`]) every
/// `T` (Kalata's α-β filter, [`alpha_beta`]): at 100 Hz α = 0.44, β = 0.125. The fixed
/// α = 0.7, β = 0.2 they replaced passed 41 % more of the noise into the velocity (twice its
/// variance), which the director feeds forward and differentiates again. Over seeds 1–10,
/// `two-actors.psl`'s two-shot measured a framing error of 0.022 on average with those,
/// 0.016 with these; `transition.psl`, one actor drifting on their mark, 0.0145 and 0.0156.
/// Facing: α = 0.7, β = 0.2. Smoothing it more was tried (α = 0.3, β = 0.05): the one-actor
/// holds of `scene.psl`, whose framings turn with the actors' drifting facing, tracked worse
/// (its first shot 2.9 → 3.8 cm RMS over seeds 1–10).
#[derive(Clone, Debug, Default)]
pub(crate) struct ActorTracker {
    pub(crate) poses: Vec<ActorPose>,
    last_t_s: Vec<Option<f64>>,
}

/// The motion capture's position noise the tracker expects (OptiTrack's sub-millimetre, as
/// the simulator's `mocap_position_sigma_m`).
const TRACK_POSITION_NOISE_M: f64 = 0.0003;
/// How fast actors change their velocity (RMS): a walk starting or stopping.
const TRACK_ACTOR_ACCEL_MPS2: f64 = 0.5;
const TRACK_FACING_ALPHA: f64 = 0.7;
const TRACK_FACING_BETA: f64 = 0.2;

/// Kalata's steady-state α-β gains for a tracking index `λ = σ_a·T²/σ_n` (the body's RMS
/// acceleration over the measurement noise, in steps of `T`): `r = (4 + λ − √(8λ + λ²))/4`,
/// `α = 1 − r²`, `β = 2(2 − α) − 4√(1 − α)`.
fn alpha_beta(lambda: f64) -> (f64, f64) {
    let r = (4.0 + lambda - (8.0 * lambda + lambda * lambda).sqrt()) / 4.0;
    let alpha = 1.0 - r * r;
    (alpha, 2.0 * (2.0 - alpha) - 4.0 * (1.0 - alpha).sqrt())
}

impl ActorTracker {
    fn new(scene: &Scene) -> Self {
        ActorTracker {
            poses: scene
                .actors
                .iter()
                .map(|a| ActorPose {
                    position_m: [a.position_m[0], a.position_m[1], 0.0],
                    velocity_mps: [0.0; 3],
                    facing_rad: a.facing_rad,
                    facing_rate_radps: 0.0,
                    height_m: a.height_m,
                })
                .collect(),
            last_t_s: vec![None; scene.actors.len()],
        }
    }

    /// Becomes `other`, reusing its vectors (no allocation once they have room).
    pub(crate) fn copy_from(&mut self, other: &ActorTracker) {
        self.poses.clone_from(&other.poses);
        self.last_t_s.clone_from(&other.last_t_s);
    }

    /// Folds a frame in. Untracked actors keep moving with their last velocity for the tick.
    pub(crate) fn update(&mut self, frame: &MocapFrame) {
        for (i, pose) in self.poses.iter_mut().enumerate() {
            let Some(Some(m)) = frame.actors.get(i) else {
                continue;
            };
            if !finite_pose(m) {
                continue;
            }
            match self.last_t_s[i] {
                Some(t0) if frame.t_s > t0 => {
                    let dt = frame.t_s - t0;
                    let (alpha, beta) =
                        alpha_beta(TRACK_ACTOR_ACCEL_MPS2 * dt * dt / TRACK_POSITION_NOISE_M);
                    for k in 0..2 {
                        let pred = pose.position_m[k] + pose.velocity_mps[k] * dt;
                        let r = m.position_m[k] - pred;
                        pose.position_m[k] = pred + alpha * r;
                        pose.velocity_mps[k] += beta * r / dt;
                    }
                    let pred = pose.facing_rad + pose.facing_rate_radps * dt;
                    let r = wrap_angle_rad(m.heading_rad - pred);
                    pose.facing_rad = wrap_angle_rad(pred + TRACK_FACING_ALPHA * r);
                    pose.facing_rate_radps += TRACK_FACING_BETA * r / dt;
                }
                Some(_) => continue,
                None => {
                    pose.position_m = [m.position_m[0], m.position_m[1], 0.0];
                    pose.facing_rad = m.heading_rad;
                }
            }
            pose.position_m[2] = 0.0;
            self.last_t_s[i] = Some(frame.t_s);
        }
    }
}

/// Whether a frame just polled is newer than the last one used, which it then becomes: an
/// out-of-order or replayed frame is not used. (The one rule, for the loop and for the
/// director ahead of it: `crate::ahead`.)
pub(crate) fn take_newer(last_frame_t_s: &mut Option<f64>, frame: &MocapFrame) -> bool {
    if last_frame_t_s.is_some_and(|t0| frame.t_s <= t0) {
        return false;
    }
    *last_frame_t_s = Some(frame.t_s);
    true
}

fn finite_pose(p: &BodyPose) -> bool {
    p.position_m.iter().all(|x| x.is_finite()) && p.heading_rad.is_finite()
}

/// The approach: a minimum-jerk flight from the take-off hover to the first framing, along
/// the route the compiler's repositioning flights take (`route::choose`): straight when that
/// is clear, else round an actor in the way, inside the stage less its margin.
#[derive(Clone, Copy, Debug)]
struct Glide {
    t0_s: f64,
    duration_s: f64,
    from_m: Vec3,
    to_m: Vec3,
    route: Route,
    from_heading_rad: f64,
    turn_rad: f64,
}

impl Glide {
    /// Long enough that the peaks stay at half the profile's speed and acceleration
    /// (minimum jerk: peak speed 1.875·d/T, peak acceleration 5.77·d/T² over the route's
    /// length d; a bend's centripetal acceleration too) and yaw rate.
    fn new(t0_s: f64, from: &Sample, to: &Sample, profile: &Profile, keep: &Keepout) -> Glide {
        let from_m = Vec3::from(from.position_m);
        let to_m = Vec3::from(to.position_m);
        let route = route::choose(&from_m, &to_m, None, keep);
        let d = match route {
            Route::Straight => (to_m - from_m).norm(),
            _ => route.length(&from_m, &to_m),
        };
        let turn_rad = wrap_angle_rad(to.heading_rad - from.heading_rad);
        let lim = &profile.limits;
        let dz = (to_m.z - from_m.z).abs();
        let mut duration_s = [
            2.0,
            1.875 * d / (0.5 * lim.speed_max_mps),
            (5.77 * d / (0.5 * lim.accel_max_mps2)).sqrt(),
            1.875 * dz / (0.5 * lim.vz_max_mps),
            1.875 * turn_rad.abs() / (0.5 * lim.yaw_rate_max_radps),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        if route != Route::Straight {
            // `fit_duration` keeps to 80% of the limits it is given: these are 62.5% of the
            // profile's, so the bend keeps to half of them.
            let half = SteerLimits {
                speed_h_mps: 0.625 * lim.speed_max_mps,
                speed_v_mps: 0.625 * lim.vz_max_mps,
                accel_h_mps2: 0.625 * lim.accel_max_mps2,
                accel_v_mps2: 0.625 * lim.accel_max_mps2,
                jerk_mps3: lim.jerk_max_mps3,
                yaw_rate_radps: lim.yaw_rate_max_radps,
                yaw_accel_radps2: 2.0 * lim.yaw_rate_max_radps,
            };
            duration_s = route.fit_duration(&from_m, &to_m, duration_s, &half);
        }
        Glide {
            t0_s,
            duration_s,
            from_m,
            to_m,
            route,
            from_heading_rad: from.heading_rad,
            turn_rad,
        }
    }

    fn end_s(&self) -> f64 {
        self.t0_s + self.duration_s
    }

    /// How its route goes, as the flight's events tell it (after the duration).
    fn way(&self) -> &'static str {
        match self.route {
            Route::Straight => "",
            Route::Around { .. } => ", round an actor in the way",
        }
    }

    fn sample(&self, t_s: f64, pitch_rad: f64) -> Sample {
        let u = ((t_s - self.t0_s) / self.duration_s).clamp(0.0, 1.0);
        let (s, ds, dds) = dronecine_compiler::blocking::min_jerk(u);
        let (ds, dds) = (
            ds / self.duration_s,
            dds / (self.duration_s * self.duration_s),
        );
        let (p, v, a) = match self.route {
            Route::Straight => {
                let d = self.to_m - self.from_m;
                (self.from_m + d * s, d * ds, d * dds)
            }
            // The route's first and second derivatives in s, by central differences (a
            // route is smooth, and defined a little beyond its ends).
            route => {
                let at = |s: f64| route.at(&self.from_m, &self.to_m, s);
                let h = 1e-4;
                let (p0, p, p1) = (at(s - h), at(s), at(s + h));
                let (p_s, p_ss) = ((p1 - p0) / (2.0 * h), (p1 - 2.0 * p + p0) / (h * h));
                (p, p_s * ds, p_ss * ds * ds + p_s * dds)
            }
        };
        Sample {
            t_s,
            position_m: p.into(),
            velocity_mps: v.into(),
            acceleration_mps2: a.into(),
            heading_rad: wrap_angle_rad(self.from_heading_rad + self.turn_rad * s),
            heading_rate_radps: self.turn_rad * ds,
            camera_pitch_rad: pitch_rad,
            shot: 0,
        }
    }
}

fn hover_sample(t_s: f64, at: &Sample) -> Sample {
    Sample {
        t_s,
        velocity_mps: [0.0; 3],
        acceleration_mps2: [0.0; 3],
        heading_rate_radps: 0.0,
        ..*at
    }
}

/// How far into an actor's safety distance or the stage's margin an approach may come
/// before it is told (a warning event): the take-off hover or the first framing themselves
/// may be that close.
const APPROACH_TOLERANCE_M: f64 = 0.1;

/// Pause after the approach's glide, before "action!", while the director steers the drone
/// from where the glide ended onto the first framing as the actors stand (it goes on steering
/// into the first shot: its arrival closes a gap as e^(−t/1 s)).
const SETTLE_S: f64 = 1.0;
/// Hold after the last shot, before the flight back to the take-off spot and the landing.
const HOLD_BEFORE_LANDING_S: f64 = 1.0;
/// Within this (horizontally) of the take-off spot, the drone lands where it is.
const HOME_RADIUS_M: f64 = 0.3;

/// Flies the script. Returns the report, also when a failsafe ended the flight early
/// (`completed` is then false); an error only when the flight could not start or a backend
/// or the log failed (the drone is landed first whenever it flies).
pub fn fly(
    setup: &FlightSetup,
    controller: &mut dyn Controller,
    backends: Backends,
    sink: &mut dyn FlightSink,
    observer: &mut dyn Observer,
) -> Result<FlightReport, FlightError> {
    Flight::new(setup, controller, backends, sink, observer)?.run()
}

struct Flight<'s, 'b> {
    setup: &'s FlightSetup<'s>,
    controller: &'s mut dyn Controller,
    drone: &'b mut dyn Drone,
    mocap: &'b mut dyn Mocap,
    clock: &'b mut dyn Clock,
    sink: &'s mut dyn FlightSink,
    observer: &'s mut dyn Observer,
    period_s: f64,
    lens: Lens,
    frame: MocapFrame,
    /// The newest frame arrived this tick.
    fresh: bool,
    last_frame_t_s: Option<f64>,
    last_drone_seen_s: f64,
    /// Per actor: when their body was last tracked, and whether the drone hovers for them.
    actor_seen_s: Vec<f64>,
    actor_lost: Vec<bool>,
    /// The drone's measurement of this tick's fresh mocap frame (`None` between frames).
    measured: Option<Measurement>,
    /// The newest finite measurement of the drone and when it arrived, held between frames:
    /// where the drone is, for what needs it every tick (the aim, the approach's start),
    /// whatever the mocap's rate against the loop's.
    drone_m: Option<(f64, Measurement)>,
    actors: ActorTracker,
    targets: Vec<ScreenTarget>,
    framing: Vec<FramingRecord>,
    /// The actors' bodies as they stand this tick, for [`Flight::clear_of_actors`] (reused:
    /// no allocation per tick).
    bodies: Vec<Body>,
    /// The last aim from a fresh measurement of the drone's position.
    last_aim: Option<Aim>,
    last_tick_s: Option<f64>,
    controller_started: bool,
    metrics: Metrics,
    failsafes: u64,
    faults: u64,
    deadline_misses: u64,
    director_errors: u64,
    hovering: bool,
    /// The first interrupt was handled (landing).
    interrupted: bool,
    /// The telemetry link was reported lost.
    link_lost: bool,
    log_error: Option<io::Error>,
    script_duration_s: f64,
    /// Where the shots are on the script's clock as written (0 before "action!").
    written_t_s: f64,
}

/// Who steps the director during the shots: the loop itself, or a thread ahead of it
/// ([`Ahead`]). Both give the same [`DirectedTick`]s ([`direct`]).
enum Stepper {
    Here(Director, Directing, DirectedTick),
    Ahead(Ahead),
}

impl Stepper {
    fn here(director: Director) -> Stepper {
        Stepper::Here(director, Directing::default(), DirectedTick::default())
    }
}

/// A heading aimed from a fresh measurement of the drone's position, and its rate.
#[derive(Clone, Copy, Debug)]
struct Aim {
    t_s: f64,
    heading_rad: f64,
    rate_radps: f64,
}

/// How a phase of the loop ended.
enum Outcome {
    Done,
    /// A failsafe asks for landing now.
    Land,
}

impl<'s, 'b> Flight<'s, 'b> {
    fn new(
        setup: &'s FlightSetup<'s>,
        controller: &'s mut dyn Controller,
        backends: Backends<'b>,
        sink: &'s mut dyn FlightSink,
        observer: &'s mut dyn Observer,
    ) -> Result<Self, FlightError> {
        if !(setup.rate_hz.is_finite() && setup.rate_hz > 0.0 && setup.rate_hz <= 1000.0) {
            return Err(FlightError::Preflight(format!(
                "the control rate must be in (0, 1000] Hz, not {}",
                setup.rate_hz
            )));
        }
        if setup.script.timeline.is_empty() {
            return Err(FlightError::Preflight(
                "the script has no shots: there is nothing to fly".into(),
            ));
        }
        let n_actors = setup.scene.actors.len();
        let script_duration_s = setup.script.timeline.last().map_or(0.0, |s| s.end_s);
        let probe = Director::new(setup.script, setup.scene, setup.profile);
        Ok(Flight {
            setup,
            controller,
            drone: backends.drone,
            mocap: backends.mocap,
            clock: backends.clock,
            sink,
            observer,
            period_s: 1.0 / setup.rate_hz,
            lens: *probe.lens(),
            frame: MocapFrame {
                actors: Vec::with_capacity(n_actors),
                ..MocapFrame::default()
            },
            fresh: false,
            last_frame_t_s: None,
            last_drone_seen_s: f64::NEG_INFINITY,
            actor_seen_s: vec![f64::NEG_INFINITY; n_actors],
            actor_lost: vec![false; n_actors],
            measured: None,
            drone_m: None,
            actors: ActorTracker::new(setup.scene),
            targets: Vec::with_capacity(4),
            framing: Vec::with_capacity(n_actors.max(2)),
            bodies: Vec::with_capacity(n_actors),
            last_aim: None,
            last_tick_s: None,
            controller_started: false,
            metrics: Metrics::new(setup.script.timeline.len(), &setup.profile.safety),
            failsafes: 0,
            director_errors: 0,
            faults: 0,
            deadline_misses: 0,
            hovering: false,
            interrupted: false,
            link_lost: false,
            log_error: None,
            script_duration_s,
            written_t_s: 0.0,
        })
    }

    fn event(&mut self, t_s: f64, level: &str, kind: &str, message: String) {
        self.tell(Event {
            t_s,
            level: level.to_string(),
            kind: kind.to_string(),
            message,
            line: None,
            help: None,
        });
    }

    /// A finding of the director's against the live actors, as an event: its message after
    /// the shot it is about, the script's line of that shot and its fix (before, the event
    /// carried the message only, and a director on set read "the shot is pinned to start at
    /// 67.0 s" without the line, or the time to pin it at instead).
    fn director_finding(&mut self, t_s: f64, d: &Diagnostic) {
        let shot = (self.setup.script.timeline.iter())
            .position(|s| s.span == d.span)
            .map_or(String::new(), |i| format!("shot {}: ", i + 1));
        // A repositioning flight is the plan working as written: logged, not printed over
        // the progress display.
        let level = match d.is_error() {
            true => "error",
            false if d.code == CompileCode::Reposition => "info",
            false => "warning",
        };
        let held = if d.code == CompileCode::Unframeable {
            "; the drone holds where it is until it solves"
        } else {
            ""
        };
        let source = self.setup.source;
        let line = (!d.span.is_empty() && d.span.start <= source.len()).then(|| {
            let (line, _) = LineIndex::new(source).line_col(source, d.span.start);
            u32::try_from(line).unwrap_or(u32::MAX)
        });
        self.tell(Event {
            t_s,
            level: level.to_string(),
            kind: d.code.as_str().to_string(),
            message: format!("{shot}{}{held}", d.message),
            line,
            help: d.help.clone(),
        });
    }

    /// What the director's monitor found over shot `index`, now that it is over (the
    /// reference's lag behind the framing and its limits, a framing out of the stage or held
    /// at its margin, the camera near an actor), told as the director's own findings are.
    ///
    /// And the drone's own closest to an actor in it, as measured, when that is inside their
    /// safety distance (`drone_near_actor`): the reference keeps the profile's tracking
    /// margin more on set, and a drone that still comes inside tracks worse than its profile
    /// says. Else, when the drone strayed toward an actor by more than the margin where the
    /// reference was near the line it keeps (`tracking_margin_exceeded`,
    /// [`CutIn`](crate::report::CutIn)): it did not come inside this time, but a reference
    /// held at the line would have had it inside.
    fn tell_findings(&mut self, t_s: f64, findings: &[Diagnostic], index: usize) {
        for d in findings {
            self.director_finding(t_s, d);
        }
        let safety = &self.setup.profile.safety;
        let profile = &self.setup.profile.name;
        let name = |actor: usize| {
            let actors = &self.setup.scene.actors;
            actors.get(actor).map_or("an actor", |a| a.name.as_str())
        };
        let inside = self
            .metrics
            .shot_closest(index)
            .filter(|c| c.distance_m < safety.actor_distance_m);
        let strayed = self
            .metrics
            .shot_cut_in(index)
            .filter(|c| c.cut_in_m > safety.tracking_margin_m);
        // The drone's distances in millimetres: at two decimals a drone 0.4996 m from an actor
        // read "came 0.50 m from Bob" against "keeps 0.50 m".
        let (kind, message, help) = if let Some(c) = inside {
            let message = format!(
                "shot {}: the drone came {:.3} m from {} at {:.2} s (as measured); {profile} \
                 keeps {:.2} m from actors",
                index + 1,
                c.distance_m,
                name(c.actor),
                c.t_s,
                safety.actor_distance_m
            );
            let inside = short_distance(safety.actor_distance_m - c.distance_m);
            let help = format!(
                "on set the reference keeps the profile's `tracking_margin_m` ({:.2} m) \
                 more than that from actors, and the drone strayed {inside} beyond it: \
                 raise the margin, or frame the shot wider",
                safety.tracking_margin_m,
            );
            ("drone_near_actor", message, help)
        } else if let Some(c) = strayed {
            let message = format!(
                "shot {}: the drone came {:.3} m nearer {} than its reference at {:.2} s (as \
                 measured), the reference {:.2} m from them; {profile}'s `tracking_margin_m` \
                 is {:.2} m",
                index + 1,
                c.cut_in_m,
                name(c.actor),
                c.t_s,
                c.reference_m,
                safety.tracking_margin_m
            );
            let help = format!(
                "on set the reference keeps {:.2} m from actors so that a drone straying by up \
                 to the margin keeps their {:.2} m; this one strayed more, and with the \
                 reference at that line it would have come inside: raise `[safety] \
                 tracking_margin_m` to {:.2} m or more in the profile",
                safety.on_set_m(),
                safety.actor_distance_m,
                (c.cut_in_m * 100.0).ceil() / 100.0
            );
            ("tracking_margin_exceeded", message, help)
        } else {
            return;
        };
        let line = self.setup.script.timeline.get(index).map(|s| {
            let source = self.setup.source;
            let (line, _) = LineIndex::new(source).line_col(source, s.span.start);
            u32::try_from(line).unwrap_or(u32::MAX)
        });
        self.tell(Event {
            t_s,
            level: "warning".into(),
            kind: kind.into(),
            message,
            line,
            help: Some(help),
        });
    }

    fn tell(&mut self, e: Event) {
        self.director_errors += u64::from(e.is_director_error());
        self.observer.event(&e);
        if let Err(err) = self.sink.event(&e) {
            self.log_error.get_or_insert(err);
        }
    }

    /// Waits for the next tick and reads the mocap.
    fn wait_tick(&mut self, t_next_s: f64) -> Result<f64, FlightError> {
        self.wait_tick_fed(t_next_s, None).map(|(now, _)| now)
    }

    /// [`Flight::wait_tick`] with the director's tick `ahead` (its thread steps ahead of the
    /// loop): the frame polled takes its actors from the frame the director's thread had from
    /// the mocap's feed at this tick ([`Mocap::actors_from_feed`]), and the tracked actors are
    /// the ones it stepped with (its tracker folded the same frames in). Also says whether the
    /// two polls agreed (the same frame, or no frame); when they do not, the frame's actors
    /// are as the mocap gave them.
    fn wait_tick_fed(
        &mut self,
        t_next_s: f64,
        ahead: Option<&DirectedTick>,
    ) -> Result<(f64, bool), FlightError> {
        self.clock.sleep_until(t_next_s);
        let now = self.clock.now_s();
        if now > t_next_s + 0.5 * self.period_s {
            self.deadline_misses += 1;
            self.event(
                now,
                "warning",
                "deadline_missed",
                format!(
                    "tick due at {t_next_s:.3} s ran at {now:.3} s ({:.1} ms late)",
                    (now - t_next_s) * 1e3
                ),
            );
        }
        self.fresh = self.mocap.poll(&mut self.frame)?;
        let agreed = ahead.is_none_or(|k| k.feed.fill(self.fresh, &mut self.frame));
        if self.fresh {
            if !take_newer(&mut self.last_frame_t_s, &self.frame) {
                // Out of order or replayed: its measurement is not used.
                self.fresh = false;
                self.event(
                    now,
                    "warning",
                    "stale_frame",
                    format!(
                        "mocap frame {} at {:.4} s is not newer than the previous one; ignored",
                        self.frame.frame, self.frame.t_s
                    ),
                );
            } else {
                match ahead {
                    // The director's tracker folded this frame in already.
                    Some(k) => self.actors.copy_from(&k.tracker),
                    None => self.actors.update(&self.frame),
                }
                for (seen, body) in self.actor_seen_s.iter_mut().zip(&self.frame.actors) {
                    if body.as_ref().is_some_and(finite_pose) {
                        *seen = now;
                    }
                }
                self.measured = match self.frame.drone {
                    Some(p) => {
                        self.last_drone_seen_s = now;
                        if finite_pose(&p) {
                            self.drone_m = Some((
                                now,
                                Measurement {
                                    position_m: p.position_m,
                                    heading_rad: p.heading_rad,
                                },
                            ));
                        }
                        Some(Measurement {
                            position_m: p.position_m,
                            heading_rad: p.heading_rad,
                        })
                    }
                    None => None,
                };
            }
        }
        if !self.fresh {
            self.measured = None;
        }
        Ok((now, agreed))
    }

    fn run(mut self) -> Result<FlightReport, FlightError> {
        let t_start = self.clock.now_s();
        // Pre-flight: the drone and every actor tracked, the drone inside the stage and clear
        // of the actors, battery, the first framing solved and inside the stage.
        // The first frame that has the drone and every actor: a body dropped from one frame
        // (a marker hidden for a moment; the simulator drops 0.5 % of them) is not
        // untracked, and refusing the flight on it refused a good set-up now and then.
        let mut t = t_start;
        let mut seen_drone: Option<Measurement> = None;
        while t - t_start <= self.setup.safety.mocap_wait_s {
            t = self.wait_tick(t + self.period_s)?;
            if let Some(m) = self.measured {
                seen_drone = Some(m);
                let actors = self.setup.scene.actors.len();
                if (0..actors).all(|i| matches!(self.frame.actors.get(i), Some(Some(_)))) {
                    break;
                }
            }
        }
        let Some(m0) = seen_drone else {
            return Err(FlightError::Preflight(format!(
                "the drone is not tracked by the motion capture (no pose in {:.1} s): \
                 check its rigid body",
                self.setup.safety.mocap_wait_s
            )));
        };
        if !finite_pose(&BodyPose {
            position_m: m0.position_m,
            heading_rad: m0.heading_rad,
        }) {
            return Err(FlightError::Preflight(
                "the drone's tracked pose is not a number".into(),
            ));
        }
        // Where it takes off from: inside the stage (the failsafe would land it at once),
        // and not under an actor's nose.
        let stage = self.setup.scene.stage;
        let [x, y, _] = m0.position_m;
        // Where it lands again after the shots (`way_home`).
        let take_off_xy = [x, y];
        let (lo, hi) = (stage.min_m(), stage.max_m());
        if !inside(&stage, &[x, y, lo[2].max(hi[2].min(m0.position_m[2]))], 0.0) {
            return Err(FlightError::Preflight(format!(
                "the drone stands at ({x:.2}, {y:.2}) m, outside the stage: place it inside, \
                 below its first framing"
            )));
        }
        let untracked: Vec<&str> = self
            .setup
            .scene
            .actors
            .iter()
            .enumerate()
            .filter(|(i, _)| !matches!(self.frame.actors.get(*i), Some(Some(_))))
            .map(|(_, a)| a.name.as_str())
            .collect();
        if !untracked.is_empty() {
            return Err(FlightError::Preflight(format!(
                "actor{} not tracked by the motion capture: {}",
                if untracked.len() > 1 { "s" } else { "" },
                untracked.join(", ")
            )));
        }
        let safety_m = self.setup.profile.safety.actor_distance_m;
        let spot = Vec3::new(x, y, m0.position_m[2]);
        if let Some((i, into_m)) = self.keepout().deepest_actor(&spot) {
            return Err(FlightError::Preflight(format!(
                "the drone stands {:.2} m from {}; {} keeps {safety_m:.2} m from actors: \
                 place it further away, below its first framing",
                safety_m - into_m,
                self.setup.scene.actors[i].name,
                self.setup.profile.name
            )));
        }
        let telemetry = self.drone.telemetry();
        if telemetry.battery_percent < self.setup.safety.battery_land_percent {
            return Err(FlightError::Preflight(format!(
                "battery at {:.0}%, below the {:.0}% needed to fly: charge or swap it",
                telemetry.battery_percent, self.setup.safety.battery_land_percent
            )));
        }
        // Where the first framing is as solved (the director's reference is kept inside the
        // stage, off a framing that is not).
        let (first, solved, unsolved) = self.probe();
        if let Some(why) = unsolved {
            // Its sample would be where the camera starts (the origin): never flown to.
            return Err(FlightError::Preflight(format!(
                "the first framing cannot be solved against the actors as they stand now \
                 ({why}): put the actors on their marks or change the first shot"
            )));
        }
        let solved: [f64; 3] = solved.into();
        let stage = self.setup.scene.stage;
        if !inside(&stage, &solved, 0.0) {
            return Err(FlightError::Preflight(format!(
                "the first framing puts the drone at ({:.2}, {:.2}, {:.2}) m, outside the \
                 stage: move the actors or change the first shot",
                solved[0], solved[1], solved[2]
            )));
        }
        // …and clear of the actors as they stand now: one off their mark can stand where the
        // first framing puts the drone. (The director would hold the drone at their distance,
        // off the framing, from the first shot on: not a take to start.)
        if let Some((i, into_m)) = self.keepout().deepest_actor(&Vec3::from(solved)) {
            if into_m > APPROACH_TOLERANCE_M {
                let name = &self.setup.scene.actors[i].name;
                return Err(FlightError::Preflight(format!(
                    "the first framing puts the drone {:.2} m from {name} as the actors stand \
                     now; {} keeps {safety_m:.2} m from actors: put {name} on their mark or \
                     change the first shot",
                    safety_m - into_m,
                    self.setup.profile.name
                )));
            }
        }

        // Take-off.
        let take_off_s = t;
        self.event(t, "info", "take_off", "taking off".into());
        self.drone.take_off()?;
        let deadline = t + self.setup.safety.take_off_timeout_s;
        loop {
            t = self.wait_tick(t + self.period_s)?;
            // No reference yet (the drone climbs on its own): the display says so.
            self.observer.progress(&Progress {
                t_s: t,
                phase: Phase::TakeOff,
                shot: None,
                shots: self.setup.script.timeline.len(),
                script_t_s: 0.0,
                script_duration_s: self.script_duration_s,
                position_error_m: None,
            });
            match self.drone.telemetry().state {
                FlightState::Flying => break,
                FlightState::Emergency => {
                    return Err(FlightError::Preflight(
                        "the drone went into emergency during take-off".into(),
                    ))
                }
                _ if t > deadline => {
                    self.drone.land()?;
                    return Err(FlightError::Preflight(format!(
                        "the drone did not report flying within {:.0} s of take-off",
                        self.setup.safety.take_off_timeout_s
                    )));
                }
                _ => {}
            }
        }

        // Approach: from where the drone hovers to the first framing.
        // Where it hovers: its newest measurement (this tick's frame may not have come yet:
        // at 200 Hz against a 100 Hz mocap, the approach set off from the ground pose).
        let here = match self.drone_m.map(|(_, m)| m).or(seen_drone) {
            Some(m) => Sample {
                t_s: t,
                position_m: m.position_m,
                velocity_mps: [0.0; 3],
                acceleration_mps2: [0.0; 3],
                heading_rad: m.heading_rad,
                heading_rate_radps: 0.0,
                camera_pitch_rad: first.camera_pitch_rad,
                shot: 0,
            },
            None => unreachable_measurement(&first, t),
        };
        // Against the actors as they stand now (they may have moved during take-off).
        let first = self.first_framing();
        let keep = self.keepout();
        let glide = Glide::new(t, &here, &first, self.setup.profile, &self.route_keepout());
        let way = glide.way();
        let intrusion_m = keep.route_intrusion_m(&glide.route, &glide.from_m, &glide.to_m);
        self.event(
            t,
            "info",
            "approach",
            format!(
                "flying to the first framing ({:.1} s{way})",
                glide.duration_s
            ),
        );
        if intrusion_m > APPROACH_TOLERANCE_M {
            self.event(
                t,
                "warning",
                "approach_not_clear",
                format!(
                    "no clear way to the first framing from where the drone took off: the \
                     approach comes {intrusion_m:.2} m into an actor's safety distance or the \
                     stage's margin; take off further from the actors and the walls"
                ),
            );
        }
        let mut outcome = Outcome::Done;
        let mut last = glide.sample(t, first.camera_pitch_rad);
        while t < glide.end_s() {
            t = self.wait_tick(t + self.period_s)?;
            last = self.clear_of_actors(glide.sample(t, first.camera_pitch_rad));
            if let Outcome::Land = self.control(t, Phase::Approach, None, &last)? {
                outcome = Outcome::Land;
                break;
            }
        }

        // The settle, and then the shots. The director is placed where the glide ended, and
        // for `SETTLE_S` before "action!" its clock is held at the script's start: the camera
        // steers from there to the first framing as the actors stand now. They moved since
        // the approach was planned (on `scene.psl`'s LS of Bob, the framing up to 0.66 m in
        // 3 s), and the reference once jumped there at "action!" (seed 5: 0.66 m of error,
        // 1.4 % of the ticks saturated). A first framing that no longer solves holds the drone
        // where the glide left it, not at the origin.
        let mut completed = false;
        let mut director = Director::new(self.setup.script, self.setup.scene, self.setup.profile);
        director.actors_measured();
        director.start_from(
            Vec3::from(last.position_m),
            Vec3::from(last.velocity_mps),
            last.heading_rad,
        );
        if let Outcome::Done = outcome {
            // How far the actors have moved the first framing since the approach was planned
            // (the log says so: the settle may not close it all before "action!").
            let (now_first, _, unsolved) = self.probe();
            let message = match unsolved {
                None => format!(
                    "settling on the first framing as the actors stand, {:.2} m from where the \
                     approach flew ({SETTLE_S:.1} s)",
                    (Vec3::from(now_first.position_m) - Vec3::from(last.position_m)).norm()
                ),
                Some(why) => format!(
                    "the first framing does not solve as the actors stand ({why}): holding \
                     where the approach flew until it does"
                ),
            };
            self.event(t, "info", "settle", message);
            // Its last tick one period before "action!", the first shot's at 0 s.
            let action_s = t + SETTLE_S;
            while t < action_s - 1.5 * self.period_s {
                t = self.wait_tick(t + self.period_s)?;
                let sample = Sample {
                    t_s: t,
                    ..director.step(t - action_s, &self.actors.poses)
                };
                last = sample;
                if let Outcome::Land = self.control(t, Phase::Approach, None, &sample)? {
                    outcome = Outcome::Land;
                    break;
                }
            }
        }
        if let Outcome::Done = outcome {
            let action_s = t + self.period_s;
            self.mocap.action(action_s);
            self.event(action_s, "info", "action", "action!".into());
            // The director: on a thread of its own, ahead of the loop, when the mocap knows
            // the actors' future (the simulator); else stepped here, tick by tick.
            let mut stepper = match (self.mocap.actors_ahead(), self.mocap.actors_ahead()) {
                (Some(feed), Some(rewind_feed)) => {
                    let start = AheadStart {
                        director,
                        tracker: &self.actors,
                        frame: &self.frame,
                        last_frame_t_s: self.last_frame_t_s,
                        t_s: t,
                        action_s,
                        period_s: self.period_s,
                    };
                    match Ahead::spawn(start, feed, rewind_feed) {
                        Ok(ahead) => {
                            // Its frames' actors are the loop's: computed once, there.
                            self.mocap.actors_from_feed(true);
                            Stepper::Ahead(ahead)
                        }
                        Err(director) => Stepper::here(*director),
                    }
                }
                _ => Stepper::here(director),
            };
            let mut current: Option<usize> = None;
            // The last shot's findings, when the director finished.
            let mut last_findings = Vec::new();
            loop {
                let t_next = t + self.period_s;
                let tick: &DirectedTick = match &mut stepper {
                    Stepper::Here(director, state, tick) => {
                        t = self.wait_tick(t_next)?;
                        direct(director, state, t, t - action_s, &self.actors.poses, tick);
                        tick
                    }
                    Stepper::Ahead(ahead) => {
                        // The director's tick first: the frame's actors come from it.
                        let next = ahead.next();
                        if next.is_none() {
                            self.mocap.actors_from_feed(false);
                        }
                        let agreed;
                        (t, agreed) = self.wait_tick_fed(t_next, next)?;
                        match next {
                            Some(tick) if agreed && tick.t_s == t => tick,
                            _ => {
                                self.failsafe(
                                    t,
                                    "the director, stepped ahead of the loop, saw other actors \
                                     than the loop (an internal error): landing",
                                );
                                break;
                            }
                        }
                    }
                };
                let sample = tick.sample;
                self.written_t_s = tick.written_t_s;
                // What the director found against the live actors, told as it arises: a
                // framing it cannot solve holds the drone where it is until it solves, which
                // the report alone would show only as a thinner framing figure.
                for d in &tick.diagnostics {
                    self.director_finding(t, d);
                }
                if current != Some(sample.shot) {
                    // The shot before is over: what the monitor found in it.
                    if let Some(over) = current {
                        self.tell_findings(t, &tick.over_findings, over);
                    }
                    current = Some(sample.shot);
                    self.event(
                        t,
                        "info",
                        "shot_start",
                        format!(
                            "shot {} of {}",
                            sample.shot + 1,
                            self.setup.script.timeline.len()
                        ),
                    );
                }
                let mut world_sample = Sample { t_s: t, ..sample };
                // Aim from where the drone is: in a hold, the heading (and gimbal pitch)
                // that frame the live actors from the measured position.
                let usable = self.measured.filter(|m| {
                    m.position_m.iter().all(|x| x.is_finite()) && m.heading_rad.is_finite()
                });
                self.aim(tick.held.as_ref(), t, usable.is_some(), &mut world_sample);
                // The framing as the drone really films it: the measured pose, the camera
                // pitch the reference asks of the gimbal (level without one).
                self.framing.clear();
                if let (Some(m), Some(held)) = (usable, &tick.held) {
                    // Its axes once for every actor projected.
                    let camera = CameraPose {
                        position_m: Vec3::from(m.position_m),
                        heading_rad: m.heading_rad,
                        pitch_rad: world_sample.camera_pitch_rad,
                    }
                    .frame();
                    if held.targets_into(&self.actors.poses, &camera.position_m, &mut self.targets)
                    {
                        for target in &self.targets {
                            self.framing.push(FramingRecord {
                                actor: target.actor,
                                screen: camera.project(&self.lens, &target.point_m),
                                requested: Some(target.screen),
                            });
                        }
                    }
                }
                let finished = tick.finished;
                if finished {
                    last_findings.clone_from(&tick.last_findings);
                }
                last = world_sample;
                if let Outcome::Land =
                    self.control(t, Phase::Shots, Some(sample.shot), &world_sample)?
                {
                    break;
                }
                if finished {
                    completed = true;
                    break;
                }
            }
            // The mocap's frames are whole again (the landing has no director ahead).
            self.mocap.actors_from_feed(false);
            if let Some(last) = current {
                // Over too: the last shot, or the one a failsafe cut short, as the director
                // had it at this tick.
                if !completed {
                    last_findings = match stepper {
                        Stepper::Here(director, ..) => director.shot_findings(last),
                        Stepper::Ahead(ahead) => ahead.rewound().shot_findings(last),
                    };
                }
                self.tell_findings(t, &last_findings, last);
            }
        }

        // Landing: hold the last pose a moment, fly back over the take-off spot, then land.
        self.framing.clear();
        if completed {
            let end = t + HOLD_BEFORE_LANDING_S;
            while t < end {
                t = self.wait_tick(t + self.period_s)?;
                let hold = self.clear_of_actors(hover_sample(t, &last));
                if let Outcome::Land = self.control(t, Phase::Landing, None, &hold)? {
                    completed = false;
                    break;
                }
            }
        }
        if completed {
            if let Some(glide) = self.way_home(t, &last, take_off_xy) {
                let pitch_rad = last.camera_pitch_rad;
                while t < glide.end_s() {
                    t = self.wait_tick(t + self.period_s)?;
                    let home = self.clear_of_actors(glide.sample(t, pitch_rad));
                    if let Outcome::Land = self.control(t, Phase::Landing, None, &home)? {
                        completed = false;
                        break;
                    }
                }
            }
        }
        self.event(t, "info", "landing", "landing".into());
        self.drone.land()?;
        let deadline = t + self.setup.safety.landing_timeout_s;
        let mut cut = false;
        loop {
            t = self.wait_tick(t + self.period_s)?;
            if self.interrupts() >= 2 && !cut {
                cut = true;
                self.failsafe(t, "interrupted twice: emergency motor cut");
                self.drone.emergency()?;
            }
            let state = self.drone.telemetry().state;
            if matches!(state, FlightState::Landed | FlightState::Emergency) {
                self.event(t, "info", "landed", format!("{state:?}").to_lowercase());
                break;
            }
            if t > deadline {
                self.event(
                    t,
                    "error",
                    "landing_timeout",
                    format!(
                        "the drone still reports {state:?} {:.0} s after the landing command",
                        self.setup.safety.landing_timeout_s
                    ),
                );
                break;
            }
        }
        self.event(
            t,
            if completed { "info" } else { "error" },
            "flight_end",
            format!(
                "{} after {:.2} s of flight",
                if completed { "completed" } else { "aborted" },
                t - take_off_s
            ),
        );
        if let Some(e) = self.log_error.take() {
            return Err(FlightError::Log(e));
        }
        let labels = crate::report::shot_labels(self.setup.script, self.setup.source);
        Ok(self.metrics.report(
            &labels,
            Counts {
                completed,
                flight_time_s: t - take_off_s,
                failsafes: self.failsafes,
                director_errors: self.director_errors,
                faults: self.faults,
                deadline_misses: self.deadline_misses,
            },
        ))
    }

    /// One controlled tick: controller, failsafes, command, metrics, record.
    fn control(
        &mut self,
        t: f64,
        phase: Phase,
        shot: Option<usize>,
        sample: &Sample,
    ) -> Result<Outcome, FlightError> {
        let mut outcome = Outcome::Done;
        let dt = match self.last_tick_s {
            Some(t0) => t - t0,
            None => self.period_s,
        };
        let input = TickInput {
            t_s: t,
            dt_s: dt,
            measurement: self.measured,
            reference: reference_of(sample),
        };
        if !self.controller_started {
            // The replay rule: reset with the first tick's measurement at t − Δ.
            match self.measured {
                Some(m) => {
                    self.controller.reset(t - dt, &m);
                    self.controller_started = true;
                }
                None => {
                    // Nothing to start the filters from: hover until the drone is seen.
                    self.drone.hover()?;
                    return Ok(outcome);
                }
            }
        }
        let output = self.controller.tick(&input);
        self.last_tick_s = Some(t);
        let mut command_sent = match &output {
            Ok(o) => o.command,
            Err(fault) => {
                self.faults += 1;
                self.event(
                    t,
                    "error",
                    "fault",
                    format!("controller refused the tick ({fault:?}); hovering"),
                );
                Command::HOVER
            }
        };
        // Failsafes.
        let unseen_s = t - self.last_drone_seen_s;
        if unseen_s >= self.setup.safety.mocap_land_s {
            self.failsafe(t, "the drone has not been tracked for 2 s: landing");
            outcome = Outcome::Land;
        } else if unseen_s >= self.setup.safety.mocap_hover_s {
            if !self.hovering {
                self.failsafe(t, "the drone is not tracked: hovering");
            }
            self.hovering = true;
        } else {
            self.hovering = false;
        }
        // An actor the drone does not see: it cannot keep clear of them (nor frame them).
        // Also while it holds after the shots and flies back to land (`way_home`).
        let mut actor_hover = false;
        if matches!(phase, Phase::Approach | Phase::Shots | Phase::Landing) {
            for i in 0..self.actor_seen_s.len() {
                let unseen_s = t - self.actor_seen_s[i];
                let name = &self.setup.scene.actors[i].name;
                if unseen_s >= self.setup.safety.mocap_land_s {
                    let land = self.setup.safety.mocap_land_s;
                    self.failsafe(
                        t,
                        &format!("actor {name} has not been tracked for {land:.0} s: landing"),
                    );
                    outcome = Outcome::Land;
                } else if unseen_s >= self.setup.safety.mocap_hover_s {
                    if !self.actor_lost[i] {
                        self.actor_lost[i] = true;
                        self.failsafe(t, &format!("actor {name} is not tracked: hovering"));
                    }
                    actor_hover = true;
                } else if self.actor_lost[i] {
                    self.actor_lost[i] = false;
                    self.event(
                        t,
                        "info",
                        "actor_tracked",
                        format!("actor {name} is tracked again: flying on"),
                    );
                }
            }
        }
        if let Some(m) = self.measured {
            // A non-finite pose is the controller's fault (hover for the tick), not a place.
            let finite = m.position_m.iter().all(|x| x.is_finite());
            if finite && !inside(&self.setup.scene.stage, &m.position_m, 0.0) {
                self.failsafe(
                    t,
                    &format!(
                        "the drone left the stage at ({:.2}, {:.2}, {:.2}) m: landing",
                        m.position_m[0], m.position_m[1], m.position_m[2]
                    ),
                );
                outcome = Outcome::Land;
            }
        }
        let telemetry = self.drone.telemetry();
        let battery = telemetry.battery_percent;
        if battery < self.setup.safety.battery_land_percent {
            self.failsafe(t, &format!("battery at {battery:.0}%: landing"));
            outcome = Outcome::Land;
        }
        if telemetry.link_age_s >= self.setup.safety.link_lost_s {
            // Nothing tells us what the drone does: ask it to land, and rely on its own
            // watchdog (it hovers, then lands, without commands) if that does not get through.
            if !self.link_lost {
                self.link_lost = true;
                self.failsafe(
                    t,
                    &format!(
                        "no telemetry from the drone for {:.1} s: landing (the drone's watchdog \
                         lands it if the command is lost too)",
                        telemetry.link_age_s
                    ),
                );
            }
            outcome = Outcome::Land;
        }
        match self.interrupts() {
            0 => {}
            1 => {
                if !self.interrupted {
                    self.interrupted = true;
                    self.failsafe(
                        t,
                        "interrupted (Ctrl-C): landing; press Ctrl-C again to cut the motors",
                    );
                }
                outcome = Outcome::Land;
            }
            _ => {
                self.failsafe(t, "interrupted twice: emergency motor cut");
                self.drone.emergency()?;
                return Ok(Outcome::Land);
            }
        }
        if self.hovering || actor_hover || output.is_err() || matches!(outcome, Outcome::Land) {
            command_sent = Command::HOVER;
            self.drone.hover()?;
        } else {
            self.drone.send(&command_sent)?;
        }

        // Mocap frame in → command out, on the flight clock.
        let latency_s = self
            .fresh
            .then(|| (self.clock.now_s() - self.frame.received_s).max(0.0));
        self.metrics.record(
            phase,
            shot,
            &input,
            &output,
            &self.framing,
            &self.actors.poses,
            latency_s,
        );
        let error = Metrics::tracking_error(&input);
        let state = self.drone.telemetry().state;
        let record = TickRecord {
            phase,
            shot,
            sample,
            input,
            output,
            command_sent,
            mocap: self.fresh.then_some(&self.frame),
            actors: &self.actors.poses,
            framing: &self.framing,
            drone_state: state,
            latency_s,
        };
        if let Err(e) = self.sink.tick(&record) {
            self.log_error.get_or_insert(e);
            self.failsafe(t, "the flight log cannot be written: landing");
            outcome = Outcome::Land;
        }
        self.observer.progress(&Progress {
            t_s: t,
            phase,
            shot,
            shots: self.setup.script.timeline.len(),
            // Not the sample's time, which is the flight's clock (the display once showed the
            // take-off's seconds as script time, and filled its bar before the shots ended).
            script_t_s: self.written_t_s,
            script_duration_s: self.script_duration_s,
            position_error_m: error.map(|e| e.0),
        });
        Ok(outcome)
    }

    fn interrupts(&self) -> u32 {
        self.setup
            .interrupts
            .map_or(0, |n| n.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// The flight back over the take-off spot after the last shot, at the altitude the shots
    /// left the drone, so that it lands where it was set down (clear of the actors' marks then:
    /// the pre-flight check's and the simulator's rule) and not where the last shot ends,
    /// perhaps an arm's length from an actor (a close-up). Along the approach's route rule and
    /// at its pace ([`Glide`]). `None`, the drone landing where it is, when it is already
    /// within [`HOME_RADIUS_M`] of the spot, or when an actor now stands within their safety
    /// distance of the spot (the landing's column, down to the floor) or in the way back
    /// (both told as a warning).
    fn way_home(&mut self, t: f64, last: &Sample, home_xy: [f64; 2]) -> Option<Glide> {
        let here = hover_sample(t, last);
        let [x, y, z] = last.position_m;
        let far_m = dronecine_math::hypot(home_xy[0] - x, home_xy[1] - y);
        if !(far_m >= HOME_RADIUS_M) {
            return None;
        }
        let home = Sample {
            position_m: [home_xy[0], home_xy[1], z],
            ..here
        };
        let safety_m = self.setup.profile.safety.actor_distance_m;
        let keep = self.keepout();
        let pad = Vec3::new(home_xy[0], home_xy[1], 0.0);
        let taken = keep.deepest_actor(&pad);
        let glide = Glide::new(t, &here, &home, self.setup.profile, &self.route_keepout());
        let intrusion_m = keep.route_intrusion_m(&glide.route, &glide.from_m, &glide.to_m);
        if let Some((i, into_m)) = taken {
            let name = &self.setup.scene.actors[i].name;
            let message = format!(
                "{name} stands {:.2} m from the take-off spot; {} keeps {safety_m:.2} m from \
                 actors: landing where the drone is",
                safety_m - into_m,
                self.setup.profile.name
            );
            self.event(t, "warning", "return_not_clear", message);
            return None;
        }
        if intrusion_m > APPROACH_TOLERANCE_M {
            let message = format!(
                "no clear way back to the take-off spot: it comes {intrusion_m:.2} m into an \
                 actor's safety distance or the stage's margin; landing where the drone is"
            );
            self.event(t, "warning", "return_not_clear", message);
            return None;
        }
        let way = glide.way();
        let message = format!(
            "flying back to the take-off spot to land ({far_m:.1} m, {:.1} s{way})",
            glide.duration_s
        );
        self.event(t, "info", "return", message);
        Some(glide)
    }

    /// A planned sample (the approach's and the way home's glides, the hold before landing)
    /// held out of the actors' safety distance as they stand this tick, as the director holds
    /// its goal (`steering::kept_clear`): the glides are planned clear of the actors as they
    /// stood, and an actor who moves after that (a live actor drifting off their mark by a
    /// few centimetres a second) walked into the reference (random script 264: 0.465 m from
    /// B at the approach's end). The sample's position moves out along the line from the
    /// body's nearest point, and its velocity and acceleration lose their inward part. The
    /// distance is the director's on set: the profile's actor distance and its tracking
    /// margin, so that the drone, lagging its reference, keeps the actor distance (with the
    /// actor distance alone, random script 379 flew home 0.464 m from A). A drone that took
    /// off nearer than that has its approach's reference start out at that distance.
    fn clear_of_actors(&mut self, sample: Sample) -> Sample {
        self.bodies.clear();
        self.bodies.extend(self.actors.poses.iter().map(Body::from));
        let kept = steering::kept_clear(
            Kinematics {
                p: Vec3::from(sample.position_m),
                v: Vec3::from(sample.velocity_mps),
                a: Vec3::from(sample.acceleration_mps2),
            },
            Bodies {
                axes: &self.bodies,
                clear_m: self.setup.profile.safety.on_set_m(),
            },
        );
        Sample {
            position_m: kept.p.into(),
            velocity_mps: kept.v.into(),
            acceleration_mps2: kept.a.into(),
            ..sample
        }
    }

    /// Where the drone may go: the stage less its margin, and out of the actors' safety
    /// distance as the actors stand now (the director's and the compiler's routes' rule).
    fn keepout(&self) -> Keepout<'_> {
        let (lo, hi) = route::stage_less_margin(
            &self.setup.scene.stage,
            self.setup.profile.safety.stage_margin_m,
        );
        Keepout {
            lo,
            hi,
            actors: &self.actors.poses,
            passing: &[],
            safety_m: self.setup.profile.safety.actor_distance_m,
            merge: None,
        }
    }

    /// [`Flight::keepout`] for choosing a glide's route: the actors' distance with the
    /// profile's tracking margin, as the director keeps it on set, so that a route that
    /// passes an actor passes where the drone, not only its reference, keeps the distance.
    /// Whether the route is clear is still judged against the distance itself.
    fn route_keepout(&self) -> Keepout<'_> {
        Keepout {
            safety_m: self.setup.profile.safety.on_set_m(),
            ..self.keepout()
        }
    }

    /// The first shot's framing against the actors as they stand now.
    fn first_framing(&self) -> Sample {
        self.probe().0
    }

    /// The first framing against the actors as they stand now: the director's first sample,
    /// its target as solved, and why it did not solve (the director's message), if it did not.
    fn probe(&self) -> (Sample, Vec3, Option<String>) {
        let mut probe = Director::new(self.setup.script, self.setup.scene, self.setup.profile);
        // As the flight's director sees them: measured (the first framing held the tracking
        // margin off an actor it comes near, so that the approach ends where the shots do).
        probe.actors_measured();
        let sample = probe.step(0.0, &self.actors.poses);
        let unsolved = (!probe.placed()).then(|| {
            (probe.diagnostics_so_far().iter().find(|d| d.is_error()))
                .map_or_else(|| "no camera position".to_string(), |d| d.message.clone())
        });
        (sample, probe.solved_target_m(), unsolved)
    }

    /// In a hold, the heading and gimbal pitch that frame the live actors from where the
    /// drone is, into `sample` (else the director's own, smoother heading stays). Aimed anew
    /// on a tick with a fresh measurement (`fresh`), its rate from the previous aim; between
    /// frames (a loop faster than the mocap, a frame dropped) carried on at that rate from
    /// the newest measurement. Before, a tick without a frame fell back to the director's
    /// heading and dropped the rate: at 200 Hz against a 100 Hz mocap every other tick, and
    /// `two-actors.psl`'s heading error went from 0.29° to 2.6° RMS, its framing error
    /// from 0.023 to 0.061.
    fn aim(&mut self, held: Option<&Held>, t: f64, fresh: bool, sample: &mut Sample) {
        let Some((seen_s, m)) = self.drone_m else {
            self.last_aim = None;
            return;
        };
        // A drone not seen this long hovers (its failsafe): nothing to aim from.
        let Some((heading, pitch)) = (t - seen_s < self.setup.safety.mocap_hover_s)
            .then(|| held?.orientation(&self.actors.poses, &Vec3::from(m.position_m)))
            .flatten()
        else {
            self.last_aim = None;
            return;
        };
        match self.last_aim {
            Some(aim) if !fresh => {
                sample.heading_rad =
                    wrap_angle_rad(aim.heading_rad + aim.rate_radps * (t - aim.t_s));
                sample.heading_rate_radps = aim.rate_radps;
            }
            previous => {
                // Its rate from the previous aim (the director's rate is that of its own,
                // smoother heading).
                if let Some(aim) = previous {
                    if t > aim.t_s {
                        sample.heading_rate_radps =
                            wrap_angle_rad(heading - aim.heading_rad) / (t - aim.t_s);
                    }
                }
                sample.heading_rad = heading;
                self.last_aim = Some(Aim {
                    t_s: t,
                    heading_rad: heading,
                    rate_radps: sample.heading_rate_radps,
                });
            }
        }
        sample.camera_pitch_rad = pitch;
    }

    fn failsafe(&mut self, t: f64, message: &str) {
        self.failsafes += 1;
        self.event(t, "error", "failsafe", message.to_string());
    }
}

/// A distance as a warning says it: in metres to the centimetre, or under a centimetre in
/// millimetres (a drone 0.3 mm inside an actor's distance strayed "0.3 mm", not "0.00 m").
fn short_distance(m: f64) -> String {
    if m.abs() < 0.01 {
        format!("{:.1} mm", m * 1000.0)
    } else {
        format!("{m:.2} m")
    }
}

/// The sample to fly when the drone has never been measured (cannot happen after the
/// pre-flight check; kept total instead of panicking).
fn unreachable_measurement(first: &Sample, t: f64) -> Sample {
    hover_sample(t, first)
}

/// What the servo tracks of a reference sample.
fn reference_of(s: &Sample) -> Reference {
    Reference {
        position_m: s.position_m,
        velocity_mps: s.velocity_mps,
        acceleration_mps2: s.acceleration_mps2,
        heading_rad: s.heading_rad,
        heading_rate_radps: s.heading_rate_radps,
    }
}

fn inside(stage: &dronecine_grammar::script::Stage, p: &[f64; 3], margin_m: f64) -> bool {
    let (lo, hi) = (stage.min_m(), stage.max_m());
    (0..3).all(|i| p[i] >= lo[i] + margin_m - 1e-9 && p[i] <= hi[i] - margin_m + 1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_backend::frames::body_to_world;
    use nalgebra::Vector3;

    /// The two conventions agree: the compiler's camera looks along (cos c, sin c), the
    /// drone's body forward axis at heading c; the camera's right is the body's −left.
    #[test]
    fn the_drone_heading_is_the_camera_heading() {
        for c in [-2.5, -0.3, 0.0, 1.0, 3.0] {
            let cam = CameraPose {
                position_m: Default::default(),
                heading_rad: c,
                pitch_rad: 0.0,
            };
            let fwd = body_to_world(c) * Vector3::x();
            assert!((cam.forward() - fwd).norm() < 1e-12);
            // The camera's right is the body's −left.
            let left = body_to_world(c) * Vector3::y();
            assert!((cam.right() + left).norm() < 1e-12);
        }
    }

    #[test]
    fn a_short_distance_is_said_in_millimetres() {
        assert_eq!(short_distance(0.0003), "0.3 mm");
        assert_eq!(short_distance(0.0099), "9.9 mm");
        assert_eq!(short_distance(0.01), "0.01 m");
        assert_eq!(short_distance(0.456), "0.46 m");
    }

    /// Kalata's closed form against the steady state of the Kalman filter it stands for,
    /// iterated to convergence: a position measured with variance σ_n² every `T`, its
    /// acceleration white and held over each step (variance σ_a²). The filter's gain is
    /// `[α, β/T]`.
    #[test]
    fn the_actor_trackers_gains_are_the_kalman_filters_steady_state() {
        for (sigma_a, t, sigma_n) in [
            (TRACK_ACTOR_ACCEL_MPS2, 0.01_f64, TRACK_POSITION_NOISE_M),
            (0.5, 1.0 / 120.0, 0.0003),
            (2.0, 0.05, 0.001),
            (0.1, 0.01, 0.01),
        ] {
            let q = sigma_a * sigma_a;
            let r = sigma_n * sigma_n;
            let (mut p11, mut p12, mut p22) = (1.0, 0.0, 1.0);
            let (mut k1, mut k2) = (0.0, 0.0);
            for _ in 0..200_000 {
                // Predict: P = F·P·Fᵀ + Q.
                let a11 = p11 + 2.0 * t * p12 + t * t * p22 + q * t.powi(4) / 4.0;
                let a12 = p12 + t * p22 + q * t.powi(3) / 2.0;
                let a22 = p22 + q * t * t;
                // Update with the position.
                let s = a11 + r;
                (k1, k2) = (a11 / s, a12 / s);
                (p11, p12, p22) = ((1.0 - k1) * a11, (1.0 - k1) * a12, a22 - k2 * a12);
            }
            let (alpha, beta) = alpha_beta(sigma_a * t * t / sigma_n);
            assert!((alpha - k1).abs() < 1e-9, "α {alpha} against {k1}");
            assert!((beta - k2 * t).abs() < 1e-9, "β {beta} against {}", k2 * t);
        }
        // At 100 Hz with the tracker's own figures.
        let (alpha, beta) = alpha_beta(TRACK_ACTOR_ACCEL_MPS2 * 1e-4 / TRACK_POSITION_NOISE_M);
        assert!((alpha - 0.4375).abs() < 1e-3 && (beta - 0.125).abs() < 1e-3);
    }
}
