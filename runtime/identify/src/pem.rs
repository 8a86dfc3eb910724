//! The prediction-error fit of the translation axes: maximum likelihood through a Kalman
//! filter whose model carries the disturbance the drone really flies in (wind), so that the
//! fit holds on a draughty stage and in closed loop (the calibration's hover hold, any
//! `shoot` log), where the plain output-error fit of [`super`] is biased or refused.
//!
//! **Model.** Per tick (command held over Δ, heading frozen at the tick's mid-heading) the
//! exact discretisation of the servo's model behind an attitude lag and a latency:
//! `ȧ = (K·u(t − latency) − a)/τ_a`, `v̇_b = (a − v_b)/τ` per body axis, plus a drift `d`
//! that moves the drone directly: `ḋ = (w − d)/τ_d`, `w` a random walk of intensity `q`
//! (m²/s³ per axis); positions are measured with white noise of variance `r`. Horizontal:
//! states `[x, y, vx, vy, a_fwd, a_left, wx, wy, dx, dy]`, gains `[K_φ, K_θ]`, time
//! constants `[τ_φ, τ_θ, τ_a, τ_d]`. Vertical: `[z, ż, d]`, `d` a random walk, one gain
//! climbing and one descending (the AR.Drone descends about twice as fast as it climbs),
//! one τ.
//!
//! The drift is deliberately *not* fed through the drag's lag, although wind physically
//! is: tied to τ, a disturbance model that misses the real gusts' spectrum pulls τ (and K)
//! with it. Kept apart (a Box–Jenkins structure), the open-loop tests' K and τ stay unbiased
//! whatever the gusts' spectrum; `τ_d` lets the drift be as smooth as the gusts are. The attitude lag is held below half the drag's τ:
//! two lags in cascade answer the input alike whichever is which.
//!
//! **Likelihood.** The filter's covariances do not depend on the gains, and the innovations
//! are affine in them: running one filter mean on the data with no input and one per gain
//! with a unit input and no data gives `e = e₀ − Σ K_j h_j`, so for fixed (τs, latency,
//! q/r) the gains are a weighted least squares in closed form, and the common scale σ² of
//! every covariance too. What is left, `ℓ(τs, λ = ln q/r, latency) = ½ Σ ln det S̃ + ½ n ln
//! σ̂²`, is minimised by a grid, then Nelder–Mead; so is the same model without the drift
//! (q → 0), and of the two the one whose predictions (below) explain the tests better (by
//! [`CALM_R2_MARGIN`], the drift's otherwise) is kept: a drift free to move as it likes can take an autopilot's own response (its shaped
//! lean) for wind, which the likelihood prefers and the predictions do not. The transition is reused while the tick's
//! length and heading hold, and the covariance recursion stops once converged (the steady
//! state), which keeps a fit of an eight-minute calibration to about a second. The first
//! [`BURN_IN`] measurements of each segment only start the filter (a diffuse start).
//!
//! **Intervals and quality.** 95 % intervals from the inverse Hessian (central differences)
//! of ℓ over the gains, the τs and λ. The quality figure is the R² of the fitted model's
//! [`HORIZON_S`]-ahead predictions (from the filtered state, driven by the commands alone)
//! against a constant-velocity extrapolation from the same state: the share of the motion
//! over a second that the model, and not drift, explains.

use dronecine_math as math;
use nalgebra::{SMatrix, SVector};

use super::{frames, AxisData, Estimate, PlaneData, TAU_MAX_S, TAU_MIN_S};

/// Measurements per segment that only start the filter.
pub const BURN_IN: usize = 5;
/// The prediction horizon of the quality figure, seconds.
pub const HORIZON_S: f64 = 1.0;
const Z95: f64 = 1.959964;
/// The search range of λ = ln(q/r), q in m²/s³, r in m².
const LAMBDA_MIN: f64 = -10.0;
const LAMBDA_MAX: f64 = 35.0;
/// The model's tick lengths and headings move only by more than these (so that the
/// transition can be reused from tick to tick; the rotation error stays below 1 %).
const DT_QUANTUM_S: f64 = 2e-5;
const HEADING_QUANTUM_RAD: f64 = 1e-2;

/// A value that follows its input only when the input moves by more than a quantum (a dead
/// band: noise around a steady value does not flip it).
struct Held {
    quantum: f64,
    value: Option<f64>,
}

impl Held {
    fn new(quantum: f64) -> Held {
        Held {
            quantum,
            value: None,
        }
    }

    fn next(&mut self, x: f64) -> f64 {
        match self.value {
            Some(v) if (x - v).abs() <= self.quantum => v,
            _ => {
                self.value = Some(x);
                x
            }
        }
    }
}

/// The command latency's range and where its search starts, seconds.
const LATENCY_MAX_S: f64 = 0.3;
const LATENCY_START_S: f64 = 0.03;
/// The attitude lag's range: from nothing to this share of the faster velocity lag.
const ATTITUDE_LAG_MIN_S: f64 = 1e-3;
const ATTITUDE_LAG_MAX_SHARE: f64 = 0.5;
/// How much better the model without drift must predict the tests to be kept instead of the
/// one with: where both predict alike (a drift that stays small), the drift's model, whose
/// intervals allow for the wind.
const CALM_R2_MARGIN: f64 = 0.01;

/// Where the search for the attitude lag starts: tum_ardrone's 1/7 s for the AR.Drone, and
/// either side of it (an autopilot that shapes the lean asked, as ArduCopter's input shaping
/// and angle loop do, lags about 0.3 s).
const ATTITUDE_LAG_STARTS_S: [f64; 3] = [0.05, 0.15, 0.35];

