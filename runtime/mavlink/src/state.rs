//! The vehicle as the messages it sends describe it: [`VehicleState`], updated by
//! [`VehicleState::apply`] with each message the link reads (a pure function of the
//! message, tested without a socket).
//!
//! The vehicle is the first system whose HEARTBEAT names an autopilot; messages from other
//! systems are counted and dropped, and only the autopilot's own component's heartbeats
//! say its mode and armed state (a gimbal or a companion computer sends heartbeats too).

use std::collections::{HashMap, VecDeque};
use std::time::Instant;

use mavlink::dialects::ardupilotmega::{
    MavAutopilot, MavLandedState, MavMessage, MavModeFlag, MavSysStatusSensor, MavType,
    ATTITUDE_DATA, EKF_STATUS_REPORT_DATA, GIMBAL_DEVICE_ATTITUDE_STATUS_DATA, HEARTBEAT_DATA,
    LOCAL_POSITION_NED_DATA, SIM_STATE_DATA, STATUSTEXT_DATA,
};
use mavlink::MavHeader;

use crate::frames::euler_from_quaternion;
use crate::messages::Target;

/// Events kept for the flight to drain; older ones are dropped (and counted) past this.
pub const MAX_EVENTS: usize = 256;

/// The part of the text ArduPilot's EKF says when it starts using the motion capture
/// ("EKF3 IMU0 is using external nav data").
pub const EXTERNAL_NAV_TEXT: &str = "is using external nav data";

/// What the autopilot's HEARTBEAT says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Heartbeat {
    /// The autopilot's own mode number (ArduCopter: `messages::copter_mode`).
    pub custom_mode: u32,
    pub armed: bool,
    /// MAV_STATE: 3 standby, 4 active, 5 critical, 6 emergency.
    pub system_status: u8,
    /// MAV_TYPE (2 for a quadrotor).
    pub vehicle_type: u8,
    /// MAV_AUTOPILOT (3 for ArduPilot).
    pub autopilot: u8,
}

/// EXTENDED_SYS_STATE's landed state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LandedState {
    Undefined,
    OnGround,
    InAir,
    TakingOff,
    Landing,
}

/// LOCAL_POSITION_NED: the autopilot's EKF estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalPosition {
    pub ned_m: [f64; 3],
    pub velocity_ned_mps: [f64; 3],
    pub received: Instant,
}

/// SIM_STATE: a simulator's true state (SITL sends it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimState {
    /// `(w, x, y, z)`, NED → body.
    pub q: [f64; 4],
    /// Roll, pitch, yaw (rad).
    pub attitude_rad: [f64; 3],
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Above mean sea level.
    pub alt_m: f64,
    pub velocity_ned_mps: [f64; 3],
    pub received: Instant,
}

/// Something the vehicle said or did, for the flight to show and log.
#[derive(Clone, Debug, PartialEq)]
pub enum VehicleEvent {
    /// STATUSTEXT, with its MAV_SEVERITY (0 emergency … 7 debug).
    Text {
        severity: u8,
        text: String,
    },
    /// The autopilot's mode changed (`from` is `None` for the first heartbeat).
    Mode {
        from: Option<u32>,
        to: u32,
    },
    Armed(bool),
    /// The EKF's status flags changed (EKF_STATUS_REPORT, MAV's `EKF_*` bits).
    EkfFlags(u16),
}

/// The last COMMAND_ACK for one command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ack {
    /// MAV_CMD.
    pub command: u32,
    /// MAV_RESULT: 0 accepted, 1 temporarily rejected, 2 denied, 3 unsupported, 4 failed, …
    pub result: u8,
    pub received: Instant,
}

