//! Deterministic replay: rebuild the controller a flight log names, feed it the logged
//! inputs, and check that it gives the logged outputs bit for bit; recompute the report from
//! the log.
//!
//! The replay rule of `flight.rs`: the controller is reset once, with the first logged tick's
//! measurement at `t_s − dt_s`, then given every logged tick in order.
//!
//! After a stretch the reader had to skip (a gap: [`Damage`](dronecine_mcap::log::Damage)
//! with where reading resumed), the controller's state depends on the ticks lost in it:
//! replay restores it from the first key frame after the gap (the flight's controller state
//! at the start of each chunk of the log) and checks every tick from there on. Ticks after a
//! gap and before a key frame (a log written without key frames) are not re-run; every tick
//! read counts in the report all the same. Where replay's controller meets a key frame
//! without a gap before it, its state must be the key frame's, bit for bit.

use crate::report::{Counts, FlightReport, Metrics};
use dronecine_backend::frames::Command;
use dronecine_mcap::log::FlightLog;
use dronecine_servo::control::{Controller, TickFault, TickOutput};
use dronecine_servo::setup::controller_for;

/// The shots' PSL text, from the script recorded in the log, its coverages expanded for the
/// profile the log records as the flight expanded them (a script that no longer resolves,
/// for example a profile file that moved, gives numbered shots instead).
fn labels(script_text: &str, profile: &dronecine_profile::Profile) -> Vec<String> {
    let opts = dronecine_grammar::Options {
        known_drones: &[],
        base_dir: None,
    };
    dronecine_grammar::check(script_text, &opts)
        .script
        .map(|s| dronecine_compiler::coverage::expand(&s, profile).0)
        .map(|s| crate::report::shot_labels(&s, script_text))
        .unwrap_or_default()
}

/// The first tick whose replayed output differs from the logged one.
#[derive(Clone, Debug, PartialEq)]
pub struct Mismatch {
    pub tick: usize,
    pub t_s: f64,
    pub logged: Result<TickOutput, TickFault>,
    pub replayed: Result<TickOutput, TickFault>,
}

#[derive(Clone, Debug)]
pub struct Replay {
    /// Ticks the controller re-ran and checked.
    pub ticks: usize,
    /// Ticks read after a gap in the log and before a key frame, in the report but not
    /// re-run (0 for an intact log, and for a damaged one with its key frames).
    pub unreplayed: usize,
    /// The index in the log's ticks of the first one not re-run.
    pub first_unreplayed: Option<usize>,
    /// The gaps after which the controller was restored from a key frame.
    pub resumed: usize,
    pub mismatches: usize,
    pub first_mismatch: Option<Mismatch>,
    /// Key frames met without a gap before them whose state is not the replayed
    /// controller's, bit for bit.
    pub state_mismatches: usize,
    pub report: FlightReport,
}

fn same_command(a: &Command, b: &Command) -> bool {
    a.roll_rad.to_bits() == b.roll_rad.to_bits()
        && a.pitch_rad.to_bits() == b.pitch_rad.to_bits()
        && a.yaw_rate_radps.to_bits() == b.yaw_rate_radps.to_bits()
        && a.vz_mps.to_bits() == b.vz_mps.to_bits()
}

fn same_output(a: &Result<TickOutput, TickFault>, b: &Result<TickOutput, TickFault>) -> bool {
    match (a, b) {
        (Ok(x), Ok(y)) => same_command(&x.command, &y.command) && x.saturated == y.saturated,
        (Err(x), Err(y)) => x == y,
        _ => false,
    }
}

/// Starts the controller at `tick` by the replay rule.
fn start(
    controller: &mut dyn Controller,
    tick: &dronecine_mcap::log::LoggedTick,
) -> Result<(), String> {
    let Some(m) = tick.input.measurement else {
        return Err(format!(
            "the log's first controller tick (t = {:.3} s) has no measurement; it was not \
             written by this dronecine",
            tick.input.t_s
        ));
    };
    controller.reset(tick.input.t_s - tick.input.dt_s, &m);
    Ok(())
}

