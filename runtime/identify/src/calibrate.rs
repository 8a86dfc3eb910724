//! The calibration flight behind `dronecine calibrate`: take off, hold a hover point, and per
//! axis fly open-loop tests around it ([`shape`]): on every axis doublets (+A for T, −A for T)
//! then steps, each sign in turn, followed by a coast at zero input where the drag's τ shows
//! (on roll and pitch a long one, and the step is short: +A for T), recording every tick; land;
//! then fit the model (the [crate root](crate), a prediction-error fit that models the wind, the
//! attitude lag and the latency) and build the profile with the fitted `[model]`
//! ([`identify::ModelFit::apply`]). Each test is a segment of its own; [`report_svg`] draws
//! the calibration report of an axis. Gusts blur τ, so roll and pitch get more tests
//! ([`Plan::tilt_repeats`]).
//!
//! Safety, as the flight loop's: before each test the prior model predicts the test's
//! excursion (times [`EXCURSION_SAFETY`]); a test that would leave the stage's keep-in box
//! (the stage shrunk by the profile's `stage_margin_m`) is flown at half the amplitude, twice
//! at most, else refused. During the flight the drone leaving the keep-in box, losing the
//! mocap for [`MOCAP_LOST_S`], or an interrupt (Ctrl-C counted by the caller) ends it: hover,
//! land, error.
//!
//! Between tests a hover hold (proportional-derivative on the measured position, scaled by
//! the prior model's gains) brings the drone back to the hover point and slows it
//! ([`SETTLED_M`], [`SETTLED_MPS`]) before the next test; only the test windows are fitted,
//! each as its own segment.

use std::fmt;
use std::sync::atomic::{AtomicU32, Ordering};

use dronecine_grammar::script::Stage;
use dronecine_profile::Profile;

use crate::{self as identify, Axis, FitError, ModelFit, Sample, Segment};
use dronecine_backend::frames::{self, Command};
use dronecine_backend::Backends;
use dronecine_backend::{BackendError, FlightState, MocapFrame};

/// The predicted excursion is multiplied by this before the stage check (the prior may be
/// wrong by this much).
pub const EXCURSION_SAFETY: f64 = 1.5;
/// Mocap lost this long → land.
pub const MOCAP_LOST_S: f64 = 0.5;
/// A test ends early (the hold takes over) when the drone comes this close to the keep-in
/// box's sides, or to its floor and ceiling; the recorded part is still fitted. Crossing the
/// box itself lands the drone. Horizontally the drone may be gliding at a metre a second
/// (the hold needs about half a metre to stop it); vertically it is slow.
pub const TEST_FENCE_M: [f64; 3] = [0.8, 0.8, 0.3];

/// A test starts once the hold has the drone this close to the hover point and this slow.
pub const SETTLED_M: f64 = 0.15;
pub const SETTLED_MPS: f64 = 0.1;

/// What to fly.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub axes: Vec<Axis>,
    /// Control rate, Hz.
    pub rate_hz: f64,
    /// Doublet amplitudes: tilt (rad), vertical speed (m/s), yaw rate (rad/s).
    pub tilt_rad: f64,
    pub vz_mps: f64,
    pub yaw_rate_radps: f64,
    /// Each half of a doublet, seconds.
    pub half_s: f64,
    /// Input 0 after the doublet, seconds (recorded).
    pub coast_s: f64,
    /// Hover hold before each test, seconds.
    pub settle_s: f64,
    /// Tests per axis on the vertical and yaw axes: doublets +, −, then steps +, − (the
    /// vertical axis: steps only), in turn.
    pub repeats: usize,
    /// Tests per axis on roll and pitch: the drag's τ is slow (≈ 1.7 s) and gusts blur it, so
    /// these axes need more of them than the others.
    pub tilt_repeats: usize,
    /// Height of the hover point, metres (clamped into the keep-in box).
    pub hover_height_m: f64,
}

impl Default for Plan {
    fn default() -> Plan {
        Plan {
            axes: Axis::ALL.to_vec(),
            rate_hz: 100.0,
            tilt_rad: 0.08,
            vz_mps: 0.3,
            yaw_rate_radps: 0.5,
            half_s: 1.5,
            coast_s: 4.0,
            settle_s: 4.0,
            repeats: 4,
            tilt_repeats: 12,
            hover_height_m: 1.3,
        }
    }
}

