//! The flight log of `dronecine shoot`: an MCAP file written tick by tick while the drone flies
//! ([`FlightLogWriter`]) and read back by `dronecine replay` ([`FlightLog`]).
//!
//! # Contents
//!
//! Metadata record `dronecine.flight`: every field of the
//! [`FlightHeader`](crate::record::FlightHeader) under its own name, each value the field's
//! JSON text (`"script_name"` → `"\"orbit.psl\""`, `"seed"` → `"42"` or `"null"`,
//! `"sim_effects_off"` → `["wind","battery"]`, `[]` or `"null"` (absent from logs that do
//! not record it), `"controller"` → `{"kind":"lqg",…}`). Attachments: the script
//! text (`text/plain`, named after the script), and the header again as one JSON object
//! ([`HEADER_ATTACHMENT`], under the attachment's CRC, which the metadata record lacks). The
//! first chunk repeats every schema and channel (under its CRC). The per-tick topics are CDR
//! with `ros2msg` schemas (`/servo/tick`: [`cdr`]; `/servo/state`: [`key_frame`]; the plot
//! topics: [`plots`], and compile's writers for `/reference`, `/actors` and `/tf`); `/events`
//! and the topics written once are JSON with JSON schemas. `log_time = publish_time =` the tick's `input.t_s` in nanoseconds (negative
//! or non-finite times: 0).
//!
//! | topic | schema | when | fields |
//! |---|---|---|---|
//! | `/reference` | `dronecine/msg/Reference` (CDR) | 10 Hz | exactly as `dronecine compile` writes it (the tick's [`Sample`](dronecine_compiler::reference::Sample)) |
//! | `/actors` | `dronecine/msg/Actors` (CDR) | 10 Hz | exactly as compile: `t_s`, `actors[] {name, position_m, facing_rad, height_m}` |
//! | `/camera` | `dronecine.Camera` | once (t = 0) | `fov_x_rad`, `aspect` |
//! | `/estimate` | `dronecine/msg/Estimate` (CDR) | 10 Hz: ticks whose controller answered | `t_s`, `position_m`, `velocity_mps`, `heading_rad` |
//! | `/measurement` | `dronecine/msg/Measurement` (CDR) | 30 Hz: ticks with a new mocap frame | `t_s` (capture), `frame`, `drone {position_m, heading_rad, tracked}`, `actors[]` (same) |
//! | `/command` | `dronecine/msg/Command` (CDR) | 10 Hz, and every tick whose `failsafe` is set (and the first after) | `t_s`, `roll_rad`, `pitch_rad`, `yaw_rate_radps`, `vz_mps` (the command **sent**), `saturated`, `failsafe` (the command sent is not the controller's) |
//! | `/framing` | `dronecine/msg/Framing` (CDR) | 10 Hz: ticks with framing records | `t_s`, `shot` (−1: none), `actors[] {name, actor, screen, requested, has_screen, has_requested}` |
//! | `/gimbal` | `dronecine/msg/Gimbal` (CDR) | every tick, only when the profile has a gimbal (no channel otherwise) | `t_s`, `asked_rad` (the pitch commanded), `reported_rad` and `has_reported` (the pitch the gimbal reported, before this tick's command) |
//! | `/events` | `dronecine.Event` | each event | `t_s`, `level`, `kind`, `message`; a finding of the director's also `line` (the script's, 1-based) and `help` (its fix, as compile says it) |
//! | `/servo/tick` | `dronecine/msg/ServoTick` (CDR, [`cdr::SCHEMA`]) | every tick | the phase, the shot, the [`TickInput`](dronecine_servo::control::TickInput), the [`TickOutput`](dronecine_servo::control::TickOutput) or the fault, the command sent, the drone's state, the latency, the actors as the director saw them, the framing records: 514 bytes with two actors framed |
//! | `/servo/state` | `dronecine/msg/ServoState` (CDR, [`key_frame::SCHEMA`]) | before the first tick of each chunk | a key frame: the [`ControllerState`](dronecine_servo::control::ControllerState) after the tick before, every float bit for bit (before the log's first tick, the mark that the controller starts there) |
//! | `/tf/drone`, `/tf/camera`, `/tf/actor/NAME`, `/tf/reference` | `foxglove_msgs/msg/FrameTransforms` (CDR) | 30 Hz (a frame when it moved) | `world→drone` (the estimate), `drone→camera`, `world→actor/NAME`, `world→reference` |
//! | `/scene/stage`, `/scene/drone`, `/scene/actors` | `foxglove.SceneUpdate` | once (actors again when a height changes) | as compile |
//! | `/camera_calibration` | `foxglove.CameraCalibration` | once | as compile |
//!
//! The plot topics (rates in [`LogOptions`]) are for Foxglove's plots and 3D view: every
//! tick's exact reference, estimate, drone measurement, commands, actors (as the director saw
//! them) and framing are on `/servo/tick` (which Foxglove plots as well, field by field), and
//! that (with `/events`) is all replay reads; the actors' raw measured poses are kept at
//! 30 Hz only, on `/measurement`. A topic is written on the first tick that has one when it is
//! due. The plot topics are CDR at 10 Hz because the writer thread must keep up with a
//! simulated flight, which runs as fast as the CPU allows: formatting their floats as text,
//! or writing them at the mocap's rate, would cost the writer more than the flight it logs.
//!
//! # Numbers
//!
//! The CDR topics hold each float's IEEE 754 bits (NaN payloads and `-0.0` included) but
//! `/tf`, rounded for the 3D view (millimetres, quaternion components to 1e-6). `/events`
//! writes its time in its shortest round-trip form, so that parsing it gives back the same
//! bits; a non-finite time is the string `"NaN"`, `"inf"` or `"-inf"` (a NaN's payload and
//! sign are not kept). An absent value on a CDR topic (an untracked body, an actor behind the
//! camera) is zero with its flag clear.
//!
//! # Crash safety
//!
//! The log is written in place, not through a temporary file: whatever reached the disk stays
//! readable after a crash. Chunks are built in memory and written whole; a chunk is closed and
//! the file flushed (to the OS, without `fsync`) every `flush_period_s` of flight time
//! ([`LogOptions`]), the ticks that record nothing included ([`FlightLogWriter::idle`]: before
//! take-off, the drone's own take-off and landing). `shoot` writes through [`LogThread`],
//! which hands the ticks to a writer thread every quarter second (taken up within 20 ms) and
//! closes chunks every 0.73 s, so a crash of the process in a flight in real time loses at
//! most the last second, in every phase (a simulated
//! flight, thousands of times faster, may lose its last few milliseconds of wall-clock time:
//! seconds of flight, which the writer had not caught up with or keeps for one larger write;
//! see [`LogThread`]); [`FlightLog::open`] reads every complete
//! chunk before the cut and sets [`FlightLog::truncated`]. (The writer reserves the file's
//! disk space 8 MB ahead, its size unchanged, and gives back what it did not use when it
//! finishes; a crash-cut log keeps up to 8 MB reserved after its data, freed when the file is
//! truncated or copied.) Damage inside the file (a bad
//! sector, a corrupt copy) costs at most the chunks it touches: the reader skips to the next
//! record it can check and reads on; what the records at the start hold is there twice, once
//! under a CRC; and each chunk's ticks start with a key frame, from which `replay` resumes
//! after a gap (see [`FlightLog`]). A power cut may lose what the OS had not yet written: for a log forced
//! to the disk as it is written ([`LogOptions::durable`]: `shoot`'s for a real flight, one
//! paced by the wall clock, or with `--sync-log`), what came since the last sync (two
//! seconds in real time); for a simulated flight's log as `shoot` writes it by default, left
//! to the OS (the flight is reproducible from the script, the profile and the seed its log
//! records), whatever the OS had not written back yet.

