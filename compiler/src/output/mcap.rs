//! The MCAP writer: the reference and the actors at the full rate, the camera, Foxglove's
//! 3D scene (decimated), a metadata record and the script as an attachment.
//!
//! Channels (all JSON messages with JSON schemas, `log_time = publish_time = t_s` in ns):
//!
//! | topic | schema | rate |
//! |---|---|---|
//! | `/reference` | `dronecine.Reference` | every sample |
//! | `/actors` | `dronecine.Actors` | every sample |
//! | `/camera` | `dronecine.Camera` | once, at the first sample |
//! | `/tf/drone`, `/tf/camera`, `/tf/actor/NAME` | `foxglove.FrameTransforms` | when it changes, at most [`McapOptions::foxglove_hz`] |
//! | `/scene/stage`, `/scene/drone` | `foxglove.SceneUpdate` | once |
//! | `/scene/actors` | `foxglove.SceneUpdate` | once, again when a height changes |
//! | `/scene/path` | `foxglove.SceneUpdate` | once, written by `finish()` |
//! | `/camera_calibration` | `foxglove.CameraCalibration` | once |
//!
//! The numbers of `/reference`, `/actors` and `/camera` are quantised to 1e-6 (six decimals,
//! rounded half away from zero, trailing zeros trimmed): positions to the micrometre, speeds,
//! accelerations, angles and rates to 1e-6 of their SI unit, and times at 100 Hz (or any rate
//! whose period has at most six decimals) exactly. That is three orders of magnitude below
//! what a drone's tracking resolves and halves the file compared with shortest round-trip
//! doubles; the CSV keeps the exact values.
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

use super::foxglove::{self, FrameTopic};
use super::{annotate, json, ns_from_s, AtomicFile, RunInfo};
use crate::reference::{ActorPose, Sample};

/// Chunk compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    None,
    /// LZ4 frames, default (fast) level.
    Lz4,
    /// Zstandard level 1: as fast as LZ4 here and 40 % smaller; level 3 costs 50 % more time
    /// for 10 % less size.
    Zstd,
}

/// Tuning of the MCAP writer.
///
/// Measured on a one-hour reference at 100 Hz with two actors (`benches/output.rs`; CPU
/// time of one core on the shared 2-core development machine): no compression 0.6–0.7 s for
/// 349 MB; LZ4 1.25–1.3 s for 139 MB; Zstandard level 1 1.3–1.35 s for 82 MB (level 3:
/// 1.8–2.0 s for 91 MB). The volume is the exact JSON of `/reference` and `/actors` at the
/// full rate (about 0.8 kB a sample with `/tf`); compressing it costs more than writing it.
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

/// The JSON schema of `/reference` messages.
pub const REFERENCE_SCHEMA: &str = "dronecine.Reference";
/// The JSON schema of `/actors` messages.
pub const ACTORS_SCHEMA: &str = "dronecine.Actors";
/// The JSON schema of `/camera` messages.
pub const CAMERA_SCHEMA: &str = "dronecine.Camera";

/// Every number of our own topics is quantised to 1e-6 ([`json::micro`]).
const QUANTISED: &str = "; quantised to 1e-6";

pub fn vec3_schema(description: &str) -> serde_json::Value {
    json!({ "type": "array", "items": { "type": "number" }, "minItems": 3, "maxItems": 3, "description": format!("{description}{QUANTISED}") })
}

pub fn number_schema(description: &str) -> serde_json::Value {
    json!({ "type": "number", "description": format!("{description}{QUANTISED}") })
}

pub fn reference_schema() -> String {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": REFERENCE_SCHEMA,
        "description": "One sample of the 6D camera reference (SI units, world z up)",
        "type": "object",
        "properties": {
            "t_s": number_schema("Time on the script's clock (s)"),
            "position_m": vec3_schema("Camera position (m)"),
            "velocity_mps": vec3_schema("Velocity (m/s)"),
            "acceleration_mps2": vec3_schema("Acceleration (m/s²)"),
            "heading_rad": number_schema("Heading, counter-clockwise from +x, in (−π, π]"),
            "heading_rate_radps": number_schema("Heading rate (rad/s)"),
            "camera_pitch_rad": number_schema("Camera pitch, up positive (rad)"),
            "shot": { "type": "integer", "minimum": 0, "description": "Index of the shot in the timeline" }
        },
        "required": ["t_s", "position_m", "velocity_mps", "acceleration_mps2", "heading_rad",
                     "heading_rate_radps", "camera_pitch_rad", "shot"]
    })
    .to_string()
}

