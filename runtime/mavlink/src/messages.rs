//! Every message the backend sends, built by one function each from values in SI units (the
//! conversions to MAVLink's units are here), and the numbers of ArduCopter's modes.
//!
//! All are plain `common` messages; the ArduPilot-only parts are the custom mode numbers and
//! the meaning of `thrust` (a climb rate, see `frames`).

use mavlink::dialects::ardupilotmega::{
    AttitudeTargetTypemask, GimbalManagerFlags, MavAutopilot, MavCmd, MavMessage, MavModeFlag,
    MavState, MavType, COMMAND_LONG_DATA, GIMBAL_MANAGER_SET_PITCHYAW_DATA, HEARTBEAT_DATA,
    PARAM_REQUEST_READ_DATA, SET_ATTITUDE_TARGET_DATA, VISION_POSITION_ESTIMATE_DATA,
};

use crate::frames::AttitudeTarget;

/// This computer's system id: a ground station's (ArduPilot accepts a ground station's
/// heartbeat, for its own failsafe, from SYSID_MYGCS, 255 by default).
pub const GCS_SYSTEM_ID: u8 = 255;
/// This computer's component id (MAV_COMP_ID_MISSIONPLANNER, a ground station).
pub const GCS_COMPONENT_ID: u8 = 190;
/// The autopilot's component id (MAV_COMP_ID_AUTOPILOT1).
pub const AUTOPILOT_COMPONENT_ID: u8 = 1;

/// ArduCopter's custom mode numbers (its `Mode::Number`).
pub mod copter_mode {
    pub const STABILIZE: u32 = 0;
    pub const ALT_HOLD: u32 = 2;
    pub const AUTO: u32 = 3;
    pub const GUIDED: u32 = 4;
    pub const LOITER: u32 = 5;
    pub const RTL: u32 = 6;
    pub const LAND: u32 = 9;
    pub const BRAKE: u32 = 17;
    pub const SMART_RTL: u32 = 21;
    /// Attitude set-points without a position estimate: the generic command's mode.
    pub const GUIDED_NOGPS: u32 = 20;

    /// The mode's name, for messages.
    pub fn name(mode: u32) -> &'static str {
        match mode {
            STABILIZE => "STABILIZE",
            1 => "ACRO",
            ALT_HOLD => "ALT_HOLD",
            AUTO => "AUTO",
            GUIDED => "GUIDED",
            LOITER => "LOITER",
            RTL => "RTL",
            7 => "CIRCLE",
            LAND => "LAND",
            11 => "DRIFT",
            13 => "SPORT",
            14 => "FLIP",
            15 => "AUTOTUNE",
            16 => "POSHOLD",
            BRAKE => "BRAKE",
            18 => "THROW",
            19 => "AVOID_ADSB",
            GUIDED_NOGPS => "GUIDED_NOGPS",
            SMART_RTL => "SMART_RTL",
            _ => "an unknown mode",
        }
    }
}

/// MAV_CMD_COMPONENT_ARM_DISARM's param2 that disarms even in flight.
pub const FORCE_DISARM_MAGIC: f32 = 21196.0;

/// The system and component a message is addressed to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    pub system: u8,
    pub component: u8,
}

/// Our HEARTBEAT: a ground station, not an autopilot, active.
pub fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// SET_ATTITUDE_TARGET with the attitude, all three body rates (0, 0, yaw rate) and the
/// thrust in use: the type mask is 0 (ArduCopter stops on a mask that uses some body rates
/// and ignores others).
pub fn attitude_target(to: Target, time_boot_ms: u32, target: &AttitudeTarget) -> MavMessage {
    MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
        time_boot_ms,
        q: target.q,
        body_roll_rate: 0.0,
        body_pitch_rate: 0.0,
        body_yaw_rate: target.yaw_rate_radps,
        thrust: target.thrust,
        target_system: to.system,
        target_component: to.component,
        type_mask: AttitudeTargetTypemask::empty(),
        thrust_body: [0.0; 3],
    })
}

/// VISION_POSITION_ESTIMATE: a NED position (m) and attitude (rad) captured at `usec`, its
/// covariance unknown (NaN first: the autopilot uses its own noise parameters).
pub fn vision_position(
    usec: u64,
    ned_m: [f64; 3],
    [roll, pitch, yaw]: [f64; 3],
    reset_counter: u8,
) -> MavMessage {
    let mut covariance = [0.0; 21];
    covariance[0] = f32::NAN;
    MavMessage::VISION_POSITION_ESTIMATE(VISION_POSITION_ESTIMATE_DATA {
        usec,
        x: ned_m[0] as f32,
        y: ned_m[1] as f32,
        z: ned_m[2] as f32,
        roll: roll as f32,
        pitch: pitch as f32,
        yaw: yaw as f32,
        covariance,
        reset_counter,
    })
}

