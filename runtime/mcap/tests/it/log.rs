//! The flight log: what is written is read back bit for bit, the file is a standard MCAP file
//! whose `/reference`, `/actors` and `/camera` are compile's, a crash loses at most the last
//! second, and no damaged or foreign file makes the reader panic.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::OnceLock;

use dronecine_backend::frames::Command;
use dronecine_backend::{BodyPose, FlightState, MocapFrame};
use dronecine_compiler::camera::Lens;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::Stage;
use dronecine_mcap::log::LogOptions;
use dronecine_mcap::log::{
    cdr, key_frame, plots, FlightLog, FlightLogWriter, LogError, LogScene, LogThread, LoggedTick,
};
use dronecine_mcap::output::mcap as compiled;
use dronecine_mcap::output::{foxglove, McapWriter, RunInfo};
use dronecine_mcap::record::{
    reference_of, Event, FlightHeader, FlightSink, FramingRecord, Phase, TickRecord,
};
use dronecine_servo::control::{
    ControllerState, Estimate, FilterState, Measurement, PidState, TickFault, TickInput, TickOutput,
};
use dronecine_servo::setup::ControllerSetup;
use proptest::prelude::*;

pub(crate) fn names() -> Vec<String> {
    vec!["Ann".to_string(), "Bo \"the\" Bear".to_string()]
}

const HEIGHTS: [f64; 2] = [1.7, 1.85];

fn stage() -> Stage {
    Stage {
        size_m: [8.0, 6.0, 3.0],
    }
}

fn lens() -> Lens {
    Lens::new(84f64.to_radians(), 16.0 / 9.0)
}

pub(crate) fn header() -> FlightHeader {
    FlightHeader {
        script_name: "orbit.psl".into(),
        script_text: "stage 8m x 6m x 3m\ndrone ardrone2\n\"quoted\" — ünïcode\n".into(),
        profile_name: "ardrone2".into(),
        profile_toml: "[drone]\nname = \"ardrone2\"\n".into(),
        profile: dronecine_profile::Profile::builtin("ardrone2").unwrap(),
        controller: ControllerSetup {
            kind: "lqg".into(),
            paper_prefilter: false,
            per_tick_solve: true,
        },
        backend: "sim".into(),
        seed: Some(u64::MAX),
        sim_effects_off: Some(vec!["wind".into(), "battery".into()]),
        rate_hz: 100.0,
        actor_names: names(),
        dronecine_version: "0.1.0".into(),
    }
}

/// Everything a `TickRecord` borrows, owned.
#[derive(Clone, Debug)]
pub(crate) struct Tick {
    phase: Phase,
    shot: Option<usize>,
    sample: Sample,
    pub(crate) input: TickInput,
    output: Result<TickOutput, TickFault>,
    command_sent: Command,
    mocap: Option<MocapFrame>,
    actors: Vec<ActorPose>,
    framing: Vec<FramingRecord>,
}

impl Tick {
    pub(crate) fn record(&self) -> TickRecord<'_> {
        TickRecord {
            phase: self.phase,
            shot: self.shot,
            sample: &self.sample,
            input: self.input,
            output: self.output,
            command_sent: self.command_sent,
            mocap: self.mocap.as_ref(),
            actors: &self.actors,
            framing: &self.framing,
            drone_state: FlightState::Flying,
            latency_s: self.mocap.as_ref().map(|_| 0.0037),
            gimbal: None,
        }
    }

    pub(crate) fn logged(&self) -> LoggedTick {
        LoggedTick {
            phase: self.phase,
            shot: self.shot,
            input: self.input,
            output: self.output,
            command_sent: self.command_sent,
            latency_s: self.mocap.as_ref().map(|_| 0.0037),
            // Both exact, on /servo/tick.
            actors: self.actors.clone(),
            framing: self.framing.clone(),
        }
    }
}

/// A plausible tick at `t_s`, every number derived from `x` (so a test can vary them).
fn tick(k: usize, t_s: f64, x: [f64; 8]) -> Tick {
    let sample = Sample {
        t_s,
        position_m: [x[0], x[1], 1.5 + x[2]],
        velocity_mps: [x[3], x[4], x[5]],
        acceleration_mps2: [x[6], x[7], x[0] * x[1]],
        heading_rad: x[2],
        heading_rate_radps: x[3],
        camera_pitch_rad: -0.2,
        shot: k % 3,
    };
    let actors: Vec<ActorPose> = (0..2)
        .map(|i| ActorPose {
            position_m: [x[i] + i as f64, x[i + 1], 0.0],
            velocity_mps: [x[4], x[5], 0.0],
            facing_rad: x[6],
            facing_rate_radps: 0.0,
            height_m: HEIGHTS[i],
        })
        .collect();
    let measurement = (k % 7 != 3).then_some(Measurement {
        position_m: [x[1], x[0], x[7]],
        heading_rad: x[5],
    });
    let output = if k % 11 == 5 {
        Err(if k.is_multiple_of(2) {
            TickFault::NotFinite
        } else {
            TickFault::TimeNotIncreasing
        })
    } else {
        Ok(TickOutput {
            command: Command {
                roll_rad: x[0],
                pitch_rad: x[1],
                yaw_rate_radps: x[2],
                vz_mps: x[3],
            },
            estimate: Estimate {
                position_m: [x[4], x[5], x[6]],
                velocity_mps: [x[7], x[0], x[1]],
                heading_rad: x[2],
            },
            saturated: k.is_multiple_of(5),
        })
    };
    let command_sent = match &output {
        Ok(o) => o.command,
        Err(_) => Command::HOVER,
    };
    Tick {
        phase: [
            Phase::TakeOff,
            Phase::Approach,
            Phase::Shots,
            Phase::Landing,
        ][k % 4],
        shot: (k % 4 == 2).then_some(k % 3),
        input: TickInput {
            t_s,
            dt_s: 0.01,
            measurement,
            reference: reference_of(&sample),
        },
        sample,
        output,
        command_sent,
        mocap: measurement.map(|m| MocapFrame {
            t_s: t_s - 0.002,
            received_s: t_s - 0.001,
            frame: k as u64,
            drone: Some(BodyPose {
                position_m: m.position_m,
                heading_rad: m.heading_rad,
            }),
            actors: vec![
                Some(BodyPose {
                    position_m: actors[0].position_m,
                    heading_rad: actors[0].facing_rad,
                }),
                None,
            ],
        }),
        framing: vec![
            FramingRecord {
                actor: 0,
                screen: Some([x[0] * 0.1, x[1] * 0.1]),
                requested: Some([-0.33, 0.1]),
            },
            FramingRecord {
                actor: 1,
                screen: None,
                requested: None,
            },
        ],
        actors,
    }
}

/// Smooth, ordinary values for tick `k` of a flight at 100 Hz.
pub(crate) fn flight_tick(k: usize) -> Tick {
    let t = k as f64 * 0.01;
    let x = [
        t.sin(),
        t.cos(),
        (0.3 * t).sin(),
        0.1 + 0.2,
        -0.0,
        t * 1e-3,
        -t,
        (t * 7.0).sin() * 1e-9,
    ];
    tick(k, t, x)
}