pub fn actors_schema() -> String {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": ACTORS_SCHEMA,
        "description": "The actors as the compiler assumed them",
        "type": "object",
        "properties": {
            "t_s": number_schema("Time on the script's clock (s)"),
            "actors": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "name": { "type": "string" },
                        "position_m": vec3_schema("Feet on the floor (m)"),
                        "facing_rad": number_schema("Facing, counter-clockwise from +x, in (−π, π]"),
                        "height_m": number_schema("Height (m)")
                    },
                    "required": ["name", "position_m", "facing_rad", "height_m"]
                }
            }
        },
        "required": ["t_s", "actors"]
    })
    .to_string()
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
/// # use dronecine_compiler::output::{McapWriter, RunInfo};
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
    /// Each actor's name as a JSON string literal with its key: `{"name":"Ann","position_m":`.
    actor_prefixes: Vec<Vec<u8>>,
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
    lens: crate::camera::Lens,
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
        let mut channel = |schema_name: &str, schema: String, topic: &str| {
            let schema_id = writer.add_schema(schema_name, "jsonschema", schema.as_bytes())?;
            let id = writer.add_channel(schema_id, topic, "json", &no_meta)?;
            Ok::<_, McapError>(Channel::new(id))
        };
        let scene = foxglove::scene_update_schema();
        let mut channels = Channels {
            reference: channel(REFERENCE_SCHEMA, reference_schema(), "/reference").map_err(err)?,
            actors: channel(ACTORS_SCHEMA, actors_schema(), "/actors").map_err(err)?,
            camera: channel(CAMERA_SCHEMA, camera_schema(), "/camera").map_err(err)?,
            tf: Vec::new(),
            stage: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/stage").map_err(err)?,
            drone: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/drone").map_err(err)?,
            actor_scene: channel(foxglove::SCENE_UPDATE, scene.clone(), "/scene/actors")
                .map_err(err)?,
            path: channel(foxglove::SCENE_UPDATE, scene, "/scene/path").map_err(err)?,
            calibration: channel(
                foxglove::CAMERA_CALIBRATION,
                foxglove::camera_calibration_schema(),
                "/camera_calibration",
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

        let actor_prefixes = info.actor_names.iter().map(|n| actor_prefix(n)).collect();
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
            actor_prefixes,
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
        if actors.len() != self.actor_prefixes.len() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "cannot write {}: {} actor poses for {} actors",
                    self.file.dest().display(),
                    actors.len(),
                    self.actor_prefixes.len()
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
            write_actors(&mut buf, sample.t_s, &self.actor_prefixes, actors);
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
        "jsonschema",
        foxglove::frame_transforms_schema().as_bytes(),
    )?;
    frame_topics_with(actor_names, extra, |topic| {
        writer.add_channel(schema, topic, "json", &BTreeMap::new())
    })
}

/// [`frame_topics`] on any MCAP writer: `add_channel` registers a JSON channel with the
/// `foxglove.FrameTransforms` schema on the topic it is given and returns its id (the
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

/// `{"name":NAME,"position_m":`, the start of an actor's entry in `/actors`.
pub fn actor_prefix(name: &str) -> Vec<u8> {
    let mut p = b"{\"name\":".to_vec();
    json::string(&mut p, name);
    p.extend_from_slice(b",\"position_m\":");
    p
}

/// The `/camera` message.
pub fn camera_message(lens: &crate::camera::Lens) -> Vec<u8> {
    let mut camera = b"{\"fov_x_rad\":".to_vec();
    json::micro(&mut camera, lens.fov_x_rad());
    camera.extend_from_slice(b",\"aspect\":");
    json::micro(&mut camera, lens.aspect());
    camera.push(b'}');
    camera
}

/// An `/actors` message; `prefixes[i]` is `{"name":NAME,"position_m":` for actor `i`
/// ([`actor_prefix`]).
pub fn write_actors(buf: &mut Vec<u8>, t_s: f64, prefixes: &[Vec<u8>], actors: &[ActorPose]) {
    buf.extend_from_slice(b"{\"t_s\":");
    json::micro(buf, t_s);
    buf.extend_from_slice(b",\"actors\":[");
    for (i, (prefix, a)) in prefixes.iter().zip(actors).enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(prefix);
        json::vec3_micro(buf, &a.position_m);
        buf.extend_from_slice(b",\"facing_rad\":");
        json::micro(buf, a.facing_rad);
        buf.extend_from_slice(b",\"height_m\":");
        json::micro(buf, a.height_m);
        buf.push(b'}');
    }
    buf.extend_from_slice(b"]}");
}

/// A `/reference` message.
pub fn write_reference(buf: &mut Vec<u8>, s: &Sample) {
    buf.extend_from_slice(b"{\"t_s\":");
    json::micro(buf, s.t_s);
    buf.extend_from_slice(b",\"position_m\":");
    json::vec3_micro(buf, &s.position_m);
    buf.extend_from_slice(b",\"velocity_mps\":");
    json::vec3_micro(buf, &s.velocity_mps);
    buf.extend_from_slice(b",\"acceleration_mps2\":");
    json::vec3_micro(buf, &s.acceleration_mps2);
    buf.extend_from_slice(b",\"heading_rad\":");
    json::micro(buf, s.heading_rad);
    buf.extend_from_slice(b",\"heading_rate_radps\":");
    json::micro(buf, s.heading_rate_radps);
    buf.extend_from_slice(b",\"camera_pitch_rad\":");
    json::micro(buf, s.camera_pitch_rad);
    buf.extend_from_slice(b",\"shot\":");
    json::u64(buf, s.shot as u64);
    buf.push(b'}');
}
