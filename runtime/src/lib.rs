//! A whole flight, set up from a script and wired: on the embedded simulator
//! ([`fly_simulated`]: what `dronecine shoot` flies by default, and what the tests and
//! benchmarks fly) or on a real AR.Drone 2.0 with OptiTrack NatNet — or the emulator that
//! speaks their protocols ([`fly_hardware`], its backends connected by [`connect_hardware`],
//! which `calibrate` flies too). This crate is where the backends meet the flight loop: the
//! loop's own crate knows none of them.

use dronecine_backend::clock::Paced;
use dronecine_backend::{Backends, Clock};
use dronecine_compiler::blocking::Blocking;
use dronecine_compiler::director::Director;
use dronecine_flight::report::FlightReport;
use dronecine_flight::{self as flight, FlightError, FlightSetup, Observer, Safety};
use dronecine_grammar::script::{Scene, Script};
use dronecine_mcap::record::FlightSink;
use dronecine_profile::Profile;
use dronecine_servo::control::Controller;
use dronecine_servo::setup::{controller_for, ControllerSetup};
use dronecine_sim::{SimConfig, Simulator};

pub mod hardware;
pub use hardware::{connect_hardware, DroneUrl, Hardware, HardwareTarget, MocapUrl};

/// Where the drone simulated by `sim` waits on the floor: below the first framing (against
/// the actors' opening marks), facing the way it will film; but never nearer an actor's mark
/// than the profile's actor distance, [`SimConfig::actor_reach_m`] (how far off their marks
/// the simulated actors stand) and [`SimConfig::takeoff_drift_m`] (how far it drifts taking
/// off) more, nor nearer a wall than the stage's margin or the take-off drift, whichever is
/// more (but never more than half the stage). There it stands at the nearest spot that is
/// clear ([`clear_spot`]); on a stage with no such spot, the nearest clear of the actors
/// without the drift (the approach then moves it out of an actor's distance it drifted
/// into).
///
/// The take-off is the drone's own, not the servo's, and gusts push it: standing clear of
/// the drift keeps the drone out of the actors' way until the approach takes over. Below a
/// close-up the spot under the framing is under an actor's nose, which `shoot`'s pre-flight
/// check refuses ("place the drone further away"), and on the simulator nobody can move it: the
/// spot is chosen clear instead.
pub fn start_pose(
    script: &Script,
    scene: &Scene,
    profile: &Profile,
    sim: &SimConfig,
) -> ([f64; 3], f64) {
    let blocking = Blocking::new(scene);
    let marks = blocking.poses(0.0);
    let first = Director::new(script, scene, profile).step(0.0, &marks);
    let marks: Vec<[f64; 2]> = (marks.iter())
        .map(|a| [a.position_m[0], a.position_m[1]])
        .collect();
    let (lo, hi) = (scene.stage.min_m(), scene.stage.max_m());
    let wall_m = profile.safety.stage_margin_m.max(sim.takeoff_drift_m());
    let inset = |i: usize| wall_m.min((hi[i] - lo[i]) / 2.0);
    let below = [first.position_m[0], first.position_m[1]];
    let (floor_lo, floor_hi) = (
        [lo[0] + inset(0), lo[1] + inset(1)],
        [hi[0] - inset(0), hi[1] - inset(1)],
    );
    let near_m = profile.safety.actor_distance_m + sim.actor_reach_m().max(0.0);
    let drifting_m = near_m + sim.takeoff_drift_m();
    // No spot at all (a stage too small for its actors): below the framing, and the
    // pre-flight check says why.
    let [x, y] = clear_spot(below, &marks, drifting_m, floor_lo, floor_hi)
        .or_else(|| clear_spot(below, &marks, near_m, floor_lo, floor_hi))
        .unwrap_or(below);
    ([x, y, 0.0], first.heading_rad)
}

