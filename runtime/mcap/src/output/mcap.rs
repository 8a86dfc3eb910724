//! The MCAP writer: the reference and the actors at the full rate, the camera, Foxglove's
//! 3D scene (decimated), a metadata record and the script as an attachment.
//!
//! Channels (`log_time = publish_time = t_s` in ns). The per-sample topics are CDR with
//! `ros2msg` schemas (every float exact, 8 bytes: smaller than its text and nothing to
//! format; readers: [`decode_reference`], [`decode_actors`],
//! [`foxglove::decode_frame_transforms`]); those written once are JSON with JSON schemas.
//!
//! | topic | schema | rate |
//! |---|---|---|
//! | `/reference` | `dronecine/msg/Reference` (CDR) | every sample |
//! | `/actors` | `dronecine/msg/Actors` (CDR) | every sample |
//! | `/camera` | `dronecine.Camera` | once, at the first sample |
//! | `/tf/drone`, `/tf/camera`, `/tf/actor/NAME` | `foxglove_msgs/msg/FrameTransforms` (CDR) | when it changes, at most [`McapOptions::foxglove_hz`] |
//! | `/scene/stage`, `/scene/drone` | `foxglove.SceneUpdate` | once |
//! | `/scene/actors` | `foxglove.SceneUpdate` | once, again when a height changes |
//! | `/scene/path` | `foxglove.SceneUpdate` | once, written by `finish()` |
//! | `/camera_calibration` | `foxglove.CameraCalibration` | once |
//!
//! The numbers of `/camera` are quantised to 1e-6 (six decimals, rounded half away from
//! zero, trailing zeros trimmed); Foxglove's scene to the millimetre, the transforms to the
//! millimetre and quaternion components to 1e-6; the CSV, `/reference` and `/actors` keep
//! the exact values.
//!
//! Each frame's transform has its own topic, published at the first sample and afterwards
//! at the `/tf` ticks ([`McapOptions::foxglove_hz`]) where it changed (see
//! [`foxglove::FrameTopic`]): a camera without gimbal is published once, an actor while it
//! walks. Foxglove's 3D panel subscribes to every `FrameTransforms` topic and keeps each
//! frame's latest transform, so a transform published once at the start stays valid until
//! the frame's next one; the topic's latest message being the frame's current transform,
//! seeking (which back-fills the latest message of each topic) shows the frame where it is.
//!
//! Metadata record `dronecine`: `script_name`, `source_sha256` (of the script's bytes),
//! `profile`, `compiler_version`, `rate_hz`. Attachment: the script text (`text/plain`,
//! named after the script file).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::Path;

use ::mcap::records::{MessageHeader, Metadata};
use ::mcap::{Attachment, McapError, WriteOptions, Writer};
use serde_json::json;
use sha2::{Digest, Sha256};

use super::cdr::{self, Cdr, CdrReader};
use super::foxglove::{self, FrameTopic};
use super::{annotate, json, ns_from_s, AtomicFile, RunInfo};
use dronecine_compiler::reference::{ActorPose, Sample};

/// Chunk compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    None,
    /// LZ4 frames, default (fast) level.
    Lz4,
    /// Zstandard level 1: about as fast as LZ4 on these files, and smaller; higher levels cost
    /// more time than they save size.
    Zstd,
}

/// Tuning of the MCAP writer.
///
/// The volume is every sample's exact `/reference` and `/actors` at the full rate, and
/// compressing it costs more CPU time than writing it (`benches/output.rs` measures both).
/// Hence two presets: [`Default`] (no compression: the compile's one-second budget) and
/// [`McapOptions::compact`] (Zstandard: a quarter of the size, for flight logs written at
/// flight pace, where the CPU time per sample does not matter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McapOptions {
    pub compression: Compression,
    /// Rate of the `/tf` topic (the 3D view's motion); the samples' rate if lower.
    pub foxglove_hz: f64,
    /// Rate of the points kept for the path's line strip (plus every shot boundary and the
    /// last sample).
    pub path_hz: f64,
}

