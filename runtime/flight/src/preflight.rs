//! The checks before take-off, each a coded diagnostic (`preflight::`) when it refuses: the
//! drone and every actor tracked, the drone inside the stage and clear of the actors, its
//! battery, and the first framing solved, inside the stage and clear of the actors as they
//! stand now.

use dronecine_backend::BodyPose;
use dronecine_compiler::camera::Vec3;
use dronecine_compiler::reference::Sample;
use dronecine_diag::{Diagnostic, Span};
use dronecine_servo::control::Measurement;

use crate::code::{refusal, PreflightCode};
use crate::flight::{inside, Flight};
use crate::tracker::finite_pose;
use crate::FlightError;

/// How far into an actor's safety distance or the stage's margin an approach may come
/// before it is told (a warning event): the take-off hover or the first framing themselves
/// may be that close.
pub(crate) const APPROACH_TOLERANCE_M: f64 = 0.1;

/// Where the drone stands when the checks pass.
pub(crate) struct Ground {
    /// The time of the last pre-flight tick.
    pub t: f64,
    /// The drone's first measurement with every actor tracked.
    pub drone: Measurement,
    /// Where it takes off from, and lands again after the shots.
    pub take_off_xy: [f64; 2],
    /// The first framing as the director solved it against the actors as they stood.
    pub first: Sample,
}

impl Flight<'_, '_> {
    /// The checks before take-off: `Ground` when the drone may take off, else the refusal.
    pub(crate) fn preflight(&mut self) -> Result<Ground, FlightError> {
        let (t, m0) = self.wait_for_the_set()?;
        let take_off_xy = self.check_where_the_drone_stands(&m0)?;
        self.check_the_actors_are_tracked()?;
        self.check_the_drone_is_clear_of_the_actors(&m0)?;
        self.check_the_battery()?;
        let first = self.check_the_first_framing()?;
        self.check_the_operator()?;
        Ok(Ground {
            t,
            drone: m0,
            take_off_xy,
            first,
        })
    }

    /// The first frame that has the drone and every actor, within `mocap_wait_s`: a body
    /// dropped from one frame (a marker hidden for a moment) is not untracked, and refusing
    /// the flight on it would refuse a good set-up now and then. The time and the drone's
    /// newest measurement.
    fn wait_for_the_set(&mut self) -> Result<(f64, Measurement), FlightError> {
        let t_start = self.clock.now_s();
        let mut t = t_start;
        let mut seen_drone: Option<Measurement> = None;
        while t - t_start <= self.setup.safety.mocap_wait_s {
            self.check_the_operator()?;
            t = self.wait_tick(t + self.period_s)?;
            self.idle(t);
            if let Some(m) = self.measured {
                seen_drone = Some(m);
                let actors = self.setup.scene.actors.len();
                if (0..actors).all(|i| matches!(self.frame.actors.get(i), Some(Some(_)))) {
                    break;
                }
            }
        }
        let Some(m0) = seen_drone else {
            return Err(refusal(
                PreflightCode::DroneUntracked,
                format!(
                    "the drone is not tracked by the motion capture (no pose in {:.1} s)",
                    self.setup.safety.mocap_wait_s
                ),
                "check its rigid body: the rig file's `drone` id, and that Motive streams it",
            ));
        };
        if !finite_pose(&BodyPose {
            position_m: m0.position_m,
            heading_rad: m0.heading_rad,
        }) {
            return Err(refusal(
                PreflightCode::DronePoseInvalid,
                "the drone's tracked pose is not a number".into(),
                "check the drone's rigid body in Motive (its markers and its calibration)",
            ));
        }
        Ok((t, m0))
    }

    /// The drone inside the stage (the failsafe would land it at once): where it takes off
    /// from, and lands again after the shots.
    fn check_where_the_drone_stands(&self, m0: &Measurement) -> Result<[f64; 2], FlightError> {
        let stage = self.setup.scene.stage;
        let [x, y, _] = m0.position_m;
        let (lo, hi) = (stage.min_m(), stage.max_m());
        if !inside(&stage, &[x, y, lo[2].max(hi[2].min(m0.position_m[2]))], 0.0) {
            return Err(refusal(
                PreflightCode::DroneOutsideStage,
                format!("the drone stands at ({x:.2}, {y:.2}) m, outside the stage"),
                "place it inside, below its first framing",
            ));
        }
        Ok([x, y])
    }

    /// Every actor in the frame: one diagnostic per untracked actor, at their declaration.
    fn check_the_actors_are_tracked(&self) -> Result<(), FlightError> {
        let untracked: Vec<Diagnostic> = (self.setup.scene.actors.iter().enumerate())
            .filter(|(i, _)| !matches!(self.frame.actors.get(*i), Some(Some(_))))
            .map(|(_, a)| {
                Diagnostic::error(
                    PreflightCode::ActorUntracked,
                    a.span,
                    format!("actor {} is not tracked by the motion capture", a.name),
                )
                .with_label("not tracked")
                .with_help(format!(
                    "check {}'s rigid body: the rig file's `[actors]` id, and that Motive \
                     streams it",
                    a.name
                ))
            })
            .collect();
        if untracked.is_empty() {
            Ok(())
        } else {
            Err(FlightError::Preflight(untracked))
        }
    }

