//! What the link's reader learnt from the Crazyflie ([`LinkState`]), and the lock the
//! link's threads share it under ([`Shared`]).

use std::collections::VecDeque;
use std::sync::atomic::AtomicBool;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use dronecine_backend::DroneMessage;

use crate::crtp::{CrtpError, FromDrone, Packet};
use crate::log::{all_vars, Field, Layout, Values};

/// The most answers and messages kept before the oldest are dropped.
const KEPT: usize = 64;
/// The longest console line kept; longer ones are cut.
const CONSOLE_LINE_MAX: usize = 200;

/// Every variable the backend logs, in [`all_vars`]' order.
const VARS: usize = 10;

/// What the Crazyflie said, as the reader applied it.
#[derive(Debug, Default)]
pub struct LinkState {
    /// When the last packet arrived.
    pub last_heard: Option<Instant>,
    /// Packets that decoded (each datagram is received or rejected).
    pub received: u64,
    /// Datagrams or packets that did not decode, and why the last did not.
    pub rejected: u64,
    pub last_rejection: Option<CrtpError>,
    pub protocol_version: Option<u8>,
    /// The log TOC's size and CRC.
    pub toc_info: Option<(u16, u32)>,
    /// The TOC entries received, by index (while the TOC is read).
    pub toc_seen: Vec<bool>,
    /// Each logged variable's TOC id and type code, once its entry was read.
    pub toc_found: [Option<(u16, u8)>; VARS],
    /// Answers to log block commands: (command, block, errno).
    pub log_acks: VecDeque<(u8, u8, u8)>,
    /// Answers to parameter writes: (`group.name`, errno).
    pub param_acks: VecDeque<(String, u8)>,
    /// The blocks created, as the TOC lays them out.
    pub layouts: [Option<Layout>; 2],
    pub values: Values,
    /// When each block ([`BLOCKS`](crate::log::BLOCKS)' order) last gave a sample.
    pub sampled_at: [Option<Instant>; 2],
    /// The console's unfinished line.
    console: String,
    /// The console's lines, for the flight's log.
    pub messages: VecDeque<DroneMessage>,
    /// Why the transport failed, if it did.
    pub link_error: Option<String>,
}

impl LinkState {
    /// Applies one datagram received at `now`.
    pub fn apply(&mut self, datagram: &[u8], now: Instant) {
        let packet = match Packet::from_bytes(datagram) {
            Ok(p) => p,
            Err(e) => return self.reject(e),
        };
        let message = match FromDrone::decode(&packet) {
            Ok(m) => m,
            Err(e) => return self.reject(e),
        };
        // Heard, whatever it said.
        self.last_heard = Some(now);
        self.received += 1;
        match message {
            FromDrone::Console(text) => self.console(text),
            FromDrone::ProtocolVersion(v) => self.protocol_version = Some(v),
            FromDrone::LogTocInfo { count, crc } => {
                self.toc_info = Some((count, crc));
                self.toc_seen = vec![false; usize::from(count)];
            }
            FromDrone::LogTocItem {
                index,
                kind,
                group,
                name,
            } => {
                if let Some(seen) = self.toc_seen.get_mut(usize::from(index)) {
                    *seen = true;
                }
                for (i, v) in all_vars().enumerate() {
                    if v.group == group && v.name == name {
                        self.toc_found[i] = Some((index, kind));
                    }
                }
            }
            FromDrone::LogTocEnd => {}
            FromDrone::LogAck {
                command,
                block,
                error,
            } => push(&mut self.log_acks, (command, block, error)),
            FromDrone::LogData { block, data, .. } => self.sample(block, data, now),
            FromDrone::ParamSet { group, name, error } => {
                push(&mut self.param_acks, (format!("{group}.{name}"), error))
            }
            FromDrone::Other { .. } => {}
        }
    }

    fn reject(&mut self, e: CrtpError) {
        self.rejected += 1;
        self.last_rejection = Some(e);
    }

    /// A sample of a block: decoded, or (the wrong length for its block) counted as rejected
    /// instead of received.
    fn sample(&mut self, block: u8, data: &[u8], now: Instant) {
        let Some(i) = self
            .layouts
            .iter()
            .position(|l| l.is_some_and(|l| l.id == block))
        else {
            return;
        };
        let decoded = self.layouts[i].is_some_and(|l| l.decode(data, &mut self.values));
        if decoded {
            self.sampled_at[i] = Some(now);
        } else {
            self.received -= 1;
            self.reject(CrtpError::Length {
                what: "log sample",
                len: data.len(),
            });
        }
    }

    fn console(&mut self, text: &[u8]) {
        for &c in text {
            match c {
                b'\n' => {
                    let line = std::mem::take(&mut self.console);
                    if !line.trim().is_empty() {
                        push(
                            &mut self.messages,
                            DroneMessage {
                                level: "info",
                                text: format!("crazyflie: {}", line.trim_end()),
                            },
                        );
                    }
                }
                c if self.console.len() < CONSOLE_LINE_MAX => {
                    self.console
                        .push(if c.is_ascii() { c as char } else { '?' })
                }
                _ => {}
            }
        }
    }

    /// The estimator's position, when a state sample came within `fresh`.
    pub fn estimate_m(&self, fresh: Duration) -> Option<[f64; 3]> {
        self.sampled_at[0]
            .filter(|t| t.elapsed() < fresh)
            .and(self.values.estimate_m())
    }

    /// The drone's roll and pitch (the generic command's signs, radians), 0 when unknown.
    pub fn tilt_rad(&self) -> (f64, f64) {
        let r = self.values.get(Field::Roll);
        let p = self.values.get(Field::Pitch);
        let ok = |v: f64| if v.is_finite() { v.to_radians() } else { 0.0 };
        (ok(r), ok(p))
    }
}

fn push<T>(q: &mut VecDeque<T>, v: T) {
    if q.len() == KEPT {
        q.pop_front();
    }
    q.push_back(v);
}

/// What the link's threads share.
pub(crate) struct Shared {
    pub(crate) state: Mutex<LinkState>,
    pub(crate) closed: AtomicBool,
}

impl Shared {
    pub(crate) fn apply(&self, datagram: &[u8]) {
        let now = Instant::now();
        self.state
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .apply(datagram, now);
    }

    pub(crate) fn fail(&self, why: String) {
        self.state
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .link_error = Some(why);
    }
}
