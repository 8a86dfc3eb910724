//! The flight report: tracking and framing figures for the whole flight and per shot.
//!
//! [`Metrics`] folds in one tick at a time from exactly what the flight record holds (the
//! controller's input and output and the framing), so `shoot` and `replay` compute the same
//! report from the same ticks. Only ticks of the shots count (not take-off, approach or
//! landing).
//!
//! - position error: |measured position − reference position|, on ticks with a measurement;
//! - heading error: the wrapped difference of measured and reference headings;
//! - framing error: the screen distance between where an actor is (projected through the
//!   measured camera pose) and where the script puts it, over the holds; an actor behind the
//!   camera counts as √8 (corner to opposite corner);
//! - saturated fraction: ticks where the controller clamped a set-point, over controlled ticks;
//! - closest to an actor: the least distance from the measured drone to an actor's body (the
//!   segment from their feet to the top of their head, [`body_axis_distance_m`]);
//! - cut-in: how much nearer an actor's body the measured drone was than its reference, on
//!   the ticks where the reference was near the distance it keeps from actors on set
//!   (`actor_distance_m + tracking_margin_m`, within one margin more): the part of the
//!   profile's tracking margin the drone used where the margin is what keeps it out of the
//!   actors' distance. The flight's measure of the margin a drone needs (see [`CutIn`]).

use dronecine_compiler::camera::Vec3;
use dronecine_compiler::compile::{framing_miss_sq, FRAMING_MISS_MAX_SQ};
use dronecine_compiler::framing::body_axis_distance_m;
use dronecine_profile::Safety;
use serde::Serialize;

pub use crate::lateness::Lateness;

use dronecine_compiler::reference::ActorPose;
use dronecine_mcap::record::{FramingRecord, Phase};
use dronecine_servo::control::{TickFault, TickInput, TickOutput};

/// Figures of one shot, or of the whole flight. A figure with nothing to average is `None`
/// (JSON null), never a zero that would read as perfect tracking.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Figures {
    /// `None` when no tick was measured (`measured_ticks` is 0: the drone's body was lost
    /// for the whole shot).
    pub rms_position_error_m: Option<f64>,
    pub max_position_error_m: Option<f64>,
    pub rms_heading_error_rad: Option<f64>,
    /// `None` when there was no hold.
    pub rms_framing_error: Option<f64>,
    /// `None` when no tick of the shots was flown.
    pub saturated_fraction: Option<f64>,
    /// The least distance from the drone (as measured) to an actor's body, the segment from
    /// their feet to the top of their head (as tracked): how near the profile's actor
    /// distance the flight came, or how far inside it. `None` without actors.
    pub closest_actor_m: Option<f64>,
    /// The most the drone (as measured) came nearer an actor's body than its reference was,
    /// over the ticks where the reference stood within `actor_distance_m + 2 ×
    /// tracking_margin_m` of that actor ([`CutIn`]): the tracking margin the drone used.
    /// Negative when it always stood farther than its reference; `None` when the reference
    /// never came that near an actor.
    pub cut_in_m: Option<f64>,
    /// Ticks with a measurement.
    pub measured_ticks: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShotReport {
    pub index: usize,
    /// The shot's PSL text.
    pub label: String,
    /// First and last tick of the shot on the flight clock.
    pub start_s: f64,
    pub end_s: f64,
    #[serde(flatten)]
    pub figures: Figures,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlightReport {
    /// Every shot flown to its end and the drone landed normally.
    pub completed: bool,
    /// From the take-off command to the end (landed, or the landing timed out).
    pub flight_time_s: f64,
    pub shots_time_s: f64,
    /// The script's shots, flown or not (`shots` lists those reached).
    pub scripted_shots: usize,
    #[serde(flatten)]
    pub figures: Figures,
    pub failsafes: u64,
    pub faults: u64,
    pub deadline_misses: u64,
    /// How late the ticks ran, on a flight paced by the wall clock (a real drone, an
    /// emulator, SITL); `None` on the simulator, whose clock waits for nothing, and in a
    /// replay (the log keeps only the late ticks, as `deadline_missed` events).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lateness: Option<Lateness>,
    /// Errors the director raised against the live actors (a framing it could not solve
    /// holds the drone until it solves): each is an event on the log's `/events`.
    pub director_errors: u64,
    /// From a mocap frame reaching the computer to the command leaving it, over the shots'
    /// ticks with a new frame (0 in the simulator, where both happen at the tick).
    pub latency_mean_s: Option<f64>,
    pub latency_max_s: Option<f64>,
    pub shots: Vec<ShotReport>,
}

/// Running sums for [`Figures`].
#[derive(Clone, Copy, Debug, Default)]
struct Accum {
    n: u64,
    sq_pos: f64,
    max_pos: f64,
    sq_heading: f64,
    framing_n: u64,
    sq_framing: f64,
    saturated: u64,
    controlled: u64,
    first_t_s: Option<f64>,
    last_t_s: f64,
    /// `None` until a measured tick with actors.
    closest: Option<Closest>,
    /// `None` until a measured tick with the reference near an actor.
    cut_in: Option<CutIn>,
}

/// Where the drone, as measured, came closest to an actor's body (the segment from their
/// feet to the top of their head) over a shot or the flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    pub distance_m: f64,
    /// The actor's index in the scene.
    pub actor: usize,
    /// The tick's flight clock.
    pub t_s: f64,
}

