//! The backend against a fake Crazyflie on cflib's UDP link (`fake_crazyflie.py`), over UDP
//! loopback: the set-up (TOC, log blocks, the Kalman estimator), the motion capture into its
//! estimator, take-off and landing by climb rate, commands in the firmware's units and signs
//! for either yaw convention, the hold, the motor stop on landing and on an emergency, the
//! refusals, the console — judged on what the fake received.

mod common;

use std::time::{Duration, Instant};

use common::Peer;
use dronecine_backend::frames::Command;
use dronecine_backend::{BackendError, BodyPose, Drone, FlightState};
use dronecine_crazyflie::{CrazyflieDrone, CrazyflieOptions, CrazyflieUrl, PoseForwarder};
use dronecine_profile::Profile;
use dronecine_pypeer::num;
use serde_json::Value;

const WAIT: Duration = Duration::from_secs(10);

fn profile() -> Profile {
    Profile::builtin("crazyflie21").expect("the built-in crazyflie21")
}

/// The values of the packets of `kind` the fake received.
fn received(peer: &mut Peer, kind: &str) -> Vec<Vec<Value>> {
    peer.drain();
    (peer.seen.iter())
        .filter(|v| v["kind"] == kind)
        .map(|v| v["values"].as_array().cloned().unwrap_or_default())
        .collect()
}

fn floats(v: &[Value]) -> Vec<f64> {
    v.iter().map(num).collect()
}

