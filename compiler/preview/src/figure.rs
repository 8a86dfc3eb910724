//! An actor as the camera sees it: the pure geometry behind the storyboard frames.
//!
//! A figure is built in the world from the actor's pose and stature (body proportions:
//! hip 0.530 H, shoulder 0.818 H, chin 0.870 H) and projected
//! through [`CameraPose::project`], so its size on screen follows the distance exactly as the
//! compiler's framing does (an MS reads as an MS). It has legs and a torso (outlines of two
//! boxes, which are wide seen from the front and narrow seen from the side), a head (a sphere:
//! a circle), its hair, the eyes that face the camera, and a nose: together they read the
//! profile at a glance (front: a face with two eyes under a fringe, nose in the middle; 3/4:
//! two eyes, off centre; side: one eye, the nose sticking out, hair behind; back: hair over
//! all of the head but the nape, no eye, no nose).
//!
//! All coordinates are screen coordinates of [`CameraPose::project`]: x right, y up, the frame
//! is [−1, 1]²; lengths (radii) are in screen-y units (multiply by half the frame height in
//! pixels).

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::reference::ActorPose;
use dronecine_math as math;

/// Hip height over stature.
pub const HIP: f64 = 0.530;
/// Shoulder height over stature.
pub const SHOULDER: f64 = 0.818;
/// Chin height over stature.
pub const CHIN: f64 = 0.870;
/// Head centre over stature (midway between chin and crown).
pub const HEAD_CENTRE: f64 = (CHIN + 1.0) / 2.0;
/// Head radius over stature.
pub const HEAD_RADIUS: f64 = (1.0 - CHIN) / 2.0;

/// Half-width (shoulder to shoulder) and half-depth of the torso, over stature.
const TORSO_HALF: [f64; 2] = [0.13, 0.07];
/// Half-width and half-depth of the legs, over stature.
const LEGS_HALF: [f64; 2] = [0.085, 0.06];
/// Half-width and half-depth of the neck, over stature.
const NECK_HALF: [f64; 2] = [0.035, 0.035];
/// Eye height above the head centre, in head radii (a little above the anatomical 0.936 H,
/// so that the eyes and the nose below them read apart at thumbnail size).
const EYE_LIFT: f64 = 0.2;
/// Angle of each eye from the facing direction, around the head.
const EYE_SPREAD_RAD: f64 = 0.55;
/// Nose tip distance from the head centre, in head radii.
const NOSE_REACH: f64 = 1.45;
/// The hair covers the part of the head whose surface normal `n` has `n·d ≥ HAIR_EDGE`, `d`
/// pointing back from the facing and up by [`HAIR_TILT_RAD`]: the back and the crown, down to
/// the nape behind and to a hairline about 35° above the eyes in front.
const HAIR_EDGE: f64 = -0.25;
const HAIR_TILT_RAD: f64 = 0.7;
/// Points drawn along each arc of the hair's outline.
const HAIR_ARC_POINTS: usize = 24;
/// Screen coordinates are clamped to this (a point very near the camera plane projects far
/// out; the frame clips it anyway).
const SCREEN_CLAMP: f64 = 1000.0;
/// Nearest forward distance drawn.
const NEAR_M: f64 = 0.02;

/// One actor's screen primitives.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// Forward distance from the camera to the actor's body axis at mid-height (painter's
    /// order: draw the farthest first).
    pub depth_m: f64,
    /// Screen point of the feet (the floor under the actor).
    pub feet: Option<[f64; 2]>,
    /// Convex outline of the legs (floor to hips); `None` when part of it is behind the camera.
    pub legs: Option<Vec<[f64; 2]>>,
    /// Convex outline of the torso (hips to shoulders).
    pub torso: Option<Vec<[f64; 2]>>,
    /// Convex outline of the neck (shoulders to chin).
    pub neck: Option<Vec<[f64; 2]>>,
    pub head_centre: [f64; 2],
    /// Head radius in screen-y units.
    pub head_radius: f64,
    /// The eyes that face the camera (0, 1 or 2), with their radius in screen-y units.
    pub eyes: Vec<[f64; 2]>,
    pub eye_radius: f64,
    /// The nose as a segment from the head's surface to its tip.
    pub nose: Option<[[f64; 2]; 2]>,
    /// Whether the nose is on the camera's side of the head (drawn over it) or behind it
    /// (drawn under it, so only a tip sticking out shows).
    pub nose_in_front: bool,
    /// The top of the head.
    pub crown: Option<[f64; 2]>,
    /// The hair as seen: drawn over the head's disk and cut to it.
    pub hair: Hair,
}

