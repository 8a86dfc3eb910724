//! The operator's signals through the real protocols: `dronecine shoot` flying the emulator
//! (the simulator behind AT commands, navdata and NatNet, in this process) in real time is
//! interrupted in take-off and in the shots. One Ctrl-C (SIGINT), SIGTERM or SIGHUP lands the
//! drone; a second Ctrl-C cuts its motors, a second SIGTERM does not. The delay from the signal
//! to the command arriving at the drone is measured and printed.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use dronecine_backend::FlightState;
use dronecine_emulator::{Emulator, EmulatorConfig, EmulatorHandle, NatNetConfig, NatNetData};
use dronecine_profile::Profile;
use dronecine_sim::{Effects, SimConfig};

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.80m at (0, 0) facing 0deg\n\
                      MS on A 34left for 8s\n";

/// How late a command may reach the drone after the signal: a tick of the loop (10 ms), the
/// client's next datagram, the emulator's next step, with room for a loaded machine.
const PROMPT_S: f64 = 0.25;

/// The emulator, flying `SCRIPT`'s scene with every effect off but the mocap's noise.
fn emulator() -> (EmulatorHandle, String, String) {
    let checked = dronecine_grammar::check(SCRIPT, &dronecine_grammar::Options::default());
    let script = checked.script.expect("the script checks");
    let scene = script.scene.clone().expect("a scene");
    let profile = Profile::builtin("ardrone2").expect("built in");
    let mut sim = SimConfig {
        effects: Effects::none(),
        ..SimConfig::new(5)
    };
    (sim.start_position_m, sim.start_heading_rad) =
        dronecine_runtime::start_pose(&script, &scene, &profile, &sim);
    let data = std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a free port");
    let config = EmulatorConfig {
        at_port: 0,
        navdata_port: 0,
        natnet: Some(NatNetConfig {
            command_port: 0,
            data: NatNetData::Unicast(data),
            ..NatNetConfig::default()
        }),
        sim,
        ..EmulatorConfig::new(profile, scene, 5)
    };
    let e = Emulator::start(config).expect("the emulator starts");
    let drone = format!(
        "ardrone://127.0.0.1:{}:{}",
        e.at_addr().port(),
        e.navdata_addr().port()
    );
    let command = e.natnet_command_addr().expect("NatNet").port();
    let mocap = format!(
        "natnet://127.0.0.1:{command}?unicast&data_port={}",
        data.port()
    );
    (e, drone, mocap)
}

/// `dronecine shoot SCRIPT` against the emulator, its log in `dir`.
fn shoot(dir: &std::path::Path, drone: &str, mocap: &str) -> Child {
    let script = dir.join("s.psl");
    std::fs::write(&script, SCRIPT).expect("the script is written");
    Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(["shoot", script.to_str().unwrap(), "-q"])
        .args(["--drone", drone, "--mocap", mocap])
        .args(["--log", dir.join("f.mcap").to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("shoot starts")
}

/// Waits until `ready` holds of the emulator's status (at most 20 s).
fn wait_for(e: &EmulatorHandle, what: &str, ready: impl Fn(&dronecine_emulator::Status) -> bool) {
    let start = Instant::now();
    while !ready(&e.status()) {
        assert!(start.elapsed() < Duration::from_secs(20), "never {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Sends `signal` to the child.
fn send(child: &Child, signal: i32) -> Instant {
    let at = Instant::now();
    // SAFETY: kill(2) with the child's pid and a signal number; no memory is touched.
    let r = unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    assert_eq!(r, 0, "kill");
    at
}

/// Seconds from `sent` until `arrived` is set in the emulator's status (at most 5 s).
fn delay(
    e: &EmulatorHandle,
    sent: Instant,
    arrived: impl Fn(&dronecine_emulator::Status) -> Option<Instant>,
) -> Option<f64> {
    while sent.elapsed() < Duration::from_secs(5) {
        if let Some(at) = arrived(&e.status()) {
            return Some(at.saturating_duration_since(sent).as_secs_f64());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    None
}

/// Flies, waits for `phase`, sends `first` then `second` if any (a tenth of a second later:
/// a drone interrupted low in its take-off lands within a second); returns the land delay,
/// the cut delay and what `shoot` said.
fn interrupt(phase: &str, first: i32, second: Option<i32>) -> (Option<f64>, Option<f64>, String) {
    let dir = crate::common::temp_dir(&format!("signals-{phase}-{first}"));
    let (e, drone, mocap) = emulator();
    let child = shoot(&dir, &drone, &mocap);
    match phase {
        // Half a metre up: high enough that it is still landing at the second signal.
        "take-off" => wait_for(&e, "taking off", |s| {
            s.truth.state == FlightState::TakingOff && s.truth.position_m[2] > 0.5
        }),
        _ => {
            // The approach and the settle take a few seconds after take-off: the shots run
            // from about 4 s after the drone flies.
            wait_for(&e, "flying", |s| s.truth.state == FlightState::Flying);
            std::thread::sleep(Duration::from_secs(5));
        }
    }
    let sent = send(&child, first);
    let land = delay(&e, sent, |s| s.first_land_at);
    let cut = second.and_then(|second| {
        std::thread::sleep(Duration::from_millis(100));
        let sent = send(&child, second);
        delay(&e, sent, |s| s.first_cut_at)
    });
    let out = child.wait_with_output().expect("shoot ends");
    (land, cut, String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn ctrl_c_lands_and_cuts_the_motors_at_once_in_take_off_and_in_the_shots() {
    for phase in ["take-off", "shots"] {
        let (land, cut, said) = interrupt(phase, libc::SIGINT, Some(libc::SIGINT));
        let land = land.unwrap_or_else(|| panic!("{phase}: never landed: {said}"));
        let cut = cut.unwrap_or_else(|| panic!("{phase}: the motors never cut: {said}"));
        eprintln!(
            "{phase}: Ctrl-C to land on the wire {:.1} ms, second Ctrl-C to motor cut {:.1} ms",
            land * 1e3,
            cut * 1e3
        );
        assert!(
            land < PROMPT_S && cut < PROMPT_S,
            "{phase}: {land} s, {cut} s"
        );
        assert!(said.contains("emergency motor cut"), "{phase}: {said}");
    }
}

#[test]
fn sigterm_and_sighup_land_like_one_ctrl_c_and_never_cut_the_motors() {
    for (phase, signal, name) in [
        ("shots", libc::SIGTERM, "SIGTERM"),
        ("take-off", libc::SIGHUP, "SIGHUP"),
    ] {
        let (land, cut, said) = interrupt(phase, signal, Some(signal));
        let land = land.unwrap_or_else(|| panic!("{name}: never landed: {said}"));
        eprintln!("{phase}: {name} to land on the wire {:.1} ms", land * 1e3);
        assert!(land < PROMPT_S, "{name}: {land} s");
        assert_eq!(cut, None, "{name} twice must not cut the motors: {said}");
        assert!(!said.contains("motor cut"), "{name}: {said}");
    }
}
