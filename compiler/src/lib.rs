//! The compiler: from a resolved PSL `Script` to the timed 6D reference a drone flies.
//!
//! Modules: `profile` (drone profiles), `camera` (lens, pose, projection, orientation: the
//! camera conventions), `reference` (the output samples).

pub mod camera;
pub mod output;
pub mod profile;
pub mod reference;
