//! The hardware a flight flies: the drone's address (the AR.Drone's protocol, MAVLink's or
//! the Crazyflie's CRTP),
//! the motion capture's (NatNet, or the truth of ArduPilot's simulator), and the backends
//! connected from them, ready for the flight loop.
//!
//! An ArduPilot vehicle is prepared before the flight: its parameters are checked (a wrong
//! one refuses the flight, named with the value it needs), the EKF's origin is set, and the
//! motion capture is forwarded to it until it reports navigating on it; during the flight
//! every pose of the drone the flight reads is forwarded as well ([`Forwarding`]). A Crazyflie
//! is given the motion capture the same way, as its estimator's external pose, until its
//! estimate agrees with it.

use std::time::Duration;

use dronecine_ardrone::client::{ArDroneClient, ArDroneOptions};
use dronecine_ardrone::url::ArDroneUrl;
use dronecine_backend::clock::WallClock;
use dronecine_backend::{BackendError, Backends, BodyPose, Drone, Mocap, MocapFrame};
use dronecine_compiler::blocking::Blocking;
use dronecine_crazyflie::{CrazyflieDrone, CrazyflieOptions, CrazyflieUrl};
use dronecine_grammar::script::{Scene, Script};
use dronecine_mavlink::{MavlinkDrone, MavlinkOptions, MavlinkUrl, PoseForwarder};
use dronecine_natnet::client::{NatNetClient, NatNetOptions};
use dronecine_natnet::rig::Rig;
use dronecine_natnet::url::NatNetUrl;
use dronecine_profile::Profile;
use dronecine_sim::SimConfig;

use crate::SessionError;

/// A drone's address: `ardrone://…`, `mavlink://…` or `crazyflie+…://…`.
#[derive(Clone, Debug, PartialEq)]
pub enum DroneUrl {
    ArDrone(ArDroneUrl),
    Mavlink(MavlinkUrl),
    Crazyflie(CrazyflieUrl),
}

impl DroneUrl {
    /// Parses either scheme; the error names both when the scheme is neither.
    pub fn parse(text: &str) -> Result<DroneUrl, String> {
        if text.starts_with("mavlink:") {
            MavlinkUrl::parse(text)
                .map(DroneUrl::Mavlink)
                .map_err(|e| e.to_string())
        } else if text.starts_with("crazyflie") {
            CrazyflieUrl::parse(text)
                .map(DroneUrl::Crazyflie)
                .map_err(|e| e.to_string())
        } else if text.starts_with("ardrone:") {
            ArDroneUrl::parse(text)
                .map(DroneUrl::ArDrone)
                .map_err(|e| e.to_string())
        } else {
            Err(format!(
                "`{text}` is not a drone address: write `ardrone://HOST` (an AR.Drone 2.0) or \
                 `mavlink://udp:HOST:PORT`, `mavlink://tcp:HOST:PORT`, \
                 `mavlink:///dev/PORT?baud=N` (an ArduPilot Copter), \
                 `crazyflie+radio://N/CHANNEL/RATE/ADDRESS` or `crazyflie+udp://HOST:PORT` (a \
                 Crazyflie)"
            ))
        }
    }
}

impl std::fmt::Display for DroneUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DroneUrl::ArDrone(u) => u.fmt(f),
            DroneUrl::Mavlink(u) => u.fmt(f),
            DroneUrl::Crazyflie(u) => u.fmt(f),
        }
    }
}

/// Where the positions come from.
#[derive(Clone, Debug, PartialEq)]
pub enum MocapUrl {
    /// An OptiTrack (or compatible) NatNet server.
    NatNet(NatNetUrl),
    /// `sitl`: ArduPilot's simulator's truth (SIM_STATE) for the drone, and the actors
    /// walking their blocking as the script writes it: software in the loop, no motion
    /// capture. Only with a `mavlink://` drone.
    SitlTruth,
}

impl MocapUrl {
    /// `sitl`, or a NatNet address.
    pub fn parse(text: &str) -> Result<MocapUrl, String> {
        if text == "sitl" {
            return Ok(MocapUrl::SitlTruth);
        }
        NatNetUrl::parse(text)
            .map(MocapUrl::NatNet)
            .map_err(|e| format!("{e} (or `sitl`: ArduPilot's simulator's truth)"))
    }
}

