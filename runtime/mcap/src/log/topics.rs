//! [`FlightTopics`]: the flight's topics, tick by tick: which messages a tick makes, when
//! (the plot rates, `/tf` when a frame moved, the key frames), and their bytes (the schemas'
//! encoders), written to a [`MessageOut`]. The flight log's writer puts them in its MCAP
//! chunks; the live view (`dronecine-live`) puts them on the Foxglove WebSocket. One schedule
//! and one set of encoders for both: the log and the live view show the same messages.
//!
//! Nothing on the per-tick path allocates: each message is encoded by its writer straight
//! into the buffer the out gives it (`/tf` through one reused buffer: a frame's message exists
//! only once it is known to have moved).

use std::io;

use crate::output::foxglove::{self, FrameTopic};
use crate::output::mcap::{
    actors_schema, advance, camera_message, camera_schema, frame_topics_with, reference_schema,
    write_actors, write_reference, Encoding, ACTORS_SCHEMA, CAMERA_SCHEMA, REFERENCE_SCHEMA,
};
use crate::output::{json, ns_from_s};
use crate::record::{Event, TickRecord};
use dronecine_compiler::reference::ActorPose;
use dronecine_servo::control::ControllerState;

use super::plots::{self, same_command};
use super::{cdr, exact, key_frame, schema, topic, LogOptions, LogScene};

/// The frame of the reference pose on `/tf/reference`.
const REFERENCE_FRAME: &str = "reference";

/// A topic as a [`MessageOut`] registers it.
#[derive(Clone, Copy, Debug)]
pub struct TopicSpec<'a> {
    pub topic: &'a str,
    pub schema_name: &'a str,
    /// The schema's text (`ros2msg` for CDR, a JSON Schema for JSON).
    pub schema: &'a str,
    pub encoding: Encoding,
}

/// Where the flight's messages go: the log's MCAP file, or the live view's WebSocket.
pub trait MessageOut {
    /// Registers a topic; the id its messages are put on.
    fn add_channel(&mut self, topic: &TopicSpec) -> io::Result<u16>;
    /// Puts a message on `channel` at `ns` (log and publish time, flight clock), its data
    /// written by `encode` (appended to the buffer it is given).
    fn put(&mut self, channel: u16, ns: u64, encode: impl FnOnce(&mut Vec<u8>)) -> io::Result<()>;
}

/// The channel ids of the flight's topics.
struct Channels {
    reference: u16,
    actors: u16,
    camera: u16,
    estimate: u16,
    measurement: u16,
    command: u16,
    framing: u16,
    /// `/gimbal`, only for a profile with a gimbal.
    gimbal: Option<u16>,
    events: u16,
    servo_tick: u16,
    /// `/servo/state`: the key frames.
    key_frame: u16,
    /// `/tf/drone`, `/tf/camera`, `/tf/actor/NAME`…, `/tf/reference`: one per frame in
    /// `FlightTopics::frames`' order.
    tf: Vec<u16>,
    stage: u16,
    drone: u16,
    actor_scene: u16,
    calibration: u16,
}

/// The flight's topics written to a [`MessageOut`] (see the module doc).
pub struct FlightTopics<O> {
    out: O,
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
    /// A tick was written (the first one follows the mark that the controller starts).
    started: bool,
    /// The key frame given since the last tick, written before the next tick.
    key_frame: Option<ControllerState>,
    /// Where `/tf` puts the drone on ticks without an estimate.
    last_estimate: Option<([f64; 3], f64)>,
}

impl<O: MessageOut> FlightTopics<O> {
    /// Every topic registered, the transforms' included, and the static scene written: what
    /// the live view starts with.
    pub fn open(
        out: O,
        scene: &LogScene,
        gimbal: bool,
        options: LogOptions,
    ) -> io::Result<FlightTopics<O>> {
        let mut topics = FlightTopics::new(out, scene.actor_names, gimbal, options)?;
        topics.add_frames()?;
        topics.write_static(scene)?;
        Ok(topics)
    }

