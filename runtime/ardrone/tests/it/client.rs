//! The AR.Drone client against a fake drone on loopback: a UDP socket pair in a thread,
//! built on the codecs, that answers the navdata trigger (bootstrap packets, then demo
//! packets once `general:navdata_demo` is set), raises and clears the command-ACK bit like
//! the firmware, flies on `AT*REF`, and records every AT datagram.

use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use dronecine_ardrone::at::{
    parse_datagram, ref_emergency, ref_take_off, AtCommand, Pcmd, PcmdLimits, PCMD_PROGRESSIVE,
};
use dronecine_ardrone::client::{
    implausible, ArDroneClient, ArDroneOptions, ConfigIds, NavdataReject, ALTITUDE_MAX_M,
    ANGLE_MAX_DEG, BATTERY_MAX_PERCENT, SPEED_MAX_MPS,
};
use dronecine_ardrone::navdata::{
    self, ControlState, Demo, DroneState, MajorState, Navdata, NavdataWriter,
};
use dronecine_ardrone::url::ArDroneUrl;
use dronecine_backend::frames::Command;
use dronecine_backend::{BackendError, Drone, FlightState};
use dronecine_profile::Profile;

#[derive(Clone, Copy)]
struct Behaviour {
    /// Streams navdata after the trigger.
    answer: bool,
    /// Raises the command-ACK bit on CONFIG.
    ack: bool,
    /// Streams demo packets from the start.
    start_in_demo: bool,
    /// Raises the com-watchdog bit until an `AT*COMWDG` arrives.
    watchdog: bool,
    /// Also sends a corrupt packet and an old one with every packet.
    garbage: bool,
    /// Sends only packets whose checksum does not match.
    corrupt_all: bool,
}

const NORMAL: Behaviour = Behaviour {
    answer: true,
    ack: true,
    start_in_demo: false,
    watchdog: false,
    garbage: false,
    corrupt_all: false,
};

#[derive(Clone, Debug, PartialEq)]
enum Cmd {
    Ref(u32),
    Pcmd(Pcmd),
    Ftrim,
    Config(String, String),
    ConfigIds(String, String, String),
    Comwdg,
    Ctrl(i32, i32),
    Other(String),
}

#[derive(Clone, Debug)]
struct Rec {
    datagram: usize,
    seq: u32,
    cmd: Cmd,
}

