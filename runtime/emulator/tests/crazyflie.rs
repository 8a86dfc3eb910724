//! The Crazyflie emulator over loopback UDP, driven by a raw client built from the CRTP
//! codecs: the protocol version, the log TOC and blocks (and their refusals), parameter
//! writes, the estimate following the external pose only, a take-off by climb rate, a
//! nose-up set-point moving the drone backward, the stop on the floor and in the air, the
//! watchdog's lock, and garbage on the port. Real time, ephemeral ports.

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use dronecine_backend::FlightState;
use dronecine_crazyflie::crtp::{log_cmd, log_type, FromDrone, LogOps, Packet, ToDrone};
use dronecine_crazyflie::frames::{alt_hold, YawRateSign};
use dronecine_emulator::crazyflie::TOC;
use dronecine_emulator::{
    empty_scene, CrazyflieEmulator, CrazyflieEmulatorConfig, CrazyflieHandle,
};
use dronecine_profile::Profile;
use dronecine_sim::{Effects, SimConfig};
use proptest::prelude::*;

const WAIT: Duration = Duration::from_secs(5);

fn start(protocol: u8) -> CrazyflieHandle {
    let mut config =
        CrazyflieEmulatorConfig::new(Profile::builtin("crazyflie21").unwrap(), empty_scene(), 3);
    config.port = 0;
    config.natnet = None;
    config.protocol = protocol;
    config.sim = dronecine_emulator::crazyflie_emulator::crazyflie_sim(SimConfig {
        effects: Effects::none(),
        start_position_m: [1.0, -0.5, 0.0],
        ..SimConfig::new(3)
    });
    CrazyflieEmulator::start(config).expect("the emulator starts")
}

struct Client {
    socket: UdpSocket,
}

