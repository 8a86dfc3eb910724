//! OptiTrack NatNet 3.0–4.1 messages: the server-info handshake, the frame of data (decoder
//! and encoder), and the conversion of Motive's axes to the world frame of `frames.rs`.
//!
//! Every message is `u16 id, u16 payload byte count, payload`, little-endian.
//!
//! **Handshake** (command port 1510): the client sends `NAT_CONNECT` (id 0) with the
//! 271-byte payload of the NatNet SDK's clients: `"Ping"`, zeros, byte 264 = 0, bytes
//! 265–268 = the requested NatNet version, a final 0 ([`encode_connect`]). The server answers
//! `NAT_SERVERINFO` (id 1): 256-byte application name, 4-byte application version, 4-byte
//! NatNet version, and from NatNet 3 on (`sSender_Server`) u64 high-resolution clock
//! frequency, u16 data port, u8 multicast flag, 4-byte multicast group
//! ([`decode_server_info`]). The frame layout depends on that NatNet version.
//!
//! **Frame of data** (`NAT_FRAMEOFDATA`, id 7), in order (sizes in bytes; "4.1:" marks what
//! NatNet 4.1 adds — an i32 byte count after every section count, the assets section and
//! the precision timestamp):
//!
//! | part | layout |
//! |---|---|
//! | prefix | i32 frame number |
//! | marker sets | i32 n, 4.1: i32 bytes; n × (C-string name, i32 m, m × 3 f32) |
//! | other markers | i32 n, 4.1: i32 bytes; n × 3 f32 |
//! | rigid bodies | i32 n, 4.1: i32 bytes; n × 38: i32 id, 3 f32 position, 4 f32 quaternion x y z w, f32 mean marker error, u16 params (bit 0 tracking valid) |
//! | skeletons | i32 n, 4.1: i32 bytes; n × (i32 id, i32 m, m × 38-byte rigid body) |
//! | assets (4.1) | i32 n, i32 bytes (skipped by the byte count) |
//! | labeled markers | i32 n, 4.1: i32 bytes; n × 26: i32 id, 3 f32, f32 size, u16 params, f32 residual |
//! | force plates | i32 n, 4.1: i32 bytes; n × (i32 id, i32 channels, per channel i32 k, k × f32) |
//! | devices | same layout as force plates |
//! | suffix | u32 timecode, u32 timecode sub, f64 timestamp (s), u64 mid-exposure, u64 data received, u64 transmit (clock ticks), 4.1: u32 precision seconds, u32 fractional; u16 params (bit 0 recording, bit 1 models changed), i32 end-of-data tag |
//!
//! NatNet 3.x sections are walked element by element; 4.1 sections are skipped by their
//! byte counts (rigid bodies are decoded and must fill their count exactly). The payload
//! must end right after the end-of-data tag, as in the NatNet SDK's `PacketClient.cpp` and
//! `NatNetClient.py`. Versions outside 3.0–4.1 are refused. Nothing panics; decoding reuses
//! the caller's rigid-body vector.
//!
//! **Axes** ([`to_world`]): the world frame is x, y on the floor, z up (`frames.rs`).
//! Motive streams Y-up (its default) or Z-up. Y-up: world = (x, −z, y) of Motive's, a
//! +90° rotation about x, so Motive's x stays world x and Motive's up (y) becomes world z;
//! Z-up: identity. The orientation is converted by the same rotation (its vector part
//! rotates, w stays), so a body's local axes follow the same map; heading is the angle of
//! the body's local +x axis in the world floor plane, counter-clockwise from world +x seen
//! from above (the heading of `frames.rs`: build the rigid body in Motive with its local x
//! along the drone's nose).

use dronecine_math as math;
use std::fmt;

use dronecine_backend::BodyPose;
use dronecine_math::wrap_angle_rad;

pub const NAT_CONNECT: u16 = 0;
pub const NAT_SERVERINFO: u16 = 1;
pub const NAT_REQUEST: u16 = 2;
pub const NAT_RESPONSE: u16 = 3;
pub const NAT_REQUEST_MODELDEF: u16 = 4;
pub const NAT_MODELDEF: u16 = 5;
pub const NAT_REQUEST_FRAMEOFDATA: u16 = 6;
pub const NAT_FRAMEOFDATA: u16 = 7;
pub const NAT_MESSAGESTRING: u16 = 8;
pub const NAT_DISCONNECT: u16 = 9;
pub const NAT_KEEPALIVE: u16 = 10;
pub const NAT_DISCONNECTBYTIMEOUT: u16 = 11;
pub const NAT_ECHOREQUEST: u16 = 12;
pub const NAT_ECHORESPONSE: u16 = 13;
pub const NAT_DISCOVERY: u16 = 14;
pub const NAT_UNRECOGNIZED_REQUEST: u16 = 100;

