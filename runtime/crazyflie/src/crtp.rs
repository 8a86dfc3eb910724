//! CRTP, the Crazyflie's packet protocol: the packet (a header byte and up to 30 bytes of
//! payload) and every message this project sends or reads, both ways: [`ToDrone`] (what a
//! client sends; the backend encodes it, the emulator decodes it) and [`FromDrone`] (what
//! the Crazyflie sends; the emulator encodes it, the backend decodes it). Pure: no sockets,
//! no allocation; decoding any bytes gives a message or a [`CrtpError`], never a panic.
//!
//! The header is `port << 4 | 3 << 2 | channel`: bits 2 and 3 set, as cflib sets them (the
//! bootloader's legacy; the radio link reuses them for its sequence bits). Numbers are
//! little-endian. The layouts are the firmware's (`crtp_commander_generic.c`, `log.c`,
//! `param_logic.c`, `platformservice.c`, `crtp_localization_service.c`); the backend's tests
//! compare every packet with what cflib encodes for the same command.

use std::fmt;

/// The most payload bytes a packet carries.
pub const MAX_PAYLOAD: usize = 30;

/// The ports this project uses.
pub mod port {
    pub const CONSOLE: u8 = 0x0;
    pub const PARAM: u8 = 0x2;
    pub const LOG: u8 = 0x5;
    pub const LOCALIZATION: u8 = 0x6;
    pub const GENERIC_COMMANDER: u8 = 0x7;
    pub const SUPERVISOR: u8 = 0x9;
    pub const PLATFORM: u8 = 0xD;
    pub const LINK: u8 = 0xF;
}

/// The generic commander's set-point types.
pub mod setpoint {
    /// Motors off.
    pub const STOP: u8 = 0;
    /// Roll and pitch (degrees), yaw rate (degrees per second), climb rate (m/s).
    pub const ALT_HOLD: u8 = 4;
    /// Position (m) and yaw (degrees), world frame.
    pub const POSITION: u8 = 7;
}

/// The log port's commands (TOC channel 0, settings channel 1).
pub mod log_cmd {
    pub const TOC_ITEM_V2: u8 = 2;
    pub const TOC_INFO_V2: u8 = 3;
    pub const DELETE_BLOCK: u8 = 2;
    pub const START: u8 = 3;
    pub const STOP: u8 = 4;
    pub const RESET: u8 = 5;
    pub const CREATE_BLOCK_V2: u8 = 6;
}

/// The log variables' type codes (the TOC's and the block's).
pub mod log_type {
    pub const UINT8: u8 = 1;
    pub const UINT16: u8 = 2;
    pub const UINT32: u8 = 3;
    pub const INT8: u8 = 4;
    pub const INT16: u8 = 5;
    pub const INT32: u8 = 6;
    pub const FLOAT: u8 = 7;
    pub const FP16: u8 = 8;

    /// The bytes a value of `kind` takes in a log block (`None`: not a log type).
    pub fn size(kind: u8) -> Option<usize> {
        match kind & 0x0F {
            UINT8 | INT8 => Some(1),
            UINT16 | INT16 | FP16 => Some(2),
            UINT32 | INT32 | FLOAT => Some(4),
            _ => None,
        }
    }
}

/// The parameter type code of an unsigned byte (`PARAM_UINT8`).
pub const PARAM_UINT8: u8 = 0x08;

const TOC_CHANNEL: u8 = 0;
const LOG_SETTINGS: u8 = 1;
const LOG_DATA: u8 = 2;
const PARAM_MISC: u8 = 3;
const PARAM_SET_BY_NAME: u8 = 0;
const PLATFORM_COMMAND: u8 = 0;
const PLATFORM_VERSION: u8 = 1;
const VERSION_GET_PROTOCOL: u8 = 0;
const PLATFORM_REQUEST_ARMING: u8 = 1;
const SUPERVISOR_COMMAND: u8 = 1;
const SUPERVISOR_ARM: u8 = 1;
const LOCALIZATION_GENERIC: u8 = 1;
const EXT_POSE: u8 = 8;

