//! **The axis and sign conventions of the runtime**: the one place that says
//! which way a positive roll, pitch and yaw rate move the drone.
//!
//! - World frame: x, y on the floor, z up, origin at the centre of the stage floor (as the
//!   script's stage).
//! - Heading `c`: counter-clockwise from +x seen from above, wrapped to (−π, π] (the
//!   compiler's camera heading: the drone's camera looks along its heading).
//! - Body frame: forward (along the heading), left, up. `body_to_world(c)` = Rz(c).
//! - The generic command ([`Command`]) uses the AR.Drone's signs, which are the usual ones of
//!   rotary-wing APIs: positive roll = right side down = the drone moves **right**; positive
//!   pitch = nose up = the drone moves **backward**; positive yaw rate = **clockwise** seen from
//!   above, so the heading `c` **decreases**; positive vertical speed = up.
//!
//! Every other module goes through the functions here: [`INPUT_TO_BODY`] for the translation
//! model, [`heading_rate_radps`] / [`yaw_rate_command_radps`] for the heading model,
//! [`wrap_angle_rad`] for every angle difference.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The generic rotary-wing set-points, in the AR.Drone's signs (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// φ: positive moves right.
    pub roll_rad: f64,
    /// θ: positive (nose up) moves backward.
    pub pitch_rad: f64,
    /// ψ̇: positive is clockwise seen from above (heading decreases).
    pub yaw_rate_radps: f64,
    /// ż: positive is up.
    pub vz_mps: f64,
}

impl Command {
    pub const HOVER: Command = Command {
        roll_rad: 0.0,
        pitch_rad: 0.0,
        yaw_rate_radps: 0.0,
        vz_mps: 0.0,
    };

    /// `[φ, θ, ż]`, the translation model's input `u1`.
    pub fn translation_input(&self) -> Vector3<f64> {
        Vector3::new(self.roll_rad, self.pitch_rad, self.vz_mps)
    }

    pub fn is_finite(&self) -> bool {
        self.roll_rad.is_finite()
            && self.pitch_rad.is_finite()
            && self.yaw_rate_radps.is_finite()
            && self.vz_mps.is_finite()
    }
}

/// Maps the translation input `u1 = [φ, θ, ż]` (after the per-axis gains) to the body-frame
/// velocity `[forward, left, up]`: forward = −θ (nose up moves back), left = −φ (roll right
/// moves right), up = ż: the fixed permutation and sign matrix P of the model.
#[rustfmt::skip]
pub const INPUT_TO_BODY: Matrix3<f64> = Matrix3::new(
    0.0, -1.0, 0.0,
    -1.0, 0.0, 0.0,
    0.0, 0.0, 1.0,
);

/// Rz(c): body (forward, left, up) → world (its `sin_cos` from `dronecine_math`: the same bits
/// on every machine, for replay).
pub fn body_to_world(heading_rad: f64) -> Matrix3<f64> {
    let (s, c) = dronecine_math::sin_cos(heading_rad);
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Body-frame lag axis of each input: φ lags the left axis, θ the forward axis, ż the
/// vertical. `tau_body = [τ_θ, τ_φ, τ_ż]` in (forward, left, up) order.
pub fn body_taus_s(tau_roll_s: f64, tau_pitch_s: f64, tau_vz_s: f64) -> [f64; 3] {
    [tau_pitch_s, tau_roll_s, tau_vz_s]
}

/// The heading rate `ċ` (counter-clockwise positive) that a yaw-rate command asks for,
/// before the model gain K_ψ: `ċ = −ψ̇`.
pub fn heading_rate_radps(yaw_rate_command_radps: f64) -> f64 {
    -yaw_rate_command_radps
}

/// The yaw-rate command that asks for a heading rate `ċ`: the inverse of
/// [`heading_rate_radps`].
pub fn yaw_rate_command_radps(heading_rate_radps: f64) -> f64 {
    -heading_rate_radps
}

/// An angle wrapped to (−π, π]: the one wrap used for headings and their errors and
/// innovations.
pub use dronecine_math::wrap_angle_rad;

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn world_velocity(heading_rad: f64, cmd: Command) -> Vector3<f64> {
        body_to_world(heading_rad) * INPUT_TO_BODY * cmd.translation_input()
    }

    #[test]
    fn nose_up_moves_backward() {
        // Facing +x, nose up: the drone moves toward −x.
        let v = world_velocity(
            0.0,
            Command {
                pitch_rad: 0.1,
                ..Command::HOVER
            },
        );
        assert!(v.x < 0.0 && v.y.abs() < 1e-12 && v.z == 0.0, "{v:?}");
        // Facing +y, nose down: toward +y.
        let v = world_velocity(
            FRAC_PI_2,
            Command {
                pitch_rad: -0.1,
                ..Command::HOVER
            },
        );
        assert!(v.y > 0.0 && v.x.abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn roll_right_moves_right() {
        // Facing +x, the right is −y.
        let v = world_velocity(
            0.0,
            Command {
                roll_rad: 0.1,
                ..Command::HOVER
            },
        );
        assert!(v.y < 0.0 && v.x.abs() < 1e-12, "{v:?}");
        // Facing +y, the right is +x.
        let v = world_velocity(
            FRAC_PI_2,
            Command {
                roll_rad: 0.1,
                ..Command::HOVER
            },
        );
        assert!(v.x > 0.0 && v.y.abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn vz_up_is_up() {
        let v = world_velocity(
            1.0,
            Command {
                vz_mps: 0.3,
                ..Command::HOVER
            },
        );
        assert!((v.z - 0.3).abs() < 1e-15 && v.x == 0.0 && v.y == 0.0);
    }

    #[test]
    fn positive_yaw_is_clockwise() {
        assert!(heading_rate_radps(0.5) < 0.0);
        assert_eq!(yaw_rate_command_radps(heading_rate_radps(0.3)), 0.3);
    }

    #[test]
    fn wrap_takes_the_short_way() {
        let e = wrap_angle_rad(-170f64.to_radians() - 170f64.to_radians());
        assert!((e - 20f64.to_radians()).abs() < 1e-12);
        assert_eq!(wrap_angle_rad(-PI), PI);
    }
}
