//! The camera conventions: lens, pose, projection and the roll-free orientation that puts a
//! target at a screen point.
//!
//! This module is the one source of truth for the camera frame: world z up; heading ψ
//! counter-clockwise from +x; camera pitch τ up positive; no roll. Screen (x, y) in [−1, 1]²,
//! x right, y up. A point at camera-frame coordinates (right r, forward f, up u) projects to
//! `(r·Sx/f, u·Sy/f)` with `Sx = 1/tan(fovX/2)`, `Sy = 1/tan(fovY/2)`.

use dronecine_math as math;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

pub type Vec3 = Vector3<f64>;

/// The angle between `a` and `b`, in [0, π] (nalgebra's `a.angle(&b)`, whose `acos` is the
/// platform's): 0 when either is zero.
#[inline]
pub fn angle(a: &Vec3, b: &Vec3) -> f64 {
    let (na, nb) = (a.norm(), b.norm());
    if na == 0.0 || nb == 0.0 {
        return 0.0;
    }
    let c = a.dot(b) / (na * nb);
    if c > 1.0 {
        0.0
    } else if c < -1.0 {
        std::f64::consts::PI
    } else {
        math::acos(c)
    }
}

/// A pinhole lens: horizontal field of view and frame aspect (width over height).
///
/// `Sx = 1/tan(fovX/2)` is computed once, in [`Lens::new`]: the director projects through
/// the lens a dozen times a tick, too often to take a `tan` each time.
/// Serialised as its two fields (`fov_x_rad`, `aspect`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "LensFields", into = "LensFields")]
pub struct Lens {
    fov_x_rad: f64,
    aspect: f64,
    sx: f64,
}

/// The serialised form of a [`Lens`].
#[derive(Clone, Copy, Serialize, Deserialize)]
struct LensFields {
    fov_x_rad: f64,
    aspect: f64,
}

impl From<LensFields> for Lens {
    fn from(f: LensFields) -> Lens {
        Lens::new(f.fov_x_rad, f.aspect)
    }
}

impl From<Lens> for LensFields {
    fn from(l: Lens) -> LensFields {
        LensFields {
            fov_x_rad: l.fov_x_rad,
            aspect: l.aspect,
        }
    }
}

impl Lens {
    pub fn new(fov_x_rad: f64, aspect: f64) -> Lens {
        Lens {
            fov_x_rad,
            aspect,
            sx: 1.0 / math::tan(fov_x_rad / 2.0),
        }
    }

    /// Horizontal field of view.
    pub fn fov_x_rad(&self) -> f64 {
        self.fov_x_rad
    }

    /// Frame width over height.
    pub fn aspect(&self) -> f64 {
        self.aspect
    }

    /// `Sx = 1/tan(fovX/2)`.
    pub fn sx(&self) -> f64 {
        self.sx
    }

    /// `Sy = 1/tan(fovY/2)` with `tan(fovY/2) = tan(fovX/2)/aspect`.
    pub fn sy(&self) -> f64 {
        self.sx * self.aspect
    }

    pub fn fov_y_rad(&self) -> f64 {
        2.0 * math::atan(math::tan(self.fov_x_rad / 2.0) / self.aspect)
    }

    /// The camera-frame ray (right, forward, up) through a screen point: `(x/Sx, 1, y/Sy)`.
    pub fn ray(&self, screen: [f64; 2]) -> Vec3 {
        let sx = self.sx();
        Vec3::new(screen[0] / sx, 1.0, screen[1] / (sx * self.aspect))
    }
}

/// Where a roll-free camera is and where it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    pub position_m: Vec3,
    /// Counter-clockwise from +x.
    pub heading_rad: f64,
    /// Up positive.
    pub pitch_rad: f64,
}

impl CameraPose {
    pub fn forward(&self) -> Vec3 {
        let (st, ct) = math::sin_cos(self.pitch_rad);
        let (sp, cp) = math::sin_cos(self.heading_rad);
        Vec3::new(ct * cp, ct * sp, st)
    }

    /// Horizontal: a roll-free camera's right never tilts.
    pub fn right(&self) -> Vec3 {
        let (sp, cp) = math::sin_cos(self.heading_rad);
        Vec3::new(sp, -cp, 0.0)
    }

    pub fn up(&self) -> Vec3 {
        self.right().cross(&self.forward())
    }

    /// The camera's position and axes, each angle's sine and cosine taken once: for
    /// projecting several points from one pose (the same values as [`CameraPose::right`],
    /// [`CameraPose::forward`] and [`CameraPose::up`], bit for bit).
    pub fn frame(&self) -> CameraFrame {
        let (st, ct) = math::sin_cos(self.pitch_rad);
        let (sp, cp) = math::sin_cos(self.heading_rad);
        let right = Vec3::new(sp, -cp, 0.0);
        let forward = Vec3::new(ct * cp, ct * sp, st);
        CameraFrame {
            position_m: self.position_m,
            right,
            forward,
            up: right.cross(&forward),
        }
    }

