//! The flight loop behind `dronecine shoot`: pre-flight checks, take-off, the approach to the
//! first framing, the settle onto it, the shots with the online director, the flight back over
//! the take-off spot, landing, and the report; and `replay`, which re-runs a logged flight's
//! controller.
//!
//! One tick, at the loop's rate on the backend's clock (`flight`):
//! 1. wait for the tick time (the simulator advances its world; a wall clock sleeps);
//! 2. read the newest mocap frame: the drone's measured pose, the actors' poses (smoothed into
//!    velocity and turn rate for the director, `tracker`);
//! 3. the reference: a planned glide (`glide`) outside the shots; during the shots the online
//!    director re-solves the framing against the live actor poses (the same evaluator
//!    `compile` runs in batch), on a thread ahead of the loop when it can (`ahead`);
//! 4. the controller's tick, the failsafes, then the command (or a failsafe's) to the drone;
//! 5. metrics (`report`), the flight record to the [`FlightSink`], progress to the
//!    [`Observer`].
//!
//! The phases are one function each (`phases`, `preflight`). The loop knows the backend only
//! through `dronecine-backend`'s traits (this crate depends on no backend crate), and
//! allocates nothing per tick once started (events, which are rare, allocate their message).
//!
//! Replay rule (`replay`): the controller is reset once, with the first logged tick's
//! measurement at `t_s − dt_s`, and then given every logged [`TickInput`] in order.
//!
//! Failsafes (each logged as an event): a controller fault (NaN, time not increasing) →
//! hover for that tick; the drone's body not tracked for `mocap_hover_s` → hover, for
//! `mocap_land_s` → land; an actor's body not tracked as long, during the approach, the
//! shots or the flight back to the take-off spot, the same (the drone cannot keep clear of an
//! actor it does not see; an actor tracked again before the landing lets it fly on); the
//! drone outside the stage → land; battery below `battery_land_percent` → land; no telemetry
//! for `link_lost_s` → land; Ctrl-C → land, a second Ctrl-C → emergency motor cut.
//!
//! [`FlightSink`]: dronecine_mcap::record::FlightSink
//! [`TickInput`]: dronecine_servo::control::TickInput

mod ahead;
mod code;
mod findings;
mod flight;
mod glide;
pub mod lateness;
mod phases;
mod preflight;
pub mod replay;
pub mod report;
mod tracker;

use std::io;

use dronecine_backend::{BackendError, Backends};
use dronecine_diag::Diagnostic;
use dronecine_grammar::script::{Scene, Script};
use dronecine_mcap::record::{Event, FlightSink, Phase};
use dronecine_profile::Profile;
use dronecine_servo::control::Controller;
use serde::Serialize;

pub use code::PreflightCode;

use crate::flight::Flight;
use crate::report::FlightReport;

/// What a progress display shows, offered every tick.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub t_s: f64,
    pub phase: Phase,
    pub shot: Option<usize>,
    pub shots: usize,
    /// Where the shots are on the script's clock as written (0 before they start, held at a
    /// shot's start during a repositioning flight inserted before it, the script's end after
    /// the last: `Director::written_t_s`).
    pub script_t_s: f64,
    /// Script duration as written.
    pub script_duration_s: f64,
    /// Distance from the measured position to the reference, when measured.
    pub position_error_m: Option<f64>,
}

pub trait Observer {
    fn progress(&mut self, progress: &Progress);
    fn event(&mut self, _event: &Event) {}
}

pub struct NoObserver;

impl Observer for NoObserver {
    fn progress(&mut self, _: &Progress) {}
}

/// Thresholds of the failsafes and the pre-flight checks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Safety {
    /// The drone, or an actor during the approach, the shots or the flight back, not tracked
    /// this long → hover.
    pub mocap_hover_s: f64,
    /// The drone, or an actor during the approach, the shots or the flight back, not tracked
    /// this long → land.
    pub mocap_land_s: f64,
    /// Below this, no take-off, and a flying drone lands.
    pub battery_land_percent: f64,
    /// Pre-flight: the first mocap frame must arrive within this.
    pub mocap_wait_s: f64,
    pub take_off_timeout_s: f64,
    pub landing_timeout_s: f64,
    /// No telemetry from the drone for this long → land.
    pub link_lost_s: f64,
}

impl Default for Safety {
    fn default() -> Self {
        Safety {
            mocap_hover_s: 0.5,
            mocap_land_s: 2.0,
            battery_land_percent: 15.0,
            mocap_wait_s: 2.0,
            take_off_timeout_s: 10.0,
            landing_timeout_s: 15.0,
            link_lost_s: 1.0,
        }
    }
}

pub struct FlightSetup<'a> {
    pub script: &'a Script,
    /// The script's text (shot labels in the report).
    pub source: &'a str,
    pub scene: &'a Scene,
    pub profile: &'a Profile,
    /// Control rate.
    pub rate_hz: f64,
    pub safety: Safety,
    /// Interrupts (Ctrl-C) counted by the caller's signal handler: the first lands the
    /// drone, the second cuts the motors.
    pub interrupts: Option<&'a std::sync::atomic::AtomicU32>,
}

#[derive(Debug)]
pub enum FlightError {
    /// A pre-flight check refused the flight (or the take-off failed): the drone is on the
    /// ground. Each refusal is a `preflight::` diagnostic, placed in the script where it is
    /// about the script (an actor, the first shot).
    Preflight(Vec<Diagnostic>),
    Backend(BackendError),
    /// The flight log could not be written; the drone was landed. The report of the flight
    /// as flown.
    Log(io::Error, Box<FlightReport>),
}

impl std::fmt::Display for FlightError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FlightError::Preflight(refusals) => {
                let said: Vec<&str> = refusals.iter().map(|d| d.message.as_str()).collect();
                write!(f, "pre-flight check failed: {}", said.join("; "))
            }
            FlightError::Backend(e) => write!(f, "drone backend: {e}"),
            FlightError::Log(e, _) => write!(
                f,
                "the flight log could not be written ({e}): the drone was landed"
            ),
        }
    }
}

impl std::error::Error for FlightError {}

impl From<BackendError> for FlightError {
    fn from(e: BackendError) -> Self {
        FlightError::Backend(e)
    }
}

/// Flies the script. Returns the report, also when a failsafe ended the flight early
/// (`completed` is then false); an error only when the flight could not start or a backend
/// or the log failed (the drone is landed first whenever it flies).
pub fn fly(
    setup: &FlightSetup,
    controller: &mut dyn Controller,
    backends: Backends,
    sink: &mut dyn FlightSink,
    observer: &mut dyn Observer,
) -> Result<FlightReport, FlightError> {
    Flight::new(setup, controller, backends, sink, observer)?.run()
}

#[cfg(test)]
mod tests {
    use dronecine_backend::frames::body_to_world;
    use dronecine_compiler::camera::CameraPose;
    use nalgebra::Vector3;

    /// The two conventions agree: the compiler's camera looks along (cos c, sin c), the
    /// drone's body forward axis at heading c; the camera's right is the body's −left.
    #[test]
    fn the_drone_heading_is_the_camera_heading() {
        for c in [-2.5, -0.3, 0.0, 1.0, 3.0] {
            let cam = CameraPose {
                position_m: Default::default(),
                heading_rad: c,
                pitch_rad: 0.0,
            };
            let fwd = body_to_world(c) * Vector3::x();
            assert!((cam.forward() - fwd).norm() < 1e-12);
            // The camera's right is the body's −left.
            let left = body_to_world(c) * Vector3::y();
            assert!((cam.right() + left).norm() < 1e-12);
        }
    }
}
