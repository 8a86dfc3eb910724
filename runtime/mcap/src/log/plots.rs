//! The flight log's own plot topics in CDR with `ros2msg` schemas, as `/servo/tick`:
//! `/estimate`, `/measurement`, `/command`, `/framing` and, for a drone with a gimbal,
//! `/gimbal` (compile's `/reference`, `/actors`
//! and `/tf` come from the compiler's writers, in CDR too). Every float is written exactly
//! (NaN, infinities and `-0.0` included); an absent value (an untracked body, an actor behind
//! the camera) is zero with its flag clear. The decoders are for tests and tools: a damaged
//! message is an error that names the field, never a panic.
//!
//! Why CDR: these topics and `/tf` are most of the log's messages (about 800,000 an hour at
//! 100 Hz), and formatting their floats as JSON text would cost the writer thread more than
//! the rest of the log.

use crate::output::cdr::{Cdr, CdrReader, SEPARATOR};

use crate::record::{FramingRecord, GimbalRecord};
use dronecine_backend::frames::Command;
use dronecine_backend::{BodyPose, MocapFrame};
use dronecine_servo::control::{Estimate, TickOutput};

pub const ESTIMATE: &str = "dronecine/msg/Estimate";
pub const MEASUREMENT: &str = "dronecine/msg/Measurement";
pub const COMMAND: &str = "dronecine/msg/Command";
pub const FRAMING: &str = "dronecine/msg/Framing";
pub const GIMBAL: &str = "dronecine/msg/Gimbal";

/// The `ros2msg` definition of `/estimate`.
pub fn estimate_schema() -> String {
    "\
# The controller's state estimate after the tick
float64 t_s                      # flight clock (s)
float64[3] position_m
float64[3] velocity_mps
float64 heading_rad              # counter-clockwise from +x
"
    .to_string()
}

/// The `ros2msg` definition of `/measurement`.
pub fn measurement_schema() -> String {
    format!(
        "\
# One motion-capture frame
float64 t_s                      # capture time on the flight clock (s)
uint64 frame                     # frame counter (a gap: frames were lost)
dronecine/TrackedBody drone
dronecine/TrackedBody[] actors   # the script's order
{SEPARATOR}
MSG: dronecine/TrackedBody
float64[3] position_m            # zero unless tracked
float64 heading_rad              # counter-clockwise from +x
bool tracked                     # false: not tracked in this frame
"
    )
}

/// The `ros2msg` definition of `/command`.
pub fn command_schema() -> String {
    "\
# The command sent to the drone
float64 t_s                      # flight clock (s)
float64 roll_rad                 # positive moves right
float64 pitch_rad                # positive (nose up) moves backward
float64 yaw_rate_radps           # positive clockwise seen from above
float64 vz_mps                   # vertical speed, positive up
bool saturated                   # a set-point was clamped to the profile's limits
bool failsafe                    # the command sent is not the controller's (fault or failsafe)
"
    .to_string()
}

/// The `ros2msg` definition of `/framing`.
pub fn framing_schema() -> String {
    format!(
        "\
# Where each actor is on screen and where the script puts it (screen coordinates)
float64 t_s                      # flight clock (s)
int32 shot                       # index of the shot, -1 outside the shots
dronecine/ActorFraming[] actors
{SEPARATOR}
MSG: dronecine/ActorFraming
string name
uint32 actor                     # index in the scene's actors
float64[2] screen                # zero unless has_screen (the actor is in front of the camera)
float64[2] requested             # zero unless has_requested (the script frames the actor)
bool has_screen
bool has_requested
"
    )
}

/// The `ros2msg` definition of `/gimbal`.
pub fn gimbal_schema() -> String {
    "\
# The camera gimbal's pitch: what the flight asked and what the gimbal reported
float64 t_s                      # flight clock (s)
float64 asked_rad                # the pitch commanded this tick, up positive
float64 reported_rad             # the pitch the gimbal reported, up positive (zero unless has_reported)
bool has_reported                # false: the drone reported no pitch this tick
"
    .to_string()
}

/// Bit-for-bit equal floats.
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits()
}

/// Bit-for-bit equal commands.
pub(super) fn same_command(a: &Command, b: &Command) -> bool {
    same(a.roll_rad, b.roll_rad)
        && same(a.pitch_rad, b.pitch_rad)
        && same(a.yaw_rate_radps, b.yaw_rate_radps)
        && same(a.vz_mps, b.vz_mps)
}

