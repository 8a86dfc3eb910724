//! The flight, one function per phase: pre-flight (`preflight`), take-off, the approach to
//! the first framing, the settle onto it, the shots with the online director, the hold and
//! the flight back over the take-off spot, the landing, and the report.

use dronecine_backend::FlightState;
use dronecine_compiler::camera::{CameraPose, Vec3};
use dronecine_compiler::director::Director;
use dronecine_compiler::reference::Sample;
use dronecine_mcap::record::{FramingRecord, Phase};

use crate::ahead::{direct, Ahead, AheadStart, DirectedTick, Directing};
use crate::code::{refusal, PreflightCode};
use crate::flight::{unreachable_measurement, Flight, Outcome};
use crate::glide::{hover_sample, Glide};
use crate::preflight::{Ground, APPROACH_TOLERANCE_M};
use crate::report::{Counts, FlightReport};
use crate::{FlightError, Progress};

/// Pause after the approach's glide, before "action!", while the director steers the drone
/// from where the glide ended onto the first framing as the actors stand (it goes on steering
/// into the first shot: its arrival closes a gap as e^(−t/1 s)).
const SETTLE_S: f64 = 1.0;
/// Hold after the last shot, before the flight back to the take-off spot and the landing.
const HOLD_BEFORE_LANDING_S: f64 = 1.0;
/// Within this (horizontally) of the take-off spot, the drone lands where it is.
const HOME_RADIUS_M: f64 = 0.3;

/// Who steps the director during the shots: the loop itself, or a thread ahead of it
/// ([`Ahead`]). Both give the same [`DirectedTick`]s ([`direct`]).
enum Stepper {
    Here(Director, Directing, DirectedTick),
    Ahead(Ahead),
}

impl Stepper {
    fn here(director: Director) -> Stepper {
        Stepper::Here(director, Directing::default(), DirectedTick::default())
    }
}

/// Where a phase left the flight: the time of its last tick, the last sample flown, and
/// whether a failsafe asks for landing.
struct Leg {
    t: f64,
    last: Sample,
    outcome: Outcome,
}

impl Flight<'_, '_> {
    /// Flies the script, phase after phase; the report, or why the flight did not start.
    pub(crate) fn run(mut self) -> Result<FlightReport, FlightError> {
        let ground = self.preflight()?;
        let take_off_s = ground.t;
        let (t, outcome) = self.take_off(ground.t)?;
        if let Outcome::Land = outcome {
            let t = self.land(t)?;
            return self.finish(t, take_off_s, false);
        }
        let mut leg = self.approach(t, &ground)?;
        let (script, scene, profile) = (self.setup.script, self.setup.scene, self.setup.profile);
        let mut director = Director::new(script, scene, profile)
            .watched(dronecine_film::watch(script, scene, profile));
        director.actors_measured();
        director.start_from(
            Vec3::from(leg.last.position_m),
            Vec3::from(leg.last.velocity_mps),
            leg.last.heading_rad,
        );
        let mut completed = false;
        if let Outcome::Done = leg.outcome {
            leg = self.settle(leg, &mut director)?;
        }
        if let Outcome::Done = leg.outcome {
            (leg.t, leg.last, completed) = self.shots(leg.t, leg.last, director)?;
        }
        self.framing.clear();
        let mut t = leg.t;
        if completed {
            (t, completed) = self.hold_and_return(t, &leg.last, ground.take_off_xy)?;
        }
        let t = self.land(t)?;
        self.finish(t, take_off_s, completed)
    }

