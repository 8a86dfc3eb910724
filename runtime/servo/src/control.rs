//! The interface of a flight controller: one tick in, one command out. The LQG servo
//! (`lqg.rs`) and the PID baseline (`pid.rs`) implement [`Controller`]; the flight loop and
//! `replay` drive either through it.
//!
//! Determinism: a controller is a pure function of its construction parameters and the
//! sequence of [`TickInput`]s it was given. `replay` relies on it: it feeds the logged inputs
//! and expects the logged commands bit for bit.

use dronecine_backend::frames::Command;
use serde::{Deserialize, Serialize};

/// What the servo tracks at one tick: a sample of the compiled (or online) reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    pub position_m: [f64; 3],
    pub velocity_mps: [f64; 3],
    pub acceleration_mps2: [f64; 3],
    pub heading_rad: f64,
    pub heading_rate_radps: f64,
}

/// A motion-capture measurement of the drone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    pub position_m: [f64; 3],
    pub heading_rad: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TickInput {
    /// Flight clock at this tick.
    pub t_s: f64,
    /// Δ\[k\]: the measured time since the previous tick (mocap timestamps), > 0.
    pub dt_s: f64,
    /// `None` on a mocap dropout: the filters predict only.
    pub measurement: Option<Measurement>,
    pub reference: Reference,
}

/// The controller's state estimate after the tick.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    pub position_m: [f64; 3],
    pub velocity_mps: [f64; 3],
    pub heading_rad: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TickOutput {
    pub command: Command,
    pub estimate: Estimate,
    /// Whether any set-point was clamped to the profile's limits this tick.
    pub saturated: bool,
}

/// Why a tick input was refused: the controller's state is unchanged and the flight loop
/// applies its failsafe (hover) and logs it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TickFault {
    /// A NaN or infinite value in the measurement or the reference.
    NotFinite,
    /// Δ ≤ 0: time went backward or stood still.
    TimeNotIncreasing,
}

pub trait Controller {
    /// Starts the filters at a known state (the measured pose at take-off, at rest).
    fn reset(&mut self, t_s: f64, measurement: &Measurement);
    /// One control step. Allocates nothing.
    fn tick(&mut self, input: &TickInput) -> Result<TickOutput, TickFault>;
}