/// One tick of a segment: the interval, the heading it flies at, the drive of each gain's
/// column, the measurement at its start.
#[derive(Clone, Copy, Debug)]
struct Tick<const M: usize, const L: usize> {
    dt: f64,
    heading: f64,
    u: SVector<f64, L>,
    y: Option<SVector<f64, M>>,
}

/// A model family: `N` states, `M` measured outputs, `L` gains, `T` time constants.
trait Family<const N: usize, const M: usize, const L: usize> {
    /// Transition and the unit-gain input columns of one tick.
    fn step(tick: &Tick<M, L>, taus: &[f64]) -> (SMatrix<f64, N, N>, SMatrix<f64, N, L>);
    /// The process noise per unit intensity over `dt` (the disturbance's random walk).
    fn q(dt: f64) -> SMatrix<f64, N, N>;
    fn h() -> SMatrix<f64, M, N>;
    /// The start: the first measurement, nothing known of velocity and disturbance (in m²,
    /// (m/s)²).
    fn start(y: &SVector<f64, M>) -> (SVector<f64, N>, SVector<f64, N>);
    /// The allowed range of ln τ number `j` given all the ln τs `x`.
    fn ln_tau_range(_j: usize, _x: &[f64]) -> (f64, f64) {
        (math::ln(TAU_MIN_S), math::ln(TAU_MAX_S))
    }
    /// The index among the time constants of the drift's own (`None`: the drift is a plain
    /// random walk).
    const DRIFT_TAU: Option<usize>;
    /// The grid's starting ln τs at a common main ln τ `lt`: one start or more.
    fn grid_taus(lt: f64) -> Vec<Vec<f64>>;
    /// The inverse and the determinant of an innovation covariance.
    fn inv_det(s: &SMatrix<f64, M, M>) -> Option<(SMatrix<f64, M, M>, f64)>;
    /// Position rows and velocity rows (for the constant-velocity baseline).
    fn pos_vel(x: &SVector<f64, N>) -> (SVector<f64, M>, SVector<f64, M>);
}

struct Plane;
struct Vertical;

/// One body axis over one tick, exactly: the attitude (in velocity units, `a = K·attitude`)
/// lags the command with `τ_a`, the air-relative velocity lags `a` with `τ`:
/// `ȧ = (K·u − a)/τ_a`, `v̇ = (a − v)/τ`, `ṡ = v`. Returns `(s, v, a)` after `dt` from
/// `(0, v₀, a₀)` with input `ku = K·u`.
fn cascade(dt: f64, tau: f64, tau_a: f64, v0: f64, a0: f64, ku: f64) -> [f64; 3] {
    // Distinct time constants (the closed form divides by their difference).
    let tau_a = if (tau_a - tau).abs() < 1e-6 * tau {
        tau * (1.0 + 1e-6)
    } else {
        tau_a
    };
    let (ea, ev) = (math::exp(-dt / tau_a), math::exp(-dt / tau));
    let b = (a0 - ku) * tau_a / (tau_a - tau);
    let a = ku + (a0 - ku) * ea;
    let v = ku + (v0 - ku - b) * ev + b * ea;
    let s = ku * dt + (v0 - ku - b) * tau * (1.0 - ev) + b * tau_a * (1.0 - ea);
    [s, v, a]
}

/// States `[x, y, vx, vy, a_fwd, a_left, wx, wy]`: world position and velocity, the body
/// attitudes in velocity units, the world wind. Time constants `[τ_φ, τ_θ, τ_a]`.
impl Family<10, 2, 2> for Plane {
    const DRIFT_TAU: Option<usize> = Some(3);

    fn step(t: &Tick<2, 2>, taus: &[f64]) -> (SMatrix<f64, 10, 10>, SMatrix<f64, 10, 2>) {
        let dt = t.dt;
        // Body order: forward (τ_θ), left (τ_φ).
        let tb = [taus[1], taus[0]];
        let tau_a = taus[2];
        let (sn, cs) = math::sin_cos(t.heading);
        let r = nalgebra::Matrix2::new(cs, -sn, sn, cs);
        // Per body axis: the response to v₀, a₀ and K·u (columns of s, v, a).
        let resp: [[[f64; 3]; 3]; 2] = std::array::from_fn(|j| {
            [
                cascade(dt, tb[j], tau_a, 1.0, 0.0, 0.0),
                cascade(dt, tb[j], tau_a, 0.0, 1.0, 0.0),
                cascade(dt, tb[j], tau_a, 0.0, 0.0, 1.0),
            ]
        });
        let diag = |which: usize, row: usize| {
            nalgebra::Matrix2::new(resp[0][which][row], 0.0, 0.0, resp[1][which][row])
        };
        let rt = r.transpose();
        // Air-relative body velocity vb = Rᵀ(v − w).
        let s_v = r * diag(0, 0) * rt;
        let v_v = r * diag(0, 1) * rt;
        let i2 = nalgebra::Matrix2::<f64>::identity();
        let mut f = SMatrix::<f64, 10, 10>::identity();
        f.fixed_view_mut::<2, 2>(0, 2).copy_from(&s_v);
        f.fixed_view_mut::<2, 2>(0, 4).copy_from(&(r * diag(1, 0)));
        // The drift d lags the random walk w with τ_d: ḋ = (w − d)/τ_d, and moves the drone.
        let ed = math::exp(-dt / taus[3]);
        let wd = taus[3] * (1.0 - ed);
        f.fixed_view_mut::<2, 2>(0, 6).copy_from(&(i2 * (dt - wd)));
        f.fixed_view_mut::<2, 2>(0, 8).copy_from(&(i2 * wd));
        f.fixed_view_mut::<2, 2>(8, 6).copy_from(&(i2 * (1.0 - ed)));
        f.fixed_view_mut::<2, 2>(8, 8).copy_from(&(i2 * ed));
        f.fixed_view_mut::<2, 2>(2, 2).copy_from(&v_v);
        f.fixed_view_mut::<2, 2>(2, 4).copy_from(&(r * diag(1, 1)));
        f.fixed_view_mut::<2, 2>(4, 4).copy_from(&diag(1, 2));
        // Unit gains: body target forward = −θ (K_θ), left = −φ (K_φ), signs from
        // frames::INPUT_TO_BODY.
        let p = frames::INPUT_TO_BODY;
        let targets = [
            nalgebra::Vector2::new(0.0, p[(1, 0)] * t.u[0]),
            nalgebra::Vector2::new(p[(0, 1)] * t.u[1], 0.0),
        ];
        let mut g = SMatrix::<f64, 10, 2>::zeros();
        for (j, tg) in targets.iter().enumerate() {
            let d = diag(2, 0) * tg;
            g.fixed_view_mut::<2, 1>(0, j).copy_from(&(r * d));
            let d = diag(2, 1) * tg;
            g.fixed_view_mut::<2, 1>(2, j).copy_from(&(r * d));
            let d = diag(2, 2) * tg;
            g.fixed_view_mut::<2, 1>(4, j).copy_from(&d);
        }
        (f, g)
    }

