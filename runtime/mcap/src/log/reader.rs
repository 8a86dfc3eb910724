//! [`FlightLog`]: reads a flight log back for `dronecine replay`: the header, every tick of
//! `/servo/tick` and every event, recovering what precedes any damage.
//!
//! The file is streamed through the mcap crate's sans-io linear reader, which frames the
//! top-level records (memory: one chunk at a time plus the decoded ticks); this module opens
//! the chunks itself, so that it knows where each record starts. A chunk's CRC is checked
//! before any of its records is used, so a damaged chunk is never half-read.
//!
//! Damage does not end the reading. A record that does not frame or parse, or a chunk whose
//! CRC fails, is skipped: the reader searches forward for the next intact chunk (one whose
//! header is consistent and whose CRC matches) and goes on from there, so one bad sector in
//! an hour's log loses a second of it, not the rest. Each skip is a [`Damage`] with the ticks
//! it separates; a file that ends before its footer (a crash, a copy that did not finish) is
//! [`FlightLog::truncated`], everything before the cut read.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use crate::output::mcap::Encoding;
use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::McapError;
use serde::Deserialize;

use super::exact::Num;
use super::{cdr, schema, topic, LogError, HEADER_METADATA};
use crate::record::{Event, FlightHeader, FramingRecord, Phase};
use dronecine_backend::frames::Command;
use dronecine_compiler::reference::ActorPose;
use dronecine_servo::control::{TickFault, TickInput, TickOutput};

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

/// A flight log, read back.
#[derive(Clone, Debug)]
pub struct FlightLog {
    pub header: FlightHeader,
    /// Every tick that could be read, in the order written.
    pub ticks: Vec<LoggedTick>,
    pub events: Vec<Event>,
    /// The file does not end with its footer and the closing magic: cut short (a crash, a
    /// copy that did not finish, even inside the magic's last bytes), or damaged with nothing
    /// intact after the damage. Everything before was read;
    /// the last entry of `damage` says where and why it ends.
    pub truncated: bool,
    /// The damage met, in file order: each a stretch skipped (reading resumed at the next
    /// intact chunk) or, last, where the readable file ends when `truncated`.
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
    /// after it.
    pub tick: usize,
    /// The offset of the intact chunk where reading went on; `None` when nothing intact
    /// follows (the file ends here, as far as it can be read).
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
    /// Reads the log at `path`. A damaged file gives every tick and event in its intact
    /// chunks, with each skipped stretch in `damage`; a file cut short gives everything before
    /// the cut with `truncated` set. A file that is not MCAP, or has no flight header, is an
    /// error.
    pub fn open(path: &Path) -> Result<FlightLog, LogError> {
        let io_err = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut file = File::open(path).map_err(io_err)?;
        let len = file.metadata().map_err(io_err)?.len();
        let limit = record_length_limit(len);
        let mut state = ReadState {
            path: path.to_path_buf(),
            schemas: HashMap::new(),
            channels: HashMap::new(),
            header: None,
            ticks: Vec::new(),
            events: Vec::new(),
            pending_framing: None,
            records: 0,
            footer: false,
        };
        let mut chunk = ChunkScratch::default();
        let mut damage: Vec<Damage> = Vec::new();
        // Where the linear reader starts: the file's magic, then each intact chunk found
        // after damage.
        let mut start: Option<u64> = None;
        loop {
            let Some((offset, error)) = read_from(&mut file, start, limit, &mut state, &mut chunk)?
            else {
                break;
            };
            if state.records == 0 {
                return Err(LogError::NotMcap {
                    path: path.to_path_buf(),
                    detail: describe_read(&error),
                });
            }
            let cut = offset >= len || matches!(error, ReadError::Mcap(McapError::UnexpectedEof));
            let detail = if state.footer {
                format!(
                    "what follows the footer is not the closing MCAP magic ({})",
                    describe_read(&error)
                )
            } else if offset >= len {
                "the file ends before its footer".to_string()
            } else {
                describe_read(&error)
            };
            let resumed_at = if state.footer || offset >= len {
                None
            } else {
                find_chunk(&mut file, offset + 1, len, limit, &mut chunk).map_err(io_err)?
            };
            damage.push(Damage {
                offset,
                detail,
                // A record cut by the end of the file, unless intact data follows it (then
                // its length was what was damaged).
                cut: cut && resumed_at.is_none(),
                tick: state.ticks.len(),
                resumed_at,
            });
            match resumed_at {
                Some(p) => start = Some(p),
                None => break,
            }
        }
        // Cut inside the closing magic, after the footer: every record was read, but the
        // file was cut short all the same (a copy that stopped 3 bytes early).
        let magic_cut = state.footer && damage.last().is_some_and(|d| d.cut);
        let truncated = !state.footer || magic_cut;
        if !state.footer && damage.last().is_none_or(|d| d.resumed_at.is_some()) {
            damage.push(Damage {
                offset: len,
                detail: "the file ends before its footer".to_string(),
                cut: true,
                tick: state.ticks.len(),
                resumed_at: None,
            });
        }
        let header = state.header.take().ok_or_else(|| LogError::NoHeader {
            path: path.to_path_buf(),
        })?;
        Ok(FlightLog {
            header,
            ticks: state.ticks,
            events: state.events,
            truncated,
            damage,
        })
    }
}

