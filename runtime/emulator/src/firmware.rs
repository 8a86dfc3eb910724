//! The emulated AR.Drone 2.0 firmware: what the drone does with AT commands and what it puts
//! in its navdata, over any [`Drone`] (the embedded simulator's). No sockets, no threads: the
//! emulator's loop feeds it datagrams and asks it for packets.
//!
//! **AT commands**. Each datagram is parsed line by line with the tolerant parser
//! (`ardrone::at::parse_datagram`); a bad line is counted and skipped, the others still act.
//! The sequence rule: a line whose seq is not larger than the last accepted one is
//! dropped; seq 1 always resets the counter; after [`SEQ_RESET_SILENCE_S`] without an
//! accepted line any seq is accepted (the drone forgot the client). One counter for every
//! command kind and every sender.
//!
//! - `REF` (only bits 8 and 9 are read): bit 9 set → take off (when landed), clear →
//!   land (when flying or taking off); it is level-triggered, as clients repeat REF until the
//!   navdata confirms. Bit 8 is the emergency *toggle*, acting on its rising edge (a client
//!   repeats the same REF every tick): in emergency it clears the emergency, otherwise it cuts
//!   the motors (in flight or on the ground, like the real drone's SELECT button).
//! - `PCMD` / `PCMD_MAG`: flag bit 0 set → the four values times the limits
//!   (`control:euler_angle_max` for roll and pitch, `control:control_vz_max` for gaz,
//!   `control:control_yaw` for yaw), each clamped to [−1, 1], as a [`Command`] (same signs,
//!   `frames.rs`); flag bit 0 clear → the drone's own hover. A non-finite value rejects the
//!   line. `PCMD_MAG`'s psi and the absolute-control flag are ignored (no magnetometer).
//! - `FTRIM`: accepted on the ground, ignored in flight. `CALIB`: accepted, no effect.
//! - `CONFIG`: the value is stored and the command-ACK state bit (6) is set until
//!   `CTRL=…,5,0` clears it (the client's configuration handshake). Values that act:
//!   `general:navdata_demo` (TRUE/FALSE), the three limits above (in the units of the
//!   firmware's `config.ini`: rad, mm/s, rad/s; values outside the documented ranges are
//!   refused and counted), and `general:com_watchdog` (seconds, 1–60). `CONFIG_IDS` is
//!   accepted and ignored (no multi-configuration check).
//! - `CTRL`: mode 5 clears the ACK bit; mode 4 (config file on TCP 5559) is not emulated.
//! - `COMWDG` clears the com-watchdog state bit (30), which is set at boot (the bootstrap
//!   packet has it) and again after `general:com_watchdog` seconds (default 2) without an
//!   accepted AT line; the simulator's own watchdog then makes the drone hover.
//!
//! **Navdata**. Bootstrap packets (header + checksum, state bit 11) until
//! `general:navdata_demo` is configured; then, with TRUE, demo packets (demo option) at
//! 15 Hz and state bit 10; with FALSE, full packets (demo and time options: the other
//! options are not emulated) at 200 Hz. The sequence number starts at 1 and increases by one
//! per packet sent, for the emulator's life. Demo option values, from the simulator's truth:
//!
//! - `ctrl_state`: landed → LANDED; taking off → TRANS_TAKEOFF/1 (AUTO); flying a
//!   progressive command → FLYING/0; flying on the drone's own hover → HOVERING/0, or
//!   HOVERING/8 (LOST_COM) while the com-watchdog bit is set; landing → TRANS_LANDING/0;
//!   emergency → DEFAULT/0 (state bit 31 says why).
//! - `theta` = pitch, `phi` = roll, in millidegrees, in the AR.Drone's signs (the ones of
//!   `frames::Command`: nose up and right side down positive). `psi` = −heading in
//!   millidegrees in (−180000, 180000]: the AR.Drone's yaw is clockwise-positive seen from
//!   above, `frames.rs`'s heading counter-clockwise; its zero is the world +x axis
//!   (a real drone's psi zero is arbitrary: clients must not rely on it).
//! - `altitude` in mm (what the drone sends in practice), the true height above the floor.
//! - `vx, vy, vz` in mm/s in the body-horizontal frame: forward, left, up (the frame of
//!   `frames.rs`; ardrone_autonomy copies vx, vy straight into a ROS x-forward, y-left twist;
//!   the SDK headers name no frame).
//! - battery = the true charge in percent, rounded; state bit 15 (battery low) below the
//!   simulator's take-off minimum.
//!
//! Other state bits: 0 flying (taking off, flying, landing), 4 altitude control (flying),
//! 6 command ACK, 10 navdata demo, 11 bootstrap, 23–27 PIC version and the firmware's
//! threads (always on, as in a real drone's bootstrap packet), 30 com watchdog, 31 emergency.