impl std::fmt::Display for MocapUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MocapUrl::NatNet(u) => u.fmt(f),
            MocapUrl::SitlTruth => f.write_str("sitl"),
        }
    }
}

/// A real drone, its positions, and how they meet.
#[derive(Clone, Debug)]
pub struct HardwareTarget {
    pub drone: DroneUrl,
    pub mocap: MocapUrl,
    /// Rigid-body ids of the drone and the actors, and the mocap's axes (NatNet).
    pub rig: Rig,
    /// Send the drone's motion-capture pose to an ArduPilot vehicle's EKF (on by default;
    /// `--no-forward-mocap`).
    pub forward_mocap: bool,
}

/// How long an ArduPilot vehicle may take to navigate on the forwarded motion capture.
const EXTERNAL_NAV_TIMEOUT: Duration = Duration::from_secs(30);

/// How long an ArduPilot vehicle that navigates may take to confirm its EKF origin.
const ORIGIN_TIMEOUT: Duration = Duration::from_secs(10);

/// How long an ArduPilot vehicle may take to pass its pre-arm checks once it navigates (its
/// EKF settles on the motion capture).
const PREARM_TIMEOUT: Duration = Duration::from_secs(60);

/// The stream rate asked of an ArduPilot vehicle whose truth is the motion capture (SITL):
/// the flight's positions come at this rate.
const TRUTH_HZ: f64 = 100.0;

/// How long a Crazyflie's estimate may take to agree with the motion capture it is given.
const ESTIMATE_TIMEOUT: Duration = Duration::from_secs(10);

/// How near the motion capture a Crazyflie's estimate must be before it flies.
const ESTIMATE_WITHIN_M: f64 = 0.05;

/// The backends of a flight on hardware, connected, and the wall clock they share.
pub struct Hardware {
    pub drone: Box<dyn Drone>,
    pub mocap: Box<dyn Mocap>,
    /// Its epoch is the mocap's: frames are timestamped on arrival on the flight's clock.
    pub clock: WallClock,
}

impl Hardware {
    /// The three as the flight loop (or the calibration) takes them.
    pub fn backends(&mut self) -> Backends<'_> {
        Backends {
            drone: self.drone.as_mut(),
            mocap: self.mocap.as_mut(),
            clock: &mut self.clock,
        }
    }
}

/// Connects to the motion capture and the drone of `target` (the actors of `flight`'s scene,
/// none without one), giving an AR.Drone the profile's limits and preparing an ArduPilot
/// vehicle (module docs). The clock starts now and is the mocap's epoch. With `sitl`, the
/// simulated vehicle's home is the stage spot a simulated flight of the script starts from
/// ([`crate::start_pose`]; the stage's origin without a script).
pub fn connect_hardware(
    target: &HardwareTarget,
    flight: Option<(&Script, &Scene)>,
    profile: &Profile,
) -> Result<Hardware, SessionError> {
    let scene = flight.map(|(_, scene)| scene);
    let clock = WallClock::new();
    let setup = |e: BackendError| SessionError::Setup(format!("drone: {e}"));
    match &target.drone {
        DroneUrl::ArDrone(url) => {
            let mocap = natnet(target, scene, &clock)?;
            let drone =
                ArDroneClient::connect(url, profile, &ArDroneOptions::default()).map_err(setup)?;
            Ok(Hardware {
                drone: Box::new(drone),
                mocap,
                clock,
            })
        }
        DroneUrl::Mavlink(url) => {
            let truth = target.mocap == MocapUrl::SitlTruth;
            let defaults = MavlinkOptions::default();
            let options = MavlinkOptions {
                stream_hz: if truth { TRUTH_HZ } else { 20.0 },
                origin: url
                    .origin
                    .map_or(defaults.origin, |[lat_deg, lon_deg, alt_m]| {
                        dronecine_mavlink::GeoOrigin {
                            lat_deg,
                            lon_deg,
                            alt_m,
                        }
                    }),
                ..defaults
            };
            let mut drone = MavlinkDrone::connect(url, options).map_err(setup)?;
            let mocap: Box<dyn Mocap> = if truth {
                let at_m = flight.map_or([0.0; 3], |(script, scene)| {
                    crate::start_pose(script, scene, profile, &SimConfig::new(0)).0
                });
                let mocap = drone.truth_mocap(at_m, clock.epoch());
                Box::new(ScriptedActors::new(mocap, scene))
            } else {
                natnet(target, scene, &clock)?
            };
            let mocap = prepare_ardupilot(&mut drone, mocap, target.forward_mocap)?;
            Ok(Hardware {
                drone: Box::new(drone),
                mocap,
                clock,
            })
        }
        DroneUrl::Crazyflie(url) => {
            let mocap = natnet(target, scene, &clock)?;
            let mut drone = CrazyflieDrone::connect(url, profile, CrazyflieOptions::default())
                .map_err(setup)?;
            let mocap = prepare_crazyflie(&mut drone, mocap, target.forward_mocap)?;
            Ok(Hardware {
                drone: Box::new(drone),
                mocap,
                clock,
            })
        }
    }
}

