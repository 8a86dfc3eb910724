//! The calibration flight on the simulator reduced to the pure first-order model (mocap
//! noise on): starting from the `ardrone2` prior, it recovers a different plant's K and τ on
//! every axis within 5 %, stays inside the stage, and lands.

use dronecine_compiler::profile::Profile;
use dronecine_grammar::script::{Scene, Stage};
use dronecine_runtime::backend::FlightState;
use dronecine_runtime::calibrate::{calibrate, Plan};
use dronecine_runtime::flight::Backends;
use dronecine_runtime::identify::Axis;
use dronecine_runtime::sim::{Effects, SimConfig, Simulator};

fn scene() -> Scene {
    Scene {
        stage: Stage {
            size_m: [6.0, 6.0, 3.0],
        },
        lens: None,
        drone: None,
        actors: Vec::new(),
        blocking: Vec::new(),
    }
}

/// The plant flown: the prior with every model value moved.
fn truth_profile() -> Profile {
    let mut p = Profile::builtin("ardrone2").unwrap();
    p.model.gain_roll_mps_per_rad = 14.0;
    p.model.tau_roll_s = 1.3;
    p.model.gain_pitch_mps_per_rad = 21.0;
    p.model.tau_pitch_s = 2.1;
    p.model.gain_vz = 0.8;
    p.model.tau_vz_s = 0.9;
    p.model.gain_yaw = 1.2;
    p
}

#[test]
fn recovers_a_different_plant_within_5_percent_from_the_prior() {
    let prior = Profile::builtin("ardrone2").unwrap();
    let truth = truth_profile();
    let mut cfg = SimConfig::new(11);
    cfg.effects = Effects {
        mocap_noise: true,
        ..Effects::none()
    };
    cfg.mocap_position_sigma_m = 0.001; // 1 mm, three times the default
    let scene = scene();
    let sim = Simulator::new(&cfg, &truth, &scene).unwrap();
    let (mut drone, mut mocap, mut clock) = (sim.drone(), sim.mocap(), sim.clock());
    let cal = calibrate(
        Backends {
            drone: &mut drone,
            mocap: &mut mocap,
            clock: &mut clock,
        },
        &scene.stage,
        &prior,
        &Plan::default(),
        None,
    )
    .unwrap();
    assert!(cal.errors.is_empty(), "{:?}", cal.errors);
    let out = cal.profile.as_ref().unwrap();
    let (m, t) = (&out.model, &truth.model);
    for (name, got, want) in [
        ("K_phi", m.gain_roll_mps_per_rad, t.gain_roll_mps_per_rad),
        ("tau_phi", m.tau_roll_s, t.tau_roll_s),
        (
            "K_theta",
            m.gain_pitch_mps_per_rad,
            t.gain_pitch_mps_per_rad,
        ),
        ("tau_theta", m.tau_pitch_s, t.tau_pitch_s),
        ("K_zdot", m.gain_vz, t.gain_vz),
        ("tau_zdot", m.tau_vz_s, t.tau_vz_s),
        ("K_psi", m.gain_yaw, t.gain_yaw),
    ] {
        eprintln!("{name}: {got:.4} (truth {want})");
        assert!((got / want - 1.0).abs() < 0.05, "{name}: {got} vs {want}");
    }
    // Every other section is the prior's (the motion limits follow the model).
    assert_eq!(out.servo, prior.servo);
    assert_eq!(out.limits.tilt_max_rad, prior.limits.tilt_max_rad);
    assert_eq!(out.limits.vz_max_mps, prior.limits.vz_max_mps);
    assert_eq!(out.camera, prior.camera);
    // Every fit has its quality figure and a CI containing the value's order.
    for axis in Axis::ALL {
        let f = cal.fit.get(axis).unwrap();
        assert!(f.r2 > 0.99, "{f:?}");
        assert!(f.gain.relative_ci() < 0.05, "{f:?}");
    }
    // The flight stayed inside the stage's keep-in box and ended on the floor.
    let lim = 3.0 - prior.safety.stage_margin_m;
    for (_, seg) in &cal.tests {
        for s in seg {
            if let Some(p) = s.position_m {
                assert!(
                    p[0].abs() < lim && p[1].abs() < lim && p[2] < 3.0 - 0.3,
                    "{p:?}"
                );
            }
        }
    }
    assert_eq!(sim.truth().state, FlightState::Landed);
}

#[test]
fn a_stage_too_small_refuses_the_test_and_lands() {
    let prior = Profile::builtin("ardrone2").unwrap();
    let cfg = SimConfig {
        effects: Effects::none(),
        ..SimConfig::new(3)
    };
    let scene = Scene {
        stage: Stage {
            size_m: [0.7, 0.7, 2.5],
        },
        ..scene()
    };
    let sim = Simulator::new(&cfg, &prior, &scene).unwrap();
    let (mut drone, mut mocap, mut clock) = (sim.drone(), sim.mocap(), sim.clock());
    let plan = Plan {
        axes: vec![Axis::Roll],
        ..Plan::default()
    };
    let err = calibrate(
        Backends {
            drone: &mut drone,
            mocap: &mut mocap,
            clock: &mut clock,
        },
        &scene.stage,
        &prior,
        &plan,
        None,
    )
    .expect_err("refused");
    assert!(
        err.to_string().contains("too small for the roll test"),
        "{err}"
    );
    assert_eq!(sim.truth().state, FlightState::Landed);
}

#[test]
fn an_interrupt_lands_the_drone_and_stops_the_calibration() {
    let prior = Profile::builtin("ardrone2").unwrap();
    let cfg = SimConfig {
        effects: Effects::none(),
        ..SimConfig::new(5)
    };
    let scene = scene();
    let sim = Simulator::new(&cfg, &prior, &scene).unwrap();
    let (mut drone, mut mocap, mut clock) = (sim.drone(), sim.mocap(), sim.clock());
    // Ctrl-C pressed once before the first test: hover, land, error.
    let interrupts = std::sync::atomic::AtomicU32::new(1);
    let err = calibrate(
        Backends {
            drone: &mut drone,
            mocap: &mut mocap,
            clock: &mut clock,
        },
        &scene.stage,
        &prior,
        &Plan::default(),
        Some(&interrupts),
    )
    .expect_err("interrupted");
    assert!(err.to_string().contains("interrupted"), "{err}");
    assert_eq!(sim.truth().state, FlightState::Landed);
}
