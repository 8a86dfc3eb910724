//! **The stage's conventions ↔ the Crazyflie's**: the one place that maps the generic
//! command to the altHold set-point and the motion capture to the external pose.
//!
//! The Crazyflie's world frame is the one its estimator is given: the stage's (x, y on the
//! floor, z up), since the external pose is the motion capture's position on the stage. Its
//! body frame is forward, left, up, as the stage's (`dronecine_backend::frames`).
//!
//! - **Roll, pitch**: the firmware's attitude set-point in degrees, in its "legacy" signs:
//!   positive roll is right side down (the drone moves right), positive pitch is nose up (the
//!   drone moves backward): the generic command's own signs. The position controller of the
//!   firmware asks `pitch = −PID(forward speed)` and `roll = −PID(left speed)`, which fixes
//!   them; the logged `stabilizer.roll` and `stabilizer.pitch` are in the same signs. The
//!   estimator's quaternion is not: its pitch (about the left axis) is nose down positive.
//! - **Yaw rate**: degrees per second. From protocol version 9 (firmware 2025.02) the altHold
//!   yaw rate is counter-clockwise positive, as the firmware's yaw; before, the firmware
//!   negated it: clockwise positive. The generic command's yaw rate is clockwise positive.
//! - **Climb rate**: m/s, up positive, world frame.
//! - **Yaw** (position set-point, `stabilizer.yaw`): degrees counter-clockwise from +x: the
//!   heading.

use dronecine_backend::frames::{wrap_angle_rad, Command};
use dronecine_backend::BodyPose;

/// The lowest protocol version whose altHold yaw rate is counter-clockwise positive.
pub const CCW_YAW_RATE_PROTOCOL: u8 = 9;

/// Which way a positive altHold yaw rate turns the drone (the firmware's protocol version
/// says; module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum YawRateSign {
    /// Protocol 8 and before: positive turns clockwise (the firmware negates it).
    Clockwise,
    /// Protocol 9 on: positive turns counter-clockwise.
    CounterClockwise,
}

impl YawRateSign {
    pub fn of_protocol(version: u8) -> YawRateSign {
        if version >= CCW_YAW_RATE_PROTOCOL {
            YawRateSign::CounterClockwise
        } else {
            YawRateSign::Clockwise
        }
    }

    /// +1 when the packet's yaw rate has the generic command's sign (clockwise), −1 when not.
    fn factor(self) -> f64 {
        match self {
            YawRateSign::Clockwise => 1.0,
            YawRateSign::CounterClockwise => -1.0,
        }
    }
}

/// The altHold set-point's four values, in the firmware's units and signs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AltHold {
    pub roll_deg: f32,
    pub pitch_deg: f32,
    pub yaw_rate_degps: f32,
    pub vz_mps: f32,
}

/// The altHold set-point that flies `command` (module docs).
pub fn alt_hold(command: &Command, yaw: YawRateSign) -> AltHold {
    AltHold {
        roll_deg: command.roll_rad.to_degrees() as f32,
        pitch_deg: command.pitch_rad.to_degrees() as f32,
        yaw_rate_degps: (yaw.factor() * command.yaw_rate_radps.to_degrees()) as f32,
        vz_mps: command.vz_mps as f32,
    }
}

/// The generic command an altHold set-point asks for: the inverse of [`alt_hold`] (the
/// emulated Crazyflie's reading).
pub fn command_of(set_point: &AltHold, yaw: YawRateSign) -> Command {
    Command {
        roll_rad: f64::from(set_point.roll_deg).to_radians(),
        pitch_rad: f64::from(set_point.pitch_deg).to_radians(),
        yaw_rate_radps: yaw.factor() * f64::from(set_point.yaw_rate_degps).to_radians(),
        vz_mps: f64::from(set_point.vz_mps),
    }
}

/// The external pose of a motion-capture pose: its position, and the quaternion
/// `[qx, qy, qz, qw]` of the heading with the drone's own roll and pitch (the generic
/// command's signs: right side down, nose up positive), as the estimator's attitude.
pub fn ext_pose(pose: &BodyPose, roll_rad: f64, pitch_rad: f64) -> ([f32; 3], [f32; 4]) {
    let q = quaternion_zyx(roll_rad, -pitch_rad, pose.heading_rad);
    (pose.position_m.map(|v| v as f32), q.map(|v| v as f32))
}