pub mod cdr;
pub mod key_frame;
mod mcap_file;
pub mod plots;
mod reader;
mod schema;
mod thread;
mod topics;
mod writer;

use std::fmt;
use std::io;
use std::path::PathBuf;

use dronecine_compiler::camera::Lens;
use dronecine_grammar::script::Stage;

pub use self::reader::{Damage, FlightLog, KeyFrame, LoggedTick};
pub use self::thread::{lower_priority, LogThread, OwnedTick, BATCH_PERIOD_S, POLL_MAX_S};
pub use self::topics::{FlightTopics, MessageOut, TopicSpec};
pub use self::writer::{FlightLogWriter, LogCompression, LogOptions};

/// The static scene the log draws in Foxglove: the stage, the lens and the actors (their
/// names in the order of [`TickRecord::actors`](crate::record::TickRecord), their heights for
/// the 3D figures).
#[derive(Clone, Copy, Debug)]
pub struct LogScene<'a> {
    pub stage: Stage,
    pub lens: Lens,
    pub actor_names: &'a [String],
    pub actor_heights_m: &'a [f64],
}

/// The name of the metadata record that holds the [`FlightHeader`](crate::record::FlightHeader).
pub const HEADER_METADATA: &str = "dronecine.flight";

/// The name of the attachment that holds the [`FlightHeader`](crate::record::FlightHeader)
/// again, as one JSON object, under the attachment's CRC.
pub const HEADER_ATTACHMENT: &str = "dronecine.flight.json";