impl Default for McapOptions {
    fn default() -> Self {
        Self {
            compression: Compression::None,
            foxglove_hz: 30.0,
            path_hz: 10.0,
        }
    }
}

impl McapOptions {
    /// The default rates with Zstandard chunks.
    pub fn compact() -> Self {
        Self {
            compression: Compression::Zstd,
            ..Self::default()
        }
    }
}

/// The `ros2msg` schema of `/reference` messages (CDR: [`reference_schema`]).
pub const REFERENCE_SCHEMA: &str = "dronecine/msg/Reference";
/// The `ros2msg` schema of `/actors` messages (CDR: [`actors_schema`]).
pub const ACTORS_SCHEMA: &str = "dronecine/msg/Actors";
/// The JSON schema of `/camera` messages.
pub const CAMERA_SCHEMA: &str = "dronecine.Camera";

/// The numbers of `/camera` are quantised to 1e-6 ([`json::micro`]).
const QUANTISED: &str = "; quantised to 1e-6";

fn number_schema(description: &str) -> serde_json::Value {
    json!({ "type": "number", "description": format!("{description}{QUANTISED}") })
}

/// The `ros2msg` definition of `/reference`: every float exact (CDR keeps the bits).
pub fn reference_schema() -> String {
    "\
# One sample of the 6D camera reference (SI units, world frame, z up)
float64 t_s                      # time on the script's clock
float64[3] position_m            # camera position
float64[3] velocity_mps
float64[3] acceleration_mps2
float64 heading_rad              # counter-clockwise from +x, in (-pi, pi]
float64 heading_rate_radps
float64 camera_pitch_rad         # up positive
uint32 shot                      # index of the shot in the timeline
"
    .to_string()
}

/// The `ros2msg` definition of `/actors`.
pub fn actors_schema() -> String {
    format!(
        "\
# The actors at one instant, in the script's order
float64 t_s                      # time on the script's clock
dronecine/NamedActor[] actors
{}
MSG: dronecine/NamedActor
string name
float64[3] position_m            # feet on the floor
float64 facing_rad               # counter-clockwise from +x, in (-pi, pi]
float64 height_m
",
        cdr::SEPARATOR
    )
}

pub fn camera_schema() -> String {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": CAMERA_SCHEMA,
        "description": "The pinhole lens",
        "type": "object",
        "properties": {
            "fov_x_rad": number_schema("Horizontal field of view (rad)"),
            "aspect": number_schema("Frame width over height")
        },
        "required": ["fov_x_rad", "aspect"]
    })
    .to_string()
}

/// Converts an MCAP error, naming the destination.
fn mcap_err(dest: &Path, e: McapError) -> io::Error {
    match e {
        McapError::Io(e) => annotate(dest, e),
        other => io::Error::other(format!("cannot write {}: {other}", dest.display())),
    }
}

/// How a channel's messages are encoded: CDR with a `ros2msg` schema (the topics written
/// every sample or tick) or JSON with a JSON schema (those written once, and events).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    Cdr,
    Json,
}

impl Encoding {
    /// The MCAP schema encoding.
    pub fn schema(self) -> &'static str {
        match self {
            Encoding::Cdr => cdr::SCHEMA_ENCODING,
            Encoding::Json => "jsonschema",
        }
    }

    /// The MCAP message encoding.
    pub fn message(self) -> &'static str {
        match self {
            Encoding::Cdr => cdr::MESSAGE_ENCODING,
            Encoding::Json => "json",
        }
    }
}

/// A channel and its message sequence counter.
/// An MCAP channel being written: its id and the sequence number of its last message
/// (shared with the runtime's flight log).
#[derive(Clone, Copy)]
pub struct Channel {
    id: u16,
    sequence: u32,
}

impl Channel {
    pub fn new(id: u16) -> Channel {
        Channel { id, sequence: 0 }
    }

    pub fn id(&self) -> u16 {
        self.id
    }