/// Why one run of the linear reader stopped early.
enum ReadError {
    /// The reader's framing (a cut record, a length beyond the limit, no magic).
    Mcap(McapError),
    /// A chunk that cannot be used (CRC, compression, inner framing).
    Chunk(String),
    /// A top-level record that does not parse or is not one a flight log holds.
    Record(String),
}

fn describe_read(e: &ReadError) -> String {
    match e {
        ReadError::Mcap(e) => describe(e),
        ReadError::Chunk(s) | ReadError::Record(s) => s.clone(),
    }
}

/// Reads records with the mcap crate's linear reader from `start` (a chunk's offset, or
/// `None`: the file's start and its magic) until the end or the first damage. Returns where
/// the damage starts and what it is (`None`: the file read to its end magic); an I/O error,
/// or an intact record that is not what a flight log holds (a message that does not
/// decode), is an error.
fn read_from(
    file: &mut File,
    start: Option<u64>,
    limit: usize,
    state: &mut ReadState,
    chunk: &mut ChunkScratch,
) -> Result<Option<(u64, ReadError)>, LogError> {
    let path = state.path.clone();
    let io_err = |source| LogError::Io {
        path: path.clone(),
        source,
    };
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(start.is_some())
            .with_emit_chunks(true)
            .with_record_length_limit(limit),
    );
    let mut offset = match start {
        Some(p) => p,
        None => MAGIC_LEN,
    };
    file.seek(SeekFrom::Start(start.unwrap_or(0)))
        .map_err(io_err)?;
    loop {
        let event = match reader.next_event() {
            None => return Ok(None),
            Some(Ok(event)) => event,
            Some(Err(e)) => {
                // Before the first record the magic itself is what failed: offset 0.
                let at = if start.is_none() && state.records == 0 {
                    0
                } else {
                    offset
                };
                return Ok(Some((at, ReadError::Mcap(e))));
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = loop {
                    match file.read(buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                        Err(e) => return Err(io_err(e)),
                    }
                };
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                let at = offset;
                offset += 9 + data.len() as u64;
                let outcome = if opcode == mcap::records::op::CHUNK {
                    chunk.open(data).map_err(ReadError::Chunk).map(|at| {
                        let records = match at {
                            RecordsAt::Body(range) => &data[range],
                            RecordsAt::Decompressed => &chunk.decompressed[..],
                        };
                        let mut result = Ok(());
                        for (opcode, range) in &chunk.records {
                            let body = &records[range.clone()];
                            // Framed, and CRC-checked when the writer set one: a record
                            // that does not parse was written so, and is skipped.
                            let Ok(record) = mcap::parse_record(*opcode, body) else {
                                continue;
                            };
                            state.records += 1;
                            if let Err(e) = state.record(record) {
                                result = Err(e);
                                break;
                            }
                        }
                        result
                    })
                } else {
                    match mcap::parse_record(opcode, data) {
                        Ok(mcap::records::Record::Unknown { opcode, .. }) => {
                            Err(ReadError::Record(format!(
                                "a record of unknown kind (opcode {opcode:#04x})"
                            )))
                        }
                        Ok(record) => {
                            state.records += 1;
                            Ok(state.record(record))
                        }
                        Err(e) => Err(ReadError::Record(e.to_string())),
                    }
                };
                match outcome {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => return Err(e),
                    Err(e) => return Ok(Some((at, e))),
                }
            }
        }
    }
}

/// The MCAP magic's length: the first record starts after it.
const MAGIC_LEN: u64 = 8;
/// A chunk record's fixed fields after its opcode and length: start and end time,
/// uncompressed size, CRC, the compression's length prefix, and the records' length prefix.
const CHUNK_FIXED: u64 = 8 + 8 + 8 + 4 + 4 + 8;

