//! ArduPilot Copter behind the [`Drone`] trait ([`MavlinkDrone`]).
//!
//! - **Take-off**: the parameter check (refused, naming each wrong parameter), the limits
//!   read, GUIDED_NOGPS (custom mode 20) through MAV_CMD_DO_SET_MODE, arming through
//!   MAV_CMD_COMPONENT_ARM_DISARM, each waited for in the vehicle's heartbeat (a refusal or
//!   no change within the command timeout refuses the take-off, with the vehicle's texts);
//!   then a level climb at [`MavlinkOptions::take_off_climb_mps`] until the EKF's height
//!   (LOCAL_POSITION_NED) reaches [`MavlinkOptions::hover_height_m`]: `Flying`. Without a
//!   fresh height the climb holds its altitude instead.
//! - **Flying**: [`Drone::send`] is one SET_ATTITUDE_TARGET (`frames`); the yaw target is
//!   the vehicle's yaw (ATTITUDE) plus the yaw-rate command times `1/ATC_ANG_YAW_P`
//!   ([`VehicleLimits::yaw_lead_s`]; at most [`MAX_YAW_LEAD_RAD`]), which the autopilot's
//!   angle controller turns into that rate (the integral of the commands before the first
//!   ATTITUDE); roll and pitch are clamped to the lean limit and the yaw rate to
//!   ATC_RATE_Y_MAX. [`Drone::hover`] is level at the vehicle's yaw, thrust 0.5. A command during the
//!   take-off ends it: the flight has taken over. The vehicle's own
//!   watchdog (its attitude timeout, then GUID_TIMEOUT) acts when the calls stop.
//! - **Landing**: LAND mode (custom mode 9), re-sent until the heartbeat shows it; `Landing`
//!   until the vehicle disarms (ArduCopter does on touching down), then `Landed`.
//! - **Emergency**: a forced disarm (param2 21196), re-sent until the heartbeat shows the
//!   motors disarmed; `Emergency` until the next take-off.
//! - **The autopilot's own decisions are never fought**: when the vehicle leaves
//!   GUIDED_NOGPS by itself during the take-off or the flight (a battery, EKF or radio
//!   failsafe switches to LAND or RTL; a pilot takes over), the backend sends no more
//!   set-points and no mode, telemetry reports `Landing` until the vehicle disarms, and
//!   [`MavlinkDrone::unrequested_mode`] names the mode; [`Drone::land`] then sends nothing.
//! - **Telemetry**: the state from the above and the heartbeat, the battery (NaN while the
//!   vehicle does not know it), the time since the vehicle was last heard.
//! - **Motion capture** goes to the autopilot's EKF as VISION_POSITION_ESTIMATE (at most
//!   every [`VISION_PERIOD_S`]); [`MavlinkDrone::set_origin`] sets the EKF's origin.

use std::sync::Arc;
use std::time::{Duration, Instant};

use dronecine_backend::frames::{wrap_angle_rad, Command};
use dronecine_backend::{BackendError, BodyPose, Drone, DroneMessage, FlightState, Telemetry};
use mavlink::dialects::ardupilotmega::{
    ATTITUDE_DATA, BATTERY_STATUS_DATA, EKF_STATUS_REPORT_DATA, EXTENDED_SYS_STATE_DATA,
    GIMBAL_DEVICE_ATTITUDE_STATUS_DATA, LOCAL_POSITION_NED_DATA, SIM_STATE_DATA, SYS_STATUS_DATA,
};
use mavlink::MessageData;

use crate::frames::{pose_to_ned, thrust_for_climb, AttitudeTarget};
use crate::link::Link;
use crate::messages::{self, copter_mode, Target};
use crate::params::{self, ParamCheck, VehicleLimits};
use crate::state::{Heartbeat, LandedState, VehicleEvent, VehicleState};
use crate::url::MavlinkUrl;

