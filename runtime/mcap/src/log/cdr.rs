//! `/servo/tick` in CDR (OMG XCDR1, little-endian, the encoding of ROS 2 messages), with a
//! `ros2msg` schema Foxglove decodes: every field replay needs, the actors as the director saw
//! them and the framing, every float bit for bit (NaN payloads and `-0.0` included): 514
//! bytes a tick with two actors framed.
//!
//! The message is a 4-byte encapsulation header (`00 01 00 00`: CDR, little-endian), a fixed
//! part of 274 bytes, then two sequences (a `uint32` count, then the elements). Every field is
//! aligned to its size from the end of the header: the fixed part's 64-bit floats come first,
//! so it needs no padding (offsets in [`SCHEMA`]); the actors' count sits at 276 after two
//! bytes of padding, the actors from 280 (72 bytes each); the framing's count follows them, and
//! each framing element starts at the next multiple of 8 (40 bytes apart, the last one 38).
//! A field that is absent (no measurement, a faulted tick's output, no latency, an actor
//! behind the camera) is zero with its flag clear.
//!
//! A message of exactly [`FIXED_LEN`] bytes is a fixed-length tick, without the two
//! sequences: its log has the framing on the JSON `/framing` topic at every tick. [`decode`]
//! reads it with empty sequences and says so.

use crate::record::{FramingRecord, Phase, TickRecord};
use dronecine_backend::frames::Command;
use dronecine_backend::FlightState;
use dronecine_compiler::reference::ActorPose;
use dronecine_servo::control::{
    Estimate, Measurement, Reference, TickFault, TickInput, TickOutput,
};

use super::LoggedTick;
// The encapsulation header and the MCAP encodings: one source, the compiler's CDR writer.
use crate::output::cdr::HEADER;
pub use crate::output::cdr::{MESSAGE_ENCODING, SCHEMA_ENCODING};

/// The schema's name (ROS 2 style, as Foxglove expects for `ros2msg`).
pub const SCHEMA_NAME: &str = "dronecine/msg/ServoTick";

/// The `ros2msg` definition; the comments give each field's byte offset after the header.
pub const SCHEMA: &str = "\
# One control tick, exactly: what dronecine replay re-runs. CDR little-endian; each float is
# the IEEE 754 value the controller saw or produced, bit for bit.
uint8 PHASE_TAKE_OFF=0
uint8 PHASE_APPROACH=1
uint8 PHASE_SHOTS=2
uint8 PHASE_LANDING=3
uint8 FAULT_NONE=0
uint8 FAULT_NOT_FINITE=1
uint8 FAULT_TIME_NOT_INCREASING=2
uint8 DRONE_LANDED=0
uint8 DRONE_TAKING_OFF=1
uint8 DRONE_FLYING=2
uint8 DRONE_LANDING=3
uint8 DRONE_EMERGENCY=4
float64 t_s                          # 0: flight clock
float64 dt_s                         # 8: measured time since the previous tick
float64[3] measurement_position_m    # 16 (zero unless has_measurement)
float64 measurement_heading_rad      # 40
float64[3] reference_position_m      # 48
float64[3] reference_velocity_mps    # 72
float64[3] reference_acceleration_mps2 # 96
float64 reference_heading_rad        # 120
float64 reference_heading_rate_radps # 128
float64 command_roll_rad             # 136: the controller's command (zero when faulted)
float64 command_pitch_rad            # 144
float64 command_yaw_rate_radps       # 152
float64 command_vz_mps               # 160
float64[3] estimate_position_m       # 168
float64[3] estimate_velocity_mps     # 192
float64 estimate_heading_rad         # 216
float64 sent_roll_rad                # 224: the command sent to the drone
float64 sent_pitch_rad               # 232
float64 sent_yaw_rate_radps          # 240
float64 sent_vz_mps                  # 248
float64 latency_s                    # 256: mocap frame arrival to command sent
int32 shot                           # 264: index in the timeline, -1 outside the shots
uint8 phase                          # 268
uint8 fault                          # 269: FAULT_NONE when the controller answered
uint8 drone_state                    # 270
bool has_measurement                 # 271
bool saturated                       # 272
bool has_latency                     # 273
dronecine/ActorPose[] actors         # 276: count; from 280, 72 bytes each
dronecine/FramedActor[] framing      # count after the actors; elements 8-aligned, 40 bytes apart
================================================================================
MSG: dronecine/ActorPose
# An actor as the director saw it this tick (tracked pose and velocity).
float64[3] position_m                # feet on the floor
float64[3] velocity_mps
float64 facing_rad                   # counter-clockwise from +x
float64 facing_rate_radps
float64 height_m
================================================================================
MSG: dronecine/FramedActor
# Where an actor is on screen and where the script puts it (holds only).
float64[2] screen                    # zero unless has_screen (the actor is in front of the camera)
float64[2] requested                 # zero unless has_requested
uint32 actor                         # index in the scene's actors
bool has_screen
bool has_requested
";

