//! The LQG servo: an LQ regulator with a reference pre-filter on the
//! translation model, a pole-placed heading loop, and non-stationary Kalman filters for both.
//!
//! **Gains.** With the body-frame lag model and equal x/y weights in Q the regulator is
//! rotation-equivariant: `K1(c) = K1_body · S(c)ᵀ`, `S = blockdiag(Rz, Rz)`. The body-frame
//! gain is solved once (three 2×2 single-input DAREs, [`dare::solve_single_input`]) and
//! rotated each tick; it is solved again only when the measured Δ strays from the Δ it was
//! solved for by more than [`RESOLVE_TOLERANCE`]. With `per_tick_solve` (or when Q weights x
//! and y differently, which breaks the symmetry) the full 6×6 DARE is solved at every tick at
//! the measured Δ and estimated heading.
//!
//! **Law.** `u1 = −K1 (x̂ − r) + G⁻¹ (M_D T_D M_Dᵀ v_ref + Δ a_ref)` with `G = M_D T_D P K`:
//! error feedback, the attitude that holds `v_ref` (`= K⁻¹ M_Dᵀ v_ref` in the paper's
//! notation), and the acceleration feed-forward `G⁻¹ Δ a_ref`. With `paper_prefilter` the law
//! is the paper's `u1 = −K1 x̂ + N1 r`, `N1 = (BᵀB)⁻¹Bᵀ((I + B K1) − A)`, with no acceleration
//! term ([`paper_n1`] equals [`n1`], the simplified form, and a test says so).
//!
//! **Heading.** The closed-loop pole `k2 = γ^(Δ/(τ − Δ̄))` (the error falls to γ after τ − Δ̄
//! seconds), realised by `ċ = (1 − k2)/(K_ψ Δ) · wrap(c_ref − ĉ) + ċ_ref/K_ψ`, sent as the yaw
//! rate [`frames::yaw_rate_command_radps`].
//!
//! **Filters** ([`Estimator`]): a 6-state Kalman filter on the translation model and a scalar
//! one on the heading, both predicting with the measured Δ, the estimated heading and the
//! command actually sent (after saturation: nothing winds up), updating when mocap gives a
//! pose and predicting only when it does not. Heading innovations are wrapped.
//!
//! `tick` allocates nothing.

use std::fmt;

use dronecine_profile::Profile;
use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};
use serde::Serialize;

use crate::control::{
    Controller, ControllerState, Estimate, FilterState, LqgState, Measurement, Reference,
    TickFault, TickInput, TickOutput,
};
use crate::dare::{self, DareError};
use crate::model::{rotation6, Matrix6x3, ModelParams};
use dronecine_backend::frames::{self, Command};

/// Relative change of Δ from the Δ the body-frame gains were solved for that triggers a new
/// solve (three 2×2 DAREs).
pub const RESOLVE_TOLERANCE: f64 = 0.05;

/// The 3×6 feedback gain `K1`.
pub type Gain = SMatrix<f64, 3, 6>;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoOptions {
    /// Fly the paper's pre-filter `N1` exactly, without the acceleration feed-forward.
    pub paper_prefilter: bool,
    /// Solve the full 6×6 DARE at every tick instead of rotating the body-frame gains.
    pub per_tick_solve: bool,
    /// Δ̄: the nominal tick, seconds (the heading pole's τ − Δ̄ and the first gain solve).
    pub nominal_dt_s: f64,
}

impl Default for ServoOptions {
    fn default() -> ServoOptions {
        ServoOptions {
            paper_prefilter: false,
            per_tick_solve: false,
            nominal_dt_s: 0.01,
        }
    }
}

/// What is wrong with a profile (or option) for the servo.
#[derive(Clone, Debug, PartialEq)]
pub enum ServoProblem {
    /// The value is outside what the servo can use; `want` says what is.
    BadValue { value: f64, want: &'static str },
    /// The weights give no (good) Riccati solution.
    Dare(DareError),
}

/// Why the servo could not be built from a profile: which profile, which key, what is wrong
/// and how to fix it.
#[derive(Clone, Debug, PartialEq)]
pub struct ServoError {
    pub profile: String,
    /// The profile key (`servo.q`, `model.tau_roll_s`, …) or option (`--dt`).
    pub key: &'static str,
    pub problem: ServoProblem,
}

impl fmt::Display for ServoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "drone profile `{}`: ", self.profile)?;
        match &self.problem {
            ServoProblem::BadValue { value, want } => {
                let section = self.key.split('.').next().unwrap_or("");
                if self.key.contains('.') {
                    write!(
                        f,
                        "{} = {value} must be {want}; change it in the profile's [{section}] \
                         section",
                        self.key
                    )
                } else {
                    write!(f, "{} = {value} must be {want}", self.key)
                }
            }
            ServoProblem::Dare(
                e @ (DareError::BadWeight { .. } | DareError::PositionsUnweighted { .. }),
            ) => {
                write!(f, "{e}")
            }
            ServoProblem::Dare(e) => write!(
                f,
                "{}: {e}; choose other weights in the profile's [servo] section",
                self.key
            ),
        }
    }
}

impl std::error::Error for ServoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.problem {
            ServoProblem::Dare(e) => Some(e),
            ServoProblem::BadValue { .. } => None,
        }
    }
}

