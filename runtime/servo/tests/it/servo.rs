//! The LQG servo and the PID baseline in closed loop on the nominal model (simulated here
//! with `A1`/`B1` and the heading model), and their properties: rotated body-frame gains equal
//! the full solve, the paper's pre-filter equals the simplified one, feed-forward tracks a
//! circle better, the heading turns the short way, faults leave the state untouched, dropouts
//! predict, saturation holds its limits and the filter sees the saturated command.

use dronecine_backend::frames::{self, Command};
use dronecine_profile::Profile;
use dronecine_servo::control::{
    Controller, Measurement, Reference, TickFault, TickInput, TickOutput,
};
use dronecine_servo::dare;
use dronecine_servo::lqg::{self, LqgServo, ServoOptions};
use dronecine_servo::model::{rotation6, ModelParams};
use dronecine_servo::pid::PidController;
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use std::f64::consts::PI;

const DT: f64 = 0.01;

fn ardrone() -> Profile {
    Profile::builtin("ardrone2").unwrap()
}

/// A profile with different roll and pitch time constants and gains (the body-frame lag
/// matters only then).
fn anisotropic_model() -> Profile {
    let mut p = ardrone();
    p.model.tau_roll_s = 1.2;
    p.model.gain_pitch_mps_per_rad = 14.0;
    p
}

/// The nominal plant: `x1 = [v; p]` and the heading.
struct Plant {
    model: ModelParams,
    x: Vector6<f64>,
    c: f64,
}

impl Plant {
    fn new(profile: &Profile, p: [f64; 3], c: f64) -> Plant {
        Plant {
            model: ModelParams::from_profile(profile),
            x: Vector6::new(0.0, 0.0, 0.0, p[0], p[1], p[2]),
            c,
        }
    }

    fn measure(&self) -> Measurement {
        Measurement {
            position_m: [self.x[3], self.x[4], self.x[5]],
            heading_rad: self.c,
        }
    }

    fn apply(&mut self, cmd: &Command, dt: f64) {
        self.x = self
            .model
            .step(&self.x, &cmd.translation_input(), dt, self.c);
        self.c = self.model.heading_step(self.c, dt, cmd.yaw_rate_radps);
    }

    fn position(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(3).into_owned()
    }
}

fn hold(p: [f64; 3], heading: f64) -> Reference {
    Reference {
        position_m: p,
        heading_rad: heading,
        ..Reference::default()
    }
}

/// A horizontal circle of radius `r` at speed `v` around (0, 0, 1), starting at (r, 0)
/// (portable arithmetic: [`command_checksum`] flies it).
fn circle(t: f64, r: f64, v: f64) -> Reference {
    let w = v / r;
    let (s, c) = dronecine_math::sin_cos(w * t);
    Reference {
        position_m: [r * c, r * s, 1.0],
        velocity_mps: [-v * s, v * c, 0.0],
        acceleration_mps2: [-v * w * c, -v * w * s, 0.0],
        heading_rad: frames::wrap_angle_rad(w * t + PI / 2.0),
        heading_rate_radps: w,
    }
}

/// Flies `ctl` on the plant for `n` ticks; the measurement is the true pose (or `None` where
/// `dropout(k)`); returns the tick times, outputs and the true positions at the ticks (what
/// the estimates refer to).
fn fly(
    ctl: &mut dyn Controller,
    plant: &mut Plant,
    n: usize,
    reference: &dyn Fn(f64) -> Reference,
    dropout: &dyn Fn(usize) -> bool,
) -> Vec<(f64, TickOutput, Vector3<f64>)> {
    let mut out = Vec::with_capacity(n);
    for k in 1..=n {
        let t = k as f64 * DT;
        let input = TickInput {
            t_s: t,
            dt_s: DT,
            measurement: (!dropout(k)).then(|| plant.measure()),
            reference: reference(t),
        };
        let o = ctl.tick(&input).expect("valid input");
        out.push((t, o, plant.position()));
        plant.apply(&o.command, DT);
    }
    out
}

fn never(_: usize) -> bool {
    false
}

fn started(ctl: &mut dyn Controller, plant: &Plant) {
    ctl.reset(0.0, &plant.measure());
}

fn lqg(profile: &Profile, options: ServoOptions) -> LqgServo {
    LqgServo::new(profile, options).unwrap()
}

