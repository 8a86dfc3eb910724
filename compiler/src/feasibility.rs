//! Feasibility: every sample checked against the drone profile, the stage and the actors.
//!
//! The monitor watches two things per shot. What the script *asks* (the target's speed and
//! acceleration, before steering caps them): if a shot asks more than the drone flies, the
//! error says by how much and how long the shot must be. And what the reference *is* (speed,
//! tilt that the servo model needs for it, vertical speed, yaw rate, distance from the
//! actors, inside the stage, how far it lags its target). Violations become one diagnostic
//! per shot and kind, on the shot's line, with the numbers and a concrete fix.

use crate::code::CompileCode;
use dronecine_diag::Diagnostic;
use dronecine_grammar::script::{Scene, Shot, ShotContent};

use crate::camera::Vec3;
use crate::reference::{ActorPose, Sample, ShotTiming};
use crate::steering::Kinematics;
use dronecine_profile::Profile;

/// How far the reference may lag its target during a shot before the framing is lost.
pub const TRACKING_TOLERANCE_M: f64 = 0.10;
/// Tolerance on the limits (numerical noise of the steering integration).
const SLACK: f64 = 1.005;

#[derive(Clone, Copy, Debug, Default)]
struct Peak {
    value: f64,
    t_s: f64,
}

impl Peak {
    fn see(&mut self, value: f64, t_s: f64) {
        if value > self.value {
            *self = Peak { value, t_s };
        }
    }
}

#[derive(Clone, Debug, Default)]
struct ShotStats {
    demand_speed: Peak,
    demand_accel: Peak,
    /// The largest step of the target as solved from one sample to the next that no drone
    /// could make ([`JUMP_MIN_M`], [`JUMP_SPEEDS`]), and the last sample's target.
    jump: Peak,
    last_solved: Option<(f64, Vec3)>,
    speed: Peak,
    tilt: Peak,
    vz: Peak,
    yaw_rate: Peak,
    /// The lag behind the target, from when it is the shot's own: a shot that starts behind
    /// its framing (a `then` shot starts where the one before left it, that one's error) owns
    /// its lag once it has caught up within [`TRACKING_TOLERANCE_M`]…
    lag: Peak,
    /// …and before that, how much further behind than the shot before left it it falls,
    /// and that lag.
    lag_further: Peak,
    lag_carried: Carried,
    /// Deepest intrusion into an actor's safety distance during the shot, and whose…
    intrusion: Peak,
    intruded: Option<usize>,
    /// …and on the repositioning flight before it.
    intrusion_on_the_way: Peak,
    intruded_on_the_way: Option<usize>,
    outside: Peak,
    outside_at: [f64; 3],
    /// The deepest point outside was the framing's (the target as solved), which the
    /// director does not follow out of the stage.
    outside_framing: bool,
    /// How far outside the shot before left the framing, where this shot continues it.
    outside_carried: Carried,
    /// How far inside an actor's distance the shot before left the camera.
    intrusion_carried: Carried,
    /// How deep the framing (the target as solved) puts the camera into the stage's margin
    /// during the shot, inside the stage, as a fraction of its distance to the nearest actor
    /// (what the screen shows of the shift: a size that much larger, or an angle of that many
    /// radians), and where, how deep, and which actor at what distance: the director holds
    /// the drone at the margin, off its framing.
    in_margin: Peak,
    in_margin_at: [f64; 3],
    in_margin_m: f64,
    in_margin_actor: Option<(usize, f64)>,
}

/// A step of the solved target between two samples is a jump, not a fast framing, from this
/// long and this many times the drone's top speed over the samples' interval: a framing that
/// changes place at once (an over-the-shoulder's other camera, a two-shot's size passing to
/// the other actor). Longer shots do not help such a shot, so it is told as a jump, not with
/// the retiming help, which would ask for an absurdly long shot.
const JUMP_MIN_M: f64 = 0.3;
const JUMP_SPEEDS: f64 = 10.0;

