//! Two actors: the toric manifold of Lino & Christie (SCA 2012; ACM TOG 34(4) 2015).
//!
//! α is the angle ∠ACB under which the camera C sees the two aim points A and B (it fixes
//! their screen positions up to a rotation of the camera); θ ∈ (0, 2(π − α)) runs along the
//! generating arc from B (θ → 0) to A (θ → 2(π − α)), β = θ/2 being the angle at A between AB
//! and AC; φ turns the arc about the line AB, φ = 0 on the side where A is screen-left and B
//! screen-right (to the right of A→B seen from above), positive φ up. θ and α are not periodic
//! and are never wrapped; φ is wrapped to (−π, π].

use crate::camera::{Lens, Vec3};
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;
use std::f64::consts::PI;

/// Why a toric computation has no answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToricError {
    /// A and B coincide.
    Coincident,
    /// A and B are vertically aligned: the reference vector z is undefined.
    Vertical,
    /// α outside (0, π).
    Alpha,
    /// θ outside [0, 2(π − α)].
    Theta,
}

impl std::fmt::Display for ToricError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ToricError::Coincident => "the two actors coincide",
            ToricError::Vertical => "the two actors are vertically aligned",
            ToricError::Alpha => "the angle between the two actors is outside (0, π)",
            ToricError::Theta => "toric θ is outside (0, 2(π − α))",
        })
    }
}

impl std::error::Error for ToricError {}

/// A toric viewpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toric {
    pub alpha_rad: f64,
    pub theta_rad: f64,
    pub phi_rad: f64,
}

/// α from two requested screen points: the angle between their rays through the lens.
pub fn alpha_from_screens(lens: &Lens, screen_a: [f64; 2], screen_b: [f64; 2]) -> f64 {
    crate::camera::angle(&lens.ray(screen_a), &lens.ray(screen_b))
}

/// Radius of the circle carrying the generating arc: `r = |AB| / (2 sin α)`.
pub fn radius_m(ab_m: f64, alpha_rad: f64) -> f64 {
    ab_m / (2.0 * math::sin(alpha_rad))
}

/// The toric frame: `z = normalize(AB_y, −AB_x, 0)`, `n = normalize(A − B)`, `t = z × n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub z: Vec3,
    pub n: Vec3,
    pub t: Vec3,
}

pub fn frame(a_m: &Vec3, b_m: &Vec3) -> Result<Frame, ToricError> {
    let ab = b_m - a_m;
    let len = ab.norm();
    if len < 1e-9 {
        return Err(ToricError::Coincident);
    }
    let horizontal = dronecine_math::norm_xy(ab.x, ab.y);
    if horizontal < 1e-9 * len.max(1.0) {
        return Err(ToricError::Vertical);
    }
    let z = Vec3::new(ab.y, -ab.x, 0.0) / horizontal;
    let n = -ab / len;
    Ok(Frame {
        z,
        n,
        t: z.cross(&n),
    })
}

/// Positive and finite (false for NaN).
fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

fn check_alpha(alpha_rad: f64) -> Result<(), ToricError> {
    if alpha_rad > 0.0 && alpha_rad < PI {
        Ok(())
    } else {
        Err(ToricError::Alpha)
    }
}

/// Camera position from (α, θ, φ):
/// `C = A + (|AC|/|AB|)·Rot(n, φ)·Rot(t, β)·(B − A)`, `|AC| = |AB|·sin(α + θ/2)/sin α`.
pub fn position(a_m: &Vec3, b_m: &Vec3, v: &Toric) -> Result<Vec3, ToricError> {
    check_alpha(v.alpha_rad)?;
    let max_theta = 2.0 * (PI - v.alpha_rad);
    if !(v.theta_rad >= -1e-12 && v.theta_rad <= max_theta + 1e-12) {
        return Err(ToricError::Theta);
    }
    let f = frame(a_m, b_m)?;
    let beta = v.theta_rad / 2.0;
    let ac_m = (b_m - a_m).norm() * math::sin(v.alpha_rad + beta) / math::sin(v.alpha_rad);
    // The two rotations in closed form (Rodrigues, on the frame's axes: B − A = −|AB|·n,
    // t × n = −z, n × z = −t): Rot(t, β)·(−n) = z sin β − n cos β, then Rot(n, φ) turns z
    // into z cos φ − t sin φ and leaves n. Pinned to the rotation matrices by a test.
    let (sin_b, cos_b) = math::sin_cos(beta);
    let (sin_p, cos_p) = math::sin_cos(v.phi_rad);
    let dir = (f.z * cos_p - f.t * sin_p) * sin_b - f.n * cos_b;
    Ok(a_m + dir * ac_m)
}