#[test]
fn rotated_body_gain_equals_the_full_solve() {
    for profile in [ardrone(), anisotropic_model()] {
        let servo = lqg(&profile, ServoOptions::default());
        let m = ModelParams::from_profile(&profile);
        let q = Matrix6::from_diagonal(&Vector6::from(profile.servo.q));
        let r = Matrix3::from_diagonal(&Vector3::from(profile.servo.r));
        for dt in [0.01, 0.02] {
            let body = servo.body_gain(dt).unwrap();
            for c in [-3.0, -PI / 2.0, -0.4, 0.0, 0.9, 2.2, PI] {
                let full = dare::solve(&m.a1(dt, c), &m.b1(dt, c), &q, &r).unwrap();
                let rotated = body * rotation6(c).transpose();
                let err = (rotated - full.k).norm() / full.k.norm();
                assert!(err < 1e-9, "dt {dt} c {c}: {err:e}");
            }
        }
    }
}

#[test]
fn per_tick_solve_flies_the_same_commands() {
    let profile = anisotropic_model();
    let mut a = lqg(&profile, ServoOptions::default());
    let mut b = lqg(
        &profile,
        ServoOptions {
            per_tick_solve: true,
            ..ServoOptions::default()
        },
    );
    let (mut pa, mut pb) = (
        Plant::new(&profile, [1.0, 0.0, 1.0], 0.3),
        Plant::new(&profile, [1.0, 0.0, 1.0], 0.3),
    );
    started(&mut a, &pa);
    started(&mut b, &pb);
    let reference = |t| circle(t, 1.0, 0.5);
    let fa = fly(&mut a, &mut pa, 600, &reference, &never);
    let fb = fly(&mut b, &mut pb, 600, &reference, &never);
    let mut worst: f64 = 0.0;
    for ((_, x, _), (_, y, _)) in fa.iter().zip(&fb) {
        for (u, v) in [
            (x.command.roll_rad, y.command.roll_rad),
            (x.command.pitch_rad, y.command.pitch_rad),
            (x.command.vz_mps, y.command.vz_mps),
            (x.command.yaw_rate_radps, y.command.yaw_rate_radps),
        ] {
            worst = worst.max((u - v).abs());
        }
    }
    assert!(worst < 1e-9, "{worst:e}");
    // The heading did turn through a wide range, so the rotation was exercised.
    assert!(fa.iter().any(|(_, o, _)| o.estimate.heading_rad < -1.0));
}

#[test]
fn paper_prefilter_equals_the_simplified_form() {
    let profile = anisotropic_model();
    let servo = lqg(&profile, ServoOptions::default());
    let m = ModelParams::from_profile(&profile);
    for c in [-2.8, -1.0, 0.0, 0.5, 2.0] {
        for dt in [0.008, 0.01, 0.03] {
            let k1 = servo.body_gain(dt).unwrap() * rotation6(c).transpose();
            let paper = lqg::paper_n1(&m.a1(dt, c), &m.b1(dt, c), &k1).unwrap();
            let simple = lqg::n1(&m, &k1, dt, c).unwrap();
            assert!(
                (paper - simple).norm() < 1e-9 * simple.norm(),
                "c {c} dt {dt}"
            );
            // … and the attitude block is K⁻¹ M_Dᵀ (with the sign permutation of frames).
            let hold = (m.input_to_body_velocity().try_inverse().unwrap()
                * frames::body_to_world(c).transpose())
                + k1.fixed_view::<3, 3>(0, 0);
            assert!((simple.fixed_view::<3, 3>(0, 0) - hold).norm() < 1e-9);
        }
    }
}