#[derive(Debug)]
pub enum CalibrateError {
    Backend(BackendError),
    /// The stage cannot hold a test even at a quarter of its amplitude.
    StageTooSmall(Axis),
    /// The drone left the keep-in box; it was landed.
    Geofence {
        position_m: [f64; 3],
    },
    /// No mocap for too long; the drone was landed.
    MocapLost,
    /// Take-off or landing did not finish in time.
    Timeout(&'static str),
    /// Ctrl-C: the drone was landed.
    Interrupted,
    BadPlan(String),
}

impl fmt::Display for CalibrateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CalibrateError::Backend(e) => write!(f, "backend: {e}"),
            CalibrateError::StageTooSmall(a) => write!(
                f,
                "the stage is too small for the {} test even at a quarter of its amplitude",
                a.name()
            ),
            CalibrateError::Geofence { position_m: p } => write!(
                f,
                "the drone left the stage's keep-in box at ({:.2}, {:.2}, {:.2}) m; landed",
                p[0], p[1], p[2]
            ),
            CalibrateError::MocapLost => write!(f, "the mocap lost the drone; landed"),
            CalibrateError::Timeout(what) => write!(f, "{what} did not finish in time"),
            CalibrateError::Interrupted => write!(f, "interrupted; landed"),
            CalibrateError::BadPlan(m) => write!(f, "bad calibration plan: {m}"),
        }
    }
}

impl std::error::Error for CalibrateError {}

impl From<BackendError> for CalibrateError {
    fn from(e: BackendError) -> Self {
        CalibrateError::Backend(e)
    }
}

/// A calibration's outcome: the recorded tests, the fits, and the profile when every fitted
/// axis passed.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub tests: Vec<(Axis, Segment)>,
    pub fit: ModelFit,
    pub errors: Vec<FitError>,
    /// `Some` only when `errors` is empty.
    pub profile: Option<Profile>,
}

/// Flies the tests, then fits. `prior` gives the hold's gains, the stage margin and every
/// section the calibration does not measure.
pub fn calibrate(
    backends: Backends<'_>,
    stage: &Stage,
    prior: &Profile,
    plan: &Plan,
    interrupts: Option<&AtomicU32>,
) -> Result<Calibration, CalibrateError> {
    let tests = fly_tests(backends, stage, prior, plan, interrupts)?;
    Ok(fit_tests(tests, prior, &plan.axes))
}

/// Fits the recorded tests: each axis on its own tests.
pub fn fit_tests(tests: Vec<(Axis, Segment)>, prior: &Profile, axes: &[Axis]) -> Calibration {
    let mut fit = ModelFit::default();
    let mut errors = Vec::new();
    for &axis in axes {
        let segs: Vec<Segment> = tests
            .iter()
            .filter(|(a, _)| *a == axis)
            .map(|(_, s)| s.clone())
            .collect();
        match identify::fit_axis(&segs, axis) {
            Ok(a) => match axis {
                Axis::Roll => fit.roll = Some(a),
                Axis::Pitch => fit.pitch = Some(a),
                Axis::Vz => fit.vz = Some(a),
                Axis::Yaw => fit.yaw = Some(a),
            },
            Err(e) => errors.push(e),
        }
    }
    let profile = errors.is_empty().then(|| fit.apply(prior));
    Calibration {
        tests,
        fit,
        errors,
        profile,
    }
}

struct Flyer<'a, 'b> {
    b: Backends<'a>,
    frame: MocapFrame,
    dt: f64,
    t: f64,
    last_seen_s: f64,
    last: Option<([f64; 3], f64)>,
    lo: [f64; 3],
    hi: [f64; 3],
    prior: &'b Profile,
    interrupts: Option<&'b AtomicU32>,
    /// Velocity estimate (smoothed differences) for the hold's damping.
    vel: [f64; 3],
}

impl Flyer<'_, '_> {
    /// Advances one tick and reads the mocap: the measured pose, if any.
    fn tick(&mut self) -> Result<Option<([f64; 3], f64)>, CalibrateError> {
        self.t += self.dt;
        self.b.clock.sleep_until(self.t);
        let fresh = self.b.mocap.poll(&mut self.frame)?;
        let pose = if fresh {
            self.frame.drone.map(|d| (d.position_m, d.heading_rad))
        } else {
            None
        };
        if let Some((p, _)) = pose {
            if let Some((q, _)) = self.last {
                let a = 0.15;
                for i in 0..3 {
                    self.vel[i] += a * ((p[i] - q[i]) / self.dt - self.vel[i]);
                }
            }
            self.last_seen_s = self.t;
            self.last = pose;
        }
        Ok(pose)
    }