use dronecine_math as math;
use std::collections::BTreeMap;

use dronecine_ardrone::at::{
    self, AtCommand, AtLine, Pcmd, CONTROL_VZ_MAX_RANGE_MPS, CONTROL_YAW_RANGE_RADPS, CTRL_ACK,
    EULER_ANGLE_MAX_RANGE_RAD, KEY_CONTROL_VZ_MAX, KEY_CONTROL_YAW, KEY_EULER_ANGLE_MAX,
};
use dronecine_ardrone::navdata::{
    ControlState, Demo, DroneState, MajorState, NavTime, NavdataError, NavdataWriter,
};
use dronecine_backend::frames::{self, Command};
use dronecine_backend::{Drone, FlightState};
use dronecine_sim::Truth;

/// Without an accepted AT line for this long, any sequence number is accepted again.
pub const SEQ_RESET_SILENCE_S: f64 = 2.0;
/// Navdata rate in demo mode.
pub const DEMO_RATE_HZ: f64 = 15.0;
/// Navdata rate with `navdata_demo` FALSE.
pub const FULL_RATE_HZ: f64 = 200.0;
/// Default `general:com_watchdog`.
pub const COM_WATCHDOG_DEFAULT_S: f64 = 2.0;
/// The firmware's defaults for the three limits (fw 2.4.8 `config.ini`).
pub const DEFAULT_EULER_ANGLE_MAX_RAD: f64 = 0.2094;
pub const DEFAULT_CONTROL_VZ_MAX_MPS: f64 = 0.7;
pub const DEFAULT_CONTROL_YAW_RADPS: f64 = 1.7453;
/// At most this many distinct configuration keys are stored (a flood of new keys is counted
/// and dropped instead of growing memory).
pub const MAX_CONFIG_KEYS: usize = 512;

const KEY_NAVDATA_DEMO: &str = "general:navdata_demo";
const KEY_COM_WATCHDOG: &str = "general:com_watchdog";

/// State bits that are always on: PIC version OK and the firmware's threads.
const BASE_STATE: u32 = DroneState::PIC_VERSION_OK
    | DroneState::ATCODEC_THREAD_ON
    | DroneState::NAVDATA_THREAD_ON
    | DroneState::VIDEO_THREAD_ON
    | DroneState::ACQUISITION_THREAD_ON;

/// What kind of navdata the drone streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NavdataMode {
    /// Header and checksum only (state bit 11), until `general:navdata_demo` is configured.
    Bootstrap,
    /// `navdata_demo` TRUE: the demo option at 15 Hz.
    Demo,
    /// `navdata_demo` FALSE: demo and time options at 200 Hz.
    Full,
}

impl NavdataMode {
    pub fn rate_hz(self) -> f64 {
        match self {
            NavdataMode::Bootstrap | NavdataMode::Demo => DEMO_RATE_HZ,
            NavdataMode::Full => FULL_RATE_HZ,
        }
    }
}

/// Counts of what the AT side did with the lines it received.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AtCounters {
    pub datagrams: u64,
    /// Lines parsed and accepted by the sequence rule.
    pub accepted: u64,
    /// Lines that do not parse (or carry a non-finite PCMD value).
    pub rejected: u64,
    /// Valid lines dropped by the sequence rule (old, duplicated or replayed).
    pub stale: u64,
    /// CONFIG lines whose value was refused (out of range, not a number, too many keys).
    pub config_refused: u64,
    /// Take-off requests the drone refused (battery, emergency).
    pub refused_take_offs: u64,
    /// REF lines that asked a flying (or taking-off) drone to land.
    pub land_requests: u64,
    /// REF lines whose emergency toggle cut the motors.
    pub motor_cuts: u64,
}

