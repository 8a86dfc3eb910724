//! The Riccati solver against independent computations: a long plain Riccati iteration, the
//! scalar closed form, a rotated diagonal problem with a closed form; residual, stability,
//! and the rejection of weights that give no stabilising solution.

use dronecine_profile::Profile;
use dronecine_servo::dare::{self, DareError};
use dronecine_servo::model::{Matrix6x3, ModelParams};
use nalgebra::{Matrix2, Matrix3, Matrix6, SMatrix, Vector2, Vector3, Vector6};

fn ardrone() -> Profile {
    Profile::builtin("ardrone2").unwrap()
}

fn weights(p: &Profile) -> (Matrix6<f64>, Matrix3<f64>) {
    (
        Matrix6::from_diagonal(&Vector6::from(p.servo.q)),
        Matrix3::from_diagonal(&Vector3::from(p.servo.r)),
    )
}

/// Plain Riccati iteration from P = Q, with nalgebra's own inverse (nothing shared with
/// the solver under test), until the relative change is below 1e-14.
fn plain_riccati<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
) -> (SMatrix<f64, N, N>, usize) {
    let mut p = *q;
    for it in 0..2_000_000 {
        let s = (r + b.transpose() * p * b).try_inverse().unwrap();
        let next = a.transpose() * p * a - a.transpose() * p * b * s * b.transpose() * p * a + q;
        let change = (next - p).norm() / next.norm();
        p = (next + next.transpose()) * 0.5;
        if change < 1e-15 {
            return (p, it);
        }
    }
    panic!("plain Riccati iteration did not converge");
}

fn rel(a: f64, b: f64) -> f64 {
    a / b.max(1e-300)
}

#[test]
fn servo_dare_matches_a_long_plain_riccati_iteration() {
    let p = ardrone();
    let m = ModelParams::from_profile(&p);
    let (q, r) = weights(&p);
    for (dt, c) in [(0.01, 0.0), (0.01, 1.3), (0.033, -2.4)] {
        let (a, b) = (m.a1(dt, c), m.b1(dt, c));
        let sol = dare::solve(&a, &b, &q, &r).unwrap();
        let (want, plain_iterations) = plain_riccati(&a, &b, &q, &r);
        // The doubling needs a few dozen steps where the plain iteration needs thousands.
        assert!(plain_iterations > 10 * sol.iterations, "{plain_iterations}");
        assert!(sol.iterations <= 30, "{}", sol.iterations);
        let err = rel((sol.p - want).norm(), want.norm());
        assert!(err < 1e-8, "dt {dt} c {c}: {err:e}");
        let k_want =
            (r + b.transpose() * want * b).try_inverse().unwrap() * b.transpose() * want * a;
        assert!(rel((sol.k - k_want).norm(), k_want.norm()) < 1e-8);
        assert!(sol.residual < 1e-9, "{}", sol.residual);
        assert!(sol.spectral_radius < 1.0);
        // Symmetric and positive definite.
        assert!((sol.p - sol.p.transpose()).norm() < 1e-12 * sol.p.norm());
        assert!(sol.p.cholesky().is_some());
    }
}

/// Scalar DARE: b²p² + (r − a²r − qb²)p − qr = 0, the positive root. An unstable plant.
#[test]
fn scalar_dare_matches_the_closed_form() {
    for (a, b, q, r) in [
        (1.2f64, 0.5f64, 2.0f64, 3.0f64),
        (0.9, 2.0, 0.1, 10.0),
        (1.0, 0.01, 5.0, 0.2),
    ] {
        let lin = r - a * a * r - q * b * b;
        let want = (-lin + (lin * lin + 4.0 * b * b * q * r).sqrt()) / (2.0 * b * b);
        let sol = dare::solve(
            &SMatrix::<f64, 1, 1>::new(a),
            &SMatrix::<f64, 1, 1>::new(b),
            &SMatrix::<f64, 1, 1>::new(q),
            &SMatrix::<f64, 1, 1>::new(r),
        )
        .unwrap();
        assert!(
            rel((sol.p[0] - want).abs(), want) < 1e-12,
            "{} vs {want}",
            sol.p[0]
        );
        let k = b * want * a / (r + b * b * want);
        assert!(rel((sol.k[0] - k).abs(), k) < 1e-12);
        assert!((sol.spectral_radius - (a - b * k).abs()).abs() < 1e-12);
    }
}