    /// The safety checks of every airborne tick.
    fn guard(&mut self, pose: Option<([f64; 3], f64)>) -> Result<(), CalibrateError> {
        let err = if self
            .interrupts
            .is_some_and(|i| i.load(Ordering::Relaxed) > 0)
        {
            Some(CalibrateError::Interrupted)
        } else if self.t - self.last_seen_s > MOCAP_LOST_S {
            Some(CalibrateError::MocapLost)
        } else if let Some((p, _)) = pose {
            let out = (0..3).any(|i| p[i] < self.lo[i] || p[i] > self.hi[i]);
            out.then_some(CalibrateError::Geofence { position_m: p })
        } else {
            None
        };
        match err {
            Some(e) => {
                let _ = self.b.drone.hover();
                self.land();
                Err(e)
            }
            None => Ok(()),
        }
    }

    fn land(&mut self) {
        let _ = self.b.drone.land();
        let end = self.t + 15.0;
        while self.t < end {
            self.t += self.dt;
            self.b.clock.sleep_until(self.t);
            // Read on: a drone whose estimator the motion capture feeds (a Crazyflie, an
            // ArduPilot's EKF) is sent each pose read, in the landing too.
            let _ = self.b.mocap.poll(&mut self.frame);
            if self
                .interrupts
                .is_some_and(|i| i.load(Ordering::Relaxed) > 1)
            {
                let _ = self.b.drone.emergency();
                return;
            }
            if matches!(
                self.b.drone.telemetry().state,
                FlightState::Landed | FlightState::Emergency
            ) {
                return;
            }
        }
    }

    /// Back at `home` and slow (within [`SETTLED_M`] and [`SETTLED_MPS`]).
    fn settled(&self, home: ([f64; 3], f64)) -> bool {
        self.last.is_some_and(|(p, _)| {
            let d = (0..3).map(|i| (p[i] - home.0[i]).powi(2)).sum::<f64>();
            let v = self.vel.iter().map(|v| v * v).sum::<f64>();
            d.sqrt() < SETTLED_M && v.sqrt() < SETTLED_MPS
        })
    }

    /// The hover hold's command toward `home` (position and heading).
    fn hold(&self, home: ([f64; 3], f64)) -> Command {
        let Some((p, c)) = self.last else {
            return Command::HOVER;
        };
        let m = &self.prior.model;
        let (kp, kd) = (0.6, 0.8);
        let want: Vec<f64> = (0..3)
            .map(|i| kp * (home.0[i] - p[i]) - kd * self.vel[i])
            .collect();
        let vw = nalgebra::Vector3::new(want[0], want[1], want[2]);
        let vb = frames::body_to_world(c).transpose() * vw; // forward, left, up
        let l = &self.prior.limits;
        let clamp = |x: f64, m: f64| x.clamp(-m, m);
        // forward = −K_θ θ, left = −K_φ φ, up = K_ż ż.
        Command {
            roll_rad: clamp(-vb.y / m.gain_roll_mps_per_rad, 0.5 * l.tilt_max_rad),
            pitch_rad: clamp(-vb.x / m.gain_pitch_mps_per_rad, 0.5 * l.tilt_max_rad),
            vz_mps: clamp(vb.z / m.gain_vz, 0.5 * l.vz_max_mps),
            yaw_rate_radps: clamp(
                frames::yaw_rate_command_radps(
                    1.0 * frames::wrap_angle_rad(home.1 - c) / m.gain_yaw,
                ),
                0.5 * l.yaw_rate_max_radps,
            ),
        }
    }
}

/// A test's input shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// +A for `half_s`, −A for `half_s`, then 0.
    Doublet,
    /// +A for `2·half_s`, then 0.
    Step,
    /// +A for `half_s`, then 0: the step of roll and pitch (a tilt held longer builds a
    /// speed that carries the drone across the stage while it coasts).
    ShortStep,
}

/// The shape of test `rep` on `axis`: every axis gets doublets and steps, each sign in turn.
/// Roll and pitch (`repeats` tests): doublets, the last two short steps
/// ([`Shape::ShortStep`]) when there are four tests or more: the doublet's + and − halves
/// separate the drag's τ from the gain better under gusts than steps do. The vertical axis
/// and yaw: doublets (tests 0 and 1 of each four), then steps (2 and 3); a vertical doublet
/// holds a climb and a descent, which the AR.Drone answers with different
/// gains, and gives the fit's descent gain its best window.
pub fn shape(axis: Axis, rep: usize, repeats: usize) -> Shape {
    match axis {
        Axis::Roll | Axis::Pitch if repeats >= 4 && rep + 2 >= repeats => Shape::ShortStep,
        Axis::Roll | Axis::Pitch => Shape::Doublet,
        _ if rep % 4 < 2 => Shape::Doublet,
        Axis::Vz | Axis::Yaw => Shape::Step,
    }
}

