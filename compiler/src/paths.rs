//! Hand-crafted paths (`path square`, `helix`, `orbit`, `waypoints`) as smooth functions of
//! time.
//!
//! Every path starts and ends at rest: the distance along the path follows a trapezoidal
//! speed profile whose ramps are minimum-jerk curves, so speed and acceleration are
//! continuous. Square corners are rounded (a quarter circle whose radius keeps the centripetal
//! acceleration within half the profile's limit) and waypoints are joined by a C¹ spline with
//! chord-length parameters, so the target the camera steers toward has bounded acceleration.

use dronecine_math as math;
use std::f64::consts::{PI, TAU};

use dronecine_grammar::script::{OrbitCenter, PathShape};

use crate::camera::Vec3;
use crate::reference::ActorPose;

/// `x` held within `lo..=hi`, as `f64::clamp` holds it, except that bounds the wrong way
/// round (or NaN) do not panic: the upper bound wins over the lower, and a NaN bound holds
/// nothing. The paths are planned from a script's numbers, whatever they are.
pub(crate) fn bounded(x: f64, lo: f64, hi: f64) -> f64 {
    let mut v = x;
    if v < lo {
        v = lo;
    }
    if v > hi {
        v = hi;
    }
    v
}

/// Fraction of the path (0 → 1) and its rate (1/s) at `t_s` into a path of `duration_s`,
/// with ramps of `ramp_s` at each end. A path without a positive, finite length of time
/// jumps from its start to its end at 0 s.
pub fn ease(t_s: f64, duration_s: f64, ramp_s: f64) -> (f64, f64) {
    let t = bounded(t_s, 0.0, duration_s);
    let r = bounded(ramp_s, 1e-9, duration_s / 2.0);
    if !(r > 0.0 && duration_s - r > 0.0 && duration_s.is_finite()) {
        return (if t_s > 0.0 { 1.0 } else { 0.0 }, 0.0);
    }
    // Ramp speed factor σ(u) (min-jerk), its integral Σ(u) = 2.5u⁴ − 3u⁵ + u⁶ (Σ(1) = ½).
    let sigma = |u: f64| u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
    let big_sigma = |u: f64| u.powi(4) * (2.5 - 3.0 * u + u * u);
    let v = 1.0 / (duration_s - r);
    if t < r {
        (v * r * big_sigma(t / r), v * sigma(t / r))
    } else if t > duration_s - r {
        let u = (duration_s - t) / r;
        (1.0 - v * r * big_sigma(u), v * sigma(u))
    } else {
        (v * (t - r / 2.0), v)
    }
}

/// Length of the ramps at each end of a path of `duration_s`.
pub fn ramp_s(duration_s: f64) -> f64 {
    (duration_s / 4.0).min(1.5)
}

/// A path ready to evaluate.
#[derive(Clone, Debug)]
pub struct PathPlan {
    geometry: Geometry,
    duration_s: f64,
    ramp_s: f64,
}

#[derive(Clone, Debug)]
enum Geometry {
    /// A closed polyline of straight segments and arcs, by arc length.
    Rounded {
        pieces: Vec<Piece>,
        length_m: f64,
        altitude_m: f64,
    },
    Helix {
        center: [f64; 2],
        radius_m: f64,
        from_m: f64,
        to_m: f64,
        start_rad: f64,
        sweep_rad: f64,
    },
    Orbit {
        center: OrbitAround,
        radius_m: f64,
        altitude_m: f64,
        start_rad: f64,
        sweep_rad: f64,
    },
    Spline {
        points: Vec<Vec3>,
        tangents: Vec<Vec3>,
        /// Cumulative chord length at each point.
        knots: Vec<f64>,
    },
}

#[derive(Clone, Debug)]
enum OrbitAround {
    Point([f64; 2]),
    Actor(usize),
}

