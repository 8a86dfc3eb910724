//! [`FlightLogWriter`]: streams the flight's ticks and events into the MCAP log (contents and
//! crash behaviour in the module doc of `log`).
//!
//! Per tick the writer formats JSON into one reused buffer with the compiler's hand-written
//! JSON helpers and hands it to the MCAP writer, whose chunk buffer is also reused: once the
//! first chunk is closed, a tick allocates nothing (except for the message-index entries the
//! MCAP writer keeps per chunk, whose vectors it reuses too).

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use dronecine_compiler::camera::Lens;
use dronecine_compiler::output::foxglove::{self, Frames};
use dronecine_compiler::output::mcap::{
    actors_schema, advance, camera_schema, reference_schema, write_reference, ACTORS_SCHEMA,
    CAMERA_SCHEMA, REFERENCE_SCHEMA,
};
use dronecine_compiler::output::{json, ns_from_s};
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, McapError, WriteOptions, Writer};

use super::{exact, schema, topic, LogScene, HEADER_METADATA};
use crate::backend::{FlightState, MocapFrame};
use crate::control::{TickFault, TickInput, TickOutput};
use crate::frames::{ActorPose, Command};
use crate::record::{Event, FlightHeader, Phase, TickRecord};

/// Chunk compression of the flight log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogCompression {
    /// The default: the flight loop's budget is CPU time per tick (see `benches/log.rs`).
    None,
    /// LZ4 frames: about a third of the size, for about twice the CPU time per tick.
    Lz4,
}

/// Tuning of the flight log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogOptions {
    pub compression: LogCompression,
    /// Rate of `/tf` (Foxglove's 3D view).
    pub tf_hz: f64,
    /// Flight time between two chunk closes and flushes: what a crash may lose. Also closed
    /// every `rate_hz · flush_period_s` ticks, whatever the ticks' clocks say.
    pub flush_period_s: f64,
}

impl Default for LogOptions {
    fn default() -> Self {
        Self {
            compression: LogCompression::None,
            tf_hz: 30.0,
            flush_period_s: 1.0,
        }
    }
}

/// A channel and its message sequence counter.
#[derive(Clone, Copy)]
struct Channel {
    id: u16,
    sequence: u32,
}

impl Channel {
    fn header(&mut self, ns: u64) -> MessageHeader {
        self.sequence = self.sequence.wrapping_add(1);
        MessageHeader {
            channel_id: self.id,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        }
    }
}

struct Channels {
    reference: Channel,
    actors: Channel,
    camera: Channel,
    estimate: Channel,
    measurement: Channel,
    command: Channel,
    framing: Channel,
    events: Channel,
    servo_tick: Channel,
    tf: Channel,
    stage: Channel,
    drone: Channel,
    actor_scene: Channel,
    calibration: Channel,
}

/// Writes a flight log, tick by tick (see the `log` module doc).
///
/// ```no_run
/// # use dronecine_runtime::log::{FlightLogWriter, LogScene};
/// # fn demo(header: &dronecine_runtime::record::FlightHeader, scene: &LogScene,
/// #         ticks: &[dronecine_runtime::record::TickRecord]) -> std::io::Result<()> {
/// let mut log = FlightLogWriter::create("flights/orbit.mcap".as_ref(), header, scene)?;
/// for tick in ticks {
///     log.write_tick(tick)?; // on disk within a second of flight time
/// }
/// log.finish()?; // the summary and the closing magic
/// # Ok(()) }
/// ```
pub struct FlightLogWriter {
    /// `None` once finished.
    writer: Option<Writer<BufWriter<File>>>,
    path: PathBuf,
    channels: Channels,
    options: LogOptions,
    frames: Frames,
    /// `{"name":"Ann","position_m":` per actor (`/actors`).
    actor_prefixes: Vec<Vec<u8>>,
    /// `,"name":"Ann","screen":` per actor (`/framing`).
    framing_names: Vec<Vec<u8>>,
    /// Quoted frame names of the reference transform.
    world_frame: Vec<u8>,
    reference_frame: Vec<u8>,
    actor_names: Vec<String>,
    /// Heights last published on `/scene/actors`.
    heights_m: Vec<f64>,
    /// Reused message buffer.
    buf: Vec<u8>,
    next_tf_s: f64,
    next_flush_s: f64,
    ticks_since_flush: u64,
    flush_every_ticks: u64,
    /// Where `/tf` puts the drone on ticks without an estimate.
    last_estimate: Option<([f64; 3], f64)>,
}

