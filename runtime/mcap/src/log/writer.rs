//! [`FlightLogWriter`]: streams the flight's ticks and events into the MCAP log (contents and
//! crash behaviour in the module doc of `log`).
//!
//! Per tick the writer encodes `/servo/tick` (`cdr.rs`) and, at the plot and `/tf` rates,
//! the plot topics (`plots.rs`, and the compiler's writers for `/reference`, `/actors` and
//! `/tf`), all CDR, each straight into the MCAP writer's in-memory chunk (`/tf` through one
//! reused buffer: a frame's message exists only once it is known to have moved), which is
//! reused from chunk to chunk ([`McapFile`],
//! written for this path: each chunk hashed once and written with one system call); chunks
//! carry no message indexes (readers scan the ≤ 1 s chunks). Nothing on the per-tick path
//! allocates. Only `/events` is JSON.
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

use crate::output::foxglove::{self, FrameTopic};
use crate::output::mcap::{
    actors_schema, advance, camera_message, camera_schema, frame_topics_with, reference_schema,
    write_actors, write_reference, Channel, Encoding, ACTORS_SCHEMA, CAMERA_SCHEMA,
    REFERENCE_SCHEMA,
};
use crate::output::{json, ns_from_s};
use dronecine_compiler::camera::Lens;

use super::mcap_file::{ChunkCompression, McapFile};
use super::plots::{self, same_command};
use super::{cdr, exact, key_frame, schema, topic, LogScene, HEADER_ATTACHMENT, HEADER_METADATA};
use crate::record::{Event, FlightHeader, TickRecord};
use dronecine_servo::control::ControllerState;

/// The frame of the reference pose on `/tf/reference`.
const REFERENCE_FRAME: &str = "reference";

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