/// Checks what the servo and its filters read from a profile. `nominal_dt_s` is the option
/// `--dt` / `ServoOptions::nominal_dt_s`.
pub fn check_profile(profile: &Profile, nominal_dt_s: f64) -> Result<(), ServoError> {
    let err = |key: &'static str, problem| ServoError {
        profile: profile.name.clone(),
        key,
        problem,
    };
    let bad = |key: &'static str, value: f64, want: &'static str| {
        Err(err(key, ServoProblem::BadValue { value, want }))
    };
    let positive = "finite and > 0";
    if !(nominal_dt_s.is_finite() && nominal_dt_s > 0.0) {
        return bad("nominal tick (--dt)", nominal_dt_s, positive);
    }
    let m = &profile.model;
    let l = &profile.limits;
    let s = &profile.servo;
    for (key, v) in [
        ("model.gain_roll_mps_per_rad", m.gain_roll_mps_per_rad),
        ("model.gain_pitch_mps_per_rad", m.gain_pitch_mps_per_rad),
        ("model.gain_vz", m.gain_vz),
        ("model.tau_roll_s", m.tau_roll_s),
        ("model.tau_pitch_s", m.tau_pitch_s),
        ("model.tau_vz_s", m.tau_vz_s),
        ("model.gain_yaw", m.gain_yaw),
        ("limits.tilt_max_deg", l.tilt_max_rad),
        ("limits.vz_max_mps", l.vz_max_mps),
        ("limits.yaw_rate_max_degps", l.yaw_rate_max_radps),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return bad(key, v, positive);
        }
    }
    dare::check_servo_weights(&s.q, &s.r).map_err(|e| {
        let key = match e {
            DareError::BadWeight { key, .. } => key,
            _ => "servo.q",
        };
        err(key, ServoProblem::Dare(e))
    })?;
    if !(s.heading_gamma.is_finite() && s.heading_gamma > 0.0 && s.heading_gamma < 1.0) {
        return bad(
            "servo.heading_gamma",
            s.heading_gamma,
            "between 0 and 1 (the share of a heading error left after heading_tau_s)",
        );
    }
    if !(s.heading_tau_s.is_finite() && s.heading_tau_s > nominal_dt_s) {
        return bad(
            "servo.heading_tau_s",
            s.heading_tau_s,
            "finite and longer than the servo's tick (`--dt`, or 1/`--rate`)",
        );
    }
    for (i, &v) in s.process_noise.iter().enumerate() {
        if !(v.is_finite() && v >= 0.0) {
            return Err(err(
                "servo.process_noise",
                ServoProblem::Dare(DareError::BadWeight {
                    key: "servo.process_noise",
                    index: i,
                    value: v,
                }),
            ));
        }
    }
    for (i, &v) in s.measurement_noise_m2.iter().enumerate() {
        if !(v.is_finite() && v > 0.0) {
            return Err(err(
                "servo.measurement_noise_m2",
                ServoProblem::Dare(DareError::BadWeight {
                    key: "servo.measurement_noise_m2",
                    index: i,
                    value: v,
                }),
            ));
        }
    }
    if !(s.heading_process_noise_rad2.is_finite() && s.heading_process_noise_rad2 >= 0.0) {
        return bad(
            "servo.heading_process_noise_rad2",
            s.heading_process_noise_rad2,
            "finite and ≥ 0",
        );
    }
    if !(s.heading_measurement_noise_rad2.is_finite() && s.heading_measurement_noise_rad2 > 0.0) {
        return bad(
            "servo.heading_measurement_noise_rad2",
            s.heading_measurement_noise_rad2,
            positive,
        );
    }
    Ok(())
}

/// The wind estimate's random walk: its variance grows by this much per second,
/// (m/s)²/s. About an Ornstein–Uhlenbeck gust of σ 0.2 m/s over 4 s (2σ²/τ = 0.02); an
/// indoor draft drifts slower, and a larger value only makes the estimate noisier.
pub const DISTURBANCE_DIFFUSION_M2PS3: f64 = 0.2;

type Matrix9 = SMatrix<f64, 9, 9>;
type Vector9 = SMatrix<f64, 9, 1>;
type Matrix9x3 = SMatrix<f64, 9, 3>;

/// The Kalman filters of the servo (shared with the PID baseline): a non-stationary filter on
/// `x1 = [v; p]` — augmented, for the LQG servo, with `d`, the velocity of the air (wind) the
/// body-frame lag pulls the drone toward (`v[k+1] = (I − L) v + G u + L d`, `L = M_D T_D
/// M_Dᵀ`; offset-free LQG: the servo tilts into the wind instead of drifting with it) — and
/// a scalar one on the heading. Without the disturbance its state stays exactly 0 with no
/// covariance, and the filter is the paper's 6-state one.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimator {
    model: ModelParams,
    /// F1 (per tick) and H1.
    process: Matrix6<f64>,
    measurement: Matrix3<f64>,
    /// f2, h2.
    heading_process: f64,
    heading_measurement: f64,
    /// Whether `d` is estimated (its diffusion per second, (m/s)²/s; 0 = off).
    disturbance_diffusion: f64,
    /// `[v; p; d]`.
    x: Vector9,
    p: Matrix9,
    c: f64,
    pc: f64,
    /// The last Δ and its [`ModelParams::body_lag`] (three `exp` a tick otherwise; Δ rarely
    /// changes).
    lag_dt_s: f64,
    lag_body: Vector3<f64>,
}

impl Estimator {
    /// Filters on the profile's model and noises, started at the origin with a wide
    /// covariance (1 m², 1 m²/s², 1 rad²) until [`Estimator::reset`]. Noises that are not
    /// finite and positive are replaced by a tiny positive floor (use [`check_profile`] to
    /// refuse them instead). No wind estimate.
    pub fn new(profile: &Profile) -> Estimator {
        let floor = |v: f64| if v.is_finite() && v > 0.0 { v } else { 1e-12 };
        let s = &profile.servo;
        let mut process = Matrix6::zeros();
        for i in 0..6 {
            process[(i, i)] = floor(s.process_noise[i]);
        }
        let mut measurement = Matrix3::zeros();
        for i in 0..3 {
            measurement[(i, i)] = floor(s.measurement_noise_m2[i]);
        }
        let mut p = Matrix9::zeros();
        for i in 0..6 {
            p[(i, i)] = 1.0;
        }
        Estimator {
            model: ModelParams::from_profile(profile),
            process,
            measurement,
            heading_process: floor(s.heading_process_noise_rad2),
            heading_measurement: floor(s.heading_measurement_noise_rad2),
            disturbance_diffusion: 0.0,
            x: Vector9::zeros(),
            p,
            c: 0.0,
            pc: 1.0,
            // body_lag(0) = 0: a consistent entry (a tick never has Δ = 0).
            lag_dt_s: 0.0,
            lag_body: Vector3::zeros(),
        }
    }