#[derive(Clone, Copy, Debug)]
enum Piece {
    Line {
        from: [f64; 2],
        dir: [f64; 2],
        len: f64,
    },
    Arc {
        center: [f64; 2],
        radius: f64,
        start_rad: f64,
        sweep_rad: f64,
    },
}

impl Piece {
    fn len(&self) -> f64 {
        match *self {
            Piece::Line { len, .. } => len,
            Piece::Arc {
                radius, sweep_rad, ..
            } => radius * sweep_rad.abs(),
        }
    }

    /// Position, unit tangent and curvature vector at distance `s` into the piece.
    fn at(&self, s: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
        match *self {
            Piece::Line { from, dir, .. } => (
                [from[0] + dir[0] * s, from[1] + dir[1] * s],
                dir,
                [0.0, 0.0],
            ),
            Piece::Arc {
                center,
                radius,
                start_rad,
                sweep_rad,
            } => {
                let sign = sweep_rad.signum();
                // A corner without a radius (a square without a side) is a point: it turns
                // the tangent without moving.
                let ang = if radius > 0.0 {
                    start_rad + sign * s / radius
                } else {
                    start_rad
                };
                let (sn, cs) = math::sin_cos(ang);
                let curvature = if radius > 0.0 {
                    [-cs / radius, -sn / radius]
                } else {
                    [0.0, 0.0]
                };
                (
                    [center[0] + radius * cs, center[1] + radius * sn],
                    [-sign * sn, sign * cs],
                    curvature,
                )
            }
        }
    }
}

/// Position, velocity and acceleration of the path target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint {
    pub p: Vec3,
    pub v: Vec3,
    pub a: Vec3,
}

impl PathPlan {
    /// Plan a path of `duration_s`. `accel_m_s2` bounds the centripetal acceleration used
    /// to round corners; `from` is where the camera is when the path is planned (an orbit
    /// starts at the camera's bearing from its centre); `actor_index` maps names.
    pub fn new(
        shape: &PathShape,
        duration_s: f64,
        accel_mps2: f64,
        from: Vec3,
        actor_index: impl Fn(&str) -> Option<usize>,
        actors: &[ActorPose],
    ) -> PathPlan {
        let ramp = ramp_s(duration_s);
        let geometry = match shape {
            PathShape::Square {
                side_m,
                center_m,
                altitude_m,
                clockwise,
            } => {
                let perimeter = 4.0 * side_m;
                let cruise = perimeter / (duration_s - ramp);
                // A square too small for the smallest corner takes the largest it has room
                // for; one without room (or a speed that is no number) has sharp corners.
                let r = bounded(
                    cruise * cruise / (0.5 * accel_mps2),
                    0.02,
                    side_m / 2.0 * 0.9,
                );
                let r = if r >= 0.0 { r } else { 0.0 };
                Geometry::Rounded {
                    pieces: rounded_square(*side_m, *center_m, r, *clockwise),
                    length_m: 0.0,
                    altitude_m: *altitude_m,
                }
            }
            PathShape::Helix {
                radius_m,
                center_m,
                from_m,
                to_m,
                turns,
                clockwise,
            } => Geometry::Helix {
                center: *center_m,
                radius_m: *radius_m,
                from_m: *from_m,
                to_m: *to_m,
                start_rad: 0.0,
                sweep_rad: TAU * turns * if *clockwise { -1.0 } else { 1.0 },
            },
            PathShape::Orbit {
                center,
                radius_m,
                altitude_m,
                turns,
                clockwise,
            } => {
                let around = match center {
                    OrbitCenter::Point { at_m } => OrbitAround::Point(*at_m),
                    OrbitCenter::Actor { name } => {
                        OrbitAround::Actor(actor_index(name).unwrap_or(0))
                    }
                };
                let c = match around {
                    OrbitAround::Point(c) => c,
                    OrbitAround::Actor(i) => actors
                        .get(i)
                        .map(|a| [a.position_m[0], a.position_m[1]])
                        .unwrap_or([0.0, 0.0]),
                };
                let start_rad = if math::hypot(from.x - c[0], from.y - c[1]) > 1e-6 {
                    math::atan2(from.y - c[1], from.x - c[0])
                } else {
                    0.0
                };
                Geometry::Orbit {
                    center: around,
                    radius_m: *radius_m,
                    altitude_m: *altitude_m,
                    start_rad,
                    sweep_rad: TAU * turns * if *clockwise { -1.0 } else { 1.0 },
                }
            }
            PathShape::Waypoints { points_m, .. } => spline(points_m),
        };
        let geometry = match geometry {
            Geometry::Rounded {
                pieces, altitude_m, ..
            } => Geometry::Rounded {
                length_m: pieces.iter().map(Piece::len).sum(),
                pieces,
                altitude_m,
            },
            g => g,
        };
        let mut plan = PathPlan {
            geometry,
            duration_s,
            ramp_s: ramp,
        };
        // Longer ramps for fast paths: a min-jerk ramp to cruise speed V over r seconds peaks
        // at 1.875·V/r in acceleration; keep that under half the limit where the duration
        // allows (r ≤ T/3), so starting and stopping never ask more than the corners do.
        let length = plan.length_m(actors);
        for _ in 0..4 {
            let cruise = length / (duration_s - plan.ramp_s);
            let wanted = 1.875 * cruise / (0.5 * accel_mps2);
            // A path of no length in no time keeps the shortest ramps.
            if wanted.is_nan() {
                break;
            }
            plan.ramp_s = bounded(wanted, ramp, duration_s / 3.0);
        }
        plan
    }

