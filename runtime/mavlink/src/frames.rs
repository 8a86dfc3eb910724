//! **The one place where the stage's frames meet MAVLink's.**
//!
//! - The stage (`dronecine_backend::frames`): x, y on the floor, z up; the heading `c`
//!   counter-clockwise from +x seen from above; the body frame forward, left, up.
//! - MAVLink: local positions in NED (north, east, down), the body frame FRD (forward, right,
//!   down), attitudes as Euler angles roll, pitch, yaw about FRD's axes (yaw clockwise from
//!   north seen from above) or as the quaternion `q = (w, x, y, z)` that turns NED into the
//!   body frame.
//! - The mapping: stage +x is east, stage +y is north, stage +z is up, so NED = (y, x, −z)
//!   and the yaw is ψ = π/2 − c. It is the frame the autopilot's EKF is given by the motion
//!   capture (VISION_POSITION_ESTIMATE), so its local position comes back in the same frame;
//!   north is the stage's +y only in name unless the autopilot takes its yaw from the motion
//!   capture too (EK3_SRC1_YAW = 6) or the stage's +y is laid out to magnetic north.
//! - The generic command's signs are the aerospace ones: positive roll is right side down,
//!   positive pitch is nose up, positive yaw rate is clockwise seen from above. So roll,
//!   pitch and yaw rate go into MAVLink unchanged, and the yaw rate integrates into ψ.
//! - `thrust` in SET_ATTITUDE_TARGET is ArduCopter's climb-rate command: 0.5 holds the
//!   altitude, `0.5 + vz / (2·climb_max)` climbs, `0.5 + vz / (2·descent_max)` descends
//!   (the vehicle's own WPNAV_SPEED_UP and WPNAV_SPEED_DN), clamped to [0, 1].

use std::f64::consts::FRAC_PI_2;

use dronecine_backend::frames::{wrap_angle_rad, Command};
use dronecine_backend::BodyPose;
use dronecine_math::{asin, atan2, sin_cos};

/// A stage position (x, y, z up) in NED metres.
pub fn stage_to_ned_m(p: [f64; 3]) -> [f64; 3] {
    [p[1], p[0], -p[2]]
}

/// A NED position (or velocity) on the stage's axes: the inverse of [`stage_to_ned_m`].
pub fn ned_to_stage_m(n: [f64; 3]) -> [f64; 3] {
    [n[1], n[0], -n[2]]
}

/// The MAVLink yaw (clockwise from north) of a stage heading (counter-clockwise from +x),
/// wrapped to (−π, π].
pub fn heading_to_yaw_rad(heading_rad: f64) -> f64 {
    wrap_angle_rad(FRAC_PI_2 - heading_rad)
}

/// The stage heading of a MAVLink yaw: the inverse of [`heading_to_yaw_rad`].
pub fn yaw_to_heading_rad(yaw_rad: f64) -> f64 {
    wrap_angle_rad(FRAC_PI_2 - yaw_rad)
}

/// A stage pose as MAVLink's NED position and yaw.
pub fn pose_to_ned(pose: &BodyPose) -> ([f64; 3], f64) {
    (
        stage_to_ned_m(pose.position_m),
        heading_to_yaw_rad(pose.heading_rad),
    )
}

/// A NED position and yaw as a stage pose: the inverse of [`pose_to_ned`].
pub fn ned_to_pose(ned_m: [f64; 3], yaw_rad: f64) -> BodyPose {
    BodyPose {
        position_m: ned_to_stage_m(ned_m),
        heading_rad: yaw_to_heading_rad(yaw_rad),
    }
}