/// A chunk opened: its records decompressed and CRC-checked, and framed.
#[derive(Default)]
struct ChunkScratch {
    /// The decompressed records of an LZ4 chunk.
    decompressed: Vec<u8>,
    /// Each inner record's opcode and body range, in `records`.
    records: Vec<(u8, std::ops::Range<usize>)>,
    /// The window [`find_chunk`] scans.
    window: Vec<u8>,
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

/// The offset of the first intact chunk at or after `from`: a chunk opcode whose length fits
/// the file and the limit, whose header is consistent, and whose records pass [`ChunkScratch::open`]
/// (its CRC matches). `None` when there is none before the end.
fn find_chunk(
    file: &mut File,
    from: u64,
    len: u64,
    limit: usize,
    chunk: &mut ChunkScratch,
) -> io::Result<Option<u64>> {
    const WINDOW: usize = 1 << 20;
    /// What a candidate's header needs in view: opcode, length, the fixed fields and a
    /// compression name of up to 8 bytes.
    const HEAD: usize = 9 + CHUNK_FIXED as usize + 8;
    let mut base = from;
    let mut window = std::mem::take(&mut chunk.window);
    let mut body = Vec::new();
    let found = 'scan: loop {
        if base >= len {
            break None;
        }
        window.clear();
        file.seek(SeekFrom::Start(base))?;
        file.by_ref()
            .take((WINDOW + HEAD) as u64)
            .read_to_end(&mut window)?;
        let last = window.len().min(WINDOW);
        for i in 0..last {
            if window[i] != mcap::records::op::CHUNK {
                continue;
            }
            let at = base + i as u64;
            let Some(head) = window.get(i..i + HEAD).or_else(|| window.get(i..)) else {
                continue;
            };
            if !plausible_chunk_head(head, at, len, limit) {
                continue;
            }
            let n = u64::from_le_bytes(head[1..9].try_into().expect("8 bytes"));
            body.clear();
            file.seek(SeekFrom::Start(at + 9))?;
            file.by_ref().take(n).read_to_end(&mut body)?;
            if body.len() as u64 == n && chunk.open(&body).is_ok() {
                break 'scan Some(at);
            }
        }
        base += last as u64;
        if last == 0 {
            break None;
        }
    };
    chunk.window = window;
    Ok(found)
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

fn describe(e: &McapError) -> String {
    match e {
        McapError::UnexpectedEof => "the file ends in the middle of a record".into(),
        McapError::BadMagic => "no MCAP magic".into(),
        other => other.to_string(),
    }
}

struct ReadState {
    path: PathBuf,
    /// The schemas' names by id, as their records come.
    schemas: HashMap<u16, String>,
    channels: HashMap<u16, Wanted>,
    header: Option<FlightHeader>,
    ticks: Vec<LoggedTick>,
    events: Vec<Event>,
    /// A `/framing` message waiting for its tick (written just before it, same `t_s`): the
    /// framing of a log whose ticks do not carry it.
    pending_framing: Option<(u64, Vec<FramingRecord>)>,
    records: usize,
    footer: bool,
}

impl ReadState {
    /// A topic this reader decodes must come under the schema it decodes: a log written with
    /// another layout under its name (a newer dronecine's) is refused, not misread. A channel
    /// whose schema record is not known (lost to damage) is read as the one it names.
    fn check_schema(&self, channel: &mcap::records::Channel) -> Result<(), LogError> {
        let (topic, expected) = match channel.topic.as_str() {
            topic::SERVO_TICK => (topic::SERVO_TICK, cdr::SCHEMA_NAME),
            topic::EVENTS => (topic::EVENTS, schema::EVENT),
            _ => return Ok(()),
        };
        match self.schemas.get(&channel.schema_id) {
            Some(name) if name != expected => Err(LogError::BadMessage {
                path: self.path.clone(),
                topic,
                index: 0,
                detail: format!(
                    "its schema is `{}`; this dronecine reads `{expected}` (the log was written \
                     by another dronecine: replay it with that version)",
                    dronecine_diag::suggest::shorten(name)
                ),
            }),
            _ => Ok(()),
        }
    }

    fn record(&mut self, record: Record) -> Result<(), LogError> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
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
                    // JSON framing at every tick: a log whose `/servo/tick` does not carry
                    // the framing (where it does, `/framing` is CDR, for plots only).
                    topic::FRAMING if channel.message_encoding == Encoding::Json.message() => {
                        Some(Wanted::Framing)
                    }
                    _ => None,
                };
                if let Some(w) = wanted {
                    self.check_schema(&channel)?;
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
                        line: e.line,
                        help: e.help,
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
