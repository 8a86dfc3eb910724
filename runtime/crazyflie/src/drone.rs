//! A Crazyflie behind the [`Drone`] trait ([`CrazyflieDrone`]).
//!
//! - **Connecting** ([`CrazyflieDrone::connect`]): the protocol version (which sets the yaw
//!   rate's sign, `frames`), the log TOC, the two log blocks (`log`), then the Kalman
//!   estimator selected (`stabilizer.estimator = 2`), each confirmed by the Crazyflie, and the
//!   first samples of both blocks waited for.
//! - **Take-off** by climb rate: a drone that does not arm itself is sent the arming request;
//!   then level altHold set-points climbing at [`CrazyflieOptions::take_off_climb_mps`] until
//!   the estimator's height is [`CrazyflieOptions::hover_height_m`] above where it stood:
//!   `Flying`. A locked, crashed or tumbled Crazyflie, a low battery or an unknown estimate
//!   refuse the take-off, saying why.
//! - **Flying**: [`Drone::send`] is one altHold set-point (`frames`), the command clamped to
//!   the profile's limits; [`Drone::hover`] a position set-point at the place and yaw the
//!   estimator gave when the hover began. A command during the take-off ends it.
//! - **Landing** by climb rate: level set-points descending at
//!   [`CrazyflieOptions::landing_descent_mps`] until the estimate is within 5 cm of the
//!   floor it took off from; then the stop set-point (motors off): `Landed`.
//! - **Emergency**: the stop set-point at once, and again at every telemetry read.
//! - **Telemetry** reads send the take-off's, the landing's and the hold's set-points when
//!   due: while the flight is in the air a set-point goes out at least every
//!   [`KEEP_ALIVE`]. When the calls stop, so do the set-points: the firmware levels out after
//!   0.5 s and stops the motors after 2 s, its own watchdog. Battery percent from
//!   `pm.batteryLevel`; the link's age from the last packet heard.
//! - **Motion capture** goes to the estimator as the external pose ([`PoseForwarder`]), at
//!   most every [`EXT_POSE_PERIOD_S`].

use std::sync::Arc;
use std::time::{Duration, Instant};

use dronecine_backend::frames::Command;
use dronecine_backend::{BackendError, BodyPose, Drone, DroneMessage, FlightState, Telemetry};
use dronecine_profile::Profile;

use crate::connect;
use crate::crtp::ToDrone;
use crate::frames::{self, YawRateSign};
use crate::link::Link;
use crate::log::{supervisor, Field};
use crate::url::CrazyflieUrl;

/// The shortest time between two external poses (100 Hz, less half a millisecond of jitter).
pub const EXT_POSE_PERIOD_S: f64 = 0.0095;
/// In the air, a set-point goes out at least this often (from `telemetry` when the flight
/// sends none).
pub const KEEP_ALIVE: Duration = Duration::from_millis(20);
/// The take-off's and the landing's set-points go out at most this often.
const CLIMB_PERIOD: Duration = Duration::from_millis(10);
/// A motor stop not known to have arrived is sent again this often.
const STOP_RESEND: Duration = Duration::from_millis(50);
/// A state sample older than this does not steer the take-off or the landing.
const ESTIMATE_FRESH: Duration = Duration::from_millis(300);
/// The take-off ends this close below the hover height.
const HOVER_TOLERANCE_M: f64 = 0.05;
/// The landing ends this close above the floor it took off from.
const LANDED_M: f64 = 0.05;
/// `pm.state` of a battery too low to fly (low power, shutting down).
const PM_LOW: f64 = 3.0;
/// The Kalman estimator's number (`stabilizer.estimator`).
pub const KALMAN: u8 = 2;

/// Timeouts and the take-off's and landing's shape.
#[derive(Clone, Debug, PartialEq)]
pub struct CrazyflieOptions {
    /// How long the Crazyflie may take to answer first.
    pub connect_timeout: Duration,
    /// How long each set-up exchange (TOC, log block, parameter) may take.
    pub request_timeout: Duration,
    /// How high above where it stood the take-off climbs.
    pub hover_height_m: f64,
    /// The take-off's climb rate (at most the profile's vertical speed limit).
    pub take_off_climb_mps: f64,
    /// The landing's descent rate (at most the profile's vertical speed limit).
    pub landing_descent_mps: f64,
    /// The local address of a UDP link (any free port when `None`).
    pub local_udp: Option<std::net::SocketAddr>,
}