/// Per-shot peaks of everything checked.
#[derive(Clone)]
pub struct Monitor {
    stats: Vec<ShotStats>,
    speed_max: f64,
    accel_max: f64,
    tilt_max: f64,
    vz_max: f64,
    yaw_max: f64,
    gain: f64,
    tau: f64,
    safety_m: f64,
    lo: Vec3,
    hi: Vec3,
    margin_m: f64,
    profile: String,
    names: Vec<String>,
    /// The shot of the last sample in a shot, and how far behind its target the drone was.
    last_lag: Option<(usize, f64)>,
    /// The last in-shot sample's shot and how far outside the stage its framing was.
    last_outside: Option<(usize, f64)>,
    /// The last in-shot sample's shot and how far inside an actor's distance the camera was.
    last_intrusion: Option<(usize, f64)>,
    /// The actors are measured (a flight): what the framing demands, and the reference's
    /// lag behind it, are not told ([`Monitor::actors_measured`]).
    measured: bool,
}

impl Monitor {
    pub fn new(profile: &Profile, scene: &Scene, shots: usize) -> Monitor {
        let (lo, hi) = (scene.stage.min_m(), scene.stage.max_m());
        let m = &profile.model;
        Monitor {
            stats: vec![ShotStats::default(); shots],
            speed_max: profile.limits.speed_max_mps,
            accel_max: profile.limits.accel_max_mps2,
            tilt_max: profile.limits.tilt_max_rad,
            vz_max: profile.limits.vz_max_mps,
            yaw_max: profile.limits.yaw_rate_max_radps,
            gain: m.gain_roll_mps_per_rad.min(m.gain_pitch_mps_per_rad),
            tau: m.tau_roll_s.max(m.tau_pitch_s),
            safety_m: profile.safety.actor_distance_m,
            lo: Vec3::from(lo),
            hi: Vec3::from(hi),
            margin_m: profile.safety.stage_margin_m,
            profile: profile.name.clone(),
            names: scene.actors.iter().map(|a| a.name.clone()).collect(),
            last_lag: None,
            last_outside: None,
            last_intrusion: None,
            measured: false,
        }
    }

    /// Tilt the servo model needs to fly `v` with acceleration `a` (per horizontal axis
    /// `v̇ = (K·tilt − v)/τ`).
    pub fn tilt_needed_rad(&self, v: &Vec3, a: &Vec3) -> f64 {
        let x = self.tau * a.x + v.x;
        let y = self.tau * a.y + v.y;
        dronecine_math::norm_xy(x, y) / self.gain
    }

