//! What the backend logs from the Crazyflie: two log blocks, their variables found by name in
//! the log TOC, and each sample decoded into [`Values`] without allocating.
//!
//! - Block [`STATE_BLOCK`], every 10 ms: the estimator's position (`stateEstimate.x`, `.y`,
//!   `.z`) and the attitude (`stabilizer.roll`, `.pitch`, `.yaw`, degrees, `frames`' signs).
//! - Block [`POWER_BLOCK`], every 100 ms: the battery (`pm.vbat` volts, `pm.batteryLevel`
//!   percent, `pm.state`: 0 on battery, 1 charging, 2 charged, 3 low, 4 shutting down) and
//!   the supervisor's state (`supervisor.info`, the bits of [`supervisor`]).

use crate::crtp::log_type;

/// One value the backend reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    X,
    Y,
    Z,
    Roll,
    Pitch,
    Yaw,
    Vbat,
    BatteryLevel,
    PmState,
    Supervisor,
}

impl Field {
    pub const COUNT: usize = 10;

    fn index(self) -> usize {
        self as usize
    }
}

/// A log variable by its TOC name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Var {
    pub group: &'static str,
    pub name: &'static str,
    pub field: Field,
}

const fn var(group: &'static str, name: &'static str, field: Field) -> Var {
    Var { group, name, field }
}

/// A log block the backend creates.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    pub id: u8,
    /// Its period, in the firmware's 10 ms units.
    pub period_10ms: u8,
    pub vars: &'static [Var],
}

pub const STATE_BLOCK: Block = Block {
    id: 1,
    period_10ms: 1,
    vars: &[
        var("stateEstimate", "x", Field::X),
        var("stateEstimate", "y", Field::Y),
        var("stateEstimate", "z", Field::Z),
        var("stabilizer", "roll", Field::Roll),
        var("stabilizer", "pitch", Field::Pitch),
        var("stabilizer", "yaw", Field::Yaw),
    ],
};

pub const POWER_BLOCK: Block = Block {
    id: 2,
    period_10ms: 10,
    vars: &[
        var("pm", "vbat", Field::Vbat),
        var("pm", "batteryLevel", Field::BatteryLevel),
        var("pm", "state", Field::PmState),
        var("supervisor", "info", Field::Supervisor),
    ],
};

pub const BLOCKS: [Block; 2] = [STATE_BLOCK, POWER_BLOCK];

/// Every variable of the blocks, in the blocks' order.
pub fn all_vars() -> impl Iterator<Item = &'static Var> {
    BLOCKS.iter().flat_map(|b| b.vars.iter())
}

/// The supervisor's bits (`supervisor.info`).
pub mod supervisor {
    pub const CAN_BE_ARMED: u16 = 1 << 0;
    pub const ARMED: u16 = 1 << 1;
    pub const AUTO_ARM: u16 = 1 << 2;
    pub const CAN_FLY: u16 = 1 << 3;
    pub const FLYING: u16 = 1 << 4;
    pub const TUMBLED: u16 = 1 << 5;
    pub const LOCKED: u16 = 1 << 6;
    pub const CRASHED: u16 = 1 << 7;

    /// The names of the bits set, for people.
    pub fn names(info: u16) -> Vec<&'static str> {
        [
            (CAN_BE_ARMED, "can be armed"),
            (ARMED, "armed"),
            (AUTO_ARM, "auto-arm"),
            (CAN_FLY, "can fly"),
            (FLYING, "flying"),
            (TUMBLED, "tumbled"),
            (LOCKED, "LOCKED (restart it)"),
            (CRASHED, "CRASHED"),
        ]
        .iter()
        .filter(|(bit, _)| info & bit != 0)
        .map(|&(_, n)| n)
        .collect()
    }
}

/// The values last logged, NaN until first received.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Values([f64; Field::COUNT]);

impl Default for Values {
    fn default() -> Self {
        Values([f64::NAN; Field::COUNT])
    }
}

