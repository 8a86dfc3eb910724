//! The discrete algebraic Riccati equation, solved by the structure-preserving doubling
//! algorithm (SDA; Chu, Fan, Lin & Wang 2004):
//!
//! ```text
//! P = AᵀPA − AᵀPB (R + BᵀPB)⁻¹ BᵀPA + Q,      K = (R + BᵀPB)⁻¹ BᵀPA
//! A₀ = A, G₀ = B R⁻¹ Bᵀ, H₀ = Q;  W = I + G H:
//! A' = A W⁻¹ A,  G' = G + A W⁻¹ G Aᵀ,  H' = H + Aᵀ H W⁻¹ A,   P = lim H
//! ```
//!
//! It converges quadratically (≈ 10–20 doublings for the servo, whose open-loop poles sit at
//! 1), needs no stabilising start, and runs on fixed-size `SMatrix` with no heap: the linear
//! solves are a partial-pivot Gauss elimination on the stack. After solving, [`solve`] checks
//! the relative residual and that the closed loop `A − BK` is stable (spectral radius < 1
//! from the real Schur form, also on the stack): Riccati solvers silently return a
//! non-stabilising P when the weights leave a mode unobserved, which [`check_servo_weights`]
//! rejects before solving for the servo's own weights.
//!
//! [`solve_single_input`] is the 2×2 fast path of the body-frame split: with diagonal Q and R
//! the servo's 6-state problem splits into three `[v_axis, p_axis]` single-input problems.

use std::fmt;

use nalgebra::{
    allocator::Allocator, Const, DefaultAllocator, DimDiff, DimSub, Matrix2, SMatrix, Vector2, U1,
};

/// Relative change of H between doublings below which the iteration has converged.
pub const TOLERANCE: f64 = 1e-13;
/// Doublings before giving up (each squares the closed-loop transition, so 60 covers any
/// spectral radius below 1 − 1e-15).
pub const MAX_ITERATIONS: usize = 60;
/// Largest relative residual accepted.
pub const MAX_RESIDUAL: f64 = 1e-8;

/// The stabilising solution of a DARE.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DareSolution<const N: usize, const M: usize> {
    pub p: SMatrix<f64, N, N>,
    /// `K = (R + BᵀPB)⁻¹ BᵀPA`; the regulator is `u = −K x`.
    pub k: SMatrix<f64, M, N>,
    /// `‖AᵀPA − P − AᵀPB(R + BᵀPB)⁻¹BᵀPA + Q‖_F / max(‖P‖_F, ‖Q‖_F)`.
    pub residual: f64,
    /// Doublings done.
    pub iterations: usize,
    /// Largest eigenvalue magnitude of `A − BK` (NaN when the check was skipped).
    pub spectral_radius: f64,
}

/// Why a DARE was not solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DareError {
    /// A, B, Q or R holds NaN or an infinity.
    NotFinite,
    /// A weight on the diagonal of `key` (a profile key, or "Q"/"R" for a bare solve) is
    /// negative (Q) or not positive (R), or not finite.
    BadWeight {
        key: &'static str,
        index: usize,
        value: f64,
    },
    /// The servo's Q puts no weight on position axis `axis` (0 x, 1 y, 2 z).
    PositionsUnweighted { axis: usize },
    /// The doubling did not settle in [`MAX_ITERATIONS`].
    NotConverged { iterations: usize, change: f64 },
    /// A singular `I + G H` or `R + BᵀPB` on the way.
    Singular,
    /// The solution does not satisfy the equation well enough.
    ResidualTooLarge { residual: f64 },
    /// `A − BK` has an eigenvalue on or outside the unit circle.
    NotStabilising { spectral_radius: f64 },
}