/// SET_GPS_GLOBAL_ORIGIN: the EKF's origin, latitude and longitude in degrees, altitude in
/// metres above mean sea level. MAVLink marks the message as superseded by a command that
/// ArduPilot's released firmware does not take; ArduPilot takes the message.
#[allow(deprecated)]
pub fn gps_origin(target_system: u8, lat_deg: f64, lon_deg: f64, alt_m: f64) -> MavMessage {
    use mavlink::dialects::ardupilotmega::SET_GPS_GLOBAL_ORIGIN_DATA;
    MavMessage::SET_GPS_GLOBAL_ORIGIN(SET_GPS_GLOBAL_ORIGIN_DATA {
        latitude: (lat_deg * 1e7).round() as i32,
        longitude: (lon_deg * 1e7).round() as i32,
        altitude: (alt_m * 1e3).round() as i32,
        target_system,
        time_usec: 0,
    })
}

/// COMMAND_LONG `command` with its seven parameters (first transmission).
pub fn command_long(to: Target, command: MavCmd, params: [f32; 7]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: params[0],
        param2: params[1],
        param3: params[2],
        param4: params[3],
        param5: params[4],
        param6: params[5],
        param7: params[6],
        command,
        target_system: to.system,
        target_component: to.component,
        confirmation: 0,
    })
}

/// MAV_CMD_DO_SET_MODE to an ArduPilot custom mode.
pub fn set_mode(to: Target, custom_mode: u32) -> MavMessage {
    let custom = f32::from(MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits());
    command_long(
        to,
        MavCmd::MAV_CMD_DO_SET_MODE,
        [custom, custom_mode as f32, 0.0, 0.0, 0.0, 0.0, 0.0],
    )
}

/// MAV_CMD_COMPONENT_ARM_DISARM: arm (`true`) or disarm with the vehicle's own checks.
pub fn arm(to: Target, armed: bool) -> MavMessage {
    let param1 = if armed { 1.0 } else { 0.0 };
    command_long(
        to,
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [param1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    )
}

/// MAV_CMD_COMPONENT_ARM_DISARM with the force code: the motors stop, even in flight.
pub fn force_disarm(to: Target) -> MavMessage {
    command_long(
        to,
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [0.0, FORCE_DISARM_MAGIC, 0.0, 0.0, 0.0, 0.0, 0.0],
    )
}

/// MAV_CMD_SET_MESSAGE_INTERVAL: the vehicle sends message `id` every `interval_us`.
pub fn message_interval(to: Target, id: u32, interval_us: f32) -> MavMessage {
    command_long(
        to,
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        [id as f32, interval_us, 0.0, 0.0, 0.0, 0.0, 0.0],
    )
}

/// MAV_CMD_REQUEST_MESSAGE: the vehicle sends message `id` once.
pub fn request_message(to: Target, id: u32) -> MavMessage {
    command_long(
        to,
        MavCmd::MAV_CMD_REQUEST_MESSAGE,
        [id as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    )
}

/// PARAM_REQUEST_READ of one parameter by name (index −1).
pub fn param_request(to: Target, name: &str) -> MavMessage {
    MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
        param_index: -1,
        target_system: to.system,
        target_component: to.component,
        param_id: name.into(),
    })
}

/// GIMBAL_MANAGER_SET_PITCHYAW (gimbal protocol v2): the camera's pitch (up positive, from
/// the horizon) with the yaw straight ahead in the vehicle's frame, no rates; to every gimbal
/// of the autopilot's (device id 0).
pub fn gimbal_pitch(to: Target, pitch_rad: f64) -> MavMessage {
    MavMessage::GIMBAL_MANAGER_SET_PITCHYAW(GIMBAL_MANAGER_SET_PITCHYAW_DATA {
        flags: GimbalManagerFlags::GIMBAL_MANAGER_FLAGS_ROLL_LOCK
            | GimbalManagerFlags::GIMBAL_MANAGER_FLAGS_PITCH_LOCK,
        pitch: pitch_rad as f32,
        yaw: 0.0,
        pitch_rate: f32::NAN,
        yaw_rate: f32::NAN,
        target_system: to.system,
        target_component: to.component,
        gimbal_device_id: 0,
    })
}