    /// Length of the path, measured along it (the timing does not change the curve).
    fn length_m(&self, actors: &[ActorPose]) -> f64 {
        let n = 400;
        let step = self.duration_s / n as f64;
        let mut len = 0.0;
        let mut prev = self.at(0.0, actors).p;
        for k in 1..=n {
            let p = self.at(k as f64 * step, actors).p;
            len += (p - prev).norm();
            prev = p;
        }
        len
    }

    /// The target at `t_s` into the path.
    pub fn at(&self, t_s: f64, actors: &[ActorPose]) -> PathPoint {
        let (s, ds) = ease(t_s, self.duration_s, self.ramp_s);
        // d²s/dt², numerically from the analytic rate (the ramps are smooth).
        let h = 1e-4;
        let dds = (ease(t_s + h, self.duration_s, self.ramp_s).1
            - ease(t_s - h, self.duration_s, self.ramp_s).1)
            / (2.0 * h);
        let dds = if t_s - h < 0.0 || t_s + h > self.duration_s {
            0.0
        } else {
            dds
        };
        match &self.geometry {
            Geometry::Rounded {
                pieces,
                length_m,
                altitude_m,
            } => {
                let mut d = s * length_m;
                let mut k = 0;
                while k + 1 < pieces.len() && d > pieces[k].len() {
                    d -= pieces[k].len();
                    k += 1;
                }
                let (p, t, c) = pieces[k].at(d.min(pieces[k].len()));
                let speed = ds * length_m;
                let along = dds * length_m;
                PathPoint {
                    p: Vec3::new(p[0], p[1], *altitude_m),
                    v: Vec3::new(t[0] * speed, t[1] * speed, 0.0),
                    a: Vec3::new(
                        t[0] * along + c[0] * speed * speed,
                        t[1] * along + c[1] * speed * speed,
                        0.0,
                    ),
                }
            }
            Geometry::Helix {
                center,
                radius_m,
                from_m,
                to_m,
                start_rad,
                sweep_rad,
            } => circle(
                *center, [0.0; 2], *radius_m, *from_m, *to_m, *start_rad, *sweep_rad, s, ds, dds,
            ),
            Geometry::Orbit {
                center,
                radius_m,
                altitude_m,
                start_rad,
                sweep_rad,
            } => {
                let (c, cv) = match center {
                    OrbitAround::Point(c) => (*c, [0.0; 2]),
                    OrbitAround::Actor(i) => actors
                        .get(*i)
                        .map(|a| {
                            (
                                [a.position_m[0], a.position_m[1]],
                                [a.velocity_mps[0], a.velocity_mps[1]],
                            )
                        })
                        .unwrap_or(([0.0; 2], [0.0; 2])),
                };
                circle(
                    c,
                    cv,
                    *radius_m,
                    *altitude_m,
                    *altitude_m,
                    *start_rad,
                    *sweep_rad,
                    s,
                    ds,
                    dds,
                )
            }
            Geometry::Spline {
                points,
                tangents,
                knots,
            } => {
                let total = *knots.last().unwrap_or(&0.0);
                if points.len() < 2 || total <= 0.0 {
                    let p = points.first().copied().unwrap_or_else(Vec3::zeros);
                    return PathPoint {
                        p,
                        v: Vec3::zeros(),
                        a: Vec3::zeros(),
                    };
                }
                let d = s * total;
                let k = knots
                    .partition_point(|&x| x <= d)
                    .clamp(1, points.len() - 1)
                    - 1;
                let h = knots[k + 1] - knots[k];
                let u = ((d - knots[k]) / h).clamp(0.0, 1.0);
                // Cubic Hermite with tangents per unit chord length.
                let (p0, p1) = (points[k], points[k + 1]);
                let (m0, m1) = (tangents[k] * h, tangents[k + 1] * h);
                let (u2, u3) = (u * u, u * u * u);
                let p = p0 * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + m0 * (u3 - 2.0 * u2 + u)
                    + p1 * (-2.0 * u3 + 3.0 * u2)
                    + m1 * (u3 - u2);
                let dp = (p0 * (6.0 * u2 - 6.0 * u)
                    + m0 * (3.0 * u2 - 4.0 * u + 1.0)
                    + p1 * (-6.0 * u2 + 6.0 * u)
                    + m1 * (3.0 * u2 - 2.0 * u))
                    / h;
                let ddp = (p0 * (12.0 * u - 6.0)
                    + m0 * (6.0 * u - 4.0)
                    + p1 * (-12.0 * u + 6.0)
                    + m1 * (6.0 * u - 2.0))
                    / (h * h);
                let speed = ds * total;
                PathPoint {
                    p,
                    v: dp * speed,
                    a: ddp * speed * speed + dp * (dds * total),
                }
            }
        }
    }

