//! Every message the backend sends, encoded here and decoded by pymavlink, field by field;
//! every message it reads, encoded by pymavlink and decoded here; over UDP on loopback.

mod common;

use std::time::Duration;

use common::{close, num, Peer};
use dronecine_backend::frames::Command;
use dronecine_mavlink::frames::{euler_from_quaternion, AttitudeTarget};
use dronecine_mavlink::link::Link;
use dronecine_mavlink::messages::{self, Target};
use dronecine_mavlink::state::{LandedState, VehicleEvent};
use dronecine_mavlink::MavlinkUrl;
use mavlink::dialects::ardupilotmega::MavMessage;
use serde_json::{json, Value};

const WAIT: Duration = Duration::from_secs(10);
const VEHICLE: Target = Target {
    system: 1,
    component: 1,
};

/// One message the backend sends, and the fields pymavlink must decode from it.
struct Expected {
    msg: MavMessage,
    kind: &'static str,
    fields: Value,
}

fn expected() -> Vec<Expected> {
    let command = Command {
        roll_rad: 0.1,
        pitch_rad: -0.2,
        yaw_rate_radps: 0.3,
        vz_mps: 0.5,
    };
    let target = AttitudeTarget::from_command(&command, 1.1, 2.5, 1.5);
    let q: Vec<f64> = target.q.iter().map(|&v| f64::from(v)).collect();
    vec![
        Expected {
            msg: messages::attitude_target(VEHICLE, 1234, &target),
            kind: "SET_ATTITUDE_TARGET",
            fields: json!({"time_boot_ms": 1234, "target_system": 1, "target_component": 1,
                "type_mask": 0, "q": q, "body_roll_rate": 0.0, "body_pitch_rate": 0.0,
                "body_yaw_rate": 0.3, "thrust": 0.6}),
        },
        Expected {
            msg: messages::vision_position(5_000_123, [1.5, -0.25, -1.2], [0.01, -0.02, 2.0], 3),
            kind: "VISION_POSITION_ESTIMATE",
            fields: json!({"usec": 5_000_123u64, "x": 1.5, "y": -0.25, "z": -1.2, "roll": 0.01,
                "pitch": -0.02, "yaw": 2.0, "reset_counter": 3}),
        },
        Expected {
            msg: messages::gps_origin(1, -35.3632621, 149.1652374, 584.09),
            kind: "SET_GPS_GLOBAL_ORIGIN",
            fields: json!({"target_system": 1, "latitude": -353632621, "longitude": 1491652374,
                "altitude": 584090}),
        },
        command_long(messages::set_mode(VEHICLE, 20), 176, [1.0, 20.0, 0.0]),
        command_long(messages::arm(VEHICLE, true), 400, [1.0, 0.0, 0.0]),
        command_long(messages::force_disarm(VEHICLE), 400, [0.0, 21196.0, 0.0]),
        command_long(messages::set_mode(VEHICLE, 9), 176, [1.0, 9.0, 0.0]),
        command_long(
            messages::message_interval(VEHICLE, 32, 50_000.0),
            511,
            [32.0, 50_000.0, 0.0],
        ),
        Expected {
            msg: messages::param_request(VEHICLE, "WPNAV_SPEED_UP"),
            kind: "PARAM_REQUEST_READ",
            fields: json!({"target_system": 1, "target_component": 1,
                "param_id": "WPNAV_SPEED_UP", "param_index": -1}),
        },
        Expected {
            msg: messages::gimbal_pitch(VEHICLE, -0.4),
            kind: "GIMBAL_MANAGER_SET_PITCHYAW",
            fields: json!({"target_system": 1, "target_component": 1, "flags": 12,
                "gimbal_device_id": 0, "pitch": -0.4, "yaw": 0.0, "pitch_rate": "NaN",
                "yaw_rate": "NaN"}),
        },
    ]
}

fn command_long(msg: MavMessage, command: u32, params: [f64; 3]) -> Expected {
    Expected {
        msg,
        kind: "COMMAND_LONG",
        fields: json!({"target_system": 1, "target_component": 1, "command": command,
            "confirmation": 0, "param1": params[0], "param2": params[1], "param3": params[2],
            "param4": 0.0, "param5": 0.0, "param6": 0.0, "param7": 0.0}),
    }
}

/// Each field of `want` is in `got` with the same value (numbers to f32 precision).
fn assert_fields(kind: &str, got: &Value, want: &Value) {
    for (name, w) in want.as_object().expect("an object") {
        let g = &got[name];
        let same = match (w, g) {
            (Value::Array(ws), Value::Array(gs)) => {
                ws.len() == gs.len() && ws.iter().zip(gs).all(|(a, b)| close(num(a), num(b)))
            }
            (Value::String(s), _) if s != "NaN" => g == w,
            _ => close(num(w), num(g)),
        };
        assert!(
            same,
            "{kind}.{name}: pymavlink decoded {g}, the backend sent {w}"
        );
    }
}

#[test]
fn pymavlink_decodes_what_the_backend_sends_and_the_backend_decodes_pymavlink() {
    let Some(python) = common::python("pymavlink cross-check") else {
        return;
    };
    let mut peer = common::peer(&python, "pymavlink_peer.py", &[]);
    let url = MavlinkUrl::parse(&format!("mavlink://udp:127.0.0.1:{}", peer.port())).unwrap();
    let link = Link::open(&url).unwrap();
    let expected = expected();
    for e in &expected {
        link.send(&e.msg).unwrap();
    }
    backend_to_pymavlink(&mut peer, &expected);
    pymavlink_to_backend(&mut peer, &link);
}

