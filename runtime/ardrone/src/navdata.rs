//! AR.Drone 2.0 navdata: decoding a packet into a caller-provided [`Navdata`], writing valid
//! packets ([`NavdataWriter`], for the emulator and tests), and the sequence rule
//! ([`NavdataSequence`]).
//!
//! Layout (little-endian): u32 header `0x55667788` (`0x55667789` also accepted, as
//! node-ar-drone does), u32 drone state, u32 sequence number, u32 vision flag, then options,
//! each u16 tag, u16 size (the 4-byte option header included), payload. The last option is
//! the checksum (tag `0xFFFF`, size 8): the wrapping u32 sum of every byte before it.
//!
//! The decoder walks every option: unknown tags are skipped by their size, a size under 4
//! or past the end is an error, the checksum is required, must be the last option and must
//! match. The demo option (tag 0) and the time option (tag 1) are decoded. Nothing
//! allocates; on error the output is left as it was.

use std::f64::consts::PI;
use std::fmt;

/// The navdata header word.
pub const NAVDATA_HEADER: u32 = 0x5566_7788;
/// The alternative header node-ar-drone also accepts.
pub const NAVDATA_HEADER_ALT: u32 = 0x5566_7789;
/// Largest packet (`NAVDATA_MAX_SIZE`).
pub const NAVDATA_MAX_SIZE: usize = 4096;
/// The first sequence number of a stream (`NAVDATA_SEQUENCE_DEFAULT`).
pub const NAVDATA_SEQUENCE_DEFAULT: u32 = 1;
/// Header, state, sequence, vision flag.
pub const HEADER_LEN: usize = 16;

pub const TAG_DEMO: u16 = 0;
pub const TAG_TIME: u16 = 1;
pub const TAG_CHECKSUM: u16 = 0xFFFF;
/// Size of the demo option, its 4-byte header included.
pub const DEMO_SIZE: u16 = 148;
/// The demo fields this decoder reads end at byte 44 of the option (after `num_frames`);
/// the rest of the 148 bytes are deprecated detection/camera fields.
pub const DEMO_MIN_SIZE: u16 = 44;
pub const TIME_SIZE: u16 = 8;
pub const CHECKSUM_SIZE: u16 = 8;

/// The 32 drone state bits, by bit number.
pub const STATE_BIT_NAMES: [&str; 32] = [
    "flying",
    "video_enabled",
    "vision_enabled",
    "control_angular_speed",
    "altitude_control_active",
    "user_start_button",
    "command_ack",
    "camera_ready",
    "travelling",
    "usb_ready",
    "navdata_demo",
    "navdata_bootstrap",
    "motors_problem",
    "communication_lost",
    "software_fault",
    "battery_low",
    "user_emergency_landing",
    "timer_elapsed",
    "magnetometer_needs_calibration",
    "angles_out_of_range",
    "too_much_wind",
    "ultrasound_deaf",
    "cutout_detected",
    "pic_version_ok",
    "atcodec_thread_on",
    "navdata_thread_on",
    "video_thread_on",
    "acquisition_thread_on",
    "ctrl_watchdog",
    "adc_watchdog",
    "com_watchdog",
    "emergency",
];

/// The drone state bitfield.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct DroneState(pub u32);