pub const COMMAND_PORT: u16 = 1510;
pub const DATA_PORT: u16 = 1511;
pub const MULTICAST_GROUP: [u8; 4] = [239, 255, 42, 99];

/// Length of the name field of `sSender`.
pub const MAX_NAME_LEN: usize = 256;
/// Payload of the SDK clients' `NAT_CONNECT`.
pub const CONNECT_PAYLOAD_LEN: usize = 271;
/// `sSender`: name, app version, NatNet version.
pub const SENDER_LEN: usize = MAX_NAME_LEN + 8;
/// `sSender_Server`: `sSender` + clock frequency, data port, multicast flag and group.
pub const SENDER_SERVER_LEN: usize = SENDER_LEN + 8 + 2 + 1 + 4;
/// Bytes of one rigid body in a frame (NatNet ≥ 3).
pub const RIGID_BODY_LEN: usize = 38;
/// Bytes of one labeled marker in a frame (NatNet ≥ 3).
pub const LABELED_MARKER_LEN: usize = 26;

/// A NatNet version `major.minor.build.revision`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Version {
    pub major: u8,
    pub minor: u8,
    pub build: u8,
    pub revision: u8,
}

impl Version {
    pub const V3_0: Version = Version::new(3, 0, 0, 0);
    pub const V3_1: Version = Version::new(3, 1, 0, 0);
    pub const V4_0: Version = Version::new(4, 0, 0, 0);
    pub const V4_1: Version = Version::new(4, 1, 0, 0);

    pub const fn new(major: u8, minor: u8, build: u8, revision: u8) -> Self {
        Version {
            major,
            minor,
            build,
            revision,
        }
    }

    pub fn from_bytes(b: [u8; 4]) -> Self {
        Version::new(b[0], b[1], b[2], b[3])
    }

    pub fn to_bytes(self) -> [u8; 4] {
        [self.major, self.minor, self.build, self.revision]
    }

    /// The frame layouts this module reads and writes: 3.0 up to 4.1.
    pub fn is_supported(self) -> bool {
        matches!((self.major, self.minor), (3, _) | (4, 0) | (4, 1))
    }

    /// 4.1 and later: section byte counts, assets, precision timestamp.
    fn has_sizes(self) -> bool {
        (self.major, self.minor) >= (4, 1)
    }
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}",
            self.major, self.minor, self.build, self.revision
        )
    }
}

/// Why a message was rejected or could not be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NatNetError {
    /// The message ends before the field at `offset` (payload offset, message header
    /// excluded).
    Truncated {
        offset: usize,
    },
    /// The datagram is shorter or longer than its header's byte count says.
    LengthMismatch {
        declared: usize,
        actual: usize,
    },
    /// Not the message that was expected.
    WrongMessage {
        expected: u16,
        got: u16,
    },
    UnsupportedVersion(Version),
    /// A negative count, or one the remaining bytes cannot hold.
    BadCount {
        offset: usize,
    },
    /// A 4.1 section byte count that is negative, runs past the end, or disagrees with its
    /// fixed-size elements.
    BadSectionSize {
        section: &'static str,
        offset: usize,
    },
    /// A C-string with no terminating NUL.
    BadName {
        offset: usize,
    },
    /// Bytes after the end-of-data tag.
    TrailingBytes {
        offset: usize,
    },
    /// The output buffer is too small (encoders).
    BufferFull,
    /// A payload over 65535 bytes, or a name with a NUL or too long (encoders).
    TooLarge,
}