fn mcap_err(path: &Path, e: McapError) -> io::Error {
    match e {
        McapError::Io(e) => annotate(path, e),
        other => io::Error::other(format!("cannot write {}: {other}", path.display())),
    }
}

fn annotate(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))
}

impl FlightLogWriter {
    /// Creates (truncating) the log at `path` and writes the header, the schemas and
    /// channels, the `dronecine.flight` metadata, the script attachment and the static scene,
    /// then flushes. The parent directory must exist (an error names the path otherwise).
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
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)
            .map_err(|e| annotate(path, e))?;
        let err = |e| mcap_err(path, e);
        let compression = match options.compression {
            LogCompression::None => None,
            LogCompression::Lz4 => Some(mcap::Compression::Lz4),
        };
        let mut writer = WriteOptions::new()
            .compression(compression)
            .profile("dronecine.flight")
            .library(format!("dronecine-runtime {}", env!("CARGO_PKG_VERSION")))
            // Chunks are built in memory and written whole: the file never holds a chunk
            // whose header is a placeholder.
            .disable_seeking(true)
            // Closed by the flush schedule only.
            .chunk_size(None)
            .compression_threads(0)
            .create(BufWriter::with_capacity(1 << 16, file))
            .map_err(err)?;

        let no_meta = BTreeMap::new();
        let mut channel = |schema_name: &str, schema: String, topic: &str| {
            let schema_id = writer.add_schema(schema_name, "jsonschema", schema.as_bytes())?;
            let id = writer.add_channel(schema_id, topic, "json", &no_meta)?;
            Ok::<_, McapError>(Channel { id, sequence: 0 })
        };
        let scene_schema = foxglove::scene_update_schema();
        let channels = Channels {
            reference: channel(REFERENCE_SCHEMA, reference_schema(), topic::REFERENCE)
                .map_err(err)?,
            actors: channel(ACTORS_SCHEMA, actors_schema(), topic::ACTORS).map_err(err)?,
            camera: channel(CAMERA_SCHEMA, camera_schema(), topic::CAMERA).map_err(err)?,
            estimate: channel(schema::ESTIMATE, schema::estimate(), topic::ESTIMATE)
                .map_err(err)?,
            measurement: channel(
                schema::MEASUREMENT,
                schema::measurement(),
                topic::MEASUREMENT,
            )
            .map_err(err)?,
            command: channel(schema::COMMAND, schema::command(), topic::COMMAND).map_err(err)?,
            framing: channel(schema::FRAMING, schema::framing(), topic::FRAMING).map_err(err)?,
            events: channel(schema::EVENT, schema::event(), topic::EVENTS).map_err(err)?,
            servo_tick: channel(schema::SERVO_TICK, schema::servo_tick(), topic::SERVO_TICK)
                .map_err(err)?,
            tf: channel(
                foxglove::FRAME_TRANSFORMS,
                foxglove::frame_transforms_schema(),
                topic::TF,
            )
            .map_err(err)?,
            stage: channel(
                foxglove::SCENE_UPDATE,
                scene_schema.clone(),
                topic::SCENE_STAGE,
            )
            .map_err(err)?,
            drone: channel(
                foxglove::SCENE_UPDATE,
                scene_schema.clone(),
                topic::SCENE_DRONE,
            )
            .map_err(err)?,
            actor_scene: channel(foxglove::SCENE_UPDATE, scene_schema, topic::SCENE_ACTORS)
                .map_err(err)?,
            calibration: channel(
                foxglove::CAMERA_CALIBRATION,
                foxglove::camera_calibration_schema(),
                topic::CAMERA_CALIBRATION,
            )
            .map_err(err)?,
        };

        writer
            .write_metadata(&Metadata {
                name: HEADER_METADATA.to_string(),
                metadata: header_metadata(header)
                    .map_err(|e| annotate(path, io::Error::other(e)))?,
            })
            .map_err(err)?;
        writer
            .attach(&Attachment {
                log_time: 0,
                create_time: 0,
                name: header.script_name.clone(),
                media_type: "text/plain".to_string(),
                data: header.script_text.as_bytes().into(),
            })
            .map_err(err)?;

        let quote = |s: &str| {
            let mut v = Vec::new();
            json::string(&mut v, s);
            v
        };
        let actor_prefixes = scene
            .actor_names
            .iter()
            .map(|name| {
                let mut p = b"{\"name\":".to_vec();
                json::string(&mut p, name);
                p.extend_from_slice(b",\"position_m\":");
                p
            })
            .collect();
        let framing_names = scene
            .actor_names
            .iter()
            .map(|name| {
                let mut p = b",\"name\":".to_vec();
                json::string(&mut p, name);
                p.extend_from_slice(b",\"screen\":");
                p
            })
            .collect();
        let rate_hz = if header.rate_hz.is_finite() && header.rate_hz > 0.0 {
            header.rate_hz
        } else {
            100.0
        };
        let flush_every_ticks = (rate_hz * options.flush_period_s).floor().max(1.0) as u64;
        let mut log = FlightLogWriter {
            writer: Some(writer),
            path: path.to_path_buf(),
            channels,
            options,
            frames: Frames::new(scene.actor_names),
            actor_prefixes,
            framing_names,
            world_frame: quote(foxglove::WORLD),
            reference_frame: quote("reference"),
            actor_names: scene.actor_names.to_vec(),
            heights_m: Vec::new(),
            buf: Vec::with_capacity(4096),
            next_tf_s: f64::NEG_INFINITY,
            next_flush_s: options.flush_period_s,
            ticks_since_flush: 0,
            flush_every_ticks,
            last_estimate: None,
        };
        log.write_static(&scene.lens, &scene.stage, scene.actor_heights_m)?;
        log.flush()?;
        Ok(log)
    }

    fn put(
        &mut self,
        channel: fn(&mut Channels) -> &mut Channel,
        ns: u64,
        data: &[u8],
    ) -> io::Result<()> {
        let header = channel(&mut self.channels).header(ns);
        let path = &self.path;
        let writer = self.writer.as_mut().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: log finished", path.display()))
        })?;
        writer
            .write_to_known_channel(&header, data)
            .map_err(|e| mcap_err(path, e))
    }

    /// Puts the reused buffer on a channel (the buffer is taken and given back).
    fn put_buf(&mut self, channel: fn(&mut Channels) -> &mut Channel, ns: u64) -> io::Result<()> {
        let buf = std::mem::take(&mut self.buf);
        let result = self.put(channel, ns, &buf);
        self.buf = buf;
        result
    }

    /// The topics published once, at time 0.
    fn write_static(
        &mut self,
        lens: &Lens,
        stage: &dronecine_grammar::script::Stage,
        heights_m: &[f64],
    ) -> io::Result<()> {
        let mut camera = b"{\"fov_x_rad\":".to_vec();
        json::f64(&mut camera, lens.fov_x_rad);
        camera.extend_from_slice(b",\"aspect\":");
        json::f64(&mut camera, lens.aspect);
        camera.push(b'}');
        self.put(|c| &mut c.camera, 0, &camera)?;
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

    /// Closes the current chunk and flushes the file to the OS.
    fn flush(&mut self) -> io::Result<()> {
        let path = &self.path;
        let writer = self.writer.as_mut().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: log finished", path.display()))
        })?;
        writer.flush().map_err(|e| mcap_err(path, e))?;
        self.ticks_since_flush = 0;
        Ok(())
    }

    /// Writes one tick on every per-tick topic, `/tf` when due, and closes the chunk when a
    /// flush is due. `tick.actors` and `tick.framing` index the scene's actors.
    pub fn write_tick(&mut self, tick: &TickRecord) -> io::Result<()> {
        let t_s = tick.input.t_s;
        let ns = ns_from_s(t_s);
        let output = tick.output.as_ref().ok();

        // /reference, exactly as compile.
        self.buf.clear();
        write_reference(&mut self.buf, tick.sample);
        self.put_buf(|c| &mut c.reference, ns)?;

        // /actors, the message compile writes.
        self.buf.clear();
        write_actors(&mut self.buf, t_s, &self.actor_prefixes, tick.actors);
        self.put_buf(|c| &mut c.actors, ns)?;

        if let Some(out) = output {
            let e = &out.estimate;
            self.buf.clear();
            self.buf.extend_from_slice(b"{\"t_s\":");
            json::f64(&mut self.buf, t_s);
            self.buf.extend_from_slice(b",\"position_m\":");
            json::vec3(&mut self.buf, &e.position_m);
            self.buf.extend_from_slice(b",\"velocity_mps\":");
            json::vec3(&mut self.buf, &e.velocity_mps);
            self.buf.extend_from_slice(b",\"heading_rad\":");
            json::f64(&mut self.buf, e.heading_rad);
            self.buf.push(b'}');
            self.put_buf(|c| &mut c.estimate, ns)?;
            self.last_estimate = Some((e.position_m, e.heading_rad));
        }

        if let Some(frame) = tick.mocap {
            self.buf.clear();
            write_measurement(&mut self.buf, frame);
            self.put_buf(|c| &mut c.measurement, ns)?;
        }

        // /command.
        {
            let c = &tick.command_sent;
            let failsafe = output.is_none_or(|o| !same_command(&o.command, c));
            let buf = &mut self.buf;
            buf.clear();
            buf.extend_from_slice(b"{\"t_s\":");
            json::f64(buf, t_s);
            buf.extend_from_slice(b",\"roll_rad\":");
            json::f64(buf, c.roll_rad);
            buf.extend_from_slice(b",\"pitch_rad\":");
            json::f64(buf, c.pitch_rad);
            buf.extend_from_slice(b",\"yaw_rate_radps\":");
            json::f64(buf, c.yaw_rate_radps);
            buf.extend_from_slice(b",\"vz_mps\":");
            json::f64(buf, c.vz_mps);
            buf.extend_from_slice(b",\"saturated\":");
            buf.extend_from_slice(bool_json(output.is_some_and(|o| o.saturated)));
            buf.extend_from_slice(b",\"failsafe\":");
            buf.extend_from_slice(bool_json(failsafe));
            buf.push(b'}');
            self.put_buf(|c| &mut c.command, ns)?;
        }

        if !tick.framing.is_empty() {
            self.buf.clear();
            write_framing(&mut self.buf, t_s, tick.shot, &self.framing_names, tick);
            self.put_buf(|c| &mut c.framing, ns)?;
        }

        self.buf.clear();
        write_servo_tick(&mut self.buf, tick);
        self.put_buf(|c| &mut c.servo_tick, ns)?;

        if t_s >= self.next_tf_s || !t_s.is_finite() {
            self.next_tf_s = advance(self.next_tf_s, t_s, self.options.tf_hz);
            self.write_tf(ns, tick)?;
        }

        self.ticks_since_flush += 1;
        if (t_s.is_finite() && t_s >= self.next_flush_s)
            || self.ticks_since_flush >= self.flush_every_ticks
        {
            if t_s.is_finite() {
                let period = self.options.flush_period_s;
                self.next_flush_s = (self.next_flush_s + period).max(t_s + period / 2.0);
                // A schedule far ahead of the clock (time jumped backward) restarts at t_s.
                if self.next_flush_s > t_s + period {
                    self.next_flush_s = t_s + period;
                }
            }
            self.flush()?;
        }
        Ok(())
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
        self.buf.clear();
        self.frames.message(
            &mut self.buf,
            ns,
            position_m,
            heading_rad,
            s.camera_pitch_rad,
            tick.actors.iter().map(|a| (a.position_m, a.facing_rad)),
        );
        // Append world→reference inside the transforms array (`…]}` → `…,{…}]}`).
        self.buf.truncate(self.buf.len() - 2);
        self.buf.push(b',');
        let mut stamp = [0u8; 48];
        let stamp = stamp_json(&mut stamp, ns);
        foxglove::transform(
            &mut self.buf,
            stamp,
            &self.world_frame,
            &self.reference_frame,
            s.position_m,
            foxglove::yaw(s.heading_rad),
        );
        self.buf.extend_from_slice(b"]}");
        self.put_buf(|c| &mut c.tf, ns)
    }

    /// Writes an event on `/events` (its time exact, as on `/servo/tick`).
    pub fn write_event(&mut self, event: &Event) -> io::Result<()> {
        let buf = &mut self.buf;
        buf.clear();
        buf.extend_from_slice(b"{\"t_s\":");
        exact::f64(buf, event.t_s);
        buf.extend_from_slice(b",\"level\":");
        json::string(buf, &event.level);
        buf.extend_from_slice(b",\"kind\":");
        json::string(buf, &event.kind);
        buf.extend_from_slice(b",\"message\":");
        json::string(buf, &event.message);
        buf.push(b'}');
        self.put_buf(|c| &mut c.events, ns_from_s(event.t_s))
    }

    /// Closes the last chunk and writes the summary and the closing magic.
    pub fn finish(mut self) -> io::Result<()> {
        let path = self.path.clone();
        let mut writer = self.writer.take().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: log finished", path.display()))
        })?;
        writer.finish().map_err(|e| mcap_err(&path, e))?;
        writer
            .into_inner()
            .into_inner()
            .map_err(|e| annotate(&path, e.into_error()))?
            .sync_all()
            .map_err(|e| annotate(&path, e))
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
            let _ = writer.into_inner().into_inner();
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