impl DroneState {
    pub const FLYING: u32 = 1 << 0;
    pub const VIDEO_ENABLED: u32 = 1 << 1;
    pub const VISION_ENABLED: u32 = 1 << 2;
    /// 0 = Euler-angle control, 1 = angular-speed control.
    pub const CONTROL_ANGULAR_SPEED: u32 = 1 << 3;
    pub const ALTITUDE_CONTROL_ACTIVE: u32 = 1 << 4;
    pub const USER_START_BUTTON: u32 = 1 << 5;
    /// Set after a CONFIG; cleared by `AT*CTRL=seq,5,0`.
    pub const COMMAND_ACK: u32 = 1 << 6;
    pub const CAMERA_READY: u32 = 1 << 7;
    pub const TRAVELLING: u32 = 1 << 8;
    pub const USB_READY: u32 = 1 << 9;
    pub const NAVDATA_DEMO: u32 = 1 << 10;
    /// A freshly booted drone: header + checksum packets only.
    pub const NAVDATA_BOOTSTRAP: u32 = 1 << 11;
    pub const MOTORS_PROBLEM: u32 = 1 << 12;
    pub const COMMUNICATION_LOST: u32 = 1 << 13;
    pub const SOFTWARE_FAULT: u32 = 1 << 14;
    pub const BATTERY_LOW: u32 = 1 << 15;
    pub const USER_EMERGENCY_LANDING: u32 = 1 << 16;
    pub const TIMER_ELAPSED: u32 = 1 << 17;
    pub const MAGNETOMETER_NEEDS_CALIBRATION: u32 = 1 << 18;
    pub const ANGLES_OUT_OF_RANGE: u32 = 1 << 19;
    pub const TOO_MUCH_WIND: u32 = 1 << 20;
    pub const ULTRASOUND_DEAF: u32 = 1 << 21;
    pub const CUTOUT_DETECTED: u32 = 1 << 22;
    pub const PIC_VERSION_OK: u32 = 1 << 23;
    pub const ATCODEC_THREAD_ON: u32 = 1 << 24;
    pub const NAVDATA_THREAD_ON: u32 = 1 << 25;
    pub const VIDEO_THREAD_ON: u32 = 1 << 26;
    pub const ACQUISITION_THREAD_ON: u32 = 1 << 27;
    pub const CTRL_WATCHDOG: u32 = 1 << 28;
    pub const ADC_WATCHDOG: u32 = 1 << 29;
    /// The drone heard no command for too long (the client should reset its navdata
    /// sequence and send `AT*COMWDG`).
    pub const COM_WATCHDOG: u32 = 1 << 30;
    pub const EMERGENCY: u32 = 1 << 31;

    /// Whether every bit of `mask` is set.
    pub fn has(self, mask: u32) -> bool {
        self.0 & mask == mask
    }

    pub fn flying(self) -> bool {
        self.has(Self::FLYING)
    }

    pub fn emergency(self) -> bool {
        self.has(Self::EMERGENCY)
    }

    pub fn com_watchdog(self) -> bool {
        self.has(Self::COM_WATCHDOG)
    }

    pub fn bootstrap(self) -> bool {
        self.has(Self::NAVDATA_BOOTSTRAP)
    }

    pub fn command_ack(self) -> bool {
        self.has(Self::COMMAND_ACK)
    }

    pub fn battery_low(self) -> bool {
        self.has(Self::BATTERY_LOW)
    }

    /// The names of the set bits, lowest bit first ([`STATE_BIT_NAMES`]).
    pub fn flags(self) -> impl Iterator<Item = &'static str> {
        (0..32)
            .filter(move |b| self.0 & (1u32 << b) != 0)
            .map(|b| STATE_BIT_NAMES[b])
    }
}

/// The major control state (`ctrl_state >> 16`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MajorState {
    Default,
    Init,
    Landed,
    Flying,
    Hovering,
    Test,
    TransTakeoff,
    TransGotofix,
    TransLanding,
    TransLooping,
    /// A value the SDK does not name.
    Unknown(u16),
}

impl MajorState {
    pub fn from_raw(v: u16) -> Self {
        match v {
            0 => MajorState::Default,
            1 => MajorState::Init,
            2 => MajorState::Landed,
            3 => MajorState::Flying,
            4 => MajorState::Hovering,
            5 => MajorState::Test,
            6 => MajorState::TransTakeoff,
            7 => MajorState::TransGotofix,
            8 => MajorState::TransLanding,
            9 => MajorState::TransLooping,
            v => MajorState::Unknown(v),
        }
    }