pub(crate) fn scene_of(names: &[String]) -> LogScene<'_> {
    LogScene {
        stage: stage(),
        lens: lens(),
        actor_names: names,
        actor_heights_m: &HEIGHTS,
    }
}

/// A controller's state after tick `k` (its numbers derived from `k`), as a flight loop
/// gives it when the log asks for a key frame.
pub(crate) fn state_after(k: usize) -> ControllerState {
    let x = k as f64;
    ControllerState::Pid(PidState {
        filter: FilterState {
            x: [x, -x, 0.5 * x, 1.0, 2.0, 3.0, 0.0, -0.0, x * 1e-9],
            heading_rad: 0.01 * x,
            ..FilterState::default()
        },
        sent_input: [0.1, 0.2, x],
        sent_yaw_rate_radps: -x,
        integral_z_ms: 0.5 * x,
    })
}

pub(crate) fn write_log(path: &Path, ticks: &[Tick], events: &[Event]) {
    let names = names();
    let mut w = FlightLogWriter::create(path, &header(), &scene_of(&names)).unwrap();
    for (i, t) in ticks.iter().enumerate() {
        w.write_tick(&t.record()).unwrap();
        if w.wants_key_frame() {
            w.write_key_frame(&state_after(i));
        }
        if let Some(e) = events.get(i) {
            w.write_event(e).unwrap();
        }
    }
    for e in events.iter().skip(ticks.len()) {
        w.write_event(e).unwrap();
    }
    w.finish().unwrap();
}

/// An event's float by bits (on `/events`, JSON, all NaNs are one NaN).
fn bits(x: f64) -> u64 {
    if x.is_nan() {
        f64::NAN.to_bits()
    } else {
        x.to_bits()
    }
}

/// Every float of a logged tick, by its exact bits (`/servo/tick` keeps NaN payloads), in a
/// fixed order (plus the discrete fields).
fn tick_bits(t: &LoggedTick) -> Vec<u64> {
    let i = &t.input;
    let r = &i.reference;
    let mut v = vec![f64::to_bits(i.t_s), f64::to_bits(i.dt_s)];
    match &i.measurement {
        Some(m) => {
            v.push(1);
            v.extend(m.position_m.iter().map(|&x| f64::to_bits(x)));
            v.push(f64::to_bits(m.heading_rad));
        }
        None => v.push(0),
    }
    v.extend(r.position_m.iter().map(|&x| f64::to_bits(x)));
    v.extend(r.velocity_mps.iter().map(|&x| f64::to_bits(x)));
    v.extend(r.acceleration_mps2.iter().map(|&x| f64::to_bits(x)));
    v.push(f64::to_bits(r.heading_rad));
    v.push(f64::to_bits(r.heading_rate_radps));
    let cmd = |c: &Command| {
        [c.roll_rad, c.pitch_rad, c.yaw_rate_radps, c.vz_mps]
            .map(f64::to_bits)
            .to_vec()
    };
    match &t.output {
        Ok(o) => {
            v.push(1);
            v.extend(cmd(&o.command));
            v.extend(o.estimate.position_m.iter().map(|&x| f64::to_bits(x)));
            v.extend(o.estimate.velocity_mps.iter().map(|&x| f64::to_bits(x)));
            v.push(f64::to_bits(o.estimate.heading_rad));
            v.push(o.saturated as u64);
        }
        Err(TickFault::NotFinite) => v.push(2),
        Err(TickFault::TimeNotIncreasing) => v.push(3),
    }
    v.extend(cmd(&t.command_sent));
    v.push(t.phase as u64);
    v.push(t.shot.map_or(u64::MAX, |s| s as u64));
    v.push(t.actors.len() as u64);
    for a in &t.actors {
        let floats = a.position_m.iter().chain(&a.velocity_mps).chain([
            &a.facing_rad,
            &a.facing_rate_radps,
            &a.height_m,
        ]);
        v.extend(floats.map(|x| x.to_bits()));
    }
    v.push(t.framing.len() as u64);
    for f in &t.framing {
        v.push(f.actor as u64);
        for p in [f.screen, f.requested] {
            match p {
                Some(p) => v.extend([1, p[0].to_bits(), p[1].to_bits()]),
                None => v.push(0),
            }
        }
    }
    v
}

/// An event as comparable bits: every field, the time's bits exactly.
#[allow(clippy::type_complexity)]
fn event_bits(e: &Event) -> (u64, String, String, String, Option<u32>, Option<String>) {
    (
        bits(e.t_s),
        e.level.clone(),
        e.kind.clone(),
        e.message.clone(),
        e.line,
        e.help.clone(),
    )
}

pub(crate) fn events() -> Vec<Event> {
    vec![
        Event {
            t_s: 0.0,
            level: "info".into(),
            kind: "take_off".into(),
            message: "taking off".into(),
            line: None,
            help: None,
        },
        Event {
            t_s: 0.1 + 0.2,
            level: "warning".into(),
            kind: "deadline_missed".into(),
            message: "tick 30 late by 2.5 ms \"quoted\"\n\u{1F3AC}".into(),
            line: Some(27),
            help: Some("pin the shot at `at 71.3s` \"or\" later\n\u{1F3AC}".into()),
        },
        Event {
            t_s: f64::NAN,
            level: "error".into(),
            kind: "fault".into(),
            message: String::new(),
            line: Some(u32::MAX),
            help: Some(String::new()),
        },
    ]
}

/// Any f64: random bits (so subnormals and huge values), plus the special values.
fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => any::<u64>().prop_map(f64::from_bits),
        1 => prop::sample::select(vec![
            0.0,
            -0.0,
            0.1 + 0.2,
            5e-324,
            f64::from_bits(0x800F_FFFF_FFFF_FFFF), // the largest negative subnormal
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]),
        3 => -1e3..1e3f64,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Inputs, outputs and commands come back bit for bit, whatever their values (NaN
    /// payloads included); events too (their NaN is one NaN).
    #[test]
    fn ticks_round_trip_bit_for_bit(
        values in prop::collection::vec((any_f64(), prop::array::uniform8(any_f64())), 1..40)
    ) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flight.mcap");
        let ticks: Vec<Tick> = values
            .iter()
            .enumerate()
            .map(|(k, (t, x))| {
                let mut tick = tick(k, *t, *x);
                // A command sent that differs from the controller's, with its own values.
                if k % 3 == 1 {
                    tick.command_sent = Command {
                        roll_rad: x[7],
                        pitch_rad: x[6],
                        yaw_rate_radps: -x[5],
                        vz_mps: x[4],
                    };
                }
                tick.input.dt_s = x[3];
                // A reference given to the controller that is not the sample's.
                if k % 5 == 4 {
                    tick.input.reference.heading_rad = x[1];
                    tick.input.reference.velocity_mps[2] = *t;
                }
                tick
            })
            .collect();
        let events = events();
        write_log(&path, &ticks, &events);
        let log = FlightLog::open(&path).unwrap();
        prop_assert!(!log.truncated);
        prop_assert_eq!(log.ticks.len(), ticks.len());
        for (got, want) in log.ticks.iter().zip(&ticks) {
            prop_assert_eq!(tick_bits(got), tick_bits(&want.logged()));
        }
        let got: Vec<_> = log.events.iter().map(event_bits).collect();
        let want: Vec<_> = events.iter().map(event_bits).collect();
        prop_assert_eq!(got, want);
    }
}

