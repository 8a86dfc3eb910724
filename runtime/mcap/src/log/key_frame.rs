//! `/servo/state` in CDR: the controller's state between two ticks (a key frame), every float
//! bit for bit, from which `replay` resumes after a gap in the log; or, before the log's first
//! tick, the mark that the controller starts there (reset with that tick's measurement at
//! `t_s − dt_s`, replay's rule). 1,140 bytes a message, header included, with no sequence:
//! every field sits at a fixed offset (in [`SCHEMA`]).
//!
//! The writer puts one before the first tick of each chunk (the mark before the log's first
//! tick), so that the ticks of every intact chunk can be checked whatever was lost before it.

use dronecine_servo::control::{ControllerState, FilterState, LqgState, PidState};

use crate::output::cdr::{Cdr, CdrReader};

/// The schema's name (ROS 2 style, as Foxglove expects for `ros2msg`).
pub const SCHEMA_NAME: &str = "dronecine/msg/ServoState";

/// The `ros2msg` definition; the comments give each field's byte offset after the header.
pub const SCHEMA: &str = "\
# The controller's state between two ticks (a key frame), every float bit for bit: what
# dronecine replay restores to check the ticks after a gap in the log. CDR little-endian.
uint8 KIND_START=0                   # no state: the controller starts at the next tick
uint8 KIND_LQG=1
uint8 KIND_PID=2
float64 t_s                          # 0: flight clock: the tick this state comes before
uint8 kind                           # 8
float64[9] x                         # 16: the filter's [v; p; d] (m/s, m, the air's m/s)
float64[81] p                        # 88: its covariance, row by row
float64 heading_rad                  # 736: the filter's heading
float64 heading_variance_rad2        # 744
float64 lag_dt_s                     # 752: the last prediction's step and its body-frame lag
float64[3] lag_body                  # 760
float64[3] sent_input                # 784: roll, pitch (rad), vertical speed (m/s) sent last
float64 sent_yaw_rate_radps          # 808
float64 integral_z_ms                # 816: PID: the height error's integral (LQG: zero)
float64 heading_pole_dt_s            # 824: LQG (PID: zero): the heading pole's step, the pole
float64 heading_pole                 # 832
float64 body_gain_dt_s               # 840: the step the body-frame gain was solved for
float64[18] body_gain                # 848: the body-frame gain, 3x6, row by row
float64[18] world_gain               # 992: the last full solve's gain, 3x6, row by row
";

/// Bytes of a message, header included.
pub const LEN: usize = 4 + 1136;

const KIND_START: u8 = 0;
const KIND_LQG: u8 = 1;
const KIND_PID: u8 = 2;

/// Appends the CDR message of a key frame before the tick at `t_s` to `buf`: `state` (the
/// controller's after the tick before), or (`None`) the mark that the controller starts at
/// this tick.
pub fn encode(buf: &mut Vec<u8>, t_s: f64, state: Option<&ControllerState>) {
    let zero = FilterState::default();
    let (kind, filter, sent, yaw) = match state {
        None => (KIND_START, &zero, [0.0; 3], 0.0),
        Some(ControllerState::Lqg(s)) => (KIND_LQG, &s.filter, s.sent_input, s.sent_yaw_rate_radps),
        Some(ControllerState::Pid(s)) => (KIND_PID, &s.filter, s.sent_input, s.sent_yaw_rate_radps),
    };
    let mut m = Cdr::new(buf);
    m.f64(t_s).u8(kind).f64s(&filter.x);
    for row in &filter.p {
        m.f64s(row);
    }
    m.f64(filter.heading_rad)
        .f64(filter.heading_variance_rad2)
        .f64(filter.lag_dt_s)
        .f64s(&filter.lag_body)
        .f64s(&sent)
        .f64(yaw);
    let lqg = match state {
        Some(ControllerState::Lqg(s)) => *s,
        _ => LqgState::default(),
    };
    let integral = match state {
        Some(ControllerState::Pid(s)) => s.integral_z_ms,
        _ => 0.0,
    };
    m.f64(integral)
        .f64(lqg.heading_pole_dt_s)
        .f64(lqg.heading_pole)
        .f64(lqg.body_gain_dt_s);
    for row in lqg.body_gain.iter().chain(&lqg.world_gain) {
        m.f64s(row);
    }
}