    /// Take-off: the drone climbs on its own until it reports flying: the time it does. The
    /// operator is obeyed here as in every phase: an interrupt lands the drone at once
    /// (`Outcome::Land`), a second cuts its motors.
    fn take_off(&mut self, mut t: f64) -> Result<(f64, Outcome), FlightError> {
        self.event(t, "info", "take_off", "taking off".into());
        self.drone.take_off()?;
        let deadline = t + self.setup.safety.take_off_timeout_s;
        loop {
            t = self.wait_tick(t + self.period_s)?;
            self.idle(t);
            if let Outcome::Land = self.watch_operator_taking_off(t)? {
                return Ok((t, Outcome::Land));
            }
            // No reference yet (the drone climbs on its own): the display says so.
            self.observer.progress(&Progress {
                t_s: t,
                phase: Phase::TakeOff,
                shot: None,
                shots: self.setup.script.timeline.len(),
                script_t_s: 0.0,
                script_duration_s: self.script_duration_s,
                position_error_m: None,
            });
            match self.drone.telemetry().state {
                FlightState::Flying => return Ok((t, Outcome::Done)),
                FlightState::Emergency => {
                    return Err(refusal(
                        PreflightCode::TakeOffEmergency,
                        "the drone went into emergency during take-off".into(),
                        "check the drone (propellers, battery, obstacles) before flying again",
                    ))
                }
                _ if t > deadline => {
                    self.drone.land()?;
                    return Err(refusal(
                        PreflightCode::TakeOffTimeout,
                        format!(
                            "the drone did not report flying within {:.0} s of take-off",
                            self.setup.safety.take_off_timeout_s
                        ),
                        "check the drone's link and state with `dronecine status`",
                    ));
                }
                _ => {}
            }
        }
    }

    /// The operator's interrupts while the drone takes off on its own: the first lands it, a
    /// second (at once, or later in the landing) cuts its motors.
    fn watch_operator_taking_off(&mut self, t: f64) -> Result<Outcome, FlightError> {
        match self.interrupts() {
            0 => Ok(Outcome::Done),
            1 => {
                self.interrupted = true;
                self.failsafe(
                    t,
                    "interrupted (Ctrl-C or a stop signal) during take-off: landing; press Ctrl-C \
                     again to cut the motors",
                );
                self.drone.land()?;
                Ok(Outcome::Land)
            }
            _ => {
                self.interrupted = true;
                self.cut_motors(t)?;
                Ok(Outcome::Land)
            }
        }
    }

    /// The approach: a glide from where the drone hovers to the first framing as the actors
    /// stand now (they may have moved during take-off), each sample held clear of them.
    fn approach(&mut self, mut t: f64, ground: &Ground) -> Result<Leg, FlightError> {
        // Where it hovers: its newest measurement (this tick's frame may not have come yet
        // when the loop is faster than the mocap).
        let here = match self.drone_m.map(|(_, m)| m).or(Some(ground.drone)) {
            Some(m) => Sample {
                t_s: t,
                position_m: m.position_m,
                velocity_mps: [0.0; 3],
                acceleration_mps2: [0.0; 3],
                heading_rad: m.heading_rad,
                heading_rate_radps: 0.0,
                camera_pitch_rad: ground.first.camera_pitch_rad,
                shot: 0,
            },
            None => unreachable_measurement(&ground.first, t),
        };
        let first = self.first_framing();
        let keep = self.keepout();
        let glide = Glide::new(t, &here, &first, self.setup.profile, &self.route_keepout());
        let way = glide.way();
        let intrusion_m = keep.route_intrusion_m(&glide.route, &glide.from_m, &glide.to_m);
        self.event(
            t,
            "info",
            "approach",
            format!(
                "flying to the first framing ({:.1} s{way})",
                glide.duration_s
            ),
        );
        if intrusion_m > APPROACH_TOLERANCE_M {
            self.event(
                t,
                "warning",
                "approach_not_clear",
                format!(
                    "no clear way to the first framing from where the drone took off: the \
                     approach comes {intrusion_m:.2} m into an actor's safety distance or the \
                     stage's margin; take off further from the actors and the walls"
                ),
            );
        }
        let mut outcome = Outcome::Done;
        let mut last = glide.sample(t, first.camera_pitch_rad);
        while t < glide.end_s() {
            t = self.wait_tick(t + self.period_s)?;
            last = self.clear_of_actors(glide.sample(t, first.camera_pitch_rad));
            if let Outcome::Land = self.control(t, Phase::Approach, None, &last)? {
                outcome = Outcome::Land;
                break;
            }
        }
        Ok(Leg { t, last, outcome })
    }