pub fn replay(log: &FlightLog) -> Result<Replay, String> {
    let profile = &log.header.profile;
    let mut controller = controller_for(&log.header.controller, profile, log.header.rate_hz)?;
    let mut metrics = Metrics::new(0, &profile.safety);
    let (mut mismatches, mut first_mismatch) = (0usize, None);
    let (mut checked, mut resumed, mut state_mismatches) = (0usize, 0usize, 0usize);
    let mut first_unreplayed = None;
    // The ticks the reader resumed at after a gap.
    let gaps: std::collections::BTreeSet<usize> = log
        .damage
        .iter()
        .filter(|d| d.resumed_at.is_some())
        .map(|d| d.tick)
        .collect();
    let mut frames = log.key_frames.iter().peekable();
    // The controller's state is the flight's before the next tick.
    let mut synced = false;
    for (k, tick) in log.ticks.iter().enumerate() {
        let after_gap = gaps.contains(&k);
        if after_gap {
            synced = false;
        }
        while let Some(frame) = frames.next_if(|f| f.tick <= k) {
            if frame.tick < k {
                continue;
            }
            match &frame.state {
                None => {
                    start(controller.as_mut(), tick)?;
                    synced = true;
                }
                Some(state) if synced => {
                    if !controller.state().same_bits(state) {
                        state_mismatches += 1;
                        controller.restore(state)?;
                    }
                }
                Some(state) => {
                    controller
                        .restore(state)
                        .map_err(|e| format!("the key frame at t = {:.3} s: {e}", frame.t_s))?;
                    synced = true;
                    resumed += 1;
                }
            }
        }
        if k == 0 && !synced && !after_gap && log.key_frames.is_empty() {
            // A log without key frames: its first tick is the flight's when nothing was
            // skipped before it.
            start(controller.as_mut(), tick)?;
            synced = true;
        }
        if !synced {
            first_unreplayed.get_or_insert(k);
        } else {
            checked += 1;
            let replayed = controller.tick(&tick.input);
            if !same_output(&replayed, &tick.output) {
                mismatches += 1;
                first_mismatch.get_or_insert(Mismatch {
                    tick: k,
                    t_s: tick.input.t_s,
                    logged: tick.output,
                    replayed,
                });
            }
        }
        metrics.record(
            tick.phase,
            tick.shot,
            &tick.input,
            &tick.output,
            &tick.framing,
            &tick.actors,
            tick.latency_s,
        );
    }
    let count = |kind: &str| log.events.iter().filter(|e| e.kind == kind).count() as u64;
    let time_of = |kind: &str| log.events.iter().find(|e| e.kind == kind).map(|e| e.t_s);
    let end = log.events.iter().rev().find(|e| e.kind == "flight_end");
    let counts = Counts {
        completed: end.is_some_and(|e| e.message.starts_with("completed")),
        flight_time_s: match (time_of("take_off"), end) {
            (Some(a), Some(b)) => b.t_s - a,
            // A log cut before the flight's end: in the air as far as it goes.
            (Some(a), None) => log.ticks.last().map_or(0.0, |t| (t.input.t_s - a).max(0.0)),
            _ => 0.0,
        },
        failsafes: count("failsafe"),
        director_errors: log.events.iter().filter(|e| e.is_director_error()).count() as u64,
        faults: count("fault"),
        deadline_misses: count("deadline_missed"),
        // The log keeps the late ticks (events), not every tick's lateness.
        lateness: None,
    };
    Ok(Replay {
        ticks: checked,
        unreplayed: log.ticks.len() - checked,
        first_unreplayed,
        resumed,
        mismatches,
        first_mismatch,
        state_mismatches,
        report: metrics.report(&labels(&log.header.script_text, profile), counts),
    })
}