/// Why bytes are not a packet or a packet is not the message its port says.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CrtpError {
    /// No header byte.
    Empty,
    /// More than a header and [`MAX_PAYLOAD`] bytes.
    TooLong(usize),
    /// A message of a known kind with the wrong payload length.
    Length { what: &'static str, len: usize },
    /// A name that is not text, or not ended by a zero byte.
    Name(&'static str),
    /// A message too long for one packet (names, log variables).
    Overflow(&'static str),
}

impl fmt::Display for CrtpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CrtpError::Empty => f.write_str("an empty datagram (no CRTP header)"),
            CrtpError::TooLong(n) => write!(
                f,
                "{n} bytes: a CRTP packet is a header and at most {MAX_PAYLOAD} bytes"
            ),
            CrtpError::Length { what, len } => write!(f, "a {what} of {len} payload bytes"),
            CrtpError::Name(what) => write!(f, "a {what} whose names are not zero-ended text"),
            CrtpError::Overflow(what) => write!(f, "a {what} too long for one CRTP packet"),
        }
    }
}

impl std::error::Error for CrtpError {}

/// One CRTP packet: the header and its payload, on the stack.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Packet {
    bytes: [u8; MAX_PAYLOAD + 1],
    len: u8,
}

impl fmt::Debug for Packet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Packet {{ port: {}, channel: {}, payload: {:02x?} }}",
            self.port(),
            self.channel(),
            self.payload()
        )
    }
}

impl Packet {
    /// An empty packet to `port` and `channel`.
    pub fn new(port: u8, channel: u8) -> Packet {
        let mut bytes = [0; MAX_PAYLOAD + 1];
        bytes[0] = (port & 0x0F) << 4 | 3 << 2 | (channel & 0x03);
        Packet { bytes, len: 1 }
    }

    /// A packet from the wire: a header byte and up to [`MAX_PAYLOAD`] bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Packet, CrtpError> {
        match bytes.len() {
            0 => Err(CrtpError::Empty),
            n if n > MAX_PAYLOAD + 1 => Err(CrtpError::TooLong(n)),
            n => {
                let mut p = Packet {
                    bytes: [0; MAX_PAYLOAD + 1],
                    len: n as u8,
                };
                p.bytes[..n].copy_from_slice(bytes);
                Ok(p)
            }
        }
    }

    pub fn header(&self) -> u8 {
        self.bytes[0]
    }

    pub fn port(&self) -> u8 {
        self.bytes[0] >> 4
    }

    pub fn channel(&self) -> u8 {
        self.bytes[0] & 0x03
    }

    pub fn payload(&self) -> &[u8] {
        &self.bytes[1..usize::from(self.len)]
    }

    /// The header and the payload, as a datagram carries them.
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }

    /// Appends `data`, or refuses (the packet unchanged) when it does not fit.
    fn push(&mut self, data: &[u8], what: &'static str) -> Result<(), CrtpError> {
        let at = usize::from(self.len);
        let end = at + data.len();
        if end > MAX_PAYLOAD + 1 {
            return Err(CrtpError::Overflow(what));
        }
        self.bytes[at..end].copy_from_slice(data);
        self.len = end as u8;
        Ok(())
    }

    /// A packet of a payload that fits by its size (checked when compiled).
    fn fixed<const N: usize>(port: u8, channel: u8, payload: [u8; N]) -> Packet {
        const { assert!(N <= MAX_PAYLOAD) };
        let mut p = Packet::new(port, channel);
        p.bytes[1..=N].copy_from_slice(&payload);
        p.len = (N + 1) as u8;
        p
    }
}

