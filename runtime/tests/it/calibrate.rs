//! The calibration flight on the simulator reduced to the pure first-order model (mocap
//! noise on): starting from the `ardrone2` prior, it recovers a different plant's K and τ on
//! every axis within 5 %, stays inside the stage, and lands. On the full simulator (gusts,
//! attitude lag, latency, drag, asymmetric climb, radio loss, dropouts), the square flown
//! with the identified profile tracks within 10 % of the same flight with the nominal one.

use dronecine_backend::Backends;
use dronecine_backend::FlightState;
use dronecine_flight::NoObserver;
use dronecine_grammar::script::{Scene, Stage};
use dronecine_identify::calibrate::{calibrate, CalibrateError, Calibration, Plan};
use dronecine_identify::Axis;
use dronecine_mcap::record::NullSink;
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::{Effects, SimConfig, Simulator};

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

/// A calibration flight on a simulator of `plant` over `scene`, from `prior`: the outcome and
/// the drone's state at the end.
fn fly_calibration(
    cfg: &SimConfig,
    plant: &Profile,
    prior: &Profile,
    scene: &Scene,
    plan: &Plan,
    interrupts: Option<&std::sync::atomic::AtomicU32>,
) -> (Result<Calibration, CalibrateError>, FlightState) {
    let sim = Simulator::new(cfg, plant, scene).unwrap();
    let (mut drone, mut mocap, mut clock) = (sim.drone(), sim.mocap(), sim.clock());
    let outcome = calibrate(
        Backends {
            drone: &mut drone,
            mocap: &mut mocap,
            clock: &mut clock,
        },
        &scene.stage,
        prior,
        plan,
        interrupts,
    );
    (outcome, sim.truth().state)
}

/// The default calibration flight on the 6 × 6 × 3 m stage; it must succeed.
fn calibrate_on(cfg: &SimConfig, plant: &Profile, prior: &Profile) -> (Calibration, FlightState) {
    let (outcome, state) = fly_calibration(cfg, plant, prior, &scene(), &Plan::default(), None);
    (outcome.unwrap(), state)
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
    let (cal, end_state) = calibrate_on(&cfg, &truth, &prior);
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
    assert_eq!(end_state, FlightState::Landed);
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
    let plan = Plan {
        axes: vec![Axis::Roll],
        ..Plan::default()
    };
    let (outcome, state) = fly_calibration(&cfg, &prior, &prior, &scene, &plan, None);
    let err = outcome.expect_err("refused");
    assert!(
        err.to_string().contains("too small for the roll test"),
        "{err}"
    );
    assert_eq!(state, FlightState::Landed);
}

#[test]
fn an_interrupt_lands_the_drone_and_stops_the_calibration() {
    let prior = Profile::builtin("ardrone2").unwrap();
    let cfg = SimConfig {
        effects: Effects::none(),
        ..SimConfig::new(5)
    };
    // Ctrl-C pressed once before the first test: hover, land, error.
    let interrupts = std::sync::atomic::AtomicU32::new(1);
    let (outcome, state) = fly_calibration(
        &cfg,
        &prior,
        &prior,
        &scene(),
        &Plan::default(),
        Some(&interrupts),
    );
    let err = outcome.expect_err("interrupted");
    assert!(err.to_string().contains("interrupted"), "{err}");
    assert_eq!(state, FlightState::Landed);
}

/// RMS position error of `shots/square.psl` flown by the LQG servo with `servo`'s model on
/// the full simulator of the nominal `ardrone2` (seed `seed`).
fn square_rms_m(servo: &Profile, seed: u64) -> f64 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shots/square.psl");
    let text = std::fs::read_to_string(&path).unwrap();
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: path.parent(),
    };
    let script = dronecine_grammar::check(&text, &opts).script.unwrap();
    let nominal = Profile::builtin("ardrone2").unwrap();
    let flight = SimFlight {
        script: &script,
        source: &text,
        scene: script.scene.as_ref().unwrap(),
        profile: servo,
        rate_hz: 100.0,
        controller: ControllerSetup::new("lqg"),
        plant: Some(&nominal),
        sim: SimConfig::new(seed),
        realtime: false,
        interrupts: None,
    };
    let report = fly_simulated(&flight, &mut NullSink, &mut NoObserver).unwrap();
    assert!(report.completed);
    report
        .figures
        .rms_position_error_m
        .expect("the shots were measured")
}