    /// The settle: for [`SETTLE_S`] before "action!" the director, placed where the glide
    /// ended, is stepped with its clock held at the script's start, so the camera steers onto
    /// the first framing as the actors stand now (they moved since the approach was planned).
    /// A first framing that no longer solves holds the drone where the glide left it.
    fn settle(&mut self, leg: Leg, director: &mut Director) -> Result<Leg, FlightError> {
        let Leg {
            mut t, mut last, ..
        } = leg;
        // How far the actors have moved the first framing since the approach was planned
        // (the log says so: the settle may not close it all before "action!").
        let (now_first, _, unsolved) = self.probe();
        let message = match unsolved {
            None => format!(
                "settling on the first framing as the actors stand, {:.2} m from where the \
                 approach flew ({SETTLE_S:.1} s)",
                (Vec3::from(now_first.position_m) - Vec3::from(last.position_m)).norm()
            ),
            Some(why) => format!(
                "the first framing does not solve as the actors stand ({why}): holding \
                 where the approach flew until it does"
            ),
        };
        self.event(t, "info", "settle", message);
        // Its last tick one period before "action!", the first shot's at 0 s.
        let action_s = t + SETTLE_S;
        while t < action_s - 1.5 * self.period_s {
            t = self.wait_tick(t + self.period_s)?;
            let sample = Sample {
                t_s: t,
                ..director.step(t - action_s, &self.actors.poses)
            };
            last = sample;
            if let Outcome::Land = self.control(t, Phase::Approach, None, &sample)? {
                return Ok(Leg {
                    t,
                    last,
                    outcome: Outcome::Land,
                });
            }
        }
        Ok(Leg {
            t,
            last,
            outcome: Outcome::Done,
        })
    }

    /// "Action!" and the shots: the director, on a thread of its own ahead of the loop when
    /// the mocap knows the actors' future (the simulator), else stepped here tick by tick,
    /// re-frames the live actors every tick. The time, the last sample flown, and whether the
    /// shots ran to their end.
    fn shots(
        &mut self,
        mut t: f64,
        mut last: Sample,
        director: Director,
    ) -> Result<(f64, Sample, bool), FlightError> {
        let action_s = t + self.period_s;
        self.mocap.action(action_s);
        self.event(action_s, "info", "action", "action!".into());
        let mut stepper = self.stepper(t, action_s, director);
        let mut current: Option<usize> = None;
        let mut completed = false;
        // The last shot's findings, when the director finished.
        let mut last_findings = Vec::new();
        loop {
            let t_next = t + self.period_s;
            let tick: &DirectedTick = match &mut stepper {
                Stepper::Here(director, state, tick) => {
                    t = self.wait_tick(t_next)?;
                    direct(director, state, t, t - action_s, &self.actors.poses, tick);
                    tick
                }
                Stepper::Ahead(ahead) => {
                    // The director's tick first: the frame's actors come from it.
                    let next = ahead.next();
                    if next.is_none() {
                        self.mocap.actors_from_feed(false);
                    }
                    let agreed;
                    (t, agreed) = self.wait_tick_fed(t_next, next)?;
                    match next {
                        Some(tick) if agreed && tick.t_s == t => tick,
                        _ => {
                            self.failsafe(
                                t,
                                "the director, stepped ahead of the loop, saw other actors \
                                 than the loop (an internal error): landing",
                            );
                            break;
                        }
                    }
                }
            };
            let sample = tick.sample;
            self.written_t_s = tick.written_t_s;
            // What the director found against the live actors, told as it arises: a framing
            // it cannot solve holds the drone where it is until it solves.
            for d in &tick.diagnostics {
                self.director_finding(t, d);
            }
            if current != Some(sample.shot) {
                // The shot before is over: what the monitor found in it.
                if let Some(over) = current {
                    self.tell_findings(t, &tick.over_findings, over);
                }
                current = Some(sample.shot);
                self.event(
                    t,
                    "info",
                    "shot_start",
                    format!(
                        "shot {} of {}",
                        sample.shot + 1,
                        self.setup.script.timeline.len()
                    ),
                );
            }
            let world_sample = self.aimed_and_measured(t, tick, sample);
            let finished = tick.finished;
            if finished {
                last_findings.clone_from(&tick.last_findings);
            }
            last = world_sample;
            if let Outcome::Land =
                self.control(t, Phase::Shots, Some(sample.shot), &world_sample)?
            {
                break;
            }
            if finished {
                completed = true;
                break;
            }
        }
        // The mocap's frames are whole again (the landing has no director ahead).
        self.mocap.actors_from_feed(false);
        if let Some(last_shot) = current {
            // Over too: the last shot, or the one a failsafe cut short, as the director had
            // it at this tick.
            if !completed {
                last_findings = match stepper {
                    Stepper::Here(director, ..) => director.shot_findings(last_shot),
                    Stepper::Ahead(ahead) => ahead.rewound().shot_findings(last_shot),
                };
            }
            self.tell_findings(t, &last_findings, last_shot);
        }
        Ok((t, last, completed))
    }