/// The inverse of [`position`]: β = ∠(AB, AC), θ = 2β, α = ∠ACB, φ the signed angle from z
/// about n = A − B. On the line AB itself φ is undefined and comes out 0.
pub fn inverse(a_m: &Vec3, b_m: &Vec3, c_m: &Vec3) -> Result<Toric, ToricError> {
    let f = frame(a_m, b_m)?;
    let ac = c_m - a_m;
    let bc = c_m - b_m;
    if ac.norm() < 1e-12 || bc.norm() < 1e-12 {
        // At an actor: α is undefined.
        return Err(ToricError::Coincident);
    }
    let beta = crate::camera::angle(&(b_m - a_m), &ac);
    let alpha = crate::camera::angle(&ac, &bc);
    let w = ac - f.n * ac.dot(&f.n);
    let phi = if w.norm() < 1e-12 {
        0.0
    } else {
        math::atan2(f.n.dot(&f.z.cross(&w)), f.z.dot(&w))
    };
    Ok(Toric {
        alpha_rad: alpha,
        theta_rad: 2.0 * beta,
        phi_rad: wrap_angle_rad(phi),
    })
}

/// Keep the θ candidates inside (0, 2(π − α)), without duplicates, ascending.
/// Up to two roots θ, ascending, on the stack (the framing solve runs every tick: no heap).
/// Reads as a slice.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Roots {
    values: [f64; 2],
    len: usize,
}