/// Appends an `/estimate` message.
pub fn estimate(buf: &mut Vec<u8>, t_s: f64, e: &Estimate) {
    Cdr::new(buf)
        .f64(t_s)
        .f64s(&e.position_m)
        .f64s(&e.velocity_mps)
        .f64(e.heading_rad);
}

fn body(m: &mut Cdr, pose: Option<&BodyPose>) {
    let p = pose.copied().unwrap_or_default();
    m.f64s(&p.position_m)
        .f64(p.heading_rad)
        .bool(pose.is_some());
}

/// Appends a `/measurement` message.
pub fn measurement(buf: &mut Vec<u8>, frame: &MocapFrame) {
    let mut m = Cdr::new(buf);
    m.f64(frame.t_s).u64(frame.frame);
    body(&mut m, frame.drone.as_ref());
    m.count(frame.actors.len());
    for a in &frame.actors {
        body(&mut m, a.as_ref());
    }
}

/// Appends a `/command` message: the command sent, whether the controller saturated it, and
/// whether it is not the controller's.
pub fn command(
    buf: &mut Vec<u8>,
    t_s: f64,
    output: Option<&TickOutput>,
    c: &Command,
    failsafe: bool,
) {
    Cdr::new(buf)
        .f64(t_s)
        .f64(c.roll_rad)
        .f64(c.pitch_rad)
        .f64(c.yaw_rate_radps)
        .f64(c.vz_mps)
        .bool(output.is_some_and(|o| o.saturated))
        .bool(failsafe);
}

/// Appends a `/framing` message (`names`: the scene's actors; an index beyond them is
/// written with an empty name).
pub fn framing(
    buf: &mut Vec<u8>,
    t_s: f64,
    shot: Option<usize>,
    names: &[String],
    framing: &[FramingRecord],
) {
    let mut m = Cdr::new(buf);
    let shot = shot.and_then(|s| i32::try_from(s).ok()).unwrap_or(-1);
    m.f64(t_s).i32(shot).count(framing.len());
    for f in framing {
        let name = names.get(f.actor).map_or("", String::as_str);
        m.string(name)
            .u32(u32::try_from(f.actor).unwrap_or(u32::MAX))
            .f64s(&f.screen.unwrap_or_default())
            .f64s(&f.requested.unwrap_or_default())
            .bool(f.screen.is_some())
            .bool(f.requested.is_some());
    }
}

/// Appends a `/gimbal` message.
pub fn gimbal(buf: &mut Vec<u8>, t_s: f64, g: &GimbalRecord) {
    Cdr::new(buf)
        .f64(t_s)
        .f64(g.asked_rad)
        .f64(g.reported_rad.unwrap_or_default())
        .bool(g.reported_rad.is_some());
}

/// A `/gimbal` message read back: the time and the record.
pub fn decode_gimbal(data: &[u8]) -> Result<(f64, GimbalRecord), String> {
    let mut r = CdrReader::new(data)?;
    let t_s = r.f64("t_s")?;
    let asked_rad = r.f64("asked_rad")?;
    let reported_rad = r.f64("reported_rad")?;
    let has_reported = r.bool("has_reported")?;
    r.finish("Gimbal")?;
    Ok((
        t_s,
        GimbalRecord {
            asked_rad,
            reported_rad: has_reported.then_some(reported_rad),
        },
    ))
}

/// An `/estimate` message read back: the time and the estimate.
pub fn decode_estimate(data: &[u8]) -> Result<(f64, Estimate), String> {
    let mut r = CdrReader::new(data)?;
    let t_s = r.f64("t_s")?;
    let e = Estimate {
        position_m: r.f64s("position_m")?,
        velocity_mps: r.f64s("velocity_mps")?,
        heading_rad: r.f64("heading_rad")?,
    };
    r.finish("Estimate")?;
    Ok((t_s, e))
}

fn read_body(r: &mut CdrReader, what: &str) -> Result<Option<BodyPose>, String> {
    let position_m = r.f64s(what)?;
    let heading_rad = r.f64(what)?;
    let tracked = r.bool(what)?;
    Ok(tracked.then_some(BodyPose {
        position_m,
        heading_rad,
    }))
}