/// Bytes of the fixed part, header included (a message with no actors and no framing is 8
/// bytes longer: the two counts).
pub const FIXED_LEN: usize = 4 + 274;
/// Bytes of one actor in the `actors` sequence.
const ACTOR_LEN: usize = 72;
/// Bytes from one framing element to the next (the last one is 2 shorter).
const FRAMED_STRIDE: usize = 40;
const FRAMED_LEN: usize = 38;

/// Appends the CDR message of `tick` to `buf`.
pub fn encode(buf: &mut Vec<u8>, tick: &TickRecord) {
    let mut out = [0u8; FIXED_LEN];
    out[..4].copy_from_slice(&HEADER);
    let mut at = 4;
    let mut f = |x: f64| {
        out[at..at + 8].copy_from_slice(&x.to_le_bytes());
        at += 8;
    };
    let i = &tick.input;
    f(i.t_s);
    f(i.dt_s);
    let m = i.measurement.unwrap_or_default();
    m.position_m.iter().for_each(|&x| f(x));
    f(m.heading_rad);
    let r = &i.reference;
    r.position_m.iter().for_each(|&x| f(x));
    r.velocity_mps.iter().for_each(|&x| f(x));
    r.acceleration_mps2.iter().for_each(|&x| f(x));
    f(r.heading_rad);
    f(r.heading_rate_radps);
    let o = tick.output.unwrap_or_default();
    let command = |c: &Command, f: &mut dyn FnMut(f64)| {
        f(c.roll_rad);
        f(c.pitch_rad);
        f(c.yaw_rate_radps);
        f(c.vz_mps);
    };
    command(&o.command, &mut f);
    o.estimate.position_m.iter().for_each(|&x| f(x));
    o.estimate.velocity_mps.iter().for_each(|&x| f(x));
    f(o.estimate.heading_rad);
    command(&tick.command_sent, &mut f);
    f(tick.latency_s.unwrap_or(0.0));
    debug_assert_eq!(at, 4 + 264);
    let shot = tick.shot.and_then(|s| i32::try_from(s).ok()).unwrap_or(-1);
    out[268..272].copy_from_slice(&shot.to_le_bytes());
    out[272] = match tick.phase {
        Phase::TakeOff => 0,
        Phase::Approach => 1,
        Phase::Shots => 2,
        Phase::Landing => 3,
    };
    out[273] = match tick.output {
        Ok(_) => 0,
        Err(TickFault::NotFinite) => 1,
        Err(TickFault::TimeNotIncreasing) => 2,
    };
    out[274] = match tick.drone_state {
        FlightState::Landed => 0,
        FlightState::TakingOff => 1,
        FlightState::Flying => 2,
        FlightState::Landing => 3,
        FlightState::Emergency => 4,
    };
    out[275] = u8::from(i.measurement.is_some());
    out[276] = u8::from(o.saturated);
    out[277] = u8::from(tick.latency_s.is_some());
    buf.extend_from_slice(&out);
    encode_sequences(buf, tick);
}

