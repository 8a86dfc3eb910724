//! Drone profiles: the model, limits, camera, safety distance and servo settings of a drone.
//!
//! The types here are the one description of a drone that the compiler (limits, camera,
//! safety) and the runtime (model, servo weights, noise) read. SI units inside, with the unit
//! in every field name.

use serde::{Deserialize, Serialize};

/// Names accepted by `drone NAME` in a script.
pub const BUILTIN_NAMES: &[&str] = &["ardrone2", "ardrone2-outdoor"];

/// The profile used when a script names none.
pub const DEFAULT_NAME: &str = "ardrone2";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    pub name: String,
    pub description: String,
    pub model: Model,
    pub limits: Limits,
    pub camera: Camera,
    pub safety: Safety,
    pub servo: Servo,
}

/// The servo's plant model (control.md §2–3): per axis `v̇ = (K·u − v)/τ`, heading
/// `ċ = K_ψ·ψ̇`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// K_φ: lateral speed per radian of roll, m/s per rad.
    pub gain_roll_mps_per_rad: f64,
    /// K_θ: longitudinal speed per radian of pitch, m/s per rad.
    pub gain_pitch_mps_per_rad: f64,
    /// K_ż: vertical speed per commanded vertical speed.
    pub gain_vz: f64,
    pub tau_roll_s: f64,
    pub tau_pitch_s: f64,
    pub tau_vz_s: f64,
    /// K_ψ: heading rate per commanded yaw rate.
    pub gain_yaw: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Largest roll or pitch command (AR.Drone `euler_angle_max`).
    pub tilt_max_rad: f64,
    /// AR.Drone `control_vz_max`.
    pub vz_max_mps: f64,
    /// AR.Drone `control_yaw`.
    pub yaw_rate_max_radps: f64,
    /// Horizontal speed the reference may ask for; follows from tilt and the model
    /// (`K·tilt_max·authority`), leaving the rest of the tilt to the servo's corrections.
    pub speed_max_mps: f64,
    /// Horizontal acceleration the reference may ask for (`K·tilt_max·(1 − authority)/τ`).
    pub accel_max_mps2: f64,
    /// Jerk bound of the reference (smoothness).
    pub jerk_max_mps3: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Horizontal field of view.
    pub fov_x_rad: f64,
    /// Frame width over height.
    pub aspect: f64,
    pub gimbal: Gimbal,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Gimbal {
    /// A camera fixed to the body, looking along the heading, level (AR.Drone front camera).
    None,
    /// A pitch gimbal with its range (up positive).
    Pitch { min_rad: f64, max_rad: f64 },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Safety {
    /// No part of the reference comes closer than this to an actor's body axis.
    pub actor_distance_m: f64,
    /// The reference stays this far inside the stage walls, floor and ceiling.
    pub stage_margin_m: f64,
}

/// Settings of the runtime's LQG servo and Kalman filters (control.md §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Servo {
    /// Diagonal of Q on the state [vx, vy, vz, x, y, z].
    pub q: [f64; 6],
    /// Diagonal of R on the input [roll, pitch, vz].
    pub r: [f64; 3],
    /// Heading loop: the error falls to `heading_gamma` after `heading_tau_s`.
    pub heading_gamma: f64,
    pub heading_tau_s: f64,
    /// Kalman process noise (F1 diagonal, state [vx, vy, vz, x, y, z]).
    pub process_noise: [f64; 6],
    /// Kalman measurement noise (H1 diagonal, position [x, y, z]), m².
    pub measurement_noise_m2: [f64; 3],
    /// Heading process noise f2 and measurement noise h2, rad².
    pub heading_process_noise_rad2: f64,
    pub heading_measurement_noise_rad2: f64,
}

impl Profile {
    /// A built-in profile by name.
    ///
    /// Placeholder values until the TOML profiles land: the numbers are those of control.md §5.
    pub fn builtin(name: &str) -> Option<Profile> {
        let outdoor = match name {
            "ardrone2" => false,
            "ardrone2-outdoor" => true,
            _ => return None,
        };
        let gain = 17.5;
        let tau = 1.7;
        let (tilt, vz, yaw) = if outdoor {
            (0.35, 1.0, 3.49)
        } else {
            (0.21, 0.7, 1.75)
        };
        let authority = 0.5;
        // 92° diagonal, 16:9.
        let half_diag = (46.0f64).to_radians().tan();
        let fov_x = 2.0 * (half_diag * 16.0 / (16.0f64.hypot(9.0))).atan();
        Some(Profile {
            name: name.to_string(),
            description: "Parrot AR.Drone 2.0".to_string(),
            model: Model {
                gain_roll_mps_per_rad: gain,
                gain_pitch_mps_per_rad: gain,
                gain_vz: 1.0,
                tau_roll_s: tau,
                tau_pitch_s: tau,
                tau_vz_s: 1.25,
                gain_yaw: 1.0,
            },
            limits: Limits {
                tilt_max_rad: tilt,
                vz_max_mps: vz,
                yaw_rate_max_radps: yaw,
                speed_max_mps: gain * tilt * authority,
                accel_max_mps2: gain * tilt * (1.0 - authority) / tau,
                jerk_max_mps3: 2.0,
            },
            camera: Camera {
                fov_x_rad: fov_x,
                aspect: 16.0 / 9.0,
                gimbal: Gimbal::None,
            },
            safety: Safety {
                actor_distance_m: 0.5,
                stage_margin_m: 0.3,
            },
            servo: Servo {
                q: [1.0, 1.0, 1.0, 10.0, 10.0, 10.0],
                r: [50.0, 50.0, 5.0],
                heading_gamma: 0.05,
                heading_tau_s: 1.0,
                process_noise: [1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5],
                measurement_noise_m2: [1e-6; 3],
                heading_process_noise_rad2: 1e-4,
                heading_measurement_noise_rad2: 1e-5,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_builtin() {
        assert!(BUILTIN_NAMES.contains(&DEFAULT_NAME));
        for name in BUILTIN_NAMES {
            assert!(Profile::builtin(name).is_some(), "{name}");
        }
    }
}