    pub fn raw(self) -> u16 {
        match self {
            MajorState::Default => 0,
            MajorState::Init => 1,
            MajorState::Landed => 2,
            MajorState::Flying => 3,
            MajorState::Hovering => 4,
            MajorState::Test => 5,
            MajorState::TransTakeoff => 6,
            MajorState::TransGotofix => 7,
            MajorState::TransLanding => 8,
            MajorState::TransLooping => 9,
            MajorState::Unknown(v) => v,
        }
    }
}

/// `ctrl_state` of the demo option: `(major << 16) + minor`. The minor state's meaning
/// depends on the major (e.g. HOVERING 8 = LOST_COM, TAKEOFF 1 = AUTO).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ControlState {
    pub major: MajorState,
    pub minor: u16,
}

impl ControlState {
    pub fn from_raw(v: u32) -> Self {
        ControlState {
            major: MajorState::from_raw((v >> 16) as u16),
            minor: v as u16,
        }
    }

    pub fn raw(self) -> u32 {
        (u32::from(self.major.raw()) << 16) | u32::from(self.minor)
    }
}

impl Default for ControlState {
    fn default() -> Self {
        ControlState::from_raw(0)
    }
}

/// The demo option (tag 0), in the drone's units; the methods give SI.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Demo {
    pub ctrl_state: ControlState,
    /// `vbat_flying_percentage` (percent, as every client reads it).
    pub battery_percent: u32,
    /// θ, pitch, millidegrees.
    pub theta_mdeg: f32,
    /// φ, roll, millidegrees.
    pub phi_mdeg: f32,
    /// ψ, yaw, millidegrees (±180000).
    pub psi_mdeg: f32,
    /// Altitude, mm (what every client finds, whatever the SDK comment says).
    pub altitude_mm: i32,
    /// Drone-estimated velocity, mm/s, body-horizontal frame.
    pub vx_mmps: f32,
    pub vy_mmps: f32,
    pub vz_mmps: f32,
    pub num_frames: u32,
}

const MDEG_TO_RAD: f64 = PI / 180_000.0;

impl Demo {
    pub fn pitch_rad(&self) -> f64 {
        f64::from(self.theta_mdeg) * MDEG_TO_RAD
    }

    pub fn roll_rad(&self) -> f64 {
        f64::from(self.phi_mdeg) * MDEG_TO_RAD
    }

    pub fn yaw_rad(&self) -> f64 {
        f64::from(self.psi_mdeg) * MDEG_TO_RAD
    }

    pub fn pitch_deg(&self) -> f64 {
        f64::from(self.theta_mdeg) / 1000.0
    }

    pub fn roll_deg(&self) -> f64 {
        f64::from(self.phi_mdeg) / 1000.0
    }

    pub fn yaw_deg(&self) -> f64 {
        f64::from(self.psi_mdeg) / 1000.0
    }

    pub fn altitude_m(&self) -> f64 {
        f64::from(self.altitude_mm) / 1000.0
    }

    /// `[vx, vy, vz]` in m/s.
    pub fn velocity_mps(&self) -> [f64; 3] {
        [
            f64::from(self.vx_mmps) / 1000.0,
            f64::from(self.vy_mmps) / 1000.0,
            f64::from(self.vz_mmps) / 1000.0,
        ]
    }
}

/// The time option (tag 1): 11 high bits seconds, 21 low bits microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavTime(pub u32);

impl NavTime {
    pub fn from_parts(seconds: u32, micros: u32) -> Self {
        NavTime((seconds << 21) | (micros & 0x1F_FFFF))
    }

    pub fn seconds(self) -> u32 {
        self.0 >> 21
    }

    pub fn micros(self) -> u32 {
        self.0 & 0x1F_FFFF
    }

    pub fn as_secs_f64(self) -> f64 {
        f64::from(self.seconds()) + f64::from(self.micros()) * 1e-6
    }
}

