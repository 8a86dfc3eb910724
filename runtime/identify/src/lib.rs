//! System identification of the servo's model from a measured response:
//! the fit behind `dronecine calibrate` and `dronecine identify`. Pure functions, no I/O.
//!
//! **Data.** A [`Segment`] is a run of [`Sample`]s: at `t_s` the mocap measured the pose
//! (or nothing, on a dropout) and the command then held until the next sample was sent.
//! Each segment has its own unknown initial position and velocity, so segments may be cut
//! anywhere (a test window, a few seconds of a flight log).
//!
//! **Translation axes: prediction-error fit (`pem.rs`).** Roll, pitch and vertical speed are
//! fitted by maximum likelihood through a Kalman filter whose model is the servo's (the
//! body-frame lag `v̇_b = (P·K·u − v_b)/τ`, exact per tick, heading frozen at the tick's
//! midpoint) plus what a real flight adds and the servo's model leaves out: a drift that
//! random-walks (wind), an attitude lag and a command latency. Gains come in closed form
//! for each (τ, lag, latency, drift intensity), which a simplex searches. A gusty stage, a
//! latency or a closed loop do not bias K and τ, where an output-error fit of the servo's
//! model alone is biased or refused. The vertical axis has one gain climbing and one
//! descending; the profile takes the climb's.
//!
//! **Report curves (output-error).** [`simulate_fit`] draws a test's response with the
//! fitted model and the segment's initial state fitted by least squares (the body axis at
//! the segment's mean heading, or world x and y with the joint model while the drone turns).
//!
//! **Heading.** `c[k+1] = c[k] + K_ψ·Δ·ċ(ψ̇[k])` ([`frames::heading_rate_radps`]): the unwrapped
//! measured heading is linear in K_ψ and the segment's initial heading.
//!
//! **Confidence and quality.** Translation axes: 95 % intervals from the inverse Hessian of
//! the likelihood, and R² of the model's one-second-ahead predictions against
//! constant-velocity extrapolation (`pem.rs`). Heading: standard errors from the least
//! squares, R² against a constant heading. A fit is refused ([`FitError`]) when R² <
//! [`R2_MIN`], a 95 % half-width exceeds [`CI_REL_MAX`] of its value, τ sits at the edge of
//! the search range, or the axis was not excited — naming the axis and the test to repeat.

use dronecine_math as math;
use std::fmt;

use dronecine_backend::frames::{self, Command};

pub mod calibrate;
mod pem;

/// Below this R² a fit is refused.
pub const R2_MIN: f64 = 0.9;
/// A 95 % half-width wider than this share of its value is refused.
pub const CI_REL_MAX: f64 = 0.2;
/// Segments whose measured heading spans more than this are left out of the report's
/// body-coordinate panels of roll and pitch.
pub const HEADING_SPAN_MAX_RAD: f64 = 0.2;
/// The τ search range, seconds.
pub const TAU_MIN_S: f64 = 0.02;
pub const TAU_MAX_S: f64 = 20.0;
const Z95: f64 = 1.959964;

/// One tick: the pose the mocap measured at `t_s`, and the command held from `t_s` on.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sample {
    pub t_s: f64,
    pub command: Command,
    /// `None` on a dropout.
    pub position_m: Option<[f64; 3]>,
    pub heading_rad: Option<f64>,
}

/// A contiguous run of samples with its own unknown initial state.
pub type Segment = Vec<Sample>;

/// The four identified axes, each with the test that excites it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    Roll,
    Pitch,
    Vz,
    Yaw,
}

impl Axis {
    pub const ALL: [Axis; 4] = [Axis::Roll, Axis::Pitch, Axis::Vz, Axis::Yaw];

    pub fn name(self) -> &'static str {
        match self {
            Axis::Roll => "roll",
            Axis::Pitch => "pitch",
            Axis::Vz => "vz",
            Axis::Yaw => "yaw",
        }
    }

    pub fn parse(s: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.name() == s)
    }

    /// The test that excites this axis (for "repeat …" messages).
    pub fn test(self) -> &'static str {
        match self {
            Axis::Roll => "the roll tests (`dronecine calibrate --axis roll`)",
            Axis::Pitch => "the pitch tests (`dronecine calibrate --axis pitch`)",
            Axis::Vz => "the vertical-speed tests (`dronecine calibrate --axis vz`)",
            Axis::Yaw => "the yaw-rate tests (`dronecine calibrate --axis yaw`)",
        }
    }

    /// Index of the input in `[φ, θ, ż]` (translation axes).
    fn input_index(self) -> Option<usize> {
        match self {
            Axis::Roll => Some(0),
            Axis::Pitch => Some(1),
            Axis::Vz => Some(2),
            Axis::Yaw => None,
        }
    }
}

/// A fitted value with its 95 % confidence half-width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub value: f64,
    pub ci95: f64,
}

impl Estimate {
    /// Half-width over |value|.
    pub fn relative_ci(&self) -> f64 {
        self.ci95 / self.value.abs().max(1e-300)
    }
}

/// One axis' fit.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisFit {
    pub axis: Axis,
    /// K (K_φ, K_θ in m/s per rad; K_ż; K_ψ).
    pub gain: Estimate,
    /// τ; `None` for the heading.
    pub tau_s: Option<Estimate>,
    /// Quality: R² against the no-input model.
    pub r2: f64,
    /// RMS of the residuals (m, or rad for the heading).
    pub rms: f64,
    /// Measured samples used.
    pub samples: usize,
    /// Vertical only: K_ż while descending (the AR.Drone's descent is about twice as strong
    /// as its climb); `gain` is the climb's, the profile's convention.
    pub descent_gain: Option<Estimate>,
    /// Translation axes: the command latency and (roll, pitch) the attitude lag the fit
    /// found, seconds — the servo's model has neither, they are reported only.
    pub latency_s: Option<f64>,
    pub attitude_lag_s: Option<f64>,
}

/// A delay (attitude lag and latency together) longer than this share of an axis' lag is
/// folded into the lag the profile writes: the servo's model has one lag per axis, and
/// designed on a lag shorter than the delay it flies with, it flies too hard (an
/// autopilot's climb-rate loop, 0.16 s behind a 0.29 s latency, saturated and oscillated).
pub const DELAY_FOLDED_SHARE: f64 = 0.5;

impl AxisFit {
    /// The lag the servo's model takes for this axis: τ, or τ with the delay folded in when
    /// the delay is longer than [`DELAY_FOLDED_SHARE`] of it (a first-order lag whose time
    /// constant is the cascade's mean delay). `None` for the heading.
    pub fn servo_tau_s(&self) -> Option<f64> {
        let tau = self.tau_s?.value;
        let delay = self.attitude_lag_s.unwrap_or(0.0) + self.latency_s.unwrap_or(0.0);
        Some(if delay > DELAY_FOLDED_SHARE * tau {
            tau + delay
        } else {
            tau
        })
    }
}

