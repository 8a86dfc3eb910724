//! AR.Drone 2.0 AT commands: the encoder, the mapping of the generic [`Command`] to `AT*PCMD`
//! values, the start-up `AT*CONFIG` lines carrying a profile's limits, and a tolerant parser
//! (for the emulator).
//!
//! Wire format: `AT*<NAME>=<seq>[,<arg>...]\r`, several lines per UDP datagram, each line
//! at most [`MAX_LINE_LEN`] bytes (the `\r` included). Integers in decimal; floats as the
//! decimal value of their IEEE-754 bits read as an `i32` (1.0 → `1065353216`); strings in
//! double quotes with no escaping, so a string holding `"`, `\r` or `\n` is refused.
//!
//! One [`AtEncoder`] per drone: every command of every kind takes the next value of its one
//! sequence counter, starting at 1 (the value that makes the drone reset its own counter).
//! A command that does not fit the datagram (or is refused) consumes no sequence number.
//!
//! Nothing here allocates: the encoder writes into a caller-provided buffer ([`Datagram`]),
//! the parser borrows its strings from the datagram.

use std::fmt;

use dronecine_profile::Limits;

use dronecine_backend::frames::Command;

/// Longest accepted command line, its terminating `\r` included (the drone rejects longer
/// lines).
pub const MAX_LINE_LEN: usize = 1024;

/// `AT*REF` input with only the legacy "always set" bits 18, 20, 22, 24 and 28: land / idle.
pub const REF_BASE: u32 = 0x1154_0000;
/// `AT*REF` bit 9 (START): 1 = take off / keep flying, 0 = land.
pub const REF_TAKE_OFF_BIT: u32 = 1 << 9;
/// `AT*REF` bit 8 (SELECT): emergency toggle (cuts the motors in flight, clears an emergency).
pub const REF_EMERGENCY_BIT: u32 = 1 << 8;

/// `AT*PCMD` flag bit 0: progressive commands (the four values are used). Flag 0 = hover.
pub const PCMD_PROGRESSIVE: i32 = 1;
/// `AT*PCMD` flag bit 1: combined yaw.
pub const PCMD_COMBINED_YAW: i32 = 1 << 1;
/// `AT*PCMD` flag bit 2: absolute (magnetometer) control, with `AT*PCMD_MAG`.
pub const PCMD_ABSOLUTE: i32 = 1 << 2;

/// `AT*CTRL` mode 4: send the configuration file on TCP 5559.
pub const CTRL_GET_CONFIG: i32 = 4;
/// `AT*CTRL` mode 5: acknowledge (clears the command-ACK state bit 6).
pub const CTRL_ACK: i32 = 5;
/// `AT*CTRL` mode 6: custom configuration ids.
pub const CTRL_CUSTOM_CFG: i32 = 6;

/// The configuration keys the generic limits are written to.
pub const KEY_EULER_ANGLE_MAX: &str = "control:euler_angle_max";
pub const KEY_CONTROL_VZ_MAX: &str = "control:control_vz_max";
pub const KEY_CONTROL_YAW: &str = "control:control_yaw";

/// The ranges the Developer Guide recommends for the three limits, in SI units.
pub const EULER_ANGLE_MAX_RANGE_RAD: (f64, f64) = (0.0, 0.52);
pub const CONTROL_VZ_MAX_RANGE_MPS: (f64, f64) = (0.2, 2.0);
pub const CONTROL_YAW_RANGE_RADPS: (f64, f64) = (0.7, 6.11);

/// The arguments of `AT*PCMD` (and the first five of `AT*PCMD_MAG`): the flag and four
/// normalised values in −1..1, in the AR.Drone's signs: roll + = tilt right,
/// pitch + = nose up (moves backward), gaz + = climb, yaw + = clockwise seen from above.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pcmd {
    pub flag: i32,
    pub roll: f32,
    pub pitch: f32,
    pub gaz: f32,
    pub yaw: f32,
}

impl Pcmd {
    /// Flag 0 and zeros: the drone ignores the values and holds its position on its own.
    pub const HOVER: Pcmd = Pcmd {
        flag: 0,
        roll: 0.0,
        pitch: 0.0,
        gaz: 0.0,
        yaw: 0.0,
    };

