//! A whole flight on the Crazyflie backend, over CRTP on UDP and NatNet, against the
//! Crazyflie emulator in this process: the flight completes and keeps to its path, the drone
//! received its set-points at the loop's rate while flying (at least the 50 Hz a Crazyflie
//! wants), its estimator was the Kalman one fed the motion capture, and its motors were
//! stopped at the landing. Real time: about 25 s.

use std::net::UdpSocket;

use dronecine_emulator::crazyflie_emulator::crazyflie_sim;
use dronecine_emulator::{CrazyflieEmulator, CrazyflieEmulatorConfig, NatNetConfig, NatNetData};
use dronecine_flight::NoObserver;
use dronecine_mcap::record::NullSink;
use dronecine_profile::Profile;
use dronecine_runtime::{fly_hardware, DroneUrl, HardwareFlight, HardwareTarget, MocapUrl};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone crazyflie21\n\
                      actor A height 1.80m at (0, 0) facing 0deg\n\
                      MS on A 34left for 4s\n";

#[test]
fn a_flight_through_the_crazyflie_emulator_commands_at_the_loops_rate() {
    let script = crate::common::parse(SCRIPT);
    let scene = script.scene.clone().expect("a scene");
    let profile = Profile::builtin("crazyflie21").unwrap();
    let data = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap();
    let mut sim = crazyflie_sim(SimConfig::new(5));
    (sim.start_position_m, sim.start_heading_rad) =
        dronecine_runtime::start_pose(&script, &scene, &profile, &sim);
    let config = CrazyflieEmulatorConfig {
        port: 0,
        natnet: Some(NatNetConfig {
            command_port: 0,
            data: NatNetData::Unicast(data),
            ..NatNetConfig::default()
        }),
        sim,
        ..CrazyflieEmulatorConfig::new(profile.clone(), scene.clone(), 5)
    };
    let emulator = CrazyflieEmulator::start(config).expect("the emulator starts");
    let target = HardwareTarget {
        drone: DroneUrl::parse(&format!("crazyflie+udp://{}", emulator.addr())).unwrap(),
        mocap: MocapUrl::parse(&format!(
            "natnet://127.0.0.1:{}?unicast&data_port={}",
            emulator.natnet_command_addr().unwrap().port(),
            data.port()
        ))
        .unwrap(),
        rig: dronecine_natnet::rig::Rig::numbered(&["A"]),
        forward_mocap: true,
    };
    let flight = HardwareFlight {
        script: &script,
        source: SCRIPT,
        scene: &scene,
        profile: &profile,
        rate_hz: 100.0,
        controller: ControllerSetup::new("lqg"),
        target: &target,
        interrupts: None,
    };
    let report = fly_hardware(&flight, &mut NullSink, &mut NoObserver).expect("it flies");
    assert!(report.completed, "{report:?}");
    let rms_m = report.figures.rms_position_error_m.unwrap();
    let status = emulator.status();
    let rate_hz = status.setpoint_rate_hz().expect("it flew");
    eprintln!(
        "through the Crazyflie emulator: {rms_m:.4} m RMS; {rate_hz:.1} set-points a second \
         over {:.1} s of flying; {} external poses",
        status.flying_s, status.firmware.ext_poses
    );
    // Within the stage's margin of its path: a sign or a unit wrong on the wire drives the
    // drone away by metres (the figure itself is the end-to-end test's, against the
    // simulator's).
    assert!(rms_m < 0.2, "{rms_m} m RMS");
    assert!(rate_hz >= 50.0, "{rate_hz} Hz");
    assert_eq!(status.estimator, 2, "the Kalman estimator");
    assert!(status.firmware.ext_poses as f64 > 50.0 * status.flying_s);
    assert_eq!(status.firmware.rejected, 0);
    // The stop is the flight's last packet: the emulator's loop reads it within a step or
    // two of the flight's return, and the last centimetres after it leave the drone on the
    // floor within a second.
    within_a_second("the motors stop at the landing", || {
        emulator.status().firmware.stops >= 1
    });
    within_a_second("on the floor after the stop", || {
        emulator.status().truth.state == dronecine_backend::FlightState::Landed
    });
}

/// Panics with `what` unless `done` holds within a second.
fn within_a_second(what: &str, done: impl FnMut() -> bool) {
    let one_s = std::time::Duration::from_secs(1);
    let poll = std::time::Duration::from_millis(10);
    let held = dronecine_backend::clock::wait_until(one_s, poll, || Ok::<(), ()>(()), done);
    assert_eq!(held, Ok(true), "{what}: not within 1 s");
}
