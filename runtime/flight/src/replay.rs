//! Deterministic replay: rebuild the controller a flight log names, feed it the logged
//! inputs, and check that it gives the logged outputs bit for bit; recompute the report from
//! the log.
//!
//! The replay rule of `flight.rs`: the controller is reset once, with the first logged tick's
//! measurement at `t_s − dt_s`, then given every logged tick in order.
//!
//! A log the reader had to skip damage in ([`FlightLog::first_gap`]) is replayed up to the
//! gap only: the controller's state after it depends on the ticks that were lost. The ticks
//! after it still count in the report (nothing that was read is dropped).

use crate::report::{Counts, FlightReport, Metrics};
use dronecine_backend::frames::Command;
use dronecine_mcap::log::FlightLog;
use dronecine_servo::control::{TickFault, TickOutput};
use dronecine_servo::setup::controller_for;

/// The shots' PSL text, from the script recorded in the log (a script that no longer
/// resolves, for example a profile file that moved, gives numbered shots instead).
fn labels(script_text: &str) -> Vec<String> {
    let opts = dronecine_grammar::Options {
        known_drones: &[],
        base_dir: None,
    };
    dronecine_grammar::check(script_text, &opts)
        .script
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
    /// Ticks the controller re-ran.
    pub ticks: usize,
    /// Ticks after a gap in the log, in the report but not re-run (0 for an intact log).
    pub unreplayed: usize,
    pub mismatches: usize,
    pub first_mismatch: Option<Mismatch>,
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

pub fn replay(log: &FlightLog) -> Result<Replay, String> {
    let profile = &log.header.profile;
    let mut controller = controller_for(&log.header.controller, profile, log.header.rate_hz)?;
    let mut metrics = Metrics::new(0, &profile.safety);
    let (mut mismatches, mut first_mismatch) = (0usize, None);
    let mut started = false;
    let replayable = log.first_gap().unwrap_or(log.ticks.len());
    for (k, tick) in log.ticks.iter().enumerate() {
        if k < replayable {
            if !started {
                let Some(m) = tick.input.measurement else {
                    return Err(format!(
                        "the log's first controller tick (t = {:.3} s) has no measurement; \
                         it was not written by this dronecine",
                        tick.input.t_s
                    ));
                };
                controller.reset(tick.input.t_s - tick.input.dt_s, &m);
                started = true;
            }
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
    };
    Ok(Replay {
        ticks: replayable,
        unreplayed: log.ticks.len() - replayable,
        mismatches,
        first_mismatch,
        report: metrics.report(&labels(&log.header.script_text), counts),
    })
}
