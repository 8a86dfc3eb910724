//! Servo timings: one LQG tick (rotated body-frame gains, target ≤ 1 µs), one LQG tick with
//! the full per-tick solve, one full 6×6 SDA solve (target ≤ 20 µs), the three 2×2 body
//! solves, and one PID tick.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use dronecine_profile::Profile;
use dronecine_servo::control::{Controller, Measurement, Reference, TickInput};
use dronecine_servo::dare;
use dronecine_servo::lqg::{LqgServo, ServoOptions};
use dronecine_servo::model::ModelParams;
use dronecine_servo::pid::PidController;
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

fn input(k: u64) -> TickInput {
    let t = k as f64 * 0.01;
    let (s, c) = (0.5 * t).sin_cos();
    TickInput {
        t_s: t,
        dt_s: 0.01,
        measurement: Some(Measurement {
            position_m: [c, s, 1.0],
            heading_rad: 0.5 * t,
        }),
        reference: Reference {
            position_m: [c, s, 1.0],
            velocity_mps: [-0.5 * s, 0.5 * c, 0.0],
            acceleration_mps2: [-0.25 * c, -0.25 * s, 0.0],
            heading_rad: 0.5 * t,
            heading_rate_radps: 0.5,
        },
    }
}

fn tick_bench(c: &mut Criterion, name: &str, ctl: &mut dyn Controller) {
    ctl.reset(
        0.0,
        &Measurement {
            position_m: [1.0, 0.0, 1.0],
            heading_rad: 0.0,
        },
    );
    let mut k = 0u64;
    c.bench_function(name, |b| {
        b.iter(|| {
            k += 1;
            black_box(ctl.tick(black_box(&input(k % 10_000))).unwrap())
        })
    });
}

fn benches(c: &mut Criterion) {
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut lqg = LqgServo::new(&profile, ServoOptions::default()).unwrap();
    tick_bench(c, "lqg tick (rotated gains)", &mut lqg);
    let mut per_tick = LqgServo::new(
        &profile,
        ServoOptions {
            per_tick_solve: true,
            ..ServoOptions::default()
        },
    )
    .unwrap();
    tick_bench(c, "lqg tick (per-tick 6x6 solve)", &mut per_tick);
    let mut pid = PidController::new(&profile);
    tick_bench(c, "pid tick", &mut pid);

    let m = ModelParams::from_profile(&profile);
    let (a, b) = (m.a1(0.01, 0.8), m.b1(0.01, 0.8));
    let q = Matrix6::from_diagonal(&Vector6::from(profile.servo.q));
    let r = Matrix3::from_diagonal(&Vector3::from(profile.servo.r));
    c.bench_function("sda 6x6 solve (unchecked)", |bch| {
        bch.iter(|| dare::solve_unchecked(black_box(&a), black_box(&b), &q, &r).unwrap())
    });
    c.bench_function("sda 6x6 solve + residual + stability", |bch| {
        bch.iter(|| dare::solve(black_box(&a), black_box(&b), &q, &r).unwrap())
    });
    c.bench_function("three 2x2 body solves", |bch| {
        bch.iter(|| lqg.body_gain(black_box(0.0101)).unwrap())
    });
}

criterion_group!(servo, benches);
criterion_main!(servo);
