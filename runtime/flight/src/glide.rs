//! The planned legs of a flight outside the shots: the approach to the first framing and the
//! flight back over the take-off spot, each a minimum-jerk glide along a route round the
//! actors.

use dronecine_compiler::camera::Vec3;
use dronecine_compiler::reference::Sample;
use dronecine_compiler::route::{self, Keepout, Route};
use dronecine_compiler::steering::SteerLimits;
use dronecine_math::wrap_angle_rad;
use dronecine_profile::Profile;

/// The approach: a minimum-jerk flight from the take-off hover to the first framing, along
/// the route the compiler's repositioning flights take (`route::choose`): straight when that
/// is clear, else round an actor in the way, inside the stage less its margin.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Glide {
    t0_s: f64,
    pub(crate) duration_s: f64,
    pub(crate) from_m: Vec3,
    pub(crate) to_m: Vec3,
    pub(crate) route: Route,
    from_heading_rad: f64,
    turn_rad: f64,
}

impl Glide {
    /// Long enough that the peaks stay at half the profile's speed and acceleration
    /// (minimum jerk: peak speed 1.875·d/T, peak acceleration 5.77·d/T² over the route's
    /// length d; a bend's centripetal acceleration too) and yaw rate.
    pub(crate) fn new(
        t0_s: f64,
        from: &Sample,
        to: &Sample,
        profile: &Profile,
        keep: &Keepout,
    ) -> Glide {
        let from_m = Vec3::from(from.position_m);
        let to_m = Vec3::from(to.position_m);
        let route = route::choose(&from_m, &to_m, None, keep);
        let d = match route {
            Route::Straight => (to_m - from_m).norm(),
            _ => route.length(&from_m, &to_m),
        };
        let turn_rad = wrap_angle_rad(to.heading_rad - from.heading_rad);
        let lim = &profile.limits;
        let dz = (to_m.z - from_m.z).abs();
        let mut duration_s = [
            2.0,
            1.875 * d / (0.5 * lim.speed_max_mps),
            (5.77 * d / (0.5 * lim.accel_max_mps2)).sqrt(),
            1.875 * dz / (0.5 * lim.vz_max_mps),
            1.875 * turn_rad.abs() / (0.5 * lim.yaw_rate_max_radps),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        if route != Route::Straight {
            // `fit_duration` keeps to 80% of the limits it is given: these are 62.5% of the
            // profile's, so the bend keeps to half of them.
            let half = SteerLimits {
                speed_h_mps: 0.625 * lim.speed_max_mps,
                speed_v_mps: 0.625 * lim.vz_max_mps,
                accel_h_mps2: 0.625 * lim.accel_max_mps2,
                accel_v_mps2: 0.625 * lim.accel_max_mps2,
                jerk_mps3: lim.jerk_max_mps3,
                yaw_rate_radps: lim.yaw_rate_max_radps,
                yaw_accel_radps2: 2.0 * lim.yaw_rate_max_radps,
            };
            duration_s = route.fit_duration(&from_m, &to_m, duration_s, &half);
        }
        Glide {
            t0_s,
            duration_s,
            from_m,
            to_m,
            route,
            from_heading_rad: from.heading_rad,
            turn_rad,
        }
    }

    pub(crate) fn end_s(&self) -> f64 {
        self.t0_s + self.duration_s
    }

    /// How its route goes, as the flight's events tell it (after the duration).
    pub(crate) fn way(&self) -> &'static str {
        match self.route {
            Route::Straight => "",
            Route::Around { .. } => ", round an actor in the way",
        }
    }

    pub(crate) fn sample(&self, t_s: f64, pitch_rad: f64) -> Sample {
        let u = ((t_s - self.t0_s) / self.duration_s).clamp(0.0, 1.0);
        let (s, ds, dds) = dronecine_compiler::blocking::min_jerk(u);
        let (ds, dds) = (
            ds / self.duration_s,
            dds / (self.duration_s * self.duration_s),
        );
        let (p, v, a) = match self.route {
            Route::Straight => {
                let d = self.to_m - self.from_m;
                (self.from_m + d * s, d * ds, d * dds)
            }
            // The route's first and second derivatives in s, by central differences (a
            // route is smooth, and defined a little beyond its ends).
            route => {
                let at = |s: f64| route.at(&self.from_m, &self.to_m, s);
                let h = 1e-4;
                let (p0, p, p1) = (at(s - h), at(s), at(s + h));
                let (p_s, p_ss) = ((p1 - p0) / (2.0 * h), (p1 - 2.0 * p + p0) / (h * h));
                (p, p_s * ds, p_ss * ds * ds + p_s * dds)
            }
        };
        Sample {
            t_s,
            position_m: p.into(),
            velocity_mps: v.into(),
            acceleration_mps2: a.into(),
            heading_rad: wrap_angle_rad(self.from_heading_rad + self.turn_rad * s),
            heading_rate_radps: self.turn_rad * ds,
            camera_pitch_rad: pitch_rad,
            shot: 0,
        }
    }
}

/// `at`, held still at `t_s`.
pub(crate) fn hover_sample(t_s: f64, at: &Sample) -> Sample {
    Sample {
        t_s,
        velocity_mps: [0.0; 3],
        acceleration_mps2: [0.0; 3],
        heading_rate_radps: 0.0,
        ..*at
    }
}