/// The quaternion `(w, x, y, z)` of the Euler angles roll, pitch, yaw (rotations about z,
/// then y, then x: MAVLink's and ArduPilot's order).
pub fn quaternion_from_euler(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> [f64; 4] {
    let (sr, cr) = sin_cos(roll_rad / 2.0);
    let (sp, cp) = sin_cos(pitch_rad / 2.0);
    let (sy, cy) = sin_cos(yaw_rad / 2.0);
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// The Euler angles `[roll, pitch, yaw]` of a quaternion `(w, x, y, z)` (the inverse of
/// [`quaternion_from_euler`]; pitch in [−π/2, π/2]).
pub fn euler_from_quaternion(q: [f64; 4]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let roll = atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
    let pitch = asin((2.0 * (w * y - z * x)).clamp(-1.0, 1.0));
    let yaw = atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}

/// ArduCopter's climb-rate `thrust` for a vertical speed (module docs), in [0, 1].
pub fn thrust_for_climb(vz_mps: f64, climb_max_mps: f64, descent_max_mps: f64) -> f64 {
    let scale = if vz_mps >= 0.0 {
        climb_max_mps
    } else {
        descent_max_mps
    };
    (0.5 + vz_mps / (2.0 * scale)).clamp(0.0, 1.0)
}

/// The vertical speed a climb-rate `thrust` asks for: the inverse of [`thrust_for_climb`]
/// inside (0, 1).
pub fn climb_for_thrust(thrust: f64, climb_max_mps: f64, descent_max_mps: f64) -> f64 {
    let scale = if thrust >= 0.5 {
        climb_max_mps
    } else {
        descent_max_mps
    };
    (thrust - 0.5) * 2.0 * scale
}

/// One SET_ATTITUDE_TARGET's set-points: the attitude, the yaw-rate feed-forward and the
/// climb-rate thrust.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeTarget {
    /// `(w, x, y, z)`, NED → body FRD.
    pub q: [f32; 4],
    /// The body yaw rate (FRD, clockwise positive), as feed-forward.
    pub yaw_rate_radps: f32,
    /// ArduCopter's climb-rate command in [0, 1] (0.5 holds the altitude).
    pub thrust: f32,
}

impl AttitudeTarget {
    /// Level, facing `yaw_rad`, holding the altitude: the hover.
    pub fn level(yaw_rad: f64) -> Self {
        Self::new(0.0, 0.0, yaw_rad, 0.0, 0.5)
    }

    /// The target of roll, pitch and yaw (radians), a yaw-rate feed-forward and a thrust.
    pub fn new(
        roll_rad: f64,
        pitch_rad: f64,
        yaw_rad: f64,
        yaw_rate_radps: f64,
        thrust: f64,
    ) -> Self {
        let q = quaternion_from_euler(roll_rad, pitch_rad, yaw_rad);
        AttitudeTarget {
            q: q.map(|v| v as f32),
            yaw_rate_radps: yaw_rate_radps as f32,
            thrust: thrust as f32,
        }
    }

    /// The generic command flown toward the yaw target `yaw_rad`, with the vehicle's climb
    /// and descent limits (m/s).
    pub fn from_command(
        command: &Command,
        yaw_rad: f64,
        climb_max_mps: f64,
        descent_max_mps: f64,
    ) -> Self {
        Self::new(
            command.roll_rad,
            command.pitch_rad,
            yaw_rad,
            command.yaw_rate_radps,
            thrust_for_climb(command.vz_mps, climb_max_mps, descent_max_mps),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_backend::frames::{body_to_world, INPUT_TO_BODY};
    use nalgebra::{Matrix3, Vector3};
    use std::f64::consts::PI;

    /// The rotation body FRD → NED of a quaternion.
    fn body_to_ned(q: [f64; 4]) -> Matrix3<f64> {
        let [w, x, y, z] = q;
        Matrix3::new(
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        )
    }

    /// The horizontal direction (stage x, y) the vehicle's thrust tilts toward under a
    /// command, facing the stage heading `c`.
    fn tilt_on_stage(heading_rad: f64, command: Command) -> Vector3<f64> {
        let t = AttitudeTarget::from_command(&command, heading_to_yaw_rad(heading_rad), 2.5, 1.5);
        let q = t.q.map(f64::from);
        let thrust_ned = body_to_ned(q) * Vector3::new(0.0, 0.0, -1.0);
        let s = ned_to_stage_m([thrust_ned.x, thrust_ned.y, thrust_ned.z]);
        Vector3::new(s[0], s[1], 0.0)
    }

    /// Where the stage's convention says the command moves the drone (horizontal part).
    fn stage_convention(heading_rad: f64, command: Command) -> Vector3<f64> {
        let v = body_to_world(heading_rad) * INPUT_TO_BODY * command.translation_input();
        Vector3::new(v.x, v.y, 0.0)
    }

    #[test]
    fn a_pose_and_its_round_trip() {
        let pose = BodyPose {
            position_m: [1.5, -2.0, 1.2],
            heading_rad: 0.3,
        };
        let (ned, yaw) = pose_to_ned(&pose);
        assert_eq!(ned, [-2.0, 1.5, -1.2]);
        assert!((yaw - (FRAC_PI_2 - 0.3)).abs() < 1e-15);
        let back = ned_to_pose(ned, yaw);
        assert_eq!(back.position_m, pose.position_m);
        assert!((back.heading_rad - pose.heading_rad).abs() < 1e-15);
        // Facing stage +x is facing east; facing +y is facing north.
        assert!((heading_to_yaw_rad(0.0) - FRAC_PI_2).abs() < 1e-15);
        assert!(heading_to_yaw_rad(FRAC_PI_2).abs() < 1e-15);
        assert!((heading_to_yaw_rad(-FRAC_PI_2) - PI).abs() < 1e-15);
    }

    #[test]
    fn quaternion_round_trip() {
        for (r, p, y) in [(0.1, -0.2, 2.5), (-0.3, 0.25, -3.0), (0.0, 0.0, PI)] {
            let q = quaternion_from_euler(r, p, y);
            let norm = q.iter().map(|v| v * v).sum::<f64>();
            assert!((norm - 1.0).abs() < 1e-12);
            let [r2, p2, y2] = euler_from_quaternion(q);
            assert!(
                (r2 - r).abs() < 1e-12 && (p2 - p).abs() < 1e-12,
                "{r2} {p2}"
            );
            assert!(wrap_angle_rad(y2 - y).abs() < 1e-12, "{y2} {y}");
        }
        // Yaw alone: a turn about down by ψ.
        let q = quaternion_from_euler(0.0, 0.0, FRAC_PI_2);
        assert!((q[0] - q[3]).abs() < 1e-15 && q[1] == 0.0 && q[2] == 0.0);
    }

    #[test]
    fn pitch_and_roll_move_the_vehicle_where_the_stage_says() {
        for heading in [0.0, FRAC_PI_2, 2.0, -2.5] {
            for command in [
                Command {
                    pitch_rad: -0.15,
                    ..Command::HOVER
                },
                Command {
                    pitch_rad: 0.1,
                    ..Command::HOVER
                },
                Command {
                    roll_rad: 0.12,
                    ..Command::HOVER
                },
                Command {
                    roll_rad: -0.08,
                    pitch_rad: 0.05,
                    ..Command::HOVER
                },
            ] {
                let tilt = tilt_on_stage(heading, command);
                let want = stage_convention(heading, command);
                let cos = tilt.dot(&want) / (tilt.norm() * want.norm());
                assert!(
                    cos > 0.999,
                    "heading {heading}, {command:?}: {tilt:?} vs {want:?}"
                );
            }
        }
        // Nose down facing +x: toward +x (forward), as the stage's convention says.
        let t = tilt_on_stage(
            0.0,
            Command {
                pitch_rad: -0.1,
                ..Command::HOVER
            },
        );
        assert!(t.x > 0.09 && t.y.abs() < 1e-6, "{t:?}");
    }

    #[test]
    fn a_positive_yaw_rate_turns_the_heading_clockwise() {
        // The yaw rate goes in unchanged: ψ grows, so the stage heading c shrinks.
        let t = AttitudeTarget::from_command(
            &Command {
                yaw_rate_radps: 0.4,
                ..Command::HOVER
            },
            0.0,
            2.5,
            1.5,
        );
        assert_eq!(t.yaw_rate_radps, 0.4);
        assert!(yaw_to_heading_rad(0.1) < yaw_to_heading_rad(0.0));
    }

    #[test]
    fn thrust_is_the_climb_rate_scaled_by_the_vehicles_limits() {
        assert_eq!(thrust_for_climb(0.0, 2.5, 1.5), 0.5);
        assert!((thrust_for_climb(1.0, 2.5, 1.5) - 0.7).abs() < 1e-12);
        assert!((thrust_for_climb(-0.75, 2.5, 1.5) - 0.25).abs() < 1e-12);
        assert_eq!(thrust_for_climb(10.0, 2.5, 1.5), 1.0);
        assert_eq!(thrust_for_climb(-10.0, 2.5, 1.5), 0.0);
        for vz in [-1.2, -0.3, 0.0, 0.4, 2.0] {
            let t = thrust_for_climb(vz, 2.5, 1.5);
            assert!((climb_for_thrust(t, 2.5, 1.5) - vz).abs() < 1e-12);
        }
    }
}