/// A `/measurement` message read back (`received_s`, not logged there, is `t_s`).
pub fn decode_measurement(data: &[u8]) -> Result<MocapFrame, String> {
    let mut r = CdrReader::new(data)?;
    let t_s = r.f64("t_s")?;
    let frame = r.u64("frame")?;
    let drone = read_body(&mut r, "drone")?;
    // Each body at least 33 bytes.
    let n = r.count("actors", 33)?;
    let actors = (0..n)
        .map(|_| read_body(&mut r, "actors"))
        .collect::<Result<_, _>>()?;
    r.finish("Measurement")?;
    Ok(MocapFrame {
        t_s,
        received_s: t_s,
        frame,
        drone,
        actors,
    })
}

/// A `/command` message read back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoggedCommand {
    pub t_s: f64,
    pub command: Command,
    pub saturated: bool,
    pub failsafe: bool,
}

pub fn decode_command(data: &[u8]) -> Result<LoggedCommand, String> {
    let mut r = CdrReader::new(data)?;
    let c = LoggedCommand {
        t_s: r.f64("t_s")?,
        command: Command {
            roll_rad: r.f64("roll_rad")?,
            pitch_rad: r.f64("pitch_rad")?,
            yaw_rate_radps: r.f64("yaw_rate_radps")?,
            vz_mps: r.f64("vz_mps")?,
        },
        saturated: r.bool("saturated")?,
        failsafe: r.bool("failsafe")?,
    };
    r.finish("Command")?;
    Ok(c)
}

/// A `/framing` message read back.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedFraming {
    pub t_s: f64,
    pub shot: Option<usize>,
    /// Each framed actor's name and record.
    pub actors: Vec<(String, FramingRecord)>,
}

