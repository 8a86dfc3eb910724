//! The flight loop's failsafes and faults, on the embedded simulator wrapped to misbehave:
//! the drone's body lost by the mocap, a NaN measurement, time going backward, the drone
//! pushed out of the stage, the director ahead of the loop given other frames than the loop,
//! and the pre-flight checks. Each ends in a defined, logged
//! behaviour — never a panic.

use dronecine_backend::{BackendError, Backends, Clock, Drone, FlightState, Mocap, MocapFrame};
use dronecine_diag::Diagnostic;
use dronecine_flight::report::FlightReport;
use dronecine_flight::{
    self as flight, FlightError, FlightSetup, Observer, PreflightCode, Progress, Safety,
};
use dronecine_mcap::record::{Event, FlightSink, Phase, TickRecord};
use dronecine_profile::Profile;
use dronecine_runtime::start_pose;
use dronecine_servo::setup::{controller_for, ControllerSetup};
use dronecine_sim::{SimConfig, Simulator};

const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.80m at (0, 0) facing 0deg\n\
                      MS on A 34left for 6s\n";

/// What a wrapper does to the mocap stream.
#[derive(Clone, Copy, Default)]
struct Faults {
    /// From this time on, the drone's body is not tracked.
    lose_drone_from_s: Option<f64>,
    /// At the first frame after this time, the drone's x is NaN.
    nan_at_s: Option<f64>,
    /// From this time on, the drone is reported this much off in x.
    shift_from_s: Option<(f64, f64)>,
    /// The actors are never tracked.
    lose_actors: bool,
    /// Actor `.0` is not tracked from `.1` until `.2` seconds.
    lose_actor: Option<(usize, f64, f64)>,
    /// Actor `.0` is measured this far (x, y) from where they are: off their mark.
    shift_actor: Option<(usize, [f64; 2])>,
    /// From `.1` seconds on, actor `.0` is measured this far (x, y) off: they step off
    /// their mark then.
    step_actor: Option<(usize, f64, [f64; 2])>,
}

struct Faulty<M: Mocap> {
    inner: M,
    faults: Faults,
    nan_done: bool,
}

impl<M: Mocap> Mocap for Faulty<M> {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        let fresh = self.inner.poll(frame)?;
        if fresh {
            if self
                .faults
                .lose_drone_from_s
                .is_some_and(|t| frame.t_s >= t)
            {
                frame.drone = None;
            }
            if self.faults.lose_actors {
                frame.actors.iter_mut().for_each(|a| *a = None);
            }
            if let Some((i, [dx, dy])) = self.faults.shift_actor {
                if let Some(Some(a)) = frame.actors.get_mut(i) {
                    a.position_m[0] += dx;
                    a.position_m[1] += dy;
                }
            }
            if let Some((i, from_s, [dx, dy])) = self.faults.step_actor {
                if let Some(Some(a)) = frame.actors.get_mut(i).filter(|_| frame.t_s >= from_s) {
                    a.position_m[0] += dx;
                    a.position_m[1] += dy;
                }
            }
            if let Some((i, from, until)) = self.faults.lose_actor {
                if (from..until).contains(&frame.t_s) {
                    frame.actors[i] = None;
                }
            }
            if let (Some(t), false) = (self.faults.nan_at_s, self.nan_done) {
                if frame.t_s >= t {
                    if let Some(d) = frame.drone.as_mut() {
                        d.position_m[0] = f64::NAN;
                        self.nan_done = true;
                    }
                }
            }
            if let Some((t, dx)) = self.faults.shift_from_s {
                if frame.t_s >= t {
                    if let Some(d) = frame.drone.as_mut() {
                        d.position_m[0] += dx;
                    }
                }
            }
        }
        Ok(fresh)
    }

    fn action(&mut self, t_s: f64) {
        self.inner.action(t_s);
    }
}

/// A clock that jumps back once, at `at_s`, by `back_s`.
struct Jumpy<C: Clock> {
    inner: C,
    at_s: f64,
    back_s: f64,
    jumped: bool,
}

impl<C: Clock> Clock for Jumpy<C> {
    fn now_s(&mut self) -> f64 {
        let t = self.inner.now_s();
        if !self.jumped && t >= self.at_s {
            self.jumped = true;
            return t - self.back_s;
        }
        t
    }
    fn sleep_until(&mut self, t_s: f64) {
        self.inner.sleep_until(t_s);
    }
}

#[derive(Default)]
struct Recorder {
    events: Vec<Event>,
    ticks: usize,
    hover_ticks_in_shots: usize,
    /// The phases the progress display was shown, each once, in order.
    phases: Vec<Phase>,
    /// Each progress report's phase and position on the script's clock.
    script_times: Vec<(Phase, f64)>,
    /// During the approach, the least horizontal distance from the reference and from the
    /// measured drone to an actor (below the top of their safety cylinder, 0.5 m over the
    /// head).
    approach_clearance_m: Option<(f64, f64)>,
    /// The reference of the approach's first tick.
    approach_start_m: Option<[f64; 3]>,
    /// The reference of the previous tick, and the largest step between two ticks'.
    last_reference_m: Option<[f64; 3]>,
    max_reference_step_m: f64,
    /// The drone as last measured before the landing command (the last tick's frame), and
    /// the reference of the last tick of the shots.
    last_measured_m: Option<[f64; 3]>,
    shots_end_m: Option<[f64; 3]>,
}

/// The observer's side of [`Recorder`]: the phases of the progress reports, and their
/// script times.
#[derive(Default)]
struct Phases(Vec<Phase>, Vec<(Phase, f64)>);

impl Observer for Phases {
    fn progress(&mut self, p: &Progress) {
        if self.0.last() != Some(&p.phase) {
            self.0.push(p.phase);
        }
        self.1.push((p.phase, p.script_t_s));
    }
}

impl FlightSink for Recorder {
    fn tick(&mut self, r: &TickRecord) -> std::io::Result<()> {
        self.ticks += 1;
        let p = r.sample.position_m;
        if let Some(q) = self.last_reference_m.replace(p) {
            let step =
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            self.max_reference_step_m = self.max_reference_step_m.max(step);
        }
        if r.phase == Phase::Approach {
            self.approach_start_m.get_or_insert(r.sample.position_m);
            let clearance = |p: [f64; 3]| {
                (r.actors.iter())
                    .filter(|a| p[2] <= a.position_m[2] + a.height_m + 0.5)
                    .map(|a| (p[0] - a.position_m[0]).hypot(p[1] - a.position_m[1]))
                    .fold(f64::INFINITY, f64::min)
            };
            let reference = clearance(r.sample.position_m);
            let measured = r
                .mocap
                .and_then(|f| f.drone)
                .map_or(f64::INFINITY, |d| clearance(d.position_m));
            let (a, b) = self
                .approach_clearance_m
                .unwrap_or((f64::INFINITY, f64::INFINITY));
            self.approach_clearance_m = Some((a.min(reference), b.min(measured)));
        }
        if let Some(d) = r.mocap.and_then(|f| f.drone) {
            self.last_measured_m = Some(d.position_m);
        }
        if r.phase == Phase::Shots {
            self.shots_end_m = Some(r.sample.position_m);
        }
        if r.phase == Phase::Shots && r.command_sent == dronecine_backend::frames::Command::HOVER {
            self.hover_ticks_in_shots += 1;
        }
        Ok(())
    }
    fn event(&mut self, e: &Event) -> std::io::Result<()> {
        self.events.push(e.clone());
        Ok(())
    }
}

