//! `dronecine status` against a fake AR.Drone on loopback (a navdata streamer in a thread,
//! already in demo mode), and against a drone that does not answer.

use std::net::UdpSocket;
use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use dronecine_ardrone::navdata::{ControlState, Demo, DroneState, MajorState, NavdataWriter};

fn dronecine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(args)
        .env("NO_COLOR", "1")
        .output()
        .expect("runs")
}

/// Answers the navdata trigger with demo packets every 5 ms (landed, battery 64 %, low
/// battery flag); AT commands are read and ignored.
struct FakeDrone {
    at_port: u16,
    nav_port: u16,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeDrone {
    fn start() -> FakeDrone {
        let at = UdpSocket::bind("127.0.0.1:0").unwrap();
        let nav = UdpSocket::bind("127.0.0.1:0").unwrap();
        nav.set_read_timeout(Some(Duration::from_millis(5)))
            .unwrap();
        at.set_nonblocking(true).unwrap();
        let at_port = at.local_addr().unwrap().port();
        let nav_port = nav.local_addr().unwrap().port();
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut client = None;
            let mut seq = 0;
            let mut buf = [0u8; 2048];
            while !stop2.load(Ordering::Relaxed) {
                if let Ok((n, from)) = nav.recv_from(&mut buf) {
                    if buf[..n] == [1, 0, 0, 0] {
                        client = Some(from);
                    }
                }
                while at.recv_from(&mut buf).is_ok() {}
                let Some(to) = client else { continue };
                seq += 1;
                let state = DroneState(DroneState::NAVDATA_DEMO | DroneState::BATTERY_LOW);
                let mut out = [0u8; 512];
                let mut w = NavdataWriter::new(&mut out, state, seq, 0).unwrap();
                w.demo(&Demo {
                    ctrl_state: ControlState {
                        major: MajorState::Landed,
                        minor: 0,
                    },
                    battery_percent: 64,
                    theta_mdeg: 500.0,
                    phi_mdeg: -250.0,
                    psi_mdeg: -45_000.0,
                    altitude_mm: 0,
                    vx_mmps: 0.0,
                    vy_mmps: 0.0,
                    vz_mmps: 0.0,
                    num_frames: 0,
                })
                .unwrap();
                let n = w.finish().unwrap();
                let _ = nav.send_to(&out[..n], to);
            }
        });
        FakeDrone {
            at_port,
            nav_port,
            stop,
            thread: Some(thread),
        }
    }

    fn url(&self) -> String {
        format!("ardrone://127.0.0.1:{}:{}", self.at_port, self.nav_port)
    }
}

impl Drop for FakeDrone {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[test]
fn status_json_prints_what_to_check_before_a_flight() {
    let fake = FakeDrone::start();
    let o = dronecine(&["status", "--drone", &fake.url(), "--json", "--timeout", "1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.lines().count(), 1, "{out}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["ctrl_state"], "landed");
    assert_eq!(v["battery_percent"], 64);
    assert_eq!(v["theta_deg"], 0.5);
    assert_eq!(v["phi_deg"], -0.25);
    assert_eq!(v["psi_deg"], -45.0);
    assert_eq!(v["altitude_m"], 0.0);
    assert_eq!(v["velocity_mps"].as_array().map(Vec::len), Some(3));
    let flags: Vec<&str> = v["flags"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f.as_str())
        .collect();
    assert_eq!(flags, ["navdata_demo", "battery_low"]);
}

#[test]
fn status_text_names_the_state_and_warns() {
    let fake = FakeDrone::start();
    let o = dronecine(&["status", "--drone", &fake.url(), "--timeout", "1"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("control state  landed"), "{out}");
    assert!(out.contains("battery        64 %"), "{out}");
    assert!(out.contains("warning        battery low"), "{out}");
}

#[test]
fn an_unreachable_drone_exits_1_with_a_clear_message() {
    // A bound socket that never answers.
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = silent.local_addr().unwrap().port();
    let url = format!("ardrone://127.0.0.1:{port}:{port}");
    let o = dronecine(&["status", "--drone", &url, "--timeout", "0.2"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no navdata"), "{err}");
    assert!(err.contains(&format!("127.0.0.1:{port}")), "{err}");
    assert!(o.stdout.is_empty());

    let o = dronecine(&["status", "--drone", "192.168.1.1"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("ardrone://HOST"), "{err}");
}