    /// Where the path starts (at rest).
    pub fn start(&self, actors: &[ActorPose]) -> Vec3 {
        self.at(0.0, actors).p
    }
}

#[allow(clippy::too_many_arguments)]
fn circle(
    c: [f64; 2],
    cv: [f64; 2],
    r: f64,
    z0: f64,
    z1: f64,
    start: f64,
    sweep: f64,
    s: f64,
    ds: f64,
    dds: f64,
) -> PathPoint {
    let ang = start + sweep * s;
    let w = sweep * ds;
    let wd = sweep * dds;
    let (sn, cs) = math::sin_cos(ang);
    PathPoint {
        p: Vec3::new(c[0] + r * cs, c[1] + r * sn, z0 + (z1 - z0) * s),
        v: Vec3::new(cv[0] - r * sn * w, cv[1] + r * cs * w, (z1 - z0) * ds),
        a: Vec3::new(
            -r * cs * w * w - r * sn * wd,
            -r * sn * w * w + r * cs * wd,
            (z1 - z0) * dds,
        ),
    }
}

/// A square of side `side` around `c`, corners rounded to radius `r`, starting where the
/// bottom edge's straight part leaves the lower-left corner, counter-clockwise unless
/// `clockwise` (then mirrored across the centre line, starting at the upper-left corner).
fn rounded_square(side: f64, c: [f64; 2], r: f64, clockwise: bool) -> Vec<Piece> {
    let h = side / 2.0;
    let straight = side - 2.0 * r;
    // Counter-clockwise: bottom edge (+x), right edge (+y), top (−x), left (−y).
    let dirs: [[f64; 2]; 4] = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];
    let mut pieces = Vec::with_capacity(8);
    // Start point: lower-left corner's end of arc on the bottom edge.
    let mut at = [c[0] - h + r, c[1] - h];
    for (k, d) in dirs.iter().enumerate() {
        pieces.push(Piece::Line {
            from: at,
            dir: *d,
            len: straight,
        });
        at = [at[0] + d[0] * straight, at[1] + d[1] * straight];
        // Arc turning left by 90° toward the next direction.
        let next = dirs[(k + 1) % 4];
        let center = [at[0] + next[0] * r, at[1] + next[1] * r];
        let start_rad = math::atan2(at[1] - center[1], at[0] - center[0]);
        pieces.push(Piece::Arc {
            center,
            radius: r,
            start_rad,
            sweep_rad: PI / 2.0,
        });
        at = [center[0] + d[0] * r, center[1] + d[1] * r];
    }
    if clockwise {
        // Mirror across the horizontal line through the centre: y → 2c_y − y.
        pieces
            .into_iter()
            .map(|p| match p {
                Piece::Line { from, dir, len } => Piece::Line {
                    from: [from[0], 2.0 * c[1] - from[1]],
                    dir: [dir[0], -dir[1]],
                    len,
                },
                Piece::Arc {
                    center,
                    radius,
                    start_rad,
                    sweep_rad,
                } => Piece::Arc {
                    center: [center[0], 2.0 * c[1] - center[1]],
                    radius,
                    start_rad: -start_rad,
                    sweep_rad: -sweep_rad,
                },
            })
            .collect()
    } else {
        pieces
    }
}