    /// Progressive command with the four values (flag = [`PCMD_PROGRESSIVE`]).
    pub fn progressive(roll: f32, pitch: f32, gaz: f32, yaw: f32) -> Pcmd {
        Pcmd {
            flag: PCMD_PROGRESSIVE,
            roll,
            pitch,
            gaz,
            yaw,
        }
    }

    pub fn is_hover(&self) -> bool {
        self.flag & PCMD_PROGRESSIVE == 0
    }
}

/// One AT command, without its sequence number. Strings are borrowed (from the caller when
/// encoding, from the datagram when parsing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AtCommand<'a> {
    /// `AT*REF=seq,input`: the take-off / land / emergency bitfield.
    Ref { input: u32 },
    /// `AT*PCMD=seq,flag,roll,pitch,gaz,yaw`.
    Pcmd(Pcmd),
    /// `AT*PCMD_MAG=seq,flag,roll,pitch,gaz,yaw,psi,psi_accuracy` (psi values normalised
    /// −1..1).
    PcmdMag {
        pcmd: Pcmd,
        psi: f32,
        psi_accuracy: f32,
    },
    /// `AT*FTRIM=seq`: flat trim (on the ground only).
    Ftrim,
    /// `AT*CONFIG=seq,"key","value"`.
    Config { key: &'a str, value: &'a str },
    /// `AT*CONFIG_IDS=seq,"session","user","application"` (precedes each CONFIG in
    /// multi-configuration mode, same datagram).
    ConfigIds {
        session: &'a str,
        user: &'a str,
        application: &'a str,
    },
    /// `AT*COMWDG=seq`: reset the communication watchdog.
    Comwdg,
    /// `AT*CTRL=seq,mode,arg` (arg is 0 in every use known).
    Ctrl { mode: i32, arg: i32 },
    /// `AT*CALIB=seq,device` (0 = magnetometer; in flight only).
    Calib { device: i32 },
}

impl AtCommand<'static> {
    /// `AT*REF` with the take-off bit clear: land (or stay landed).
    pub const LAND: AtCommand<'static> = AtCommand::Ref { input: REF_BASE };
    /// `AT*REF` with the take-off bit: take off (or keep flying).
    pub const TAKE_OFF: AtCommand<'static> = AtCommand::Ref {
        input: REF_BASE | REF_TAKE_OFF_BIT,
    };
    /// `AT*REF` with the emergency bit (take-off bit clear).
    pub const EMERGENCY: AtCommand<'static> = AtCommand::Ref {
        input: REF_BASE | REF_EMERGENCY_BIT,
    };
    pub const HOVER: AtCommand<'static> = AtCommand::Pcmd(Pcmd::HOVER);
    /// `AT*CTRL=seq,5,0`: acknowledge a command (clears state bit 6).
    pub const ACK: AtCommand<'static> = AtCommand::Ctrl {
        mode: CTRL_ACK,
        arg: 0,
    };
}

impl AtCommand<'_> {
    /// The name after `AT*`.
    pub fn name(&self) -> &'static str {
        match self {
            AtCommand::Ref { .. } => "REF",
            AtCommand::Pcmd(_) => "PCMD",
            AtCommand::PcmdMag { .. } => "PCMD_MAG",
            AtCommand::Ftrim => "FTRIM",
            AtCommand::Config { .. } => "CONFIG",
            AtCommand::ConfigIds { .. } => "CONFIG_IDS",
            AtCommand::Comwdg => "COMWDG",
            AtCommand::Ctrl { .. } => "CTRL",
            AtCommand::Calib { .. } => "CALIB",
        }
    }
}

/// What an `AT*REF` input asks for. Only bits 8 and 9 count (node-ar-drone sends REF
/// without the legacy bits and the drone takes it).
pub fn ref_take_off(input: u32) -> bool {
    input & REF_TAKE_OFF_BIT != 0
}

/// See [`ref_take_off`].
pub fn ref_emergency(input: u32) -> bool {
    input & REF_EMERGENCY_BIT != 0
}

/// A float as it goes on the wire: its IEEE-754 bits read as an `i32`.
pub fn float_to_wire(v: f32) -> i32 {
    v.to_bits() as i32
}

