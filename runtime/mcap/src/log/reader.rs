//! [`FlightLog`]: reads a flight log back for `dronecine replay`: the header, every tick of
//! `/servo/tick`, every key frame of `/servo/state` and every event, recovering what
//! surrounds any damage.
//!
//! The reader frames the file's records itself (memory: one record at a time plus what it
//! decodes), checks that each one's length is exactly what its fields make, and opens the
//! chunks itself: a chunk's CRC is checked before any of its records is used, so a damaged
//! chunk is never half-read.
//!
//! Damage does not end the reading. A record that does not frame or parse, whose length is
//! not its fields', a chunk or attachment whose CRC fails, or a record a flight log's data
//! section does not hold (a message outside a chunk) is skipped from its first byte: the
//! reader searches forward from the byte after that for the next intact record it can check
//! (a chunk or an attachment whose CRC matches, the header's metadata record) and goes on
//! from there, so one bad sector in an hour's log loses the chunk it hits, not the rest, and a
//! damaged length does not hide the record after it. Each skip is a [`Damage`] with the ticks
//! it separates; a file that ends before its footer (a crash, a copy that did not finish) is
//! [`FlightLog::truncated`], everything before the cut read.
//!
//! What the first records hold is kept twice: the schemas and channels also in the first
//! chunk (under its CRC), the header also as an attachment (under its CRC), which the reader
//! prefers. A finished log's summary section (checked against the footer's CRC) gives the
//! schemas and channels a third time, before the rest is read, and says where the data ends.
//! A record under a CRC overrides one without: a damaged first copy is never what decides
//! how a topic is read.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use crate::output::mcap::Encoding;
use mcap::records::{op, Record};
use serde::Deserialize;

use super::exact::Num;
use super::{cdr, key_frame, schema, topic, LogError, HEADER_ATTACHMENT, HEADER_METADATA};
use crate::record::{Event, FlightHeader, FramingRecord, Phase};
use dronecine_backend::frames::Command;
use dronecine_compiler::reference::ActorPose;
use dronecine_servo::control::{ControllerState, TickFault, TickInput, TickOutput};

/// One tick as replay needs it.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedTick {
    pub phase: Phase,
    pub shot: Option<usize>,
    pub input: TickInput,
    pub output: Result<TickOutput, TickFault>,
    pub command_sent: Command,
    /// The actors as the director saw them (empty in a log whose ticks do not carry them).
    pub actors: Vec<ActorPose>,
    /// The tick's framing records (empty outside holds).
    pub framing: Vec<FramingRecord>,
    /// Mocap frame arrival → command sent, seconds (`None` without a new frame).
    pub latency_s: Option<f64>,
}

/// A key frame of `/servo/state`: where replay can start checking ticks.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyFrame {
    /// The index in [`FlightLog::ticks`] of the tick it comes before (the number of ticks
    /// when none was read after it).
    pub tick: usize,
    /// The flight time of the tick it comes before.
    pub t_s: f64,
    /// The controller's state after the tick before it, or (`None`) the mark that the
    /// controller starts at the next tick: reset with that tick's measurement at
    /// `t_s − dt_s`.
    pub state: Option<ControllerState>,
}

/// A flight log, read back.
#[derive(Clone, Debug)]
pub struct FlightLog {
    pub header: FlightHeader,
    /// Every tick that could be read, in the order written.
    pub ticks: Vec<LoggedTick>,
    /// Every key frame that could be read, in the order written (none in a log written
    /// without them).
    pub key_frames: Vec<KeyFrame>,
    pub events: Vec<Event>,
    /// The file does not end with its footer and the closing magic: cut short (a crash, a
    /// copy that did not finish, even inside the magic's last bytes), or damaged with nothing
    /// intact after the damage. Everything before was read;
    /// the last entry of `damage` says where and why it ends.
    pub truncated: bool,
    /// The damage met, in file order: each a stretch skipped (reading resumed at the next
    /// intact record) or, last, where the readable file ends.
    pub damage: Vec<Damage>,
}

/// Where a flight log could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    /// File offset of the first byte that could not be used (the start of the bad record,
    /// or the file's length when it simply ends before its footer).
    pub offset: u64,
    /// What was wrong, for the user.
    pub detail: String,
    /// Whether the file simply ends there (before its footer, or inside a record): a
    /// flight cut short or a copy that did not finish, rather than corrupt bytes.
    pub cut: bool,
    /// Ticks read before the damage: the index in [`FlightLog::ticks`] of the first tick
    /// after it. The ticks on either side may not follow each other: replay resumes after
    /// it at the next key frame.
    pub tick: usize,
    /// The offset of the intact record where reading went on (a chunk, an attachment, the
    /// header's metadata, or the end of the data); `None` when nothing intact follows (the
    /// file ends here, as far as it can be read).
    pub resumed_at: Option<u64>,
}