/// What the emulator must do after a datagram beyond what the firmware did itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// The emergency was toggled off: the simulated drone must be rebuilt where it stands
    /// (the simulator cannot leave its emergency state).
    pub clear_emergency: bool,
}

/// The three firmware limits PCMD values are fractions of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub euler_angle_max_rad: f64,
    pub control_vz_max_mps: f64,
    pub control_yaw_radps: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            euler_angle_max_rad: DEFAULT_EULER_ANGLE_MAX_RAD,
            control_vz_max_mps: DEFAULT_CONTROL_VZ_MAX_MPS,
            control_yaw_radps: DEFAULT_CONTROL_YAW_RADPS,
        }
    }
}

impl Limits {
    /// The command a progressive PCMD asks for; `None` when a value is not finite.
    pub fn command(&self, p: &Pcmd) -> Option<Command> {
        let v = [p.roll, p.pitch, p.gaz, p.yaw].map(f64::from);
        if !v.iter().all(|x| x.is_finite()) {
            return None;
        }
        let c = |x: f64| x.clamp(-1.0, 1.0);
        Some(Command {
            roll_rad: c(v[0]) * self.euler_angle_max_rad,
            pitch_rad: c(v[1]) * self.euler_angle_max_rad,
            vz_mps: c(v[2]) * self.control_vz_max_mps,
            yaw_rate_radps: c(v[3]) * self.control_yaw_radps,
        })
    }
}

/// The emulated firmware's state.
#[derive(Debug)]
pub struct Firmware {
    last_seq: u32,
    /// Wall time of the last accepted line (`None` before the first).
    last_at_s: Option<f64>,
    limits: Limits,
    config: BTreeMap<String, String>,
    ack: bool,
    com_watchdog: bool,
    com_watchdog_s: f64,
    mode: NavdataMode,
    /// The last accepted REF input (bit 8 acts on its rising edge).
    prev_ref: u32,
    battery_low_percent: f64,
    nav_seq: u32,
    counters: AtCounters,
}

impl Firmware {
    /// A freshly booted drone: bootstrap navdata, com-watchdog bit set, default limits.
    /// `battery_low_percent`: below it state bit 15 is set.
    pub fn new(battery_low_percent: f64) -> Self {
        Firmware {
            last_seq: 0,
            last_at_s: None,
            limits: Limits::default(),
            config: BTreeMap::new(),
            ack: false,
            com_watchdog: true,
            com_watchdog_s: COM_WATCHDOG_DEFAULT_S,
            mode: NavdataMode::Bootstrap,
            prev_ref: 0,
            battery_low_percent,
            nav_seq: 0,
            counters: AtCounters::default(),
        }
    }

    pub fn counters(&self) -> AtCounters {
        self.counters
    }

    pub fn limits(&self) -> Limits {
        self.limits
    }

    pub fn navdata_mode(&self) -> NavdataMode {
        self.mode
    }

    pub fn command_ack(&self) -> bool {
        self.ack
    }

    pub fn com_watchdog(&self) -> bool {
        self.com_watchdog
    }

    /// A stored configuration value.
    pub fn config(&self, key: &str) -> Option<&str> {
        self.config.get(key).map(String::as_str)
    }

    /// The sequence number of the last navdata packet written (0 before the first).
    pub fn navdata_sequence(&self) -> u32 {
        self.nav_seq
    }

    /// Time passes (`now_s`, the wall clock): raises the com-watchdog bit after
    /// `general:com_watchdog` seconds without an accepted line.
    pub fn tick(&mut self, now_s: f64) {
        if let Some(t) = self.last_at_s {
            if now_s - t > self.com_watchdog_s {
                self.com_watchdog = true;
            }
        }
    }

    /// Handles one AT datagram received at `now_s` (wall seconds). Never panics.
    pub fn datagram<D: Drone>(&mut self, bytes: &[u8], now_s: f64, drone: &mut D) -> Outcome {
        self.counters.datagrams += 1;
        let mut out = Outcome::default();
        for line in at::parse_datagram(bytes) {
            match line {
                Ok(line) => self.line(&line, now_s, drone, &mut out),
                Err(_) => self.counters.rejected += 1,
            }
        }
        out
    }