/// A channel and its message sequence counter.
struct Channels {
    reference: Channel,
    actors: Channel,
    camera: Channel,
    estimate: Channel,
    measurement: Channel,
    command: Channel,
    framing: Channel,
    /// `/gimbal`, only for a profile with a gimbal.
    gimbal: Option<Channel>,
    events: Channel,
    servo_tick: Channel,
    /// `/servo/state`: the key frames.
    key_frame: Channel,
    /// `/tf/drone`, `/tf/camera`, `/tf/actor/NAME`…, `/tf/reference`: one per frame in
    /// `FlightLogWriter::frames`' order.
    tf: Vec<Channel>,
    stage: Channel,
    drone: Channel,
    actor_scene: Channel,
    calibration: Channel,
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
    /// `None` once finished.
    writer: Option<McapFile>,
    path: PathBuf,
    channels: Channels,
    options: LogOptions,
    /// The transform topics, as compile's: the drone (at its estimate), the camera, each
    /// actor, and the reference; each published when it changes, at most at `tf_hz`.
    frames: Vec<FrameTopic>,
    /// Time of the last `/tf` tick.
    last_tf_ns: Option<u64>,
    actor_names: Vec<String>,
    /// Heights last published on `/scene/actors`.
    heights_m: Vec<f64>,
    /// The reused buffer of `/tf` messages ([`FrameTopic::message`] fills it).
    buf: Vec<u8>,
    next_tf_s: f64,
    /// When the plot topics are next due (`plot_hz`; `/measurement` at `measurement_hz`):
    /// `/reference` with `/actors`, `/estimate`, `/measurement`, `/command`, `/framing`.
    next_reference_s: f64,
    next_estimate_s: f64,
    next_measurement_s: f64,
    next_command_s: f64,
    next_framing_s: f64,
    /// The last `/command` written had its `failsafe` flag set.
    command_failsafe: bool,
    clock: ChunkClock,
    /// A tick was written (the first one follows the mark that the controller starts).
    started: bool,
    /// The last tick closed a chunk: the next chunk starts with a key frame, which
    /// [`FlightLogWriter::write_key_frame`] gives.
    key_frame_due: bool,
    /// The key frame given since the last tick, written before the next tick.
    key_frame: Option<ControllerState>,
    /// Where `/tf` puts the drone on ticks without an estimate.
    last_estimate: Option<([f64; 3], f64)>,
    /// A second handle on the file, for syncing it from another thread (a durable log only).
    sync_file: Option<File>,
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

/// Adds the log's schemas and channels but `/tf`'s: the per-tick topics in CDR with ros2msg
/// schemas, events and the static ones JSON; `/servo/tick` first (its schema and channel ids
/// are 1), `/gimbal` (for a drone with a gimbal) just before `/servo/state`, which is last.
fn add_channels(writer: &mut McapFile, gimbal: bool) -> io::Result<Channels> {
    let mut channel = |schema_name: &str, schema: &str, topic: &str, enc: Encoding| {
        let schema_id = writer.add_schema(schema_name, enc.schema(), schema.as_bytes())?;
        let id = writer.add_channel(schema_id, topic, enc.message())?;
        Ok::<_, io::Error>(Channel::new(id))
    };
    let (c, j) = (Encoding::Cdr, Encoding::Json);
    let servo_tick = channel(cdr::SCHEMA_NAME, cdr::SCHEMA, topic::SERVO_TICK, c)?;
    let scene_schema = foxglove::scene_update_schema();
    Ok(Channels {
        reference: channel(REFERENCE_SCHEMA, &reference_schema(), topic::REFERENCE, c)?,
        actors: channel(ACTORS_SCHEMA, &actors_schema(), topic::ACTORS, c)?,
        camera: channel(CAMERA_SCHEMA, &camera_schema(), topic::CAMERA, j)?,
        estimate: channel(
            plots::ESTIMATE,
            &plots::estimate_schema(),
            topic::ESTIMATE,
            c,
        )?,
        measurement: channel(
            plots::MEASUREMENT,
            &plots::measurement_schema(),
            topic::MEASUREMENT,
            c,
        )?,
        command: channel(plots::COMMAND, &plots::command_schema(), topic::COMMAND, c)?,
        framing: channel(plots::FRAMING, &plots::framing_schema(), topic::FRAMING, c)?,
        events: channel(schema::EVENT, &schema::event(), topic::EVENTS, j)?,
        servo_tick,
        tf: Vec::new(),
        stage: channel(foxglove::SCENE_UPDATE, &scene_schema, topic::SCENE_STAGE, j)?,
        drone: channel(foxglove::SCENE_UPDATE, &scene_schema, topic::SCENE_DRONE, j)?,
        actor_scene: channel(
            foxglove::SCENE_UPDATE,
            &scene_schema,
            topic::SCENE_ACTORS,
            j,
        )?,
        calibration: channel(
            foxglove::CAMERA_CALIBRATION,
            &foxglove::camera_calibration_schema(),
            topic::CAMERA_CALIBRATION,
            j,
        )?,
        gimbal: if gimbal {
            Some(channel(
                plots::GIMBAL,
                &plots::gimbal_schema(),
                topic::GIMBAL,
                c,
            )?)
        } else {
            None
        },
        key_frame: channel(
            key_frame::SCHEMA_NAME,
            key_frame::SCHEMA,
            topic::SERVO_STATE,
            c,
        )?,
    })
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
        let mut writer = McapFile::new(
            file,
            "dronecine.flight",
            &format!("dronecine-runtime {}", env!("CARGO_PKG_VERSION")),
            compression,
        )
        .map_err(err)?;

        let gimbal = header.profile.camera.gimbal != dronecine_profile::Gimbal::None;
        let channels = add_channels(&mut writer, gimbal).map_err(err)?;

        let metadata = header_metadata(header).map_err(|e| annotate(path, io::Error::other(e)))?;
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
        // The header again, under a CRC: a reader whose metadata record is damaged (it has no
        // CRC) reads this one.
        let json = serde_json::to_vec(header).map_err(|e| annotate(path, io::Error::other(e)))?;
        writer
            .attach(0, 0, HEADER_ATTACHMENT, "application/json", &json)
            .map_err(err)?;

        let rate_hz = if header.rate_hz.is_finite() && header.rate_hz > 0.0 {
            header.rate_hz
        } else {
            100.0
        };
        let mut channels = channels;
        // The transform topics, as compile's.
        let tf_schema = writer
            .add_schema(
                foxglove::FRAME_TRANSFORMS,
                Encoding::Cdr.schema(),
                foxglove::frame_transforms_schema().as_bytes(),
            )
            .map_err(err)?;
        let (frames, tf) = frame_topics_with(
            scene.actor_names,
            &[(foxglove::WORLD, REFERENCE_FRAME)],
            |topic| writer.add_channel(tf_schema, topic, Encoding::Cdr.message()),
        )
        .map_err(err)?;
        channels.tf = tf;
        // Every schema and channel again, in the first chunk, under its CRC.
        writer.repeat_schemas_and_channels();
        let mut log = FlightLogWriter {
            writer: Some(writer),
            path: path.to_path_buf(),
            channels,
            options,
            frames,
            last_tf_ns: None,
            actor_names: scene.actor_names.to_vec(),
            heights_m: Vec::new(),
            buf: Vec::with_capacity(4096),
            next_tf_s: f64::NEG_INFINITY,
            next_reference_s: f64::NEG_INFINITY,
            next_estimate_s: f64::NEG_INFINITY,
            next_measurement_s: f64::NEG_INFINITY,
            next_command_s: f64::NEG_INFINITY,
            next_framing_s: f64::NEG_INFINITY,
            command_failsafe: false,
            clock: ChunkClock::new(options.flush_period_s, rate_hz),
            started: false,
            key_frame_due: false,
            key_frame: None,
            last_estimate: None,
            sync_file,
        };
        log.write_static(&scene.lens, &scene.stage, scene.actor_heights_m)?;
        log.flush()?;
        Ok(log)
    }