#[test]
fn a_finished_log_reads_back_whole_with_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.mcap");
    let ticks: Vec<Tick> = (0..500).map(flight_tick).collect();
    let events = events();
    write_log(&path, &ticks, &events);
    let log = FlightLog::open(&path).unwrap();
    assert!(!log.truncated, "{:?}", log.damage);
    assert_eq!(log.header, header());
    let want: Vec<LoggedTick> = ticks.iter().map(Tick::logged).collect();
    assert_eq!(log.ticks, want);
    // Plain equality for the events but the NaN time.
    assert_eq!(log.events.len(), 3);
    assert_eq!(log.events[..2], events[..2]);
    assert!(log.events[2].t_s.is_nan());
    // -0.0 survives (PartialEq would not tell).
    assert!(log.ticks[0].input.reference.velocity_mps[1].is_sign_negative());
    assert_eq!(log.ticks[1].input.reference.velocity_mps[0], 0.1 + 0.2);
}

/// Every message of one topic, as (log_time, bytes), through the mcap crate's standard reader.
fn messages(bytes: &[u8]) -> BTreeMap<String, Vec<(u64, Vec<u8>)>> {
    let mut out: BTreeMap<String, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        let m = m.unwrap();
        out.entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, m.data.into_owned()));
    }
    out
}

#[test]
fn the_log_is_a_standard_mcap_file_with_a_schema_on_every_channel() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.mcap");
    let ticks: Vec<Tick> = (0..300).map(flight_tick).collect();
    write_log(&path, &ticks, &events());
    let bytes = std::fs::read(&path).unwrap();

    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let topics: BTreeSet<&str> = summary
        .channels
        .values()
        .map(|c| c.topic.as_str())
        .collect();
    let expected: BTreeSet<&str> = [
        "/reference",
        "/actors",
        "/camera",
        "/estimate",
        "/measurement",
        "/command",
        "/framing",
        "/events",
        "/servo/tick",
        "/servo/state",
        "/tf/drone",
        "/tf/camera",
        "/tf/actor/Ann",
        "/tf/actor/Bo \"the\" Bear",
        "/tf/reference",
        "/scene/stage",
        "/scene/drone",
        "/scene/actors",
        "/camera_calibration",
    ]
    .into_iter()
    .collect();
    assert_eq!(topics, expected);
    for c in summary.channels.values() {
        let schema = c
            .schema
            .as_ref()
            .unwrap_or_else(|| panic!("{} has no schema", c.topic));
        if c.topic == "/servo/tick" {
            // CDR with a ros2msg schema, as Foxglove reads ROS 2 messages.
            assert_eq!(schema.name, "dronecine/msg/ServoTick");
            assert_eq!(schema.encoding, "ros2msg");
            assert_eq!(c.message_encoding, "cdr");
            assert_eq!(&schema.data[..], cdr::SCHEMA.as_bytes());
            continue;
        }
        // The other per-tick topics: CDR too, compile's schemas or the log's own.
        let cdr_schema = match c.topic.as_str() {
            "/reference" => Some(("dronecine/msg/Reference", compiled::reference_schema())),
            "/actors" => Some(("dronecine/msg/Actors", compiled::actors_schema())),
            "/estimate" => Some(("dronecine/msg/Estimate", plots::estimate_schema())),
            "/measurement" => Some(("dronecine/msg/Measurement", plots::measurement_schema())),
            "/command" => Some(("dronecine/msg/Command", plots::command_schema())),
            "/framing" => Some(("dronecine/msg/Framing", plots::framing_schema())),
            "/servo/state" => Some(("dronecine/msg/ServoState", key_frame::SCHEMA.to_string())),
            topic if topic.starts_with("/tf/") => Some((
                "foxglove_msgs/msg/FrameTransforms",
                foxglove::frame_transforms_schema(),
            )),
            _ => None,
        };
        if let Some((name, definition)) = cdr_schema {
            assert_eq!(schema.name, name, "{}", c.topic);
            assert_eq!(schema.encoding, "ros2msg", "{}", c.topic);
            assert_eq!(c.message_encoding, "cdr", "{}", c.topic);
            assert_eq!(schema.data, definition.as_bytes(), "{}", c.topic);
            continue;
        }
        assert_eq!(schema.encoding, "jsonschema", "{}", c.topic);
        assert_eq!(c.message_encoding, "json", "{}", c.topic);
        let s: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert_eq!(s["type"], "object", "{}", c.topic);
    }

    let by_topic = messages(&bytes);
    for (k, (_, data)) in by_topic["/servo/tick"].iter().enumerate() {
        let decoded = cdr::decode(data).unwrap();
        assert!(decoded.extended && data.len() > cdr::FIXED_LEN);
        assert_eq!(tick_bits(&decoded.tick), tick_bits(&ticks[k].logged()));
    }
    // Every other message reads back whole (CDR through its decoder, the rest as JSON), and
    // a timed one carries its log time.
    let ns_of = |t_s: f64| (t_s * 1e9).round() as u64;
    for (topic, msgs) in &by_topic {
        for (ns, data) in msgs {
            let stamped_ns = match topic.as_str() {
                "/servo/tick" => continue, // above
                "/servo/state" => Some(ns_of(key_frame::decode(data).unwrap().0)),
                "/reference" => Some(ns_of(compiled::decode_reference(data).unwrap().t_s)),
                "/actors" => Some(ns_of(compiled::decode_actors(data).unwrap().0)),
                "/estimate" => Some(ns_of(plots::decode_estimate(data).unwrap().0)),
                "/command" => Some(ns_of(plots::decode_command(data).unwrap().t_s)),
                "/framing" => Some(ns_of(plots::decode_framing(data).unwrap().t_s)),
                "/measurement" => {
                    // Stamped with the tick that took the frame, after its capture.
                    let m = plots::decode_measurement(data).unwrap();
                    assert!(ns_of(m.t_s) <= *ns, "{topic}");
                    None
                }
                t if t.starts_with("/tf/") => {
                    let transforms = foxglove::decode_frame_transforms(data).unwrap();
                    Some(transforms.last().unwrap().timestamp_ns)
                }
                _ => {
                    let v: serde_json::Value = serde_json::from_slice(data).unwrap_or_else(|e| {
                        panic!("{topic}: {e}: {}", String::from_utf8_lossy(data))
                    });
                    assert!(v.is_object(), "{topic}");
                    None
                }
            };
            if let Some(stamped_ns) = stamped_ns {
                assert_eq!(stamped_ns, *ns, "{topic}");
            }
        }
    }
    let n = ticks.len();
    assert_eq!(by_topic["/servo/tick"].len(), n);
    // The plot topics at 10 Hz over 3 s (/command also on every failsafe tick and the one
    // after; /framing on ticks with framing), /measurement (the actors' raw poses) at 30 Hz
    // on ticks with a mocap frame; /servo/tick has every tick exactly.
    for topic in ["/reference", "/actors", "/estimate"] {
        let m = by_topic[topic].len();
        assert!((28..=31).contains(&m), "{m} {topic} messages");
    }
    let m = by_topic["/measurement"].len();
    assert!((85..=91).contains(&m), "{m} /measurement messages");
    let faulted = ticks.iter().filter(|t| t.output.is_err()).count();
    let commands = by_topic["/command"].len();
    assert!(
        commands > faulted && commands <= 31 + 2 * faulted,
        "{commands} /command messages"
    );
    assert_eq!(by_topic["/events"].len(), 3);
    // One topic per frame, as compile writes them: a frame is published at a 30 Hz tick
    // when it changed. The fixed camera (no gimbal pitch change) once; the drone's
    // estimate, which moves, at every 30 Hz tick over 3 s.
    assert_eq!(by_topic["/tf/camera"].len(), 1);
    let drone = by_topic["/tf/drone"].len();
    assert!((85..=91).contains(&drone), "{drone} /tf/drone messages");
    for (topic, child) in [
        ("/tf/drone", "drone"),
        ("/tf/camera", "camera"),
        ("/tf/actor/Ann", "actor/Ann"),
        ("/tf/reference", "reference"),
    ] {
        let transforms = foxglove::decode_frame_transforms(&by_topic[topic][0].1).unwrap();
        assert_eq!(transforms.last().unwrap().child_frame_id, child, "{topic}");
    }
    // The failsafe flag: set exactly on the faulted ticks (their sent command is HOVER),
    // every one of which is written, with the tick after it.
    let by_time: BTreeMap<u64, &Vec<u8>> = by_topic["/command"]
        .iter()
        .map(|(ns, data)| (*ns, data))
        .collect();
    assert_eq!(by_time.len(), commands);
    for (k, t) in ticks.iter().enumerate() {
        let ns = (t.input.t_s * 1e9).round() as u64;
        let data = by_time.get(&ns);
        if t.output.is_err() || (k > 0 && ticks[k - 1].output.is_err()) {
            assert!(data.is_some(), "tick {k}: no /command");
        }
        if let Some(data) = data {
            let c = plots::decode_command(data).unwrap();
            assert_eq!(c.failsafe, t.output.is_err(), "tick {k}");
            let sent = [
                c.command.roll_rad,
                c.command.pitch_rad,
                c.command.yaw_rate_radps,
                c.command.vz_mps,
            ];
            let expected = [
                t.command_sent.roll_rad,
                t.command_sent.pitch_rad,
                t.command_sent.yaw_rate_radps,
                t.command_sent.vz_mps,
            ];
            assert_eq!(
                sent.map(f64::to_bits),
                expected.map(f64::to_bits),
                "tick {k}"
            );
        }
    }
    // The metadata record: every header field, as JSON.
    let index = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == "dronecine.flight")
        .unwrap();
    let meta = mcap::read::metadata(&bytes, index).unwrap();
    assert_eq!(meta.metadata["script_name"], "\"orbit.psl\"");
    assert_eq!(meta.metadata["seed"], u64::MAX.to_string());
    let attachment = &summary.attachment_indexes[0];
    assert_eq!(attachment.name, "orbit.psl");
    let a = mcap::read::attachment(&bytes, attachment).unwrap();
    assert_eq!(a.data.as_ref(), header().script_text.as_bytes());
    // The header again, one JSON object under the attachment's CRC.
    let attachment = &summary.attachment_indexes[1];
    assert_eq!(
        (attachment.name.as_str(), attachment.media_type.as_str()),
        ("dronecine.flight.json", "application/json")
    );
    let a = mcap::read::attachment(&bytes, attachment).unwrap();
    let json: FlightHeader = serde_json::from_slice(&a.data).unwrap();
    assert_eq!(json, header());
    // The key frames: the start mark before the first tick, then the controller's state at
    // the start of every chunk after it, each the state after the tick before it.
    let frames = &by_topic["/servo/state"];
    assert!(key_frame::decode(&frames[0].1).unwrap().1.is_none());
    let mut with_ticks = 0;
    for index in &summary.chunk_indexes {
        let first: Vec<_> = summary
            .stream_chunk(&bytes, index)
            .unwrap()
            .map(|m| m.unwrap())
            .filter(|m| m.channel.topic.starts_with("/servo/"))
            .take(1)
            .collect();
        if let Some(m) = first.first() {
            with_ticks += 1;
            assert_eq!(
                m.channel.topic, "/servo/state",
                "a chunk starts with a key frame"
            );
        }
    }
    assert_eq!(frames.len(), with_ticks);
    for (ns, data) in &frames[1..] {
        let (t_s, state) = key_frame::decode(data).unwrap();
        let k = ticks.iter().position(|t| t.input.t_s == t_s).unwrap();
        assert_eq!((t_s * 1e9).round() as u64, *ns);
        assert!(
            state.unwrap().same_bits(&state_after(k - 1)),
            "before tick {k}"
        );
    }
}