    fn sequence_ok(&mut self, seq: u32, now_s: f64) -> bool {
        let silent = self
            .last_at_s
            .is_none_or(|t| now_s - t > SEQ_RESET_SILENCE_S);
        if seq == 1 || silent || seq > self.last_seq {
            self.last_seq = seq;
            self.last_at_s = Some(now_s);
            true
        } else {
            false
        }
    }

    fn line<D: Drone>(&mut self, line: &AtLine<'_>, now_s: f64, drone: &mut D, out: &mut Outcome) {
        // A PCMD with a NaN is a bad line, whatever its seq.
        let pcmd = match line.command {
            AtCommand::Pcmd(p) | AtCommand::PcmdMag { pcmd: p, .. } => {
                if p.is_hover() {
                    Some(None)
                } else {
                    match self.limits.command(&p) {
                        Some(c) => Some(Some(c)),
                        None => {
                            self.counters.rejected += 1;
                            return;
                        }
                    }
                }
            }
            _ => None,
        };
        if !self.sequence_ok(line.seq, now_s) {
            self.counters.stale += 1;
            return;
        }
        self.counters.accepted += 1;
        let state = drone.telemetry().state;
        match line.command {
            AtCommand::Ref { input } => {
                let rising = at::ref_emergency(input) && !at::ref_emergency(self.prev_ref);
                self.prev_ref = input;
                if rising {
                    if state == FlightState::Emergency {
                        out.clear_emergency = true;
                    } else {
                        let _ = drone.emergency();
                        self.counters.motor_cuts += 1;
                    }
                    return;
                }
                if state == FlightState::Emergency || out.clear_emergency {
                    return;
                }
                if at::ref_take_off(input) {
                    if matches!(state, FlightState::Landed | FlightState::Landing)
                        && drone.take_off().is_err()
                    {
                        self.counters.refused_take_offs += 1;
                    }
                } else if matches!(state, FlightState::Flying | FlightState::TakingOff) {
                    let _ = drone.land();
                    self.counters.land_requests += 1;
                }
            }
            AtCommand::Pcmd(_) | AtCommand::PcmdMag { .. } => match pcmd {
                Some(Some(c)) => {
                    let _ = drone.send(&c);
                }
                _ => {
                    let _ = drone.hover();
                }
            },
            AtCommand::Config { key, value } => {
                self.ack = true;
                self.configure(key, value);
            }
            AtCommand::Ctrl { mode, .. } => {
                if mode == CTRL_ACK {
                    self.ack = false;
                }
            }
            AtCommand::Comwdg => self.com_watchdog = false,
            AtCommand::Ftrim | AtCommand::Calib { .. } | AtCommand::ConfigIds { .. } => {}
        }
    }

    fn configure(&mut self, key: &str, value: &str) {
        let num = value.trim().parse::<f64>().ok().filter(|v| v.is_finite());
        let in_range =
            |v: Option<f64>, (lo, hi): (f64, f64)| v.filter(|v| *v > 0.0 && (lo..=hi).contains(v));
        let applied = match key {
            KEY_NAVDATA_DEMO => match value.trim().to_ascii_uppercase().as_str() {
                "TRUE" => {
                    self.mode = NavdataMode::Demo;
                    true
                }
                "FALSE" => {
                    self.mode = NavdataMode::Full;
                    true
                }
                _ => false,
            },
            KEY_EULER_ANGLE_MAX => in_range(num, EULER_ANGLE_MAX_RANGE_RAD)
                .map(|v| self.limits.euler_angle_max_rad = v)
                .is_some(),
            KEY_CONTROL_VZ_MAX => {
                let mm = CONTROL_VZ_MAX_RANGE_MPS;
                in_range(num, (mm.0 * 1000.0, mm.1 * 1000.0))
                    .map(|v| self.limits.control_vz_max_mps = v / 1000.0)
                    .is_some()
            }
            KEY_CONTROL_YAW => in_range(num, CONTROL_YAW_RANGE_RADPS)
                .map(|v| self.limits.control_yaw_radps = v)
                .is_some(),
            KEY_COM_WATCHDOG => in_range(num, (1.0, 60.0))
                .map(|v| self.com_watchdog_s = v)
                .is_some(),
            _ => true,
        };
        if !applied {
            self.counters.config_refused += 1;
            return;
        }
        if self.config.len() >= MAX_CONFIG_KEYS && !self.config.contains_key(key) {
            self.counters.config_refused += 1;
            return;
        }
        self.config.insert(key.to_string(), value.to_string());
    }

