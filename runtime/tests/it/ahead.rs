//! The director stepped ahead of the loop on a thread of its own (`SimConfig::actors_ahead`,
//! `runtime/flight/src/ahead.rs`) flies the same flight as the director stepped on the loop's
//! thread, to the bit: every tick as the log records it (`/servo/tick`'s CDR: the input, the
//! output, the command sent, the actors the director saw and the framing), every event in
//! order, and the report. On every shipped script that has a scene to fly (two seeds each),
//! with the motion capture faster and slower than the loop, on flights cut short in
//! the middle of a shot (Ctrl-C: the cut shot's findings are the director's at that tick,
//! not the thread's, which is ahead), and on the random scenes that fly
//! (`random_flights.rs` flies each both ways).

use crate::common::{load, parse};
use std::sync::atomic::{AtomicU32, Ordering};

use dronecine_flight::{Observer, Progress};
use dronecine_grammar::script::DroneRef;
use dronecine_mcap::log::cdr;
use dronecine_mcap::record::FlightSink;
use dronecine_mcap::record::{Event, Phase, TickRecord};
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;

const SHIPPED: &[&str] = &[
    "shots/square.psl",
    "shots/helix.psl",
    "shots/transition.psl",
    "shots/two-actors.psl",
    "shots/two-heights.psl",
    "shots/scene.psl",
];

/// Every tick's CDR record and every event, as the flight gave them.
#[derive(Default)]
struct Recording {
    ticks: Vec<u8>,
    count: usize,
    events: Vec<String>,
}

impl FlightSink for Recording {
    fn tick(&mut self, record: &TickRecord) -> std::io::Result<()> {
        cdr::encode(&mut self.ticks, record);
        self.count += 1;
        Ok(())
    }
    fn event(&mut self, event: &Event) -> std::io::Result<()> {
        self.events.push(format!("{event:?}"));
        Ok(())
    }
}

/// Presses Ctrl-C once, `after_s` seconds into the shots.
struct CtrlC<'a> {
    interrupts: &'a AtomicU32,
    after_s: Option<f64>,
}

impl Observer for CtrlC<'_> {
    fn progress(&mut self, p: &Progress) {
        if let Some(after) = self.after_s {
            if p.phase == Phase::Shots && p.script_t_s >= after {
                self.interrupts.fetch_add(1, Ordering::Relaxed);
                self.after_s = None;
            }
        }
    }
}

/// The loop's rate and the motion capture's.
#[derive(Clone, Copy)]
struct Rates {
    loop_hz: f64,
    mocap_hz: f64,
}

impl Default for Rates {
    fn default() -> Rates {
        Rates {
            loop_hz: 100.0,
            mocap_hz: 100.0,
        }
    }
}

/// Flies `path` at `rates` with `seed`, the director ahead or not, Ctrl-C pressed `ctrl_c_s`
/// into the shots if asked: what the flight recorded, and its report (or its error) in words.
fn fly_at(
    path: &str,
    seed: u64,
    ahead: bool,
    ctrl_c_s: Option<f64>,
    rates: Rates,
) -> (Recording, String) {
    let (text, script) = match path.strip_prefix("inline:") {
        Some(text) => (text.to_string(), parse(text)),
        None => load(path),
    };
    let scene = script.scene.as_ref().unwrap();
    let profile = match &scene.drone {
        Some(DroneRef::Builtin { name }) => Profile::builtin(name).unwrap(),
        _ => Profile::builtin("ardrone2").unwrap(),
    };
    let mut sim = SimConfig::new(seed);
    sim.actors_ahead = ahead;
    sim.mocap_rate_hz = rates.mocap_hz;
    let interrupts = AtomicU32::new(0);
    let mut recording = Recording::default();
    let report = fly_simulated(
        &SimFlight {
            script: &script,
            source: &text,
            scene,
            profile: &profile,
            rate_hz: rates.loop_hz,
            controller: ControllerSetup::new("lqg"),
            plant: None,
            sim,
            realtime: false,
            interrupts: Some(&interrupts),
        },
        &mut recording,
        &mut CtrlC {
            interrupts: &interrupts,
            after_s: ctrl_c_s,
        },
    );
    (recording, format!("{report:?}"))
}