/// A coupled 2×2 problem with a closed form: `A = U diag(a) Uᵀ`, `B = I`, `Q = U diag(q) Uᵀ`,
/// `R = r I` with U a rotation decouples into two scalar DAREs, `P = U diag(p) Uᵀ`.
#[test]
fn rotated_diagonal_dare_matches_the_closed_form() {
    let u = nalgebra::Rotation2::new(0.7).into_inner();
    let (a_d, q_d, r) = ([1.1, 0.95], [2.0, 0.5], 0.7);
    let scalar = |a: f64, q: f64| {
        let lin = r - a * a * r - q;
        (-lin + (lin * lin + 4.0 * q * r).sqrt()) / 2.0
    };
    let want =
        u * Matrix2::from_diagonal(&Vector2::new(
            scalar(a_d[0], q_d[0]),
            scalar(a_d[1], q_d[1]),
        )) * u.transpose();
    let a = u * Matrix2::from_diagonal(&Vector2::from(a_d)) * u.transpose();
    let q = u * Matrix2::from_diagonal(&Vector2::from(q_d)) * u.transpose();
    let sol = dare::solve(&a, &Matrix2::identity(), &q, &(Matrix2::identity() * r)).unwrap();
    assert!(rel((sol.p - want).norm(), want.norm()) < 1e-12, "{}", sol.p);
}

/// The single-input fast path agrees with the general solver and with the plain iteration
/// on each body axis of the servo.
#[test]
fn single_input_fast_path_matches() {
    let p = ardrone();
    let m = ModelParams::from_profile(&p);
    for axis in 0..3 {
        let (a, b, j) = m.body_axis(0.01, axis).unwrap();
        let q = Matrix2::new(p.servo.q[axis], 0.0, 0.0, p.servo.q[axis + 3]);
        let r = p.servo.r[j];
        let fast = dare::solve_single_input(&a, &b, &q, r).unwrap();
        let general = dare::solve(&a, &b, &q, &SMatrix::<f64, 1, 1>::new(r)).unwrap();
        let (plain, _) = plain_riccati(&a, &b, &q, &SMatrix::<f64, 1, 1>::new(r));
        assert!(rel((fast.p - plain).norm(), plain.norm()) < 1e-8);
        assert_eq!(fast.p, general.p);
        assert!((fast.spectral_radius - general.spectral_radius).abs() < 1e-12);
        assert!(fast.residual < 1e-9);
    }
}

/// Positions unweighted: the bare solver must not hand back the non-stabilising P; the servo
/// check refuses the weights before solving, naming `servo.q`.
#[test]
fn unweighted_positions_are_rejected() {
    let p = ardrone();
    let m = ModelParams::from_profile(&p);
    let mut qd = p.servo.q;
    qd[3] = 0.0;
    qd[4] = 0.0;
    qd[5] = 0.0;
    let q = Matrix6::from_diagonal(&Vector6::from(qd));
    let (_, r) = weights(&p);
    match dare::solve(&m.a1(0.01, 0.0), &m.b1(0.01, 0.0), &q, &r) {
        Err(DareError::NotStabilising { spectral_radius }) => {
            assert!(spectral_radius >= 1.0 - 1e-12)
        }
        Err(DareError::NotConverged { .. } | DareError::ResidualTooLarge { .. }) => {}
        other => panic!("accepted unweighted positions: {other:?}"),
    }
    let mut one = p.servo.q;
    one[4] = 0.0;
    let e = dare::check_servo_weights(&one, &p.servo.r).unwrap_err();
    assert_eq!(e, DareError::PositionsUnweighted { axis: 1 });
    let msg = e.to_string();
    assert!(
        msg.contains("servo.q[4]") && msg.contains("y position"),
        "{msg}"
    );
    // Only the velocities unweighted is fine: the positions make them observable.
    let mut vel = p.servo.q;
    vel[0] = 0.0;
    vel[1] = 0.0;
    vel[2] = 0.0;
    dare::check_servo_weights(&vel, &p.servo.r).unwrap();
    let q = Matrix6::from_diagonal(&Vector6::from(vel));
    let sol = dare::solve(&m.a1(0.01, 0.0), &m.b1(0.01, 0.0), &q, &r).unwrap();
    assert!(sol.spectral_radius < 1.0);
}