impl Values {
    pub fn get(&self, f: Field) -> f64 {
        self.0[f.index()]
    }

    pub fn set(&mut self, f: Field, v: f64) {
        self.0[f.index()] = v;
    }

    /// The estimator's position, when logged.
    pub fn estimate_m(&self) -> Option<[f64; 3]> {
        let p = [self.get(Field::X), self.get(Field::Y), self.get(Field::Z)];
        p.iter().all(|v| v.is_finite()).then_some(p)
    }

    /// The supervisor's bits, when logged.
    pub fn supervisor(&self) -> Option<u16> {
        let v = self.get(Field::Supervisor);
        (v.is_finite() && (0.0..=65535.0).contains(&v)).then_some(v as u16)
    }
}

/// A block as the TOC lays it out: each variable's field and type code, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub id: u8,
    vars: [(Field, u8); 6],
    len: usize,
}

impl Layout {
    /// `block`'s layout with the type codes the TOC gave (`kinds`, in the block's order);
    /// `None` when a type is not a log type or the block does not fit a sample.
    pub fn new(block: &Block, kinds: &[u8]) -> Option<Layout> {
        if block.vars.len() != kinds.len() || kinds.len() > 6 {
            return None;
        }
        let mut vars = [(Field::X, 0u8); 6];
        let mut bytes = 0;
        for (i, (v, &k)) in block.vars.iter().zip(kinds).enumerate() {
            bytes += log_type::size(k)?;
            vars[i] = (v.field, k & 0x0F);
        }
        (bytes <= 26).then_some(Layout {
            id: block.id,
            vars,
            len: kinds.len(),
        })
    }

    /// The bytes of one sample.
    pub fn sample_len(&self) -> usize {
        self.vars[..self.len]
            .iter()
            .map(|&(_, k)| log_type::size(k).unwrap_or(0))
            .sum()
    }

    /// Decodes one sample into `values`; `false` (nothing written) when its length is not
    /// the block's.
    pub fn decode(&self, data: &[u8], values: &mut Values) -> bool {
        if data.len() != self.sample_len() {
            return false;
        }
        let mut at = 0;
        for &(field, kind) in &self.vars[..self.len] {
            let n = log_type::size(kind).unwrap_or(0);
            values.set(field, value(kind, &data[at..at + n]));
            at += n;
        }
        true
    }

    /// Encodes `values` as one sample of this block (the emulated Crazyflie's), into `out`;
    /// its length.
    pub fn encode(&self, values: &Values, out: &mut [u8; 26]) -> usize {
        let mut at = 0;
        for &(field, kind) in &self.vars[..self.len] {
            at += encode_value(kind, values.get(field), &mut out[at..]);
        }
        at
    }
}

/// Writes `v` as a log value of type `kind` (little-endian, saturating) at the start of
/// `out`: the bytes written, 0 for a type that is not a log type or an `out` too short.
pub fn encode_value(kind: u8, v: f64, out: &mut [u8]) -> usize {
    let Some(n) = log_type::size(kind).filter(|&n| n <= out.len()) else {
        return 0;
    };
    let b = &mut out[..n];
    match kind & 0x0F {
        log_type::UINT8 => b.copy_from_slice(&[v as u8]),
        log_type::INT8 => b.copy_from_slice(&(v as i8).to_le_bytes()),
        log_type::UINT16 => b.copy_from_slice(&(v as u16).to_le_bytes()),
        log_type::INT16 => b.copy_from_slice(&(v as i16).to_le_bytes()),
        log_type::UINT32 => b.copy_from_slice(&(v as u32).to_le_bytes()),
        log_type::INT32 => b.copy_from_slice(&(v as i32).to_le_bytes()),
        log_type::FLOAT => b.copy_from_slice(&(v as f32).to_le_bytes()),
        _ => b.copy_from_slice(&half_bits(v as f32).to_le_bytes()),
    }
    n
}