/// The inverse of [`float_to_wire`].
pub fn wire_to_float(v: i32) -> f32 {
    f32::from_bits(v as u32)
}

/// Why a command could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtError {
    /// The datagram buffer has no room for the line (nothing was written).
    BufferFull,
    /// The line would be longer than [`MAX_LINE_LEN`].
    LineTooLong,
    /// A quoted string holds `"`, `\r` or `\n` (the protocol has no escaping).
    BadString,
    /// A limit is not finite, not positive, or outside the range the firmware documents
    /// (the key says which).
    LimitOutOfRange(&'static str),
}

impl fmt::Display for AtError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AtError::BufferFull => write!(f, "the AT datagram buffer is full"),
            AtError::LineTooLong => write!(f, "AT command line over {MAX_LINE_LEN} bytes"),
            AtError::BadString => write!(f, "AT string argument holds '\"', CR or LF"),
            AtError::LimitOutOfRange(k) => write!(f, "{k}: limit outside the firmware's range"),
        }
    }
}

impl std::error::Error for AtError {}

/// A datagram being filled: a caller-provided buffer and how much of it is used.
#[derive(Debug)]
pub struct Datagram<'b> {
    buf: &'b mut [u8],
    len: usize,
}

impl<'b> Datagram<'b> {
    pub fn new(buf: &'b mut [u8]) -> Self {
        Datagram { buf, len: 0 }
    }

    /// The bytes to send.
    pub fn as_bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Empties the datagram (keeps the buffer).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), AtError> {
        let end = self
            .len
            .checked_add(bytes.len())
            .ok_or(AtError::BufferFull)?;
        let dst = self.buf.get_mut(self.len..end).ok_or(AtError::BufferFull)?;
        dst.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    fn put_int(&mut self, v: i64) -> Result<(), AtError> {
        let mut b = itoa::Buffer::new();
        self.put(b.format(v).as_bytes())
    }

    fn put_str(&mut self, s: &str) -> Result<(), AtError> {
        if s.bytes().any(|c| c == b'"' || c == b'\r' || c == b'\n') {
            return Err(AtError::BadString);
        }
        self.put(b",\"")?;
        self.put(s.as_bytes())?;
        self.put(b"\"")
    }
}

/// The AT command encoder: one global sequence counter per drone.
#[derive(Clone, Debug)]
pub struct AtEncoder {
    next: u32,
}

impl Default for AtEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl AtEncoder {
    /// The first command will carry sequence number 1.
    pub fn new() -> Self {
        AtEncoder { next: 1 }
    }

    /// The sequence number the next command will carry.
    pub fn next_seq(&self) -> u32 {
        self.next
    }

    /// Starts again at 1 (the drone resets its counter when it sees 1; do this after the
    /// link was lost for more than 2 s, when the drone forgot the client).
    pub fn reset(&mut self) {
        self.next = 1;
    }

    /// Appends one command line to `dg` and returns the sequence number it carries. On error
    /// nothing is written and no sequence number is used.
    pub fn push(&mut self, dg: &mut Datagram<'_>, cmd: &AtCommand<'_>) -> Result<u32, AtError> {
        let start = dg.len;
        let seq = self.next;
        match write_line(dg, seq, cmd) {
            Ok(()) if dg.len - start <= MAX_LINE_LEN => {
                // The drone reads seq as a signed int: wrap to 1 (its reset value) before
                // the sign bit.
                self.next = if seq >= i32::MAX as u32 { 1 } else { seq + 1 };
                Ok(seq)
            }
            Ok(()) => {
                dg.len = start;
                Err(AtError::LineTooLong)
            }
            Err(e) => {
                dg.len = start;
                // A line that does not fit a buffer larger than the limit is too long, not
                // a full buffer.
                Err(
                    if e == AtError::BufferFull && dg.buf.len() - start > MAX_LINE_LEN {
                        AtError::LineTooLong
                    } else {
                        e
                    },
                )
            }
        }
    }
}

