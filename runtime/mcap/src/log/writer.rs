//! [`FlightLogWriter`]: streams the flight's ticks and events into the MCAP log (contents and
//! crash behaviour in the module doc of `log`).
//!
//! Per tick the writer has [`FlightTopics`] encode the tick's messages (`/servo/tick`, and at
//! the plot and `/tf` rates the plot topics, all CDR) straight into the MCAP writer's
//! in-memory chunk, which is reused from chunk to chunk ([`McapFile`], written for this path:
//! each chunk hashed once and written with one system call); chunks carry no message indexes
//! (readers scan the ≤ 1 s chunks). Nothing on the per-tick path allocates. Only `/events` is
//! JSON.
//!
//! Chunks close by the flight's clock ([`ChunkClock`]), on ticks and on the ticks that record
//! nothing alike. After a tick that closes one, the writer asks for the controller's state
//! ([`FlightLogWriter::wants_key_frame`]) and writes it before the next tick, as the new
//! chunk's key frame on `/servo/state`; before the log's first tick it writes the mark that
//! the controller starts there. A key frame at every chunk's start (rather than every N ticks)
//! lets replay check every tick of any intact chunk, whatever was lost before it.

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use crate::output::mcap::Channel;

use super::mcap_file::{ChunkCompression, McapFile};
use super::topics::{FlightTopics, MessageOut, TopicSpec};
use super::{LogScene, HEADER_ATTACHMENT, HEADER_METADATA};
use crate::record::{Event, FlightHeader, TickRecord};
use dronecine_servo::control::ControllerState;

/// Chunk compression of the flight log.
///
/// LZ4 makes the log less than half the size for about three times the writer's CPU time per
/// tick (`benches/log.rs` measures both), which would make the log thread slower than the
/// simulated flight it logs. The default is no compression: a flight of minutes is a few
/// hundred megabytes at most.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogCompression {
    /// The default (see above).
    None,
    /// LZ4 frames: less than half the size for three times the CPU time per tick.
    Lz4,
}

/// Tuning of the flight log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogOptions {
    pub compression: LogCompression,
    /// Rate of `/tf` (Foxglove's 3D view).
    pub tf_hz: f64,
    /// Rate of `/reference`, `/actors`, `/estimate`, `/command` and `/framing` (Foxglove's
    /// plots; `/servo/tick` holds every tick's exact controller input and output, actors and
    /// framing, which Foxglove plots too). A `/command` whose `failsafe` flag is set, and the
    /// first after it, are written whatever the rate.
    pub plot_hz: f64,
    /// Rate of `/measurement`: the actors' raw measured poses are kept nowhere else.
    pub measurement_hz: f64,
    /// Flight time between two chunk closes and flushes: what a crash may lose. Also closed
    /// every `rate_hz · flush_period_s` ticks, whatever the ticks' clocks say; the ticks that
    /// record nothing ([`FlightLogWriter::idle`]: before take-off, the drone's own take-off
    /// and landing) count as ticks. (After [`FlightLogWriter::defer_hand_over`], closed
    /// chunks may wait for one larger write.)
    pub flush_period_s: f64,
    /// Whether the log is forced to the disk as it is written: its data synced every few
    /// seconds while the flight goes on ([`LogThread`](super::LogThread)'s syncer) and the
    /// file at [`FlightLogWriter::finish`]; a power cut then loses at most what came since the
    /// last sync. Without, the log is handed to the OS all the same (a crash of the process
    /// loses what it did before), which writes it to the disk in its own time. `shoot` forces
    /// a flight paced by the wall clock (a real one, or `--realtime`), whose log cannot be
    /// made again; a simulated flight as fast as it can go is reproducible from its script,
    /// profile and seed (which its log records), and is forced only with `--sync-log`.
    pub durable: bool,
}

impl Default for LogOptions {
    fn default() -> Self {
        Self {
            compression: LogCompression::None,
            tf_hz: 30.0,
            plot_hz: 10.0,
            measurement_hz: 30.0,
            flush_period_s: 1.0,
            durable: true,
        }
    }
}

