//! Repositioning routes: how the drone flies from where one shot leaves it to where the next
//! one starts (a `cut to`, when the drone cannot jump).
//!
//! A route is a curve from `a` to `b` parametrised by `s` in [0, 1] (the director runs `s`
//! on a minimum-jerk clock). By default it turns round the vertical through the actors the
//! next shot frames (the pivot), in cylindrical coordinates, the short way: the radius and
//! the angle change together, so the camera keeps its distance from those actors. That arc
//! can still cross the stage's walls, or pass through an actor who is not at the pivot (two
//! actors: the pivot is between them). [`choose`] therefore flies the short arc when it keeps
//! inside the stage and out of every actor's safety distance (as far as its two ends allow);
//! otherwise the shortest clear route among the long arc, the straight line and the arcs
//! round each actor (the long way round the pivot can be nearly twice the straight line's
//! length, and every metre is time taken from the script's clock; an arc round the actor in
//! the way gets from in front of them to behind them where both the straight line and the
//! arcs round the pivot cut through them); when none is clear, the one that intrudes least.
//! Steering still applies on top (containment and separation), but a route that stays clear
//! does not lean on it. A flight that arrives on a moving framing flies its route plus the
//! merge's offset ([`merge_m_per_mps`]), and that is what is kept clear ([`Keepout::merge`]).
//!
//! The route is chosen once, when the flight starts, against the actors as they stand; its
//! end `b` follows the next shot's framing as the actors move.

use crate::camera::Vec3;
use crate::reference::ActorPose;
use crate::steering::SteerLimits;
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;
use std::f64::consts::PI;

/// Below this distance from the pivot's vertical an end has no useful angle: the arc is
/// flown as a straight line.
const MIN_RADIUS_M: f64 = 0.2;
/// The long way round is a candidate only when the short way turns at least this much (a
/// smaller turn the long way is nearly a full circle).
const MIN_TURN_FOR_LONG_WAY_RAD: f64 = 0.5;
/// Points at which a route's clearance is checked.
const CHECKS: usize = 64;
/// Intrusions (into an actor's safety distance or through a wall) up to this count as clear: the
/// steering's containment and separation push the camera back from a route that only grazes
/// them (the short arcs of `shots/scene.psl` graze a wall or an actor's distance by a couple
/// of centimetres and are flown clear of both). A deeper intrusion is flown as is only when no
/// other route is clearer.
const TOLERANCE_M: f64 = 0.1;
/// The same for an actor's safety distance, where separation pushes back less than containment does
/// from a wall: a flight that comes nearly [`TOLERANCE_M`] into a walking actor's distance is
/// flown well inside it, and the arcs of `shots/scene.psl`, which graze it by a couple of
/// centimetres, stay clear.
const ACTOR_TOLERANCE_M: f64 = 0.03;

/// Points at which a route's length is measured: its arcs' lengths to a fraction of a
/// percent.
const LENGTH_SAMPLES: usize = 32;
/// The share of the profile's limits a route's duration is fitted under
/// ([`Route::fit_duration`]): the rest is left for the steering to follow a moving framing.
pub const FIT_SHARE: f64 = 0.8;
/// How many times [`Route::fit_duration`] stretches a duration to fit: one stretch fits a
/// flight that arrives at rest; a merge's offset changes with the duration, and the next
/// stretches take that up.
const FIT_ROUNDS: usize = 4;
/// Each stretch of a duration to fit is this much longer than the excess asks, so that the
/// next measure fits rather than falls just short.
const FIT_STRETCH: f64 = 1.02;
/// A merge's τ is at least this many times the time the profile's acceleration takes to
/// reach the framing's speed: the merge's peak acceleration, 3.93·speed/τ, then stays within
/// half the profile's.
const MERGE_TAU_FACTOR: f64 = 7.9;
/// The shortest merge: a framing that moves slowly is merged into gently all the same.
const MERGE_TAU_MIN_S: f64 = 1.0;

/// The shape of a repositioning flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Route {
    Straight,
    /// Round the vertical through `pivot`, the short way or the long way.
    Around {
        pivot: Vec3,
        long_way: bool,
    },
}

/// Cylindrical coordinates (radius, angle, height) of `p` about the vertical through `c`.
fn cylindrical(p: &Vec3, c: &Vec3) -> (f64, f64, f64) {
    let d = p - c;
    (
        dronecine_math::norm_xy(d.x, d.y),
        math::atan2(d.y, d.x),
        p.z,
    )
}

impl Route {
    /// The point a fraction `s` of the way from `a` to `b`.
    pub fn at(&self, a: &Vec3, b: &Vec3, s: f64) -> Vec3 {
        self.at_turning(a, b, s, None).0
    }