pub fn decode_framing(data: &[u8]) -> Result<LoggedFraming, String> {
    let mut r = CdrReader::new(data)?;
    let t_s = r.f64("t_s")?;
    let shot = r.i32("shot")?;
    // Each element at least: an empty name, the index, four floats, two flags.
    let n = r.count("actors", 5 + 4 + 32 + 2)?;
    let mut actors = Vec::with_capacity(n);
    for _ in 0..n {
        let name = r.string("name")?.to_string();
        let actor = r.u32("actor")? as usize;
        let screen: [f64; 2] = r.f64s("screen")?;
        let requested: [f64; 2] = r.f64s("requested")?;
        let has_screen = r.bool("has_screen")?;
        let has_requested = r.bool("has_requested")?;
        actors.push((
            name,
            FramingRecord {
                actor,
                screen: has_screen.then_some(screen),
                requested: has_requested.then_some(requested),
            },
        ));
    }
    r.finish("Framing")?;
    Ok(LoggedFraming {
        t_s,
        shot: usize::try_from(shot).ok(),
        actors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_message_reads_back_bit_for_bit() {
        let mut buf = Vec::new();
        let e = Estimate {
            position_m: [1.0, -0.0, f64::NAN],
            velocity_mps: [0.1 + 0.2, 5e-324, f64::INFINITY],
            heading_rad: -3.0,
        };
        estimate(&mut buf, 1.25, &e);
        let (t, back) = decode_estimate(&buf).unwrap();
        assert_eq!(t, 1.25);
        let bits = |e: &Estimate| {
            e.position_m
                .iter()
                .chain(&e.velocity_mps)
                .chain([&e.heading_rad])
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&back), bits(&e));

        let frame = MocapFrame {
            t_s: 2.0,
            received_s: 2.0,
            frame: u64::MAX - 3,
            drone: None,
            actors: vec![
                Some(BodyPose {
                    position_m: [1.0, 2.0, 0.0],
                    heading_rad: 0.5,
                }),
                None,
            ],
        };
        buf.clear();
        measurement(&mut buf, &frame);
        assert_eq!(decode_measurement(&buf).unwrap(), frame);

        let c = Command {
            roll_rad: 0.1,
            pitch_rad: -0.2,
            yaw_rate_radps: 0.3,
            vz_mps: -0.4,
        };
        buf.clear();
        command(&mut buf, 3.0, None, &c, true);
        let back = decode_command(&buf).unwrap();
        assert_eq!(
            back,
            LoggedCommand {
                t_s: 3.0,
                command: c,
                saturated: false,
                failsafe: true
            }
        );

        let names = ["Ann".to_string(), "Bo \"the\" Bear".to_string()];
        let records = [
            FramingRecord {
                actor: 1,
                screen: Some([0.25, -0.5]),
                requested: None,
            },
            FramingRecord {
                actor: 7,
                screen: None,
                requested: Some([0.0, 0.1]),
            },
        ];
        buf.clear();
        framing(&mut buf, 4.0, Some(2), &names, &records);
        let back = decode_framing(&buf).unwrap();
        assert_eq!(back.t_s, 4.0);
        assert_eq!(back.shot, Some(2));
        assert_eq!(back.actors[0], (names[1].clone(), records[0]));
        assert_eq!(back.actors[1], (String::new(), records[1]));
        buf.clear();
        framing(&mut buf, 4.0, None, &names, &[]);
        assert_eq!(decode_framing(&buf).unwrap().shot, None);

        for g in [
            GimbalRecord {
                asked_rad: -0.25,
                reported_rad: Some(-0.0),
            },
            GimbalRecord {
                asked_rad: 0.1 + 0.2,
                reported_rad: None,
            },
        ] {
            buf.clear();
            gimbal(&mut buf, 5.0, &g);
            // Three floats and a flag, no padding.
            assert_eq!(buf.len(), 4 + 25);
            let (t, back) = decode_gimbal(&buf).unwrap();
            assert_eq!(t, 5.0);
            assert_eq!(back.asked_rad.to_bits(), g.asked_rad.to_bits());
            assert_eq!(
                back.reported_rad.map(f64::to_bits),
                g.reported_rad.map(f64::to_bits)
            );
        }
        let last = buf.len() - 1;
        buf[last] = 2;
        assert!(decode_gimbal(&buf).unwrap_err().contains("has_reported"));
    }

    #[test]
    fn the_layout_is_the_schemas() {
        // /command: seven fields, no padding: the floats at 0..40, the flags at 40 and 41.
        let mut buf = Vec::new();
        let c = Command {
            roll_rad: 0.1,
            pitch_rad: 0.2,
            yaw_rate_radps: 0.3,
            vz_mps: 0.4,
        };
        command(&mut buf, 9.0, None, &c, true);
        let body = &buf[4..];
        assert_eq!(body.len(), 42);
        assert_eq!(&body[8..16], &0.1f64.to_le_bytes());
        assert_eq!(&body[32..40], &0.4f64.to_le_bytes());
        assert_eq!(&body[40..42], &[0, 1]);
        // /measurement: t_s 0, frame 8, the drone (position 16, heading 40, flag 48), the
        // actors' count at 52, the first actor from 56 (8-aligned).
        let frame = MocapFrame {
            t_s: 1.0,
            received_s: 1.0,
            frame: 5,
            drone: Some(BodyPose {
                position_m: [1.0, 2.0, 3.0],
                heading_rad: 4.0,
            }),
            actors: vec![None],
        };
        buf.clear();
        measurement(&mut buf, &frame);
        let body = &buf[4..];
        assert_eq!(&body[8..16], &5u64.to_le_bytes());
        assert_eq!(&body[16..24], &1.0f64.to_le_bytes());
        assert_eq!(&body[40..48], &4.0f64.to_le_bytes());
        assert_eq!(body[48], 1);
        assert_eq!(&body[52..56], &1u32.to_le_bytes());
        assert_eq!(&body[56..88], &[0; 32]);
        assert_eq!(body[88], 0);
        assert_eq!(body.len(), 89);
    }

    #[test]
    fn damaged_messages_are_errors() {
        let mut buf = Vec::new();
        let names = ["Ann".to_string()];
        let record = FramingRecord {
            actor: 0,
            screen: Some([0.1, 0.2]),
            requested: Some([0.3, 0.4]),
        };
        framing(&mut buf, 1.0, Some(0), &names, &[record]);
        for cut in 0..buf.len() - 1 {
            assert!(decode_framing(&buf[..cut]).is_err(), "cut at {cut}");
        }
        let mut bad_flag = buf.clone();
        let last = bad_flag.len() - 1;
        bad_flag[last] = 2;
        let err = decode_framing(&bad_flag).unwrap_err();
        assert!(err.contains("has_requested"), "{err}");
        assert!(decode_command(&buf).is_err(), "a framing is not a command");
    }
}