impl LogOptions {
    /// `shoot`'s log: a chunk closed every `1 − BATCH_PERIOD_S − POLL_MAX_S` (0.73 s) of
    /// flight, so that a crash of the process loses at most the last second of a flight in
    /// real time ([`LogThread`](super::LogThread)), forced to the disk as it is written if
    /// `durable`.
    pub fn shoot(durable: bool) -> LogOptions {
        LogOptions {
            flush_period_s: 1.0 - super::BATCH_PERIOD_S - super::POLL_MAX_S,
            durable,
            ..LogOptions::default()
        }
    }
}

/// Writes a flight log, tick by tick (see the `log` module doc).
///
/// ```no_run
/// # use dronecine_mcap::log::{FlightLogWriter, LogScene};
/// # fn demo(header: &dronecine_mcap::record::FlightHeader, scene: &LogScene,
/// #         ticks: &[dronecine_mcap::record::TickRecord]) -> std::io::Result<()> {
/// let mut log = FlightLogWriter::create("flights/orbit.mcap".as_ref(), header, scene)?;
/// for tick in ticks {
///     log.write_tick(tick)?; // on disk within a second of flight time
/// }
/// log.finish()?; // the summary and the closing magic
/// # Ok(()) }
/// ```
pub struct FlightLogWriter {
    /// The topics, written into the MCAP file.
    topics: FlightTopics<McapOut>,
    options: LogOptions,
    clock: ChunkClock,
    /// The last tick closed a chunk: the next chunk starts with a key frame, which
    /// [`FlightLogWriter::write_key_frame`] gives.
    key_frame_due: bool,
    /// A second handle on the file, for syncing it from another thread (a durable log only).
    sync_file: Option<File>,
}

/// The MCAP file as the topics' [`MessageOut`]: each message straight into the open chunk.
struct McapOut {
    /// `None` once finished.
    writer: Option<McapFile>,
    path: PathBuf,
    /// Each channel's sequence counter, by channel id.
    channels: Vec<Channel>,
}

impl McapOut {
    /// The MCAP writer and the log's path, or the error of a finished log.
    fn mcap(&mut self) -> io::Result<(&mut McapFile, &Path)> {
        let path = &self.path;
        match self.writer.as_mut() {
            Some(w) => Ok((w, path)),
            None => Err(io::Error::other(format!(
                "cannot write {}: log finished",
                path.display()
            ))),
        }
    }
}

impl MessageOut for McapOut {
    fn add_channel(&mut self, t: &TopicSpec) -> io::Result<u16> {
        let (writer, path) = self.mcap()?;
        let err = |e| annotate(path, e);
        let schema = writer
            .add_schema(t.schema_name, t.encoding.schema(), t.schema.as_bytes())
            .map_err(err)?;
        let id = writer
            .add_channel(schema, t.topic, t.encoding.message())
            .map_err(err)?;
        debug_assert_eq!(usize::from(id), self.channels.len());
        self.channels.push(Channel::new(id));
        Ok(id)
    }

    #[inline]
    fn put(&mut self, channel: u16, ns: u64, encode: impl FnOnce(&mut Vec<u8>)) -> io::Result<()> {
        let Some(channel) = self.channels.get_mut(usize::from(channel)) else {
            return Err(io::Error::other(format!("no channel {channel} in the log")));
        };
        let header = channel.header(ns);
        let (path, writer) = (&self.path, self.writer.as_mut());
        let writer = writer.ok_or_else(|| {
            io::Error::other(format!("cannot write {}: log finished", path.display()))
        })?;
        writer
            .write_message_with(&header, encode)
            .map_err(|e| annotate(path, e))
    }
}

fn annotate(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))
}

/// The log's file for writing: a new one (`new`: an existing file is an error), or created
/// or truncated.
fn open(path: &Path, new: bool) -> io::Result<File> {
    let mut o = OpenOptions::new();
    o.write(true);
    if new {
        o.create_new(true);
    } else {
        o.create(true).truncate(true);
    }
    o.open(path).map_err(|e| annotate(path, e))
}

