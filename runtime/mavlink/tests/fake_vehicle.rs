//! The backend against a fake ArduCopter written on pymavlink (`fake_vehicle.py`), over UDP
//! loopback: the pre-flight parameter check, the motion capture and the origin, take-off,
//! a known command, hover, the gimbal, the autopilot's own failsafe, landing and the
//! emergency, judged on what the vehicle received.

mod common;

use std::time::{Duration, Instant};

use common::{close, num, Peer};
use dronecine_backend::frames::Command;
use dronecine_backend::{BackendError, BodyPose, Drone, FlightState};
use dronecine_mavlink::frames::quaternion_from_euler;
use dronecine_mavlink::messages::copter_mode;
use dronecine_mavlink::{MavlinkDrone, MavlinkOptions, MavlinkUrl};
use serde_json::Value;

const WAIT: Duration = Duration::from_secs(10);
/// The fake vehicle's yaw (ATTITUDE), which the take-off holds.
const VEHICLE_YAW_RAD: f64 = 0.3;

fn connect(peer: &mut Peer) -> MavlinkDrone {
    let url = MavlinkUrl::parse(&format!("mavlink://udp:127.0.0.1:{}", peer.port())).unwrap();
    let options = MavlinkOptions {
        hover_height_m: 0.5,
        ..MavlinkOptions::default()
    };
    MavlinkDrone::connect(&url, options).unwrap()
}

