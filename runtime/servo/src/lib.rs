//! The servo: the drone's model, the Riccati solver, the LQG controller with its Kalman
//! filters, and the PID baseline, behind one [`Controller`](control::Controller) trait.
//!
//! - `control`: the trait the flight loop and `replay` drive (one tick in, one command out)
//!   and its inputs and outputs.
//! - `model`: the translation and heading models (A1, B1, the body-frame lag).
//! - `dare`: the discrete algebraic Riccati equation by structure-preserving doubling, no heap.
//! - `lqg`: the LQG servo and the Kalman filters.
//! - `pid`: tum_ardrone's PID autopilot, the baseline.
//! - `setup`: which controller a flight uses, as its log records it, and building it again.
//!
//! Invariant: a controller is a pure function of its set-up and its inputs, the same bits on
//! every machine (IEEE arithmetic and `dronecine_math` only), and its tick allocates nothing.

pub mod control;
pub mod dare;
pub mod lqg;
pub mod model;
pub mod pid;
pub mod setup;