fn backend_to_pymavlink(peer: &mut Peer, expected: &[Expected]) {
    // Our heartbeat, from the link's own thread.
    let hb = peer.until(WAIT, |v| v["received"] == "HEARTBEAT");
    assert_eq!(hb["src"], json!([255, 190]));
    assert_fields(
        "HEARTBEAT",
        &hb["fields"],
        &json!({"type": 6, "autopilot": 8, "base_mode": 0, "custom_mode": 0,
            "system_status": 4, "mavlink_version": 3}),
    );
    let mut got: Vec<Value> = Vec::new();
    for (i, e) in expected.iter().enumerate() {
        // The n-th message of a kind is the n-th sent (UDP on loopback keeps the order).
        let n = expected[..i].iter().filter(|x| x.kind == e.kind).count();
        let kind = e.kind;
        let mut seen = 0;
        let v = peer.until(WAIT, |v| {
            v["received"] == kind && {
                seen += 1;
                seen > n
            }
        });
        assert_eq!(v["src"], json!([255, 190]), "{kind}");
        assert_fields(kind, &v["fields"], &e.fields);
        got.push(v);
    }
    // Nothing pymavlink could not decode.
    peer.drain();
    let bad: Vec<&Value> = (peer.seen.iter())
        .filter(|v| v["received"] == "BAD_DATA")
        .collect();
    assert!(bad.is_empty(), "pymavlink could not decode: {bad:?}");
}

fn pymavlink_to_backend(peer: &mut Peer, link: &Link) {
    peer.tell("vehicle");
    peer.until(WAIT, |v| v["done"] == "vehicle");
    let sent = |kind: &str| -> Value {
        (peer.seen.iter())
            .find(|v| v["sent"] == kind)
            .unwrap_or_else(|| panic!("the peer sent no {kind}"))["fields"]
            .clone()
    };
    let (att, pos, ekf, sim) = (
        sent("ATTITUDE"),
        sent("LOCAL_POSITION_NED"),
        sent("EKF_STATUS_REPORT"),
        sent("SIM_STATE"),
    );
    let all_in = link
        .wait_for(
            WAIT,
            || Ok(()),
            |s| s.sim.is_some() && s.gimbal_pitch_rad.is_some(),
        )
        .unwrap();
    assert!(all_in, "the backend did not read the peer's messages");
    let s = link.state();
    assert_eq!(
        s.vehicle,
        Some(Target {
            system: 1,
            component: 1
        })
    );
    let hb = s.heartbeat.expect("a heartbeat");
    assert_eq!(
        (
            hb.custom_mode,
            hb.armed,
            hb.system_status,
            hb.vehicle_type,
            hb.autopilot
        ),
        (20, true, 4, 2, 3)
    );
    assert_eq!(s.battery_percent, Some(77.0));
    let [r, p, y] = s.attitude_rad.expect("an attitude");
    assert!(
        close(r, num(&att["roll"])) && close(p, num(&att["pitch"])) && close(y, num(&att["yaw"]))
    );
    assert_eq!(s.landed, Some(LandedState::InAir));
    assert!(s.external_nav_said);
    assert!(s.events.iter().any(|(_, e)| *e
        == VehicleEvent::Text {
            severity: 6,
            text: "EKF3 IMU0 is using external nav data".into()
        }));
    assert_eq!(s.params.get("WPNAV_SPEED_UP"), Some(&250.0));
    assert_eq!(
        s.acks.first().map(|a| (a.command, a.result)),
        Some((176, 0))
    );
    assert_eq!(s.ekf_flags.map(f64::from), Some(num(&ekf["flags"])));
    let lp = s.local_position.expect("a local position");
    for (i, k) in ["x", "y", "z"].iter().enumerate() {
        assert!(close(lp.ned_m[i], num(&pos[k])), "{k}");
    }
    for (i, k) in ["vx", "vy", "vz"].iter().enumerate() {
        assert!(close(lp.velocity_ned_mps[i], num(&pos[k])), "{k}");
    }
    // The gimbal's quaternion was made by the peer from pitch −0.5 rad.
    let pitch = s.gimbal_pitch_rad.expect("a gimbal pitch");
    assert!((pitch + 0.5).abs() < 1e-6, "{pitch}");
    let sim_state = s.sim.expect("a SIM_STATE");
    assert!(close(sim_state.lat_deg, num(&sim["lat_int"]) * 1e-7));
    assert!(close(sim_state.lon_deg, num(&sim["lon_int"]) * 1e-7));
    assert!(close(sim_state.alt_m, num(&sim["alt"])));
    let [sr, sp, sy] = euler_from_quaternion(sim_state.q);
    assert!((sr - 0.05).abs() < 1e-6 && (sp + 0.1).abs() < 1e-6 && (sy - 1.2).abs() < 1e-6);
    for (i, k) in ["vn", "ve", "vd"].iter().enumerate() {
        assert!(close(sim_state.velocity_ned_mps[i], num(&sim[k])), "{k}");
    }
    drop(s);
    peer.tell("battery");
    peer.until(WAIT, |v| v["done"] == "battery");
    let battery = link
        .wait_for(WAIT, || Ok(()), |s| s.battery_percent == Some(55.0))
        .unwrap();
    assert!(battery, "BATTERY_STATUS's 55% not read");
    assert_eq!(link.state().ignored, 0);
}