impl Recorder {
    fn kinds(&self) -> Vec<&str> {
        self.events.iter().map(|e| e.kind.as_str()).collect()
    }
    fn first(&self, kind: &str) -> Option<&Event> {
        self.events.iter().find(|e| e.kind == kind)
    }
}

/// The backends one test flies: the simulator's, wrapped as the test wants.
struct Rig {
    drone: Box<dyn Drone>,
    mocap: Box<dyn Mocap>,
    clock: Box<dyn Clock>,
}

impl Rig {
    fn plain(sim: &Simulator) -> Rig {
        Rig {
            drone: Box::new(sim.drone()),
            mocap: Box::new(sim.mocap()),
            clock: Box::new(sim.clock()),
        }
    }
}

/// The script `src` (valid: the tests' scripts are).
fn parse(src: &str) -> dronecine_grammar::Script {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    dronecine_grammar::check(src, &opts)
        .script
        .expect("valid script")
}

/// Flies `src` (actors waiting for "action!", the drone below its first framing) on the
/// simulator set up by `config`, through the backends `rig` makes of it.
fn fly_on(
    src: &str,
    config: impl FnOnce(&mut SimConfig),
    interrupts: Option<&std::sync::atomic::AtomicU32>,
    rig: impl FnOnce(&Simulator) -> Rig,
) -> (Result<FlightReport, FlightError>, Recorder, FlightState) {
    fly_at(100.0, src, config, interrupts, rig)
}

/// [`fly_on`] with the loop at `rate_hz`.
fn fly_at(
    rate_hz: f64,
    src: &str,
    config: impl FnOnce(&mut SimConfig),
    interrupts: Option<&std::sync::atomic::AtomicU32>,
    rig: impl FnOnce(&Simulator) -> Rig,
) -> (Result<FlightReport, FlightError>, Recorder, FlightState) {
    let script = parse(src);
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut cfg = SimConfig::new(3);
    (cfg.start_position_m, cfg.start_heading_rad) = start_pose(&script, scene, &profile, &cfg);
    cfg.wait_for_action = true;
    config(&mut cfg);
    let sim = Simulator::new(&cfg, &profile, scene).unwrap();
    let mut backends = rig(&sim);
    let setup = ControllerSetup::new("lqg");
    let mut controller = controller_for(&setup, &profile, rate_hz).unwrap();
    let mut rec = Recorder::default();
    let mut phases = Phases::default();
    let result = flight::fly(
        &FlightSetup {
            script: &script,
            source: src,
            scene,
            profile: &profile,
            rate_hz,
            safety: Safety::default(),
            interrupts,
        },
        controller.as_mut(),
        Backends {
            drone: backends.drone.as_mut(),
            mocap: backends.mocap.as_mut(),
            clock: backends.clock.as_mut(),
        },
        &mut rec,
        &mut phases,
    );
    (rec.phases, rec.script_times) = (phases.0, phases.1);
    let state = backends.drone.telemetry().state;
    (result, rec, state)
}

/// Flies `src` on the plain simulator, the drone taking off from `start_m`.
fn fly_from(src: &str, start_m: [f64; 3]) -> (Result<FlightReport, FlightError>, Recorder) {
    let (result, rec, _) = fly_on(src, |c| c.start_position_m = start_m, None, Rig::plain);
    (result, rec)
}

/// The pre-flight refusal's diagnostics, checking that nothing took off.
fn refused_before_take_off(
    r: Result<FlightReport, FlightError>,
    rec: &Recorder,
) -> Vec<Diagnostic> {
    assert!(rec.first("take_off").is_none(), "{:?}", rec.kinds());
    match r {
        Err(FlightError::Preflight(d)) => {
            assert!(d.iter().all(|d| d.is_error() && d.help.is_some()), "{d:?}");
            d
        }
        other => panic!("{other:?}"),
    }
}

/// The codes of a refusal's diagnostics.
fn codes(d: &[Diagnostic]) -> Vec<dronecine_diag::Code> {
    d.iter().map(|d| d.code).collect()
}

/// The text a diagnostic points at in `src` (`""` for one about the set, not the script).
fn at<'a>(src: &'a str, d: &Diagnostic) -> &'a str {
    match d.span.is_placed() {
        true => &src[d.span.start..d.span.end],
        false => "",
    }
}

fn fly_with(
    faults: Faults,
    clock_jump: Option<(f64, f64)>,
    config: impl FnOnce(&mut SimConfig),
) -> (Result<FlightReport, FlightError>, Recorder) {
    let (result, rec, _) = fly_on(SCRIPT, config, None, |sim| Rig {
        mocap: Box::new(Faulty {
            inner: sim.mocap(),
            faults,
            nan_done: false,
        }),
        clock: match clock_jump {
            Some((at_s, back_s)) => Box::new(Jumpy {
                inner: sim.clock(),
                at_s,
                back_s,
                jumped: false,
            }),
            None => Box::new(sim.clock()),
        },
        ..Rig::plain(sim)
    });
    (result, rec)
}

/// Time of the "action!" event (the shots start) in an undisturbed flight.
fn action_s() -> f64 {
    let (r, rec) = fly_with(Faults::default(), None, |_| {});
    assert!(r.unwrap().completed);
    rec.first("action").unwrap().t_s
}

#[test]
fn an_undisturbed_flight_completes_without_failsafes() {
    let (r, rec) = fly_with(Faults::default(), None, |_| {});
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    assert_eq!((r.failsafes, r.faults), (0, 0));
    let kinds = rec.kinds();
    for k in [
        "take_off",
        "approach",
        "settle",
        "action",
        "shot_start",
        "landing",
        "landed",
        "flight_end",
    ] {
        assert!(kinds.contains(&k), "{k} missing from {kinds:?}");
    }
    assert!(r.figures.rms_framing_error.is_some());
    // The progress display follows the flight from its first tick: the take-off, seconds on
    // set, shows as a phase of its own, not as an empty bar.
    assert_eq!(
        rec.phases,
        [
            Phase::TakeOff,
            Phase::Approach,
            Phase::Shots,
            Phase::Landing
        ]
    );
}