    /// Registers every topic but the transforms' ([`FlightTopics::add_frames`]): the
    /// per-tick topics in CDR with ros2msg schemas, events and the static ones JSON;
    /// `/servo/tick` first, `/gimbal` (for a drone with a gimbal) just before
    /// `/servo/state`, which is last.
    pub fn new(
        mut out: O,
        actor_names: &[String],
        gimbal: bool,
        options: LogOptions,
    ) -> io::Result<FlightTopics<O>> {
        let mut channel = |schema_name: &str, schema: &str, topic: &str, enc| {
            out.add_channel(&TopicSpec {
                topic,
                schema_name,
                schema,
                encoding: enc,
            })
        };
        let (c, j) = (Encoding::Cdr, Encoding::Json);
        let servo_tick = channel(cdr::SCHEMA_NAME, cdr::SCHEMA, topic::SERVO_TICK, c)?;
        let scene = foxglove::scene_update_schema();
        let reference = channel(REFERENCE_SCHEMA, &reference_schema(), topic::REFERENCE, c)?;
        let actors = channel(ACTORS_SCHEMA, &actors_schema(), topic::ACTORS, c)?;
        let camera = channel(CAMERA_SCHEMA, &camera_schema(), topic::CAMERA, j)?;
        let estimate = channel(
            plots::ESTIMATE,
            &plots::estimate_schema(),
            topic::ESTIMATE,
            c,
        )?;
        let measurement = channel(
            plots::MEASUREMENT,
            &plots::measurement_schema(),
            topic::MEASUREMENT,
            c,
        )?;
        let command = channel(plots::COMMAND, &plots::command_schema(), topic::COMMAND, c)?;
        let framing = channel(plots::FRAMING, &plots::framing_schema(), topic::FRAMING, c)?;
        let events = channel(schema::EVENT, &schema::event(), topic::EVENTS, j)?;
        let update = foxglove::SCENE_UPDATE;
        let stage = channel(update, &scene, topic::SCENE_STAGE, j)?;
        let drone = channel(update, &scene, topic::SCENE_DRONE, j)?;
        let actor_scene = channel(update, &scene, topic::SCENE_ACTORS, j)?;
        let calibration = channel(
            foxglove::CAMERA_CALIBRATION,
            &foxglove::camera_calibration_schema(),
            topic::CAMERA_CALIBRATION,
            j,
        )?;
        let gimbal = match gimbal {
            true => Some(channel(
                plots::GIMBAL,
                &plots::gimbal_schema(),
                topic::GIMBAL,
                c,
            )?),
            false => None,
        };
        let key_frame = channel(
            key_frame::SCHEMA_NAME,
            key_frame::SCHEMA,
            topic::SERVO_STATE,
            c,
        )?;
        let channels = Channels {
            reference,
            actors,
            camera,
            estimate,
            measurement,
            command,
            framing,
            gimbal,
            events,
            servo_tick,
            key_frame,
            tf: Vec::new(),
            stage,
            drone,
            actor_scene,
            calibration,
        };
        Ok(FlightTopics {
            out,
            channels,
            options,
            frames: Vec::new(),
            last_tf_ns: None,
            actor_names: actor_names.to_vec(),
            heights_m: Vec::new(),
            buf: Vec::with_capacity(4096),
            next_tf_s: f64::NEG_INFINITY,
            next_reference_s: f64::NEG_INFINITY,
            next_estimate_s: f64::NEG_INFINITY,
            next_measurement_s: f64::NEG_INFINITY,
            next_command_s: f64::NEG_INFINITY,
            next_framing_s: f64::NEG_INFINITY,
            command_failsafe: false,
            started: false,
            key_frame: None,
            last_estimate: None,
        })
    }

    /// Registers the transform topics, as compile's, and `/tf/reference`.
    pub fn add_frames(&mut self) -> io::Result<()> {
        let tf_schema = foxglove::frame_transforms_schema();
        let out = &mut self.out;
        let (frames, tf) = frame_topics_with(
            &self.actor_names,
            &[(foxglove::WORLD, REFERENCE_FRAME)],
            |topic| {
                out.add_channel(&TopicSpec {
                    topic,
                    schema_name: foxglove::FRAME_TRANSFORMS,
                    schema: &tf_schema,
                    encoding: Encoding::Cdr,
                })
            },
        )?;
        self.frames = frames;
        self.channels.tf = tf.iter().map(|c| c.id()).collect();
        Ok(())
    }

