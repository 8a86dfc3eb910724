//! The runtime: the LQG servo, the `Drone` and `Mocap` backends (embedded simulator,
//! AR.Drone 2.0, OptiTrack NatNet) and the flight loop behind `dronecine shoot`.
//!
//! - `frames`: the axis and sign conventions (the one source of truth).
//! - `backend`: the `Drone`, `Mocap` and `Clock` traits.
//! - `control`: the `Controller` trait the servo and the PID baseline implement.
//! - `model`: the translation and heading models (A1, B1, the body-frame lag).
//! - `identify`: the least-squares fit of the model from a measured response; `calibrate`:
//!   the calibration flight (doublets around hover) that feeds it.
//! - `dare`: the Riccati solver (structure-preserving doubling, no heap).
//! - `lqg`: the LQG servo and the Kalman filters.
//! - `pid`: tum_ardrone's PID autopilot, the baseline.
//! - `record`: what a flight logs each tick (flight loop → log → replay).
//! - `flight`: the flight loop (pre-flight, take-off, approach, shots, landing, report).
//! - `sim`: the embedded AR.Drone 2.0 simulator (drone, mocap and clock over one world).
//! - `report`: the flight report's figures (shared by shoot and replay).
//! - `log`: the flight log (MCAP), written incrementally and read back; `replay` re-runs it.
//! - `session`: a whole flight on the simulator, and building a controller from its set-up.
//! - `ardrone`, `natnet`: the AR.Drone 2.0 (AT commands, navdata) and NatNet wire codecs.
//! - `emulator`: the simulator in real time behind those protocols (`dronecine emulate`).

mod ahead;
pub mod ardrone;
pub mod backend;
pub mod calibrate;
pub mod clock;
pub mod control;
pub mod dare;
pub mod emulator;
pub mod flight;
pub mod frames;
pub mod identify;
pub mod log;
pub mod lqg;
pub mod math;
pub mod model;
pub mod natnet;
pub mod pid;
pub mod record;
pub mod replay;
pub mod report;
pub mod session;
pub mod sim;
pub mod url;