    fn grid_taus(lt: f64) -> Vec<Vec<f64>> {
        ATTITUDE_LAG_STARTS_S
            .iter()
            .map(|lag| vec![lt, lt, math::ln(*lag), lt])
            .collect()
    }

    /// The two lags in cascade answer the input alike whichever is which; the attitude's is
    /// the faster one by definition, and may vanish.
    fn ln_tau_range(j: usize, x: &[f64]) -> (f64, f64) {
        let main = (math::ln(TAU_MIN_S), math::ln(TAU_MAX_S));
        if j != 2 {
            return main;
        }
        let slowest_fast = x[0].min(x[1]).clamp(main.0, main.1) + math::ln(ATTITUDE_LAG_MAX_SHARE);
        (
            math::ln(ATTITUDE_LAG_MIN_S),
            slowest_fast.max(math::ln(ATTITUDE_LAG_MIN_S)),
        )
    }

    fn q(dt: f64) -> SMatrix<f64, 10, 10> {
        let mut q = SMatrix::<f64, 10, 10>::zeros();
        q[(6, 6)] = dt;
        q[(7, 7)] = dt;
        q
    }

    fn h() -> SMatrix<f64, 2, 10> {
        let mut h = SMatrix::<f64, 2, 10>::zeros();
        h[(0, 0)] = 1.0;
        h[(1, 1)] = 1.0;
        h
    }

    fn start(y: &SVector<f64, 2>) -> (SVector<f64, 10>, SVector<f64, 10>) {
        let mut x = SVector::<f64, 10>::zeros();
        x[0] = y[0];
        x[1] = y[1];
        let p = SVector::<f64, 10>::from_column_slice(&[
            0.0, 0.0, 4.0, 4.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ]);
        (x, p)
    }

    fn inv_det(s: &SMatrix<f64, 2, 2>) -> Option<(SMatrix<f64, 2, 2>, f64)> {
        let d = s.determinant();
        (d > 0.0).then(|| s.try_inverse().map(|i| (i, d))).flatten()
    }

    fn pos_vel(x: &SVector<f64, 10>) -> (SVector<f64, 2>, SVector<f64, 2>) {
        let v: SVector<f64, 2> = x.fixed_rows::<2>(2).into();
        let d: SVector<f64, 2> = x.fixed_rows::<2>(8).into();
        (x.fixed_rows::<2>(0).into(), v + d)
    }
}

impl Family<3, 1, 2> for Vertical {
    const DRIFT_TAU: Option<usize> = None;

    fn step(t: &Tick<1, 2>, taus: &[f64]) -> (SMatrix<f64, 3, 3>, SMatrix<f64, 3, 2>) {
        let dt = t.dt;
        let a = math::exp(-dt / taus[0]);
        let w = taus[0] * (1.0 - a);
        let f = SMatrix::<f64, 3, 3>::new(1.0, w, dt - w, 0.0, a, 1.0 - a, 0.0, 0.0, 1.0);
        let mut g = SMatrix::<f64, 3, 2>::zeros();
        for j in 0..2 {
            g[(0, j)] = (dt - w) * t.u[j];
            g[(1, j)] = (1.0 - a) * t.u[j];
        }
        (f, g)
    }

    fn grid_taus(lt: f64) -> Vec<Vec<f64>> {
        vec![vec![lt]]
    }

    fn q(dt: f64) -> SMatrix<f64, 3, 3> {
        let mut q = SMatrix::<f64, 3, 3>::zeros();
        q[(2, 2)] = dt;
        q
    }

    fn h() -> SMatrix<f64, 1, 3> {
        SMatrix::<f64, 1, 3>::new(1.0, 0.0, 0.0)
    }

    fn start(y: &SVector<f64, 1>) -> (SVector<f64, 3>, SVector<f64, 3>) {
        (
            SVector::<f64, 3>::new(y[0], 0.0, 0.0),
            SVector::<f64, 3>::new(0.0, 1.0, 0.25),
        )
    }