/// The test input at time `s` into it.
fn test_input(shape: Shape, s: f64, amp: f64, half_s: f64) -> f64 {
    match shape {
        Shape::Doublet if s < half_s => amp,
        Shape::Doublet if s < 2.0 * half_s => -amp,
        Shape::Step if s < 2.0 * half_s => amp,
        Shape::ShortStep if s < half_s => amp,
        _ => 0.0,
    }
}

/// The prior model's largest displacement (body axis) over a doublet from rest.
fn predicted_excursion(k: f64, tau: f64, amp: f64, plan: &Plan, shape: Shape) -> f64 {
    let h = 0.01;
    let (mut v, mut s, mut max) = (0.0f64, 0.0f64, 0.0f64);
    let total = 2.0 * plan.half_s + plan.coast_s;
    let mut t = 0.0;
    while t < total {
        let u = test_input(shape, t, amp, plan.half_s);
        v += h * (k * u - v) / tau;
        s += h * v;
        max = max.max(s.abs());
        t += h;
    }
    // After the test the hold brings it back; allow one more τ of coasting at the end speed.
    max.max((s + v * tau).abs())
}

fn command_for(axis: Axis, x: f64) -> Command {
    let mut c = Command::HOVER;
    match axis {
        Axis::Roll => c.roll_rad = x,
        Axis::Pitch => c.pitch_rad = x,
        Axis::Vz => c.vz_mps = x,
        Axis::Yaw => c.yaw_rate_radps = x,
    }
    c
}

/// Takes off, flies the plan's tests, lands; the recorded test windows.
pub fn fly_tests(
    backends: Backends<'_>,
    stage: &Stage,
    prior: &Profile,
    plan: &Plan,
    interrupts: Option<&AtomicU32>,
) -> Result<Vec<(Axis, Segment)>, CalibrateError> {
    if !(plan.rate_hz > 0.0 && plan.rate_hz <= 1000.0 && plan.half_s > 0.0) {
        return Err(CalibrateError::BadPlan(
            "rate and durations must be positive".into(),
        ));
    }
    let (lo, hi) = keep_in_box(stage, prior);
    let mut f = Flyer {
        b: backends,
        frame: MocapFrame::default(),
        dt: 1.0 / plan.rate_hz,
        t: 0.0,
        last_seen_s: 0.0,
        last: None,
        lo,
        hi,
        prior,
        interrupts,
        vel: [0.0; 3],
    };
    f.t = f.b.clock.now_s();
    f.last_seen_s = f.t;
    f.take_off()?;
    let Some(start) = f.last else {
        f.land();
        return Err(CalibrateError::MocapLost);
    };
    // Not `clamp`, which panics on a stage too low for the floor of 0.5 m: there the
    // ceiling wins, and the keep-in box refuses the test.
    let hz = plan.hover_height_m.max(lo[2].max(0.5)).min(hi[2]);
    let home = ([start.0[0], start.0[1], hz], start.1);
    let mut tests = Vec::new();
    for &axis in &plan.axes {
        let repeats = match axis {
            Axis::Roll | Axis::Pitch => plan.tilt_repeats,
            Axis::Vz | Axis::Yaw => plan.repeats,
        };
        for rep in 0..repeats.max(1) {
            f.settle(home, plan.settle_s)?;
            let sign = if rep % 2 == 0 { 1.0 } else { -1.0 };
            let sh = shape(axis, rep, repeats);
            let Some(amp) = f.test_amplitude(axis, sh, home, plan) else {
                f.land();
                return Err(CalibrateError::StageTooSmall(axis));
            };
            let seg = f.record_test(axis, sh, sign * amp, plan)?;
            tests.push((axis, seg));
        }
    }
    // Back home, then land.
    let end = f.t + plan.settle_s;
    while f.t < end {
        f.hold_tick(home)?;
    }
    f.land();
    if f.b.drone.telemetry().state != FlightState::Landed {
        return Err(CalibrateError::Timeout("landing"));
    }
    Ok(tests)
}