impl std::ops::Deref for Roots {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

impl IntoIterator for Roots {
    type Item = f64;
    type IntoIter = std::iter::Take<std::array::IntoIter<f64, 2>>;
    fn into_iter(self) -> Self::IntoIter {
        self.values.into_iter().take(self.len)
    }
}

impl<'a> IntoIterator for &'a Roots {
    type Item = &'a f64;
    type IntoIter = std::slice::Iter<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// The candidates inside (0, 2(π − α)), finite, sorted, equal ones (within 1e-12) once.
fn keep_valid(alpha_rad: f64, thetas: [f64; 2]) -> Roots {
    let max_theta = 2.0 * (PI - alpha_rad);
    let mut out = Roots::default();
    for t in thetas {
        if t.is_finite() && t > 1e-12 && t < max_theta - 1e-12 {
            out.values[out.len] = t;
            out.len += 1;
        }
    }
    if out.len == 2 {
        if out.values[1] < out.values[0] {
            out.values.swap(0, 1);
        }
        if (out.values[1] - out.values[0]).abs() < 1e-12 {
            out.len = 1;
        }
    }
    out
}

/// Every θ at which the camera is `distance_m` from A: `sin(α + θ/2) = d/(2r)`,
/// θ = π − 2α ± 2β' with β' = arccos(d/2r), kept in (0, 2(π − α)). Empty when no point of the
/// torus is that far from A (d above 2r when α < π/2, above |AB| otherwise).
pub fn theta_for_distance_to_a(alpha_rad: f64, ab_m: f64, distance_m: f64) -> Roots {
    if check_alpha(alpha_rad).is_err() || !positive(ab_m) {
        return Roots::default();
    }
    theta_for_distance_to_a_on(alpha_rad, radius_m(ab_m, alpha_rad), distance_m)
}

/// [`theta_for_distance_to_a`] on the circle of radius `radius_m` ([`radius_m`]), for a caller
/// that already has it (the framing solve needs it for both actors).
pub fn theta_for_distance_to_a_on(alpha_rad: f64, radius_m: f64, distance_m: f64) -> Roots {
    if check_alpha(alpha_rad).is_err() || !positive(distance_m) || !positive(radius_m) {
        return Roots::default();
    }
    let ratio = distance_m / (2.0 * radius_m);
    if ratio > 1.0 {
        return Roots::default();
    }
    let bp = math::acos(ratio);
    keep_valid(
        alpha_rad,
        [
            PI - 2.0 * alpha_rad + 2.0 * bp,
            PI - 2.0 * alpha_rad - 2.0 * bp,
        ],
    )
}

/// Every θ at which the camera is `distance_m` from B: `sin(θ/2) = d/(2r)`, θ = π ∓ 2β',
/// kept in (0, 2(π − α)).
pub fn theta_for_distance_to_b(alpha_rad: f64, ab_m: f64, distance_m: f64) -> Roots {
    if check_alpha(alpha_rad).is_err() || !positive(ab_m) {
        return Roots::default();
    }
    theta_for_distance_to_b_on(alpha_rad, radius_m(ab_m, alpha_rad), distance_m)
}

/// [`theta_for_distance_to_b`] on the circle of radius `radius_m`.
pub fn theta_for_distance_to_b_on(alpha_rad: f64, radius_m: f64, distance_m: f64) -> Roots {
    if check_alpha(alpha_rad).is_err() || !positive(distance_m) || !positive(radius_m) {
        return Roots::default();
    }
    let ratio = distance_m / (2.0 * radius_m);
    if ratio > 1.0 {
        return Roots::default();
    }
    let bp = math::acos(ratio);
    keep_valid(alpha_rad, [PI - 2.0 * bp, PI + 2.0 * bp])
}

/// Distance from X along the unit direction `u` at which the other actor Y and X are seen
/// under α: `|XC| = |XY|·sin(π − α − γ)/sin α` with γ = ∠(XY, u); `None` unless γ < π − α.
pub fn toric_distance_m(x_m: &Vec3, y_m: &Vec3, alpha_rad: f64, u: &Vec3) -> Option<f64> {
    check_alpha(alpha_rad).ok()?;
    let xy = y_m - x_m;
    if xy.norm() < 1e-12 || u.norm() < 1e-12 {
        return None;
    }
    let gamma = crate::camera::angle(&xy, u);
    if gamma >= PI - alpha_rad {
        return None;
    }
    Some(xy.norm() * math::sin(PI - alpha_rad - gamma) / math::sin(alpha_rad))
}

/// The vantage formula: the camera on the torus seen from A along direction `u` (a profile
/// angle), `C = A + û·|AB|·sin(π − α − ∠(AB, u))/sin α`; `None` when ∠(AB, u) ≥ π − α.
pub fn vantage_position(a_m: &Vec3, b_m: &Vec3, alpha_rad: f64, u: &Vec3) -> Option<Vec3> {
    let d = toric_distance_m(a_m, b_m, alpha_rad, u)?;
    Some(a_m + u.normalize() * d)
}

/// Width of the band of directions, next to the edge of the torus (∠(XY, u) → π − α, where
/// the toric distance falls to 0), over which [`interpolate`] fades the pull toward the toric
/// distance out, so that the interpolated position stays continuous.
pub const PULL_FADE_RAD: f64 = 0.2;

/// Interpolation between two toric viewpoints `c0` (angle `alpha0_rad`) and `c1` (`alpha1_rad`)
/// of the same actors A and B at parameter `s` ∈ [0, 1] (Lino & Christie 2015): for each actor
/// X, the yaw of C − X is interpolated the short way round (or, given `last_turns_rad` — the
/// turn from `c0`'s yaw to `c1`'s about A and about B on the tick before —, the way nearest it:
/// see [`nearest_turn_rad`]), its elevation and length linearly; α is linear in s; the length
/// is then pulled toward the toric distance for the current α along that direction (fully,
/// except within [`PULL_FADE_RAD`] of the edge of the torus, where the pull fades linearly to
/// none so the path stays continuous; the linear length beyond the edge); the result is the
/// midpoint of the two candidates, from A and from B. The endpoints are `c0` and `c1` exactly
/// when they lie on their tori. Returns the position and the two turns taken (about A, about
/// B), for the next tick's `last_turns_rad`.
#[allow(clippy::too_many_arguments)]
pub fn interpolate(
    a_m: &Vec3,
    b_m: &Vec3,
    c0_m: &Vec3,
    c1_m: &Vec3,
    alpha0_rad: f64,
    alpha1_rad: f64,
    s: f64,
    last_turns_rad: [Option<f64>; 2],
) -> (Vec3, [f64; 2]) {
    let alpha = alpha0_rad + (alpha1_rad - alpha0_rad) * s;
    let candidate = |x: &Vec3, y: &Vec3, last: Option<f64>| -> (Vec3, f64) {
        let v0 = c0_m - x;
        let v1 = c1_m - x;
        let yaw0 = math::atan2(v0.y, v0.x);
        let yaw1 = math::atan2(v1.y, v1.x);
        let el0 = math::atan2(v0.z, math::hypot(v0.x, v0.y));
        let el1 = math::atan2(v1.z, math::hypot(v1.x, v1.y));
        let turn = nearest_turn_rad(wrap_angle_rad(yaw1 - yaw0), last);
        let yaw = yaw0 + turn * s;
        let el = el0 + (el1 - el0) * s;
        let u = Vec3::new(
            math::cos(el) * math::cos(yaw),
            math::cos(el) * math::sin(yaw),
            math::sin(el),
        );
        let linear = v0.norm() + (v1.norm() - v0.norm()) * s;
        let d = match toric_distance_m(x, y, alpha, &u) {
            Some(toric) => {
                let margin = PI - alpha - crate::camera::angle(&(y - x), &u);
                let w = (margin / PULL_FADE_RAD).clamp(0.0, 1.0);
                linear + (toric - linear) * w
            }
            None => linear,
        };
        (x + u * d, turn)
    };
    let (from_a, turn_a) = candidate(a_m, b_m, last_turns_rad[0]);
    let (from_b, turn_b) = candidate(b_m, a_m, last_turns_rad[1]);
    ((from_a + from_b) / 2.0, [turn_a, turn_b])
}

/// The turn `short_rad + 2πn` (`short_rad` wrapped to (−π, π]) nearest `last_rad`: `short_rad`
/// itself, bit for bit, when that is the nearest or when there is no `last_rad`. An
/// interpolated angle whose ends swing through the opposite side between two ticks (an actor
/// turning round) then keeps going the way it went, instead of flipping to the other side
/// of the actors in one tick. One turn past the short way is kept for as long as it lasts;
/// the move's end still lands on its end, since the turn is a whole number of turns away.
pub fn nearest_turn_rad(short_rad: f64, last_rad: Option<f64>) -> f64 {
    match last_rad {
        Some(last) if last.is_finite() && short_rad.is_finite() => {
            let near = last + wrap_angle_rad(short_rad - last);
            if (near - short_rad).abs() < PI {
                short_rad
            } else {
                near
            }
        }
        _ => short_rad,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The way round: the short turn itself, bit for bit, while it is the nearest (or with
    /// nothing to be near); past ±π, the turn the last one went on to, a whole turn from the
    /// short one.
    #[test]
    fn a_turn_goes_on_the_way_it_went() {
        for short in [-3.0, -0.4, 0.0, 1.3, PI] {
            assert_eq!(nearest_turn_rad(short, None).to_bits(), short.to_bits());
            assert_eq!(
                nearest_turn_rad(short, Some(f64::NAN)).to_bits(),
                short.to_bits()
            );
            assert_eq!(
                nearest_turn_rad(short, Some(short + 1.0)).to_bits(),
                short.to_bits()
            );
        }
        // 170° last tick, −175° (the short way now the other side) this tick: 185°.
        let got = nearest_turn_rad((-175f64).to_radians(), Some(170f64.to_radians()));
        assert!((got - 185f64.to_radians()).abs() < 1e-12, "{got}");
        // Wound one and a half turns round, and on round.
        let got = nearest_turn_rad(0.5, Some(2.0 * PI + 0.4));
        assert!((got - (2.0 * PI + 0.5)).abs() < 1e-12, "{got}");
        let got = nearest_turn_rad(-3.0, Some(-2.0 * PI - 3.1));
        assert!((got - (-2.0 * PI - 3.0)).abs() < 1e-12, "{got}");
    }

    /// `position`'s closed form is `A + |AC|/|AB|·Rot(n, φ)·Rot(t, β)·(B − A)` with the
    /// rotations as matrices, over the whole (θ, φ) range and tilted pairs.
    #[test]
    fn the_closed_form_position_is_the_two_rotations() {
        use nalgebra::{Rotation3, Unit};
        let pairs = [
            (Vec3::new(0.0, 0.0, 1.5), Vec3::new(2.0, 0.0, 1.5)),
            (Vec3::new(-1.0, 0.5, 1.7), Vec3::new(1.2, -0.3, 1.4)),
            (Vec3::new(3.0, 2.0, 0.2), Vec3::new(-0.5, 4.0, 2.9)),
        ];
        for (a, b) in pairs {
            let f = frame(&a, &b).unwrap();
            for alpha in [0.1, 0.6, 1.5, 2.8] {
                for k in 0..=8 {
                    let theta = 2.0 * (PI - alpha) * k as f64 / 8.0;
                    for phi in [-3.0, -1.2, 0.0, 0.4, 2.0, PI] {
                        let v = Toric {
                            alpha_rad: alpha,
                            theta_rad: theta,
                            phi_rad: phi,
                        };
                        let beta = theta / 2.0;
                        let rot = Rotation3::from_axis_angle(&Unit::new_unchecked(f.n), phi)
                            * Rotation3::from_axis_angle(&Unit::new_unchecked(f.t), beta);
                        let expected = a + rot * (b - a) * ((alpha + beta).sin() / alpha.sin());
                        let got = position(&a, &b, &v).unwrap();
                        assert!(
                            (got - expected).norm() < 1e-12 * (1.0 + expected.norm()),
                            "{v:?}: {got:?} against {expected:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn phi_zero_is_right_of_a_to_b_and_positive_phi_is_up() {
        let a = Vec3::new(0.0, 0.0, 1.5);
        let b = Vec3::new(2.0, 0.0, 1.5);
        let alpha = 0.6;
        let theta = PI - alpha;
        let c = position(
            &a,
            &b,
            &Toric {
                alpha_rad: alpha,
                theta_rad: theta,
                phi_rad: 0.0,
            },
        )
        .unwrap();
        assert!(c.y < 0.0 && (c.z - 1.5).abs() < 1e-12, "{c:?}");
        let up = position(
            &a,
            &b,
            &Toric {
                alpha_rad: alpha,
                theta_rad: theta,
                phi_rad: 0.3,
            },
        )
        .unwrap();
        assert!(up.z > 1.5);
    }

    #[test]
    fn theta_ends_are_the_actors() {
        let a = Vec3::new(0.0, 0.0, 1.0);
        let b = Vec3::new(1.0, 2.0, 1.2);
        let alpha = 0.8;
        let at_b = position(
            &a,
            &b,
            &Toric {
                alpha_rad: alpha,
                theta_rad: 0.0,
                phi_rad: 0.4,
            },
        )
        .unwrap();
        let at_a = position(
            &a,
            &b,
            &Toric {
                alpha_rad: alpha,
                theta_rad: 2.0 * (PI - alpha),
                phi_rad: 0.4,
            },
        )
        .unwrap();
        assert!((at_b - b).norm() < 1e-12 && (at_a - a).norm() < 1e-12);
    }

    #[test]
    fn errors_on_degenerate_input() {
        let a = Vec3::new(0.0, 0.0, 1.0);
        let v = Toric {
            alpha_rad: 0.5,
            theta_rad: 1.0,
            phi_rad: 0.0,
        };
        assert_eq!(position(&a, &a, &v), Err(ToricError::Coincident));
        assert_eq!(
            position(&a, &Vec3::new(0.0, 0.0, 2.0), &v),
            Err(ToricError::Vertical)
        );
        let bad = Toric {
            theta_rad: 5.5,
            ..v
        };
        assert_eq!(
            position(&a, &Vec3::new(1.0, 0.0, 1.0), &bad),
            Err(ToricError::Theta)
        );
    }
}
