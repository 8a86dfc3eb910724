//! End to end through the real wire protocols: `dronecine emulate ardrone` (the simulator
//! behind AR.Drone AT/navdata and NatNet on loopback) and `dronecine emulate crazyflie` (CRTP
//! over UDP and NatNet) flown by `dronecine shoot --drone --mocap`, in real time. The tracking
//! error must stay within twice the in-process simulator's for the same seed and profile,
//! and the log must replay exactly.

use std::process::Command;

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.80m at (0, 0) facing 0deg\n\
                      at 1s A walks to (0.5, 0.5) over 3s\n\
                      MS on A 34left for 6s\n";

fn report(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn shoot_through_the_emulator_tracks_like_the_simulator() {
    through_the_emulator("ardrone", "ardrone2");
}

#[test]
fn shoot_through_the_crazyflie_emulator_tracks_like_the_simulator() {
    through_the_emulator("crazyflie", "crazyflie21");
}

/// `SCRIPT` flown by `drone` through `dronecine emulate KIND` and on the in-process
/// simulator, seed 4.
fn through_the_emulator(kind: &str, drone: &str) {
    let dir = crate::common::temp_dir(&format!("e2e-{kind}"));
    let script = dir.join("walk.psl");
    std::fs::write(
        &script,
        SCRIPT.replace("drone ardrone2", &format!("drone {drone}")),
    )
    .unwrap();
    let script = script.to_str().unwrap();
    let bin = env!("CARGO_BIN_EXE_dronecine");
    let emulator = crate::common::Emulator::start_as(kind, &["--seed", "4", "--script", script]);

    let log = dir.join("e2e.mcap");
    let wire = report(
        &Command::new(bin)
            .args(["shoot", script, "-q", "--report", "json"])
            .args(["--drone", &emulator.drone_url])
            .args(["--mocap", &emulator.mocap_url])
            .args(["--log", log.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    let sim = report(
        &Command::new(bin)
            .args(["shoot", script, "-q", "--report", "json", "--seed", "4"])
            .args(["--log", dir.join("sim.mcap").to_str().unwrap()])
            .output()
            .unwrap(),
    );
    assert_eq!(wire["completed"], true, "{wire}");
    let (w, s) = (
        wire["rms_position_error_m"].as_f64().unwrap(),
        sim["rms_position_error_m"].as_f64().unwrap(),
    );
    eprintln!("{kind}: RMS position error through the protocols {w:.4} m, in process {s:.4} m");
    assert!(w <= 2.0 * s, "{w} m against {s} m in process");
    assert!(wire["rms_framing_error"].as_f64().unwrap() < 0.1, "{wire}");

    // The log of a flight on the wire replays exactly too.
    let o = Command::new(bin)
        .args(["replay", log.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