#[test]
fn losing_the_drone_hovers_then_lands() {
    let lost_at = action_s() + 2.0;
    let (r, rec) = fly_with(
        Faults {
            lose_drone_from_s: Some(lost_at),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let r = r.unwrap();
    assert!(!r.completed);
    let failsafes: Vec<&Event> = rec.events.iter().filter(|e| e.kind == "failsafe").collect();
    assert!(failsafes.len() >= 2, "{:?}", rec.kinds());
    // Hover after 0.5 s without the drone, land after 2 s.
    let hover = failsafes[0];
    assert!(hover.message.contains("hovering"), "{}", hover.message);
    assert!(
        (hover.t_s - (lost_at + 0.5)).abs() < 0.05,
        "hover at {}",
        hover.t_s
    );
    let land = failsafes
        .iter()
        .find(|e| e.message.contains("landing"))
        .unwrap();
    assert!(
        (land.t_s - (lost_at + 2.0)).abs() < 0.05,
        "land at {}",
        land.t_s
    );
    assert!(
        rec.hover_ticks_in_shots >= 140,
        "{} hover ticks",
        rec.hover_ticks_in_shots
    );
    assert!(rec.first("landed").is_some());
}

/// A mocap body lost is a failsafe for an actor as for the drone (the drone cannot keep clear
/// of an actor it does not see): hover after 0.5 s, land after 2 s; an actor tracked again
/// before that lets the flight go on. Framing a lost actor's last pose instead would fly on
/// a stale actor for as long as they are lost, without a word.
#[test]
fn losing_an_actor_hovers_then_lands_and_finding_them_flies_on() {
    let lost_at = action_s() + 1.0;
    // Lost for 1 s: a hover, then the shot goes on to its end.
    let (r, rec) = fly_with(
        Faults {
            lose_actor: Some((0, lost_at, lost_at + 1.0)),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    assert_eq!(r.failsafes, 1);
    let hover = rec.first("failsafe").unwrap();
    assert_eq!(hover.message, "actor A is not tracked: hovering");
    assert!(
        (hover.t_s - (lost_at + 0.5)).abs() < 0.05,
        "hover at {}",
        hover.t_s
    );
    let back = rec.first("actor_tracked").unwrap();
    assert!(
        (back.t_s - (lost_at + 1.0)).abs() < 0.05,
        "back at {}",
        back.t_s
    );
    // Half a second of hovering, no more.
    assert!(
        (45..=55).contains(&rec.hover_ticks_in_shots),
        "{} hover ticks",
        rec.hover_ticks_in_shots
    );

    // Lost for good: hover, then land 2 s after.
    let (r, rec) = fly_with(
        Faults {
            lose_actor: Some((0, lost_at, f64::INFINITY)),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let r = r.unwrap();
    assert!(!r.completed);
    let land = rec
        .events
        .iter()
        .find(|e| e.kind == "failsafe" && e.message.contains("landing"))
        .unwrap();
    assert_eq!(
        land.message,
        "actor A has not been tracked for 2 s: landing"
    );
    assert!(
        (land.t_s - (lost_at + 2.0)).abs() < 0.05,
        "land at {}",
        land.t_s
    );
    assert!(rec.first("landed").is_some());
}

#[test]
fn a_nan_measurement_is_a_logged_fault_and_the_flight_goes_on() {
    let at = action_s() + 1.0;
    let (r, rec) = fly_with(
        Faults {
            nan_at_s: Some(at),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let r = r.unwrap();
    assert_eq!(r.faults, 1, "{:?}", rec.kinds());
    let fault = rec.first("fault").unwrap();
    assert!(fault.message.contains("NotFinite"), "{}", fault.message);
    assert!(r.completed);
    assert!(
        r.figures.rms_position_error_m.is_some_and(|e| e < 0.1),
        "{:?}",
        r.figures
    );
}

#[test]
fn time_going_backward_is_a_logged_fault() {
    let at = action_s() + 1.0;
    let (r, rec) = fly_with(Faults::default(), Some((at, 0.5)), |_| {});
    let r = r.unwrap();
    assert!(r.faults >= 1, "{:?}", rec.kinds());
    assert!(rec
        .first("fault")
        .unwrap()
        .message
        .contains("TimeNotIncreasing"));
}

#[test]
fn leaving_the_stage_lands() {
    let at = action_s() + 1.0;
    // The mocap says the drone is 10 m off: outside the 8 m stage.
    let (r, rec) = fly_with(
        Faults {
            shift_from_s: Some((at, 10.0)),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let r = r.unwrap();
    assert!(!r.completed);
    let e = rec.first("failsafe").unwrap();
    assert!(e.message.contains("left the stage"), "{}", e.message);
    assert!(rec.first("landed").is_some());
}

#[test]
fn preflight_refuses_an_untracked_drone_or_actor_and_a_flat_battery() {
    let (r, rec) = fly_with(
        Faults {
            lose_drone_from_s: Some(0.0),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let d = refused_before_take_off(r, &rec);
    assert_eq!(codes(&d), [PreflightCode::DroneUntracked.code()], "{d:?}");
    assert_eq!(at(SCRIPT, &d[0]), "", "about the set, not the script");

    let (r, rec) = fly_with(
        Faults {
            lose_actors: true,
            ..Faults::default()
        },
        None,
        |_| {},
    );
    let d = refused_before_take_off(r, &rec);
    assert_eq!(codes(&d), [PreflightCode::ActorUntracked.code()], "{d:?}");
    assert!(at(SCRIPT, &d[0]).starts_with("actor A "), "{d:?}");

    // An actor missing from the first frames only (a marker hidden for a moment; the
    // simulator drops 0.5 % of frames) is tracked: the check waits for a whole frame.
    let (r, rec) = fly_with(
        Faults {
            lose_actor: Some((0, 0.0, 0.05)),
            ..Faults::default()
        },
        None,
        |_| {},
    );
    assert!(rec.first("take_off").is_some(), "{:?}", rec.kinds());
    assert!(r.unwrap().completed, "{:?}", rec.kinds());

    let (r, rec) = fly_with(Faults::default(), None, |c| c.battery_start_percent = 10.0);
    let d = refused_before_take_off(r, &rec);
    assert_eq!(codes(&d), [PreflightCode::BatteryLow.code()], "{d:?}");
}

/// A clock that "presses Ctrl-C" at the given times.
struct Presses<C: Clock> {
    inner: C,
    at_s: Vec<f64>,
    count: &'static std::sync::atomic::AtomicU32,
}

impl<C: Clock> Clock for Presses<C> {
    fn now_s(&mut self) -> f64 {
        self.inner.now_s()
    }
    fn sleep_until(&mut self, t_s: f64) {
        self.inner.sleep_until(t_s);
        let pressed = self.at_s.iter().filter(|&&t| t <= t_s).count() as u32;
        self.count
            .store(pressed, std::sync::atomic::Ordering::Relaxed);
    }
}

fn fly_interrupted(
    presses: Vec<f64>,
    count: &'static std::sync::atomic::AtomicU32,
) -> (FlightReport, Recorder, FlightState) {
    let (r, rec, state) = fly_on(
        SCRIPT,
        |_| {},
        Some(count),
        |sim| Rig {
            clock: Box::new(Presses {
                inner: sim.clock(),
                at_s: presses,
                count,
            }),
            ..Rig::plain(sim)
        },
    );
    (r.unwrap(), rec, state)
}

#[test]
fn ctrl_c_lands_and_a_second_one_cuts_the_motors() {
    use std::sync::atomic::AtomicU32;
    static ONCE: AtomicU32 = AtomicU32::new(0);
    static TWICE: AtomicU32 = AtomicU32::new(0);
    let action = action_s();

    let (r, rec, state) = fly_interrupted(vec![action + 1.0], &ONCE);
    assert!(!r.completed);
    let e = rec.first("failsafe").unwrap();
    assert!(
        e.message.contains("Ctrl-C") && e.message.contains("landing"),
        "{}",
        e.message
    );
    assert!((e.t_s - (action + 1.0)).abs() < 0.05);
    assert_eq!(state, FlightState::Landed);
    assert!(!rec.events.iter().any(|e| e.message.contains("motor cut")));

    let (r, rec, state) = fly_interrupted(vec![action + 1.0, action + 1.5], &TWICE);
    assert!(!r.completed);
    let cut = rec
        .events
        .iter()
        .find(|e| e.message.contains("emergency motor cut"))
        .unwrap();
    assert!(
        cut.t_s >= action + 1.5 && cut.t_s < action + 1.6,
        "{}",
        cut.t_s
    );
    assert_eq!(state, FlightState::Emergency);
}

/// The drone, with the time of every land and motor-cut command sent to it.
struct Obeying<D: Drone, C: Clock> {
    inner: D,
    clock: C,
    sent: std::rc::Rc<std::cell::RefCell<Vec<(f64, &'static str)>>>,
}

impl<D: Drone, C: Clock> Drone for Obeying<D, C> {
    fn take_off(&mut self) -> Result<(), BackendError> {
        self.inner.take_off()
    }
    fn land(&mut self) -> Result<(), BackendError> {
        self.sent.borrow_mut().push((self.clock.now_s(), "land"));
        self.inner.land()
    }
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.sent
            .borrow_mut()
            .push((self.clock.now_s(), "emergency"));
        self.inner.emergency()
    }
    fn send(&mut self, c: &dronecine_backend::frames::Command) -> Result<(), BackendError> {
        self.inner.send(c)
    }
    fn hover(&mut self) -> Result<(), BackendError> {
        self.inner.hover()
    }
    fn telemetry(&mut self) -> dronecine_backend::Telemetry {
        self.inner.telemetry()
    }
}

/// Flies SCRIPT with the operator pressing Ctrl-C at `presses`: the flight's result, its
/// events, and the land and motor-cut commands with their times.
fn fly_pressed(
    presses: Vec<f64>,
    count: &'static std::sync::atomic::AtomicU32,
) -> (
    Result<FlightReport, FlightError>,
    Recorder,
    Vec<(f64, &'static str)>,
) {
    let sent = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let log = std::rc::Rc::clone(&sent);
    let (r, rec, _) = fly_on(
        SCRIPT,
        |_| {},
        Some(count),
        |sim| Rig {
            drone: Box::new(Obeying {
                inner: sim.drone(),
                clock: sim.clock(),
                sent: log,
            }),
            clock: Box::new(Presses {
                inner: sim.clock(),
                at_s: presses,
                count,
            }),
            ..Rig::plain(sim)
        },
    );
    let sent = sent.borrow().clone();
    (r, rec, sent)
}

/// The operator is obeyed in every phase, within one control tick (10 ms at 100 Hz): one
/// Ctrl-C lands the drone (before take-off: keeps it on the ground), a second cuts its motors.
#[test]
fn an_interrupt_is_obeyed_within_a_tick_in_every_phase() {
    use std::sync::atomic::AtomicU32;
    const TICK_S: f64 = 0.01;
    // The phases' starts, from an undisturbed flight.
    let (r, rec) = fly_with(Faults::default(), None, |_| {});
    assert!(r.unwrap().completed);
    let at = |kind: &str| rec.first(kind).unwrap_or_else(|| panic!("no {kind}")).t_s;
    let (take_off, approach, settle, action) =
        (at("take_off"), at("approach"), at("settle"), at("action"));
    let (back, landing) = (at("return"), at("landing"));
    assert!(take_off < approach && approach < settle && settle < action && action < back);

    // Before take-off: refused, on the ground.
    static BEFORE: AtomicU32 = AtomicU32::new(0);
    let (r, rec, sent) = fly_pressed(vec![take_off / 2.0], &BEFORE);
    let d = refused_before_take_off(r, &rec);
    assert_eq!(codes(&d), [PreflightCode::Interrupted.code()], "{d:?}");
    assert!(sent.is_empty(), "{sent:?}");

    // In flight: the land command within a tick of the press, and the motor cut within a
    // tick of the second press.
    static PRESSED: [AtomicU32; 7] = [const { AtomicU32::new(0) }; 7];
    let phases = [
        ("take-off", (take_off + approach) / 2.0),
        ("approach", (approach + settle) / 2.0),
        ("settle", settle + 0.5),
        ("shots", action + 1.0),
        ("return", back + 0.5),
        ("landing", landing + 0.5),
        ("hold", back - 0.5),
    ];
    for ((phase, press_s), count) in phases.into_iter().zip(&PRESSED) {
        let cut_s = press_s + 0.2;
        let (r, rec, sent) = fly_pressed(vec![press_s, cut_s], count);
        let r = r.unwrap_or_else(|e| panic!("{phase}: {e}"));
        // (A flight whose shots are over and which lands is complete, pressed or not.)
        assert_eq!(r.completed, phase == "landing", "{phase}");
        let first = |what: &str, after: f64| {
            (sent.iter())
                .find(|(t, w)| *w == what && *t >= after - 1e-9)
                .map(|(t, _)| *t)
                .unwrap_or_else(|| panic!("{phase}: no {what} after {after} s: {sent:?}"))
        };
        if phase != "landing" {
            let land = first("land", press_s);
            assert!(
                land - press_s <= TICK_S + 1e-9,
                "{phase}: land {land} s, pressed {press_s} s"
            );
        }
        let cut = first("emergency", cut_s);
        assert!(
            cut - cut_s <= TICK_S + 1e-9,
            "{phase}: cut {cut} s, pressed {cut_s} s"
        );
        let cuts = rec
            .events
            .iter()
            .filter(|e| e.message.contains("motor cut"))
            .count();
        assert_eq!(cuts, 1, "{phase}: the cut is told once");
    }
}

/// The drone, reporting `battery_percent` from `from_s` on.
struct Battery<D: Drone, C: Clock> {
    inner: D,
    clock: C,
    from_s: f64,
    battery_percent: f64,
}

impl<D: Drone, C: Clock> Drone for Battery<D, C> {
    fn take_off(&mut self) -> Result<(), BackendError> {
        self.inner.take_off()
    }
    fn land(&mut self) -> Result<(), BackendError> {
        self.inner.land()
    }
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.inner.emergency()
    }
    fn send(&mut self, c: &dronecine_backend::frames::Command) -> Result<(), BackendError> {
        self.inner.send(c)
    }
    fn hover(&mut self) -> Result<(), BackendError> {
        self.inner.hover()
    }
    fn telemetry(&mut self) -> dronecine_backend::Telemetry {
        let mut t = self.inner.telemetry();
        if self.clock.now_s() >= self.from_s {
            t.battery_percent = self.battery_percent;
        }
        t
    }
}

/// A battery level no battery has is broken telemetry: refused before take-off; in flight a
/// level that is not a number lands the drone (it may be low).
#[test]
fn implausible_battery_levels_are_refused_and_an_unknown_one_lands() {
    let with_battery = |from_s: f64, battery_percent: f64| {
        fly_on(
            SCRIPT,
            |_| {},
            None,
            |sim| Rig {
                drone: Box::new(Battery {
                    inner: sim.drone(),
                    clock: sim.clock(),
                    from_s,
                    battery_percent,
                }),
                ..Rig::plain(sim)
            },
        )
    };
    for level in [4_294_967_295.0, -1.0, f64::NAN] {
        let (r, rec, _) = with_battery(0.0, level);
        let d = refused_before_take_off(r, &rec);
        assert_eq!(
            codes(&d),
            [PreflightCode::TelemetryImplausible.code()],
            "{level}: {d:?}"
        );
    }
    let (r, rec, state) = with_battery(action_s() + 1.0, f64::NAN);
    assert!(!r.unwrap().completed);
    let e = rec.first("failsafe").expect("a failsafe");
    assert!(e.message.contains("battery"), "{}", e.message);
    assert_eq!(state, FlightState::Landed);
}

/// The drone's telemetry goes silent from `lost_from_s` on (its link age grows).
struct Silent<D: dronecine_backend::Drone, C: Clock> {
    inner: D,
    clock: C,
    lost_from_s: f64,
}

impl<D: dronecine_backend::Drone, C: Clock> dronecine_backend::Drone for Silent<D, C> {
    fn take_off(&mut self) -> Result<(), BackendError> {
        self.inner.take_off()
    }
    fn land(&mut self) -> Result<(), BackendError> {
        self.inner.land()
    }
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.inner.emergency()
    }
    fn send(&mut self, c: &dronecine_backend::frames::Command) -> Result<(), BackendError> {
        self.inner.send(c)
    }
    fn hover(&mut self) -> Result<(), BackendError> {
        self.inner.hover()
    }
    fn telemetry(&mut self) -> dronecine_backend::Telemetry {
        let mut t = self.inner.telemetry();
        let now = self.clock.now_s();
        if now >= self.lost_from_s {
            t.link_age_s = now - self.lost_from_s;
        }
        t
    }
}

#[test]
fn losing_the_telemetry_lands() {
    let lost = action_s() + 1.0;
    let (r, rec, _) = fly_on(
        SCRIPT,
        |_| {},
        None,
        |sim| Rig {
            drone: Box::new(Silent {
                inner: sim.drone(),
                clock: sim.clock(),
                lost_from_s: lost,
            }),
            ..Rig::plain(sim)
        },
    );
    let r = r.unwrap();
    assert!(!r.completed);
    let e = rec.first("failsafe").unwrap();
    assert!(e.message.contains("no telemetry"), "{}", e.message);
    assert!((e.t_s - (lost + 1.0)).abs() < 0.05, "{}", e.t_s);
    assert!(rec.first("landing").unwrap().t_s >= e.t_s);
}

/// Mocap frames stall for `stall_s` from `from_s` (the network holds them), then all arrive
/// at once: `poll` returns only the newest.
struct Bursty<M: Mocap> {
    inner: M,
    from_s: f64,
    stall_s: f64,
    held: Option<MocapFrame>,
    /// (time a frame was handed out, its capture time).
    delivered: std::rc::Rc<std::cell::RefCell<Vec<(f64, f64)>>>,
}

impl<M: Mocap> Mocap for Bursty<M> {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        let mut newest = MocapFrame::default();
        let fresh = self.inner.poll(&mut newest)?;
        let now = newest.t_s;
        if fresh && now >= self.from_s && now < self.from_s + self.stall_s {
            self.held = Some(newest);
            return Ok(false);
        }
        if let Some(h) = self.held.take() {
            // The burst: the held frames and this one arrive together; the newest wins.
            let pick = if fresh { newest } else { h };
            self.delivered
                .borrow_mut()
                .push((pick.received_s, pick.t_s));
            *frame = pick;
            return Ok(true);
        }
        if fresh {
            *frame = newest;
        }
        Ok(fresh)
    }
    fn action(&mut self, t_s: f64) {
        self.inner.action(t_s);
    }
}

#[test]
fn a_mocap_stall_and_burst_keep_the_loop_ticking() {
    let from = action_s() + 1.0;
    let delivered = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let (r, rec, _) = fly_on(
        SCRIPT,
        |_| {},
        None,
        |sim| Rig {
            mocap: Box::new(Bursty {
                inner: sim.mocap(),
                from_s: from,
                stall_s: 0.3,
                held: None,
                delivered: delivered.clone(),
            }),
            ..Rig::plain(sim)
        },
    );
    let r = r.unwrap();
    // 0.3 s without frames is below the 0.5 s hover failsafe: the flight goes on, the loop
    // ticking at its rate (the filters predict), and completes.
    assert!(r.completed, "{:?}", rec.kinds());
    assert_eq!(r.failsafes, 0);
    let (undisturbed, _) = fly_with(Faults::default(), None, |_| {});
    let undisturbed = undisturbed.unwrap();
    assert_eq!(
        r.figures.measured_ticks + 30,
        undisturbed.figures.measured_ticks,
        "every tick of the stall ran without a measurement, no other tick was lost"
    );
    // After the stall only the newest frame was used.
    let d = delivered.borrow();
    assert_eq!(d.len(), 1);
    assert!((d[0].1 - (from + 0.3)).abs() < 0.011, "{:?}", d[0]);
    assert!(r.figures.rms_position_error_m.is_some_and(|e| e < 0.1));
}

#[test]
fn a_late_tick_is_logged_as_a_missed_deadline() {
    let at = action_s() + 1.0;
    // The clock reads 20 ms late once: the tick ran 2 periods after it was due.
    let (r, rec) = fly_with(Faults::default(), Some((at, -0.02)), |_| {});
    let r = r.unwrap();
    assert_eq!(r.deadline_misses, 1);
    let e = rec.first("deadline_missed").unwrap();
    assert!(e.message.contains("ms late"), "{}", e.message);
    assert!(r.completed);
}

#[test]
fn a_draining_battery_lands_mid_flight() {
    // 21 % at take-off, draining 1 %/s: below the 15 % threshold during the shot.
    let (r, rec) = fly_with(Faults::default(), None, |c| {
        c.battery_start_percent = 21.0;
        c.battery_drain_percent_per_min = 60.0;
    });
    let r = r.unwrap();
    assert!(!r.completed);
    let e = rec.first("failsafe").unwrap();
    assert!(e.message.contains("battery"), "{}", e.message);
    assert!(rec.first("landed").is_some());
}

#[test]
fn preflight_refuses_a_take_off_outside_the_stage_or_by_an_actor() {
    // SCRIPT's stage is 8 m × 6 m, A stands at the origin: the first would be landed by the
    // stage failsafe at once, the second takes off 0.3 m from A.
    let cases = [
        ([-4.5, 0.0, 0.0], PreflightCode::DroneOutsideStage, ""),
        ([0.3, 0.0, 0.0], PreflightCode::DroneTooClose, "actor A "),
    ];
    for (start_m, code, place) in cases {
        let (r, rec) = fly_from(SCRIPT, start_m);
        let d = refused_before_take_off(r, &rec);
        assert_eq!(codes(&d), [code.code()], "{d:?}");
        assert!(at(SCRIPT, &d[0]).starts_with(place), "{d:?}");
    }
}

#[test]
fn preflight_refuses_a_first_framing_where_an_actor_stands() {
    // B, off their mark, stands where the first framing (A's front MS) puts the drone; on
    // their mark, 2 m to the side, the flight is fine.
    let src = "stage 10m x 8m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\n\
               actor B height 1.80m at (0, 2) facing 0deg\nMS on A front for 4s\n";
    let fly = |shift: Option<[f64; 2]>| {
        let faults = Faults {
            shift_actor: shift.map(|d| (1, d)),
            ..Faults::default()
        };
        // (Taking off away from both, so that the take-off spot's own check does not speak.)
        let (r, rec, _) = fly_on(
            src,
            |c| c.start_position_m = [-3.0, -2.0, 0.0],
            None,
            |sim| Rig {
                mocap: Box::new(Faulty {
                    inner: sim.mocap(),
                    faults,
                    nan_done: false,
                }),
                ..Rig::plain(sim)
            },
        );
        (r, rec)
    };
    let (r, rec) = fly(None);
    assert!(r.unwrap().completed, "{:?}", rec.kinds());
    // The front MS puts the camera at (0.80, 0, 1.49) m (compile's first sample).
    let (r, rec) = fly(Some([0.8, -2.0]));
    let d = refused_before_take_off(r, &rec);
    assert_eq!(
        codes(&d),
        [PreflightCode::FirstFramingNearActor.code()],
        "{d:?}"
    );
    assert_eq!(at(src, &d[0]), "MS on A front for 4s", "at the first shot");
    let near = d[0].related.first().map(|r| &src[r.span.start..r.span.end]);
    assert!(near.is_some_and(|t| t.starts_with("actor B ")), "{d:?}");
}

#[test]
fn preflight_refuses_a_first_framing_outside_the_stage() {
    // The actor faces the wall 0.2 m away: the front MS puts the camera outside the stage.
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (3.8, 0) facing 0deg\nMS on A front for 4s\n";
    let (r, rec) = fly_from(src, [3.0, 0.0, 0.0]);
    let d = refused_before_take_off(r, &rec);
    assert_eq!(
        codes(&d),
        [PreflightCode::FirstFramingOutsideStage.code()],
        "{d:?}"
    );
    assert_eq!(at(src, &d[0]), "MS on A front for 4s", "at the first shot");
}

#[test]
fn preflight_refuses_a_first_framing_that_does_not_solve() {
    // Profiles on opposite sides of the line between A and B: no camera stands in both. An
    // unsolved framing's sample is where the director's camera starts, the origin: never
    // flown to.
    let src = "stage 10m x 8m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\n\
               actor B height 1.65m at (1.5, 0) facing 180deg\n\
               MS on B 34backleft LS on A 34left screen right for 6s\n";
    let (r, rec) = fly_from(src, [-3.0, 2.0, 0.0]);
    let d = refused_before_take_off(r, &rec);
    assert_eq!(
        codes(&d),
        [PreflightCode::FirstFramingUnsolved.code()],
        "{d:?}"
    );
    assert!(
        at(src, &d[0]).starts_with("MS on B 34backleft"),
        "at the first shot"
    );
}

#[test]
fn the_approach_flies_round_an_actor_in_its_way() {
    // The drone takes off behind A; the first framing is in front of A: the straight line
    // to it goes through A.
    let src = "stage 10m x 8m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\nMS on A front for 4s\n";
    let (r, rec) = fly_from(src, [-2.5, 0.2, 0.0]);
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    let (reference_m, measured_m) = rec.approach_clearance_m.unwrap();
    // ardrone2 keeps 0.5 m from actors.
    assert!(
        reference_m >= 0.5 - 1e-6,
        "the reference came {reference_m} m from A"
    );
    assert!(measured_m >= 0.4, "the drone came {measured_m} m from A");
    let approach = rec.first("approach").unwrap();
    assert!(
        approach.message.contains("round an actor in the way"),
        "{}",
        approach.message
    );
    assert!(rec.first("approach_not_clear").is_none());

    // Taken off 0.1 m from a wall, inside the stage's 0.3 m margin: no way is clear, which is
    // told; the drone still flies to its framing.
    let (r, rec) = fly_from(src, [-4.9, 0.2, 0.0]);
    assert!(r.unwrap().completed, "{:?}", rec.kinds());
    let told = rec.first("approach_not_clear").unwrap();
    assert_eq!(told.level, "warning");
    // (The hover drifts a few centimetres from the take-off spot.)
    let into_m: f64 = told
        .message
        .split(" m into")
        .next()
        .and_then(|m| m.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{}", told.message));
    assert!((0.1..0.25).contains(&into_m), "{}", told.message);
}

#[test]
fn preflight_refuses_a_scene_without_shots() {
    // The director needs a first shot: a scene without one is refused, never flown.
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n";
    let (r, rec, state) = fly_on(src, |_| {}, None, Rig::plain);
    let d = refused_before_take_off(r, &rec);
    assert_eq!(codes(&d), [PreflightCode::NoShots.code()], "{d:?}");
    assert_eq!(state, FlightState::Landed);
}

/// A loop faster than the mocap (200 Hz against the simulator's 100 Hz frames: every other
/// tick has no fresh frame) aims and sets off from the newest measurement: its heading and
/// framing errors stay under 1.5 times those at 100 Hz (the framing's under 0.05), and the
/// approach sets off from the hover, not from the take-off pose on the ground, with no false
/// `approach_not_clear`. Between frames the aim carries on at its last rate: falling back to
/// the director's heading would make the heading reference jump between two sources every
/// other tick.
#[test]
fn a_loop_faster_than_the_mocap_aims_and_sets_off_from_the_newest_measurement() {
    let src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shots/two-actors.psl"),
    )
    .unwrap();
    let fly = |rate_hz: f64, seed: u64| {
        let (r, rec, _) = fly_at(rate_hz, &src, |c| c.seed = seed, None, Rig::plain);
        let r = r.unwrap();
        assert!(r.completed, "{rate_hz} Hz: {:?}", rec.kinds());
        (r, rec)
    };
    for seed in [1, 2] {
        let (at_100, _) = fly(100.0, seed);
        let (at_200, rec) = fly(200.0, seed);
        let heading = |r: &FlightReport| r.figures.rms_heading_error_rad.unwrap();
        let framing = |r: &FlightReport| r.figures.rms_framing_error.unwrap();
        assert!(
            heading(&at_200) < 1.5 * heading(&at_100),
            "seed {seed}: heading error {:.4} rad at 200 Hz, {:.4} at 100 Hz",
            heading(&at_200),
            heading(&at_100)
        );
        assert!(
            framing(&at_200) < 0.05 && framing(&at_200) < 1.5 * framing(&at_100),
            "seed {seed}: framing error {:.4} at 200 Hz, {:.4} at 100 Hz",
            framing(&at_200),
            framing(&at_100)
        );
        // The approach sets off from the hover after take-off, not from the floor.
        let start = rec.approach_start_m.unwrap();
        assert!(
            start[2] > 0.5,
            "seed {seed}: the approach set off at {start:?}"
        );
        assert!(
            rec.first("approach_not_clear").is_none(),
            "{:?}",
            rec.kinds()
        );
    }
}

/// The progress display's position runs on the script's clock as written: 0 until "action!",
/// from 0 to the script's end over the shots, held at a shot's start while a repositioning
/// flight inserted before it flies, and at the end while landing: the take-off's seconds
/// are not script time, and the position reaches the end when the shots do.
#[test]
fn the_progress_runs_on_the_scripts_clock_as_written() {
    // A cut that needs a repositioning flight: the shots take longer than written.
    const CUT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                       actor A height 1.80m at (0, 0) facing 0deg\n\
                       MS on A front for 3s\ncut to MS on A back for 3s\n";
    let (r, rec, _) = fly_on(CUT, |_| {}, None, Rig::plain);
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    assert!(
        r.shots_time_s > 7.0,
        "a repositioning flight: {} s",
        r.shots_time_s
    );
    let before: Vec<f64> = (rec.script_times.iter())
        .filter(|(p, _)| matches!(p, Phase::TakeOff | Phase::Approach))
        .map(|x| x.1)
        .collect();
    assert!(
        !before.is_empty() && before.iter().all(|&t| t == 0.0),
        "{before:?}"
    );
    let shots: Vec<f64> = (rec.script_times.iter())
        .filter(|(p, _)| *p == Phase::Shots)
        .map(|x| x.1)
        .collect();
    assert!(shots[0] < 0.02, "the shots start at {}", shots[0]);
    assert!(shots.windows(2).all(|w| w[1] >= w[0]), "it never runs back");
    assert!(shots.iter().all(|&t| t <= 6.0 + 1e-9));
    // Held at 3 s for the repositioning flight's length.
    let held = shots.iter().filter(|&&t| t == 3.0).count() as f64 * 0.01;
    assert!(
        (held - (r.shots_time_s - 6.0)).abs() < 0.05,
        "held {held} s for {} s of repositioning",
        r.shots_time_s - 6.0
    );
    assert!((shots.last().unwrap() - 6.0).abs() < 1e-9);
    let landing: Vec<f64> = (rec.script_times.iter())
        .filter(|(p, _)| *p == Phase::Landing)
        .map(|x| x.1)
        .collect();
    assert!(landing.iter().all(|&t| t == 6.0), "{landing:?}");
}

/// An actor who steps off their mark after the approach was planned moves the first framing
/// (here 0.4 m, as an LS of a drifting actor does on `scene.psl`): the drone settles onto it
/// as it is, steered, and the reference never jumps (under 0.02 m a tick); the first shot
/// keeps within 0.10 m and under 1 % saturated. Flying to the framing as planned would make
/// the reference jump the difference at "action!".
#[test]
fn a_first_framing_that_moves_after_the_approach_is_planned_is_steered_to() {
    // The approach is planned when the drone reports flying, a few seconds in.
    let (r, rec) = fly_with(
        Faults {
            step_actor: Some((0, 4.5, [0.0, 0.4])),
            ..Faults::default()
        },
        None,
        |c| c.effects.actor_deviation = false,
    );
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    let approach = rec.first("approach").unwrap().t_s;
    assert!(
        approach < 4.5,
        "the actor steps off after the approach is planned ({approach} s)"
    );
    // The log says how far the first framing moved: A 0.4 m sideways (the simulator's own
    // drift of the actors is off), the MS with them.
    let settle = &rec.first("settle").unwrap().message;
    let moved_m: f64 = settle
        .strip_prefix("settling on the first framing as the actors stand, ")
        .and_then(|m| m.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or(f64::NAN);
    assert!((moved_m - 0.4).abs() < 0.03, "{settle}");
    // At most the profile's top speed (1.84 m/s) for a 10 ms tick, with room for rounding.
    assert!(
        rec.max_reference_step_m < 0.02,
        "the reference jumped {:.3} m in a tick",
        rec.max_reference_step_m
    );
    let first = &r.shots[0].figures;
    assert!(
        first.max_position_error_m.unwrap() < 0.10 && first.saturated_fraction.unwrap() < 0.01,
        "{first:?}"
    );
    assert!(first.rms_framing_error.unwrap() < 0.05, "{first:?}");
}

/// A script that ends on a close-up (MCU on A, 0.6 m from them), its first framing (the
/// take-off spot below it) metres away.
const CLOSE_UP: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                        actor A height 1.80m at (0, 0) facing 0deg\n\
                        MS on A 34left for 4s\nthen dolly to MCU on A front over 4s\n";

/// Where the simulated drone takes off for [`CLOSE_UP`] (as `fly_on` places it).
fn close_up_take_off_m() -> [f64; 3] {
    let script = parse(CLOSE_UP);
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    start_pose(&script, scene, &profile, &SimConfig::new(3)).0
}

/// After the last shot the drone flies back over the spot it took off from, and lands there,
/// not an arm's length from A.
#[test]
fn after_the_last_shot_the_drone_lands_where_it_took_off() {
    let (r, rec, state) = fly_on(CLOSE_UP, |_| {}, None, Rig::plain);
    let r = r.unwrap();
    assert!(r.completed, "{:?}", rec.kinds());
    assert_eq!(state, FlightState::Landed);
    let kinds = rec.kinds();
    let at = |k: &str| kinds.iter().position(|x| *x == k);
    assert!(
        at("return").is_some() && at("return") < at("landing"),
        "{kinds:?}"
    );
    let home = close_up_take_off_m();
    let [end, landed] = [rec.shots_end_m.unwrap(), rec.last_measured_m.unwrap()];
    let flat = |p: [f64; 3], q: [f64; 3]| (p[0] - q[0]).hypot(p[1] - q[1]);
    // The last shot ends a close-up's distance from A (0.6 m: on set the actor distance and
    // the tracking margin, 0.5 + 0.1 m); the drone took off clear of A's mark by the actor
    // distance and the actors' reach (0.8 m), 0.5 m from there.
    assert!(flat(end, [0.0; 3]) < 0.7, "{end:?}");
    assert!(flat(home, [0.0; 3]) > 0.75, "{home:?}");
    assert!(flat(end, home) > 0.4, "{end:?} {home:?}");
    // It lands over its take-off spot.
    assert!(flat(landed, home) < 0.1, "{landed:?} {home:?}");
}

/// When an actor stands on the take-off spot at the end (here A is measured there once the
/// shots are over), the drone does not fly back onto them: it lands where it is, and says why.
#[test]
fn a_take_off_spot_an_actor_stands_on_is_not_flown_back_to() {
    let (r, rec, _) = fly_on(
        CLOSE_UP,
        |c| c.effects.actor_deviation = false,
        None,
        Rig::plain,
    );
    assert!(r.unwrap().completed);
    let home = close_up_take_off_m();
    // The shots (8 s) are over 8.5 s after "action!"; A stands at the origin until then.
    let after_s = rec.first("action").unwrap().t_s + 8.5;
    let (r, rec, _) = fly_on(
        CLOSE_UP,
        |c| c.effects.actor_deviation = false,
        None,
        |sim| Rig {
            mocap: Box::new(Faulty {
                inner: sim.mocap(),
                faults: Faults {
                    step_actor: Some((0, after_s, [home[0], home[1]])),
                    ..Faults::default()
                },
                nan_done: false,
            }),
            ..Rig::plain(sim)
        },
    );
    assert!(r.unwrap().completed, "{:?}", rec.kinds());
    assert!(!rec.kinds().contains(&"return"), "{:?}", rec.kinds());
    let e = rec.first("return_not_clear").expect("told");
    assert!(
        e.level == "warning"
            && e.message.starts_with("A stands 0.")
            && e.message.ends_with(
                " m from the take-off spot; ardrone2 keeps 0.50 m from actors: landing where \
                 the drone is"
            ),
        "{e:?}"
    );
}

/// An actor the drone loses on its way back to the take-off spot: it cannot keep clear of
/// them, so it hovers, and lands where it is after 2 s, as during the shots.
#[test]
fn an_actor_lost_on_the_way_back_lands_the_drone_where_it_is() {
    let (r, rec, _) = fly_on(CLOSE_UP, |_| {}, None, Rig::plain);
    assert!(r.unwrap().completed);
    let back_s = rec.first("return").unwrap().t_s;
    let (r, rec, state) = fly_on(
        CLOSE_UP,
        |_| {},
        None,
        |sim| Rig {
            mocap: Box::new(Faulty {
                inner: sim.mocap(),
                faults: Faults {
                    lose_actor: Some((0, back_s + 0.1, f64::INFINITY)),
                    ..Faults::default()
                },
                nan_done: false,
            }),
            ..Rig::plain(sim)
        },
    );
    let r = r.unwrap();
    assert!(!r.completed, "{:?}", rec.kinds());
    assert_eq!(state, FlightState::Landed);
    let hover = rec.first("failsafe").unwrap();
    assert_eq!(hover.message, "actor A is not tracked: hovering");
    let land = (rec.events.iter())
        .find(|e| e.message == "actor A has not been tracked for 2 s: landing")
        .expect("landed by the failsafe");
    assert!(land.t_s < back_s + 2.5, "{land:?}");
    assert!(rec.first("landing").unwrap().t_s >= land.t_s);
}

/// The simulator's mocap whose feed ahead (`Mocap::actors_ahead`) gives no frame at the first
/// poll after `drop_at_s`: the director's thread then stepped with other frames than the
/// loop had, which the loop must catch (a bug's symptom, made here on purpose).
struct Disagreeing {
    inner: dronecine_sim::SimMocap,
    drop_at_s: f64,
}

struct DroppingFeed {
    inner: Box<dyn dronecine_backend::ActorFeed>,
    drop_at_s: f64,
    dropped: bool,
}

impl dronecine_backend::ActorFeed for DroppingFeed {
    fn poll_at(&mut self, t_s: f64, frame: &mut MocapFrame) -> bool {
        let polled = self.inner.poll_at(t_s, frame);
        if polled && !self.dropped && frame.t_s >= self.drop_at_s {
            self.dropped = true;
            return false;
        }
        polled
    }
}

impl Mocap for Disagreeing {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        self.inner.poll(frame)
    }
    fn action(&mut self, t_s: f64) {
        self.inner.action(t_s);
    }
    fn actors_ahead(&self) -> Option<Box<dyn dronecine_backend::ActorFeed>> {
        Some(Box::new(DroppingFeed {
            inner: self.inner.actors_ahead()?,
            drop_at_s: self.drop_at_s,
            dropped: false,
        }))
    }
    fn actors_from_feed(&mut self, on: bool) {
        self.inner.actors_from_feed(on);
    }
}

/// With the director stepped ahead, a tick whose frame the director's thread did not have
/// as the loop had it lands the drone with a failsafe that says so: no panic, no framing
/// flown on actors the loop never saw (the simulator's frames leave the actors to the
/// director's then); the landing after it sees the actors again.
#[test]
fn the_director_ahead_with_other_frames_than_the_loop_lands() {
    let (result, rec, state) = fly_on(
        SCRIPT,
        |c| c.actors_ahead = true,
        None,
        |sim| Rig {
            drone: Box::new(sim.drone()),
            mocap: Box::new(Disagreeing {
                inner: sim.mocap(),
                drop_at_s: f64::NEG_INFINITY,
            }),
            clock: Box::new(sim.clock()),
        },
    );
    let report = result.expect("a report, not an error");
    assert!(!report.completed);
    let failsafe = rec.first("failsafe").expect("a failsafe");
    assert!(
        failsafe.message.contains("stepped ahead of the loop"),
        "{}",
        failsafe.message
    );
    // The first shot tick: right after "action!".
    let action = rec.first("action").expect("action!");
    assert!(
        failsafe.t_s - action.t_s < 0.015,
        "{} {}",
        failsafe.t_s,
        action.t_s
    );
    assert_eq!(state, FlightState::Landed);
    assert!(rec.first("landing").is_some(), "{:?}", rec.kinds());
}
