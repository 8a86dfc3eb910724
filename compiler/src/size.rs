//! Shot size → framed band → camera distance.
//!
//! A shot size names a vertical band of the actor's body (as fractions of stature H) that the
//! frame height shows. The camera distance follows from the lens: centred and level,
//! `d = W / (2 tan(fovY/2))`; in general (tilted camera, off-centre framing) the exact variant
//! puts the camera at the distance where the band's top and bottom subtend the angle between the
//! rays through the two screen points they should land on.

use crate::camera::{Lens, Vec3};
use dronecine_grammar::vocab::Size;
use dronecine_math as math;

/// Frame bottom and top as fractions of stature, for every size in `Size::ALL` order.
/// LS and ELS frame 2.0 H and 5.0 H centred on the actor's half height.
const BAND_FRACTIONS: [(f64, f64); 9] = [
    (0.90, 0.97),  // ECU
    (0.87, 0.97),  // BCU
    (0.80, 1.03),  // CU
    (0.72, 1.04),  // MCU
    (0.60, 1.05),  // MS
    (0.285, 1.06), // MLS
    (-0.03, 1.07), // FS
    (-0.50, 1.50), // LS: 2.0 H about 0.5 H
    (-2.00, 3.00), // ELS: 5.0 H about 0.5 H
];

/// Frame bottom and top of a size as fractions of stature.
pub fn band_fractions(size: Size) -> (f64, f64) {
    BAND_FRACTIONS[size as usize]
}

/// Framed band `(bottom_m, top_m)` above the actor's feet for an actor of `height_m`.
pub fn band(size: Size, height_m: f64) -> (f64, f64) {
    let (b, t) = band_fractions(size);
    (b * height_m, t * height_m)
}

/// How far a framed band may be from its size's (as a ratio of heights, either way) and
/// still be that size.
pub const SIZE_SLACK: f64 = 1.1;

/// The framed height of a size as a share of stature.
fn share(size: Size) -> f64 {
    let (b, t) = band_fractions(size);
    t - b
}

/// The size a camera frames standing `ratio` times the distance `asked` wants: the nearest
/// of the table, in the ratio of framed heights, to `asked`'s band scaled by `ratio`.
pub fn framed_at_ratio(asked: Size, ratio: f64) -> Size {
    let shown = share(asked) * ratio;
    Size::ALL
        .into_iter()
        .min_by(|x, y| {
            let off = |s: Size| math::ln(shown / share(s)).abs();
            off(*x).total_cmp(&off(*y))
        })
        .unwrap_or(asked)
}

/// Whether a camera `ratio` times the distance `asked` wants still frames that size
/// (within [`SIZE_SLACK`]).
pub fn holds_at_ratio(ratio: f64) -> bool {
    ratio <= SIZE_SLACK && ratio * SIZE_SLACK >= 1.0
}

/// The size to write for a framing whose camera stands `ratio` times the distance `asked`
/// wants. Above 1 (the camera cannot come nearer), the tightest size that needs the camera
/// no nearer than it stands, within [`SIZE_SLACK`]: written, it holds. Below 1 (the camera
/// cannot stand farther: written screen positions fix its distance), the size that camera
/// frames within the slack, or the nearest.
pub fn size_to_write(asked: Size, ratio: f64) -> Size {
    let shown = share(asked) * ratio;
    let found = if ratio >= 1.0 {
        Size::ALL
            .into_iter()
            .find(|s| shown / share(*s) <= SIZE_SLACK)
    } else {
        Size::ALL
            .into_iter()
            .rev()
            .find(|s| holds_at_ratio(shown / share(*s)))
    };
    found.unwrap_or_else(|| framed_at_ratio(asked, ratio))
}

/// Framed height W of a size for an actor of `height_m`.
pub fn framed_height_m(size: Size, height_m: f64) -> f64 {
    let (b, t) = band(size, height_m);
    t - b
}

/// Distance at which a level camera shows `framed_height_m` over the full frame height with
/// the band centred: `d = W / (2 tan(fovY/2)) = W·Sy/2`.
pub fn centred_distance_m(framed_height_m: f64, lens: &Lens) -> f64 {
    framed_height_m * lens.sy() / 2.0
}

/// Angle between the camera rays through `(x, y + 1)` and `(x, y − 1)`: the angle the band
/// subtends when it spans the frame height with its centre requested at `screen`.
pub fn band_angle_rad(lens: &Lens, screen: [f64; 2]) -> f64 {
    let top = lens.ray([screen[0], screen[1] + 1.0]);
    let bottom = lens.ray([screen[0], screen[1] - 1.0]);
    crate::camera::angle(&top, &bottom)
}

/// The screen point of the bisector of the rays through `(x, y + 1)` and `(x, y − 1)`: where
/// the band's bisector point (see [`bisector_point`]) must land for the band's top and bottom
/// to land on `(x, y ± 1)`. Its x is `x` exactly; its y equals `y` when `y = 0`.
pub fn band_aim_screen(lens: &Lens, screen: [f64; 2]) -> [f64; 2] {
    let top = lens.ray([screen[0], screen[1] + 1.0]).normalize();
    let bottom = lens.ray([screen[0], screen[1] - 1.0]).normalize();
    let v = top + bottom;
    [screen[0], v.z / v.y * lens.sy()]
}