/// Everything the link has read from the vehicle.
#[derive(Clone, Debug, Default)]
pub struct VehicleState {
    /// The autopilot, once its heartbeat was heard.
    pub vehicle: Option<Target>,
    pub heartbeat: Option<Heartbeat>,
    /// When the last message from the vehicle arrived.
    pub last_heard: Option<Instant>,
    /// The battery's remaining charge (SYS_STATUS or BATTERY_STATUS), when the vehicle
    /// knows it.
    pub battery_percent: Option<f64>,
    /// SYS_STATUS: whether the autopilot's pre-arm checks pass (`None` before it said).
    pub prearm_ok: Option<bool>,
    /// ATTITUDE: roll, pitch, yaw (rad, NED).
    pub attitude_rad: Option<[f64; 3]>,
    pub landed: Option<LandedState>,
    /// EKF_STATUS_REPORT's flags.
    pub ekf_flags: Option<u16>,
    pub local_position: Option<LocalPosition>,
    /// The camera gimbal's pitch (up positive), from GIMBAL_DEVICE_ATTITUDE_STATUS.
    pub gimbal_pitch_rad: Option<f64>,
    pub sim: Option<SimState>,
    /// The EKF said it uses the external navigation ([`EXTERNAL_NAV_TEXT`]).
    pub external_nav_said: bool,
    /// GPS_GLOBAL_ORIGIN: the EKF's origin as the autopilot holds it (latitude and
    /// longitude in degrees, altitude above mean sea level in metres).
    pub origin: Option<[f64; 3]>,
    /// Parameter values by name, as PARAM_VALUE gave them.
    pub params: HashMap<String, f32>,
    /// The last COMMAND_ACK of each command.
    pub acks: Vec<Ack>,
    pub events: VecDeque<(Instant, VehicleEvent)>,
    /// Events dropped because nobody drained them.
    pub events_dropped: u64,
    /// Messages read from the vehicle.
    pub received: u64,
    /// Messages from other systems, and frames the decoder refused.
    pub ignored: u64,
    /// The last error of the link's reader (a closed TCP connection, a serial port gone).
    pub link_error: Option<String>,
}

impl VehicleState {
    /// Takes one message read from the link at `now`.
    pub fn apply(&mut self, header: &MavHeader, msg: &MavMessage, now: Instant) {
        if let MavMessage::HEARTBEAT(hb) = msg {
            if self.vehicle.is_none() && is_autopilot(hb) {
                self.vehicle = Some(Target {
                    system: header.system_id as u8,
                    component: header.component_id,
                });
            }
        }
        let Some(vehicle) = self.vehicle else {
            self.ignored += 1;
            return;
        };
        if header.system_id != u32::from(vehicle.system) {
            self.ignored += 1;
            return;
        }
        self.received += 1;
        self.last_heard = Some(now);
        match msg {
            MavMessage::HEARTBEAT(hb) if header.component_id == vehicle.component => {
                self.heartbeat(hb, now)
            }
            MavMessage::SYS_STATUS(s) => {
                self.battery(s.battery_remaining);
                let prearm = MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK;
                if s.onboard_control_sensors_present.contains(prearm) {
                    self.prearm_ok = Some(s.onboard_control_sensors_health.contains(prearm));
                }
            }
            MavMessage::BATTERY_STATUS(b) if b.id == 0 => self.battery(b.battery_remaining),
            MavMessage::ATTITUDE(a) => self.attitude(a),
            MavMessage::EXTENDED_SYS_STATE(e) => self.landed = Some(landed_state(e.landed_state)),
            MavMessage::STATUSTEXT(t) => self.status_text(t, now),
            MavMessage::PARAM_VALUE(p) => {
                if let Ok(name) = p.param_id.to_str() {
                    self.params.insert(name.to_string(), p.param_value);
                }
            }
            MavMessage::COMMAND_ACK(a) => self.ack(a.command as u32, a.result as u8, now),
            MavMessage::EKF_STATUS_REPORT(e) => self.ekf(e, now),
            MavMessage::LOCAL_POSITION_NED(p) => self.local_position(p, now),
            MavMessage::GIMBAL_DEVICE_ATTITUDE_STATUS(g) => self.gimbal(g),
            MavMessage::SIM_STATE(s) => self.sim_state(s, now),
            MavMessage::GPS_GLOBAL_ORIGIN(o) => {
                self.origin = Some([
                    f64::from(o.latitude) * 1e-7,
                    f64::from(o.longitude) * 1e-7,
                    f64::from(o.altitude) * 1e-3,
                ])
            }
            _ => {}
        }
    }

    /// The last acknowledgement of `command` received after `since`.
    pub fn ack_since(&self, command: u32, since: Instant) -> Option<u8> {
        self.acks
            .iter()
            .find(|a| a.command == command && a.received >= since)
            .map(|a| a.result)
    }

    /// The texts the vehicle sent after `since`, oldest first.
    pub fn texts_since(&self, since: Instant) -> impl Iterator<Item = &str> {
        self.events.iter().filter_map(move |(t, e)| match e {
            VehicleEvent::Text { text, .. } if *t >= since => Some(text.as_str()),
            _ => None,
        })
    }

