//! Every CRTP packet the backend sends, byte for byte as cflib encodes the same command; every
//! packet the emulated Crazyflie sends, decoded by cflib as the emulator means it.
//!
//! The packets are the backend's own: two whole connections (protocols 12 and 8, neither
//! Crazyflie arming itself) against the fake Crazyflie on cflib's UDP link, captured as the
//! fake received them. Each is decoded here to the command it carries, and
//! `cflib_codec.py` encodes that command with cflib's own call: the bytes must be equal.

mod common;

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use common::Peer;
use dronecine_backend::frames::Command;
use dronecine_backend::{BodyPose, Drone, FlightState};
use dronecine_crazyflie::crtp::{log_cmd, log_type, FromDrone, Packet, ToDrone};
use dronecine_crazyflie::log::{Field, Layout, Values, POWER_BLOCK};
use dronecine_crazyflie::CrazyflieDrone;
use dronecine_profile::Profile;
use serde_json::{json, Value};

const WAIT: Duration = Duration::from_secs(10);

/// One whole connection: set-up, the motion capture, take-off, commands, the hold, landing,
/// take-off again and the emergency stop.
fn one_connection(drone: &mut CrazyflieDrone) {
    let pose = BodyPose {
        position_m: [0.25, 0.5, 0.0],
        heading_rad: -0.4,
    };
    let mut fwd = drone.forwarder();
    let start = Instant::now();
    let t = |start: Instant| start.elapsed().as_secs_f64();
    drone
        .wait_for_estimate(0.05, WAIT, |_| {
            fwd.forward(t(start), &pose)?;
            Ok(Some(pose.position_m))
        })
        .unwrap();
    drone.reset_estimator().unwrap();
    let mut until = |drone: &mut CrazyflieDrone, want: FlightState| {
        let deadline = Instant::now() + WAIT;
        while drone.telemetry().state != want {
            assert!(Instant::now() < deadline, "not {want:?}");
            fwd.forward(t(start), &pose).unwrap();
            std::thread::sleep(Duration::from_millis(10));
        }
    };
    drone.take_off().unwrap();
    until(drone, FlightState::Flying);
    for c in [
        Command {
            roll_rad: 0.05,
            pitch_rad: -0.08,
            yaw_rate_radps: 0.4,
            vz_mps: 0.2,
        },
        Command {
            roll_rad: -0.12,
            pitch_rad: 0.1,
            yaw_rate_radps: -1.2,
            vz_mps: -0.3,
        },
    ] {
        drone.send(&c).unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    drone.hover().unwrap();
    for _ in 0..5 {
        std::thread::sleep(Duration::from_millis(10));
        drone.telemetry();
    }
    drone.land().unwrap();
    until(drone, FlightState::Landed);
    drone.take_off().unwrap();
    drone.telemetry();
    drone.emergency().unwrap();
    std::thread::sleep(Duration::from_millis(100));
}

/// What cflib is asked to encode for the command a packet carries.
fn command_for(m: &ToDrone) -> Value {
    match *m {
        ToDrone::AltHold {
            roll_deg,
            pitch_deg,
            yaw_rate_degps,
            vz_mps,
        } => json!({"kind": "alt_hold", "roll": roll_deg, "pitch": pitch_deg,
            "yawrate": yaw_rate_degps, "vz": vz_mps}),
        ToDrone::Stop => json!({"kind": "stop"}),
        ToDrone::Position {
            position_m: [x, y, z],
            yaw_deg,
        } => json!({"kind": "position", "x": x, "y": y, "z": z, "yaw": yaw_deg}),
        ToDrone::ExtPose {
            position_m,
            quaternion,
        } => json!({"kind": "ext_pose", "pos": position_m, "quat": quaternion}),
        ToDrone::ProtocolVersion => json!({"kind": "protocol_version"}),
        ToDrone::LogTocInfo => json!({"kind": "toc_info"}),
        ToDrone::LogTocItem(index) => json!({"kind": "toc_item", "index": index}),
        ToDrone::LogReset => json!({"kind": "log_reset"}),
        ToDrone::LogCreate { block, ops } => {
            // cflib finds the variables by name in its TOC: any names, the packet's ids.
            let vars: Vec<Value> = (ops.iter())
                .map(|(kind, id)| json!([format!("g.v{id}"), kind & 0x0F, id]))
                .collect();
            json!({"kind": "log_create", "block": block, "period_10ms": 1, "vars": vars})
        }
        ToDrone::LogStart { block, period_10ms } => json!({"kind": "log_start",
            "block": block, "period_10ms": period_10ms, "vars": []}),
        ToDrone::LogStop(block) => json!({"kind": "log_stop", "block": block,
            "period_10ms": 1, "vars": []}),
        ToDrone::LogDelete(block) => json!({"kind": "log_delete", "block": block,
            "period_10ms": 1, "vars": []}),
        ToDrone::SetParam {
            group,
            name,
            kind,
            value,
        } => {
            assert_eq!(value.len(), 1, "a byte parameter");
            json!({"kind": "set_param", "name": format!("{group}.{name}"), "type": kind,
                "value": value[0]})
        }
        ToDrone::Arm { arm, supervisor } => json!({"kind": "arm", "arm": arm,
            "protocol": if supervisor { 12 } else { 11 }}),
        ToDrone::Other { port, channel } => {
            panic!("the backend sent a packet it has no name for: port {port}, channel {channel}")
        }
    }
}

/// Every datagram the fake received, as hex, in order.
fn captured(peer: &mut Peer) -> Vec<String> {
    peer.drain();
    (peer.seen.iter())
        .filter_map(|v| v["rx"].as_str().map(str::to_string))
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn every_packet_the_backend_sends_is_what_cflib_encodes() {
    let Some(python) = common::python("cflib cross-check") else {
        return;
    };
    let profile = Profile::builtin("crazyflie21").unwrap();
    let mut sent: Vec<String> = Vec::new();
    for protocol in [12, 8] {
        let (mut peer, mut drone) = common::fake(&python, protocol, &["no-auto-arm"], &profile);
        one_connection(&mut drone);
        drop(drone);
        std::thread::sleep(Duration::from_millis(50));
        sent.extend(captured(&mut peer));
    }
    // The distinct packets, each with the command it carries.
    let mut distinct: BTreeMap<String, Value> = BTreeMap::new();
    let mut kinds: BTreeMap<String, usize> = BTreeMap::new();
    for h in &sent {
        let bytes: Vec<u8> = (0..h.len() / 2)
            .map(|i| u8::from_str_radix(&h[2 * i..2 * i + 2], 16).unwrap())
            .collect();
        let packet = Packet::from_bytes(&bytes).unwrap();
        let message = ToDrone::decode(&packet).unwrap_or_else(|e| panic!("{h}: {e}"));
        let command = command_for(&message);
        *kinds
            .entry(command["kind"].as_str().unwrap().into())
            .or_default() += 1;
        distinct.insert(h.clone(), command);
    }
    for kind in [
        "alt_hold",
        "stop",
        "position",
        "ext_pose",
        "protocol_version",
        "toc_info",
        "toc_item",
        "log_reset",
        "log_create",
        "log_start",
        "set_param",
        "arm",
    ] {
        assert!(
            kinds.contains_key(kind),
            "the connections sent no {kind}: {kinds:?}"
        );
    }
    let (ours, commands): (Vec<String>, Vec<Value>) = distinct.into_iter().unzip();
    let out = dronecine_pypeer::run_json(
        &python,
        &common::script("cflib_codec.py"),
        &json!({"encode": commands}).to_string(),
    );
    let theirs = out["encoded"].as_array().unwrap();
    assert_eq!(theirs.len(), ours.len());
    for ((o, t), c) in ours.iter().zip(theirs).zip(&commands) {
        assert_eq!(
            Some(o.as_str()),
            t.as_str(),
            "{c}: the backend sent {o}, cflib encodes {t}"
        );
    }
    eprintln!(
        "cflib cross-check: {} packets sent, {} distinct, every one byte-equal to cflib's: {kinds:?}",
        sent.len(),
        ours.len()
    );
}

#[test]
fn cflib_decodes_what_the_emulated_crazyflie_sends() {
    let Some(python) = common::python("cflib decodes the emulator's packets") else {
        return;
    };
    let power_vars = json!([
        ["pm.vbat", 7, 200],
        ["pm.batteryLevel", 1, 201],
        ["pm.state", 4, 202],
        ["supervisor.info", 2, 300]
    ]);
    let layout = Layout::new(
        &POWER_BLOCK,
        &[
            log_type::FLOAT,
            log_type::UINT8,
            log_type::INT8,
            log_type::UINT16,
        ],
    )
    .unwrap();
    let mut values = Values::default();
    for (f, v) in [
        (Field::Vbat, 3.75),
        (Field::BatteryLevel, 64.0),
        (Field::PmState, 3.0),
        (Field::Supervisor, f64::from(0x1Fu16)),
    ] {
        values.set(f, v);
    }
    let mut sample = [0u8; 26];
    let n = layout.encode(&values, &mut sample);
    let packets = [
        (json!({"kind": "version"}), FromDrone::ProtocolVersion(12)),
        (
            json!({"kind": "toc_info"}),
            FromDrone::LogTocInfo {
                count: 450,
                crc: 0xC0FF_EE42,
            },
        ),
        (
            json!({"kind": "toc_item", "index": 17}),
            FromDrone::LogTocItem {
                index: 17,
                kind: log_type::FLOAT,
                group: "stateEstimate",
                name: "z",
            },
        ),
        (
            json!({"kind": "toc_item", "index": 300}),
            FromDrone::LogTocItem {
                index: 300,
                kind: log_type::UINT16,
                group: "supervisor",
                name: "info",
            },
        ),
        (
            json!({"kind": "log_data", "block": 2, "vars": power_vars}),
            FromDrone::LogData {
                block: 2,
                timestamp_ms: 0x12_3456,
                data: &sample[..n],
            },
        ),
        (
            json!({"kind": "log_ack", "block": 2, "vars": power_vars}),
            FromDrone::LogAck {
                command: log_cmd::CREATE_BLOCK_V2,
                block: 2,
                error: 0,
            },
        ),
        (
            json!({"kind": "log_ack", "block": 2, "vars": power_vars}),
            FromDrone::LogAck {
                command: log_cmd::START,
                block: 2,
                error: 0,
            },
        ),
    ];
    let decode: Vec<Value> = (packets.iter())
        .map(|(spec, m)| {
            let mut spec = spec.clone();
            spec["hex"] = hex(m.encode().unwrap().as_bytes()).into();
            spec
        })
        .collect();
    let out = dronecine_pypeer::run_json(
        &python,
        &common::script("cflib_codec.py"),
        &json!({"decode": decode}).to_string(),
    );
    let got = out["decoded"].as_array().unwrap();
    assert_eq!(got[0], json!({"version": 12}));
    assert_eq!(got[1], json!({"count": 450, "crc": 0xC0FF_EE42u32}));
    assert_eq!(
        got[2],
        json!({"group": "stateEstimate", "name": "z", "ctype": "float"})
    );
    assert_eq!(
        got[3],
        json!({"group": "supervisor", "name": "info", "ctype": "uint16_t"})
    );
    assert_eq!(
        got[4],
        json!({"timestamp": 0x12_3456, "data": {"pm.vbat": 3.75, "pm.batteryLevel": 64,
            "pm.state": 3, "supervisor.info": 31}})
    );
    // Its block created, cflib starts it (every 10 ms, as asked); started, it is started.
    assert_eq!(got[5]["added"], true);
    assert_eq!(got[5]["sent"], json!(["5d030201"]));
    assert_eq!(got[6]["started"], true);
}
