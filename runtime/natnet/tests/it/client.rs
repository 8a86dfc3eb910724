//! The NatNet client against a fake Motive on loopback (unicast): the fake answers
//! `NAT_CONNECT` with its server info (NatNet 3.0 or 4.1), then the test streams frames
//! (`encode_frame`) and garbage from the fake's socket to the address the connect came from.

use std::f64::consts::FRAC_PI_2;
use std::net::{SocketAddr, UdpSocket};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use dronecine_backend::{BackendError, Mocap, MocapFrame};
use dronecine_natnet::client::{NatNetClient, NatNetOptions};
use dronecine_natnet::frame::{
    decode_connect, encode_frame, encode_server_info, FrameOut, RigidBody, ServerDetails,
    ServerInfo, Version,
};
use dronecine_natnet::rig::Rig;
use dronecine_natnet::url::NatNetUrl;

struct FakeMotive {
    socket: UdpSocket,
    port: u16,
    /// The client's command socket, once it connected.
    client: mpsc::Receiver<SocketAddr>,
}

/// A server that answers one `NAT_CONNECT` with `version` (and says it streams multicast
/// when `multicast`).
fn fake_motive(version: Version, multicast: bool) -> FakeMotive {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = socket.local_addr().unwrap().port();
    let server = socket.try_clone().unwrap();
    server
        .set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 2048];
        let deadline = Instant::now() + Duration::from_secs(2);
        while Instant::now() < deadline {
            let Ok((n, from)) = server.recv_from(&mut buf) else {
                continue;
            };
            if decode_connect(&buf[..n]).is_err() {
                continue;
            }
            let mut info = ServerInfo::new("Motive", [3, 1, 0, 0], version);
            info.details = Some(ServerDetails {
                high_res_clock_hz: 1_000_000,
                data_port: 1511,
                multicast,
                multicast_group: [239, 255, 42, 99],
            });
            let mut out = [0u8; 512];
            let m = encode_server_info(&info, &mut out).unwrap();
            server.send_to(&out[..m], from).unwrap();
            let _ = tx.send(from);
            return;
        }
    });
    FakeMotive {
        socket,
        port,
        client: rx,
    }
}

impl FakeMotive {
    fn url(&self) -> NatNetUrl {
        // A free data port, so that parallel tests do not share one.
        let data = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        NatNetUrl::parse(&format!(
            "natnet://127.0.0.1:{}?unicast&data_port={data}",
            self.port
        ))
        .unwrap()
    }

    fn send(&self, bytes: &[u8], to: SocketAddr) {
        self.socket.send_to(bytes, to).unwrap();
    }
}

fn body(id: i32, position_m: [f32; 3], q: [f32; 4], tracked: bool) -> RigidBody {
    RigidBody {
        id,
        position_m,
        orientation_xyzw: q,
        mean_error_m: 0.0005,
        params: u16::from(tracked),
    }
}

const IDENTITY: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