    /// Who steps the director during the shots: a thread ahead of the loop when the mocap
    /// knows the actors' future (its frames' actors then come from that thread, computed
    /// once), else the loop itself.
    fn stepper(&mut self, t: f64, action_s: f64, director: Director) -> Stepper {
        match (self.mocap.actors_ahead(), self.mocap.actors_ahead()) {
            (Some(feed), Some(rewind_feed)) => {
                let start = AheadStart {
                    director,
                    tracker: &self.actors,
                    frame: &self.frame,
                    last_frame_t_s: self.last_frame_t_s,
                    t_s: t,
                    action_s,
                    period_s: self.period_s,
                };
                match Ahead::spawn(start, feed, rewind_feed) {
                    Ok(ahead) => {
                        self.mocap.actors_from_feed(true);
                        Stepper::Ahead(ahead)
                    }
                    Err(director) => Stepper::here(*director),
                }
            }
            _ => Stepper::here(director),
        }
    }

    /// A shot's sample as flown: in a hold, aimed from where the drone is (the heading and
    /// gimbal pitch that frame the live actors from its measured position); and the framing
    /// as the drone really films it, from the measured pose and the camera pitch the gimbal
    /// reported at the start of the tick (the pitch asked when it reports none; level without
    /// a gimbal), into `self.framing`.
    fn aimed_and_measured(&mut self, t: f64, tick: &DirectedTick, sample: Sample) -> Sample {
        let mut world_sample = Sample { t_s: t, ..sample };
        let usable = self
            .measured
            .filter(|m| m.position_m.iter().all(|x| x.is_finite()) && m.heading_rad.is_finite());
        self.aim(tick.held.as_ref(), t, usable.is_some(), &mut world_sample);
        self.framing.clear();
        if let (Some(m), Some(held)) = (usable, &tick.held) {
            // Its axes once for every actor projected.
            let camera = CameraPose {
                position_m: Vec3::from(m.position_m),
                heading_rad: m.heading_rad,
                pitch_rad: self
                    .gimbal_pitch_rad
                    .unwrap_or(world_sample.camera_pitch_rad),
            }
            .frame();
            if held.targets_into(&self.actors.poses, &camera.position_m, &mut self.targets) {
                for target in &self.targets {
                    self.framing.push(FramingRecord {
                        actor: target.actor,
                        screen: camera.project(&self.lens, &target.point_m),
                        requested: Some(target.screen),
                    });
                }
            }
        }
        world_sample
    }

    /// After the last shot: hold the last pose a moment, then fly back over the take-off
    /// spot. The time, and whether it went without a failsafe.
    fn hold_and_return(
        &mut self,
        mut t: f64,
        last: &Sample,
        take_off_xy: [f64; 2],
    ) -> Result<(f64, bool), FlightError> {
        let end = t + HOLD_BEFORE_LANDING_S;
        while t < end {
            t = self.wait_tick(t + self.period_s)?;
            let hold = self.clear_of_actors(hover_sample(t, last));
            if let Outcome::Land = self.control(t, Phase::Landing, None, &hold)? {
                return Ok((t, false));
            }
        }
        if let Some(glide) = self.way_home(t, last, take_off_xy) {
            let pitch_rad = last.camera_pitch_rad;
            while t < glide.end_s() {
                t = self.wait_tick(t + self.period_s)?;
                let home = self.clear_of_actors(glide.sample(t, pitch_rad));
                if let Outcome::Land = self.control(t, Phase::Landing, None, &home)? {
                    return Ok((t, false));
                }
            }
        }
        Ok((t, true))
    }

