//! The live actors: the script's blocking ([`Blocking`]) plus smooth, seeded deviations —
//! nobody walks a script exactly.
//!
//! Per actor, smooth bounded OU processes (`smooth.rs`): a place offset per floor axis, a
//! facing wobble, and a timing lag or lead (the actor is where the script puts
//! them at `t + δ(t)`). All are continuous with continuous derivatives, so the director never
//! sees an actor jump; velocities and facing rates include the deviations' rates.

use super::config::SimConfig;
use super::rng::{Rng, Ziggurat};
use super::smooth::SmoothOu;
use dronecine_compiler::blocking::Blocking;
use dronecine_compiler::reference::ActorPose;
use dronecine_grammar::script::Scene;

/// A span of script time in which an actor stands still (no walk or turn under way), and its
/// pose there: the blocking is read once per span, not once per frame.
#[derive(Clone, Copy, Debug)]
struct Still {
    from_s: f64,
    until_s: f64,
    pose: ActorPose,
}

/// One actor's movements as script-time intervals, sorted by start, with the running
/// maximum of their ends (walks and turns may overlap).
#[derive(Clone, Debug, Default)]
struct Moves {
    start_s: Vec<f64>,
    max_end_s: Vec<f64>,
}

#[derive(Clone, Debug)]
struct Deviation {
    offset: [SmoothOu; 2],
    facing: SmoothOu,
    timing: SmoothOu,
}

#[derive(Clone, Debug)]
pub struct Actors {
    blocking: Blocking,
    moves: Vec<Moves>,
    still: Vec<Option<Still>>,
    deviations: Vec<Deviation>,
    on: bool,
    /// World time of "action!" (the script's t = 0); `None` while waiting for it.
    action_s: Option<f64>,
}

/// Random stream ids: actors use `ACTOR_STREAM_BASE + 8·i + channel`.
const ACTOR_STREAM_BASE: u64 = 1000;

impl Actors {
    pub fn new(cfg: &SimConfig, scene: &Scene, z: &Ziggurat) -> Actors {
        let blocking = Blocking::new(scene);
        let mut moves = vec![Moves::default(); blocking.len()];
        // `scene.blocking` is sorted by start.
        for m in &scene.blocking {
            if let Some(i) = blocking.names().iter().position(|n| *n == m.actor) {
                let mv = &mut moves[i];
                let end = mv.max_end_s.last().map_or(m.end_s, |&e| e.max(m.end_s));
                mv.start_s.push(m.start_s);
                mv.max_end_s.push(end);
            }
        }
        let deviations = (0..blocking.len() as u64)
            .map(|i| {
                let s = |ch: u64| Rng::stream(cfg.seed, ACTOR_STREAM_BASE + 8 * i + ch);
                let offset = |ch| {
                    SmoothOu::new(
                        s(ch),
                        cfg.actor_offset_sigma_m,
                        cfg.actor_offset_tau_s,
                        cfg.actor_offset_max_m,
                        cfg.actor_knots_per_tau,
                        z,
                    )
                };
                Deviation {
                    offset: [offset(0), offset(1)],
                    facing: SmoothOu::new(
                        s(2),
                        cfg.actor_facing_sigma_rad,
                        cfg.actor_facing_tau_s,
                        cfg.actor_facing_max_rad,
                        cfg.actor_knots_per_tau,
                        z,
                    ),
                    timing: SmoothOu::new(
                        s(3),
                        cfg.actor_timing_sigma_s,
                        cfg.actor_timing_tau_s,
                        cfg.actor_timing_max_s,
                        cfg.actor_knots_per_tau,
                        z,
                    ),
                }
            })
            .collect();
        Actors {
            still: vec![None; blocking.len()],
            blocking,
            moves,
            deviations,
            on: cfg.effects.actor_deviation,
            action_s: (!cfg.wait_for_action).then_some(0.0),
        }
    }

    pub fn len(&self) -> usize {
        self.blocking.len()
    }