/// One decoded packet.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Navdata {
    /// [`NAVDATA_HEADER`] or [`NAVDATA_HEADER_ALT`].
    pub header: u32,
    pub state: DroneState,
    pub sequence: u32,
    pub vision_defined: u32,
    /// The demo option, when the packet has one (not in bootstrap packets).
    pub demo: Option<Demo>,
    pub time: Option<NavTime>,
    /// The (verified) checksum.
    pub checksum: u32,
    /// Bit `t` set when an option with tag `t < 32` was present.
    pub options_seen: u32,
    /// Number of options other than demo, time and checksum (skipped by size).
    pub skipped_options: u16,
}

/// Why a packet was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NavdataError {
    /// Shorter than the 16-byte header.
    Truncated,
    /// Longer than [`NAVDATA_MAX_SIZE`].
    TooLarge,
    BadHeader(u32),
    /// The option at `offset` has a size under 4 or one that runs past the end.
    BadOptionSize {
        tag: u16,
        size: u16,
        offset: usize,
    },
    /// An option header cut by the end of the packet.
    TruncatedOption {
        offset: usize,
    },
    /// A demo option under [`DEMO_MIN_SIZE`], a time or checksum option not 8 bytes.
    BadKnownOptionSize {
        tag: u16,
        size: u16,
    },
    /// No checksum option.
    MissingChecksum,
    /// Bytes after the checksum option (it must be the last).
    DataAfterChecksum,
    ChecksumMismatch {
        in_packet: u32,
        computed: u32,
    },
    /// The writer's buffer is too small.
    BufferFull,
    /// The writer was asked for an option the protocol cannot carry (tag 0xFFFF, payload
    /// over 65531 bytes).
    BadOption,
}

impl fmt::Display for NavdataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NavdataError::Truncated => write!(f, "navdata: packet shorter than its header"),
            NavdataError::TooLarge => write!(f, "navdata: packet over {NAVDATA_MAX_SIZE} bytes"),
            NavdataError::BadHeader(h) => write!(f, "navdata: bad header {h:#010x}"),
            NavdataError::BadOptionSize { tag, size, offset } => write!(
                f,
                "navdata: option {tag:#06x} at byte {offset} has a bad size {size}"
            ),
            NavdataError::TruncatedOption { offset } => {
                write!(f, "navdata: option header cut at byte {offset}")
            }
            NavdataError::BadKnownOptionSize { tag, size } => {
                write!(f, "navdata: option {tag:#06x} has the wrong size {size}")
            }
            NavdataError::MissingChecksum => write!(f, "navdata: no checksum option"),
            NavdataError::DataAfterChecksum => write!(f, "navdata: data after the checksum"),
            NavdataError::ChecksumMismatch {
                in_packet,
                computed,
            } => write!(
                f,
                "navdata: checksum {in_packet:#x} in the packet, {computed:#x} computed"
            ),
            NavdataError::BufferFull => write!(f, "navdata: output buffer too small"),
            NavdataError::BadOption => write!(f, "navdata: option cannot be encoded"),
        }
    }
}

impl std::error::Error for NavdataError {}

/// The navdata checksum: the wrapping u32 sum of the bytes.
pub fn checksum(bytes: &[u8]) -> u32 {
    bytes
        .iter()
        .fold(0u32, |acc, &b| acc.wrapping_add(u32::from(b)))
}

fn u16_at(b: &[u8], off: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(off..off.checked_add(2)?)?.try_into().ok()?,
    ))
}

fn u32_at(b: &[u8], off: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(off..off.checked_add(4)?)?.try_into().ok()?,
    ))
}

fn f32_at(b: &[u8], off: usize) -> Option<f32> {
    u32_at(b, off).map(f32::from_bits)
}