    /// Puts a message already encoded on a channel.
    fn put(
        &mut self,
        channel: fn(&mut Channels) -> &mut Channel,
        ns: u64,
        data: &[u8],
    ) -> io::Result<()> {
        let channel = channel(&mut self.channels);
        put_with(&mut self.writer, &self.path, channel, ns, |b| {
            b.extend_from_slice(data)
        })
    }

    /// The topics published once, at time 0.
    fn write_static(
        &mut self,
        lens: &Lens,
        stage: &dronecine_grammar::script::Stage,
        heights_m: &[f64],
    ) -> io::Result<()> {
        self.put(|c| &mut c.camera, 0, &camera_message(lens))?;
        self.put(|c| &mut c.stage, 0, &foxglove::stage_scene(0, stage))?;
        self.put(|c| &mut c.drone, 0, &foxglove::drone_scene(0))?;
        self.put(
            |c| &mut c.calibration,
            0,
            &foxglove::camera_calibration(0, lens),
        )?;
        let mut heights = heights_m.to_vec();
        heights.resize(self.actor_names.len(), 1.7);
        self.write_actor_scene(0, heights)
    }

    fn write_actor_scene(&mut self, ns: u64, heights_m: Vec<f64>) -> io::Result<()> {
        let scene = foxglove::actors_scene(ns, &self.actor_names, &heights_m);
        self.heights_m = heights_m;
        self.put(|c| &mut c.actor_scene, ns, &scene)
    }

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
        let t_s = tick.input.t_s;
        let ns = ns_from_s(t_s);
        let output = tick.output.as_ref().ok();
        if !self.started {
            self.started = true;
            // No state before the first tick: the controller starts there.
            self.key_frame = None;
            let (w, path, channel) = (&mut self.writer, &self.path, &mut self.channels.key_frame);
            put_with(w, path, channel, ns, |b| key_frame::encode(b, t_s, None))?;
        } else if let Some(state) = self.key_frame.take() {
            let (w, path, channel) = (&mut self.writer, &self.path, &mut self.channels.key_frame);
            put_with(w, path, channel, ns, |b| {
                key_frame::encode(b, t_s, Some(&state))
            })?;
        }
        self.key_frame_due = false;