impl Default for CrazyflieOptions {
    fn default() -> Self {
        CrazyflieOptions {
            connect_timeout: Duration::from_secs(5),
            request_timeout: Duration::from_secs(3),
            hover_height_m: 0.8,
            take_off_climb_mps: 0.3,
            landing_descent_mps: 0.25,
            local_udp: None,
        }
    }
}

/// What the backend does with the Crazyflie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    Ground,
    /// Climbing from the floor at `floor_m` (the estimator's height where it stood).
    TakingOff {
        floor_m: f64,
    },
    Flying {
        floor_m: f64,
    },
    Landing {
        floor_m: f64,
    },
    /// The motors were stopped by [`Drone::emergency`].
    Emergency,
}

/// A Crazyflie over CRTP (module docs).
pub struct CrazyflieDrone {
    link: Arc<Link>,
    protocol: u8,
    yaw: YawRateSign,
    options: CrazyflieOptions,
    tilt_max_rad: f64,
    vz_max_mps: f64,
    yaw_rate_max_radps: f64,
    phase: Phase,
    /// Where a hover holds the drone: position and yaw (degrees).
    hold: Option<([f32; 3], f32)>,
    last_setpoint: Option<Instant>,
    /// The supervisor's bits last seen, to tell their changes.
    supervisor_seen: Option<u16>,
    told: Vec<DroneMessage>,
}

impl CrazyflieDrone {
    /// Opens the link and sets the Crazyflie up (module docs); the profile gives the limits
    /// the commands are clamped to.
    pub fn connect(
        url: &CrazyflieUrl,
        profile: &Profile,
        options: CrazyflieOptions,
    ) -> Result<Self, BackendError> {
        let (link, protocol) = monitor(url, &options)?;
        let t = options.request_timeout;
        connect::set_u8_param(&link, "stabilizer", "estimator", KALMAN, t)?;
        let l = &profile.limits;
        Ok(CrazyflieDrone {
            link,
            protocol,
            yaw: YawRateSign::of_protocol(protocol),
            tilt_max_rad: l.tilt_max_rad,
            vz_max_mps: l.vz_max_mps,
            yaw_rate_max_radps: l.yaw_rate_max_radps,
            options,
            phase: Phase::Ground,
            hold: None,
            last_setpoint: None,
            supervisor_seen: None,
            told: Vec::new(),
        })
    }