    /// The header of the channel's next message, logged and published at `ns`.
    pub fn header(&mut self, ns: u64) -> MessageHeader {
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
    /// One per frame, in the order of `McapWriter::frames`.
    tf: Vec<Channel>,
    stage: Channel,
    drone: Channel,
    actor_scene: Channel,
    path: Channel,
    calibration: Channel,
}

/// Streams a compiled reference into an MCAP file (see the module doc for its contents).
///
/// ```no_run
/// # use dronecine_mcap::output::{McapWriter, RunInfo};
/// # fn demo(info: &RunInfo, samples: &[dronecine_compiler::reference::Sample],
/// #         actors: &[Vec<dronecine_compiler::reference::ActorPose>]) -> std::io::Result<()> {
/// let mut w = McapWriter::create("out.mcap".as_ref(), info)?;
/// for (s, a) in samples.iter().zip(actors) {
///     w.write(s, a)?;
/// }
/// w.finish()?; // out.mcap appears only now
/// # Ok(()) }
/// ```
pub struct McapWriter {
    /// `None` once finished (or failed to finish).
    writer: Option<Writer<BufWriter<File>>>,
    file: AtomicFile,
    channels: Channels,
    info: OwnedInfo,
    /// The drone, the camera, then each actor.
    frames: Vec<FrameTopic>,
    /// Time of the last `/tf` tick.
    last_tick_ns: Option<u64>,
    options: McapOptions,
    /// Reusable message buffer.
    buf: Vec<u8>,
    /// Time of the first sample (the static topics' time), once a sample was written.
    first_ns: Option<u64>,
    next_tf_s: f64,
    next_path_s: f64,
    /// Heights last published on `/scene/actors`.
    heights_m: Vec<f64>,
    /// Decimated path, one segment per run of samples with the same shot.
    path: Vec<(usize, Vec<[f64; 3]>)>,
    /// Last sample written and whether it is already in `path`.
    last: Option<(Sample, bool)>,
}

/// What `finish` and the lazy static topics need from the `RunInfo`.
struct OwnedInfo {
    lens: dronecine_compiler::camera::Lens,
    stage: dronecine_grammar::script::Stage,
    actor_names: Vec<String>,
}

impl McapWriter {
    /// Creates the temporary file next to `path` and writes the header, schemas, channels,
    /// the metadata record and the script attachment.
    pub fn create(path: &Path, info: &RunInfo) -> io::Result<Self> {
        Self::create_with(path, info, McapOptions::default())
    }