#[test]
fn servo_errors_name_the_key_and_the_fix() {
    let mut p = ardrone();
    p.servo.q = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let e = LqgServo::new(&p, ServoOptions::default()).unwrap_err();
    assert_eq!(e.key, "servo.q");
    let msg = e.to_string();
    assert!(
        msg.contains("ardrone2") && msg.contains("servo.q[3] = 0") && msg.contains("q = ["),
        "{msg}"
    );
    let mut p = ardrone();
    p.servo.r[2] = -5.0;
    let e = LqgServo::new(&p, ServoOptions::default()).unwrap_err();
    assert_eq!(e.key, "servo.r");
    assert!(e.to_string().contains("servo.r[2] = -5"), "{e}");
    let mut p = ardrone();
    p.servo.heading_gamma = 1.5;
    let e = LqgServo::new(&p, ServoOptions::default()).unwrap_err();
    assert!(e.to_string().contains("servo.heading_gamma = 1.5"), "{e}");
    assert!(e.to_string().contains("[servo] section"), "{e}");
    let mut p = ardrone();
    p.model.tau_pitch_s = f64::NAN;
    let e = LqgServo::new(&p, ServoOptions::default()).unwrap_err();
    assert_eq!(e.key, "model.tau_pitch_s");
    let e = LqgServo::new(
        &ardrone(),
        ServoOptions {
            nominal_dt_s: 0.0,
            ..ServoOptions::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("--dt"), "{e}");
    // An error is a std error with the Riccati cause as its source.
    let mut p = ardrone();
    p.servo.q[5] = 0.0;
    let e: Box<dyn std::error::Error> =
        Box::new(LqgServo::new(&p, ServoOptions::default()).unwrap_err());
    assert!(e.source().is_some());
}

#[test]
fn hover_recovers_from_half_a_metre() {
    let profile = ardrone();
    for ctl in [
        &mut lqg(&profile, ServoOptions::default()) as &mut dyn Controller,
        &mut PidController::new(&profile),
    ] {
        let mut plant = Plant::new(&profile, [0.5, -0.3, 1.4], 0.7);
        started(ctl, &plant);
        let target = [0.0, 0.0, 1.0];
        let trace = fly(ctl, &mut plant, 2000, &|_| hold(target, 0.7), &never);
        let last = trace.last().unwrap().2;
        let err = (last - Vector3::from(target)).norm();
        assert!(err < 0.01, "{err}");
        assert!(plant.x.fixed_rows::<3>(0).norm() < 0.01);
        // It got there without flying off: never more than 0.2 m beyond the start distance.
        let start = (Vector3::new(0.5, -0.3, 1.4) - Vector3::from(target)).norm();
        assert!(trace
            .iter()
            .all(|(_, _, p)| (p - Vector3::from(target)).norm() < start + 0.2));
    }
}

/// Largest position error over the second half of a 0.5 m/s circle of radius 1 m.
fn circle_error(options: ServoOptions, profile: &Profile) -> f64 {
    let mut servo = lqg(profile, options);
    let mut plant = Plant::new(profile, [1.0, 0.0, 1.0], PI / 2.0);
    started(&mut servo, &plant);
    // Start on the circle at its speed.
    plant.x[1] = 0.5;
    let reference = |t| circle(t, 1.0, 0.5);
    let n = 4000; // ≈ 3 laps
    let trace = fly(&mut servo, &mut plant, n, &reference, &never);
    trace[n / 2..]
        .iter()
        .map(|(t, _, p)| (p - Vector3::from(reference(*t).position_m)).norm())
        .fold(0.0, f64::max)
}

#[test]
fn circle_is_tracked_and_feed_forward_helps() {
    for profile in [ardrone(), anisotropic_model()] {
        let ff = circle_error(ServoOptions::default(), &profile);
        let paper = circle_error(
            ServoOptions {
                paper_prefilter: true,
                ..ServoOptions::default()
            },
            &profile,
        );
        // On the nominal model the feed-forward law is exact up to the discretisation of a_ref:
        // about 1 mm, where the paper's pre-filter lags by about 5 cm.
        assert!(ff < 0.005, "feed-forward error {ff}");
        assert!(ff < 0.25 * paper, "feed-forward {ff} vs paper {paper}");
    }
}

#[test]
fn heading_turns_the_short_way_across_pi() {
    let profile = ardrone();
    for ctl in [
        &mut lqg(&profile, ServoOptions::default()) as &mut dyn Controller,
        &mut PidController::new(&profile),
    ] {
        let from = 170f64.to_radians();
        let to = -170f64.to_radians();
        let mut plant = Plant::new(&profile, [0.0, 0.0, 1.0], from);
        started(ctl, &plant);
        let mut headings = Vec::new();
        for k in 1..=500 {
            let input = TickInput {
                t_s: k as f64 * DT,
                dt_s: DT,
                measurement: Some(plant.measure()),
                reference: hold([0.0, 0.0, 1.0], to),
            };
            let o = ctl.tick(&input).unwrap();
            // Counter-clockwise (heading increasing): a non-positive yaw-rate command.
            assert!(o.command.yaw_rate_radps <= 0.0, "{:?}", o.command);
            plant.apply(&o.command, DT);
            headings.push(plant.c);
        }
        // Never left the 20° arc through ±180°.
        for &c in &headings {
            assert!(c.abs() >= from - 1e-9, "{}", c.to_degrees());
        }
        let end = frames::wrap_angle_rad(plant.c - to).abs();
        assert!(end < 0.5f64.to_radians(), "{}", plant.c.to_degrees());
    }
}

/// The LQG heading loop realises its pole: after heading_tau_s − Δ̄ the error is γ of itself.
#[test]
fn heading_error_falls_to_gamma_after_tau() {
    let profile = ardrone();
    let mut servo = lqg(&profile, ServoOptions::default());
    let mut plant = Plant::new(&profile, [0.0, 0.0, 1.0], 0.0);
    started(&mut servo, &plant);
    let target = 0.3;
    let steps = ((profile.servo.heading_tau_s - DT) / DT).round() as usize;
    fly(
        &mut servo,
        &mut plant,
        steps,
        &|_| hold([0.0, 0.0, 1.0], target),
        &never,
    );
    let left = (target - plant.c) / target;
    // The estimate lags the truth a little through the filter.
    assert!(
        (left - profile.servo.heading_gamma).abs() < 0.02,
        "{left} vs {}",
        profile.servo.heading_gamma
    );
}

#[test]
fn faults_leave_the_state_unchanged() {
    let profile = ardrone();
    let controllers: Vec<Box<dyn Fn() -> Box<dyn Controller>>> = vec![
        Box::new(|| Box::new(lqg(&ardrone(), ServoOptions::default()))),
        Box::new(|| Box::new(PidController::new(&ardrone()))),
    ];
    for make in controllers {
        let mut plant = Plant::new(&profile, [0.3, 0.2, 1.0], 0.1);
        let (mut a, mut b) = (make(), make());
        started(a.as_mut(), &plant);
        started(b.as_mut(), &plant);
        let reference = |t| circle(t, 1.0, 0.5);
        // Some history first.
        for k in 1..=50 {
            let input = TickInput {
                t_s: k as f64 * DT,
                dt_s: DT,
                measurement: Some(plant.measure()),
                reference: reference(k as f64 * DT),
            };
            let o = a.tick(&input).unwrap();
            assert_eq!(b.tick(&input).unwrap(), o);
            plant.apply(&o.command, DT);
        }
        let good = TickInput {
            t_s: 0.51,
            dt_s: DT,
            measurement: Some(plant.measure()),
            reference: reference(0.51),
        };
        let mut bad = Vec::new();
        for f in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut i = good;
            i.measurement.as_mut().unwrap().position_m[1] = f;
            bad.push((i, TickFault::NotFinite));
            let mut i = good;
            i.measurement.as_mut().unwrap().heading_rad = f;
            bad.push((i, TickFault::NotFinite));
            let mut i = good;
            i.reference.velocity_mps[2] = f;
            bad.push((i, TickFault::NotFinite));
            let mut i = good;
            i.reference.heading_rate_radps = f;
            bad.push((i, TickFault::NotFinite));
            let mut i = good;
            i.dt_s = f;
            bad.push((i, TickFault::NotFinite));
        }
        for dt in [0.0, -0.01] {
            let mut i = good;
            i.dt_s = dt;
            bad.push((i, TickFault::TimeNotIncreasing));
        }
        for (input, fault) in &bad {
            assert_eq!(a.tick(input), Err(*fault), "{input:?}");
        }
        // After all those refusals, `a` answers exactly as `b`, which saw none.
        assert_eq!(a.tick(&good).unwrap(), b.tick(&good).unwrap());
    }
}

