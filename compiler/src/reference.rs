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
    pub fn same_bits(&self, other: &ActorPose) -> bool {
        let bits = |p: &ActorPose| {
            let [x, y, z] = p.position_m;
            let [vx, vy, vz] = p.velocity_mps;
            let (f, r, h) = (p.facing_rad, p.facing_rate_radps, p.height_m);
            [x, y, z, vx, vy, vz, f, r, h].map(f64::to_bits)
        };
        bits(self) == bits(other)
    }
}