    fn inv_det(s: &SMatrix<f64, 1, 1>) -> Option<(SMatrix<f64, 1, 1>, f64)> {
        (s[0] > 0.0).then(|| (SMatrix::<f64, 1, 1>::new(1.0 / s[0]), s[0]))
    }

    fn pos_vel(x: &SVector<f64, 3>) -> (SVector<f64, 1>, SVector<f64, 1>) {
        (SVector::<f64, 1>::new(x[0]), SVector::<f64, 1>::new(x[1]))
    }
}

/// The sufficient statistics of one filter pass at fixed (τ, λ): the gains enter only here.
struct Pass<const L: usize> {
    /// Σ hᵀ S̃⁻¹ h, Σ hᵀ S̃⁻¹ e₀, Σ e₀ᵀ S̃⁻¹ e₀.
    a: SMatrix<f64, L, L>,
    b: SVector<f64, L>,
    c: f64,
    logdet: f64,
    /// Scalar measurements counted.
    n: usize,
}

impl<const L: usize> Pass<L> {
    fn ssr(&self, k: &SVector<f64, L>) -> f64 {
        (self.c - 2.0 * self.b.dot(k) + (k.transpose() * self.a * k)[0]).max(1e-300)
    }

    /// The concentrated negative log-likelihood at gains `k`.
    fn nll(&self, k: &SVector<f64, L>) -> f64 {
        let n = self.n as f64;
        0.5 * self.logdet + 0.5 * n * math::ln(self.ssr(k) / n)
    }

    /// The best gains (unexcited ones held at 0).
    fn gains(&self, excited: &[bool; L]) -> SVector<f64, L> {
        let mut a = self.a;
        let mut b = self.b;
        for j in 0..L {
            if !excited[j] {
                for i in 0..L {
                    a[(i, j)] = 0.0;
                    a[(j, i)] = 0.0;
                }
                a[(j, j)] = 1.0;
                b[j] = 0.0;
            }
        }
        a.try_inverse().map_or(SVector::zeros(), |inv| inv * b)
    }
}

/// One tick's transition with the commands reaching the drone `delay_s` late: the tick
/// starts under the command sent `n` ticks before it and switches, a fraction `ε` of the way
/// in, to the one sent `n − 1` ticks before — exact for commands held over ticks of (near)
/// equal length; before the segment's start, its first command. Returns the transition and
/// the input columns per unit of the early and of the late command
/// (`G = B_early·diag(u_early) + B_late·diag(u_late)`).
struct Delayed<const N: usize, const L: usize> {
    f: SMatrix<f64, N, N>,
    b_early: SMatrix<f64, N, L>,
    b_late: SMatrix<f64, N, L>,
}

fn delayed<F, const N: usize, const M: usize, const L: usize>(
    t: &Tick<M, L>,
    taus: &[f64],
    eps: f64,
) -> Delayed<N, L>
where
    F: Family<N, M, L>,
{
    let unit = Tick {
        u: SVector::repeat(1.0),
        ..*t
    };
    if eps < 1e-9 {
        let (f, b) = F::step(&unit, taus);
        return Delayed {
            f,
            b_early: SMatrix::zeros(),
            b_late: b,
        };
    }
    let (f1, b1) = F::step(
        &Tick {
            dt: eps * t.dt,
            ..unit
        },
        taus,
    );
    let (f2, b2) = F::step(
        &Tick {
            dt: (1.0 - eps) * t.dt,
            ..unit
        },
        taus,
    );
    Delayed {
        f: f2 * f1,
        b_early: f2 * b1,
        b_late: b2,
    }
}

/// The filtered state after each measured tick (for the quality figure): per segment, per
/// tick, the transition, the input term at the fitted gains, and the filtered state.
type Track<const N: usize> = Vec<Vec<(SMatrix<f64, N, N>, SVector<f64, N>, SVector<f64, N>)>>;