#[test]
fn bad_weights_are_rejected() {
    let p = ardrone();
    let mut q = p.servo.q;
    q[2] = -1.0;
    let e = dare::check_servo_weights(&q, &p.servo.r).unwrap_err();
    assert!(matches!(
        e,
        DareError::BadWeight {
            key: "servo.q",
            index: 2,
            ..
        }
    ));
    assert!(e.to_string().contains("servo.q[2] = -1"), "{e}");
    let mut r = p.servo.r;
    r[0] = 0.0;
    let e = dare::check_servo_weights(&p.servo.q, &r).unwrap_err();
    assert!(
        e.to_string()
            .contains("servo.r[0] = 0 must be finite and > 0"),
        "{e}"
    );
    r[0] = f64::NAN;
    assert!(dare::check_servo_weights(&p.servo.q, &r).is_err());
    // The bare solver: non-finite entries and R not positive.
    let m = ModelParams::from_profile(&p);
    let (qm, rm) = weights(&p);
    let mut a = m.a1(0.01, 0.0);
    a[(0, 0)] = f64::INFINITY;
    assert_eq!(
        dare::solve(&a, &m.b1(0.01, 0.0), &qm, &rm).unwrap_err(),
        DareError::NotFinite
    );
    let mut r0 = rm;
    r0[(1, 1)] = 0.0;
    assert!(matches!(
        dare::solve(&m.a1(0.01, 0.0), &m.b1(0.01, 0.0), &qm, &r0),
        Err(DareError::BadWeight {
            key: "R",
            index: 1,
            ..
        })
    ));
}

/// An uncontrollable unstable mode: no stabilising solution exists, whatever Q is.
#[test]
fn unstabilisable_plant_is_not_stabilising() {
    let a = Matrix2::new(1.05, 0.0, 0.0, 0.9);
    let b = Vector2::new(0.0, 1.0);
    let q = Matrix2::identity();
    match dare::solve_single_input(&a, &b, &q, 1.0) {
        Err(e @ DareError::NotConverged { change, .. }) if change.is_infinite() => {
            assert!(e.to_string().contains("no stabilising solution"), "{e}")
        }
        Err(DareError::NotStabilising { .. }) => {}
        other => panic!("{other:?}"),
    }
}

/// The general solver works for any N×M: the dual (filter) DARE of the servo model.
#[test]
fn the_filter_dare_is_solved_as_the_dual() {
    let p = ardrone();
    let m = ModelParams::from_profile(&p);
    let a = m.a1(0.01, 0.4);
    let mut ht = Matrix6x3::zeros();
    ht.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&Matrix3::identity());
    let f = Matrix6::from_diagonal(&Vector6::from(p.servo.process_noise));
    let h = Matrix3::from_diagonal(&Vector3::from(p.servo.measurement_noise_m2));
    let sol = dare::solve(&a.transpose(), &ht, &f, &h).unwrap();
    let (plain, _) = plain_riccati(&a.transpose(), &ht, &f, &h);
    assert!(rel((sol.p - plain).norm(), plain.norm()) < 1e-8);
    assert!(sol.residual < 1e-9);
}