fn decode_demo(opt: &[u8]) -> Option<Demo> {
    Some(Demo {
        ctrl_state: ControlState::from_raw(u32_at(opt, 4)?),
        battery_percent: u32_at(opt, 8)?,
        theta_mdeg: f32_at(opt, 12)?,
        phi_mdeg: f32_at(opt, 16)?,
        psi_mdeg: f32_at(opt, 20)?,
        altitude_mm: u32_at(opt, 24)? as i32,
        vx_mmps: f32_at(opt, 28)?,
        vy_mmps: f32_at(opt, 32)?,
        vz_mmps: f32_at(opt, 36)?,
        num_frames: u32_at(opt, 40)?,
    })
}

/// Decodes one packet into `out` (left unchanged on error).
pub fn decode(packet: &[u8], out: &mut Navdata) -> Result<(), NavdataError> {
    if packet.len() > NAVDATA_MAX_SIZE {
        return Err(NavdataError::TooLarge);
    }
    let word = |off| u32_at(packet, off).ok_or(NavdataError::Truncated);
    let header = word(0)?;
    if header != NAVDATA_HEADER && header != NAVDATA_HEADER_ALT {
        return Err(NavdataError::BadHeader(header));
    }
    let mut nav = Navdata {
        header,
        state: DroneState(word(4)?),
        sequence: word(8)?,
        vision_defined: word(12)?,
        ..Navdata::default()
    };
    let mut off = HEADER_LEN;
    let mut found_checksum = false;
    while off < packet.len() {
        let (Some(tag), Some(size)) = (u16_at(packet, off), u16_at(packet, off + 2)) else {
            return Err(NavdataError::TruncatedOption { offset: off });
        };
        let end = off + usize::from(size);
        if size < 4 || end > packet.len() {
            return Err(NavdataError::BadOptionSize {
                tag,
                size,
                offset: off,
            });
        }
        let opt = &packet[off..end];
        if tag < 32 {
            nav.options_seen |= 1 << tag;
        }
        match tag {
            TAG_CHECKSUM => {
                if size != CHECKSUM_SIZE {
                    return Err(NavdataError::BadKnownOptionSize { tag, size });
                }
                if end != packet.len() {
                    return Err(NavdataError::DataAfterChecksum);
                }
                let in_packet = u32_at(opt, 4).ok_or(NavdataError::Truncated)?;
                let computed = checksum(&packet[..off]);
                if in_packet != computed {
                    return Err(NavdataError::ChecksumMismatch {
                        in_packet,
                        computed,
                    });
                }
                nav.checksum = in_packet;
                found_checksum = true;
            }
            TAG_DEMO => {
                if size < DEMO_MIN_SIZE {
                    return Err(NavdataError::BadKnownOptionSize { tag, size });
                }
                nav.demo = decode_demo(opt);
            }
            TAG_TIME => {
                if size != TIME_SIZE {
                    return Err(NavdataError::BadKnownOptionSize { tag, size });
                }
                nav.time = u32_at(opt, 4).map(NavTime);
            }
            _ => nav.skipped_options = nav.skipped_options.saturating_add(1),
        }
        off = end;
    }
    if !found_checksum {
        return Err(NavdataError::MissingChecksum);
    }
    *out = nav;
    Ok(())
}

/// Writes a valid packet: the header fields, any options, then the checksum.
#[derive(Debug)]
pub struct NavdataWriter<'b> {
    buf: &'b mut [u8],
    len: usize,
}

impl<'b> NavdataWriter<'b> {
    /// Starts a packet with the standard header [`NAVDATA_HEADER`].
    pub fn new(
        buf: &'b mut [u8],
        state: DroneState,
        sequence: u32,
        vision_defined: u32,
    ) -> Result<Self, NavdataError> {
        Self::with_header(buf, NAVDATA_HEADER, state, sequence, vision_defined)
    }