impl fmt::Display for DareError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DareError::NotFinite => write!(
                f,
                "the Riccati equation has a NaN or infinite entry (check the model's gains and \
                 time constants and the weights)"
            ),
            DareError::BadWeight { key, index, value } => {
                let (want, why) = if key.ends_with('r') || key.ends_with("noise_m2") || key == "R" {
                    (
                        "finite and > 0",
                        "a zero or negative cost makes the problem ill-posed",
                    )
                } else {
                    ("finite and ≥ 0", "a negative cost rewards errors")
                };
                write!(f, "{key}[{index}] = {value} must be {want}: {why}")
            }
            DareError::PositionsUnweighted { axis } => {
                let name = ["x", "y", "z"][axis.min(2)];
                write!(
                    f,
                    "servo.q[{}] = 0 puts no weight on the {name} position: the regulator would \
                     never pull the drone back to the reference (no stabilising Riccati \
                     solution); give the three position weights servo.q[3..6] positive values, \
                     e.g. q = [1.0, 1.0, 1.0, 10.0, 10.0, 10.0]",
                    axis + 3
                )
            }
            DareError::NotConverged { iterations, change } if !change.is_finite() => write!(
                f,
                "the Riccati iteration diverged after {iterations} doublings: no stabilising \
                 solution exists (a mode the input cannot move is unstable, or an unstable mode \
                 carries no weight)"
            ),
            DareError::NotConverged { iterations, change } => write!(
                f,
                "the Riccati iteration did not converge in {iterations} doublings (last \
                 relative change {change:.3e}); the weights or the model are badly scaled"
            ),
            DareError::Singular => write!(
                f,
                "the Riccati iteration met a singular matrix; the weights or the model are \
                 degenerate"
            ),
            DareError::ResidualTooLarge { residual } => write!(
                f,
                "the Riccati solution's relative residual {residual:.3e} exceeds \
                 {MAX_RESIDUAL:e}; the weights or the model are badly scaled"
            ),
            DareError::NotStabilising { spectral_radius } => write!(
                f,
                "the regulator does not stabilise the model (closed-loop spectral radius \
                 {spectral_radius:.6} ≥ 1); some state is neither weighted in Q nor seen \
                 through a weighted state"
            ),
        }
    }
}

impl std::error::Error for DareError {}

/// Checks the servo's diagonal weights (profile `servo.q` on `[vx, vy, vz, x, y, z]`,
/// `servo.r` on `[φ, θ, ż]`): finite, Q ≥ 0, R > 0, and every position weighted.
pub fn check_servo_weights(q: &[f64; 6], r: &[f64; 3]) -> Result<(), DareError> {
    for (i, &v) in q.iter().enumerate() {
        if !(v.is_finite() && v >= 0.0) {
            return Err(DareError::BadWeight {
                key: "servo.q",
                index: i,
                value: v,
            });
        }
    }
    for (i, &v) in r.iter().enumerate() {
        if !(v.is_finite() && v > 0.0) {
            return Err(DareError::BadWeight {
                key: "servo.r",
                index: i,
                value: v,
            });
        }
    }
    for axis in 0..3 {
        if q[3 + axis] == 0.0 {
            return Err(DareError::PositionsUnweighted { axis });
        }
    }
    Ok(())
}

