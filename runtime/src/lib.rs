//! The runtime: the LQG servo, the `Drone` and `Mocap` backends (embedded simulator,
//! AR.Drone 2.0, OptiTrack NatNet) and the flight loop behind `dronecine shoot`.
//!
//! - `frames`: the axis and sign conventions (the one source of truth).
//! - `backend`: the `Drone`, `Mocap` and `Clock` traits.
//! - `control`: the `Controller` trait the servo and the PID baseline implement.
//! - `record`: what a flight logs each tick (flight loop → log → replay).

pub mod backend;
pub mod control;
pub mod frames;
pub mod log;
pub mod record;