/// The keep-in box: the stage shrunk by the profile's stage margin, its floor just below the
/// ground.
fn keep_in_box(stage: &Stage, prior: &Profile) -> ([f64; 3], [f64; 3]) {
    let margin = prior.safety.stage_margin_m;
    let (mut lo, mut hi) = (stage.min_m(), stage.max_m());
    for i in 0..3 {
        lo[i] += margin;
        hi[i] -= margin;
    }
    lo[2] = -0.1; // the floor itself (take-off and landing; mocap noise around z = 0)
    (lo, hi)
}

/// The prior model's predicted excursion of a test at amplitude `amp`, and the world
/// direction it moves the drone in (none for yaw).
fn excursion(
    m: &dronecine_profile::Model,
    axis: Axis,
    heading: f64,
    amp: f64,
    plan: &Plan,
    sh: Shape,
) -> (f64, [f64; 3]) {
    match axis {
        Axis::Roll => {
            let d = frames::body_to_world(heading) * nalgebra::Vector3::y();
            (
                predicted_excursion(m.gain_roll_mps_per_rad, m.tau_roll_s, amp, plan, sh),
                [d.x, d.y, 0.0],
            )
        }
        Axis::Pitch => {
            let d = frames::body_to_world(heading) * nalgebra::Vector3::x();
            (
                predicted_excursion(m.gain_pitch_mps_per_rad, m.tau_pitch_s, amp, plan, sh),
                [d.x, d.y, 0.0],
            )
        }
        Axis::Vz => (
            predicted_excursion(m.gain_vz, m.tau_vz_s, amp, plan, sh),
            [0.0, 0.0, 1.0],
        ),
        Axis::Yaw => (0.0, [0.0; 3]),
    }
}

impl Flyer<'_, '_> {
    /// Takes off and waits until the drone flies, the safety checks running.
    fn take_off(&mut self) -> Result<(), CalibrateError> {
        self.b.drone.take_off()?;
        let deadline = self.t + 10.0;
        loop {
            let pose = self.tick()?;
            self.guard(pose)?;
            if self.b.drone.telemetry().state == FlightState::Flying {
                return Ok(());
            }
            if self.t > deadline {
                self.land();
                return Err(CalibrateError::Timeout("take-off"));
            }
        }
    }

    /// One tick of the hover hold toward `home`.
    fn hold_tick(&mut self, home: ([f64; 3], f64)) -> Result<(), CalibrateError> {
        let pose = self.tick()?;
        self.guard(pose)?;
        let c = self.hold(home);
        self.b.drone.send(&c)?;
        Ok(())
    }

    /// Holds at `home` for at least `settle_s`, then until back and slow (three times that at
    /// most), so that every test starts with the stage's room around it.
    fn settle(&mut self, home: ([f64; 3], f64), settle_s: f64) -> Result<(), CalibrateError> {
        let (start, end) = (self.t, self.t + settle_s);
        while self.t < end || (!self.settled(home) && self.t < start + 3.0 * settle_s) {
            self.hold_tick(home)?;
        }
        Ok(())
    }

    /// Distance to the keep-in box along ±`dir` from `here` (the smaller side).
    fn room(&self, here: [f64; 3], dir: [f64; 3]) -> f64 {
        let mut r = f64::INFINITY;
        for i in 0..3 {
            if dir[i].abs() > 1e-9 {
                r = r.min((self.hi[i] - here[i]) / dir[i].abs());
                r = r.min((here[i] - self.lo[i]) / dir[i].abs());
            }
        }
        r
    }

    /// The plan's amplitude of a test on `axis`, halved (twice at most) until the prior's
    /// predicted excursion fits the keep-in box from where the drone is; `None` when even the
    /// quarter does not fit.
    fn test_amplitude(
        &self,
        axis: Axis,
        sh: Shape,
        home: ([f64; 3], f64),
        plan: &Plan,
    ) -> Option<f64> {
        let base = match axis {
            Axis::Roll | Axis::Pitch => plan.tilt_rad,
            Axis::Vz => plan.vz_mps,
            Axis::Yaw => plan.yaw_rate_radps,
        };
        let here = self.last.map_or(home.0, |l| l.0);
        let heading = self.last.map_or(home.1, |l| l.1);
        let mut amp = base;
        for _ in 0..3 {
            let (need, dir) = excursion(&self.prior.model, axis, heading, amp, plan, sh);
            if need * EXCURSION_SAFETY <= self.room(here, dir) {
                return Some(amp);
            }
            amp *= 0.5;
        }
        None
    }