/// Reads a key frame: the time of the tick it comes before, and the state (`None`: the
/// controller starts at that tick). A message of another length, encapsulation or kind is an error that says what is
/// wrong.
pub fn decode(data: &[u8]) -> Result<(f64, Option<ControllerState>), String> {
    if data.len() != LEN {
        return Err(format!(
            "a key frame is {LEN} bytes, this message {}",
            data.len()
        ));
    }
    // The header checked; every field at its fixed offset.
    let body = &data[CdrReader::new(data).map(|_| 4)?..];
    let float = |at: usize| f64::from_le_bytes(body[at..at + 8].try_into().expect("8 bytes"));
    let (t_s, kind) = (float(0), body[8]);
    let mut at = 16;
    let mut f = || {
        at += 8;
        float(at - 8)
    };
    // Field by field, in the message's order.
    let filter = FilterState {
        x: std::array::from_fn(|_| f()),
        p: std::array::from_fn(|_| std::array::from_fn(|_| f())),
        heading_rad: f(),
        heading_variance_rad2: f(),
        lag_dt_s: f(),
        lag_body: std::array::from_fn(|_| f()),
    };
    let sent_input = std::array::from_fn(|_| f());
    let sent_yaw_rate_radps = f();
    let integral_z_ms = f();
    let heading_pole_dt_s = f();
    let heading_pole = f();
    let body_gain_dt_s = f();
    let body_gain: [[f64; 6]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| f()));
    let world_gain: [[f64; 6]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| f()));
    let state = match kind {
        KIND_START => None,
        KIND_LQG => Some(ControllerState::Lqg(LqgState {
            filter,
            sent_input,
            sent_yaw_rate_radps,
            heading_pole_dt_s,
            heading_pole,
            body_gain_dt_s,
            body_gain,
            world_gain,
        })),
        KIND_PID => Some(ControllerState::Pid(PidState {
            filter,
            sent_input,
            sent_yaw_rate_radps,
            integral_z_ms,
        })),
        other => return Err(format!("`kind` is {other}, not a kind of key frame")),
    };
    Ok((t_s, state))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A state whose every float is distinct (its index, scaled), NaN and -0.0 among them.
    fn lqg() -> ControllerState {
        let mut k = 0.0;
        let mut next = || {
            k += 1.0;
            k * 0.37 + 0.1
        };
        let mut s = LqgState::default();
        s.filter.x.iter_mut().for_each(|x| *x = next());
        s.filter.p.iter_mut().flatten().for_each(|x| *x = next());
        s.filter.heading_rad = f64::from_bits(0x7ff8_0000_0000_1234);
        s.filter.heading_variance_rad2 = -0.0;
        s.filter.lag_dt_s = next();
        s.filter.lag_body.iter_mut().for_each(|x| *x = next());
        s.sent_input.iter_mut().for_each(|x| *x = next());
        s.sent_yaw_rate_radps = next();
        s.heading_pole_dt_s = next();
        s.heading_pole = next();
        s.body_gain_dt_s = next();
        s.body_gain.iter_mut().flatten().for_each(|x| *x = next());
        s.world_gain.iter_mut().flatten().for_each(|x| *x = next());
        ControllerState::Lqg(s)
    }

    #[test]
    fn key_frames_round_trip_bit_for_bit_at_the_schemas_offsets() {
        let pid = ControllerState::Pid(PidState {
            filter: FilterState {
                x: [1.5; 9],
                ..FilterState::default()
            },
            sent_input: [0.1, -0.2, 0.3],
            sent_yaw_rate_radps: -0.5,
            integral_z_ms: 7.25,
        });
        for state in [Some(lqg()), Some(pid), None] {
            let mut buf = vec![0xAA];
            encode(&mut buf, 12.5, state.as_ref());
            let msg = &buf[1..];
            assert_eq!(msg.len(), LEN);
            let (t_s, back) = decode(msg).unwrap();
            assert_eq!(t_s, 12.5);
            match (&state, &back) {
                (Some(a), Some(b)) => assert!(a.same_bits(b), "{a:?}"),
                (None, None) => {}
                _ => panic!("{state:?} read back as {back:?}"),
            }
            // The offsets in the schema's comments.
            let at = |offset: usize| {
                f64::from_le_bytes(msg[4 + offset..12 + offset].try_into().unwrap())
            };
            if let Some(ControllerState::Lqg(s)) = &state {
                assert_eq!(msg[4 + 8], KIND_LQG);
                assert_eq!(at(16), s.filter.x[0]);
                assert_eq!(at(88), s.filter.p[0][0]);
                assert_eq!(at(736).to_bits(), s.filter.heading_rad.to_bits());
                assert_eq!(at(752), s.filter.lag_dt_s);
                assert_eq!(at(784), s.sent_input[0]);
                assert_eq!(at(808), s.sent_yaw_rate_radps);
                assert_eq!(at(824), s.heading_pole_dt_s);
                assert_eq!(at(848), s.body_gain[0][0]);
                assert_eq!(at(992), s.world_gain[0][0]);
                assert_eq!(at(1128), s.world_gain[2][5]);
            }
            if let Some(ControllerState::Pid(s)) = &state {
                assert_eq!(msg[4 + 8], KIND_PID);
                assert_eq!(at(816), s.integral_z_ms);
            }
        }
    }

    #[test]
    fn a_key_frame_of_another_length_or_kind_is_an_error() {
        let mut buf = Vec::new();
        encode(&mut buf, 1.0, Some(&lqg()));
        assert!(decode(&buf[..LEN - 1]).unwrap_err().contains("1140 bytes"));
        let mut longer = buf.clone();
        longer.push(0);
        assert!(decode(&longer).is_err());
        let mut kind = buf.clone();
        kind[4 + 8] = 3;
        assert!(decode(&kind).unwrap_err().contains("`kind` is 3"));
    }
}