/// The shortest time between two VISION_POSITION_ESTIMATEs (50 Hz, less half a
/// millisecond for the motion capture's jitter).
pub const VISION_PERIOD_S: f64 = 0.0195;
/// The shortest time between two gimbal set-points (10 Hz: a gimbal's own loop follows
/// set-points at that rate, and more would only crowd the link).
pub const GIMBAL_PERIOD: Duration = Duration::from_millis(100);
/// How far the integrated yaw target may lead the measured yaw: a vehicle that cannot turn
/// as fast as asked does not store up a turn it makes later.
pub const MAX_YAW_LEAD_RAD: f64 = 0.5;
/// The longest interval a yaw-rate command is integrated over (a stalled caller does not
/// make the target jump).
const MAX_YAW_STEP_S: f64 = 0.1;
/// The take-off ends this close below the hover height.
const HOVER_TOLERANCE_M: f64 = 0.05;
/// An EKF height older than this does not steer the take-off climb.
const HEIGHT_FRESH: Duration = Duration::from_millis(500);
/// During the take-off, a set-point goes out at least this often (from `telemetry` too).
const TAKE_OFF_KEEP_ALIVE: Duration = Duration::from_millis(50);
/// A mode change or a disarm not yet seen in the heartbeat is sent again this often.
const RESEND: Duration = Duration::from_millis(500);
/// The EKF flags that say the position is known (attitude, horizontal velocity, relative
/// and absolute horizontal position, absolute vertical position).
const EKF_NAV_GOOD: u16 = 1 | 2 | 8 | 16 | 32;
/// The EKF flags that say it is not navigating (constant-position mode, never healthy).
const EKF_NAV_BAD: u16 = 128 | 1024;

/// How often [`MavlinkDrone::wait_for_origin`] sends the origin again.
pub const ORIGIN_RESEND: Duration = Duration::from_secs(1);
/// GPS_GLOBAL_ORIGIN's message id.
const ORIGIN_MESSAGE_ID: u32 = 49;

/// The EKF's origin (SET_GPS_GLOBAL_ORIGIN): where on Earth the stage is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeoOrigin {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Above mean sea level.
    pub alt_m: f64,
}

/// Timeouts and the take-off's shape.
#[derive(Clone, Debug, PartialEq)]
pub struct MavlinkOptions {
    /// How long to wait for the vehicle's first heartbeat.
    pub heartbeat_timeout: Duration,
    /// How long a mode change or an arming may take to show in the heartbeat.
    pub command_timeout: Duration,
    /// How long a batch of parameter reads may take.
    pub param_timeout: Duration,
    /// The height the take-off climbs to (the EKF's, above the origin's floor).
    pub hover_height_m: f64,
    /// The take-off's climb rate (at most the vehicle's WPNAV_SPEED_UP).
    pub take_off_climb_mps: f64,
    /// The EKF's origin. The autopilot takes its magnetic declination from it, so it should
    /// be the stage's real place when the autopilot's yaw comes from its compass.
    pub origin: GeoOrigin,
    /// How often the vehicle is asked to send its attitude and local position.
    pub stream_hz: f64,
}

impl Default for MavlinkOptions {
    fn default() -> Self {
        MavlinkOptions {
            heartbeat_timeout: Duration::from_secs(5),
            command_timeout: Duration::from_secs(3),
            param_timeout: Duration::from_secs(3),
            hover_height_m: 1.0,
            take_off_climb_mps: 0.5,
            origin: GeoOrigin {
                lat_deg: 51.4779,
                lon_deg: -0.0015,
                alt_m: 45.0,
            },
            stream_hz: 20.0,
        }
    }
}

/// What the backend is doing with the vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Not flying for the flight (on the ground, or flown by someone else).
    Ground,
    /// The take-off asked: GUIDED_NOGPS, then arming, each asked again every half second
    /// until the heartbeat shows it (the vehicle's refusals come as its texts).
    Arming,
    TakingOff,
    Flying,
    /// Landing: asked by the flight, or decided by the autopilot.
    Landing,
    /// A forced disarm was asked.
    Emergency,
}

/// The vehicle's [`FlightState`] from the backend's phase, its heartbeat and its landed
/// state (module docs): a vehicle that left GUIDED_NOGPS during the flight is `Landing`.
pub fn flight_state(
    phase: Phase,
    heartbeat: Option<Heartbeat>,
    landed: Option<LandedState>,
) -> FlightState {
    let ours = |hb: Heartbeat| hb.custom_mode == copter_mode::GUIDED_NOGPS;
    match (phase, heartbeat) {
        (Phase::Emergency, _) => FlightState::Emergency,
        (Phase::Arming, _) => FlightState::TakingOff,
        (_, None) => FlightState::Landed,
        (_, Some(hb)) if !hb.armed => FlightState::Landed,
        (Phase::Landing, _) => FlightState::Landing,
        (Phase::TakingOff | Phase::Flying, Some(hb)) if !ours(hb) => FlightState::Landing,
        (Phase::TakingOff, _) => FlightState::TakingOff,
        (Phase::Flying, _) => FlightState::Flying,
        (Phase::Ground, Some(hb)) => match landed {
            Some(LandedState::InAir) if ours(hb) => FlightState::Flying,
            Some(LandedState::InAir | LandedState::Landing) => FlightState::Landing,
            Some(LandedState::TakingOff) => FlightState::TakingOff,
            _ => FlightState::Landed,
        },
    }
}