impl Client {
    fn new(h: &CrazyflieHandle) -> Client {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket.connect(h.addr()).unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(20)))
            .unwrap();
        Client { socket }
    }

    fn send(&self, m: &ToDrone) {
        self.socket.send(m.encode().unwrap().as_bytes()).unwrap();
    }

    /// Reads packets until `want` takes one (its answer), failing after [`WAIT`].
    fn until<T>(&self, mut want: impl FnMut(&FromDrone) -> Option<T>) -> T {
        let deadline = Instant::now() + WAIT;
        let mut buf = [0u8; 64];
        while Instant::now() < deadline {
            let Ok(n) = self.socket.recv(&mut buf) else {
                continue;
            };
            let p = Packet::from_bytes(&buf[..n]).expect("the emulator sends packets");
            let m = FromDrone::decode(&p).expect("the emulator sends messages");
            if let Some(v) = want(&m) {
                return v;
            }
        }
        panic!("no answer wanted within {WAIT:?}");
    }

    /// Sends `m` and waits for the log answer to `command`: its errno.
    fn log(&self, m: &ToDrone, command: u8) -> u8 {
        self.send(m);
        self.until(|f| match *f {
            FromDrone::LogAck {
                command: c, error, ..
            } if c == command => Some(error),
            _ => None,
        })
    }

    /// Sends set-points of `command` every 10 ms for `s` seconds.
    fn fly(&self, command: &dronecine_backend::frames::Command, s: f64) {
        let sp = alt_hold(command, YawRateSign::CounterClockwise);
        let m = ToDrone::AltHold {
            roll_deg: sp.roll_deg,
            pitch_deg: sp.pitch_deg,
            yaw_rate_degps: sp.yaw_rate_degps,
            vz_mps: sp.vz_mps,
        };
        let until = Instant::now() + Duration::from_secs_f64(s);
        while Instant::now() < until {
            self.send(&m);
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

fn toc_index(group: &str, name: &str) -> u16 {
    TOC.iter()
        .position(|&(g, n, _)| g == group && n == name)
        .unwrap() as u16
}

#[test]
fn the_set_up_answers_and_refusals() {
    let h = start(8);
    let c = Client::new(&h);
    c.send(&ToDrone::ProtocolVersion);
    let v = c.until(|m| match *m {
        FromDrone::ProtocolVersion(v) => Some(v),
        _ => None,
    });
    assert_eq!(v, 8);
    c.send(&ToDrone::LogTocInfo);
    let count = c.until(|m| match *m {
        FromDrone::LogTocInfo { count, .. } => Some(count),
        _ => None,
    });
    assert_eq!(usize::from(count), TOC.len());
    c.send(&ToDrone::LogTocItem(count));
    c.until(|m| matches!(m, FromDrone::LogTocEnd).then_some(()));
    let mut buf = [0u8; 27];
    let z = toc_index("stateEstimate", "z");
    let ops = LogOps::encode(&[(log_type::FLOAT, z)], &mut buf).unwrap();
    let create = ToDrone::LogCreate { block: 3, ops };
    assert_eq!(c.log(&create, log_cmd::CREATE_BLOCK_V2), 0);
    assert_eq!(c.log(&create, log_cmd::CREATE_BLOCK_V2), 17, "EEXIST");
    let mut buf = [0u8; 27];
    let unknown = LogOps::encode(&[(log_type::FLOAT, 999)], &mut buf).unwrap();
    let bad = ToDrone::LogCreate {
        block: 4,
        ops: unknown,
    };
    assert_eq!(c.log(&bad, log_cmd::CREATE_BLOCK_V2), 2, "ENOENT");
    let mut buf = [0u8; 27];
    let big = LogOps::encode(&[(log_type::FLOAT, z); 7], &mut buf).unwrap();
    let big = ToDrone::LogCreate { block: 5, ops: big };
    assert_eq!(c.log(&big, log_cmd::CREATE_BLOCK_V2), 7, "E2BIG");
    let start_unknown = ToDrone::LogStart {
        block: 9,
        period_10ms: 1,
    };
    assert_eq!(c.log(&start_unknown, log_cmd::START), 2);
    for (group, name, kind, want) in [
        ("stabilizer", "estimator", 0x08, 0),
        ("stabilizer", "estimator", 0x07, 22),
        ("stabilizer", "nothing", 0x08, 2),
    ] {
        c.send(&ToDrone::SetParam {
            group,
            name,
            kind,
            value: &[2],
        });
        let e = c.until(|m| match *m {
            FromDrone::ParamSet {
                group: g,
                name: n,
                error,
            } if (g, n) == (group, name) => Some(error),
            _ => None,
        });
        assert_eq!(e, want, "{group}.{name} type {kind}");
    }
    // The status is published at the loop's next tick, after the answer went out.
    let asked = std::time::Instant::now();
    while h.status().estimator != 2 && asked.elapsed() < std::time::Duration::from_secs(2) {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert_eq!(h.status().estimator, 2);
}

/// The estimate stays at the origin without external poses, and is the truth with them.
#[test]
fn the_estimate_follows_the_external_pose_only() {
    let h = start(12);
    let c = Client::new(&h);
    let mut buf = [0u8; 27];
    let ids = [
        toc_index("stateEstimate", "x"),
        toc_index("stateEstimate", "y"),
    ];
    let ops = LogOps::encode(
        &[(log_type::FLOAT, ids[0]), (log_type::FLOAT, ids[1])],
        &mut buf,
    )
    .unwrap();
    assert_eq!(
        c.log(
            &ToDrone::LogCreate { block: 1, ops },
            log_cmd::CREATE_BLOCK_V2
        ),
        0
    );
    let start = ToDrone::LogStart {
        block: 1,
        period_10ms: 2,
    };
    assert_eq!(c.log(&start, log_cmd::START), 0);
    let xy = |c: &Client| {
        c.until(|m| match *m {
            FromDrone::LogData { block: 1, data, .. } if data.len() == 8 => Some([
                f32::from_le_bytes(data[..4].try_into().unwrap()),
                f32::from_le_bytes(data[4..].try_into().unwrap()),
            ]),
            _ => None,
        })
    };
    assert_eq!(xy(&c), [0.0, 0.0]);
    {
        let (group, name, v) = ("stabilizer", "estimator", 2u8);
        c.send(&ToDrone::SetParam {
            group,
            name,
            kind: 0x08,
            value: &[v],
        });
    }
    let deadline = Instant::now() + WAIT;
    loop {
        c.send(&ToDrone::ExtPose {
            position_m: [1.0, -0.5, 0.0],
            quaternion: [0.0, 0.0, 0.0, 1.0],
        });
        let p = xy(&c);
        if (p[0] - 1.0).abs() < 1e-3 && (p[1] + 0.5).abs() < 1e-3 {
            break;
        }
        assert!(Instant::now() < deadline, "{p:?}");
    }
}

/// Climbing set-points take the drone off; nose up moves it backward (its heading 0: −x);
/// a stop in the air drops it and it rests, landed; without set-points in the air the
/// supervisor locks it.
#[test]
fn a_flight_by_set_points_and_the_watchdog() {
    use dronecine_backend::frames::Command;
    let h = start(12);
    let c = Client::new(&h);
    c.fly(
        &Command {
            vz_mps: 0.4,
            ..Command::HOVER
        },
        3.5,
    );
    let t = h.status().truth;
    assert_eq!(t.state, FlightState::Flying);
    assert!(t.position_m[2] > 0.5, "{:?}", t.position_m);
    let x0 = t.position_m[0];
    c.fly(
        &Command {
            pitch_rad: 0.1,
            ..Command::HOVER
        },
        1.0,
    );
    let t = h.status().truth;
    assert!(
        t.position_m[0] < x0 - 0.1,
        "nose up moves backward: {x0} → {:?}",
        t.position_m
    );
    assert!(h.status().setpoint_rate_hz().unwrap() > 50.0);
    c.send(&ToDrone::Stop);
    let deadline = Instant::now() + WAIT;
    while h.status().rests == 0 {
        assert!(Instant::now() < deadline, "{:?}", h.status().truth.state);
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(h.status().truth.state, FlightState::Landed);
    // Up again, then silence: it levels out at 0.5 s, and is locked at 2 s.
    c.fly(
        &Command {
            vz_mps: 0.4,
            ..Command::HOVER
        },
        2.5,
    );
    std::thread::sleep(Duration::from_millis(2300));
    let s = h.status();
    assert!(s.locked);
    c.fly(
        &Command {
            vz_mps: 0.4,
            ..Command::HOVER
        },
        0.5,
    );
    assert!(
        h.status().truth.state != FlightState::Flying,
        "a locked drone stays down"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1))]

    /// Garbage on the port is counted and dropped; the emulator answers afterwards.
    #[test]
    fn garbage_is_counted_and_the_emulator_goes_on(
        datagrams in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..64), 200)
    ) {
        let h = start(12);
        let c = Client::new(&h);
        let to: SocketAddr = h.addr();
        let raw = UdpSocket::bind("127.0.0.1:0").unwrap();
        for d in &datagrams {
            let _ = raw.send_to(d, to);
        }
        c.send(&ToDrone::ProtocolVersion);
        let v = c.until(|m| match *m {
            FromDrone::ProtocolVersion(v) => Some(v),
            _ => None,
        });
        prop_assert_eq!(v, 12);
        prop_assert!(h.status().firmware.datagrams >= 201);
    }
}