struct FakeDrone {
    at_port: u16,
    nav_port: u16,
    log: Arc<Mutex<Vec<Vec<u8>>>>,
    triggers: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for FakeDrone {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn owned(c: &AtCommand<'_>) -> Cmd {
    match *c {
        AtCommand::Ref { input } => Cmd::Ref(input),
        AtCommand::Pcmd(p) => Cmd::Pcmd(p),
        AtCommand::Ftrim => Cmd::Ftrim,
        AtCommand::Config { key, value } => Cmd::Config(key.into(), value.into()),
        AtCommand::ConfigIds {
            session,
            user,
            application,
        } => Cmd::ConfigIds(session.into(), user.into(), application.into()),
        AtCommand::Comwdg => Cmd::Comwdg,
        AtCommand::Ctrl { mode, arg } => Cmd::Ctrl(mode, arg),
        other => Cmd::Other(other.name().into()),
    }
}

impl FakeDrone {
    fn start(b: Behaviour) -> FakeDrone {
        let at = UdpSocket::bind("127.0.0.1:0").unwrap();
        let nav = UdpSocket::bind("127.0.0.1:0").unwrap();
        at.set_nonblocking(true).unwrap();
        nav.set_nonblocking(true).unwrap();
        let (at_port, nav_port) = (
            at.local_addr().unwrap().port(),
            nav.local_addr().unwrap().port(),
        );
        let log = Arc::new(Mutex::new(Vec::new()));
        let triggers = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let (log2, trig2, stop2) = (log.clone(), triggers.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let mut client = None;
            let mut demo_mode = b.start_in_demo;
            let mut bits = 0u32;
            let mut major = MajorState::Landed;
            let mut watchdog = b.watchdog;
            let mut seq = 0u32;
            let mut last_packet = Instant::now();
            let mut buf = [0u8; 4096];
            while !stop2.load(Ordering::Relaxed) {
                while let Ok((n, from)) = nav.recv_from(&mut buf) {
                    if buf[..n] == [1, 0, 0, 0] {
                        client = Some(from);
                        trig2.fetch_add(1, Ordering::Relaxed);
                    }
                }
                while let Ok((n, _)) = at.recv_from(&mut buf) {
                    log2.lock().unwrap().push(buf[..n].to_vec());
                    for line in parse_datagram(&buf[..n]).flatten() {
                        match line.command {
                            AtCommand::Config { key, value } => {
                                if b.ack {
                                    bits |= DroneState::COMMAND_ACK;
                                }
                                if key == "general:navdata_demo" && value == "TRUE" {
                                    demo_mode = true;
                                }
                            }
                            AtCommand::Ctrl { mode: 5, .. } => bits &= !DroneState::COMMAND_ACK,
                            AtCommand::Comwdg => watchdog = false,
                            AtCommand::Ref { input } => {
                                if ref_emergency(input) {
                                    bits |= DroneState::EMERGENCY;
                                } else if ref_take_off(input) {
                                    major = match major {
                                        MajorState::Landed => MajorState::TransTakeoff,
                                        _ => MajorState::Hovering,
                                    };
                                } else {
                                    major = MajorState::Landed;
                                }
                            }
                            _ => {}
                        }
                    }
                }
                if let (Some(to), true) = (client, b.answer) {
                    if last_packet.elapsed() >= Duration::from_millis(4) {
                        last_packet = Instant::now();
                        seq += 1;
                        let mut state = bits
                            | if demo_mode {
                                DroneState::NAVDATA_DEMO
                            } else {
                                DroneState::NAVDATA_BOOTSTRAP
                            };
                        if watchdog {
                            state |= DroneState::COM_WATCHDOG;
                        }
                        if matches!(major, MajorState::Hovering | MajorState::TransTakeoff) {
                            state |= DroneState::FLYING;
                        }
                        let mut out = [0u8; 512];
                        let mut w =
                            NavdataWriter::new(&mut out, DroneState(state), seq, 0).unwrap();
                        if demo_mode {
                            w.demo(&Demo {
                                ctrl_state: ControlState { major, minor: 0 },
                                battery_percent: 87,
                                theta_mdeg: -1500.0,
                                phi_mdeg: 2500.0,
                                psi_mdeg: 90_000.0,
                                altitude_mm: 1234,
                                vx_mmps: 100.0,
                                vy_mmps: -200.0,
                                vz_mmps: 0.0,
                                num_frames: seq,
                            })
                            .unwrap();
                        }
                        let n = w.finish().unwrap();
                        if b.garbage {
                            let mut bad = out[..n].to_vec();
                            bad[5] ^= 0x40; // the checksum no longer matches
                            let _ = nav.send_to(&bad, to);
                        }
                        if b.corrupt_all {
                            out[5] ^= 0x40;
                        }
                        let _ = nav.send_to(&out[..n], to);
                        if b.garbage && seq > 3 {
                            // An old packet after the new one: the sequence rule drops it.
                            let mut old = [0u8; 64];
                            let w = NavdataWriter::new(&mut old, DroneState(state), seq - 2, 0)
                                .unwrap();
                            let m = w.finish().unwrap();
                            let _ = nav.send_to(&old[..m], to);
                        }
                    }
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        });
        FakeDrone {
            at_port,
            nav_port,
            log,
            triggers,
            stop,
            thread: Some(thread),
        }
    }

    fn url(&self) -> ArDroneUrl {
        ArDroneUrl::parse(&format!(
            "ardrone://127.0.0.1:{}:{}",
            self.at_port, self.nav_port
        ))
        .unwrap()
    }

    fn datagrams(&self) -> usize {
        self.log.lock().unwrap().len()
    }

    /// Waits (up to 1 s) until at least `n` datagrams arrived.
    fn wait_for(&self, n: usize) {
        let deadline = Instant::now() + Duration::from_secs(1);
        while self.datagrams() < n && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(self.datagrams() >= n, "the fake drone got no datagram");
    }

    fn records(&self) -> Vec<Rec> {
        let log = self.log.lock().unwrap();
        let mut out = Vec::new();
        for (i, dg) in log.iter().enumerate() {
            for line in parse_datagram(dg) {
                let line = line.expect("the client sends valid AT lines");
                out.push(Rec {
                    datagram: i,
                    seq: line.seq,
                    cmd: owned(&line.command),
                });
            }
        }
        out
    }
}

fn profile() -> Profile {
    Profile::builtin("ardrone2").unwrap()
}

fn fast() -> ArDroneOptions {
    ArDroneOptions {
        navdata_timeout: Duration::from_millis(300),
        ack_timeout: Duration::from_millis(300),
        config_ids: None,
    }
}

fn connect(fake: &FakeDrone) -> ArDroneClient {
    ArDroneClient::connect(&fake.url(), &profile(), &fast()).expect("connects to the fake")
}

fn configs(recs: &[Rec]) -> Vec<(String, String)> {
    recs.iter()
        .filter_map(|r| match &r.cmd {
            Cmd::Config(k, v) => Some((k.clone(), v.clone())),
            _ => None,
        })
        .collect()
}

#[test]
fn start_up_sets_demo_mode_then_writes_the_profile_limits_each_acknowledged() {
    let fake = FakeDrone::start(NORMAL);
    let client = connect(&fake);
    assert!(fake.triggers.load(Ordering::Relaxed) >= 1);
    let recs = fake.records();
    let limits = PcmdLimits::from_profile(&profile().limits).unwrap();
    assert_eq!(client.limits(), Some(limits));
    let mut expected = vec![("general:navdata_demo".to_string(), "TRUE".to_string())];
    expected.extend(
        limits
            .config_lines()
            .iter()
            .map(|l| (l.key.to_string(), l.value().to_string())),
    );
    // Each CONFIG once (the fake acks within a resend period) and in this order.
    let mut got = configs(&recs);
    got.dedup();
    assert_eq!(got, expected);
    assert_eq!(
        expected[1..]
            .iter()
            .map(|(k, _)| k.as_str())
            .collect::<Vec<_>>(),
        [
            "control:euler_angle_max",
            "control:control_vz_max",
            "control:control_yaw"
        ]
    );
    // The handshake: after every CONFIG an AT*CTRL=…,5,0 before the next CONFIG.
    let positions: Vec<usize> = recs
        .iter()
        .enumerate()
        .filter(|(_, r)| matches!(r.cmd, Cmd::Config(..)))
        .map(|(i, _)| i)
        .collect();
    for (n, &p) in positions.iter().enumerate() {
        let end = positions.get(n + 1).copied().unwrap_or(recs.len());
        if n + 1 < positions.len() && recs[positions[n + 1]].cmd == recs[p].cmd {
            continue; // a resend of the same CONFIG
        }
        assert!(
            recs[p..end].iter().any(|r| r.cmd == Cmd::Ctrl(5, 0)),
            "no ACK after {:?}",
            recs[p].cmd
        );
    }
    // One global sequence counter: starts at 1, strictly increasing across datagrams.
    assert_eq!(recs[0].seq, 1);
    for w in recs.windows(2) {
        assert!(w[1].seq > w[0].seq, "{:?} then {:?}", w[0], w[1]);
        assert!(w[1].datagram >= w[0].datagram);
    }
    // No watchdog raised: no COMWDG sent.
    assert!(!recs.iter().any(|r| r.cmd == Cmd::Comwdg));
}

#[test]
fn send_maps_the_command_to_progressive_pcmd_with_ardrone_signs() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = connect(&fake);
    let limits = client.limits().unwrap();
    let cmd = Command {
        roll_rad: 0.1,
        pitch_rad: -0.05,
        yaw_rate_radps: 0.5,
        vz_mps: -0.3,
    };
    let before = fake.datagrams();
    client.send(&cmd).unwrap();
    fake.wait_for(before + 1);
    let recs = fake.records();
    let last = recs.iter().rev().find_map(|r| match r.cmd {
        Cmd::Pcmd(p) => Some((r.datagram, p)),
        _ => None,
    });
    let (dg, p) = last.expect("a PCMD went out");
    assert_eq!(dg, before, "send emits one datagram");
    assert_eq!(p.flag, PCMD_PROGRESSIVE);
    let e = limits.euler_angle_max_rad();
    assert!((f64::from(p.roll) - 0.1 / e).abs() < 1e-6, "{p:?}");
    assert!((f64::from(p.pitch) + 0.05 / e).abs() < 1e-6, "{p:?}");
    assert!((f64::from(p.gaz) + 0.3 / limits.control_vz_max_mps()).abs() < 1e-6);
    assert!((f64::from(p.yaw) - 0.5 / limits.control_yaw_radps()).abs() < 1e-6);
    // Signs unchanged: roll right +, pitch (nose down) −, descend −, clockwise +.
    assert!(p.roll > 0.0 && p.pitch < 0.0 && p.gaz < 0.0 && p.yaw > 0.0);
    // The REF rides along (landed: take-off bit clear).
    assert!(recs
        .iter()
        .any(|r| r.datagram == dg && matches!(r.cmd, Cmd::Ref(i) if !ref_take_off(i))));

    // Beyond the limits: clamped to ±1.
    let before = fake.datagrams();
    client
        .send(&Command {
            roll_rad: -5.0,
            pitch_rad: 5.0,
            yaw_rate_radps: -50.0,
            vz_mps: 9.0,
        })
        .unwrap();
    fake.wait_for(before + 1);
    let recs = fake.records();
    let p = recs
        .iter()
        .rev()
        .find_map(|r| match r.cmd {
            Cmd::Pcmd(p) => Some(p),
            _ => None,
        })
        .unwrap();
    assert_eq!((p.roll, p.pitch, p.gaz, p.yaw), (-1.0, 1.0, 1.0, -1.0));

    // Hover: flag 0, one datagram.
    let before = fake.datagrams();
    client.hover().unwrap();
    fake.wait_for(before + 1);
    let recs = fake.records();
    let (dg, p) = recs
        .iter()
        .rev()
        .find_map(|r| match r.cmd {
            Cmd::Pcmd(p) => Some((r.datagram, p)),
            _ => None,
        })
        .unwrap();
    assert_eq!(dg, before);
    assert_eq!(p, Pcmd::HOVER);
}

fn wait_state(client: &mut ArDroneClient, want: FlightState) {
    let deadline = Instant::now() + Duration::from_secs(1);
    while client.telemetry().state != want {
        assert!(Instant::now() < deadline, "never reached {want:?}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn take_off_trims_first_and_repeats_the_ref_until_flying_then_lands() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = connect(&fake);
    assert_eq!(client.telemetry().state, FlightState::Landed);
    let start = fake.records().len();
    client.take_off().unwrap();
    // The fake goes TRANS_TAKEOFF on the first take-off REF and HOVERING on the next: only
    // the keep-alive of `telemetry` repeats it.
    wait_state(&mut client, FlightState::Flying);
    let recs = fake.records()[start..].to_vec();
    let first_ftrim = recs.iter().position(|r| r.cmd == Cmd::Ftrim);
    let first_take_off = recs
        .iter()
        .position(|r| matches!(r.cmd, Cmd::Ref(i) if ref_take_off(i)));
    assert!(first_ftrim.is_some(), "no FTRIM before take-off");
    assert!(first_ftrim < first_take_off, "{recs:?}");
    assert!(
        recs.iter()
            .filter(|r| matches!(r.cmd, Cmd::Ref(i) if ref_take_off(i)))
            .count()
            >= 2
    );

    // Flying: take_off again sends no FTRIM (trim is for the ground only).
    let n = fake.records().len();
    let before = fake.datagrams();
    client.take_off().unwrap();
    fake.wait_for(before + 1);
    std::thread::sleep(Duration::from_millis(10));
    assert!(!fake.records()[n..].iter().any(|r| r.cmd == Cmd::Ftrim));

    client.land().unwrap();
    wait_state(&mut client, FlightState::Landed);
    let t = client.telemetry();
    assert_eq!(t.battery_percent, 87.0);
    assert!(t.link_age_s < 0.5, "{t:?}");
}

#[test]
fn emergency_sends_the_select_bit() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = connect(&fake);
    client.emergency().unwrap();
    wait_state(&mut client, FlightState::Emergency);
    assert!(fake
        .records()
        .iter()
        .any(|r| matches!(r.cmd, Cmd::Ref(i) if ref_emergency(i) && !ref_take_off(i))));
    // In emergency, take-off is refused with the reason.
    match client.take_off() {
        Err(BackendError::Refused(m)) => assert!(m.contains("emergency"), "{m}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_com_watchdog_bit_gets_a_comwdg() {
    let fake = FakeDrone::start(Behaviour {
        watchdog: true,
        start_in_demo: true,
        ..NORMAL
    });
    let mut client = connect(&fake);
    client.hover().unwrap();
    fake.wait_for(1);
    let recs = fake.records();
    let wdg = recs
        .iter()
        .find(|r| r.cmd == Cmd::Comwdg)
        .expect("COMWDG sent while the bit was set");
    // Appended to a datagram with another command, not sent alone.
    assert!(recs
        .iter()
        .any(|r| r.datagram == wdg.datagram && r.cmd != Cmd::Comwdg));
    // The drone started in demo mode: no navdata_demo CONFIG needed.
    assert!(!configs(&recs)
        .iter()
        .any(|(k, _)| k == "general:navdata_demo"));
}

#[test]
fn config_ids_precede_each_config_in_the_same_datagram() {
    let fake = FakeDrone::start(NORMAL);
    let ids = ConfigIds {
        session: "d2e081a3".into(),
        user: "be27e2e4".into(),
        application: "d87f7e0c".into(),
    };
    let options = ArDroneOptions {
        config_ids: Some(ids.clone()),
        ..fast()
    };
    ArDroneClient::connect(&fake.url(), &profile(), &options).unwrap();
    let recs = fake.records();
    let mut n = 0;
    for (i, r) in recs.iter().enumerate() {
        if let Cmd::Config(..) = r.cmd {
            n += 1;
            let prev = &recs[i - 1];
            assert_eq!(prev.datagram, r.datagram);
            assert_eq!(
                prev.cmd,
                Cmd::ConfigIds(
                    ids.session.clone(),
                    ids.user.clone(),
                    ids.application.clone()
                )
            );
        }
    }
    assert!(n >= 4);
}

#[test]
fn a_silent_drone_gives_a_clear_timeout() {
    let fake = FakeDrone::start(Behaviour {
        answer: false,
        ..NORMAL
    });
    let err = ArDroneClient::connect(&fake.url(), &profile(), &fast()).unwrap_err();
    let BackendError::Link(m) = err else {
        panic!("{err:?}")
    };
    assert!(m.contains("no navdata"), "{m}");
    assert!(m.contains(&format!("127.0.0.1:{}", fake.nav_port)), "{m}");
    // The trigger was re-sent while waiting.
    assert!(fake.triggers.load(Ordering::Relaxed) >= 2, "{m}");
}

#[test]
fn an_unacknowledged_config_names_the_key() {
    let fake = FakeDrone::start(Behaviour {
        ack: false,
        start_in_demo: true,
        ..NORMAL
    });
    let err = ArDroneClient::connect(&fake.url(), &profile(), &fast()).unwrap_err();
    let BackendError::Link(m) = err else {
        panic!("{err:?}")
    };
    assert!(m.contains("control:euler_angle_max"), "{m}");
    assert!(m.contains("did not acknowledge"), "{m}");
    assert!(m.contains(&format!("127.0.0.1:{}", fake.at_port)), "{m}");
}

#[test]
fn telemetry_skips_malformed_and_old_navdata() {
    let fake = FakeDrone::start(Behaviour {
        garbage: true,
        ..NORMAL
    });
    let mut client = connect(&fake);
    let deadline = Instant::now() + Duration::from_secs(1);
    while client.stats().navdata_stale == 0 && Instant::now() < deadline {
        client.telemetry();
        std::thread::sleep(Duration::from_millis(2));
    }
    let stats = client.stats();
    assert!(stats.navdata_malformed > 0, "{stats:?}");
    assert!(stats.navdata_stale > 0, "{stats:?}");
    let t = client.telemetry();
    assert_eq!(t.state, FlightState::Landed);
    assert_eq!(t.battery_percent, 87.0);
    let s = client.status();
    assert_eq!(s.ctrl_state, "landed");
    assert_eq!((s.theta_deg, s.phi_deg, s.psi_deg), (-1.5, 2.5, 90.0));
    assert_eq!(s.altitude_m, 1.234);
    assert!((s.velocity_mps[1] + 0.2).abs() < 1e-9);
    assert!(s.flags.contains(&"navdata_demo"), "{:?}", s.flags);
}

#[test]
fn status_counts_rejected_packets_since_the_previous_read_out() {
    let fake = FakeDrone::start(Behaviour {
        garbage: true,
        ..NORMAL
    });
    let mut client = connect(&fake);
    let first = client.status();
    std::thread::sleep(Duration::from_millis(50));
    let second = client.status();
    let stats = client.stats();
    // The read-outs split the packets since connecting between them.
    assert_eq!(
        first.navdata_received + second.navdata_received,
        stats.navdata_received()
    );
    assert_eq!(
        first.navdata_rejected.bad_checksum + second.navdata_rejected.bad_checksum,
        stats.navdata_rejected.bad_checksum
    );
    assert_eq!(stats.navdata_rejected.total(), stats.navdata_malformed);
    // The fake sends one packet with a bad checksum with each good one; its old ones are valid.
    let r = second.navdata_rejected;
    assert!(r.bad_checksum > 0, "{r:?}");
    assert_eq!((r.truncated, r.unknown, r.malformed), (0, 0, 0));
    let sentence = format!(
        "navdata: {} of {} packets received had a bad checksum (the last, ",
        r.bad_checksum, second.navdata_received
    );
    assert_eq!(second.problems.len(), 1, "{:?}", second.problems);
    assert!(
        second.problems[0].starts_with(&sentence),
        "{:?}",
        second.problems
    );
    assert!(second.implausible.is_empty());
}

#[test]
fn a_drone_whose_packets_all_fail_their_checksum_is_not_called_silent() {
    let fake = FakeDrone::start(Behaviour {
        corrupt_all: true,
        ..NORMAL
    });
    let err = ArDroneClient::monitor(&fake.url(), &fast()).unwrap_err();
    let BackendError::Link(m) = err else {
        panic!("{err:?}")
    };
    assert!(!m.contains("no navdata"), "{m}");
    assert!(m.contains("navdata arrives"), "{m}");
    // "N of N packets received had a bad checksum": every packet, counted.
    let (counts, _) = m
        .split_once(" packets received had a bad checksum")
        .unwrap_or_else(|| panic!("{m}"));
    let words: Vec<&str> = counts.rsplitn(4, ' ').collect();
    assert_eq!(words[1], "of", "{m}");
    let (n, of): (u64, u64) = (words[2].parse().unwrap(), words[0].parse().unwrap());
    assert!(n > 10 && n == of, "{m}");
}

#[test]
fn status_of_a_clean_drone_has_no_problem() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = ArDroneClient::monitor(&fake.url(), &fast()).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    let s = client.status();
    assert!(s.navdata_received > 0);
    assert_eq!(s.navdata_rejected.total(), 0);
    assert!(s.implausible.is_empty() && s.problems.is_empty(), "{s:?}");
}

/// A valid demo packet.
fn packet() -> Vec<u8> {
    let mut out = [0u8; 512];
    let mut w = NavdataWriter::new(&mut out, DroneState(DroneState::NAVDATA_DEMO), 7, 0).unwrap();
    w.demo(&Demo::default()).unwrap();
    let n = w.finish().unwrap();
    out[..n].to_vec()
}

fn kind_of(p: &[u8]) -> Option<NavdataReject> {
    let mut nav = Navdata::default();
    navdata::decode(p, &mut nav)
        .err()
        .map(|e| NavdataReject::of(&e, p.len()))
}

#[test]
fn each_decoder_error_has_its_kind() {
    use NavdataReject::*;
    let good = packet();
    let demo_end = 16 + 148;
    assert_eq!(kind_of(&good), None);
    let with = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut p = good.clone();
        f(&mut p);
        kind_of(&p)
    };
    // A flipped bit anywhere before the checksum.
    assert_eq!(with(&|p| p[40] ^= 1), Some(BadChecksum));
    assert_eq!(with(&|p| p[5] ^= 0x40), Some(BadChecksum));
    // Cut by the end of the datagram: in the header, in an option header, inside the demo
    // option, right before the checksum option, inside the checksum option.
    for cut in [10, 18, 100, demo_end, demo_end + 6] {
        assert_eq!(kind_of(&good[..cut]), Some(Truncated), "cut at {cut}");
    }
    // A demo option that declares itself shorter than its fields (checksum made right).
    let mut short = good[..16].to_vec();
    short.extend_from_slice(&[0, 0, 40, 0]);
    short.extend_from_slice(&[0; 36]);
    let sum = navdata::checksum(&short);
    short.extend_from_slice(&[0xFF, 0xFF, 8, 0]);
    short.extend_from_slice(&sum.to_le_bytes());
    assert_eq!(kind_of(&short), Some(Truncated));
    // Not navdata.
    assert_eq!(with(&|p| p[0] = 0), Some(Unknown));
    assert_eq!(kind_of(b"hello, drone"), Some(Unknown));
    assert_eq!(kind_of(b"GET / HTTP/1.1\r\n\r\n"), Some(Unknown));
    // A layout the protocol does not allow.
    assert_eq!(with(&|p| p.extend_from_slice(&[0; 4])), Some(Malformed));
    assert_eq!(with(&|p| p[18] = 2), Some(Malformed)); // demo option size 2
    assert_eq!(with(&|p| p.resize(5000, 0)), Some(Malformed));
}

#[test]
fn implausible_names_each_field_beyond_its_bound() {
    let ok = Demo {
        ctrl_state: ControlState::from_raw(4 << 16),
        battery_percent: BATTERY_MAX_PERCENT,
        theta_mdeg: (ANGLE_MAX_DEG * 1000.0) as f32,
        phi_mdeg: -(ANGLE_MAX_DEG * 1000.0) as f32,
        psi_mdeg: 180_000.0,
        altitude_mm: (ALTITUDE_MAX_M * 1000.0) as i32,
        vx_mmps: (SPEED_MAX_MPS * 1000.0) as f32,
        vy_mmps: -(SPEED_MAX_MPS * 1000.0) as f32,
        vz_mmps: 0.0,
        num_frames: 0,
    };
    // The bounds themselves are plausible.
    assert_eq!(implausible(&ok), []);
    let fields = |d: Demo| -> Vec<(&str, String)> {
        implausible(&d)
            .into_iter()
            .map(|i| (i.field, i.reason))
            .collect()
    };
    assert_eq!(
        fields(Demo {
            battery_percent: 101,
            ..ok
        }),
        [("battery_percent", "over 100 %".to_string())]
    );
    assert_eq!(
        fields(Demo {
            phi_mdeg: f32::NAN,
            psi_mdeg: 180_001.0,
            ..ok
        }),
        [
            ("phi_deg", "not a number".to_string()),
            ("psi_deg", "beyond ±180°".to_string())
        ]
    );
    assert_eq!(
        fields(Demo {
            altitude_mm: -1_000_001,
            vy_mmps: f32::NEG_INFINITY,
            vz_mmps: 50_001.0,
            ..ok
        }),
        [
            ("altitude_m", "beyond ±1000 m".to_string()),
            ("velocity_mps[1]", "infinite".to_string()),
            ("velocity_mps[2]", "beyond ±50 m/s".to_string())
        ]
    );
    assert_eq!(
        fields(Demo {
            ctrl_state: ControlState::from_raw(12 << 16),
            ..ok
        }),
        [(
            "ctrl_state",
            "not a control state the SDK names (0 to 9)".to_string()
        )]
    );
    let nan = implausible(&Demo {
        theta_mdeg: f32::NAN,
        ..ok
    });
    assert_eq!(nan[0].value, "NaN");
}

#[test]
fn monitoring_writes_no_limits_and_refuses_to_fly() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = ArDroneClient::monitor(&fake.url(), &fast()).unwrap();
    for _ in 0..30 {
        client.status();
        std::thread::sleep(Duration::from_millis(2));
    }
    let recs = fake.records();
    assert!(configs(&recs)
        .iter()
        .all(|(k, _)| k == "general:navdata_demo"));
    // Someone else may be flying the drone: a monitor sends no REF (no "land").
    assert!(
        !recs.iter().any(|r| matches!(r.cmd, Cmd::Ref(_))),
        "{recs:?}"
    );
    assert!(matches!(
        client.send(&Command::HOVER),
        Err(BackendError::Refused(_))
    ));
}

#[test]
fn a_drone_that_goes_silent_never_stalls_the_caller() {
    let fake = FakeDrone::start(NORMAL);
    let mut client = connect(&fake);
    drop(fake); // the drone is gone: nothing answers, nothing reads
    let started = Instant::now();
    let mut slowest = Duration::ZERO;
    for k in 0..200 {
        let t = Instant::now();
        client
            .send(&Command {
                pitch_rad: 0.01 * (k % 3) as f64,
                ..Command::HOVER
            })
            .ok();
        let telemetry = client.telemetry();
        slowest = slowest.max(t.elapsed());
        assert!(telemetry.link_age_s >= 0.0);
        std::thread::sleep(Duration::from_millis(1));
    }
    // Every call returns at once (non-blocking sockets), and the link age tells the loop.
    assert!(
        slowest < Duration::from_millis(20),
        "a call took {slowest:?}"
    );
    assert!(client.telemetry().link_age_s >= started.elapsed().as_secs_f64() * 0.9);
}
