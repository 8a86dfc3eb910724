//! The flight's state and its tick: wait for the tick time, read the mocap, run the
//! controller, watch the failsafes, command the drone, record. Each phase (`phases`) drives
//! these ticks with its own reference.

use std::io;

use dronecine_backend::frames::Command;
use dronecine_backend::{Backends, Clock, Drone, Mocap, MocapFrame};
use dronecine_compiler::camera::{Lens, Vec3};
use dronecine_compiler::director::{Director, Held};
use dronecine_compiler::framing::ScreenTarget;
use dronecine_compiler::reference::Sample;
use dronecine_compiler::route::{self, Keepout};
use dronecine_compiler::steering::{self, Bodies, Body, Kinematics};
use dronecine_grammar::script::Stage;
use dronecine_math::wrap_angle_rad;
use dronecine_mcap::record::{
    reference_of, Event, FlightSink, FramingRecord, GimbalRecord, Phase, TickRecord,
};
use dronecine_servo::control::{Controller, Measurement, TickFault, TickInput, TickOutput};

use crate::ahead::DirectedTick;
use crate::code::{refusal, PreflightCode};
use crate::glide::hover_sample;
use crate::report::Metrics;
use crate::tracker::{finite_pose, take_newer, ActorTracker};
use crate::{FlightError, FlightSetup, Observer, Progress};

pub(crate) struct Flight<'s, 'b> {
    pub(crate) setup: &'s FlightSetup<'s>,
    pub(crate) controller: &'s mut dyn Controller,
    pub(crate) drone: &'b mut dyn Drone,
    pub(crate) mocap: &'b mut dyn Mocap,
    pub(crate) clock: &'b mut dyn Clock,
    pub(crate) sink: &'s mut dyn FlightSink,
    pub(crate) observer: &'s mut dyn Observer,
    pub(crate) period_s: f64,
    pub(crate) lens: Lens,
    pub(crate) frame: MocapFrame,
    /// The newest frame arrived this tick.
    pub(crate) fresh: bool,
    pub(crate) last_frame_t_s: Option<f64>,
    pub(crate) last_drone_seen_s: f64,
    /// Per actor: when their body was last tracked, and whether the drone hovers for them.
    pub(crate) actor_seen_s: Vec<f64>,
    pub(crate) actor_lost: Vec<bool>,
    /// The drone's measurement of this tick's fresh mocap frame (`None` between frames).
    pub(crate) measured: Option<Measurement>,
    /// The newest finite measurement of the drone and when it arrived, held between frames:
    /// where the drone is, for what needs it every tick (the aim, the approach's start),
    /// whatever the mocap's rate against the loop's.
    pub(crate) drone_m: Option<(f64, Measurement)>,
    pub(crate) actors: ActorTracker,
    pub(crate) targets: Vec<ScreenTarget>,
    pub(crate) framing: Vec<FramingRecord>,
    /// The profile has a camera gimbal: each tick reads its pitch and commands it.
    pub(crate) gimbal: bool,
    /// The pitch the gimbal reported at the start of this tick (`None` without a gimbal, or
    /// when the drone reports none).
    pub(crate) gimbal_pitch_rad: Option<f64>,
    /// The actors' bodies as they stand this tick, for [`Flight::clear_of_actors`] (reused:
    /// no allocation per tick).
    pub(crate) bodies: Vec<Body>,
    /// The last aim from a fresh measurement of the drone's position.
    pub(crate) last_aim: Option<Aim>,
    pub(crate) last_tick_s: Option<f64>,
    pub(crate) controller_started: bool,
    pub(crate) metrics: Metrics,
    pub(crate) failsafes: u64,
    pub(crate) faults: u64,
    pub(crate) deadline_misses: u64,
    /// How late each tick ran.
    pub(crate) lateness: crate::lateness::LatenessHistogram,
    /// What the drone said since the last tick (kept for its capacity).
    drone_messages: Vec<dronecine_backend::DroneMessage>,
    pub(crate) director_errors: u64,
    pub(crate) hovering: bool,
    /// The first interrupt was handled (landing).
    pub(crate) interrupted: bool,
    /// The second interrupt was handled: the motors are cut.
    pub(crate) motors_cut: bool,
    /// The telemetry link was reported lost.
    pub(crate) link_lost: bool,
    pub(crate) log_error: Option<io::Error>,
    pub(crate) script_duration_s: f64,
    /// Where the shots are on the script's clock as written (0 before "action!").
    pub(crate) written_t_s: f64,
}