fn write_line(dg: &mut Datagram<'_>, seq: u32, cmd: &AtCommand<'_>) -> Result<(), AtError> {
    dg.put(b"AT*")?;
    dg.put(cmd.name().as_bytes())?;
    dg.put(b"=")?;
    dg.put_int(i64::from(seq))?;
    let pcmd = |dg: &mut Datagram<'_>, p: &Pcmd| -> Result<(), AtError> {
        for v in [
            p.flag,
            float_to_wire(p.roll),
            float_to_wire(p.pitch),
            float_to_wire(p.gaz),
            float_to_wire(p.yaw),
        ] {
            dg.put(b",")?;
            dg.put_int(i64::from(v))?;
        }
        Ok(())
    };
    match cmd {
        AtCommand::Ref { input } => {
            dg.put(b",")?;
            dg.put_int(i64::from(*input as i32))?;
        }
        AtCommand::Pcmd(p) => pcmd(dg, p)?,
        AtCommand::PcmdMag {
            pcmd: p,
            psi,
            psi_accuracy,
        } => {
            pcmd(dg, p)?;
            for v in [float_to_wire(*psi), float_to_wire(*psi_accuracy)] {
                dg.put(b",")?;
                dg.put_int(i64::from(v))?;
            }
        }
        AtCommand::Ftrim | AtCommand::Comwdg => {}
        AtCommand::Config { key, value } => {
            dg.put_str(key)?;
            dg.put_str(value)?;
        }
        AtCommand::ConfigIds {
            session,
            user,
            application,
        } => {
            dg.put_str(session)?;
            dg.put_str(user)?;
            dg.put_str(application)?;
        }
        AtCommand::Ctrl { mode, arg } => {
            dg.put(b",")?;
            dg.put_int(i64::from(*mode))?;
            dg.put(b",")?;
            dg.put_int(i64::from(*arg))?;
        }
        AtCommand::Calib { device } => {
            dg.put(b",")?;
            dg.put_int(i64::from(*device))?;
        }
    }
    dg.put(b"\r")
}

/// The drone's three control limits, as written to its configuration and as used to
/// normalise the generic command. Values are rounded to what goes on the wire
/// (1e-6 rad, 1 mm/s, 1e-6 rad/s), so the normalisation uses exactly the limits the drone
/// was given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcmdLimits {
    /// `control:euler_angle_max` (radians).
    euler_angle_max_rad: f64,
    /// `control:control_vz_max` (the firmware takes mm/s).
    control_vz_max_mmps: f64,
    /// `control:control_yaw` (rad/s).
    control_yaw_radps: f64,
}

/// `v` rounded to `1/per_unit` (dividing by the exact power of ten gives the f64 nearest to
/// the short decimal, so it prints short).
fn round_to(v: f64, per_unit: f64) -> f64 {
    (v * per_unit).round() / per_unit
}

fn check_range(v: f64, (lo, hi): (f64, f64), key: &'static str) -> Result<(), AtError> {
    // A tilt of exactly 0 cannot normalise anything: the lower bound is exclusive when 0.
    if v.is_finite() && v > 0.0 && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(AtError::LimitOutOfRange(key))
    }
}

impl PcmdLimits {
    /// Checks the limits against the ranges the Developer Guide documents: tilt in
    /// (0, 0.52] rad, vertical speed in [0.2, 2.0] m/s, yaw rate in [0.7, 6.11] rad/s.
    pub fn new(
        euler_angle_max_rad: f64,
        control_vz_max_mps: f64,
        control_yaw_radps: f64,
    ) -> Result<Self, AtError> {
        check_range(
            euler_angle_max_rad,
            EULER_ANGLE_MAX_RANGE_RAD,
            KEY_EULER_ANGLE_MAX,
        )?;
        check_range(
            control_vz_max_mps,
            CONTROL_VZ_MAX_RANGE_MPS,
            KEY_CONTROL_VZ_MAX,
        )?;
        check_range(control_yaw_radps, CONTROL_YAW_RANGE_RADPS, KEY_CONTROL_YAW)?;
        let euler = round_to(euler_angle_max_rad, 1e6);
        if euler <= 0.0 {
            return Err(AtError::LimitOutOfRange(KEY_EULER_ANGLE_MAX));
        }
        Ok(PcmdLimits {
            euler_angle_max_rad: euler,
            control_vz_max_mmps: (control_vz_max_mps * 1000.0).round(),
            control_yaw_radps: round_to(control_yaw_radps, 1e6),
        })
    }