#[test]
fn reference_actors_and_camera_are_exactly_compiles() {
    let dir = tempfile::tempdir().unwrap();
    let flight = dir.path().join("flight.mcap");
    let compiled = dir.path().join("compiled.mcap");
    let ticks: Vec<Tick> = (0..120).map(flight_tick).collect();
    write_log(&flight, &ticks, &[]);
    let names = names();
    let h = header();
    let info = RunInfo {
        script_name: &h.script_name,
        script_text: &h.script_text,
        profile_name: &h.profile_name,
        rate_hz: 100.0,
        lens: lens(),
        stage: stage(),
        actor_names: &names,
    };
    let mut w = McapWriter::create(&compiled, &info).unwrap();
    for t in &ticks {
        w.write(&t.sample, &t.actors).unwrap();
    }
    w.finish().unwrap();

    let flown = messages(&std::fs::read(&flight).unwrap());
    let compiled = messages(&std::fs::read(&compiled).unwrap());
    for topic in ["/camera", "/camera_calibration"] {
        assert_eq!(flown[topic], compiled[topic], "{topic}");
    }
    // The flight's /reference and /actors at 10 Hz: each message byte for byte compile's of
    // the same tick (same log time), a tenth of them.
    for topic in ["/reference", "/actors"] {
        let (a, b) = (&flown[topic], &compiled[topic]);
        assert!((11..=14).contains(&a.len()), "{} {topic}", a.len());
        assert_eq!(b.len(), ticks.len());
        for m in a {
            assert!(b.contains(m), "{topic} at {} ns", m.0);
        }
    }
}