/// The whole model, as far as it was fitted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelFit {
    pub roll: Option<AxisFit>,
    pub pitch: Option<AxisFit>,
    pub vz: Option<AxisFit>,
    pub yaw: Option<AxisFit>,
}

impl ModelFit {
    pub fn get(&self, axis: Axis) -> Option<&AxisFit> {
        match axis {
            Axis::Roll => self.roll.as_ref(),
            Axis::Pitch => self.pitch.as_ref(),
            Axis::Vz => self.vz.as_ref(),
            Axis::Yaw => self.yaw.as_ref(),
        }
    }

    fn set(&mut self, fit: AxisFit) {
        match fit.axis {
            Axis::Roll => self.roll = Some(fit),
            Axis::Pitch => self.pitch = Some(fit),
            Axis::Vz => self.vz = Some(fit),
            Axis::Yaw => self.yaw = Some(fit),
        }
    }

    /// The profile with the fitted values in `[model]` (axes not fitted keep theirs). The
    /// motion limits that follow from the model (`speed_max_mps`, `accel_max_mps2`,
    /// [`dronecine_profile::derived_motion_limits`]) follow it at the previous
    /// profile's authority; a limit the previous profile had set lower stays, if still below.
    pub fn apply(&self, previous: &dronecine_profile::Profile) -> dronecine_profile::Profile {
        let mut p = previous.clone();
        let m = &mut p.model;
        if let Some(f) = &self.roll {
            m.gain_roll_mps_per_rad = f.gain.value;
            m.tau_roll_s = f.servo_tau_s().unwrap_or(m.tau_roll_s);
        }
        if let Some(f) = &self.pitch {
            m.gain_pitch_mps_per_rad = f.gain.value;
            m.tau_pitch_s = f.servo_tau_s().unwrap_or(m.tau_pitch_s);
        }
        if let Some(f) = &self.vz {
            m.gain_vz = f.gain.value;
            m.tau_vz_s = f.servo_tau_s().unwrap_or(m.tau_vz_s);
        }
        if let Some(f) = &self.yaw {
            m.gain_yaw = f.gain.value;
        }
        use dronecine_profile::derived_motion_limits;
        let l = &previous.limits;
        let pm = &previous.model;
        let k_min = pm.gain_roll_mps_per_rad.min(pm.gain_pitch_mps_per_rad);
        let authority = (l.speed_max_mps / (k_min * l.tilt_max_rad)).clamp(0.0, 1.0);
        let authority = if authority.is_finite() {
            authority
        } else {
            0.5
        };
        let (s0, a0) = derived_motion_limits(pm, l.tilt_max_rad, authority);
        let (s1, a1) = derived_motion_limits(&p.model, l.tilt_max_rad, authority);
        let follow = |old: f64, derived_old: f64, derived_new: f64| {
            if old >= derived_old * (1.0 - 1e-9) {
                derived_new
            } else {
                old.min(derived_new)
            }
        };
        p.limits.speed_max_mps = follow(l.speed_max_mps, s0, s1);
        p.limits.accel_max_mps2 = follow(l.accel_max_mps2, a0, a1);
        p
    }
}

/// Why an axis' fit was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum FitProblem {
    /// Not enough measured samples with input on this axis.
    NotExcited,
    /// R² below [`R2_MIN`].
    PoorFit { r2: f64 },
    /// A 95 % half-width wider than [`CI_REL_MAX`] of its value.
    Uncertain {
        what: &'static str,
        value: f64,
        ci95: f64,
    },
    /// The best τ is at the edge of the search range, or K ≤ 0.
    Implausible { what: &'static str, value: f64 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct FitError {
    pub axis: Axis,
    pub problem: FitProblem,
    /// The fit as far as it went (for the report), if it got to numbers (boxed: an error
    /// stays small on the `Ok` path).
    pub fit: Option<Box<AxisFit>>,
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.axis.name();
        match &self.problem {
            FitProblem::NotExcited => write!(f, "{a}: the axis was not excited")?,
            FitProblem::PoorFit { r2 } => {
                write!(f, "{a}: poor fit, R² = {r2:.3} (needs ≥ {R2_MIN})")?
            }
            FitProblem::Uncertain { what, value, ci95 } => write!(
                f,
                "{a}: {what} = {value:.4} ± {ci95:.4} is too uncertain (needs ± ≤ {:.0} %)",
                CI_REL_MAX * 100.0
            )?,
            FitProblem::Implausible { what, value } => {
                write!(f, "{a}: implausible {what} = {value:.4}")?
            }
        }
        write!(f, "; repeat {}", self.axis.test())?;
        if matches!(self.problem, FitProblem::Uncertain { .. }) {
            f.write_str(" with more tests (`--repeats N`)")?;
        }
        Ok(())
    }
}

impl std::error::Error for FitError {}

/// Fits each of `axes` on `segments`; every axis is tried, the first refusal (in `axes`'s
/// order) is returned after all were fitted, along with the fits that passed.
pub fn fit_model(segments: &[Segment], axes: &[Axis]) -> (ModelFit, Vec<FitError>) {
    let mut out = ModelFit::default();
    let mut errors = Vec::new();
    let horizontal = (axes.contains(&Axis::Roll) || axes.contains(&Axis::Pitch))
        .then(|| fit_horizontal_pem(segments));
    for &axis in axes {
        let fit = match (axis, &horizontal) {
            (Axis::Roll, Some(h)) => h.0.clone(),
            (Axis::Pitch, Some(h)) => h.1.clone(),
            (Axis::Vz, _) => fit_vz_pem(segments),
            _ => fit_heading(segments),
        };
        let checked = fit
            .ok_or(FitError {
                axis,
                problem: FitProblem::NotExcited,
                fit: None,
            })
            .and_then(check);
        match checked {
            Ok(fit) => out.set(fit),
            Err(e) => errors.push(e),
        }
    }
    (out, errors)
}

/// Fits one axis and checks the fit's quality ([`fit_model`] on that axis alone).
pub fn fit_axis(segments: &[Segment], axis: Axis) -> Result<AxisFit, FitError> {
    let (fit, mut errors) = fit_model(segments, &[axis]);
    match (errors.pop(), fit.get(axis)) {
        (Some(e), _) => Err(e),
        (None, Some(f)) => Ok(f.clone()),
        (None, None) => Err(FitError {
            axis,
            problem: FitProblem::NotExcited,
            fit: None,
        }),
    }
}

