//! One actor: the sphere manifold.
//!
//! `C = P + d·û`, `û = cos φ (cos θ f̂ + sin θ l̂) + sin φ ẑ`, with P the aim point (centre of
//! the framed band), f̂ = (cos h, sin h, 0) the actor's facing, `l̂ = ẑ × f̂` the actor's left,
//! θ the profile azimuth (counter-clockwise toward the actor's left, front 0) and φ the
//! elevation (camera angle, [`elevation_rad`]). Since `cos θ f̂ + sin θ l̂` is the horizontal
//! unit vector at angle `h + θ`, the sphere direction depends on h and θ only through their
//! sum: an actor who turns swings the camera round.

use crate::camera::Vec3;
use dronecine_grammar::vocab::CameraAngle;
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;

/// Elevation of `high angle` (project convention).
pub const HIGH_ANGLE_ELEVATION_RAD: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// Elevation of `low angle` (project convention).
pub const LOW_ANGLE_ELEVATION_RAD: f64 = -15.0 * std::f64::consts::PI / 180.0;
/// Elevation of `eye level`.
pub const EYE_LEVEL_ELEVATION_RAD: f64 = 0.0;

/// The camera elevation φ of a camera angle: the one place these numbers live.
pub fn elevation_rad(angle: CameraAngle) -> f64 {
    match angle {
        CameraAngle::EyeLevel => EYE_LEVEL_ELEVATION_RAD,
        CameraAngle::High => HIGH_ANGLE_ELEVATION_RAD,
        CameraAngle::Low => LOW_ANGLE_ELEVATION_RAD,
    }
}

/// The unit vector û from the aim point to the camera for an actor facing `facing_rad`,
/// profile azimuth `azimuth_rad` (θ) and elevation `elevation_rad` (φ).
pub fn direction(facing_rad: f64, azimuth_rad: f64, elevation_rad: f64) -> Vec3 {
    let (sa, ca) = math::sin_cos(facing_rad + azimuth_rad);
    let (se, ce) = math::sin_cos(elevation_rad);
    Vec3::new(ce * ca, ce * sa, se)
}

/// ∂û/∂θ (equal to ∂û/∂h).
pub fn d_direction_d_azimuth(facing_rad: f64, azimuth_rad: f64, elevation_rad: f64) -> Vec3 {
    let (sa, ca) = math::sin_cos(facing_rad + azimuth_rad);
    let ce = math::cos(elevation_rad);
    Vec3::new(-ce * sa, ce * ca, 0.0)
}

/// ∂û/∂φ.
pub fn d_direction_d_elevation(facing_rad: f64, azimuth_rad: f64, elevation_rad: f64) -> Vec3 {
    let (sa, ca) = math::sin_cos(facing_rad + azimuth_rad);
    let (se, ce) = math::sin_cos(elevation_rad);
    Vec3::new(-se * ca, -se * sa, ce)
}

/// A point of the sphere: distance, azimuth relative to the facing, elevation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spherical {
    pub distance_m: f64,
    /// θ, measured from the actor's facing, counter-clockwise, wrapped to (−π, π].
    pub azimuth_rad: f64,
    /// φ, up positive, in [−π/2, π/2].
    pub elevation_rad: f64,
}

/// Camera position `C = P + d·û(h + θ, φ)`.
pub fn position(aim_m: &Vec3, facing_rad: f64, s: &Spherical) -> Vec3 {
    aim_m + direction(facing_rad, s.azimuth_rad, s.elevation_rad) * s.distance_m
}

/// The inverse of [`position`]: the spherical coordinates of `camera_m` about `aim_m` for an
/// actor facing `facing_rad`. At the aim point itself the direction is undefined and the
/// azimuth and elevation come out 0.
pub fn inverse(aim_m: &Vec3, facing_rad: f64, camera_m: &Vec3) -> Spherical {
    let v = camera_m - aim_m;
    let rho = math::hypot(v.x, v.y);
    Spherical {
        distance_m: v.norm(),
        azimuth_rad: wrap_angle_rad(math::atan2(v.y, v.x) - facing_rad),
        elevation_rad: math::atan2(v.z, rho),
    }
}

/// Rates of the sphere coordinates and of the actor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    /// Ṗ: velocity of the aim point (the actor's velocity when the band height is fixed).
    pub aim_velocity_mps: Vec3,
    /// ḣ: the actor's turn rate.
    pub facing_rate_radps: f64,
    pub distance_rate_mps: f64,
    pub azimuth_rate_radps: f64,
    pub elevation_rate_radps: f64,
}

/// Camera velocity `Ċ = Ṗ + ḋ·û + d·(∂û/∂θ·(θ̇ + ḣ) + ∂û/∂φ·φ̇)`. The actor terms Ṗ and ḣ are
/// the feed-forward that keeps the camera with a walking or turning actor.
pub fn velocity(facing_rad: f64, s: &Spherical, r: &Rates) -> Vec3 {
    let u = direction(facing_rad, s.azimuth_rad, s.elevation_rad);
    let du_dt = d_direction_d_azimuth(facing_rad, s.azimuth_rad, s.elevation_rad);
    let du_dp = d_direction_d_elevation(facing_rad, s.azimuth_rad, s.elevation_rad);
    r.aim_velocity_mps
        + u * r.distance_rate_mps
        + (du_dt * (r.azimuth_rate_radps + r.facing_rate_radps) + du_dp * r.elevation_rate_radps)
            * s.distance_m
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_grammar::vocab::Profile;

    #[test]
    fn profile_34left_is_front_left_of_the_actor() {
        // Actor faces +y: the left is −x.
        let h = std::f64::consts::FRAC_PI_2;
        let u = direction(h, Profile::ThreeQuarterLeft.azimuth_rad(), 0.0);
        assert!(u.y > 0.0 && u.x < 0.0, "{u:?}");
        let f = Vec3::new(h.cos(), h.sin(), 0.0);
        let l = Vec3::z().cross(&f);
        let th = 0.7f64;
        let phi = 0.3f64;
        let doc = (f * th.cos() + l * th.sin()) * phi.cos() + Vec3::z() * phi.sin();
        assert!((direction(h, th, phi) - doc).norm() < 1e-12);
    }

    #[test]
    fn inverse_undoes_position() {
        let p = Vec3::new(0.5, -1.0, 1.2);
        let s = Spherical {
            distance_m: 2.3,
            azimuth_rad: -2.1,
            elevation_rad: 0.35,
        };
        let back = inverse(&p, 1.1, &position(&p, 1.1, &s));
        assert!((back.distance_m - s.distance_m).abs() < 1e-12);
        assert!((back.azimuth_rad - s.azimuth_rad).abs() < 1e-12);
        assert!((back.elevation_rad - s.elevation_rad).abs() < 1e-12);
    }

    #[test]
    fn camera_angles_are_in_one_table() {
        assert!(elevation_rad(CameraAngle::High) > 0.0);
        assert!(elevation_rad(CameraAngle::Low) < 0.0);
        assert_eq!(elevation_rad(CameraAngle::EyeLevel), 0.0);
    }
}