/// Flies `path` both ways and asserts the same flight; gives what it recorded and its report.
fn same_flight(path: &str, seed: u64, ctrl_c_s: Option<f64>) -> (Recording, String) {
    same_flight_at(path, seed, ctrl_c_s, Rates::default())
}

fn same_flight_at(
    path: &str,
    seed: u64,
    ctrl_c_s: Option<f64>,
    rates: Rates,
) -> (Recording, String) {
    let (here, here_report) = fly_at(path, seed, false, ctrl_c_s, rates);
    let (ahead, ahead_report) = fly_at(path, seed, true, ctrl_c_s, rates);
    assert!(
        here.count > 500,
        "{path}, seed {seed}: {} ticks",
        here.count
    );
    assert_eq!(here.count, ahead.count, "{path}, seed {seed}: tick counts");
    if let Some(k) = (here.ticks.iter().zip(&ahead.ticks)).position(|(a, b)| a != b) {
        panic!("{path}, seed {seed}: the ticks differ from byte {k} on");
    }
    assert_eq!(here.ticks.len(), ahead.ticks.len(), "{path}, seed {seed}");
    assert_eq!(here.events, ahead.events, "{path}, seed {seed}: the events");
    assert_eq!(here_report, ahead_report, "{path}, seed {seed}: the report");
    (here, here_report)
}

#[test]
fn every_shipped_script_flies_the_same_with_the_director_ahead() {
    for path in SHIPPED {
        for seed in [1, 7] {
            let (_, report) = same_flight(path, seed, None);
            assert!(
                report.contains("completed: true"),
                "{path}, seed {seed}: {report}"
            );
        }
    }
}

/// A shot whose camera comes near its actor late in it: A walks toward the wall the camera
/// films them from, 6 s in, and the framing is pressed between the wall and A. The monitor
/// finds it then (`compile::too_close`, told when the shot is over).
const LEAVES_THE_STAGE: &str = "inline:stage 6m x 5m x 3m\ndrone ardrone2\n\
    actor A height 1.80m at (-1, 0) facing 0deg\n\
    at 6s A walks to (1.6, 0) over 3s\n\
    MS on A front for 12s\n";

#[test]
fn a_flight_cut_short_mid_shot_tells_the_same_findings_with_the_director_ahead() {
    // Cut 3 s into a shot whose camera comes near its actor 6 s in: the loop lands at once,
    // and the shot's findings are none (the thread, seconds ahead, has found the camera near).
    let (cut, _) = same_flight(LEAVES_THE_STAGE, 3, Some(3.0));
    let (whole, _) = same_flight(LEAVES_THE_STAGE, 3, None);
    let near = |r: &Recording| r.events.iter().any(|e| e.contains("compile::too_close"));
    assert!(
        near(&whole),
        "the whole shot finds its camera near A: {:#?}",
        whole.events
    );
    assert!(
        !near(&cut),
        "cut at 3 s, the camera had not come near A: {:#?}",
        cut.events
    );
    assert!(cut.events.iter().any(|e| e.contains("Ctrl-C")));
    // Mid-way through the shots of the scene (one- and two-actor holds, cuts, moves) and of
    // the transition.
    for (path, after_s) in [("shots/scene.psl", 9.3), ("shots/transition.psl", 4.1)] {
        for seed in [2, 5] {
            let (recording, report) = same_flight(path, seed, Some(after_s));
            assert!(report.contains("completed: false"), "{path}: {report}");
            assert!(
                recording.events.iter().any(|e| e.contains("Ctrl-C")),
                "{path}: the interrupt was not taken"
            );
        }
    }
}

#[test]
fn the_director_ahead_takes_the_frames_the_loop_takes_at_any_rates() {
    // A faster motion capture than the loop (frames the loop never sees), a slower one (ticks
    // without a frame), and a loop at 50 Hz.
    for (loop_hz, mocap_hz) in [(100.0, 240.0), (100.0, 60.0), (50.0, 120.0)] {
        let rates = Rates { loop_hz, mocap_hz };
        for path in ["shots/two-actors.psl", "shots/scene.psl"] {
            let (_, report) = same_flight_at(path, 4, None, rates);
            assert!(
                report.contains("completed: true"),
                "{path} at {loop_hz} Hz, mocap {mocap_hz} Hz: {report}"
            );
        }
    }
}