/// How much nearer an actor's body the drone, as measured, was than its reference, at the
/// tick of a shot or the flight where that was most, among the ticks where the reference
/// stood within `actor_distance_m + 2 × tracking_margin_m` of the actor.
///
/// On set the director holds the reference `actor_distance_m + tracking_margin_m` from the
/// actors (`Director::actors_measured`), so that a drone which strays from it by up to the
/// margin still keeps `actor_distance_m`. Where the reference is at that line or near it
/// (within one margin more), this is the part of the margin the drone used; more than the
/// margin, and a reference held at the line would have had the drone inside the actor's
/// distance. Far from the actors the drone's lag toward one is not counted: there the margin
/// does not matter, and the reference's faster moves there would overstate the need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutIn {
    /// Reference's distance to the actor's body minus the drone's.
    pub cut_in_m: f64,
    /// The actor's index in the scene.
    pub actor: usize,
    /// The tick's flight clock.
    pub t_s: f64,
    /// The reference's distance to that actor's body then.
    pub reference_m: f64,
}

impl Accum {
    fn figures(&self) -> Figures {
        let rms = |s: f64, n: u64| (n > 0).then(|| (s / n as f64).sqrt());
        Figures {
            rms_position_error_m: rms(self.sq_pos, self.n),
            max_position_error_m: (self.n > 0).then_some(self.max_pos),
            rms_heading_error_rad: rms(self.sq_heading, self.n),
            rms_framing_error: rms(self.sq_framing, self.framing_n),
            saturated_fraction: (self.controlled > 0)
                .then(|| self.saturated as f64 / self.controlled as f64),
            closest_actor_m: self.closest.map(|c| c.distance_m),
            cut_in_m: self.cut_in.map(|c| c.cut_in_m),
            measured_ticks: self.n,
        }
    }
}

/// Accumulates the report tick by tick (no allocation per tick).
#[derive(Clone, Debug)]
pub struct Metrics {
    total: Accum,
    shots: Vec<Accum>,
    /// Sum, max and count of the mocap-to-command latencies.
    latency: (f64, f64, u64),
    /// The reference's distance to an actor's body under which a tick counts for the cut-in:
    /// `actor_distance_m + 2 × tracking_margin_m` of the profile flown.
    cut_in_within_m: f64,
}

impl Metrics {
    /// For `shots` shots (more are added as met), flown with a profile's `safety`.
    pub fn new(shots: usize, safety: &Safety) -> Metrics {
        Metrics {
            total: Accum::default(),
            shots: vec![Accum::default(); shots],
            latency: (0.0, 0.0, 0),
            cut_in_within_m: safety.on_set_m() + safety.tracking_margin_m,
        }
    }

