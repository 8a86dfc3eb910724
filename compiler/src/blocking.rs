//! The actors as the script moves them: start poses plus the timed blocking, with smooth
//! (minimum-jerk) velocity profiles.
//!
//! A walk goes in a straight line from where the actor is to the target; a turn takes the
//! short way round. Both follow the quintic `σ(u) = 10u³ − 15u⁴ + 6u⁵` in normalised time,
//! so speed and acceleration are zero at both ends and the camera that follows an actor never
//! sees a step. A walk does not turn the actor (turns are written as turns).
//!
//! [`Blocking::contacts`] finds the walks that bring two actors within
//! [`ACTORS_MIN_APART_M`] of each other (the grammar checks only where they start).

use dronecine_diag::Span;
use dronecine_grammar::script::{Action, Scene, ACTORS_MIN_APART_M};
use dronecine_math::wrap_angle_rad;

use crate::reference::ActorPose;
use dronecine_math as math;

/// Minimum-jerk profile: position, velocity and acceleration factors of `u ∈ [0, 1]`.
pub fn min_jerk(u: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (
        u3 * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - u) * (1.0 - u),
        60.0 * u * (1.0 - u) * (1.0 - 2.0 * u),
    )
}

/// One movement, with its start state resolved.
#[derive(Clone, Debug)]
struct Leg {
    start_s: f64,
    end_s: f64,
    kind: LegKind,
    /// The movement's line in the script.
    span: Span,
}

#[derive(Clone, Debug)]
enum LegKind {
    Walk { from: [f64; 2], to: [f64; 2] },
    Turn { from_rad: f64, delta_rad: f64 },
}

/// Two actors within [`ACTORS_MIN_APART_M`] of each other during a walk: the closest point
/// of their first such encounter.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// The actor whose walk brings them together (the later-started walk when both walk).
    pub walker: usize,
    /// That walk's line.
    pub walk_span: Span,
    pub other: usize,
    /// The other actor's walk under way at that moment, or the line that put them where they
    /// stand (their last walk, else their declaration).
    pub other_span: Span,
    pub other_walks: bool,
    /// Script time of the closest approach.
    pub t_s: f64,
    pub distance_m: f64,
}

/// Every actor's poses over time.
#[derive(Clone, Debug)]
pub struct Blocking {
    names: Vec<String>,
    /// Each actor's declaration line.
    spans: Vec<Span>,
    heights_m: Vec<f64>,
    start: Vec<([f64; 2], f64)>,
    /// Per actor, walks and turns sorted by start (they never overlap per actor).
    walks: Vec<Vec<Leg>>,
    turns: Vec<Vec<Leg>>,
}

impl Blocking {
    pub fn new(scene: &Scene) -> Blocking {
        let n = scene.actors.len();
        let mut walks = vec![Vec::new(); n];
        let mut turns = vec![Vec::new(); n];
        let mut pos: Vec<[f64; 2]> = scene.actors.iter().map(|a| a.position_m).collect();
        let mut facing: Vec<f64> = scene.actors.iter().map(|a| a.facing_rad).collect();
        // `scene.blocking` is sorted by start; movements of one actor do not overlap.
        for m in &scene.blocking {
            let Some(i) = scene.actors.iter().position(|a| a.name == m.actor) else {
                continue;
            };
            match m.action {
                Action::Walk { to_m } => {
                    walks[i].push(Leg {
                        start_s: m.start_s,
                        end_s: m.end_s,
                        kind: LegKind::Walk {
                            from: pos[i],
                            to: to_m,
                        },
                        span: m.span,
                    });
                    pos[i] = to_m;
                }
                Action::Turn { to_rad } => {
                    let delta_rad = wrap_angle_rad(to_rad - facing[i]);
                    turns[i].push(Leg {
                        start_s: m.start_s,
                        end_s: m.end_s,
                        kind: LegKind::Turn {
                            from_rad: facing[i],
                            delta_rad,
                        },
                        span: m.span,
                    });
                    facing[i] = to_rad;
                }
            }
        }
        Blocking {
            names: scene.actors.iter().map(|a| a.name.clone()).collect(),
            spans: scene.actors.iter().map(|a| a.span).collect(),
            heights_m: scene.actors.iter().map(|a| a.height_m).collect(),
            start: scene
                .actors
                .iter()
                .map(|a| (a.position_m, a.facing_rad))
                .collect(),
            walks,
            turns,
        }
    }