/// The nearest spot to `spot` at least `keep_m` from every mark and inside the floor's box
/// `lo..hi`: `spot` itself when it is, else the first found on rings around it, 2 cm apart,
/// each searched from the direction away from the nearest mark. `None` when no spot is (a
/// stage too small for its actors).
pub fn clear_spot(
    spot: [f64; 2],
    marks: &[[f64; 2]],
    keep_m: f64,
    lo: [f64; 2],
    hi: [f64; 2],
) -> Option<[f64; 2]> {
    let clear = |p: [f64; 2]| {
        (0..2).all(|i| p[i] >= lo[i] && p[i] <= hi[i])
            && marks
                .iter()
                .all(|m| dronecine_math::hypot(p[0] - m[0], p[1] - m[1]) >= keep_m)
    };
    if clear(spot) {
        return Some(spot);
    }
    let away = marks
        .iter()
        .map(|m| (dronecine_math::hypot(spot[0] - m[0], spot[1] - m[1]), m))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(0.0, |(_, m)| {
            dronecine_math::atan2(spot[1] - m[1], spot[0] - m[0])
        });
    const STEP_M: f64 = 0.02;
    const DIRECTIONS: i32 = 72;
    let reach_m = dronecine_math::hypot(hi[0] - lo[0], hi[1] - lo[1]);
    let rings = (reach_m / STEP_M).ceil().min(2000.0) as i32;
    for ring in 1..=rings {
        let r = f64::from(ring) * STEP_M;
        // Away from the nearest mark first, then turning either way: 0, +1, −1, +2, …, +36.
        for j in 0..DIRECTIONS {
            let k = if j % 2 == 1 { (j + 1) / 2 } else { -(j / 2) };
            let a = away + f64::from(k) * std::f64::consts::TAU / f64::from(DIRECTIONS);
            let (sin, cos) = dronecine_math::sin_cos(a);
            let p = [spot[0] + r * cos, spot[1] + r * sin];
            if clear(p) {
                return Some(p);
            }
        }
    }
    None
}

pub struct SimFlight<'a> {
    pub script: &'a Script,
    pub source: &'a str,
    pub scene: &'a Scene,
    pub profile: &'a Profile,
    pub rate_hz: f64,
    pub controller: ControllerSetup,
    /// The drone the simulator truly is, when it is not the one the servo flies with
    /// (`profile`): a calibrated profile flown on the nominal plant, a wrong guess of a model.
    pub plant: Option<&'a Profile>,
    /// Seed and effects; the start pose is set by [`fly_simulated`] from [`start_pose`].
    pub sim: SimConfig,
    /// Keep to the wall clock.
    pub realtime: bool,
    /// Ctrl-C presses, counted by the caller's signal handler (see `FlightSetup`).
    pub interrupts: Option<&'a std::sync::atomic::AtomicU32>,
}

#[derive(Debug)]
pub enum SessionError {
    /// The controller or the simulator cannot be set up.
    Setup(String),
    Flight(FlightError),
}

impl std::fmt::Display for SessionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SessionError::Setup(m) => f.write_str(m),
            SessionError::Flight(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for SessionError {}

/// Whether a simulated flight gains by stepping its director on a thread of its own
/// ([`SimConfig::actors_ahead`]): when the machine has a second core, the director's thread
/// steps the director and computes the actors while the loop flies its ticks (the same
/// flight, bit for bit). On one core the threads only take turns. `shoot` asks it.
pub fn director_thread_pays() -> bool {
    std::thread::available_parallelism().is_ok_and(|n| n.get() >= 2)
}

/// The servo a flight runs, or why it cannot.
fn servo(
    setup: &ControllerSetup,
    profile: &Profile,
    rate_hz: f64,
) -> Result<Box<dyn Controller>, SessionError> {
    controller_for(setup, profile, rate_hz)
        .map_err(|e| SessionError::Setup(format!("the servo cannot be set up: {e}")))
}

/// What the flight loop needs of a simulated or hardware flight (default safety limits).
fn flight_setup<'a>(
    script: &'a Script,
    source: &'a str,
    scene: &'a Scene,
    profile: &'a Profile,
    rate_hz: f64,
    interrupts: Option<&'a std::sync::atomic::AtomicU32>,
) -> FlightSetup<'a> {
    FlightSetup {
        script,
        source,
        scene,
        profile,
        rate_hz,
        safety: Safety::default(),
        interrupts,
    }
}