    /// [`Estimator::new`] that also estimates the air's velocity `d` (a random walk with
    /// [`DISTURBANCE_DIFFUSION_M2PS3`]).
    pub fn with_disturbance(profile: &Profile) -> Estimator {
        Estimator {
            disturbance_diffusion: DISTURBANCE_DIFFUSION_M2PS3,
            ..Estimator::new(profile)
        }
    }

    /// At rest at the measured pose: the position as uncertain as a measurement, the velocity
    /// as one tick of process noise, the wind unknown within ±0.5 m/s (1σ) when estimated.
    pub fn reset(&mut self, m: &Measurement) {
        self.x = Vector9::zeros();
        for i in 0..3 {
            self.x[3 + i] = m.position_m[i];
        }
        self.p = Matrix9::zeros();
        for i in 0..3 {
            self.p[(i, i)] = self.process[(i, i)];
            self.p[(i + 3, i + 3)] = self.measurement[(i, i)];
            if self.disturbance_diffusion > 0.0 {
                self.p[(i + 6, i + 6)] = 0.25;
            }
        }
        self.c = frames::wrap_angle_rad(m.heading_rad);
        self.pc = self.heading_measurement;
    }

    /// Predicts over Δ with the translation input `u = [φ, θ, ż]` and yaw-rate command that
    /// were sent, at the estimated heading.
    pub fn predict(&mut self, dt_s: f64, u: &Vector3<f64>, yaw_rate_command_radps: f64) {
        // A = [[I − L, 0, L], [Δ I, I, 0], [0, 0, I]] (the L block only with the wind
        // estimate), B = [G; 0; 0]: the state by block rows, the covariance by its distinct
        // 3×3 blocks below (`predict_dense` in the tests is the dense 9×9 A P Aᵀ).
        if dt_s != self.lag_dt_s {
            self.lag_dt_s = dt_s;
            self.lag_body = self.model.body_lag(dt_s);
        }
        let (lag, g) = self.model.lag_and_input(&self.lag_body, self.c);
        let m = Matrix3::identity() - lag;
        let wind = self.disturbance_diffusion > 0.0;
        let v = self.x.fixed_rows::<3>(0).into_owned();
        let d = self.x.fixed_rows::<3>(6).into_owned();
        let mut v1 = m * v + g * u;
        if wind {
            v1 += lag * d;
        }
        let p1 = self.x.fixed_rows::<3>(3) + v * dt_s;
        self.x.fixed_rows_mut::<3>(0).copy_from(&v1);
        self.x.fixed_rows_mut::<3>(3).copy_from(&p1);

        // P' = A P Aᵀ + Q by its six distinct 3×3 blocks (P is symmetric: `P_pv = P_vpᵀ`…).
        // With X = [M, 0, L] P, the v rows of A P:
        //   P'_vv = X_v Mᵀ + X_d Lᵀ,  P'_vp = Δ X_v + X_p,  P'_vd = X_d,
        //   P'_pp = Δ² P_vv + Δ (P_vp + P_vpᵀ) + P_pp,  P'_pd = Δ P_vd + P_pd,  P'_dd = P_dd.
        // Without the wind estimate the d blocks are zero and stay zero.
        let block =
            |p: &Matrix9, i: usize, j: usize| p.fixed_view::<3, 3>(3 * i, 3 * j).into_owned();
        let p = &self.p;
        let (vv, vp, pp) = (block(p, 0, 0), block(p, 0, 1), block(p, 1, 1));
        let mut xv = mul_xy_z(&m, &vv);
        let mut xp = mul_xy_z(&m, &vp);
        let nvv;
        if wind {
            let (vd, pd, dd) = (block(p, 0, 2), block(p, 1, 2), block(p, 2, 2));
            xv += mul_xy_z(&lag, &vd.transpose());
            xp += mul_xy_z(&lag, &pd.transpose());
            let xd = mul_xy_z(&m, &vd) + mul_xy_z(&lag, &dd);
            nvv = mul_xy_z(&xv, &m.transpose()) + mul_xy_z(&xd, &lag.transpose());
            let npd = vd * dt_s + pd;
            let mut ndd = dd;
            for i in 0..3 {
                ndd[(i, i)] += self.disturbance_diffusion * dt_s;
            }
            let pn = &mut self.p;
            pn.fixed_view_mut::<3, 3>(0, 6).copy_from(&xd);
            pn.fixed_view_mut::<3, 3>(6, 0).copy_from(&xd.transpose());
            pn.fixed_view_mut::<3, 3>(3, 6).copy_from(&npd);
            pn.fixed_view_mut::<3, 3>(6, 3).copy_from(&npd.transpose());
            pn.fixed_view_mut::<3, 3>(6, 6).copy_from(&ndd);
        } else {
            nvv = mul_xy_z(&xv, &m.transpose());
        }
        let q = &self.process;
        let nvv = (nvv + nvv.transpose()) * 0.5 + q.fixed_view::<3, 3>(0, 0);
        let nvp = xv * dt_s + xp + q.fixed_view::<3, 3>(0, 3);
        let npp = vv * (dt_s * dt_s) + (vp + vp.transpose()) * dt_s + pp;
        let npp = (npp + npp.transpose()) * 0.5 + q.fixed_view::<3, 3>(3, 3);
        let pn = &mut self.p;
        pn.fixed_view_mut::<3, 3>(0, 0).copy_from(&nvv);
        pn.fixed_view_mut::<3, 3>(0, 3).copy_from(&nvp);
        pn.fixed_view_mut::<3, 3>(3, 0).copy_from(&nvp.transpose());
        pn.fixed_view_mut::<3, 3>(3, 3).copy_from(&npp);
        self.c = self
            .model
            .heading_step(self.c, dt_s, yaw_rate_command_radps);
        self.pc += self.heading_process;
    }

    /// One tick of the filters: refuses a bad input (state unchanged), else predicts over
    /// its Δ with what was sent and corrects with its measurement, if any.
    pub fn step(
        &mut self,
        input: &TickInput,
        u_sent: &Vector3<f64>,
        yaw_sent_radps: f64,
    ) -> Result<(), TickFault> {
        check_input(input)?;
        self.predict(input.dt_s, u_sent, yaw_sent_radps);
        if let Some(m) = &input.measurement {
            self.update(m);
        }
        Ok(())
    }