/// Appends the actors and the framing after the fixed part (which `buf` ends with).
fn encode_sequences(buf: &mut Vec<u8>, tick: &TickRecord) {
    let origin = buf.len() - (FIXED_LEN - 4);
    let align = |buf: &mut Vec<u8>, to: usize| {
        let pad = (to - (buf.len() - origin) % to) % to;
        buf.extend_from_slice(&[0u8; 8][..pad]);
    };
    let count = |buf: &mut Vec<u8>, n: usize| {
        align(buf, 4);
        buf.extend_from_slice(&u32::try_from(n).unwrap_or(u32::MAX).to_le_bytes());
    };
    // Each element filled in a stack array of its constant length and appended whole: one
    // capacity check per element rather than one per field.
    let floats = |e: &mut [u8], xs: &[f64]| {
        for (k, x) in xs.iter().enumerate() {
            e[8 * k..8 * k + 8].copy_from_slice(&x.to_le_bytes());
        }
    };
    count(buf, tick.actors.len());
    for a in tick.actors {
        align(buf, 8);
        let mut e = [0u8; ACTOR_LEN];
        let (p, v) = (&a.position_m, &a.velocity_mps);
        let xs = [
            p[0],
            p[1],
            p[2],
            v[0],
            v[1],
            v[2],
            a.facing_rad,
            a.facing_rate_radps,
            a.height_m,
        ];
        floats(&mut e, &xs);
        buf.extend_from_slice(&e);
    }
    count(buf, tick.framing.len());
    for f in tick.framing {
        align(buf, 8);
        let mut e = [0u8; FRAMED_LEN];
        let (s, r) = (
            f.screen.unwrap_or_default(),
            f.requested.unwrap_or_default(),
        );
        floats(&mut e, &[s[0], s[1], r[0], r[1]]);
        e[32..36].copy_from_slice(&u32::try_from(f.actor).unwrap_or(u32::MAX).to_le_bytes());
        e[36] = u8::from(f.screen.is_some());
        e[37] = u8::from(f.requested.is_some());
        buf.extend_from_slice(&e);
    }
}

/// Reads a message written by [`encode`] (or a fixed-length one: see the module doc,
/// then `extended` is false); a message that is cut or too long, of another encapsulation, or
/// with an unknown enum value or an impossible count, is an error that says which.
pub fn decode(data: &[u8]) -> Result<Decoded, String> {
    if data.len() < FIXED_LEN {
        return Err(format!(
            "a CDR /servo/tick message is at least {FIXED_LEN} bytes, this one {}",
            data.len()
        ));
    }
    if data[..4] != HEADER {
        return Err(format!(
            "CDR encapsulation {:02x?}, expected {HEADER:02x?} (little-endian CDR)",
            &data[..4]
        ));
    }
    let f = |i: usize| {
        let at = 4 + 8 * i;
        f64::from_le_bytes(data[at..at + 8].try_into().expect("8 bytes"))
    };
    let v3 = |i: usize| [f(i), f(i + 1), f(i + 2)];
    let cmd = |i: usize| Command {
        roll_rad: f(i),
        pitch_rad: f(i + 1),
        yaw_rate_radps: f(i + 2),
        vz_mps: f(i + 3),
    };
    let flag = |at: usize, name: &str| bool_of(data[at], name);
    let shot = i32::from_le_bytes(data[268..272].try_into().expect("4 bytes"));
    let phase = match data[272] {
        0 => Phase::TakeOff,
        1 => Phase::Approach,
        2 => Phase::Shots,
        3 => Phase::Landing,
        b => return Err(format!("unknown phase {b}")),
    };
    let fault = match data[273] {
        0 => None,
        1 => Some(TickFault::NotFinite),
        2 => Some(TickFault::TimeNotIncreasing),
        b => return Err(format!("unknown fault {b}")),
    };
    if data[274] > 4 {
        return Err(format!("unknown drone state {}", data[274]));
    }
    let input = TickInput {
        t_s: f(0),
        dt_s: f(1),
        measurement: flag(275, "has_measurement")?.then(|| Measurement {
            position_m: v3(2),
            heading_rad: f(5),
        }),
        reference: Reference {
            position_m: v3(6),
            velocity_mps: v3(9),
            acceleration_mps2: v3(12),
            heading_rad: f(15),
            heading_rate_radps: f(16),
        },
    };
    let saturated = flag(276, "saturated")?;
    let output = match fault {
        None => Ok(TickOutput {
            command: cmd(17),
            estimate: Estimate {
                position_m: v3(21),
                velocity_mps: v3(24),
                heading_rad: f(27),
            },
            saturated,
        }),
        Some(fault) => Err(fault),
    };
    let mut tick = LoggedTick {
        phase,
        shot: usize::try_from(shot).ok(),
        input,
        output,
        command_sent: cmd(28),
        actors: Vec::new(),
        framing: Vec::new(),
        latency_s: flag(277, "has_latency")?.then(|| f(32)),
    };
    let extended = data.len() > FIXED_LEN;
    if extended {
        decode_sequences(&data[4..], &mut tick)?;
    }
    Ok(Decoded { tick, extended })
}

/// A CDR `bool` (one byte, 0 or 1); another value is damage, named by its field.
fn bool_of(b: u8, name: &str) -> Result<bool, String> {
    match b {
        0 => Ok(false),
        1 => Ok(true),
        b => Err(format!("`{name}` is {b}, not a bool")),
    }
}

