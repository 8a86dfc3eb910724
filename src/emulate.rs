//! `dronecine emulate ardrone` and `dronecine emulate crazyflie`: the embedded simulator in
//! real time behind the AR.Drone 2.0's protocols (AT commands in, navdata out) or the
//! Crazyflie's (CRTP over UDP), and OptiTrack NatNet, so a client (the backends, or the
//! drone's own apps) can fly it over UDP. The actors (and the drone profile) come from an
//! optional script (loaded as `compile` and `shoot` load it); without one there are none.

use std::net::{IpAddr, SocketAddr};
use std::path::Path;
use std::process::ExitCode;

use dronecine_emulator::{
    empty_scene, CrazyflieEmulator, CrazyflieEmulatorConfig, Emulator, EmulatorConfig,
    NatNetConfig, NatNetData, ACTOR_ID_BASE, DRONE_ID,
};
use dronecine_grammar::script::Scene;
use dronecine_natnet::frame::{UpAxis, Version};
use dronecine_profile::{Profile, DEFAULT_NAME};
use dronecine_sim::SimConfig;

/// The drone emulated, and its ports.
pub enum Emulated {
    ArDrone {
        at_port: u16,
        navdata_port: u16,
    },
    /// CRTP over UDP on `port`, announcing CRTP protocol `protocol`.
    Crazyflie {
        port: u16,
        protocol: u8,
    },
}

pub struct Args<'a> {
    pub drone: Emulated,
    pub host: IpAddr,
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
    /// Serve the simulator's world to Foxglove on this address (`--live`).
    pub live: Option<SocketAddr>,
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