fn check(fit: AxisFit) -> Result<AxisFit, FitError> {
    let fail = |problem, fit: AxisFit| {
        Err(FitError {
            axis: fit.axis,
            problem,
            fit: Some(Box::new(fit)),
        })
    };
    if !(fit.gain.value > 0.0) {
        return fail(
            FitProblem::Implausible {
                what: "K",
                value: fit.gain.value,
            },
            fit,
        );
    }
    if let Some(t) = fit.tau_s {
        if t.value <= TAU_MIN_S * 1.01 || t.value >= TAU_MAX_S * 0.99 {
            return fail(
                FitProblem::Implausible {
                    what: "τ",
                    value: t.value,
                },
                fit,
            );
        }
    }
    if !(fit.r2 >= R2_MIN) {
        return fail(FitProblem::PoorFit { r2: fit.r2 }, fit);
    }
    let mut parts = vec![("K", fit.gain)];
    if let Some(t) = fit.tau_s {
        parts.push(("τ", t));
    }
    for (what, e) in parts {
        if !(e.relative_ci() <= CI_REL_MAX) {
            return fail(
                FitProblem::Uncertain {
                    what,
                    value: e.value,
                    ci95: e.ci95,
                },
                fit,
            );
        }
    }
    Ok(fit)
}

/// One segment prepared for the joint horizontal fit: measured world x, y (stacked: x then
/// y), the heading each interval flies at (the last measured one), roll and pitch inputs.
struct PlaneData {
    y: Vec<f64>,
    mask: Vec<bool>,
    heading: Vec<f64>,
    roll: Vec<f64>,
    pitch: Vec<f64>,
    dt: Vec<f64>,
}

fn prepare_plane(seg: &[Sample]) -> Option<PlaneData> {
    if seg.len() < 3 {
        return None;
    }
    let n = seg.len();
    let first_heading = seg
        .iter()
        .find_map(|s| s.heading_rad.filter(|h| h.is_finite()))?;
    let mut d = PlaneData {
        y: vec![0.0; 2 * n],
        mask: vec![false; 2 * n],
        heading: Vec::with_capacity(n),
        roll: Vec::with_capacity(n),
        pitch: Vec::with_capacity(n),
        dt: Vec::with_capacity(n),
    };
    let mut c = first_heading;
    for (k, s) in seg.iter().enumerate() {
        if let Some(h) = s.heading_rad.filter(|h| h.is_finite()) {
            c = h;
        }
        // The heading turns during the tick: the lag acts at its midpoint (when the next
        // heading is measured), which keeps the per-tick rotation error second order.
        let next = seg
            .get(k + 1)
            .and_then(|n| n.heading_rad.filter(|h| h.is_finite()));
        d.heading
            .push(next.map_or(c, |n| c + 0.5 * frames::wrap_angle_rad(n - c)));
        if let Some(p) = s
            .position_m
            .filter(|p| p[0].is_finite() && p[1].is_finite())
        {
            d.y[k] = p[0];
            d.y[n + k] = p[1];
            d.mask[k] = true;
            d.mask[n + k] = true;
        }
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        d.roll.push(finite(s.command.roll_rad));
        d.pitch.push(finite(s.command.pitch_rad));
        let dt = seg.get(k + 1).map_or(0.0, |nx| nx.t_s - s.t_s);
        if !(dt >= 0.0 && dt.is_finite()) {
            return None;
        }
        d.dt.push(dt);
    }
    (d.mask.iter().filter(|m| **m).count() >= 6).then_some(d)
}

/// What drives one horizontal response.
#[derive(Clone, Copy)]
enum Drive {
    /// Unit roll gain (K_φ = 1), from rest.
    Roll,
    Pitch,
    /// Unit initial world velocity along x (0) or y (1).
    Velocity(usize),
    /// A unit constant world wind along x (0) or y (1), from rest relative to it.
    Wind(usize),
}

/// The model's world x, y positions (stacked) for one drive, at time constants
/// `taus = [τ_φ, τ_θ]`: per interval the body-frame lag toward `P·K·u + Mᵀw` at the
/// interval's heading (heading frozen per step), integrated exactly.
fn plane_response(d: &PlaneData, taus: [f64; 2], drive: Drive) -> Vec<f64> {
    let n = d.dt.len();
    let mut out = vec![0.0; 2 * n];
    let (mut p, mut v) = ([0.0f64; 2], [0.0f64; 2]);
    let mut wind = [0.0f64; 2];
    match drive {
        Drive::Velocity(i) => v[i] = 1.0,
        Drive::Wind(i) => wind[i] = 1.0,
        _ => {}
    }
    // Body order: forward (τ_θ), left (τ_φ).
    let tb = [taus[1], taus[0]];
    let (mut last_dt, mut a) = (f64::NAN, [0.0; 2]);
    for k in 0..n {
        out[k] = p[0];
        out[n + k] = p[1];
        let (sn, cs) = math::sin_cos(d.heading[k]);
        // Body-frame target velocity: forward = −K_θ θ, left = −K_φ φ (unit gains).
        let target = match drive {
            Drive::Roll => [0.0, -d.roll[k]],
            Drive::Pitch => [-d.pitch[k], 0.0],
            _ => [0.0, 0.0],
        };
        // Air-relative velocity in the body frame.
        let rel = [v[0] - wind[0], v[1] - wind[1]];
        let vb = [cs * rel[0] + sn * rel[1], -sn * rel[0] + cs * rel[1]];
        let dt = d.dt[k];
        if dt != last_dt {
            a = [math::exp(-dt / tb[0]), math::exp(-dt / tb[1])];
            last_dt = dt;
        }
        let mut vb_new = [0.0; 2];
        let mut db = [0.0; 2];
        for j in 0..2 {
            db[j] = dt * target[j] + (vb[j] - target[j]) * tb[j] * (1.0 - a[j]);
            vb_new[j] = target[j] + (vb[j] - target[j]) * a[j];
        }
        p[0] += cs * db[0] - sn * db[1] + wind[0] * dt;
        p[1] += sn * db[0] + cs * db[1] + wind[1] * dt;
        v[0] = cs * vb_new[0] - sn * vb_new[1] + wind[0];
        v[1] = sn * vb_new[0] + cs * vb_new[1] + wind[1];
    }
    out
}

fn plane_nuisance(d: &PlaneData, taus: [f64; 2], disturbance: bool) -> Vec<Vec<f64>> {
    let n = d.dt.len();
    let mut ox = vec![0.0; 2 * n];
    let mut oy = vec![0.0; 2 * n];
    ox[..n].fill(1.0);
    oy[n..].fill(1.0);
    let mut cols = vec![
        ox,
        oy,
        plane_response(d, taus, Drive::Velocity(0)),
        plane_response(d, taus, Drive::Velocity(1)),
    ];
    if disturbance {
        cols.push(plane_response(d, taus, Drive::Wind(0)));
        cols.push(plane_response(d, taus, Drive::Wind(1)));
    }
    cols
}

/// The prediction-error fit of roll and pitch ([`pem`]): wind modelled, any loop.
fn fit_horizontal_pem(segments: &[Segment]) -> (Option<AxisFit>, Option<AxisFit>) {
    let data: Vec<PlaneData> = segments.iter().filter_map(|s| prepare_plane(s)).collect();
    let Some((f, excited)) = pem::fit_plane(&data) else {
        return (None, None);
    };
    let make = |axis: Axis, j: usize| -> Option<AxisFit> {
        excited[j].then(|| AxisFit {
            axis,
            gain: f.gains[j],
            tau_s: Some(f.taus[j]),
            r2: f.r2,
            rms: f.rms_m,
            samples: f.samples,
            descent_gain: None,
            latency_s: Some(f.latency_s),
            attitude_lag_s: f.attitude_lag_s,
        })
    };
    (make(Axis::Roll, 0), make(Axis::Pitch, 1))
}