        // The plot topics at `plot_hz` (each on the first tick that has one when due); every
        // tick's exact values are on /servo/tick.
        let hz = self.options.plot_hz;
        let due = |next_s: f64| t_s >= next_s || !t_s.is_finite();

        // /reference and /actors, exactly as compile writes them.
        if due(self.next_reference_s) {
            self.next_reference_s = advance(self.next_reference_s, t_s, hz);
            let (w, path, channels) = (&mut self.writer, &self.path, &mut self.channels);
            put_with(w, path, &mut channels.reference, ns, |b| {
                write_reference(b, tick.sample)
            })?;
            put_with(w, path, &mut channels.actors, ns, |b| {
                write_actors(b, t_s, &self.actor_names, tick.actors)
            })?;
        }
        if let Some(out) = output {
            if due(self.next_estimate_s) {
                self.next_estimate_s = advance(self.next_estimate_s, t_s, hz);
                let (w, path, channel) =
                    (&mut self.writer, &self.path, &mut self.channels.estimate);
                put_with(w, path, channel, ns, |b| {
                    plots::estimate(b, t_s, &out.estimate)
                })?;
            }
            self.last_estimate = Some((out.estimate.position_m, out.estimate.heading_rad));
        }

        if let Some(frame) = tick.mocap {
            if due(self.next_measurement_s) {
                self.next_measurement_s =
                    advance(self.next_measurement_s, t_s, self.options.measurement_hz);
                let (w, path) = (&mut self.writer, &self.path);
                let channel = &mut self.channels.measurement;
                put_with(w, path, channel, ns, |b| plots::measurement(b, frame))?;
            }
        }

        let failsafe = output.is_none_or(|o| !same_command(&o.command, &tick.command_sent));
        if due(self.next_command_s) || failsafe || self.command_failsafe {
            self.next_command_s = advance(self.next_command_s, t_s, hz);
            self.command_failsafe = failsafe;
            let (w, path, channel) = (&mut self.writer, &self.path, &mut self.channels.command);
            put_with(w, path, channel, ns, |b| {
                plots::command(b, t_s, output, &tick.command_sent, failsafe)
            })?;
        }

        if !tick.framing.is_empty() && due(self.next_framing_s) {
            self.next_framing_s = advance(self.next_framing_s, t_s, hz);
            let (w, path, channel) = (&mut self.writer, &self.path, &mut self.channels.framing);
            put_with(w, path, channel, ns, |b| {
                plots::framing(b, t_s, tick.shot, &self.actor_names, tick.framing)
            })?;
        }

        if let (Some(g), Some(channel)) = (&tick.gimbal, &mut self.channels.gimbal) {
            put_with(&mut self.writer, &self.path, channel, ns, |b| {
                plots::gimbal(b, t_s, g)
            })?;
        }

        let (w, path, channel) = (&mut self.writer, &self.path, &mut self.channels.servo_tick);
        put_with(w, path, channel, ns, |b| cdr::encode(b, tick))?;

        if t_s >= self.next_tf_s || !t_s.is_finite() {
            self.next_tf_s = advance(self.next_tf_s, t_s, self.options.tf_hz);
            self.write_tf(ns, tick)?;
        }

        if self.clock.step(t_s) {
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
        self.key_frame = Some(*state);
        self.key_frame_due = false;
    }

    /// The schedule of the chunks' closes, as it stands.
    pub(crate) fn chunk_clock(&self) -> ChunkClock {
        self.clock
    }

