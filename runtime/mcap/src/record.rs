//! What a flight records, tick by tick: the contract between the flight loop
//! (`dronecine-flight`), the flight log (`log`, MCAP) and `replay`.
//!
//! Replay re-runs the controller from [`FlightHeader`] (which controller, which profile, which
//! options) on the logged [`TickInput`]s and compares its commands with the logged ones, bit
//! for bit; so every field the controller reads is here, and floats are logged exactly
//! (shortest round-trip form).

use dronecine_backend::frames::Command;
use dronecine_backend::{FlightState, MocapFrame};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_servo::control::{ControllerState, Reference, TickFault, TickInput, TickOutput};
use dronecine_servo::setup::ControllerSetup;
use serde::{Deserialize, Serialize};
use std::io;

/// What the servo tracks of a reference sample: the part of [`TickRecord::sample`] it is
/// given as [`TickInput::reference`].
pub fn reference_of(s: &Sample) -> Reference {
    Reference {
        position_m: s.position_m,
        velocity_mps: s.velocity_mps,
        acceleration_mps2: s.acceleration_mps2,
        heading_rad: s.heading_rad,
        heading_rate_radps: s.heading_rate_radps,
    }
}

/// Where the flight record goes (the MCAP flight log, or nowhere).
pub trait FlightSink {
    fn tick(&mut self, record: &TickRecord) -> io::Result<()>;
    fn event(&mut self, event: &Event) -> io::Result<()>;
    /// The flight's clock reached `t_s` on a tick that records nothing (waiting for the
    /// motion capture before take-off, the drone's own take-off and landing): a sink that
    /// keeps its records by time (the log's chunks) keeps them as on any other tick.
    fn idle(&mut self, _t_s: f64) -> io::Result<()> {
        Ok(())
    }
    /// Whether the sink wants the controller's state after the tick it was just given (a
    /// key frame: the log starts a chunk after that tick, and replay resumes from its key
    /// frame after a gap). The flight loop asks after each tick it records.
    fn wants_key_frame(&self) -> bool {
        false
    }
    /// The controller's state after the tick last given, when the sink wants it.
    fn key_frame(&mut self, _state: &ControllerState) -> io::Result<()> {
        Ok(())
    }
    /// How late the loop's tick about to be recorded (or idle) ran past its due time: a sink
    /// that reports what it costs the loop (the live view, with a client and without) counts
    /// it. Told every tick, before the tick's record.
    fn tick_lateness(&mut self, _late_s: f64) {}
}

/// Records nothing (benchmarks, tests).
pub struct NullSink;

impl FlightSink for NullSink {
    fn tick(&mut self, _: &TickRecord) -> io::Result<()> {
        Ok(())
    }
    fn event(&mut self, _: &Event) -> io::Result<()> {
        Ok(())
    }
}

/// Written once, at the start of the log (MCAP metadata `dronecine.flight`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightHeader {
    pub script_name: String,
    pub script_text: String,
    pub profile_name: String,
    /// The profile as TOML (`Profile::to_toml`), for people: degrees in the TOML do not
    /// round-trip to the bit.
    pub profile_toml: String,
    /// The profile exactly (every float bit for bit): what replay builds the controller from.
    pub profile: dronecine_profile::Profile,
    pub controller: ControllerSetup,
    /// `"sim"` or the drone URL.
    pub backend: String,
    /// The simulator's seed (`None` on hardware).
    pub seed: Option<u64>,
    /// The simulator's effects that were off, by their names (the simulator's `Effects::NAMES`;
    /// `[]`: every effect on, the default; `None` on hardware, and in logs that do not
    /// record it): with the seed, what reproduces a simulated flight.
    #[serde(default)]
    pub sim_effects_off: Option<Vec<String>>,
    pub rate_hz: f64,
    pub actor_names: Vec<String>,
    pub dronecine_version: String,
}

/// Where one actor is on screen and where the script puts it (holds only; `None` when the
/// actor is behind the camera or the shot has no framing for it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FramingRecord {
    pub actor: usize,
    pub screen: Option<[f64; 2]>,
    pub requested: Option<[f64; 2]>,
}

/// The camera gimbal at one tick: the pitch asked of it and the pitch it reported (up
/// positive). Only a drone whose profile has a gimbal has one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GimbalRecord {
    /// The pitch commanded this tick (the reference sample's).
    pub asked_rad: f64,
    /// The pitch the gimbal reported this tick, before this tick's command (`None` when the
    /// drone reports none).
    pub reported_rad: Option<f64>,
}

/// One control tick.
#[derive(Clone, Debug, PartialEq)]
pub struct TickRecord<'a> {
    /// Phase of the flight (take-off, approach, shots, landing).
    pub phase: Phase,
    /// Index of the shot in the timeline (`None` outside the shots).
    pub shot: Option<usize>,
    /// The full reference sample (camera pitch included) the servo was given.
    pub sample: &'a Sample,
    /// Exactly what the controller was given…
    pub input: TickInput,
    /// …and what it returned.
    pub output: Result<TickOutput, TickFault>,
    /// What was sent to the drone (the output's command, or the failsafe's).
    pub command_sent: Command,
    /// The raw mocap frame of this tick (`None` when no new frame arrived).
    pub mocap: Option<&'a MocapFrame>,
    /// The actors as the director saw them this tick.
    pub actors: &'a [ActorPose],
    pub framing: &'a [FramingRecord],
    pub drone_state: FlightState,
    /// Seconds from this tick's mocap frame reaching the computer to the command leaving it
    /// (`None` without a new frame).
    pub latency_s: Option<f64>,
    /// The camera gimbal (`None` when the profile has no gimbal).
    pub gimbal: Option<GimbalRecord>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    TakeOff,
    /// From the take-off hover to the first sample of the reference.
    Approach,
    Shots,
    Landing,
}

/// Something that happened, on `/events`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    pub t_s: f64,
    /// `"info"`, `"warning"` or `"error"`.
    pub level: String,
    /// A stable kind: `take_off`, `shot_start`, `landing`, `landed`, `failsafe`,
    /// `deadline_missed`, `fault`, …
    pub kind: String,
    pub message: String,
    /// The script's line the event is about (1-based): a finding of the director's, at the
    /// shot it is about. `None` for the flight's own events.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<u32>,
    /// How to fix it, as `compile` says it (a finding of the director's that has a fix).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub help: Option<String>,
}

impl Event {
    /// An error the director raised against the live actors during the shots (a framing it
    /// could not solve, …): its kind is the compiler's diagnostic code. The flight's report
    /// counts these, and `replay` counts them again from the log, by this one rule.
    pub fn is_director_error(&self) -> bool {
        self.level == "error" && self.kind.starts_with("compile::")
    }
}