    /// A profile's `tilt_max_rad`, `vz_max_mps` and `yaw_rate_max_radps`.
    pub fn from_profile(limits: &Limits) -> Result<Self, AtError> {
        Self::new(
            limits.tilt_max_rad,
            limits.vz_max_mps,
            limits.yaw_rate_max_radps,
        )
    }

    pub fn euler_angle_max_rad(&self) -> f64 {
        self.euler_angle_max_rad
    }

    pub fn control_vz_max_mps(&self) -> f64 {
        self.control_vz_max_mmps / 1000.0
    }

    pub fn control_yaw_radps(&self) -> f64 {
        self.control_yaw_radps
    }

    /// The generic command as `AT*PCMD` values: roll and pitch ÷ `euler_angle_max`, gaz =
    /// vz ÷ `control_vz_max`, yaw = yaw rate ÷ `control_yaw`, each clamped to [−1, 1], signs
    /// unchanged (the generic command already uses the AR.Drone's, `frames.rs`). Always
    /// progressive (flag 1), so zeros mean "level, no climb, no turn", not the drone's own
    /// position hold. A command with any non-finite value gives [`Pcmd::HOVER`].
    pub fn pcmd(&self, cmd: &Command) -> Pcmd {
        if !cmd.is_finite() {
            return Pcmd::HOVER;
        }
        // `+ 0.0` turns −0.0 into +0.0, so zero always goes out as `0`.
        let norm = |v: f64, max: f64| ((v / max).clamp(-1.0, 1.0) as f32) + 0.0;
        Pcmd::progressive(
            norm(cmd.roll_rad, self.euler_angle_max_rad),
            norm(cmd.pitch_rad, self.euler_angle_max_rad),
            norm(cmd.vz_mps, self.control_vz_max_mps()),
            norm(cmd.yaw_rate_radps, self.control_yaw_radps),
        )
    }

    /// The three `AT*CONFIG` lines that give the drone these limits, in the units the
    /// firmware's configuration uses (a real fw 2.4.8 `config.ini`: `euler_angle_max` in
    /// rad, `control_vz_max` in mm/s, `control_yaw` in rad/s).
    pub fn config_lines(&self) -> [ConfigLine; 3] {
        [
            ConfigLine::new(KEY_EULER_ANGLE_MAX, self.euler_angle_max_rad),
            ConfigLine::new(KEY_CONTROL_VZ_MAX, self.control_vz_max_mmps),
            ConfigLine::new(KEY_CONTROL_YAW, self.control_yaw_radps),
        ]
    }
}

/// One `AT*CONFIG` key and its value text, held without allocation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConfigLine {
    pub key: &'static str,
    value: [u8; 32],
    value_len: u8,
}

struct FixedWriter<'a> {
    buf: &'a mut [u8; 32],
    len: usize,
}

impl fmt::Write for FixedWriter<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        let dst = self.buf.get_mut(self.len..end).ok_or(fmt::Error)?;
        dst.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

impl ConfigLine {
    /// `value` printed in plain decimal (shortest text that reads back to it; never an
    /// exponent: Rust's `Display` for `f64` never writes one).
    fn new(key: &'static str, value: f64) -> Self {
        use fmt::Write;
        let mut buf = [0u8; 32];
        let mut w = FixedWriter {
            buf: &mut buf,
            len: 0,
        };
        // Limits were range-checked and rounded: the text is short ("0.20944", "700").
        let len = if write!(w, "{value}").is_ok() {
            w.len
        } else {
            0
        };
        ConfigLine {
            key,
            value: buf,
            value_len: len as u8,
        }
    }

    pub fn value(&self) -> &str {
        std::str::from_utf8(&self.value[..self.value_len as usize]).unwrap_or("")
    }