    /// `/tf`: the drone at its estimate, the camera, the actors and the reference; and
    /// `/scene/actors` again when an actor's height changed.
    fn write_tf(&mut self, ns: u64, tick: &TickRecord) -> io::Result<()> {
        if tick.actors.len() == self.heights_m.len()
            && tick
                .actors
                .iter()
                .zip(&self.heights_m)
                .any(|(a, &h)| (a.height_m - h).abs() > 1e-3)
        {
            let heights = tick.actors.iter().map(|a| a.height_m).collect();
            self.write_actor_scene(ns, heights)?;
        }
        let s = tick.sample;
        let (position_m, heading_rad) = self.last_estimate.unwrap_or((s.position_m, s.heading_rad));
        let prev_ns = self.last_tf_ns.replace(ns);
        let n_actors = tick.actors.len().min(self.frames.len().saturating_sub(3));
        let poses = [
            (position_m, foxglove::yaw(heading_rad)),
            ([0.0; 3], foxglove::camera_in_drone(s.camera_pitch_rad)),
        ]
        .into_iter()
        .chain(
            tick.actors[..n_actors]
                .iter()
                .map(|a| (a.position_m, foxglove::yaw(a.facing_rad))),
        )
        .enumerate()
        .chain(std::iter::once((
            self.frames.len() - 1,
            (s.position_m, foxglove::yaw(s.heading_rad)),
        )));
        for (i, (t, q)) in poses {
            if self.frames[i].message(&mut self.buf, prev_ns, ns, t, q) {
                let (w, path, buf) = (&mut self.writer, &self.path, &self.buf);
                put_with(w, path, &mut self.channels.tf[i], ns, |b| {
                    b.extend_from_slice(buf)
                })?;
            }
        }
        Ok(())
    }

    /// Writes an event on `/events` (its time exact, as on `/servo/tick`).
    pub fn write_event(&mut self, event: &Event) -> io::Result<()> {
        let channel = &mut self.channels.events;
        put_with(
            &mut self.writer,
            &self.path,
            channel,
            ns_from_s(event.t_s),
            |buf| {
                buf.extend_from_slice(b"{\"t_s\":");
                exact::f64(buf, event.t_s);
                buf.extend_from_slice(b",\"level\":");
                json::string(buf, &event.level);
                buf.extend_from_slice(b",\"kind\":");
                json::string(buf, &event.kind);
                buf.extend_from_slice(b",\"message\":");
                json::string(buf, &event.message);
                if let Some(line) = event.line {
                    buf.extend_from_slice(b",\"line\":");
                    json::u64(buf, line as u64);
                }
                if let Some(help) = &event.help {
                    buf.extend_from_slice(b",\"help\":");
                    json::string(buf, help);
                }
                buf.push(b'}');
            },
        )
    }

    /// Closes the last chunk, writes the summary and the closing magic, and (a
    /// [`LogOptions::durable`] log) `fsync`s the file.
    pub fn finish(mut self) -> io::Result<()> {
        let path = self.path.clone();
        let mut writer = self.writer.take().ok_or_else(|| {
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
        &self.path
    }
}

impl Drop for FlightLogWriter {
    fn drop(&mut self) {
        // Dropped without `finish()` (an error path): close the last chunk and the summary
        // so the file is whole; errors have nowhere to go.
        if let Some(mut writer) = self.writer.take() {
            let _ = writer.finish();
        }
    }
}

/// Puts a message on a channel, encoded by `encode` straight into the open chunk (a free
/// function, so that `encode` may borrow the writer's other fields).
fn put_with(
    writer: &mut Option<McapFile>,
    path: &Path,
    channel: &mut Channel,
    ns: u64,
    encode: impl FnOnce(&mut Vec<u8>),
) -> io::Result<()> {
    let header = channel.header(ns);
    let writer = writer.as_mut().ok_or_else(|| {
        io::Error::other(format!("cannot write {}: log finished", path.display()))
    })?;
    writer
        .write_message_with(&header, encode)
        .map_err(|e| annotate(path, e))
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