/// When the log closes its chunks: every `period_s` of flight time, and every `every_ticks`
/// ticks whatever their clocks say. A tick that records nothing counts as a tick: the log's
/// time passes as on any other. [`LogThread`](super::LogThread) keeps a copy, stepped with the
/// same ticks, to know where the writer starts its chunks.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChunkClock {
    period_s: f64,
    /// The flight time at which the next chunk closes.
    next_s: f64,
    ticks: u64,
    every_ticks: u64,
}

impl ChunkClock {
    fn new(period_s: f64, rate_hz: f64) -> ChunkClock {
        ChunkClock {
            period_s,
            next_s: period_s,
            ticks: 0,
            every_ticks: (rate_hz * period_s).floor().max(1.0) as u64,
        }
    }

    /// A tick at `t_s`: whether the chunk closes after it.
    pub(crate) fn step(&mut self, t_s: f64) -> bool {
        self.ticks += 1;
        let due = (t_s.is_finite() && t_s >= self.next_s) || self.ticks >= self.every_ticks;
        if due {
            if t_s.is_finite() {
                // The next close at most one period after this one.
                self.next_s = (self.next_s + self.period_s).clamp(t_s, t_s + self.period_s);
            }
            self.ticks = 0;
        }
        due
    }
}

impl FlightLogWriter {
    /// Creates (truncating) the log at `path` and writes the header, the schemas and
    /// channels, the `dronecine.flight` metadata, the script attachment, the header again as
    /// an attachment (its CRC checked), and a chunk with the schemas and channels again and
    /// the static scene, then flushes. The parent directory must exist (an error names the path otherwise).
    pub fn create(
        path: &Path,
        header: &FlightHeader,
        scene: &LogScene,
    ) -> io::Result<FlightLogWriter> {
        Self::create_with(path, header, scene, LogOptions::default())
    }

    pub fn create_with(
        path: &Path,
        header: &FlightHeader,
        scene: &LogScene,
        options: LogOptions,
    ) -> io::Result<FlightLogWriter> {
        Self::start(open(path, false)?, path, header, scene, options)
    }

    /// As [`FlightLogWriter::create_with`], but only as a new file: a file already at `path`
    /// (a previous flight's recording, say) is left alone and the error's kind is
    /// [`io::ErrorKind::AlreadyExists`]. The check and the creation are one step, so two
    /// flights started at once cannot both take the name.
    pub fn create_new_with(
        path: &Path,
        header: &FlightHeader,
        scene: &LogScene,
        options: LogOptions,
    ) -> io::Result<FlightLogWriter> {
        Self::start(open(path, true)?, path, header, scene, options)
    }