    fn push(&mut self, now: Instant, event: VehicleEvent) {
        if self.events.len() >= MAX_EVENTS {
            self.events.pop_front();
            self.events_dropped += 1;
        }
        self.events.push_back((now, event));
    }

    fn heartbeat(&mut self, hb: &HEARTBEAT_DATA, now: Instant) {
        let new = Heartbeat {
            custom_mode: hb.custom_mode,
            armed: hb
                .base_mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
            system_status: hb.system_status as u8,
            vehicle_type: hb.mavtype as u8,
            autopilot: hb.autopilot as u8,
        };
        let old = self.heartbeat.replace(new);
        if old.map(|o| o.custom_mode) != Some(new.custom_mode) {
            let from = old.map(|o| o.custom_mode);
            self.push(
                now,
                VehicleEvent::Mode {
                    from,
                    to: new.custom_mode,
                },
            );
        }
        if old.is_some_and(|o| o.armed != new.armed) || (old.is_none() && new.armed) {
            self.push(now, VehicleEvent::Armed(new.armed));
        }
    }

    /// A remaining charge in percent; −1 means the vehicle does not know it.
    fn battery(&mut self, remaining: i8) {
        if remaining >= 0 {
            self.battery_percent = Some(f64::from(remaining));
        }
    }

    fn attitude(&mut self, a: &ATTITUDE_DATA) {
        self.attitude_rad = Some([a.roll, a.pitch, a.yaw].map(f64::from));
    }

    fn status_text(&mut self, t: &STATUSTEXT_DATA, now: Instant) {
        let text = String::from_utf8_lossy(&t.text[..])
            .trim_end_matches('\0')
            .to_string();
        if text.to_ascii_lowercase().contains(EXTERNAL_NAV_TEXT) {
            self.external_nav_said = true;
        }
        let severity = t.severity as u8;
        self.push(now, VehicleEvent::Text { severity, text });
    }

    fn ack(&mut self, command: u32, result: u8, received: Instant) {
        let ack = Ack {
            command,
            result,
            received,
        };
        match self.acks.iter_mut().find(|a| a.command == command) {
            Some(a) => *a = ack,
            None => self.acks.push(ack),
        }
    }

    fn ekf(&mut self, e: &EKF_STATUS_REPORT_DATA, now: Instant) {
        let flags = e.flags.bits();
        if self.ekf_flags.replace(flags) != Some(flags) {
            self.push(now, VehicleEvent::EkfFlags(flags));
        }
    }

    fn local_position(&mut self, p: &LOCAL_POSITION_NED_DATA, now: Instant) {
        self.local_position = Some(LocalPosition {
            ned_m: [p.x, p.y, p.z].map(f64::from),
            velocity_ned_mps: [p.vx, p.vy, p.vz].map(f64::from),
            received: now,
        });
    }

    fn gimbal(&mut self, g: &GIMBAL_DEVICE_ATTITUDE_STATUS_DATA) {
        let q = g.q.map(f64::from);
        if q.iter().all(|v| v.is_finite()) {
            self.gimbal_pitch_rad = Some(euler_from_quaternion(q)[1]);
        }
    }

    fn sim_state(&mut self, s: &SIM_STATE_DATA, now: Instant) {
        // The integer fields carry the full precision when the simulator fills them.
        let deg = |int: i32, float: f32| {
            if int != 0 {
                f64::from(int) * 1e-7
            } else {
                f64::from(float)
            }
        };
        self.sim = Some(SimState {
            q: [s.q1, s.q2, s.q3, s.q4].map(f64::from),
            attitude_rad: [s.roll, s.pitch, s.yaw].map(f64::from),
            lat_deg: deg(s.lat_int, s.lat),
            lon_deg: deg(s.lon_int, s.lon),
            alt_m: f64::from(s.alt),
            velocity_ned_mps: [s.vn, s.ve, s.vd].map(f64::from),
            received: now,
        });
    }
}

/// A heartbeat from a flight controller (not a ground station, gimbal or companion).
fn is_autopilot(hb: &HEARTBEAT_DATA) -> bool {
    hb.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID
        && !matches!(
            hb.mavtype,
            MavType::MAV_TYPE_GCS | MavType::MAV_TYPE_GIMBAL | MavType::MAV_TYPE_ONBOARD_CONTROLLER
        )
}