    /// [`Route::at`] for an end `b` that moves during the flight (the next framing against
    /// live actors), going round the way nearest `near` (the turn, in radians, it went at the
    /// last tick), and the turn it went. An arc's turn is taken the short (or long) way
    /// afresh at each point: an end near the far side of the pivot from `a` (a cut from
    /// behind an actor to their front) crosses from one way to the other with the noise of
    /// the measured poses, and the target would jump from one side of the actor to the other
    /// and back, taking the camera, between the two, through the actor. `None` when the route
    /// does not turn (straight, or an end on the pivot's vertical).
    pub fn at_turning(&self, a: &Vec3, b: &Vec3, s: f64, near: Option<f64>) -> (Vec3, Option<f64>) {
        if let Route::Around { pivot: c, long_way } = self {
            let (ra, ta, za) = cylindrical(a, c);
            let (rb, tb, zb) = cylindrical(b, c);
            if ra > MIN_RADIUS_M && rb > MIN_RADIUS_M {
                let short = wrap_angle_rad(tb - ta);
                let mut turn = if *long_way {
                    short - 2.0 * PI * short.signum()
                } else {
                    short
                };
                if let Some(n) = near {
                    if turn - n > PI {
                        turn -= 2.0 * PI;
                    } else if n - turn > PI {
                        turn += 2.0 * PI;
                    }
                }
                let r = ra + (rb - ra) * s;
                let t = ta + turn * s;
                return (
                    Vec3::new(
                        c.x + r * math::cos(t),
                        c.y + r * math::sin(t),
                        za + (zb - za) * s,
                    ),
                    Some(turn),
                );
            }
        }
        (a + (b - a) * s, None)
    }

    /// The route's length from `a` to `b` (sampled).
    pub fn length(&self, a: &Vec3, b: &Vec3) -> f64 {
        let mut len = 0.0;
        let mut prev = *a;
        for k in 1..=LENGTH_SAMPLES {
            let p = self.at(a, b, k as f64 / LENGTH_SAMPLES as f64);
            len += (p - prev).norm();
            prev = p;
        }
        len
    }

    /// The shortest duration, from `t0` up, for which the minimum-jerk flight along the
    /// route keeps its speed and acceleration (centripetal included) under [`FIT_SHARE`] of
    /// the limits.
    pub fn fit_duration(&self, a: &Vec3, b: &Vec3, t0: f64, limits: &SteerLimits) -> f64 {
        self.fit_duration_arriving(a, b, &Vec3::zeros(), t0, limits)
    }

    /// [`Route::fit_duration`] for a flight that arrives moving at `arrive_v` (the route
    /// plus its [`merge_m_per_mps`] offset).
    pub fn fit_duration_arriving(
        &self,
        a: &Vec3,
        b: &Vec3,
        arrive_v: &Vec3,
        t0: f64,
        limits: &SteerLimits,
    ) -> f64 {
        /// Steps of the flight's time at which its speed and acceleration are measured.
        const N: usize = 64;
        let speed = arrive_v.norm();
        let mut t = t0;
        for _ in 0..FIT_ROUNDS {
            let n = N as i64;
            let h = t / n as f64;
            // Before the start at rest; after the end moving on at `arrive_v`.
            let at = |k: i64| {
                let u = k as f64 * h / t;
                let p = self.at(a, b, crate::blocking::min_jerk(u).0);
                if speed > 0.0 {
                    p + arrive_v * (merge_m_per_mps(u, t, speed, limits) + (u - 1.0).max(0.0) * t)
                } else {
                    p
                }
            };
            // Each sample once (k = −1 ..= n + 1), on the stack.
            let mut points = [Vec3::zeros(); N + 3];
            for (i, point) in points.iter_mut().enumerate() {
                *point = at(i as i64 - 1);
            }
            let (mut v_max, mut a_max, mut vz_max): (f64, f64, f64) = (0.0, 0.0, 0.0);
            for w in points.windows(3) {
                let (p0, p1, p2) = (w[0], w[1], w[2]);
                let v = (p2 - p0) / (2.0 * h);
                let acc = (p2 - 2.0 * p1 + p0) / (h * h);
                v_max = v_max.max(dronecine_math::norm_xy(v.x, v.y));
                vz_max = vz_max.max(v.z.abs());
                a_max = a_max.max(dronecine_math::norm_xy(acc.x, acc.y));
            }
            let scale = (v_max / (FIT_SHARE * limits.speed_h_mps))
                .max(vz_max / (FIT_SHARE * limits.speed_v_mps))
                .max((a_max / (FIT_SHARE * limits.accel_h_mps2)).sqrt());
            if scale <= 1.0 {
                break;
            }
            t *= scale * FIT_STRETCH;
        }
        t
    }
}