    /// Flies one test open loop at signed amplitude `amp` and records it; the test ends early
    /// when the drone comes within [`TEST_FENCE_M`] of the keep-in box.
    fn record_test(
        &mut self,
        axis: Axis,
        sh: Shape,
        amp: f64,
        plan: &Plan,
    ) -> Result<Segment, CalibrateError> {
        let mut seg = Segment::new();
        let t0 = self.t;
        let total = 2.0 * plan.half_s + plan.coast_s;
        let mut pose = self.last;
        loop {
            let s = self.t - t0;
            if s > total + 1e-9 {
                break;
            }
            let c = command_for(axis, test_input(sh, s, amp, plan.half_s));
            self.b.drone.send(&c)?;
            seg.push(Sample {
                t_s: self.t,
                command: c,
                position_m: pose.map(|p| p.0),
                heading_rad: pose.map(|p| p.1),
            });
            pose = self.tick()?;
            self.guard(pose)?;
            if let Some((p, _)) = pose {
                if self.near_fence(p) {
                    break;
                }
            }
        }
        Ok(seg)
    }

    /// Whether `p` is within [`TEST_FENCE_M`] of the keep-in box's sides, floor or ceiling.
    fn near_fence(&self, p: [f64; 3]) -> bool {
        // The floor counts from z = 0 (the box's floor is below it for landing).
        let floor = [self.lo[0], self.lo[1], self.lo[2].max(0.0)];
        (0..3).any(|i| p[i] < floor[i] + TEST_FENCE_M[i] || p[i] > self.hi[i] - TEST_FENCE_M[i])
    }
}

/// The calibration report of one axis (SVG): per test (up to four), the measured response
/// (body-axis position, or the unwrapped heading) against the fitted model's and the previous
/// profile's, each with its initial state and a steady wind fitted to the test by least
/// squares, both driven by the input as the fit says the drone applied it
/// ([`identify::as_applied`]: latency, attitude lag, descent gain), so that the two curves
/// differ by K and τ alone; the fitted values ± 95 % next to the previous ones in the title.
/// `None` when the axis has no fit.
pub fn report_svg(
    axis: Axis,
    segments: &[&Segment],
    fit: &identify::AxisFit,
    previous: &Profile,
) -> Option<String> {
    use dronecine_preview::svg::{Anchor, Svg};
    let m = &previous.model;
    let (k_prev, tau_prev) = previous_values(axis, m);
    let prev_fit = identify::AxisFit {
        gain: identify::Estimate {
            value: k_prev,
            ci95: 0.0,
        },
        tau_s: tau_prev.map(|t| identify::Estimate {
            value: t,
            ci95: 0.0,
        }),
        ..fit.clone()
    };
    let shown = report_curves(axis, segments, fit, &prev_fit, m);
    if shown.is_empty() {
        return None;
    }
    let (w, panel_h, top) = (900.0, 200.0, 70.0);
    let mut svg = Svg::new(w, top + panel_h * shown.len() as f64 + 20.0);
    let unit = if axis == Axis::Yaw { "rad" } else { "m" };
    let title = report_title(axis, fit, k_prev, tau_prev);
    let how = report_how(axis);
    svg.text(20.0, 28.0, 15.0, Anchor::Start, "#222222", &title);
    svg.text(
        20.0,
        52.0,
        12.0,
        Anchor::Start,
        "#666666",
        &format!(
            "measured (black), fitted (blue), previous (red, dashed): {how}; {unit} against s"
        ),
    );
    for (i, (fitted, prev)) in shown.iter().enumerate() {
        let y0 = top + panel_h * i as f64;
        let panel = Panel::new(y0, w, panel_h, fitted, prev);
        panel.draw_frame(&mut svg);
        panel.draw_curves(&mut svg, fitted, prev);
    }
    Some(svg.finish())
}

/// The previous profile's gain and time constant of `axis` (yaw has no time constant).
fn previous_values(axis: Axis, m: &dronecine_profile::Model) -> (f64, Option<f64>) {
    match axis {
        Axis::Roll => (m.gain_roll_mps_per_rad, Some(m.tau_roll_s)),
        Axis::Pitch => (m.gain_pitch_mps_per_rad, Some(m.tau_pitch_s)),
        Axis::Vz => (m.gain_vz, Some(m.tau_vz_s)),
        Axis::Yaw => (m.gain_yaw, None),
    }
}

/// A report curve: (time, measured, model) per sample.
type Curve = Vec<(f64, Option<f64>, f64)>;