/// One Kalman pass over every segment at fixed (τ, λ, latency). The transition is cached
/// while the tick's length and heading stay the same, and the covariance recursion is
/// skipped once it has converged under an unchanged transition (the steady state), until a
/// dropout or a new transition restarts it.
fn pass<F, const N: usize, const M: usize, const L: usize>(
    segs: &[Vec<Tick<M, L>>],
    taus: &[f64],
    lambda: f64,
    delay_s: f64,
    noise_var_m2: f64,
    track_gains: Option<&SVector<f64, L>>,
) -> (Pass<L>, Track<N>)
where
    F: Family<N, M, L>,
{
    let h = F::h();
    let q_rel = math::exp(lambda);
    let mut out = Pass {
        a: SMatrix::zeros(),
        b: SVector::zeros(),
        c: 0.0,
        logdet: 0.0,
        n: 0,
    };
    let mut track = Vec::new();
    let mut cache: Option<((u64, u64), Delayed<N, L>, SMatrix<f64, N, N>)> = None;
    for seg in segs {
        let Some(first) = seg.iter().position(|t| t.y.is_some()) else {
            continue;
        };
        let (x0, p0) = F::start(&seg[first].y.unwrap_or_else(SVector::zeros));
        let mut xa = x0;
        let mut xb = SMatrix::<f64, N, L>::zeros();
        // Covariances in units of the measurement noise variance (σ² factored out).
        let mut p = SMatrix::<f64, N, N>::from_diagonal(&(p0 / noise_var_m2));
        for i in 0..M {
            p[(i, i)] = 1.0;
        }
        let mut seen = 0usize;
        let mut steps = Vec::new();
        let seg = &seg[first..];
        // The steady state: the gain, S̃⁻¹ and ln det S̃ of a converged update.
        let mut steady: Option<(SMatrix<f64, N, M>, SMatrix<f64, M, M>, f64)> = None;
        let mut prior = SMatrix::<f64, N, N>::zeros();
        for (k, t) in seg.iter().enumerate() {
            if let Some(y) = &t.y {
                if seen > 0 {
                    let (kg, si, logdet) = match steady {
                        Some(s) => s,
                        None => {
                            let s = h * p * h.transpose() + SMatrix::<f64, M, M>::identity();
                            let Some((si, det)) = F::inv_det(&s) else {
                                break;
                            };
                            (p * h.transpose() * si, si, math::ln(det))
                        }
                    };
                    let e0 = y - h * xa;
                    let hb = h * xb;
                    if seen >= BURN_IN {
                        out.a += hb.transpose() * si * hb;
                        out.b += hb.transpose() * si * e0;
                        out.c += (e0.transpose() * si * e0)[0];
                        out.logdet += logdet;
                        out.n += M;
                    }
                    xa += kg * e0;
                    xb -= kg * hb;
                    if steady.is_none() {
                        let ikh = SMatrix::<f64, N, N>::identity() - kg * h;
                        p = ikh * p;
                        p = 0.5 * (p + p.transpose());
                    }
                }
                seen += 1;
            } else {
                steady = None;
            }
            if t.dt <= 0.0 {
                continue;
            }
            let ticks = (delay_s / t.dt).max(0.0);
            let n = ticks.floor();
            let eps = ticks - n;
            let key = (t.dt.to_bits(), t.heading.to_bits());
            let hit = cache.as_ref().is_some_and(|c| c.0 == key);
            if !hit {
                let d = delayed::<F, N, M, L>(t, taus, eps);
                let q = F::q(t.dt) * q_rel;
                cache = Some((key, d, q));
                if let Some((kg, _, _)) = steady.take() {
                    // This tick's update ran on the steady gain: its posterior.
                    if t.y.is_some() {
                        p = (SMatrix::<f64, N, N>::identity() - kg * h) * p;
                    }
                }
            }
            let Some((_, d, q)) = &cache else {
                continue;
            };
            let at = |back: f64| &seg[k.saturating_sub(back as usize)].u;
            let (u_late, u_early) = (at(n), at(n + 1.0));
            let g = d.b_early * SMatrix::<f64, L, L>::from_diagonal(u_early)
                + d.b_late * SMatrix::<f64, L, L>::from_diagonal(u_late);
            if let Some(k) = track_gains {
                steps.push((d.f, g * k, xa + xb * k));
            }
            xa = d.f * xa;
            xb = d.f * xb + g;
            if steady.is_none() {
                let next = d.f * p * d.f.transpose() + q;
                let change = (next - prior).abs().max();
                p = next;
                prior = next;
                if hit && t.y.is_some() && change <= 1e-7 * p.abs().max() && seen > 1 {
                    let s = h * p * h.transpose() + SMatrix::<f64, M, M>::identity();
                    if let Some((si, det)) = F::inv_det(&s) {
                        steady = Some((p * h.transpose() * si, si, math::ln(det)));
                    }
                }
            }
        }
        if track_gains.is_some() {
            track.push(steps);
        }
    }
    (out, track)
}

/// What a fit found.
pub(super) struct PemFit<const L: usize> {
    pub gains: [Estimate; L],
    pub taus: Vec<Estimate>,
    /// The command latency and the attitude lag (not in the servo's model), seconds.
    pub latency_s: f64,
    pub attitude_lag_s: Option<f64>,
    pub r2: f64,
    pub rms_m: f64,
    /// Measured samples used.
    pub samples: usize,
}

/// A rough measurement noise variance from third differences of the positions (the scale of
/// the filter's starting covariance only; σ² itself is fitted).
fn rough_noise<const M: usize, const L: usize>(segs: &[Vec<Tick<M, L>>]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for seg in segs {
        for w in seg.windows(4) {
            if let (Some(a), Some(b), Some(c), Some(d)) = (&w[0].y, &w[1].y, &w[2].y, &w[3].y) {
                let d3 = d - 3.0 * c + 3.0 * b - a;
                s += d3.norm_squared() / M as f64;
                n += 1;
            }
        }
    }
    if n == 0 {
        1e-6
    } else {
        (s / n as f64 / 20.0).max(1e-12)
    }
}

