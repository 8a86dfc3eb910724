//! The emulator over loopback UDP, driven by a raw client built from the wire codecs: the
//! navdata start-up (trigger, bootstrap, navdata_demo, command ACK, com watchdog), take-off
//! to the hover height, a nose-up PCMD moving the drone backward, landing, the emergency
//! toggle, the sequence rule, the configured limits, random garbage on every port, and the
//! NatNet handshake and frames (drone id 1, actors 2…, Y-up and Z-up). Ephemeral ports;
//! the flying tests run the simulator 4× faster than real time so each stays under 3 s.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use dronecine_ardrone::at::{AtCommand, AtEncoder, Datagram, Pcmd};
use dronecine_ardrone::navdata::{self, DroneState, MajorState, Navdata};
use dronecine_backend::FlightState;
use dronecine_emulator::{
    empty_scene, Emulator, EmulatorConfig, EmulatorHandle, NatNetConfig, NatNetData, NavdataMode,
    ACTOR_ID_BASE, DRONE_ID,
};
use dronecine_grammar::script::Scene;
use dronecine_natnet::frame::{
    decode_frame, decode_server_info, encode_connect, Frame, UpAxis, Version,
};
use dronecine_profile::Profile;
use dronecine_sim::{Effects, SimConfig};
use proptest::prelude::*;

const LOCAL: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

fn config(scene: Scene, time_scale: f64) -> EmulatorConfig {
    EmulatorConfig {
        at_port: 0,
        navdata_port: 0,
        natnet: None,
        sim: SimConfig {
            effects: Effects::none(),
            ..SimConfig::new(7)
        },
        time_scale,
        ..EmulatorConfig::new(Profile::builtin("ardrone2").unwrap(), scene, 7)
    }
}

fn start(time_scale: f64) -> EmulatorHandle {
    Emulator::start(config(empty_scene(), time_scale)).expect("the emulator starts")
}

/// A raw AR.Drone client: one AT socket with its encoder, one navdata socket.
struct Client {
    at: UdpSocket,
    nav: UdpSocket,
    enc: AtEncoder,
    at_dest: SocketAddr,
    nav_dest: SocketAddr,
}

impl Client {
    fn new(h: &EmulatorHandle) -> Client {
        let at = UdpSocket::bind((LOCAL, 0)).unwrap();
        let nav = UdpSocket::bind((LOCAL, 0)).unwrap();
        nav.set_read_timeout(Some(Duration::from_millis(150)))
            .unwrap();
        Client {
            at,
            nav,
            enc: AtEncoder::new(),
            at_dest: h.at_addr(),
            nav_dest: h.navdata_addr(),
        }
    }