    /// Camera-frame coordinates (right, forward, up) of a world point.
    pub fn to_camera(&self, point_m: &Vec3) -> Vec3 {
        self.frame().to_camera(point_m)
    }

    /// Screen position of a world point, `None` when it is not in front of the camera.
    /// Points outside the frame project outside [−1, 1]².
    pub fn project(&self, lens: &Lens, point_m: &Vec3) -> Option<[f64; 2]> {
        self.frame().project(lens, point_m)
    }
}

/// A [`CameraPose`]'s position and unit axes ([`CameraPose::frame`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    pub position_m: Vec3,
    pub right: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
}

impl CameraFrame {
    /// Camera-frame coordinates (right, forward, up) of a world point.
    pub fn to_camera(&self, point_m: &Vec3) -> Vec3 {
        let d = point_m - self.position_m;
        Vec3::new(d.dot(&self.right), d.dot(&self.forward), d.dot(&self.up))
    }

    /// Screen position of a world point, `None` when it is not in front of the camera.
    /// Points outside the frame project outside [−1, 1]².
    pub fn project(&self, lens: &Lens, point_m: &Vec3) -> Option<[f64; 2]> {
        let c = self.to_camera(point_m);
        if c.y <= 1e-9 {
            return None;
        }
        let sx = lens.sx();
        Some([c.x * sx / c.y, c.z * (sx * lens.aspect()) / c.y])
    }
}

/// The outcome of [`orient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orientation {
    pub heading_rad: f64,
    pub pitch_rad: f64,
    /// No roll-free orientation puts the target at the requested point (it is nearly
    /// straight above or below): the pitch was clamped and the target lands elsewhere.
    pub clamped: bool,
}

/// Heading and pitch that put `target_m`, seen from `position_m`, at `screen`:
/// `τ = asin(n·sin e / √(1 + y'²)) − atan(y')`, `ψ = b + atan2(x', cos τ − y'·sin τ)`.
pub fn orient(lens: &Lens, position_m: &Vec3, target_m: &Vec3, screen: [f64; 2]) -> Orientation {
    let d = target_m - position_m;
    let b = math::atan2(d.y, d.x);
    let e = math::atan2(d.z, dronecine_math::norm_xy(d.x, d.y));
    let sx = lens.sx();
    let xp = screen[0] / sx;
    let yp = screen[1] / (sx * lens.aspect());
    let n = (1.0 + xp * xp + yp * yp).sqrt();
    let arg = n * math::sin(e) / (1.0 + yp * yp).sqrt();
    let clamped = !(-1.0..=1.0).contains(&arg);
    let pitch = math::asin(arg.clamp(-1.0, 1.0)) - math::atan(yp);
    let heading = b + math::atan2(xp, math::cos(pitch) - yp * math::sin(pitch));
    Orientation {
        heading_rad: dronecine_math::wrap_angle_rad(heading),
        pitch_rad: pitch,
        clamped,
    }
}