/// Minimises `f` from `x0` with a simplex of steps `step` (Nelder–Mead).
fn nelder_mead(f: &dyn Fn(&[f64]) -> f64, x0: &[f64], step: &[f64], iters: usize) -> Vec<f64> {
    let d = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    simplex.push((x0.to_vec(), f(x0)));
    for i in 0..d {
        let mut x = x0.to_vec();
        x[i] += step[i];
        let v = f(&x);
        simplex.push((x, v));
    }
    let comb = |a: &[f64], b: &[f64], t: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect()
    };
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let size = simplex[1..]
            .iter()
            .flat_map(|(x, _)| x.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        if (simplex[d].1 - simplex[0].1).abs() < 1e-3 || size < 1e-3 {
            break;
        }
        let mut centroid = vec![0.0; d];
        for (x, _) in &simplex[..d] {
            for i in 0..d {
                centroid[i] += x[i] / d as f64;
            }
        }
        let worst = simplex[d].clone();
        let xr = comb(&centroid, &worst.0, -1.0);
        let fr = f(&xr);
        if fr < simplex[0].1 {
            let xe = comb(&centroid, &worst.0, -2.0);
            let fe = f(&xe);
            simplex[d] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[d - 1].1 {
            simplex[d] = (xr, fr);
        } else {
            let xc = if fr < worst.1 {
                comb(&centroid, &xr, 0.5)
            } else {
                comb(&centroid, &worst.0, 0.5)
            };
            let fc = f(&xc);
            if fc < worst.1.min(fr) {
                simplex[d] = (xc, fc);
            } else {
                let best = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    s.0 = comb(&best, &s.0, 0.5);
                    s.1 = f(&s.0);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0).0
}

/// The fit of one family: `T` time constants (the search starts from a grid on a common main
/// τ, [`Family::grid_taus`]), only those marked in `tau_free` searched and only those marked
/// in `tau_measured` given intervals.
fn fit<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    segs: &[Vec<Tick<M, L>>],
    excited: [bool; L],
    tau_free: [bool; T],
    tau_measured: [bool; T],
) -> Option<PemFit<L>>
where
    F: Family<N, M, L>,
{
    if !excited.iter().any(|e| *e) {
        return None;
    }
    let r0 = rough_noise(segs);
    let objective = |x: &[f64]| objective::<F, N, M, L, T>(segs, &excited, r0, x);
    let drifting = refine::<T>(
        &objective,
        grid_start::<F, N, M, L, T>(&objective),
        tau_free,
    );
    // The same model with no drift: a flexible drift can take the drone's own response for
    // wind (the likelihood prefers it, its predictions do not). Of the two, the one that
    // predicts the tests better.
    let calm_objective = |y: &[f64]| {
        let mut x = y.to_vec();
        x[T] = LAMBDA_MIN;
        objective(&x)
    };
    let mut calm = refine::<T>(
        &calm_objective,
        grid_start::<F, N, M, L, T>(&calm_objective),
        tau_free,
    );
    calm[T] = LAMBDA_MIN;
    let r2_of = |x: &[f64]| {
        let (taus, lambda, delay_s, _) = unpack::<F, N, M, L, T>(x);
        let (p, _) = pass::<F, N, M, L>(segs, &taus, lambda, delay_s, r0, None);
        quality::<F, N, M, L>(segs, &taus, lambda, delay_s, r0, &p.gains(&excited))
    };
    let (x, tau_measured) = if r2_of(&calm) > r2_of(&drifting) + CALM_R2_MARGIN {
        let mut measured = tau_measured;
        if let Some(j) = F::DRIFT_TAU {
            measured[j] = false;
        }
        (calm, measured)
    } else {
        (drifting, tau_measured)
    };
    let (taus, lambda, delay_s, _) = unpack::<F, N, M, L, T>(&x);
    let (p, _) = pass::<F, N, M, L>(segs, &taus, lambda, delay_s, r0, None);
    let k = p.gains(&excited);
    let sigma2 = p.ssr(&k) / p.n as f64;
    let sd = std_devs::<F, N, M, L, T>(segs, r0, &x, &k, &excited, tau_measured);
    let gains = std::array::from_fn(|j| Estimate {
        value: k[j],
        ci95: if excited[j] {
            Z95 * sd(j)
        } else {
            f64::INFINITY
        },
    });
    let taus_est = (0..T)
        .map(|j| Estimate {
            value: taus[j],
            // d τ = τ · d ln τ.
            ci95: Z95 * sd(L + j) * taus[j],
        })
        .collect();
    let r2 = quality::<F, N, M, L>(segs, &taus, lambda, delay_s, r0, &k);
    Some(PemFit {
        gains,
        taus: taus_est,
        latency_s: delay_s,
        attitude_lag_s: (T >= 3).then(|| taus[2]),
        r2,
        rms_m: sigma2.sqrt(),
        samples: p.n / M,
    })
}

/// The parameters `x` (ln τ for each of the `T` time constants, λ, the command latency) as
/// (τs, λ, latency) clamped into their ranges, and the penalty of the clamping.
fn unpack<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    x: &[f64],
) -> (Vec<f64>, f64, f64, f64)
where
    F: Family<N, M, L>,
{
    let mut pen = 0.0;
    let taus = (0..T)
        .map(|j| {
            let (lo, hi) = F::ln_tau_range(j, x);
            let c = x[j].clamp(lo, hi);
            pen += (x[j] - c).powi(2);
            math::exp(c)
        })
        .collect();
    let l = x[T].clamp(LAMBDA_MIN, LAMBDA_MAX);
    pen += (x[T] - l).powi(2);
    let d = x[T + 1].clamp(0.0, LATENCY_MAX_S);
    pen += ((x[T + 1] - d) / LATENCY_MAX_S).powi(2);
    (taus, l, d, pen)
}

/// The concentrated negative log-likelihood at parameters `x` (see [`unpack`]) and the best
/// gains, plus the clamping penalty; infinite where the filter fails.
fn objective<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    segs: &[Vec<Tick<M, L>>],
    excited: &[bool; L],
    r0: f64,
    x: &[f64],
) -> f64
where
    F: Family<N, M, L>,
{
    let (taus, l, d, pen) = unpack::<F, N, M, L, T>(x);
    let (p, _) = pass::<F, N, M, L>(segs, &taus, l, d, r0, None);
    if p.n == 0 {
        return f64::INFINITY;
    }
    let nll = p.nll(&p.gains(excited));
    if nll.is_finite() {
        nll + 1e3 * pen
    } else {
        f64::INFINITY
    }
}

