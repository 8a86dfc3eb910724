//! The servo's plant models, discretised with the measured time step Δ.
//!
//! **Translation.** State `x1 = [v; p]` (world-frame velocity and position), input
//! `u1 = [φ, θ, ż]` in the signs of [`dronecine_backend::frames`]. Each body axis (forward, left, up) is a
//! first-order lag toward `K·u` mapped through [`frames::INPUT_TO_BODY`]; the lag acts on the
//! **body-frame** velocity (the paper's world-frame lag is only right when τ_φ = τ_θ):
//!
//! ```text
//! x1[k+1] = A1 x1[k] + B1 u1[k]
//! A1 = [[I − M_D T_D M_Dᵀ, 0], [Δ I, I]]     B1 = [[M_D T_D P K], [0]]
//! ```
//!
//! with `M_D = Rz(c)` ([`frames::body_to_world`]), `P` = [`frames::INPUT_TO_BODY`],
//! `K = diag(K_φ, K_θ, K_ż)` and the exact discrete pole `T_D = diag(1 − exp(−Δ/τ))` (body
//! order, [`frames::body_taus_s`]).
//!
//! **Heading.** `c[k+1] = c[k] + K_ψ Δ ċ` with `ċ` the counter-clockwise rate a yaw-rate command
//! asks for ([`frames::heading_rate_radps`]), wrapped to (−π, π].
//!
//! Nothing here allocates.

use dronecine_profile::Profile;
use nalgebra::{Matrix2, Matrix3, Matrix6, SMatrix, Vector2, Vector3, Vector6};

use dronecine_backend::frames;
use dronecine_math as math;

/// 6×3 input matrix of the translation model.
pub type Matrix6x3 = SMatrix<f64, 6, 3>;

/// The plant parameters the servo models (`[model]` of a profile).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelParams {
    /// `[K_φ, K_θ, K_ż]`, in the input order `[φ, θ, ż]`.
    pub gains: [f64; 3],
    /// `[τ_φ, τ_θ, τ_ż]`, in the input order, seconds.
    pub taus_s: [f64; 3],
    /// K_ψ: heading rate per commanded yaw rate.
    pub gain_yaw: f64,
}

impl ModelParams {
    pub fn from_profile(profile: &Profile) -> ModelParams {
        let m = &profile.model;
        ModelParams {
            gains: [m.gain_roll_mps_per_rad, m.gain_pitch_mps_per_rad, m.gain_vz],
            taus_s: [m.tau_roll_s, m.tau_pitch_s, m.tau_vz_s],
            gain_yaw: m.gain_yaw,
        }
    }

    /// `P·K`: body-frame velocity `[forward, left, up]` per unit input `[φ, θ, ż]` at steady
    /// state. A signed permutation (one non-zero per row and column).
    pub fn input_to_body_velocity(&self) -> Matrix3<f64> {
        frames::INPUT_TO_BODY * Matrix3::from_diagonal(&Vector3::from(self.gains))
    }

    /// The body-order time constants `[τ_forward, τ_left, τ_up]`.
    pub fn body_taus_s(&self) -> [f64; 3] {
        frames::body_taus_s(self.taus_s[0], self.taus_s[1], self.taus_s[2])
    }

    /// Diagonal of `T_D = 1 − exp(−Δ/τ)` in body order (forward, left, up).
    pub fn body_lag(&self, dt_s: f64) -> Vector3<f64> {
        let t = self.body_taus_s();
        Vector3::new(
            -math::exp_m1(-dt_s / t[0]),
            -math::exp_m1(-dt_s / t[1]),
            -math::exp_m1(-dt_s / t[2]),
        )
    }

    /// `M_D T_D M_Dᵀ`: the world-frame velocity lag over one step.
    pub fn world_lag(&self, dt_s: f64, heading_rad: f64) -> Matrix3<f64> {
        let m = frames::body_to_world(heading_rad);
        m * Matrix3::from_diagonal(&self.body_lag(dt_s)) * m.transpose()
    }

    /// `G = M_D T_D P K`: the velocity change one step of input makes (the top block of B1).
    pub fn input_matrix(&self, dt_s: f64, heading_rad: f64) -> Matrix3<f64> {
        frames::body_to_world(heading_rad)
            * Matrix3::from_diagonal(&self.body_lag(dt_s))
            * self.input_to_body_velocity()
    }

