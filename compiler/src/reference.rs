//! The compiled reference: what the servo flies, sample by sample, and the actors as the
//! compiler assumed them.
//!
//! A sample is the state of the camera at `t_s` on the script's clock (the first shot starts
//! at 0, already framed). Velocity and acceleration are the derivatives of position (the
//! steering integrates them, never differences clamped values).

use serde::{Deserialize, Serialize};

/// One sample of the 6D reference (`Default`: at rest at the origin at t = 0, heading +x,
/// camera level, shot 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    pub t_s: f64,
    pub position_m: [f64; 3],
    pub velocity_mps: [f64; 3],
    pub acceleration_mps2: [f64; 3],
    /// Counter-clockwise from +x, wrapped to (−π, π].
    pub heading_rad: f64,
    pub heading_rate_radps: f64,
    /// Up positive; 0 for a drone without a gimbal.
    pub camera_pitch_rad: f64,
    /// Index into the script's timeline of the shot this sample belongs to (a repositioning
    /// flight belongs to the shot it flies to).
    pub shot: usize,
}

/// When each shot was actually flown.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ShotTiming {
    pub index: usize,
    /// As written (back to back, or pinned).
    pub script_start_s: f64,
    pub start_s: f64,
    pub end_s: f64,
    /// The repositioning flight inserted before the shot, if any.
    pub reposition: Option<(f64, f64)>,
}

/// An actor at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ActorPose {
    /// Feet on the floor (z = 0).
    pub position_m: [f64; 3],
    pub velocity_mps: [f64; 3],
    /// Counter-clockwise from +x, wrapped to (−π, π].
    pub facing_rad: f64,
    pub facing_rate_radps: f64,
    pub height_m: f64,
}

impl ActorPose {
    /// Whether `other` is the same pose, bit for bit (NaN and signed zeros included; `==`
    /// says a NaN differs from itself and `-0.0` equals `0.0`).
    ///
    /// Field by field, stopping at the first that differs: the director asks it of walking
    /// actors many times a tick (its solve memo), and their x differs at once, so most calls
    /// read one field, not nine.
    pub fn same_bits(&self, other: &ActorPose) -> bool {
        let same = |x: f64, y: f64| x.to_bits() == y.to_bits();
        let (a, b) = (self, other);
        same(a.position_m[0], b.position_m[0])
            && same(a.position_m[1], b.position_m[1])
            && same(a.position_m[2], b.position_m[2])
            && same(a.velocity_mps[0], b.velocity_mps[0])
            && same(a.velocity_mps[1], b.velocity_mps[1])
            && same(a.velocity_mps[2], b.velocity_mps[2])
            && same(a.facing_rad, b.facing_rad)
            && same(a.facing_rate_radps, b.facing_rate_radps)
            && same(a.height_m, b.height_m)
    }
}