    fn start(
        file: File,
        path: &Path,
        header: &FlightHeader,
        scene: &LogScene,
        options: LogOptions,
    ) -> io::Result<FlightLogWriter> {
        let err = |e| annotate(path, e);
        // The syncer's handle, for a log forced to the disk only.
        let sync_file = options.durable.then(|| file.try_clone().ok()).flatten();
        let compression = match options.compression {
            LogCompression::None => ChunkCompression::None,
            LogCompression::Lz4 => ChunkCompression::Lz4,
        };
        // Chunks are built in memory and written whole (the file never holds a chunk whose
        // header is a placeholder), closed by the flush schedule only; a crash-cut log has no
        // data-end record to hold a data section CRC, the chunks' CRCs suffice.
        let writer = McapFile::new(
            file,
            "dronecine.flight",
            &format!("dronecine-runtime {}", env!("CARGO_PKG_VERSION")),
            compression,
        )
        .map_err(err)?;

        let gimbal = header.profile.camera.gimbal != dronecine_profile::Gimbal::None;
        let out = McapOut {
            writer: Some(writer),
            path: path.to_path_buf(),
            channels: Vec::new(),
        };
        let mut topics = FlightTopics::new(out, scene.actor_names, gimbal, options)?;
        let metadata = header_metadata(header).map_err(|e| annotate(path, io::Error::other(e)))?;
        // The header again, under a CRC: a reader whose metadata record is damaged (it has no
        // CRC) reads this one.
        let json = serde_json::to_vec(header).map_err(|e| annotate(path, io::Error::other(e)))?;
        let (writer, _) = topics.out_mut().mcap()?;
        writer
            .write_metadata(
                HEADER_METADATA,
                metadata.iter().map(|(k, v)| (k.as_str(), v.as_str())),
            )
            .map_err(err)?;
        writer
            .attach(
                0,
                0,
                &header.script_name,
                "text/plain",
                header.script_text.as_bytes(),
            )
            .map_err(err)?;
        writer
            .attach(0, 0, HEADER_ATTACHMENT, "application/json", &json)
            .map_err(err)?;

        let rate_hz = if header.rate_hz.is_finite() && header.rate_hz > 0.0 {
            header.rate_hz
        } else {
            100.0
        };
        // The transform topics, as compile's.
        topics.add_frames()?;
        // Every schema and channel again, in the first chunk, under its CRC.
        topics.out_mut().mcap()?.0.repeat_schemas_and_channels();
        topics.write_static(scene)?;
        let mut log = FlightLogWriter {
            topics,
            options,
            clock: ChunkClock::new(options.flush_period_s, rate_hz),
            key_frame_due: false,
            sync_file,
        };
        log.flush()?;
        Ok(log)
    }

    /// The MCAP writer and the log's path, or the error of a finished log.
    fn mcap(&mut self) -> io::Result<(&mut McapFile, &Path)> {
        self.topics.out_mut().mcap()
    }

    /// Closes the current chunk and flushes the file to the OS.
    fn flush(&mut self) -> io::Result<()> {
        let (writer, path) = self.mcap()?;
        writer.flush().map_err(|e| annotate(path, e))
    }

    /// Closes the current chunk at its flush time; it reaches the OS then, or, after
    /// [`FlightLogWriter::defer_hand_over`], with the chunks after it.
    fn close_chunk(&mut self) -> io::Result<()> {
        let (writer, path) = self.mcap()?;
        writer
            .close_and_hand_over_when_due()
            .map_err(|e| annotate(path, e))
    }

    /// Keeps closed chunks until they reach `bytes`, then hands them to the OS in one write
    /// (the default, 0: each chunk as it closes, every `flush_period_s` of flight). For a
    /// writer that keeps up with a flight faster than real time ([`LogThread`](super::LogThread)):
    /// the kernel's cost per byte falls with the write's size. What waits is what a crash of
    /// the process may lose, so the caller calls [`FlightLogWriter::hand_over`] whenever it
    /// has no tick waiting to be written.
    pub fn defer_hand_over(&mut self, bytes: usize) -> io::Result<()> {
        self.mcap()?.0.set_hand_over_bytes(bytes);
        Ok(())
    }

    /// Hands the closed chunks to the OS (see [`FlightLogWriter::defer_hand_over`]).
    pub fn hand_over(&mut self) -> io::Result<()> {
        let (writer, path) = self.mcap()?;
        writer.hand_over().map_err(|e| annotate(path, e))
    }

    /// Writes one tick on every per-tick topic, `/tf` when due, and closes the chunk when a
    /// flush is due. `tick.actors` and `tick.framing` index the scene's actors. Before the
    /// first tick, the mark that the controller starts there; before any other, the key frame
    /// given since the last tick, if any.
    pub fn write_tick(&mut self, tick: &TickRecord) -> io::Result<()> {
        self.key_frame_due = false;
        self.topics.write_tick(tick)?;
        if self.clock.step(tick.input.t_s) {
            self.close_chunk()?;
            self.key_frame_due = true;
        }
        Ok(())
    }