/// A heading aimed from a fresh measurement of the drone's position, and its rate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Aim {
    t_s: f64,
    heading_rad: f64,
    rate_radps: f64,
}

/// How a phase of the loop ended.
pub(crate) enum Outcome {
    Done,
    /// A failsafe asks for landing now.
    Land,
}

/// What the controller was given in a tick, and what it answered.
type Ticked = (TickInput, Result<TickOutput, TickFault>);

/// What the operator's interrupts ask of a tick.
pub(crate) enum Operator {
    Fly,
    Land,
    /// The motors were cut: nothing more is sent.
    MotorsCut,
}

impl<'s, 'b> Flight<'s, 'b> {
    pub(crate) fn new(
        setup: &'s FlightSetup<'s>,
        controller: &'s mut dyn Controller,
        backends: Backends<'b>,
        sink: &'s mut dyn FlightSink,
        observer: &'s mut dyn Observer,
    ) -> Result<Self, FlightError> {
        if !(setup.rate_hz.is_finite() && setup.rate_hz > 0.0 && setup.rate_hz <= 1000.0) {
            return Err(refusal(
                PreflightCode::BadRate,
                format!("the control rate is {} Hz", setup.rate_hz),
                "give a rate in (0, 1000] Hz (100 Hz by default)",
            ));
        }
        if setup.script.timeline.is_empty() {
            return Err(refusal(
                PreflightCode::NoShots,
                "the script has no shots: there is nothing to fly".into(),
                "write at least one shot after the set-up lines",
            ));
        }
        let n_actors = setup.scene.actors.len();
        let script_duration_s = setup.script.timeline.last().map_or(0.0, |s| s.end_s);
        let probe = Director::new(setup.script, setup.scene, setup.profile);
        Ok(Flight {
            setup,
            controller,
            drone: backends.drone,
            mocap: backends.mocap,
            clock: backends.clock,
            sink,
            observer,
            period_s: 1.0 / setup.rate_hz,
            lens: *probe.lens(),
            frame: MocapFrame {
                actors: Vec::with_capacity(n_actors),
                ..MocapFrame::default()
            },
            fresh: false,
            last_frame_t_s: None,
            last_drone_seen_s: f64::NEG_INFINITY,
            actor_seen_s: vec![f64::NEG_INFINITY; n_actors],
            actor_lost: vec![false; n_actors],
            measured: None,
            drone_m: None,
            actors: ActorTracker::new(setup.scene),
            targets: Vec::with_capacity(4),
            framing: Vec::with_capacity(n_actors.max(2)),
            gimbal: setup.profile.camera.gimbal != dronecine_profile::Gimbal::None,
            gimbal_pitch_rad: None,
            bodies: Vec::with_capacity(n_actors),
            last_aim: None,
            last_tick_s: None,
            controller_started: false,
            metrics: Metrics::new(setup.script.timeline.len(), &setup.profile.safety),
            failsafes: 0,
            director_errors: 0,
            faults: 0,
            deadline_misses: 0,
            drone_messages: Vec::new(),
            lateness: crate::lateness::LatenessHistogram::default(),
            hovering: false,
            interrupted: false,
            motors_cut: false,
            link_lost: false,
            log_error: None,
            script_duration_s,
            written_t_s: 0.0,
        })
    }

    /// Logs what the drone said or did since the last tick as `drone` events.
    fn tell_drone_messages(&mut self, t_s: f64) {
        let mut said = std::mem::take(&mut self.drone_messages);
        self.drone.messages(&mut said);
        for m in said.drain(..) {
            self.event(t_s, m.level, "drone", m.text);
        }
        self.drone_messages = said;
    }