    pub fn command(&self) -> AtCommand<'_> {
        AtCommand::Config {
            key: self.key,
            value: self.value(),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Parser (for the emulator).

/// Why a line of a datagram is not a valid AT command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtParseErrorKind {
    /// Longer than [`MAX_LINE_LEN`] (the drone drops it).
    LineTooLong,
    /// Does not start with `AT*`.
    NoPrefix,
    /// No `=` after the name, or no sequence number.
    NoSeq,
    /// The sequence number is not a decimal `u32`.
    BadSeq,
    /// A name this parser does not know (LED, ANIM, …).
    UnknownCommand,
    /// Wrong number of arguments for the command.
    ArgCount,
    /// An argument that should be a decimal `i32` is not.
    BadInt,
    /// A string argument is unquoted, unterminated, or not UTF-8.
    BadString,
}

/// A rejected line: what is wrong and which line of the datagram (0-based, empty lines
/// not counted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtParseError {
    pub kind: AtParseErrorKind,
    pub line: usize,
}

impl fmt::Display for AtParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AT line {}: {:?}", self.line, self.kind)
    }
}

impl std::error::Error for AtParseError {}

/// One parsed command line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtLine<'a> {
    pub seq: u32,
    pub command: AtCommand<'a>,
}

/// The lines of a datagram, each parsed or rejected; see [`parse_datagram`].
#[derive(Clone, Debug)]
pub struct AtLines<'a> {
    rest: &'a [u8],
    line: usize,
}

/// Parses a datagram into its command lines. Lines end in `\r`, `\n` or both (a last line
/// without a terminator is parsed too); empty lines are skipped. A bad line yields an error
/// and parsing goes on with the next line. Never panics, never allocates.
pub fn parse_datagram(datagram: &[u8]) -> AtLines<'_> {
    AtLines {
        rest: datagram,
        line: 0,
    }
}

impl<'a> Iterator for AtLines<'a> {
    type Item = Result<AtLine<'a>, AtParseError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.rest.is_empty() {
                return None;
            }
            let end = self
                .rest
                .iter()
                .position(|&c| c == b'\r' || c == b'\n')
                .unwrap_or(self.rest.len());
            let line = &self.rest[..end];
            // Skip the terminator (one byte; the `\n` of a `\r\n` makes an empty line).
            self.rest = self.rest.get(end + 1..).unwrap_or(&[]);
            if line.is_empty() {
                continue;
            }
            let n = self.line;
            self.line += 1;
            // The drone counts the terminator in the 1024.
            if line.len() + 1 > MAX_LINE_LEN {
                return Some(Err(AtParseError {
                    kind: AtParseErrorKind::LineTooLong,
                    line: n,
                }));
            }
            return Some(parse_line(line).map_err(|kind| AtParseError { kind, line: n }));
        }
    }
}

/// Parses one line (no terminator).
pub fn parse_line(line: &[u8]) -> Result<AtLine<'_>, AtParseErrorKind> {
    use AtParseErrorKind as K;
    let body = line.strip_prefix(b"AT*").ok_or(K::NoPrefix)?;
    let eq = body.iter().position(|&c| c == b'=').ok_or(K::NoSeq)?;
    let (name, args) = (&body[..eq], &body[eq + 1..]);
    let mut args = Args { rest: Some(args) };
    let seq_text = args.next_raw().ok_or(K::NoSeq)?;
    if seq_text.is_empty() {
        return Err(K::NoSeq);
    }
    let seq = parse_u32(seq_text).ok_or(K::BadSeq)?;
    let command = match name {
        b"REF" => AtCommand::Ref {
            input: args.int()? as u32,
        },
        b"PCMD" => AtCommand::Pcmd(args.pcmd()?),
        b"PCMD_MAG" => AtCommand::PcmdMag {
            pcmd: args.pcmd()?,
            psi: wire_to_float(args.int()?),
            psi_accuracy: wire_to_float(args.int()?),
        },
        b"FTRIM" => {
            args.allow_empty_trailer();
            AtCommand::Ftrim
        }
        b"COMWDG" => {
            args.allow_empty_trailer();
            AtCommand::Comwdg
        }
        b"CONFIG" => AtCommand::Config {
            key: args.string()?,
            value: args.string()?,
        },
        b"CONFIG_IDS" => AtCommand::ConfigIds {
            session: args.string()?,
            user: args.string()?,
            application: args.string()?,
        },
        b"CTRL" => AtCommand::Ctrl {
            mode: args.int()?,
            arg: args.int()?,
        },
        b"CALIB" => AtCommand::Calib {
            device: args.int()?,
        },
        _ => return Err(K::UnknownCommand),
    };
    if args.rest.is_some() {
        return Err(K::ArgCount);
    }
    Ok(AtLine { seq, command })
}