fn frame_bytes(version: Version, number: i32, bodies: &[RigidBody]) -> Vec<u8> {
    let out = FrameOut {
        frame_number: number,
        rigid_bodies: bodies,
        timestamp_s: f64::from(number) / 120.0,
        camera_mid_exposure_ticks: 1_000,
        camera_data_received_ticks: 3_000,
        // 5 ms after mid-exposure at 1 MHz.
        transmit_ticks: 6_000,
        ..FrameOut::default()
    };
    let mut buf = vec![0u8; 4096];
    let n = encode_frame(&out, version, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

const RIG: &str =
    "up = \"y\"\ndrone = 1\norigin_m = [1.0, 0.0, 0.0]\n[actors]\nAlice = 2\nBob = 3\n";

fn options() -> NatNetOptions {
    NatNetOptions {
        handshake_timeout: Duration::from_millis(500),
        ..NatNetOptions::default()
    }
}

/// Polls until a frame arrives (up to 1 s).
fn poll_one(client: &mut NatNetClient, frame: &mut MocapFrame) {
    let deadline = Instant::now() + Duration::from_secs(1);
    while !client.poll(frame).unwrap() {
        assert!(Instant::now() < deadline, "no frame arrived");
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

fn check_version(version: Version) {
    let fake = fake_motive(version, false);
    let rig = Rig::from_toml(RIG).unwrap();
    let opts = options();
    let mut client = NatNetClient::connect(&fake.url(), &rig, ["Bob", "Alice"], &opts).unwrap();
    assert_eq!(client.version(), version);
    let to = fake.client.recv_timeout(Duration::from_secs(1)).unwrap();

    let s = std::f32::consts::FRAC_1_SQRT_2;
    let bodies = [
        body(1, [1.0, 2.0, 3.0], IDENTITY, true),
        body(2, [5.0, 5.0, 5.0], IDENTITY, false),
        // 90° about Motive's up (y): a quarter turn counter-clockwise seen from above.
        body(3, [0.0, 1.0, -2.0], [0.0, s, 0.0, s], true),
    ];
    let mut frame = MocapFrame::default();
    let sent_s = opts.epoch.elapsed().as_secs_f64();
    fake.send(&frame_bytes(version, 42, &bodies), to);
    poll_one(&mut client, &mut frame);
    let polled_s = opts.epoch.elapsed().as_secs_f64();
    assert_eq!(frame.frame, 42);
    // Y-up → world (x, −z, y), then the rig's origin offset.
    let drone = frame.drone.expect("drone tracked");
    assert!(close(drone.position_m, [2.0, -3.0, 2.0]), "{drone:?}");
    assert!(drone.heading_rad.abs() < 1e-6);
    // Actors in the scene's order: Bob, then Alice (untracked).
    assert_eq!(frame.actors.len(), 2);
    let bob = frame.actors[0].expect("Bob tracked");
    assert!(close(bob.position_m, [1.0, 2.0, 1.0]), "{bob:?}");
    assert!((bob.heading_rad - FRAC_PI_2).abs() < 1e-5, "{bob:?}");
    assert_eq!(frame.actors[1], None);
    // Capture time: arrival on the flight clock minus Motive's 5 ms latency.
    assert!(
        frame.t_s >= sent_s - 0.005 - 1e-9 && frame.t_s <= polled_s - 0.005 + 1e-9,
        "{} not in [{sent_s}, {polled_s}] − 5 ms",
        frame.t_s
    );

    // Nothing new: false, frame untouched.
    let before = frame.clone();
    assert!(!client.poll(&mut frame).unwrap());
    assert_eq!(frame, before);

    // Several queued: the newest is returned once; an old one is skipped.
    let mut moved = bodies;
    moved[0].position_m = [0.0, 0.0, 0.0];
    fake.send(&frame_bytes(version, 43, &bodies), to);
    fake.send(&frame_bytes(version, 44, &moved), to);
    fake.send(&frame_bytes(version, 40, &bodies), to);
    std::thread::sleep(Duration::from_millis(20));
    poll_one(&mut client, &mut frame);
    assert_eq!(frame.frame, 44);
    assert!(close(frame.drone.unwrap().position_m, [1.0, 0.0, 0.0]));
    assert!(!client.poll(&mut frame).unwrap());
    let stats = client.stats();
    assert_eq!(stats.frames_returned, 2, "{stats:?}");
    assert!(stats.stale >= 1, "{stats:?}");

    // The drone untracked: None, the actors still filled.
    let mut lost = bodies;
    lost[0].params = 0;
    fake.send(&frame_bytes(version, 45, &lost), to);
    poll_one(&mut client, &mut frame);
    assert_eq!(frame.drone, None);
    assert!(frame.actors[0].is_some());
}

#[test]
fn natnet_3_0_frames_are_mapped_and_converted() {
    check_version(Version::V3_0);
}

#[test]
fn natnet_4_1_frames_are_mapped_and_converted() {
    check_version(Version::V4_1);
}

#[test]
fn garbage_datagrams_are_skipped_and_counted() {
    let version = Version::V4_1;
    let fake = fake_motive(version, false);
    let rig = Rig::from_toml(RIG).unwrap();
    let mut client = NatNetClient::connect(&fake.url(), &rig, ["Alice"], &options()).unwrap();
    let to = fake.client.recv_timeout(Duration::from_secs(1)).unwrap();
    let good = frame_bytes(version, 7, &[body(1, [0.0, 1.0, 0.0], IDENTITY, true)]);
    fake.send(&[0xde, 0xad], to); // no header
    fake.send(&good[..good.len() - 9], to); // truncated
    let mut lying = good.clone();
    lying[8..12].copy_from_slice(&(-5i32).to_le_bytes()); // negative marker-set count
    fake.send(&lying, to);
    fake.send(&[8, 0, 3, 0, b'h', b'i', 0], to); // NAT_MESSAGESTRING
                                                 // A 3.0 frame read as 4.1: no byte counts where 4.1 expects them.
    fake.send(&frame_bytes(Version::V3_0, 6, &[]), to);
    fake.send(&good, to);
    std::thread::sleep(Duration::from_millis(20));
    let mut frame = MocapFrame::default();
    poll_one(&mut client, &mut frame);
    assert_eq!(frame.frame, 7);
    assert!(close(frame.drone.unwrap().position_m, [1.0, 0.0, 1.0]));
    let stats = client.stats();
    assert!(stats.malformed >= 4, "{stats:?}");
    assert_eq!(stats.other_messages, 1, "{stats:?}");
}

#[test]
fn z_up_rigs_keep_motive_axes() {
    let fake = fake_motive(Version::V4_1, false);
    let rig = Rig::from_toml("up = \"z\"\ndrone = 4\nyaw_deg = 180\n").unwrap();
    let mut client =
        NatNetClient::connect(&fake.url(), &rig, Vec::<String>::new(), &options()).unwrap();
    let to = fake.client.recv_timeout(Duration::from_secs(1)).unwrap();
    fake.send(
        &frame_bytes(
            Version::V4_1,
            1,
            &[body(4, [1.0, 2.0, 3.0], IDENTITY, true)],
        ),
        to,
    );
    let mut frame = MocapFrame::default();
    poll_one(&mut client, &mut frame);
    let d = frame.drone.unwrap();
    // Z-up is the world frame; the rig's 180° yaw turns it about the stage origin.
    assert!(close(d.position_m, [-1.0, -2.0, 3.0]), "{d:?}");
    assert!((d.heading_rad.abs() - std::f64::consts::PI).abs() < 1e-9);
    assert!(frame.actors.is_empty());
}

#[test]
fn a_silent_server_gives_a_clear_timeout() {
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = silent.local_addr().unwrap().port();
    let url = NatNetUrl::parse(&format!("natnet://127.0.0.1:{port}?unicast")).unwrap();
    let rig = Rig::from_toml(RIG).unwrap();
    let err = NatNetClient::connect(
        &url,
        &rig,
        ["Alice"],
        &NatNetOptions {
            handshake_timeout: Duration::from_millis(150),
            ..NatNetOptions::default()
        },
    )
    .unwrap_err();
    let BackendError::Link(m) = err else {
        panic!("{err:?}")
    };
    assert!(m.contains("no NatNet server info"), "{m}");
    assert!(m.contains(&format!("127.0.0.1:{port}")), "{m}");
}

#[test]
fn connect_checks_the_rig_and_the_transport() {
    let rig = Rig::from_toml(RIG).unwrap();
    let fake = fake_motive(Version::V4_1, false);
    let err = NatNetClient::connect(&fake.url(), &rig, ["Alice", "Carol"], &options()).unwrap_err();
    assert!(
        matches!(&err, BackendError::Refused(m) if m.contains("actor `Carol`")),
        "{err:?}"
    );
    // Motive streams multicast, the URL says unicast: the error gives the URL to use.
    let fake = fake_motive(Version::V4_1, true);
    let err = NatNetClient::connect(&fake.url(), &rig, ["Alice"], &options()).unwrap_err();
    assert!(
        matches!(&err, BackendError::Link(m) if m.contains("?multicast=239.255.42.99")),
        "{err:?}"
    );
}
