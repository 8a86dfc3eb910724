//! `dronecine status` against a fake AR.Drone on loopback (a navdata streamer in a thread,
//! already in demo mode) that sends clean navdata, rejected packets of each kind or
//! implausible values, and against a drone that does not answer.

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::process::{Command, Output, Stdio};
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

/// The demo values of the clean fake: landed, battery 64 %.
const CLEAN: Demo = Demo {
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
};

/// What the fake drone sends.
#[derive(Clone, Copy)]
struct Peer {
    /// Packets with a bad checksum sent at a client's first trigger, before anything else.
    bad_checksums_first: u32,
    /// Then demo packets with these values every 5 ms (`None`: nothing more).
    demo: Option<Demo>,
    /// Before each demo packet, one rejected packet of each kind: a bad checksum, a packet
    /// cut inside its demo option, one with an unknown header word, one with data after
    /// its checksum.
    each_kind: bool,
}

const CLEAN_PEER: Peer = Peer {
    bad_checksums_first: 0,
    demo: Some(CLEAN),
    each_kind: false,
};

/// A demo packet with `demo`, the low-battery flag set.
fn demo_packet(seq: u32, demo: &Demo) -> Vec<u8> {
    let state = DroneState(DroneState::NAVDATA_DEMO | DroneState::BATTERY_LOW);
    let mut out = [0u8; 512];
    let mut w = NavdataWriter::new(&mut out, state, seq, 0).unwrap();
    w.demo(demo).unwrap();
    let n = w.finish().unwrap();
    out[..n].to_vec()
}

/// The packet with one bit of its state word flipped: its checksum no longer matches.
fn bad_checksum(mut packet: Vec<u8>) -> Vec<u8> {
    packet[5] ^= 0x40;
    packet
}