/// The point of segment `bottom`–`top` on the bisector of the angle ∠(top, camera, bottom)
/// (angle-bisector theorem: it divides the segment in the ratio |C top| : |C bottom|). Aiming
/// this point at [`band_aim_screen`] lands the band's ends symmetrically about it.
pub fn bisector_point(camera_m: &Vec3, top_m: &Vec3, bottom_m: &Vec3) -> Vec3 {
    let ct = (top_m - camera_m).norm();
    let cb = (bottom_m - camera_m).norm();
    if ct + cb < 1e-12 {
        return (top_m + bottom_m) / 2.0;
    }
    (top_m * cb + bottom_m * ct) / (ct + cb)
}

/// The exact variant: distance `d` along a unit direction of elevation `asin(sin_elevation)`
/// from the band centre at which a vertical band of half height `half_band_m` subtends
/// `band_angle_rad`. With `s = sin(elevation)`, `c = cos²α` and `D = d²`:
/// `(1 − c)·D² − 2h²(1 + c − 2c·s²)·D + (1 − c)·h⁴ = 0`; the roots multiply to h⁴ and the one
/// above h² is taken (d above half the band). `None` for a non-positive band or an angle
/// outside (0, π).
pub fn exact_distance_m(half_band_m: f64, sin_elevation: f64, band_angle_rad: f64) -> Option<f64> {
    let h = half_band_m;
    let alpha = band_angle_rad;
    if !(h > 0.0 && h.is_finite() && alpha > 0.0 && alpha < std::f64::consts::PI) {
        return None;
    }
    let s = sin_elevation.clamp(-1.0, 1.0);
    if alpha < std::f64::consts::FRAC_PI_2 {
        let c = math::cos(alpha).powi(2);
        let a = 1.0 - c;
        let b = h * h * (1.0 + c - 2.0 * c * s * s);
        let disc = (b * b - a * a * h.powi(4)).max(0.0);
        let big_d = (b + disc.sqrt()) / a;
        return Some(big_d.sqrt());
    }
    // Wide angles (α ≥ 90°, fovY ≥ 90°): the squared equation loses the sign of cos α, so
    // bisect the subtended angle, which falls monotonically from π to 0 along the ray.
    let u = Vec3::new((1.0 - s * s).sqrt(), 0.0, s);
    let angle = |d: f64| {
        let c = u * d;
        crate::camera::angle(
            &(Vec3::new(0.0, 0.0, h) - c),
            &(Vec3::new(0.0, 0.0, -h) - c),
        )
    };
    let (mut lo, mut hi) = (0.0, h);
    while angle(hi) > alpha {
        hi *= 2.0;
        if hi > 1e9 {
            return None;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if angle(mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> Lens {
        Lens::new(84f64.to_radians(), 16.0 / 9.0)
    }

    #[test]
    fn table_matches_camera_math() {
        let w: Vec<f64> = Size::ALL.iter().map(|s| framed_height_m(*s, 1.0)).collect();
        let expected = [0.07, 0.10, 0.23, 0.32, 0.45, 0.775, 1.10, 2.0, 5.0];
        for (got, want) in w.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{w:?}");
        }
        // LS and ELS are centred on half the stature.
        for s in [Size::LS, Size::ELS] {
            let (b, t) = band(s, 1.8);
            assert!(((b + t) / 2.0 - 0.9).abs() < 1e-12);
        }
        // Sizes get wider from ECU to ELS.
        assert!(w.windows(2).all(|p| p[0] < p[1]));
    }

    #[test]
    fn exact_variant_reduces_to_centred_distance() {
        let l = lens();
        for size in Size::ALL {
            let w = framed_height_m(size, 1.75);
            let d = exact_distance_m(w / 2.0, 0.0, band_angle_rad(&l, [0.0, 0.0])).unwrap();
            assert!(
                (d - centred_distance_m(w, &l)).abs() < 1e-9 * d.max(1.0),
                "{size:?}"
            );
        }
    }

    #[test]
    fn exact_distance_subtends_the_angle() {
        for &(h, s, alpha) in &[
            (0.4, 0.34, 0.9),
            (0.4, -0.26, 0.5),
            (1.0, 0.9, 1.2),
            (0.3, 0.5, 1.8), // wide angle branch
            (0.3, 0.0, 2.5),
        ] {
            let d = exact_distance_m(h, s, alpha).unwrap();
            // Above half the band exactly when the band subtends less than 90°.
            assert_eq!(d > h, alpha < std::f64::consts::FRAC_PI_2);
            let c = Vec3::new((1.0f64 - s * s).sqrt(), 0.0, s) * d;
            let got = (Vec3::new(0.0, 0.0, h) - c).angle(&(Vec3::new(0.0, 0.0, -h) - c));
            assert!((got - alpha).abs() < 1e-9, "{h} {s} {alpha}: {got}");
        }
        assert!(exact_distance_m(0.0, 0.0, 1.0).is_none());
        assert!(exact_distance_m(1.0, 0.0, 0.0).is_none());
    }

    #[test]
    fn bisector_point_sees_equal_angles() {
        let c = Vec3::new(1.0, 0.3, 2.2);
        let (t, b) = (Vec3::new(0.0, 0.0, 1.9), Vec3::new(0.0, 0.0, 1.1));
        let q = bisector_point(&c, &t, &b);
        assert!(((t - c).angle(&(q - c)) - (b - c).angle(&(q - c))).abs() < 1e-12);
        let s = band_aim_screen(&lens(), [0.3, 0.0]);
        assert!((s[0] - 0.3).abs() < 1e-15 && s[1].abs() < 1e-12);
    }
}
