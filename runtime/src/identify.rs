//! System identification of the servo's model (control.md §2–3) from a measured response:
//! the fit behind `dronecine calibrate` and `dronecine identify`. Pure functions, no I/O.
//!
//! **Data.** A [`Segment`] is a run of [`Sample`]s: at `t_s` the mocap measured the pose
//! (or nothing, on a dropout) and the command then held until the next sample was sent.
//! Each segment has its own unknown initial position and velocity, so segments may be cut
//! anywhere (a test window, a few seconds of a flight log).
//!
//! **Translation axes (output-error fit on positions).** Per body axis the model is
//! `v̇ = (K·u − v)/τ` with `u` the input of [`frames::INPUT_TO_BODY`] (sign included); with the
//! command held over each interval Δ the exact response is
//! `v[k+1] = a·v[k] + (1 − a)·K·u[k]`, `a = e^{−Δ/τ}` (the discrete model of control.md §2),
//! and the position integrates it exactly:
//! `s[k+1] = s[k] + Δ·K·u[k] + (v[k] − K·u[k])·τ·(1 − a)`. The position is linear in K and in
//! each segment's initial position s₀ and velocity v₀ once τ is fixed, so the fit is
//! separable: for each τ the linear least squares in (K, s₀, v₀) is solved in closed form,
//! and τ minimises the residual sum of squares (a log grid, then golden section). Fitting the
//! positions themselves (no differentiated velocity) keeps the white mocap noise white and the
//! estimate unbiased. The body coordinate of a segment is its positions rotated by the
//! segment's mean measured heading; segments whose heading spans more than
//! [`HEADING_SPAN_MAX_RAD`] are left out of the translation fits (the lag acts in the body
//! frame).
//!
//! **Heading.** `c[k+1] = c[k] + K_ψ·Δ·ċ(ψ̇[k])` ([`frames::heading_rate_radps`]): the unwrapped
//! measured heading is linear in K_ψ and the segment's initial heading.
//!
//! **Confidence and quality.** Standard errors from the Gauss–Newton information matrix of
//! (K, τ) with the nuisance parameters projected out, σ² from the residuals; 95 % intervals
//! are ±1.96 standard errors (the delta method is implicit: τ itself is the parameter). The
//! quality figure is R² against the model with no input (each segment a constant-velocity
//! drift, or a constant heading): the share of the motion left after drift that the fitted
//! model explains. A fit is refused ([`FitError`]) when R² < [`R2_MIN`], a 95 % half-width
//! exceeds [`CI_REL_MAX`] of its value, τ sits at the edge of the search range, or the axis
//! was not excited — naming the axis and the test to repeat.

use std::fmt;

use crate::frames::{self, Command};

/// Below this R² a fit is refused.
pub const R2_MIN: f64 = 0.9;
/// A 95 % half-width wider than this share of its value is refused.
pub const CI_REL_MAX: f64 = 0.2;
/// Segments whose measured heading spans more than this are left out of translation fits.
pub const HEADING_SPAN_MAX_RAD: f64 = 0.2;
/// The τ search range, seconds.
pub const TAU_MIN_S: f64 = 0.02;
pub const TAU_MAX_S: f64 = 20.0;
const Z95: f64 = 1.959964;

/// One tick: the pose the mocap measured at `t_s`, and the command held from `t_s` on.
#[derive(Clone, Copy, Debug, PartialEq)]
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
            Axis::Roll => "the roll doublets (`dronecine calibrate --axis roll`)",
            Axis::Pitch => "the pitch doublets (`dronecine calibrate --axis pitch`)",
            Axis::Vz => "the vertical-speed doublets (`dronecine calibrate --axis vz`)",
            Axis::Yaw => "the yaw-rate doublets (`dronecine calibrate --axis yaw`)",
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

    /// The profile with the fitted values in `[model]` (axes not fitted keep theirs).
    pub fn apply(
        &self,
        previous: &dronecine_compiler::profile::Profile,
    ) -> dronecine_compiler::profile::Profile {
        let mut p = previous.clone();
        let m = &mut p.model;
        if let Some(f) = &self.roll {
            m.gain_roll_mps_per_rad = f.gain.value;
            m.tau_roll_s = f.tau_s.map_or(m.tau_roll_s, |t| t.value);
        }
        if let Some(f) = &self.pitch {
            m.gain_pitch_mps_per_rad = f.gain.value;
            m.tau_pitch_s = f.tau_s.map_or(m.tau_pitch_s, |t| t.value);
        }
        if let Some(f) = &self.vz {
            m.gain_vz = f.gain.value;
            m.tau_vz_s = f.tau_s.map_or(m.tau_vz_s, |t| t.value);
        }
        if let Some(f) = &self.yaw {
            m.gain_yaw = f.gain.value;
        }
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
    /// The fit as far as it went (for the report), if it got to numbers.
    pub fit: Option<AxisFit>,
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
        write!(f, "; repeat {}", self.axis.test())
    }
}

