//! [`FlightLog`]: reads a flight log back for `dronecine replay`: the header, every tick of
//! `/servo/tick` and every event, recovering what precedes any damage.
//!
//! The file is streamed through the mcap crate's sans-io linear reader (memory: one chunk at a
//! time plus the decoded ticks). Chunk CRCs are checked before a chunk's records are used, so a
//! damaged chunk is never half-read; reading stops at the first damage (a cut or a corrupt
//! record) and [`FlightLog::truncated`] says so.

use std::collections::HashMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::McapError;
use serde::Deserialize;

use super::exact::Num;
use super::{cdr, topic, LogError, HEADER_METADATA};
use crate::control::{TickFault, TickInput, TickOutput};
use crate::frames::{ActorPose, Command};
use crate::record::{Event, FlightHeader, FramingRecord, Phase};

/// One tick as replay needs it.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedTick {
    pub phase: Phase,
    pub shot: Option<usize>,
    pub input: TickInput,
    pub output: Result<TickOutput, TickFault>,
    pub command_sent: Command,
    /// The actors as the director saw them (empty in a log of an older dronecine).
    pub actors: Vec<ActorPose>,
    /// The tick's framing records (empty outside holds).
    pub framing: Vec<FramingRecord>,
    /// Mocap frame arrival → command sent, seconds (`None` without a new frame).
    pub latency_s: Option<f64>,
}

/// A flight log, read back.
#[derive(Clone, Debug)]
pub struct FlightLog {
    pub header: FlightHeader,
    /// Every tick, in the order written.
    pub ticks: Vec<LoggedTick>,
    pub events: Vec<Event>,
    /// The file ends before its footer (a crash, a cut copy) or is damaged: everything before
    /// the damage was read.
    pub truncated: bool,
    /// What stopped the reading when `truncated` (for the user).
    pub damage: Option<String>,
}

#[derive(Deserialize)]
struct RawFraming {
    /// A number, or null (a non-finite time): then the framing matches no tick.
    t_s: serde_json::Value,
    actors: Vec<RawFramed>,
}

#[derive(Deserialize)]
struct RawFramed {
    actor: usize,
    screen: Option<Vec<Option<f64>>>,
    requested: Option<Vec<Option<f64>>>,
}

/// A screen point, `None` unless both coordinates are numbers.
fn screen_point(v: Option<Vec<Option<f64>>>) -> Option<[f64; 2]> {
    match v.as_deref() {
        Some([Some(x), Some(y)]) => Some([*x, *y]),
        _ => None,
    }
}

#[derive(Deserialize)]
struct RawEvent {
    t_s: Num,
    level: String,
    kind: String,
    message: String,
}

/// Which channels the reader decodes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Wanted {
    Tick,
    Framing,
    Event,
}

/// Rebuilds the header from the metadata map (each value a field's JSON).
fn parse_header(
    metadata: &std::collections::BTreeMap<String, String>,
) -> Result<FlightHeader, String> {
    let mut object = serde_json::Map::new();
    for (key, text) in metadata {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("field `{key}`: {e}"))?;
        object.insert(key.clone(), value);
    }
    serde_json::from_value(serde_json::Value::Object(object)).map_err(|e| e.to_string())
}

impl FlightLog {
    /// Reads the log at `path`. A cut or damaged file gives every tick and event before the
    /// damage with `truncated` set; a file that is not MCAP, or has no flight header, is an
    /// error.
    pub fn open(path: &Path) -> Result<FlightLog, LogError> {
        let io_err = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut file = File::open(path).map_err(io_err)?;
        let len = file.metadata().map_err(io_err)?.len();
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_validate_chunk_crcs(true)
                .with_prevalidate_chunk_crcs(true)
                .with_record_length_limit(record_length_limit(len)),
        );
        let mut state = ReadState {
            path: path.to_path_buf(),
            channels: HashMap::new(),
            header: None,
            ticks: Vec::new(),
            events: Vec::new(),
            pending_framing: None,
            records: 0,
            footer: false,
        };
        let damage = loop {
            let event = match reader.next_event() {
                None => break None,
                Some(Ok(event)) => event,
                Some(Err(e)) => break Some(e),
            };
            match event {
                LinearReadEvent::ReadRequest(need) => {
                    let buf = reader.insert(need);
                    let n = loop {
                        match file.read(buf) {
                            Ok(n) => break n,
                            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                            Err(e) => return Err(io_err(e)),
                        }
                    };
                    reader.notify_read(n);
                }
                LinearReadEvent::Record { opcode, data } => {
                    let record = match mcap::parse_record(opcode, data) {
                        Ok(record) => record,
                        Err(e) => break Some(e),
                    };
                    state.records += 1;
                    state.record(record)?;
                }
            }
        };
        let truncated = damage.is_some() || !state.footer;
        if let Some(e) = &damage {
            if state.records == 0 {
                return Err(LogError::NotMcap {
                    path: path.to_path_buf(),
                    detail: describe(e),
                });
            }
        }
        let header = state.header.take().ok_or_else(|| LogError::NoHeader {
            path: path.to_path_buf(),
        })?;
        let damage = match damage {
            Some(e) => Some(describe(&e)),
            None if truncated => Some("the file ends before its footer".to_string()),
            None => None,
        };
        Ok(FlightLog {
            header,
            ticks: state.ticks,
            events: state.events,
            truncated,
            damage,
        })
    }
}