impl FlightLog {
    /// The index in [`ticks`](Self::ticks) of the first tick after the first stretch the
    /// reader skipped: the ticks from there on do not follow the ones before without a gap.
    pub fn first_gap(&self) -> Option<usize> {
        self.damage
            .iter()
            .find(|d| d.resumed_at.is_some())
            .map(|d| d.tick)
    }
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
    /// Absent from logs whose events do not carry the script's line and the fix.
    #[serde(default)]
    line: Option<u32>,
    #[serde(default)]
    help: Option<String>,
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

/// Which channels the reader decodes, and how.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Wanted {
    Tick,
    Framing,
    Event,
    KeyFrame,
    /// A topic it decodes, under a schema or an encoding it does not: the log is refused at
    /// the topic's first message.
    Refused {
        topic: &'static str,
        detail: String,
    },
}

/// The MCAP magic, at both ends of the file.
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";
/// A chunk record's fixed fields after its opcode and length: start and end time,
/// uncompressed size, CRC, the compression's length prefix, and the records' length prefix.
const CHUNK_FIXED: u64 = 8 + 8 + 8 + 4 + 4 + 8;
/// The Footer record, opcode and length included.
const FOOTER_LEN: u64 = 1 + 8 + 8 + 8 + 4;
/// The Data End record, opcode and length included.
const DATA_END_LEN: u64 = 1 + 8 + 4;

impl FlightLog {
    /// Reads the log at `path`. A damaged file gives every tick, key frame and event in its
    /// intact chunks, with each skipped stretch in `damage`; a file cut short gives everything
    /// before the cut with `truncated` set. A file that is not MCAP, or has no flight header,
    /// is an error.
    pub fn open(path: &Path) -> Result<FlightLog, LogError> {
        let io_err = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::open(path).map_err(io_err)?;
        let len = file.metadata().map_err(io_err)?.len();
        read(
            path,
            FileBytes {
                file,
                len,
                pos: 0,
                buf: Vec::new(),
            },
        )
    }

    /// [`FlightLog::open`] of a log held in memory; `path` names it in errors.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<FlightLog, LogError> {
        read(path, bytes)
    }
}

/// Where the reader's bytes come from: a file, read at offsets, or bytes in memory.
trait Bytes {
    fn len(&self) -> u64;
    /// The `n` bytes at `at`: fewer at the end of the file.
    fn get(&mut self, at: u64, n: u64) -> io::Result<&[u8]>;
}

/// A file, read at offsets (a seek only when the offset is not where the last read ended).
struct FileBytes {
    file: File,
    len: u64,
    pos: u64,
    buf: Vec<u8>,
}

impl Bytes for FileBytes {
    fn len(&self) -> u64 {
        self.len
    }

    fn get(&mut self, at: u64, n: u64) -> io::Result<&[u8]> {
        self.buf.clear();
        if at >= self.len {
            return Ok(&self.buf);
        }
        let n = n.min(self.len - at);
        if self.pos != at {
            self.file.seek(SeekFrom::Start(at))?;
            self.pos = at;
        }
        self.buf.reserve(usize::try_from(n).unwrap_or(usize::MAX));
        let read = (&mut self.file).take(n).read_to_end(&mut self.buf);
        self.pos = at + self.buf.len() as u64;
        read?;
        Ok(&self.buf)
    }
}

impl Bytes for &[u8] {
    fn len(&self) -> u64 {
        <[u8]>::len(self) as u64
    }

    fn get(&mut self, at: u64, n: u64) -> io::Result<&[u8]> {
        let len = <[u8]>::len(self);
        let at = usize::try_from(at).unwrap_or(usize::MAX).min(len);
        let end = usize::try_from(n).map_or(len, |n| at.saturating_add(n).min(len));
        Ok(&self[at..end])
    }
}

/// What reading one record gave.
enum Step {
    /// Read; the next record is at this offset.
    Next(u64),
    /// The footer and the closing magic, or where a checked summary says the data ends:
    /// the end.
    End,
    /// Damage from the record's first byte: what is wrong, and whether the record runs past
    /// the end of the file.
    Bad { detail: String, past_end: bool },
}

/// Where a finished log's summary says its data ends, once its CRC matches.
#[derive(Clone, Copy, PartialEq, Eq)]
enum SummaryCheck {
    /// No footer to check (a log cut short), or one whose summary has no CRC.
    Absent,
    /// The summary matches the footer's CRC: the data section ends at `data_end` (the Data
    /// End record's offset).
    Checked { data_end: u64 },
    /// The footer is there but the summary from `start` does not match its CRC.
    Mismatch { start: u64 },
}

/// The `dronecine.flight` metadata record first met: where it is, and the header it holds.
struct MetadataHeader {
    offset: u64,
    end: u64,
    tick: usize,
    header: Result<FlightHeader, String>,
}

struct Reader<B> {
    src: B,
    /// The largest record the reader takes (see [`record_length_limit`]).
    limit: u64,
    state: ReadState,
    chunk: ChunkScratch,
    damage: Vec<Damage>,
    summary: SummaryCheck,
    /// Past the Data End record: the summary section.
    in_summary: bool,
    footer: bool,
    /// The file ends inside the closing magic.
    magic_cut: bool,
    /// The file's last bytes are the closing magic: it was not cut.
    ends_with_magic: bool,
    metadata: Option<MetadataHeader>,
    /// The header attachment's header (the first that parses, else the first met).
    attached: Option<Result<FlightHeader, String>>,
}