    fn send(&mut self, cmds: &[AtCommand<'_>]) {
        let mut buf = [0u8; 2048];
        let mut dg = Datagram::new(&mut buf);
        for c in cmds {
            self.enc.push(&mut dg, c).unwrap();
        }
        self.at.send_to(dg.as_bytes(), self.at_dest).unwrap();
    }

    /// One raw line with an explicit seq.
    fn send_raw(&self, text: &str) {
        self.at.send_to(text.as_bytes(), self.at_dest).unwrap();
    }

    fn trigger(&self) {
        self.nav.send_to(&[1, 0, 0, 0], self.nav_dest).unwrap();
    }

    /// The next navdata packet (decoded; the checksum verified), with its sender and size.
    fn recv(&self) -> Option<(Navdata, SocketAddr, usize)> {
        let mut buf = [0u8; 4096];
        let (n, from) = self.nav.recv_from(&mut buf).ok()?;
        let mut nd = Navdata::default();
        navdata::decode(&buf[..n], &mut nd).expect("a valid navdata packet");
        Some((nd, from, n))
    }

    /// Waits (re-sending `cmds` every 30 ms, as a client does) for a packet that satisfies
    /// `pred`.
    fn until(
        &mut self,
        timeout_s: f64,
        cmds: &[AtCommand<'_>],
        pred: impl Fn(&Navdata) -> bool,
    ) -> Navdata {
        let t0 = Instant::now();
        let mut last_send = None::<Instant>;
        let mut last = None;
        while t0.elapsed().as_secs_f64() < timeout_s {
            if !cmds.is_empty()
                && last_send.is_none_or(|t| t.elapsed() >= Duration::from_millis(30))
            {
                self.send(cmds);
                last_send = Some(Instant::now());
            }
            if let Some((nd, _, _)) = self.recv() {
                if pred(&nd) {
                    return nd;
                }
                last = Some(nd);
            }
        }
        panic!("no matching navdata within {timeout_s} s; last: {last:?}");
    }

    /// Trigger, demo mode, ACK, com watchdog cleared: a client ready to fly.
    fn handshake(&mut self) {
        self.trigger();
        self.until(1.0, &[], |_| true);
        self.send(&[AtCommand::Config {
            key: "general:navdata_demo",
            value: "TRUE",
        }]);
        self.until(1.0, &[], |nd| nd.demo.is_some() && nd.state.command_ack());
        self.send(&[AtCommand::ACK, AtCommand::Comwdg]);
        self.until(1.0, &[], |nd| {
            !nd.state.command_ack() && !nd.state.com_watchdog() && nd.demo.is_some()
        });
    }
}

fn wait_for(
    h: &EmulatorHandle,
    timeout_s: f64,
    what: &str,
    pred: impl Fn(&EmulatorHandle) -> bool,
) {
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < timeout_s {
        if pred(h) {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("{what}: not within {timeout_s} s; status {:?}", h.status());
}

#[test]
fn navdata_starts_in_bootstrap_and_follows_the_handshake() {
    let h = start(1.0);
    let mut c = Client::new(&h);
    assert!(c.recv().is_none(), "no navdata before the trigger");
    c.trigger();
    let (nd, from, len) = c.recv().expect("a bootstrap packet");
    // From the navdata port, to the trigger's sender; header + checksum only.
    assert_eq!(from, h.navdata_addr());
    assert_eq!(len, 24);
    assert!(nd.state.bootstrap() && nd.demo.is_none());
    assert!(
        nd.state.com_watchdog(),
        "set at boot, as in a real drone's bootstrap packet"
    );
    assert!(!nd.state.flying() && !nd.state.emergency());

    c.send(&[AtCommand::Config {
        key: "general:navdata_demo",
        value: "TRUE",
    }]);
    let nd = c.until(1.0, &[], |nd| nd.demo.is_some());
    assert!(nd.state.command_ack(), "CONFIG sets the ACK bit");
    assert!(nd.state.has(DroneState::NAVDATA_DEMO) && !nd.state.bootstrap());
    let demo = nd.demo.unwrap();
    assert_eq!(demo.ctrl_state.major, MajorState::Landed);
    assert_eq!(demo.battery_percent, 100);
    assert_eq!(demo.altitude_mm, 0);

    // Demo packets: valid checksums (decode checks them), sequence increasing, ~15 Hz.
    let t0 = Instant::now();
    let mut seqs = vec![nd.sequence];
    while t0.elapsed() < Duration::from_millis(400) {
        if let Some((nd, _, len)) = c.recv() {
            assert_eq!(len, 16 + 148 + 8);
            seqs.push(nd.sequence);
        }
    }
    assert!(seqs.windows(2).all(|w| w[1] == w[0] + 1), "{seqs:?}");
    // 0.4 s at 15 Hz: 6 packets (±2 for scheduling).
    assert!(
        (4..=9).contains(&seqs.len()),
        "{} packets in 0.4 s",
        seqs.len()
    );

    c.send(&[AtCommand::ACK]);
    c.until(1.0, &[], |nd| !nd.state.command_ack());
    assert!(c.recv().unwrap().0.state.com_watchdog());
    c.send(&[AtCommand::Comwdg]);
    c.until(1.0, &[], |nd| !nd.state.com_watchdog());
    let s = h.status();
    assert_eq!(s.navdata_mode, Some(NavdataMode::Demo));
    assert_eq!(s.navdata_client, Some(c.nav.local_addr().unwrap()));
    assert_eq!(s.counters.at.rejected, 0);
    assert_eq!(s.counters.at.accepted, 3);
    h.stop().unwrap();
}

#[test]
fn navdata_demo_false_streams_full_packets_at_200_hz() {
    let h = start(1.0);
    let mut c = Client::new(&h);
    c.trigger();
    c.send(&[AtCommand::Config {
        key: "general:navdata_demo",
        value: "FALSE",
    }]);
    let nd = c.until(1.0, &[], |nd| nd.time.is_some());
    assert!(nd.demo.is_some() && !nd.state.has(DroneState::NAVDATA_DEMO));
    let t0 = Instant::now();
    let mut n = 0;
    while t0.elapsed() < Duration::from_millis(200) {
        if c.recv().is_some() {
            n += 1;
        }
    }
    // 0.2 s at 200 Hz: 40 packets (the loop's 5 ms step sends one per step).
    assert!((20..=45).contains(&n), "{n} packets in 0.2 s");
    h.stop().unwrap();
}

#[test]
fn take_off_hovers_then_nose_up_moves_backward_then_lands() {
    let h = start(4.0);
    let mut c = Client::new(&h);
    c.handshake();

    // REF take-off repeated until the navdata shows the take-off, then the hover.
    let nd = c.until(1.0, &[AtCommand::TAKE_OFF, AtCommand::Comwdg], |nd| {
        nd.state.flying()
    });
    assert_eq!(nd.demo.unwrap().ctrl_state.major, MajorState::TransTakeoff);
    let nd = c.until(2.5, &[AtCommand::TAKE_OFF, AtCommand::Comwdg], |nd| {
        nd.demo.unwrap().ctrl_state.major == MajorState::Hovering
    });
    let alt = nd.demo.unwrap().altitude_m();
    assert!((0.74..=0.86).contains(&alt), "hovering at {alt} m");
    assert!(nd.state.flying() && !nd.state.com_watchdog());

    // Nose up (PCMD pitch +0.5 of euler_angle_max): heading 0, so backward is −x.
    let x0 = h.truth().position_m[0];
    let pitch_up = AtCommand::Pcmd(Pcmd::progressive(0.0, 0.5, 0.0, 0.0));
    let nd = c.until(1.0, &[AtCommand::TAKE_OFF, pitch_up], |_| {
        h.truth().position_m[0] < x0 - 0.1
    });
    let d = nd.demo.unwrap();
    assert_eq!(d.ctrl_state.major, MajorState::Flying);
    assert!(
        d.theta_mdeg > 2000.0,
        "pitch {} mdeg: nose up",
        d.theta_mdeg
    );
    assert!(d.vx_mmps < -100.0, "vx {} mm/s: backward", d.vx_mmps);
    let t = h.truth();
    assert!(
        t.position_m[1].abs() < 1e-6,
        "straight back: y {}",
        t.position_m[1]
    );
    assert!(t.velocity_mps[0] < -0.1 && t.pitch_rad > 0.0);
    assert!(h.status().commanded);

    // PCMD flag 0: the drone's own hover.
    c.until(1.0, &[AtCommand::TAKE_OFF, AtCommand::HOVER], |nd| {
        nd.demo.unwrap().ctrl_state.major == MajorState::Hovering
    });
    // REF land: landing, then landed (not flying).
    c.until(1.0, &[AtCommand::LAND], |nd| {
        nd.demo.unwrap().ctrl_state.major == MajorState::TransLanding
    });
    h.stop().unwrap();
}

#[test]
fn sequence_rule_drops_old_duplicated_and_replayed_lines() {
    let h = start(1.0);
    let c = Client::new(&h);
    let accepted = |h: &EmulatorHandle| h.counters().at.accepted;
    let stale = |h: &EmulatorHandle| h.counters().at.stale;
    c.send_raw("AT*COMWDG=10\r");
    wait_for(&h, 1.0, "seq 10 accepted", |h| accepted(h) == 1);
    // Duplicate and older: dropped.
    c.send_raw("AT*COMWDG=10\rAT*COMWDG=7\r");
    wait_for(&h, 1.0, "10 and 7 dropped", |h| stale(h) == 2);
    // A replayed take-off (old seq) does not take off.
    c.send_raw("AT*REF=9,290718208\r");
    wait_for(&h, 1.0, "replayed REF dropped", |h| stale(h) == 3);
    std::thread::sleep(Duration::from_millis(30));
    assert_eq!(h.truth().state, FlightState::Landed);
    // Newer: accepted; seq 1 resets, then 2 follows.
    c.send_raw("AT*COMWDG=11\rAT*COMWDG=1\rAT*COMWDG=2\r");
    wait_for(&h, 1.0, "11, 1, 2 accepted", |h| accepted(h) == 4);
    // After the reset 2 was the last: a replayed 2 is dropped.
    c.send_raw("AT*REF=2,290718208\r");
    wait_for(&h, 1.0, "2 dropped after the reset", |h| stale(h) == 4);
    assert_eq!(h.truth().state, FlightState::Landed);
    c.send_raw("AT*REF=3,290718208\r");
    wait_for(&h, 1.0, "take-off", |h| {
        h.truth().state == FlightState::TakingOff
    });
    assert_eq!(h.counters().at.rejected, 0);
    h.stop().unwrap();
}

#[test]
fn config_sets_the_limits_pcmd_is_scaled_by() {
    let h = start(1.0);
    let mut c = Client::new(&h);
    let lim = h.status().limits.unwrap();
    assert_eq!(
        (
            lim.euler_angle_max_rad,
            lim.control_vz_max_mps,
            lim.control_yaw_radps
        ),
        (0.2094, 0.7, 1.7453),
        "the firmware defaults"
    );
    c.send(&[
        AtCommand::Config {
            key: "control:euler_angle_max",
            value: "0.3",
        },
        AtCommand::Config {
            key: "control:control_vz_max",
            value: "1000",
        },
        AtCommand::Config {
            key: "control:control_yaw",
            value: "3.0",
        },
        // Out of the documented ranges, or not a number: refused.
        AtCommand::Config {
            key: "control:euler_angle_max",
            value: "0.9",
        },
        AtCommand::Config {
            key: "control:control_vz_max",
            value: "fast",
        },
    ]);
    wait_for(&h, 1.0, "limits configured", |h| {
        h.counters().at.config_refused == 2
    });
    let s = h.status();
    let lim = s.limits.unwrap();
    assert_eq!(
        (
            lim.euler_angle_max_rad,
            lim.control_vz_max_mps,
            lim.control_yaw_radps
        ),
        (0.3, 1.0, 3.0)
    );
    assert!(s.command_ack);
    let cmd = lim
        .command(&Pcmd::progressive(0.5, -1.0, 0.25, 2.0))
        .unwrap();
    assert_eq!(
        (cmd.roll_rad, cmd.pitch_rad, cmd.vz_mps, cmd.yaw_rate_radps),
        (0.15, -0.3, 0.25, 3.0),
        "fractions of the limits, clamped to ±1"
    );
    h.stop().unwrap();
}

#[test]
fn emergency_bit_toggles_on_its_rising_edge() {
    let h = start(1.0);
    let mut c = Client::new(&h);
    c.handshake();
    // Bit 8 repeated: one toggle (on), not a flicker.
    let nd = c.until(1.0, &[AtCommand::EMERGENCY], |nd| nd.state.emergency());
    assert_eq!(nd.demo.unwrap().ctrl_state.major, MajorState::Default);
    for _ in 0..5 {
        c.send(&[AtCommand::EMERGENCY]);
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(c.until(0.5, &[], |_| true).state.emergency());
    // Take-off is ignored in emergency.
    c.send(&[AtCommand::TAKE_OFF]);
    std::thread::sleep(Duration::from_millis(30));
    assert_eq!(h.truth().state, FlightState::Emergency);
    // Bit 8 off, then on again: cleared.
    c.send(&[AtCommand::LAND]);
    let nd = c.until(1.0, &[AtCommand::EMERGENCY], |nd| !nd.state.emergency());
    assert_eq!(nd.demo.unwrap().ctrl_state.major, MajorState::Landed);
    assert_eq!(h.counters().emergency_resets, 1);
    // And the drone flies again.
    c.until(1.0, &[AtCommand::TAKE_OFF], |nd| nd.state.flying());
    h.stop().unwrap();
}

/// A valid AT line or navdata trigger with some bytes changed, cut or repeated, or pure
/// noise.
fn datagram() -> impl Strategy<Value = Vec<u8>> {
    let valid = prop::sample::select(vec![
        b"AT*REF=5,290718208\r".to_vec(),
        b"AT*PCMD=6,1,1056964608,-1090519040,0,1065353216\r".to_vec(),
        b"AT*CONFIG=7,\"general:navdata_demo\",\"TRUE\"\r".to_vec(),
        b"AT*CTRL=8,5,0\rAT*COMWDG=9\r".to_vec(),
        b"AT*PCMD_MAG=10,1,0,0,0,0,0,0\r".to_vec(),
        vec![1, 0, 0, 0],
    ]);
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..1500),
        (
            valid,
            prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
            any::<usize>()
        )
            .prop_map(|(mut v, edits, cut)| {
                for (i, b) in edits {
                    let n = v.len();
                    v[i % n] = b;
                }
                let n = v.len();
                v.truncate(cut % (n + 1));
                v
            }),
        prop::collection::vec(any::<u8>(), 0..8).prop_map(|mut v| {
            // Huge numbers, NaN floats, long lines.
            v.extend_from_slice(b"AT*PCMD=99999999999,1,2143289344,0,0,0\r");
            v.extend(std::iter::repeat_n(b'7', 1100));
            v
        }),
    ]
}

#[test]
fn garbage_on_every_port_is_counted_never_a_panic() {
    let mut cfg = config(empty_scene(), 1.0);
    let data = UdpSocket::bind((LOCAL, 0)).unwrap();
    cfg.natnet = Some(NatNetConfig {
        command_port: 0,
        data: NatNetData::Unicast(data.local_addr().unwrap()),
        ..NatNetConfig::default()
    });
    let h = Emulator::start(cfg).unwrap();
    let sock = UdpSocket::bind((LOCAL, 0)).unwrap();
    let ports = [
        h.at_addr(),
        h.navdata_addr(),
        h.natnet_command_addr().unwrap(),
    ];
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig {
        cases: 300,
        failure_persistence: None,
        ..ProptestConfig::default()
    });
    let sent = std::cell::Cell::new(0u64);
    runner
        .run(&datagram(), |d| {
            for p in ports {
                sock.send_to(&d, p).unwrap();
            }
            sent.set(sent.get() + 1);
            if sent.get().is_multiple_of(16) {
                // Leave the emulator time to drain (loopback buffers are finite).
                std::thread::sleep(Duration::from_millis(6));
            }
            Ok(())
        })
        .unwrap();
    let sent = sent.get();
    wait_for(&h, 2.0, "every datagram read", |h| {
        let c = h.counters();
        c.at.datagrams == sent
            && c.navdata_triggers + c.navdata_rejected == sent
            && c.natnet_requests + c.natnet_rejected == sent
    });
    let c = h.counters();
    assert!(h.is_running());
    assert!(c.at.rejected > 100, "{c:?}");
    assert!(c.natnet_rejected > 100, "{c:?}");
    // Still serving: a fresh client gets navdata and its commands act.
    let mut client = Client::new(&h);
    client.send_raw("AT*COMWDG=1\r");
    client.trigger();
    client.until(
        1.0,
        &[AtCommand::Config {
            key: "custom:x",
            value: "1",
        }],
        |nd| nd.state.command_ack(),
    );
    h.stop().unwrap();
}

const SCENE: &str = "stage 8m x 6m x 3m\n\
    actor A height 1.80m at (-1, 0.5) facing 0deg\n\
    actor B height 1.65m at (2, -1) facing 180deg\n\
    MS on A and B for 16s\n";

fn scene() -> Scene {
    let checked = dronecine_grammar::check(SCENE, &dronecine_grammar::Options::default());
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.unwrap().scene.unwrap()
}

fn natnet_case(version: Version, up: UpAxis) {
    let data = UdpSocket::bind((LOCAL, 0)).unwrap();
    data.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let mut cfg = config(scene(), 1.0);
    cfg.sim.start_position_m = [0.5, -0.25, 0.0];
    cfg.sim.start_heading_rad = 1.0;
    cfg.natnet = Some(NatNetConfig {
        command_port: 0,
        data: NatNetData::Unicast(data.local_addr().unwrap()),
        version,
        up_axis: up,
    });
    let h = Emulator::start(cfg).unwrap();

    // Handshake: NAT_CONNECT → NAT_SERVERINFO with the configured version.
    let cmd = UdpSocket::bind((LOCAL, 0)).unwrap();
    cmd.set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    let mut buf = [0u8; 4096];
    let n = encode_connect(Version::V4_1, &mut buf).unwrap();
    cmd.send_to(&buf[..n], h.natnet_command_addr().unwrap())
        .unwrap();
    let (n, from) = cmd.recv_from(&mut buf).expect("a server info reply");
    assert_eq!(from, h.natnet_command_addr().unwrap());
    let info = decode_server_info(&buf[..n]).unwrap();
    assert_eq!(info.natnet_version, version);
    assert_eq!(info.app_name(), "Motive");
    let details = info.details.unwrap();
    assert_eq!(details.data_port, data.local_addr().unwrap().port());
    assert!(!details.multicast);

    // Frames: decode with that version; drone id 1, actors 2 and 3, all tracked (no
    // dropouts in this set-up), poses in the world frame after the axis conversion.
    let mut frame = Frame::default();
    let mut numbers = Vec::new();
    let mut stamps = Vec::new();
    for _ in 0..10 {
        let n = data.recv(&mut buf).expect("a frame");
        decode_frame(&buf[..n], version, &mut frame).unwrap();
        numbers.push(frame.frame_number);
        stamps.push(frame.timestamp_s);
    }
    assert!(numbers.windows(2).all(|w| w[1] > w[0]), "{numbers:?}");
    assert!(stamps.windows(2).all(|w| w[1] > w[0]), "{stamps:?}");
    // 100 Hz: the timestamp follows the frame number.
    let dt = (stamps[9] - stamps[0]) / f64::from(numbers[9] - numbers[0]);
    assert!((dt - 0.01).abs() < 1e-9, "{dt}");
    assert_eq!(frame.rigid_bodies.len(), 3);
    let drone = frame.rigid_body(DRONE_ID).unwrap().body_pose(up).unwrap();
    let p = drone.position_m;
    assert!((p[0] - 0.5).abs() < 1e-6 && (p[1] + 0.25).abs() < 1e-6 && p[2].abs() < 1e-6);
    assert!((drone.heading_rad - 1.0).abs() < 1e-6);
    let truth = h.truth();
    for (i, actor) in truth.actors.iter().enumerate() {
        let rb = frame.rigid_body(ACTOR_ID_BASE + i as i32).unwrap();
        let pose = rb.body_pose(up).unwrap();
        for k in 0..3 {
            assert!((pose.position_m[k] - actor.position_m[k]).abs() < 1e-5);
        }
    }
    wait_for(&h, 0.5, "frames counted", |h| {
        h.counters().frames_sent >= 10
    });
    h.stop().unwrap();
}

#[test]
fn natnet_handshake_and_frames_4_1_y_up() {
    natnet_case(Version::V4_1, UpAxis::Y);
}

#[test]
fn natnet_handshake_and_frames_3_1_z_up() {
    natnet_case(Version::V3_1, UpAxis::Z);
}

#[test]
fn the_simulator_keeps_to_the_wall_clock() {
    let h = start(1.0);
    std::thread::sleep(Duration::from_millis(300));
    let s = h.status();
    assert!(
        (s.truth.t_s - s.uptime_s).abs() < 0.02,
        "sim {} s, wall {} s",
        s.truth.t_s,
        s.uptime_s
    );
    h.stop().unwrap();
}

#[test]
fn bad_settings_and_busy_ports_are_errors() {
    let mut cfg = config(empty_scene(), 1.0);
    cfg.time_scale = 0.0;
    assert!(Emulator::start(cfg).is_err());
    let h = start(1.0);
    let mut cfg = config(empty_scene(), 1.0);
    cfg.at_port = h.at_addr().port();
    let e = Emulator::start(cfg).err().expect("the AT port is taken");
    assert!(e.to_string().contains("AT socket"), "{e}");
    let mut cfg = config(empty_scene(), 1.0);
    cfg.sim.mocap_rate_hz = f64::NAN;
    assert!(Emulator::start(cfg).is_err());
    h.stop().unwrap();
}