pub fn fly_simulated(
    f: &SimFlight,
    sink: &mut dyn FlightSink,
    observer: &mut dyn Observer,
) -> Result<FlightReport, SessionError> {
    let mut controller = servo(&f.controller, f.profile, f.rate_hz)?;
    let mut config = f.sim.clone();
    (config.start_position_m, config.start_heading_rad) =
        start_pose(f.script, f.scene, f.profile, &config);
    // The actors wait on their marks until the flight loop's "action!".
    config.wait_for_action = true;
    let sim = Simulator::new(&config, f.plant.unwrap_or(f.profile), f.scene)
        .map_err(|e| SessionError::Setup(format!("the simulator cannot be set up: {e}")))?;
    let (mut drone, mut mocap) = (sim.drone(), sim.mocap());
    let (mut paced, mut plain);
    let clock: &mut dyn Clock = if f.realtime {
        paced = Paced::new(sim.clock());
        &mut paced
    } else {
        plain = sim.clock();
        &mut plain
    };
    let setup = flight_setup(
        f.script,
        f.source,
        f.scene,
        f.profile,
        f.rate_hz,
        f.interrupts,
    );
    flight::fly(
        &setup,
        controller.as_mut(),
        Backends {
            drone: &mut drone,
            mocap: &mut mocap,
            clock,
        },
        sink,
        observer,
    )
    .map(|mut report| {
        // A simulated clock waits for nothing: its ticks' lateness says nothing.
        if !f.realtime {
            report.lateness = None;
        }
        report
    })
    .map_err(SessionError::Flight)
}

/// A flight on hardware: the drone over its protocol, positions from the motion capture,
/// paced by the wall clock.
pub struct HardwareFlight<'a> {
    pub script: &'a Script,
    pub source: &'a str,
    pub scene: &'a Scene,
    pub profile: &'a Profile,
    pub rate_hz: f64,
    pub controller: ControllerSetup,
    pub target: &'a HardwareTarget,
    pub interrupts: Option<&'a std::sync::atomic::AtomicU32>,
}