fn read(path: &Path, src: impl Bytes) -> Result<FlightLog, LogError> {
    let len = src.len();
    let mut reader = Reader {
        src,
        limit: record_length_limit(len) as u64,
        state: ReadState::new(path),
        chunk: ChunkScratch::default(),
        damage: Vec::new(),
        summary: SummaryCheck::Absent,
        in_summary: false,
        ends_with_magic: false,
        footer: false,
        magic_cut: false,
        metadata: None,
        attached: None,
    };
    reader.run().map_err(|e| match e {
        Failure::Io(source) => LogError::Io {
            path: path.to_path_buf(),
            source,
        },
        Failure::Log(e) => e,
    })?;
    reader.finish(path)
}

/// Why reading stopped: the file could not be read, or it holds what the reader refuses.
enum Failure {
    Io(io::Error),
    Log(LogError),
}

impl From<io::Error> for Failure {
    fn from(e: io::Error) -> Failure {
        Failure::Io(e)
    }
}

impl From<LogError> for Failure {
    fn from(e: LogError) -> Failure {
        Failure::Log(e)
    }
}

impl<B: Bytes> Reader<B> {
    fn run(&mut self) -> Result<(), Failure> {
        let len = self.src.len();
        self.ends_with_magic = len >= 16 && self.src.get(len - 8, 8)? == MAGIC;
        self.summary = self.read_summary()?;
        let mut next = if self.src.get(0, 8)? == MAGIC {
            Some(8)
        } else {
            self.skip(0, "no MCAP magic".into(), len < 8)?
        };
        while let Some(at) = next {
            if let SummaryCheck::Checked { data_end } = self.summary {
                if at == data_end && !self.in_summary {
                    // The summary, checked, follows: every record of the data was read.
                    self.footer = true;
                    break;
                }
            }
            if at >= len {
                self.damage.push(Damage {
                    offset: len,
                    detail: "the file ends before its footer".into(),
                    cut: true,
                    tick: self.state.ticks.len(),
                    resumed_at: None,
                });
                break;
            }
            next = match self.record_at(at)? {
                Step::Next(p) => Some(p),
                Step::End => None,
                Step::Bad { detail, past_end } => self.skip(at, detail, past_end)?,
            };
        }
        if let SummaryCheck::Mismatch { start } = self.summary {
            if self.footer && self.damage.last().is_none_or(|d| d.resumed_at.is_some()) {
                self.damage.push(Damage {
                    offset: start,
                    detail: "the summary after the data does not match the footer's CRC \
                             (every record before it was read)"
                        .into(),
                    cut: false,
                    tick: self.state.ticks.len(),
                    resumed_at: None,
                });
            }
        }
        Ok(())
    }

    /// Damage from `at`: noted, with where reading resumes (the next intact record after
    /// `at`, if any).
    fn skip(&mut self, at: u64, detail: String, past_end: bool) -> io::Result<Option<u64>> {
        let resumed_at = if self.in_summary {
            None
        } else {
            self.find_intact(at + 1)?
        };
        self.damage.push(Damage {
            offset: at,
            detail,
            // A record cut by the end of the file, unless intact data follows it or the file
            // ends with the closing magic (then its length was what was damaged).
            cut: past_end && resumed_at.is_none() && !self.ends_with_magic,
            tick: self.state.ticks.len(),
            resumed_at,
        });
        Ok(resumed_at)
    }

    /// Reads the record at `at`.
    fn record_at(&mut self, at: u64) -> Result<Step, Failure> {
        let len = self.src.len();
        let head = self.src.get(at, 9)?;
        if head.len() < 9 {
            return Ok(Step::Bad {
                detail: "the file ends in the middle of a record".into(),
                past_end: true,
            });
        }
        let opcode = head[0];
        let n = u64::from_le_bytes(head[1..9].try_into().expect("8 bytes"));
        if n > self.limit {
            return Ok(Step::Bad {
                detail: format!("a record that claims {n} bytes, more than the file can hold"),
                past_end: false,
            });
        }
        if at + 9 + n > len {
            return Ok(Step::Bad {
                detail: "the file ends in the middle of a record".into(),
                past_end: true,
            });
        }
        let next = at + 9 + n;
        let body = self.src.get(at + 9, n)?;
        let bad = |detail: String| {
            Ok(Step::Bad {
                detail,
                past_end: false,
            })
        };
        if self.in_summary || opcode == op::FOOTER {
            return match summary_record(opcode, body) {
                Ok(false) => Ok(Step::Next(next)),
                Ok(true) => self.closing_magic(next),
                Err(detail) => bad(detail),
            };
        }
        match opcode {
            op::CHUNK => {
                let records_at = match self.chunk.open(body) {
                    Ok(r) => r,
                    Err(detail) => return bad(detail),
                };
                let records = match records_at {
                    RecordsAt::Body(range) => &body[range],
                    RecordsAt::Decompressed => &self.chunk.decompressed[..],
                };
                for (opcode, range) in &self.chunk.records {
                    // Under the chunk's CRC: a record that does not parse was written so,
                    // and is skipped.
                    let Ok(record) = mcap::parse_record(*opcode, &records[range.clone()]) else {
                        continue;
                    };
                    self.state.records += 1;
                    self.state.record(record, true)?;
                }
                Ok(Step::Next(next))
            }
            op::MESSAGE => bad("a message outside a chunk, where no CRC covers it".into()),
            op::ATTACHMENT => match attachment(body) {
                Ok((name, data)) => {
                    self.state.records += 1;
                    if name == HEADER_ATTACHMENT && !matches!(self.attached, Some(Ok(_))) {
                        let header =
                            serde_json::from_slice::<FlightHeader>(data).map_err(|e| e.to_string());
                        if header.is_ok() || self.attached.is_none() {
                            self.attached = Some(header);
                        }
                    }
                    Ok(Step::Next(next))
                }
                Err(detail) => bad(detail),
            },
            op::DATA_END => {
                if body.len() != 4 {
                    return bad("a Data End record of another length".into());
                }
                self.state.records += 1;
                self.in_summary = true;
                Ok(Step::Next(next))
            }
            op::HEADER | op::SCHEMA | op::CHANNEL | op::METADATA | op::MESSAGE_INDEX => {
                let record = match whole_record(opcode, body) {
                    Ok(r) => r,
                    Err(detail) => return bad(detail),
                };
                self.state.records += 1;
                if let Record::Metadata(m) = &record {
                    if m.name == HEADER_METADATA && self.metadata.is_none() {
                        self.metadata = Some(MetadataHeader {
                            offset: at,
                            end: next,
                            tick: self.state.ticks.len(),
                            header: parse_header(&m.metadata),
                        });
                    }
                }
                self.state.record(record, false)?;
                Ok(Step::Next(next))
            }
            other => bad(format!(
                "a record of a kind a flight log's data does not hold (opcode {other:#04x})"
            )),
        }
    }