/// The best point of a grid on a common τ and λ, the latency at its start: where the simplex
/// starts.
fn grid_start<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    objective: &dyn Fn(&[f64]) -> f64,
) -> Vec<f64>
where
    F: Family<N, M, L>,
{
    let mut best = (f64::INFINITY, vec![0.0; T + 2]);
    for it in 0..5 {
        let lt = math::ln(0.25f64 * 2.5f64.powi(it));
        for il in 0..5 {
            let l = 2.0 * il as f64 + if T > 1 { 8.0 } else { -6.0 };
            for mut x in F::grid_taus(lt) {
                x.push(l);
                x.push(LATENCY_START_S);
                let v = objective(&x);
                if v < best.0 {
                    best = (v, x);
                }
            }
        }
    }
    best.1
}

/// Nelder–Mead from `x0` over the free parameters only (the τs marked in `tau_free`, λ and
/// the latency); the others stay at `x0`'s values.
fn refine<const T: usize>(
    objective: &dyn Fn(&[f64]) -> f64,
    x0: Vec<f64>,
    tau_free: [bool; T],
) -> Vec<f64> {
    let free: Vec<usize> = (0..T).filter(|&j| tau_free[j]).chain([T, T + 1]).collect();
    let full = |y: &[f64]| -> Vec<f64> {
        let mut x = x0.clone();
        for (i, &fi) in free.iter().enumerate() {
            x[fi] = y[i];
        }
        x
    };
    let y0: Vec<f64> = free.iter().map(|&i| x0[i]).collect();
    let steps: Vec<f64> = free
        .iter()
        .map(|&i| match i - T.min(i) {
            _ if i < T => 0.3,
            0 => 2.0,
            _ => 0.02,
        })
        .collect();
    let y = nelder_mead(&|y| objective(&full(y)), &y0, &steps, 60 * free.len());
    full(&y)
}

/// The standard deviations of the fit at parameters `x` and gains `k`, from the inverse
/// Hessian (central differences) of ℓ over the free gains, ln τs and λ (and the latency):
/// per parameter index (gains first, then `L +` the index in `x`), 0 for a parameter held,
/// infinite for all when the Hessian is singular.
fn std_devs<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    segs: &[Vec<Tick<M, L>>],
    r0: f64,
    x: &[f64],
    k: &SVector<f64, L>,
    excited: &[bool; L],
    tau_free: [bool; T],
) -> impl Fn(usize) -> f64
where
    F: Family<N, M, L>,
{
    let names = hessian_parameters::<F, N, M, L, T>(x, k, excited, tau_free);
    let ell = |d: &[(usize, f64)]| -> f64 {
        let mut kk = *k;
        let mut xx = x.to_vec();
        for &(i, dv) in d {
            if i < L {
                kk[i] += dv;
            } else {
                xx[i - L] += dv;
            }
        }
        let (taus, l, d, _) = unpack::<F, N, M, L, T>(&xx);
        let (pp, _) = pass::<F, N, M, L>(segs, &taus, l, d, r0, None);
        pp.nll(&kk)
    };
    let m = names.len();
    let f0 = ell(&[]);
    let mut hess = nalgebra::DMatrix::<f64>::zeros(m, m);
    for a in 0..m {
        let (ia, ha) = names[a];
        let fp = ell(&[(ia, ha)]);
        let fm = ell(&[(ia, -ha)]);
        hess[(a, a)] = (fp - 2.0 * f0 + fm) / (ha * ha);
        for b in 0..a {
            let (ib, hb) = names[b];
            let fpp = ell(&[(ia, ha), (ib, hb)]);
            let fpm = ell(&[(ia, ha), (ib, -hb)]);
            let fmp = ell(&[(ia, -ha), (ib, hb)]);
            let fmm = ell(&[(ia, -ha), (ib, -hb)]);
            let v = (fpp - fpm - fmp + fmm) / (4.0 * ha * hb);
            hess[(a, b)] = v;
            hess[(b, a)] = v;
        }
    }
    // A parameter the likelihood is flat or saddled in (an attitude lag the data does not
    // show, near its lower bound) is held at its value, as one on a bound is: the
    // non-gain with the weakest curvature is left out until the rest is positive definite.
    let mut kept: Vec<usize> = (0..m).collect();
    let cov = loop {
        let sub = nalgebra::DMatrix::<f64>::from_fn(kept.len(), kept.len(), |r, c| {
            hess[(kept[r], kept[c])]
        });
        if let Some(ch) = sub.clone().cholesky() {
            break Some(ch.inverse());
        }
        let weakest = (kept.iter().enumerate())
            .filter(|(_, &a)| names[a].0 >= L)
            .min_by(|x, y| hess[(*x.1, *x.1)].total_cmp(&hess[(*y.1, *y.1)]))
            .map(|(r, _)| r);
        match weakest {
            Some(r) => {
                kept.remove(r);
            }
            None => break None,
        }
    };
    let names: Vec<(usize, f64)> = kept.iter().map(|&a| names[a]).collect();
    move |param: usize| -> f64 {
        let Some(cov) = &cov else {
            return f64::INFINITY;
        };
        names
            .iter()
            .position(|(i, _)| *i == param)
            .map_or(0.0, |r| cov[(r, r)].max(0.0).sqrt())
    }
}