/// The prediction-error fit of the vertical axis ([`pem`]): climb and descent gains, one τ.
fn fit_vz_pem(segments: &[Segment]) -> Option<AxisFit> {
    let data: Vec<AxisData> = segments.iter().filter_map(|s| prepare(s, 2)).collect();
    let (f, excited) = pem::fit_vertical(&data)?;
    if !excited[0] {
        return None;
    }
    Some(AxisFit {
        axis: Axis::Vz,
        gain: f.gains[0],
        tau_s: Some(f.taus[0]),
        r2: f.r2,
        rms: f.rms_m,
        samples: f.samples,
        descent_gain: excited[1].then_some(f.gains[1]),
        latency_s: Some(f.latency_s),
        attitude_lag_s: None,
    })
}

/// One segment prepared for a translation axis: measured body coordinate (or `None`), the
/// signed input, the interval to the next sample.
struct AxisData {
    y: Vec<Option<f64>>,
    u: Vec<f64>,
    dt: Vec<f64>,
}

fn mean_heading(seg: &[Sample]) -> Option<(f64, f64)> {
    let hs: Vec<f64> = seg.iter().filter_map(|s| s.heading_rad).collect();
    if hs.is_empty() {
        return None;
    }
    let (s, c) = hs.iter().fold((0.0, 0.0), |(s, c), &h| {
        let (sin, cos) = math::sin_cos(h);
        (s + sin, c + cos)
    });
    let mean = math::atan2(s, c);
    let span = hs
        .iter()
        .map(|h| frames::wrap_angle_rad(h - mean).abs())
        .fold(0.0, f64::max);
    Some((mean, span))
}

fn prepare(seg: &[Sample], j: usize) -> Option<AxisData> {
    if seg.len() < 3 {
        return None;
    }
    let (c, span) = mean_heading(seg)?;
    if span > HEADING_SPAN_MAX_RAD && j != 2 {
        return None;
    }
    // Body axis driven by input j, and the sign: body velocity = P·K·u.
    let p = frames::INPUT_TO_BODY;
    let i = (0..3).find(|&i| p[(i, j)] != 0.0)?;
    let sign = p[(i, j)];
    let r = frames::body_to_world(c);
    let mut d = AxisData {
        y: Vec::with_capacity(seg.len()),
        u: Vec::with_capacity(seg.len()),
        dt: Vec::with_capacity(seg.len()),
    };
    for (k, s) in seg.iter().enumerate() {
        let y = s.position_m.and_then(|pw| {
            let b = r.transpose() * nalgebra::Vector3::from(pw);
            b[i].is_finite().then_some(b[i])
        });
        d.y.push(y);
        let u = s.command.translation_input()[j] * sign;
        d.u.push(if u.is_finite() { u } else { 0.0 });
        let dt = seg.get(k + 1).map_or(0.0, |n| n.t_s - s.t_s);
        if !(dt >= 0.0 && dt.is_finite()) {
            return None;
        }
        d.dt.push(dt);
    }
    Some(d)
}

/// Free (v₀ = 1, K = 0) and forced (v₀ = 0, K = 1) position responses of one segment.
fn responses(d: &AxisData, tau: f64) -> (Vec<f64>, Vec<f64>) {
    let n = d.y.len();
    let (mut g, mut h) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut vg, mut sg, mut vh, mut sh) = (1.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        g.push(sg);
        h.push(sh);
        let dt = d.dt[k];
        let a = math::exp(-dt / tau);
        let w = tau * (1.0 - a); // ∫₀^Δ e^{−t/τ} dt
        let u = d.u[k];
        sg += vg * w;
        vg *= a;
        sh += dt * u + (vh - u) * w;
        vh = u + (vh - u) * a;
    }
    (g, h)
}

/// Removes from `x` its least-squares projection on `basis` (over the measured samples).
fn project_out(x: &mut [f64], basis: &[&[f64]], mask: &[bool]) -> Vec<f64> {
    let m = basis.len();
    let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
    let mut b = nalgebra::DVector::<f64>::zeros(m);
    for k in 0..x.len() {
        if !mask[k] {
            continue;
        }
        for r in 0..m {
            b[r] += basis[r][k] * x[k];
            for c in 0..m {
                a[(r, c)] += basis[r][k] * basis[c][k];
            }
        }
    }
    let Some(coef) = a.clone().try_inverse().map(|inv| inv * b) else {
        return vec![0.0; m];
    };
    for k in 0..x.len() {
        for r in 0..m {
            x[k] -= coef[r] * basis[r][k];
        }
    }
    coef.iter().copied().collect()
}

/// Accumulates the lag-1 products and squares of the residual `r` over consecutive measured
/// samples (`half`: the stacked x/y boundary, pairs across it are skipped).
fn lag1(acc: &mut (f64, f64), r: &[f64], mask: &[bool], half: usize) {
    for k in 0..r.len() {
        if !mask[k] {
            continue;
        }
        acc.1 += r[k] * r[k];
        if k + 1 < r.len() && mask[k + 1] && k + 1 != half {
            acc.0 += r[k] * r[k + 1];
        }
    }
}

/// The variance inflation `(1 + ρ)/(1 − ρ)` of a lag-1 autocorrelation ρ of the residuals
/// (clamped to [0, 0.999]): coloured residuals (a gust, a model mismatch) carry fewer
/// independent samples than white mocap noise, so the intervals widen accordingly.
fn inflation(acc: (f64, f64)) -> f64 {
    let rho = if acc.1 > 0.0 { acc.0 / acc.1 } else { 0.0 };
    let rho = if rho.is_finite() {
        rho.clamp(0.0, 0.999)
    } else {
        0.999
    };
    (1.0 + rho) / (1.0 - rho)
}