/// Calls `telemetry` (forwarding `pose` every 10 ms) until it reports `want`.
fn until_state(
    drone: &mut CrazyflieDrone,
    fwd: &mut PoseForwarder,
    pose: &BodyPose,
    want: FlightState,
) {
    let start = Instant::now();
    loop {
        let t = start.elapsed().as_secs_f64();
        fwd.forward(1000.0 + t, pose).unwrap();
        let state = drone.telemetry().state;
        if state == want {
            return;
        }
        assert!(start.elapsed() < WAIT, "still {state:?}, not {want:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn the_backend_flies_the_fake_crazyflie() {
    let Some(python) = common::python("fake Crazyflie: flight") else {
        return;
    };
    let (mut peer, mut drone) = common::fake(&python, 12, &[], &profile());
    assert_eq!(drone.protocol_version(), 12);
    // The Kalman estimator was asked for, and both blocks created and started.
    let params = received(&mut peer, "param");
    assert!(params
        .iter()
        .any(|p| p[0] == "stabilizer.estimator" && p[1] == 2 && p[2] == 0));
    let log = received(&mut peer, "log");
    for (cmd, block) in [(6, 1), (6, 2), (3, 1), (3, 2)] {
        assert!(
            log.iter()
                .any(|l| l[0] == cmd && l[1] == block && l[2] == 0),
            "{log:?}"
        );
    }
    let pose = BodyPose {
        position_m: [0.5, -1.0, 0.02],
        heading_rad: 1.0,
    };
    let mut fwd = drone.forwarder();
    estimate_follows_the_motion_capture(&mut drone, &mut fwd, &mut peer, &pose);
    let t = drone.telemetry();
    assert_eq!((t.state, t.battery_percent), (FlightState::Landed, 80.0));
    assert!(t.link_age_s < 0.5, "{}", t.link_age_s);
    take_off(&mut drone, &mut fwd, &mut peer, &pose);
    fly(&mut drone, &mut peer);
    land(&mut drone, &mut fwd, &mut peer, &pose);
    emergency(&mut drone, &mut fwd, &mut peer, &pose);
    peer.tell("console SYS: Crazyflie 2.1 is up");
    let deadline = Instant::now() + WAIT;
    let mut messages = Vec::new();
    while !messages
        .iter()
        .any(|m: &dronecine_backend::DroneMessage| m.text == "crazyflie: SYS: Crazyflie 2.1 is up")
    {
        assert!(Instant::now() < deadline, "{messages:?}");
        drone.messages(&mut messages);
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn estimate_follows_the_motion_capture(
    drone: &mut CrazyflieDrone,
    fwd: &mut PoseForwarder,
    peer: &mut Peer,
    pose: &BodyPose,
) {
    let start = Instant::now();
    drone
        .wait_for_estimate(0.05, WAIT, |_| {
            fwd.forward(start.elapsed().as_secs_f64(), pose)?;
            Ok(Some(pose.position_m))
        })
        .unwrap();
    let p = received(peer, "ext_pose").pop().expect("an external pose");
    let p = floats(&p);
    // The position, and the heading as a quaternion about z (roll and pitch the drone's: 0).
    let want = [0.5, -1.0, 0.02, 0.0, 0.0, 0.5f64.sin(), 0.5f64.cos()];
    for (g, w) in p.iter().zip(want) {
        assert!((g - w).abs() < 1e-6, "{p:?}");
    }
    // At most one per 9.5 ms of the flight's clock.
    assert!(!fwd.forward(2000.0, pose).unwrap() || !fwd.forward(2000.005, pose).unwrap());
    drone.reset_estimator().unwrap();
    let resets: Vec<Value> = (received(peer, "param").into_iter())
        .filter(|p| p[0] == "kalman.resetEstimation")
        .map(|p| p[1].clone())
        .collect();
    assert_eq!(resets, [1, 0]);
}

fn take_off(drone: &mut CrazyflieDrone, fwd: &mut PoseForwarder, peer: &mut Peer, pose: &BodyPose) {
    drone.take_off().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::TakingOff);
    until_state(drone, fwd, pose, FlightState::Flying);
    // Level set-points climbing at 0.3 m/s, to 0.5 m above the floor it stood on.
    let climbs = received(peer, "alt_hold");
    assert!(
        climbs
            .iter()
            .any(|v| floats(v) == [0.0, 0.0, 0.0, 0.3f32 as f64]),
        "{climbs:?}"
    );
    let z = drone.estimate_m().unwrap()[2];
    assert!(z >= 0.02 + 0.5 - 0.05, "{z}");
    // An auto-arming Crazyflie is not asked to arm.
    assert!(received(peer, "arm").is_empty());
}

fn fly(drone: &mut CrazyflieDrone, peer: &mut Peer) {
    let command = Command {
        roll_rad: 0.1,
        pitch_rad: -0.15,
        yaw_rate_radps: 0.3,
        vz_mps: -0.1,
    };
    drone.send(&command).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let sent = floats(&received(peer, "alt_hold").pop().unwrap());
    // Degrees; the yaw rate counter-clockwise positive on protocol 12 (the command's is
    // clockwise positive): negated.
    let want = [
        0.1f64.to_degrees(),
        -0.15f64.to_degrees(),
        -0.3f64.to_degrees(),
        -0.1,
    ];
    for (g, w) in sent.iter().zip(want) {
        assert!((g - w).abs() < 1e-4, "{sent:?}");
    }
    // Beyond the profile's limits: clamped.
    let limits = profile().limits;
    drone
        .send(&Command {
            roll_rad: 1.0,
            pitch_rad: -1.0,
            yaw_rate_radps: 10.0,
            vz_mps: 5.0,
        })
        .unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let sent = floats(&received(peer, "alt_hold").pop().unwrap());
    let tilt = limits.tilt_max_rad.to_degrees();
    let want = [
        tilt,
        -tilt,
        -limits.yaw_rate_max_radps.to_degrees(),
        limits.vz_max_mps,
    ];
    for (g, w) in sent.iter().zip(want) {
        assert!((g - w).abs() < 1e-3, "{sent:?}");
    }
    // The hold: a position set-point where the estimate was, kept alive by telemetry
    // reads alone.
    let estimate = drone.estimate_m().unwrap();
    drone.hover().unwrap();
    let before = received(peer, "position").len();
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(200) {
        drone.telemetry();
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(30));
    let holds = received(peer, "position");
    // Every 20 ms at least: 200 ms of reads send 9 or more.
    assert!(holds.len() - before >= 9, "{} holds", holds.len() - before);
    let h = floats(holds.last().unwrap());
    for i in 0..3 {
        assert!((h[i] - estimate[i]).abs() < 0.05, "{h:?} {estimate:?}");
    }
    assert!(
        (h[3] - 1f64.to_degrees()).abs() < 0.1,
        "the yaw held: {h:?}"
    );
}

fn land(drone: &mut CrazyflieDrone, fwd: &mut PoseForwarder, peer: &mut Peer, pose: &BodyPose) {
    drone.land().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::Landing);
    until_state(drone, fwd, pose, FlightState::Landed);
    std::thread::sleep(Duration::from_millis(50));
    peer.drain();
    let last_descent = (peer.seen.iter())
        .rposition(|v| v["kind"] == "alt_hold")
        .unwrap();
    let descent = floats(peer.seen[last_descent]["values"].as_array().unwrap());
    assert_eq!(descent, [0.0, 0.0, 0.0, -0.25f32 as f64]);
    // Then the motors stop.
    assert!(
        (peer.seen[last_descent..].iter()).any(|v| v["kind"] == "stop"),
        "no stop after the landing"
    );
    assert!(drone.estimate_m().unwrap()[2] <= 0.02 + 0.05 + 0.01);
}

fn emergency(
    drone: &mut CrazyflieDrone,
    fwd: &mut PoseForwarder,
    peer: &mut Peer,
    pose: &BodyPose,
) {
    drone.take_off().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    drone.telemetry();
    let stops = received(peer, "stop").len();
    drone.emergency().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::Emergency);
    std::thread::sleep(Duration::from_millis(30));
    assert!(
        received(peer, "stop").len() > stops,
        "the stop goes out at once"
    );
    // And again while the emergency lasts.
    std::thread::sleep(Duration::from_millis(60));
    fwd.forward(3000.0, pose).unwrap();
    drone.telemetry();
    std::thread::sleep(Duration::from_millis(30));
    assert!(received(peer, "stop").len() >= stops + 2);
    drone.send(&Command::HOVER).unwrap();
    assert_eq!(drone.telemetry().state, FlightState::Emergency);
}

/// Protocol 8: the firmware negates the altHold yaw rate, and a Crazyflie that does not arm
/// itself is asked to, on the platform port.
#[test]
fn an_older_firmware_gets_its_own_yaw_sign_and_the_arming_request() {
    let Some(python) = common::python("fake Crazyflie: protocol 8") else {
        return;
    };
    let (mut peer, mut drone) = common::fake(&python, 8, &["no-auto-arm"], &profile());
    let pose = BodyPose {
        position_m: [0.0, 0.0, 0.0],
        heading_rad: 0.0,
    };
    let mut fwd = drone.forwarder();
    let start = Instant::now();
    drone
        .wait_for_estimate(0.05, WAIT, |_| {
            fwd.forward(start.elapsed().as_secs_f64(), &pose)?;
            Ok(Some(pose.position_m))
        })
        .unwrap();
    drone.take_off().unwrap();
    let arm = peer.until(WAIT, |v| v["kind"] == "arm");
    assert_eq!(arm["values"], serde_json::json!([1]));
    assert_eq!(
        (arm["port"].as_u64(), arm["channel"].as_u64()),
        (Some(13), Some(0))
    );
    let turn = Command {
        yaw_rate_radps: 0.5,
        ..Command::HOVER
    };
    drone.send(&turn).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let sent = floats(&received(&mut peer, "alt_hold").pop().unwrap());
    assert!((sent[2] - 0.5f64.to_degrees()).abs() < 1e-4, "{sent:?}");
    assert_eq!(received(&mut peer, "arm").len(), 1, "armed once");
}

#[test]
fn a_locked_crazyflie_or_a_low_battery_refuses_the_take_off() {
    let Some(python) = common::python("fake Crazyflie: refusals") else {
        return;
    };
    let (mut peer, mut drone) = common::fake(&python, 12, &[], &profile());
    peer.tell("battery_low");
    let refusal = |drone: &mut CrazyflieDrone, needle: &str| {
        let deadline = Instant::now() + WAIT;
        loop {
            match drone.take_off() {
                Err(BackendError::Refused(why)) if why.contains(needle) => return,
                _ if Instant::now() > deadline => panic!("no refusal saying `{needle}`"),
                _ => {
                    drone.land().unwrap();
                    drone.emergency().unwrap();
                    std::thread::sleep(Duration::from_millis(20));
                }
            }
        }
    };
    refusal(&mut drone, "charge it");
    peer.tell("lock");
    refusal(&mut drone, "restart the Crazyflie");
    assert_eq!(drone.telemetry().state, FlightState::Emergency);
    let mut told = Vec::new();
    drone.messages(&mut told);
    assert!(
        told.iter()
            .any(|m| m.level == "error" && m.text.contains("LOCKED")),
        "{told:?}"
    );
}

/// Nothing answers: a clear error, not a wait without end nor a panic.
#[test]
fn a_silent_address_is_an_error_naming_it() {
    let port = common::free_port();
    let url = CrazyflieUrl::parse(&format!("crazyflie+udp://127.0.0.1:{port}")).unwrap();
    let options = CrazyflieOptions {
        connect_timeout: Duration::from_millis(300),
        ..CrazyflieOptions::default()
    };
    let Err(BackendError::Link(why)) = CrazyflieDrone::connect(&url, &profile(), options) else {
        panic!("connected to nothing");
    };
    assert!(
        why.contains("no answer from a Crazyflie at crazyflie+udp://127.0.0.1:")
            && why.contains("0.3 s"),
        "{why}"
    );
}

/// A radio address with no Crazyradio plugged in (as on CI) fails saying so.
#[cfg(feature = "radio")]
#[test]
fn a_radio_address_without_a_radio_is_an_error() {
    let url = CrazyflieUrl::parse("crazyflie+radio://0/80/2M/E7E7E7E7E7").unwrap();
    let options = CrazyflieOptions {
        connect_timeout: Duration::from_millis(500),
        ..CrazyflieOptions::default()
    };
    match CrazyflieDrone::connect(&url, &profile(), options) {
        Err(BackendError::Link(why)) => {
            assert!(
                why.starts_with("cannot open crazyflie+radio://0/80/2M/E7E7E7E7E7: "),
                "{why}"
            );
            assert!(why.contains("Crazyradio"), "{why}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => eprintln!("a Crazyflie answered on radio 0: nothing to refuse"),
    }
}
