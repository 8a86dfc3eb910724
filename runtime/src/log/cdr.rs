//! `/servo/tick` in CDR (OMG XCDR1, little-endian, the encoding of ROS 2 messages), with a
//! `ros2msg` schema Foxglove decodes: every field replay needs, every float bit for bit
//! (NaN payloads and `-0.0` included), 278 bytes a tick where the JSON form took about 1.1 kB.
//!
//! The message is a 4-byte encapsulation header (`00 01 00 00`: CDR, little-endian) and a
//! fixed layout, the fields in [`SCHEMA`]'s order, each aligned to its size from the end of the
//! header. The 64-bit floats come first, so no padding is needed: offsets in [`SCHEMA`].
//! A field that is absent (no measurement, a faulted tick's output, no latency) is zero with
//! its flag clear.

use crate::backend::FlightState;
use crate::control::{Estimate, Measurement, Reference, TickFault, TickInput, TickOutput};
use crate::frames::Command;
use crate::record::{Phase, TickRecord};

use super::LoggedTick;

/// The schema's name (ROS 2 style, as Foxglove expects for `ros2msg`).
pub const SCHEMA_NAME: &str = "dronecine/msg/ServoTick";
pub const SCHEMA_ENCODING: &str = "ros2msg";
pub const MESSAGE_ENCODING: &str = "cdr";

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
";

/// Bytes of one message, header included.
pub const LEN: usize = 4 + 274;
const HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Appends the CDR message of `tick` to `buf`.
pub fn encode(buf: &mut Vec<u8>, tick: &TickRecord) {
    let mut out = [0u8; LEN];
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
}

/// Reads a message written by [`encode`]; a message of another length or encapsulation, or
/// with an unknown enum value, is an error that says which.
pub fn decode(data: &[u8]) -> Result<LoggedTick, String> {
    if data.len() != LEN {
        return Err(format!(
            "a CDR /servo/tick message is {LEN} bytes, this one {}",
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
    let flag = |at: usize, name: &str| match data[at] {
        0 => Ok(false),
        1 => Ok(true),
        b => Err(format!("`{name}` is {b}, not a bool")),
    };
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
    Ok(LoggedTick {
        phase,
        shot: usize::try_from(shot).ok(),
        input,
        output,
        command_sent: cmd(28),
        framing: Vec::new(),
        latency_s: flag(277, "has_latency")?.then(|| f(32)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::Sample;

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
        assert_eq!(buf.len(), 278);
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
        assert_eq!(&buf[4 + 268..], &[2, 0, 2, 1, 1, 1]);
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
                let back = decode(&buf).unwrap();
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
        let s = sample();
        let mut buf = Vec::new();
        encode(&mut buf, &record(&s, Ok(TickOutput::default())));
        assert!(decode(&buf[..100]).unwrap_err().contains("278 bytes"));
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