fn fit_heading(segments: &[Segment]) -> Option<AxisFit> {
    let (mut xy, mut xx, mut yy, mut n, mut nseg) = (0.0, 0.0, 0.0, 0usize, 0usize);
    let mut kept = Vec::new();
    let mut excited = false;
    for seg in segments {
        let mut y = Vec::with_capacity(seg.len());
        let mut x = Vec::with_capacity(seg.len());
        let mut mask = Vec::with_capacity(seg.len());
        let (mut last, mut unwrapped, mut cum) = (None::<f64>, 0.0, 0.0);
        for (k, s) in seg.iter().enumerate() {
            match s.heading_rad.filter(|h| h.is_finite()) {
                Some(h) => {
                    unwrapped = match last {
                        Some(l) => unwrapped + frames::wrap_angle_rad(h - l),
                        None => h,
                    };
                    last = Some(h);
                    y.push(unwrapped);
                    mask.push(true);
                }
                None => {
                    y.push(0.0);
                    mask.push(false);
                }
            }
            x.push(cum);
            let dt = seg.get(k + 1).map_or(0.0, |nx| nx.t_s - s.t_s);
            let r = frames::heading_rate_radps(s.command.yaw_rate_radps);
            if dt > 0.0 && r.is_finite() {
                cum += dt * r;
                excited |= r != 0.0;
            }
        }
        if mask.iter().filter(|m| **m).count() < 3 {
            continue;
        }
        nseg += 1;
        let ones = vec![1.0; y.len()];
        project_out(&mut y, &[&ones], &mask);
        project_out(&mut x, &[&ones], &mask);
        for k in 0..y.len() {
            if mask[k] {
                xy += x[k] * y[k];
                xx += x[k] * x[k];
                yy += y[k] * y[k];
                n += 1;
            }
        }
        kept.push((y, x, mask));
    }
    if !excited || xx <= 0.0 {
        return None;
    }
    let k = xy / xx;
    let ssr = (yy - k * xy).max(0.0);
    let dof = n.saturating_sub(1 + nseg).max(1) as f64;
    let mut acc = (0.0, 0.0);
    for (y, x, mask) in &kept {
        let r: Vec<f64> = y.iter().zip(x).map(|(y, x)| y - k * x).collect();
        lag1(&mut acc, &r, mask, usize::MAX);
    }
    let var = ssr / dof / xx * inflation(acc);
    Some(AxisFit {
        axis: Axis::Yaw,
        gain: Estimate {
            value: k,
            ci95: Z95 * var.sqrt(),
        },
        tau_s: None,
        r2: if yy > 0.0 { 1.0 - ssr / yy } else { 0.0 },
        rms: (ssr / n.max(1) as f64).sqrt(),
        samples: n,
        descent_gain: None,
        latency_s: None,
        attitude_lag_s: None,
    })
}

/// The commands of a test as the fitted model says the drone applied them, for plotting the
/// fit against the test: on roll and pitch each tilt delayed by the fitted latency and passed
/// through the fitted attitude lag; on the vertical axis delayed, and each descent scaled by
/// the descent's gain over the climb's. Before the test the input is taken as zero (the
/// drone was held settled). The servo's model has none of these: the plot shows them so that
/// the fitted and the previous K and τ are compared on the same applied input.
pub fn as_applied(seg: &[Sample], fit: &AxisFit) -> Segment {
    let latency_s = fit.latency_s.unwrap_or(0.0).max(0.0);
    let lag_s = fit.attitude_lag_s.unwrap_or(0.0).max(0.0);
    let descent = match fit.descent_gain {
        Some(d) if fit.gain.value > 0.0 && d.value.is_finite() => d.value / fit.gain.value,
        _ => 1.0,
    };
    let mut out = seg.to_vec();
    let (mut j, mut filtered) = (None::<usize>, [0.0f64; 2]);
    for k in 0..seg.len() {
        // The command in force at t_k − latency.
        let at = seg[k].t_s - latency_s;
        while seg
            .get(j.map_or(0, |j| j + 1))
            .is_some_and(|n| n.t_s <= at + 1e-12)
        {
            j = Some(j.map_or(0, |j| j + 1));
        }
        let delayed = j.map_or(Command::HOVER, |j| seg[j].command);
        let c = &mut out[k].command;
        match fit.axis {
            Axis::Roll | Axis::Pitch => {
                // The attitude over this tick: the lag's response to the delayed command,
                // averaged over the tick (the model holds its input through the tick).
                let dt = seg.get(k + 1).map_or(0.0, |n| n.t_s - seg[k].t_s);
                let a = if lag_s > 0.0 {
                    1.0 - math::exp(-dt / lag_s)
                } else {
                    1.0
                };
                let target = [delayed.roll_rad, delayed.pitch_rad];
                let mut held = [0.0; 2];
                for i in 0..2 {
                    let before = filtered[i];
                    filtered[i] += a * (target[i] - before);
                    held[i] = if lag_s > 0.0 {
                        0.5 * (before + filtered[i])
                    } else {
                        target[i]
                    };
                }
                c.roll_rad = held[0];
                c.pitch_rad = held[1];
            }
            Axis::Vz => {
                let u = delayed.vz_mps;
                c.vz_mps = if u < 0.0 { u * descent } else { u };
            }
            Axis::Yaw => {}
        }
    }
    out
}

/// The fitted model's response on one segment, for plotting against the measurement: the
/// measured body coordinate (or unwrapped heading) and the model's, per sample (`None` where
/// nothing was measured). The initial position and velocity and a steady wind (or vertical
/// drift) from least squares on the segment.
pub fn simulate_fit(seg: &[Sample], fit: &AxisFit) -> Option<Vec<(f64, Option<f64>, f64)>> {
    match (fit.axis.input_index(), fit.tau_s) {
        (Some(j), Some(tau)) => {
            let d = prepare(seg, j)?;
            let (g, h) = responses(&d, tau.value);
            // A steady wind (or vertical drift): the response to a constant unit input.
            let steady = AxisData {
                y: d.y.clone(),
                u: vec![1.0; d.u.len()],
                dt: d.dt.clone(),
            };
            let (_, w) = responses(&steady, tau.value);
            let mask: Vec<bool> = d.y.iter().map(|y| y.is_some()).collect();
            let ones = vec![1.0; g.len()];
            let orig: Vec<f64> = (0..g.len())
                .map(|i| d.y[i].unwrap_or(0.0) - fit.gain.value * h[i])
                .collect();
            let mut r = orig.clone();
            project_out(&mut r, &[&ones, &g, &w], &mask);
            Some(
                (0..g.len())
                    .map(|i| {
                        let fitted = orig[i] - r[i] + fit.gain.value * h[i];
                        (seg[i].t_s, d.y[i], fitted)
                    })
                    .collect(),
            )
        }
        _ => {
            let mut out = Vec::with_capacity(seg.len());
            let (mut last, mut unwrapped, mut cum) = (None::<f64>, 0.0, 0.0);
            let mut offs = Vec::new();
            for (k, s) in seg.iter().enumerate() {
                let y = s.heading_rad.map(|h| {
                    unwrapped = match last {
                        Some(l) => unwrapped + frames::wrap_angle_rad(h - l),
                        None => h,
                    };
                    last = Some(h);
                    unwrapped
                });
                let model = fit.gain.value * cum;
                if let Some(y) = y {
                    offs.push(y - model);
                }
                out.push((s.t_s, y, model));
                let dt = seg.get(k + 1).map_or(0.0, |nx| nx.t_s - s.t_s);
                cum += dt * frames::heading_rate_radps(s.command.yaw_rate_radps);
            }
            let c0 = offs.iter().sum::<f64>() / offs.len().max(1) as f64;
            Some(out.into_iter().map(|(t, y, m)| (t, y, m + c0)).collect())
        }
    }
}