    /// A tick that records nothing (waiting for the motion capture before take-off, the
    /// drone's own take-off and landing) at `t_s`: the chunk closes when it would on a tick,
    /// so that what came before (the events) reaches the file within a second of flight.
    pub fn idle(&mut self, t_s: f64) -> io::Result<()> {
        if self.clock.step(t_s) {
            self.close_chunk()?;
        }
        Ok(())
    }

    /// Whether the last tick written closed a chunk: the next chunk then starts with the
    /// controller's state after that tick ([`FlightLogWriter::write_key_frame`]).
    pub fn wants_key_frame(&self) -> bool {
        self.key_frame_due
    }

    /// The controller's state after the last tick written (a key frame): written before the
    /// next tick, in the chunk that tick goes in, so that replay can resume there after a gap.
    pub fn write_key_frame(&mut self, state: &ControllerState) {
        self.topics.set_key_frame(state);
        self.key_frame_due = false;
    }

    /// The schedule of the chunks' closes, as it stands.
    pub(crate) fn chunk_clock(&self) -> ChunkClock {
        self.clock
    }

    /// Writes an event on `/events` (its time exact, as on `/servo/tick`).
    pub fn write_event(&mut self, event: &Event) -> io::Result<()> {
        self.topics.write_event(event)
    }

    /// Closes the last chunk, writes the summary and the closing magic, and (a
    /// [`LogOptions::durable`] log) `fsync`s the file.
    pub fn finish(mut self) -> io::Result<()> {
        let path = self.topics.out().path.clone();
        let mut writer = self.topics.out_mut().writer.take().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: log finished", path.display()))
        })?;
        writer.finish().map_err(|e| annotate(&path, e))?;
        let file = writer.into_file().map_err(|e| annotate(&path, e))?;
        if self.options.durable {
            file.sync_all().map_err(|e| annotate(&path, e))?;
        }
        Ok(())
    }

    /// A handle on the log's file for `sync_data` from another thread while this one writes
    /// ([`LogThread`](super::LogThread) syncs every few seconds, so that the final `fsync` of
    /// [`finish`](Self::finish) has only the tail left to write, and a power cut loses less).
    /// `None` for a log that is not [`LogOptions::durable`], or when the OS could not
    /// duplicate the handle.
    pub fn sync_handle(&self) -> Option<File> {
        self.sync_file.as_ref().and_then(|f| f.try_clone().ok())
    }

    /// The log's path.
    pub fn path(&self) -> &Path {
        &self.topics.out().path
    }
}

impl Drop for FlightLogWriter {
    fn drop(&mut self) {
        // Dropped without `finish()` (an error path): close the last chunk and the summary
        // so the file is whole; errors have nowhere to go.
        if let Some(mut writer) = self.topics.out_mut().writer.take() {
            let _ = writer.finish();
        }
    }
}

/// The metadata map: each field of the header under its name, its value the field's JSON.
fn header_metadata(header: &FlightHeader) -> Result<BTreeMap<String, String>, String> {
    let value = serde_json::to_value(header).map_err(|e| e.to_string())?;
    let serde_json::Value::Object(fields) = value else {
        return Err("the flight header is not a JSON object".into());
    };
    Ok(fields
        .into_iter()
        .map(|(k, v)| (k, v.to_string()))
        .collect())
}

/// The writer as a flight's sink on the loop's own thread: each tick written as it comes
/// (tests, tools). `shoot` writes through [`LogThread`](super::LogThread) instead, so that
/// formatting and the disk never sit on the control loop.
impl crate::record::FlightSink for FlightLogWriter {
    fn tick(&mut self, record: &TickRecord) -> io::Result<()> {
        self.write_tick(record)
    }
    fn event(&mut self, event: &Event) -> io::Result<()> {
        self.write_event(event)
    }
    fn idle(&mut self, t_s: f64) -> io::Result<()> {
        FlightLogWriter::idle(self, t_s)
    }
    fn wants_key_frame(&self) -> bool {
        FlightLogWriter::wants_key_frame(self)
    }
    fn key_frame(&mut self, state: &ControllerState) -> io::Result<()> {
        self.write_key_frame(state);
        Ok(())
    }
}