    pub(crate) fn event(&mut self, t_s: f64, level: &str, kind: &str, message: String) {
        self.tell(Event {
            t_s,
            level: level.to_string(),
            kind: kind.to_string(),
            message,
            line: None,
            help: None,
        });
    }

    pub(crate) fn tell(&mut self, e: Event) {
        self.director_errors += u64::from(e.is_director_error());
        self.observer.event(&e);
        if let Err(err) = self.sink.event(&e) {
            self.log_error.get_or_insert(err);
        }
    }

    /// Waits for the next tick and reads the mocap.
    pub(crate) fn wait_tick(&mut self, t_next_s: f64) -> Result<f64, FlightError> {
        self.wait_tick_fed(t_next_s, None).map(|(now, _)| now)
    }

    /// A tick that records nothing (the drone flies on its own, or has not taken off): the
    /// log is told the time all the same, so that it keeps its records as on any tick.
    pub(crate) fn idle(&mut self, t: f64) {
        if let Err(err) = self.sink.idle(t) {
            self.log_error.get_or_insert(err);
        }
    }

    /// [`Flight::wait_tick`] with the director's tick `ahead` (its thread steps ahead of the
    /// loop): the frame polled takes its actors from the frame the director's thread had from
    /// the mocap's feed at this tick ([`Mocap::actors_from_feed`]), and the tracked actors are
    /// the ones it stepped with (its tracker folded the same frames in). Also says whether the
    /// two polls agreed (the same frame, or no frame); when they do not, the frame's actors
    /// are as the mocap gave them.
    pub(crate) fn wait_tick_fed(
        &mut self,
        t_next_s: f64,
        ahead: Option<&DirectedTick>,
    ) -> Result<(f64, bool), FlightError> {
        self.clock.sleep_until(t_next_s);
        let now = self.clock.now_s();
        let late_s = self.clock.lateness_s(t_next_s);
        self.lateness.add(late_s);
        self.sink.tick_lateness(late_s);
        if now > t_next_s + 0.5 * self.period_s {
            self.deadline_misses += 1;
            self.event(
                now,
                "warning",
                "deadline_missed",
                format!(
                    "tick due at {t_next_s:.3} s ran at {now:.3} s ({:.1} ms late)",
                    (now - t_next_s) * 1e3
                ),
            );
        }
        self.fresh = self.mocap.poll(&mut self.frame)?;
        self.tell_drone_messages(now);
        if self.gimbal {
            self.gimbal_pitch_rad = self.drone.camera_pitch_rad();
        }
        let agreed = ahead.is_none_or(|k| k.feed.fill(self.fresh, &mut self.frame));
        if self.fresh {
            if !take_newer(&mut self.last_frame_t_s, &self.frame) {
                // Out of order or replayed: its measurement is not used.
                self.fresh = false;
                self.event(
                    now,
                    "warning",
                    "stale_frame",
                    format!(
                        "mocap frame {} at {:.4} s is not newer than the previous one; ignored",
                        self.frame.frame, self.frame.t_s
                    ),
                );
            } else {
                match ahead {
                    // The director's tracker folded this frame in already.
                    Some(k) => self.actors.copy_from(&k.tracker),
                    None => self.actors.update(&self.frame),
                }
                for (seen, body) in self.actor_seen_s.iter_mut().zip(&self.frame.actors) {
                    if body.as_ref().is_some_and(finite_pose) {
                        *seen = now;
                    }
                }
                self.measured = match self.frame.drone {
                    Some(p) => {
                        self.last_drone_seen_s = now;
                        if finite_pose(&p) {
                            self.drone_m = Some((
                                now,
                                Measurement {
                                    position_m: p.position_m,
                                    heading_rad: p.heading_rad,
                                },
                            ));
                        }
                        Some(Measurement {
                            position_m: p.position_m,
                            heading_rad: p.heading_rad,
                        })
                    }
                    None => None,
                };
            }
        }
        if !self.fresh {
            self.measured = None;
        }
        Ok((now, agreed))
    }