fn spline(points: &[[f64; 3]]) -> Geometry {
    let points: Vec<Vec3> = points.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let mut knots = vec![0.0];
    for w in points.windows(2) {
        let l = (w[1] - w[0]).norm().max(1e-6);
        knots.push(knots.last().unwrap() + l);
    }
    let n = points.len();
    let tangents = (0..n)
        .map(|i| {
            if n < 2 || i == 0 || i == n - 1 {
                // Natural-ish ends: zero tangent would stop; use the chord direction.
                if n < 2 {
                    Vec3::zeros()
                } else if i == 0 {
                    (points[1] - points[0]) / (knots[1] - knots[0])
                } else {
                    (points[n - 1] - points[n - 2]) / (knots[n - 1] - knots[n - 2])
                }
            } else {
                (points[i + 1] - points[i - 1]) / (knots[i + 1] - knots[i - 1])
            }
        })
        .collect();
    Geometry::Spline {
        points,
        tangents,
        knots,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ease_covers_the_path_at_rest_at_both_ends() {
        let (d, r) = (20.0, 1.5);
        assert_eq!(ease(0.0, d, r), (0.0, 0.0));
        let (s, v) = ease(d, d, r);
        assert!((s - 1.0).abs() < 1e-12 && v.abs() < 1e-12);
        // The rate is the derivative of the fraction, everywhere.
        let h = 1e-6;
        for t in [0.3, 1.2, 1.5, 7.0, 18.9, 19.7] {
            let num = (ease(t + h, d, r).0 - ease(t - h, d, r).0) / (2.0 * h);
            assert!((num - ease(t, d, r).1).abs() < 1e-6, "{t}");
        }
    }

    /// Numbers at the extremes of an `f64`, and the ordinary ones between.
    const EXTREMES: [f64; 16] = [
        0.0,
        -0.0,
        5e-324,
        2.2e-308,
        1e-12,
        1e-9,
        2e-9,
        1e-3,
        0.01,
        1.0,
        20.0,
        1e9,
        1e308,
        -1.0,
        f64::INFINITY,
        f64::NAN,
    ];

    /// `ease` never panics, whatever its arguments; with a duration and a time that are
    /// numbers, its fraction stays within 0..=1 and its rate is a number.
    #[test]
    fn ease_takes_any_numbers() {
        for t in EXTREMES {
            for d in EXTREMES {
                for r in EXTREMES {
                    let (s, v) = ease(t, d, r);
                    if !(t.is_nan() || d.is_nan()) {
                        assert!((0.0..=1.0).contains(&s), "ease({t}, {d}, {r}) = {s}");
                        assert!(v.is_finite() && v >= 0.0, "ease({t}, {d}, {r}) rate {v}");
                    }
                }
            }
        }
        // A path that takes no time is at its start at 0 s and at its end after.
        assert_eq!(ease(0.0, 0.0, 1.5), (0.0, 0.0));
        assert_eq!(ease(1.0, 0.0, 1.5), (1.0, 0.0));
        assert_eq!(ease(1.0, -3.0, 1.5), (1.0, 0.0));
    }

    /// A plan is made and evaluated without a panic for every shape at any size and
    /// duration; for sizes and durations the language accepts, every point is finite.
    #[test]
    fn paths_take_any_numbers() {
        let shapes = |x: f64| {
            [
                PathShape::Square {
                    side_m: x,
                    center_m: [0.0, 0.0],
                    altitude_m: 1.5,
                    clockwise: false,
                },
                PathShape::Square {
                    side_m: 2.0,
                    center_m: [x, -x],
                    altitude_m: x,
                    clockwise: true,
                },
                PathShape::Helix {
                    radius_m: x,
                    center_m: [0.0, 0.0],
                    from_m: 1.0,
                    to_m: x,
                    turns: x,
                    clockwise: false,
                },
                PathShape::Orbit {
                    center: OrbitCenter::Point { at_m: [x, 0.0] },
                    radius_m: x,
                    altitude_m: 1.5,
                    turns: x,
                    clockwise: true,
                },
                PathShape::Waypoints {
                    file: "x.csv".into(),
                    points_m: vec![[0.0, 0.0, 1.0], [x, x, 1.0], [x, 0.0, x]],
                },
                PathShape::Waypoints {
                    file: "x.csv".into(),
                    points_m: vec![[x, 0.0, 1.0]],
                },
            ]
        };
        // What the language accepts: lengths 0.01..=1000 m, turns up to 100, durations from
        // 1 ms to a day.
        let accepted =
            |x: f64, d: f64| (0.01..=100.0).contains(&x) && (1e-3..=86_400.0).contains(&d);
        for x in EXTREMES {
            for d in EXTREMES {
                for shape in shapes(x) {
                    let plan =
                        PathPlan::new(&shape, d, 1.0, Vec3::new(1.0, 0.0, 1.0), |_| None, &[]);
                    for t in [0.0, d / 3.0, d / 2.0, d, d + 1.0, -1.0] {
                        let p = plan.at(t, &[]);
                        if accepted(x, d) {
                            let all = [p.p, p.v, p.a];
                            assert!(
                                all.iter().all(|v| v.iter().all(|c| c.is_finite())),
                                "{shape:?} for {d} s at {t} s: {p:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    fn check_derivatives(plan: &PathPlan, duration: f64) {
        let h = 1e-5;
        let mut t = 0.05;
        while t < duration - 0.05 {
            let a = plan.at(t - h, &[]);
            let b = plan.at(t + h, &[]);
            let m = plan.at(t, &[]);
            let v_num = (b.p - a.p) / (2.0 * h);
            let a_num = (b.v - a.v) / (2.0 * h);
            assert!(
                (v_num - m.v).norm() < 1e-4,
                "v at {t}: {v_num:?} vs {:?}",
                m.v
            );
            assert!(
                (a_num - m.a).norm() < 1e-2,
                "a at {t}: {a_num:?} vs {:?}",
                m.a
            );
            t += 0.0371;
        }
    }

    #[test]
    fn square_is_a_rounded_square_with_consistent_derivatives() {
        let shape = PathShape::Square {
            side_m: 2.0,
            center_m: [0.0, 0.0],
            altitude_m: 1.5,
            clockwise: false,
        };
        let plan = PathPlan::new(&shape, 20.0, 1.0, Vec3::zeros(), |_| None, &[]);
        check_derivatives(&plan, 20.0);
        let mut worst_a: f64 = 0.0;
        for k in 0..=2000 {
            let p = plan.at(k as f64 * 0.01, &[]);
            assert!(p.p.x.abs() <= 1.0 + 1e-9 && p.p.y.abs() <= 1.0 + 1e-9);
            assert!((p.p.z - 1.5).abs() < 1e-12);
            worst_a = worst_a.max(p.a.norm());
        }
        assert!(worst_a <= 0.6, "corner acceleration {worst_a}");
        let end = plan.at(20.0, &[]).p;
        assert!((end - plan.start(&[])).norm() < 1e-9, "closed");
    }

    #[test]
    fn clockwise_mirrors() {
        let mk = |cw| PathShape::Square {
            side_m: 2.0,
            center_m: [0.5, 0.0],
            altitude_m: 1.0,
            clockwise: cw,
        };
        let a = PathPlan::new(&mk(false), 10.0, 1.0, Vec3::zeros(), |_| None, &[]);
        let b = PathPlan::new(&mk(true), 10.0, 1.0, Vec3::zeros(), |_| None, &[]);
        for t in [1.0, 3.3, 7.1] {
            let (p, q) = (a.at(t, &[]).p, b.at(t, &[]).p);
            assert!((p.x - q.x).abs() < 1e-12 && (p.y + q.y).abs() < 1e-12);
        }
    }

    #[test]
    fn helix_climbs_and_turns() {
        let shape = PathShape::Helix {
            radius_m: 1.5,
            center_m: [0.0, 0.0],
            from_m: 1.0,
            to_m: 2.5,
            turns: 2.0,
            clockwise: false,
        };
        let plan = PathPlan::new(&shape, 24.0, 1.0, Vec3::zeros(), |_| None, &[]);
        check_derivatives(&plan, 24.0);
        for k in 0..=240 {
            let p = plan.at(k as f64 * 0.1, &[]).p;
            assert!((p.x.hypot(p.y) - 1.5).abs() < 1e-9);
        }
        assert!((plan.at(24.0, &[]).p - Vec3::new(1.5, 0.0, 2.5)).norm() < 1e-9);
    }

    #[test]
    fn waypoints_pass_through_every_point() {
        let pts = vec![
            [0.0, 0.0, 1.0],
            [1.0, 0.5, 1.2],
            [2.0, 0.0, 1.5],
            [2.5, -1.0, 1.5],
        ];
        let shape = PathShape::Waypoints {
            file: "x.csv".into(),
            points_m: pts.clone(),
        };
        let plan = PathPlan::new(&shape, 10.0, 1.0, Vec3::zeros(), |_| None, &[]);
        check_derivatives(&plan, 10.0);
        let Geometry::Spline { knots, .. } = &plan.geometry else {
            unreachable!()
        };
        let total = *knots.last().unwrap();
        for (k, p) in pts.iter().enumerate() {
            // Find the time whose fraction reaches this knot, by bisection.
            let target = knots[k] / total;
            let (mut lo, mut hi) = (0.0, 10.0);
            for _ in 0..60 {
                let mid = (lo + hi) / 2.0;
                if ease(mid, 10.0, plan.ramp_s).0 < target {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            let q = plan.at(lo, &[]).p;
            assert!(
                (q - Vec3::new(p[0], p[1], p[2])).norm() < 1e-6,
                "{k}: {q:?}"
            );
        }
    }
}
