//! Replay is deterministic and can tell: a flight logged to MCAP replays with zero
//! mismatches, and one altered command in the log is found. A damaged log costs at most the
//! chunk the damage hits: replay resumes after it from the next chunk's key frame and checks
//! every tick it read (a sweep flips every byte of a log's first 32 KB and 1,000 more), and
//! what it read counts in the report. A crash during take-off loses at most its last second.

use dronecine_flight::replay::replay;
use dronecine_flight::NoObserver;
use dronecine_mcap::log::{FlightLog, FlightLogWriter, LogOptions, LogScene};
use dronecine_mcap::record::{Event, FlightHeader, FlightSink, Phase, TickRecord};
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::control::ControllerState;
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
    fly_logged(
        text,
        controller,
        100.0,
        LogOptions::default(),
        path,
        |log| log,
    )
}

/// Flies `text` (its actors named A, B, … as the script lists them) at `rate_hz` on the
/// simulator (seed 9) into a log at `path` written with `options`, through the sink `wrap`
/// makes of the log's writer.
fn fly_logged<S: FlightSink + Finish>(
    text: &str,
    controller: &str,
    rate_hz: f64,
    options: LogOptions,
    path: &std::path::Path,
    wrap: impl FnOnce(FlightLogWriter) -> S,
) -> dronecine_flight::report::FlightReport {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(text, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let setup = ControllerSetup::new(controller);
    let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
    let heights: Vec<f64> = names.iter().map(|_| 1.8).collect();
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
        rate_hz,
        actor_names: names.clone(),
        dronecine_version: "test".into(),
    };
    let lens = *dronecine_compiler::director::Director::new(&script, scene, &profile).lens();
    let writer = FlightLogWriter::create_with(
        path,
        &header,
        &LogScene {
            stage: scene.stage,
            lens,
            actor_names: &names,
            actor_heights_m: &heights,
        },
        options,
    )
    .unwrap();
    let mut log = wrap(writer);
    let report = fly_simulated(
        &SimFlight {
            script: &script,
            source: text,
            scene,
            profile: &profile,
            rate_hz,
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
    log.finish();
    report
}

/// A sink that finishes its log.
trait Finish {
    fn finish(self);
}

impl Finish for FlightLogWriter {
    fn finish(self) {
        FlightLogWriter::finish(self).unwrap();
    }
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

/// One flipped bit in a chunk in the middle of the shot: that chunk's ticks are lost, replay
/// resumes at the next chunk from its key frame and checks every tick it read, and the ticks
/// read after the damage count in the report. Without key frames (a log written before them)
/// replay stops at the gap, as it must: the controller's state after it is unknown.
#[test]
fn a_damaged_log_replays_every_tick_it_read_resuming_after_the_damage() {
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
    let lost = whole.ticks.len() - log.ticks.len();
    assert!((1..=100).contains(&lost), "{lost} ticks lost: one chunk's");
    let r = replay(&log).unwrap();
    assert_eq!(r.mismatches, 0, "{:?}", r.first_mismatch);
    assert_eq!(r.state_mismatches, 0);
    assert_eq!(
        (r.ticks, r.unreplayed),
        (log.ticks.len(), 0),
        "every tick read"
    );
    assert_eq!(r.resumed, 1);
    // The report counts every tick read: fewer than the flight's.
    let measured = r.report.figures.measured_ticks;
    assert!(measured < flown.figures.measured_ticks);
    assert!(
        r.report.completed,
        "the flight's end event is after the damage"
    );

    // The same log without its key frames: replayed up to the gap only.
    let without = FlightLog {
        key_frames: Vec::new(),
        ..log.clone()
    };
    let r = replay(&without).unwrap();
    assert_eq!(r.mismatches, 0, "{:?}", r.first_mismatch);
    assert_eq!(r.ticks, gap, "replayed up to the gap");
    assert_eq!(r.unreplayed, log.ticks.len() - gap);
    assert_eq!(r.first_unreplayed, Some(gap));
    assert_eq!(r.report.figures.measured_ticks, measured, "the same report");

    // A key frame that is not the flight's state is found where replay meets it.
    let mut altered = whole.clone();
    let frame = altered
        .key_frames
        .iter_mut()
        .find(|f| f.state.is_some())
        .unwrap();
    let Some(ControllerState::Lqg(s)) = frame.state.as_mut() else {
        panic!("an LQG state")
    };
    s.filter.x[3] += 1e-9;
    assert!(replay(&altered).unwrap().state_mismatches >= 1);
}

/// The ticks of each chunk of `bytes` (a flight log) and its events, as index ranges into
/// `log`'s (the log read whole), with the chunk's byte range.
fn chunk_contents(
    bytes: &[u8],
    log: &FlightLog,
) -> Vec<(
    std::ops::Range<u64>,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
)> {
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    let (mut ticks, mut events) = (0, 0);
    let out: Vec<_> = summary
        .chunk_indexes
        .iter()
        .map(|c| {
            let (t0, e0) = (ticks, events);
            for m in summary.stream_chunk(bytes, c).unwrap() {
                match m.unwrap().channel.topic.as_str() {
                    "/servo/tick" => ticks += 1,
                    "/events" => events += 1,
                    _ => {}
                }
            }
            let at = c.chunk_start_offset;
            (at..at + c.chunk_length, t0..ticks, e0..events)
        })
        .collect();
    assert_eq!((ticks, events), (log.ticks.len(), log.events.len()));
    out
}

/// Where `short` (a log read from a damaged copy) differs from `whole`: the index of the
/// first tick missing, and how many are, when `short` is `whole` less one run of ticks
/// (`None` otherwise).
fn lost_run<T: PartialEq>(whole: &[T], short: &[T]) -> Option<(usize, usize)> {
    let a = whole.iter().zip(short).take_while(|(x, y)| x == y).count();
    let n = whole.len().checked_sub(short.len())?;
    (short[a..] == whole[a + n..]).then_some((a, n))
}

/// The corruption sweep: a short flight's log (a square at 10 Hz, about 24 s from take-off to
/// landing, logged as `shoot` logs it, the plot topics off: every read decodes the whole file)
/// with every byte of its first 32 KB flipped in turn, and 1,000 bytes at seeded random places
/// changed. Each damaged copy opens; it loses at most the ticks and events of the chunk the
/// damaged byte is in (none when the byte is outside every chunk: the records at the start,
/// the summary), each chunk spanning less than a second of flight; and replay checks every
/// tick it read, bit for bit, resuming after the damage from the next chunk's key frame.
#[test]
fn any_damaged_byte_costs_at_most_its_chunk_and_replay_checks_every_tick_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("square.mcap");
    let text = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                path square side 2m center (0, 0) altitude 1.5m for 11s\n";
    let never = 1e-9;
    let options = LogOptions {
        tf_hz: never,
        plot_hz: never,
        measurement_hz: never,
        ..LogOptions::shoot(false)
    };
    fly_logged(text, "lqg", 10.0, options, &path, |log| log);
    let mut bytes = std::fs::read(&path).unwrap();
    let whole = FlightLog::open(&path).unwrap();
    assert!(whole.damage.is_empty() && !whole.truncated);
    let chunks = chunk_contents(&bytes, &whole);
    for (_, ticks, _) in &chunks {
        if let (Some(a), Some(b)) = (whole.ticks.get(ticks.start), ticks.end.checked_sub(1)) {
            assert!(
                whole.ticks[b].input.t_s - a.input.t_s < 1.0,
                "a chunk spans < 1 s"
            );
        }
    }
    let sweep = 32 << 10;
    assert!(bytes.len() > sweep + (16 << 10), "{} bytes", bytes.len());
    let r = replay(&whole).unwrap();
    assert_eq!((r.ticks, r.mismatches), (whole.ticks.len(), 0));

    let mut rng = 0x5eed_u64;
    let mut random = move || {
        // splitmix64
        rng = rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let len = bytes.len() as u64;
    let places: Vec<(usize, u8)> = (0..sweep)
        .map(|p| (p, 0xff))
        .chain((0..1000).map(|_| ((random() % len) as usize, (random() % 255) as u8 + 1)))
        .collect();
    // Replay's verdict depends only on what was read: the log less one run of ticks and key
    // frames, and where the gaps are (checked below for each copy).
    let mut verdicts: std::collections::HashMap<(usize, usize, Vec<usize>, usize), usize> =
        std::collections::HashMap::new();
    let (mut worst_ticks, mut worst_s, mut checked) = (0usize, 0.0f64, 0usize);
    for &(p, mask) in &places {
        bytes[p] ^= mask;
        let name = std::path::Path::new("damaged.mcap");
        let log = FlightLog::from_bytes(name, &bytes)
            .unwrap_or_else(|e| panic!("byte {p} ^ {mask:#04x}: {e}"));
        bytes[p] ^= mask;
        let case = format!("byte {p} ^ {mask:#04x}: {:?}", log.damage);
        assert_eq!(log.header, whole.header, "{case}");
        let chunk = chunks
            .iter()
            .find(|(range, _, _)| range.contains(&(p as u64)));
        let (ticks, events) = chunk.map_or((0..0, 0..0), |(_, t, e)| (t.clone(), e.clone()));
        let (a, n) = lost_run(&whole.ticks, &log.ticks).unwrap_or_else(|| panic!("{case}"));
        assert!(
            n == 0 || (ticks.start <= a && a + n <= ticks.end),
            "{case}: ticks {a}..{} lost, the chunk has {ticks:?}",
            a + n
        );
        let (e, m) = lost_run(&whole.events, &log.events).unwrap_or_else(|| panic!("{case}"));
        assert!(
            m == 0 || (events.start <= e && e + m <= events.end),
            "{case}"
        );
        let frames = lost_run(&whole.key_frames, &log.key_frames);
        let (f, k) = match frames {
            Some(x) => x,
            // The read frames' tick indices move down by the ticks lost before them.
            None => {
                let same = log.key_frames.iter().all(|x| {
                    whole.key_frames.iter().any(|y| {
                        y.t_s.to_bits() == x.t_s.to_bits()
                            && (y.tick == x.tick || y.tick == x.tick + n)
                            && y.state == x.state
                    })
                });
                assert!(same, "{case}: key frames");
                (usize::MAX, whole.key_frames.len() - log.key_frames.len())
            }
        };
        if n > 0 {
            worst_ticks = worst_ticks.max(n);
            let span = whole.ticks[a + n - 1].input.t_s - whole.ticks[a].input.t_s + 0.1;
            worst_s = worst_s.max(span);
        }
        let gaps: Vec<usize> = log
            .damage
            .iter()
            .filter(|d| d.resumed_at.is_some())
            .map(|d| d.tick)
            .collect();
        let verdict = *verdicts
            .entry((a * (n > 0) as usize, n, gaps, f.min(k)))
            .or_insert_with(|| {
                let r = replay(&log).unwrap_or_else(|e| panic!("{case}: {e}"));
                assert_eq!(r.mismatches, 0, "{case}: {:?}", r.first_mismatch);
                assert_eq!(r.state_mismatches, 0, "{case}");
                assert_eq!(r.unreplayed, 0, "{case}: every tick read is checked");
                assert_eq!(r.ticks, log.ticks.len(), "{case}");
                r.ticks
            });
        assert_eq!(verdict, log.ticks.len(), "{case}");
        checked += verdict;
    }
    assert!(
        worst_ticks > 0 && worst_s < 1.0,
        "{worst_ticks} ticks, {worst_s} s"
    );
    eprintln!(
        "{} places: at worst {worst_ticks} ticks lost ({worst_s:.2} s of flight); replay \
         checked {checked} ticks ({} replays)",
        places.len(),
        verdicts.len()
    );
}

/// A crash at any moment before the first controlled tick (waiting for the motion capture,
/// the drone's own take-off) loses at most the last second: the flight loop tells the log the
/// time on those ticks, and the log closes its chunks by it. Here the log's file is read as a
/// crash would leave it at every such tick, with an event written at each (so that there is
/// something to lose), through the writer `shoot`'s thread uses, with `shoot`'s chunks.
#[test]
fn a_crash_during_take_off_loses_at_most_the_last_second() {
    /// The writer, with a probe event at every tick that records nothing, and the file as a
    /// crash would leave it checked there.
    struct Crash {
        log: FlightLogWriter,
        path: std::path::PathBuf,
        probes: Vec<f64>,
        ticked: bool,
        checked: usize,
    }
    impl FlightSink for Crash {
        fn tick(&mut self, record: &TickRecord) -> std::io::Result<()> {
            self.ticked = true;
            self.log.tick(record)
        }
        fn event(&mut self, event: &Event) -> std::io::Result<()> {
            self.log.event(event)
        }
        fn idle(&mut self, t_s: f64) -> std::io::Result<()> {
            if !self.ticked {
                self.probes.push(t_s);
                self.log.event(&Event {
                    t_s,
                    level: "info".into(),
                    kind: "probe".into(),
                    message: String::new(),
                    line: None,
                    help: None,
                })?;
            }
            self.log.idle(t_s)?;
            if !self.ticked {
                let bytes = std::fs::read(&self.path).unwrap();
                let log = FlightLog::from_bytes(&self.path, &bytes).unwrap();
                assert!(log.truncated);
                let kept = log.events.iter().filter(|e| e.kind == "probe").count();
                let must = self.probes.iter().filter(|&&t| t <= t_s - 1.0).count();
                assert!(kept >= must, "at {t_s} s: {kept} probes kept, {must} due");
                self.checked += 1;
            }
            Ok(())
        }
        fn wants_key_frame(&self) -> bool {
            self.log.wants_key_frame()
        }
        fn key_frame(&mut self, state: &ControllerState) -> std::io::Result<()> {
            self.log.key_frame(state)
        }
    }
    impl Finish for Crash {
        fn finish(self) {
            assert!(
                self.checked > 300,
                "{} crashes before the first tick",
                self.checked
            );
            let took_off = self.probes.last().unwrap() - self.probes[0];
            assert!(took_off > 3.0, "{took_off} s of take-off");
            self.log.finish().unwrap();
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("take-off.mcap");
    let owned = path.clone();
    fly_logged(
        SCRIPT,
        "lqg",
        100.0,
        LogOptions::shoot(false),
        &path,
        |log| Crash {
            log,
            path: owned,
            probes: Vec::new(),
            ticked: false,
            checked: 0,
        },
    );
    let log = FlightLog::open(&path).unwrap();
    assert!(log.damage.is_empty());
    assert_eq!(replay(&log).unwrap().mismatches, 0);
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