    /// After the footer, at `at`: the closing magic, the end.
    fn closing_magic(&mut self, at: u64) -> Result<Step, Failure> {
        self.footer = true;
        let tail = self.src.get(at, 8)?;
        if tail != MAGIC {
            let cut = tail.len() < 8 && MAGIC.starts_with(tail);
            self.magic_cut = cut;
            self.damage.push(Damage {
                offset: at,
                detail: format!(
                    "what follows the footer is not the closing MCAP magic ({})",
                    if cut {
                        "the file ends in the middle of a record"
                    } else {
                        "no MCAP magic"
                    }
                ),
                cut,
                tick: self.state.ticks.len(),
                resumed_at: None,
            });
        }
        Ok(Step::End)
    }

    /// A finished log's footer and summary: the summary checked against the footer's CRC, its
    /// schemas and channels taken (as checked copies), and where the data ends.
    fn read_summary(&mut self) -> Result<SummaryCheck, Failure> {
        let len = self.src.len();
        if len < 8 + FOOTER_LEN + 8 {
            return Ok(SummaryCheck::Absent);
        }
        let footer_at = len - 8 - FOOTER_LEN;
        let b = self.src.get(footer_at, FOOTER_LEN + 8)?;
        let u64_at = |k: usize| u64::from_le_bytes(b[k..k + 8].try_into().expect("8 bytes"));
        if b.len() as u64 != FOOTER_LEN + 8
            || &b[FOOTER_LEN as usize..] != MAGIC
            || b[0] != op::FOOTER
            || u64_at(1) != FOOTER_LEN - 9
        {
            return Ok(SummaryCheck::Absent);
        }
        let summary_start = u64_at(9);
        let crc = u32::from_le_bytes(b[25..29].try_into().expect("4 bytes"));
        if crc == 0 || summary_start < 8 + DATA_END_LEN || summary_start > footer_at {
            return Ok(SummaryCheck::Absent);
        }
        // The CRC covers the summary and the footer up to its CRC.
        let covered = self
            .src
            .get(summary_start, footer_at + 25 - summary_start)?;
        if crc32fast::hash(covered) != crc {
            return Ok(SummaryCheck::Mismatch {
                start: summary_start,
            });
        }
        let summary = &covered[..(footer_at - summary_start) as usize];
        let mut i = 0usize;
        while i + 9 <= summary.len() {
            let opcode = summary[i];
            let n = u64::from_le_bytes(summary[i + 1..i + 9].try_into().expect("8 bytes"));
            let Some(end) = usize::try_from(n)
                .ok()
                .and_then(|n| (i + 9).checked_add(n))
                .filter(|&end| end <= summary.len())
            else {
                break;
            };
            if let Ok(record @ (Record::Schema { .. } | Record::Channel(_))) =
                whole_record(opcode, &summary[i + 9..end])
            {
                self.state.record(record, true)?;
            }
            i = end;
        }
        Ok(SummaryCheck::Checked {
            data_end: summary_start - DATA_END_LEN,
        })
    }