#[test]
fn a_crash_loses_at_most_the_last_second() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    for n in [1usize, 99, 100, 101, 737, 1000, 1234] {
        let path = dir.path().join(format!("crash-{n}.mcap"));
        let ticks: Vec<Tick> = (0..n).map(flight_tick).collect();
        let mut w = FlightLogWriter::create(&path, &header(), &scene_of(&names)).unwrap();
        for t in &ticks {
            w.write_tick(&t.record()).unwrap();
        }
        w.write_event(&events()[0]).unwrap();
        let crash_s = ticks[n - 1].input.t_s;
        // The process dies: no finish, no drop, nothing flushed.
        std::mem::forget(w);

        let log = FlightLog::open(&path).unwrap();
        assert!(log.truncated, "{n} ticks");
        assert_eq!(log.damage.len(), 1, "{:?}", log.damage);
        assert_eq!(log.damage[0].resumed_at, None);
        assert!(log.damage[0].cut, "{:?}", log.damage);
        assert_eq!(log.first_gap(), None);
        assert_eq!(log.header, header());
        let recovered = log.ticks.len();
        let must = ticks
            .iter()
            .filter(|t| t.input.t_s <= crash_s - 1.0)
            .count();
        assert!(
            recovered >= must,
            "{n} ticks, crash at {crash_s} s: {recovered} recovered, {must} expected"
        );
        let want: Vec<LoggedTick> = ticks[..recovered].iter().map(Tick::logged).collect();
        assert_eq!(log.ticks, want, "a prefix of what was written");
    }
}

/// A crash before the first tick (waiting for the motion capture, the drone's own take-off,
/// when the flight loop records nothing but events and tells the log the time) loses at most
/// the last second: the log closes its chunks by the flight's time there too.
#[test]
fn a_crash_during_take_off_loses_at_most_the_last_second() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    for n in [1usize, 72, 73, 74, 99, 100, 101, 250, 399, 400] {
        let path = dir.path().join(format!("take-off-{n}.mcap"));
        let options = LogOptions::shoot(false);
        let mut w =
            FlightLogWriter::create_with(&path, &header(), &scene_of(&names), options).unwrap();
        let mut probes = Vec::new();
        for k in 0..n {
            let t_s = k as f64 * 0.01;
            if k % 10 == 0 {
                w.write_event(&probe(t_s)).unwrap();
                probes.push(t_s);
            }
            w.idle(t_s).unwrap();
        }
        let crash_s = (n - 1) as f64 * 0.01;
        // The process dies: no finish, no drop, nothing flushed.
        std::mem::forget(w);
        let log = FlightLog::open(&path).unwrap();
        assert!(log.truncated && log.ticks.is_empty(), "{n}");
        let kept: Vec<f64> = log.events.iter().map(|e| e.t_s).collect();
        let must = probes.iter().filter(|&&t| t <= crash_s - 1.0).count();
        assert!(kept.len() >= must, "{n} idle ticks: {kept:?}");
        assert_eq!(kept, probes[..kept.len()], "{n}: a prefix");
    }
}

/// Through `LogThread`, in real time, a take-off loses at most its last second too: the loop
/// hands the writer its ticks that record nothing, batch by batch, as it hands over ticks.
#[test]
fn a_take_off_in_real_time_through_the_log_thread_loses_at_most_the_last_second() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let path = dir.path().join("take-off.mcap");
    let w = FlightLogWriter::create_with(
        &path,
        &header(),
        &scene_of(&names),
        LogOptions::shoot(false),
    )
    .unwrap();
    let mut sink = LogThread::spawn(w, 100.0).unwrap();
    let mut probes = Vec::new();
    for k in 0..400 {
        let t_s = k as f64 * 0.01;
        if k % 10 == 0 {
            sink.event(&probe(t_s)).unwrap();
            probes.push(t_s);
        }
        sink.idle(t_s).unwrap();
        if k % 25 == 24 {
            // A quarter of a second of flight, in a fraction of one: the writer idles.
            std::thread::sleep(std::time::Duration::from_millis(30));
        }
    }
    let must = probes.iter().filter(|&&t| t <= 3.99 - 1.0).count();
    let cut = dir.path().join("cut.mcap");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
    let log = loop {
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::copy(&path, &cut).unwrap();
        let log = FlightLog::open(&cut).unwrap();
        if log.events.len() >= must || std::time::Instant::now() > deadline {
            break log;
        }
    };
    assert!(log.truncated);
    assert!(
        log.events.len() >= must,
        "{} probes recovered, {must} expected",
        log.events.len()
    );
    sink.finish().unwrap();
}

/// Through `LogThread` (as `shoot` writes), a flight in real time loses at most the last
/// second too: the writer thread keeps closed chunks for one larger write only while batches
/// wait (a flight faster than real time), and hands them to the OS before it sleeps. The
/// file is read while the thread runs, as a crash would leave it.
#[test]
fn a_flight_in_real_time_through_the_log_thread_loses_at_most_the_last_second() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let path = dir.path().join("real-time.mcap");
    let ticks: Vec<Tick> = (0..400).map(flight_tick).collect();
    let w = FlightLogWriter::create(&path, &header(), &scene_of(&names)).unwrap();
    let mut sink = LogThread::spawn(w, 100.0).unwrap();
    for (k, t) in ticks.iter().enumerate() {
        sink.tick(&t.record()).unwrap();
        if k % 25 == 24 {
            // A quarter of a second of flight, in a fraction of one: the writer idles.
            std::thread::sleep(std::time::Duration::from_millis(30));
        }
    }
    let crash_s = ticks.last().unwrap().input.t_s;
    let must = ticks
        .iter()
        .filter(|t| t.input.t_s <= crash_s - 1.0)
        .count();
    // Once the writer has caught up (no more batches come, so nothing else writes: a busy
    // machine may only delay it).
    let cut = dir.path().join("cut.mcap");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
    let log = loop {
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::copy(&path, &cut).unwrap();
        let log = FlightLog::open(&cut).unwrap();
        if log.ticks.len() >= must || std::time::Instant::now() > deadline {
            break log;
        }
    };
    assert!(log.truncated);
    assert!(
        log.ticks.len() >= must,
        "{} recovered, {must} expected",
        log.ticks.len()
    );
    let want: Vec<LoggedTick> = ticks[..log.ticks.len()].iter().map(Tick::logged).collect();
    assert_eq!(log.ticks, want, "a prefix of what was written");
    sink.finish().unwrap();
}

pub(crate) fn reference_log() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flight.mcap");
        let ticks: Vec<Tick> = (0..250).map(flight_tick).collect();
        write_log(&path, &ticks, &events());
        std::fs::read(&path).unwrap()
    })
}