/// `[qx, qy, qz, qw]` of the rotation Rz(yaw)·Ry(pitch)·Rx(roll), the angles right-handed
/// about the body's forward, left and up axes.
pub fn quaternion_zyx(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> [f64; 4] {
    let (sr, cr) = dronecine_math::sin_cos(roll_rad / 2.0);
    let (sp, cp) = dronecine_math::sin_cos(pitch_rad / 2.0);
    let (sy, cy) = dronecine_math::sin_cos(yaw_rad / 2.0);
    [
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    ]
}

/// The drone's attitude from its log (`stabilizer.roll`, `.pitch`, `.yaw`, degrees): roll
/// and pitch in the generic command's signs, and the heading, in radians.
pub fn attitude_of_log(roll_deg: f32, pitch_deg: f32, yaw_deg: f32) -> (f64, f64, f64) {
    (
        f64::from(roll_deg).to_radians(),
        f64::from(pitch_deg).to_radians(),
        wrap_angle_rad(f64::from(yaw_deg).to_radians()),
    )
}

/// The yaw of a position set-point that holds `heading_rad`, in degrees.
pub fn yaw_deg_of_heading(heading_rad: f64) -> f32 {
    wrap_angle_rad(heading_rad).to_degrees() as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_backend::frames::{heading_rate_radps, INPUT_TO_BODY};

    /// The velocity the firmware's position controller's signs make of a set-point: it asks
    /// `pitch = −PID(forward)` and `roll = −PID(left)` (degrees), so a positive pitch drives
    /// backward and a positive roll drives right.
    fn firmware_body_velocity(sp: &AltHold) -> [f64; 3] {
        [
            -f64::from(sp.pitch_deg),
            -f64::from(sp.roll_deg),
            f64::from(sp.vz_mps),
        ]
    }

    /// The generic command and the set-point it becomes move the drone the same way, and
    /// turn it the same way, in either yaw convention.
    #[test]
    fn the_set_point_flies_where_the_command_says() {
        for (roll, pitch, vz) in [(0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (-0.05, -0.08, 0.3)] {
            let c = Command {
                roll_rad: roll,
                pitch_rad: pitch,
                yaw_rate_radps: 0.0,
                vz_mps: vz,
            };
            let body = INPUT_TO_BODY * c.translation_input();
            let sp = alt_hold(&c, YawRateSign::CounterClockwise);
            let fw = firmware_body_velocity(&sp);
            let sign = |v: f64| (v > 1e-12) as i8 - (v < -1e-12) as i8;
            for i in 0..3 {
                assert_eq!(sign(fw[i]), sign(body[i]), "{c:?} axis {i}");
            }
        }
        let turn = Command {
            yaw_rate_radps: 0.5,
            ..Command::HOVER
        };
        // Clockwise (heading decreasing): negative, counter-clockwise positive, on 9 on.
        assert!(heading_rate_radps(turn.yaw_rate_radps) < 0.0);
        let new = alt_hold(&turn, YawRateSign::CounterClockwise);
        assert!((f64::from(new.yaw_rate_degps) + 0.5f64.to_degrees()).abs() < 1e-4);
        let old = alt_hold(&turn, YawRateSign::Clockwise);
        assert!((f64::from(old.yaw_rate_degps) - 0.5f64.to_degrees()).abs() < 1e-4);
        assert_eq!(YawRateSign::of_protocol(8), YawRateSign::Clockwise);
        assert_eq!(YawRateSign::of_protocol(9), YawRateSign::CounterClockwise);
        assert_eq!(YawRateSign::of_protocol(12), YawRateSign::CounterClockwise);
    }

    #[test]
    fn command_of_inverts_alt_hold() {
        let c = Command {
            roll_rad: 0.07,
            pitch_rad: -0.12,
            yaw_rate_radps: 0.9,
            vz_mps: -0.4,
        };
        for yaw in [YawRateSign::Clockwise, YawRateSign::CounterClockwise] {
            let back = command_of(&alt_hold(&c, yaw), yaw);
            assert!((back.roll_rad - c.roll_rad).abs() < 1e-6);
            assert!((back.pitch_rad - c.pitch_rad).abs() < 1e-6);
            assert!((back.yaw_rate_radps - c.yaw_rate_radps).abs() < 1e-6);
            assert!((back.vz_mps - c.vz_mps).abs() < 1e-6);
        }
    }

    /// The external pose's quaternion: the heading about z, the roll about the forward axis
    /// (right side down), and a nose-up pitch lifting the nose.
    #[test]
    fn the_external_pose_has_the_heading_and_the_drones_tilt() {
        let pose = BodyPose {
            position_m: [1.0, -2.0, 0.5],
            heading_rad: std::f64::consts::FRAC_PI_2,
        };
        let (p, q) = ext_pose(&pose, 0.0, 0.0);
        assert_eq!(p, [1.0, -2.0, 0.5]);
        let h = std::f32::consts::FRAC_PI_4;
        for (got, want) in q.iter().zip([0.0, 0.0, h.sin(), h.cos()]) {
            assert!((got - want).abs() < 1e-6, "{q:?}");
        }
        // Nose up by 0.2 rad, heading 0: the nose vector (forward) points up.
        let level = BodyPose::default();
        let (_, q) = ext_pose(&level, 0.0, 0.2);
        let nose = rotate(q.map(f64::from), [1.0, 0.0, 0.0]);
        assert!(nose[2] > 0.19 && nose[0] > 0.97, "{nose:?}");
        // Right side down by 0.2 rad: the left vector points up.
        let (_, q) = ext_pose(&level, 0.2, 0.0);
        let left = rotate(q.map(f64::from), [0.0, 1.0, 0.0]);
        assert!(left[2] > 0.19, "{left:?}");
    }

    /// `v` rotated by the unit quaternion `[x, y, z, w]`.
    fn rotate([x, y, z, w]: [f64; 4], v: [f64; 3]) -> [f64; 3] {
        let u = [x, y, z];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let t = cross(u, v).map(|c| 2.0 * c);
        let ut = cross(u, t);
        [0, 1, 2].map(|i| v[i] + w * t[i] + ut[i])
    }

    #[test]
    fn the_logged_attitude_reads_in_the_stages_signs() {
        let (r, p, h) = attitude_of_log(10.0, -5.0, 270.0);
        assert!((r - 10f64.to_radians()).abs() < 1e-9);
        assert!((p + 5f64.to_radians()).abs() < 1e-9);
        assert!((h + 90f64.to_radians()).abs() < 1e-6);
        assert!((yaw_deg_of_heading(-std::f64::consts::FRAC_PI_2) + 90.0).abs() < 1e-4);
    }
}