/// Answers the navdata trigger as its [`Peer`] says (by default demo packets every 5 ms:
/// landed, battery 64 %, low battery flag); AT commands are read and ignored.
struct FakeDrone {
    at_port: u16,
    nav_port: u16,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeDrone {
    fn start() -> FakeDrone {
        Self::with(CLEAN_PEER)
    }

    fn with(peer: Peer) -> FakeDrone {
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
                    if buf[..n] == [1, 0, 0, 0] && client != Some(from) {
                        client = Some(from);
                        for k in 0..peer.bad_checksums_first {
                            seq += 1;
                            let _ = nav.send_to(&bad_checksum(demo_packet(seq, &CLEAN)), from);
                            // In bursts the client drains before its socket's buffer fills.
                            if k % 10 == 9 {
                                std::thread::sleep(Duration::from_millis(1));
                            }
                        }
                    }
                }
                while at.recv_from(&mut buf).is_ok() {}
                let (Some(to), Some(demo)) = (client, peer.demo) else {
                    continue;
                };
                seq += 1;
                let packet = demo_packet(seq, &demo);
                if peer.each_kind {
                    let mut unknown = packet.clone();
                    unknown[..4].copy_from_slice(&0x1234_5678u32.to_le_bytes());
                    let mut trailing = packet.clone();
                    trailing.extend_from_slice(&[0; 4]);
                    for p in [bad_checksum(packet.clone()), packet[..100].to_vec()] {
                        let _ = nav.send_to(&p, to);
                    }
                    let _ = nav.send_to(&unknown, to);
                    let _ = nav.send_to(&trailing, to);
                }
                let _ = nav.send_to(&packet, to);
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

fn json(out: &[u8]) -> serde_json::Value {
    let out = String::from_utf8_lossy(out);
    assert_eq!(out.lines().count(), 1, "{out}");
    serde_json::from_str(out.trim()).unwrap()
}

fn problems(v: &serde_json::Value) -> Vec<String> {
    v["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect()
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
    // Clean navdata: nothing rejected, nothing implausible, no problem.
    assert!(v["navdata_received"].as_u64().unwrap() > 0, "{v}");
    assert_eq!(
        v["navdata_rejected"],
        serde_json::json!({"bad_checksum": 0, "truncated": 0, "unknown": 0, "malformed": 0})
    );
    assert_eq!(v["implausible"], serde_json::json!([]));
    assert_eq!(problems(&v), Vec::<String>::new());
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
    assert!(!out.contains("problem"), "{out}");
    assert!(o.stderr.is_empty());
}

#[test]
fn packets_that_all_fail_their_checksum_are_named_not_taken_for_silence() {
    let fake = FakeDrone::with(Peer {
        bad_checksums_first: 200,
        demo: None,
        ..CLEAN_PEER
    });
    let o = dronecine(&["status", "--drone", &fake.url(), "--timeout", "0.5"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("200 of 200 packets received had a bad checksum"),
        "{err}"
    );
    assert!(err.contains("navdata arrives"), "{err}");
    assert!(!err.contains("switched on"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn bad_checksums_among_good_packets_are_counted_and_fail_the_check() {
    let fake = FakeDrone::with(Peer {
        bad_checksums_first: 200,
        ..CLEAN_PEER
    });
    let o = dronecine(&["status", "--drone", &fake.url(), "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("control state  landed"), "{out}");
    let line = out
        .lines()
        .find(|l| l.contains("problem") && l.contains("bad checksum"))
        .unwrap_or_else(|| panic!("no bad-checksum problem: {out}"));
    assert!(line.contains("navdata: 200 of "), "{line}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("1 problem with the drone's navdata"), "{err}");

    let o = dronecine(&["status", "--drone", &fake.url(), "--json", "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let v = json(&o.stdout);
    assert_eq!(v["navdata_rejected"]["bad_checksum"], 200, "{v}");
    assert!(v["navdata_received"].as_u64().unwrap() > 200, "{v}");
    assert_eq!(v["battery_percent"], 64, "{v}");
    let p = problems(&v);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(
        p[0].contains("200 of ") && p[0].contains("bad checksum"),
        "{p:?}"
    );
}

#[test]
fn each_kind_of_rejected_packet_is_named_with_its_count() {
    let fake = FakeDrone::with(Peer {
        each_kind: true,
        ..CLEAN_PEER
    });
    let o = dronecine(&["status", "--drone", &fake.url(), "--json", "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let v = json(&o.stdout);
    let received = v["navdata_received"].as_u64().unwrap();
    let p = problems(&v);
    assert_eq!(p.len(), 4, "{p:?}");
    for (kind, says) in [
        ("bad_checksum", "had a bad checksum"),
        ("truncated", "were truncated"),
        ("unknown", "were not navdata"),
        ("malformed", "were malformed"),
    ] {
        let n = v["navdata_rejected"][kind].as_u64().unwrap();
        // One of each kind per good packet: about a fifth of what arrived.
        assert!(n > 1 && 4 * n < received, "{kind}: {n} of {received}");
        let sentence = format!("navdata: {n} of {received} packets received {says}");
        assert!(
            p.iter().any(|l| l.starts_with(&sentence)),
            "{sentence}: {p:?}"
        );
    }
    // The last packet of each kind, told by its length and the decoder's reason.
    assert!(p.iter().any(|l| l.contains("the last, 100 bytes")), "{p:?}");
    assert!(
        p.iter().any(|l| l.contains("data after the checksum")),
        "{p:?}"
    );

    let o = dronecine(&["status", "--drone", &fake.url(), "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        out.matches("\n  problem        navdata: ").count(),
        4,
        "{out}"
    );
}

/// A demo option no working drone sends: NaN and infinite numbers, a battery of
/// 4294967295 %, 5 km up, a speed of a million m/s.
const GARBAGE: Demo = Demo {
    battery_percent: u32::MAX,
    theta_mdeg: f32::NAN,
    altitude_mm: 5_000_000,
    vx_mmps: 1e9,
    vz_mmps: f32::INFINITY,
    ..CLEAN
};

#[test]
fn implausible_values_are_named_field_by_field_and_fail_the_check() {
    let fake = FakeDrone::with(Peer {
        demo: Some(GARBAGE),
        ..CLEAN_PEER
    });
    let o = dronecine(&["status", "--drone", &fake.url(), "--json", "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let v = json(&o.stdout);
    // The values as read stay where they were.
    assert_eq!(v["battery_percent"], 4_294_967_295u64);
    assert_eq!(v["phi_deg"], -0.25);
    let fields: Vec<&str> = v["implausible"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["field"].as_str().unwrap())
        .collect();
    assert_eq!(
        fields,
        [
            "battery_percent",
            "theta_deg",
            "altitude_m",
            "velocity_mps[0]",
            "velocity_mps[2]"
        ]
    );
    assert_eq!(v["implausible"][1]["value"], "NaN");
    assert_eq!(v["implausible"][1]["reason"], "not a number");
    assert_eq!(v["implausible"][4]["reason"], "infinite");
    assert_eq!(problems(&v).len(), 5, "{v}");

    let o = dronecine(&["status", "--drone", &fake.url(), "--timeout", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    for line in [
        "problem        implausible battery_percent 4294967295: over 100 %",
        "problem        implausible theta_deg NaN: not a number",
        "problem        implausible altitude_m 5000: beyond ±1000 m",
        "problem        implausible velocity_mps[0] 1e6: beyond ±50 m/s",
        "problem        implausible velocity_mps[2] inf: infinite",
    ] {
        assert!(out.contains(line), "{line}: {out}");
    }
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("5 problems with the drone's navdata"), "{err}");
}

#[test]
fn watch_keeps_going_and_shows_the_problems_of_each_read_out() {
    let fake = FakeDrone::with(Peer {
        demo: Some(GARBAGE),
        each_kind: true,
        ..CLEAN_PEER
    });
    let mut child = Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(["status", "--drone", &fake.url(), "--watch", "--json"])
        .args(["--timeout", "1", "--interval", "0.05"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("runs");
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    for k in 0..4 {
        let line = lines.next().expect("another read-out").unwrap();
        let v: serde_json::Value = serde_json::from_str(&line).unwrap();
        let p = problems(&v);
        assert!(
            p.iter().any(|l| l.contains("implausible theta_deg NaN")),
            "read-out {k}: {p:?}"
        );
        // Each read-out counts the packets since the previous one.
        assert!(
            v["navdata_rejected"]["truncated"].as_u64().unwrap() > 0,
            "{v}"
        );
    }
    assert!(child.try_wait().unwrap().is_none(), "--watch stopped");
    child.kill().unwrap();
    child.wait().unwrap();
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