    /// One controlled tick: the controller, the failsafes, the command to the drone, the
    /// metrics and the record.
    pub(crate) fn control(
        &mut self,
        t: f64,
        phase: Phase,
        shot: Option<usize>,
        sample: &Sample,
    ) -> Result<Outcome, FlightError> {
        let Some((input, output)) = self.controller_tick(t, sample)? else {
            return Ok(Outcome::Done);
        };
        let mut command_sent = match &output {
            Ok(o) => o.command,
            Err(fault) => {
                self.faults += 1;
                self.event(
                    t,
                    "error",
                    "fault",
                    format!("controller refused the tick ({fault:?}); hovering"),
                );
                Command::HOVER
            }
        };
        let mut land = self.watch_drone(t);
        let (actors_land, actor_hover) = self.watch_actors(t, phase);
        land |= actors_land;
        land |= self.watch_stage(t);
        land |= self.watch_drone_state(t);
        match self.watch_operator(t)? {
            Operator::Fly => {}
            Operator::Land => land = true,
            Operator::MotorsCut => return Ok(Outcome::Land),
        }
        if self.gimbal {
            self.drone.point_camera(sample.camera_pitch_rad)?;
        }
        if self.hovering || actor_hover || output.is_err() || land {
            command_sent = Command::HOVER;
            self.drone.hover()?;
        } else {
            self.drone.send(&command_sent)?;
        }
        land |= self.record_tick(t, phase, shot, sample, input, output, command_sent);
        Ok(if land { Outcome::Land } else { Outcome::Done })
    }

    /// The controller's tick, once it has started: the replay rule resets it with the first
    /// tick's measurement at `t − Δ`. `None` (the drone told to hover) until the drone has
    /// been measured: nothing to start the filters from.
    fn controller_tick(&mut self, t: f64, sample: &Sample) -> Result<Option<Ticked>, FlightError> {
        let dt = match self.last_tick_s {
            Some(t0) => t - t0,
            None => self.period_s,
        };
        let input = TickInput {
            t_s: t,
            dt_s: dt,
            measurement: self.measured,
            reference: reference_of(sample),
        };
        if !self.controller_started {
            match self.measured {
                Some(m) => {
                    self.controller.reset(t - dt, &m);
                    self.controller_started = true;
                }
                None => {
                    self.drone.hover()?;
                    return Ok(None);
                }
            }
        }
        let output = self.controller.tick(&input);
        self.last_tick_s = Some(t);
        Ok(Some((input, output)))
    }

    /// The drone's tracking: not seen for `mocap_hover_s` → hover (told once), for
    /// `mocap_land_s` → land (the return value).
    fn watch_drone(&mut self, t: f64) -> bool {
        let unseen_s = t - self.last_drone_seen_s;
        if unseen_s >= self.setup.safety.mocap_land_s {
            let land_s = self.setup.safety.mocap_land_s;
            self.failsafe(
                t,
                &format!("the drone has not been tracked for {land_s:.0} s: landing"),
            );
            return true;
        }
        if unseen_s >= self.setup.safety.mocap_hover_s {
            if !self.hovering {
                self.failsafe(t, "the drone is not tracked: hovering");
            }
            self.hovering = true;
        } else {
            self.hovering = false;
        }
        false
    }

