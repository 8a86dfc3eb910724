//! The emulated Crazyflie firmware: what a Crazyflie does with the CRTP packets a client
//! sends, over any [`Drone`] (the embedded simulator's), and the packets it sends back. No
//! sockets, no threads: the Crazyflie emulator's loop feeds it datagrams and asks it for
//! its log samples.
//!
//! - **Platform**: the protocol version asked is answered ([`CrazyflieFirmware::new`]'s,
//!   12 by default: the altHold yaw rate counter-clockwise positive; 8 and before clockwise,
//!   `dronecine_crazyflie::frames`).
//! - **Log**: a TOC of [`TOC`]'s variables (v2 commands); up to [`MAX_BLOCKS`] blocks of up
//!   to 26 bytes created, started (at their period), stopped, deleted and reset, each
//!   command answered `[command, block, errno]` as the firmware does (ENOENT for an unknown
//!   block or variable, EEXIST for a block that exists, E2BIG for one too large). Values:
//!   `stateEstimate.*` the estimator's (below), `stabilizer.roll/pitch` the true attitude in
//!   degrees (the firmware's signs: right side down and nose up positive), `stabilizer.yaw`
//!   the true heading in degrees, `pm.batteryLevel` the true charge, `pm.vbat` 3.0 V empty to
//!   4.2 V full, `pm.state` 3 (low) below 10 %, `supervisor.info` its bits; the others 0.
//! - **Parameters** written by name: `stabilizer.estimator` and `kalman.resetEstimation`
//!   (unsigned bytes), answered with the errno (ENOENT for another name, EINVAL for another
//!   type).
//! - **Estimator**: with the Kalman estimator (2) and an external pose in the last
//!   [`EXT_POSE_FRESH_S`], the estimate is the simulator's true position; otherwise it stays
//!   where it was (at first the stage's origin), as an estimator without its position
//!   source drifts off.
//! - **Set-points** (the generic commander): altHold becomes the command it means; a
//!   landed drone whose motors start climbing (a positive climb rate) takes off, the
//!   simulator's own lift-off to its take-off height, then flies the climb rates asked. A
//!   position set-point holds (the simulator's hover). Stop: on the floor (below 5 cm) the
//!   drone is landed; in the air its motors are cut and it falls, and once it rests on the
//!   floor it is landed again ([`Outcome::rest`]). Arming requests arm it; it arms itself
//!   at its first set-point anyway (auto-arm, as a Crazyflie 2.1).
//! - **Watchdog**: without a set-point for 0.5 s in the air the simulator's own watchdog
//!   levels it out (its hover: `SimConfig::watchdog_s` is set so); after 2 s the motors stop
//!   and the supervisor locks it (bit 6) until the emulator restarts, as the firmware's.
//!
//! Every datagram goes through `dronecine_crazyflie::crtp`'s decoders; a bad one is counted
//! ([`CrazyflieCounters::rejected`]) and dropped.

use dronecine_backend::{Drone, FlightState};
use dronecine_crazyflie::crtp::{self, log_cmd, FromDrone, Packet, ToDrone};
use dronecine_crazyflie::frames::{self, AltHold, YawRateSign};
use dronecine_crazyflie::log::{encode_value, supervisor, Field};
use dronecine_sim::Truth;

/// The log TOC: every variable the backend reads, and others a Crazyflie logs.
pub const TOC: &[(&str, &str, u8)] = &[
    ("acc", "x", crtp::log_type::FLOAT),
    ("acc", "y", crtp::log_type::FLOAT),
    ("acc", "z", crtp::log_type::FLOAT),
    ("pm", "vbat", crtp::log_type::FLOAT),
    ("pm", "vbatMV", crtp::log_type::UINT16),
    ("pm", "state", crtp::log_type::INT8),
    ("pm", "batteryLevel", crtp::log_type::UINT8),
    ("stabilizer", "roll", crtp::log_type::FLOAT),
    ("stabilizer", "pitch", crtp::log_type::FLOAT),
    ("stabilizer", "yaw", crtp::log_type::FLOAT),
    ("stabilizer", "thrust", crtp::log_type::FLOAT),
    ("stateEstimate", "x", crtp::log_type::FLOAT),
    ("stateEstimate", "y", crtp::log_type::FLOAT),
    ("stateEstimate", "z", crtp::log_type::FLOAT),
    ("stateEstimate", "vx", crtp::log_type::FLOAT),
    ("stateEstimate", "vy", crtp::log_type::FLOAT),
    ("stateEstimate", "vz", crtp::log_type::FLOAT),
    ("supervisor", "info", crtp::log_type::UINT16),
    ("sys", "canfly", crtp::log_type::UINT8),
];