    /// The script's pose of actor `i` at script time `t_s`: `Blocking::pose`, read once per
    /// still span.
    #[inline]
    fn scripted(&mut self, i: usize, t_s: f64) -> ActorPose {
        if let Some(s) = &self.still[i] {
            if t_s >= s.from_s && t_s < s.until_s {
                return s.pose;
            }
        }
        let pose = self.blocking.pose(i, t_s);
        let mv = &self.moves[i];
        let k = mv.start_s.partition_point(|&s| s <= t_s);
        let last_end = if k > 0 {
            mv.max_end_s[k - 1]
        } else {
            f64::NEG_INFINITY
        };
        if last_end < t_s {
            self.still[i] = Some(Still {
                from_s: last_end,
                until_s: mv.start_s.get(k).copied().unwrap_or(f64::INFINITY),
                pose,
            });
        }
        pose
    }

    /// "Action!" at world time `t_s`: the script's clock starts (once; later cues are
    /// ignored, so the actors' clock never jumps).
    pub fn action(&mut self, t_s: f64) {
        if self.action_s.is_none() && t_s.is_finite() {
            self.action_s = Some(t_s);
        }
    }

    /// Where actor `i` truly is at world time `t_s` (reads go forward in time). Before
    /// "action!" the script's clock stands at 0 (the deviations still run: actors waiting
    /// on their marks still sway).
    #[inline]
    pub fn pose(&mut self, i: usize, t_s: f64, z: &Ziggurat) -> ActorPose {
        let (script_t, running) = match self.action_s {
            Some(a) => ((t_s - a).max(0.0), t_s >= a),
            None => (0.0, false),
        };
        if !self.on {
            let mut pose = self.scripted(i, script_t);
            if !running {
                pose.velocity_mps = [0.0; 3];
                pose.facing_rate_radps = 0.0;
            }
            return pose;
        }
        let (lag, lag_rate) = self.deviations[i].timing.value_rate(t_s, z);
        // The script's clock for this actor runs at 1 + δ' (stopped before the cue).
        let (clock_rate, lag) = if running {
            (1.0 + lag_rate, lag)
        } else {
            (0.0, 0.0)
        };
        let mut pose = self.scripted(i, script_t + lag);
        let d = &mut self.deviations[i];
        for j in 0..2 {
            let (o, rate) = d.offset[j].value_rate(t_s, z);
            pose.position_m[j] += o;
            pose.velocity_mps[j] = pose.velocity_mps[j] * clock_rate + rate;
        }
        let (f, rate) = d.facing.value_rate(t_s, z);
        pose.facing_rad = super::wrap(pose.facing_rad + f);
        pose.facing_rate_radps = pose.facing_rate_radps * clock_rate + rate;
        pose
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reading the blocking once per still span gives the blocking's poses bit for bit.
    #[test]
    fn still_spans_give_the_blockings_poses_exactly() {
        let src = "stage 8m x 6m x 3m\nactor A height 1.8m at (0, 0) facing 170deg\n\
                   actor B height 1.7m at (1, 1) facing 0deg\n\
                   at 1s A walks to (2, 1) over 4s\nat 5s A turns to -170deg over 2s\n\
                   at 6s B turns to 90deg over 1s\nat 9s A walks to (0, 0) over 2s\n\
                   MS on A for 12s\n";
        let checked = dronecine_grammar::check(src, &dronecine_grammar::Options::default());
        assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
        let scene = checked.script.unwrap().scene.unwrap();
        let cfg = SimConfig {
            effects: crate::Effects::none(),
            ..SimConfig::new(1)
        };
        let z = Ziggurat::get();
        let mut actors = Actors::new(&cfg, &scene, z);
        let blocking = Blocking::new(&scene);
        for k in 0..1500 {
            let t = k as f64 * 0.01;
            for i in 0..2 {
                assert_eq!(
                    actors.pose(i, t, z),
                    blocking.pose(i, t),
                    "actor {i} at {t}"
                );
            }
        }
        // The spans were used: A stands still in [0, 1), (7, 9) and after 11 s.
        assert!(actors.still[0].is_some_and(|s| s.from_s == 11.0));
    }
}
