//! `dronecine status --drone mavlink://…` against the fake ArduCopter on pymavlink
//! (`runtime/mavlink/tests/fake_vehicle.py`) over UDP loopback: the read-out names the
//! vehicle's state and each parameter that is wrong with the value it needs, its verdict is
//! the exit code, and the vehicle is only read (no parameter, mode, arming or set-point).

use std::path::PathBuf;
use std::process::{Command, Output};

use dronecine_pypeer::Peer;
use serde_json::Value;

fn fake_vehicle(test: &str, params: &str) -> Option<Peer> {
    let python = dronecine_pypeer::python(test, "pymavlink")?;
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("runtime/mavlink/tests/fake_vehicle.py");
    Some(Peer::start(&python, &script, &[params]))
}

fn status(peer: &mut Peer, extra: &[&str]) -> Output {
    let url = format!("mavlink://udp:127.0.0.1:{}", peer.port());
    Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(["status", "--drone", &url, "--timeout", "5"])
        .args(extra)
        .env("NO_COLOR", "1")
        .output()
        .expect("runs")
}

/// How many PARAM_REQUEST_READs the vehicle received (the read-out's own questions).
fn param_reads(peer: &mut Peer) -> usize {
    peer.drain();
    (peer.seen.iter())
        .filter(|v| v["rx"] == "PARAM_REQUEST_READ")
        .count()
}

/// What the vehicle received that changes it: a parameter written, a mode, an arming, a
/// set-point (a ground station's stream requests, COMMAND_LONG 511 and 512, only ask).
fn changes(peer: &mut Peer) -> Vec<Value> {
    peer.drain();
    (peer.seen.iter())
        .filter(|v| match v["rx"].as_str() {
            Some("COMMAND_LONG") => !matches!(v["fields"]["command"].as_u64(), Some(511 | 512)),
            Some(t) => matches!(
                t,
                "PARAM_SET"
                    | "SET_MODE"
                    | "SET_ATTITUDE_TARGET"
                    | "SET_POSITION_TARGET_LOCAL_NED"
                    | "GIMBAL_MANAGER_SET_PITCHYAW"
                    | "SET_GPS_GLOBAL_ORIGIN"
            ),
            None => false,
        })
        .cloned()
        .collect()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn status_names_each_wrong_parameter_and_fails() {
    let Some(mut peer) = fake_vehicle("status over MAVLink: wrong parameters", "wrong") else {
        return;
    };
    let o = status(&mut peer, &["--json"]);
    assert!(!o.status.success(), "{}", text(&o.stdout));
    let out = text(&o.stdout);
    assert_eq!(out.lines().count(), 1, "{out}");
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["armed"], false, "{v}");
    assert_eq!(v["battery_percent"], 90.0, "{v}");
    let yaw_deg = v["attitude_deg"][2].as_f64().unwrap();
    assert!((yaw_deg - 0.3f64.to_degrees()).abs() < 0.01, "{v}");
    assert_eq!(
        v["wrong_parameters"],
        serde_json::json!([
            "VISO_TYPE is 0, needs 1",
            "GPS_TYPE is 1, needs 0",
            "EK3_SRC1_POSZ is 1, needs 6",
            "GUID_OPTIONS is 8, needs bit 3 (value 8) clear",
        ])
    );
    let ok: Vec<(&str, bool)> = (v["parameters"].as_array().unwrap().iter())
        .map(|p| (p["name"].as_str().unwrap(), p["ok"].as_bool().unwrap()))
        .collect();
    assert!(ok.contains(&("VISO_TYPE", false)), "{ok:?}");
    assert!(ok.contains(&("EK3_SRC1_POSXY", true)), "{ok:?}");
    let problems = v["problems"].as_array().unwrap();
    for w in v["wrong_parameters"].as_array().unwrap() {
        assert!(problems.contains(w), "{problems:?}");
    }
    let err = text(&o.stderr);
    assert!(
        err.contains(&format!("{} problems with the vehicle", problems.len())),
        "{err}"
    );
    assert!(param_reads(&mut peer) >= 4);
    assert_eq!(changes(&mut peer), Vec::<Value>::new());
}

#[test]
fn status_text_reads_a_well_set_vehicle_and_says_what_is_left() {
    let Some(mut peer) = fake_vehicle("status over MAVLink: right parameters", "right") else {
        return;
    };
    let o = status(&mut peer, &[]);
    let out = text(&o.stdout);
    for line in [
        "  mode: STABILIZE, armed: no",
        "  battery: 90 %",
        "  gimbal: pitch 0.0°",
        "    VISO_TYPE = 1  ok",
        "    GUID_OPTIONS = 0  ok",
        "  limits: climb 2.50 m/s, descent 1.50 m/s, tilt 30.0°, yaw rate no limit of its own, \
         set-points time out after 3.0 s",
    ] {
        assert!(out.lines().any(|l| l == line), "no `{line}` in:\n{out}");
    }
    assert!(!out.contains("WRONG"), "{out}");
    // Only read, the vehicle never hears the motion capture: its EKF does not use it yet,
    // which is the one problem.
    let problems: Vec<&str> = out.lines().filter(|l| l.contains("problem:")).collect();
    assert_eq!(problems.len(), 1, "{out}");
    assert!(problems[0].contains("does not navigate on the motion capture"));
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("1 problem with the vehicle"),
        "{}",
        text(&o.stderr)
    );
    assert!(param_reads(&mut peer) >= 4);
    assert_eq!(changes(&mut peer), Vec::<Value>::new());
}
