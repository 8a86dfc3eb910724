//! Replay is deterministic and can tell: a flight logged to MCAP replays with zero
//! mismatches, and one altered command in the log is found. A damaged log replays up to its
//! damage, and what follows still counts in the report.

use dronecine_flight::replay::replay;
use dronecine_flight::NoObserver;
use dronecine_mcap::log::{FlightLog, FlightLogWriter, LogScene};
use dronecine_mcap::record::{FlightHeader, Phase};
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.80m at (0, 0) facing 0deg\n\
                      at 1s A walks to (1, 0.5) over 3s\n\
                      MS on A 34left for 5s\n";

fn fly_to_log(controller: &str, path: &std::path::Path) -> dronecine_flight::report::FlightReport {
    fly_script_to_log(SCRIPT, controller, path)
}

/// [`fly_to_log`] of `text`, whose one actor is named A.
fn fly_script_to_log(
    text: &str,
    controller: &str,
    path: &std::path::Path,
) -> dronecine_flight::report::FlightReport {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(text, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let setup = ControllerSetup::new(controller);
    let names = vec!["A".to_string()];
    let header = FlightHeader {
        script_name: "walk.psl".into(),
        script_text: text.into(),
        profile_name: profile.name.clone(),
        profile_toml: profile.to_toml(),
        profile: profile.clone(),
        controller: setup.clone(),
        backend: "sim".into(),
        seed: Some(9),
        sim_effects_off: None,
        rate_hz: 100.0,
        actor_names: names.clone(),
        dronecine_version: "test".into(),
    };
    let lens = *dronecine_compiler::director::Director::new(&script, scene, &profile).lens();
    let writer = FlightLogWriter::create(
        path,
        &header,
        &LogScene {
            stage: scene.stage,
            lens,
            actor_names: &names,
            actor_heights_m: &[1.8],
        },
    )
    .unwrap();
    let mut log = writer;
    let report = fly_simulated(
        &SimFlight {
            script: &script,
            source: text,
            scene,
            profile: &profile,
            rate_hz: 100.0,
            controller: setup,
            plant: None,
            sim: SimConfig::new(9),
            realtime: false,
            interrupts: None,
        },
        &mut log,
        &mut NoObserver,
    )
    .unwrap();
    log.finish().unwrap();
    report
}

#[test]
fn a_logged_flight_replays_exactly_and_an_altered_command_is_found() {
    let dir = tempfile::tempdir().unwrap();
    for controller in ["lqg", "pid"] {
        let path = dir.path().join(format!("{controller}.mcap"));
        let flown = fly_to_log(controller, &path);
        let log = FlightLog::open(&path).unwrap();
        assert!(!log.truncated);
        let r = replay(&log).unwrap();
        assert_eq!(r.mismatches, 0, "{controller}: {:?}", r.first_mismatch);
        assert!(r.ticks > 500);
        assert_eq!(r.report, flown, "{controller}: the report again");

        // One command off by one unit in the last place: found, at that tick.
        let mut altered = log.clone();
        let k = altered.ticks.len() / 2;
        let out = altered.ticks[k].output.as_mut().unwrap();
        out.command.pitch_rad = f64::from_bits(out.command.pitch_rad.to_bits() + 1);
        let r = replay(&altered).unwrap();
        assert_eq!(r.mismatches, 1);
        assert_eq!(r.first_mismatch.unwrap().tick, k);
    }
}

#[test]
fn a_damaged_log_replays_up_to_the_damage_and_reports_all_it_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lqg.mcap");
    let flown = fly_to_log("lqg", &path);
    let whole = FlightLog::open(&path).unwrap();
    // The chunk that holds the middle of the shot: one bit of it flipped.
    let in_shot: Vec<f64> = whole
        .ticks
        .iter()
        .filter(|t| t.phase == Phase::Shots)
        .map(|t| t.input.t_s)
        .collect();
    let mid_ns = (in_shot[in_shot.len() / 2] * 1e9).round() as u64;
    let mut bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let c = summary
        .chunk_indexes
        .iter()
        .find(|c| (c.message_start_time..=c.message_end_time).contains(&mid_ns))
        .unwrap();
    bytes[(c.chunk_start_offset + c.chunk_length / 2) as usize] ^= 0x01;
    let damaged = dir.path().join("damaged.mcap");
    std::fs::write(&damaged, &bytes).unwrap();

    let log = FlightLog::open(&damaged).unwrap();
    let gap = log.first_gap().expect("the damaged chunk is skipped");
    assert!(
        gap > 0 && gap < log.ticks.len(),
        "{gap} of {}",
        log.ticks.len()
    );
    let r = replay(&log).unwrap();
    assert_eq!(r.mismatches, 0, "{:?}", r.first_mismatch);
    assert_eq!(r.ticks, gap, "replayed up to the gap");
    assert_eq!(r.unreplayed, log.ticks.len() - gap);
    // The report counts every tick read: fewer than the flight's, more than the replayed.
    assert!(log.ticks.len() < whole.ticks.len());
    let measured = r.report.figures.measured_ticks;
    assert!(measured < flown.figures.measured_ticks);
    let replayed_only = replay(&FlightLog {
        ticks: log.ticks[..gap].to_vec(),
        ..log.clone()
    })
    .unwrap();
    assert!(measured > replayed_only.report.figures.measured_ticks);
    assert!(
        r.report.completed,
        "the flight's end event is after the damage"
    );
}