/// The part of a head's disk the hair covers.
#[derive(Clone, Debug, PartialEq)]
pub enum Hair {
    /// No hair shows (a face seen from below the hairline).
    None,
    /// The hair inside this outline; its edge on the head's outline lies a little outside
    /// the disk, for the disk to cut it.
    Inside(Vec<[f64; 2]>),
    /// Hair over the whole disk but this outline (skin).
    AllBut(Vec<[f64; 2]>),
    /// Hair over the whole disk.
    All,
}

impl Hair {
    /// The share of a head's disk the hair covers, the disk of `radius` (screen-y units)
    /// about `centre` through a lens of `aspect`: the share of a grid of points over the disk
    /// inside the hair (screen x is `aspect` times shorter than screen y).
    pub fn share(&self, centre: [f64; 2], radius: f64, aspect: f64) -> f64 {
        let (n, mut inside, mut hair) = (60, 0usize, 0usize);
        for i in 0..n {
            for j in 0..n {
                let u = [
                    (i as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                    (j as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                ];
                if u[0] * u[0] + u[1] * u[1] > 1.0 {
                    continue;
                }
                inside += 1;
                let p = [
                    centre[0] + u[0] * radius / aspect,
                    centre[1] + u[1] * radius,
                ];
                hair += usize::from(match self {
                    Hair::None => false,
                    Hair::Inside(o) => contains(o, p),
                    Hair::AllBut(o) => !contains(o, p),
                    Hair::All => true,
                });
            }
        }
        hair as f64 / inside.max(1) as f64
    }
}

/// Whether `p` is inside the outline (even-odd rule).
fn contains(outline: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    for (i, a) in outline.iter().enumerate() {
        let b = outline[(i + 1) % outline.len()];
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
        {
            inside = !inside;
        }
    }
    inside
}

fn clamp_screen(p: [f64; 2]) -> [f64; 2] {
    [
        p[0].clamp(-SCREEN_CLAMP, SCREEN_CLAMP),
        p[1].clamp(-SCREEN_CLAMP, SCREEN_CLAMP),
    ]
}

fn project(pose: &CameraPose, lens: &Lens, p: &Vec3) -> Option<[f64; 2]> {
    if pose.to_camera(p).y < NEAR_M {
        return None;
    }
    pose.project(lens, p).map(clamp_screen)
}

/// Convex hull (counter-clockwise, Andrew's monotone chain) of screen points.
pub fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut pts: Vec<[f64; 2]> = points
        .iter()
        .copied()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(pts.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The projected outline of an upright box around the body axis.
fn box_outline(
    pose: &CameraPose,
    lens: &Lens,
    base: &Vec3,
    facing: &Vec3,
    left: &Vec3,
    z: [f64; 2],
    half: [f64; 2],
) -> Option<Vec<[f64; 2]>> {
    let mut pts = Vec::with_capacity(8);
    for &zz in &z {
        for sw in [-1.0, 1.0] {
            for sd in [-1.0, 1.0] {
                let p = base + left * (sw * half[0]) + facing * (sd * half[1]) + Vec3::z() * zz;
                pts.push(project(pose, lens, &p)?);
            }
        }
    }
    Some(convex_hull(&pts))
}

/// The screen primitives of `actor` seen from `pose` through `lens`; `None` when its head is
/// behind the camera (or the pose is not finite).
pub fn figure(pose: &CameraPose, lens: &Lens, actor: &ActorPose) -> Option<Figure> {
    let h = actor.height_m;
    let finite = h.is_finite()
        && h > 0.0
        && actor.facing_rad.is_finite()
        && actor.position_m.iter().all(|v| v.is_finite());
    if !finite {
        return None;
    }
    let base = Vec3::new(
        actor.position_m[0],
        actor.position_m[1],
        actor.position_m[2],
    );
    let (s, c) = math::sin_cos(actor.facing_rad);
    let facing = Vec3::new(c, s, 0.0);
    let left = Vec3::new(-s, c, 0.0);

    let head_c = base + Vec3::z() * (HEAD_CENTRE * h);
    let head_r = HEAD_RADIUS * h;
    let head_cam = pose.to_camera(&head_c);
    if head_cam.y < NEAR_M + head_r * 0.5 {
        return None;
    }
    let head_centre = project(pose, lens, &head_c)?;
    let head_radius = head_r * lens.sy() / head_cam.y;

    let to_camera = |p: &Vec3| (pose.position_m - p).normalize();

    let mut eyes = Vec::new();
    let eye_z = EYE_LIFT * head_r;
    for side in [-1.0, 1.0] {
        let (se, ce) = math::sin_cos(side * EYE_SPREAD_RAD);
        let normal = facing * ce + left * se;
        let p = head_c + normal * (head_r * 0.92) + Vec3::z() * eye_z;
        // Visible when the surface there faces the camera.
        if normal.dot(&to_camera(&p)) > 0.15 {
            if let Some(q) = project(pose, lens, &p) {
                eyes.push(q);
            }
        }
    }
    let eye_radius = head_radius * 0.16;

    // The nose slopes down from between the eyes: a short vertical stroke seen from the
    // front, a beak seen from the side.
    let nose_root = head_c + facing * (head_r * 0.9);
    let nose_tip = head_c + facing * (head_r * NOSE_REACH) - Vec3::z() * (0.45 * head_r);
    let nose = match (
        project(pose, lens, &nose_root),
        project(pose, lens, &nose_tip),
    ) {
        (Some(a), Some(b)) => Some([a, b]),
        _ => None,
    };
    let nose_in_front = facing.dot(&to_camera(&head_c)) > 0.0;

    let (sh, ch) = math::sin_cos(HAIR_TILT_RAD);
    let hair_dir = Vec3::z() * sh - facing * ch;
    let hair = hair(pose, lens, &head_c, head_r, &hair_dir, head_centre);

    let mid = base + Vec3::z() * (0.5 * h);
    Some(Figure {
        depth_m: pose.to_camera(&mid).y,
        feet: project(pose, lens, &base),
        legs: box_outline(
            pose,
            lens,
            &base,
            &facing,
            &left,
            [0.0, HIP * h],
            LEGS_HALF.map(|v| v * h),
        ),
        torso: box_outline(
            pose,
            lens,
            &base,
            &facing,
            &left,
            [HIP * h, SHOULDER * h],
            TORSO_HALF.map(|v| v * h),
        ),
        neck: box_outline(
            pose,
            lens,
            &base,
            &facing,
            &left,
            [(SHOULDER - 0.02) * h, (CHIN + 0.02) * h],
            NECK_HALF.map(|v| v * h),
        ),
        head_centre,
        head_radius,
        eyes,
        eye_radius,
        nose,
        nose_in_front,
        crown: project(pose, lens, &(base + Vec3::z() * h)),
        hair,
    })
}

/// Two unit vectors that make a right-handed frame with the unit vector `d`.
fn basis(d: &Vec3) -> (Vec3, Vec3) {
    let seed = if d.z.abs() < 0.9 {
        Vec3::z()
    } else {
        Vec3::x()
    };
    let e1 = seed.cross(d).normalize();
    (e1, d.cross(&e1))
}

/// Where on the circle `centre + radius (cos t e1 + sin t e2)` (unit normals) the normal's
/// dot with `w` reaches `at_least`: the arc `(mid, half)`, `t` in `mid ± half`; `half` is π
/// for the whole circle, `None` for none of it.
fn arc(centre: &Vec3, radius: f64, e: (Vec3, Vec3), w: &Vec3, at_least: f64) -> Option<(f64, f64)> {
    let a = centre.dot(w) - at_least;
    let (b1, b2) = (radius * e.0.dot(w), radius * e.1.dot(w));
    let b = math::hypot(b1, b2);
    if b < 1e-12 {
        return (a >= 0.0).then_some((0.0, std::f64::consts::PI));
    }
    let c = -a / b;
    (c <= 1.0).then(|| (math::atan2(b2, b1), math::acos(c.max(-1.0))))
}

/// The hair of a head of radius `r` about `c` seen from `pose`: the part of its visible
/// surface whose normal `n` has `n·d ≥ HAIR_EDGE`. Its outline is the arc of the visible
/// rim (normals with `n·v = r/D`, `v` toward the camera `D` away) inside the hair, then the
/// arc of the hairline (`n·d = HAIR_EDGE`) on the visible side.
fn hair(pose: &CameraPose, lens: &Lens, c: &Vec3, r: f64, d: &Vec3, centre_px: [f64; 2]) -> Hair {
    let to_cam = pose.position_m - c;
    let dist = to_cam.norm();
    if !(dist > r) {
        return Hair::None;
    }
    let v = to_cam / dist;
    let s = r / dist;
    // The rim: normals s·v + ρ(cos t e1 + sin t e2); the hairline: k·d + σ(cos u g1 + sin u g2).
    let (rim_c, rim_r, rim_e) = (v * s, (1.0 - s * s).sqrt(), basis(&v));
    let k = HAIR_EDGE;
    let (line_c, line_r, line_e) = (d * k, (1.0 - k * k).sqrt(), basis(d));
    let point = |centre: &Vec3, radius: f64, e: &(Vec3, Vec3), t: f64| {
        let (st, ct) = math::sin_cos(t);
        centre + (e.0 * ct + e.1 * st) * radius
    };
    let rim = arc(&rim_c, rim_r, rim_e, d, k);
    let line = arc(&line_c, line_r, line_e, &v, s);
    let to_screen = |n: Vec3, push: f64| {
        project(pose, lens, &(c + n * r)).map(|p| {
            [
                centre_px[0] + (p[0] - centre_px[0]) * push,
                centre_px[1] + (p[1] - centre_px[1]) * push,
            ]
        })
    };
    let samples = |centre: &Vec3, radius: f64, e: &(Vec3, Vec3), from: f64, to: f64, push: f64| {
        (0..=HAIR_ARC_POINTS)
            .map(|i| {
                let t = from + (to - from) * i as f64 / HAIR_ARC_POINTS as f64;
                to_screen(point(centre, radius, e, t), push)
            })
            .collect::<Option<Vec<[f64; 2]>>>()
    };
    let full = std::f64::consts::PI - 1e-9;
    let whole_hairline = || {
        samples(
            &line_c,
            line_r,
            &line_e,
            0.0,
            2.0 * std::f64::consts::PI,
            1.0,
        )
    };
    let outline = match (rim, line) {
        (None, None) => return Hair::None,
        (Some((_, half)), _) if half >= full => {
            // The whole rim is hair: the skin, if any, is a patch inside it.
            return match line {
                Some((_, h)) if h >= full => whole_hairline().map_or(Hair::All, Hair::AllBut),
                _ => Hair::All,
            };
        }
        (None, Some((_, half))) if half >= full => whole_hairline(),
        (Some((t, a)), Some((u, b))) => {
            // The rim's arc ends where the hairline's does; walk the hairline back from there.
            let rim_end = point(&rim_c, rim_r, &rim_e, t + a);
            let near_hi = (point(&line_c, line_r, &line_e, u + b) - rim_end).norm();
            let near_lo = (point(&line_c, line_r, &line_e, u - b) - rim_end).norm();
            let (from, to) = if near_hi <= near_lo {
                (u + b, u - b)
            } else {
                (u - b, u + b)
            };
            // Pushed out a tenth: the head's disk cuts the rim's arc.
            let rim_pts = samples(&rim_c, rim_r, &rim_e, t - a, t + a, 1.1);
            let line_pts = samples(&line_c, line_r, &line_e, from, to, 1.0);
            rim_pts.zip(line_pts).map(|(mut p, q)| {
                p.extend(q);
                p
            })
        }
        _ => return Hair::None,
    };
    outline.map_or(Hair::None, Hair::Inside)
}

/// Clips the world segment `a`–`b` to the part in front of the camera and projects it.
pub fn project_segment(
    pose: &CameraPose,
    lens: &Lens,
    a: &Vec3,
    b: &Vec3,
) -> Option<[[f64; 2]; 2]> {
    let (da, db) = (pose.to_camera(a).y, pose.to_camera(b).y);
    if da < NEAR_M && db < NEAR_M {
        return None;
    }
    let cut = |p: &Vec3, q: &Vec3, dp: f64, dq: f64| p + (q - p) * ((NEAR_M - dp) / (dq - dp));
    // A cut lands exactly on the near plane; it is nudged inside before projecting.
    let nudge = |p: Vec3| p + pose.forward() * 1e-6;
    let a2 = if da < NEAR_M {
        nudge(cut(a, b, da, db))
    } else {
        *a
    };
    let b2 = if db < NEAR_M {
        nudge(cut(b, a, db, da))
    } else {
        *b
    };
    let pa = pose.project(lens, &a2)?;
    let pb = pose.project(lens, &b2)?;
    Some([clamp_screen(pa), clamp_screen(pb)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_an_inner_point() {
        let hull = convex_hull(&[[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(hull.len(), 4);
        assert!(!hull.contains(&[0.5, 0.5]));
    }

    #[test]
    fn segment_behind_is_cut_at_the_near_plane() {
        let lens = Lens::new(std::f64::consts::FRAC_PI_2, 16.0 / 9.0);
        let pose = CameraPose {
            position_m: Vec3::zeros(),
            heading_rad: 0.0,
            pitch_rad: 0.0,
        };
        // From behind the camera to 2 m ahead, 1 m below: the visible part ends at the
        // ahead point.
        let s = project_segment(
            &pose,
            &lens,
            &Vec3::new(-1.0, 0.0, -1.0),
            &Vec3::new(2.0, 0.0, -1.0),
        )
        .unwrap();
        let far = pose.project(&lens, &Vec3::new(2.0, 0.0, -1.0)).unwrap();
        assert!((s[1][0] - far[0]).abs() < 1e-12 && (s[1][1] - far[1]).abs() < 1e-12);
        assert!(s[0][1] < -10.0, "the near end runs far down: {:?}", s[0]);
        assert!(project_segment(
            &pose,
            &lens,
            &Vec3::new(-1.0, 0.0, 0.0),
            &Vec3::new(-2.0, 1.0, 0.0)
        )
        .is_none());
    }
}