impl fmt::Display for NatNetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NatNetError::Truncated { offset } => write!(f, "natnet: truncated at byte {offset}"),
            NatNetError::LengthMismatch { declared, actual } => write!(
                f,
                "natnet: header says {declared} payload bytes, datagram has {actual}"
            ),
            NatNetError::WrongMessage { expected, got } => {
                write!(f, "natnet: message {got}, expected {expected}")
            }
            NatNetError::UnsupportedVersion(v) => {
                write!(f, "natnet: version {v} not supported (3.0–4.1)")
            }
            NatNetError::BadCount { offset } => write!(f, "natnet: bad count at byte {offset}"),
            NatNetError::BadSectionSize { section, offset } => {
                write!(f, "natnet: bad {section} section size at byte {offset}")
            }
            NatNetError::BadName { offset } => {
                write!(f, "natnet: unterminated name at byte {offset}")
            }
            NatNetError::TrailingBytes { offset } => {
                write!(
                    f,
                    "natnet: bytes after the end of the frame at byte {offset}"
                )
            }
            NatNetError::BufferFull => write!(f, "natnet: output buffer too small"),
            NatNetError::TooLarge => write!(f, "natnet: message too large to encode"),
        }
    }
}

impl std::error::Error for NatNetError {}

/// The message id and payload of a datagram. The payload is the header's byte count long;
/// bytes after it are ignored (as the SDK does).
pub fn split_message(datagram: &[u8]) -> Result<(u16, &[u8]), NatNetError> {
    let (Some(id), Some(n)) = (
        datagram.get(0..2).and_then(|b| b.try_into().ok()),
        datagram.get(2..4).and_then(|b| b.try_into().ok()),
    ) else {
        return Err(NatNetError::LengthMismatch {
            declared: 0,
            actual: datagram.len().saturating_sub(4),
        });
    };
    let n = usize::from(u16::from_le_bytes(n));
    let payload = datagram.get(4..4 + n).ok_or(NatNetError::LengthMismatch {
        declared: n,
        actual: datagram.len() - 4,
    })?;
    Ok((u16::from_le_bytes(id), payload))
}