    /// The link (its state: the values logged, the counters).
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// The Crazyflie's CRTP protocol version.
    pub fn protocol_version(&self) -> u8 {
        self.protocol
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// A handle that sends the motion capture's poses to the estimator from another owner
    /// (the flight's motion capture), sharing this link.
    pub fn forwarder(&self) -> PoseForwarder {
        PoseForwarder {
            link: Arc::clone(&self.link),
            last_t_s: None,
        }
    }

    /// Restarts the Kalman estimator (`kalman.resetEstimation`), so that it starts from the
    /// external poses it is given.
    pub fn reset_estimator(&self) -> Result<(), BackendError> {
        let t = self.options.request_timeout;
        connect::set_u8_param(&self.link, "kalman", "resetEstimation", 1, t)?;
        connect::set_u8_param(&self.link, "kalman", "resetEstimation", 0, t)
    }

    /// The estimator's position, when fresh.
    pub fn estimate_m(&self) -> Option<[f64; 3]> {
        self.link.state().estimate_m(ESTIMATE_FRESH)
    }

    /// Waits until the estimator's position is within `within_m` of `target` (the motion
    /// capture's), calling `tick` every few milliseconds meanwhile (to forward the motion
    /// capture and update `target`); refused after `timeout`, saying how far it was.
    pub fn wait_for_estimate(
        &mut self,
        within_m: f64,
        timeout: Duration,
        mut tick: impl FnMut(&mut Self) -> Result<Option<[f64; 3]>, BackendError>,
    ) -> Result<(), BackendError> {
        let deadline = Instant::now() + timeout;
        let mut off_m = f64::INFINITY;
        loop {
            if let (Some(target), Some(estimate)) = (tick(self)?, self.estimate_m()) {
                off_m = (0..3)
                    .map(|i| (target[i] - estimate[i]) * (target[i] - estimate[i]))
                    .sum::<f64>()
                    .sqrt();
                if off_m <= within_m {
                    return Ok(());
                }
            }
            if Instant::now() >= deadline {
                return Err(BackendError::Refused(format!(
                    "the Crazyflie's estimate is {} from the motion capture after {:.0} s: is \
                     the drone's rigid body the right one, and its axes the stage's?",
                    if off_m.is_finite() {
                        format!("{off_m:.2} m")
                    } else {
                        "unknown".into()
                    },
                    timeout.as_secs_f64()
                )));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    fn floor_m(&self) -> Option<f64> {
        match self.phase {
            Phase::TakingOff { floor_m }
            | Phase::Flying { floor_m }
            | Phase::Landing { floor_m } => Some(floor_m),
            _ => None,
        }
    }

    fn flying_for_us(&self) -> bool {
        matches!(self.phase, Phase::TakingOff { .. } | Phase::Flying { .. })
    }

    fn due(&self, period: Duration) -> bool {
        self.last_setpoint.is_none_or(|t| t.elapsed() >= period)
    }

    fn setpoint(&mut self, message: &ToDrone) -> Result<(), BackendError> {
        self.link.send_setpoint(message)?;
        self.last_setpoint = Some(Instant::now());
        Ok(())
    }

    /// A level set-point at climb rate `vz_mps`.
    fn climb(&mut self, vz_mps: f64) -> Result<(), BackendError> {
        let sp = frames::alt_hold(
            &Command {
                vz_mps,
                ..Command::HOVER
            },
            self.yaw,
        );
        self.setpoint(&alt_hold(&sp))
    }

    /// The position set-point that holds where the estimate was when the hold began.
    fn send_hold(&mut self) -> Result<(), BackendError> {
        if self.hold.is_none() {
            let s = self.link.state();
            let yaw = s.values.get(Field::Yaw);
            self.hold = s.values.estimate_m().map(|p| {
                (
                    p.map(|v| v as f32),
                    if yaw.is_finite() { yaw as f32 } else { 0.0 },
                )
            });
        }
        match self.hold {
            Some((position_m, yaw_deg)) => self.setpoint(&ToDrone::Position {
                position_m,
                yaw_deg,
            }),
            None => self.climb(0.0),
        }
    }

    /// The phase's transitions and the set-points due (module docs).
    fn update(&mut self) -> Result<(), BackendError> {
        let height = self.link.state().estimate_m(ESTIMATE_FRESH).map(|p| p[2]);
        match self.phase {
            Phase::TakingOff { floor_m } => {
                if height
                    .is_some_and(|h| h >= floor_m + self.options.hover_height_m - HOVER_TOLERANCE_M)
                {
                    self.phase = Phase::Flying { floor_m };
                    self.hold = None;
                    self.send_hold()?;
                } else if self.due(CLIMB_PERIOD) {
                    // Without a fresh height the climb holds its altitude instead.
                    let vz = if height.is_some() {
                        self.options.take_off_climb_mps.min(self.vz_max_mps)
                    } else {
                        0.0
                    };
                    self.climb(vz)?;
                }
            }
            Phase::Flying { .. } if self.due(KEEP_ALIVE) => self.send_hold()?,
            Phase::Landing { floor_m } => {
                if height.is_some_and(|h| h <= floor_m + LANDED_M) {
                    self.setpoint(&ToDrone::Stop)?;
                    self.phase = Phase::Ground;
                } else if self.due(CLIMB_PERIOD) {
                    let vz = self.options.landing_descent_mps.min(self.vz_max_mps);
                    self.climb(-vz)?;
                }
            }
            Phase::Emergency if self.due(STOP_RESEND) => self.setpoint(&ToDrone::Stop)?,
            _ => {}
        }
        self.watch_supervisor();
        Ok(())
    }

    /// Tells the supervisor's changes that matter (armed, locked, crashed, tumbled).
    fn watch_supervisor(&mut self) {
        let Some(info) = self.link.state().values.supervisor() else {
            return;
        };
        let before = self.supervisor_seen.replace(info);
        let changed = before.map_or(info, |b| b ^ info);
        let told =
            supervisor::ARMED | supervisor::LOCKED | supervisor::CRASHED | supervisor::TUMBLED;
        if changed & told != 0 {
            let bad = info & (supervisor::LOCKED | supervisor::CRASHED | supervisor::TUMBLED) != 0;
            self.told.push(DroneMessage {
                level: if bad { "error" } else { "info" },
                text: format!(
                    "crazyflie supervisor: {}",
                    supervisor::names(info).join(", ")
                ),
            });
        }
    }

    /// The command within the profile's limits.
    fn clamped(&self, c: &Command) -> Command {
        let (t, v, y) = (self.tilt_max_rad, self.vz_max_mps, self.yaw_rate_max_radps);
        Command {
            roll_rad: c.roll_rad.clamp(-t, t),
            pitch_rad: c.pitch_rad.clamp(-t, t),
            yaw_rate_radps: c.yaw_rate_radps.clamp(-y, y),
            vz_mps: c.vz_mps.clamp(-v, v),
        }
    }

    /// Why the Crazyflie cannot take off now, if it cannot.
    fn take_off_refusal(&self) -> Option<String> {
        let s = self.link.state();
        let info = s.values.supervisor().unwrap_or(0);
        let bad = info & (supervisor::LOCKED | supervisor::CRASHED | supervisor::TUMBLED);
        if bad != 0 {
            return Some(format!(
                "the Crazyflie's supervisor says {}: restart the Crazyflie (power it off and on)",
                supervisor::names(bad).join(", ")
            ));
        }
        if s.values.get(Field::PmState) >= PM_LOW {
            return Some(format!(
                "the Crazyflie's battery is low ({:.2} V, {:.0} %): charge it",
                s.values.get(Field::Vbat),
                s.values.get(Field::BatteryLevel)
            ));
        }
        if s.estimate_m(ESTIMATE_FRESH).is_none() {
            return Some("the Crazyflie's estimate is not known (no recent log sample)".into());
        }
        None
    }
}

/// The link to the Crazyflie at `url` with its log blocks started and sampled, and its
/// protocol version: what `dronecine status` reads (no parameter is written, no set-point
/// is sent; the log blocks are created, as any client's).
pub fn monitor(
    url: &CrazyflieUrl,
    options: &CrazyflieOptions,
) -> Result<(Arc<Link>, u8), BackendError> {
    let link = Arc::new(Link::open(url, options.local_udp)?);
    let protocol = connect::protocol_version(&link, options.connect_timeout)?;
    let toc = connect::read_toc(&link, options.request_timeout)?;
    connect::start_blocks(&link, &toc, options.request_timeout)?;
    let sampled = link.wait_for(
        options.request_timeout,
        || Ok(()),
        |s| s.sampled_at.iter().all(Option::is_some),
    )?;
    if !sampled {
        return Err(BackendError::Link(format!(
            "the Crazyflie at {url} sends no log samples"
        )));
    }
    Ok((link, protocol))
}

fn alt_hold(sp: &frames::AltHold) -> ToDrone<'static> {
    ToDrone::AltHold {
        roll_deg: sp.roll_deg,
        pitch_deg: sp.pitch_deg,
        yaw_rate_degps: sp.yaw_rate_degps,
        vz_mps: sp.vz_mps,
    }
}

/// The flight state from the backend's phase and the supervisor's bits: a locked, crashed
/// or tumbled Crazyflie has its motors stopped.
pub fn flight_state(phase: Phase, supervisor_info: Option<u16>) -> FlightState {
    let cut = supervisor::LOCKED | supervisor::CRASHED | supervisor::TUMBLED;
    if phase == Phase::Emergency || supervisor_info.is_some_and(|i| i & cut != 0) {
        return FlightState::Emergency;
    }
    match phase {
        Phase::Ground | Phase::Emergency => FlightState::Landed,
        Phase::TakingOff { .. } => FlightState::TakingOff,
        Phase::Flying { .. } => FlightState::Flying,
        Phase::Landing { .. } => FlightState::Landing,
    }
}

impl Drone for CrazyflieDrone {
    fn take_off(&mut self) -> Result<(), BackendError> {
        if self.flying_for_us() {
            return Ok(());
        }
        if let Some(why) = self.take_off_refusal() {
            return Err(BackendError::Refused(why));
        }
        let info = self.link.state().values.supervisor().unwrap_or(0);
        if info & (supervisor::ARMED | supervisor::AUTO_ARM) == 0 {
            self.link.send_message(&ToDrone::Arm {
                arm: true,
                supervisor: self.protocol >= 12,
            })?;
        }
        let floor_m = self.estimate_m().map_or(0.0, |p| p[2]);
        self.phase = Phase::TakingOff { floor_m };
        self.last_setpoint = None;
        self.update()
    }

    /// The descent by climb rate (module docs); nothing on the ground.
    fn land(&mut self) -> Result<(), BackendError> {
        if let Some(floor_m) = self.floor_m() {
            if !matches!(self.phase, Phase::Landing { .. }) {
                self.phase = Phase::Landing { floor_m };
                self.last_setpoint = None;
            }
        }
        self.update()
    }

    /// The stop set-point: the motors stop, in flight too.
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.phase = Phase::Emergency;
        self.setpoint(&ToDrone::Stop)
    }

    fn send(&mut self, command: &Command) -> Result<(), BackendError> {
        if !command.is_finite() {
            return Err(BackendError::Refused(format!(
                "a command that is not a number: {command:?}"
            )));
        }
        if let Phase::TakingOff { floor_m } = self.phase {
            self.phase = Phase::Flying { floor_m };
        }
        if !matches!(self.phase, Phase::Flying { .. }) {
            return self.update();
        }
        self.hold = None;
        let sp = frames::alt_hold(&self.clamped(command), self.yaw);
        self.setpoint(&alt_hold(&sp))
    }

    fn hover(&mut self) -> Result<(), BackendError> {
        if matches!(self.phase, Phase::Flying { .. }) {
            return self.send_hold();
        }
        self.update()
    }

    fn telemetry(&mut self) -> Telemetry {
        // A failed send shows as the Crazyflie's silence: the link age tells the loop.
        let _ = self.update();
        let (info, battery) = {
            let s = self.link.state();
            (s.values.supervisor(), s.values.get(Field::BatteryLevel))
        };
        Telemetry {
            state: flight_state(self.phase, info),
            battery_percent: battery,
            link_age_s: self.link.link_age_s(),
        }
    }

    fn messages(&mut self, out: &mut Vec<DroneMessage>) {
        out.append(&mut self.told);
        let mut s = self.link.state();
        if !s.messages.is_empty() {
            out.extend(s.messages.drain(..));
        }
    }
}

/// Sends the motion capture's poses of the drone to its estimator
/// ([`CrazyflieDrone::forwarder`]), at most one per [`EXT_POSE_PERIOD_S`].
pub struct PoseForwarder {
    link: Arc<Link>,
    last_t_s: Option<f64>,
}

impl PoseForwarder {
    /// Sends the pose captured at `t_s` (the flight's clock) as the external pose, with the
    /// drone's own roll and pitch, unless one went out less than [`EXT_POSE_PERIOD_S`]
    /// before: `true` when sent.
    pub fn forward(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError> {
        if self
            .last_t_s
            .is_some_and(|last| t_s - last < EXT_POSE_PERIOD_S)
        {
            return Ok(false);
        }
        let (roll, pitch) = self.link.state().tilt_rad();
        let (position_m, quaternion) = frames::ext_pose(pose, roll, pitch);
        self.link.send_message(&ToDrone::ExtPose {
            position_m,
            quaternion,
        })?;
        self.last_t_s = Some(t_s);
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flight_state_follows_the_phase_and_the_supervisor() {
        use FlightState as F;
        let floor_m = 0.0;
        let cases = [
            (Phase::Ground, None, F::Landed),
            (
                Phase::TakingOff { floor_m },
                Some(supervisor::ARMED),
                F::TakingOff,
            ),
            (
                Phase::Flying { floor_m },
                Some(supervisor::FLYING),
                F::Flying,
            ),
            (Phase::Landing { floor_m }, None, F::Landing),
            (Phase::Emergency, None, F::Emergency),
            (
                Phase::Flying { floor_m },
                Some(supervisor::LOCKED),
                F::Emergency,
            ),
            (Phase::Ground, Some(supervisor::TUMBLED), F::Emergency),
            (
                Phase::Landing { floor_m },
                Some(supervisor::CRASHED),
                F::Emergency,
            ),
        ];
        for (phase, info, want) in cases {
            assert_eq!(flight_state(phase, info), want, "{phase:?} {info:?}");
        }
    }
}