#[test]
fn dropouts_predict_with_the_velocity() {
    let profile = ardrone();
    for ctl in [
        &mut lqg(&profile, ServoOptions::default()) as &mut dyn Controller,
        &mut PidController::new(&profile),
    ] {
        let mut plant = Plant::new(&profile, [0.0, 0.0, 1.0], 0.0);
        started(ctl, &plant);
        // A straight line at 0.5 m/s along +y; mocap lost from 8 s to 8.5 s.
        let reference = |t: f64| Reference {
            position_m: [0.0, 0.5 * t, 1.0],
            velocity_mps: [0.0, 0.5, 0.0],
            ..Reference::default()
        };
        let lost = |k: usize| (800..850).contains(&k);
        let trace = fly(ctl, &mut plant, 850, &reference, &lost);
        let before = trace[798].1.estimate.position_m[1];
        let (_, last, truth) = &trace[849];
        let moved = last.estimate.position_m[1] - before;
        assert!((moved - 0.5 * 0.51).abs() < 0.02, "moved {moved}");
        let err = (Vector3::from(last.estimate.position_m) - truth).norm();
        assert!(err < 0.01, "estimate off by {err}");
    }
}

#[test]
fn saturation_holds_the_limits_and_the_filter_sees_it() {
    let profile = ardrone();
    let l = &profile.limits;
    for ctl in [
        &mut lqg(&profile, ServoOptions::default()) as &mut dyn Controller,
        &mut PidController::new(&profile),
    ] {
        let mut plant = Plant::new(&profile, [0.0, 0.0, 1.0], 0.4);
        started(ctl, &plant);
        // Far away and turned around, and mocap lost from the start: the estimate is the
        // filter's prediction alone, which must follow the plant flying the *sent* commands.
        let far = hold([-6.0, 5.0, 2.5], -2.6);
        let trace = fly(ctl, &mut plant, 300, &|_| far, &|_| true);
        let (_, first, _) = &trace[0];
        assert!(first.saturated);
        for (_, o, _) in &trace {
            let c = o.command;
            assert!(c.roll_rad.abs() <= l.tilt_max_rad + 1e-12);
            assert!(c.pitch_rad.abs() <= l.tilt_max_rad + 1e-12);
            assert!(c.vz_mps.abs() <= l.vz_max_mps + 1e-12);
            assert!(c.yaw_rate_radps.abs() <= l.yaw_rate_max_radps + 1e-12);
        }
        // The last tick's estimate against the plant before it flew that tick's command.
        let (_, last, truth) = trace.last().unwrap();
        let err = (Vector3::from(last.estimate.position_m) - truth).norm();
        assert!(err < 1e-9, "prediction off by {err}");
        let mut before = Plant::new(&profile, [0.0, 0.0, 1.0], 0.4);
        for (_, o, _) in &trace[..trace.len() - 1] {
            before.apply(&o.command, DT);
        }
        let v_err =
            (Vector3::from(last.estimate.velocity_mps) - before.x.fixed_rows::<3>(0)).norm();
        assert!(v_err < 1e-9, "velocity off by {v_err}");
        assert!((frames::wrap_angle_rad(last.estimate.heading_rad - before.c)).abs() < 1e-9);
        // The commands did move the drone a long way: the unsaturated law would ask for
        // several times the limits.
        assert!(v_err < 1e-9 && before.x.fixed_rows::<3>(0).norm() > 1.0);
    }
}