    /// The offset of the first intact record at or after `from` that the reader can check:
    /// a chunk (its opcode, a length that fits the file, a consistent header, its CRC), an
    /// attachment with its CRC, or the header's metadata record (its length exactly what
    /// its fields make); or, in a log whose summary is checked, where its data ends. `None`
    /// when there is none.
    fn find_intact(&mut self, from: u64) -> io::Result<Option<u64>> {
        const WINDOW: u64 = 1 << 20;
        /// What a candidate chunk's header needs in view: opcode, length, the fixed fields
        /// and a compression name of up to 8 bytes.
        const HEAD: u64 = 9 + CHUNK_FIXED + 8;
        let end = match self.summary {
            SummaryCheck::Checked { data_end } => data_end,
            _ => self.src.len(),
        };
        let limit = self.limit;
        let mut candidates = Vec::new();
        let mut base = from;
        while base < end {
            // The places whose first bytes could start such a record, then each checked.
            let window = self.src.get(base, WINDOW + HEAD)?;
            let last = (window.len() as u64).min(WINDOW).min(end - base) as usize;
            candidates.clear();
            for i in memchr::memchr3_iter(op::CHUNK, op::ATTACHMENT, op::METADATA, &window[..last])
            {
                let opcode = window[i];
                let at = base + i as u64;
                let head = &window[i..window.len().min(i + HEAD as usize)];
                let Some(n) = head
                    .get(1..9)
                    .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
                else {
                    continue;
                };
                let fits = n <= limit && at.saturating_add(9).saturating_add(n) <= end;
                if fits
                    && (opcode != op::CHUNK || plausible_chunk_head(head, at, end, limit as usize))
                {
                    candidates.push((at, opcode, n));
                }
            }
            for &(at, opcode, n) in &candidates {
                let body = self.src.get(at + 9, n)?;
                let intact = match opcode {
                    op::CHUNK => self.chunk.open(body).is_ok(),
                    // With its CRC set (not 0).
                    op::ATTACHMENT => attachment(body).is_ok() && !body.ends_with(&[0; 4]),
                    _ => matches!(
                        whole_record(op::METADATA, body),
                        Ok(Record::Metadata(m)) if m.name == HEADER_METADATA
                    ),
                };
                if intact {
                    return Ok(Some(at));
                }
            }
            if last == 0 {
                break;
            }
            base += last as u64;
        }
        Ok(match self.summary {
            SummaryCheck::Checked { data_end } if data_end >= from => Some(data_end),
            _ => None,
        })
    }

    /// The log read: its header (the attachment's, under its CRC, else the metadata
    /// record's), and its damage in file order.
    fn finish(mut self, path: &Path) -> Result<FlightLog, LogError> {
        let len = self.src.len();
        if self.state.records == 0 {
            return Err(LogError::NotMcap {
                path: path.to_path_buf(),
                detail: self
                    .damage
                    .first()
                    .map_or_else(|| "no record".to_string(), |d| d.detail.clone()),
            });
        }
        let header = match (self.attached, self.metadata) {
            (Some(Ok(header)), metadata) => {
                if let Some(m) = metadata {
                    // Read over, by its checked copy: say so.
                    if m.header.as_ref() != Ok(&header) && m.end < len {
                        self.damage.push(Damage {
                            offset: m.offset,
                            detail: format!(
                                "the `{HEADER_METADATA}` metadata record differs from its \
                                 copy under a CRC (the attachment `{HEADER_ATTACHMENT}`), \
                                 which is read instead"
                            ),
                            cut: false,
                            tick: m.tick,
                            resumed_at: Some(m.end),
                        });
                    }
                }
                header
            }
            (_, Some(m)) => m.header.map_err(|detail| LogError::BadHeader {
                path: path.to_path_buf(),
                detail,
            })?,
            (Some(Err(detail)), None) => {
                return Err(LogError::BadHeader {
                    path: path.to_path_buf(),
                    detail,
                })
            }
            (None, None) => {
                return Err(LogError::NoHeader {
                    path: path.to_path_buf(),
                })
            }
        };
        self.damage.sort_by_key(|d| d.offset);
        Ok(FlightLog {
            header,
            ticks: self.state.ticks,
            key_frames: self.state.key_frames,
            events: self.state.events,
            truncated: !self.footer || self.magic_cut,
            damage: self.damage,
        })
    }
}

/// A record of the summary section (or the footer, in a file with none): whether it is the
/// footer, or what is wrong with it. The summary's schemas and channels repeat the data
/// section's (read there), and its indexes are not used.
fn summary_record(opcode: u8, body: &[u8]) -> Result<bool, String> {
    match opcode {
        op::FOOTER
        | op::SCHEMA
        | op::CHANNEL
        | op::STATISTICS
        | op::CHUNK_INDEX
        | op::ATTACHMENT_INDEX
        | op::METADATA_INDEX
        | op::SUMMARY_OFFSET => whole_record(opcode, body).map(|_| opcode == op::FOOTER),
        other => Err(format!(
            "a record of a kind a summary does not hold (opcode {other:#04x})"
        )),
    }
}