/// A logged value of type `kind` from its little-endian bytes.
fn value(kind: u8, b: &[u8]) -> f64 {
    match kind {
        log_type::UINT8 => f64::from(b[0]),
        log_type::INT8 => f64::from(b[0] as i8),
        log_type::UINT16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        log_type::INT16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        log_type::UINT32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        log_type::INT32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        log_type::FLOAT => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => f64::from(half(u16::from_le_bytes([b[0], b[1]]))),
    }
}

/// An IEEE half-precision number's value (exact: every half is an f32).
fn half(bits: u16) -> f32 {
    let sign = u32::from(bits & 0x8000) << 16;
    let exp = u32::from((bits >> 10) & 0x1F);
    let frac = u32::from(bits & 0x3FF);
    match exp {
        // Subnormal: frac · 2⁻²⁴.
        0 => {
            let magnitude = frac as f32 * f32::from_bits((127 - 24) << 23);
            f32::from_bits(sign | magnitude.to_bits())
        }
        31 => f32::from_bits(sign | 0x7F80_0000 | frac << 13),
        e => f32::from_bits(sign | (e + 127 - 15) << 23 | frac << 13),
    }
}

/// The half-precision bits nearest `v` (truncating; out of range saturates to infinity).
fn half_bits(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    if v.is_nan() {
        return sign | 0x7E00;
    }
    let exp = ((bits >> 23) & 0xFF) as i32 - 127 + 15;
    let frac = (bits >> 13) & 0x3FF;
    match exp {
        e if e >= 31 => sign | 0x7C00,
        e if e <= 0 => sign,
        e => sign | ((e as u16) << 10) | frac as u16,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blocks_fit_a_sample_and_decode_what_they_encode() {
        let kinds_state = [log_type::FLOAT; 6];
        let kinds_power = [
            log_type::FLOAT,
            log_type::UINT8,
            log_type::INT8,
            log_type::UINT16,
        ];
        let state = Layout::new(&STATE_BLOCK, &kinds_state).unwrap();
        let power = Layout::new(&POWER_BLOCK, &kinds_power).unwrap();
        assert_eq!((state.sample_len(), power.sample_len()), (24, 8));
        let mut v = Values::default();
        for (f, x) in [
            (Field::X, 1.5),
            (Field::Y, -0.25),
            (Field::Z, 0.75),
            (Field::Roll, 2.0),
            (Field::Pitch, -3.0),
            (Field::Yaw, 170.0),
            (Field::Vbat, 3.75),
            (Field::BatteryLevel, 64.0),
            (Field::PmState, 3.0),
            (Field::Supervisor, 0x001F as f64),
        ] {
            v.set(f, x);
        }
        let mut back = Values::default();
        let mut buf = [0u8; 26];
        for l in [state, power] {
            let n = l.encode(&v, &mut buf);
            assert!(l.decode(&buf[..n], &mut back));
            assert!(!l.decode(&buf[..n - 1], &mut back), "a short sample");
        }
        assert_eq!(back, v);
        assert_eq!(back.supervisor(), Some(0x1F));
        assert_eq!(back.estimate_m(), Some([1.5, -0.25, 0.75]));
        // A block that would not fit, or a type that is not one.
        assert!(Layout::new(&POWER_BLOCK, &[9, 1, 1, 1]).is_none());
        assert!(Layout::new(&POWER_BLOCK, &[7, 1]).is_none());
    }

    #[test]
    fn half_precision_values() {
        assert_eq!(half(0x3C00), 1.0);
        assert_eq!(half(0xC000), -2.0);
        assert_eq!(half(0x3555), 0.333_251_95);
        assert_eq!(half(half_bits(0.5)), 0.5);
        assert!(half(0x7C00).is_infinite() && half(0x7E00).is_nan());
    }

    #[test]
    fn supervisor_bits_are_named() {
        let info = supervisor::ARMED | supervisor::FLYING | supervisor::LOCKED;
        assert_eq!(
            supervisor::names(info),
            ["armed", "flying", "LOCKED (restart it)"]
        );
    }
}
