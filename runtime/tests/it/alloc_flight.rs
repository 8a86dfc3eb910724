//! The whole control loop allocates nothing per tick once it runs: a counting global
//! allocator around a simulated two-actor flight (director re-framing live actors, LQG servo,
//! simulator), checked between consecutive ticks of the shots. Ticks that raise an event (a
//! new shot, a failsafe) may allocate its message and are left out. The count is per thread.
//!
//! With the MCAP flight log on, the `mcap` crate's chunk writer grows a fresh buffer for each
//! chunk (one a second) and its record encoder allocates now and then: a handful of
//! allocations a second, bounded here; dronecine's own log code reuses its buffers. Written
//! as `shoot` writes it, on its own thread (`LogThread`), the loop's thread allocates nothing;
//! nor with the director stepped ahead of it on another thread (`SimConfig::actors_ahead`);
//! nor with the live view beside the log (`shoot --live`: `LiveFeed` through `Tee`).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use dronecine_flight::{Observer, Progress};
use dronecine_live::{LiveFeed, LiveServer, Tee};
use dronecine_mcap::log::{FlightLogWriter, LogScene, LogThread};
use dronecine_mcap::record::FlightSink;
use dronecine_mcap::record::{Event, FlightHeader, Phase};
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() -> usize {
    ALLOCATIONS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|a| a.set(a.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|a| a.set(a.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.80m at (-1, 0) facing 0deg\n\
                      actor B height 1.75m at (1, 0) facing 180deg\n\
                      at 1s A walks to (-0.5, 1) over 5s\n\
                      at 2s B walks to (1.5, 0.5) over 5s\n\
                      FS on A and B for 12s\n\
                      then dolly to FS on A screen (-0.6, 0.1) and B screen (0.6, 0.1) over 4s\n";

/// Counts allocations between consecutive shot ticks.
#[derive(Default)]
struct Watch {
    first_shot_s: Option<f64>,
    last: Option<usize>,
    event_since: bool,
    intervals: usize,
    allocating: Vec<(f64, usize)>,
}

impl Observer for Watch {
    fn progress(&mut self, p: &Progress) {
        let now = count();
        if p.phase == Phase::Shots {
            self.first_shot_s.get_or_insert(p.t_s);
            if let (Some(before), false) = (self.last, self.event_since) {
                self.intervals += 1;
                if now > before {
                    // Recording allocates: note it, then re-read the counter.
                    self.allocating.push((p.t_s, now - before));
                }
            }
        }
        self.event_since = false;
        self.last = Some(count());
    }
    fn event(&mut self, _: &Event) {
        self.event_since = true;
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Sink {
    None,
    /// The writer on the loop's thread.
    Direct,
    /// `LogThread`, as `shoot` writes it.
    Thread,
    /// `LogThread` and the live view, as `shoot --live` feeds them.
    Live,
}

/// Flies the script; returns (shot-tick intervals, allocating intervals after warm-up as
/// (time, count)).
fn fly(mode: Sink) -> (usize, Vec<(f64, usize)>) {
    fly_with(mode, false)
}

/// [`fly`], the director stepped ahead of the loop on a thread of its own or not.
fn fly_with(mode: Sink, ahead: bool) -> (usize, Vec<(f64, usize)>) {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(SCRIPT, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let setup = ControllerSetup::new("lqg");
    let names: Vec<String> = vec!["A".into(), "B".into()];
    let dir = tempfile::tempdir().unwrap();
    let writer = FlightLogWriter::create(
        &dir.path().join("f.mcap"),
        &FlightHeader {
            script_name: "a.psl".into(),
            script_text: SCRIPT.into(),
            profile_name: profile.name.clone(),
            profile_toml: String::new(),
            profile: profile.clone(),
            controller: setup.clone(),
            backend: "sim".into(),
            seed: Some(2),
            sim_effects_off: Some(Vec::new()),
            rate_hz: 100.0,
            actor_names: names.clone(),
            dronecine_version: "test".into(),
        },
        &LogScene {
            stage: scene.stage,
            lens: *dronecine_compiler::director::Director::new(&script, scene, &profile).lens(),
            actor_names: &names,
            actor_heights_m: &[1.8, 1.75],
        },
    )
    .unwrap();
    let mut log = Some(writer);
    let mut thread = None;
    if mode == Sink::Thread || mode == Sink::Live {
        thread = Some(LogThread::spawn(log.take().unwrap(), 100.0).unwrap());
    }
    let server =
        (mode == Sink::Live).then(|| LiveServer::bind(([127, 0, 0, 1], 0).into()).unwrap());
    let live_scene = LogScene {
        stage: scene.stage,
        lens: *dronecine_compiler::director::Director::new(&script, scene, &profile).lens(),
        actor_names: &names,
        actor_heights_m: &[1.8, 1.75],
    };
    let mut feed = server
        .as_ref()
        .map(|s| LiveFeed::start(s, &live_scene, false).unwrap());
    let mut null = dronecine_mcap::record::NullSink;
    let mut tee;
    let sink: &mut dyn FlightSink = match (mode, &mut log, &mut thread, &mut feed) {
        (Sink::Direct, Some(log), _, _) => log,
        (Sink::Thread, _, Some(thread), _) => thread,
        (Sink::Live, _, Some(thread), Some(live)) => {
            tee = Tee { log: thread, live };
            &mut tee
        }
        _ => &mut null,
    };
    let mut watch = Watch::default();
    let report = fly_simulated(
        &SimFlight {
            script: &script,
            source: SCRIPT,
            scene,
            profile: &profile,
            rate_hz: 100.0,
            controller: setup,
            plant: None,
            sim: SimConfig {
                actors_ahead: ahead,
                ..SimConfig::new(2)
            },
            realtime: false,
            interrupts: None,
        },
        sink,
        &mut watch,
    )
    .unwrap();
    match (log, thread) {
        (Some(log), _) => log.finish().unwrap(),
        (_, Some(thread)) => thread.finish().unwrap(),
        _ => {}
    }
    if let Some(feed) = feed {
        // As fast as it goes, the flight outruns the live thread: the ticks it has no room
        // for are dropped (both paths of the loop's side run), never waited for.
        let live = feed.finish();
        assert!(live.ticks_served > 0, "{live:?}");
        assert!(live.ticks_served + live.ticks_dropped > 1500, "{live:?}");
    }
    assert!(report.completed);
    // The first second of the shots warms the buffers up.
    let start = watch.first_shot_s.unwrap();
    let late = watch
        .allocating
        .into_iter()
        .filter(|(t, _)| *t > start + 1.0)
        .collect();
    (watch.intervals, late)
}

/// Every shot tick after the warm-up allocated nothing.
fn assert_none_late((intervals, late): (usize, Vec<(f64, usize)>)) {
    assert!(intervals > 1500, "{intervals} intervals");
    assert!(
        late.is_empty(),
        "{} of {intervals} shot ticks allocated after warm-up: {:?}",
        late.len(),
        &late[..late.len().min(10)]
    );
}

#[test]
fn a_flight_tick_allocates_nothing() {
    assert_none_late(fly(Sink::None));
}

#[test]
fn with_the_flight_log_only_the_mcap_chunks_allocate() {
    let (intervals, late) = fly(Sink::Direct);
    let total: usize = late.iter().map(|(_, n)| n).sum();
    // ~16 s of shots: a chunk a second, a few allocations each.
    assert!(
        total < 40 * 16,
        "{total} allocations over {intervals} ticks"
    );
}

/// `shoot`'s log: the loop copies each tick into a reused batch and hands it to the writer
/// thread; on the loop's thread nothing allocates once the batches are warm.
#[test]
fn with_the_log_on_its_own_thread_the_loop_allocates_nothing() {
    assert_none_late(fly(Sink::Thread));
}

/// With the director stepped ahead of the loop on a thread of its own (the counts are per
/// thread: that thread's director is the one the tests above count on the loop's): the loop
/// takes its ticks from reused batches, and allocates nothing, its log on its own thread too.
#[test]
fn with_the_director_ahead_the_loop_allocates_nothing() {
    assert_none_late(fly_with(Sink::None, true));
    assert_none_late(fly_with(Sink::Thread, true));
}

/// `shoot --live`'s loop: each tick copied into a preallocated slot of the live view's ring
/// besides the log's batch; the loop's thread allocates nothing.
#[test]
fn with_the_live_view_beside_the_log_the_loop_allocates_nothing() {
    assert_none_late(fly(Sink::Live));
}

/// The Crazyflie backend's per-tick calls (the motion capture forwarded, a command, a hold,
/// the telemetry) allocate nothing on the loop's thread, over UDP to the Crazyflie emulator
/// in this process (its own thread's allocations are its own).
#[test]
fn the_crazyflie_backends_tick_allocates_nothing() {
    use dronecine_backend::frames::Command;
    use dronecine_backend::{BodyPose, Drone, FlightState};
    use dronecine_crazyflie::{CrazyflieDrone, CrazyflieOptions, CrazyflieUrl};
    use dronecine_emulator::{empty_scene, CrazyflieEmulator, CrazyflieEmulatorConfig};
    use std::time::{Duration, Instant};

    let profile = Profile::builtin("crazyflie21").unwrap();
    let mut config = CrazyflieEmulatorConfig::new(profile.clone(), empty_scene(), 2);
    config.port = 0;
    config.natnet = None;
    config.sim.effects = dronecine_sim::Effects::none();
    let emulator = CrazyflieEmulator::start(config).unwrap();
    let url = CrazyflieUrl::parse(&format!("crazyflie+udp://{}", emulator.addr())).unwrap();
    let options = CrazyflieOptions {
        hover_height_m: 0.3,
        ..CrazyflieOptions::default()
    };
    let mut drone = CrazyflieDrone::connect(&url, &profile, options).unwrap();
    let mut fwd = drone.forwarder();
    let start = Instant::now();
    let pose = |t: f64| BodyPose {
        position_m: [0.0, 0.0, emulator.status().truth.position_m[2]],
        heading_rad: 0.01 * t,
    };
    let mut tick = |drone: &mut CrazyflieDrone, command: Option<&Command>| {
        let t = start.elapsed().as_secs_f64();
        let p = pose(t);
        let before = count();
        fwd.forward(t, &p).unwrap();
        match command {
            Some(c) => drone.send(c).unwrap(),
            None => drone.hover().unwrap(),
        }
        let state = drone.telemetry().state;
        let allocated = count() - before;
        std::thread::sleep(Duration::from_millis(10));
        (state, allocated)
    };
    drone.take_off().unwrap();
    let deadline = Instant::now() + Duration::from_secs(15);
    while tick(&mut drone, None).0 != FlightState::Flying {
        assert!(Instant::now() < deadline, "no take-off");
    }
    let command = Command {
        roll_rad: 0.01,
        pitch_rad: -0.01,
        yaw_rate_radps: 0.1,
        vz_mps: 0.0,
    };
    // Warm-up (the hold's first set-point, the supervisor's first bits told), then counted.
    for _ in 0..20 {
        tick(&mut drone, Some(&command));
    }
    let mut allocated = 0;
    for i in 0..200 {
        let c = (i % 2 == 0).then_some(&command);
        allocated += tick(&mut drone, c).1;
    }
    assert_eq!(allocated, 0, "allocations in 200 ticks");
}
