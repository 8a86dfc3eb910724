//! The actors as the director sees them: each tracked body's pose smoothed into a position,
//! a velocity, a facing and a turn rate, and the rule for which mocap frames count.

use dronecine_backend::{BodyPose, MocapFrame};
use dronecine_compiler::reference::ActorPose;
use dronecine_grammar::script::Scene;
use dronecine_math::wrap_angle_rad;

/// Actor poses from the mocap, smoothed by an α-β tracker per actor: the director wants a
/// velocity and a turn rate (feed-forward), which raw differences of a noisy position would
/// make jumpy.
///
/// Positions: the steady-state gains of the Kalman filter of a body whose acceleration is
/// white ([`TRACK_ACTOR_ACCEL_MPS2`]) measured with noise ([`TRACK_POSITION_NOISE_M`]) every
/// `T` (Kalata's α-β filter, [`alpha_beta`]): at 100 Hz α = 0.44, β = 0.125. These pass as
/// little of the mocap's noise into the velocity as a walk's acceleration allows, and the
/// director feeds that velocity forward and differentiates it again.
/// Facing: fixed α = 0.7, β = 0.2, which follow an actor turning on their mark closely enough
/// for the one-actor holds whose framing turns with the actor's facing.
#[derive(Clone, Debug, Default)]
pub(crate) struct ActorTracker {
    pub(crate) poses: Vec<ActorPose>,
    last_t_s: Vec<Option<f64>>,
}

/// The motion capture's position noise the tracker expects (OptiTrack's sub-millimetre, as
/// the simulator's `mocap_position_sigma_m`).
const TRACK_POSITION_NOISE_M: f64 = 0.0003;
/// How fast actors change their velocity (RMS): a walk starting or stopping.
const TRACK_ACTOR_ACCEL_MPS2: f64 = 0.5;
const TRACK_FACING_ALPHA: f64 = 0.7;
const TRACK_FACING_BETA: f64 = 0.2;

/// Kalata's steady-state α-β gains for a tracking index `λ = σ_a·T²/σ_n` (the body's RMS
/// acceleration over the measurement noise, in steps of `T`): `r = (4 + λ − √(8λ + λ²))/4`,
/// `α = 1 − r²`, `β = 2(2 − α) − 4√(1 − α)`.
fn alpha_beta(lambda: f64) -> (f64, f64) {
    let r = (4.0 + lambda - (8.0 * lambda + lambda * lambda).sqrt()) / 4.0;
    let alpha = 1.0 - r * r;
    (alpha, 2.0 * (2.0 - alpha) - 4.0 * (1.0 - alpha).sqrt())
}

impl ActorTracker {
    pub(crate) fn new(scene: &Scene) -> Self {
        ActorTracker {
            poses: scene
                .actors
                .iter()
                .map(|a| ActorPose {
                    position_m: [a.position_m[0], a.position_m[1], 0.0],
                    velocity_mps: [0.0; 3],
                    facing_rad: a.facing_rad,
                    facing_rate_radps: 0.0,
                    height_m: a.height_m,
                })
                .collect(),
            last_t_s: vec![None; scene.actors.len()],
        }
    }

    /// Becomes `other`, reusing its vectors (no allocation once they have room).
    pub(crate) fn copy_from(&mut self, other: &ActorTracker) {
        self.poses.clone_from(&other.poses);
        self.last_t_s.clone_from(&other.last_t_s);
    }