    /// Landing: the drone's own, straight down, until it reports landed (a second interrupt
    /// still cuts the motors) or the landing timeout. The time it ends.
    fn land(&mut self, mut t: f64) -> Result<f64, FlightError> {
        self.event(t, "info", "landing", "landing".into());
        self.drone.land()?;
        let deadline = t + self.setup.safety.landing_timeout_s;
        loop {
            t = self.wait_tick(t + self.period_s)?;
            self.idle(t);
            if self.interrupts() >= 2 {
                self.cut_motors(t)?;
            }
            let state = self.drone.telemetry().state;
            if matches!(state, FlightState::Landed | FlightState::Emergency) {
                self.event(t, "info", "landed", format!("{state:?}").to_lowercase());
                return Ok(t);
            }
            if t > deadline {
                self.event(
                    t,
                    "error",
                    "landing_timeout",
                    format!(
                        "the drone still reports {state:?} {:.0} s after the landing command",
                        self.setup.safety.landing_timeout_s
                    ),
                );
                return Ok(t);
            }
        }
    }

    /// The flight's end: its event, the log's error if any, and the report.
    fn finish(
        mut self,
        t: f64,
        take_off_s: f64,
        completed: bool,
    ) -> Result<FlightReport, FlightError> {
        self.event(
            t,
            if completed { "info" } else { "error" },
            "flight_end",
            format!(
                "{} after {:.2} s of flight",
                if completed { "completed" } else { "aborted" },
                t - take_off_s
            ),
        );
        let log_error = self.log_error.take();
        let labels = crate::report::shot_labels(self.setup.script, self.setup.source);
        let report = self.metrics.report(
            &labels,
            Counts {
                completed,
                flight_time_s: t - take_off_s,
                failsafes: self.failsafes,
                director_errors: self.director_errors,
                faults: self.faults,
                deadline_misses: self.deadline_misses,
                lateness: self.lateness.summary(),
            },
        );
        match log_error {
            Some(e) => Err(FlightError::Log(e, Box::new(report))),
            None => Ok(report),
        }
    }

    /// The flight back over the take-off spot after the last shot, at the altitude the shots
    /// left the drone, so that it lands where it was set down (clear of the actors' marks then:
    /// the pre-flight check's and the simulator's rule) and not where the last shot ends,
    /// perhaps an arm's length from an actor (a close-up). Along the approach's route rule and
    /// at its pace ([`Glide`]). `None`, the drone landing where it is, when it is already
    /// within [`HOME_RADIUS_M`] of the spot, or when an actor now stands within their safety
    /// distance of the spot (the landing's column, down to the floor) or in the way back
    /// (both told as a warning).
    pub(crate) fn way_home(&mut self, t: f64, last: &Sample, home_xy: [f64; 2]) -> Option<Glide> {
        let here = hover_sample(t, last);
        let [x, y, z] = last.position_m;
        let far_m = dronecine_math::hypot(home_xy[0] - x, home_xy[1] - y);
        if !(far_m >= HOME_RADIUS_M) {
            return None;
        }
        let home = Sample {
            position_m: [home_xy[0], home_xy[1], z],
            ..here
        };
        let safety_m = self.setup.profile.safety.actor_distance_m;
        let keep = self.keepout();
        let pad = Vec3::new(home_xy[0], home_xy[1], 0.0);
        let taken = keep.deepest_actor(&pad);
        let glide = Glide::new(t, &here, &home, self.setup.profile, &self.route_keepout());
        let intrusion_m = keep.route_intrusion_m(&glide.route, &glide.from_m, &glide.to_m);
        if let Some((i, into_m)) = taken {
            let name = &self.setup.scene.actors[i].name;
            let message = format!(
                "{name} stands {:.2} m from the take-off spot; {} keeps {safety_m:.2} m from \
                 actors: landing where the drone is",
                safety_m - into_m,
                self.setup.profile.name
            );
            self.event(t, "warning", "return_not_clear", message);
            return None;
        }
        if intrusion_m > APPROACH_TOLERANCE_M {
            let message = format!(
                "no clear way back to the take-off spot: it comes {intrusion_m:.2} m into an \
                 actor's safety distance or the stage's margin; landing where the drone is"
            );
            self.event(t, "warning", "return_not_clear", message);
            return None;
        }
        let way = glide.way();
        let message = format!(
            "flying back to the take-off spot to land ({far_m:.1} m, {:.1} s{way})",
            glide.duration_s
        );
        self.event(t, "info", "return", message);
        Some(glide)
    }
}