/// With `forward`, gives a Crazyflie's estimator the motion capture (the Kalman estimator
/// restarted on it) until its estimate agrees within [`ESTIMATE_WITHIN_M`]; the motion
/// capture then goes on forwarding in the flight.
fn prepare_crazyflie(
    drone: &mut CrazyflieDrone,
    mut mocap: Box<dyn Mocap>,
    forward: bool,
) -> Result<Box<dyn Mocap>, SessionError> {
    if !forward {
        return Ok(mocap);
    }
    let refused = |e: BackendError| SessionError::Setup(format!("drone: {e}"));
    let mut forwarder = drone.forwarder();
    let mut frame = MocapFrame::default();
    let mut forward = |_: &mut CrazyflieDrone| -> Result<Option<[f64; 3]>, BackendError> {
        if mocap.poll(&mut frame)? {
            if let Some(pose) = frame.drone {
                forwarder.forward(frame.t_s, &pose)?;
            }
        }
        Ok(frame.drone.map(|p| p.position_m))
    };
    // Some poses first, so that the restarted estimator starts from them.
    drone
        .wait_for_estimate(f64::INFINITY, ESTIMATE_TIMEOUT, &mut forward)
        .map_err(refused)?;
    drone.reset_estimator().map_err(refused)?;
    drone
        .wait_for_estimate(ESTIMATE_WITHIN_M, ESTIMATE_TIMEOUT, &mut forward)
        .map_err(refused)?;
    Ok(Box::new(Forwarding {
        inner: mocap,
        forwarder: Box::new(forwarder),
    }))
}

/// The NatNet client of `target` (an error for `sitl`, which only an ArduPilot simulator
/// gives).
fn natnet(
    target: &HardwareTarget,
    scene: Option<&Scene>,
    clock: &WallClock,
) -> Result<Box<dyn Mocap>, SessionError> {
    let MocapUrl::NatNet(url) = &target.mocap else {
        return Err(SessionError::Setup(
            "motion capture: `--mocap sitl` is ArduPilot's simulator's truth: it needs a \
             `mavlink://` drone"
                .into(),
        ));
    };
    let options = NatNetOptions {
        epoch: clock.epoch(),
        ..NatNetOptions::default()
    };
    let names = scene.map_or(Vec::new(), |s| {
        s.actors.iter().map(|a| a.name.as_str()).collect()
    });
    let client = NatNetClient::connect(url, &target.rig, names, &options)
        .map_err(|e| SessionError::Setup(format!("motion capture: {e}")))?;
    Ok(Box::new(client))
}