/// The simulated world of `a`: the simulator's settings, the scene, the profile and the
/// actors' names.
fn world(a: &Args) -> Result<(SimConfig, Scene, Profile, Vec<String>), ExitCode> {
    let mut sim = SimConfig::new(a.seed);
    let loaded = match a.script {
        None => None,
        Some(path) => Some(crate::compile::load_scene(
            path, a.color, "emulated", false,
        )?),
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
    sim.effects = crate::shoot::sim_effects(a.ideal, a.sim_off).map_err(fail)?;
    // The drone stands below its first framing, clear of the actors, as the embedded
    // simulator's does (at the origin it could stand on an actor's mark, which `shoot`
    // refuses).
    if let Some(script) = (loaded.as_ref().map(|l| l.script())).filter(|s| !s.timeline.is_empty()) {
        (sim.start_position_m, sim.start_heading_rad) =
            dronecine_runtime::start_pose(script, &scene, &profile, &sim);
    }
    Ok((sim, scene, profile, names))
}

pub fn run(a: &Args) -> ExitCode {
    let Some(version) = parse_version(a.natnet_version) else {
        return fail(format!(
            "--natnet-version {}: expected a NatNet version from 3.0 to 4.1",
            a.natnet_version
        ));
    };
    let (sim, scene, profile, names) = match world(a) {
        Ok(w) => w,
        Err(code) => return code,
    };
    let effects_off = sim.effects.off();
    let natnet = (!a.no_natnet).then(|| NatNetConfig {
        command_port: a.natnet_command_port,
        data: NatNetData::from_addr(a.natnet),
        version,
        up_axis: if a.z_up { UpAxis::Z } else { UpAxis::Y },
    });
    let profile_name = profile.name.clone();
    let off = crate::shoot::effects_off_phrase(&effects_off);
    let live = match a
        .live
        .map(|addr| live_world(addr, &scene, &profile))
        .transpose()
    {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
    let (natnet_at, wait): (_, Box<dyn FnOnce() -> Result<(), String>>) = match a.drone {
        Emulated::ArDrone {
            at_port,
            navdata_port,
        } => {
            let config = EmulatorConfig {
                host: a.host,
                at_port,
                navdata_port,
                natnet,
                sim,
                ..EmulatorConfig::new(profile, scene, a.seed)
            };
            let handle = match Emulator::start(config) {
                Ok(h) => h,
                Err(e) => return fail(e),
            };
            outln!(
                "emulating an AR.Drone 2.0 ({profile_name}, seed {}, {off}) in real time",
                a.seed
            );
            outln!("  AT commands     udp {}", handle.at_addr());
            outln!(
                "  navdata         udp {} (send 01 00 00 00 to start it)",
                handle.navdata_addr()
            );
            let at = (handle.natnet_command_addr(), handle.natnet_data());
            let wait = move || {
                if let Some((server, world)) = live {
                    serve_truth(|| handle.is_running().then(|| handle.truth()), world);
                    server.stop();
                }
                handle.wait().map_err(|e| e.to_string())
            };
            (
                at,
                Box::new(wait) as Box<dyn FnOnce() -> Result<(), String>>,
            )
        }
        Emulated::Crazyflie { port, protocol } => {
            let config = CrazyflieEmulatorConfig {
                host: a.host,
                port,
                natnet,
                protocol,
                sim: dronecine_emulator::crazyflie_emulator::crazyflie_sim(sim),
                ..CrazyflieEmulatorConfig::new(profile, scene, a.seed)
            };
            let handle = match CrazyflieEmulator::start(config) {
                Ok(h) => h,
                Err(e) => return fail(e),
            };
            outln!(
                "emulating a Crazyflie ({profile_name}, CRTP protocol {protocol}, seed {}, \
                 {off}) in real time",
                a.seed
            );
            outln!(
                "  CRTP            udp {} (--drone crazyflie+udp://{})",
                handle.addr(),
                handle.addr()
            );
            let at = (handle.natnet_command_addr(), handle.natnet_data());
            let wait = move || {
                if let Some((server, world)) = live {
                    serve_truth(|| handle.is_running().then(|| handle.status().truth), world);
                    server.stop();
                }
                handle.wait().map_err(|e| e.to_string())
            };
            (
                at,
                Box::new(wait) as Box<dyn FnOnce() -> Result<(), String>>,
            )
        }
    };
    print_natnet(a, natnet_at, version, &names);
    outln!("Ctrl-C to stop.");
    match wait() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

/// Where the motion capture is, and its rigid bodies.
fn print_natnet(
    a: &Args,
    at: (Option<SocketAddr>, Option<NatNetData>),
    version: Version,
    names: &[String],
) {
    let (Some(cmd), Some(data)) = at else {
        outln!("  NatNet          off");
        return;
    };
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

/// The live view of the emulator's world: its server (where to connect said) and the scene.
fn live_world(
    addr: SocketAddr,
    scene: &Scene,
    profile: &Profile,
) -> Result<(dronecine_live::LiveServer, dronecine_live::LiveWorld), String> {
    let server = crate::live::serve(addr)?;
    let camera = &profile.camera;
    let lens = match scene.lens {
        Some(l) => dronecine_compiler::camera::Lens::new(l.fov_x_rad, l.aspect),
        None => dronecine_compiler::camera::Lens::new(camera.fov_x_rad, camera.aspect),
    };
    let names: Vec<String> = scene.actors.iter().map(|x| x.name.clone()).collect();
    let heights: Vec<f64> = scene.actors.iter().map(|x| x.height_m).collect();
    let log_scene = dronecine_mcap::log::LogScene {
        stage: scene.stage,
        lens,
        actor_names: &names,
        actor_heights_m: &heights,
    };
    let world = dronecine_live::LiveWorld::start(&server, &log_scene, false)
        .map_err(|e| format!("the live view cannot start: {e}"))?;
    Ok((server, world))
}

/// The simulator's truth to the live view at 30 Hz, from this thread (the emulator's own
/// never waits for it), while `truth` gives one (the emulator runs).
fn serve_truth(
    truth: impl Fn() -> Option<dronecine_sim::Truth>,
    mut world: dronecine_live::LiveWorld,
) {
    while let Some(truth) = truth() {
        let drone = (truth.position_m, truth.heading_rad);
        world.pose(truth.t_s, drone, 0.0, &truth.actors);
        std::thread::sleep(std::time::Duration::from_millis(33));
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