/// A flight that arrives on a framing moving at `speed_mps` arrives moving with it: on top of
/// its route (which arrives at rest), an offset `v·merge(u)` along the framing's velocity `v`,
/// with `merge = −τ·φ(1 − (1 − u)·D/τ)` over the flight's last τ seconds (`D` its duration,
/// `u` how far along it is) and `φ(w) = 4w³ − 7w⁴ + 3w⁵`, which is 0 with its first two
/// derivatives at w = 0, and 0 with slope −1 and no curvature at w = 1: the offset starts
/// smoothly and is back to nothing on arrival, where it moves at `v`. On the way it first
/// falls behind (by at most 0.2·τ·speed), as a car does that merges into traffic. τ (at
/// least 1 s, at most the flight) is long enough that the merge's own acceleration,
/// 3.93·speed/τ at most, stays within half the profile's.
pub fn merge_m_per_mps(u: f64, duration_s: f64, speed_mps: f64, limits: &SteerLimits) -> f64 {
    let tau_s = (MERGE_TAU_FACTOR * speed_mps / limits.accel_h_mps2)
        .max(MERGE_TAU_MIN_S)
        .min(duration_s);
    if tau_s <= 0.0 {
        return 0.0;
    }
    let w = 1.0 - (1.0 - u.clamp(0.0, 1.0)) * duration_s / tau_s;
    if w <= 0.0 {
        return 0.0;
    }
    let (w3, w4, w5) = (w * w * w, w * w * w * w, w * w * w * w * w);
    -tau_s * (4.0 * w3 - 7.0 * w4 + 3.0 * w5)
}

/// Where a route may go: inside the box `[lo, hi]` (the director gives the stage less the
/// profile's `stage_margin_m`, where it keeps its target: a route that hugged a wall took the
/// reference there, and a few centimetres of tracking error then landed the drone) and outside
/// each actor's safety distance `safety_m` (from the segment from their feet to the top of
/// their head, as [`body_intrusion_m`] measures it), where they stand and where they pass
/// while the drone flies.
pub struct Keepout<'a> {
    pub lo: Vec3,
    pub hi: Vec3,
    /// The actors: kept out of, and the verticals routes may turn round.
    pub actors: &'a [ActorPose],
    /// Where actors pass while the drone flies, each with the fraction of the flight's time
    /// at which they are there (poses along their walks, in time order): kept out of there
    /// and then only (see [`Keepout::route_intrusion_m`]).
    pub passing: &'a [(f64, ActorPose)],
    pub safety_m: f64,
    /// The merge of a flight that arrives moving, when it does: its offset from the route is
    /// part of where the drone flies, and is kept clear too.
    pub merge: Option<Merge<'a>>,
}

/// The merge of a flight that arrives on a moving framing (see [`merge_m_per_mps`]): on the
/// way, the drone flies its route plus `arrive_v · merge(u)`, an offset that falls behind
/// along the framing's velocity by up to 0.2·τ·speed (metres, for a framing that moves fast:
/// a flight planned clear on its route alone can swing into an actor's distance).
#[derive(Clone, Copy, Debug)]
pub struct Merge<'a> {
    /// The framing's velocity on arrival.
    pub arrive_v: Vec3,
    /// The flight's duration, as the director flies it (start to arrival).
    pub duration_s: f64,
    pub limits: &'a SteerLimits,
}

impl Merge<'_> {
    /// The offset from the route at `u` (a fraction of the flight's time).
    pub fn offset_m(&self, u: f64) -> Vec3 {
        let speed = self.arrive_v.norm();
        self.arrive_v * merge_m_per_mps(u, self.duration_s, speed, self.limits)
    }
}

/// The stage less `margin_m` on every side (the floor and the ceiling too): the box the
/// director keeps its target in, and the one routes keep to.
pub fn stage_less_margin(stage: &dronecine_grammar::script::Stage, margin_m: f64) -> (Vec3, Vec3) {
    let (lo, hi) = (stage.min_m(), stage.max_m());
    (
        Vec3::new(lo[0] + margin_m, lo[1] + margin_m, lo[2] + margin_m),
        Vec3::new(hi[0] - margin_m, hi[1] - margin_m, hi[2] - margin_m),
    )
}

