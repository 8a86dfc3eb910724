//! The boundary between the flight loop and the hardware: a [`Drone`] takes the generic
//! command, a [`Mocap`] gives timestamped poses, a [`Clock`] says what time it is and waits.
//!
//! The flight loop (`dronecine-flight`) knows the backends through these traits only; the
//! build enforces it (its crate depends on no backend crate). The embedded simulator
//! (`dronecine-sim`) implements all three over one shared world, its clock advancing the
//! physics, so a flight runs as fast as the CPU allows; real backends (AR.Drone over UDP,
//! NatNet, the wall clock) implement the same traits. No method allocates on the per-tick
//! path (`send`, `poll`, `now_s`, `sleep_until`, `telemetry`).
//!
//! - `frames`: **the axis and sign conventions** and the generic [`frames::Command`].
//! - `clock`: the wall clock and the paced clock.
//! - `address`: the pieces of `scheme://host:port` addresses every backend parses.

pub mod address;
pub mod clock;
pub mod frames;

use crate::frames::Command;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The drone's own view of its flight, as a backend reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FlightState {
    Landed,
    TakingOff,
    /// Flying and taking commands.
    Flying,
    Landing,
    /// Motors cut.
    Emergency,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Telemetry {
    pub state: FlightState,
    pub battery_percent: f64,
    /// Seconds since the backend last heard from the drone (0 for the simulator's link when
    /// up); the flight loop's failsafes read it.
    pub link_age_s: f64,
}

pub trait Drone {
    /// Asks for take-off; the drone climbs to its own hover height and reports `Flying`.
    fn take_off(&mut self) -> Result<(), BackendError>;
    fn land(&mut self) -> Result<(), BackendError>;
    /// Cuts the motors.
    fn emergency(&mut self) -> Result<(), BackendError>;
    /// The set-points to fly from now on (held until the next call or the drone's watchdog).
    fn send(&mut self, command: &Command) -> Result<(), BackendError>;
    /// Asks the drone to hold its position on its own (AR.Drone: PCMD with the progressive
    /// flag off).
    fn hover(&mut self) -> Result<(), BackendError>;
    fn telemetry(&mut self) -> Telemetry;
    /// Points the camera gimbal at `pitch_rad` (up positive, from level); a drone without a
    /// gimbal ignores it.
    fn point_camera(&mut self, _pitch_rad: f64) -> Result<(), BackendError> {
        Ok(())
    }
    /// The camera pitch the gimbal last reported (up positive), if the drone has a gimbal
    /// that reports one.
    fn camera_pitch_rad(&mut self) -> Option<f64> {
        None
    }
    /// Moves into `out` what the drone itself said or did since the last call (an
    /// autopilot's texts, a mode it chose, its failsafes), for the flight to show and log.
    fn messages(&mut self, _out: &mut Vec<DroneMessage>) {}
}

/// Something the drone itself said or did ([`Drone::messages`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DroneMessage {
    /// `error`, `warning` or `info`, as the flight's events.
    pub level: &'static str,
    pub text: String,
}

/// One tracked body: position and heading in the world frame (see `frames.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyPose {
    pub position_m: [f64; 3],
    pub heading_rad: f64,
}

/// One motion-capture frame. `poll` fills it in place (the actor vector keeps its capacity),
/// so reading a frame allocates nothing.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MocapFrame {
    /// Capture time on the flight clock (the [`Clock`]'s seconds).
    pub t_s: f64,
    /// When the frame reached this computer, on the flight clock (≥ `t_s`; equal in the
    /// simulator). The flight loop measures the mocap-to-command latency from it.
    pub received_s: f64,
    /// Increases by one per frame the mocap produced; a gap means frames were lost.
    pub frame: u64,
    /// `None` when the drone is not tracked in this frame.
    pub drone: Option<BodyPose>,
    /// One entry per scene actor, in the script's order; `None` when not tracked.
    pub actors: Vec<Option<BodyPose>>,
}

pub trait Mocap {
    /// Fills `frame` with the newest frame not yet returned; `false` when none has arrived
    /// since the last call (then `frame` is left as it was).
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError>;

    /// "Action!": the shots start now, at `t_s` on the flight clock. The simulator's actors
    /// start their blocking (the script's clock) from this moment; live actors take the cue
    /// from the set, so real backends ignore it.
    fn action(&mut self, _t_s: f64) {}

    /// The actors' part of the frames to come, if this motion capture knows it ahead of the
    /// flight's clock: a simulation's, whose actors do not depend on the drone (taken after
    /// [`Mocap::action`], it follows the cue). The flight then steps its director on a thread
    /// of its own, ahead of the loop. Real backends know nothing ahead.
    fn actors_ahead(&self) -> Option<Box<dyn ActorFeed>> {
        None
    }

    /// The flight tells the mocap that it takes the actors' part of each frame from a feed
    /// taken with [`Mocap::actors_ahead`] (`true`: the feed's frame of the same tick is the
    /// same frame, by that method's contract, and the flight checks that it is), or that it
    /// no longer does (`false`). A simulation then leaves the actors out of its own frames
    /// (`None`) instead of computing them a second time. Real backends ignore it.
    fn actors_from_feed(&mut self, _on: bool) {}
}

/// The actors' part of a motion capture's frames, read ahead of the flight
/// ([`Mocap::actors_ahead`]).
pub trait ActorFeed: Send {
    /// Fills `frame` as [`Mocap::poll`] would after the flight's clock slept until `t_s`
    /// (called with increasing `t_s`), the drone left out (`None`); `false` when no frame
    /// arrived since the last call.
    fn poll_at(&mut self, t_s: f64, frame: &mut MocapFrame) -> bool;
}

/// The hardware (or the simulator) a flight flies: the three boundaries together.
pub struct Backends<'a> {
    pub drone: &'a mut dyn Drone,
    pub mocap: &'a mut dyn Mocap,
    pub clock: &'a mut dyn Clock,
}

pub trait Clock {
    /// Seconds since the flight started.
    fn now_s(&mut self) -> f64;
    /// Returns at `t_s` or as soon after as the backend can (the simulator advances its
    /// world to `t_s`; a wall clock sleeps).
    fn sleep_until(&mut self, t_s: f64);
    /// How late, in seconds of wall time when the flight keeps to it, the clock returned
    /// from `sleep_until(t_s)`: what the report's timing and the live view's cost measure.
    fn lateness_s(&mut self, t_s: f64) -> f64 {
        self.now_s() - t_s
    }
}

/// What a backend reports when it cannot do what was asked.
#[derive(Clone, Debug, PartialEq)]
pub enum BackendError {
    /// The link to the drone or the mocap is down or a socket failed.
    Link(String),
    /// The drone refused (for example take-off with a low battery).
    Refused(String),
}

impl fmt::Display for BackendError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BackendError::Link(m) => write!(f, "link: {m}"),
            BackendError::Refused(m) => write!(f, "refused: {m}"),
        }
    }
}

impl std::error::Error for BackendError {}