/// The parameters the Hessian is taken over, each with its difference step: the excited
/// gains (indices `0..L`), then, as `L +` their index in `x`, the free ln τs, λ and the
/// latency that ended inside their ranges.
fn hessian_parameters<F, const N: usize, const M: usize, const L: usize, const T: usize>(
    x: &[f64],
    k: &SVector<f64, L>,
    excited: &[bool; L],
    tau_free: [bool; T],
) -> Vec<(usize, f64)>
where
    F: Family<N, M, L>,
{
    let mut names: Vec<(usize, f64)> = Vec::new(); // (parameter index, step)
    for j in 0..L {
        if excited[j] {
            names.push((j, (k[j].abs() * 1e-3).max(1e-6)));
        }
    }
    // A parameter that ended on a bound of its range (no attitude lag, no latency, no wind)
    // is held there: the likelihood has no interior curvature in it.
    let inside = |i: usize, lo: f64, hi: f64| x[i] > lo + 1e-3 && x[i] < hi - 1e-3;
    for (j, free) in tau_free.iter().enumerate() {
        let (lo, hi) = F::ln_tau_range(j, x);
        if *free && inside(j, lo, hi) {
            names.push((L + j, 1e-3));
        }
    }
    if inside(T, LAMBDA_MIN, LAMBDA_MAX) {
        names.push((L + T, 1e-2));
    }
    if inside(T + 1, 0.0, LATENCY_MAX_S) {
        names.push((L + T + 1, 1e-3));
    }
    names
}

/// R² of the [`HORIZON_S`]-ahead predictions against constant-velocity extrapolation.
fn quality<F, const N: usize, const M: usize, const L: usize>(
    segs: &[Vec<Tick<M, L>>],
    taus: &[f64],
    lambda: f64,
    delay_s: f64,
    r0: f64,
    k: &SVector<f64, L>,
) -> f64
where
    F: Family<N, M, L>,
{
    let (_, track) = pass::<F, N, M, L>(segs, taus, lambda, delay_s, r0, Some(k));
    let (mut fit_ss, mut cv_ss) = (0.0, 0.0);
    for (seg, steps) in segs.iter().zip(&track) {
        let Some(first) = seg.iter().position(|t| t.y.is_some()) else {
            continue;
        };
        let ticks: Vec<&Tick<M, L>> = seg[first..].iter().filter(|t| t.dt > 0.0).collect();
        let n = steps.len().min(ticks.len());
        // From one horizon in: the filter has found the velocity by then.
        let mut start = 0;
        let mut settle_s = 0.0;
        while start < n && settle_s < HORIZON_S {
            settle_s += ticks[start].dt;
            start += 1;
        }
        while start < n {
            let mut x = steps[start].2;
            let (p0, v0) = F::pos_vel(&x);
            let mut elapsed = 0.0;
            let mut end = start;
            while end < n && elapsed < HORIZON_S - 1e-9 {
                x = steps[end].0 * x + steps[end].1;
                elapsed += ticks[end].dt;
                end += 1;
            }
            if elapsed >= HORIZON_S - 1e-9 && end < ticks.len() {
                if let Some(y) = &ticks[end].y {
                    let (pf, _) = F::pos_vel(&x);
                    fit_ss += (y - pf).norm_squared();
                    cv_ss += (y - (p0 + v0 * elapsed)).norm_squared();
                }
            }
            start += 10;
        }
    }
    if cv_ss > 0.0 {
        1.0 - fit_ss / cv_ss
    } else {
        0.0
    }
}

/// The horizontal fit: `[K_φ, K_θ]`, `[τ_φ, τ_θ]` (only the excited axes are meaningful).
pub(super) fn fit_plane(data: &[PlaneData]) -> Option<(PemFit<2>, [bool; 2])> {
    let segs: Vec<Vec<Tick<2, 2>>> = data
        .iter()
        .map(|d| {
            let n = d.dt.len();
            let (mut dt, mut heading) = (Held::new(DT_QUANTUM_S), Held::new(HEADING_QUANTUM_RAD));
            (0..n)
                .map(|k| Tick {
                    dt: dt.next(d.dt[k]),
                    heading: heading.next(d.heading[k]),
                    u: SVector::<f64, 2>::new(d.roll[k], d.pitch[k]),
                    y: d.mask[k].then(|| SVector::<f64, 2>::new(d.y[k], d.y[n + k])),
                })
                .collect()
        })
        .collect();
    let excited = [0, 1].map(|j| {
        segs.iter()
            .any(|s| s.iter().any(|t| t.u[j] != 0.0 && t.dt > 0.0))
    });
    // An axis not excited has no τ to measure, but it is searched all the same: held, it would
    // bound the attitude lag (at most half the faster τ) by a value the data never saw.
    let measured = [excited[0], excited[1], true, true];
    fit::<Plane, 10, 2, 2, 4>(&segs, excited, [true; 4], measured).map(|f| (f, excited))
}

/// The vertical fit: `[K_ż climbing, K_ż descending]`, `[τ_ż]`.
pub(super) fn fit_vertical(data: &[AxisData]) -> Option<(PemFit<2>, [bool; 2])> {
    let segs: Vec<Vec<Tick<1, 2>>> = data
        .iter()
        .map(|d| {
            let mut dt = Held::new(DT_QUANTUM_S);
            (0..d.dt.len())
                .map(|k| Tick {
                    dt: dt.next(d.dt[k]),
                    heading: 0.0,
                    u: SVector::<f64, 2>::new(d.u[k].max(0.0), d.u[k].min(0.0)),
                    y: d.y[k].map(SVector::<f64, 1>::new),
                })
                .collect()
        })
        .collect();
    let excited = [0, 1].map(|j| {
        segs.iter()
            .any(|s| s.iter().any(|t| t.u[j] != 0.0 && t.dt > 0.0))
    });
    fit::<Vertical, 3, 1, 2, 1>(&segs, excited, [true], [true]).map(|f| (f, excited))
}