    /// The error of one tick: distance and wrapped heading error, when measured (and finite).
    pub fn tracking_error(input: &TickInput) -> Option<(f64, f64)> {
        let m = input.measurement?;
        let r = &input.reference;
        let d: f64 = (0..3)
            .map(|i| (m.position_m[i] - r.position_m[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let h = dronecine_math::wrap_angle_rad(m.heading_rad - r.heading_rad);
        // A faulty (non-finite) tick is counted as a fault, not as an error of NaN metres.
        (d.is_finite() && h.is_finite()).then_some((d, h))
    }

    /// Where the drone came closest to an actor in shot `index` so far (`None` before a
    /// measured tick of it).
    pub fn shot_closest(&self, index: usize) -> Option<Closest> {
        self.shots.get(index).and_then(|a| a.closest)
    }

    /// The drone's most cut-in toward an actor in shot `index` so far ([`CutIn`]; `None`
    /// before a measured tick of it with the reference near an actor).
    pub fn shot_cut_in(&self, index: usize) -> Option<CutIn> {
        self.shots.get(index).and_then(|a| a.cut_in)
    }

    /// One tick, from what the flight logs of it (the flight and replay both call this with
    /// a tick's fields: they hold them in different records).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        phase: Phase,
        shot: Option<usize>,
        input: &TickInput,
        output: &Result<TickOutput, TickFault>,
        framing: &[FramingRecord],
        actors: &[ActorPose],
        latency_s: Option<f64>,
    ) {
        let (Phase::Shots, Some(i)) = (phase, shot) else {
            return;
        };
        // One pass over the actors: the drone's distance to each body serves both figures.
        let (mut closest, mut cut_in) = (None::<Closest>, None::<CutIn>);
        if let Some(m) = input.measurement {
            let p = Vec3::from(m.position_m);
            let r = Vec3::from(input.reference.position_m);
            for (actor, a) in actors.iter().enumerate() {
                let distance_m = body_axis_distance_m(&p, a);
                if distance_m.is_finite() && closest.is_none_or(|c| distance_m < c.distance_m) {
                    closest = Some(Closest {
                        distance_m,
                        actor,
                        t_s: input.t_s,
                    });
                }
                let reference_m = body_axis_distance_m(&r, a);
                let cut_in_m = reference_m - distance_m;
                if reference_m < self.cut_in_within_m
                    && cut_in_m.is_finite()
                    && cut_in.is_none_or(|c| cut_in_m >= c.cut_in_m)
                {
                    cut_in = Some(CutIn {
                        cut_in_m,
                        actor,
                        t_s: input.t_s,
                        reference_m,
                    });
                }
            }
        }
        if let Some(l) = latency_s.filter(|l| l.is_finite()) {
            self.latency.0 += l;
            self.latency.1 = self.latency.1.max(l);
            self.latency.2 += 1;
        }
        if i >= self.shots.len() {
            self.shots.resize(i + 1, Accum::default());
        }
        let saturated = matches!(
            output,
            Ok(TickOutput {
                saturated: true,
                ..
            })
        );
        let error = Self::tracking_error(input);
        for acc in [&mut self.total, &mut self.shots[i]] {
            acc.first_t_s.get_or_insert(input.t_s);
            acc.last_t_s = input.t_s;
            acc.controlled += 1;
            acc.saturated += saturated as u64;
            if let Some(d) = closest {
                if acc.closest.is_none_or(|c| d.distance_m < c.distance_m) {
                    acc.closest = Some(d);
                }
            }
            if let Some(c) = cut_in {
                if acc.cut_in.is_none_or(|m| c.cut_in_m > m.cut_in_m) {
                    acc.cut_in = Some(c);
                }
            }
            if let Some((e, h)) = error {
                acc.n += 1;
                acc.sq_pos += e * e;
                acc.max_pos = acc.max_pos.max(e);
                acc.sq_heading += h * h;
            }
            for f in framing {
                let sq = match f.requested {
                    Some(r) => framing_miss_sq(f.screen, r),
                    None => FRAMING_MISS_MAX_SQ,
                };
                if sq.is_finite() {
                    acc.framing_n += 1;
                    acc.sq_framing += sq;
                }
            }
        }
    }

    /// The report; `labels[i]` names shot `i`. Shots never reached are left out.
    pub fn report(&self, labels: &[String], counts: Counts) -> FlightReport {
        let shots = self
            .shots
            .iter()
            .enumerate()
            .filter_map(|(i, a)| {
                Some(ShotReport {
                    index: i,
                    label: labels
                        .get(i)
                        .cloned()
                        .unwrap_or_else(|| format!("shot {}", i + 1)),
                    start_s: a.first_t_s?,
                    end_s: a.last_t_s,
                    figures: a.figures(),
                })
            })
            .collect();
        FlightReport {
            completed: counts.completed,
            flight_time_s: counts.flight_time_s,
            shots_time_s: self
                .total
                .first_t_s
                .map_or(0.0, |t0| self.total.last_t_s - t0),
            scripted_shots: labels.len(),
            figures: self.total.figures(),
            failsafes: counts.failsafes,
            director_errors: counts.director_errors,
            faults: counts.faults,
            deadline_misses: counts.deadline_misses,
            lateness: counts.lateness,
            latency_mean_s: (self.latency.2 > 0).then(|| self.latency.0 / self.latency.2 as f64),
            latency_max_s: (self.latency.2 > 0).then_some(self.latency.1),
            shots,
        }
    }
}

/// Each shot's PSL text, by timeline index.
pub fn shot_labels(script: &dronecine_grammar::Script, source: &str) -> Vec<String> {
    script
        .timeline
        .iter()
        .map(|shot| shot.label(source))
        .collect()
}

/// What the report takes from the flight's events.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub completed: bool,
    pub flight_time_s: f64,
    pub failsafes: u64,
    pub director_errors: u64,
    pub faults: u64,
    pub deadline_misses: u64,
    pub lateness: Option<Lateness>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_servo::control::{Measurement, Reference};

    /// `ardrone2`'s: 0.5 m from actors, a tracking margin of 0.08 m.
    fn safety() -> Safety {
        dronecine_profile::Profile::builtin("ardrone2")
            .unwrap()
            .safety
    }

    fn input(t_s: f64, err_m: f64, heading_err_rad: f64, measured: bool) -> TickInput {
        TickInput {
            t_s,
            dt_s: 0.01,
            measurement: measured.then_some(Measurement {
                position_m: [1.0 + err_m, 2.0, 1.0],
                heading_rad: 3.0 + heading_err_rad,
            }),
            reference: Reference {
                position_m: [1.0, 2.0, 1.0],
                heading_rad: 3.0,
                ..Reference::default()
            },
        }
    }

    #[test]
    fn figures_are_rms_and_max_over_the_shots_only() {
        let mut m = Metrics::new(2, &safety());
        let ok = Ok(TickOutput::default());
        let sat = Ok(TickOutput {
            saturated: true,
            ..TickOutput::default()
        });
        m.record(
            Phase::Approach,
            None,
            &input(0.0, 9.0, 0.0, true),
            &ok,
            &[],
            &[],
            None,
        );
        m.record(
            Phase::Shots,
            Some(0),
            &input(1.0, 0.3, 0.0, true),
            &ok,
            &[],
            &[],
            None,
        );
        m.record(
            Phase::Shots,
            Some(0),
            &input(1.01, 0.4, 0.0, true),
            &sat,
            &[],
            &[],
            None,
        );
        m.record(
            Phase::Shots,
            Some(1),
            &input(2.0, 0.0, 0.2, false),
            &ok,
            &[],
            &[],
            None,
        );
        // A heading error across ±π is short.
        m.record(
            Phase::Shots,
            Some(1),
            &input(2.01, 0.0, 6.2, true),
            &ok,
            &[],
            &[],
            None,
        );
        let r = m.report(&["a".into(), "b".into()], Counts::default());
        let rms = ((0.09 + 0.16 + 0.0) / 3.0f64).sqrt();
        let near = |x: Option<f64>, want: f64, tol: f64| x.is_some_and(|x| (x - want).abs() < tol);
        assert!(near(r.figures.rms_position_error_m, rms, 1e-12));
        assert!(near(r.figures.max_position_error_m, 0.4, 1e-12));
        assert_eq!(r.figures.measured_ticks, 3);
        assert!(near(r.figures.saturated_fraction, 0.25, 1e-12));
        let h = 6.2 - 2.0 * std::f64::consts::PI;
        assert!(near(
            r.shots[1].figures.rms_heading_error_rad,
            h.abs(),
            1e-9
        ));
        assert!(near(r.shots[0].figures.max_position_error_m, 0.4, 1e-12));
        assert_eq!((r.shots[1].start_s, r.shots[1].end_s), (2.0, 2.01));
        assert_eq!(r.figures.rms_framing_error, None);
    }

    #[test]
    fn a_shot_never_measured_has_null_errors_not_zero() {
        // Shot 0 measured, shot 1 flown blind (its body lost throughout).
        let mut m = Metrics::new(2, &safety());
        let ok = Ok(TickOutput::default());
        m.record(
            Phase::Shots,
            Some(0),
            &input(1.0, 0.3, 0.1, true),
            &ok,
            &[],
            &[],
            None,
        );
        for k in 0..3 {
            let t = 2.0 + 0.01 * k as f64;
            m.record(
                Phase::Shots,
                Some(1),
                &input(t, 0.0, 0.0, false),
                &ok,
                &[],
                &[],
                None,
            );
        }
        let r = m.report(&["a".into(), "b".into()], Counts::default());
        let blind = &r.shots[1].figures;
        assert_eq!(blind.measured_ticks, 0);
        assert_eq!(
            (
                blind.rms_position_error_m,
                blind.max_position_error_m,
                blind.rms_heading_error_rad
            ),
            (None, None, None)
        );
        // Flown, so its saturation is known.
        assert_eq!(blind.saturated_fraction, Some(0.0));
        // The flight's figures come from the measured tick alone.
        assert_eq!(r.figures.measured_ticks, 1);
        assert!(r
            .figures
            .rms_position_error_m
            .is_some_and(|e| (e - 0.3).abs() < 1e-12));
        let json = serde_json::to_value(&r).unwrap();
        let shot = &json["shots"][1];
        for key in [
            "rms_position_error_m",
            "max_position_error_m",
            "rms_heading_error_rad",
        ] {
            assert!(shot[key].is_null(), "{key}: {}", shot[key]);
        }
        assert!(json["rms_position_error_m"].is_number());
        // Nothing flown: nothing to average, not even the saturation.
        let r = Metrics::new(1, &safety()).report(&["a".into()], Counts::default());
        assert_eq!(r.figures, Figures::default());
        assert_eq!(r.figures.saturated_fraction, None);
    }

    #[test]
    fn framing_error_is_the_screen_distance() {
        let mut m = Metrics::new(1, &safety());
        let f = [
            FramingRecord {
                actor: 0,
                screen: Some([0.3, 0.4]),
                requested: Some([0.0, 0.0]),
            },
            FramingRecord {
                actor: 1,
                screen: None,
                requested: Some([0.0, 0.0]),
            },
        ];
        m.record(
            Phase::Shots,
            Some(0),
            &input(0.0, 0.0, 0.0, true),
            &Ok(TickOutput::default()),
            &f[..1],
            &[],
            None,
        );
        let r = m.report(&[], Counts::default());
        assert!((r.figures.rms_framing_error.unwrap() - 0.5).abs() < 1e-12);
        m.record(
            Phase::Shots,
            Some(0),
            &input(0.01, 0.0, 0.0, true),
            &Ok(TickOutput::default()),
            &f[1..],
            &[],
            None,
        );
        let r = m.report(&[], Counts::default());
        assert!(
            (r.figures.rms_framing_error.unwrap() - ((0.25 + 8.0) / 2.0f64).sqrt()).abs() < 1e-12
        );
        // An actor near the camera's plane projects hundreds of frames away: off the frame,
        // it counts as the frame's diagonal, as one behind the camera does (one such tick
        // made a whole flight's RMS 10).
        let far = [FramingRecord {
            actor: 0,
            screen: Some([600.0, -2.0]),
            requested: Some([0.0, 0.0]),
        }];
        m.record(
            Phase::Shots,
            Some(0),
            &input(0.02, 0.0, 0.0, true),
            &Ok(TickOutput::default()),
            &far,
            &[],
            None,
        );
        let r = m.report(&[], Counts::default());
        assert!(
            (r.figures.rms_framing_error.unwrap() - ((0.25 + 8.0 + 8.0) / 3.0f64).sqrt()).abs()
                < 1e-12
        );
    }

    /// The cut-in counts only the ticks with the reference near an actor (within
    /// `actor_distance_m + 2 × tracking_margin_m` of their body), takes the most of them, and
    /// may be negative (the drone farther than its reference); a shot whose reference stayed
    /// away has none.
    #[test]
    fn the_cut_in_is_measured_where_the_reference_is_near_an_actor() {
        let safety = safety();
        let within_m = safety.actor_distance_m + 2.0 * safety.tracking_margin_m;
        let actor = ActorPose {
            position_m: [0.0, 0.0, 0.0],
            velocity_mps: [0.0; 3],
            facing_rad: 0.0,
            facing_rate_radps: 0.0,
            height_m: 1.8,
        };
        let tick = |t_s: f64, reference: [f64; 3], drone: Option<[f64; 3]>| TickInput {
            t_s,
            dt_s: 0.01,
            measurement: drone.map(|position_m| Measurement {
                position_m,
                heading_rad: 0.0,
            }),
            reference: Reference {
                position_m: reference,
                ..Reference::default()
            },
        };
        let mut m = Metrics::new(3, &safety);
        let ok = Ok(TickOutput::default());
        let mut record = |shot: usize, input: TickInput| {
            m.record(Phase::Shots, Some(shot), &input, &ok, &[], &[actor], None)
        };
        let near = within_m - 0.01;
        // Shot 0: 4 cm nearer beside the actor; then far off, 1 m nearer, not counted.
        record(
            0,
            tick(1.0, [near, 0.0, 1.0], Some([near - 0.04, 0.0, 1.0])),
        );
        record(
            0,
            tick(1.01, [within_m + 1.0, 0.0, 1.0], Some([1.0, 0.0, 1.0])),
        );
        // Unmeasured: not counted, however near.
        record(0, tick(1.02, [0.5, 0.0, 1.0], None));
        // Shot 1: over the head (distance to its top), 3 cm farther than the reference.
        record(
            1,
            tick(2.0, [0.0, 0.0, 1.8 + near], Some([0.0, 0.0, 1.83 + near])),
        );
        // Shot 2: only far.
        record(
            2,
            tick(3.0, [0.0, within_m + 0.2, 1.0], Some([0.0, 0.1, 1.0])),
        );
        let cut = |shot: usize| m.shot_cut_in(shot).map(|c| c.cut_in_m);
        let close = |x: Option<f64>, want: f64| x.is_some_and(|x| (x - want).abs() < 1e-12);
        assert!(close(cut(0), 0.04), "{:?}", cut(0));
        assert!(close(cut(1), -0.03), "{:?}", cut(1));
        assert_eq!(cut(2), None);
        let c = m.shot_cut_in(0).unwrap();
        assert_eq!((c.actor, c.t_s), (0, 1.0));
        assert!((c.reference_m - near).abs() < 1e-12);
        let r = m.report(&[], Counts::default());
        assert!(close(r.figures.cut_in_m, 0.04));
        assert!(close(r.shots[1].figures.cut_in_m, -0.03));
        assert_eq!(r.shots[2].figures.cut_in_m, None);
        let json = serde_json::to_value(&r).unwrap();
        assert!(json["shots"][2]["cut_in_m"].is_null());
        assert!(json["cut_in_m"].is_number());
    }
}