/// Writes `id`, the payload length and the payload produced by `fill` (which writes into the
/// slice after the header and returns its length).
fn write_message(
    buf: &mut [u8],
    id: u16,
    fill: impl FnOnce(&mut Writer<'_>) -> Result<(), NatNetError>,
) -> Result<usize, NatNetError> {
    let body = buf.get_mut(4..).ok_or(NatNetError::BufferFull)?;
    let mut w = Writer { buf: body, len: 0 };
    fill(&mut w)?;
    let n = u16::try_from(w.len).map_err(|_| NatNetError::TooLarge)?;
    let len = w.len;
    buf[0..2].copy_from_slice(&id.to_le_bytes());
    buf[2..4].copy_from_slice(&n.to_le_bytes());
    Ok(4 + len)
}

struct Writer<'b> {
    buf: &'b mut [u8],
    len: usize,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) -> Result<(), NatNetError> {
        let end = self.len + bytes.len();
        if end > usize::from(u16::MAX) {
            return Err(NatNetError::TooLarge);
        }
        self.buf
            .get_mut(self.len..end)
            .ok_or(NatNetError::BufferFull)?
            .copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    fn i32(&mut self, v: i32) -> Result<(), NatNetError> {
        self.put(&v.to_le_bytes())
    }

    fn count(&mut self, n: usize) -> Result<(), NatNetError> {
        self.i32(i32::try_from(n).map_err(|_| NatNetError::TooLarge)?)
    }

    fn f32s(&mut self, v: &[f32]) -> Result<(), NatNetError> {
        v.iter().try_for_each(|x| self.put(&x.to_le_bytes()))
    }

    /// A section: count, the 4.1 byte count, then the elements written by `body`.
    fn section(
        &mut self,
        version: Version,
        count: usize,
        body: impl FnOnce(&mut Self) -> Result<(), NatNetError>,
    ) -> Result<(), NatNetError> {
        self.count(count)?;
        let size_at = self.len;
        if version.has_sizes() {
            self.i32(0)?;
        }
        let start = self.len;
        body(self)?;
        if version.has_sizes() {
            let size = i32::try_from(self.len - start).map_err(|_| NatNetError::TooLarge)?;
            self.buf[size_at..size_at + 4].copy_from_slice(&size.to_le_bytes());
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Handshake.

/// `NAT_CONNECT` asking for `requested` (the layout of the SDK's clients).
pub fn encode_connect(requested: Version, buf: &mut [u8]) -> Result<usize, NatNetError> {
    write_message(buf, NAT_CONNECT, |w| {
        let mut p = [0u8; CONNECT_PAYLOAD_LEN];
        p[..4].copy_from_slice(b"Ping");
        p[265..269].copy_from_slice(&requested.to_bytes());
        w.put(&p)
    })
}

/// For the emulator: checks a datagram is a `NAT_CONNECT` and returns the version it asks
/// for (`None` for a short "Ping"-only request of older clients, or version 0.0.0.0).
pub fn decode_connect(datagram: &[u8]) -> Result<Option<Version>, NatNetError> {
    let (id, payload) = split_message(datagram)?;
    if id != NAT_CONNECT {
        return Err(NatNetError::WrongMessage {
            expected: NAT_CONNECT,
            got: id,
        });
    }
    Ok(payload
        .get(265..269)
        .and_then(|b| b.try_into().ok())
        .map(Version::from_bytes)
        .filter(|v| *v != Version::default()))
}

/// What `sSender_Server` adds to `sSender` (NatNet ≥ 3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ServerDetails {
    /// Ticks per second of the frame's high-resolution timestamps.
    pub high_res_clock_hz: u64,
    pub data_port: u16,
    pub multicast: bool,
    pub multicast_group: [u8; 4],
}

/// The `NAT_SERVERINFO` reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServerInfo {
    /// NUL-padded application name ("Motive").
    pub app_name: [u8; MAX_NAME_LEN],
    pub app_version: [u8; 4],
    pub natnet_version: Version,
    /// Present when the reply carries `sSender_Server`'s extra fields.
    pub details: Option<ServerDetails>,
}

impl ServerInfo {
    /// `name` is cut to 255 bytes (the field keeps a NUL).
    pub fn new(name: &str, app_version: [u8; 4], natnet_version: Version) -> Self {
        let mut app_name = [0u8; MAX_NAME_LEN];
        let n = name.len().min(MAX_NAME_LEN - 1);
        app_name[..n].copy_from_slice(&name.as_bytes()[..n]);
        ServerInfo {
            app_name,
            app_version,
            natnet_version,
            details: None,
        }
    }

    /// The application name up to its NUL (the valid UTF-8 part of it).
    pub fn app_name(&self) -> &str {
        let n = self
            .app_name
            .iter()
            .position(|&c| c == 0)
            .unwrap_or(MAX_NAME_LEN);
        match std::str::from_utf8(&self.app_name[..n]) {
            Ok(s) => s,
            Err(e) => std::str::from_utf8(&self.app_name[..e.valid_up_to()]).unwrap_or(""),
        }
    }
}

/// Decodes a `NAT_SERVERINFO` datagram (at least the 264 bytes of `sSender`).
pub fn decode_server_info(datagram: &[u8]) -> Result<ServerInfo, NatNetError> {
    let (id, p) = split_message(datagram)?;
    if id != NAT_SERVERINFO {
        return Err(NatNetError::WrongMessage {
            expected: NAT_SERVERINFO,
            got: id,
        });
    }
    let mut r = Reader::new(p);
    let mut info = ServerInfo {
        app_name: r.array()?,
        app_version: r.array()?,
        natnet_version: Version::from_bytes(r.array()?),
        details: None,
    };
    if p.len() >= SENDER_SERVER_LEN {
        info.details = Some(ServerDetails {
            high_res_clock_hz: r.u64()?,
            data_port: r.u16()?,
            multicast: r.array::<1>()?[0] != 0,
            multicast_group: r.array()?,
        });
    }
    Ok(info)
}

/// Writes a `NAT_SERVERINFO` reply (279-byte `sSender_Server` payload with details,
/// 264-byte `sSender` without).
pub fn encode_server_info(info: &ServerInfo, buf: &mut [u8]) -> Result<usize, NatNetError> {
    write_message(buf, NAT_SERVERINFO, |w| {
        w.put(&info.app_name)?;
        w.put(&info.app_version)?;
        w.put(&info.natnet_version.to_bytes())?;
        if let Some(d) = &info.details {
            w.put(&d.high_res_clock_hz.to_le_bytes())?;
            w.put(&d.data_port.to_le_bytes())?;
            w.put(&[u8::from(d.multicast)])?;
            w.put(&d.multicast_group)?;
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------------------
// Frame of data.

/// One rigid body of a frame, in Motive's axes and units (metres).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RigidBody {
    /// The streaming id set in Motive.
    pub id: i32,
    pub position_m: [f32; 3],
    /// Quaternion x, y, z, w.
    pub orientation_xyzw: [f32; 4],
    /// Mean marker error, m.
    pub mean_error_m: f32,
    /// Bit 0: tracking valid.
    pub params: u16,
}

impl RigidBody {
    pub fn tracking_valid(&self) -> bool {
        self.params & 1 != 0
    }

    /// The pose in the world frame; `None` when not tracked or the quaternion is unusable.
    pub fn world_pose(&self, up: UpAxis) -> Option<WorldPose> {
        if !self.tracking_valid() {
            return None;
        }
        to_world(up, self.position_m, self.orientation_xyzw)
    }

    /// Position and heading as the `Mocap` trait reports them.
    pub fn body_pose(&self, up: UpAxis) -> Option<BodyPose> {
        self.world_pose(up).map(|p| BodyPose {
            position_m: p.position_m,
            heading_rad: p.heading_rad,
        })
    }
}

/// A decoded frame. The sections this runtime does not use are counted, not kept.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    pub frame_number: i32,
    pub marker_set_count: u32,
    pub other_marker_count: u32,
    /// Refilled on each decode; keeps its capacity.
    pub rigid_bodies: Vec<RigidBody>,
    pub skeleton_count: u32,
    /// 4.1 only (0 before).
    pub asset_count: u32,
    pub labeled_marker_count: u32,
    pub force_plate_count: u32,
    pub device_count: u32,
    pub timecode: u32,
    pub timecode_sub: u32,
    /// Seconds since Motive started streaming.
    pub timestamp_s: f64,
    /// High-resolution clock ticks (see [`ServerDetails::high_res_clock_hz`]).
    pub camera_mid_exposure_ticks: u64,
    pub camera_data_received_ticks: u64,
    pub transmit_ticks: u64,
    /// 4.1 only (0 before): PTP-style precision timestamp.
    pub precision_timestamp_secs: u32,
    pub precision_timestamp_frac_secs: u32,
    /// Bit 0 recording, bit 1 tracked models changed.
    pub params: u16,
}

impl Frame {
    pub fn is_recording(&self) -> bool {
        self.params & 1 != 0
    }

    pub fn tracked_models_changed(&self) -> bool {
        self.params & 2 != 0
    }

    /// The rigid body with this streaming id.
    pub fn rigid_body(&self, id: i32) -> Option<&RigidBody> {
        self.rigid_bodies.iter().find(|b| b.id == id)
    }
}

struct Reader<'a> {
    b: &'a [u8],
    off: usize,
}

impl<'a> Reader<'a> {
    fn new(b: &'a [u8]) -> Self {
        Reader { b, off: 0 }
    }

    fn remaining(&self) -> usize {
        self.b.len() - self.off
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], NatNetError> {
        let end = self
            .off
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or(NatNetError::Truncated { offset: self.off })?;
        let s = &self.b[self.off..end];
        self.off = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], NatNetError> {
        let s = self.take(N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn u16(&mut self) -> Result<u16, NatNetError> {
        self.array().map(u16::from_le_bytes)
    }

    fn u32(&mut self) -> Result<u32, NatNetError> {
        self.array().map(u32::from_le_bytes)
    }

    fn i32(&mut self) -> Result<i32, NatNetError> {
        self.array().map(i32::from_le_bytes)
    }

    fn u64(&mut self) -> Result<u64, NatNetError> {
        self.array().map(u64::from_le_bytes)
    }

    fn f32(&mut self) -> Result<f32, NatNetError> {
        self.array().map(f32::from_le_bytes)
    }

    fn f64(&mut self) -> Result<f64, NatNetError> {
        self.array().map(f64::from_le_bytes)
    }

    /// A count whose elements take at least `min_elem` bytes each: negative counts and
    /// counts the remaining bytes cannot hold are errors.
    fn count(&mut self, min_elem: usize) -> Result<usize, NatNetError> {
        let at = self.off;
        let n = self.i32()?;
        let n = usize::try_from(n).map_err(|_| NatNetError::BadCount { offset: at })?;
        if n.saturating_mul(min_elem) > self.remaining() {
            return Err(NatNetError::BadCount { offset: at });
        }
        Ok(n)
    }

    /// The 4.1 section byte count; the section must fit.
    fn section_size(&mut self, section: &'static str) -> Result<usize, NatNetError> {
        let at = self.off;
        let n = self.i32()?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= self.remaining())
            .ok_or(NatNetError::BadSectionSize {
                section,
                offset: at,
            })
    }

    fn cstr(&mut self) -> Result<&'a [u8], NatNetError> {
        let rest = &self.b[self.off..];
        let n = rest
            .iter()
            .position(|&c| c == 0)
            .ok_or(NatNetError::BadName { offset: self.off })?;
        self.off += n + 1;
        Ok(&rest[..n])
    }

    fn rigid_body(&mut self) -> Result<RigidBody, NatNetError> {
        Ok(RigidBody {
            id: self.i32()?,
            position_m: [self.f32()?, self.f32()?, self.f32()?],
            orientation_xyzw: [self.f32()?, self.f32()?, self.f32()?, self.f32()?],
            mean_error_m: self.f32()?,
            params: self.u16()?,
        })
    }

    /// A section's opening: its count (elements of at least `min_elem` bytes) and, when the
    /// version has them (`sized`, 4.1), its byte count. In 4.1, sections not decoded are
    /// skipped by their byte count.
    fn open(
        &mut self,
        sized: bool,
        min_elem: usize,
        name: &'static str,
    ) -> Result<(usize, Option<usize>), NatNetError> {
        let n = self.count(min_elem)?;
        let size = if sized {
            Some(self.section_size(name)?)
        } else {
            None
        };
        Ok((n, size))
    }

    /// Checks a section's byte count, if any, against its `n` elements of `elem` bytes.
    fn check_fixed(
        &self,
        n: usize,
        size: Option<usize>,
        elem: usize,
        name: &'static str,
    ) -> Result<(), NatNetError> {
        match size {
            Some(s) if s != n * elem => Err(NatNetError::BadSectionSize {
                section: name,
                offset: self.off,
            }),
            _ => Ok(()),
        }
    }

    /// Force plates and devices: n × (id, channels, per channel k, k × f32).
    fn skip_channels(&mut self, n: usize) -> Result<(), NatNetError> {
        for _ in 0..n {
            self.i32()?;
            let channels = self.count(4)?;
            for _ in 0..channels {
                let k = self.count(4)?;
                self.take(k * 4)?;
            }
        }
        Ok(())
    }
}

/// Decodes a `NAT_FRAMEOFDATA` datagram streamed with NatNet `version` into `out`. The
/// datagram must be exactly the header's length. On error `out` holds partial contents
/// (its rigid-body vector keeps its capacity).
pub fn decode_frame(datagram: &[u8], version: Version, out: &mut Frame) -> Result<(), NatNetError> {
    let (id, payload) = split_message(datagram)?;
    if id != NAT_FRAMEOFDATA {
        return Err(NatNetError::WrongMessage {
            expected: NAT_FRAMEOFDATA,
            got: id,
        });
    }
    if datagram.len() != 4 + payload.len() {
        return Err(NatNetError::LengthMismatch {
            declared: payload.len(),
            actual: datagram.len() - 4,
        });
    }
    decode_frame_payload(payload, version, out)
}

/// [`decode_frame`] on the payload alone (after the 4-byte message header).
pub fn decode_frame_payload(
    payload: &[u8],
    version: Version,
    out: &mut Frame,
) -> Result<(), NatNetError> {
    if !version.is_supported() {
        return Err(NatNetError::UnsupportedVersion(version));
    }
    let sized = version.has_sizes();
    let mut r = Reader::new(payload);
    out.frame_number = r.i32()?;

    // Marker sets: C-string name (≥ 1 byte), i32 count, 12 bytes per marker.
    let (n, size) = r.open(sized, 5, "marker set")?;
    out.marker_set_count = n as u32;
    match size {
        Some(s) => {
            r.take(s)?;
        }
        None => {
            for _ in 0..n {
                r.cstr()?;
                let m = r.count(12)?;
                r.take(m * 12)?;
            }
        }
    }

    // Other (legacy unlabeled) markers: 12 bytes each.
    let (n, size) = r.open(sized, 12, "other marker")?;
    r.check_fixed(n, size, 12, "other marker")?;
    out.other_marker_count = n as u32;
    r.take(n * 12)?;

    // Rigid bodies: 38 bytes each, decoded.
    let (n, size) = r.open(sized, RIGID_BODY_LEN, "rigid body")?;
    r.check_fixed(n, size, RIGID_BODY_LEN, "rigid body")?;
    out.rigid_bodies.clear();
    out.rigid_bodies.reserve(n);
    for _ in 0..n {
        let b = r.rigid_body()?;
        out.rigid_bodies.push(b);
    }

    // Skeletons: i32 id, i32 bone count, 38 bytes per bone.
    let (n, size) = r.open(sized, 8, "skeleton")?;
    out.skeleton_count = n as u32;
    match size {
        Some(s) => {
            r.take(s)?;
        }
        None => {
            for _ in 0..n {
                r.i32()?;
                let m = r.count(RIGID_BODY_LEN)?;
                r.take(m * RIGID_BODY_LEN)?;
            }
        }
    }

    // Assets (4.1): skipped by their byte count.
    out.asset_count = 0;
    if sized {
        let (n, size) = r.open(sized, 0, "asset")?;
        out.asset_count = n as u32;
        r.take(size.unwrap_or(0))?;
    }

    // Labeled markers: 26 bytes each.
    let (n, size) = r.open(sized, LABELED_MARKER_LEN, "labeled marker")?;
    r.check_fixed(n, size, LABELED_MARKER_LEN, "labeled marker")?;
    out.labeled_marker_count = n as u32;
    r.take(n * LABELED_MARKER_LEN)?;

    // Force plates and devices: id, channels, per channel a frame count and floats.
    for (name, count) in [
        ("force plate", &mut out.force_plate_count),
        ("device", &mut out.device_count),
    ] {
        let (n, size) = r.open(sized, 8, name)?;
        *count = n as u32;
        match size {
            Some(s) => {
                r.take(s)?;
            }
            None => r.skip_channels(n)?,
        }
    }

    decode_suffix(&mut r, sized, out)
}

/// The frame's suffix: timecode, timestamps and parameters, then the end-of-data tag, which
/// must end the payload.
fn decode_suffix(r: &mut Reader<'_>, sized: bool, out: &mut Frame) -> Result<(), NatNetError> {
    out.timecode = r.u32()?;
    out.timecode_sub = r.u32()?;
    out.timestamp_s = r.f64()?;
    out.camera_mid_exposure_ticks = r.u64()?;
    out.camera_data_received_ticks = r.u64()?;
    out.transmit_ticks = r.u64()?;
    if sized {
        out.precision_timestamp_secs = r.u32()?;
        out.precision_timestamp_frac_secs = r.u32()?;
    } else {
        out.precision_timestamp_secs = 0;
        out.precision_timestamp_frac_secs = 0;
    }
    out.params = r.u16()?;
    // End-of-data tag (0 from Motive; its value is not checked).
    r.i32()?;
    if r.remaining() != 0 {
        return Err(NatNetError::TrailingBytes { offset: r.off });
    }
    Ok(())
}

/// A marker set to encode: its name and marker positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkerSet<'a> {
    pub name: &'a str,
    pub markers: &'a [[f32; 3]],
}

/// A labeled marker to encode.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LabeledMarker {
    pub id: i32,
    pub position_m: [f32; 3],
    pub size_m: f32,
    pub params: u16,
    pub residual_m: f32,
}