#[test]
fn on_the_full_simulator_the_identified_profile_flies_the_square_within_10_percent() {
    let nominal = Profile::builtin("ardrone2").unwrap();
    // A deliberately wrong prior: the calibration must find the plant, not echo the prior.
    let mut prior = nominal.clone();
    prior.model.gain_roll_mps_per_rad = 12.0;
    prior.model.tau_roll_s = 1.0;
    prior.model.gain_pitch_mps_per_rad = 12.0;
    prior.model.tau_pitch_s = 1.0;
    prior.model.gain_vz = 0.7;
    prior.model.tau_vz_s = 0.8;
    let (cal, end_state) = calibrate_on(&SimConfig::new(3), &nominal, &prior);
    assert!(cal.errors.is_empty(), "{:?}", cal.errors);
    let identified = cal.profile.clone().unwrap();
    let (m, t) = (&identified.model, &nominal.model);
    for (name, got, want, tol) in [
        // Gusts of 0.3 m/s blur the drag's τ: the intervals are ±10–15 % here.
        (
            "K_phi",
            m.gain_roll_mps_per_rad,
            t.gain_roll_mps_per_rad,
            0.2,
        ),
        ("tau_phi", m.tau_roll_s, t.tau_roll_s, 0.2),
        (
            "K_theta",
            m.gain_pitch_mps_per_rad,
            t.gain_pitch_mps_per_rad,
            0.2,
        ),
        ("tau_theta", m.tau_pitch_s, t.tau_pitch_s, 0.2),
        // The climb's gain (the profile's convention; the descent's is twice it).
        ("K_zdot", m.gain_vz, t.gain_vz, 0.05),
        ("tau_zdot", m.tau_vz_s, t.tau_vz_s, 0.05),
        ("K_psi", m.gain_yaw, t.gain_yaw, 0.05),
    ] {
        eprintln!("{name}: {got:.4} (nominal {want})");
        assert!((got / want - 1.0).abs() < tol, "{name}: {got} vs {want}");
    }
    // The descent's own gain: the simulator's descents act twice as strongly as its climbs
    // (`descent_gain_factor`); the vertical doublets, a climb then a descent, find it.
    let vz = cal.fit.vz.as_ref().unwrap();
    let descent = vz.descent_gain.unwrap();
    let want = SimConfig::new(3).descent_gain_factor * t.gain_vz;
    eprintln!("descent gain {descent:?} (simulated {want})");
    assert!((descent.value / want - 1.0).abs() < 0.05, "{vz:?}");
    let roll = cal.fit.roll.as_ref().unwrap();
    eprintln!(
        "latency {:?} s, attitude lag {:?} s",
        roll.latency_s, roll.attitude_lag_s
    );
    assert!((roll.latency_s.unwrap() - 0.04).abs() < 0.015, "{roll:?}");
    assert_eq!(end_state, FlightState::Landed);
    // The square, the identified profile against the nominal one, on two seeded flights.
    for seed in [7, 9] {
        let (with_nominal, with_identified) = (
            square_rms_m(&nominal, seed),
            square_rms_m(&identified, seed),
        );
        eprintln!("seed {seed}: nominal {with_nominal:.4} m, identified {with_identified:.4} m");
        assert!(
            with_identified <= 1.1 * with_nominal,
            "seed {seed}: {with_identified} vs {with_nominal}"
        );
    }
}