/// The curves of a roll or pitch test that turns, in world x and y, from the joint model at
/// gain `k` and time constant `tau` on `axis` (the other axis at the previous profile's
/// values).
fn plane_curves(
    axis: Axis,
    m: &dronecine_profile::Model,
    s: &Segment,
    k: f64,
    tau: f64,
) -> Option<[Curve; 2]> {
    let (own, other) = match axis {
        Axis::Roll => ((k, tau), (m.gain_pitch_mps_per_rad, m.tau_pitch_s)),
        _ => ((k, tau), (m.gain_roll_mps_per_rad, m.tau_roll_s)),
    };
    let (r, p) = if axis == Axis::Roll {
        (own, other)
    } else {
        (other, own)
    };
    let v = identify::simulate_plane(s, r, p)?;
    Some([0, 1].map(|i| {
        v.iter()
            .map(|(t, y, mdl)| (*t, y.map(|y| y[i]), mdl[i]))
            .collect()
    }))
}

/// A panel per test (the first four): the curves of the fit and of the previous profile, each
/// on the input as the fit says the drone applied it.
fn report_curves(
    axis: Axis,
    segments: &[&Segment],
    fit: &identify::AxisFit,
    prev_fit: &identify::AxisFit,
    m: &dronecine_profile::Model,
) -> Vec<(Vec<Curve>, Vec<Curve>)> {
    let (k_prev, tau_prev) = (prev_fit.gain.value, prev_fit.tau_s.map(|t| t.value));
    segments
        .iter()
        .take(4)
        .map(|s| identify::as_applied(s, fit))
        .filter_map(|applied| {
            let s = &applied;
            match (
                identify::simulate_fit(s, fit),
                identify::simulate_fit(s, prev_fit),
            ) {
                (Some(a), Some(b)) => Some((vec![a], vec![b])),
                _ if matches!(axis, Axis::Roll | Axis::Pitch) => {
                    let t = fit.tau_s?.value;
                    let a = plane_curves(axis, m, s, fit.gain.value, t)?;
                    let b = plane_curves(axis, m, s, k_prev, tau_prev?)?;
                    Some((a.to_vec(), b.to_vec()))
                }
                _ => None,
            }
        })
        .collect()
}

/// What the report's curves fit to each test, by axis.
fn report_how(axis: Axis) -> &'static str {
    match axis {
        Axis::Yaw => "start heading fitted",
        Axis::Vz => "start and steady drift fitted, latency and descent gain as fitted",
        Axis::Roll | Axis::Pitch => {
            "start and steady wind fitted, latency and attitude lag as fitted"
        }
    }
}

/// The report's title: the fitted values ± 95 % next to the previous ones, and R².
fn report_title(axis: Axis, fit: &identify::AxisFit, k_prev: f64, tau_prev: Option<f64>) -> String {
    match fit.tau_s {
        Some(t) => format!(
            "{}: K = {:.4} ± {:.4} (previous {:.4}), τ = {:.4} ± {:.4} s (previous {:.4} s), R² = {:.4}",
            axis.name(),
            fit.gain.value,
            fit.gain.ci95,
            k_prev,
            t.value,
            t.ci95,
            tau_prev.unwrap_or(f64::NAN),
            fit.r2
        ),
        None => format!(
            "{}: K = {:.4} ± {:.4} (previous {:.4}), R² = {:.4}",
            axis.name(),
            fit.gain.value,
            fit.gain.ci95,
            k_prev,
            fit.r2
        ),
    }
}

/// One test's panel of the report: its box on the page and the time and value ranges it
/// shows.
struct Panel {
    x_lo: f64,
    x_hi: f64,
    y_lo: f64,
    y_hi: f64,
    t0: f64,
    t1: f64,
    lo: f64,
    hi: f64,
}