impl std::error::Error for FitError {}

/// Fits each of `axes` on `segments`; every axis is tried, the first refusal (in `axes`'s
/// order) is returned after all were fitted, along with the fits that passed.
pub fn fit_model(segments: &[Segment], axes: &[Axis]) -> (ModelFit, Vec<FitError>) {
    let mut out = ModelFit::default();
    let mut errors = Vec::new();
    for &axis in axes {
        match fit_axis(segments, axis) {
            Ok(fit) => out.set(fit),
            Err(e) => errors.push(e),
        }
    }
    (out, errors)
}

/// Fits one axis and checks the fit's quality.
pub fn fit_axis(segments: &[Segment], axis: Axis) -> Result<AxisFit, FitError> {
    let fit = match axis.input_index() {
        Some(j) => fit_lag(segments, axis, j),
        None => fit_heading(segments),
    }
    .ok_or(FitError {
        axis,
        problem: FitProblem::NotExcited,
        fit: None,
    })?;
    check(fit)
}

fn check(fit: AxisFit) -> Result<AxisFit, FitError> {
    let fail = |problem, fit: AxisFit| {
        Err(FitError {
            axis: fit.axis,
            problem,
            fit: Some(fit),
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
    let (s, c) = hs
        .iter()
        .fold((0.0, 0.0), |(s, c), h| (s + h.sin(), c + h.cos()));
    let mean = s.atan2(c);
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
    if span > HEADING_SPAN_MAX_RAD {
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
        let a = (-dt / tau).exp();
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
fn project_out(x: &mut [f64], basis: &[&[f64]], mask: &[bool]) {
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
        return;
    };
    for k in 0..x.len() {
        for r in 0..m {
            x[k] -= coef[r] * basis[r][k];
        }
    }
}

struct LagSolution {
    k: f64,
    ssr: f64,
    /// Σ H⊥², per fit.
    hh: f64,
    n: usize,
    /// Per segment: (residual y⊥ − K·H⊥ …) not needed; the fitted v₀ per segment.
    v0: Vec<f64>,
}

/// The linear least squares in (K, s₀, v₀ per segment) at a fixed τ.
fn solve_lag(data: &[AxisData], tau: f64) -> LagSolution {
    let (mut hy, mut hh, mut yy, mut n) = (0.0, 0.0, 0.0, 0);
    let mut per = Vec::with_capacity(data.len());
    for d in data {
        let (g, h) = responses(d, tau);
        let mask: Vec<bool> = d.y.iter().map(|y| y.is_some()).collect();
        let ones = vec![1.0; g.len()];
        let mut y: Vec<f64> = d.y.iter().map(|y| y.unwrap_or(0.0)).collect();
        let mut hp = h.clone();
        project_out(&mut y, &[&ones, &g], &mask);
        project_out(&mut hp, &[&ones, &g], &mask);
        for k in 0..y.len() {
            if mask[k] {
                hy += hp[k] * y[k];
                hh += hp[k] * hp[k];
                yy += y[k] * y[k];
                n += 1;
            }
        }
        per.push((g, h, mask));
    }
    let k = if hh > 0.0 { hy / hh } else { 0.0 };
    let ssr = (yy - k * hy).max(0.0);
    // v₀ per segment: regress y − K·H on [1, G].
    let v0 = data
        .iter()
        .zip(&per)
        .map(|(d, (g, h, mask))| {
            let ones = vec![1.0; g.len()];
            let mut r: Vec<f64> = (0..g.len())
                .map(|i| d.y[i].unwrap_or(0.0) - k * h[i])
                .collect();
            let orig = r.clone();
            project_out(&mut r, &[&ones, g], mask);
            // Coefficient of G: solve from the fitted part using two measured points.
            fitted_coef(&orig, &r, g, mask)
        })
        .collect();
    LagSolution { k, ssr, hh, n, v0 }
}

/// Given `x` and its residual after projecting on [1, g], the coefficient of g.
fn fitted_coef(x: &[f64], resid: &[f64], g: &[f64], mask: &[bool]) -> f64 {
    // fitted = c0 + c1·g; c1 = cov(fitted, g)/var(g) over the measured samples.
    let idx: Vec<usize> = (0..x.len()).filter(|&k| mask[k]).collect();
    let n = idx.len() as f64;
    let mf = idx.iter().map(|&k| x[k] - resid[k]).sum::<f64>() / n;
    let mg = idx.iter().map(|&k| g[k]).sum::<f64>() / n;
    let (mut c, mut v) = (0.0, 0.0);
    for &k in &idx {
        c += (x[k] - resid[k] - mf) * (g[k] - mg);
        v += (g[k] - mg) * (g[k] - mg);
    }
    if v > 0.0 {
        c / v
    } else {
        0.0
    }
}

fn fit_lag(segments: &[Segment], axis: Axis, j: usize) -> Option<AxisFit> {
    let data: Vec<AxisData> = segments
        .iter()
        .filter_map(|s| prepare(s, j))
        .filter(|d| d.y.iter().filter(|y| y.is_some()).count() >= 3)
        .collect();
    let excited = data
        .iter()
        .any(|d| d.u.iter().zip(&d.dt).any(|(u, dt)| *u != 0.0 && *dt > 0.0));
    if !excited {
        return None;
    }
    // τ: log grid, then golden section around the best point.
    let ssr = |tau: f64| solve_lag(&data, tau).ssr;
    let grid = 48;
    let lt = |i: usize| {
        (TAU_MIN_S.ln() + (TAU_MAX_S.ln() - TAU_MIN_S.ln()) * i as f64 / grid as f64).exp()
    };
    let (best, _) = (0..=grid)
        .map(|i| (i, ssr(lt(i))))
        .fold(
            (0, f64::INFINITY),
            |acc, (i, s)| {
                if s < acc.1 {
                    (i, s)
                } else {
                    acc
                }
            },
        );
    let (mut lo, mut hi) = (
        lt(best.saturating_sub(1)).ln(),
        lt((best + 1).min(grid)).ln(),
    );
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
    let (mut f1, mut f2) = (ssr(x1.exp()), ssr(x2.exp()));
    for _ in 0..60 {
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - phi * (hi - lo);
            f1 = ssr(x1.exp());
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + phi * (hi - lo);
            f2 = ssr(x2.exp());
        }
    }
    let tau = (0.5 * (lo + hi)).exp();
    let sol = solve_lag(&data, tau);
    // Information matrix of (K, τ) with s₀, v₀ projected out: columns H (∂/∂K) and
    // D = K·∂H/∂τ + v₀·∂G/∂τ (∂/∂τ), central differences.
    let eps = tau * 1e-4;
    let (mut hh, mut hd, mut dd, mut null_ss) = (0.0, 0.0, 0.0, 0.0);
    for (d, v0) in data.iter().zip(&sol.v0) {
        let (g, h) = responses(d, tau);
        let (gp, hp) = responses(d, tau + eps);
        let (gm, hm) = responses(d, tau - eps);
        let mask: Vec<bool> = d.y.iter().map(|y| y.is_some()).collect();
        let ones = vec![1.0; g.len()];
        let mut dcol: Vec<f64> = (0..g.len())
            .map(|i| (sol.k * (hp[i] - hm[i]) + v0 * (gp[i] - gm[i])) / (2.0 * eps))
            .collect();
        let mut hcol = h.clone();
        project_out(&mut dcol, &[&ones, &g], &mask);
        project_out(&mut hcol, &[&ones, &g], &mask);
        // The no-input model: constant-velocity drift.
        let t: Vec<f64> = (0..g.len())
            .scan(0.0, |acc, i| {
                let now = *acc;
                *acc += d.dt[i];
                Some(now)
            })
            .collect();
        let mut y0: Vec<f64> = d.y.iter().map(|y| y.unwrap_or(0.0)).collect();
        project_out(&mut y0, &[&ones, &t], &mask);
        for k in 0..g.len() {
            if mask[k] {
                hh += hcol[k] * hcol[k];
                hd += hcol[k] * dcol[k];
                dd += dcol[k] * dcol[k];
                null_ss += y0[k] * y0[k];
            }
        }
    }
    let _ = sol.hh;
    let params = 2 + 2 * data.len();
    let dof = sol.n.saturating_sub(params).max(1) as f64;
    let sigma2 = sol.ssr / dof;
    let det = hh * dd - hd * hd;
    let (var_k, var_t) = if det > 0.0 {
        (sigma2 * dd / det, sigma2 * hh / det)
    } else {
        (f64::INFINITY, f64::INFINITY)
    };
    let r2 = if null_ss > 0.0 {
        1.0 - sol.ssr / null_ss
    } else {
        0.0
    };
    Some(AxisFit {
        axis,
        gain: Estimate {
            value: sol.k,
            ci95: Z95 * var_k.sqrt(),
        },
        tau_s: Some(Estimate {
            value: tau,
            ci95: Z95 * var_t.sqrt(),
        }),
        r2,
        rms: (sol.ssr / sol.n.max(1) as f64).sqrt(),
        samples: sol.n,
    })
}

fn fit_heading(segments: &[Segment]) -> Option<AxisFit> {
    let (mut xy, mut xx, mut yy, mut n, mut nseg) = (0.0, 0.0, 0.0, 0usize, 0usize);
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
    }
    if !excited || xx <= 0.0 {
        return None;
    }
    let k = xy / xx;
    let ssr = (yy - k * xy).max(0.0);
    let dof = n.saturating_sub(1 + nseg).max(1) as f64;
    let var = ssr / dof / xx;
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
    })
}