/// What the frame encoder writes (skeletons, assets, force plates and devices are written
/// empty).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameOut<'a> {
    pub frame_number: i32,
    pub marker_sets: &'a [MarkerSet<'a>],
    pub other_markers: &'a [[f32; 3]],
    pub rigid_bodies: &'a [RigidBody],
    pub labeled_markers: &'a [LabeledMarker],
    pub timecode: u32,
    pub timecode_sub: u32,
    pub timestamp_s: f64,
    pub camera_mid_exposure_ticks: u64,
    pub camera_data_received_ticks: u64,
    pub transmit_ticks: u64,
    /// Written in 4.1 only.
    pub precision_timestamp_secs: u32,
    pub precision_timestamp_frac_secs: u32,
    pub params: u16,
}

/// Writes a `NAT_FRAMEOFDATA` datagram in the layout of `version`; returns its length.
pub fn encode_frame(
    frame: &FrameOut<'_>,
    version: Version,
    buf: &mut [u8],
) -> Result<usize, NatNetError> {
    if !version.is_supported() {
        return Err(NatNetError::UnsupportedVersion(version));
    }
    write_message(buf, NAT_FRAMEOFDATA, |w| {
        w.i32(frame.frame_number)?;
        w.section(version, frame.marker_sets.len(), |w| {
            for set in frame.marker_sets {
                if set.name.as_bytes().contains(&0) || set.name.len() >= MAX_NAME_LEN {
                    return Err(NatNetError::TooLarge);
                }
                w.put(set.name.as_bytes())?;
                w.put(&[0])?;
                w.count(set.markers.len())?;
                set.markers.iter().try_for_each(|m| w.f32s(m))?;
            }
            Ok(())
        })?;
        w.section(version, frame.other_markers.len(), |w| {
            frame.other_markers.iter().try_for_each(|m| w.f32s(m))
        })?;
        w.section(version, frame.rigid_bodies.len(), |w| {
            for b in frame.rigid_bodies {
                w.i32(b.id)?;
                w.f32s(&b.position_m)?;
                w.f32s(&b.orientation_xyzw)?;
                w.f32s(&[b.mean_error_m])?;
                w.put(&b.params.to_le_bytes())?;
            }
            Ok(())
        })?;
        w.section(version, 0, |_| Ok(()))?; // skeletons
        if version.has_sizes() {
            w.section(version, 0, |_| Ok(()))?; // assets
        }
        w.section(version, frame.labeled_markers.len(), |w| {
            for m in frame.labeled_markers {
                w.i32(m.id)?;
                w.f32s(&m.position_m)?;
                w.f32s(&[m.size_m])?;
                w.put(&m.params.to_le_bytes())?;
                w.f32s(&[m.residual_m])?;
            }
            Ok(())
        })?;
        w.section(version, 0, |_| Ok(()))?; // force plates
        w.section(version, 0, |_| Ok(()))?; // devices
        w.put(&frame.timecode.to_le_bytes())?;
        w.put(&frame.timecode_sub.to_le_bytes())?;
        w.put(&frame.timestamp_s.to_le_bytes())?;
        w.put(&frame.camera_mid_exposure_ticks.to_le_bytes())?;
        w.put(&frame.camera_data_received_ticks.to_le_bytes())?;
        w.put(&frame.transmit_ticks.to_le_bytes())?;
        if version.has_sizes() {
            w.put(&frame.precision_timestamp_secs.to_le_bytes())?;
            w.put(&frame.precision_timestamp_frac_secs.to_le_bytes())?;
        }
        w.put(&frame.params.to_le_bytes())?;
        w.i32(0) // end-of-data tag
    })
}