    /// Folds a frame in. Untracked actors keep moving with their last velocity for the tick.
    pub(crate) fn update(&mut self, frame: &MocapFrame) {
        for (i, pose) in self.poses.iter_mut().enumerate() {
            let Some(Some(m)) = frame.actors.get(i) else {
                continue;
            };
            if !finite_pose(m) {
                continue;
            }
            match self.last_t_s[i] {
                Some(t0) if frame.t_s > t0 => {
                    let dt = frame.t_s - t0;
                    let (alpha, beta) =
                        alpha_beta(TRACK_ACTOR_ACCEL_MPS2 * dt * dt / TRACK_POSITION_NOISE_M);
                    for k in 0..2 {
                        let pred = pose.position_m[k] + pose.velocity_mps[k] * dt;
                        let r = m.position_m[k] - pred;
                        pose.position_m[k] = pred + alpha * r;
                        pose.velocity_mps[k] += beta * r / dt;
                    }
                    let pred = pose.facing_rad + pose.facing_rate_radps * dt;
                    let r = wrap_angle_rad(m.heading_rad - pred);
                    pose.facing_rad = wrap_angle_rad(pred + TRACK_FACING_ALPHA * r);
                    pose.facing_rate_radps += TRACK_FACING_BETA * r / dt;
                }
                Some(_) => continue,
                None => {
                    pose.position_m = [m.position_m[0], m.position_m[1], 0.0];
                    pose.facing_rad = m.heading_rad;
                }
            }
            pose.position_m[2] = 0.0;
            self.last_t_s[i] = Some(frame.t_s);
        }
    }
}

/// Whether a frame just polled is newer than the last one used, which it then becomes: an
/// out-of-order or replayed frame is not used. (The one rule, for the loop and for the
/// director ahead of it.)
pub(crate) fn take_newer(last_frame_t_s: &mut Option<f64>, frame: &MocapFrame) -> bool {
    if last_frame_t_s.is_some_and(|t0| frame.t_s <= t0) {
        return false;
    }
    *last_frame_t_s = Some(frame.t_s);
    true
}

/// Whether a tracked pose is numbers (a body the mocap lost can come as NaN).
pub(crate) fn finite_pose(p: &BodyPose) -> bool {
    p.position_m.iter().all(|x| x.is_finite()) && p.heading_rad.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kalata's closed form against the steady state of the Kalman filter it stands for,
    /// iterated to convergence: a position measured with variance σ_n² every `T`, its
    /// acceleration white and held over each step (variance σ_a²). The filter's gain is
    /// `[α, β/T]`.
    #[test]
    fn the_actor_trackers_gains_are_the_kalman_filters_steady_state() {
        for (sigma_a, t, sigma_n) in [
            (TRACK_ACTOR_ACCEL_MPS2, 0.01_f64, TRACK_POSITION_NOISE_M),
            (0.5, 1.0 / 120.0, 0.0003),
            (2.0, 0.05, 0.001),
            (0.1, 0.01, 0.01),
        ] {
            let q = sigma_a * sigma_a;
            let r = sigma_n * sigma_n;
            let (mut p11, mut p12, mut p22) = (1.0, 0.0, 1.0);
            let (mut k1, mut k2) = (0.0, 0.0);
            for _ in 0..200_000 {
                // Predict: P = F·P·Fᵀ + Q.
                let a11 = p11 + 2.0 * t * p12 + t * t * p22 + q * t.powi(4) / 4.0;
                let a12 = p12 + t * p22 + q * t.powi(3) / 2.0;
                let a22 = p22 + q * t * t;
                // Update with the position.
                let s = a11 + r;
                (k1, k2) = (a11 / s, a12 / s);
                (p11, p12, p22) = ((1.0 - k1) * a11, (1.0 - k1) * a12, a22 - k2 * a12);
            }
            let (alpha, beta) = alpha_beta(sigma_a * t * t / sigma_n);
            assert!((alpha - k1).abs() < 1e-9, "α {alpha} against {k1}");
            assert!((beta - k2 * t).abs() < 1e-9, "β {beta} against {}", k2 * t);
        }
        // At 100 Hz with the tracker's own figures.
        let (alpha, beta) = alpha_beta(TRACK_ACTOR_ACCEL_MPS2 * 1e-4 / TRACK_POSITION_NOISE_M);
        assert!((alpha - 0.4375).abs() < 1e-3 && (beta - 0.125).abs() < 1e-3);
    }
}