    pub fn with_header(
        buf: &'b mut [u8],
        header: u32,
        state: DroneState,
        sequence: u32,
        vision_defined: u32,
    ) -> Result<Self, NavdataError> {
        let mut w = NavdataWriter { buf, len: 0 };
        for v in [header, state.0, sequence, vision_defined] {
            w.put(&v.to_le_bytes())?;
        }
        Ok(w)
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), NavdataError> {
        let end = self.len + bytes.len();
        if end > NAVDATA_MAX_SIZE {
            return Err(NavdataError::TooLarge);
        }
        let dst = self
            .buf
            .get_mut(self.len..end)
            .ok_or(NavdataError::BufferFull)?;
        dst.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    fn option_header(&mut self, tag: u16, size: u16) -> Result<(), NavdataError> {
        let start = self.len;
        let r = self
            .put(&tag.to_le_bytes())
            .and_then(|()| self.put(&size.to_le_bytes()));
        if r.is_err() {
            self.len = start;
        }
        r
    }

    /// Any option (tag other than the checksum's), payload after the 4-byte header.
    pub fn option(&mut self, tag: u16, payload: &[u8]) -> Result<(), NavdataError> {
        if tag == TAG_CHECKSUM || payload.len() > usize::from(u16::MAX) - 4 {
            return Err(NavdataError::BadOption);
        }
        let start = self.len;
        let r = self
            .option_header(tag, (payload.len() + 4) as u16)
            .and_then(|()| self.put(payload));
        if r.is_err() {
            self.len = start;
        }
        r
    }

    /// The demo option, 148 bytes (the deprecated tail zero).
    pub fn demo(&mut self, d: &Demo) -> Result<(), NavdataError> {
        let mut p = [0u8; DEMO_SIZE as usize - 4];
        let words = [
            d.ctrl_state.raw(),
            d.battery_percent,
            d.theta_mdeg.to_bits(),
            d.phi_mdeg.to_bits(),
            d.psi_mdeg.to_bits(),
            d.altitude_mm as u32,
            d.vx_mmps.to_bits(),
            d.vy_mmps.to_bits(),
            d.vz_mmps.to_bits(),
            d.num_frames,
        ];
        for (chunk, w) in p.chunks_exact_mut(4).zip(words) {
            chunk.copy_from_slice(&w.to_le_bytes());
        }
        self.option(TAG_DEMO, &p)
    }

    pub fn time(&mut self, t: NavTime) -> Result<(), NavdataError> {
        self.option(TAG_TIME, &t.0.to_le_bytes())
    }

    /// Appends the checksum option; returns the packet length.
    pub fn finish(mut self) -> Result<usize, NavdataError> {
        let cks = checksum(&self.buf[..self.len]);
        self.option_header(TAG_CHECKSUM, CHECKSUM_SIZE)?;
        self.put(&cks.to_le_bytes())?;
        Ok(self.len)
    }
}

/// The sequence rule of the SDK's navdata client (`ardrone_navdata_client.c`): a packet is
/// used only when its sequence number is larger than the last one seen. Every packet, used
/// or not, becomes the last one seen, so after a drone reboot (sequence back to 1) or a
/// wrap-around one packet is dropped and the stream is followed again. A packet with the
/// com-watchdog bit set resets the rule first (the drone restarts its numbering), as does
/// [`NavdataSequence::reset`] (call it on a read timeout, when re-sending the navdata
/// request).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NavdataSequence {
    last: u32,
}

impl Default for NavdataSequence {
    fn default() -> Self {
        Self::new()
    }
}

impl NavdataSequence {
    /// Accepts any sequence number ≥ [`NAVDATA_SEQUENCE_DEFAULT`].
    pub fn new() -> Self {
        NavdataSequence {
            last: NAVDATA_SEQUENCE_DEFAULT - 1,
        }
    }

    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// The last sequence number seen.
    pub fn last(&self) -> u32 {
        self.last
    }

    /// Whether the packet is newer than the last one and should be used.
    pub fn accept(&mut self, sequence: u32, state: DroneState) -> bool {
        if state.com_watchdog() {
            self.reset();
        }
        let newer = sequence > self.last;
        self.last = sequence;
        newer
    }
}