/// The messages the vehicle is asked to stream, with their rate (0: the options' rate).
const STREAMS: [(u32, f64); 8] = [
    (ATTITUDE_DATA::ID, 0.0),
    (LOCAL_POSITION_NED_DATA::ID, 0.0),
    (SIM_STATE_DATA::ID, 0.0),
    (GIMBAL_DEVICE_ATTITUDE_STATUS_DATA::ID, 10.0),
    (SYS_STATUS_DATA::ID, 2.0),
    (EXTENDED_SYS_STATE_DATA::ID, 2.0),
    (EKF_STATUS_REPORT_DATA::ID, 2.0),
    (BATTERY_STATUS_DATA::ID, 1.0),
];

/// An ArduPilot Copter over MAVLink 2 (module docs).
pub struct MavlinkDrone {
    link: Arc<Link>,
    target: Target,
    options: MavlinkOptions,
    limits: Option<VehicleLimits>,
    check: Option<ParamCheck>,
    phase: Phase,
    /// The mode the vehicle chose by itself during the flight.
    took_over: Option<u32>,
    yaw_target_rad: f64,
    /// The yaw rate in force since the last set-point (integrated up to the next).
    yaw_rate_radps: f64,
    last_setpoint: Option<Instant>,
    /// The last mode change or disarm sent, for its re-sending.
    last_request: Option<Instant>,
    last_vision_t_s: Option<f64>,
    last_gimbal: Option<(Instant, f64)>,
}

impl MavlinkDrone {
    /// Opens the link, waits for the vehicle's heartbeat and asks for the messages the
    /// backend reads.
    pub fn connect(url: &MavlinkUrl, options: MavlinkOptions) -> Result<Self, BackendError> {
        let link = Arc::new(Link::open(url)?);
        let target = link.wait_for_vehicle(options.heartbeat_timeout)?;
        let drone = MavlinkDrone {
            link,
            target,
            options,
            limits: None,
            check: None,
            phase: Phase::Ground,
            took_over: None,
            yaw_target_rad: 0.0,
            yaw_rate_radps: 0.0,
            last_setpoint: None,
            last_request: None,
            last_vision_t_s: None,
            last_gimbal: None,
        };
        drone.request_streams()?;
        Ok(drone)
    }

    /// The link (its state, and messages of the caller's own).
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// A handle that sends the motion capture's poses to the autopilot from another owner
    /// (the flight's motion capture), sharing this link.
    pub fn forwarder(&self) -> PoseForwarder {
        PoseForwarder {
            link: Arc::clone(&self.link),
            last_t_s: None,
        }
    }

    /// A motion capture made from the simulator's truth (SIM_STATE), for software in the
    /// loop: the vehicle's position at the link's first SIM_STATE is `at_m` on the stage.
    pub fn truth_mocap(&self, at_m: [f64; 3], epoch: Instant) -> crate::truth::TruthMocap {
        crate::truth::TruthMocap::new(Arc::clone(&self.link), at_m, epoch)
    }