    /// The topics published once, at time 0: the lens, the stage, the drone, the lens as a
    /// calibration, the actors' figures.
    pub fn write_static(&mut self, scene: &LogScene) -> io::Result<()> {
        let c = &self.channels;
        let (camera, stage, drone, calibration) = (c.camera, c.stage, c.drone, c.calibration);
        self.put(camera, 0, &camera_message(&scene.lens))?;
        self.put(stage, 0, &foxglove::stage_scene(0, &scene.stage))?;
        self.put(drone, 0, &foxglove::drone_scene(0))?;
        let calibrated = foxglove::camera_calibration(0, &scene.lens);
        self.put(calibration, 0, &calibrated)?;
        let mut heights = scene.actor_heights_m.to_vec();
        heights.resize(self.actor_names.len(), 1.7);
        self.write_actor_scene(0, heights)
    }

    fn write_actor_scene(&mut self, ns: u64, heights_m: Vec<f64>) -> io::Result<()> {
        let scene = foxglove::actors_scene(ns, &self.actor_names, &heights_m);
        self.heights_m = heights_m;
        self.put(self.channels.actor_scene, ns, &scene)
    }

    /// Puts a message already encoded.
    fn put(&mut self, channel: u16, ns: u64, data: &[u8]) -> io::Result<()> {
        self.out.put(channel, ns, |b| b.extend_from_slice(data))
    }

    /// The controller's state after the last tick written (a key frame): written before the
    /// next tick, on `/servo/state`.
    pub fn set_key_frame(&mut self, state: &ControllerState) {
        self.key_frame = Some(*state);
    }

    /// Writes one tick on every per-tick topic, and `/tf` when due. `tick.actors` and
    /// `tick.framing` index the scene's actors. Before the first tick, the mark that the
    /// controller starts there; before any other, the key frame given since the last tick,
    /// if any.
    pub fn write_tick(&mut self, tick: &TickRecord) -> io::Result<()> {
        let t_s = tick.input.t_s;
        let ns = ns_from_s(t_s);
        let output = tick.output.as_ref().ok();
        let key_frame = self.channels.key_frame;
        if !self.started {
            self.started = true;
            // No state before the first tick: the controller starts there.
            self.key_frame = None;
            self.out
                .put(key_frame, ns, |b| key_frame::encode(b, t_s, None))?;
        } else if let Some(state) = self.key_frame.take() {
            self.out
                .put(key_frame, ns, |b| key_frame::encode(b, t_s, Some(&state)))?;
        }

        // The plot topics at `plot_hz` (each on the first tick that has one when due); every
        // tick's exact values are on /servo/tick.
        let hz = self.options.plot_hz;
        let due = |next_s: f64| t_s >= next_s || !t_s.is_finite();
        let (out, c) = (&mut self.out, &self.channels);

        // /reference and /actors, exactly as compile writes them.
        if due(self.next_reference_s) {
            self.next_reference_s = advance(self.next_reference_s, t_s, hz);
            out.put(c.reference, ns, |b| write_reference(b, tick.sample))?;
            let names = &self.actor_names;
            out.put(c.actors, ns, |b| write_actors(b, t_s, names, tick.actors))?;
        }
        if let Some(o) = output {
            if due(self.next_estimate_s) {
                self.next_estimate_s = advance(self.next_estimate_s, t_s, hz);
                out.put(c.estimate, ns, |b| plots::estimate(b, t_s, &o.estimate))?;
            }
            self.last_estimate = Some((o.estimate.position_m, o.estimate.heading_rad));
        }

        if let Some(frame) = tick.mocap {
            if due(self.next_measurement_s) {
                let measurement_hz = self.options.measurement_hz;
                self.next_measurement_s = advance(self.next_measurement_s, t_s, measurement_hz);
                out.put(c.measurement, ns, |b| plots::measurement(b, frame))?;
            }
        }

        let failsafe = output.is_none_or(|o| !same_command(&o.command, &tick.command_sent));
        if due(self.next_command_s) || failsafe || self.command_failsafe {
            self.next_command_s = advance(self.next_command_s, t_s, hz);
            self.command_failsafe = failsafe;
            out.put(c.command, ns, |b| {
                plots::command(b, t_s, output, &tick.command_sent, failsafe)
            })?;
        }

        if !tick.framing.is_empty() && due(self.next_framing_s) {
            self.next_framing_s = advance(self.next_framing_s, t_s, hz);
            let names = &self.actor_names;
            out.put(c.framing, ns, |b| {
                plots::framing(b, t_s, tick.shot, names, tick.framing)
            })?;
        }

        if let (Some(g), Some(channel)) = (&tick.gimbal, c.gimbal) {
            out.put(channel, ns, |b| plots::gimbal(b, t_s, g))?;
        }

        out.put(c.servo_tick, ns, |b| cdr::encode(b, tick))?;

        if t_s >= self.next_tf_s || !t_s.is_finite() {
            self.next_tf_s = advance(self.next_tf_s, t_s, self.options.tf_hz);
            self.write_tf(ns, tick)?;
        }
        Ok(())
    }