/// Calls `telemetry` until it reports `want`.
fn until_state(drone: &mut MavlinkDrone, want: FlightState) {
    let deadline = Instant::now() + WAIT;
    loop {
        let state = drone.telemetry().state;
        if state == want {
            return;
        }
        assert!(Instant::now() < deadline, "still {state:?}, not {want:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The COMMAND_LONGs the vehicle received: (command, param1, param2).
fn commands(peer: &mut Peer) -> Vec<(u64, f64, f64)> {
    peer.drain();
    (peer.seen.iter())
        .filter(|v| v["rx"] == "COMMAND_LONG")
        .map(|v| {
            let f = &v["fields"];
            (
                f["command"].as_u64().unwrap(),
                num(&f["param1"]),
                num(&f["param2"]),
            )
        })
        .collect()
}

/// The fields of the SET_ATTITUDE_TARGETs the vehicle received.
fn targets(peer: &mut Peer) -> Vec<Value> {
    peer.drain();
    (peer.seen.iter())
        .filter(|v| v["rx"] == "SET_ATTITUDE_TARGET")
        .map(|v| v["fields"].clone())
        .collect()
}

/// A set-point with this attitude and thrust, all body rates used, arrived.
fn has_target(peer: &mut Peer, roll: f64, pitch: f64, yaw: f64, rate: f64, thrust: f64) -> bool {
    let q = quaternion_from_euler(roll, pitch, yaw);
    targets(peer).iter().any(|f| {
        let got: Vec<f64> = f["q"].as_array().unwrap().iter().map(num).collect();
        got.iter().zip(q).all(|(g, w)| close(*g, w))
            && close(num(&f["thrust"]), thrust)
            && close(num(&f["body_yaw_rate"]), rate)
            && num(&f["type_mask"]) == 0.0
    })
}

#[test]
fn wrong_parameters_refuse_the_take_off_naming_each() {
    let Some(python) = common::python("fake vehicle: wrong parameters") else {
        return;
    };
    let mut peer = common::peer(&python, "fake_vehicle.py", &["wrong"]);
    let mut drone = connect(&mut peer);
    let check = drone.check_parameters().unwrap();
    let wrong: Vec<String> = check.wrong.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        wrong,
        [
            "VISO_TYPE is 0, needs 1",
            "GPS_TYPE is 1, needs 0",
            "EK3_SRC1_POSZ is 1, needs 6",
            "GUID_OPTIONS is 8, needs bit 3 (value 8) clear",
        ]
    );
    let Err(BackendError::Refused(why)) = drone.take_off() else {
        panic!("the take-off was not refused");
    };
    for w in &wrong {
        assert!(why.contains(w.as_str()), "{why}");
    }
    // Nothing was asked of the vehicle: no mode, no arming.
    assert!(
        commands(&mut peer).iter().all(|c| c.0 == 511),
        "{:?}",
        commands(&mut peer)
    );
    assert_eq!(drone.telemetry().state, FlightState::Landed);
}

#[test]
fn the_backend_flies_the_fake_vehicle() {
    let Some(python) = common::python("fake vehicle: flight") else {
        return;
    };
    let mut peer = common::peer(&python, "fake_vehicle.py", &["right"]);
    let mut drone = connect(&mut peer);
    peer.until(WAIT, |v| v["rx"] == "HEARTBEAT" && v["fields"]["type"] == 6);
    preflight(&mut drone, &mut peer);
    take_off(&mut drone, &mut peer);
    fly(&mut drone, &mut peer);
    autopilot_failsafe(&mut drone, &mut peer);
    take_off(&mut drone, &mut peer);
    land(&mut drone, &mut peer);
    take_off(&mut drone, &mut peer);
    emergency(&mut drone, &mut peer);
}

fn preflight(drone: &mut MavlinkDrone, peer: &mut Peer) {
    assert!(drone.check_parameters().unwrap().passed());
    let limits = drone.limits().unwrap();
    assert_eq!((limits.climb_max_mps, limits.descent_max_mps), (2.5, 1.5));
    assert!((limits.tilt_max_rad - 30f64.to_radians()).abs() < 1e-9);
    assert_eq!(
        (limits.yaw_rate_max_radps, limits.guided_timeout_s),
        (None, 3.0)
    );
    drone.set_origin().unwrap();
    let start = Instant::now();
    let pose = BodyPose {
        position_m: [0.5, -1.0, 0.0],
        heading_rad: 1.0,
    };
    drone
        .wait_for_external_nav(WAIT, |d| {
            d.forward_pose(start.elapsed().as_secs_f64(), &pose)
                .map(|_| ())
        })
        .unwrap();
    let v = peer.until(WAIT, |v| v["rx"] == "VISION_POSITION_ESTIMATE");
    let f = &v["fields"];
    // The stage's (0.5, −1, 0) facing 1 rad is NED (−1, 0.5, 0) with yaw π/2 − 1.
    assert!(close(num(&f["x"]), -1.0) && close(num(&f["y"]), 0.5) && close(num(&f["z"]), 0.0));
    assert!(close(num(&f["yaw"]), std::f64::consts::FRAC_PI_2 - 1.0));
    let o = peer.until(WAIT, |v| v["rx"] == "SET_GPS_GLOBAL_ORIGIN");
    assert_eq!(o["fields"]["target_system"], 1);
    // The origin sent before the first estimate was dropped (as ArduPilot's EKF drops it):
    // the wait sends it again until the vehicle confirms it.
    assert!(drone.vehicle_state().origin.is_none());
    drone
        .wait_for_origin(WAIT, |d| {
            d.forward_pose(start.elapsed().as_secs_f64(), &pose)
                .map(|_| ())
        })
        .unwrap();
    let [lat, lon, _] = drone.vehicle_state().origin.unwrap();
    let want = dronecine_mavlink::MavlinkOptions::default().origin;
    assert!((lat - want.lat_deg).abs() < 1e-6 && (lon - want.lon_deg).abs() < 1e-6);
    // At most one estimate per 19.5 ms of the flight clock.
    assert!(
        !drone.forward_pose(10.0, &pose).unwrap() || !drone.forward_pose(10.01, &pose).unwrap()
    );
}

fn take_off(drone: &mut MavlinkDrone, peer: &mut Peer) {
    let before = commands(peer).len();
    drone.take_off().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::TakingOff);
    until_state(drone, FlightState::Flying);
    let asked = &commands(peer)[before..];
    let mode = asked
        .iter()
        .position(|c| c.0 == 176 && c.1 == 1.0 && c.2 == 20.0);
    let arm = asked.iter().position(|c| c.0 == 400 && c.1 == 1.0);
    assert!(
        matches!((mode, arm), (Some(m), Some(a)) if m < a),
        "GUIDED_NOGPS, then arming: {asked:?}"
    );
    // The climb: level, the vehicle's yaw held, thrust 0.5 + 0.5 / (2 · 2.5).
    assert!(has_target(peer, 0.0, 0.0, VEHICLE_YAW_RAD, 0.0, 0.6));
}

fn fly(drone: &mut MavlinkDrone, peer: &mut Peer) {
    let command = Command {
        roll_rad: 0.1,
        pitch_rad: -0.2,
        yaw_rate_radps: 0.0,
        vz_mps: -0.3,
    };
    drone.send(&command).unwrap();
    // Thrust 0.5 − 0.3 / (2 · 1.5) = 0.4.
    std::thread::sleep(Duration::from_millis(100));
    assert!(has_target(peer, 0.1, -0.2, VEHICLE_YAW_RAD, 0.0, 0.4));
    let turning = Command {
        yaw_rate_radps: 0.2,
        ..Command::HOVER
    };
    let yaw_of = |target: &serde_json::Value| {
        let q: Vec<f64> = target["q"].as_array().unwrap().iter().map(num).collect();
        dronecine_mavlink::frames::euler_from_quaternion([q[0], q[1], q[2], q[3]])[2]
    };
    drone.send(&turning).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    // The turn: the yaw target leads the vehicle's yaw by the rate over ATC_ANG_YAW_P (the
    // fake vehicle has none: ArduCopter's default, 4.5).
    let turn = targets(peer).pop().unwrap();
    assert!(close(num(&turn["body_yaw_rate"]), 0.2), "{turn}");
    let lead = yaw_of(&turn) - VEHICLE_YAW_RAD;
    assert!((lead - 0.2 / 4.5).abs() < 1e-4, "{lead}");
    drone.hover().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    let last = targets(peer).pop().unwrap();
    // The hover: level, thrust 0.5, no rate, the vehicle's yaw held.
    assert!(close(num(&last["thrust"]), 0.5) && num(&last["body_yaw_rate"]) == 0.0);
    assert!(
        (yaw_of(&last) - VEHICLE_YAW_RAD).abs() < 1e-4,
        "{}",
        yaw_of(&last)
    );
    drone.point_camera(-0.3).unwrap();
    let g = peer.until(WAIT, |v| v["rx"] == "GIMBAL_MANAGER_SET_PITCHYAW");
    assert!(close(num(&g["fields"]["pitch"]), -0.3));
    let deadline = Instant::now() + WAIT;
    while drone
        .camera_pitch_rad()
        .is_none_or(|p| (p + 0.3).abs() > 1e-5)
    {
        assert!(Instant::now() < deadline, "{:?}", drone.camera_pitch_rad());
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn autopilot_failsafe(drone: &mut MavlinkDrone, peer: &mut Peer) {
    peer.tell("failsafe");
    until_state(drone, FlightState::Landing);
    assert_eq!(drone.unrequested_mode(), Some(copter_mode::LAND));
    // No more set-points, and no mode of ours, while the autopilot lands.
    std::thread::sleep(Duration::from_millis(100));
    let (sent, asked) = (targets(peer).len(), commands(peer).len());
    drone.send(&Command::HOVER).unwrap();
    drone.land().unwrap();
    until_state(drone, FlightState::Landed);
    assert_eq!((targets(peer).len(), commands(peer).len()), (sent, asked));
    let mut events = Vec::new();
    drone.drain_events(&mut events);
    assert!(
        events.iter().any(|(_, e)| matches!(e,
        dronecine_mavlink::VehicleEvent::Text { severity: 2, text } if text == "Battery failsafe"))
    );
}

fn land(drone: &mut MavlinkDrone, peer: &mut Peer) {
    let before = commands(peer).len();
    drone.land().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::Landing);
    until_state(drone, FlightState::Landed);
    assert!(commands(peer)[before..].contains(&(176, 1.0, 9.0)));
}

fn emergency(drone: &mut MavlinkDrone, peer: &mut Peer) {
    drone.emergency().unwrap();
    assert_eq!(drone.telemetry().state, FlightState::Emergency);
    let deadline = Instant::now() + WAIT;
    while !commands(peer).contains(&(400, 0.0, 21196.0)) {
        assert!(Instant::now() < deadline, "no forced disarm");
        std::thread::sleep(Duration::from_millis(10));
    }
    let disarmed = drone
        .link()
        .wait_for(WAIT, || Ok(()), |s| s.heartbeat.is_some_and(|h| !h.armed))
        .unwrap();
    assert!(disarmed);
    assert_eq!(drone.telemetry().state, FlightState::Emergency);
}