/// A log cut inside its closing magic, after the footer, holds every record, but it was cut
/// short all the same: flagged as such.
#[test]
fn a_log_cut_inside_its_closing_magic_is_truncated_and_read_whole() {
    let bytes = reference_log();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.mcap");
    let whole: Vec<LoggedTick> = (0..250).map(|k| flight_tick(k).logged()).collect();
    for short in 1..=8 {
        std::fs::write(&path, &bytes[..bytes.len() - short]).unwrap();
        let log = FlightLog::open(&path).unwrap();
        assert!(log.truncated, "{short} bytes short: {:?}", log.damage);
        assert_eq!(log.ticks, whole, "{short} bytes short");
        assert_eq!(log.events.len(), events().len());
        assert!(
            log.damage.len() == 1 && log.damage[0].cut && log.damage[0].resumed_at.is_none(),
            "{short} bytes short: {:?}",
            log.damage
        );
    }
    std::fs::write(&path, bytes).unwrap();
    let log = FlightLog::open(&path).unwrap();
    assert!(!log.truncated && log.damage.is_empty(), "{:?}", log.damage);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// A log cut anywhere reads without panicking: an error before the header, else the ticks
    /// written before the cut, flagged as truncated.
    #[test]
    fn a_log_cut_anywhere_never_panics_the_reader(cut in 0.0..1.0f64) {
        let bytes = reference_log();
        let at = ((bytes.len() as f64) * cut) as usize;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.mcap");
        std::fs::write(&path, &bytes[..at]).unwrap();
        let whole: Vec<LoggedTick> = (0..250).map(|k| flight_tick(k).logged()).collect();
        match FlightLog::open(&path) {
            Ok(log) => {
                prop_assert!(log.truncated);
                prop_assert_eq!(&log.ticks[..], &whole[..log.ticks.len()]);
            }
            Err(e) => {
                prop_assert!(
                    matches!(e, LogError::NotMcap { .. } | LogError::NoHeader { .. }),
                    "{e}"
                );
                prop_assert!(e.to_string().contains("cut.mcap"));
            }
        }
    }

    /// Flipped bytes never panic the reader either, and never make it invent a tick: what it
    /// reads is what was written, less at most one run of ticks (the damaged chunk's).
    #[test]
    fn a_corrupted_log_never_panics_the_reader(at in 0.0..1.0f64, byte in any::<u8>()) {
        let mut bytes = reference_log().to_vec();
        let i = ((bytes.len() as f64) * at) as usize;
        bytes[i] ^= byte | 1;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("corrupt.mcap");
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(log) = FlightLog::open(&path) {
            let whole: Vec<LoggedTick> = (0..250).map(|k| flight_tick(k).logged()).collect();
            let n = log.ticks.len();
            let a = log.ticks.iter().zip(&whole).take_while(|(x, y)| x == y).count();
            prop_assert!(n <= whole.len());
            prop_assert_eq!(&log.ticks[a..], &whole[whole.len() - (n - a)..]);
        }
    }
}

/// Each chunk of an MCAP file: its offset, its length, and its messages' first and last log
/// times (ns), from the summary's chunk indexes (read by the mcap crate).
pub(crate) fn chunks_of(bytes: &[u8]) -> Vec<(u64, u64, u64, u64)> {
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    summary
        .chunk_indexes
        .iter()
        .map(|c| {
            (
                c.chunk_start_offset,
                c.chunk_length,
                c.message_start_time,
                c.message_end_time,
            )
        })
        .collect()
}

/// A log damaged in one chunk, in the middle: the reader skips that chunk and reads on. The
/// ticks read are the ones written less those of that chunk, the damage says where it was
/// and where reading resumed, and the footer is still found.
#[test]
fn damage_in_the_middle_costs_its_chunk_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let ticks: Vec<Tick> = (0..1000).map(flight_tick).collect();
    let whole: Vec<LoggedTick> = ticks.iter().map(Tick::logged).collect();
    for compression in [
        dronecine_mcap::log::LogCompression::None,
        dronecine_mcap::log::LogCompression::Lz4,
    ] {
        let path = dir.path().join("whole.mcap");
        let options = dronecine_mcap::log::LogOptions {
            compression,
            ..Default::default()
        };
        let mut w =
            FlightLogWriter::create_with(&path, &header(), &scene_of(&names), options).unwrap();
        for t in &ticks {
            w.write_tick(&t.record()).unwrap();
        }
        w.write_event(&events()[0]).unwrap();
        w.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let chunks = chunks_of(&bytes);
        assert!(chunks.len() >= 8, "{} chunks", chunks.len());
        let k = chunks.len() / 2;
        let (start, len, t0_ns, t1_ns) = chunks[k];

        // A flipped bit in the chunk's records (its CRC fails), or a length that runs past
        // the end of the file (its framing fails).
        let flip = |b: &mut Vec<u8>| b[(start + len / 2) as usize] ^= 0x10;
        let overrun = |b: &mut Vec<u8>| {
            let at = start as usize + 1;
            b[at..at + 8].copy_from_slice(&(u64::MAX / 4).to_le_bytes());
        };
        for (what, damage) in [
            ("a flipped bit", &flip as &dyn Fn(&mut Vec<u8>)),
            ("a wrong length", &overrun),
        ] {
            let mut bad = bytes.clone();
            damage(&mut bad);
            let path = dir.path().join("damaged.mcap");
            std::fs::write(&path, &bad).unwrap();
            let log = FlightLog::open(&path).unwrap();
            let case = format!("{compression:?}, {what}");
            assert!(!log.truncated, "{case}: {:?}", log.damage);
            assert_eq!(log.damage.len(), 1, "{case}: {:?}", log.damage);
            let d = &log.damage[0];
            assert_eq!(d.offset, start, "{case}");
            assert!(!d.cut, "{case}: corrupt, not cut");
            assert_eq!(d.resumed_at, Some(chunks[k + 1].0), "{case}");
            assert_eq!(log.first_gap(), Some(d.tick), "{case}");

            // What is missing is one run of ticks, exactly those logged inside that chunk.
            let a = d.tick;
            let lost = whole.len() - log.ticks.len();
            assert!(lost > 0, "{case}");
            assert_eq!(&log.ticks[..a], &whole[..a], "{case}");
            assert_eq!(&log.ticks[a..], &whole[a + lost..], "{case}");
            for t in &whole[a..a + lost] {
                let ns = (t.input.t_s * 1e9).round() as u64;
                assert!((t0_ns..=t1_ns).contains(&ns), "{case}: {} s", t.input.t_s);
            }
            for t in whole[..a].iter().chain(&whole[a + lost..]) {
                let ns = (t.input.t_s * 1e9).round() as u64;
                assert!(!(t0_ns..=t1_ns).contains(&ns), "{case}: {} s", t.input.t_s);
            }
            assert_eq!(log.events.len(), 1, "{case}: the event after the damage");
        }
    }
}

#[test]
fn foreign_files_are_errors_that_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = dir.path().join("garbage.mcap");
    std::fs::write(
        &garbage,
        b"this is not an MCAP file at all, just text\n".repeat(50),
    )
    .unwrap();
    let e = FlightLog::open(&garbage).unwrap_err();
    assert!(matches!(e, LogError::NotMcap { .. }), "{e:?}");
    assert!(e.to_string().contains("garbage.mcap"), "{e}");

    let empty = dir.path().join("empty.mcap");
    std::fs::write(&empty, b"").unwrap();
    assert!(FlightLog::open(&empty).is_err());

    let missing = dir.path().join("missing.mcap");
    let e = FlightLog::open(&missing).unwrap_err();
    assert!(matches!(e, LogError::Io { .. }), "{e:?}");
    assert!(e.to_string().contains("missing.mcap"), "{e}");

    // A compiled reference is MCAP but not a flight log.
    let compiled = dir.path().join("compiled.mcap");
    let names = names();
    let info = RunInfo {
        script_name: "orbit.psl",
        script_text: "",
        profile_name: "ardrone2",
        rate_hz: 100.0,
        lens: lens(),
        stage: stage(),
        actor_names: &names,
    };
    let mut w = McapWriter::create(&compiled, &info).unwrap();
    w.write(&flight_tick(0).sample, &flight_tick(0).actors)
        .unwrap();
    w.finish().unwrap();
    let e = FlightLog::open(&compiled).unwrap_err();
    assert!(matches!(e, LogError::NoHeader { .. }), "{e:?}");
    assert!(e.to_string().contains("dronecine.flight"), "{e}");
}

