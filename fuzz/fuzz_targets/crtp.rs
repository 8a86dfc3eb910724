//! Fuzz CRTP on arbitrary bytes, cut into datagrams (each first byte gives the next
//! datagram's length): every datagram through both decoders, a message they accept
//! re-encoded and decoded to the same; the datagrams applied to the backend's link state; and
//! the same datagrams to the emulated Crazyflie firmware flying the simulator. None panics.
#![no_main]

use std::time::Instant;

use dronecine_backend::Clock;
use dronecine_crazyflie::crtp::{FromDrone, Packet, ToDrone};
use dronecine_crazyflie::link::LinkState;
use dronecine_emulator::crazyflie::CrazyflieFirmware;
use dronecine_emulator::empty_scene;
use dronecine_profile::Profile;
use dronecine_sim::{SimConfig, Simulator, Truth};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut datagrams = Vec::new();
    let mut rest = data;
    while let Some((&n, tail)) = rest.split_first() {
        let n = usize::from(n % 40).min(tail.len());
        datagrams.push(&tail[..n]);
        rest = &tail[n..];
    }
    let mut state = LinkState::default();
    let now = Instant::now();
    for d in &datagrams {
        if let Ok(p) = Packet::from_bytes(d) {
            if let Ok(m) = FromDrone::decode(&p) {
                if !matches!(m, FromDrone::Other { .. }) {
                    let again = m.encode().expect("a decoded message fits a packet");
                    assert_eq!(FromDrone::decode(&again), Ok(m));
                }
            }
            if let Ok(m) = ToDrone::decode(&p) {
                if !matches!(m, ToDrone::Other { .. }) {
                    let again = m.encode().expect("a decoded message fits a packet");
                    let back = ToDrone::decode(&again).expect("its encoding decodes");
                    assert_eq!(back.encode().expect("again"), again);
                }
            }
        }
        state.apply(d, now);
    }
    assert_eq!(state.received + state.rejected, datagrams.len() as u64);
    let profile = Profile::builtin("crazyflie21").expect("built in");
    let sim = Simulator::new(&SimConfig::new(1), &profile, &empty_scene()).expect("a simulator");
    let (mut drone, mut clock) = (sim.drone(), sim.clock());
    let mut fw = CrazyflieFirmware::new(12);
    let mut truth = Truth::default();
    let mut out = Vec::new();
    for (i, d) in datagrams.iter().enumerate() {
        let t = i as f64 * 0.01;
        clock.sleep_until(t);
        sim.truth_into(&mut truth);
        fw.datagram(d, t, &mut drone, &truth, &mut out);
        fw.tick(t, &mut drone, &truth, &mut out);
        out.clear();
    }
});