impl Keepout<'_> {
    /// How far `p` is into a wall or an actor's safety distance (0 when clear).
    pub fn intrusion_m(&self, p: &Vec3) -> f64 {
        let (walls, actors) = self.intrusions_m(p);
        walls.max(actors)
    }

    /// How far `p` is into the walls, and into the actors' safety distance (each 0 when clear).
    fn intrusions_m(&self, p: &Vec3) -> (f64, f64) {
        let mut walls: f64 = 0.0;
        for i in 0..3 {
            walls = walls.max(self.lo[i] - p[i]).max(p[i] - self.hi[i]);
        }
        (walls, self.deepest_actor(p).map_or(0.0, |(_, d)| d))
    }

    /// The actor (by index) whose safety distance `p` is deepest in, and how deep; `None`
    /// when `p` is clear of every actor's.
    pub fn deepest_actor(&self, p: &Vec3) -> Option<(usize, f64)> {
        let mut deepest = None;
        for (i, a) in self.actors.iter().enumerate() {
            let d = body_intrusion_m(p, a, self.safety_m);
            if d > deepest.map_or(0.0, |(_, worst)| worst) {
                deepest = Some((i, d));
            }
        }
        deepest
    }

    /// The deepest intrusion along `route` from `a` to `b`. An actor passing at a fraction of
    /// the flight's time counts where the flight is then, give or take the spacing of the
    /// passing poses.
    pub fn route_intrusion_m(&self, route: &Route, a: &Vec3, b: &Vec3) -> f64 {
        let (walls, actors) = self.route_intrusions_m(route, a, b);
        walls.max(actors)
    }

    /// The deepest intrusions along `route` from `a` to `b`: into the walls, into the
    /// actors' safety distance. An actor passing at a fraction `u` of the flight's time is checked
    /// against where the flight is then (flown on a minimum-jerk clock, as the director flies
    /// it), and as early or late as the spacing of the passing poses, for a flight that runs
    /// a little behind or ahead.
    fn route_intrusions_m(&self, route: &Route, a: &Vec3, b: &Vec3) -> (f64, f64) {
        // Where the drone is at `u` of the flight's time, merge included.
        let flown = |u: f64| {
            let p = route.at(a, b, crate::blocking::min_jerk(u).0);
            match &self.merge {
                Some(m) => p + m.offset_m(u),
                None => p,
            }
        };
        let (walls, standing): (f64, f64) = (0..=CHECKS)
            .map(|k| {
                let x = k as f64 / CHECKS as f64;
                // Without a merge, evenly along the route; with one, evenly in time (the
                // offset is a function of time).
                self.intrusions_m(&match self.merge {
                    Some(_) => flown(x),
                    None => route.at(a, b, x),
                })
            })
            .fold((0.0, 0.0), |(w, ac), (wk, ak)| (w.max(wk), ac.max(ak)));
        // The passing poses' spacing in time (they come in time order).
        let slack = self
            .passing
            .windows(2)
            .map(|w| (w[1].0 - w[0].0).abs())
            .filter(|&du| du > 0.0)
            .fold(1.0, f64::min);
        let passing = self.passing.iter().fold(0.0, |worst: f64, (u, pose)| {
            [u - slack, *u, u + slack]
                .into_iter()
                .filter(|u| (0.0..=1.0).contains(u))
                .map(flown)
                .fold(worst, |w, p| {
                    w.max(body_intrusion_m(&p, pose, self.safety_m))
                })
        });
        (walls, standing.max(passing))
    }
}

/// How far `p` is inside the actor's safety distance `safety_m`, measured as everywhere
/// ([`framing::body_axis_distance_m`](crate::framing::body_axis_distance_m), to the segment
/// from their feet to the top of their head); 0 or less when clear.
pub fn body_intrusion_m(p: &Vec3, a: &ActorPose, safety_m: f64) -> f64 {
    safety_m - crate::framing::body_axis_distance_m(p, a)
}

/// The route a flight takes unless something is in its way: round `pivot` the short way, or
/// straight without one.
pub fn usual(pivot: Option<Vec3>) -> Route {
    match pivot {
        Some(pivot) => Route::Around {
            pivot,
            long_way: false,
        },
        None => Route::Straight,
    }
}