    pub fn names(&self) -> &[String] {
        &self.names
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Pose of actor `i` at `t_s`.
    pub fn pose(&self, i: usize, t_s: f64) -> ActorPose {
        let (mut xy, mut facing) = self.start[i];
        let mut vel = [0.0; 2];
        let mut rate = 0.0;
        // The last walk that started at or before t.
        let walks = &self.walks[i];
        let k = walks.partition_point(|l| l.start_s <= t_s);
        if k > 0 {
            let leg = &walks[k - 1];
            if let LegKind::Walk { from, to } = leg.kind {
                let dur = leg.end_s - leg.start_s;
                let (s, ds, _) = min_jerk((t_s - leg.start_s) / dur);
                for j in 0..2 {
                    xy[j] = from[j] + (to[j] - from[j]) * s;
                    vel[j] = (to[j] - from[j]) * ds / dur;
                }
            }
        }
        let turns = &self.turns[i];
        let k = turns.partition_point(|l| l.start_s <= t_s);
        if k > 0 {
            let leg = &turns[k - 1];
            if let LegKind::Turn {
                from_rad,
                delta_rad,
            } = leg.kind
            {
                let dur = leg.end_s - leg.start_s;
                let (s, ds, _) = min_jerk((t_s - leg.start_s) / dur);
                facing = wrap_angle_rad(from_rad + delta_rad * s);
                rate = delta_rad * ds / dur;
            }
        }
        ActorPose {
            position_m: [xy[0], xy[1], 0.0],
            velocity_mps: [vel[0], vel[1], 0.0],
            facing_rad: facing,
            facing_rate_radps: rate,
            height_m: self.heights_m[i],
        }
    }

    /// The first encounter of each pair of actors closer than [`ACTORS_MIN_APART_M`] during
    /// a walk, by pair (declaration order). Between the walks' starts and ends each actor
    /// stands or follows one walk, so each such interval is sampled finely enough that the
    /// two move at most 1 cm between samples (the distance found is within 5 mm of the
    /// closest), then the closest sample refined by golden-section search. Standing actors
    /// keep their distance: the grammar checked where they start, and each walk's end is a
    /// sample.
    pub fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::new();
        for a in 0..self.len() {
            for b in a + 1..self.len() {
                if let Some(c) = self.first_contact(a, b) {
                    out.push(c);
                }
            }
        }
        out
    }