fn bool_json(b: bool) -> &'static [u8] {
    if b {
        b"true"
    } else {
        b"false"
    }
}

/// Bit-for-bit equal commands.
fn same_command(a: &Command, b: &Command) -> bool {
    a.roll_rad.to_bits() == b.roll_rad.to_bits()
        && a.pitch_rad.to_bits() == b.pitch_rad.to_bits()
        && a.yaw_rate_radps.to_bits() == b.yaw_rate_radps.to_bits()
        && a.vz_mps.to_bits() == b.vz_mps.to_bits()
}

/// `{"sec":…,"nsec":…}` into a stack buffer.
fn stamp_json(buf: &mut [u8; 48], ns: u64) -> &[u8] {
    let mut n = 0;
    let mut put = |bytes: &[u8]| {
        buf[n..n + bytes.len()].copy_from_slice(bytes);
        n += bytes.len();
    };
    let mut digits = itoa::Buffer::new();
    put(b"{\"sec\":");
    put(digits.format(ns / 1_000_000_000).as_bytes());
    put(b",\"nsec\":");
    put(digits.format(ns % 1_000_000_000).as_bytes());
    put(b"}");
    &buf[..n]
}

/// A `/actors` message, as compile writes it.
fn write_actors(buf: &mut Vec<u8>, t_s: f64, prefixes: &[Vec<u8>], actors: &[ActorPose]) {
    buf.extend_from_slice(b"{\"t_s\":");
    json::f64(buf, t_s);
    buf.extend_from_slice(b",\"actors\":[");
    for (i, (prefix, a)) in prefixes.iter().zip(actors).enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(prefix);
        json::vec3(buf, &a.position_m);
        buf.extend_from_slice(b",\"facing_rad\":");
        json::f64(buf, a.facing_rad);
        buf.extend_from_slice(b",\"height_m\":");
        json::f64(buf, a.height_m);
        buf.push(b'}');
    }
    buf.extend_from_slice(b"]}");
}