/// Checks an ArduPilot vehicle's parameters, sets its EKF's origin and, with `forward`,
/// forwards the motion capture until the autopilot navigates on it; the motion capture
/// then goes on forwarding in the flight.
fn prepare_ardupilot(
    drone: &mut MavlinkDrone,
    mut mocap: Box<dyn Mocap>,
    forward: bool,
) -> Result<Box<dyn Mocap>, SessionError> {
    let refused = |e: BackendError| SessionError::Setup(format!("drone: {e}"));
    let check = drone.check_parameters().map_err(refused)?;
    if !check.passed() {
        return Err(SessionError::Setup(format!("drone: {}", check.refusal())));
    }
    // Read now, so that the take-off does not wait for them in the flight's loop.
    drone.limits().map_err(refused)?;
    if !forward {
        return Ok(mocap);
    }
    drone.set_origin().map_err(refused)?;
    let mut forwarder = drone.forwarder();
    let mut frame = MocapFrame::default();
    // The motion capture's newest pose of the drone, forwarded while the autopilot is waited
    // for.
    let mut forward = |_: &mut MavlinkDrone| -> Result<(), BackendError> {
        if mocap.poll(&mut frame)? {
            if let Some(pose) = frame.drone {
                forwarder.forward(frame.t_s, &pose)?;
            }
        }
        Ok(())
    };
    drone
        .wait_for_external_nav(EXTERNAL_NAV_TIMEOUT, &mut forward)
        .map_err(refused)?;
    drone
        .wait_for_origin(ORIGIN_TIMEOUT, &mut forward)
        .map_err(refused)?;
    drone
        .wait_for_prearm(PREARM_TIMEOUT, &mut forward)
        .map_err(refused)?;
    Ok(Box::new(Forwarding {
        inner: mocap,
        forwarder: Box::new(forwarder),
    }))
}

/// Where [`Forwarding`] sends the drone's poses: an autopilot's EKF, a Crazyflie's estimator.
pub trait PoseSink {
    /// Sends the pose captured at `t_s` unless the last went out too recently: `true` when
    /// sent.
    fn forward(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError>;
}

impl PoseSink for PoseForwarder {
    fn forward(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError> {
        PoseForwarder::forward(self, t_s, pose)
    }
}

impl PoseSink for dronecine_crazyflie::PoseForwarder {
    fn forward(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError> {
        dronecine_crazyflie::PoseForwarder::forward(self, t_s, pose)
    }
}

/// A motion capture that sends each pose of the drone it gives to the drone as well.
pub struct Forwarding {
    inner: Box<dyn Mocap>,
    forwarder: Box<dyn PoseSink>,
}

impl Mocap for Forwarding {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        let fresh = self.inner.poll(frame)?;
        if let (true, Some(pose)) = (fresh, frame.drone) {
            // A link that fails here fails for the commands too: the drone's link failsafe
            // acts on it; the flight's positions are not lost for it.
            let _ = self.forwarder.forward(frame.t_s, &pose);
        }
        Ok(fresh)
    }

    fn action(&mut self, t_s: f64) {
        self.inner.action(t_s);
    }
}

/// The actors of a scene walking their blocking from "Action!" (standing on their marks
/// before), added to the frames of a motion capture that sees only the drone.
pub struct ScriptedActors<M> {
    inner: M,
    blocking: Option<Blocking>,
    action_s: Option<f64>,
}

impl<M: Mocap> ScriptedActors<M> {
    pub fn new(inner: M, scene: Option<&Scene>) -> ScriptedActors<M> {
        ScriptedActors {
            inner,
            blocking: scene.map(Blocking::new),
            action_s: None,
        }
    }
}

impl<M: Mocap> Mocap for ScriptedActors<M> {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        let fresh = self.inner.poll(frame)?;
        if fresh {
            frame.actors.clear();
            if let Some(blocking) = &self.blocking {
                let script_s = self.action_s.map_or(0.0, |a| (frame.t_s - a).max(0.0));
                for i in 0..blocking.len() {
                    let p = blocking.pose(i, script_s);
                    frame.actors.push(Some(BodyPose {
                        position_m: p.position_m,
                        heading_rad: p.facing_rad,
                    }));
                }
            }
        }
        Ok(fresh)
    }

    fn action(&mut self, t_s: f64) {
        self.action_s = Some(t_s);
        self.inner.action(t_s);
    }
}