/// Writes `values` little-endian after the type byte `kind`.
fn floats<const N: usize>(kind: u8, values: [f32; N]) -> [u8; 29] {
    let mut out = [0u8; 29];
    out[0] = kind;
    for (i, v) in values.iter().enumerate() {
        out[1 + 4 * i..5 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    out
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[i..i + 4]);
    f32::from_le_bytes(a)
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

/// Requires a payload of exactly `n` bytes.
fn exactly(b: &[u8], n: usize, what: &'static str) -> Result<(), CrtpError> {
    if b.len() == n {
        Ok(())
    } else {
        Err(CrtpError::Length { what, len: b.len() })
    }
}

/// The first zero-ended text of `b` and the bytes after its zero.
fn name<'a>(b: &'a [u8], what: &'static str) -> Result<(&'a str, &'a [u8]), CrtpError> {
    let end = b
        .iter()
        .position(|&c| c == 0)
        .ok_or(CrtpError::Name(what))?;
    let text = std::str::from_utf8(&b[..end]).map_err(|_| CrtpError::Name(what))?;
    Ok((text, &b[end + 1..]))
}

/// The log variables of a block being created, three bytes each: the type byte (fetch type
/// in the low nibble, stored type in the high one) and the TOC id.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogOps<'a>(&'a [u8]);

impl<'a> LogOps<'a> {
    /// The most variables one create packet carries.
    pub const MAX: usize = (MAX_PAYLOAD - 2) / 3;

    /// `vars` (type code, TOC id) laid out in `buf`; each variable fetched as it is stored.
    pub fn encode(vars: &[(u8, u16)], buf: &'a mut [u8; 27]) -> Result<LogOps<'a>, CrtpError> {
        if vars.len() > LogOps::MAX {
            return Err(CrtpError::Overflow("log block"));
        }
        for (i, &(kind, id)) in vars.iter().enumerate() {
            let [lo, hi] = id.to_le_bytes();
            buf[3 * i..3 * i + 3].copy_from_slice(&[(kind & 0x0F) * 0x11, lo, hi]);
        }
        Ok(LogOps(&buf[..3 * vars.len()]))
    }

    /// Each variable's (type byte, TOC id).
    pub fn iter(&self) -> impl Iterator<Item = (u8, u16)> + 'a {
        self.0.chunks_exact(3).map(|c| (c[0], u16_at(c, 1)))
    }

    pub fn len(&self) -> usize {
        self.0.len() / 3
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// What a client sends the Crazyflie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToDrone<'a> {
    /// Generic commander altHold: roll and pitch in degrees, yaw rate in degrees per second,
    /// climb rate in m/s (world frame); signs in `frames`.
    AltHold {
        roll_deg: f32,
        pitch_deg: f32,
        yaw_rate_degps: f32,
        vz_mps: f32,
    },
    /// Generic commander stop: motors off.
    Stop,
    /// Generic commander position: hold this place and yaw (world frame).
    Position {
        position_m: [f32; 3],
        yaw_deg: f32,
    },
    /// Localization external pose: position and attitude quaternion `[qx, qy, qz, qw]`.
    ExtPose {
        position_m: [f32; 3],
        quaternion: [f32; 4],
    },
    /// Platform: the CRTP protocol version, please.
    ProtocolVersion,
    /// The log TOC's size and CRC (v2).
    LogTocInfo,
    /// One log TOC entry (v2).
    LogTocItem(u16),
    /// Deletes every log block.
    LogReset,
    LogCreate {
        block: u8,
        ops: LogOps<'a>,
    },
    /// Starts a block, sent every `period_10ms` × 10 ms.
    LogStart {
        block: u8,
        period_10ms: u8,
    },
    LogStop(u8),
    LogDelete(u8),
    /// Parameter write by name (no TOC needed): the type code and the value's bytes.
    SetParam {
        group: &'a str,
        name: &'a str,
        kind: u8,
        value: &'a [u8],
    },
    /// Arming request: through the supervisor port (protocol 12 on), or the platform's
    /// (before).
    Arm {
        arm: bool,
        supervisor: bool,
    },
    /// A well-formed packet this project does not use.
    Other {
        port: u8,
        channel: u8,
    },
}

impl ToDrone<'_> {
    /// The packet, or [`CrtpError::Overflow`] for names or variables too long for one.
    pub fn encode(&self) -> Result<Packet, CrtpError> {
        use ToDrone as T;
        let g = port::GENERIC_COMMANDER;
        Ok(match *self {
            T::AltHold {
                roll_deg,
                pitch_deg,
                yaw_rate_degps,
                vz_mps,
            } => {
                let b = floats(
                    setpoint::ALT_HOLD,
                    [roll_deg, pitch_deg, yaw_rate_degps, vz_mps],
                );
                Packet::fixed::<17>(g, 0, first(&b))
            }
            T::Stop => Packet::fixed(g, 0, [setpoint::STOP]),
            T::Position {
                position_m: [x, y, z],
                yaw_deg,
            } => {
                let b = floats(setpoint::POSITION, [x, y, z, yaw_deg]);
                Packet::fixed::<17>(g, 0, first(&b))
            }
            T::ExtPose {
                position_m: [x, y, z],
                quaternion: [qx, qy, qz, qw],
            } => {
                let b = floats(EXT_POSE, [x, y, z, qx, qy, qz, qw]);
                Packet::fixed(port::LOCALIZATION, LOCALIZATION_GENERIC, b)
            }
            T::ProtocolVersion => {
                Packet::fixed(port::PLATFORM, PLATFORM_VERSION, [VERSION_GET_PROTOCOL])
            }
            T::LogTocInfo => Packet::fixed(port::LOG, TOC_CHANNEL, [log_cmd::TOC_INFO_V2]),
            T::LogTocItem(i) => {
                let [lo, hi] = i.to_le_bytes();
                Packet::fixed(port::LOG, TOC_CHANNEL, [log_cmd::TOC_ITEM_V2, lo, hi])
            }
            T::LogReset => Packet::fixed(port::LOG, LOG_SETTINGS, [log_cmd::RESET]),
            T::LogCreate { block, ops } => {
                let mut p =
                    Packet::fixed(port::LOG, LOG_SETTINGS, [log_cmd::CREATE_BLOCK_V2, block]);
                p.push(ops.0, "log block")?;
                p
            }
            T::LogStart { block, period_10ms } => Packet::fixed(
                port::LOG,
                LOG_SETTINGS,
                [log_cmd::START, block, period_10ms],
            ),
            T::LogStop(block) => Packet::fixed(port::LOG, LOG_SETTINGS, [log_cmd::STOP, block]),
            T::LogDelete(block) => {
                Packet::fixed(port::LOG, LOG_SETTINGS, [log_cmd::DELETE_BLOCK, block])
            }
            T::SetParam {
                group,
                name,
                kind,
                value,
            } => {
                let what = "parameter write";
                if group.contains('\0') || name.contains('\0') {
                    return Err(CrtpError::Name(what));
                }
                let mut p = Packet::fixed(port::PARAM, PARAM_MISC, [PARAM_SET_BY_NAME]);
                p.push(group.as_bytes(), what)?;
                p.push(&[0], what)?;
                p.push(name.as_bytes(), what)?;
                p.push(&[0, kind], what)?;
                p.push(value, what)?;
                p
            }
            T::Arm { arm, supervisor } => {
                if supervisor {
                    Packet::fixed(
                        port::SUPERVISOR,
                        SUPERVISOR_COMMAND,
                        [SUPERVISOR_ARM, arm as u8],
                    )
                } else {
                    Packet::fixed(
                        port::PLATFORM,
                        PLATFORM_COMMAND,
                        [PLATFORM_REQUEST_ARMING, arm as u8],
                    )
                }
            }
            T::Other { port, channel } => Packet::new(port, channel),
        })
    }
}

/// The first `N` bytes of a 29-byte buffer.
fn first<const N: usize>(b: &[u8; 29]) -> [u8; N] {
    let mut out = [0u8; N];
    out.copy_from_slice(&b[..N]);
    out
}

impl<'a> ToDrone<'a> {
    /// What a packet a client sent asks (the emulated Crazyflie's reading).
    pub fn decode(p: &'a Packet) -> Result<ToDrone<'a>, CrtpError> {
        let b = p.payload();
        let other = ToDrone::Other {
            port: p.port(),
            channel: p.channel(),
        };
        Ok(match (p.port(), p.channel(), b.first().copied()) {
            (port::GENERIC_COMMANDER, 0, Some(setpoint::ALT_HOLD)) => {
                exactly(b, 17, "altHold set-point")?;
                ToDrone::AltHold {
                    roll_deg: f32_at(b, 1),
                    pitch_deg: f32_at(b, 5),
                    yaw_rate_degps: f32_at(b, 9),
                    vz_mps: f32_at(b, 13),
                }
            }
            (port::GENERIC_COMMANDER, 0, Some(setpoint::STOP)) => {
                exactly(b, 1, "stop set-point")?;
                ToDrone::Stop
            }
            (port::GENERIC_COMMANDER, 0, Some(setpoint::POSITION)) => {
                exactly(b, 17, "position set-point")?;
                ToDrone::Position {
                    position_m: [f32_at(b, 1), f32_at(b, 5), f32_at(b, 9)],
                    yaw_deg: f32_at(b, 13),
                }
            }
            (port::LOCALIZATION, LOCALIZATION_GENERIC, Some(EXT_POSE)) => {
                exactly(b, 29, "external pose")?;
                ToDrone::ExtPose {
                    position_m: [f32_at(b, 1), f32_at(b, 5), f32_at(b, 9)],
                    quaternion: [f32_at(b, 13), f32_at(b, 17), f32_at(b, 21), f32_at(b, 25)],
                }
            }
            (port::PLATFORM, PLATFORM_VERSION, Some(VERSION_GET_PROTOCOL)) => {
                ToDrone::ProtocolVersion
            }
            (port::LOG, TOC_CHANNEL, Some(log_cmd::TOC_INFO_V2)) => ToDrone::LogTocInfo,
            (port::LOG, TOC_CHANNEL, Some(log_cmd::TOC_ITEM_V2)) => {
                exactly(b, 3, "log TOC request")?;
                ToDrone::LogTocItem(u16_at(b, 1))
            }
            (port::LOG, LOG_SETTINGS, Some(cmd)) => log_setting(cmd, b)?.unwrap_or(other),
            (port::PARAM, PARAM_MISC, Some(PARAM_SET_BY_NAME)) => {
                let what = "parameter write";
                let (group, rest) = name(&b[1..], what)?;
                let (name, rest) = name(rest, what)?;
                let (&kind, value) = rest
                    .split_first()
                    .ok_or(CrtpError::Length { what, len: b.len() })?;
                ToDrone::SetParam {
                    group,
                    name,
                    kind,
                    value,
                }
            }
            (port::SUPERVISOR, SUPERVISOR_COMMAND, Some(SUPERVISOR_ARM))
            | (port::PLATFORM, PLATFORM_COMMAND, Some(PLATFORM_REQUEST_ARMING)) => {
                exactly(b, 2, "arming request")?;
                ToDrone::Arm {
                    arm: b[1] != 0,
                    supervisor: p.port() == port::SUPERVISOR,
                }
            }
            _ => other,
        })
    }
}

/// A log settings command; `None` for one this project does not use.
fn log_setting(cmd: u8, b: &[u8]) -> Result<Option<ToDrone<'_>>, CrtpError> {
    let what = "log block command";
    Ok(Some(match cmd {
        log_cmd::RESET => {
            exactly(b, 1, what)?;
            ToDrone::LogReset
        }
        log_cmd::CREATE_BLOCK_V2 => {
            let n = b.len();
            if n < 2 || !(n - 2).is_multiple_of(3) {
                return Err(CrtpError::Length { what, len: n });
            }
            ToDrone::LogCreate {
                block: b[1],
                ops: LogOps(&b[2..]),
            }
        }
        log_cmd::START => {
            exactly(b, 3, what)?;
            ToDrone::LogStart {
                block: b[1],
                period_10ms: b[2],
            }
        }
        log_cmd::STOP => {
            exactly(b, 2, what)?;
            ToDrone::LogStop(b[1])
        }
        log_cmd::DELETE_BLOCK => {
            exactly(b, 2, what)?;
            ToDrone::LogDelete(b[1])
        }
        _ => return Ok(None),
    }))
}

/// What the Crazyflie sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FromDrone<'a> {
    /// Text from the firmware's console (lines end in `\n`, split across packets).
    Console(&'a [u8]),
    /// The CRTP protocol version.
    ProtocolVersion(u8),
    /// The log TOC: its number of variables and its CRC.
    LogTocInfo { count: u16, crc: u32 },
    /// One log variable: its id, type code, group and name.
    LogTocItem {
        index: u16,
        kind: u8,
        group: &'a str,
        name: &'a str,
    },
    /// A TOC request past its end.
    LogTocEnd,
    /// The answer to a log settings command: the command, the block, an errno (0: done).
    LogAck { command: u8, block: u8, error: u8 },
    /// One sample of a block: the firmware's milliseconds (24 bits) and the values.
    LogData {
        block: u8,
        timestamp_ms: u32,
        data: &'a [u8],
    },
    /// The answer to a parameter write by name: an errno (0: written).
    ParamSet {
        group: &'a str,
        name: &'a str,
        error: u8,
    },
    /// A well-formed packet this project does not read.
    Other { port: u8, channel: u8 },
}

impl FromDrone<'_> {
    /// The packet (the emulated Crazyflie's answer).
    pub fn encode(&self) -> Result<Packet, CrtpError> {
        use FromDrone as F;
        Ok(match *self {
            F::Console(text) => {
                let mut p = Packet::new(port::CONSOLE, 0);
                p.push(text, "console text")?;
                p
            }
            F::ProtocolVersion(v) => Packet::fixed(
                port::PLATFORM,
                PLATFORM_VERSION,
                [VERSION_GET_PROTOCOL, v, 0, 0, 0],
            ),
            F::LogTocInfo { count, crc } => {
                let [c0, c1] = count.to_le_bytes();
                let [r0, r1, r2, r3] = crc.to_le_bytes();
                // The firmware's block and operation limits follow (16 blocks, 128 ops).
                Packet::fixed(
                    port::LOG,
                    TOC_CHANNEL,
                    [log_cmd::TOC_INFO_V2, c0, c1, r0, r1, r2, r3, 16, 128],
                )
            }
            F::LogTocItem {
                index,
                kind,
                group,
                name,
            } => {
                let what = "log TOC entry";
                let [lo, hi] = index.to_le_bytes();
                let mut p =
                    Packet::fixed(port::LOG, TOC_CHANNEL, [log_cmd::TOC_ITEM_V2, lo, hi, kind]);
                p.push(group.as_bytes(), what)?;
                p.push(&[0], what)?;
                p.push(name.as_bytes(), what)?;
                p.push(&[0], what)?;
                p
            }
            F::LogTocEnd => Packet::fixed(port::LOG, TOC_CHANNEL, [log_cmd::TOC_ITEM_V2]),
            F::LogAck {
                command,
                block,
                error,
            } => Packet::fixed(port::LOG, LOG_SETTINGS, [command, block, error]),
            F::LogData {
                block,
                timestamp_ms,
                data,
            } => {
                let [t0, t1, t2, _] = timestamp_ms.to_le_bytes();
                let mut p = Packet::fixed(port::LOG, LOG_DATA, [block, t0, t1, t2]);
                p.push(data, "log sample")?;
                p
            }
            F::ParamSet { group, name, error } => {
                let what = "parameter answer";
                let mut p = Packet::fixed(port::PARAM, PARAM_MISC, [PARAM_SET_BY_NAME]);
                p.push(group.as_bytes(), what)?;
                p.push(&[0], what)?;
                p.push(name.as_bytes(), what)?;
                p.push(&[0, error], what)?;
                p
            }
            F::Other { port, channel } => Packet::new(port, channel),
        })
    }
}