fn write_pose(buf: &mut Vec<u8>, pose: Option<&crate::backend::BodyPose>) {
    match pose {
        Some(p) => {
            buf.extend_from_slice(b"{\"position_m\":");
            json::vec3(buf, &p.position_m);
            buf.extend_from_slice(b",\"heading_rad\":");
            json::f64(buf, p.heading_rad);
            buf.push(b'}');
        }
        None => buf.extend_from_slice(b"null"),
    }
}

fn write_measurement(buf: &mut Vec<u8>, frame: &MocapFrame) {
    buf.extend_from_slice(b"{\"t_s\":");
    json::f64(buf, frame.t_s);
    buf.extend_from_slice(b",\"frame\":");
    json::u64(buf, frame.frame);
    buf.extend_from_slice(b",\"drone\":");
    write_pose(buf, frame.drone.as_ref());
    buf.extend_from_slice(b",\"actors\":[");
    for (i, a) in frame.actors.iter().enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        write_pose(buf, a.as_ref());
    }
    buf.extend_from_slice(b"]}");
}

fn write_screen(buf: &mut Vec<u8>, p: Option<[f64; 2]>) {
    match p {
        Some([x, y]) => {
            buf.push(b'[');
            json::f64(buf, x);
            buf.push(b',');
            json::f64(buf, y);
            buf.push(b']');
        }
        None => buf.extend_from_slice(b"null"),
    }
}