    pub fn create_with(path: &Path, info: &RunInfo, options: McapOptions) -> io::Result<Self> {
        let (file, handle) = AtomicFile::create(path)?;
        let dest = file.dest().to_path_buf();
        let err = |e| mcap_err(&dest, e);
        let compression = match options.compression {
            Compression::None => None,
            Compression::Lz4 => Some(::mcap::Compression::Lz4),
            Compression::Zstd => Some(::mcap::Compression::Zstd),
        };
        let mut writer = WriteOptions::new()
            .compression(compression)
            .library(format!("dronecine-compiler {}", env!("CARGO_PKG_VERSION")))
            // One core: no zstd worker threads.
            .compression_threads(0)
            // Zstandard level 1 (LZ4 ignores levels below 3).
            .compression_level(1)
            .create(BufWriter::with_capacity(1 << 16, handle))
            .map_err(err)?;

        let no_meta = BTreeMap::new();
        let mut channel = |schema_name: &str, schema: String, topic: &str, enc: Encoding| {
            let schema_id = writer.add_schema(schema_name, enc.schema(), schema.as_bytes())?;
            let id = writer.add_channel(schema_id, topic, enc.message(), &no_meta)?;
            Ok::<_, McapError>(Channel::new(id))
        };
        let (c, j) = (Encoding::Cdr, Encoding::Json);
        let scene = foxglove::scene_update_schema();
        let mut channels = Channels {
            reference: channel(REFERENCE_SCHEMA, reference_schema(), "/reference", c)
                .map_err(err)?,
            actors: channel(ACTORS_SCHEMA, actors_schema(), "/actors", c).map_err(err)?,
            camera: channel(CAMERA_SCHEMA, camera_schema(), "/camera", j).map_err(err)?,
            tf: Vec::new(),
            stage: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/stage", j)
                .map_err(err)?,
            drone: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/drone", j)
                .map_err(err)?,
            actor_scene: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/actors", j)
                .map_err(err)?,
            path: channel(foxglove::SCENE_UPDATE, scene, "/scene/path", j).map_err(err)?,
            calibration: channel(
                foxglove::CAMERA_CALIBRATION,
                foxglove::camera_calibration_schema(),
                "/camera_calibration",
                j,
            )
            .map_err(err)?,
        };

        let (frames, tf) = frame_topics(&mut writer, info.actor_names, &[]).map_err(err)?;
        channels.tf = tf;
        let sha = Sha256::digest(info.script_text.as_bytes());
        let sha_hex: String = sha.iter().map(|b| format!("{b:02x}")).collect();
        let mut metadata = BTreeMap::new();
        metadata.insert("script_name".to_string(), info.script_name.to_string());
        metadata.insert("source_sha256".to_string(), sha_hex);
        metadata.insert("profile".to_string(), info.profile_name.to_string());
        metadata.insert(
            "compiler_version".to_string(),
            env!("CARGO_PKG_VERSION").to_string(),
        );
        metadata.insert("rate_hz".to_string(), info.rate_hz.to_string());
        writer
            .write_metadata(&Metadata {
                name: "dronecine".to_string(),
                metadata,
            })
            .map_err(err)?;
        writer
            .attach(&Attachment {
                log_time: 0,
                create_time: 0,
                name: info.script_name.to_string(),
                media_type: "text/plain".to_string(),
                data: info.script_text.as_bytes().into(),
            })
            .map_err(err)?;

        Ok(Self {
            writer: Some(writer),
            file,
            channels,
            frames,
            last_tick_ns: None,
            info: OwnedInfo {
                lens: info.lens,
                stage: info.stage,
                actor_names: info.actor_names.to_vec(),
            },
            options,
            buf: Vec::with_capacity(1024),
            first_ns: None,
            next_tf_s: f64::NEG_INFINITY,
            next_path_s: f64::NEG_INFINITY,
            heights_m: Vec::new(),
            path: Vec::new(),
            last: None,
        })
    }

    fn put(
        &mut self,
        channel: fn(&mut Channels) -> &mut Channel,
        ns: u64,
        data: &[u8],
    ) -> io::Result<()> {
        let header = channel(&mut self.channels).header(ns);
        self.put_header(&header, data)
    }