fn landed_state(s: MavLandedState) -> LandedState {
    match s {
        MavLandedState::MAV_LANDED_STATE_UNDEFINED => LandedState::Undefined,
        MavLandedState::MAV_LANDED_STATE_ON_GROUND => LandedState::OnGround,
        MavLandedState::MAV_LANDED_STATE_IN_AIR => LandedState::InAir,
        MavLandedState::MAV_LANDED_STATE_TAKEOFF => LandedState::TakingOff,
        MavLandedState::MAV_LANDED_STATE_LANDING => LandedState::Landing,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::ardupilotmega::{MavSeverity, MavState, PARAM_VALUE_DATA};

    fn header(system_id: u32, component_id: u8) -> MavHeader {
        MavHeader {
            system_id,
            component_id,
            sequence: 0,
        }
    }

    fn heartbeat(mode: u32, armed: bool, autopilot: MavAutopilot) -> MavMessage {
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: mode,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot,
            base_mode: if armed {
                MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
            } else {
                MavModeFlag::empty()
            },
            system_status: MavState::MAV_STATE_STANDBY,
            mavlink_version: 3,
        })
    }

    #[test]
    fn the_vehicle_is_the_first_autopilot_heard() {
        let now = Instant::now();
        let mut s = VehicleState::default();
        let gcs = heartbeat(0, false, MavAutopilot::MAV_AUTOPILOT_INVALID);
        s.apply(&header(200, 190), &gcs, now);
        assert_eq!((s.vehicle, s.ignored), (None, 1));
        s.apply(
            &header(1, 1),
            &heartbeat(20, false, MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA),
            now,
        );
        assert_eq!(
            s.vehicle,
            Some(Target {
                system: 1,
                component: 1
            })
        );
        assert_eq!(s.heartbeat.map(|h| h.custom_mode), Some(20));
        // Another component of the vehicle does not change its mode; another system is ignored.
        s.apply(
            &header(1, 154),
            &heartbeat(0, true, MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA),
            now,
        );
        s.apply(
            &header(2, 1),
            &heartbeat(9, true, MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA),
            now,
        );
        assert_eq!(
            s.heartbeat.map(|h| (h.custom_mode, h.armed)),
            Some((20, false))
        );
        assert_eq!(s.ignored, 2);
    }

    #[test]
    fn mode_and_arming_changes_and_texts_are_events() {
        let now = Instant::now();
        let mut s = VehicleState::default();
        let ap = MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA;
        s.apply(&header(1, 1), &heartbeat(20, false, ap), now);
        s.apply(&header(1, 1), &heartbeat(20, true, ap), now);
        s.apply(&header(1, 1), &heartbeat(9, true, ap), now);
        let text = MavMessage::STATUSTEXT(STATUSTEXT_DATA {
            severity: MavSeverity::MAV_SEVERITY_INFO,
            text: "EKF3 IMU0 is using external nav data".into(),
            id: 0,
            chunk_seq: 0,
        });
        s.apply(&header(1, 1), &text, now);
        let events: Vec<_> = s.events.iter().map(|(_, e)| e.clone()).collect();
        assert_eq!(
            events,
            [
                VehicleEvent::Mode { from: None, to: 20 },
                VehicleEvent::Armed(true),
                VehicleEvent::Mode {
                    from: Some(20),
                    to: 9
                },
                VehicleEvent::Text {
                    severity: 6,
                    text: "EKF3 IMU0 is using external nav data".into()
                },
            ]
        );
        assert!(s.external_nav_said);
    }

    #[test]
    fn parameters_and_an_unknown_battery() {
        let now = Instant::now();
        let mut s = VehicleState::default();
        s.apply(
            &header(1, 1),
            &heartbeat(0, false, MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA),
            now,
        );
        let p = MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
            param_value: 250.0,
            param_id: "WPNAV_SPEED_UP".into(),
            ..Default::default()
        });
        s.apply(&header(1, 1), &p, now);
        assert_eq!(s.params.get("WPNAV_SPEED_UP"), Some(&250.0));
        s.battery(-1);
        assert_eq!(s.battery_percent, None);
        s.battery(87);
        s.battery(-1);
        assert_eq!(s.battery_percent, Some(87.0));
    }

    #[test]
    fn old_events_make_room() {
        let now = Instant::now();
        let mut s = VehicleState::default();
        for i in 0..MAX_EVENTS + 3 {
            s.push(now, VehicleEvent::EkfFlags(i as u16));
        }
        assert_eq!((s.events.len(), s.events_dropped), (MAX_EVENTS, 3));
        assert_eq!(
            s.events.front().map(|e| e.1.clone()),
            Some(VehicleEvent::EkfFlags(3))
        );
    }
}