fn write_framing(
    buf: &mut Vec<u8>,
    t_s: f64,
    shot: Option<usize>,
    names: &[Vec<u8>],
    tick: &TickRecord,
) {
    buf.extend_from_slice(b"{\"t_s\":");
    json::f64(buf, t_s);
    buf.extend_from_slice(b",\"shot\":");
    write_shot(buf, shot);
    buf.extend_from_slice(b",\"actors\":[");
    for (i, f) in tick.framing.iter().enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(b"{\"actor\":");
        json::u64(buf, f.actor as u64);
        match names.get(f.actor) {
            Some(name) => buf.extend_from_slice(name),
            None => buf.extend_from_slice(b",\"name\":\"\",\"screen\":"),
        }
        write_screen(buf, f.screen);
        buf.extend_from_slice(b",\"requested\":");
        write_screen(buf, f.requested);
        buf.push(b'}');
    }
    buf.extend_from_slice(b"]}");
}

fn write_shot(buf: &mut Vec<u8>, shot: Option<usize>) {
    match shot {
        Some(s) => json::u64(buf, s as u64),
        None => buf.extend_from_slice(b"null"),
    }
}

fn phase_json(p: Phase) -> &'static [u8] {
    match p {
        Phase::TakeOff => b"\"TakeOff\"",
        Phase::Approach => b"\"Approach\"",
        Phase::Shots => b"\"Shots\"",
        Phase::Landing => b"\"Landing\"",
    }
}