    /// The actors' tracking during the approach, the shots and the flight back: the drone
    /// cannot keep clear of an actor it does not see (nor frame them). `(land, hover)`.
    fn watch_actors(&mut self, t: f64, phase: Phase) -> (bool, bool) {
        let (mut land, mut hover) = (false, false);
        if !matches!(phase, Phase::Approach | Phase::Shots | Phase::Landing) {
            return (land, hover);
        }
        for i in 0..self.actor_seen_s.len() {
            let unseen_s = t - self.actor_seen_s[i];
            let name = &self.setup.scene.actors[i].name;
            if unseen_s >= self.setup.safety.mocap_land_s {
                let land_s = self.setup.safety.mocap_land_s;
                self.failsafe(
                    t,
                    &format!("actor {name} has not been tracked for {land_s:.0} s: landing"),
                );
                land = true;
            } else if unseen_s >= self.setup.safety.mocap_hover_s {
                if !self.actor_lost[i] {
                    self.actor_lost[i] = true;
                    self.failsafe(t, &format!("actor {name} is not tracked: hovering"));
                }
                hover = true;
            } else if self.actor_lost[i] {
                self.actor_lost[i] = false;
                self.event(
                    t,
                    "info",
                    "actor_tracked",
                    format!("actor {name} is tracked again: flying on"),
                );
            }
        }
        (land, hover)
    }

    /// The drone measured outside the stage → land. A non-finite pose is the controller's
    /// fault (hover for the tick), not a place.
    fn watch_stage(&mut self, t: f64) -> bool {
        let Some(m) = self.measured else {
            return false;
        };
        let finite = m.position_m.iter().all(|x| x.is_finite());
        if finite && !inside(&self.setup.scene.stage, &m.position_m, 0.0) {
            self.failsafe(
                t,
                &format!(
                    "the drone left the stage at ({:.2}, {:.2}, {:.2}) m: landing",
                    m.position_m[0], m.position_m[1], m.position_m[2]
                ),
            );
            return true;
        }
        false
    }

    /// What the drone reports: a low battery or a silent link → land.
    fn watch_drone_state(&mut self, t: f64) -> bool {
        let mut land = false;
        let telemetry = self.drone.telemetry();
        let battery = telemetry.battery_percent;
        // Not a number: the level is not known, and may be low.
        if !(battery >= self.setup.safety.battery_land_percent) {
            self.failsafe(t, &format!("battery at {battery:.0}%: landing"));
            land = true;
        }
        if telemetry.link_age_s >= self.setup.safety.link_lost_s {
            // Nothing tells us what the drone does: ask it to land, and rely on its own
            // watchdog (it hovers, then lands, without commands) if that does not get through.
            if !self.link_lost {
                self.link_lost = true;
                self.failsafe(
                    t,
                    &format!(
                        "no telemetry from the drone for {:.1} s: landing (the drone's watchdog \
                         lands it if the command is lost too)",
                        telemetry.link_age_s
                    ),
                );
            }
            land = true;
        }
        land
    }

    /// The operator's second interrupt: the motors cut, told once.
    pub(crate) fn cut_motors(&mut self, t: f64) -> Result<(), FlightError> {
        if !self.motors_cut {
            self.motors_cut = true;
            self.failsafe(t, "interrupted twice: emergency motor cut");
            self.drone.emergency()?;
        }
        Ok(())
    }

    /// The operator's interrupts: the first lands the drone, the second cuts its motors.
    fn watch_operator(&mut self, t: f64) -> Result<Operator, FlightError> {
        match self.interrupts() {
            0 => Ok(Operator::Fly),
            1 => {
                if !self.interrupted {
                    self.interrupted = true;
                    self.failsafe(
                        t,
                        "interrupted (Ctrl-C or a stop signal): landing; press Ctrl-C again to \
                         cut the motors",
                    );
                }
                Ok(Operator::Land)
            }
            _ => {
                self.cut_motors(t)?;
                Ok(Operator::MotorsCut)
            }
        }
    }

