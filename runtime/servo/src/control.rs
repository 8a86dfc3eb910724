//! The interface of a flight controller: one tick in, one command out. The LQG servo
//! (`lqg.rs`) and the PID baseline (`pid.rs`) implement [`Controller`]; the flight loop and
//! `replay` drive either through it.
//!
//! Determinism: a controller is a pure function of its construction parameters and the
//! sequence of [`TickInput`]s it was given. `replay` relies on it: it feeds the logged inputs
//! and expects the logged commands bit for bit. Its state between two ticks
//! ([`ControllerState`]) is all that the next ticks depend on besides their inputs: the flight
//! log keeps it at the start of each chunk, and `replay` restores it after a gap.

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

/// The Kalman filters' state ([`Estimator`](crate::lqg::Estimator)), every float as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilterState {
    /// `[v; p; d]`: the velocity (m/s), the position (m) and the air's velocity (m/s, zero
    /// when the filter does not estimate it).
    pub x: [f64; 9],
    /// The covariance of `x`, row by row.
    pub p: [[f64; 9]; 9],
    pub heading_rad: f64,
    pub heading_variance_rad2: f64,
    /// The Δ of the last prediction and its body-frame lag, which the next prediction reuses
    /// when its Δ is the same.
    pub lag_dt_s: f64,
    pub lag_body: [f64; 3],
}

/// The LQG servo's state between two ticks: its filters, what it sent last, and the gains it
/// keeps from tick to tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LqgState {
    pub filter: FilterState,
    /// The translation input `[φ, θ, ż]` sent last tick (after saturation) and the yaw rate.
    pub sent_input: [f64; 3],
    pub sent_yaw_rate_radps: f64,
    /// The Δ of the cached heading pole, and the pole (NaN before the first tick).
    pub heading_pole_dt_s: f64,
    pub heading_pole: f64,
    /// The body-frame gain (3×6, row by row) and the Δ it was solved for.
    pub body_gain_dt_s: f64,
    pub body_gain: [[f64; 6]; 3],
    /// The gain of the last full solve (3×6, row by row): flown in the per-tick mode.
    pub world_gain: [[f64; 6]; 3],
}

/// The PID baseline's state between two ticks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PidState {
    pub filter: FilterState,
    pub sent_input: [f64; 3],
    pub sent_yaw_rate_radps: f64,
    /// ∫ e_z dt, m·s.
    pub integral_z_ms: f64,
}

/// Everything a controller's tick reads or writes that is not fixed at its construction:
/// restored into a controller built the same way ([`Controller::restore`]), the next ticks
/// give the same bits as the controller it was taken from. Replay restores it from a flight
/// log's key frames to resume after a gap.
// Held by value, not boxed: taking a controller's state allocates nothing (the flight loop
// takes it on its own thread), and a PID state is only somewhat smaller than an LQG one.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ControllerState {
    Lqg(LqgState),
    Pid(PidState),
}

impl ControllerState {
    /// The controller kind's name, as [`ControllerSetup`](crate::setup::ControllerSetup)
    /// names it.
    pub fn kind(&self) -> &'static str {
        match self {
            ControllerState::Lqg(_) => "lqg",
            ControllerState::Pid(_) => "pid",
        }
    }

    /// Calls `f` with every float of the state, in a fixed order: the filter's (`x`, `p` row
    /// by row, the heading, its variance, the lag's Δ and the lag), what was sent, then the
    /// controller's own (LQG: the heading pole's Δ and the pole, the body gain's Δ, the body
    /// gain, the world gain; PID: the integral).
    pub fn for_each_float(&self, mut f: impl FnMut(f64)) {
        let (filter, sent, yaw) = match self {
            ControllerState::Lqg(s) => (&s.filter, &s.sent_input, s.sent_yaw_rate_radps),
            ControllerState::Pid(s) => (&s.filter, &s.sent_input, s.sent_yaw_rate_radps),
        };
        filter.x.iter().for_each(|&x| f(x));
        filter.p.iter().flatten().for_each(|&x| f(x));
        f(filter.heading_rad);
        f(filter.heading_variance_rad2);
        f(filter.lag_dt_s);
        filter.lag_body.iter().for_each(|&x| f(x));
        sent.iter().for_each(|&x| f(x));
        f(yaw);
        match self {
            ControllerState::Lqg(s) => {
                f(s.heading_pole_dt_s);
                f(s.heading_pole);
                f(s.body_gain_dt_s);
                s.body_gain.iter().flatten().for_each(|&x| f(x));
                s.world_gain.iter().flatten().for_each(|&x| f(x));
            }
            ControllerState::Pid(s) => f(s.integral_z_ms),
        }
    }

    /// Whether the two states are of the same kind and every float is the same bits (NaN
    /// payloads and the sign of zero included).
    pub fn same_bits(&self, other: &ControllerState) -> bool {
        let bits = |s: &ControllerState| {
            let mut out = Vec::with_capacity(160);
            s.for_each_float(|x| out.push(x.to_bits()));
            out
        };
        self.kind() == other.kind() && bits(self) == bits(other)
    }
}

pub trait Controller {
    /// Starts the filters at a known state (the measured pose at take-off, at rest).
    fn reset(&mut self, t_s: f64, measurement: &Measurement);
    /// One control step. Allocates nothing.
    fn tick(&mut self, input: &TickInput) -> Result<TickOutput, TickFault>;
    /// Its state between two ticks (see [`ControllerState`]).
    fn state(&self) -> ControllerState;
    /// Puts it in `state`, taken from a controller of the same kind built the same way; a
    /// state of another kind is refused and changes nothing.
    fn restore(&mut self, state: &ControllerState) -> Result<(), String>;
}
