//! The emulated Motive: the answers on the NatNet command port and the frames of data, built
//! from the simulator's mocap frames. No sockets.
//!
//! - Command port: `NAT_CONNECT` (the SDK's "ping", whatever version it asks for) is answered
//!   with `NAT_SERVERINFO`: application "Motive" 3.0.0.0, the configured NatNet version
//!   (4.1 by default), and `sSender_Server`'s details (10 MHz high-resolution clock, the data
//!   port, the multicast flag and group). `NAT_KEEPALIVE` is accepted silently; any other
//!   well-formed request gets `NAT_UNRECOGNIZED_REQUEST` (no model definitions); garbage is
//!   counted and dropped.
//! - Frames: one `NAT_FRAMEOFDATA` per simulator mocap frame (100 Hz by default), with the
//!   drone as rigid body **id 1** and the script's actors as **ids 2, 3, …** in the script's
//!   order. A body the simulator did not track in that frame (its dropouts) is sent with
//!   tracking-valid clear (params bit 0), zero position and identity orientation. Poses are
//!   the simulator's mocap poses (its noise included): position, and an orientation that is
//!   the heading alone (a rotation about the vertical; the simulator's mocap reports no tilt),
//!   in Motive's axes: Y-up (default; world (x, y, z) → Motive (x, z, −y), the inverse of
//!   `natnet::frame::to_world`) or Z-up (identity). Mean marker error 0.3 mm.
//! - Timing: the frame number is the simulator's frame index (continued across an emergency
//!   reset); `timestamp` is seconds since the emulator started streaming; the three
//!   high-resolution stamps are that time in 10 MHz ticks (mid-exposure = capture time, data
//!   received and transmit = the wall time of sending); 4.1's precision timestamp is the
//!   capture time as seconds and a 2⁻³² fraction.

use dronecine_backend::{BodyPose, MocapFrame};
use dronecine_math as math;
use dronecine_natnet::frame::{
    decode_connect, encode_frame, encode_server_info, split_message, FrameOut, NatNetError,
    RigidBody, ServerDetails, ServerInfo, UpAxis, Version, NAT_CONNECT, NAT_KEEPALIVE,
    NAT_UNRECOGNIZED_REQUEST,
};

/// Ticks per second of the frames' high-resolution timestamps.
pub const HIGH_RES_CLOCK_HZ: u64 = 10_000_000;
/// Rigid-body id of the drone; actor `i` (0-based, script order) is `ACTOR_ID_BASE + i`.
pub const DRONE_ID: i32 = 1;
pub const ACTOR_ID_BASE: i32 = 2;
/// Mean marker error written for tracked bodies.
const MEAN_ERROR_M: f32 = 0.0003;

/// What the command port answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reply {
    /// Send these bytes back to the requester.
    Send(usize),
    /// Nothing to send.
    None,
}

/// The emulated Motive server.
#[derive(Debug)]
pub struct Motive {
    version: Version,
    up: UpAxis,
    info: ServerInfo,
    bodies: Vec<RigidBody>,
}

impl Motive {
    /// `data_port`, `multicast`, `group`: what the server info announces.
    pub fn new(
        version: Version,
        up: UpAxis,
        data_port: u16,
        multicast: bool,
        group: [u8; 4],
    ) -> Result<Self, NatNetError> {
        if !version.is_supported() {
            return Err(NatNetError::UnsupportedVersion(version));
        }
        let mut info = ServerInfo::new("Motive", [3, 0, 0, 0], version);
        info.details = Some(ServerDetails {
            high_res_clock_hz: HIGH_RES_CLOCK_HZ,
            data_port,
            multicast,
            multicast_group: if multicast { group } else { [0; 4] },
        });
        Ok(Motive {
            version,
            up,
            info,
            bodies: Vec::new(),
        })
    }

    pub fn version(&self) -> Version {
        self.version
    }

    /// The answer to one command-port datagram, written into `buf`. `Err` for a datagram
    /// that is not a NatNet message.
    pub fn command(&self, datagram: &[u8], buf: &mut [u8]) -> Result<Reply, NatNetError> {
        let (id, _) = split_message(datagram)?;
        match id {
            NAT_CONNECT => {
                decode_connect(datagram)?;
                Ok(Reply::Send(encode_server_info(&self.info, buf)?))
            }
            NAT_KEEPALIVE => Ok(Reply::None),
            _ => {
                let out = buf.get_mut(..4).ok_or(NatNetError::BufferFull)?;
                out[..2].copy_from_slice(&NAT_UNRECOGNIZED_REQUEST.to_le_bytes());
                out[2..].copy_from_slice(&0u16.to_le_bytes());
                Ok(Reply::Send(4))
            }
        }
    }

    /// A Motive rigid body from a world pose (`None`: untracked).
    pub fn rigid_body(&self, id: i32, pose: Option<&BodyPose>) -> RigidBody {
        let Some(p) = pose else {
            return RigidBody {
                id,
                position_m: [0.0; 3],
                orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
                mean_error_m: 0.0,
                params: 0,
            };
        };
        let [x, y, z] = p.position_m;
        let (s, c) = math::sin_cos(p.heading_rad / 2.0);
        // World quaternion (0, 0, s, c): a rotation by the heading about world z.
        let (position, q) = match self.up {
            // Motive Y-up: (x, z, −y); a world vector part (qx, qy, qz) → (qx, qz, −qy).
            UpAxis::Y => ([x, z, -y], [0.0, s, 0.0, c]),
            UpAxis::Z => ([x, y, z], [0.0, 0.0, s, c]),
        };
        RigidBody {
            id,
            position_m: position.map(|v| v as f32),
            orientation_xyzw: q.map(|v| v as f32),
            mean_error_m: MEAN_ERROR_M,
            params: 1,
        }
    }

    /// Writes the frame of data for `frame` (numbered `frame_number`, captured at
    /// `capture_s` and sent at `send_s`, both seconds since streaming started).
    pub fn frame(
        &mut self,
        frame: &MocapFrame,
        frame_number: u64,
        capture_s: f64,
        send_s: f64,
        buf: &mut [u8],
    ) -> Result<usize, NatNetError> {
        let mut bodies = std::mem::take(&mut self.bodies);
        bodies.clear();
        bodies.push(self.rigid_body(DRONE_ID, frame.drone.as_ref()));
        for (i, a) in frame.actors.iter().enumerate() {
            let id = i32::try_from(i)
                .ok()
                .and_then(|i| i.checked_add(ACTOR_ID_BASE))
                .ok_or(NatNetError::TooLarge)?;
            bodies.push(self.rigid_body(id, a.as_ref()));
        }
        let ticks = |t: f64| (t.max(0.0) * HIGH_RES_CLOCK_HZ as f64) as u64;
        let capture = capture_s.max(0.0);
        let out = FrameOut {
            frame_number: (frame_number & 0x7FFF_FFFF) as i32,
            marker_sets: &[],
            other_markers: &[],
            rigid_bodies: &bodies,
            labeled_markers: &[],
            timecode: 0,
            timecode_sub: 0,
            timestamp_s: capture,
            camera_mid_exposure_ticks: ticks(capture),
            camera_data_received_ticks: ticks(send_s),
            transmit_ticks: ticks(send_s),
            precision_timestamp_secs: capture.floor() as u32,
            precision_timestamp_frac_secs: (capture.fract() * 4_294_967_296.0) as u32,
            params: 0,
        };
        let r = encode_frame(&out, self.version, buf);
        self.bodies = bodies;
        r
    }
}