/// Heading only, for a camera whose pitch is fixed at `pitch_rad` (no gimbal): the target
/// lands at the requested screen x; its screen y is whatever the altitude gives.
pub fn orient_fixed_pitch(
    lens: &Lens,
    position_m: &Vec3,
    target_m: &Vec3,
    screen_x: f64,
    pitch_rad: f64,
) -> f64 {
    // In the frame turned by the heading, the target's right and forward coordinates are
    // (d·r, d·f); with pitch τ, forward f = cos τ·h + sin τ·dz where h is the horizontal
    // component along the heading. Solve r·Sx = x·f for the heading.
    let d = target_m - position_m;
    let rho = dronecine_math::norm_xy(d.x, d.y);
    let xp = screen_x / lens.sx();
    // A level camera (+0, bit for bit: sin(−0) is −0) skips the library call.
    let (sin_t, cos_t) = if pitch_rad.to_bits() == 0 {
        (0.0, 1.0)
    } else {
        math::sin_cos(pitch_rad)
    };
    // Let δ = heading − bearing; r = ρ·sin δ, f = cos τ·ρ·cos δ + sin τ·dz.
    // ρ sin δ = x' (cos τ ρ cos δ + sin τ dz)  →  ρ sin δ − x' cos τ ρ cos δ = x' sin τ dz,
    // that is amp·sin(δ + φ) = rhs with (amp cos φ, amp sin φ) = (a, c).
    let a = rho;
    let c = -xp * cos_t * rho;
    let rhs = xp * sin_t * d.z;
    let amp = dronecine_math::norm_xy(a, c);
    if amp < 1e-12 {
        return dronecine_math::wrap_angle_rad(math::atan2(d.y, d.x));
    }
    // heading = bearing + asin(s) − φ, composed as unit vectors (one atan2, no asin):
    // bearing (d.x, d.y)/ρ, asin(s) (√(1 − s²), s), −φ (a, −c)/amp; the scales do not
    // change the angle.
    let s = (rhs / amp).clamp(-1.0, 1.0);
    let cs = (1.0 - s * s).sqrt();
    let (u, v) = (cs * a + s * c, s * a - cs * c);
    let (x, y) = (d.x * u - d.y * v, d.x * v + d.y * u);
    dronecine_math::wrap_angle_rad(math::atan2(y, x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// nalgebra's `angle`, with the portable `acos`: within an ulp, the same edge cases.
    #[test]
    fn angle_is_nalgebras() {
        use dronecine_math::cos;
        fn ulps(a: f64, b: f64) -> u64 {
            (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
        }
        for k in 0..500 {
            let t = k as f64 * 0.0127;
            let a = Vector3::new(cos(t), 0.3 * t - 1.0, 0.7);
            let b = Vector3::new(-0.4, t.sin(), 1.0 - t);
            assert!(ulps(angle(&a, &b), a.angle(&b)) <= 1, "{t}");
        }
        let (x, z) = (Vector3::x(), Vector3::zeros());
        assert_eq!(angle(&x, &z), 0.0);
        assert_eq!(angle(&x, &x), 0.0);
        assert_eq!(angle(&x, &-x), std::f64::consts::PI);
    }

    fn lens() -> Lens {
        Lens::new(84f64.to_radians(), 16.0 / 9.0)
    }

    #[test]
    fn axes_are_right_handed_and_level() {
        let pose = CameraPose {
            position_m: Vec3::zeros(),
            heading_rad: 0.7,
            pitch_rad: -0.3,
        };
        let (r, f, u) = (pose.right(), pose.forward(), pose.up());
        assert!((r.cross(&f) - u).norm() < 1e-12);
        // One frame, its trigonometry taken once: the same axes, bit for bit.
        let frame = pose.frame();
        assert_eq!((frame.right, frame.forward, frame.up), (r, f, u));
        assert!(r.z.abs() < 1e-15, "no roll: right stays horizontal");
        assert!(u.z > 0.0);
        // Heading 0 looks along +x with +y on the left.
        let level = CameraPose {
            position_m: Vec3::zeros(),
            heading_rad: 0.0,
            pitch_rad: 0.0,
        };
        let p = level.project(&lens(), &Vec3::new(2.0, 0.5, 0.2)).unwrap();
        assert!(p[0] < 0.0 && p[1] > 0.0, "{p:?}");
    }

    #[test]
    fn orient_puts_the_target_where_asked() {
        let lens = lens();
        let c = Vec3::new(0.3, -2.0, 1.4);
        for target in [
            Vec3::new(0.0, 0.0, 1.5),
            Vec3::new(-1.0, 1.0, 0.2),
            Vec3::new(2.0, -1.0, 3.0),
        ] {
            for screen in [[0.0, 0.0], [-1.0 / 3.0, 0.2], [0.5, -0.4], [1.0 / 3.0, 0.6]] {
                let o = orient(&lens, &c, &target, screen);
                assert!(!o.clamped);
                let pose = CameraPose {
                    position_m: c,
                    heading_rad: o.heading_rad,
                    pitch_rad: o.pitch_rad,
                };
                let p = pose.project(&lens, &target).unwrap();
                assert!(
                    (p[0] - screen[0]).abs() < 1e-9 && (p[1] - screen[1]).abs() < 1e-9,
                    "{target:?} {screen:?} → {p:?}"
                );
            }
        }
    }

    #[test]
    fn fixed_pitch_heading_puts_the_target_at_x() {
        let lens = lens();
        let c = Vec3::new(1.0, 2.0, 1.0);
        let target = Vec3::new(-1.0, 0.5, 1.6);
        for x in [-0.5, -1.0 / 3.0, 0.0, 0.4] {
            let heading = orient_fixed_pitch(&lens, &c, &target, x, 0.0);
            let pose = CameraPose {
                position_m: c,
                heading_rad: heading,
                pitch_rad: 0.0,
            };
            let p = pose.project(&lens, &target).unwrap();
            assert!((p[0] - x).abs() < 1e-9, "{x} → {p:?}");
        }
    }

    #[test]
    fn lens_fov_y_follows_aspect() {
        let l = lens();
        assert!(((l.fov_y_rad() / 2.0).tan() - (l.fov_x_rad / 2.0).tan() / l.aspect).abs() < 1e-12);
        assert!((l.sy() - 1.0 / (l.fov_y_rad() / 2.0).tan()).abs() < 1e-12);
    }
}
