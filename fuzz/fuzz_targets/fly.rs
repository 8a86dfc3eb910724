//! Fuzz what comes after the front end: any script that checks without errors is compiled
//! (`compile`, at 20 Hz) and flown on the embedded simulator (as `shoot` flies it, every
//! effect on but the battery) without a panic. A script `compile` refuses must be refused by
//! the flight too, and every sample either gives is finite. Scripts longer than 60 s are
//! skipped (one input would otherwise take seconds). Seed it with the shipped shots
//! (`../shots/*.psl`).
#![no_main]

use dronecine_compiler::compile::{compile, unflyable, Options};
use dronecine_flight::NoObserver;
use dronecine_grammar::{check, decode};
use dronecine_mcap::record::NullSink;
use dronecine_profile::{Profile, BUILTIN_NAMES};
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = decode(data) else {
        return;
    };
    let opts = dronecine_grammar::Options {
        known_drones: BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = check(&src, &opts);
    if checked.has_errors() {
        return;
    }
    let Some(script) = checked.script else {
        return;
    };
    if !(script.duration_s <= 60.0) {
        return;
    }
    // A profile file cannot be read here (no base folder): the built-in one it names, or the
    // default.
    let name = script
        .scene
        .as_ref()
        .and_then(|s| match &s.drone {
            Some(dronecine_grammar::script::DroneRef::Builtin { name }) => Some(name.as_str()),
            _ => None,
        })
        .unwrap_or("ardrone2");
    let profile = Profile::builtin(name).unwrap_or_else(|| Profile::builtin("ardrone2").unwrap());
    let compiled = compile(&script, &profile, &Options { rate_hz: 20.0 }, |s, _| {
        let all = s
            .position_m
            .iter()
            .chain(&s.velocity_mps)
            .chain(&s.acceleration_mps2);
        assert!(all.copied().all(f64::is_finite), "{s:?}");
        assert!(
            s.heading_rad.is_finite() && s.camera_pitch_rad.is_finite(),
            "{s:?}"
        );
        Ok::<(), ()>(())
    })
    .unwrap();
    let Some(scene) = script.scene.as_ref() else {
        assert!(compiled.has_errors());
        return;
    };
    if unflyable(&script).is_some() {
        assert!(compiled.has_errors());
    }
    let mut sim = SimConfig::new(1);
    sim.effects.battery = false;
    let flight = SimFlight {
        script: &script,
        source: &src,
        scene,
        profile: &profile,
        rate_hz: 50.0,
        controller: ControllerSetup::new("lqg"),
        plant: None,
        sim,
        realtime: false,
        interrupts: None,
    };
    if fly_simulated(&flight, &mut NullSink, &mut NoObserver).is_ok() {
        assert!(unflyable(&script).is_none(), "an unflyable script flew");
    }
});