    /// The autopilot's system and component.
    pub fn target(&self) -> Target {
        self.target
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// A copy of everything read from the vehicle (allocates: not for every tick).
    pub fn vehicle_state(&self) -> VehicleState {
        self.link.state().clone()
    }

    /// Moves the vehicle's events (texts, mode and arming changes, EKF flags) not yet
    /// drained into `out`, oldest first.
    pub fn drain_events(&mut self, out: &mut Vec<(Instant, VehicleEvent)>) {
        out.extend(self.link.state().events.drain(..));
    }

    /// The mode the autopilot switched to by itself during the take-off or the flight
    /// (`messages::copter_mode`), if it did.
    pub fn unrequested_mode(&self) -> Option<u32> {
        self.took_over
    }

    /// The vehicle's limits, read from its parameters once.
    pub fn limits(&mut self) -> Result<VehicleLimits, BackendError> {
        if let Some(l) = self.limits {
            return Ok(l);
        }
        let l = VehicleLimits::read(&self.link, self.options.param_timeout)?;
        self.limits = Some(l);
        Ok(l)
    }

    /// Reads the parameters flying on motion capture needs and checks them
    /// (`params::REQUIRED`).
    pub fn check_parameters(&mut self) -> Result<ParamCheck, BackendError> {
        let check = params::check_parameters(&self.link, self.options.param_timeout)?;
        self.check = Some(check.clone());
        Ok(check)
    }

    /// Reads parameters by name (`None` for those the vehicle does not answer).
    pub fn read_params(&self, names: &[&str]) -> Result<Vec<Option<f32>>, BackendError> {
        params::read_params(&self.link, names, self.options.param_timeout)
    }

    /// Sends SET_GPS_GLOBAL_ORIGIN with the options' origin.
    pub fn set_origin(&mut self) -> Result<(), BackendError> {
        let o = self.options.origin;
        let msg = messages::gps_origin(self.target.system, o.lat_deg, o.lon_deg, o.alt_m);
        self.link.send(&msg)
    }

    /// Waits for the autopilot to confirm the EKF's origin (GPS_GLOBAL_ORIGIN), sending
    /// SET_GPS_GLOBAL_ORIGIN and asking for the confirmation every [`ORIGIN_RESEND`] (an EKF
    /// not yet initialised drops an origin, and one set too early is never set: the vehicle
    /// then flies with no position on Earth, and its landing, which needs one, fails), calling
    /// `tick` every few milliseconds meanwhile; refused after `timeout`.
    pub fn wait_for_origin(
        &mut self,
        timeout: Duration,
        mut tick: impl FnMut(&mut Self) -> Result<(), BackendError>,
    ) -> Result<(), BackendError> {
        let mut last_sent: Option<Instant> = None;
        let confirmed = self.wait_until(
            timeout,
            |d| d.link.state().origin.is_some(),
            |d| {
                if last_sent.is_none_or(|t| t.elapsed() >= ORIGIN_RESEND) {
                    d.set_origin()?;
                    d.link
                        .send(&messages::request_message(d.target, ORIGIN_MESSAGE_ID))?;
                    last_sent = Some(Instant::now());
                }
                tick(d)
            },
        )?;
        if confirmed {
            return Ok(());
        }
        Err(BackendError::Refused(format!(
            "the autopilot at {} did not confirm its EKF origin within {:.0} s (no \
             GPS_GLOBAL_ORIGIN after SET_GPS_GLOBAL_ORIGIN): without one it has no position on \
             Earth, and its landing needs one",
            self.link.url(),
            timeout.as_secs_f64()
        )))
    }

    /// Sends the drone's motion-capture pose (stage frame, captured at `t_s` on the flight's
    /// clock) as VISION_POSITION_ESTIMATE, unless one went out less than
    /// [`VISION_PERIOD_S`] before: `true` when sent. Roll and pitch are the vehicle's own
    /// (ATTITUDE): the motion capture gives the position and the heading.
    pub fn forward_pose(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError> {
        let sent = send_vision(&self.link, self.last_vision_t_s, t_s, pose)?;
        if sent {
            self.last_vision_t_s = Some(t_s);
        }
        Ok(sent)
    }

    /// The autopilot navigates on the external navigation: its EKF said so, or its flags
    /// show a known position outside constant-position mode.
    pub fn uses_external_nav(&self) -> bool {
        let state = self.link.state();
        let flags = state.ekf_flags.unwrap_or(0);
        state.external_nav_said
            || (flags & EKF_NAV_GOOD == EKF_NAV_GOOD && flags & EKF_NAV_BAD == 0)
    }

    /// Waits for the autopilot's pre-arm checks to pass (SYS_STATUS), calling `tick` every few
    /// milliseconds meanwhile (to forward the motion capture); refused after `timeout` with
    /// the autopilot's last pre-arm texts. A vehicle that never reports its checks passes.
    pub fn wait_for_prearm(
        &mut self,
        timeout: Duration,
        tick: impl FnMut(&mut Self) -> Result<(), BackendError>,
    ) -> Result<(), BackendError> {
        if self.wait_until(timeout, |d| d.link.state().prearm_ok != Some(false), tick)? {
            return Ok(());
        }
        let state = self.link.state();
        let mut texts: Vec<&str> = (state.events.iter().rev())
            .filter_map(|(_, e)| match e {
                VehicleEvent::Text { text, .. } if text.starts_with("PreArm") => {
                    Some(text.as_str())
                }
                _ => None,
            })
            .take(4)
            .collect();
        texts.dedup();
        Err(BackendError::Refused(format!(
            "the autopilot at {} did not pass its pre-arm checks within {:.0} s{}",
            self.link.url(),
            timeout.as_secs_f64(),
            if texts.is_empty() {
                String::new()
            } else {
                format!(": {}", texts.join("; "))
            }
        )))
    }

    /// Calls `tick` every few milliseconds until `done` holds (`true`) or `timeout` passes
    /// (`false`); a failed `tick` ends the wait with its error.
    fn wait_until(
        &mut self,
        timeout: Duration,
        done: impl Fn(&Self) -> bool,
        mut tick: impl FnMut(&mut Self) -> Result<(), BackendError>,
    ) -> Result<bool, BackendError> {
        let deadline = Instant::now() + timeout;
        while !done(self) {
            if Instant::now() >= deadline {
                return Ok(false);
            }
            tick(self)?;
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(true)
    }

    /// Waits for [`MavlinkDrone::uses_external_nav`], calling `tick` every few milliseconds
    /// meanwhile (to forward the motion capture); refused after `timeout`, with the EKF's
    /// flags.
    pub fn wait_for_external_nav(
        &mut self,
        timeout: Duration,
        tick: impl FnMut(&mut Self) -> Result<(), BackendError>,
    ) -> Result<(), BackendError> {
        if self.wait_until(timeout, Self::uses_external_nav, tick)? {
            return Ok(());
        }
        let flags = self.link.state().ekf_flags;
        Err(BackendError::Refused(format!(
            "the autopilot at {} did not report using the motion capture within {:.0} s \
             (EKF flags: {}): check VISO_TYPE and EK3_SRC1_*, that the motion capture reaches \
             it, and that the origin was set",
            self.link.url(),
            timeout.as_secs_f64(),
            flags.map_or("none received".into(), |f| format!("{f:#06x}"))
        )))
    }

    fn request_streams(&self) -> Result<(), BackendError> {
        for (id, hz) in STREAMS {
            let hz = if hz > 0.0 { hz } else { self.options.stream_hz };
            let msg = messages::message_interval(self.target, id, (1e6 / hz) as f32);
            self.link.send(&msg)?;
        }
        Ok(())
    }

    // -----------------------------------------------------------------------------------
    // Set-points.

    /// Follows the vehicle: the take-off's end, the autopilot's own mode changes, the
    /// landing's end, and the requests not yet seen in the heartbeat.
    fn update(&mut self) -> Result<(), BackendError> {
        let (hb, height) = {
            let s = self.link.state();
            let fresh = s
                .local_position
                .filter(|p| p.received.elapsed() < HEIGHT_FRESH);
            (s.heartbeat, fresh.map(|p| -p.ned_m[2]))
        };
        let Some(hb) = hb else { return Ok(()) };
        match self.phase {
            Phase::Arming if hb.custom_mode != copter_mode::GUIDED_NOGPS => {
                self.resend(|d| messages::set_mode(d.target, copter_mode::GUIDED_NOGPS))?
            }
            Phase::Arming if !hb.armed => self.resend(|d| messages::arm(d.target, true))?,
            Phase::Arming => {
                self.phase = Phase::TakingOff;
                self.yaw_target_rad = self.link.state().attitude_rad.map_or(0.0, |a| a[2]);
                self.yaw_rate_radps = 0.0;
                self.last_setpoint = None;
                self.send_climb()?;
            }
            Phase::TakingOff | Phase::Flying
                if hb.armed && hb.custom_mode != copter_mode::GUIDED_NOGPS =>
            {
                self.took_over = Some(hb.custom_mode);
                self.phase = Phase::Landing;
            }
            Phase::TakingOff
                if height.is_some_and(|h| h >= self.options.hover_height_m - HOVER_TOLERANCE_M) =>
            {
                self.phase = Phase::Flying;
                self.hover()?;
            }
            Phase::Landing if !hb.armed => self.phase = Phase::Ground,
            Phase::Landing if self.took_over.is_none() && hb.custom_mode != copter_mode::LAND => {
                self.resend(|d| messages::set_mode(d.target, copter_mode::LAND))?
            }
            Phase::Emergency if hb.armed => self.resend(|d| messages::force_disarm(d.target))?,
            _ => {}
        }
        Ok(())
    }

    /// Sends a request again when [`RESEND`] passed since the last.
    fn resend(
        &mut self,
        msg: impl Fn(&Self) -> mavlink::dialects::ardupilotmega::MavMessage,
    ) -> Result<(), BackendError> {
        if self.last_request.is_none_or(|t| t.elapsed() >= RESEND) {
            self.last_request = Some(Instant::now());
            self.link.send(&msg(self))?;
        }
        Ok(())
    }

    /// Integrates the yaw rate in force up to now and makes `rate` the one in force.
    fn advance_yaw(&mut self, rate_radps: f64) {
        let now = Instant::now();
        let dt_s = self.last_setpoint.map_or(0.0, |t| {
            now.duration_since(t).as_secs_f64().min(MAX_YAW_STEP_S)
        });
        let measured = self.link.state().attitude_rad.map(|a| a[2]);
        self.yaw_target_rad = match (measured, self.limits) {
            // Anchored on the vehicle's yaw: its angle controller (P = 1/lead) then turns it
            // at the rate asked, with no integral of past commands for it to catch up on.
            (Some(yaw), Some(limits)) => {
                let lead =
                    (rate_radps * limits.yaw_lead_s).clamp(-MAX_YAW_LEAD_RAD, MAX_YAW_LEAD_RAD);
                wrap_angle_rad(yaw + lead)
            }
            _ => wrap_angle_rad(self.yaw_target_rad + self.yaw_rate_radps * dt_s),
        };
        self.yaw_rate_radps = rate_radps;
        self.last_setpoint = Some(now);
    }

    fn send_target(&mut self, target: &AttitudeTarget) -> Result<(), BackendError> {
        let msg = messages::attitude_target(self.target, self.link.time_ms(), target);
        self.link.send(&msg)
    }

    /// The take-off's set-point: level, climbing while the EKF's height is known and below
    /// the hover height, holding the altitude otherwise.
    fn send_climb(&mut self) -> Result<(), BackendError> {
        let limits = self.limits()?;
        let height = self
            .link
            .state()
            .local_position
            .filter(|p| p.received.elapsed() < HEIGHT_FRESH)
            .map(|p| -p.ned_m[2]);
        let climbing = height.is_some_and(|h| h < self.options.hover_height_m);
        let vz = if climbing {
            self.options.take_off_climb_mps.min(limits.climb_max_mps)
        } else {
            0.0
        };
        self.advance_yaw(0.0);
        let thrust = thrust_for_climb(vz, limits.climb_max_mps, limits.descent_max_mps);
        let target = AttitudeTarget::new(0.0, 0.0, self.yaw_target_rad, 0.0, thrust);
        self.send_target(&target)
    }

    /// The command within the vehicle's limits: roll and pitch within ANGLE_MAX, the yaw
    /// rate within ATC_RATE_Y_MAX.
    fn clamped(command: &Command, limits: &VehicleLimits) -> Command {
        let tilt = limits.tilt_max_rad;
        let yaw = limits.yaw_rate_max_radps.unwrap_or(f64::INFINITY);
        Command {
            roll_rad: command.roll_rad.clamp(-tilt, tilt),
            pitch_rad: command.pitch_rad.clamp(-tilt, tilt),
            yaw_rate_radps: command.yaw_rate_radps.clamp(-yaw, yaw),
            vz_mps: command.vz_mps,
        }
    }

    /// The set-points fly only in the backend's own guided flight.
    fn flying_for_us(&self) -> bool {
        matches!(self.phase, Phase::TakingOff | Phase::Flying)
    }
}

impl Drone for MavlinkDrone {
    fn messages(&mut self, out: &mut Vec<DroneMessage>) {
        let mut state = self.link.state();
        if state.events.is_empty() {
            return;
        }
        out.extend(state.events.drain(..).map(|(_, e)| message_of(&e)));
    }

    /// The parameter check and the limits, GUIDED_NOGPS, arming, then the climb (module
    /// docs); refused, saying why, when any step fails.
    fn take_off(&mut self) -> Result<(), BackendError> {
        self.update()?;
        let armed = self.link.state().heartbeat.is_some_and(|h| h.armed);
        if self.flying_for_us() && armed {
            return Ok(());
        }
        let check = match &self.check {
            Some(c) if c.passed() => c.clone(),
            _ => self.check_parameters()?,
        };
        if !check.passed() {
            return Err(BackendError::Refused(check.refusal()));
        }
        self.limits()?;
        // The mode and the arming are asked here and again at every telemetry read until the
        // heartbeat shows them (`update`): the flight's loop goes on meanwhile, forwarding
        // the motion capture that the autopilot's pre-arm checks want fresh.
        self.phase = Phase::Arming;
        self.took_over = None;
        self.last_request = None;
        self.update()
    }

    /// LAND mode (re-sent until the heartbeat shows it); nothing when the autopilot chose
    /// its own mode.
    fn land(&mut self) -> Result<(), BackendError> {
        self.update()?;
        if self.took_over.is_some() || matches!(self.phase, Phase::Ground | Phase::Emergency) {
            return Ok(());
        }
        let armed = self.link.state().heartbeat.is_some_and(|h| h.armed);
        if self.phase == Phase::Arming && !armed {
            self.phase = Phase::Ground;
            return Ok(());
        }
        self.phase = Phase::Landing;
        self.last_request = Some(Instant::now());
        self.link
            .send(&messages::set_mode(self.target, copter_mode::LAND))
    }

    /// A forced disarm: the motors stop, in flight too.
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.phase = Phase::Emergency;
        self.last_request = Some(Instant::now());
        self.link.send(&messages::force_disarm(self.target))
    }

    fn send(&mut self, command: &Command) -> Result<(), BackendError> {
        if !command.is_finite() {
            return Err(BackendError::Refused(format!(
                "a command that is not a number: {command:?}"
            )));
        }
        self.update()?;
        if !self.flying_for_us() {
            return Ok(());
        }
        self.phase = Phase::Flying;
        let limits = self.limits()?;
        let command = Self::clamped(command, &limits);
        self.advance_yaw(command.yaw_rate_radps);
        let target = AttitudeTarget::from_command(
            &command,
            self.yaw_target_rad,
            limits.climb_max_mps,
            limits.descent_max_mps,
        );
        self.send_target(&target)
    }

    fn hover(&mut self) -> Result<(), BackendError> {
        if !self.flying_for_us() {
            return Ok(());
        }
        self.advance_yaw(0.0);
        self.send_target(&AttitudeTarget::level(self.yaw_target_rad))
    }

    fn telemetry(&mut self) -> Telemetry {
        // A failed send shows as the vehicle's silence: the link age tells the loop.
        let _ = self.update();
        if self.phase == Phase::TakingOff
            && self
                .last_setpoint
                .is_none_or(|t| t.elapsed() >= TAKE_OFF_KEEP_ALIVE)
        {
            let _ = self.send_climb();
        }
        let (hb, landed, battery) = {
            let s = self.link.state();
            (s.heartbeat, s.landed, s.battery_percent)
        };
        Telemetry {
            state: flight_state(self.phase, hb, landed),
            battery_percent: battery.unwrap_or(f64::NAN),
            link_age_s: self.link.link_age_s(),
        }
    }

    /// GIMBAL_MANAGER_SET_PITCHYAW, at most every [`GIMBAL_PERIOD`].
    fn point_camera(&mut self, pitch_rad: f64) -> Result<(), BackendError> {
        if !pitch_rad.is_finite() {
            return Err(BackendError::Refused(format!(
                "a camera pitch that is not a number: {pitch_rad}"
            )));
        }
        if self
            .last_gimbal
            .is_some_and(|(t, _)| t.elapsed() < GIMBAL_PERIOD)
        {
            return Ok(());
        }
        self.last_gimbal = Some((Instant::now(), pitch_rad));
        self.link
            .send(&messages::gimbal_pitch(self.target, pitch_rad))
    }

    fn camera_pitch_rad(&mut self) -> Option<f64> {
        self.link.state().gimbal_pitch_rad
    }
}

/// Sends `pose` as VISION_POSITION_ESTIMATE unless the last one (at `last_t_s`) went out less
/// than [`VISION_PERIOD_S`] before `t_s`: `true` when sent. Roll and pitch are the vehicle's
/// own (ATTITUDE): the motion capture gives the position and the heading.
fn send_vision(
    link: &Link,
    last_t_s: Option<f64>,
    t_s: f64,
    pose: &BodyPose,
) -> Result<bool, BackendError> {
    if last_t_s.is_some_and(|last| t_s - last < VISION_PERIOD_S) {
        return Ok(false);
    }
    let (ned_m, yaw_rad) = pose_to_ned(pose);
    let [roll, pitch, _] = link.state().attitude_rad.unwrap_or([0.0; 3]);
    let usec = (t_s.max(0.0) * 1e6) as u64;
    let msg = messages::vision_position(usec, ned_m, [roll, pitch, yaw_rad], 0);
    link.send(&msg)?;
    Ok(true)
}

/// Sends the motion capture's poses of the drone to the autopilot's EKF
/// ([`MavlinkDrone::forwarder`]), at most one per [`VISION_PERIOD_S`].
pub struct PoseForwarder {
    link: Arc<Link>,
    last_t_s: Option<f64>,
}

impl PoseForwarder {
    /// Sends the pose captured at `t_s` (the flight's clock) unless one went out less than
    /// [`VISION_PERIOD_S`] before: `true` when sent.
    pub fn forward(&mut self, t_s: f64, pose: &BodyPose) -> Result<bool, BackendError> {
        let sent = send_vision(&self.link, self.last_t_s, t_s, pose)?;
        if sent {
            self.last_t_s = Some(t_s);
        }
        Ok(sent)
    }
}

/// A vehicle event as the flight logs it: STATUSTEXT of severity error or worse (0–3) as
/// `error`, warning (4) as `warning`, the rest and the vehicle's changes as `info`.
pub fn message_of(e: &VehicleEvent) -> DroneMessage {
    match e {
        VehicleEvent::Text { severity, text } => DroneMessage {
            level: match severity {
                0..=3 => "error",
                4 => "warning",
                _ => "info",
            },
            text: format!("autopilot: {text}"),
        },
        VehicleEvent::Mode { from, to } => DroneMessage {
            level: "info",
            text: match from {
                Some(from) => format!(
                    "autopilot mode {} (was {})",
                    copter_mode::name(*to),
                    copter_mode::name(*from)
                ),
                None => format!("autopilot mode {}", copter_mode::name(*to)),
            },
        },
        VehicleEvent::Armed(armed) => DroneMessage {
            level: "info",
            text: if *armed { "armed" } else { "disarmed" }.into(),
        },
        VehicleEvent::EkfFlags(flags) => DroneMessage {
            level: "info",
            text: format!("EKF flags {flags:#06x}"),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The autopilot's texts keep their gravity in the flight's log; its changes are told.
    #[test]
    fn vehicle_events_become_the_flights_events() {
        let text = |severity| VehicleEvent::Text {
            severity,
            text: "EKF3 lane switch".into(),
        };
        assert_eq!(message_of(&text(2)).level, "error");
        assert_eq!(message_of(&text(4)).level, "warning");
        assert_eq!(message_of(&text(6)).level, "info");
        assert_eq!(message_of(&text(6)).text, "autopilot: EKF3 lane switch");
        let mode = VehicleEvent::Mode {
            from: Some(copter_mode::GUIDED_NOGPS),
            to: copter_mode::LAND,
        };
        assert_eq!(
            message_of(&mode).text,
            "autopilot mode LAND (was GUIDED_NOGPS)"
        );
        assert_eq!(message_of(&VehicleEvent::Armed(false)).text, "disarmed");
    }

    fn hb(mode: u32, armed: bool) -> Option<Heartbeat> {
        Some(Heartbeat {
            custom_mode: mode,
            armed,
            system_status: 4,
            vehicle_type: 2,
            autopilot: 3,
        })
    }

    #[test]
    fn the_flight_state_follows_the_phase_and_the_vehicle() {
        use copter_mode::{GUIDED_NOGPS, LAND, RTL};
        use FlightState as F;
        let cases = [
            (Phase::Ground, None, None, F::Landed),
            (Phase::Ground, hb(0, false), None, F::Landed),
            (Phase::TakingOff, hb(GUIDED_NOGPS, true), None, F::TakingOff),
            (Phase::Flying, hb(GUIDED_NOGPS, true), None, F::Flying),
            // The autopilot left GUIDED_NOGPS by itself: landing.
            (Phase::Flying, hb(RTL, true), None, F::Landing),
            (Phase::TakingOff, hb(LAND, true), None, F::Landing),
            (
                Phase::Landing,
                hb(LAND, true),
                Some(LandedState::OnGround),
                F::Landing,
            ),
            (
                Phase::Landing,
                hb(LAND, false),
                Some(LandedState::OnGround),
                F::Landed,
            ),
            (Phase::Flying, hb(GUIDED_NOGPS, false), None, F::Landed),
            (Phase::Emergency, hb(GUIDED_NOGPS, true), None, F::Emergency),
            (
                Phase::Emergency,
                hb(GUIDED_NOGPS, false),
                None,
                F::Emergency,
            ),
            // Flown by someone else: what the vehicle says.
            (
                Phase::Ground,
                hb(GUIDED_NOGPS, true),
                Some(LandedState::InAir),
                F::Flying,
            ),
            (
                Phase::Ground,
                hb(5, true),
                Some(LandedState::InAir),
                F::Landing,
            ),
            (
                Phase::Ground,
                hb(5, true),
                Some(LandedState::OnGround),
                F::Landed,
            ),
        ];
        for (phase, heartbeat, landed, want) in cases {
            assert_eq!(
                flight_state(phase, heartbeat, landed),
                want,
                "{phase:?} {heartbeat:?} {landed:?}"
            );
        }
    }

    #[test]
    fn commands_are_clamped_to_the_vehicles_limits() {
        let limits = VehicleLimits::from_values(250.0, 150.0, 2000.0, 45.0, 3.0).unwrap();
        let c = MavlinkDrone::clamped(
            &Command {
                roll_rad: 1.0,
                pitch_rad: -1.0,
                yaw_rate_radps: 3.0,
                vz_mps: 9.0,
            },
            &limits,
        );
        assert!((c.roll_rad - 20f64.to_radians()).abs() < 1e-12);
        assert!((c.pitch_rad + 20f64.to_radians()).abs() < 1e-12);
        assert!((c.yaw_rate_radps - 45f64.to_radians()).abs() < 1e-12);
        assert_eq!(c.vz_mps, 9.0);
    }
}