impl Panel {
    /// The panel whose top is at `y0`, spanning every value of its curves with 5 % to spare.
    fn new(y0: f64, w: f64, panel_h: f64, fitted: &[Curve], prev: &[Curve]) -> Panel {
        let (x_lo, x_hi) = (80.0, w - 20.0);
        let (y_lo, y_hi) = (y0 + panel_h - 30.0, y0 + 10.0);
        let t0 = fitted[0].first().map_or(0.0, |p| p.0);
        let t1 = fitted[0].last().map_or(1.0, |p| p.0).max(t0 + 1e-6);
        let vals = fitted
            .iter()
            .flatten()
            .flat_map(|p| [p.1.unwrap_or(p.2), p.2])
            .chain(prev.iter().flatten().map(|p| p.2));
        let (mut lo, mut hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        if !(hi > lo) {
            hi = lo + 1e-3;
        }
        let pad = 0.05 * (hi - lo);
        lo -= pad;
        hi += pad;
        Panel {
            x_lo,
            x_hi,
            y_lo,
            y_hi,
            t0,
            t1,
            lo,
            hi,
        }
    }

    /// The page x of time `t`.
    fn px(&self, t: f64) -> f64 {
        self.x_lo + (t - self.t0) / (self.t1 - self.t0) * (self.x_hi - self.x_lo)
    }

    /// The page y of value `v`.
    fn py(&self, v: f64) -> f64 {
        self.y_lo + (v - self.lo) / (self.hi - self.lo) * (self.y_hi - self.y_lo)
    }

    /// The panel's box and its value and time labels.
    fn draw_frame(&self, svg: &mut dronecine_preview::svg::Svg) {
        use dronecine_preview::svg::{Anchor, Style};
        let (x_lo, x_hi, y_lo, y_hi) = (self.x_lo, self.x_hi, self.y_lo, self.y_hi);
        let (t0, t1, lo, hi) = (self.t0, self.t1, self.lo, self.hi);
        svg.rect(
            x_lo,
            y_hi,
            x_hi - x_lo,
            y_lo - y_hi,
            &Style::stroke("#cccccc", 1.0),
        );
        svg.text(
            x_lo - 6.0,
            y_hi + 10.0,
            11.0,
            Anchor::End,
            "#666666",
            &format!("{hi:.3}"),
        );
        svg.text(
            x_lo - 6.0,
            y_lo,
            11.0,
            Anchor::End,
            "#666666",
            &format!("{lo:.3}"),
        );
        svg.text(
            x_lo,
            y_lo + 16.0,
            11.0,
            Anchor::Start,
            "#666666",
            &format!("{t0:.1} s"),
        );
        svg.text(
            x_hi,
            y_lo + 16.0,
            11.0,
            Anchor::End,
            "#666666",
            &format!("{t1:.1} s"),
        );
    }

    /// The measured, fitted and previous curves, and a note when they are in world x and y.
    fn draw_curves(&self, svg: &mut dronecine_preview::svg::Svg, fitted: &[Curve], prev: &[Curve]) {
        use dronecine_preview::svg::{Anchor, Style};
        for (fitted, prev) in fitted.iter().zip(prev) {
            let measured: Vec<[f64; 2]> = fitted
                .iter()
                .filter_map(|p| p.1.map(|v| [self.px(p.0), self.py(v)]))
                .collect();
            let model: Vec<[f64; 2]> = fitted
                .iter()
                .map(|p| [self.px(p.0), self.py(p.2)])
                .collect();
            let before: Vec<[f64; 2]> = prev.iter().map(|p| [self.px(p.0), self.py(p.2)]).collect();
            svg.polyline(&measured, &Style::stroke("#222222", 2.5));
            svg.polyline(&model, &Style::stroke("#1f77b4", 1.5));
            svg.polyline(&before, &Style::stroke("#d62728", 1.5).dashed("6 4"));
        }
        if fitted.len() == 2 {
            svg.text(
                0.5 * (self.x_lo + self.x_hi),
                self.y_lo + 16.0,
                11.0,
                Anchor::Middle,
                "#666666",
                "world x and y (the drone turns)",
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_axis_gets_doublets_and_steps_of_both_signs() {
        let plan = Plan::default();
        for axis in Axis::ALL {
            let repeats = match axis {
                Axis::Roll | Axis::Pitch => plan.tilt_repeats,
                Axis::Vz | Axis::Yaw => plan.repeats,
            };
            let shapes: Vec<(Shape, bool)> = (0..repeats)
                .map(|rep| (shape(axis, rep, repeats), rep % 2 == 0))
                .collect();
            for positive in [true, false] {
                assert!(shapes.contains(&(Shape::Doublet, positive)), "{axis:?}");
                let step = shapes
                    .iter()
                    .any(|&(s, p)| p == positive && matches!(s, Shape::Step | Shape::ShortStep));
                assert!(step, "{axis:?}: {shapes:?}");
            }
        }
        // A tilt step is released after half_s; the others are held for the doublet's length.
        assert_eq!(test_input(Shape::ShortStep, 1.0, 0.1, 1.5), 0.1);
        assert_eq!(test_input(Shape::ShortStep, 1.6, 0.1, 1.5), 0.0);
        assert_eq!(test_input(Shape::Step, 2.9, 0.1, 1.5), 0.1);
        assert_eq!(test_input(Shape::Doublet, 2.9, 0.1, 1.5), -0.1);
        assert_eq!(test_input(Shape::Doublet, 3.1, 0.1, 1.5), 0.0);
    }
}