    /// Corrects with a mocap pose (position and wrapped heading innovation).
    pub fn update(&mut self, m: &Measurement) {
        let s = self.p.fixed_view::<3, 3>(3, 3).into_owned() + self.measurement;
        let pht: Matrix9x3 = self.p.fixed_view::<9, 3>(0, 3).into_owned();
        // K = P Hᵀ S⁻¹, S symmetric positive definite (a covariance plus the measurement
        // noise, so well conditioned): S⁻¹ in closed form; a non-finite or non-positive
        // determinant skips the correction.
        if let Some(si) = inverse_spd3(&s) {
            // K = P Hᵀ S⁻¹ (S⁻¹ is built exactly symmetric; z apart, as every block).
            let k = gain_xy_z(&pht, &si);
            let y = Vector3::from(m.position_m) - self.x.fixed_rows::<3>(3);
            self.x += k * y;
            // P −= K (H P) = P Hᵀ S⁻¹ H P, symmetric: one triangle computed, mirrored
            // (without the wind estimate the d rows and columns are zero and stay zero).
            if self.disturbance_diffusion > 0.0 {
                subtract_symmetric::<9>(&mut self.p, &k, &pht);
            } else {
                subtract_symmetric::<6>(&mut self.p, &k, &pht);
            }
        }
        let kc = self.pc / (self.pc + self.heading_measurement);
        let innovation = frames::wrap_angle_rad(m.heading_rad - self.c);
        self.c = frames::wrap_angle_rad(self.c + kc * innovation);
        self.pc *= 1.0 - kc;
    }

    /// [`ModelParams::body_lag`] of the step `dt_s` (the last prediction's, when it was
    /// this step).
    pub fn body_lag(&self, dt_s: f64) -> Vector3<f64> {
        if dt_s == self.lag_dt_s {
            self.lag_body
        } else {
            self.model.body_lag(dt_s)
        }
    }

    /// `x̂1 = [v; p]`.
    pub fn state(&self) -> Vector6<f64> {
        self.x.fixed_rows::<6>(0).into_owned()
    }

    /// The estimated air velocity `d` (zero when not estimated).
    pub fn disturbance_mps(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(6).into_owned()
    }

    pub fn heading_rad(&self) -> f64 {
        self.c
    }

    /// The covariance of `[v; p]`.
    pub fn covariance(&self) -> Matrix6<f64> {
        self.p.fixed_view::<6, 6>(0, 0).into_owned()
    }

    pub fn estimate(&self) -> Estimate {
        Estimate {
            position_m: [self.x[3], self.x[4], self.x[5]],
            velocity_mps: [self.x[0], self.x[1], self.x[2]],
            heading_rad: self.c,
        }
    }

    /// What the filters carry from tick to tick (the model and the noises are fixed at
    /// construction).
    pub fn filter_state(&self) -> FilterState {
        FilterState {
            x: rows(&self.x.transpose())[0],
            p: rows(&self.p),
            heading_rad: self.c,
            heading_variance_rad2: self.pc,
            lag_dt_s: self.lag_dt_s,
            lag_body: rows(&self.lag_body.transpose())[0],
        }
    }

    /// Puts the filters in `state` (from [`Estimator::filter_state`] of filters built the
    /// same way).
    pub fn restore_filter(&mut self, state: &FilterState) {
        self.x = Vector9::from_fn(|i, _| state.x[i]);
        self.p = Matrix9::from_fn(|i, j| state.p[i][j]);
        self.c = state.heading_rad;
        self.pc = state.heading_variance_rad2;
        self.lag_dt_s = state.lag_dt_s;
        self.lag_body = Vector3::from(state.lag_body);
    }
}

/// The inverse of a symmetric 3×3 matrix by its cofactors (the upper triangle is read), or
/// `None` when its determinant is not finite and positive (not positive definite, or
/// damaged).
fn inverse_spd3(s: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let (a, b, c) = (s[(0, 0)], s[(0, 1)], s[(0, 2)]);
    let (d, e, f) = (s[(1, 1)], s[(1, 2)], s[(2, 2)]);
    let c00 = d * f - e * e;
    let c01 = c * e - b * f;
    let c02 = b * e - c * d;
    let det = a * c00 + b * c01 + c * c02;
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let c11 = a * f - c * c;
    let c12 = b * c - a * e;
    let c22 = a * d - b * b;
    let k = 1.0 / det;
    Some(Matrix3::new(c00, c01, c02, c01, c11, c12, c02, c12, c22) * k)
}

/// `P −= K Yᵀ` on the leading `N × N` block, for a product known to be symmetric: the lower
/// triangle computed, the upper one mirrored from it.
#[inline]
fn subtract_symmetric<const N: usize>(p: &mut Matrix9, k: &Matrix9x3, y: &Matrix9x3) {
    // Only entries within one group (see `mul_xy_z`): the others are zero and stay zero.
    let (xy, z) = (&XY_STATES[..N / 3 * 2], &Z_STATES[..N / 3]);
    for (a, &j) in xy.iter().enumerate() {
        let (y0, y1) = (y[(j, 0)], y[(j, 1)]);
        for &i in &xy[a..] {
            let v = p[(i, j)] - (k[(i, 0)] * y0 + k[(i, 1)] * y1);
            p[(i, j)] = v;
            p[(j, i)] = v;
        }
    }
    for (a, &j) in z.iter().enumerate() {
        let y2 = y[(j, 2)];
        for &i in &z[a..] {
            let v = p[(i, j)] - k[(i, 2)] * y2;
            p[(i, j)] = v;
            p[(j, i)] = v;
        }
    }
}

/// The x and y states of `[v; p; d]`, and the z ones.
const XY_STATES: [usize; 6] = [0, 1, 3, 4, 6, 7];
const Z_STATES: [usize; 3] = [2, 5, 8];