    /// `/tf`: the drone at its estimate, the camera, the actors and the reference; and
    /// `/scene/actors` again when an actor's height changed.
    fn write_tf(&mut self, ns: u64, tick: &TickRecord) -> io::Result<()> {
        let s = tick.sample;
        let drone = self.last_estimate.unwrap_or((s.position_m, s.heading_rad));
        let reference = (s.position_m, s.heading_rad);
        self.write_frames(ns, drone, s.camera_pitch_rad, tick.actors, Some(reference))
    }

    /// The world as it stands at `t_s`, without a flight loop (`emulate --live`: the
    /// simulator's truth): the drone's pose (position, heading), the camera's pitch and the
    /// actors on `/tf` (the frames that moved) and `/actors`. No reference, no tick.
    pub fn write_world(
        &mut self,
        t_s: f64,
        drone: ([f64; 3], f64),
        camera_pitch_rad: f64,
        actors: &[ActorPose],
    ) -> io::Result<()> {
        let ns = ns_from_s(t_s);
        let names = &self.actor_names;
        let channel = self.channels.actors;
        self.out
            .put(channel, ns, |b| write_actors(b, t_s, names, actors))?;
        self.write_frames(ns, drone, camera_pitch_rad, actors, None)
    }

    /// `/tf`'s frames that moved (the reference's when given) and `/scene/actors` again when
    /// an actor's height changed.
    fn write_frames(
        &mut self,
        ns: u64,
        (position_m, heading_rad): ([f64; 3], f64),
        camera_pitch_rad: f64,
        actors: &[ActorPose],
        reference: Option<([f64; 3], f64)>,
    ) -> io::Result<()> {
        if actors.len() == self.heights_m.len()
            && actors
                .iter()
                .zip(&self.heights_m)
                .any(|(a, &h)| (a.height_m - h).abs() > 1e-3)
        {
            let heights = actors.iter().map(|a| a.height_m).collect();
            self.write_actor_scene(ns, heights)?;
        }
        let prev_ns = self.last_tf_ns.replace(ns);
        let n_actors = actors.len().min(self.frames.len().saturating_sub(3));
        let reference = reference.map(|(p, h)| (self.frames.len() - 1, (p, foxglove::yaw(h))));
        let poses = [
            (position_m, foxglove::yaw(heading_rad)),
            ([0.0; 3], foxglove::camera_in_drone(camera_pitch_rad)),
        ]
        .into_iter()
        .chain(
            actors[..n_actors]
                .iter()
                .map(|a| (a.position_m, foxglove::yaw(a.facing_rad))),
        )
        .enumerate()
        .chain(reference);
        for (i, (t, q)) in poses {
            if self.frames[i].message(&mut self.buf, prev_ns, ns, t, q) {
                let buf = &self.buf;
                self.out
                    .put(self.channels.tf[i], ns, |b| b.extend_from_slice(buf))?;
            }
        }
        Ok(())
    }

    /// Writes an event on `/events` (its time exact, as on `/servo/tick`).
    pub fn write_event(&mut self, event: &Event) -> io::Result<()> {
        let ns = ns_from_s(event.t_s);
        self.out.put(self.channels.events, ns, |buf| {
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
        })
    }

    /// Where the messages go.
    pub fn out(&self) -> &O {
        &self.out
    }

    pub fn out_mut(&mut self) -> &mut O {
        &mut self.out
    }
}