    fn put_header(&mut self, header: &MessageHeader, data: &[u8]) -> io::Result<()> {
        let dest = self.file.dest();
        let writer = self.writer.as_mut().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: writer finished", dest.display()))
        })?;
        writer
            .write_to_known_channel(header, data)
            .map_err(|e| mcap_err(dest, e))
    }

    /// The topics published once, at the time of the first sample.
    fn write_static(&mut self, ns: u64, heights_m: &[f64]) -> io::Result<()> {
        self.first_ns = Some(ns);
        let camera = camera_message(&self.info.lens);
        self.put(|c| &mut c.camera, ns, &camera)?;
        let stage = foxglove::stage_scene(ns, &self.info.stage);
        self.put(|c| &mut c.stage, ns, &stage)?;
        let drone = foxglove::drone_scene(ns);
        self.put(|c| &mut c.drone, ns, &drone)?;
        let calibration = foxglove::camera_calibration(ns, &self.info.lens);
        self.put(|c| &mut c.calibration, ns, &calibration)?;
        self.write_actor_scene(ns, heights_m)
    }

    fn write_actor_scene(&mut self, ns: u64, heights_m: &[f64]) -> io::Result<()> {
        self.heights_m.clear();
        self.heights_m.extend_from_slice(heights_m);
        let scene = foxglove::actors_scene(ns, &self.info.actor_names, heights_m);
        self.put(|c| &mut c.actor_scene, ns, &scene)
    }

    /// Writes one sample and the actors at that instant (in the order of
    /// `RunInfo::actor_names`; a different count is an `InvalidInput` error).
    pub fn write(&mut self, sample: &Sample, actors: &[ActorPose]) -> io::Result<()> {
        if actors.len() != self.info.actor_names.len() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "cannot write {}: {} actor poses for {} actors",
                    self.file.dest().display(),
                    actors.len(),
                    self.info.actor_names.len()
                ),
            ));
        }
        let ns = ns_from_s(sample.t_s);
        if self.first_ns.is_none() {
            let heights: Vec<f64> = actors.iter().map(|a| a.height_m).collect();
            self.write_static(ns, &heights)?;
        }

        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        write_reference(&mut buf, sample);
        let result = self.put(|c| &mut c.reference, ns, &buf);
        if result.is_ok() {
            buf.clear();
            write_actors(&mut buf, sample.t_s, &self.info.actor_names, actors);
        }
        let result = result.and_then(|()| self.put(|c| &mut c.actors, ns, &buf));
        self.buf = buf;
        result?;

        if sample.t_s >= self.next_tf_s || !sample.t_s.is_finite() {
            self.next_tf_s = advance(self.next_tf_s, sample.t_s, self.options.foxglove_hz);
            if actors
                .iter()
                .zip(&self.heights_m)
                .any(|(a, &h)| (a.height_m - h).abs() > 1e-3)
            {
                let heights: Vec<f64> = actors.iter().map(|a| a.height_m).collect();
                self.write_actor_scene(ns, &heights)?;
            }
            let prev_ns = self.last_tick_ns.replace(ns);
            let mut buf = std::mem::take(&mut self.buf);
            let mut result = Ok(());
            let poses = [
                (sample.position_m, foxglove::yaw(sample.heading_rad)),
                ([0.0; 3], foxglove::camera_in_drone(sample.camera_pitch_rad)),
            ]
            .into_iter()
            .chain(
                actors
                    .iter()
                    .map(|a| (a.position_m, foxglove::yaw(a.facing_rad))),
            );
            for (i, (t, q)) in poses.enumerate() {
                if self.frames[i].message(&mut buf, prev_ns, ns, t, q) {
                    let header = self.channels.tf[i].header(ns);
                    result = self.put_header(&header, &buf);
                    if result.is_err() {
                        break;
                    }
                }
            }
            self.buf = buf;
            result?;
        }

        self.record_path(sample);
        Ok(())
    }

    fn record_path(&mut self, sample: &Sample) {
        let new_shot = self
            .path
            .last()
            .is_none_or(|(shot, _)| *shot != sample.shot);
        if new_shot {
            // Close the previous strip at this point so that the strips join.
            if let Some((_, points)) = self.path.last_mut() {
                points.push(sample.position_m);
            }
            self.path.push((sample.shot, Vec::new()));
        }
        let keep = new_shot || sample.t_s >= self.next_path_s;
        if keep {
            self.next_path_s = advance(self.next_path_s, sample.t_s, self.options.path_hz);
            if let Some((_, points)) = self.path.last_mut() {
                points.push(sample.position_m);
            }
        }
        self.last = Some((*sample, keep));
    }

    /// Writes the path's line strip and the summary, then renames the temporary file onto
    /// the destination.
    pub fn finish(mut self) -> io::Result<()> {
        let dest = self.file.dest().to_path_buf();
        let ns = match self.first_ns {
            Some(ns) => ns,
            None => {
                let heights = vec![1.7; self.info.actor_names.len()];
                self.write_static(0, &heights)?;
                0
            }
        };
        if let Some((last, false)) = self.last {
            if let Some((_, points)) = self.path.last_mut() {
                points.push(last.position_m);
            }
        }
        if !self.path.is_empty() {
            let path = foxglove::path_scene(ns, &self.path);
            self.put(|c| &mut c.path, ns, &path)?;
        }
        let mut writer = self.writer.take().ok_or_else(|| {
            io::Error::other(format!("cannot write {}: writer finished", dest.display()))
        })?;
        writer.finish().map_err(|e| mcap_err(&dest, e))?;
        let file = writer
            .into_inner()
            .into_inner()
            .map_err(|e| annotate(&dest, e.into_error()))?;
        drop(file);
        self.file.commit()
    }
}