/// `a·b` for 3×3 blocks that do not couple z with x and y: `[[a, b, 0], [c, d, 0], [0, 0,
/// e]]`. The filter's matrices all have this shape — the lag and the input matrix turn about
/// z, the noises are diagonal, so every 3×3 block of the covariance keeps it — and this is the
/// full product's sums without their terms that are exactly zero: the same numbers for a
/// third of the multiplications (`covariance_keeps_z_apart` pins the shape).
#[inline]
fn mul_xy_z(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    let mut r = Matrix3::zeros();
    for i in 0..2 {
        for j in 0..2 {
            r[(i, j)] = a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)];
        }
    }
    r[(2, 2)] = a[(2, 2)] * b[(2, 2)];
    r
}

/// `P Hᵀ · S⁻¹` with the shapes of `mul_xy_z`: an x or y state's row has no z column and a z
/// state's row only that one.
#[inline]
fn gain_xy_z(pht: &Matrix9x3, si: &Matrix3<f64>) -> Matrix9x3 {
    let mut k = Matrix9x3::zeros();
    for i in XY_STATES {
        for j in 0..2 {
            k[(i, j)] = pht[(i, 0)] * si[(0, j)] + pht[(i, 1)] * si[(1, j)];
        }
    }
    for i in Z_STATES {
        k[(i, 2)] = pht[(i, 2)] * si[(2, 2)];
    }
    k
}

/// Whether a tick input can be used: every number finite and Δ > 0.
pub fn check_input(input: &TickInput) -> Result<(), TickFault> {
    let r = &input.reference;
    let finite = input.t_s.is_finite()
        && input.dt_s.is_finite()
        && r.position_m.iter().all(|v| v.is_finite())
        && r.velocity_mps.iter().all(|v| v.is_finite())
        && r.acceleration_mps2.iter().all(|v| v.is_finite())
        && r.heading_rad.is_finite()
        && r.heading_rate_radps.is_finite()
        && input.measurement.is_none_or(|m| {
            m.position_m.iter().all(|v| v.is_finite()) && m.heading_rad.is_finite()
        });
    if !finite {
        return Err(TickFault::NotFinite);
    }
    if input.dt_s <= 0.0 {
        return Err(TickFault::TimeNotIncreasing);
    }
    Ok(())
}

/// The simplified pre-filter `N1 = K1 + [G⁻¹ M_D T_D M_Dᵀ, 0]` (`= K1 + [K⁻¹ M_Dᵀ, 0]`).
pub fn n1(model: &ModelParams, k1: &Gain, dt_s: f64, heading_rad: f64) -> Option<Gain> {
    let g = model.input_matrix(dt_s, heading_rad);
    let hold = dare::solve_linear(&g, &model.world_lag(dt_s, heading_rad))?;
    let mut n = *k1;
    let mut left = n.fixed_view_mut::<3, 3>(0, 0);
    left += hold;
    Some(n)
}

/// The paper's pre-filter `N1 = (BᵀB)⁻¹Bᵀ((I + B K1) − A)`, literally.
pub fn paper_n1(a: &Matrix6<f64>, b: &Matrix6x3, k1: &Gain) -> Option<Gain> {
    let rhs = b.transpose() * ((Matrix6::identity() + b * k1) - a);
    dare::solve_linear(&(b.transpose() * b), &rhs)
}

/// The heading loop's closed-loop pole for a step Δ: `γ^(Δ/(τ − Δ̄))`.
pub fn heading_pole(gamma: f64, tau_s: f64, nominal_dt_s: f64, dt_s: f64) -> f64 {
    dronecine_math::powf(gamma, dt_s / (tau_s - nominal_dt_s))
}

/// What `dronecine gains` prints: the regulator and filter at one Δ and heading.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GainsReport {
    pub dt_s: f64,
    pub heading_rad: f64,
    /// Riccati solution (world frame at `heading_rad`).
    #[serde(rename = "P")]
    pub p: [[f64; 6]; 6],
    #[serde(rename = "K1")]
    pub k1: [[f64; 6]; 3],
    #[serde(rename = "N1")]
    pub n1: [[f64; 6]; 3],
    /// |eigenvalues| of `A1 − B1 K1`.
    pub closed_loop_pole_magnitudes: [f64; 6],
    /// The steady-state Kalman gain (6×3, update form `P Hᵀ (H P Hᵀ + H1)⁻¹`).
    pub kalman_gain: [[f64; 3]; 6],
    pub k2: f64,
    /// Relative residual of the regulator DARE.
    pub residual: f64,
    pub iterations: usize,
}

fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> [[f64; C]; R] {
    let mut out = [[0.0; C]; R];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = m[(i, j)];
        }
    }
    out
}

/// The LQG servo.
#[derive(Clone, Debug)]
pub struct LqgServo {
    profile_name: String,
    model: ModelParams,
    options: ServoOptions,
    q: Matrix6<f64>,
    r: Matrix3<f64>,
    process: Matrix6<f64>,
    measurement: Matrix3<f64>,
    tilt_max_rad: f64,
    vz_max_mps: f64,
    yaw_rate_max_radps: f64,
    heading_gamma: f64,
    heading_tau_s: f64,
    /// The last Δ and its [`heading_pole`] (a `powf` a tick otherwise; Δ rarely changes).
    k2_dt_s: f64,
    k2: f64,
    /// Whether `K1(c) = K1_body S(c)ᵀ` holds (x and y weighted alike).
    symmetric: bool,
    k_body: Gain,
    k_body_dt_s: f64,
    /// The gain of the last full solve (per-tick mode).
    k_world: Gain,
    estimator: Estimator,
    /// The translation input and yaw rate sent last tick (after saturation).
    sent: Vector3<f64>,
    sent_yaw_radps: f64,
}