/// Topics of the flight log.
pub mod topic {
    pub const REFERENCE: &str = "/reference";
    pub const ACTORS: &str = "/actors";
    pub const CAMERA: &str = "/camera";
    pub const ESTIMATE: &str = "/estimate";
    pub const MEASUREMENT: &str = "/measurement";
    pub const COMMAND: &str = "/command";
    pub const FRAMING: &str = "/framing";
    /// The camera gimbal's pitch, asked and reported: only for a drone with a gimbal.
    pub const GIMBAL: &str = "/gimbal";
    pub const EVENTS: &str = "/events";
    pub const SERVO_TICK: &str = "/servo/tick";
    /// The key frames: the controller's state at the start of each chunk.
    pub const SERVO_STATE: &str = "/servo/state";
    /// Transforms: `/tf/drone` (the estimate), `/tf/camera`, `/tf/actor/NAME`,
    /// `/tf/reference`, one topic per frame as `compile` writes them.
    pub const TF_PREFIX: &str = "/tf/";
    pub const SCENE_STAGE: &str = "/scene/stage";
    pub const SCENE_DRONE: &str = "/scene/drone";
    pub const SCENE_ACTORS: &str = "/scene/actors";
    pub const CAMERA_CALIBRATION: &str = "/camera_calibration";

    /// Whether a topic is written once (or again only when it changes: the actors' figures):
    /// a reader that comes late, a live view's client, wants its last message.
    pub fn is_latched(topic: &str) -> bool {
        [
            CAMERA,
            SCENE_STAGE,
            SCENE_DRONE,
            SCENE_ACTORS,
            CAMERA_CALIBRATION,
        ]
        .contains(&topic)
    }
}

/// Why a flight log could not be read.
#[derive(Debug)]
pub enum LogError {
    /// The file could not be opened or read.
    Io { path: PathBuf, source: io::Error },
    /// The file is not an MCAP file (or is damaged before its first record).
    NotMcap { path: PathBuf, detail: String },
    /// An MCAP file without the `dronecine.flight` metadata record: not a flight log (or one
    /// cut before its header reached the disk).
    NoHeader { path: PathBuf },
    /// The `dronecine.flight` record is there but does not describe a flight.
    BadHeader { path: PathBuf, detail: String },
    /// A message in an intact chunk does not parse.
    BadMessage {
        path: PathBuf,
        topic: &'static str,
        /// Index of the message on its topic.
        index: usize,
        detail: String,
    },
}