impl Drop for McapWriter {
    fn drop(&mut self) {
        // Unfinished: skip the summary the mcap writer would write on drop; the
        // `AtomicFile` then removes the temporary file.
        if let Some(writer) = self.writer.take() {
            drop(writer.into_inner());
        }
    }
}

/// The next time a decimated topic is due after publishing at `t_s`: one period later on
/// the running schedule, or one period after `t_s` if the schedule fell behind.
pub fn advance(next_s: f64, t_s: f64, hz: f64) -> f64 {
    if !(hz.is_finite() && hz > 0.0 && t_s.is_finite()) {
        return f64::NEG_INFINITY;
    }
    let period = 1.0 / hz;
    let next = next_s + period;
    if next > t_s {
        next
    } else {
        t_s + period
    }
}

/// The transform topics, one per frame (`/tf/drone`, `/tf/camera`, `/tf/actor/NAME` for each
/// actor, then `/tf/CHILD` for each `extra` (parent, child)), in that order: each frame's
/// publisher and its channel.
pub fn frame_topics<W: std::io::Write + std::io::Seek>(
    writer: &mut Writer<W>,
    actor_names: &[String],
    extra: &[(&str, &str)],
) -> Result<(Vec<FrameTopic>, Vec<Channel>), McapError> {
    let schema = writer.add_schema(
        foxglove::FRAME_TRANSFORMS,
        Encoding::Cdr.schema(),
        foxglove::frame_transforms_schema().as_bytes(),
    )?;
    frame_topics_with(actor_names, extra, |topic| {
        writer.add_channel(schema, topic, Encoding::Cdr.message(), &BTreeMap::new())
    })
}

/// [`frame_topics`] on any MCAP writer: `add_channel` registers a CDR channel with the
/// `foxglove_msgs/msg/FrameTransforms` schema on the topic it is given and returns its id (the
/// runtime's flight log has a writer of its own).
pub fn frame_topics_with<E>(
    actor_names: &[String],
    extra: &[(&str, &str)],
    mut add_channel: impl FnMut(&str) -> Result<u16, E>,
) -> Result<(Vec<FrameTopic>, Vec<Channel>), E> {
    let mut frames = vec![
        (foxglove::WORLD.to_string(), foxglove::DRONE.to_string()),
        (foxglove::DRONE.to_string(), foxglove::CAMERA.to_string()),
    ];
    frames.extend(
        actor_names
            .iter()
            .map(|n| (foxglove::WORLD.to_string(), foxglove::actor_frame(n))),
    );
    frames.extend(extra.iter().map(|(p, c)| (p.to_string(), c.to_string())));
    let mut topics = Vec::with_capacity(frames.len());
    let mut channels = Vec::with_capacity(frames.len());
    for (parent, child) in &frames {
        channels.push(Channel::new(add_channel(&format!("/tf/{child}"))?));
        topics.push(FrameTopic::new(parent, child));
    }
    Ok((topics, channels))
}

/// The `/camera` message.
pub fn camera_message(lens: &dronecine_compiler::camera::Lens) -> Vec<u8> {
    let mut camera = b"{\"fov_x_rad\":".to_vec();
    json::micro(&mut camera, lens.fov_x_rad());
    camera.extend_from_slice(b",\"aspect\":");
    json::micro(&mut camera, lens.aspect());
    camera.push(b'}');
    camera
}

/// An `/actors` message (CDR): `names[i]` is actor `i`'s.
pub fn write_actors(buf: &mut Vec<u8>, t_s: f64, names: &[String], actors: &[ActorPose]) {
    let mut m = Cdr::new(buf);
    m.f64(t_s).count(names.len().min(actors.len()));
    for (name, a) in names.iter().zip(actors) {
        m.string(name)
            .f64s(&a.position_m)
            .f64(a.facing_rad)
            .f64(a.height_m);
    }
}

/// A `/reference` message (CDR).
pub fn write_reference(buf: &mut Vec<u8>, s: &Sample) {
    Cdr::new(buf)
        .f64(s.t_s)
        .f64s(&s.position_m)
        .f64s(&s.velocity_mps)
        .f64s(&s.acceleration_mps2)
        .f64(s.heading_rad)
        .f64(s.heading_rate_radps)
        .f64(s.camera_pitch_rad)
        .u32(u32::try_from(s.shot).unwrap_or(u32::MAX));
}