/// The route from `a` to `b` (see the module doc): round `pivot` the short way (without a
/// pivot, straight) when that is clear; else the shortest clear route; else the one that
/// intrudes least.
pub fn choose(a: &Vec3, b: &Vec3, pivot: Option<Vec3>, keep: &Keepout) -> Route {
    let first = usual(pivot);
    // No route is clearer than its ends.
    let ((walls_a, actors_a), (walls_b, actors_b)) = (keep.intrusions_m(a), keep.intrusions_m(b));
    let clear = |(walls, actors): (f64, f64)| {
        walls <= walls_a.max(walls_b) + TOLERANCE_M
            && actors <= actors_a.max(actors_b) + ACTOR_TOLERANCE_M
    };
    let first_intrusions = keep.route_intrusions_m(&first, a, b);
    if clear(first_intrusions) {
        return first;
    }
    // Round a vertical either way: the long way only when the short way turns enough that
    // the long way is not nearly a full circle.
    let both_ways = |c: Vec3| {
        let (_, ta, _) = cylindrical(a, &c);
        let (_, tb, _) = cylindrical(b, &c);
        let long_way_too = wrap_angle_rad(tb - ta).abs() >= MIN_TURN_FOR_LONG_WAY_RAD;
        [
            Some(Route::Around {
                pivot: c,
                long_way: false,
            }),
            long_way_too.then_some(Route::Around {
                pivot: c,
                long_way: true,
            }),
        ]
    };
    let long_round_pivot = pivot.map(|p| both_ways(p)[1]).unwrap_or(None);
    // Round an actor who stands in the way: both ends are outside their distance, so an arc
    // that keeps its radius between the ends' keeps out of it.
    let round_actors = keep.actors.iter().flat_map(|actor| {
        let [x, y, _] = actor.position_m;
        both_ways(Vec3::new(x, y, 0.0))
    });
    let others = [long_round_pivot, Some(Route::Straight)]
        .into_iter()
        .chain(round_actors)
        .flatten()
        .filter(|r| *r != first);
    // The shortest clear route (with its length), and the least intruding (with its depth).
    let mut shortest_clear: Option<(Route, f64)> = None;
    let mut least = (first, first_intrusions.0.max(first_intrusions.1));
    for route in others {
        let intrusions = keep.route_intrusions_m(&route, a, b);
        let intrusion = intrusions.0.max(intrusions.1);
        if clear(intrusions) {
            let length = route.length(a, b);
            if shortest_clear.is_none_or(|(_, l)| length < l) {
                shortest_clear = Some((route, length));
            }
        }
        if intrusion < least.1 {
            least = (route, intrusion);
        }
    }
    shortest_clear.map_or(least.0, |(route, _)| route)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The merge offset is nothing at the start and on arrival, moves at the framing's speed
    /// on arrival (slope 1 in seconds), starts at rest, and its acceleration stays within half
    /// the profile's; it falls behind by at most 0.2·τ·speed.
    #[test]
    fn a_merge_arrives_on_the_framing_at_its_speed() {
        let limits = ardrone_limits();
        for (duration_s, speed) in [(6.0, 0.5), (3.0, 0.3), (10.0, 1.2), (0.8, 0.4)] {
            let m = |t_s: f64| merge_m_per_mps(t_s / duration_s, duration_s, speed, &limits);
            let h = 1e-4;
            assert_eq!(m(0.0), 0.0);
            assert!(m(duration_s).abs() < 1e-12);
            let slope_end = (m(duration_s) - m(duration_s - h)) / h;
            assert!((slope_end - 1.0).abs() < 1e-3, "{slope_end}");
            assert!(((m(h) - m(0.0)) / h).abs() < 1e-6, "at rest at the start");
            let tau_s = (7.9 * speed / limits.accel_h_mps2).max(1.0).min(duration_s);
            let mut worst_behind = 0.0f64;
            for k in 1..1000 {
                let t = duration_s * k as f64 / 1000.0;
                let acc_mps2 = speed * (m(t + h) - 2.0 * m(t) + m(t - h)) / (h * h);
                worst_behind = worst_behind.max(-m(t));
                if tau_s > 7.9 * speed / limits.accel_h_mps2 - 1e-9 {
                    assert!(
                        acc_mps2.abs() <= 0.5 * limits.accel_h_mps2 + 1e-3,
                        "{acc_mps2}"
                    );
                }
            }
            assert!(
                worst_behind <= 0.198 * tau_s,
                "{worst_behind} behind, τ {tau_s}"
            );
        }
    }

    /// `ardrone2`'s limits, as the director steers with them.
    fn ardrone_limits() -> SteerLimits {
        SteerLimits {
            speed_h_mps: 1.84,
            speed_v_mps: 0.9,
            accel_h_mps2: 1.08,
            accel_v_mps2: 1.0,
            jerk_mps3: 3.0,
            yaw_rate_radps: 1.5,
            yaw_accel_radps2: 3.0,
        }
    }

    fn actor(x: f64, y: f64) -> ActorPose {
        ActorPose {
            position_m: [x, y, 0.0],
            velocity_mps: [0.0; 3],
            facing_rad: 0.0,
            facing_rate_radps: 0.0,
            height_m: 1.8,
        }
    }

    /// Between `lo` and `hi`, 0.5 m from each of `actors`.
    fn keepout(lo: Vec3, hi: Vec3, actors: &[ActorPose]) -> Keepout<'_> {
        Keepout {
            lo,
            hi,
            actors,
            passing: &[],
            safety_m: 0.5,
            merge: None,
        }
    }

    /// One measure of an actor's distance, the segment from their feet to the top of their
    /// head: the routes, the monitor (both [`body_intrusion_m`]) and the steering's
    /// separation agree with `framing::body_axis_distance_m`, above the head's corner too
    /// (where a flat-topped cylinder would reach 0.5 m above the head at any horizontal
    /// distance under 0.5 m).
    #[test]
    fn an_actors_distance_is_measured_one_way() {
        use crate::framing::body_axis_distance_m;
        use crate::steering::{separation, Body};
        let a = actor(1.0, -1.0);
        let top = a.position_m[2] + a.height_m;
        let body = [Body::from(&a)];
        let (lo, hi) = (Vec3::new(-9.0, -9.0, -9.0), Vec3::new(9.0, 9.0, 9.0));
        let actors = [a];
        let keep = keepout(lo, hi, &actors);
        for (out_m, up_m, inside) in [
            (0.3, -0.5, true),  // beside the body
            (0.6, -0.5, false), // beside, clear
            (0.3, 0.3, true),   // over the head's corner: 0.42 m
            (0.4, 0.45, false), // over the corner: 0.60 m (inside a flat-topped cylinder)
            (0.0, 0.45, true),  // right over the head
        ] {
            let p = Vec3::new(1.0 + out_m, -1.0, top + up_m);
            let d = body_axis_distance_m(&p, &a);
            assert_eq!(d < 0.5, inside, "{out_m}, {up_m}: {d}");
            assert_eq!(body_intrusion_m(&p, &a, 0.5), 0.5 - d);
            assert_eq!(keep.deepest_actor(&p).is_some(), inside, "{out_m}, {up_m}");
            let push = separation(&p, &body, 0.5, 3.0);
            assert_eq!(push != Vec3::zeros(), inside && d > 1e-6, "{out_m}, {up_m}");
            if push != Vec3::zeros() {
                // Away from the body's nearest point.
                let away = p - body[0].nearest_m(&p);
                assert!(push.normalize().dot(&away.normalize()) > 1.0 - 1e-12);
            }
        }
    }

    /// `stage 8m x 6m x 3m`.
    fn stage() -> (Vec3, Vec3) {
        (Vec3::new(-4.0, -3.0, 0.0), Vec3::new(4.0, 3.0, 3.0))
    }

    /// A flight that arrives on a framing moving at 1.5 m/s falls behind it on the way, by up
    /// to 1.8 m over 6 s: a straight route 1.4 m clear of an actor is flown through them. With
    /// the merge in the keep-out the straight route counts as intruding and another is flown,
    /// whose path, merge included, keeps clear.
    #[test]
    fn a_merge_that_swings_into_an_actor_takes_another_route() {
        let (lo, hi) = stage();
        let actors = [actor(0.0, 1.4)];
        let (a, b) = (Vec3::new(-2.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0));
        let limits = ardrone_limits();
        let merge = Merge {
            arrive_v: Vec3::new(0.0, -1.5, 0.0),
            duration_s: 6.0,
            limits: &limits,
        };
        let bare = keepout(lo, hi, &actors);
        let merged = Keepout {
            merge: Some(merge),
            ..keepout(lo, hi, &actors)
        };
        // Where the drone flies on `route`: the route plus the offset, on the flight's clock.
        let flown_intrusion = |route: &Route| {
            (0..=400)
                .map(|k| {
                    let u = k as f64 / 400.0;
                    let p = route.at(&a, &b, crate::blocking::min_jerk(u).0) + merge.offset_m(u);
                    body_intrusion_m(&p, &actors[0], 0.5)
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        assert_eq!(bare.route_intrusion_m(&Route::Straight, &a, &b), 0.0);
        assert_eq!(choose(&a, &b, None, &bare), Route::Straight);
        assert!(flown_intrusion(&Route::Straight) > 0.4);
        assert!(merged.route_intrusion_m(&Route::Straight, &a, &b) > 0.4);
        let r = choose(&a, &b, None, &merged);
        assert_ne!(r, Route::Straight);
        assert!(flown_intrusion(&r) <= 0.0, "{r:?}: {}", flown_intrusion(&r));
    }

    #[test]
    fn arcs_keep_their_ends_and_turn_the_way_asked() {
        let c = Vec3::new(0.0, 0.0, 0.0);
        let (a, b) = (Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 3.0, 1.5));
        for long_way in [false, true] {
            let r = Route::Around { pivot: c, long_way };
            assert!((r.at(&a, &b, 0.0) - a).norm() < 1e-12);
            assert!((r.at(&a, &b, 1.0) - b).norm() < 1e-12);
            // Halfway: radius 2.5, angle 45° the short way, −135° the long way.
            let m = r.at(&a, &b, 0.5);
            let want = if long_way { -0.75 * PI } else { 0.25 * PI };
            assert!((dronecine_math::norm_xy(m.x, m.y) - 2.5).abs() < 1e-12);
            assert!(wrap_angle_rad(math::atan2(m.y, m.x) - want).abs() < 1e-12);
            assert!((m.z - 1.25).abs() < 1e-12);
        }
        // The long way is longer: three quarters of a turn against one.
        let short = Route::Around {
            pivot: c,
            long_way: false,
        };
        let long = Route::Around {
            pivot: c,
            long_way: true,
        };
        assert!(long.length(&a, &b) > 2.5 * short.length(&a, &b));
    }

    #[test]
    fn the_short_arc_is_kept_when_it_is_clear() {
        let (lo, hi) = stage();
        let actors = [actor(0.0, 0.0)];
        let keep = keepout(lo, hi, &actors);
        let (a, b) = (Vec3::new(1.5, 0.0, 1.5), Vec3::new(-1.5, 0.3, 1.5));
        let r = choose(&a, &b, Some(Vec3::zeros()), &keep);
        assert_eq!(
            r,
            Route::Around {
                pivot: Vec3::zeros(),
                long_way: false
            }
        );
        assert_eq!(keep.route_intrusion_m(&r, &a, &b), 0.0);
        // Without a pivot: a straight line, unless an actor stands on it.
        let nobody = keepout(lo, hi, &[]);
        assert_eq!(choose(&a, &b, None, &nobody), Route::Straight);
        let r = choose(&a, &b, None, &keep);
        assert_ne!(r, Route::Straight);
        assert_eq!(keep.route_intrusion_m(&r, &a, &b), 0.0);
    }

    /// Two actors, the pivot between them: the short arc from beside B out to a wide framing
    /// sweeps through B and out of the stage. The long way round and the straight line are
    /// both clear; the straight line, under 70 % of the long way's length, is flown.
    #[test]
    fn a_blocked_arc_gives_way_to_the_shortest_clear_route() {
        let (lo, hi) = stage();
        let actors = [actor(0.0, 0.0), actor(2.5, 0.0)];
        let keep = keepout(lo, hi, &actors);
        let pivot = Vec3::new(1.25, 0.0, 0.0);
        let (a, b) = (Vec3::new(2.2, 0.6, 1.2), Vec3::new(-2.7, -2.5, 1.1));
        let short = Route::Around {
            pivot,
            long_way: false,
        };
        let long = Route::Around {
            pivot,
            long_way: true,
        };
        assert!(keep.route_intrusion_m(&short, &a, &b) > 0.2);
        assert!(keep.route_intrusion_m(&long, &a, &b) <= TOLERANCE_M);
        assert!(keep.route_intrusion_m(&Route::Straight, &a, &b) <= TOLERANCE_M);
        let straight_m = Route::Straight.length(&a, &b);
        assert!(straight_m < 0.7 * long.length(&a, &b));
        assert!((straight_m - (b - a).norm()).abs() < 1e-9);
        assert_eq!(choose(&a, &b, Some(pivot), &keep), Route::Straight);
    }

    /// The same flight with a third actor standing on the straight line: an arc is flown,
    /// clear, and no longer than the long way round the pivot (clear too).
    #[test]
    fn an_arc_when_the_straight_line_is_blocked() {
        let (lo, hi) = stage();
        let actors = [actor(0.0, 0.0), actor(2.5, 0.0), actor(-0.25, -0.95)];
        let keep = keepout(lo, hi, &actors);
        let pivot = Vec3::new(1.25, 0.0, 0.0);
        let (a, b) = (Vec3::new(2.2, 0.6, 1.2), Vec3::new(-2.7, -2.5, 1.1));
        assert!(keep.route_intrusion_m(&Route::Straight, &a, &b) > 0.4);
        let long = Route::Around {
            pivot,
            long_way: true,
        };
        assert!(keep.route_intrusion_m(&long, &a, &b) <= TOLERANCE_M);
        let r = choose(&a, &b, Some(pivot), &keep);
        assert!(matches!(r, Route::Around { .. }), "{r:?}");
        assert!(keep.route_intrusion_m(&r, &a, &b) <= TOLERANCE_M);
        assert!(r.length(&a, &b) <= long.length(&a, &b));
    }

    /// From 0.63 m in front of an actor to 0.68 m behind their shoulder, the pivot between
    /// them and a second actor 2 m away (the over-the-shoulder shot after a close single in
    /// `shots/scene.psl`, rewritten `MS … MS …`): the straight line and both arcs round the
    /// pivot cut into the actor's distance, which a director cannot fix by moving a path.
    /// Round the actor, the flight keeps clear.
    #[test]
    fn round_the_actor_in_the_way() {
        let (lo, hi) = stage();
        let actors = [actor(1.5, 0.5), actor(-0.5, 0.5)];
        let keep = keepout(lo, hi, &actors);
        let pivot = Vec3::new(0.5, 0.5, 0.0);
        let (a, b) = (Vec3::new(0.134, 0.507, 1.37), Vec3::new(-0.932, 1.02, 1.37));
        for r in [
            Route::Straight,
            Route::Around {
                pivot,
                long_way: false,
            },
            Route::Around {
                pivot,
                long_way: true,
            },
        ] {
            assert!(keep.route_intrusion_m(&r, &a, &b) > 0.2, "{r:?}");
        }
        let r = choose(&a, &b, Some(pivot), &keep);
        let Route::Around { pivot: c, .. } = r else {
            panic!("{r:?}")
        };
        assert_eq!((c.x, c.y), (-0.5, 0.5), "round the actor in the way");
        assert_eq!(keep.route_intrusion_m(&r, &a, &b), 0.0);
        // Without a pivot (a flight to a path shot with no actor to frame) the same holds.
        let r = choose(&a, &b, None, &keep);
        assert_eq!(keep.route_intrusion_m(&r, &a, &b), 0.0, "{r:?}");
    }

    /// An actor who walks across a straight flight's line is in the way only if they are
    /// there when the flight is: crossing it as the drone passes (halfway, on the flight's
    /// minimum-jerk clock) blocks the line, and the flight goes round the actor's far end;
    /// crossing it near the end of the flight, after the drone has passed, does not.
    #[test]
    fn a_walking_actor_is_kept_clear_of_where_they_are_when_the_drone_passes() {
        let (lo, hi) = stage();
        let (a, b) = (Vec3::new(-3.0, 0.0, 1.5), Vec3::new(3.0, 0.0, 1.5));
        // The actor walks along x = 0 from y = -2.8 to y = 2.8, at `y(u)` at the fraction u
        // of the flight's time; the director keeps its two ends as standing actors.
        let ends = [actor(0.0, -2.8), actor(0.0, 2.8)];
        let passing = |y: &dyn Fn(f64) -> f64| -> Vec<(f64, ActorPose)> {
            (1..16)
                .map(|k| {
                    let u = k as f64 / 16.0;
                    (u, actor(0.0, y(u)))
                })
                .collect()
        };
        let on_time = passing(&|u| -2.8 + 5.6 * u);
        let keep = Keepout {
            passing: &on_time,
            ..keepout(lo, hi, &ends)
        };
        let straight = keep.route_intrusion_m(&Route::Straight, &a, &b);
        assert!((straight - 0.5).abs() < 1e-9, "{straight}");
        let r = choose(&a, &b, None, &keep);
        assert_ne!(r, Route::Straight);
        assert!(
            keep.route_intrusion_m(&r, &a, &b) <= ACTOR_TOLERANCE_M,
            "{r:?}"
        );
        // The same walk, crossing the line at 90 % of the flight's time: the drone is 2.9 m
        // past by then.
        let late = passing(&|u| -2.8 + 2.8 * u / 0.9);
        let keep = Keepout {
            passing: &late,
            ..keepout(lo, hi, &ends)
        };
        assert_eq!(keep.route_intrusion_m(&Route::Straight, &a, &b), 0.0);
        assert_eq!(choose(&a, &b, None, &keep), Route::Straight);
    }

    /// A route that grazes a wall by less than `TOLERANCE_M` is clear (containment pushes
    /// the camera back); one that comes as far into an actor's distance is not (separation
    /// pushes back less: flown, such a route comes well inside the distance the profile
    /// keeps).
    #[test]
    fn an_actor_is_grazed_less_than_a_wall() {
        // The short arc round the origin from -30° to +30° at 2 m: its middle, (2, 0), bulges
        // 0.27 m past its ends' x.
        let (a, b) = (Vec3::new(1.732, -1.0, 1.5), Vec3::new(1.732, 1.0, 1.5));
        let pivot = Vec3::zeros();
        let arc = Route::Around {
            pivot,
            long_way: false,
        };
        // 0.08 m through the wall x = 1.92.
        let (lo, _) = stage();
        let walled = keepout(lo, Vec3::new(1.92, 3.0, 3.0), &[]);
        let wall = walled.route_intrusion_m(&arc, &a, &b);
        assert!((wall - 0.08).abs() < 1e-3, "{wall}");
        assert_eq!(choose(&a, &b, Some(pivot), &walled), arc);
        // 0.08 m into the distance of an actor at (2.42, 0).
        let (lo, hi) = stage();
        let actors = [actor(2.42, 0.0)];
        let near_actor = keepout(lo, hi, &actors);
        let grazing = near_actor.route_intrusion_m(&arc, &a, &b);
        assert!((grazing - 0.08).abs() < 1e-3, "{grazing}");
        let r = choose(&a, &b, Some(pivot), &near_actor);
        assert_ne!(r, arc);
        assert!(near_actor.route_intrusion_m(&r, &a, &b) <= ACTOR_TOLERANCE_M);
    }

    #[test]
    fn when_nothing_is_clear_the_least_intrusion_wins() {
        // A stage too narrow for any arc, an actor near the straight line: the straight line
        // comes 0.2 m into the actor's distance, the arcs leave the stage by metres.
        let lo = Vec3::new(-4.0, -0.6, 0.0);
        let hi = Vec3::new(4.0, 0.6, 3.0);
        let actors = [actor(0.0, 0.3)];
        let keep = keepout(lo, hi, &actors);
        let (a, b) = (Vec3::new(-3.0, 0.0, 1.5), Vec3::new(3.0, 0.0, 1.5));
        let pivot = Vec3::new(0.0, 0.3, 0.0);
        for long_way in [false, true] {
            let arc = Route::Around { pivot, long_way };
            assert!(keep.route_intrusion_m(&arc, &a, &b) > 2.0);
        }
        let r = choose(&a, &b, Some(pivot), &keep);
        assert_eq!(r, Route::Straight);
        let i = keep.route_intrusion_m(&r, &a, &b);
        assert!((i - 0.2).abs() < 1e-9, "{i}");
    }
}