#[test]
fn a_missing_directory_is_an_error_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flights").join("orbit-1.mcap");
    let names = names();
    let e = match FlightLogWriter::create(&path, &header(), &scene_of(&names)) {
        Ok(_) => panic!("created a log in a missing directory"),
        Err(e) => e,
    };
    assert!(e.to_string().contains("orbit-1.mcap"), "{e}");
}

/// A probe event at flight time `t_s` (something a crash could lose).
fn probe(t_s: f64) -> Event {
    Event {
        t_s,
        level: "info".into(),
        kind: "probe".into(),
        message: String::new(),
        line: None,
        help: None,
    }
}

/// Four seconds of take-off at 100 Hz before the flight's ticks: ticks that record nothing,
/// with a probe event every tenth.
fn take_off(sink: &mut dyn FlightSink) {
    for k in 0..400 {
        let t_s = k as f64 * 0.01;
        if k % 10 == 0 {
            sink.event(&probe(t_s)).unwrap();
        }
        sink.idle(t_s).unwrap();
    }
}

/// `shoot` writes through `LogThread`: the file is the one the writer makes on the loop's own
/// thread, byte for byte (same chunks, same order of ticks, ticks that record nothing, key
/// frames and events), across several batches; and a thread dropped without `finish` (an
/// error path, a panic) still closes it.
#[test]
fn the_log_thread_writes_the_same_file_and_closes_it_when_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let ticks: Vec<Tick> = (0..1234).map(|k| flight_tick(k + 400)).collect();
    let events = events();
    let direct = dir.path().join("direct.mcap");
    {
        // As `write_log`, after the same take-off.
        let mut w = FlightLogWriter::create(&direct, &header(), &scene_of(&names)).unwrap();
        take_off(&mut w);
        for (i, t) in ticks.iter().enumerate() {
            w.write_tick(&t.record()).unwrap();
            if w.wants_key_frame() {
                w.write_key_frame(&state_after(i));
            }
            if let Some(e) = events.get(i) {
                w.write_event(e).unwrap();
            }
        }
        w.finish().unwrap();
    }
    for finish in [true, false] {
        let threaded = dir.path().join(format!("threaded-{finish}.mcap"));
        let w = FlightLogWriter::create(&threaded, &header(), &scene_of(&names)).unwrap();
        let mut sink = LogThread::spawn(w, 100.0).unwrap();
        take_off(&mut sink);
        for (i, t) in ticks.iter().enumerate() {
            sink.tick(&t.record()).unwrap();
            if sink.wants_key_frame() {
                sink.key_frame(&state_after(i)).unwrap();
            }
            if let Some(e) = events.get(i) {
                sink.event(e).unwrap();
            }
        }
        if finish {
            sink.finish().unwrap();
            assert!(std::fs::read(&threaded).unwrap() == std::fs::read(&direct).unwrap());
        } else {
            drop(sink);
            let log = FlightLog::open(&threaded).unwrap();
            assert!(!log.truncated, "{:?}", log.damage);
            assert_eq!(log.ticks.len(), ticks.len());
            assert_eq!(
                log.events.len(),
                40 + events.len(),
                "the probes and the events"
            );
        }
    }
}

/// A log whose `/servo/tick` is JSON, not CDR: replay says why it cannot read it and what to
/// do.
#[test]
fn a_json_servo_tick_from_an_older_dronecine_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("old.mcap");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let schema = w
        .add_schema("dronecine.ServoTick", "jsonschema", b"{}")
        .unwrap();
    let channel = w
        .add_channel(schema, "/servo/tick", "json", &BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 0,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, b"{}").unwrap();
    w.finish().unwrap();
    drop(w);
    let e = FlightLog::open(&path).unwrap_err().to_string();
    assert!(
        e.contains("old.mcap") && e.contains("`json`") && e.contains("older dronecine"),
        "{e}"
    );
}

/// A log whose `/servo/tick` or `/events` comes under another schema (another layout under
/// the topic's name, as a newer dronecine would write it) is refused by name, not misread.
#[test]
fn a_topic_under_another_schema_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    for (topic, schema_name, encoding) in [
        ("/servo/tick", "dronecine/msg/ServoTick2", "cdr"),
        ("/events", "dronecine.Event2", "json"),
    ] {
        let path = dir.path().join("newer.mcap");
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut w = mcap::Writer::new(file).unwrap();
        let schema = w.add_schema(schema_name, "ros2msg", b"").unwrap();
        let channel = w
            .add_channel(schema, topic, encoding, &BTreeMap::new())
            .unwrap();
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        };
        w.write_to_known_channel(&header, b"").unwrap();
        w.finish().unwrap();
        drop(w);
        let e = FlightLog::open(&path).unwrap_err().to_string();
        assert!(
            e.contains(topic) && e.contains(&format!("`{schema_name}`")),
            "{topic}: {e}"
        );
    }
}

/// A log with fixed-length ticks — `/servo/tick` the 278-byte fixed part only, the framing on
/// `/framing` (JSON) at every tick — replays: its framing is read from `/framing`.
#[test]
fn a_log_with_fixed_length_ticks_reads_its_framing_from_the_json_topic() {
    let dir = tempfile::tempdir().unwrap();
    let new = dir.path().join("new.mcap");
    let old = dir.path().join("old.mcap");
    let ticks: Vec<Tick> = (0..250).map(flight_tick).collect();
    write_log(&new, &ticks, &[]);

    // Rewrite it in that format.
    let bytes = std::fs::read(&new).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let meta_index = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == "dronecine.flight")
        .unwrap();
    let meta = mcap::read::metadata(&bytes, meta_index).unwrap();
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&old).unwrap(),
    ))
    .unwrap();
    w.write_metadata(&meta).unwrap();
    let tick_schema = w
        .add_schema(
            cdr::SCHEMA_NAME,
            cdr::SCHEMA_ENCODING,
            cdr::SCHEMA.as_bytes(),
        )
        .unwrap();
    let tick_channel = w
        .add_channel(tick_schema, "/servo/tick", "cdr", &BTreeMap::new())
        .unwrap();
    let framing_schema = w
        .add_schema("dronecine.Framing", "jsonschema", b"{}")
        .unwrap();
    let framing_channel = w
        .add_channel(framing_schema, "/framing", "json", &BTreeMap::new())
        .unwrap();
    let mut framed = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic != "/servo/tick" {
            continue;
        }
        let tick = cdr::decode(&m.data).unwrap().tick;
        let header = |channel_id| mcap::records::MessageHeader {
            channel_id,
            sequence: 0,
            log_time: m.log_time,
            publish_time: m.log_time,
        };
        if !tick.framing.is_empty() {
            let point = |p: Option<[f64; 2]>| p.map(|p| p.to_vec());
            let actors: Vec<serde_json::Value> = tick
                .framing
                .iter()
                .map(|f| {
                    serde_json::json!({"actor": f.actor, "name": "x",
                        "screen": point(f.screen), "requested": point(f.requested)})
                })
                .collect();
            let json = serde_json::json!({"t_s": tick.input.t_s, "shot": tick.shot,
                "actors": actors});
            w.write_to_known_channel(&header(framing_channel), json.to_string().as_bytes())
                .unwrap();
            framed += 1;
        }
        w.write_to_known_channel(&header(tick_channel), &m.data[..cdr::FIXED_LEN])
            .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    assert!(framed > 200);

    let (a, b) = (
        FlightLog::open(&new).unwrap(),
        FlightLog::open(&old).unwrap(),
    );
    assert!(!b.truncated, "{:?}", b.damage);
    assert_eq!(a.ticks.len(), b.ticks.len());
    for (x, y) in a.ticks.iter().zip(&b.ticks) {
        assert_eq!(tick_bits(y), {
            let mut old_form = x.clone();
            old_form.actors.clear();
            tick_bits(&old_form)
        });
    }
    // The framing came from /framing (the ticks carry none), and it is the same.
    assert!(b.ticks.iter().filter(|t| !t.framing.is_empty()).count() == framed);
    assert!(b.ticks.iter().all(|t| t.actors.is_empty()));
}