pub fn fly_hardware(
    f: &HardwareFlight,
    sink: &mut dyn FlightSink,
    observer: &mut dyn Observer,
) -> Result<FlightReport, SessionError> {
    let mut controller = servo(&f.controller, f.profile, f.rate_hz)?;
    let mut hw = connect_hardware(f.target, Some((f.script, f.scene)), f.profile)?;
    let setup = flight_setup(
        f.script,
        f.source,
        f.scene,
        f.profile,
        f.rate_hz,
        f.interrupts,
    );
    flight::fly(&setup, controller.as_mut(), hw.backends(), sink, observer)
        .map_err(SessionError::Flight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_backend::{FlightState, MocapFrame};
    use dronecine_emulator::{empty_scene, Emulator, EmulatorConfig, NatNetConfig, NatNetData};
    use dronecine_sim::Effects;
    use std::net::UdpSocket;

    fn ardrone2() -> Profile {
        Profile::builtin("ardrone2").unwrap()
    }

    /// The simulated drone takes off clear of an actor's mark by the actor distance, the
    /// actors' reach and its take-off drift; where the stage has no such spot (6 × 3 m: the
    /// walls keep it within 0.3 m of the middle line), clear by the distance and the reach.
    #[test]
    fn the_drone_waits_clear_of_its_take_off_drift_where_the_stage_allows() {
        let profile = ardrone2();
        let sim = SimConfig::new(1);
        let near_m = profile.safety.actor_distance_m + sim.actor_reach_m();
        let drifting_m = near_m + sim.takeoff_drift_m();
        assert!(sim.takeoff_drift_m() > 1.0, "{}", sim.takeoff_drift_m());
        let waits = |stage: &str| {
            let text = format!(
                "{stage}\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
                 MS on A front for 4s\n"
            );
            let opts = dronecine_grammar::Options {
                known_drones: dronecine_profile::BUILTIN_NAMES,
                base_dir: None,
            };
            let script = dronecine_grammar::check(&text, &opts).script.unwrap();
            let scene = script.scene.as_ref().unwrap();
            let (p, _) = start_pose(&script, scene, &profile, &sim);
            p[0].hypot(p[1])
        };
        let wide = waits("stage 10m x 8m x 3m");
        assert!(wide >= drifting_m - 1e-9, "{wide}");
        let narrow = waits("stage 6m x 3m x 3m");
        assert!(narrow >= near_m - 1e-9 && narrow < drifting_m, "{narrow}");
    }

    /// The simulated drone's spot: below the framing when that is clear, else the nearest
    /// clear spot, away from the actor first, inside the box, never on another mark.
    #[test]
    fn the_drone_waits_at_the_nearest_spot_clear_of_every_mark() {
        let (lo, hi) = ([-3.7, -2.7], [3.7, 2.7]);
        let dist = |p: [f64; 2], m: [f64; 2]| (p[0] - m[0]).hypot(p[1] - m[1]);
        // Clear: unchanged, bit for bit.
        let spot = [1.234, -0.5];
        assert_eq!(clear_spot(spot, &[[0.0, 0.0]], 0.7, lo, hi), Some(spot));
        // 0.3 m east of a mark: straight away from it, to the first ring past 0.7 m.
        let p = clear_spot([0.3, 0.0], &[[0.0, 0.0]], 0.7, lo, hi).unwrap();
        assert!(
            p[1].abs() < 1e-12 && p[0] >= 0.7 && p[0] < 0.7 + 0.021,
            "{p:?}"
        );
        // Between two marks 1 m apart: clear of both (sideways).
        let marks = [[-0.5, 0.0], [0.5, 0.0]];
        let p = clear_spot([0.1, 0.0], &marks, 0.7, lo, hi).unwrap();
        assert!(marks.iter().all(|&m| dist(p, m) >= 0.7), "{p:?}");
        assert!(dist(p, [0.1, 0.0]) < 0.6, "the nearest: {p:?}");
        // Against a wall, away from the mark is out of the box: along it instead.
        let p = clear_spot([3.6, 0.0], &[[3.3, 0.0]], 0.7, lo, hi).unwrap();
        assert!(p[0] <= hi[0] && dist(p, [3.3, 0.0]) >= 0.7, "{p:?}");
        // No spot is clear (a box inside the keep-out).
        let p = clear_spot([0.1, 0.0], &[[0.0, 0.0]], 5.0, [-1.0, -1.0], [1.0, 1.0]);
        assert_eq!(p, None);
    }

    #[test]
    fn connect_hardware_refuses_an_actor_without_a_rigid_body_before_any_traffic() {
        // Nothing listens on these ports: the rig check must come first.
        let target = HardwareTarget {
            drone: DroneUrl::parse("ardrone://127.0.0.1:9:9").unwrap(),
            mocap: MocapUrl::parse("natnet://127.0.0.1:9?unicast").unwrap(),
            rig: dronecine_natnet::rig::Rig::numbered::<&str>(&[]),
            forward_mocap: true,
        };
        let text = "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) \
                    facing 0deg\nMS on A front for 4s\n";
        let opts = dronecine_grammar::Options {
            known_drones: dronecine_profile::BUILTIN_NAMES,
            base_dir: None,
        };
        let script = dronecine_grammar::check(text, &opts).script.unwrap();
        let scene = script.scene.as_ref().unwrap();
        let e = connect_hardware(&target, Some((&script, scene)), &ardrone2())
            .err()
            .expect("refused");
        let msg = e.to_string();
        assert!(
            matches!(e, SessionError::Setup(_)) && msg.starts_with("motion capture: "),
            "{msg}"
        );
        assert!(msg.contains("actor `A`"), "{msg}");
    }

    /// `--mocap sitl` is the truth of ArduPilot's simulator: with an AR.Drone it is refused
    /// before any traffic.
    #[test]
    fn sitl_truth_needs_a_mavlink_drone() {
        let target = HardwareTarget {
            drone: DroneUrl::parse("ardrone://127.0.0.1:9:9").unwrap(),
            mocap: MocapUrl::parse("sitl").unwrap(),
            rig: dronecine_natnet::rig::Rig::numbered::<&str>(&[]),
            forward_mocap: true,
        };
        let e = connect_hardware(&target, None, &ardrone2())
            .err()
            .expect("refused");
        assert!(e.to_string().contains("needs a `mavlink://` drone"), "{e}");
    }

    /// Each scheme parses; anything else names them all.
    #[test]
    fn drone_addresses_name_their_protocol() {
        assert!(matches!(
            DroneUrl::parse("ardrone://192.168.1.1"),
            Ok(DroneUrl::ArDrone(_))
        ));
        assert!(matches!(
            DroneUrl::parse("mavlink://tcp:127.0.0.1:5760"),
            Ok(DroneUrl::Mavlink(_))
        ));
        assert!(matches!(
            DroneUrl::parse("crazyflie+udp://127.0.0.1:19850"),
            Ok(DroneUrl::Crazyflie(_))
        ));
        let e = DroneUrl::parse("crazyflie://x").unwrap_err();
        assert!(e.contains("crazyflie+radio://"), "{e}");
        let e = DroneUrl::parse("tello://x").unwrap_err();
        assert!(
            e.contains("ardrone://") && e.contains("mavlink://") && e.contains("crazyflie+udp://"),
            "{e}"
        );
    }

    #[test]
    fn connect_hardware_timestamps_mocap_frames_on_the_flight_clock() {
        let data = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap();
        let config = EmulatorConfig {
            at_port: 0,
            navdata_port: 0,
            natnet: Some(NatNetConfig {
                command_port: 0,
                data: NatNetData::Unicast(data),
                ..NatNetConfig::default()
            }),
            sim: SimConfig {
                effects: Effects::none(),
                ..SimConfig::new(3)
            },
            ..EmulatorConfig::new(ardrone2(), empty_scene(), 3)
        };
        let emulator = Emulator::start(config).expect("the emulator starts");
        let target = HardwareTarget {
            drone: DroneUrl::parse(&format!(
                "ardrone://127.0.0.1:{}:{}",
                emulator.at_addr().port(),
                emulator.navdata_addr().port()
            ))
            .unwrap(),
            mocap: MocapUrl::parse(&format!(
                "natnet://127.0.0.1:{}?unicast&data_port={}",
                emulator.natnet_command_addr().unwrap().port(),
                data.port()
            ))
            .unwrap(),
            rig: dronecine_natnet::rig::Rig::numbered::<&str>(&[]),
            forward_mocap: true,
        };
        let mut hw =
            connect_hardware(&target, None, &ardrone2()).expect("connects to the emulator");
        let b = hw.backends();
        assert_eq!(b.drone.telemetry().state, FlightState::Landed);
        let mut frame = MocapFrame::default();
        let mut t = b.clock.now_s();
        let deadline = t + 3.0;
        while !b.mocap.poll(&mut frame).unwrap() {
            assert!(t < deadline, "no NatNet frame in 3 s");
            t += 0.01;
            b.clock.sleep_until(t);
        }
        // Arrival times are on the clock the flight ticks by (one epoch): not ahead of it,
        // and not from before it started.
        let now = b.clock.now_s();
        assert!(
            frame.received_s >= 0.0 && frame.received_s <= now,
            "received at {} s, clock at {now} s",
            frame.received_s
        );
        assert!(frame.drone.is_some(), "the drone is rigid body 1");
    }
}