/// The comma-separated arguments after `=`; `rest` is `None` once every argument was taken.
struct Args<'a> {
    rest: Option<&'a [u8]>,
}

impl<'a> Args<'a> {
    /// The next unquoted argument (up to the next comma).
    fn next_raw(&mut self) -> Option<&'a [u8]> {
        let rest = self.rest?;
        match rest.iter().position(|&c| c == b',') {
            Some(i) => {
                self.rest = Some(&rest[i + 1..]);
                Some(&rest[..i])
            }
            None => {
                self.rest = None;
                Some(rest)
            }
        }
    }

    fn int(&mut self) -> Result<i32, AtParseErrorKind> {
        let raw = self.next_raw().ok_or(AtParseErrorKind::ArgCount)?;
        parse_i32(raw).ok_or(AtParseErrorKind::BadInt)
    }

    fn pcmd(&mut self) -> Result<Pcmd, AtParseErrorKind> {
        Ok(Pcmd {
            flag: self.int()?,
            roll: wire_to_float(self.int()?),
            pitch: wire_to_float(self.int()?),
            gaz: wire_to_float(self.int()?),
            yaw: wire_to_float(self.int()?),
        })
    }

    fn string(&mut self) -> Result<&'a str, AtParseErrorKind> {
        let rest = self.rest.ok_or(AtParseErrorKind::ArgCount)?;
        let inner = rest
            .strip_prefix(b"\"")
            .ok_or(AtParseErrorKind::BadString)?;
        let close = inner
            .iter()
            .position(|&c| c == b'"')
            .ok_or(AtParseErrorKind::BadString)?;
        let s = std::str::from_utf8(&inner[..close]).map_err(|_| AtParseErrorKind::BadString)?;
        let after = &inner[close + 1..];
        self.rest = match after.split_first() {
            None => None,
            Some((b',', tail)) => Some(tail),
            Some(_) => return Err(AtParseErrorKind::BadString),
        };
        Ok(s)
    }

    /// `AT*FTRIM=5,` (the SDK's format) as well as `AT*FTRIM=5`.
    fn allow_empty_trailer(&mut self) {
        if self.rest == Some(b"") {
            self.rest = None;
        }
    }
}

fn parse_u32(s: &[u8]) -> Option<u32> {
    if s.is_empty() || s.len() > 10 || !s.iter().all(u8::is_ascii_digit) {
        return None;
    }
    let v = s
        .iter()
        .fold(0u64, |acc, &c| acc * 10 + u64::from(c - b'0'));
    u32::try_from(v).ok()
}

fn parse_i32(s: &[u8]) -> Option<i32> {
    let (neg, digits) = match s.split_first() {
        Some((b'-', d)) => (true, d),
        _ => (false, s),
    };
    if digits.is_empty() || digits.len() > 10 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    let v = digits
        .iter()
        .fold(0i64, |acc, &c| acc * 10 + i64::from(c - b'0'));
    i32::try_from(if neg { -v } else { v }).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_push_leaves_datagram_and_counter_alone() {
        let mut buf = [0u8; 20];
        let mut dg = Datagram::new(&mut buf);
        let mut enc = AtEncoder::new();
        assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(1));
        let before = dg.as_bytes().to_vec();
        assert_eq!(
            enc.push(&mut dg, &AtCommand::HOVER),
            Err(AtError::BufferFull)
        );
        assert_eq!(dg.as_bytes(), &before[..]);
        assert_eq!(enc.next_seq(), 2);
    }

    #[test]
    fn seq_wraps_to_one_before_the_sign_bit() {
        let mut enc = AtEncoder {
            next: i32::MAX as u32,
        };
        let mut buf = [0u8; 64];
        let mut dg = Datagram::new(&mut buf);
        assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(i32::MAX as u32));
        assert_eq!(enc.next_seq(), 1);
    }
}