/// The TOC's CRC as announced (a client caches a TOC by it).
pub const TOC_CRC: u32 = 0x4446_4331;
/// The firmware's limit of log blocks.
pub const MAX_BLOCKS: usize = 16;
/// An external pose older than this no longer steers the estimate.
pub const EXT_POSE_FRESH_S: f64 = 0.5;
/// Without a set-point for this long in the air, the motors stop and the supervisor locks.
pub const WATCHDOG_SHUTDOWN_S: f64 = 2.0;
/// A stop below this height is a landing.
const ON_THE_FLOOR_M: f64 = 0.05;
const ENOENT: u8 = 2;
const E2BIG: u8 = 7;
const EEXIST: u8 = 17;
const EINVAL: u8 = 22;
const ENOMEM: u8 = 12;
const KALMAN: u8 = 2;

/// One log block: its variables (fetch type, TOC index), its period, when it is next due.
#[derive(Clone, Debug, PartialEq)]
struct Block {
    id: u8,
    ops: Vec<(u8, u16)>,
    period_s: Option<f64>,
    next_s: f64,
}

/// What the firmware did with the datagrams it received.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CrazyflieCounters {
    pub datagrams: u64,
    /// Datagrams that are not CRTP packets, or packets that are not what their port says.
    pub rejected: u64,
    /// Well-formed packets the emulator does not act on (other ports, other set-points).
    pub unsupported: u64,
    pub alt_holds: u64,
    pub positions: u64,
    pub stops: u64,
    pub ext_poses: u64,
    pub samples_sent: u64,
}

/// What the emulator must do after a datagram or a tick beyond what the firmware did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// The drone whose motors were cut rests on the floor: rebuild the simulator there,
    /// landed (it cannot leave its emergency state itself).
    pub rest: bool,
}

/// The emulated firmware's state (module docs).
#[derive(Debug)]
pub struct CrazyflieFirmware {
    protocol: u8,
    yaw: YawRateSign,
    blocks: Vec<Block>,
    estimator: u8,
    reset_estimation: u8,
    estimate_m: [f64; 3],
    last_ext_pose_s: Option<f64>,
    last_setpoint_s: Option<f64>,
    armed: bool,
    locked: bool,
    /// The motors were cut in the air: the world is rebuilt once the drone rests.
    falling: bool,
    counters: CrazyflieCounters,
}

impl CrazyflieFirmware {
    /// A Crazyflie speaking CRTP protocol `protocol`.
    pub fn new(protocol: u8) -> CrazyflieFirmware {
        CrazyflieFirmware {
            protocol,
            yaw: YawRateSign::of_protocol(protocol),
            blocks: Vec::new(),
            estimator: 1,
            reset_estimation: 0,
            estimate_m: [0.0; 3],
            last_ext_pose_s: None,
            last_setpoint_s: None,
            armed: false,
            locked: false,
            falling: false,
            counters: CrazyflieCounters::default(),
        }
    }

    pub fn counters(&self) -> CrazyflieCounters {
        self.counters
    }

    /// Whether the supervisor locked the drone (its watchdog stopped the motors in the air).
    pub fn locked(&self) -> bool {
        self.locked
    }

    /// The estimator chosen (`stabilizer.estimator`).
    pub fn estimator(&self) -> u8 {
        self.estimator
    }

    /// Acts on one datagram received at `now_s` (wall seconds), the answers pushed to `out`.
    pub fn datagram(
        &mut self,
        bytes: &[u8],
        now_s: f64,
        drone: &mut dyn Drone,
        truth: &Truth,
        out: &mut Vec<Packet>,
    ) {
        self.counters.datagrams += 1;
        let packet = match Packet::from_bytes(bytes) {
            Ok(p) => p,
            Err(_) => {
                self.counters.rejected += 1;
                return;
            }
        };
        match ToDrone::decode(&packet) {
            Ok(m) => self.act(&m, now_s, drone, truth, out),
            Err(_) => self.counters.rejected += 1,
        }
    }

