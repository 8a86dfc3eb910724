//! `dronecine emulate ardrone`: the embedded simulator in real time behind the AR.Drone 2.0
//! (AT commands in, navdata out) and OptiTrack NatNet protocols, so a client (the AR.Drone
//! and NatNet backends, or any AR.Drone app) can fly it over UDP. The actors come from an
//! optional script (loaded as `compile` and `shoot` load it); without one there are none.

use std::net::{IpAddr, SocketAddr};
use std::path::Path;
use std::process::ExitCode;

use dronecine_emulator::{
    empty_scene, Emulator, EmulatorConfig, NatNetConfig, NatNetData, ACTOR_ID_BASE, DRONE_ID,
};
use dronecine_natnet::frame::{UpAxis, Version};
use dronecine_profile::{Profile, DEFAULT_NAME};
use dronecine_sim::SimConfig;

pub struct Args<'a> {
    pub host: IpAddr,
    pub at_port: u16,
    pub navdata_port: u16,
    /// Where NatNet frames go (unicast, or a multicast group).
    pub natnet: SocketAddr,
    pub natnet_command_port: u16,
    pub natnet_version: &'a str,
    pub z_up: bool,
    pub no_natnet: bool,
    pub seed: u64,
    pub script: Option<&'a Path>,
    pub ideal: bool,
    /// Simulator effects to switch off, by their names.
    pub sim_off: &'a [String],
    pub color: bool,
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

/// `"4.1"`, `"3.0"`, `"4.1.0.0"` → a version the codec supports.
fn parse_version(s: &str) -> Option<Version> {
    let mut parts = [0u8; 4];
    let mut n = 0;
    for p in s.split('.') {
        *parts.get_mut(n)? = p.parse().ok()?;
        n += 1;
    }
    let v = Version::from_bytes(parts);
    (n >= 2 && v.is_supported()).then_some(v)
}

pub fn run(a: &Args) -> ExitCode {
    let Some(version) = parse_version(a.natnet_version) else {
        return fail(format!(
            "--natnet-version {}: expected a NatNet version from 3.0 to 4.1",
            a.natnet_version
        ));
    };
    let mut sim = SimConfig::new(a.seed);
    let loaded = match a.script {
        None => None,
        Some(path) => match crate::compile::load_scene(path, a.color, "emulated", false) {
            Ok(l) => Some(l),
            Err(code) => return code,
        },
    };
    let (scene, profile, names) = match &loaded {
        None => (
            empty_scene(),
            Profile::builtin(DEFAULT_NAME).expect("the default profile is built in"),
            Vec::new(),
        ),
        Some(loaded) => {
            let scene = loaded.scene();
            let names = scene.actors.iter().map(|x| x.name.clone()).collect();
            (scene.clone(), loaded.profile.clone(), names)
        }
    };
    sim.effects = match crate::shoot::sim_effects(a.ideal, a.sim_off) {
        Ok(e) => e,
        Err(e) => {
            errln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // The drone stands below its first framing, clear of the actors, as the embedded
    // simulator's does (at the origin it could stand on an actor's mark, which `shoot`
    // refuses).
    if let Some(script) = (loaded.as_ref().map(|l| l.script())).filter(|s| !s.timeline.is_empty()) {
        (sim.start_position_m, sim.start_heading_rad) =
            dronecine_runtime::start_pose(script, &scene, &profile, &sim);
    }
    let effects_off = sim.effects.off();
    let config = EmulatorConfig {
        host: a.host,
        at_port: a.at_port,
        navdata_port: a.navdata_port,
        natnet: (!a.no_natnet).then(|| NatNetConfig {
            command_port: a.natnet_command_port,
            data: NatNetData::from_addr(a.natnet),
            version,
            up_axis: if a.z_up { UpAxis::Z } else { UpAxis::Y },
        }),
        sim,
        ..EmulatorConfig::new(profile, scene, a.seed)
    };
    let profile_name = config.profile.name.clone();
    let handle = match Emulator::start(config) {
        Ok(h) => h,
        Err(e) => return fail(e),
    };
    outln!(
        "emulating an AR.Drone 2.0 ({profile_name}, seed {}, {}) in real time",
        a.seed,
        crate::shoot::effects_off_phrase(&effects_off)
    );
    outln!("  AT commands     udp {}", handle.at_addr());
    outln!(
        "  navdata         udp {} (send 01 00 00 00 to start it)",
        handle.navdata_addr()
    );
    match (handle.natnet_command_addr(), handle.natnet_data()) {
        (Some(cmd), Some(data)) => {
            outln!("  NatNet command  udp {cmd} (NatNet {version})");
            let kind = match data {
                NatNetData::Multicast(_) => "multicast",
                NatNetData::Unicast(_) => "unicast",
            };
            outln!(
                "  NatNet frames → udp {} ({kind}, {}-up, 100 Hz)",
                data.addr(),
                if a.z_up { "Z" } else { "Y" }
            );
            if matches!(data, NatNetData::Multicast(_)) && a.host.is_loopback() {
                errln!(
                    "warning: multicast frames from {} leave by the loopback interface, which \
                     often carries no multicast: use --host 0.0.0.0, or unicast \
                     (--natnet 127.0.0.1:PORT) for a client on this machine",
                    a.host
                );
            }
            outln!("  rigid bodies    {DRONE_ID} = drone");
            for (i, n) in names.iter().enumerate() {
                outln!("                  {} = {n}", ACTOR_ID_BASE + i as i32);
            }
        }
        _ => outln!("  NatNet          off"),
    }
    outln!("Ctrl-C to stop.");
    match handle.wait() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions() {
        assert_eq!(parse_version("4.1"), Some(Version::V4_1));
        assert_eq!(parse_version("3.0.0.0"), Some(Version::V3_0));
        assert_eq!(parse_version("2.10"), None);
        assert_eq!(parse_version("4"), None);
        assert_eq!(parse_version("4.1.0.0.0"), None);
        assert_eq!(parse_version("x.1"), None);
    }
}