    /// [`ModelParams::world_lag`] and [`ModelParams::input_matrix`] together (one rotation),
    /// from the step's [`ModelParams::body_lag`], which depends on Δ only and which the
    /// caller keeps: what the Kalman filter's prediction needs each tick.
    pub fn lag_and_input(
        &self,
        body_lag: &Vector3<f64>,
        heading_rad: f64,
    ) -> (Matrix3<f64>, Matrix3<f64>) {
        let m = frames::body_to_world(heading_rad);
        let mt = m * Matrix3::from_diagonal(body_lag);
        (mt * m.transpose(), mt * self.input_to_body_velocity())
    }

    /// The input that meets `M_D T_D M_Dᵀ·hold + step` (hold the velocity `hold`, change it by
    /// `step` over the step): `G⁻¹(M_D T_D M_Dᵀ·hold + step)` with `G` =
    /// [`ModelParams::input_matrix`], in closed form. `G = Rz(c)·T_D·P·K` is a rotation, a
    /// diagonal, a signed permutation and a diagonal, so this is
    /// `K⁻¹·Pᵀ·(Rz(c)ᵀ·hold + T_D⁻¹·Rz(c)ᵀ·step)`: one rotation and six divisions, no
    /// elimination. `body_lag` is the step's [`ModelParams::body_lag`] (T_D). `None` when G
    /// is singular (a zero gain or lag) or the result is not finite.
    pub fn input_for(
        &self,
        body_lag: &Vector3<f64>,
        heading_rad: f64,
        hold: &Vector3<f64>,
        step: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        let mt = frames::body_to_world(heading_rad).transpose();
        let body = mt * hold + (mt * step).component_div(body_lag);
        let u =
            (frames::INPUT_TO_BODY.transpose() * body).component_div(&Vector3::from(self.gains));
        u.iter().all(|x| x.is_finite()).then_some(u)
    }

    /// A1(Δ, c).
    pub fn a1(&self, dt_s: f64, heading_rad: f64) -> Matrix6<f64> {
        let mut a = Matrix6::identity();
        let lag = self.world_lag(dt_s, heading_rad);
        a.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() - lag));
        a.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(Matrix3::identity() * dt_s));
        a
    }

    /// B1(Δ, c).
    pub fn b1(&self, dt_s: f64, heading_rad: f64) -> Matrix6x3 {
        let mut b = Matrix6x3::zeros();
        b.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&self.input_matrix(dt_s, heading_rad));
        b
    }

    /// One step of the translation model: `A1 x + B1 u`.
    pub fn step(
        &self,
        x: &Vector6<f64>,
        u: &Vector3<f64>,
        dt_s: f64,
        heading_rad: f64,
    ) -> Vector6<f64> {
        self.a1(dt_s, heading_rad) * x + self.b1(dt_s, heading_rad) * u
    }

    /// One step of the heading model: `wrap(c + K_ψ Δ ċ(ψ̇))`.
    pub fn heading_step(&self, heading_rad: f64, dt_s: f64, yaw_rate_command_radps: f64) -> f64 {
        frames::wrap_angle_rad(
            heading_rad + self.gain_yaw * dt_s * frames::heading_rate_radps(yaw_rate_command_radps),
        )
    }

    /// The single-input 2-state problem of body axis `axis` (0 forward, 1 left, 2 up) taken
    /// out of the body-frame model (heading 0): state `[v_axis, p_axis]`, and the index of
    /// the one input that drives this axis. `None` if `P·K` is not a signed permutation
    /// (then the problem does not split).
    pub fn body_axis(&self, dt_s: f64, axis: usize) -> Option<(Matrix2<f64>, Vector2<f64>, usize)> {
        let pk = self.input_to_body_velocity();
        let row = pk.row(axis);
        let mut input = None;
        for j in 0..3 {
            if row[j] != 0.0 {
                if input.is_some() {
                    return None;
                }
                input = Some(j);
            }
        }
        let j = input?;
        let a = self.a1(dt_s, 0.0);
        let b = self.b1(dt_s, 0.0);
        let (v, p) = (axis, axis + 3);
        Some((
            Matrix2::new(a[(v, v)], a[(v, p)], a[(p, v)], a[(p, p)]),
            Vector2::new(b[(v, j)], b[(p, j)]),
            j,
        ))
    }
}