    /// The state word for the drone's current flight state.
    pub fn state_bits(&self, state: FlightState, battery_percent: f64) -> DroneState {
        let mut s = BASE_STATE;
        if matches!(
            state,
            FlightState::TakingOff | FlightState::Flying | FlightState::Landing
        ) {
            s |= DroneState::FLYING | DroneState::ALTITUDE_CONTROL_ACTIVE;
        }
        if state == FlightState::Emergency {
            s |= DroneState::EMERGENCY;
        }
        if self.ack {
            s |= DroneState::COMMAND_ACK;
        }
        if self.com_watchdog {
            s |= DroneState::COM_WATCHDOG;
        }
        match self.mode {
            NavdataMode::Bootstrap => s |= DroneState::NAVDATA_BOOTSTRAP,
            NavdataMode::Demo => s |= DroneState::NAVDATA_DEMO,
            NavdataMode::Full => {}
        }
        if battery_percent < self.battery_low_percent {
            s |= DroneState::BATTERY_LOW;
        }
        DroneState(s)
    }

    /// The control state. `commanded`: the drone flies a progressive command (not its
    /// own hover).
    pub fn control_state(&self, state: FlightState, commanded: bool) -> ControlState {
        let (major, minor) = match state {
            FlightState::Landed => (MajorState::Landed, 0),
            FlightState::TakingOff => (MajorState::TransTakeoff, 1),
            FlightState::Flying if commanded => (MajorState::Flying, 0),
            FlightState::Flying if self.com_watchdog => (MajorState::Hovering, 8),
            FlightState::Flying => (MajorState::Hovering, 0),
            FlightState::Landing => (MajorState::TransLanding, 0),
            FlightState::Emergency => (MajorState::Default, 0),
        };
        ControlState { major, minor }
    }

    /// Writes the next navdata packet (the current mode's) into `buf`; returns its length.
    /// `commanded` as in [`Firmware::control_state`]; `drone_time_s` for the time option.
    pub fn navdata(
        &mut self,
        truth: &Truth,
        commanded: bool,
        drone_time_s: f64,
        buf: &mut [u8],
    ) -> Result<usize, NavdataError> {
        let state = self.state_bits(truth.state, truth.battery_percent);
        let seq = self.nav_seq.wrapping_add(1).max(1);
        let mut w = NavdataWriter::new(buf, state, seq, 0)?;
        if self.mode != NavdataMode::Bootstrap {
            w.demo(&self.demo(truth, commanded))?;
        }
        if self.mode == NavdataMode::Full {
            let t = drone_time_s.max(0.0);
            let secs = (t.floor() as u64 & 0x7FF) as u32;
            let micros = ((t.fract() * 1e6) as u32).min(999_999);
            w.time(NavTime::from_parts(secs, micros))?;
        }
        let n = w.finish()?;
        self.nav_seq = seq;
        Ok(n)
    }

    fn demo(&self, t: &Truth, commanded: bool) -> Demo {
        const MDEG_PER_RAD: f64 = 180_000.0 / std::f64::consts::PI;
        // World velocity → body (forward, left, up): Rz(−c).
        let (s, c) = math::sin_cos(t.heading_rad);
        let [vx, vy, vz] = t.velocity_mps;
        let fwd = c * vx + s * vy;
        let left = -s * vx + c * vy;
        let psi = frames::wrap_angle_rad(-t.heading_rad);
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        Demo {
            ctrl_state: self.control_state(t.state, commanded),
            battery_percent: finite(t.battery_percent).round().clamp(0.0, 100.0) as u32,
            theta_mdeg: (finite(t.pitch_rad) * MDEG_PER_RAD) as f32,
            phi_mdeg: (finite(t.roll_rad) * MDEG_PER_RAD) as f32,
            psi_mdeg: (finite(psi) * MDEG_PER_RAD) as f32,
            altitude_mm: (finite(t.position_m[2]) * 1000.0).round() as i32,
            vx_mmps: (finite(fwd) * 1000.0) as f32,
            vy_mmps: (finite(left) * 1000.0) as f32,
            vz_mmps: (finite(vz) * 1000.0) as f32,
            num_frames: 0,
        }
    }
}