/// A short LZ4 log decompresses to more than its file's length: still read whole.
#[test]
fn a_short_compressed_log_reads_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lz4.mcap");
    let names = names();
    let options = dronecine_mcap::log::LogOptions {
        compression: dronecine_mcap::log::LogCompression::Lz4,
        ..Default::default()
    };
    let ticks: Vec<Tick> = (0..150).map(flight_tick).collect();
    let mut w = FlightLogWriter::create_with(&path, &header(), &scene_of(&names), options).unwrap();
    for t in &ticks {
        w.write_tick(&t.record()).unwrap();
    }
    w.finish().unwrap();
    let log = FlightLog::open(&path).unwrap();
    assert!(!log.truncated, "{:?}", log.damage);
    assert_eq!(log.ticks.len(), ticks.len());
}

/// A log not forced to the disk (`shoot`'s for a simulated flight) is the same file as one that
/// is, through the log thread as `shoot` writes them: only the durable one gets a handle for
/// its syncer.
#[test]
fn a_log_not_forced_to_the_disk_is_the_same_file() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let ticks: Vec<Tick> = (0..600).map(flight_tick).collect();
    let mut files = Vec::new();
    for durable in [true, false] {
        let path = dir.path().join(format!("durable-{durable}.mcap"));
        let options = LogOptions::shoot(durable);
        assert_eq!(options.durable, durable);
        let w = FlightLogWriter::create_with(&path, &header(), &scene_of(&names), options).unwrap();
        assert_eq!(w.sync_handle().is_some(), durable);
        let mut sink = LogThread::spawn(w, 100.0).unwrap();
        for t in &ticks {
            sink.tick(&t.record()).unwrap();
        }
        sink.finish().unwrap();
        let log = FlightLog::open(&path).unwrap();
        assert!(!log.truncated, "{:?}", log.damage);
        assert_eq!(log.ticks.len(), ticks.len());
        files.push(std::fs::read(&path).unwrap());
    }
    assert!(files[0] == files[1], "the same bytes either way");
}

/// The log's writer and syncer lower their own priority (nice +10, clamped at 19) so that the
/// loop comes first when every core is busy; the loop's thread keeps its own.
#[cfg(target_os = "linux")]
#[test]
fn the_log_threads_yield_to_the_loop() {
    // Field 19 of a task's `stat` (the 17th after the command name's closing parenthesis).
    fn nice(stat_path: &Path) -> Option<i64> {
        let stat = std::fs::read_to_string(stat_path).ok()?;
        stat.get(stat.rfind(')')? + 2..)?
            .split_whitespace()
            .nth(16)?
            .parse()
            .ok()
    }
    /// The nice values of this process's log threads (other tests' included), by name.
    fn log_threads() -> Vec<(String, i64)> {
        let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
            return Vec::new();
        };
        tasks
            .flatten()
            .filter_map(|t| {
                let comm = std::fs::read_to_string(t.path().join("comm")).ok()?;
                let comm = comm.trim().to_string();
                comm.starts_with("flight-log")
                    .then(|| Some((comm, nice(&t.path().join("stat"))?)))?
            })
            .collect()
    }
    let own = nice(Path::new("/proc/thread-self/stat")).expect("this thread's nice value");
    let expected = (own + 10).min(19);
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let w = FlightLogWriter::create(&dir.path().join("nice.mcap"), &header(), &scene_of(&names))
        .unwrap();
    let sink = LogThread::spawn(w, 100.0).unwrap();
    // Each thread lowers its priority as it starts: wait for it (and for any other test's).
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
    let threads = loop {
        let threads = log_threads();
        let names: BTreeSet<&str> = threads.iter().map(|(n, _)| n.as_str()).collect();
        let both = names.contains("flight-log") && names.contains("flight-log-sync");
        if both && threads.iter().all(|&(_, n)| n == expected) {
            break threads;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "log threads {threads:?}, expected nice {expected} (this thread's {own})"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    assert_eq!(
        nice(Path::new("/proc/thread-self/stat")),
        Some(own),
        "the loop's thread keeps its priority ({threads:?})"
    );
    sink.finish().unwrap();
}

/// The log reserves its disk space ahead of its writes (Linux: `fallocate`, the size kept)
/// and a finished log gives back what it did not use: its size is its data, and it holds
/// no more disk than that. A log cut by a crash keeps its size too (it reads whole), with
/// at most the reservation step allocated beyond it.
#[cfg(target_os = "linux")]
#[test]
fn a_log_holds_the_disk_it_uses_once_finished() {
    use std::os::unix::fs::MetadataExt;
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let ticks: Vec<Tick> = (0..18_000).map(flight_tick).collect();
    let allocated = |path: &Path| std::fs::metadata(path).unwrap().blocks() * 512;
    let size = |path: &Path| std::fs::metadata(path).unwrap().len();

    let cut = dir.path().join("cut.mcap");
    let mut w = FlightLogWriter::create(&cut, &header(), &scene_of(&names)).unwrap();
    for t in &ticks {
        w.write_tick(&t.record()).unwrap();
    }
    // Nothing past the data is readable: the size is what was written.
    let written = size(&cut);
    assert!(
        written > 8 << 20,
        "{written} bytes: more than one reservation step"
    );
    let reserved = allocated(&cut);
    std::mem::forget(w); // a crash
    assert!(
        reserved <= written + (8 << 20) + (1 << 20),
        "{reserved} for {written}"
    );
    let log = FlightLog::open(&cut).unwrap();
    assert!(log.truncated);
    assert!(log.ticks.len() >= ticks.len() - 100, "{}", log.ticks.len());

    let whole = dir.path().join("whole.mcap");
    let mut w = FlightLogWriter::create(&whole, &header(), &scene_of(&names)).unwrap();
    for t in &ticks[..2_000] {
        w.write_tick(&t.record()).unwrap();
    }
    w.finish().unwrap();
    let (len, blocks) = (size(&whole), allocated(&whole));
    assert!(
        blocks <= len.next_multiple_of(64 << 10),
        "a finished log of {len} bytes holds {blocks} bytes of disk"
    );
    assert!(!FlightLog::open(&whole).unwrap().truncated);
}
