//! The compiler: from a resolved PSL `Script` to the timed 6D reference a drone flies.
//!
//! - `camera`: **the camera conventions** (lens, roll-free pose, projection, orientation).
//! - `size`, `sphere`, `toric`: the one- and two-actor manifolds; `framing`: a composition →
//!   visual parameters → a camera placement; `framed_as`: what a hold really frames.
//! - `blocking`: the actors over time; `paths`: square, helix, orbit, waypoints.
//! - `steering`: jerk-limited arrival with feed-forward, braking for walls and bodies;
//!   `route`: repositioning routes round the actors.
//! - `director`: **the one evaluator**, `Director::step(t, actors) -> Sample`, which
//!   `compile` runs over the scripted blocking and `shoot` runs against live actors.
//! - `feasibility`: the monitor of a reference against the profile's limits and the stage.
//! - `coverage`: a `coverage A and B` line expanded into the classic set of shots.
//! - `compile`: the whole script, sampled; `reference`: the samples.
//! - `code`: the `compile::` diagnostic codes.
//!
//! The compiler renders nothing and writes no file: `dronecine-preview` draws a reference,
//! `dronecine-mcap` writes it.

pub mod blocking;
pub mod camera;
pub mod code;
pub mod compile;
pub mod coverage;
pub mod director;
pub mod feasibility;
pub mod framed_as;
pub mod framing;
pub mod line;
pub mod paths;
pub mod reference;
pub mod route;
pub mod size;
pub mod sized;
pub mod sphere;
pub mod steering;
pub mod toric;

pub use code::CompileCode;