/// Solves `w X = rhs` by Gauss elimination with partial pivoting; `None` when `w` is
/// (numerically) singular. On the stack.
pub fn solve_linear<const N: usize, const C: usize>(
    w: &SMatrix<f64, N, N>,
    rhs: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    let mut a = *w;
    let mut x = *rhs;
    let scale = a.amax();
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    for col in 0..N {
        let mut piv = col;
        let mut best = a[(col, col)].abs();
        for r in col + 1..N {
            let v = a[(r, col)].abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        if best <= scale * 1e-300_f64.max(f64::EPSILON * 1e-6) {
            return None;
        }
        if piv != col {
            a.swap_rows(col, piv);
            x.swap_rows(col, piv);
        }
        let d = a[(col, col)];
        for r in col + 1..N {
            let f = a[(r, col)] / d;
            if f != 0.0 {
                for c in col..N {
                    a[(r, c)] -= f * a[(col, c)];
                }
                for c in 0..C {
                    x[(r, c)] -= f * x[(col, c)];
                }
            }
        }
    }
    for col in (0..N).rev() {
        let d = a[(col, col)];
        for c in 0..C {
            let mut s = x[(col, c)];
            for k in col + 1..N {
                s -= a[(col, k)] * x[(k, c)];
            }
            x[(col, c)] = s / d;
        }
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

fn check_inputs<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
) -> Result<(), DareError> {
    let finite = |s: &[f64]| s.iter().all(|v| v.is_finite());
    if !(finite(a.as_slice())
        && finite(b.as_slice())
        && finite(q.as_slice())
        && finite(r.as_slice()))
    {
        return Err(DareError::NotFinite);
    }
    for i in 0..N {
        if q[(i, i)] < 0.0 {
            return Err(DareError::BadWeight {
                key: "Q",
                index: i,
                value: q[(i, i)],
            });
        }
    }
    for i in 0..M {
        if r[(i, i)] <= 0.0 {
            return Err(DareError::BadWeight {
                key: "R",
                index: i,
                value: r[(i, i)],
            });
        }
    }
    Ok(())
}

fn sym<const N: usize>(m: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (m + m.transpose()) * 0.5
}

/// The doubling itself and the gain, with no checks after the solve: P, K, doublings.
/// Allocation-free. Use [`solve`] unless the caller checks the result itself.
pub fn solve_unchecked<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
) -> Result<(SMatrix<f64, N, N>, SMatrix<f64, M, N>, usize), DareError> {
    check_inputs(a, b, q, r)?;
    let rinv_bt = solve_linear(r, &b.transpose()).ok_or(DareError::Singular)?;
    let mut ak = *a;
    let mut gk = sym(&(b * rinv_bt));
    let mut hk = sym(q);
    let eye = SMatrix::<f64, N, N>::identity();
    let mut change = f64::INFINITY;
    for it in 1..=MAX_ITERATIONS {
        let w = eye + gk * hk;
        // W⁻¹A and W⁻¹G in one elimination would need a wider matrix type; two solves on
        // the same W cost little at these sizes.
        let wa = solve_linear(&w, &ak).ok_or(DareError::Singular)?;
        let wg = solve_linear(&w, &gk).ok_or(DareError::Singular)?;
        let h_next = sym(&(hk + ak.transpose() * hk * wa));
        let g_next = sym(&(gk + ak * wg * ak.transpose()));
        let a_next = ak * wa;
        let norm = h_next.norm();
        change = (h_next - hk).norm() / norm.max(f64::MIN_POSITIVE);
        hk = h_next;
        gk = g_next;
        ak = a_next;
        if !change.is_finite() {
            // The inputs were finite: H ran away, so no stabilising solution exists.
            return Err(DareError::NotConverged {
                iterations: it,
                change: f64::INFINITY,
            });
        }
        if change <= TOLERANCE || ak.amax() <= f64::EPSILON * 1e-3 {
            let k = gain(a, b, r, &hk)?;
            return Ok((hk, k, it));
        }
    }
    Err(DareError::NotConverged {
        iterations: MAX_ITERATIONS,
        change,
    })
}

/// `K = (R + BᵀPB)⁻¹ BᵀPA`.
pub fn gain<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    r: &SMatrix<f64, M, M>,
    p: &SMatrix<f64, N, N>,
) -> Result<SMatrix<f64, M, N>, DareError> {
    let btp = b.transpose() * p;
    solve_linear(&(r + btp * b), &(btp * a)).ok_or(DareError::Singular)
}