/// An attachment record's body, checked: its length exactly what its fields make, and its
/// CRC (when set). Its name and data.
fn attachment(body: &[u8]) -> Result<(&str, &[u8]), String> {
    let bad = || "an attachment that does not parse".to_string();
    let mut at = 16usize;
    let string = |at: &mut usize| -> Result<&str, String> {
        let n = body
            .get(*at..*at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize)
            .ok_or_else(bad)?;
        let s = body
            .get(*at + 4..)
            .and_then(|b| b.get(..n))
            .ok_or_else(bad)?;
        *at += 4 + n;
        std::str::from_utf8(s).map_err(|_| bad())
    };
    let name = string(&mut at)?;
    let _media_type = string(&mut at)?;
    let n = body
        .get(at..at + 8)
        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
        .ok_or_else(bad)?;
    let data_at = at + 8;
    if usize::try_from(n).ok().and_then(|n| data_at.checked_add(n)) != body.len().checked_sub(4) {
        return Err("an attachment whose length is not what its fields make".into());
    }
    let crc_at = body.len() - 4;
    let crc = u32::from_le_bytes(body[crc_at..].try_into().expect("4 bytes"));
    if crc != 0 && crc32fast::hash(&body[..crc_at]) != crc {
        return Err("an attachment whose CRC does not match its bytes".into());
    }
    Ok((name, &body[data_at..crc_at]))
}

/// A record parsed, whose length is exactly what its fields make (a damaged length is damage
/// at this record, not a misreading of the next).
fn whole_record(opcode: u8, body: &[u8]) -> Result<Record<'_>, String> {
    let record = mcap::parse_record(opcode, body)
        .map_err(|e| format!("a record that does not parse ({e})"))?;
    let string = |s: &str| 4 + s.len() as u64;
    let map = |m: &BTreeMap<String, String>| {
        4 + m.iter().map(|(k, v)| string(k) + string(v)).sum::<u64>()
    };
    let expected = match &record {
        Record::Header(h) => string(&h.profile) + string(&h.library),
        Record::Footer(_) => 20,
        Record::Schema { header, data } => {
            2 + string(&header.name) + string(&header.encoding) + 4 + data.len() as u64
        }
        Record::Channel(c) => 4 + string(&c.topic) + string(&c.message_encoding) + map(&c.metadata),
        Record::MessageIndex(m) => 2 + 4 + 16 * m.records.len() as u64,
        Record::ChunkIndex(c) => {
            8 * 4 + 4 + 10 * c.message_index_offsets.len() as u64 + 8 + string(&c.compression) + 16
        }
        Record::AttachmentIndex(a) => 8 * 5 + string(&a.name) + string(&a.media_type),
        Record::Statistics(s) => {
            8 + 2 + 4 * 4 + 16 + 4 + 10 * s.channel_message_counts.len() as u64
        }
        Record::Metadata(m) => string(&m.name) + map(&m.metadata),
        Record::MetadataIndex(m) => 16 + string(&m.name),
        Record::SummaryOffset(_) => 17,
        Record::DataEnd(_) => 4,
        _ => body.len() as u64,
    };
    if expected != body.len() as u64 {
        return Err(format!(
            "a record whose length ({} bytes) is not what its fields make ({expected})",
            body.len()
        ));
    }
    Ok(record)
}

/// A chunk opened: its records decompressed and CRC-checked, and framed.
#[derive(Default)]
struct ChunkScratch {
    /// The decompressed records of a compressed chunk.
    decompressed: Vec<u8>,
    /// Each inner record's opcode and body range, in `records`.
    records: Vec<(u8, std::ops::Range<usize>)>,
}

impl ChunkScratch {
    /// Opens a chunk record's body: decompresses it, checks its CRC (when the writer set one)
    /// and frames every inner record, before any of them is used. Returns where the records'
    /// bytes are.
    fn open(&mut self, body: &[u8]) -> Result<RecordsAt, String> {
        let record = mcap::parse_record(mcap::records::op::CHUNK, body)
            .map_err(|e| format!("a chunk that does not parse ({e})"))?;
        let mcap::records::Record::Chunk { header, data } = record else {
            return Err("a chunk that does not parse".into());
        };
        // `data` borrows `body` (parse_record does not copy): its place in it.
        let std::borrow::Cow::Borrowed(data) = data else {
            return Err("a chunk that does not parse".into());
        };
        let start = data.as_ptr() as usize - body.as_ptr() as usize;
        let compression = header.compression.as_str();
        // Its length is what its fields make: a damaged length is damage here, not at the
        // record after it (which would be skipped with it).
        if body.len() as u64 != CHUNK_FIXED + compression.len() as u64 + data.len() as u64 {
            return Err(format!(
                "a chunk whose length ({} bytes) is not what its fields make",
                body.len()
            ));
        }
        let records: &[u8] = if compression.is_empty() {
            data
        } else {
            let size = usize::try_from(header.uncompressed_size)
                .ok()
                .filter(|&n| n <= body.len().saturating_mul(256).max(16 << 20))
                .ok_or_else(|| {
                    format!(
                        "a chunk that claims {} bytes uncompressed",
                        header.uncompressed_size
                    )
                })?;
            self.decompressed.clear();
            self.decompressed.reserve(size);
            // One byte more than it claims: a chunk that holds more is caught below.
            let cap = size as u64 + 1;
            let read = match compression {
                "lz4" => lz4::Decoder::new(data)
                    .and_then(|d| d.take(cap).read_to_end(&mut self.decompressed)),
                "zstd" => zstd::stream::read::Decoder::new(data)
                    .and_then(|d| d.take(cap).read_to_end(&mut self.decompressed)),
                other => {
                    return Err(format!(
                        "a chunk compressed with `{}`, which this reader does not know",
                        dronecine_diag::suggest::shorten(other)
                    ))
                }
            };
            read.map_err(|e| {
                format!("a chunk whose {compression} data does not decompress ({e})")
            })?;
            &self.decompressed
        };
        let at = if compression.is_empty() {
            RecordsAt::Body(start..start + data.len())
        } else {
            RecordsAt::Decompressed
        };
        if records.len() as u64 != header.uncompressed_size {
            return Err(format!(
                "a chunk of {} bytes that says it holds {}",
                records.len(),
                header.uncompressed_size
            ));
        }
        if header.uncompressed_crc != 0 && crc32fast::hash(records) != header.uncompressed_crc {
            return Err("a chunk whose CRC does not match its bytes".into());
        }
        self.records.clear();
        let mut i = 0usize;
        while i < records.len() {
            let head = records
                .get(i..i + 9)
                .ok_or_else(|| "a chunk whose last record is cut".to_string())?;
            let n = u64::from_le_bytes(head[1..9].try_into().expect("8 bytes"));
            let end = usize::try_from(n)
                .ok()
                .and_then(|n| (i + 9).checked_add(n))
                .filter(|&end| end <= records.len())
                .ok_or_else(|| "a chunk whose records overrun it".to_string())?;
            self.records.push((head[0], i + 9..end));
            i = end;
        }
        Ok(at)
    }
}