    /// The tick's metrics, record and progress; `true` when the record cannot be written (a
    /// failsafe: landing).
    #[allow(clippy::too_many_arguments)]
    fn record_tick(
        &mut self,
        t: f64,
        phase: Phase,
        shot: Option<usize>,
        sample: &Sample,
        input: TickInput,
        output: Result<TickOutput, TickFault>,
        command_sent: Command,
    ) -> bool {
        let mut land = false;
        // Mocap frame in → command out, on the flight clock.
        let latency_s = self
            .fresh
            .then(|| (self.clock.now_s() - self.frame.received_s).max(0.0));
        self.metrics.record(
            phase,
            shot,
            &input,
            &output,
            &self.framing,
            &self.actors.poses,
            latency_s,
        );
        let error = Metrics::tracking_error(&input);
        let state = self.drone.telemetry().state;
        let record = TickRecord {
            phase,
            shot,
            sample,
            input,
            output,
            command_sent,
            mocap: self.fresh.then_some(&self.frame),
            actors: &self.actors.poses,
            framing: &self.framing,
            drone_state: state,
            latency_s,
            gimbal: self.gimbal.then_some(GimbalRecord {
                asked_rad: sample.camera_pitch_rad,
                reported_rad: self.gimbal_pitch_rad,
            }),
        };
        // A log that starts a chunk after this tick opens it with the controller's state (a
        // key frame), from which replay resumes after a gap.
        let written = self.sink.tick(&record).and_then(|()| {
            if self.sink.wants_key_frame() {
                self.sink.key_frame(&self.controller.state())
            } else {
                Ok(())
            }
        });
        if let Err(e) = written {
            self.log_error.get_or_insert(e);
            self.failsafe(t, "the flight log cannot be written: landing");
            land = true;
        }
        self.observer.progress(&Progress {
            t_s: t,
            phase,
            shot,
            shots: self.setup.script.timeline.len(),
            // The script's clock as written, not the flight's: the display's bar fills with
            // the shots, not with the take-off.
            script_t_s: self.written_t_s,
            script_duration_s: self.script_duration_s,
            position_error_m: error.map(|e| e.0),
        });
        land
    }

    pub(crate) fn interrupts(&self) -> u32 {
        self.setup
            .interrupts
            .map_or(0, |n| n.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// A planned sample (the approach's and the way home's glides, the hold before landing)
    /// held out of the actors' safety distance as they stand this tick, as the director holds
    /// its goal (`steering::kept_clear`): the glides are planned clear of the actors as they
    /// stood, and an actor who moves after that (a live actor drifting off their mark by a
    /// few centimetres a second) walked into the reference (random script 264: 0.465 m from
    /// B at the approach's end). The sample's position moves out along the line from the
    /// body's nearest point, and its velocity and acceleration lose their inward part. The
    /// distance is the director's on set: the profile's actor distance and its tracking
    /// margin, so that the drone, lagging its reference, keeps the actor distance (with the
    /// actor distance alone, random script 379 flew home 0.464 m from A). A drone that took
    /// off nearer than that has its approach's reference start out at that distance.
    pub(crate) fn clear_of_actors(&mut self, sample: Sample) -> Sample {
        self.bodies.clear();
        self.bodies.extend(self.actors.poses.iter().map(Body::from));
        let kept = steering::kept_clear(
            Kinematics {
                p: Vec3::from(sample.position_m),
                v: Vec3::from(sample.velocity_mps),
                a: Vec3::from(sample.acceleration_mps2),
            },
            Bodies {
                axes: &self.bodies,
                clear_m: self.setup.profile.safety.on_set_m(),
            },
        );
        Sample {
            position_m: kept.p.into(),
            velocity_mps: kept.v.into(),
            acceleration_mps2: kept.a.into(),
            ..sample
        }
    }

    /// Where the drone may go: the stage less its margin, and out of the actors' safety
    /// distance as the actors stand now (the director's and the compiler's routes' rule).
    pub(crate) fn keepout(&self) -> Keepout<'_> {
        let (lo, hi) = route::stage_less_margin(
            &self.setup.scene.stage,
            self.setup.profile.safety.stage_margin_m,
        );
        Keepout {
            lo,
            hi,
            actors: &self.actors.poses,
            passing: &[],
            safety_m: self.setup.profile.safety.actor_distance_m,
            merge: None,
        }
    }

    /// [`Flight::keepout`] for choosing a glide's route: the actors' distance with the
    /// profile's tracking margin, as the director keeps it on set, so that a route that
    /// passes an actor passes where the drone, not only its reference, keeps the distance.
    /// Whether the route is clear is still judged against the distance itself.
    pub(crate) fn route_keepout(&self) -> Keepout<'_> {
        Keepout {
            safety_m: self.setup.profile.safety.on_set_m(),
            ..self.keepout()
        }
    }