/// The fitted model's response on one segment, for plotting against the measurement: the
/// measured body coordinate (or unwrapped heading) and the model's, per sample (`None` where
/// nothing was measured). Initial state from the same least squares as the fit.
pub fn simulate_fit(seg: &[Sample], fit: &AxisFit) -> Option<Vec<(f64, Option<f64>, f64)>> {
    let one = vec![seg.to_vec()];
    match (fit.axis.input_index(), fit.tau_s) {
        (Some(j), Some(tau)) => {
            let d = prepare(seg, j)?;
            let (g, h) = responses(&d, tau.value);
            let mask: Vec<bool> = d.y.iter().map(|y| y.is_some()).collect();
            let ones = vec![1.0; g.len()];
            let orig: Vec<f64> = (0..g.len())
                .map(|i| d.y[i].unwrap_or(0.0) - fit.gain.value * h[i])
                .collect();
            let mut r = orig.clone();
            project_out(&mut r, &[&ones, &g], &mask);
            let _ = one;
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

#[cfg(test)]
mod tests {
    use super::*;

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
        let mut noise = Noise(seed);
        let mut segs = Vec::new();
        let tests: [(usize, f64); 4] = [(0, 0.03), (1, -0.03), (2, 0.3), (3, 0.5)];
        for (axis, amp) in tests {
            let mut seg = Vec::new();
            let (mut p, mut v, mut h) = ([0.3, -0.2, 1.0], [0.02, -0.01, 0.0], c);
            let dt = 0.01;
            let n = 700;
            for i in 0..n {
                let t = i as f64 * dt;
                let a = if t < 2.5 {
                    amp
                } else if t < 5.0 {
                    -amp
                } else {
                    0.0
                };
                let mut cmd = Command::HOVER;
                match axis {
                    0 => cmd.roll_rad = a,
                    1 => cmd.pitch_rad = a,
                    2 => cmd.vz_mps = a,
                    _ => cmd.yaw_rate_radps = a,
                }
                seg.push(Sample {
                    t_s: t,
                    command: cmd,
                    position_m: Some(p.map(|x| x + sigma * noise.next())),
                    heading_rad: Some(frames::wrap_angle_rad(h + 0.1 * sigma * noise.next())),
                });
                // Fine integration of the body-frame lag.
                let u = cmd.translation_input();
                let target = frames::INPUT_TO_BODY
                    * nalgebra::Vector3::new(k[0] * u[0], k[1] * u[1], k[2] * u[2]);
                let bt = frames::body_taus_s(tau[0], tau[1], tau[2]);
                for _ in 0..10 {
                    let hs = dt / 10.0;
                    let r = frames::body_to_world(h);
                    let vb = r.transpose() * nalgebra::Vector3::from(v);
                    let mut nb = vb;
                    for j in 0..3 {
                        nb[j] = target[j] + (vb[j] - target[j]) * (-hs / bt[j]).exp();
                    }
                    let vw = r * nb;
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
                assert!(f.r2 > 0.99, "{f:?}");
            }
        }
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
        let prev = dronecine_compiler::profile::Profile::builtin("ardrone2").unwrap();
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
        assert_eq!(p.limits, prev.limits);
    }
}