fn state_json(s: FlightState) -> &'static [u8] {
    match s {
        FlightState::Landed => b"\"Landed\"",
        FlightState::TakingOff => b"\"TakingOff\"",
        FlightState::Flying => b"\"Flying\"",
        FlightState::Landing => b"\"Landing\"",
        FlightState::Emergency => b"\"Emergency\"",
    }
}

fn fault_json(f: TickFault) -> &'static [u8] {
    match f {
        TickFault::NotFinite => b"\"NotFinite\"",
        TickFault::TimeNotIncreasing => b"\"TimeNotIncreasing\"",
    }
}

fn write_command_exact(buf: &mut Vec<u8>, c: &Command) {
    buf.extend_from_slice(b"{\"roll_rad\":");
    exact::f64(buf, c.roll_rad);
    buf.extend_from_slice(b",\"pitch_rad\":");
    exact::f64(buf, c.pitch_rad);
    buf.extend_from_slice(b",\"yaw_rate_radps\":");
    exact::f64(buf, c.yaw_rate_radps);
    buf.extend_from_slice(b",\"vz_mps\":");
    exact::f64(buf, c.vz_mps);
    buf.push(b'}');
}

fn write_input_exact(buf: &mut Vec<u8>, input: &TickInput) {
    buf.extend_from_slice(b"{\"t_s\":");
    exact::f64(buf, input.t_s);
    buf.extend_from_slice(b",\"dt_s\":");
    exact::f64(buf, input.dt_s);
    buf.extend_from_slice(b",\"measurement\":");
    match &input.measurement {
        Some(m) => {
            buf.extend_from_slice(b"{\"position_m\":");
            exact::vec3(buf, &m.position_m);
            buf.extend_from_slice(b",\"heading_rad\":");
            exact::f64(buf, m.heading_rad);
            buf.push(b'}');
        }
        None => buf.extend_from_slice(b"null"),
    }
    let r = &input.reference;
    buf.extend_from_slice(b",\"reference\":{\"position_m\":");
    exact::vec3(buf, &r.position_m);
    buf.extend_from_slice(b",\"velocity_mps\":");
    exact::vec3(buf, &r.velocity_mps);
    buf.extend_from_slice(b",\"acceleration_mps2\":");
    exact::vec3(buf, &r.acceleration_mps2);
    buf.extend_from_slice(b",\"heading_rad\":");
    exact::f64(buf, r.heading_rad);
    buf.extend_from_slice(b",\"heading_rate_radps\":");
    exact::f64(buf, r.heading_rate_radps);
    buf.extend_from_slice(b"}}");
}