    /// One sample, the goal the steering chased and the target as solved (`solved`: before
    /// the director kept it inside the stage).
    pub fn record(
        &mut self,
        s: &Sample,
        goal: &Kinematics,
        solved: &Vec3,
        actors: &[ActorPose],
        in_shot: bool,
    ) {
        let Some(st) = self.stats.get_mut(s.shot) else {
            return;
        };
        let t = s.t_s;
        let p = Vec3::from(s.position_m);
        let v = Vec3::from(s.velocity_mps);
        let a = Vec3::from(s.acceleration_mps2);
        if in_shot {
            st.demand_speed
                .see(dronecine_math::norm_xy(goal.v.x, goal.v.y), t);
            st.demand_accel
                .see(dronecine_math::norm_xy(goal.a.x, goal.a.y), t);
            let lag_m = (goal.p - p).norm();
            // What the shot just before left: the lag of its last sample. (A target that
            // steps at the boundary is this shot's lag, not an inherited one.)
            let left_m = left_by(self.last_lag, s.shot);
            st.lag_carried.see(left_m, lag_m, TRACKING_TOLERANCE_M);
            self.last_lag = Some((s.shot, lag_m));
            if st.lag_carried.returning {
                st.lag_further.see(lag_m - st.lag_carried.entry(), t);
            } else {
                st.lag.see(lag_m, t);
            }
            if let Some((t0, p0)) = st.last_solved {
                let step_m = (solved - p0).norm();
                if t > t0 && step_m > JUMP_MIN_M && step_m > JUMP_SPEEDS * self.speed_max * (t - t0)
                {
                    st.jump.see(step_m, t);
                }
            }
            st.last_solved = Some((t, *solved));
        }
        if !in_shot {
            // A repositioning flight: the shot after it starts from where the flight left it,
            // not where the shot before left the drone.
            self.last_lag = None;
            self.last_outside = None;
            self.last_intrusion = None;
        }
        st.speed.see(dronecine_math::norm_xy(v.x, v.y), t);
        let x = self.tau * a.x + v.x;
        let y = self.tau * a.y + v.y;
        st.tilt.see(dronecine_math::norm_xy(x, y) / self.gain, t);
        st.vz.see(v.z.abs(), t);
        st.yaw_rate.see(s.heading_rate_radps.abs(), t);
        let intrusion_of =
            |actor: &ActorPose| crate::route::body_intrusion_m(&p, actor, self.safety_m);
        let deepest = in_shot.then(|| actors.iter().map(intrusion_of).fold(0.0, f64::max));
        if let Some(deepest) = deepest {
            // As for the stage: a shot that continues the one before starts where that one
            // left the camera, inside an actor's distance (that shot's error, told there).
            let left_m = left_by(self.last_intrusion, s.shot);
            st.intrusion_carried.see(left_m, deepest, INTRUSION_TOLD_M);
            self.last_intrusion = Some((s.shot, deepest));
        }
        let carried = st.intrusion_carried;
        // Clear of every actor (the usual sample): no peak to raise.
        let clear = deepest.is_some_and(|d| d <= 0.0);
        for (i, actor) in actors.iter().enumerate().filter(|_| !clear) {
            let intrusion = intrusion_of(actor);
            if in_shot && carried.holds(intrusion, INTRUSION_TOLD_M) {
                continue;
            }
            let (peak, whose) = if in_shot {
                (&mut st.intrusion, &mut st.intruded)
            } else {
                (&mut st.intrusion_on_the_way, &mut st.intruded_on_the_way)
            };
            if intrusion > peak.value {
                *peak = Peak {
                    value: intrusion,
                    t_s: t,
                };
                *whose = Some(i);
            }
        }
        let outside = |q: &Vec3| {
            (0..3).fold(0.0f64, |out, i| {
                out.max(self.lo[i] - q[i]).max(q[i] - self.hi[i])
            })
        };
        let framing_out = outside(solved);
        if in_shot {
            // A shot that continues the one before starts with that one's framing, out where
            // it left it: that shot's error, told there.
            let left_m = left_by(self.last_outside, s.shot);
            st.outside_carried.see(left_m, framing_out, OUTSIDE_TOLD_M);
            self.last_outside = Some((s.shot, framing_out));
        }
        let inherited = st.outside_carried.holds(framing_out, OUTSIDE_TOLD_M);
        for (q, framing) in [(p, false), (*solved, true)] {
            if framing && inherited {
                continue;
            }
            let out = outside(&q);
            if out > st.outside.value {
                st.outside = Peak { value: out, t_s: t };
                st.outside_at = q.into();
                st.outside_framing = framing;
            }
        }
        if in_shot {
            // Signed: how far beyond the nearest face (negative inside), plus the margin.
            let beyond = (0..3).fold(f64::NEG_INFINITY, |d, i| {
                d.max(self.lo[i] - solved[i]).max(solved[i] - self.hi[i])
            });
            let into = beyond + self.margin_m;
            if into > 0.0 && into <= self.margin_m {
                let nearest = (actors.iter().enumerate())
                    .map(|(i, a)| (i, crate::framing::body_axis_distance_m(solved, a)))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                // Without actors (a path), the shift is the shift: as if 1 m away.
                let share = into / nearest.map_or(1.0, |(_, d)| d.max(0.1));
                if share > st.in_margin.value {
                    st.in_margin = Peak {
                        value: share,
                        t_s: t,
                    };
                    st.in_margin_at = (*solved).into();
                    st.in_margin_m = into;
                    st.in_margin_actor = nearest;
                }
            }
        }
    }