    fn act(
        &mut self,
        m: &ToDrone,
        now_s: f64,
        drone: &mut dyn Drone,
        truth: &Truth,
        out: &mut Vec<Packet>,
    ) {
        let mut reply = |m: FromDrone| {
            if let Ok(p) = m.encode() {
                out.push(p);
            }
        };
        match *m {
            ToDrone::AltHold {
                roll_deg,
                pitch_deg,
                yaw_rate_degps,
                vz_mps,
            } => {
                let sp = AltHold {
                    roll_deg,
                    pitch_deg,
                    yaw_rate_degps,
                    vz_mps,
                };
                self.counters.alt_holds += 1;
                self.alt_hold(&sp, now_s, drone, truth);
            }
            ToDrone::Position { .. } => {
                self.counters.positions += 1;
                if self.setpoint(now_s) && truth.state == FlightState::Flying {
                    let _ = drone.hover();
                }
            }
            ToDrone::Stop => {
                self.counters.stops += 1;
                self.stop(drone, truth);
            }
            ToDrone::ExtPose { .. } => {
                self.counters.ext_poses += 1;
                self.last_ext_pose_s = Some(now_s);
            }
            ToDrone::ProtocolVersion => reply(FromDrone::ProtocolVersion(self.protocol)),
            ToDrone::LogTocInfo => reply(FromDrone::LogTocInfo {
                count: TOC.len() as u16,
                crc: TOC_CRC,
            }),
            ToDrone::LogTocItem(i) => reply(match TOC.get(usize::from(i)) {
                Some(&(group, name, kind)) => FromDrone::LogTocItem {
                    index: i,
                    kind,
                    group,
                    name,
                },
                None => FromDrone::LogTocEnd,
            }),
            ToDrone::LogReset => {
                self.blocks.clear();
                reply(log_ack(log_cmd::RESET, 0, 0));
            }
            ToDrone::LogCreate { block, ops } => {
                let error = self.create(block, ops.iter().collect());
                reply(log_ack(log_cmd::CREATE_BLOCK_V2, block, error));
            }
            ToDrone::LogStart { block, period_10ms } => {
                let error = self.with_block(block, |b| {
                    b.period_s = (period_10ms > 0).then(|| f64::from(period_10ms) * 0.01);
                    b.next_s = now_s;
                });
                reply(log_ack(log_cmd::START, block, error));
            }
            ToDrone::LogStop(block) => {
                let error = self.with_block(block, |b| b.period_s = None);
                reply(log_ack(log_cmd::STOP, block, error));
            }
            ToDrone::LogDelete(block) => {
                let before = self.blocks.len();
                self.blocks.retain(|b| b.id != block);
                let error = if self.blocks.len() < before {
                    0
                } else {
                    ENOENT
                };
                reply(log_ack(log_cmd::DELETE_BLOCK, block, error));
            }
            ToDrone::SetParam {
                group,
                name,
                kind,
                value,
            } => {
                let error = self.set_param(group, name, kind, value);
                reply(FromDrone::ParamSet { group, name, error });
            }
            ToDrone::Arm { arm, .. } => self.armed = arm && !self.locked,
            ToDrone::Other { .. } => self.counters.unsupported += 1,
        }
    }

    /// Notes a set-point at `now_s` and arms (auto-arm); `false` while locked (ignored).
    fn setpoint(&mut self, now_s: f64) -> bool {
        if self.locked {
            return false;
        }
        self.last_setpoint_s = Some(now_s);
        self.armed = true;
        true
    }

    fn alt_hold(&mut self, sp: &AltHold, now_s: f64, drone: &mut dyn Drone, truth: &Truth) {
        if !self.setpoint(now_s) {
            return;
        }
        let command = frames::command_of(sp, self.yaw);
        match truth.state {
            FlightState::Landed if command.vz_mps > 0.0 && command.is_finite() => {
                let _ = drone.take_off();
            }
            FlightState::Flying => {
                let _ = drone.send(&command);
            }
            _ => {}
        }
    }

    fn stop(&mut self, drone: &mut dyn Drone, truth: &Truth) {
        self.last_setpoint_s = None;
        match truth.state {
            FlightState::Landed | FlightState::Emergency => {}
            _ if truth.position_m[2] < ON_THE_FLOOR_M => {
                let _ = drone.land();
            }
            _ => {
                let _ = drone.emergency();
                self.falling = true;
            }
        }
    }

    fn create(&mut self, block: u8, ops: Vec<(u8, u16)>) -> u8 {
        if self.blocks.iter().any(|b| b.id == block) {
            return EEXIST;
        }
        if self.blocks.len() >= MAX_BLOCKS {
            return ENOMEM;
        }
        let mut bytes = 0;
        for &(kind, id) in &ops {
            if usize::from(id) >= TOC.len() {
                return ENOENT;
            }
            bytes += crtp::log_type::size(kind).unwrap_or(usize::MAX / 2);
        }
        if bytes > 26 {
            return E2BIG;
        }
        self.blocks.push(Block {
            id: block,
            ops,
            period_s: None,
            next_s: 0.0,
        });
        0
    }

    fn with_block(&mut self, block: u8, f: impl FnOnce(&mut Block)) -> u8 {
        match self.blocks.iter_mut().find(|b| b.id == block) {
            Some(b) => {
                f(b);
                0
            }
            None => ENOENT,
        }
    }

