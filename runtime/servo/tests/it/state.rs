//! A controller's state between two ticks, taken and restored: a controller built the same
//! way, whatever it flew before, restored to the state another had before tick k gives that
//! controller's outputs from tick k on, bit for bit, and ends in the same state. What the
//! flight log's key frames and replay's resumption after a gap rely on.
//!
//! The flights change Δ by more than the body gain's re-solve tolerance and back, repeat Δ
//! exactly for runs of ticks (the caches keyed by Δ: the lag, the heading pole), drop the
//! measurement now and then and for runs, and refuse a tick (Δ = 0), so that every field
//! that a tick reads or writes is exercised.

use dronecine_backend::frames;
use dronecine_profile::Profile;
use dronecine_servo::control::{
    Controller, ControllerState, Measurement, Reference, TickFault, TickInput, TickOutput,
};
use dronecine_servo::lqg::{LqgServo, ServoOptions};
use dronecine_servo::model::ModelParams;
use dronecine_servo::pid::PidController;
use nalgebra::Vector6;

const TICKS: usize = 600;

fn ardrone() -> Profile {
    Profile::builtin("ardrone2").unwrap()
}

/// Δ at tick `k`: 10 ms in runs, jittered by up to ±35 % in others (the body gain is solved
/// again beyond ±5 %), and 0 (a refused tick) once.
fn dt_at(k: usize) -> f64 {
    match k {
        250 => 0.0,
        _ if (k / 40) % 3 == 1 => 0.01 * (1.0 + 0.35 * (k as f64 * 1.7).sin()),
        _ if (k / 40) % 3 == 2 => 0.013,
        _ => 0.01,
    }
}

/// Mocap dropouts: every seventh tick, and a run of twelve.
fn dropped(k: usize) -> bool {
    k % 7 == 3 || (300..312).contains(&k)
}

/// A turning circle: the heading sweeps all the way round (the rotated gains matter).
fn reference(t: f64) -> Reference {
    let (w, r, v) = (0.6, 1.2, 0.72);
    let (s, c) = dronecine_math::sin_cos(w * t);
    Reference {
        position_m: [r * c, r * s, 1.2],
        velocity_mps: [-v * s, v * c, 0.0],
        acceleration_mps2: [-v * w * c, -v * w * s, 0.0],
        heading_rad: frames::wrap_angle_rad(w * t + 1.3),
        heading_rate_radps: w,
    }
}

/// Flies `ctl` in closed loop on the nominal model for [`TICKS`] ticks; returns each tick's
/// input, the controller's state before it, and its output.
fn fly(
    ctl: &mut dyn Controller,
    profile: &Profile,
) -> Vec<(TickInput, ControllerState, Result<TickOutput, TickFault>)> {
    let model = ModelParams::from_profile(profile);
    let mut x = Vector6::new(0.0, 0.0, 0.0, 1.0, -0.3, 1.0);
    let mut c = 0.4;
    ctl.reset(
        0.0,
        &Measurement {
            position_m: [x[3], x[4], x[5]],
            heading_rad: c,
        },
    );
    let mut t = 0.0;
    let mut out = Vec::with_capacity(TICKS);
    for k in 0..TICKS {
        let dt = dt_at(k);
        t += dt;
        let input = TickInput {
            t_s: t,
            dt_s: dt,
            measurement: (!dropped(k)).then_some(Measurement {
                position_m: [x[3], x[4], x[5]],
                heading_rad: c,
            }),
            reference: reference(t),
        };
        let before = ctl.state();
        let o = ctl.tick(&input);
        if let Ok(o) = &o {
            let step = dt.max(0.01);
            x = model.step(&x, &o.command.translation_input(), step, c);
            c = model.heading_step(c, step, o.command.yaw_rate_radps);
        }
        out.push((input, before, o));
    }
    assert!(
        out.iter().filter(|(_, _, o)| o.is_err()).count() == 1,
        "one refused tick"
    );
    out
}

fn same_output(a: &Result<TickOutput, TickFault>, b: &Result<TickOutput, TickFault>) -> bool {
    match (a, b) {
        (Ok(a), Ok(b)) => {
            let bits = |o: &TickOutput| {
                let (c, e) = (&o.command, &o.estimate);
                [c.roll_rad, c.pitch_rad, c.yaw_rate_radps, c.vz_mps]
                    .into_iter()
                    .chain(e.position_m)
                    .chain(e.velocity_mps)
                    .chain([e.heading_rad])
                    .map(f64::to_bits)
                    .collect::<Vec<_>>()
            };
            bits(a) == bits(b) && a.saturated == b.saturated
        }
        (Err(a), Err(b)) => a == b,
        _ => false,
    }
}