    /// The actors it is fed are measured (a flight's director, `Director::actors_measured`):
    /// the framing's own speed and acceleration are the live actors' noise differentiated, and
    /// how far the reference is from it is mostly that noise smoothed away; neither is told (a
    /// framing that swings with an actor's measured facing would "need" many times what the
    /// drone flies, and seem to leave the reference behind). The report's framing error says
    /// what the shot got. The reference's own limits, the framing's jumps, the stage and the
    /// actors' distance are told as in `compile`.
    pub fn actors_measured(&mut self) {
        self.measured = true;
    }

    /// The diagnostics of everything in shot `i` (its repositioning flight included) that
    /// exceeded a limit, into `out`: `compile` tells every shot's at the end, a flight each
    /// shot's when it is over (a shot's samples end where the next shot's, its repositioning
    /// flight's first, begin). `is_held_off(k)`: shot `k`'s framing puts the camera inside an
    /// actor's safety distance, an error already reported. Its consequences are not told
    /// again: how far the drone, keeping its distance, stays behind that framing, and a
    /// repositioning flight after the shot that starts inside the actor's distance, where
    /// the shot left the drone.
    pub fn shot_diagnostics(
        &self,
        i: usize,
        shots: &[Shot],
        timings: &[ShotTiming],
        is_held_off: impl Fn(usize) -> bool,
        out: &mut Vec<Diagnostic>,
    ) {
        let Some(report) = ShotReport::new(self, i, shots, timings) else {
            return;
        };
        // One demand at most: a jump sets it, then what the script asks, then the lag, then
        // the reference's own limits.
        let demand = report
            .jump()
            .or_else(|| report.demand_speed())
            .or_else(|| report.demand_accel())
            .or_else(|| report.lag(&is_held_off))
            .or_else(|| report.reference_limit());
        out.extend(demand);
        out.extend(report.too_close(&is_held_off));
        out.extend(report.in_margin());
        out.extend(report.leaves_stage());
    }
}

/// One shot's peaks, with what its diagnostics say them with: when, how long, the fix.
struct ShotReport<'m> {
    monitor: &'m Monitor,
    st: &'m ShotStats,
    shot: &'m Shot,
    i: usize,
    duration: f64,
    retimeable: bool,
    /// The shot's start: its samples begin with the repositioning flight before it, if any.
    start: f64,
    /// How much longer a retimeable shot must be for both its speed and its acceleration to
    /// fit (speed scales as 1/T, acceleration as 1/T²), with 5% margin.
    retime: f64,
}

