//! The Python peers of this folder, on cflib (`dronecine-pypeer`), and a backend connected
//! to the fake Crazyflie.

#![allow(dead_code)]

use std::path::PathBuf;

use dronecine_crazyflie::{CrazyflieDrone, CrazyflieOptions, CrazyflieUrl};
use dronecine_profile::Profile;
pub use dronecine_pypeer::Peer;

/// The Python with cflib, or `None` (after saying why) when the test is to be skipped.
pub fn python(test: &str) -> Option<String> {
    dronecine_pypeer::python(test, "cflib")
}

/// This folder's `script`.
pub fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join(name)
}

/// A UDP port free on loopback now.
pub fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// `fake_crazyflie.py` speaking `protocol` (`args` added), and the backend connected to it
/// with `profile`'s limits: the fake's cflib UDP driver sends to the backend's port, the
/// backend to the fake's.
pub fn fake(
    python: &str,
    protocol: u8,
    args: &[&str],
    profile: &Profile,
) -> (Peer, CrazyflieDrone) {
    let backend = free_port();
    let mut all = vec![backend.to_string(), protocol.to_string()];
    all.extend(args.iter().map(|a| a.to_string()));
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    let mut peer = Peer::start(python, &script("fake_crazyflie.py"), &all);
    let port = peer.port();
    let url = CrazyflieUrl::parse(&format!("crazyflie+udp://127.0.0.1:{port}")).unwrap();
    let options = CrazyflieOptions {
        hover_height_m: 0.5,
        local_udp: Some(([127, 0, 0, 1], backend).into()),
        ..CrazyflieOptions::default()
    };
    let drone = CrazyflieDrone::connect(&url, profile, options).expect("connects to the fake");
    (peer, drone)
}