// ---------------------------------------------------------------------------------------
// Axes.

/// Motive's up axis (a streaming setting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UpAxis {
    /// Motive's default: x, y up, z (right-handed).
    #[default]
    Y,
    Z,
}

/// A pose in the world frame (`frames.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldPose {
    pub position_m: [f64; 3],
    /// Unit quaternion x, y, z, w: body → world.
    pub orientation_xyzw: [f64; 4],
    /// The body's +x axis in the floor plane, counter-clockwise from world +x, in (−π, π].
    pub heading_rad: f64,
}

/// Motive's position and orientation in the world frame (module docs: Y-up maps
/// (x, y, z) → (x, −z, y)). `None` when a value is not finite or the quaternion is (near)
/// zero; the quaternion is normalised.
pub fn to_world(up: UpAxis, position_m: [f32; 3], orientation_xyzw: [f32; 4]) -> Option<WorldPose> {
    let p = position_m.map(f64::from);
    let q = orientation_xyzw.map(f64::from);
    if !p.iter().chain(q.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if norm < 1e-6 {
        return None;
    }
    let [x, y, z, w] = q.map(|v| v / norm);
    let (position_m, [x, y, z]) = match up {
        UpAxis::Y => ([p[0], -p[2], p[1]], [x, -z, y]),
        UpAxis::Z => (p, [x, y, z]),
    };
    // Body +x in the world: the first column of the rotation matrix.
    let fx = 1.0 - 2.0 * (y * y + z * z);
    let fy = 2.0 * (x * y + w * z);
    Some(WorldPose {
        position_m,
        orientation_xyzw: [x, y, z, w],
        heading_rad: wrap_angle_rad(math::atan2(fy, fx)),
    })
}