/// Reads a `/reference` message back (tests and tools; a damaged message is an error).
pub fn decode_reference(data: &[u8]) -> Result<Sample, String> {
    let mut r = CdrReader::new(data)?;
    let s = Sample {
        t_s: r.f64("t_s")?,
        position_m: r.f64s("position_m")?,
        velocity_mps: r.f64s("velocity_mps")?,
        acceleration_mps2: r.f64s("acceleration_mps2")?,
        heading_rad: r.f64("heading_rad")?,
        heading_rate_radps: r.f64("heading_rate_radps")?,
        camera_pitch_rad: r.f64("camera_pitch_rad")?,
        shot: r.u32("shot")? as usize,
    };
    r.finish("Reference")?;
    Ok(s)
}

/// One actor of an `/actors` message, as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedActor {
    pub name: String,
    pub position_m: [f64; 3],
    pub facing_rad: f64,
    pub height_m: f64,
}

/// Reads an `/actors` message back: the time and the actors.
pub fn decode_actors(data: &[u8]) -> Result<(f64, Vec<NamedActor>), String> {
    let mut r = CdrReader::new(data)?;
    let t_s = r.f64("t_s")?;
    // Each actor at least: an empty name and five floats.
    let n = r.count("actors", 5 + 5 * 8)?;
    let mut actors = Vec::with_capacity(n);
    for _ in 0..n {
        actors.push(NamedActor {
            name: r.string("name")?.to_string(),
            position_m: r.f64s("position_m")?,
            facing_rad: r.f64("facing_rad")?,
            height_m: r.f64("height_m")?,
        });
    }
    r.finish("Actors")?;
    Ok((t_s, actors))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_message_has_the_schemas_layout() {
        let s = Sample {
            t_s: 1.5,
            position_m: [1.0, 2.0, 3.0],
            velocity_mps: [4.0, 5.0, 6.0],
            acceleration_mps2: [7.0, 8.0, 9.0],
            heading_rad: 10.0,
            heading_rate_radps: 11.0,
            camera_pitch_rad: -0.0,
            shot: 7,
        };
        let mut buf = Vec::new();
        write_reference(&mut buf, &s);
        // Thirteen floats at 0..104 (t_s, the three vectors, heading, rate, pitch), then
        // the shot.
        let body = &buf[4..];
        assert_eq!(body.len(), 108);
        for i in 1..=11 {
            let x = i as f64;
            assert_eq!(&body[8 * i..8 * i + 8], &x.to_le_bytes(), "float {i}");
        }
        assert_eq!(&body[0..8], &1.5f64.to_le_bytes());
        assert_eq!(&body[96..104], &(-0.0f64).to_le_bytes());
        assert_eq!(&body[104..108], &7u32.to_le_bytes());
        assert_eq!(decode_reference(&buf).unwrap(), s);
        assert!(decode_reference(&buf[..buf.len() - 1]).is_err());
    }

    #[test]
    fn an_actors_message_reads_back() {
        let names = ["Ann".to_string(), "Bo \"B\"".to_string()];
        let pose = |x: f64| ActorPose {
            position_m: [x, -x, 0.0],
            velocity_mps: [9.0; 3],
            facing_rad: x / 10.0,
            facing_rate_radps: 9.0,
            height_m: 1.7,
        };
        let mut buf = Vec::new();
        write_actors(&mut buf, 2.0, &names, &[pose(1.0), pose(2.0)]);
        let (t_s, read) = decode_actors(&buf).unwrap();
        assert_eq!(t_s, 2.0);
        assert_eq!(read.len(), 2);
        assert_eq!(read[1].name, names[1]);
        assert_eq!(read[1].position_m, [2.0, -2.0, 0.0]);
        assert_eq!((read[1].facing_rad, read[1].height_m), (0.2, 1.7));
        // A count far beyond the bytes is an error, not an allocation.
        buf[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_actors(&buf).unwrap_err().contains("counts"));
    }
}