/// Saturation winds nothing up: a minute pinned at the climb limit toward a target far above,
/// then the target drops to where the drone is: it stops, instead of climbing on while an
/// integrator (or a filter fed the unsaturated command) unwinds.
#[test]
fn no_wind_up_after_a_long_saturated_climb() {
    let profile = ardrone();
    for ctl in [
        &mut lqg(&profile, ServoOptions::default()) as &mut dyn Controller,
        &mut PidController::new(&profile),
    ] {
        let mut plant = Plant::new(&profile, [0.0, 0.0, 1.0], 0.0);
        started(ctl, &plant);
        let trace = fly(
            ctl,
            &mut plant,
            6000,
            &|_| hold([0.0, 0.0, 60.0], 0.0),
            &never,
        );
        assert!(trace[5000..].iter().all(|(_, o, _)| o.saturated));
        let stop = plant.position().z;
        assert!(stop > 20.0, "{stop}");
        let trace = fly(
            ctl,
            &mut plant,
            3000,
            &|_| hold([0.0, 0.0, stop], 0.0),
            &never,
        );
        let top = trace.iter().map(|(_, _, p)| p.z).fold(0.0, f64::max);
        assert!(top < stop + 0.5, "overshoot {}", top - stop);
        assert!((trace.last().unwrap().2.z - stop).abs() < 0.05);
    }
}