    fn set_param(&mut self, group: &str, name: &str, kind: u8, value: &[u8]) -> u8 {
        let slot = match (group, name) {
            ("stabilizer", "estimator") => &mut self.estimator,
            ("kalman", "resetEstimation") => &mut self.reset_estimation,
            _ => return ENOENT,
        };
        match (kind, value) {
            (crtp::PARAM_UINT8, [v]) => {
                *slot = *v;
                0
            }
            _ => EINVAL,
        }
    }

    /// The firmware's time passing: its estimate and watchdog at `now_s`, and the samples of
    /// the blocks due pushed to `out`.
    pub fn tick(
        &mut self,
        now_s: f64,
        drone: &mut dyn Drone,
        truth: &Truth,
        out: &mut Vec<Packet>,
    ) -> Outcome {
        let fresh = self
            .last_ext_pose_s
            .is_some_and(|t| now_s - t <= EXT_POSE_FRESH_S);
        if self.estimator == KALMAN && fresh {
            self.estimate_m = truth.position_m;
        }
        let in_the_air = matches!(truth.state, FlightState::Flying | FlightState::TakingOff);
        if in_the_air
            && self
                .last_setpoint_s
                .is_some_and(|t| now_s - t > WATCHDOG_SHUTDOWN_S)
        {
            let _ = drone.emergency();
            self.locked = true;
            self.armed = false;
            self.falling = true;
            if let Ok(p) = FromDrone::Console(b"SUPERVISOR: Locked, reboot required\n").encode() {
                out.push(p);
            }
        }
        self.samples(now_s, truth, out);
        let rest =
            self.falling && truth.state == FlightState::Emergency && truth.position_m[2] <= 0.0;
        if rest {
            self.falling = false;
        }
        Outcome { rest }
    }

    fn samples(&mut self, now_s: f64, truth: &Truth, out: &mut Vec<Packet>) {
        let ms = (now_s * 1000.0) as u32 & 0x00FF_FFFF;
        for i in 0..self.blocks.len() {
            let Some(period) = self.blocks[i].period_s else {
                continue;
            };
            if now_s < self.blocks[i].next_s {
                continue;
            }
            // No burst after a late step: the next one period from now.
            self.blocks[i].next_s = (self.blocks[i].next_s + period).max(now_s);
            let mut data = [0u8; 26];
            let mut at = 0;
            for &(kind, id) in &self.blocks[i].ops {
                at += encode_value(kind, self.value(id, truth), &mut data[at..]);
            }
            let sample = FromDrone::LogData {
                block: self.blocks[i].id,
                timestamp_ms: ms,
                data: &data[..at],
            };
            if let Ok(p) = sample.encode() {
                out.push(p);
                self.counters.samples_sent += 1;
            }
        }
    }

    /// The value of TOC variable `id` now.
    fn value(&self, id: u16, truth: &Truth) -> f64 {
        let Some(&(group, name, _)) = TOC.get(usize::from(id)) else {
            return 0.0;
        };
        let field = dronecine_crazyflie::log::all_vars()
            .find(|v| v.group == group && v.name == name)
            .map(|v| v.field);
        let battery = truth.battery_percent.clamp(0.0, 100.0);
        match field {
            Some(Field::X) => self.estimate_m[0],
            Some(Field::Y) => self.estimate_m[1],
            Some(Field::Z) => self.estimate_m[2],
            Some(Field::Roll) => truth.roll_rad.to_degrees(),
            Some(Field::Pitch) => truth.pitch_rad.to_degrees(),
            Some(Field::Yaw) => truth.heading_rad.to_degrees(),
            Some(Field::Vbat) => 3.0 + 1.2 * battery / 100.0,
            Some(Field::BatteryLevel) => battery.round(),
            Some(Field::PmState) if battery < 10.0 => 3.0,
            Some(Field::PmState) => 0.0,
            Some(Field::Supervisor) => f64::from(self.supervisor_info(truth)),
            None => 0.0,
        }
    }

    fn supervisor_info(&self, truth: &Truth) -> u16 {
        let mut info = supervisor::AUTO_ARM;
        if !self.locked {
            info |= supervisor::CAN_BE_ARMED | supervisor::CAN_FLY;
        }
        if self.armed {
            info |= supervisor::ARMED;
        }
        if matches!(
            truth.state,
            FlightState::TakingOff | FlightState::Flying | FlightState::Landing
        ) {
            info |= supervisor::FLYING;
        }
        if self.locked {
            info |= supervisor::LOCKED;
        }
        info
    }
}

fn log_ack(command: u8, block: u8, error: u8) -> FromDrone<'static> {
    FromDrone::LogAck {
        command,
        block,
        error,
    }
}