impl<'a> FromDrone<'a> {
    /// What a packet from the Crazyflie says (the backend's reading).
    pub fn decode(p: &'a Packet) -> Result<FromDrone<'a>, CrtpError> {
        let b = p.payload();
        let other = FromDrone::Other {
            port: p.port(),
            channel: p.channel(),
        };
        Ok(match (p.port(), p.channel(), b.first().copied()) {
            (port::CONSOLE, 0, _) => FromDrone::Console(b),
            (port::PLATFORM, PLATFORM_VERSION, Some(VERSION_GET_PROTOCOL)) => {
                // The firmware sends an int32; cflib reads its low byte, as here.
                let v = *b.get(1).ok_or(CrtpError::Length {
                    what: "protocol version",
                    len: b.len(),
                })?;
                FromDrone::ProtocolVersion(v)
            }
            (port::LOG, TOC_CHANNEL, Some(log_cmd::TOC_INFO_V2)) => {
                if b.len() < 7 {
                    return Err(CrtpError::Length {
                        what: "log TOC info",
                        len: b.len(),
                    });
                }
                FromDrone::LogTocInfo {
                    count: u16_at(b, 1),
                    crc: u32::from_le_bytes([b[3], b[4], b[5], b[6]]),
                }
            }
            (port::LOG, TOC_CHANNEL, Some(log_cmd::TOC_ITEM_V2)) => toc_item(b)?,
            (port::LOG, LOG_SETTINGS, Some(command)) => {
                exactly(b, 3, "log block answer")?;
                FromDrone::LogAck {
                    command,
                    block: b[1],
                    error: b[2],
                }
            }
            (port::LOG, LOG_DATA, _) => {
                if b.len() < 4 {
                    return Err(CrtpError::Length {
                        what: "log sample",
                        len: b.len(),
                    });
                }
                FromDrone::LogData {
                    block: b[0],
                    timestamp_ms: u32::from_le_bytes([b[1], b[2], b[3], 0]),
                    data: &b[4..],
                }
            }
            (port::PARAM, PARAM_MISC, Some(PARAM_SET_BY_NAME)) => {
                let what = "parameter answer";
                let (group, rest) = name(&b[1..], what)?;
                let (name, rest) = name(rest, what)?;
                let [error] = rest else {
                    return Err(CrtpError::Length { what, len: b.len() });
                };
                FromDrone::ParamSet {
                    group,
                    name,
                    error: *error,
                }
            }
            _ => other,
        })
    }
}

/// A log TOC entry, or the end of the TOC.
fn toc_item(b: &[u8]) -> Result<FromDrone<'_>, CrtpError> {
    let what = "log TOC entry";
    if b.len() == 1 {
        return Ok(FromDrone::LogTocEnd);
    }
    if b.len() < 4 {
        return Err(CrtpError::Length { what, len: b.len() });
    }
    let (group, rest) = name(&b[4..], what)?;
    let (name, rest) = name(rest, what)?;
    if !rest.is_empty() {
        return Err(CrtpError::Length { what, len: b.len() });
    }
    Ok(FromDrone::LogTocItem {
        index: u16_at(b, 1),
        kind: b[3],
        group,
        name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_is_port_reserved_bits_and_channel() {
        let p = Packet::new(port::GENERIC_COMMANDER, 0);
        assert_eq!(p.header(), 0x7C);
        assert_eq!(Packet::new(port::LOG, 2).header(), 0x5E);
        assert_eq!(Packet::new(port::PLATFORM, 1).header(), 0xDD);
        let p = Packet::from_bytes(&[0x5E, 1, 2]).unwrap();
        assert_eq!((p.port(), p.channel(), p.payload()), (5, 2, &[1u8, 2][..]));
        assert_eq!(Packet::from_bytes(&[]), Err(CrtpError::Empty));
        assert_eq!(Packet::from_bytes(&[0; 32]), Err(CrtpError::TooLong(32)));
    }

    #[test]
    fn alt_hold_is_a_type_byte_and_four_floats() {
        let p = ToDrone::AltHold {
            roll_deg: 1.0,
            pitch_deg: -2.0,
            yaw_rate_degps: 0.5,
            vz_mps: 0.25,
        }
        .encode()
        .unwrap();
        let mut want = vec![0x7C, 4];
        for v in [1.0f32, -2.0, 0.5, 0.25] {
            want.extend(v.to_le_bytes());
        }
        assert_eq!(p.as_bytes(), &want[..]);
    }

    /// Every message decodes to itself.
    #[test]
    fn messages_round_trip() {
        let mut buf = [0u8; 27];
        let ops = LogOps::encode(&[(7, 300), (1, 2)], &mut buf).unwrap();
        let to = [
            ToDrone::AltHold {
                roll_deg: 3.0,
                pitch_deg: -1.5,
                yaw_rate_degps: 45.0,
                vz_mps: -0.3,
            },
            ToDrone::Stop,
            ToDrone::Position {
                position_m: [1.0, -2.0, 1.5],
                yaw_deg: 90.0,
            },
            ToDrone::ExtPose {
                position_m: [0.1, 0.2, 0.3],
                quaternion: [0.0, 0.0, 0.38268343, 0.9238795],
            },
            ToDrone::ProtocolVersion,
            ToDrone::LogTocInfo,
            ToDrone::LogTocItem(513),
            ToDrone::LogReset,
            ToDrone::LogCreate { block: 1, ops },
            ToDrone::LogStart {
                block: 1,
                period_10ms: 10,
            },
            ToDrone::LogStop(1),
            ToDrone::LogDelete(2),
            ToDrone::SetParam {
                group: "stabilizer",
                name: "estimator",
                kind: PARAM_UINT8,
                value: &[2],
            },
            ToDrone::Arm {
                arm: true,
                supervisor: true,
            },
            ToDrone::Arm {
                arm: false,
                supervisor: false,
            },
        ];
        for m in to {
            let p = m.encode().unwrap();
            assert_eq!(ToDrone::decode(&p).unwrap(), m, "{p:?}");
        }
        assert_eq!(ops.iter().collect::<Vec<_>>(), [(0x77, 300), (0x11, 2)]);
        let from = [
            FromDrone::Console(b"SYS: Crazyflie 2.1\n"),
            FromDrone::ProtocolVersion(12),
            FromDrone::LogTocInfo {
                count: 450,
                crc: 0xDEAD_BEEF,
            },
            FromDrone::LogTocItem {
                index: 17,
                kind: 7,
                group: "stateEstimate",
                name: "z",
            },
            FromDrone::LogTocEnd,
            FromDrone::LogAck {
                command: log_cmd::CREATE_BLOCK_V2,
                block: 1,
                error: 0,
            },
            FromDrone::LogData {
                block: 2,
                timestamp_ms: 0x00AB_CDEF,
                data: &[1, 2, 3],
            },
            FromDrone::ParamSet {
                group: "stabilizer",
                name: "estimator",
                error: 0,
            },
        ];
        for m in from {
            let p = m.encode().unwrap();
            assert_eq!(FromDrone::decode(&p).unwrap(), m, "{p:?}");
        }
    }

    #[test]
    fn malformed_messages_are_errors() {
        let p = |bytes: &[u8]| Packet::from_bytes(bytes).unwrap();
        // An altHold one float short.
        let short = p(&[0x7C, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert!(matches!(
            ToDrone::decode(&short),
            Err(CrtpError::Length { .. })
        ));
        // A parameter write whose name has no end.
        let open = p(&[0x2F, 0, b'a', 0, b'b']);
        assert_eq!(
            ToDrone::decode(&open),
            Err(CrtpError::Name("parameter write"))
        );
        // A log sample without its timestamp.
        let data = p(&[0x5E, 1, 2]);
        assert!(FromDrone::decode(&data).is_err());
        // A TOC entry whose group is not text.
        let item = p(&[0x5C, 2, 0, 0, 7, 0xFF, 0, b'z', 0]);
        assert_eq!(
            FromDrone::decode(&item),
            Err(CrtpError::Name("log TOC entry"))
        );
        // Names too long for one packet.
        let long = "x".repeat(20);
        let set = ToDrone::SetParam {
            group: &long,
            name: &long,
            kind: PARAM_UINT8,
            value: &[1],
        };
        assert_eq!(set.encode(), Err(CrtpError::Overflow("parameter write")));
        let mut buf = [0u8; 27];
        assert!(LogOps::encode(&[(7, 1); 10], &mut buf).is_err());
    }
}