impl fmt::Display for LogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LogError::Io { path, source } => {
                write!(f, "cannot read flight log {}: {source}", path.display())
            }
            LogError::NotMcap { path, detail } => write!(
                f,
                "{} is not a flight log: not a readable MCAP file ({detail})",
                path.display()
            ),
            LogError::NoHeader { path } => write!(
                f,
                "{} is not a flight log: no `{HEADER_METADATA}` metadata record",
                path.display()
            ),
            LogError::BadHeader { path, detail } => write!(
                f,
                "flight log {}: bad `{HEADER_METADATA}` header: {detail}",
                path.display()
            ),
            LogError::BadMessage {
                path,
                topic,
                index,
                detail,
            } => write!(
                f,
                "flight log {}: message {index} on {topic} does not parse: {detail}",
                path.display()
            ),
        }
    }
}

impl std::error::Error for LogError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LogError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Exact floats for `/events` (JSON).
mod exact {
    use crate::output::json;
    use serde::de::{self, Deserializer, Visitor};
    use serde::Deserialize;
    use std::fmt;

    /// Appends `x` in its shortest round-trip form, or `"NaN"`, `"inf"`, `"-inf"`.
    #[inline]
    pub fn f64(out: &mut Vec<u8>, x: f64) {
        if x.is_finite() {
            json::f64(out, x);
        } else if x.is_nan() {
            out.extend_from_slice(b"\"NaN\"");
        } else if x > 0.0 {
            out.extend_from_slice(b"\"inf\"");
        } else {
            out.extend_from_slice(b"\"-inf\"");
        }
    }

    /// A float as [`f64`] writes it (also `null`, read as NaN, and integers).
    #[derive(Clone, Copy, Debug)]
    pub struct Num(pub f64);

    impl<'de> Deserialize<'de> for Num {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Num, D::Error> {
            struct V;
            impl Visitor<'_> for V {
                type Value = Num;
                fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                    f.write_str("a number, \"NaN\", \"inf\", \"-inf\" or null")
                }
                fn visit_f64<E>(self, x: f64) -> Result<Num, E> {
                    Ok(Num(x))
                }
                fn visit_u64<E>(self, x: u64) -> Result<Num, E> {
                    Ok(Num(x as f64))
                }
                fn visit_i64<E>(self, x: i64) -> Result<Num, E> {
                    Ok(Num(x as f64))
                }
                fn visit_unit<E>(self) -> Result<Num, E> {
                    Ok(Num(f64::NAN))
                }
                fn visit_none<E>(self) -> Result<Num, E> {
                    Ok(Num(f64::NAN))
                }
                fn visit_str<E: de::Error>(self, s: &str) -> Result<Num, E> {
                    match s {
                        "NaN" => Ok(Num(f64::NAN)),
                        "inf" => Ok(Num(f64::INFINITY)),
                        "-inf" => Ok(Num(f64::NEG_INFINITY)),
                        _ => Err(E::invalid_value(de::Unexpected::Str(s), &self)),
                    }
                }
            }
            d.deserialize_any(V)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::exact;

    fn round_trip(x: f64) -> f64 {
        let mut out = Vec::new();
        exact::f64(&mut out, x);
        serde_json::from_slice::<exact::Num>(&out).unwrap().0
    }

    #[test]
    fn exact_floats_keep_their_bits() {
        for x in [
            0.0,
            -0.0,
            0.1 + 0.2,
            1.0,
            -3.0,
            5e-324,
            -2.2250738585072014e-308,
            f64::MAX,
            f64::MIN,
            1e21,
            123456789012345680000.0,
            std::f64::consts::PI,
        ] {
            assert_eq!(round_trip(x).to_bits(), x.to_bits(), "{x:e}");
        }
        assert!(round_trip(f64::NAN).is_nan());
        assert_eq!(round_trip(f64::INFINITY), f64::INFINITY);
        assert_eq!(round_trip(f64::NEG_INFINITY), f64::NEG_INFINITY);
    }
}