/// Where an opened chunk's records are: a range of the chunk record's body (uncompressed),
/// or [`ChunkScratch::decompressed`].
enum RecordsAt {
    Body(std::ops::Range<usize>),
    Decompressed,
}

/// Whether `head` (a candidate chunk's first bytes, at file offset `at`) can start a chunk of
/// a flight log: its length fits the file and the limit, its compression is one this reader
/// opens, its records' length is what is left of it, and it carries a CRC.
fn plausible_chunk_head(head: &[u8], at: u64, len: u64, limit: usize) -> bool {
    let u64_at = |k: usize| {
        head.get(k..k + 8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
    };
    let u32_at = |k: usize| {
        head.get(k..k + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
    };
    let (Some(n), Some(crc), Some(name_len)) = (u64_at(1), u32_at(9 + 24), u32_at(9 + 28)) else {
        return false;
    };
    let name_len = u64::from(name_len);
    if n < CHUNK_FIXED || n > limit as u64 || at.saturating_add(9).saturating_add(n) > len {
        return false;
    }
    if crc == 0 || name_len > 8 {
        return false;
    }
    let name_at = 9 + 32;
    let Some(name) = head.get(name_at..name_at + name_len as usize) else {
        return false;
    };
    if !matches!(name, b"" | b"lz4" | b"zstd") {
        return false;
    }
    let Some(records_len) = u64_at(name_at + name_len as usize) else {
        return false;
    };
    records_len == n - CHUNK_FIXED - name_len
}

/// The largest record (or decompressed chunk) the reader accepts in a file of `len` bytes:
/// what a damaged length field cannot exceed, so it is refused instead of allocated. A
/// compressed chunk decompresses to more than the file holds (LZ4's ratio reaches 255; a
/// short LZ4 flight log's first chunk is larger than the whole file), hence the factor.
fn record_length_limit(len: u64) -> usize {
    let limit = len.saturating_mul(256).max(16 << 20);
    usize::try_from(limit).unwrap_or(usize::MAX)
}

/// A channel as its record describes it.
struct ChannelInfo {
    topic: String,
    encoding: String,
    schema_id: u16,
}

struct ReadState {
    path: PathBuf,
    /// The schemas' names by id, and whether the record was under a CRC (in a chunk, or in a
    /// checked summary): such a record overrides one that was not, never the other way.
    schemas: HashMap<u16, (String, bool)>,
    channels: HashMap<u16, (ChannelInfo, bool)>,
    /// What each channel is read as, from `schemas` and `channels`; rebuilt when they change.
    wanted: HashMap<u16, Wanted>,
    stale: bool,
    ticks: Vec<LoggedTick>,
    key_frames: Vec<KeyFrame>,
    events: Vec<Event>,
    /// A `/framing` message waiting for its tick (written just before it, same `t_s`): the
    /// framing of a log whose ticks do not carry it.
    pending_framing: Option<(u64, Vec<FramingRecord>)>,
    records: usize,
}

impl ReadState {
    fn new(path: &Path) -> ReadState {
        ReadState {
            path: path.to_path_buf(),
            schemas: HashMap::new(),
            channels: HashMap::new(),
            wanted: HashMap::new(),
            stale: false,
            ticks: Vec::new(),
            key_frames: Vec::new(),
            events: Vec::new(),
            pending_framing: None,
            records: 0,
        }
    }

    /// How a channel is read. A topic this reader decodes must come under the schema it
    /// decodes: a log written with another layout under its name (a newer dronecine's) is
    /// refused, not misread (a key frame under another schema is ignored: the log reads as
    /// one without key frames). A channel whose schema record is not known (lost to damage)
    /// is read as the one it names.
    fn wanted_for(&self, channel: &ChannelInfo) -> Option<Wanted> {
        let schema = self
            .schemas
            .get(&channel.schema_id)
            .map(|(name, _)| name.as_str());
        let refused = |topic: &'static str, expected: &str| {
            schema
                .filter(|&name| name != expected)
                .map(|name| Wanted::Refused {
                    topic,
                    detail: format!(
                    "its schema is `{}`; this dronecine reads `{expected}` (the log was written \
                     by another dronecine: replay it with that version)",
                    dronecine_diag::suggest::shorten(name)
                ),
                })
        };
        match channel.topic.as_str() {
            topic::SERVO_TICK if channel.encoding != cdr::MESSAGE_ENCODING => {
                Some(Wanted::Refused {
                    topic: topic::SERVO_TICK,
                    detail: format!(
                        "its encoding is `{}`; this dronecine reads `{}` (the log was written by \
                         an older dronecine: replay it with that version)",
                        dronecine_diag::suggest::shorten(&channel.encoding),
                        cdr::MESSAGE_ENCODING
                    ),
                })
            }
            topic::SERVO_TICK => {
                Some(refused(topic::SERVO_TICK, cdr::SCHEMA_NAME).unwrap_or(Wanted::Tick))
            }
            topic::EVENTS => Some(refused(topic::EVENTS, schema::EVENT).unwrap_or(Wanted::Event)),
            topic::SERVO_STATE
                if channel.encoding == cdr::MESSAGE_ENCODING
                    && schema.is_none_or(|name| name == key_frame::SCHEMA_NAME) =>
            {
                Some(Wanted::KeyFrame)
            }
            // JSON framing at every tick: a log whose `/servo/tick` does not carry the
            // framing (where it does, `/framing` is CDR, for plots only).
            topic::FRAMING if channel.encoding == Encoding::Json.message() => Some(Wanted::Framing),
            _ => None,
        }
    }

    /// What channel `id` is read as.
    fn wanted(&mut self, id: u16) -> Option<&Wanted> {
        if self.stale {
            self.stale = false;
            let wanted = self
                .channels
                .iter()
                .filter_map(|(&id, (c, _))| Some((id, self.wanted_for(c)?)))
                .collect();
            self.wanted = wanted;
        }
        self.wanted.get(&id)
    }

    /// A record of the log; `checked`: under a CRC (in a chunk, or a checked summary).
    fn record(&mut self, record: Record, checked: bool) -> Result<(), LogError> {
        match record {
            Record::Schema { header, .. }
                if checked || self.schemas.get(&header.id).is_none_or(|(_, c)| !c) =>
            {
                self.schemas.insert(header.id, (header.name, checked));
                self.stale = true;
            }
            Record::Channel(c) if checked || self.channels.get(&c.id).is_none_or(|(_, c)| !c) => {
                let info = ChannelInfo {
                    topic: c.topic,
                    encoding: c.message_encoding,
                    schema_id: c.schema_id,
                };
                self.channels.insert(c.id, (info, checked));
                self.stale = true;
            }
            Record::Message { header, data } => self.message(header.channel_id, &data)?,
            _ => {}
        }
        Ok(())
    }

    fn message(&mut self, channel_id: u16, data: &[u8]) -> Result<(), LogError> {
        let Some(wanted) = self.wanted(channel_id) else {
            return Ok(());
        };
        let wanted = match wanted {
            Wanted::Refused { topic, detail } => Err((*topic, detail.clone())),
            other => Ok(other.clone()),
        };
        let path = &self.path;
        let bad = |topic, index, detail| LogError::BadMessage {
            path: path.clone(),
            topic,
            index,
            detail,
        };
        match wanted {
            Err((topic, detail)) => return Err(bad(topic, 0, detail)),
            Ok(Wanted::Tick) => {
                let decoded =
                    cdr::decode(data).map_err(|d| bad(topic::SERVO_TICK, self.ticks.len(), d))?;
                let mut tick = decoded.tick;
                if let Some((t_bits, framing)) = self.pending_framing.take() {
                    if !decoded.extended && t_bits == tick.input.t_s.to_bits() {
                        tick.framing = framing;
                    }
                }
                self.ticks.push(tick);
            }
            Ok(Wanted::KeyFrame) => {
                let (t_s, state) = key_frame::decode(data)
                    .map_err(|d| bad(topic::SERVO_STATE, self.key_frames.len(), d))?;
                self.key_frames.push(KeyFrame {
                    tick: self.ticks.len(),
                    t_s,
                    state,
                });
            }
            Ok(Wanted::Framing) => {
                let f = serde_json::from_slice::<RawFraming>(data)
                    .map_err(|e| bad(topic::FRAMING, self.ticks.len(), e.to_string()))?;
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
            Ok(Wanted::Event) => {
                let e = serde_json::from_slice::<RawEvent>(data)
                    .map_err(|e| bad(topic::EVENTS, self.events.len(), e.to_string()))?;
                self.events.push(Event {
                    t_s: e.t_s.0,
                    level: e.level,
                    kind: e.kind,
                    message: e.message,
                    line: e.line,
                    help: e.help,
                });
            }
            Ok(Wanted::Refused { .. }) => {}
        }
        Ok(())
    }
}