impl LqgServo {
    pub fn new(profile: &Profile, options: ServoOptions) -> Result<LqgServo, ServoError> {
        check_profile(profile, options.nominal_dt_s)?;
        let s = &profile.servo;
        let q = Matrix6::from_diagonal(&Vector6::from(s.q));
        let r = Matrix3::from_diagonal(&Vector3::from(s.r));
        let mut process = Matrix6::zeros();
        for i in 0..6 {
            process[(i, i)] = s.process_noise[i];
        }
        let measurement = Matrix3::from_diagonal(&Vector3::from(s.measurement_noise_m2));
        let symmetric = s.q[0] == s.q[1] && s.q[3] == s.q[4];
        let model = ModelParams::from_profile(profile);
        let mut servo = LqgServo {
            profile_name: profile.name.clone(),
            model,
            options,
            q,
            r,
            process,
            measurement,
            tilt_max_rad: profile.limits.tilt_max_rad,
            vz_max_mps: profile.limits.vz_max_mps,
            yaw_rate_max_radps: profile.limits.yaw_rate_max_radps,
            heading_gamma: s.heading_gamma,
            heading_tau_s: s.heading_tau_s,
            k2_dt_s: f64::NAN,
            k2: f64::NAN,
            symmetric,
            k_body: Gain::zeros(),
            k_body_dt_s: options.nominal_dt_s,
            k_world: Gain::zeros(),
            // The paper's law flies the paper's 6-state filter; ours also estimates the wind.
            estimator: if options.paper_prefilter {
                Estimator::new(profile)
            } else {
                Estimator::with_disturbance(profile)
            },
            sent: Vector3::zeros(),
            sent_yaw_radps: 0.0,
        };
        let dt = options.nominal_dt_s;
        let dare_err = |e| ServoError {
            profile: profile.name.clone(),
            key: "servo.q",
            problem: ServoProblem::Dare(e),
        };
        // The full solve checks residual and stability whichever mode flies.
        let full = dare::solve(&model.a1(dt, 0.0), &model.b1(dt, 0.0), &q, &r).map_err(dare_err)?;
        servo.k_world = full.k;
        if symmetric {
            servo.k_body = servo.body_gain(dt).map_err(dare_err)?;
        }
        Ok(servo)
    }

    pub fn options(&self) -> ServoOptions {
        self.options
    }

    pub fn model(&self) -> &ModelParams {
        &self.model
    }

    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// The body-frame gain from the three single-input DAREs at Δ.
    pub fn body_gain(&self, dt_s: f64) -> Result<Gain, DareError> {
        let mut k = Gain::zeros();
        for axis in 0..3 {
            let (a, b, j) = self
                .model
                .body_axis(dt_s, axis)
                .ok_or(DareError::Singular)?;
            let q = nalgebra::Matrix2::new(
                self.q[(axis, axis)],
                0.0,
                0.0,
                self.q[(axis + 3, axis + 3)],
            );
            let sol = dare::solve_single_input(&a, &b, &q, self.r[(j, j)])?;
            k[(j, axis)] = sol.k[(0, 0)];
            k[(j, axis + 3)] = sol.k[(0, 1)];
        }
        Ok(k)
    }

    /// The feedback gain flown at Δ and heading c (updates the cached solves).
    fn feedback_gain(&mut self, dt_s: f64, heading_rad: f64) -> Gain {
        if self.options.per_tick_solve || !self.symmetric {
            let a = self.model.a1(dt_s, heading_rad);
            let b = self.model.b1(dt_s, heading_rad);
            if let Ok((_, k, _)) = dare::solve_unchecked(&a, &b, &self.q, &self.r) {
                self.k_world = k;
            }
            return self.k_world;
        }
        if (dt_s - self.k_body_dt_s).abs() > RESOLVE_TOLERANCE * self.k_body_dt_s {
            if let Ok(k) = self.body_gain(dt_s) {
                self.k_body = k;
                self.k_body_dt_s = dt_s;
            }
        }
        self.k_body * rotation6(heading_rad).transpose()
    }

    /// The gains at the nominal Δ and the current heading estimate.
    pub fn gains(&self) -> Result<GainsReport, ServoError> {
        self.gains_at(self.options.nominal_dt_s, self.estimator.heading_rad())
    }

    /// The regulator (full 6×6 solve), pre-filter, closed-loop poles, steady-state Kalman
    /// gain (the dual DARE) and heading pole at Δ and heading c.
    pub fn gains_at(&self, dt_s: f64, heading_rad: f64) -> Result<GainsReport, ServoError> {
        let err = |key, e| ServoError {
            profile: self.profile_name.clone(),
            key,
            problem: ServoProblem::Dare(e),
        };
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(ServoError {
                profile: self.profile_name.clone(),
                key: "--dt",
                problem: ServoProblem::BadValue {
                    value: dt_s,
                    want: "finite and > 0",
                },
            });
        }
        let a = self.model.a1(dt_s, heading_rad);
        let b = self.model.b1(dt_s, heading_rad);
        let sol = dare::solve(&a, &b, &self.q, &self.r).map_err(|e| err("servo.q", e))?;
        let n1 = n1(&self.model, &sol.k, dt_s, heading_rad)
            .ok_or_else(|| err("model", DareError::Singular))?;
        let poles = dare::eigenvalue_magnitudes(&(a - b * sol.k)).ok_or_else(|| {
            err(
                "servo.q",
                DareError::NotStabilising {
                    spectral_radius: f64::NAN,
                },
            )
        })?;
        // The filter's DARE is the regulator's dual: (Aᵀ, Hᵀ, F1, H1).
        let mut ht = Matrix6x3::zeros();
        ht.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&Matrix3::identity());
        let kf = dare::solve(&a.transpose(), &ht, &self.process, &self.measurement)
            .map_err(|e| err("servo.process_noise", e))?;
        let pf = kf.p;
        let s = ht.transpose() * pf * ht + self.measurement;
        let l = dare::solve_linear(&s, &(ht.transpose() * pf))
            .ok_or_else(|| err("servo.measurement_noise_m2", DareError::Singular))?
            .transpose();
        Ok(GainsReport {
            dt_s,
            heading_rad,
            p: rows(&sol.p),
            k1: rows(&sol.k),
            n1: rows(&n1),
            closed_loop_pole_magnitudes: poles,
            kalman_gain: rows(&l),
            k2: heading_pole(
                self.heading_gamma,
                self.heading_tau_s,
                self.options.nominal_dt_s,
                dt_s,
            ),
            residual: sol.residual,
            iterations: sol.iterations,
        })
    }

    /// The translation input before saturation.
    fn translation_law(&self, k1: &Gain, dt_s: f64, c: f64, r: &Reference) -> Vector3<f64> {
        let x = self.estimator.state();
        let v_ref = Vector3::from(r.velocity_mps);
        let p_ref = Vector3::from(r.position_m);
        let mut xr = Vector6::zeros();
        xr.fixed_rows_mut::<3>(0).copy_from(&v_ref);
        xr.fixed_rows_mut::<3>(3).copy_from(&p_ref);
        if self.options.paper_prefilter {
            let a = self.model.a1(dt_s, c);
            let b = self.model.b1(dt_s, c);
            if let Some(n) = paper_n1(&a, &b, k1) {
                return -k1 * x + n * xr;
            }
        }
        let mut u = -k1 * (x - xr);
        // G⁻¹ (M_D T_D M_Dᵀ v_ref + Δ a_ref): holds v_ref and follows a_ref.
        // With the wind estimate d: the lag pulls toward G u + d, so hold v_ref − d.
        let hold = v_ref - self.estimator.disturbance_mps();
        let step = if self.options.paper_prefilter {
            Vector3::zeros()
        } else {
            Vector3::from(r.acceleration_mps2) * dt_s
        };
        if let Some(ff) = self
            .model
            .input_for(&self.estimator.body_lag(dt_s), c, &hold, &step)
        {
            u += ff;
        }
        u
    }
}