#[test]
fn jittery_steps_resolve_and_still_track() {
    let profile = ardrone();
    let mut servo = lqg(&profile, ServoOptions::default());
    let mut plant = Plant::new(&profile, [1.0, 0.0, 1.0], PI / 2.0);
    started(&mut servo, &plant);
    plant.x[1] = 0.5;
    let mut t = 0.0;
    let mut worst: f64 = 0.0;
    for k in 1..=4000usize {
        // Δ between 7 and 13 ms, deterministic.
        let dt = 0.01 + 0.003 * ((k as f64 * 1.7).sin());
        t += dt;
        let r = circle(t, 1.0, 0.5);
        let o = servo
            .tick(&TickInput {
                t_s: t,
                dt_s: dt,
                measurement: Some(plant.measure()),
                reference: r,
            })
            .unwrap();
        // The plant flies the command for the next (unknown) step.
        let next = 0.01 + 0.003 * (((k + 1) as f64 * 1.7).sin());
        plant.apply(&o.command, next);
        if k > 2000 {
            let r_next = circle(t + next, 1.0, 0.5);
            worst = worst.max((plant.position() - Vector3::from(r_next.position_m)).norm());
        }
    }
    assert!(worst < 0.03, "{worst}");
}

#[test]
fn gains_report_is_consistent() {
    let profile = ardrone();
    let servo = lqg(&profile, ServoOptions::default());
    let g = servo.gains_at(0.01, 0.6).unwrap();
    assert!(g.residual < 1e-9);
    assert!(g
        .closed_loop_pole_magnitudes
        .iter()
        .all(|&m| m < 1.0 && m > 0.0));
    let k2 = profile
        .servo
        .heading_gamma
        .powf(0.01 / (profile.servo.heading_tau_s - 0.01));
    assert!((g.k2 - k2).abs() < 1e-15);
    // The Kalman gain of a position measurement: mostly on the positions, each axis its own.
    for i in 0..3 {
        assert!(g.kalman_gain[3 + i][i] > 0.0 && g.kalman_gain[3 + i][i] < 1.0);
        assert!(g.kalman_gain[i][i] > 0.0);
    }
    let k_rot = servo.body_gain(0.01).unwrap() * rotation6(0.6).transpose();
    for i in 0..3 {
        for j in 0..6 {
            assert!((g.k1[i][j] - k_rot[(i, j)]).abs() < 1e-9 * k_rot.norm());
        }
    }
}

/// A closed-loop flight whose every number is portable arithmetic (the plant is the nominal
/// model, the reference a circle with the heading turning through ±π, Δ jittering, every
/// ninth measurement missing), reduced to a checksum of the commands' bits (FNV-1a).
fn command_checksum(ctl: &mut dyn Controller, profile: &Profile) -> u64 {
    let mut plant = Plant::new(profile, [1.0, 0.0, 1.0], 0.0);
    started(ctl, &plant);
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bits: u64| {
        for byte in bits.to_le_bytes() {
            hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    let mut t = 0.0;
    for k in 1..=3000usize {
        let dt = DT + 0.002 * ((k % 7) as f64 - 3.0) / 3.0;
        t += dt;
        let input = TickInput {
            t_s: t,
            dt_s: dt,
            measurement: (k % 9 != 0).then(|| plant.measure()),
            reference: circle(t, 1.0, 0.5),
        };
        let o = ctl.tick(&input).expect("valid input");
        let cmd = o.command;
        for x in [cmd.roll_rad, cmd.pitch_rad, cmd.yaw_rate_radps, cmd.vz_mps] {
            eat(x.to_bits());
        }
        eat(u64::from(o.saturated));
        plant.apply(&cmd, dt);
    }
    hash
}

/// Replay must reproduce a log's commands bit for bit on any machine, so the controllers'
/// arithmetic must not depend on the machine: the same flight gives the same checksum
/// everywhere. A different checksum means the control law changed (update the constants:
/// logs written before no longer replay) or a platform function crept into a controller
/// (instead of `dronecine_math`'s; replay would then fail on another machine).
#[test]
fn the_commands_are_the_same_bits_on_every_machine() {
    let profile = ardrone();
    let options = ServoOptions::default();
    let cases: [(&str, Box<dyn Controller>, u64); 3] = [
        (
            "lqg",
            Box::new(lqg(&profile, options)),
            0x59a6_0754_fec4_60c7,
        ),
        (
            "lqg --paper-prefilter",
            Box::new(lqg(
                &profile,
                ServoOptions {
                    paper_prefilter: true,
                    ..options
                },
            )),
            0x9e1a_707b_c7d3_eb30,
        ),
        (
            "pid",
            Box::new(PidController::new(&profile)),
            0x3cd4_138a_64a5_a0f1,
        ),
    ];
    for (name, mut ctl, want) in cases {
        let got = command_checksum(ctl.as_mut(), &profile);
        assert_eq!(got, want, "{name}: checksum {got:#018x}");
    }
}