    /// The first shot's framing against the actors as they stand now.
    pub(crate) fn first_framing(&self) -> Sample {
        self.probe().0
    }

    /// The first framing against the actors as they stand now: the director's first sample,
    /// its target as solved, and why it did not solve (the director's message), if it did not.
    pub(crate) fn probe(&self) -> (Sample, Vec3, Option<String>) {
        let mut probe = Director::new(self.setup.script, self.setup.scene, self.setup.profile);
        // As the flight's director sees them: measured (the first framing held the tracking
        // margin off an actor it comes near, so that the approach ends where the shots do).
        probe.actors_measured();
        let sample = probe.step(0.0, &self.actors.poses);
        let unsolved = (!probe.placed()).then(|| {
            (probe.diagnostics_so_far().iter().find(|d| d.is_error()))
                .map_or_else(|| "no camera position".to_string(), |d| d.message.clone())
        });
        (sample, probe.solved_target_m(), unsolved)
    }

    /// In a hold, the heading and gimbal pitch that frame the live actors from where the
    /// drone is, into `sample` (else the director's own, smoother heading stays). Aimed anew
    /// on a tick with a fresh measurement (`fresh`), its rate from the previous aim; between
    /// frames (a loop faster than the mocap, a frame dropped) carried on at that rate from
    /// the newest measurement: falling back to the director's heading on a tick without a
    /// frame (every other tick at 200 Hz against a 100 Hz mocap) would jerk the heading
    /// between the two aims.
    pub(crate) fn aim(&mut self, held: Option<&Held>, t: f64, fresh: bool, sample: &mut Sample) {
        let Some((seen_s, m)) = self.drone_m else {
            self.last_aim = None;
            return;
        };
        // A drone not seen this long hovers (its failsafe): nothing to aim from.
        let Some((heading, pitch)) = (t - seen_s < self.setup.safety.mocap_hover_s)
            .then(|| held?.orientation(&self.actors.poses, &Vec3::from(m.position_m)))
            .flatten()
        else {
            self.last_aim = None;
            return;
        };
        match self.last_aim {
            Some(aim) if !fresh => {
                sample.heading_rad =
                    wrap_angle_rad(aim.heading_rad + aim.rate_radps * (t - aim.t_s));
                sample.heading_rate_radps = aim.rate_radps;
            }
            previous => {
                // Its rate from the previous aim (the director's rate is that of its own,
                // smoother heading).
                if let Some(aim) = previous {
                    if t > aim.t_s {
                        sample.heading_rate_radps =
                            wrap_angle_rad(heading - aim.heading_rad) / (t - aim.t_s);
                    }
                }
                sample.heading_rad = heading;
                self.last_aim = Some(Aim {
                    t_s: t,
                    heading_rad: heading,
                    rate_radps: sample.heading_rate_radps,
                });
            }
        }
        sample.camera_pitch_rad = pitch;
    }

    pub(crate) fn failsafe(&mut self, t: f64, message: &str) {
        self.failsafes += 1;
        self.event(t, "error", "failsafe", message.to_string());
    }
}

/// The sample to fly when the drone has never been measured (cannot happen after the
/// pre-flight check; kept total instead of panicking).
pub(crate) fn unreachable_measurement(first: &Sample, t: f64) -> Sample {
    hover_sample(t, first)
}

/// Whether `p` lies inside the stage less `margin_m`.
pub(crate) fn inside(stage: &Stage, p: &[f64; 3], margin_m: f64) -> bool {
    let (lo, hi) = (stage.min_m(), stage.max_m());
    (0..3).all(|i| p[i] >= lo[i] + margin_m - 1e-9 && p[i] <= hi[i] - margin_m + 1e-9)
}