    fn first_contact(&self, a: usize, b: usize) -> Option<Contact> {
        let walk_len = |l: &Leg| match l.kind {
            LegKind::Walk { from, to } => math::hypot(to[0] - from[0], to[1] - from[1]),
            LegKind::Turn { .. } => 0.0,
        };
        let mut times: Vec<f64> = self.walks[a]
            .iter()
            .chain(&self.walks[b])
            .flat_map(|l| [l.start_s, l.end_s])
            .filter(|t| t.is_finite())
            .collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let distance = |t: f64| {
            let (p, q) = (self.pose(a, t).position_m, self.pose(b, t).position_m);
            math::hypot(p[0] - q[0], p[1] - q[1])
        };
        // The walk of actor `i` under way in (t0, t1), if any.
        let walking = |i: usize, t0: f64, t1: f64| {
            self.walks[i]
                .iter()
                .find(|l| l.start_s < t1 && l.end_s > t0)
        };
        for w in times.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            let (wa, wb) = (walking(a, t0, t1), walking(b, t0, t1));
            // The walker: the walk under way that started last.
            let (walker, walk, other, other_walk) = match (wa, wb) {
                (Some(x), Some(y)) if y.start_s > x.start_s => (b, y, a, Some(x)),
                (Some(x), y) => (a, x, b, y),
                (None, Some(y)) => (b, y, a, None),
                (None, None) => continue,
            };
            // Peak speed of a minimum-jerk walk: 1.875 · length / duration.
            let peak =
                |l: Option<&Leg>| l.map_or(0.0, |l| 1.875 * walk_len(l) / (l.end_s - l.start_s));
            let (reach_a, reach_b) = (wa.map_or(0.0, walk_len), wb.map_or(0.0, walk_len));
            if distance(t0) - (reach_a + reach_b) >= ACTORS_MIN_APART_M {
                continue;
            }
            let speed = peak(wa) + peak(wb);
            let steps = ((t1 - t0) * speed / 0.01).ceil().clamp(8.0, 1e6) as usize;
            let h = (t1 - t0) / steps as f64;
            let (k, d) = (0..=steps)
                .map(|k| (k, distance(t0 + k as f64 * h)))
                .fold((0, f64::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
            if !(d < ACTORS_MIN_APART_M) {
                continue;
            }
            // Golden-section search around the closest sample.
            let (mut lo, mut hi) = (
                t0 + k.saturating_sub(1) as f64 * h,
                (t0 + (k + 1) as f64 * h).min(t1),
            );
            let g = (5f64.sqrt() - 1.0) / 2.0;
            for _ in 0..60 {
                let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
                if distance(m1) <= distance(m2) {
                    hi = m2;
                } else {
                    lo = m1;
                }
            }
            let t = 0.5 * (lo + hi);
            let (t_s, distance_m) = if distance(t) < d {
                (t, distance(t))
            } else {
                (t0 + k as f64 * h, d)
            };
            let other_span = other_walk.map(|l| l.span).unwrap_or_else(|| {
                self.walks[other]
                    .iter()
                    .rev()
                    .find(|l| l.end_s <= t_s)
                    .map_or(self.spans[other], |l| l.span)
            });
            return Some(Contact {
                walker,
                walk_span: walk.span,
                other,
                other_span,
                other_walks: other_walk.is_some(),
                t_s,
                distance_m,
            });
        }
        None
    }

    /// The first end of a movement (any actor's walk or turn) after `t_s`, if any.
    pub fn next_movement_end_after(&self, t_s: f64) -> Option<f64> {
        self.walks
            .iter()
            .chain(&self.turns)
            .flatten()
            .map(|l| l.end_s)
            .filter(|&e| e > t_s)
            .min_by(f64::total_cmp)
    }

    /// Every actor's pose at `t_s`, written into `out` (one per actor, declaration order).
    pub fn poses_into(&self, t_s: f64, out: &mut [ActorPose]) {
        for (i, slot) in out.iter_mut().enumerate().take(self.len()) {
            *slot = self.pose(i, t_s);
        }
    }

    pub fn poses(&self, t_s: f64) -> Vec<ActorPose> {
        (0..self.len()).map(|i| self.pose(i, t_s)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        let src = "stage 8m x 6m x 3m\nactor A height 1.8m at (0, 0) facing 170deg\n\
                   at 1s A walks to (2, 1) over 4s\nat 6s A turns to -170deg over 2s\n\
                   MS on A for 8s\n";
        let checked = dronecine_grammar::check(src, &dronecine_grammar::Options::default());
        assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
        checked.script.unwrap().scene.unwrap()
    }

    #[test]
    fn min_jerk_derivatives_are_consistent() {
        let h = 1e-6;
        for u in [0.1, 0.3, 0.5, 0.77, 0.9] {
            let (s0, v0, a0) = min_jerk(u);
            let (s1, v1, _) = min_jerk(u + h);
            assert!(((s1 - s0) / h - v0).abs() < 1e-4);
            assert!(((v1 - v0) / h - a0).abs() < 1e-3);
        }
        assert_eq!(min_jerk(0.0), (0.0, 0.0, 0.0));
        assert_eq!(min_jerk(1.0).0, 1.0);
    }

    #[test]
    fn walks_and_turns_are_smooth_and_take_the_short_way() {
        let b = Blocking::new(&scene());
        let p0 = b.pose(0, 0.0);
        assert_eq!(p0.position_m, [0.0, 0.0, 0.0]);
        let mid = b.pose(0, 3.0);
        assert!((mid.position_m[0] - 1.0).abs() < 1e-12 && (mid.position_m[1] - 0.5).abs() < 1e-12);
        // Peak speed of a min-jerk walk: 1.875 · distance / duration.
        let speed = mid.velocity_mps[0].hypot(mid.velocity_mps[1]);
        assert!((speed - 1.875 * 5f64.sqrt() / 4.0).abs() < 1e-9);
        // 170° → −170° is +20°, not −340°.
        assert!(b.pose(0, 7.0).facing_rate_radps > 0.0);
        assert_eq!(mid.facing_rate_radps, 0.0, "a walk does not turn the actor");
        let end = b.pose(0, 10.0);
        assert_eq!(end.position_m, [2.0, 1.0, 0.0]);
        assert!((end.facing_rad - (-170f64).to_radians()).abs() < 1e-12);
        assert_eq!(end.velocity_mps, [0.0; 3]);
        // Velocity is the derivative of position.
        let h = 1e-6;
        let a = b.pose(0, 2.2);
        let c = b.pose(0, 2.2 + h);
        assert!(((c.position_m[0] - a.position_m[0]) / h - a.velocity_mps[0]).abs() < 1e-4);
    }
}