impl<'m> ShotReport<'m> {
    /// Shot `i`'s peaks and timing, or `None` for a shot the monitor or the script lacks.
    fn new(
        monitor: &'m Monitor,
        i: usize,
        shots: &'m [Shot],
        timings: &[ShotTiming],
    ) -> Option<ShotReport<'m>> {
        let (Some(st), Some(shot)) = (monitor.stats.get(i), shots.get(i)) else {
            return None;
        };
        let duration = shot.end_s - shot.start_s;
        let retimeable = matches!(shot.content, ShotContent::Path(_))
            || dronecine_grammar::script::moves_camera(shots, i);
        let start = timings
            .iter()
            .find(|x| x.index == i)
            .map(|x| x.start_s)
            .unwrap_or(shot.start_s);
        let retime = (st.demand_speed.value / monitor.speed_max)
            .max((st.demand_accel.value / monitor.accel_max).sqrt())
            * 1.05;
        Some(ShotReport {
            monitor,
            st,
            shot,
            i,
            duration,
            retimeable,
            start,
            retime,
        })
    }

    /// Time `t` is on the repositioning flight before the shot.
    fn on_the_flight(&self, t: f64) -> bool {
        t < self.start - 0.005
    }

    /// When `t` is, said from the shot's start.
    fn at(&self, t: f64) -> String {
        if self.on_the_flight(t) {
            format!(
                "on the repositioning flight, {:.1} s before the shot starts",
                round_up_1(self.start - t)
            )
        } else {
            format!("{:.1} s into the shot", (t - self.start).max(0.0))
        }
    }

    /// What the shot asks that the drone cannot give: an error on its line, with what the
    /// label points at and the fix.
    fn infeasible(&self, message: String, label: &str, help: String) -> Diagnostic {
        Diagnostic::error(CompileCode::Infeasible, self.shot.span, message)
            .with_label(label)
            .with_help(help)
    }

    /// A framing that jumps further between two samples than any drone flies, said as such
    /// with what changes it.
    fn jump(&self) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let jumps = st.jump.value > 0.0;
        if !jumps {
            return None;
        }
        let message = format!(
            "the framing jumps {:.2} m from one sample to the next ({}): no drone follows \
             that, {} flies {:.2} m/s",
            st.jump.value,
            self.at(st.jump.t_s),
            m.profile,
            m.speed_max
        );
        let help = "as the actors move, the framing's camera has to change place at once (an \
                    over-the-shoulder's other camera frames the profile better, or a \
                    two-shot's size passes to the other actor, who is now nearer): cut to the \
                    framing as it is after the change, or block the actors so that it does \
                    not happen"
            .to_string();
        Some(self.infeasible(message, "the framing jumps here", help))
    }

    /// A shot that asks more speed than the drone flies.
    fn demand_speed(&self) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let over = st.demand_speed.value > m.speed_max * SLACK;
        if m.measured || !over {
            return None;
        }
        let need = st.demand_speed.value;
        let help = if self.retimeable {
            format!(
                "make it at least {:.1} s",
                round_up_1(self.duration * self.retime)
            )
        } else {
            "the framing follows the actors: slow their movement (a longer `over`) or \
             use a wider size"
                .to_string()
        };
        Some(self.infeasible(
            format!(
                "this shot needs {need:.2} m/s ({}); {} flies {:.2} m/s",
                self.at(st.demand_speed.t_s),
                m.profile,
                m.speed_max
            ),
            "too fast for the drone",
            help,
        ))
    }

    /// A shot that asks more acceleration than the drone gives.
    fn demand_accel(&self) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let over = st.demand_accel.value > m.accel_max * SLACK;
        if m.measured || !over {
            return None;
        }
        let need = st.demand_accel.value;
        let help = if self.retimeable {
            format!(
                "make it at least {:.1} s",
                round_up_1(self.duration * self.retime)
            )
        } else {
            "the framing follows the actors: make their movements smoother (a longer \
             `over`) or use a wider size"
                .to_string()
        };
        Some(self.infeasible(
            format!(
                "this shot needs {need:.2} m/s² ({}); {} accelerates at most {:.2} m/s²",
                self.at(st.demand_accel.t_s),
                m.profile,
                m.accel_max
            ),
            "too abrupt for the drone",
            help,
        ))
    }

    /// The drone falling behind its framing within the drone's limits. A shot that the one
    /// before left behind its framing (that one's error already) is told only for what it
    /// adds: the lag it starts with is not its doing, and its fix ("make it longer") would
    /// not fix it.
    fn lag(&self, is_held_off: impl Fn(usize) -> bool) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let entry_m = st.lag_carried.entry();
        let own = st.lag.value > TRACKING_TOLERANCE_M;
        let further = !own && st.lag_further.value > TRACKING_TOLERANCE_M;
        if m.measured || is_held_off(self.i) || !(own || further) {
            return None;
        }
        Some(self.infeasible(
            if further {
                format!(
                    "the drone falls a further {:.2} m behind the framing ({}), {:.2} m \
                     in all, within {}'s limits (it starts {:.2} m behind, where the shot \
                     before left it)",
                    st.lag_further.value,
                    self.at(st.lag_further.t_s),
                    st.lag_further.value + entry_m,
                    m.profile,
                    entry_m
                )
            } else {
                format!(
                    "the drone falls {:.2} m behind the framing ({}) within {}'s limits",
                    st.lag.value,
                    self.at(st.lag.t_s),
                    m.profile
                )
            },
            "the framing is lost here",
            if self.retimeable {
                format!(
                    "make it longer (at least {:.1} s)",
                    round_up_1(self.duration * 1.5)
                )
            } else {
                "slow the actors' movements or use a wider size".to_string()
            },
        ))
    }

    /// The first of the reference's own limits (tilt, vertical speed, yaw rate, speed) that
    /// it exceeds.
    fn reference_limit(&self) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let checks = [
            (st.tilt, m.tilt_max, "tilt", "rad"),
            (st.vz, m.vz_max, "vertical speed", "m/s"),
            (st.yaw_rate, m.yaw_max, "yaw rate", "rad/s"),
            (st.speed, m.speed_max, "speed", "m/s"),
        ];
        let (peak, max, what, unit) = checks
            .into_iter()
            .find(|(peak, max, _, _)| peak.value > max * SLACK)?;
        Some(
            Diagnostic::error(
                CompileCode::Infeasible,
                self.shot.span,
                format!(
                    "the reference needs a {what} of {:.2} {unit} ({}); {} allows {:.2} {unit}",
                    peak.value,
                    self.at(peak.t_s),
                    m.profile,
                    max
                ),
            )
            .with_label(format!("{what} over the limit"))
            .with_help(format!(
                "make the shot at least {:.1} s long",
                round_up_1(self.duration * peak.value / max)
            )),
        )
    }

    /// The deepest intrusion into an actor's safety distance, in the shot or on the
    /// repositioning flight before it.
    fn too_close(&self, is_held_off: impl Fn(usize) -> bool) -> Option<Diagnostic> {
        let (st, m, i) = (self.st, self.monitor, self.i);
        let after_held_off = i > 0 && is_held_off(i - 1);
        let (intrusion, intruded) =
            if after_held_off || st.intrusion.value >= st.intrusion_on_the_way.value {
                (st.intrusion, st.intruded)
            } else {
                (st.intrusion_on_the_way, st.intruded_on_the_way)
            };
        let told = intrusion.value > INTRUSION_TOLD_M;
        if !told {
            return None;
        }
        let who = intruded
            .and_then(|i| m.names.get(i))
            .map(String::as_str)
            .unwrap_or("an actor");
        Some(
            Diagnostic::error(
                CompileCode::TooClose,
                self.shot.span,
                format!(
                    "the camera comes within {:.2} m of {who} ({}); {} keeps {:.2} m from actors",
                    m.safety_m - intrusion.value,
                    self.at(intrusion.t_s),
                    m.profile,
                    m.safety_m
                ),
            )
            .with_label(format!("too close to {who}"))
            .with_help(if self.on_the_flight(intrusion.t_s) {
                // No way there clear of the actor (routes keep clear where one is).
                format!(
                    "the drone passes {who} on its way to this framing: frame the shot \
                     from the side of {who} it comes from, or use a wider size or a \
                     longer lens (`lens …`), which stand the framing further off"
                )
            } else {
                "use a wider size, a longer lens (`lens …`), or move the path away from \
                 the actors"
                    .to_string()
            }),
        )
    }

    /// Held at the margin: a warning (the shot is flown, a little off its framing) when the
    /// screen shows it (`IN_MARGIN_TOLD`), and the framing does not leave the stage (an
    /// error of its own).
    fn in_margin(&self) -> Option<Diagnostic> {
        let (st, m) = (self.st, self.monitor);
        let told = st.in_margin.value > IN_MARGIN_TOLD && st.outside.value <= OUTSIDE_TOLD_M;
        if !told {
            return None;
        }
        let (p, by, when) = (st.in_margin_at, st.in_margin_m, self.at(st.in_margin.t_s));
        let margin = m.margin_m;
        let share = match st.in_margin_actor {
            Some((i, d)) => format!(
                " ({:.0} % of its {d:.2} m to {})",
                st.in_margin.value * 100.0,
                m.names.get(i).map_or("the actor", String::as_str)
            ),
            None => String::new(),
        };
        Some(
            Diagnostic::warning(
                CompileCode::InMargin,
                self.shot.span,
                format!(
                    "this framing puts the camera {by:.2} m into the stage's {margin:.2} m \
                     margin at ({:.2}, {:.2}, {:.2}) ({when}); the drone is held at the \
                     margin, up to {by:.2} m off its framing{share}",
                    p[0], p[1], p[2]
                ),
            )
            .with_label("into the stage's margin")
            .with_help(format!(
                "{} keeps {margin:.2} m from the stage's walls, floor and ceiling: make the \
                 stage larger, or move the framing inward (a tighter size brings the \
                 camera closer to the actors)",
                m.profile
            )),
        )
    }

    /// The camera, or its framing, outside the stage.
    fn leaves_stage(&self) -> Option<Diagnostic> {
        let st = self.st;
        let told = st.outside.value > OUTSIDE_TOLD_M;
        if !told {
            return None;
        }
        let (p, by, when) = (st.outside_at, st.outside.value, self.at(st.outside.t_s));
        let at_p = format!("at ({:.2}, {:.2}, {:.2}) ({when})", p[0], p[1], p[2]);
        let message = if st.outside_framing {
            format!(
                "this framing puts the camera {by:.2} m outside the stage {at_p}; the \
                 drone would be held inside, off its framing"
            )
        } else {
            format!("the camera leaves the stage by {by:.2} m {at_p}")
        };
        let help = "make the stage larger, or move the path or the framing inside it (a \
                    tighter size brings the camera closer)";
        Some(
            Diagnostic::error(CompileCode::LeavesStage, self.shot.span, message)
                .with_label("outside the flight volume")
                .with_help(help),
        )
    }
}