/// The segments a flight log gives: the ticks of the approach and the shots (the servo's
/// commands; take-off and landing are the firmware's), cut into windows of `window_s`, at
/// every tick whose controller output was refused (a failsafe hover is not the command) and
/// where ticks are missing (a damaged log, read past its damage).
pub fn segments_from_log(ticks: &[dronecine_mcap::log::LoggedTick], window_s: f64) -> Vec<Segment> {
    use dronecine_mcap::record::Phase;
    let mut out = Vec::new();
    let mut seg: Segment = Vec::new();
    for t in ticks {
        let usable = matches!(t.phase, Phase::Approach | Phase::Shots)
            && t.output.is_ok()
            && t.input.t_s.is_finite();
        let too_long = seg.first().is_some_and(|f| t.input.t_s - f.t_s >= window_s);
        let backwards = seg.last().is_some_and(|l| t.input.t_s <= l.t_s);
        // Ticks missing in between (a damaged log read past the damage): the tick came
        // `dt_s` after the loop's previous one, which is not the segment's last.
        let gap = seg
            .last()
            .is_some_and(|l| t.input.t_s - l.t_s > 1.5 * t.input.dt_s);
        if !usable || too_long || backwards || gap {
            if seg.len() >= 3 {
                out.push(std::mem::take(&mut seg));
            } else {
                seg.clear();
            }
        }
        if usable {
            seg.push(Sample {
                t_s: t.input.t_s,
                command: t.command_sent,
                position_m: t.input.measurement.map(|m| m.position_m),
                heading_rad: t.input.measurement.map(|m| m.heading_rad),
            });
        }
    }
    if seg.len() >= 3 {
        out.push(seg);
    }
    out
}