/// Clamps `v` to ±`max`; sets `*hit` when it had to.
pub fn clamp_to(v: f64, max: f64, hit: &mut bool) -> f64 {
    if v > max {
        *hit = true;
        max
    } else if v < -max {
        *hit = true;
        -max
    } else {
        v
    }
}

impl Controller for LqgServo {
    fn reset(&mut self, _t_s: f64, measurement: &Measurement) {
        self.estimator.reset(measurement);
        self.sent = Vector3::zeros();
        self.sent_yaw_radps = 0.0;
    }

    fn tick(&mut self, input: &TickInput) -> Result<TickOutput, TickFault> {
        self.estimator
            .step(input, &self.sent, self.sent_yaw_radps)?;
        let dt = input.dt_s;
        let c = self.estimator.heading_rad();
        let r = &input.reference;

        let k1 = self.feedback_gain(dt, c);
        let u = self.translation_law(&k1, dt, c, r);

        if dt != self.k2_dt_s {
            self.k2_dt_s = dt;
            self.k2 = heading_pole(
                self.heading_gamma,
                self.heading_tau_s,
                self.options.nominal_dt_s,
                dt,
            );
        }
        let k2 = self.k2;
        let e = frames::wrap_angle_rad(r.heading_rad - c);
        let c_dot = ((1.0 - k2) / dt * e + r.heading_rate_radps) / self.model.gain_yaw;
        let yaw = frames::yaw_rate_command_radps(c_dot);

        let mut saturated = false;
        let command = Command {
            roll_rad: clamp_to(u[0], self.tilt_max_rad, &mut saturated),
            pitch_rad: clamp_to(u[1], self.tilt_max_rad, &mut saturated),
            vz_mps: clamp_to(u[2], self.vz_max_mps, &mut saturated),
            yaw_rate_radps: clamp_to(yaw, self.yaw_rate_max_radps, &mut saturated),
        };
        self.sent = command.translation_input();
        self.sent_yaw_radps = command.yaw_rate_radps;
        Ok(TickOutput {
            command,
            estimate: self.estimator.estimate(),
            saturated,
        })
    }

    fn state(&self) -> ControllerState {
        ControllerState::Lqg(LqgState {
            filter: self.estimator.filter_state(),
            sent_input: [self.sent[0], self.sent[1], self.sent[2]],
            sent_yaw_rate_radps: self.sent_yaw_radps,
            heading_pole_dt_s: self.k2_dt_s,
            heading_pole: self.k2,
            body_gain_dt_s: self.k_body_dt_s,
            body_gain: rows(&self.k_body),
            world_gain: rows(&self.k_world),
        })
    }