/// A decoded `/servo/tick`.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    pub tick: LoggedTick,
    /// The message has the actors and framing sequences (else it is a fixed-length tick,
    /// whose framing is on `/framing`).
    pub extended: bool,
}

/// Reads the two sequences after the fixed part; `body` is the message after its header.
fn decode_sequences(body: &[u8], tick: &mut LoggedTick) -> Result<(), String> {
    let mut at = FIXED_LEN - 4;
    let align = |at: &mut usize, to: usize| *at = at.div_ceil(to) * to;
    let take = |at: &mut usize, n: usize, what: &str| -> Result<std::ops::Range<usize>, String> {
        let r = *at..*at + n;
        if r.end > body.len() {
            return Err(format!(
                "the message ends at byte {} in {what} (it needs {} bytes)",
                body.len() + 4,
                r.end + 4
            ));
        }
        *at = r.end;
        Ok(r)
    };
    let f = |r: &std::ops::Range<usize>, i: usize| {
        let s = r.start + 8 * i;
        f64::from_le_bytes(body[s..s + 8].try_into().expect("8 bytes"))
    };
    let count = |at: &mut usize, what: &str, each: usize| -> Result<usize, String> {
        align(at, 4);
        let r = take(at, 4, what)?;
        let n = u32::from_le_bytes(body[r].try_into().expect("4 bytes")) as usize;
        // Each element takes at least `each - 7` bytes: a count the rest cannot hold is damage
        // (and is refused before anything is allocated for it).
        if n.saturating_mul(each - 7) > body.len() - *at {
            return Err(format!(
                "{what}: a count of {n} in a message of {} bytes",
                body.len() + 4
            ));
        }
        Ok(n)
    };
    let n = count(&mut at, "the actors' count", ACTOR_LEN)?;
    tick.actors.reserve_exact(n);
    for _ in 0..n {
        align(&mut at, 8);
        let r = take(&mut at, ACTOR_LEN, "an actor")?;
        tick.actors.push(ActorPose {
            position_m: [f(&r, 0), f(&r, 1), f(&r, 2)],
            velocity_mps: [f(&r, 3), f(&r, 4), f(&r, 5)],
            facing_rad: f(&r, 6),
            facing_rate_radps: f(&r, 7),
            height_m: f(&r, 8),
        });
    }
    let n = count(&mut at, "the framing's count", FRAMED_STRIDE)?;
    tick.framing.reserve_exact(n);
    for _ in 0..n {
        align(&mut at, 8);
        let r = take(&mut at, FRAMED_LEN, "a framing element")?;
        let actor = u32::from_le_bytes(body[r.start + 32..r.start + 36].try_into().expect("4"));
        let screen = bool_of(body[r.start + 36], "has_screen")?;
        let requested = bool_of(body[r.start + 37], "has_requested")?;
        tick.framing.push(FramingRecord {
            actor: actor as usize,
            screen: screen.then(|| [f(&r, 0), f(&r, 1)]),
            requested: requested.then(|| [f(&r, 2), f(&r, 3)]),
        });
    }
    if at != body.len() {
        return Err(format!(
            "{} bytes after the framing (the message is {} bytes, its fields end at {})",
            body.len() - at,
            body.len() + 4,
            at + 4
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_compiler::reference::Sample;

    fn record<'a>(sample: &'a Sample, output: Result<TickOutput, TickFault>) -> TickRecord<'a> {
        TickRecord {
            phase: Phase::Shots,
            shot: Some(3),
            sample,
            input: TickInput {
                t_s: 12.5,
                dt_s: 0.01,
                measurement: Some(Measurement {
                    position_m: [1.0, -2.0, 1.5],
                    heading_rad: -0.0,
                }),
                reference: Reference {
                    position_m: [1.0, 2.0, 3.0],
                    velocity_mps: [0.1, 0.2, 0.3],
                    acceleration_mps2: [f64::from_bits(0x7ff8_0000_0000_0abc), 0.0, 5e-324],
                    heading_rad: std::f64::consts::PI,
                    heading_rate_radps: f64::NEG_INFINITY,
                },
            },
            output,
            command_sent: Command {
                roll_rad: 0.01,
                pitch_rad: -0.02,
                yaw_rate_radps: 0.3,
                vz_mps: -0.4,
            },
            mocap: None,
            actors: &[],
            framing: &[],
            drone_state: FlightState::Flying,
            latency_s: Some(2.5e-5),
            gimbal: None,
        }
    }

    fn sample() -> Sample {
        Sample::default()
    }

    /// The byte layout, field by field, against offsets written out by hand from the schema.
    #[test]
    fn the_layout_is_the_schemas() {
        let s = sample();
        let out = TickOutput {
            command: Command {
                roll_rad: 0.5,
                pitch_rad: 0.25,
                yaw_rate_radps: -1.0,
                vz_mps: 2.0,
            },
            estimate: Estimate {
                position_m: [7.0, 8.0, 9.0],
                velocity_mps: [-1.0, -2.0, -3.0],
                heading_rad: 0.75,
            },
            saturated: true,
        };
        let mut buf = Vec::new();
        encode(&mut buf, &record(&s, Ok(out)));
        // The fixed part and two empty sequences.
        assert_eq!(buf.len(), 278 + 2 + 4 + 4);
        assert_eq!(&buf[278..], &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(&buf[..4], &[0, 1, 0, 0]);
        let at = |off: usize| f64::from_le_bytes(buf[4 + off..12 + off].try_into().unwrap());
        assert_eq!(at(0), 12.5);
        assert_eq!(at(8), 0.01);
        assert_eq!(at(24), -2.0);
        assert_eq!(at(40).to_bits(), (-0.0f64).to_bits());
        assert_eq!(at(48), 1.0);
        assert_eq!(at(96).to_bits(), 0x7ff8_0000_0000_0abc);
        assert_eq!(at(112).to_bits(), 1); // the smallest subnormal
        assert_eq!(at(128), f64::NEG_INFINITY);
        assert_eq!(at(136), 0.5);
        assert_eq!(at(160), 2.0);
        assert_eq!(at(168), 7.0);
        assert_eq!(at(208), -3.0);
        assert_eq!(at(216), 0.75);
        assert_eq!(at(224), 0.01);
        assert_eq!(at(248), -0.4);
        assert_eq!(at(256), 2.5e-5);
        assert_eq!(&buf[4 + 264..4 + 268], &3i32.to_le_bytes());
        assert_eq!(&buf[4 + 268..4 + 274], &[2, 0, 2, 1, 1, 1]);
        // The schema's comments give the same offsets.
        for (field, off) in [
            ("float64 estimate_heading_rad", 216),
            ("float64 latency_s", 256),
            ("int32 shot", 264),
            ("bool has_latency", 273),
        ] {
            let line = SCHEMA.lines().find(|l| l.starts_with(field)).unwrap();
            assert!(line.contains(&format!("# {off}")), "{line}");
        }
    }

    const ACTORS: [ActorPose; 2] = [
        ActorPose {
            position_m: [1.0, 2.0, 0.0],
            velocity_mps: [0.5, -0.5, 0.0],
            facing_rad: 0.25,
            facing_rate_radps: -0.125,
            height_m: 1.8,
        },
        ActorPose {
            position_m: [-1.0, 0.0, 0.0],
            velocity_mps: [0.0; 3],
            facing_rad: -0.0,
            facing_rate_radps: 0.0,
            height_m: 1.65,
        },
    ];
    const FRAMING: [FramingRecord; 2] = [
        FramingRecord {
            actor: 0,
            screen: Some([-0.33, 0.1]),
            requested: Some([-1.0 / 3.0, 0.0]),
        },
        FramingRecord {
            actor: 1,
            screen: None,
            requested: Some([1.0 / 3.0, 0.0]),
        },
    ];

    /// A tick with both actors and their framing, encoded.
    fn with_sequences() -> Vec<u8> {
        let s = sample();
        let mut r = record(&s, Ok(TickOutput::default()));
        r.actors = &ACTORS;
        r.framing = &FRAMING;
        let mut buf = Vec::new();
        encode(&mut buf, &r);
        buf
    }

    /// The sequences' layout: counts aligned to 4, elements to 8, from the end of the header
    /// (offsets written out by hand from the CDR rules).
    #[test]
    fn the_sequences_layout_is_the_schemas() {
        let buf = with_sequences();
        let body = &buf[4..];
        let f = |off: usize| f64::from_le_bytes(body[off..off + 8].try_into().unwrap());
        let u = |off: usize| u32::from_le_bytes(body[off..off + 4].try_into().unwrap());
        assert_eq!(&body[274..276], &[0, 0], "padding to the count");
        assert_eq!(u(276), 2);
        // Actor 0 at 280, actor 1 at 352 (72 bytes each).
        assert_eq!(f(280), 1.0);
        assert_eq!(f(280 + 24), 0.5);
        assert_eq!(f(280 + 48), 0.25);
        assert_eq!(f(280 + 56), -0.125);
        assert_eq!(f(280 + 64), 1.8);
        assert_eq!(f(352), -1.0);
        assert_eq!(f(352 + 48).to_bits(), (-0.0f64).to_bits());
        assert_eq!(f(352 + 64), 1.65);
        // The framing's count right after (424, 4-aligned), its first element at 432.
        assert_eq!(u(424), 2);
        assert_eq!(&body[428..432], &[0; 4]);
        assert_eq!(f(432), -0.33);
        assert_eq!(f(432 + 16), -1.0 / 3.0);
        assert_eq!(u(432 + 32), 0);
        assert_eq!(&body[432 + 36..432 + 40], &[1, 1, 0, 0]);
        // The second at 472: no screen (zeros, flag clear).
        assert_eq!(f(472), 0.0);
        assert_eq!(f(472 + 16), 1.0 / 3.0);
        assert_eq!(u(472 + 32), 1);
        assert_eq!(&body[472 + 36..], &[0, 1]);
        assert_eq!(buf.len(), 514);
        let back = decode(&buf).unwrap();
        assert!(back.extended);
        assert_eq!(back.tick.actors, ACTORS);
        assert_eq!(back.tick.framing, FRAMING);
    }

    /// A fixed-length tick (the fixed part only) reads, with empty sequences.
    #[test]
    fn a_fixed_length_tick_of_an_older_log_reads() {
        let buf = with_sequences();
        let old = decode(&buf[..FIXED_LEN]).unwrap();
        assert!(!old.extended);
        assert!(old.tick.actors.is_empty() && old.tick.framing.is_empty());
        let new = decode(&buf).unwrap().tick;
        assert_eq!(old.tick.input.t_s, new.input.t_s);
        assert_eq!(old.tick.command_sent, new.command_sent);
        assert_eq!(old.tick.output, new.output);
    }

    #[test]
    fn a_tick_round_trips_bit_for_bit() {
        let s = sample();
        for output in [
            Ok(TickOutput::default()),
            Err(TickFault::NotFinite),
            Err(TickFault::TimeNotIncreasing),
        ] {
            let mut r = record(&s, output);
            for (shot, latency, measured) in [(Some(3), Some(1e-4), true), (None, None, false)] {
                r.shot = shot;
                r.latency_s = latency;
                if !measured {
                    r.input.measurement = None;
                }
                let mut buf = Vec::new();
                encode(&mut buf, &r);
                let back = decode(&buf).unwrap().tick;
                assert_eq!(back.shot, shot);
                assert_eq!(back.latency_s, latency);
                assert_eq!(back.output, output);
                assert_eq!(back.input.measurement, r.input.measurement);
                let a = back.input.reference.acceleration_mps2[0];
                assert_eq!(a.to_bits(), 0x7ff8_0000_0000_0abc);
                assert_eq!(back.command_sent, r.command_sent);
            }
        }
    }

    #[test]
    fn damaged_messages_are_errors() {
        let buf = with_sequences();
        assert!(decode(&buf[..100])
            .unwrap_err()
            .contains("at least 278 bytes"));
        // Cut anywhere in the sequences.
        for len in [FIXED_LEN + 1, FIXED_LEN + 5, 300, 431, 440, 513] {
            let e = decode(&buf[..len]).unwrap_err();
            assert!(
                e.contains("ends at byte") || e.contains("a count of"),
                "{len}: {e}"
            );
        }
        let mut long = buf.clone();
        long.push(0);
        assert!(decode(&long)
            .unwrap_err()
            .contains("1 bytes after the framing"));
        // A count the message cannot hold is refused before anything is allocated for it.
        let mut huge = buf.clone();
        huge[4 + 276..4 + 280].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode(&huge).unwrap_err().contains("a count of 4294967295"));
        let mut bad_flag = buf.clone();
        bad_flag[4 + 432 + 36] = 2;
        assert!(decode(&bad_flag).unwrap_err().contains("has_screen"));
        let mut big_endian = buf.clone();
        big_endian[1] = 0;
        assert!(decode(&big_endian).unwrap_err().contains("encapsulation"));
        for (at, what) in [
            (272, "phase"),
            (273, "fault"),
            (274, "drone state"),
            (275, "bool"),
        ] {
            let mut bad = buf.clone();
            bad[at] = 9;
            assert!(decode(&bad).unwrap_err().contains(what), "{at}");
        }
    }
}