/// The largest record (or decompressed chunk) the reader accepts in a file of `len` bytes:
/// what a damaged length field cannot exceed, so it is refused instead of allocated. A
/// compressed chunk decompresses to more than the file holds (LZ4's ratio reaches 255; a
/// short LZ4 flight log's first chunk is larger than the whole file), hence the factor.
fn record_length_limit(len: u64) -> usize {
    let limit = len.saturating_mul(256).max(16 << 20);
    usize::try_from(limit).unwrap_or(usize::MAX)
}

fn describe(e: &McapError) -> String {
    match e {
        McapError::UnexpectedEof => "the file ends in the middle of a record".into(),
        McapError::BadMagic => "no MCAP magic".into(),
        other => other.to_string(),
    }
}

struct ReadState {
    path: PathBuf,
    channels: HashMap<u16, Wanted>,
    header: Option<FlightHeader>,
    ticks: Vec<LoggedTick>,
    events: Vec<Event>,
    /// A `/framing` message waiting for its tick (written just before it, same `t_s`): the
    /// framing of a log whose ticks do not carry it (an older dronecine's).
    pending_framing: Option<(u64, Vec<FramingRecord>)>,
    records: usize,
    footer: bool,
}

impl ReadState {
    fn record(&mut self, record: Record) -> Result<(), LogError> {
        match record {
            Record::Channel(channel) => {
                let wanted = match channel.topic.as_str() {
                    topic::SERVO_TICK if channel.message_encoding != cdr::MESSAGE_ENCODING => {
                        return Err(LogError::BadMessage {
                            path: self.path.clone(),
                            topic: topic::SERVO_TICK,
                            index: 0,
                            detail: format!(
                                "its encoding is `{}`; this dronecine reads `{}` (the log was \
                                 written by an older dronecine: replay it with that version)",
                                channel.message_encoding,
                                cdr::MESSAGE_ENCODING
                            ),
                        });
                    }
                    topic::SERVO_TICK => Some(Wanted::Tick),
                    topic::EVENTS => Some(Wanted::Event),
                    topic::FRAMING => Some(Wanted::Framing),
                    _ => None,
                };
                if let Some(w) = wanted {
                    self.channels.insert(channel.id, w);
                }
            }
            Record::Metadata(m) if m.name == HEADER_METADATA && self.header.is_none() => {
                let header = parse_header(&m.metadata).map_err(|detail| LogError::BadHeader {
                    path: self.path.clone(),
                    detail,
                })?;
                self.header = Some(header);
            }
            Record::Message { header, data } => match self.channels.get(&header.channel_id) {
                Some(Wanted::Tick) => {
                    let decoded = cdr::decode(&data).map_err(|detail| LogError::BadMessage {
                        path: self.path.clone(),
                        topic: topic::SERVO_TICK,
                        index: self.ticks.len(),
                        detail,
                    })?;
                    let mut tick = decoded.tick;
                    if let Some((t_bits, framing)) = self.pending_framing.take() {
                        if !decoded.extended && t_bits == tick.input.t_s.to_bits() {
                            tick.framing = framing;
                        }
                    }
                    self.ticks.push(tick);
                }
                Some(Wanted::Framing) => {
                    let f = serde_json::from_slice::<RawFraming>(&data).map_err(|e| {
                        LogError::BadMessage {
                            path: self.path.clone(),
                            topic: topic::FRAMING,
                            index: self.ticks.len(),
                            detail: e.to_string(),
                        }
                    })?;
                    let records = f
                        .actors
                        .into_iter()
                        .map(|a| FramingRecord {
                            actor: a.actor,
                            screen: screen_point(a.screen),
                            requested: screen_point(a.requested),
                        })
                        .collect();
                    self.pending_framing = f.t_s.as_f64().map(|t| (t.to_bits(), records));
                }
                Some(Wanted::Event) => {
                    let e = serde_json::from_slice::<RawEvent>(&data).map_err(|e| {
                        LogError::BadMessage {
                            path: self.path.clone(),
                            topic: topic::EVENTS,
                            index: self.events.len(),
                            detail: e.to_string(),
                        }
                    })?;
                    self.events.push(Event {
                        t_s: e.t_s.0,
                        level: e.level,
                        kind: e.kind,
                        message: e.message,
                    });
                }
                None => {}
            },
            Record::Footer(_) => self.footer = true,
            _ => {}
        }
        Ok(())
    }
}