    /// The drone not under an actor's nose.
    fn check_the_drone_is_clear_of_the_actors(&self, m0: &Measurement) -> Result<(), FlightError> {
        let safety_m = self.setup.profile.safety.actor_distance_m;
        let [x, y, z] = m0.position_m;
        let Some((i, into_m)) = self.keepout().deepest_actor(&Vec3::new(x, y, z)) else {
            return Ok(());
        };
        let actor = &self.setup.scene.actors[i];
        Err(FlightError::Preflight(vec![Diagnostic::error(
            PreflightCode::DroneTooClose,
            actor.span,
            format!(
                "the drone stands {:.2} m from {}; {} keeps {safety_m:.2} m from actors",
                safety_m - into_m,
                actor.name,
                self.setup.profile.name
            ),
        )
        .with_label("the drone stands too close to this actor")
        .with_help(
            "place the drone further away, below its first framing",
        )]))
    }

    /// No interrupt from the operator: one before take-off keeps the drone on the ground.
    fn check_the_operator(&self) -> Result<(), FlightError> {
        if self.interrupts() == 0 {
            return Ok(());
        }
        Err(refusal(
            PreflightCode::Interrupted,
            "interrupted before take-off: the drone stays on the ground".into(),
            "run `dronecine shoot` again when the set is ready",
        ))
    }

    /// A battery that can fly the take-off.
    fn check_the_battery(&mut self) -> Result<(), FlightError> {
        let telemetry = self.drone.telemetry();
        let battery = telemetry.battery_percent;
        // A level no battery has is not one to fly on: the drone's telemetry is broken.
        if !(0.0..=100.0).contains(&battery) {
            return Err(refusal(
                PreflightCode::TelemetryImplausible,
                format!("the drone reports its battery at {battery}%: no battery reads that"),
                "check the drone with `dronecine status`, which names what it reports wrong",
            ));
        }
        if battery < self.setup.safety.battery_land_percent {
            return Err(refusal(
                PreflightCode::BatteryLow,
                format!(
                    "battery at {:.0}%, below the {:.0}% needed to fly",
                    telemetry.battery_percent, self.setup.safety.battery_land_percent
                ),
                "charge or swap it",
            ));
        }
        Ok(())
    }

    /// The first framing solved against the actors as they stand now (an unsolved one would
    /// be flown to the origin), inside the stage, and clear of them: one off their mark can
    /// stand where it puts the drone, and the director would hold the drone at their
    /// distance, off the framing, from the first shot on — not a take to start. Its first
    /// sample.
    fn check_the_first_framing(&self) -> Result<Sample, FlightError> {
        let shot = self.setup.script.timeline[0].span;
        let (first, solved, unsolved) = self.probe();
        if let Some(why) = unsolved {
            return Err(FlightError::Preflight(vec![Diagnostic::error(
                PreflightCode::FirstFramingUnsolved,
                shot,
                format!(
                    "the first framing cannot be solved against the actors as they stand now \
                     ({why})"
                ),
            )
            .with_label("this framing does not solve")
            .with_help("put the actors on their marks or change the first shot")]));
        }
        let solved: [f64; 3] = solved.into();
        if !inside(&self.setup.scene.stage, &solved, 0.0) {
            return Err(FlightError::Preflight(vec![Diagnostic::error(
                PreflightCode::FirstFramingOutsideStage,
                shot,
                format!(
                    "the first framing puts the drone at ({:.2}, {:.2}, {:.2}) m, outside the \
                     stage",
                    solved[0], solved[1], solved[2]
                ),
            )
            .with_label("this framing is outside the stage")
            .with_help("move the actors or change the first shot")]));
        }
        if let Some((i, into_m)) = self.keepout().deepest_actor(&Vec3::from(solved)) {
            if into_m > APPROACH_TOLERANCE_M {
                return Err(self.first_framing_near_actor(shot, i, into_m));
            }
        }
        Ok(first)
    }

    /// The refusal of a first framing that puts the drone `into_m` inside actor `i`'s
    /// distance.
    fn first_framing_near_actor(&self, shot: Span, i: usize, into_m: f64) -> FlightError {
        let safety_m = self.setup.profile.safety.actor_distance_m;
        let actor = &self.setup.scene.actors[i];
        let name = &actor.name;
        FlightError::Preflight(vec![Diagnostic::error(
            PreflightCode::FirstFramingNearActor,
            shot,
            format!(
                "the first framing puts the drone {:.2} m from {name} as the actors stand \
                 now; {} keeps {safety_m:.2} m from actors",
                safety_m - into_m,
                self.setup.profile.name
            ),
        )
        .with_label("this framing comes too close")
        .with_related(actor.span, format!("{name} is declared here"))
        .with_help(format!("put {name} on their mark or change the first shot"))])
    }
}