fn write_output_exact(buf: &mut Vec<u8>, out: &TickOutput) {
    buf.extend_from_slice(b"{\"command\":");
    write_command_exact(buf, &out.command);
    let e = &out.estimate;
    buf.extend_from_slice(b",\"estimate\":{\"position_m\":");
    exact::vec3(buf, &e.position_m);
    buf.extend_from_slice(b",\"velocity_mps\":");
    exact::vec3(buf, &e.velocity_mps);
    buf.extend_from_slice(b",\"heading_rad\":");
    exact::f64(buf, e.heading_rad);
    buf.extend_from_slice(b"},\"saturated\":");
    buf.extend_from_slice(bool_json(out.saturated));
    buf.push(b'}');
}

/// A `/servo/tick` message: everything replay needs, floats exact.
fn write_servo_tick(buf: &mut Vec<u8>, tick: &TickRecord) {
    buf.extend_from_slice(b"{\"phase\":");
    buf.extend_from_slice(phase_json(tick.phase));
    buf.extend_from_slice(b",\"shot\":");
    write_shot(buf, tick.shot);
    buf.extend_from_slice(b",\"input\":");
    write_input_exact(buf, &tick.input);
    match &tick.output {
        Ok(out) => {
            buf.extend_from_slice(b",\"output\":");
            write_output_exact(buf, out);
            buf.extend_from_slice(b",\"fault\":null");
        }
        Err(fault) => {
            buf.extend_from_slice(b",\"output\":null,\"fault\":");
            buf.extend_from_slice(fault_json(*fault));
        }
    }
    buf.extend_from_slice(b",\"command_sent\":");
    write_command_exact(buf, &tick.command_sent);
    buf.extend_from_slice(b",\"drone_state\":");
    buf.extend_from_slice(state_json(tick.drone_state));
    buf.push(b'}');
}