/// The share of its distance to the nearest actor that a framing's camera may be held off by
/// the stage's margin before `compile::in_margin` is told: 8 % (a size that much off, about a
/// quarter of the step between two named sizes, or an angle of 5°). A camera held 0.08 m off
/// at 1.3 m (6 %) or 0.10 m off at 2.3 m (4 %) is not told; an MS held 0.10 m off at 0.8 m
/// (12 %) is.
const IN_MARGIN_TOLD: f64 = 0.08;

/// What a shot carries over from the shot before, which it continues (`then`): a lag behind
/// the target, a framing outside the stage, a camera inside an actor's distance (here and in
/// the director's own check of its framings). That is the shot before's error, told there;
/// the shot owns only what goes beyond it, or what comes back after it has got clear.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Carried {
    /// What the shot before left (`None` before this shot's first sample).
    entry: Option<f64>,
    /// Still over the figure told since the shot's first sample: on its way back from it.
    returning: bool,
}

impl Carried {
    /// One in-shot sample: `left` what the sample before left this shot ([`left_by`]), `now`
    /// this sample's figure, `told` the figure from which it is told.
    pub(crate) fn see(&mut self, left: f64, now: f64, told: f64) {
        if self.entry.is_none() {
            self.entry = Some(left);
            self.returning = left > told;
        }
        self.returning &= now > told;
    }

    pub(crate) fn entry(&self) -> f64 {
        self.entry.unwrap_or(0.0)
    }

    /// `now` is still what the shot before left: on the way back, and no further out than
    /// it started.
    pub(crate) fn holds(&self, now: f64, told: f64) -> bool {
        self.returning && now <= self.entry() + told
    }
}

/// What the last in-shot sample (its shot, and a figure) left shot `shot`: the figure when
/// that was the shot just before (a repositioning flight in between clears it), else 0.
fn left_by(last: Option<(usize, f64)>, shot: usize) -> f64 {
    match last {
        Some((before, figure)) if before + 1 == shot => figure,
        _ => 0.0,
    }
}

/// How far inside an actor's distance the camera may come before `compile::too_close` is
/// told.
const INTRUSION_TOLD_M: f64 = 0.02;

/// How far outside the stage the camera or its framing may go before `compile::leaves_stage`
/// is told.
const OUTSIDE_TOLD_M: f64 = 0.02;

/// Round up to a tenth (durations and times suggested to the user).
pub(crate) fn round_up_1(x: f64) -> f64 {
    (x * 10.0).ceil() / 10.0
}