/// `S(c) = blockdiag(Rz(c), Rz(c))`: body-frame `[v; p]` → world frame.
pub fn rotation6(heading_rad: f64) -> Matrix6<f64> {
    let m = frames::body_to_world(heading_rad);
    let mut s = Matrix6::zeros();
    s.fixed_view_mut::<3, 3>(0, 0).copy_from(&m);
    s.fixed_view_mut::<3, 3>(3, 3).copy_from(&m);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> ModelParams {
        ModelParams {
            gains: [17.5, 12.0, 1.0],
            taus_s: [1.7, 0.9, 1.25],
            gain_yaw: 1.0,
        }
    }

    /// The closed-form `G⁻¹` agrees with a general linear solve of `G u = target`, at any
    /// heading and step, and declines a singular G.
    #[test]
    fn closed_form_input_inverts_the_input_matrix() {
        let m = params();
        for (dt, c) in [(0.01, 0.0), (0.0123, 0.7), (0.05, -2.0), (0.002, 3.1)] {
            let hold = Vector3::new(0.4, -1.3, 0.2);
            let step = Vector3::new(-0.02, 0.005, 0.01);
            let u = m.input_for(&m.body_lag(dt), c, &hold, &step);
            let lag = m.world_lag(dt, c);
            let g = m.input_matrix(dt, c);
            // The filter's pair, from the kept body lag, is the same two matrices.
            let (lag2, g2) = m.lag_and_input(&m.body_lag(dt), c);
            assert!((lag2 - lag).norm() < 1e-15 && (g2 - g).norm() < 1e-15);
            let want = g.lu().solve(&(lag * hold + step)).unwrap();
            let u = u.unwrap();
            assert!(
                (u - want).norm() < 1e-12 * want.norm(),
                "{dt} {c}: {u:?} {want:?}"
            );
            // And it is an inverse: G u gives the target back.
            assert!((g * u - (lag * hold + step)).norm() < 1e-14);
        }
        let mut dead = params();
        dead.gains[1] = 0.0;
        assert!(dead
            .input_for(&dead.body_lag(0.01), 0.3, &Vector3::x(), &Vector3::y())
            .is_none());
    }

    /// The body-frame lag: with τ_φ ≠ τ_θ, a pitch command at heading c accelerates along the
    /// heading only, with τ_θ, whatever c is (the world-frame lag would leak across axes).
    #[test]
    fn pitch_lags_along_the_heading_with_tau_theta() {
        let m = params();
        let dt = 0.01;
        for c in [0.0, 0.7, -2.0, 3.0] {
            let mut x = Vector6::zeros();
            let u = Vector3::new(0.0, -0.1, 0.0); // nose down: forward
            for _ in 0..100 {
                x = m.step(&x, &u, dt, c);
            }
            let v = x.fixed_rows::<3>(0).into_owned();
            let fwd = frames::body_to_world(c) * Vector3::x();
            // 1 s of a first-order lag toward K_θ·0.1 with τ_θ.
            let want = 12.0 * 0.1 * (1.0 - (-1.0f64 / 0.9).exp());
            assert!((v - fwd * want).norm() < 1e-12, "{c}: {v:?}");
        }
    }

    #[test]
    fn equals_the_paper_model_when_taus_are_equal() {
        let mut m = params();
        m.taus_s = [1.3, 1.3, 1.25];
        let (dt, c) = (0.02, 1.1);
        let t = m.body_lag(dt);
        // The paper: (I − T_D) on the world velocity.
        let lag = m.world_lag(dt, c);
        let paper = Matrix3::from_diagonal(&t);
        assert!((lag - paper).norm() < 1e-15);
    }

    #[test]
    fn axes_split_into_single_input_problems() {
        let m = params();
        let dt = 0.01;
        let ab = m.a1(dt, 0.0);
        let bb = m.b1(dt, 0.0);
        for axis in 0..3 {
            let (a, b, j) = m.body_axis(dt, axis).unwrap();
            assert_eq!(a[(0, 0)], ab[(axis, axis)]);
            assert_eq!(b[0], bb[(axis, j)]);
        }
        // forward ← θ, left ← φ, up ← ż (frames::INPUT_TO_BODY).
        assert_eq!(m.body_axis(dt, 0).unwrap().2, 1);
        assert_eq!(m.body_axis(dt, 1).unwrap().2, 0);
        assert_eq!(m.body_axis(dt, 2).unwrap().2, 2);
    }

    #[test]
    fn world_model_is_the_rotated_body_model() {
        let m = params();
        for c in [-3.0, -1.0, 0.4, 2.5] {
            let s = rotation6(c);
            assert!((m.a1(0.01, c) - s * m.a1(0.01, 0.0) * s.transpose()).norm() < 1e-14);
            assert!((m.b1(0.01, c) - s * m.b1(0.01, 0.0)).norm() < 1e-14);
        }
    }

    #[test]
    fn heading_step_wraps_and_follows_the_yaw_sign() {
        let m = params();
        // A clockwise yaw-rate command decreases the heading.
        assert!(m.heading_step(0.0, 0.1, 0.5) < 0.0);
        let c = m.heading_step(3.1, 0.1, -1.0); // ccw across π
        assert!((c - (3.2 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
    }
}