    fn restore(&mut self, state: &ControllerState) -> Result<(), String> {
        let ControllerState::Lqg(s) = state else {
            return Err(format!(
                "the state of a {} controller cannot be restored into the LQG servo",
                state.kind()
            ));
        };
        self.estimator.restore_filter(&s.filter);
        self.sent = Vector3::from(s.sent_input);
        self.sent_yaw_radps = s.sent_yaw_rate_radps;
        self.k2_dt_s = s.heading_pole_dt_s;
        self.k2 = s.heading_pole;
        self.k_body_dt_s = s.body_gain_dt_s;
        self.k_body = Gain::from_fn(|i, j| s.body_gain[i][j]);
        self.k_world = Gain::from_fn(|i, j| s.world_gain[i][j]);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The prediction as A P Aᵀ with the dense 9×9 A (what `predict` computes block by block).
    fn predict_dense(e: &mut Estimator, dt_s: f64, u: &Vector3<f64>, yaw: f64) {
        let a1 = e.model.a1(dt_s, e.c);
        let b1 = e.model.b1(dt_s, e.c);
        let mut a = Matrix9::zeros();
        a.fixed_view_mut::<6, 6>(0, 0).copy_from(&a1);
        for i in 6..9 {
            a[(i, i)] = 1.0;
        }
        let d = e.x.fixed_rows::<3>(6).into_owned();
        let x1 = a1 * e.x.fixed_rows::<6>(0) + b1 * u;
        e.x.fixed_rows_mut::<6>(0).copy_from(&x1);
        if e.disturbance_diffusion > 0.0 {
            let lag = Matrix3::identity() - a1.fixed_view::<3, 3>(0, 0);
            a.fixed_view_mut::<3, 3>(0, 6).copy_from(&lag);
            let dv = lag * d;
            for i in 0..3 {
                e.x[i] += dv[i];
            }
        }
        let mut p = a * e.p * a.transpose();
        let mut pvp = p.fixed_view_mut::<6, 6>(0, 0);
        pvp += e.process;
        if e.disturbance_diffusion > 0.0 {
            for i in 6..9 {
                p[(i, i)] += e.disturbance_diffusion * dt_s;
            }
        }
        e.p = (p + p.transpose()) * 0.5;
        e.c = e.model.heading_step(e.c, dt_s, yaw);
        e.pc += e.heading_process;
    }

    /// The Kalman correction with a general linear solve (what `update` does by Cholesky).
    fn update_dense(e: &mut Estimator, m: &Measurement) {
        let s = e.p.fixed_view::<3, 3>(3, 3).into_owned() + e.measurement;
        let pht: Matrix9x3 = e.p.fixed_view::<9, 3>(0, 3).into_owned();
        let kt = dare::solve_linear(&s, &pht.transpose()).unwrap();
        let k: Matrix9x3 = kt.transpose();
        let y = Vector3::from(m.position_m) - e.x.fixed_rows::<3>(3);
        e.x += k * y;
        let p = e.p - k * pht.transpose();
        e.p = (p + p.transpose()) * 0.5;
        let kc = e.pc / (e.pc + e.heading_measurement);
        e.c = frames::wrap_angle_rad(e.c + kc * frames::wrap_angle_rad(m.heading_rad - e.c));
        e.pc *= 1.0 - kc;
    }

    #[test]
    fn the_closed_form_inverse_inverts_and_refuses_what_is_not_positive_definite() {
        let s = Matrix3::new(4.0, 1.0, 0.5, 1.0, 3.0, -0.25, 0.5, -0.25, 2.0);
        let inv = inverse_spd3(&s).unwrap();
        assert!((inv * s - Matrix3::identity()).amax() < 1e-15);
        let indefinite = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert_eq!(inverse_spd3(&indefinite), None);
        assert_eq!(inverse_spd3(&(s * f64::NAN)), None);
        assert_eq!(inverse_spd3(&Matrix3::zeros()), None);
    }

    /// A filter of the built-in profile, with or without the wind estimate, reset at rest.
    fn filter_at_rest(wind: bool, heading_rad: f64) -> Estimator {
        let profile = Profile::builtin("ardrone2").unwrap();
        let mut e = if wind {
            Estimator::with_disturbance(&profile)
        } else {
            Estimator::new(&profile)
        };
        e.reset(&Measurement {
            position_m: [0.5, -1.0, 1.2],
            heading_rad,
        });
        e
    }

    #[test]
    fn covariance_keeps_z_apart() {
        // The shape `mul_xy_z`, `gain_xy_z` and `subtract_symmetric` rely on: through turns,
        // gaps in the measurements and varying Δ, no covariance entry couples a z state with
        // an x or y one (exactly zero, with and without the wind estimate)…
        for wind in [false, true] {
            let mut e = filter_at_rest(wind, -2.0);
            for k in 0..3000 {
                let t = k as f64 * 0.01;
                let dt = 0.01 + 0.004 * (k as f64 * 0.37).sin();
                let u = Vector3::new(0.1 * (t * 1.3).sin(), -0.08 * (t * 0.7).cos(), 0.3);
                e.predict(dt, &u, 1.5 * (t * 0.5).sin());
                if k % 5 != 2 {
                    e.update(&Measurement {
                        position_m: [t.cos(), 0.5 * t.sin(), 1.2 + 0.1 * (3.0 * t).sin()],
                        heading_rad: -2.0 + 0.9 * t,
                    });
                }
                for i in 0..9 {
                    for j in 0..9 {
                        if (i % 3 == 2) != (j % 3 == 2) {
                            assert_eq!(e.p[(i, j)], 0.0, "wind {wind}, tick {k}, P[{i},{j}]");
                        }
                    }
                }
            }
            assert!(e.p[(3, 4)] != 0.0, "x and y do couple (the heading turned)");
        }
        // …and on such blocks the structured products are the full ones, bit for bit.
        let block = |s: f64| {
            Matrix3::new(
                0.3 * s.sin(),
                -1.7 * s.cos(),
                0.0,
                2.1 * (2.0 * s).sin(),
                0.9 + s,
                0.0,
                0.0,
                0.0,
                -0.4 * s.cos(),
            )
        };
        for k in 0..200 {
            let (a, b) = (block(k as f64 * 0.37), block(k as f64 * 0.11 + 1.0));
            let (full, fast) = (a * b, mul_xy_z(&a, &b));
            // Equal as numbers: the same bits, but for the sign of a zero.
            for i in 0..9 {
                assert_eq!(full[i], fast[i]);
            }
            let pht = Matrix9x3::from_fn(|i, j| {
                if (i % 3 == 2) == (j == 2) {
                    (i as f64 + 1.0) * (k as f64 * 0.3 + j as f64).cos()
                } else {
                    0.0
                }
            });
            let (full, fast) = (pht * a, gain_xy_z(&pht, &a));
            for i in 0..27 {
                assert_eq!(full[i], fast[i]);
            }
        }
    }

    /// Block-wise prediction and closed-form correction against the dense products, over a
    /// flight of varying Δ, heading, inputs and missing measurements, with and without the
    /// wind estimate (which couples v and d).
    #[test]
    fn the_structured_filter_is_the_dense_one() {
        for wind in [false, true] {
            let mut fast = filter_at_rest(wind, 2.9);
            let mut dense = fast.clone();
            for k in 0..2000 {
                let t = k as f64 * 0.01;
                let dt = 0.01 + 0.004 * (k as f64 * 0.37).sin();
                let u = Vector3::new(0.1 * (t * 1.3).sin(), -0.08 * (t * 0.7).cos(), 0.3);
                let yaw = 0.8 * (t * 0.5).sin();
                fast.predict(dt, &u, yaw);
                predict_dense(&mut dense, dt, &u, yaw);
                if k % 7 != 3 {
                    let m = Measurement {
                        position_m: [t.cos(), 0.5 * t.sin(), 1.2 + 0.1 * (3.0 * t).sin()],
                        heading_rad: 2.9 + 0.4 * t,
                    };
                    fast.update(&m);
                    update_dense(&mut dense, &m);
                }
                let dx = (fast.x - dense.x).amax();
                let dp = (fast.p - dense.p).amax() / dense.p.amax();
                assert!(
                    dx < 1e-9 && dp < 1e-9,
                    "wind {wind}, tick {k}: {dx:e} {dp:e}"
                );
                assert_eq!(fast.c.to_bits(), dense.c.to_bits());
            }
            // The filter did follow the measurements (the comparison is not of two idle states).
            assert!(fast.x[3].abs() > 0.1 && fast.p[(3, 3)] < 0.01);
        }
    }
}