/// A fresh controller that flew something else first: reset elsewhere and ticked on other
/// inputs (other Δs, other measurements), so that none of its state is the flight's.
fn elsewhere(make: &dyn Fn() -> Box<dyn Controller>) -> Box<dyn Controller> {
    let mut ctl = make();
    ctl.reset(
        5.0,
        &Measurement {
            position_m: [-2.0, 1.5, 0.4],
            heading_rad: -2.5,
        },
    );
    let mut t = 5.0;
    for k in 0..37 {
        let dt = 0.0171 + 0.001 * (k % 3) as f64;
        t += dt;
        let _ = ctl.tick(&TickInput {
            t_s: t,
            dt_s: dt,
            measurement: (k % 2 == 0).then_some(Measurement {
                position_m: [-2.0 + 0.01 * k as f64, 1.5, 0.5],
                heading_rad: -2.4,
            }),
            reference: reference(-t),
        });
    }
    ctl
}

/// Restored before each of several ticks (the first, mid-run, in a dropout, after the
/// refused tick), a controller built the same way gives the flight's outputs and states.
fn restoring_resumes_bit_for_bit(name: &str, make: &dyn Fn() -> Box<dyn Controller>) {
    let profile = ardrone();
    let flight = fly(make().as_mut(), &profile);
    let mut a = make();
    let last = fly(a.as_mut(), &profile);
    let end = a.state();
    assert!(
        last.iter()
            .zip(&flight)
            .all(|(x, y)| same_output(&x.2, &y.2)),
        "{name}: the flight is deterministic"
    );
    let mut distinct = 0;
    for k in [0, 1, 41, 80, 121, 250, 251, 305, 450, TICKS - 1] {
        let mut b = elsewhere(make);
        let (_, before, _) = &flight[k];
        if !b.state().same_bits(before) {
            distinct += 1;
        }
        b.restore(before).unwrap();
        assert!(b.state().same_bits(before), "{name}: restored before {k}");
        for (j, (input, state, output)) in flight.iter().enumerate().skip(k) {
            assert!(
                b.state().same_bits(state),
                "{name}: restored before tick {k}, the state before tick {j}"
            );
            let o = b.tick(input);
            assert!(
                same_output(&o, output),
                "{name}: restored before tick {k}, tick {j}: {o:?} against {output:?}"
            );
        }
        assert!(
            b.state().same_bits(&end),
            "{name}: from {k}, the last state"
        );
    }
    assert_eq!(
        distinct, 10,
        "{name}: each restore had something to restore"
    );
}

#[test]
fn lqg_with_rotated_gains_resumes_from_its_state_bit_for_bit() {
    let profile = ardrone();
    restoring_resumes_bit_for_bit("lqg", &|| {
        Box::new(LqgServo::new(&profile, ServoOptions::default()).unwrap())
    });
}

#[test]
fn lqg_solving_each_tick_resumes_from_its_state_bit_for_bit() {
    let profile = ardrone();
    restoring_resumes_bit_for_bit("lqg per-tick solve", &|| {
        let options = ServoOptions {
            per_tick_solve: true,
            ..ServoOptions::default()
        };
        Box::new(LqgServo::new(&profile, options).unwrap())
    });
}

#[test]
fn lqg_with_the_papers_prefilter_resumes_from_its_state_bit_for_bit() {
    let profile = ardrone();
    restoring_resumes_bit_for_bit("lqg paper", &|| {
        let options = ServoOptions {
            paper_prefilter: true,
            ..ServoOptions::default()
        };
        Box::new(LqgServo::new(&profile, options).unwrap())
    });
}

#[test]
fn pid_resumes_from_its_state_bit_for_bit() {
    let profile = ardrone();
    restoring_resumes_bit_for_bit("pid", &|| Box::new(PidController::new(&profile)));
}

#[test]
fn a_state_of_another_kind_is_refused_and_changes_nothing() {
    let profile = ardrone();
    let mut lqg = LqgServo::new(&profile, ServoOptions::default()).unwrap();
    let mut pid = PidController::new(&profile);
    let (l, p) = (lqg.state(), pid.state());
    assert!(lqg.restore(&p).unwrap_err().contains("pid"));
    assert!(pid.restore(&l).unwrap_err().contains("lqg"));
    assert!(lqg.state().same_bits(&l) && pid.state().same_bits(&p));
    assert!(!l.same_bits(&p));
}