/// The joint horizontal model's response on one segment (turning or not), for plotting:
/// per sample the time, the measured world (x, y) and the model's, with `roll` and `pitch`
/// given as (K, τ) and the initial position and velocity and a steady wind fitted by least
/// squares.
#[allow(clippy::type_complexity)]
pub fn simulate_plane(
    seg: &[Sample],
    roll: (f64, f64),
    pitch: (f64, f64),
) -> Option<Vec<(f64, Option<[f64; 2]>, [f64; 2])>> {
    let d = prepare_plane(seg)?;
    let taus = [roll.1, pitch.1];
    if !(taus.iter().all(|t| *t > 0.0 && t.is_finite())) {
        return None;
    }
    let hr = plane_response(&d, taus, Drive::Roll);
    let hp = plane_response(&d, taus, Drive::Pitch);
    let cols = plane_nuisance(&d, taus, true);
    let basis: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
    let forced: Vec<f64> = (0..d.y.len())
        .map(|i| roll.0 * hr[i] + pitch.0 * hp[i])
        .collect();
    let mut r: Vec<f64> = (0..d.y.len()).map(|i| d.y[i] - forced[i]).collect();
    let coef = project_out(&mut r, &basis, &d.mask);
    let n = d.dt.len();
    let model = |i: usize| forced[i] + cols.iter().zip(&coef).map(|(c, b)| c[i] * b).sum::<f64>();
    Some(
        (0..n)
            .map(|k| {
                let measured = d.mask[k].then(|| [d.y[k], d.y[n + k]]);
                (seg[k].t_s, measured, [model(k), model(n + k)])
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A damaged log read past its damage has ticks missing: no segment spans the gap (the
    /// model would be integrated over commands that were never seen).
    #[test]
    fn log_segments_never_span_missing_ticks() {
        use dronecine_mcap::log::LoggedTick;
        use dronecine_mcap::record::Phase;
        use dronecine_servo::control::{Measurement, TickInput, TickOutput};
        let tick = |k: usize| LoggedTick {
            phase: Phase::Shots,
            shot: Some(0),
            input: TickInput {
                t_s: k as f64 * 0.01,
                dt_s: 0.01,
                measurement: Some(Measurement {
                    position_m: [0.0, 0.0, 1.5],
                    heading_rad: 0.0,
                }),
                ..TickInput::default()
            },
            output: Ok(TickOutput::default()),
            command_sent: Command::HOVER,
            actors: Vec::new(),
            framing: Vec::new(),
            latency_s: None,
        };
        let whole: Vec<LoggedTick> = (1..=300).map(tick).collect();
        let lens = |ticks: &[LoggedTick]| -> Vec<usize> {
            segments_from_log(ticks, 20.0)
                .iter()
                .map(Vec::len)
                .collect()
        };
        assert_eq!(lens(&whole), [300]);
        // Ticks 101–150 lost: two segments, split where they are missing.
        let damaged: Vec<LoggedTick> = whole[..100].iter().chain(&whole[150..]).cloned().collect();
        assert_eq!(lens(&damaged), [100, 150]);
        let first = &segments_from_log(&damaged, 20.0)[1][0];
        assert_eq!(first.t_s, whole[150].input.t_s);
    }

    /// A deterministic Gaussian-ish noise (sum of uniforms) so the tests need no RNG crate.
    struct Noise(u64);
    impl Noise {
        fn next(&mut self) -> f64 {
            let mut s = 0.0;
            for _ in 0..12 {
                self.0 ^= self.0 << 13;
                self.0 ^= self.0 >> 7;
                self.0 ^= self.0 << 17;
                s += (self.0 >> 11) as f64 / (1u64 << 53) as f64;
            }
            s - 6.0
        }
    }

    /// Synthetic doublets from the exact model at heading `c`, fine sub-steps, noise σ.
    fn synthetic(k: [f64; 4], tau: [f64; 3], c: f64, sigma: f64, seed: u64) -> Vec<Segment> {
        synthetic_with(k, tau, c, sigma, seed, Extra::default())
    }

    /// What the synthetic plant adds to the servo's model.
    #[derive(Clone, Copy, Default)]
    struct Extra {
        /// A world wind `w·g(t)`, `g` a random walk from 1: it drifts through every test.
        wind: [f64; 2],
        /// A yaw-rate command held during the translation tests.
        yaw_rate: f64,
        /// A first-order lag on roll and pitch, and a latency on every command, seconds.
        attitude_lag_s: f64,
        latency_s: f64,
    }

    fn synthetic_with(
        k: [f64; 4],
        tau: [f64; 3],
        c: f64,
        sigma: f64,
        seed: u64,
        extra: Extra,
    ) -> Vec<Segment> {
        let Extra {
            wind,
            yaw_rate,
            attitude_lag_s,
            latency_s,
        } = extra;
        let mut noise = Noise(seed);
        let mut segs = Vec::new();
        let tests: [(usize, f64); 4] = [(0, 0.03), (1, -0.03), (2, 0.3), (3, 0.5)];
        for (axis, amp) in tests {
            let mut seg = Vec::new();
            let (mut p, mut v, mut h) = ([0.3, -0.2, 1.0], [0.02, -0.01, 0.0], c);
            let mut att = [0.0f64; 2];
            let mut gust = 1.0f64;
            let dt = 0.01;
            let n = 900;
            let input = |t: f64| {
                if (0.0..2.5).contains(&t) {
                    amp
                } else if (2.5..5.0).contains(&t) {
                    -amp
                } else {
                    0.0
                }
            };
            for i in 0..n {
                let t = i as f64 * dt;
                let a = input(t);
                let mut cmd = Command::HOVER;
                match axis {
                    0 => cmd.roll_rad = a,
                    1 => cmd.pitch_rad = a,
                    2 => cmd.vz_mps = a,
                    _ => cmd.yaw_rate_radps = a,
                }
                if axis < 2 {
                    cmd.yaw_rate_radps = yaw_rate;
                }
                seg.push(Sample {
                    t_s: t,
                    command: cmd,
                    position_m: Some(p.map(|x| x + sigma * noise.next())),
                    heading_rad: Some(frames::wrap_angle_rad(h + 0.1 * sigma * noise.next())),
                });
                // Fine integration of the body-frame lag, the command `latency_s` late.
                let mut late = cmd;
                let a_late = input(t - latency_s);
                match axis {
                    0 => late.roll_rad = a_late,
                    1 => late.pitch_rad = a_late,
                    2 => late.vz_mps = a_late,
                    _ => late.yaw_rate_radps = a_late,
                }
                let u = late.translation_input();
                let bt = frames::body_taus_s(tau[0], tau[1], tau[2]);
                // The gust factor random-walks (0.3 per √s), independent of the tests.
                gust += 0.3 * dt.sqrt() * noise.next();
                for _ in 0..10 {
                    let hs = dt / 10.0;
                    if attitude_lag_s > 0.0 {
                        for j in 0..2 {
                            att[j] = u[j] + (att[j] - u[j]) * (-hs / attitude_lag_s).exp();
                        }
                    } else {
                        att = [u[0], u[1]];
                    }
                    let target = frames::INPUT_TO_BODY
                        * nalgebra::Vector3::new(k[0] * att[0], k[1] * att[1], k[2] * u[2]);
                    let r = frames::body_to_world(h);
                    let w = nalgebra::Vector3::new(wind[0] * gust, wind[1] * gust, 0.0);
                    let vb = r.transpose() * (nalgebra::Vector3::from(v) - w);
                    let mut nb = vb;
                    for j in 0..3 {
                        nb[j] = target[j] + (vb[j] - target[j]) * (-hs / bt[j]).exp();
                    }
                    let vw = r * nb + w;
                    for j in 0..3 {
                        p[j] += hs * 0.5 * (v[j] + vw[j]);
                    }
                    v = [vw.x, vw.y, vw.z];
                    h += hs * k[3] * frames::heading_rate_radps(cmd.yaw_rate_radps);
                }
            }
            segs.push(seg);
        }
        segs
    }

    #[test]
    fn recovers_every_gain_and_time_constant_within_5_percent_with_noise() {
        let k = [12.0, 20.0, 0.8, 1.3];
        let tau = [1.2, 2.1, 0.6];
        for (c, seed) in [(0.0, 1), (2.3, 2), (-1.0, 3)] {
            let segs = synthetic(k, tau, c, 0.002, seed);
            let (fit, errors) = fit_model(&segs, &Axis::ALL);
            assert!(errors.is_empty(), "{errors:?}");
            for (axis, kk, tt) in [
                (Axis::Roll, k[0], Some(tau[0])),
                (Axis::Pitch, k[1], Some(tau[1])),
                (Axis::Vz, k[2], Some(tau[2])),
                (Axis::Yaw, k[3], None),
            ] {
                let f = fit.get(axis).unwrap();
                assert!((f.gain.value / kk - 1.0).abs() < 0.05, "{f:?}");
                // The truth inside the 95 % interval (generous: 2× for the one seed).
                assert!(
                    (f.gain.value - kk).abs() < 2.0 * f.gain.ci95 + 1e-9,
                    "{f:?}"
                );
                if let Some(tt) = tt {
                    let t = f.tau_s.unwrap();
                    assert!((t.value / tt - 1.0).abs() < 0.05, "{f:?}");
                    assert!((t.value - tt).abs() < 2.0 * t.ci95, "{f:?}");
                }
                assert!(f.r2 > 0.95, "{f:?}");
            }
        }
    }

    #[test]
    fn roll_and_pitch_while_yawing_are_fitted_jointly_within_5_percent() {
        // The heading turns at 0.8 rad/s through every roll and pitch test: the body-frame
        // lag couples the two axes, which the joint fit follows.
        let k = [12.0, 20.0, 0.8, 1.3];
        let tau = [1.2, 2.1, 0.6];
        let segs = synthetic_with(
            k,
            tau,
            0.4,
            0.002,
            7,
            Extra {
                yaw_rate: 0.8,
                ..Extra::default()
            },
        );
        let (fit, errors) = fit_model(&segs[..2], &[Axis::Roll, Axis::Pitch]);
        assert!(errors.is_empty(), "{errors:?}");
        let (r, p) = (fit.roll.unwrap(), fit.pitch.unwrap());
        assert!((r.gain.value / k[0] - 1.0).abs() < 0.05, "{r:?}");
        assert!(
            (r.tau_s.unwrap().value / tau[0] - 1.0).abs() < 0.05,
            "{r:?}"
        );
        assert!((p.gain.value / k[1] - 1.0).abs() < 0.05, "{p:?}");
        assert!(
            (p.tau_s.unwrap().value / tau[1] - 1.0).abs() < 0.05,
            "{p:?}"
        );
    }

    #[test]
    fn a_drifting_wind_attitude_lag_and_latency_are_modelled() {
        // What an output-error fit of the servo's model cannot take: a wind that drifts
        // through every test, a 0.14 s attitude lag and a 40 ms latency. The prediction-error
        // fit models all three: K and τ within their 95 % intervals (which the drift widens),
        // the lag and the latency found.
        let k = [12.0, 20.0, 0.8, 1.3];
        let tau = [1.2, 2.1, 0.6];
        let extra = Extra {
            wind: [0.3, -0.2],
            attitude_lag_s: 0.14,
            latency_s: 0.04,
            ..Extra::default()
        };
        let segs = synthetic_with(k, tau, 0.3, 0.0005, 8, extra);
        let (roll, pitch) = fit_horizontal_pem(&segs[..2]);
        let vz = fit_vz_pem(&segs[2..3]).unwrap();
        for (f, kk, tt) in [
            (roll.clone().unwrap(), k[0], tau[0]),
            (pitch.unwrap(), k[1], tau[1]),
            (vz, k[2], tau[2]),
        ] {
            // Within the interval, or 1 % where it is narrower than the synthetic plant's own
            // integration error (the vertical axis has no wind).
            let t = f.tau_s.unwrap();
            assert!(
                (f.gain.value - kk).abs() < f.gain.ci95.max(0.01 * kk),
                "{f:?}"
            );
            assert!((t.value - tt).abs() < t.ci95.max(0.01 * tt), "{f:?}");
            assert!((f.gain.value / kk - 1.0).abs() < 0.15, "{f:?}");
            assert!((f.latency_s.unwrap() - 0.04).abs() < 0.01, "{f:?}");
        }
        let lag = roll.unwrap().attitude_lag_s.unwrap();
        assert!((lag - 0.14).abs() < 0.03, "attitude lag {lag}");
    }

    #[test]
    fn refuses_an_unexcited_or_noisy_axis_and_names_the_test() {
        let mut segs = synthetic([12.0, 20.0, 0.8, 1.3], [1.2, 2.1, 0.6], 0.0, 0.002, 4);
        // Drop the roll test: roll is never commanded.
        segs.remove(0);
        let e = fit_axis(&segs, Axis::Roll).unwrap_err();
        assert_eq!(e.problem, FitProblem::NotExcited);
        assert!(e.to_string().contains("--axis roll"), "{e}");
        // Vertical test (±0.3 m/s) buried in 30 cm of noise: too uncertain or too poor.
        let noisy = synthetic([12.0, 20.0, 0.8, 1.3], [1.2, 2.1, 0.6], 0.0, 0.3, 5);
        let e = fit_axis(&noisy[2..3], Axis::Vz).unwrap_err();
        assert!(
            matches!(
                e.problem,
                FitProblem::PoorFit { .. } | FitProblem::Uncertain { .. }
            ),
            "{e:?}"
        );
        assert!(e.to_string().contains("--axis vz"), "{e}");
    }

    #[test]
    fn applies_the_fit_to_the_profile_model_only() {
        let prev = dronecine_profile::Profile::builtin("ardrone2").unwrap();
        let segs = synthetic([12.0, 20.0, 0.8, 1.3], [1.2, 2.1, 0.6], 0.0, 0.001, 6);
        let (fit, errors) = fit_model(&segs, &[Axis::Pitch]);
        assert!(errors.is_empty());
        let p = fit.apply(&prev);
        assert!((p.model.gain_pitch_mps_per_rad - 20.0).abs() < 1.0);
        assert_eq!(
            p.model.gain_roll_mps_per_rad,
            prev.model.gain_roll_mps_per_rad
        );
        assert_eq!(p.servo, prev.servo);
        // The firmware limits stay; the motion limits follow the new model (authority 0.5).
        assert_eq!(p.limits.tilt_max_rad, prev.limits.tilt_max_rad);
        assert_eq!(p.limits.jerk_max_mps3, prev.limits.jerk_max_mps3);
        let (speed, accel) =
            dronecine_profile::derived_motion_limits(&p.model, p.limits.tilt_max_rad, 0.5);
        assert!((p.limits.speed_max_mps - speed).abs() < 1e-9);
        assert!((p.limits.accel_max_mps2 - accel).abs() < 1e-9);
        // So the written profile is a valid one.
        let (back, _) = dronecine_profile::Profile::from_toml("cal", &p.to_toml())
            .expect("the calibrated profile loads");
        assert!((back.model.gain_pitch_mps_per_rad - p.model.gain_pitch_mps_per_rad).abs() < 1e-9);
    }

    /// The report's curve of a vertical doublet: the drone (descents twice as strong as
    /// climbs, 40 ms of latency) is matched by the fitted model only on the input as applied.
    #[test]
    fn as_applied_delays_the_input_and_scales_descents() {
        let (k, tau, latency, descent) = (1.0, 1.25, 0.04, 2.0);
        let dt = 0.01;
        let mut seg = Segment::new();
        let (mut z, mut v) = (1.0, 0.0);
        for i in 0..600 {
            let t = i as f64 * dt;
            let cmd = |t: f64| {
                if (0.0..1.5).contains(&t) {
                    0.3
                } else if (1.5..3.0).contains(&t) {
                    -0.3
                } else {
                    0.0
                }
            };
            let mut c = Command::HOVER;
            c.vz_mps = cmd(t);
            seg.push(Sample {
                t_s: t,
                command: c,
                position_m: Some([0.0, 0.0, z]),
                heading_rad: Some(0.0),
            });
            // The plant, finely integrated: the command acts `latency` late.
            for j in 0..100 {
                let u = cmd(t + j as f64 * dt / 100.0 - latency);
                let u = if u < 0.0 { descent * u } else { u };
                v += dt / 100.0 * (k * u - v) / tau;
                z += dt / 100.0 * v;
            }
        }
        let fit = AxisFit {
            axis: Axis::Vz,
            gain: Estimate {
                value: k,
                ci95: 0.0,
            },
            tau_s: Some(Estimate {
                value: tau,
                ci95: 0.0,
            }),
            r2: 1.0,
            rms: 0.0,
            samples: seg.len(),
            descent_gain: Some(Estimate {
                value: descent * k,
                ci95: 0.0,
            }),
            latency_s: Some(latency),
            attitude_lag_s: None,
        };
        let applied = as_applied(&seg, &fit);
        assert_eq!(applied[3].command.vz_mps, 0.0); // before the latency: nothing yet
        assert_eq!(applied[10].command.vz_mps, 0.3);
        assert_eq!(applied[160].command.vz_mps, -0.6); // a descent, twice as strong
        let worst = |s: &[Sample]| {
            simulate_fit(s, &fit)
                .unwrap()
                .iter()
                .map(|(_, y, m)| (y.unwrap() - m).abs())
                .fold(0.0, f64::max)
        };
        assert!(worst(&applied) < 0.005, "{}", worst(&applied));
        assert!(worst(&seg) > 0.05, "{}", worst(&seg));
    }

    /// Tilts pass through the attitude lag after the latency.
    #[test]
    fn as_applied_lags_the_tilt() {
        let seg: Segment = (0..200)
            .map(|i| Sample {
                t_s: i as f64 * 0.01,
                command: Command {
                    pitch_rad: 0.1,
                    ..Command::HOVER
                },
                position_m: None,
                heading_rad: None,
            })
            .collect();
        let fit = AxisFit {
            axis: Axis::Pitch,
            gain: Estimate {
                value: 17.5,
                ci95: 0.0,
            },
            tau_s: Some(Estimate {
                value: 1.7,
                ci95: 0.0,
            }),
            r2: 1.0,
            rms: 0.0,
            samples: 0,
            descent_gain: None,
            latency_s: Some(0.05),
            attitude_lag_s: Some(0.14),
        };
        let a = as_applied(&seg, &fit);
        assert_eq!(a[4].command.pitch_rad, 0.0);
        // One lag after the latency: 1 − 1/e of the step (the tick's mean, ±half a tick).
        let at = a[5 + 14].command.pitch_rad / 0.1;
        assert!((at - (1.0 - (-1.0f64).exp())).abs() < 0.03, "{at}");
        assert!((a[199].command.pitch_rad - 0.1).abs() < 1e-4);
    }
}