/// The relative residual of P in the DARE (see [`DareSolution::residual`]).
pub fn residual<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
    p: &SMatrix<f64, N, N>,
) -> f64 {
    let atp = a.transpose() * p;
    let btp = b.transpose() * p;
    let rhs = btp * a;
    let Some(x) = solve_linear(&(r + btp * b), &rhs) else {
        return f64::INFINITY;
    };
    let res = atp * a - p - atp * b * x + q;
    res.norm() / p.norm().max(q.norm()).max(f64::MIN_POSITIVE)
}

/// Magnitudes of the eigenvalues of `m` (real Schur form, on the stack), or `None` if the
/// QR iteration did not converge.
pub fn eigenvalue_magnitudes<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<[f64; N]>
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<Const<N>, DimDiff<Const<N>, U1>> + Allocator<DimDiff<Const<N>, U1>>,
{
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let schur = m.try_schur(f64::EPSILON, 10_000)?;
    let ev = schur.complex_eigenvalues();
    let mut out = [0.0; N];
    for (o, e) in out.iter_mut().zip(ev.iter()) {
        *o = e.norm();
    }
    Some(out)
}

/// The spectral radius of `m` (infinite if it cannot be computed).
pub fn spectral_radius<const N: usize>(m: &SMatrix<f64, N, N>) -> f64
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<Const<N>, DimDiff<Const<N>, U1>> + Allocator<DimDiff<Const<N>, U1>>,
{
    eigenvalue_magnitudes(m).map_or(f64::INFINITY, |e| e.iter().fold(0.0, |a: f64, &b| a.max(b)))
}

/// Solves the DARE and checks the result: relative residual ≤ [`MAX_RESIDUAL`] and
/// `A − BK` stable.
pub fn solve<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
) -> Result<DareSolution<N, M>, DareError>
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<Const<N>, DimDiff<Const<N>, U1>> + Allocator<DimDiff<Const<N>, U1>>,
{
    let (p, k, iterations) = solve_unchecked(a, b, q, r)?;
    let res = residual(a, b, q, r, &p);
    checked(p, k, iterations, res, || spectral_radius(&(a - b * k)))
}

/// The residual and stability checks of a solve.
fn checked<const N: usize, const M: usize>(
    p: SMatrix<f64, N, N>,
    k: SMatrix<f64, M, N>,
    iterations: usize,
    residual: f64,
    spectral_radius: impl FnOnce() -> f64,
) -> Result<DareSolution<N, M>, DareError> {
    if residual.is_nan() || residual > MAX_RESIDUAL {
        return Err(DareError::ResidualTooLarge { residual });
    }
    let rho = spectral_radius();
    if rho.is_nan() || rho >= 1.0 {
        return Err(DareError::NotStabilising {
            spectral_radius: rho,
        });
    }
    Ok(DareSolution {
        p,
        k,
        residual,
        iterations,
        spectral_radius: rho,
    })
}

/// The 2-state single-input fast path (one body axis `[v, p]`): the same doubling, then the
/// residual and the closed-loop eigenvalues in closed form. Allocation-free.
pub fn solve_single_input(
    a: &Matrix2<f64>,
    b: &Vector2<f64>,
    q: &Matrix2<f64>,
    r: f64,
) -> Result<DareSolution<2, 1>, DareError> {
    let r = SMatrix::<f64, 1, 1>::new(r);
    let (p, k, iterations) = solve_unchecked(a, b, q, &r)?;
    let res = residual(a, b, q, &r, &p);
    checked(p, k, iterations, res, || spectral_radius_2x2(&(a - b * k)))
}

/// The spectral radius of a 2×2 matrix from its characteristic polynomial.
pub fn spectral_radius_2x2(m: &Matrix2<f64>) -> f64 {
    let tr = m[(0, 0)] + m[(1, 1)];
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    let disc = tr * tr / 4.0 - det;
    let rho = if disc >= 0.0 {
        let s = disc.sqrt();
        (tr / 2.0 + s).abs().max((tr / 2.0 - s).abs())
    } else {
        det.max(0.0).sqrt()
    };
    if rho.is_finite() {
        rho
    } else {
        f64::INFINITY
    }
}
