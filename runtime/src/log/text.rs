//! The JSON text of the flight log's per-tick messages, written into one reused buffer.
//!
//! A tick's numbers repeat across topics (the clock on every topic, the reference on
//! `/reference` and `/servo/tick`, the estimate, the command…) and from tick to tick (zeros,
//! constants). Formatting a float in its shortest round-trip form is the bulk of a tick's
//! cost, so [`Text`] keeps the text of recently formatted floats in a small direct-mapped
//! cache keyed by their bits: each distinct value is formatted once. The text is the
//! compiler's `output::json::f64` (zmij), the same on every topic.

use dronecine_compiler::output::json;

use super::exact;
use crate::backend::{BodyPose, MocapFrame};
use crate::control::{Estimate, TickOutput};
use crate::frames::Command;
use crate::record::FramingRecord;

const SLOTS: usize = 256;
/// Longest shortest-round-trip text of an f64 (`-2.2250738585072014e-308`: 24 bytes).
const TEXT_MAX: usize = 32;

#[derive(Clone, Copy)]
struct Slot {
    /// A NaN pattern while empty: never equal to a cached (finite) value.
    bits: u64,
    len: u8,
    text: [u8; TEXT_MAX],
}

const EMPTY: Slot = Slot {
    bits: u64::MAX,
    len: 0,
    text: [0; TEXT_MAX],
};

pub(super) struct Text {
    pub(super) buf: Vec<u8>,
    slots: Box<[Slot; SLOTS]>,
}

/// Bit-for-bit equal floats.
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits()
}

/// Bit-for-bit equal commands.
pub(super) fn same_command(a: &Command, b: &Command) -> bool {
    same(a.roll_rad, b.roll_rad)
        && same(a.pitch_rad, b.pitch_rad)
        && same(a.yaw_rate_radps, b.yaw_rate_radps)
        && same(a.vz_mps, b.vz_mps)
}

fn bool_json(b: bool) -> &'static [u8] {
    if b {
        b"true"
    } else {
        b"false"
    }
}

impl Text {
    pub(super) fn new() -> Self {
        Self {
            buf: Vec::with_capacity(4096),
            slots: Box::new([EMPTY; SLOTS]),
        }
    }

    #[inline]
    pub(super) fn raw(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// A finite float, through the cache.
    #[inline]
    fn finite(&mut self, x: f64) {
        let bits = x.to_bits();
        let h = (bits ^ (bits >> 32)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56;
        let i = h as usize % SLOTS;
        let slot = &self.slots[i];
        if slot.bits == bits {
            // A fixed-size copy (no call to memcpy), then the excess cut off.
            let end = self.buf.len() + slot.len as usize;
            self.buf.extend_from_slice(&slot.text);
            self.buf.truncate(end);
            return;
        }
        let start = self.buf.len();
        json::f64(&mut self.buf, x);
        let text = &self.buf[start..];
        if text.len() <= TEXT_MAX {
            let slot = &mut self.slots[i];
            slot.bits = bits;
            slot.len = text.len() as u8;
            slot.text[..text.len()].copy_from_slice(text);
        }
    }

    /// A float, `null` if not finite (as compile's topics).
    #[inline]
    pub(super) fn num(&mut self, x: f64) {
        if x.is_finite() {
            self.finite(x);
        } else {
            self.raw(b"null");
        }
    }

    /// A float, exact: non-finite as `"NaN"`, `"inf"`, `"-inf"`.
    #[inline]
    pub(super) fn exact(&mut self, x: f64) {
        if x.is_finite() {
            self.finite(x);
        } else {
            exact::f64(&mut self.buf, x);
        }
    }

    fn vec3(&mut self, v: &[f64; 3]) {
        self.raw(b"[");
        self.num(v[0]);
        self.raw(b",");
        self.num(v[1]);
        self.raw(b",");
        self.num(v[2]);
        self.raw(b"]");
    }

    fn shot(&mut self, shot: Option<usize>) {
        match shot {
            Some(s) => json::u64(&mut self.buf, s as u64),
            None => self.raw(b"null"),
        }
    }

    pub(super) fn estimate(&mut self, t_s: f64, e: &Estimate) {
        self.buf.clear();
        self.raw(b"{\"t_s\":");
        self.num(t_s);
        self.raw(b",\"position_m\":");
        self.vec3(&e.position_m);
        self.raw(b",\"velocity_mps\":");
        self.vec3(&e.velocity_mps);
        self.raw(b",\"heading_rad\":");
        self.num(e.heading_rad);
        self.raw(b"}");
    }

    fn pose(&mut self, pose: Option<&BodyPose>) {
        match pose {
            Some(p) => {
                self.raw(b"{\"position_m\":");
                self.vec3(&p.position_m);
                self.raw(b",\"heading_rad\":");
                self.num(p.heading_rad);
                self.raw(b"}");
            }
            None => self.raw(b"null"),
        }
    }

    pub(super) fn measurement(&mut self, frame: &MocapFrame) {
        self.buf.clear();
        self.raw(b"{\"t_s\":");
        self.num(frame.t_s);
        self.raw(b",\"frame\":");
        json::u64(&mut self.buf, frame.frame);
        self.raw(b",\"drone\":");
        self.pose(frame.drone.as_ref());
        self.raw(b",\"actors\":[");
        for (i, a) in frame.actors.iter().enumerate() {
            if i > 0 {
                self.raw(b",");
            }
            self.pose(a.as_ref());
        }
        self.raw(b"]}");
    }

    /// `/command`: the command sent, and whether it is not the controller's.
    pub(super) fn command(
        &mut self,
        t_s: f64,
        output: Option<&TickOutput>,
        c: &Command,
        failsafe: bool,
    ) {
        self.buf.clear();
        self.raw(b"{\"t_s\":");
        self.num(t_s);
        self.raw(b",\"roll_rad\":");
        self.num(c.roll_rad);
        self.raw(b",\"pitch_rad\":");
        self.num(c.pitch_rad);
        self.raw(b",\"yaw_rate_radps\":");
        self.num(c.yaw_rate_radps);
        self.raw(b",\"vz_mps\":");
        self.num(c.vz_mps);
        self.raw(b",\"saturated\":");
        self.raw(bool_json(output.is_some_and(|o| o.saturated)));
        self.raw(b",\"failsafe\":");
        self.raw(bool_json(failsafe));
        self.raw(b"}");
    }

    fn screen(&mut self, p: Option<[f64; 2]>) {
        match p {
            Some([x, y]) => {
                self.raw(b"[");
                self.num(x);
                self.raw(b",");
                self.num(y);
                self.raw(b"]");
            }
            None => self.raw(b"null"),
        }
    }

    /// `/framing` (`names`: `,"name":NAME,"screen":` per actor).
    pub(super) fn framing(
        &mut self,
        t_s: f64,
        shot: Option<usize>,
        names: &[Vec<u8>],
        framing: &[FramingRecord],
    ) {
        self.buf.clear();
        self.raw(b"{\"t_s\":");
        self.num(t_s);
        self.raw(b",\"shot\":");
        self.shot(shot);
        self.raw(b",\"actors\":[");
        for (i, f) in framing.iter().enumerate() {
            if i > 0 {
                self.raw(b",");
            }
            self.raw(b"{\"actor\":");
            json::u64(&mut self.buf, f.actor as u64);
            match names.get(f.actor) {
                Some(name) => self.raw(name),
                None => self.raw(b",\"name\":\"\",\"screen\":"),
            }
            self.screen(f.screen);
            self.raw(b",\"requested\":");
            self.screen(f.requested);
            self.raw(b"}");
        }
        self.raw(b"]}");
    }
}