/// The report's `closest_actor_m` is the least distance, over the shots' ticks, from the
/// drone's logged measurement to an actor's body as the log has them: the segment from the
/// feet up to the head, so a drone beside the actor is its horizontal distance away and one
/// above the head its distance to the top of the head. Here A walks past a camera that
/// frames them at an MS, about 0.9 m away.
#[test]
fn the_report_says_how_close_the_drone_came_to_an_actor() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("closest.mcap");
    let flown = fly_to_log("lqg", &path);
    let log = FlightLog::open(&path).unwrap();
    let mut closest = f64::INFINITY;
    let mut per_shot = f64::INFINITY;
    for t in log.ticks.iter().filter(|t| t.phase == Phase::Shots) {
        let Some(m) = t.input.measurement else {
            continue;
        };
        for a in &t.actors {
            let horizontal =
                (m.position_m[0] - a.position_m[0]).hypot(m.position_m[1] - a.position_m[1]);
            let head = a.position_m[2] + a.height_m;
            let d = if m.position_m[2] > head {
                horizontal.hypot(m.position_m[2] - head)
            } else if m.position_m[2] < a.position_m[2] {
                horizontal.hypot(a.position_m[2] - m.position_m[2])
            } else {
                horizontal
            };
            closest = closest.min(d);
            if t.shot == Some(0) {
                per_shot = per_shot.min(d);
            }
        }
    }
    let got = flown.figures.closest_actor_m.unwrap();
    assert!((got - closest).abs() < 1e-12, "{got} against {closest}");
    // Computed another way here (`hypot`, not the segment's nearest point): to the last bits.
    let shot = flown.shots[0].figures.closest_actor_m.unwrap();
    assert!((shot - per_shot).abs() < 1e-12, "{shot} against {per_shot}");
    assert!((0.5..1.5).contains(&got), "{got}");
}

/// The tracking margin the drone used (`cut_in_m`) is computed again from the log, with the
/// logged profile's margin: here a close-up of A (0.6 m on set, inside the 0.70 m where the
/// reference counts), whose report has one.
#[test]
fn replay_measures_the_tracking_margin_used_again() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("close.mcap");
    let text = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                actor A height 1.80m at (0, 0) facing 0deg\n\
                at 1s A walks to (0.5, 0.5) over 3s\n\
                MCU on A 34left for 5s\n";
    let flown = fly_script_to_log(text, "lqg", &path);
    let used = flown.figures.cut_in_m.expect("the reference near A");
    assert!(used.abs() < 0.1, "{used}");
    let r = replay(&FlightLog::open(&path).unwrap()).unwrap();
    assert_eq!(r.mismatches, 0);
    assert_eq!(r.report.figures.cut_in_m, Some(used));
    assert_eq!(r.report, flown);
}
