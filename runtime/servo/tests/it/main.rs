//! The servo's tests: the Riccati solver, the LQG servo and the PID baseline, their sign
//! conventions and determinism, their state taken and restored, and a tick that allocates
//! nothing.

mod alloc;
mod dare;
mod servo;
mod state;
