//! The baseline: tum_ardrone's per-axis PID autopilot (Engel, Sturm & Cremers),
//! kept to compare against the LQG servo on the same seeded flights.
//!
//! Errors are taken in metres and degrees, exactly as tum_ardrone does, and the outputs are
//! the AR.Drone's normalised commands in [−1, 1], scaled to our units with the profile's
//! limits (roll/pitch × tilt_max, gaz × vz_max, yaw × yaw_rate_max):
//!
//! - roll/pitch: `Kp_rp·e + Kd_rp·ė` per body axis, clipped to ±max_rp, with the world error
//!   rotated into the body frame and mapped to inputs through [`frames::INPUT_TO_BODY`];
//! - gaz: `Kp_gaz·e + Kd_gaz·ė + Ki_gaz·∫e`, clipped to [max_gaz_drop, max_gaz_rise/rise],
//!   then multiplied by the rise factor when positive;
//! - yaw: `Kp_yaw·e_deg` on the wrapped heading error, clipped to ±1.
//!
//! The D-term acts on the estimated velocity (`ė = v_ref − v̂`, tum_ardrone's `−v̂` when the
//! target is still), from the servo's own Kalman filter ([`crate::lqg::Estimator`]), fed with
//! the command actually sent. The integrator only integrates while gaz is not saturated in
//! the direction of the error (conditional integration: no wind-up), and is bounded.

use dronecine_profile::Profile;
use nalgebra::Vector3;

use crate::control::{
    Controller, ControllerState, Measurement, PidState, TickFault, TickInput, TickOutput,
};
use crate::lqg::Estimator;
use dronecine_backend::frames::{self, Command};

/// tum_ardrone's autopilot gains (errors in m and deg, outputs normalised).
pub const KP_RP: f64 = 0.5;
pub const KD_RP: f64 = 0.35;
pub const KP_GAZ: f64 = 0.6;
pub const KD_GAZ: f64 = 0.1;
pub const KI_GAZ: f64 = 0.001;
/// Per degree of heading error.
pub const KP_YAW: f64 = 0.05;
pub const MAX_RP: f64 = 1.0;
pub const MAX_YAW: f64 = 1.0;
pub const RISE_FACTOR: f64 = 2.5;
pub const MAX_GAZ_RISE: f64 = 0.8;
pub const MAX_GAZ_DROP: f64 = -0.25;

/// The PID baseline.
#[derive(Clone, Debug)]
pub struct PidController {
    estimator: Estimator,
    tilt_max_rad: f64,
    vz_max_mps: f64,
    yaw_rate_max_radps: f64,
    /// ∫ e_z dt, m·s.
    integral_z_ms: f64,
    sent: Vector3<f64>,
    sent_yaw_radps: f64,
}

impl PidController {
    pub fn new(profile: &Profile) -> PidController {
        PidController {
            estimator: Estimator::new(profile),
            tilt_max_rad: profile.limits.tilt_max_rad,
            vz_max_mps: profile.limits.vz_max_mps,
            yaw_rate_max_radps: profile.limits.yaw_rate_max_radps,
            integral_z_ms: 0.0,
            sent: Vector3::zeros(),
            sent_yaw_radps: 0.0,
        }
    }

    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }
}

impl Controller for PidController {
    fn reset(&mut self, _t_s: f64, measurement: &Measurement) {
        self.estimator.reset(measurement);
        self.integral_z_ms = 0.0;
        self.sent = Vector3::zeros();
        self.sent_yaw_radps = 0.0;
    }

    fn tick(&mut self, input: &TickInput) -> Result<TickOutput, TickFault> {
        self.estimator
            .step(input, &self.sent, self.sent_yaw_radps)?;
        let dt = input.dt_s;
        let x = self.estimator.state();
        let c = self.estimator.heading_rad();
        let r = &input.reference;

        let e = Vector3::from(r.position_m) - x.fixed_rows::<3>(3);
        let de = Vector3::from(r.velocity_mps) - x.fixed_rows::<3>(0);
        let to_body = frames::body_to_world(c).transpose();
        let (e_b, de_b) = (to_body * e, to_body * de);

        let mut saturated = false;
        // Horizontal: the body-frame push [forward, left] → inputs [φ, θ].
        let push = Vector3::new(
            KP_RP * e_b.x + KD_RP * de_b.x,
            KP_RP * e_b.y + KD_RP * de_b.y,
            0.0,
        );
        let rp = frames::INPUT_TO_BODY.transpose() * push;
        let roll = crate::lqg::clamp_to(rp[0], MAX_RP, &mut saturated);
        let pitch = crate::lqg::clamp_to(rp[1], MAX_RP, &mut saturated);

        // Vertical, with conditional integration.
        let ez = e_b.z;
        let unclipped = KP_GAZ * ez + KD_GAZ * de_b.z + KI_GAZ * self.integral_z_ms;
        let hi = MAX_GAZ_RISE / RISE_FACTOR;
        let mut gaz = unclipped.clamp(MAX_GAZ_DROP, hi);
        let gaz_saturated = gaz != unclipped;
        saturated |= gaz_saturated;
        let pushes_further = (unclipped > hi && ez > 0.0) || (unclipped < MAX_GAZ_DROP && ez < 0.0);
        if !pushes_further {
            let bound = MAX_GAZ_RISE / KI_GAZ;
            self.integral_z_ms = (self.integral_z_ms + ez * dt).clamp(-bound, bound);
        }
        if gaz > 0.0 {
            gaz *= RISE_FACTOR;
        }

        // Heading: the wrapped error in degrees, counter-clockwise positive.
        let e_deg = frames::wrap_angle_rad(r.heading_rad - c).to_degrees();
        let turn = crate::lqg::clamp_to(KP_YAW * e_deg, MAX_YAW, &mut saturated);

        let command = Command {
            roll_rad: roll * self.tilt_max_rad,
            pitch_rad: pitch * self.tilt_max_rad,
            vz_mps: gaz * self.vz_max_mps,
            yaw_rate_radps: frames::yaw_rate_command_radps(turn * self.yaw_rate_max_radps),
        };
        self.sent = command.translation_input();
        self.sent_yaw_radps = command.yaw_rate_radps;
        Ok(TickOutput {
            command,
            estimate: self.estimator.estimate(),
            saturated,
        })
    }

    fn state(&self) -> ControllerState {
        ControllerState::Pid(PidState {
            filter: self.estimator.filter_state(),
            sent_input: [self.sent[0], self.sent[1], self.sent[2]],
            sent_yaw_rate_radps: self.sent_yaw_radps,
            integral_z_ms: self.integral_z_ms,
        })
    }

    fn restore(&mut self, state: &ControllerState) -> Result<(), String> {
        let ControllerState::Pid(s) = state else {
            return Err(format!(
                "the state of a {} controller cannot be restored into the PID baseline",
                state.kind()
            ));
        };
        self.estimator.restore_filter(&s.filter);
        self.sent = Vector3::from(s.sent_input);
        self.sent_yaw_radps = s.sent_yaw_rate_radps;
        self.integral_z_ms = s.integral_z_ms;
        Ok(())
    }
}
