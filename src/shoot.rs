//! `dronecine shoot`: fly a script. Checks and compiles it first (a script the drone cannot
//! fly is refused, as `compile` refuses it), then flies it on the embedded simulator (or a
//! real drone, `--drone`/`--mocap`) with the chosen controller, logging the flight to MCAP,
//! and prints the report.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

use dronecine_compiler::compile::{self, Options};
use dronecine_compiler::director::Director;
use dronecine_diag as diag;
use dronecine_flight::report::FlightReport;
use dronecine_flight::{FlightError, Observer, Progress};
use dronecine_grammar::script::Scene;
use dronecine_live::{LiveFeed, Tee};
use dronecine_mcap::log::{FlightLogWriter, LogOptions, LogScene, LogThread};
use dronecine_mcap::record::{Event, FlightHeader, FlightSink, Phase};
use dronecine_runtime::{HardwareFlight, SessionError, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::{Effects, SimConfig};

/// Ctrl-C presses during the flight.
static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

pub struct Args<'a> {
    pub file: &'a Path,
    pub log: Option<&'a Path>,
    /// The simulator's seed (`None`: 1; refused on hardware).
    pub seed: Option<u64>,
    pub controller: &'a str,
    pub paper_prefilter: bool,
    pub per_tick_solve: bool,
    pub realtime: bool,
    /// Force a simulated flight's log to the disk as it is written (as a real flight's is).
    pub sync_log: bool,
    pub rate_hz: f64,
    pub json: bool,
    pub quiet: bool,
    pub ideal: bool,
    /// Simulator effects to switch off, by [`Effects::NAMES`].
    pub sim_off: &'a [String],
    /// `ardrone://…` or `mavlink://…`: fly a real drone (or the emulator, or SITL).
    pub drone: Option<&'a str>,
    /// `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`, or `sitl`: its
    /// positions.
    pub mocap: Option<&'a str>,
    /// Do not send the motion capture to an ArduPilot vehicle's EKF.
    pub no_forward_mocap: bool,
    /// Do not ask for real-time scheduling and locked memory on a real drone.
    pub normal_priority: bool,
    /// The rig file (rigid-body ids); default: the emulator's layout.
    pub rig: Option<&'a Path>,
    pub color: bool,
    /// Serve the flight as it happens to Foxglove on this address (`--live`).
    pub live: Option<std::net::SocketAddr>,
}

/// Where the flight happens.
enum Target {
    Sim,
    Hardware(crate::hardware::Target),
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

/// The simulator's effects for `--ideal` (every one off) and `--sim-off NAME,…` (those off):
/// `Err` names an effect that does not exist, with the names that do.
pub(crate) fn sim_effects(ideal: bool, off: &[String]) -> Result<Effects, String> {
    let mut effects = if ideal {
        Effects::none()
    } else {
        Effects::all()
    };
    // `--sim-off wind,` names nothing after its comma: nothing to switch.
    for name in off.iter().map(|n| n.trim()).filter(|n| !n.is_empty()) {
        if !effects.set(name, false) {
            let names = Effects::NAMES.iter().map(|(n, _)| *n);
            let guess = dronecine_diag::suggest::did_you_mean(name, names.clone())
                .map_or(String::new(), |g| format!(" ({g})"));
            return Err(format!(
                "--sim-off: no simulator effect `{name}`{guess}; the effects are {}",
                names.collect::<Vec<_>>().join(", ")
            ));
        }
    }
    Ok(effects)
}

/// The simulator's effects that were off, as a phrase: `every effect on`, `every effect
/// off`, or `wind, battery off` (`emulate`'s banner, `replay`).
pub(crate) fn effects_off_phrase<S: AsRef<str>>(off: &[S]) -> String {
    match off.len() {
        0 => "every effect on".to_string(),
        n if n == Effects::NAMES.len() => "every effect off".to_string(),
        _ => {
            let names: Vec<&str> = off.iter().map(AsRef::as_ref).collect();
            format!("{} off", names.join(", "))
        }
    }
}

/// With a real drone: `Err` names the simulator options among `given` (each `(given, flag)`)
/// that were given, since a real drone has its own plant and noise (`shoot`, `calibrate`).
pub(crate) fn refuse_sim_options(given: &[(bool, &str)]) -> Result<(), String> {
    let sim_only: Vec<&str> = given
        .iter()
        .filter_map(|&(given, name)| given.then_some(name))
        .collect();
    let (names, verb) = match sim_only.as_slice() {
        [] => return Ok(()),
        [one] => (one.to_string(), "is a simulator option"),
        _ => (sim_only.join(", "), "are simulator options"),
    };
    Err(format!(
        "{names} {verb}: a real drone (--drone) has its own plant and noise"
    ))
}

/// The servo rates a flight may take (`shoot`, `calibrate`): `Err` says why not.
pub(crate) fn check_servo_rate(rate_hz: f64) -> Result<(), String> {
    if rate_hz.is_finite() && (10.0..=1000.0).contains(&rate_hz) {
        Ok(())
    } else {
        Err(format!(
            "--rate {rate_hz} is outside 10–1000 Hz; the servo runs at 100 Hz (the default)"
        ))
    }
}

/// One line before take-off for the compiler's warnings about a script flown anyway (the
/// shot will not look quite as written; `compile` tells each in full, with its fix), or
/// `None` without any. A repositioning flight is the plan working as written: not counted.
fn warnings_line(diagnostics: &[diag::Diagnostic], name: &str, rate: &str) -> Option<String> {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for d in diagnostics {
        if d.is_error() || d.code == dronecine_compiler::CompileCode::Reposition {
            continue;
        }
        match counts.iter_mut().find(|(c, _)| *c == d.code.as_str()) {
            Some((_, n)) => *n += 1,
            None => counts.push((d.code.as_str(), 1)),
        }
    }
    let total: usize = counts.iter().map(|(_, n)| n).sum();
    if total == 0 {
        return None;
    }
    let list: Vec<String> = counts
        .iter()
        .map(|&(c, n)| {
            if n > 1 {
                format!("{c} ×{n}")
            } else {
                c.to_string()
            }
        })
        .collect();
    let s = if total > 1 { "s" } else { "" };
    Some(format!(
        "warning: `{name}` is flown as written with {total} warning{s} ({})\n  \
         help: `dronecine compile {name}{rate} -o OUT.mcap` tells each, with its fix",
        list.join(", ")
    ))
}

/// The refusal of a `--log` that names an existing file.
fn log_exists(path: &Path) -> String {
    format!(
        "the flight log `{}` already exists; a flight does not overwrite a recording\n  \
         help: give --log a new name, or leave it out for a time-stamped one in flights/",
        path.display()
    )
}

pub fn run(a: &Args) -> ExitCode {
    if let Err(e) = check_servo_rate(a.rate_hz) {
        return fail(e);
    }
    let loaded = match crate::compile::load_scene(a.file, a.color, "flown", true) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let (target, seed, effects) = match where_it_flies(a, loaded.scene()) {
        Ok(t) => t,
        Err(e) => return fail(e),
    };
    let script_name = a
        .file
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "flight".into());
    let (log_path, into_dir) = match log_path_for(a, &script_name) {
        Ok(p) => p,
        Err(e) => return fail(e),
    };
    if let Err(code) = compiler_verdict(a, &loaded) {
        return code;
    }
    let setup = ControllerSetup {
        kind: a.controller.to_string(),
        paper_prefilter: a.paper_prefilter,
        per_tick_solve: a.per_tick_solve,
    };
    if let Err(e) = crate::files::prepare_output(&log_path, "--log") {
        return fail(e);
    }
    let live = match a.live.map(crate::live::serve).transpose() {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    if live.is_some() && matches!(target, Target::Sim) && !a.realtime {
        errln!("note: the simulator flies as fast as it can; --realtime flies it at its pace");
    }
    let flight = Flight {
        a,
        loaded: &loaded,
        target: &target,
        seed,
        effects,
        setup,
        script_name,
    };
    let (log, log_path) = match flight.open_log(log_path, into_dir) {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    flight.fly(log, &log_path, live.as_ref())
}

/// The target (the simulator, or the hardware `--drone`/`--mocap`/`--rig` name), the
/// simulator's seed and effects: the simulator's options are refused with a real drone,
/// before anything is compiled or flown.
fn where_it_flies(a: &Args, scene: &Scene) -> Result<(Target, u64, Effects), String> {
    if a.drone.is_some() {
        let given = [
            (a.seed.is_some(), "--seed"),
            (a.ideal, "--ideal"),
            (!a.sim_off.is_empty(), "--sim-off"),
        ];
        refuse_sim_options(&given)?;
    }
    let names: Vec<&str> = scene.actors.iter().map(|x| x.name.as_str()).collect();
    let target =
        match crate::hardware::target("shoot", a.drone, a.mocap, a.rig, Some(&names), a.color)? {
            None => Target::Sim,
            Some(t) => Target::Hardware(crate::hardware::Target {
                forward_mocap: !a.no_forward_mocap,
                ..t
            }),
        };
    Ok((
        target,
        a.seed.unwrap_or(1),
        sim_effects(a.ideal, a.sim_off)?,
    ))
}

/// Where the log goes, and the folder `--log` names if it names one (the time-stamped name
/// then goes in it). A `--log` that names a recording is refused here, ahead of the compile
/// (which takes a while on a long script); creating the log refuses it again, race-free.
fn log_path_for<'a>(
    a: &Args<'a>,
    script_name: &str,
) -> Result<(PathBuf, Option<&'a Path>), String> {
    let into_dir = a.log.filter(|p| p.is_dir());
    let path = match (a.log, into_dir) {
        (_, Some(dir)) => dir.join(default_log_name(script_name)),
        (Some(p), None) => p.to_path_buf(),
        (None, None) => Path::new("flights").join(default_log_name(script_name)),
    };
    if a.log.is_some() && into_dir.is_none() && path.exists() {
        return Err(log_exists(&path));
    }
    Ok((path, into_dir))
}

/// The compiler's verdict first: a script the drone cannot fly is not flown (its errors as
/// `compile` shows them); one flown with warnings says so in one line.
fn compiler_verdict(a: &Args, loaded: &crate::compile::Loaded) -> Result<(), ExitCode> {
    let (r, profile) = (&loaded.file, &loaded.profile);
    let opts = Options { rate_hz: a.rate_hz };
    let no_output = |_: &_, _: &_| Ok::<(), std::io::Error>(());
    let compiled = match dronecine_film::compile(loaded.script(), profile, &opts, no_output) {
        Ok(c) => c,
        Err(e) => return Err(fail(e)),
    };
    // The same compilation as `compile`'s at this rate: its output shows the same.
    let rate = if a.rate_hz == compile::DEFAULT_RATE_HZ {
        String::new()
    } else {
        format!(" --rate {}", a.rate_hz)
    };
    if compiled.has_errors() {
        err!(
            "{}",
            diag::render(&r.name, &r.text, &compiled.diagnostics, a.color, 100)
        );
        errln!(
            "error: `{}` cannot be flown by {}; nothing was flown\n  help: `dronecine compile {}{rate} \
             --allow-infeasible -o OUT.mcap --preview DIR` draws the flight it would be",
            r.name,
            profile.name,
            r.name,
        );
        return Err(ExitCode::FAILURE);
    }
    if !a.quiet {
        let warned =
            crate::compile::with_script_warnings(&loaded.script_warnings(), &compiled.diagnostics);
        if let Some(line) = warnings_line(&warned, &r.name, &rate) {
            errln!("{line}");
        }
    }
    Ok(())
}

/// One flight as the command line asks for it.
struct Flight<'a> {
    a: &'a Args<'a>,
    loaded: &'a crate::compile::Loaded,
    target: &'a Target,
    seed: u64,
    effects: Effects,
    setup: ControllerSetup,
    script_name: String,
}

impl Flight<'_> {
    /// The log's header: what replay needs to fly the controller again, and what reproduces
    /// a simulated flight (the seed and the effects off).
    fn header(&self) -> FlightHeader {
        let (a, r, profile) = (self.a, &self.loaded.file, &self.loaded.profile);
        let sim = matches!(self.target, Target::Sim);
        FlightHeader {
            script_name: self.script_name.clone(),
            script_text: r.text.clone(),
            profile_name: profile.name.clone(),
            profile_toml: profile.to_toml(),
            profile: profile.clone(),
            controller: self.setup.clone(),
            backend: match (self.target, a.drone) {
                (Target::Hardware(_), Some(d)) => d.to_string(),
                _ => "sim".into(),
            },
            seed: sim.then_some(self.seed),
            sim_effects_off: sim
                .then(|| self.effects.off().into_iter().map(String::from).collect()),
            rate_hz: a.rate_hz,
            actor_names: self
                .loaded
                .scene()
                .actors
                .iter()
                .map(|x| x.name.clone())
                .collect(),
            dronecine_version: env!("CARGO_PKG_VERSION").into(),
        }
    }

    /// The flight log, always a new file, written on a thread of its own: a crash loses at
    /// most the last second (a batch handed to the writer every 0.25 s, taken up within
    /// 0.02 s, a chunk closed every 0.73 s). Forced to the disk as it is written when the
    /// flight cannot be flown again (paced by the wall clock), or asked: a simulated flight
    /// as fast as it goes is its script's, profile's and seed's to reproduce, and leaves the
    /// disk to the OS. The log and its path.
    fn open_log(
        &self,
        path: PathBuf,
        into_dir: Option<&Path>,
    ) -> Result<(LogThread, PathBuf), String> {
        let a = self.a;
        let (actor_names, heights, lens) = self.scene_parts();
        let header = self.header();
        let log_scene = LogScene {
            stage: self.loaded.scene().stage,
            lens,
            actor_names: &actor_names,
            actor_heights_m: &heights,
        };
        let durable = a.sync_log || a.realtime || !matches!(self.target, Target::Sim);
        let options = LogOptions::shoot(durable);
        // A flight never overwrites a recording: a `--log` that exists is refused before
        // take-off, and a default name already taken (two flights in one second) gets `-2`,
        // `-3`, …
        let (path, created) = if a.log.is_some() && into_dir.is_none() {
            let created = FlightLogWriter::create_new_with(&path, &header, &log_scene, options);
            (path, created)
        } else {
            first_free(&path, |p| {
                FlightLogWriter::create_new_with(p, &header, &log_scene, options)
            })
        };
        match created.and_then(|w| LogThread::spawn(w, a.rate_hz)) {
            Ok(w) => Ok((w, path)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(log_exists(&path)),
            Err(e) => {
                // Created new here, and not whole (a full disk): not left in the way of the
                // retry.
                let _ = std::fs::remove_file(&path);
                Err(e.to_string())
            }
        }
    }

    /// What the log's scene is made of: the actors' names and heights, the lens.
    fn scene_parts(&self) -> (Vec<String>, Vec<f64>, dronecine_compiler::camera::Lens) {
        let scene = self.loaded.scene();
        let actor_names = scene.actors.iter().map(|x| x.name.clone()).collect();
        let heights = scene.actors.iter().map(|x| x.height_m).collect();
        let lens = *Director::new(self.loaded.script(), scene, &self.loaded.profile).lens();
        (actor_names, heights, lens)
    }

    /// The live view's side of the loop, on `server`: the log's scene and topics.
    fn live_feed(&self, server: &dronecine_live::LiveServer) -> std::io::Result<LiveFeed> {
        let (actor_names, heights, lens) = self.scene_parts();
        let scene = LogScene {
            stage: self.loaded.scene().stage,
            lens,
            actor_names: &actor_names,
            actor_heights_m: &heights,
        };
        let gimbal = self.loaded.profile.camera.gimbal != dronecine_profile::Gimbal::None;
        LiveFeed::start(server, &scene, gimbal)
    }

    /// Flies, logging into `log` (and serving the flight on `live`), and prints the report;
    /// the exit status says whether the flight completed.
    fn fly(
        &self,
        mut log: LogThread,
        log_path: &Path,
        live: Option<&dronecine_live::LiveServer>,
    ) -> ExitCode {
        let a = self.a;
        // Ctrl-C lands, a second Ctrl-C cuts the motors; SIGTERM and SIGHUP land (the flight
        // loop reads the count).
        if let Err(e) = crate::signals::count_interrupts(&INTERRUPTS) {
            errln!(
                "warning: Ctrl-C cannot be caught ({e}); it will stop dronecine without landing"
            );
        }
        let r = &self.loaded.file;
        let mut display = Display::new(a.quiet, &r.name, &r.text);
        let mut feed = match live.map(|server| self.live_feed(server)).transpose() {
            Ok(f) => f,
            Err(e) => return fail(format!("the live view cannot start: {e}")),
        };
        let result = match &mut feed {
            Some(live) => self.fly_on_target(
                &mut Tee {
                    log: &mut log,
                    live,
                },
                &mut display,
            ),
            None => self.fly_on_target(&mut log, &mut display),
        };
        display.finish();
        let finished = log.finish();
        if let Some(feed) = feed {
            errln!("{}", crate::live::summary_line(&feed.finish()));
        }
        let report = match result {
            Ok(report) => report,
            Err(SessionError::Flight(FlightError::Log(e, report))) => {
                // The flight was flown (and landed for it): its report first.
                let _ = self.tell_report(&report, None);
                return fail(format!(
                    "the flight log could not be written ({e}): the drone was landed\n  help: \
                     the log keeps the flight up to the failure (`dronecine replay {}` reads \
                     it); free space on its disk, or give --log a place that has some",
                    log_path.display()
                ));
            }
            Err(e) => return self.not_flown(e, log_path),
        };
        if let Err(e) = finished {
            let _ = self.tell_report(&report, None);
            return fail(format!(
                "the flight log `{}` is incomplete: {e}",
                log_path.display()
            ));
        }
        if let Err(code) = self.tell_report(&report, Some(log_path)) {
            return code;
        }
        if report.completed {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        }
    }

    /// The report, as text (ending with the log and how to see it, when `log` is given) or
    /// JSON (the log's path then on stderr).
    fn tell_report(&self, report: &FlightReport, log: Option<&Path>) -> Result<(), ExitCode> {
        if self.a.json {
            match serde_json::to_string_pretty(report) {
                Ok(s) => outln!("{s}"),
                Err(e) => return Err(fail(e)),
            }
            if let Some(log) = log {
                errln!("flight log: {}", log.display());
            }
        } else {
            use crate::report::{render, Ending, Next};
            let next = log.map_or(Next::Nothing, Next::Shot);
            let profile = &self.loaded.profile.name;
            let ending = Ending::of(report);
            out!(
                "{}",
                render(report, ending, profile, self.a.controller, next)
            );
        }
        Ok(())
    }

    /// The flight on the simulator or on the hardware the command line names.
    fn fly_on_target(
        &self,
        log: &mut dyn FlightSink,
        display: &mut Display,
    ) -> Result<FlightReport, SessionError> {
        let (a, r) = (self.a, &self.loaded.file);
        let (script, scene, profile) = (
            self.loaded.script(),
            self.loaded.scene(),
            &self.loaded.profile,
        );
        match self.target {
            Target::Sim => {
                let mut sim = SimConfig::new(self.seed);
                sim.effects = self.effects;
                // As fast as it can: the director on a thread of its own if there is a core
                // for it (the same flight either way). Paced, the loop waits anyway.
                sim.actors_ahead = !a.realtime && dronecine_runtime::director_thread_pays();
                let flight = SimFlight {
                    script,
                    source: &r.text,
                    scene,
                    profile,
                    rate_hz: a.rate_hz,
                    controller: self.setup.clone(),
                    plant: None,
                    sim,
                    realtime: a.realtime,
                    interrupts: Some(&INTERRUPTS),
                };
                dronecine_runtime::fly_simulated(&flight, log, display)
            }
            Target::Hardware(target) => {
                if !a.normal_priority {
                    errln!("note: {}", crate::realtime::request().describe());
                }
                let flight = HardwareFlight {
                    script,
                    source: &r.text,
                    scene,
                    profile,
                    rate_hz: a.rate_hz,
                    controller: self.setup.clone(),
                    target,
                    interrupts: Some(&INTERRUPTS),
                };
                dronecine_runtime::fly_hardware(&flight, log, display)
            }
        }
    }

    /// A flight that did not fly to its end without a report: a pre-flight refusal (each
    /// check's diagnostic, quoting the script where it is about the script), a log that
    /// could not be written, or a backend's failure.
    fn not_flown(&self, e: SessionError, log_path: &Path) -> ExitCode {
        let r = &self.loaded.file;
        match e {
            SessionError::Flight(FlightError::Preflight(refusals)) => {
                err!(
                    "{}",
                    diag::render(&r.name, &r.text, &refusals, self.a.color, 100)
                );
                errln!(
                    "error: `{}` was not flown: the drone is on the ground",
                    r.name
                );
                self.keep_or_remove(log_path, took_off(&refusals));
                ExitCode::FAILURE
            }
            // Nothing connected: nothing flew.
            e @ SessionError::Setup(_) => {
                self.keep_or_remove(log_path, false);
                fail(e)
            }
            e => {
                errln!("flight log: {}", log_path.display());
                fail(e)
            }
        }
    }

    /// The log of a flight that never started is removed: nothing was recorded that the
    /// script, the profile and the set do not say again, and a `--log` given again must not
    /// find it in the way. A take-off that failed is a flight: its log stays.
    fn keep_or_remove(&self, log_path: &Path, took_off: bool) {
        if took_off {
            errln!("flight log: {}", log_path.display());
        } else if let Err(e) = std::fs::remove_file(log_path) {
            errln!(
                "warning: the log of the flight not flown, `{}`, cannot be removed: {e}",
                log_path.display()
            );
        }
    }
}

/// Whether a refused flight had taken off (a refusal of the take-off itself, not of a check
/// before it).
fn took_off(refusals: &[diag::Diagnostic]) -> bool {
    use dronecine_flight::PreflightCode;
    refusals.iter().any(|d| {
        d.code == PreflightCode::TakeOffEmergency || d.code == PreflightCode::TakeOffTimeout
    })
}

/// `<script>-<UTC timestamp>.mcap` (in `flights/`, or the folder `--log` names).
fn default_log_name(script: &str) -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (y, m, d) = civil_from_days(days as i64);
    format!(
        "{script}-{y:04}{m:02}{d:02}-{:02}{:02}{:02}.mcap",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// `create(base)`, or while that says the file exists, `create` of `base` numbered `-2`,
/// `-3`, … (`flights/x-20261123-023000-2.mcap`), up to `-999`: the name taken and what
/// `create` gave.
fn first_free<T>(
    base: &Path,
    mut create: impl FnMut(&Path) -> std::io::Result<T>,
) -> (PathBuf, std::io::Result<T>) {
    let stem = base.file_stem().unwrap_or_default().to_string_lossy();
    let mut path = base.to_path_buf();
    let mut n = 1;
    loop {
        match create(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 999 => {
                n += 1;
                path = base.with_file_name(format!("{stem}-{n}.mcap"));
            }
            r => return (path, r),
        }
    }
}

/// Days since 1970-01-01 → (year, month, day), proleptic Gregorian (Howard Hinnant's
/// algorithm).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// The terminal progress line (only when stderr is a terminal), refreshed at most 10 times a
/// second of wall time, and warnings and errors as they happen.
struct Display {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
    /// The warnings and errors as they are shown.
    told: EventTally,
    /// When the line's text was last set, and the phase and shot it showed: the loop offers
    /// progress every tick, and formatting the line each time (a string per tick, and the
    /// bar's lock) would slow a simulated flight that runs as fast as it can.
    shown: Option<(Instant, Phase, Option<usize>)>,
}

/// How often the progress line's text is set (the bar draws it 10 times a second).
const DISPLAY_PERIOD: Duration = Duration::from_millis(50);

impl Display {
    fn new(quiet: bool, script_name: &str, script_text: &str) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:30} {msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar.enable_steady_tick(Duration::from_millis(100));
            bar
        });
        Display {
            bar,
            quiet,
            told: EventTally::new(script_name, script_text),
            shown: None,
        }
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    /// The progress line at wall time `now`: a new phase or shot at once, else at most every
    /// `DISPLAY_PERIOD`.
    fn show(&mut self, p: &Progress, now: Instant) {
        let Some(bar) = &self.bar else {
            return;
        };
        if let Some((at, phase, shot)) = self.shown {
            if phase == p.phase && shot == p.shot && now.duration_since(at) < DISPLAY_PERIOD {
                return;
            }
        }
        self.shown = Some((now, p.phase, p.shot));
        let fraction = if p.script_duration_s > 0.0 {
            (p.script_t_s / p.script_duration_s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        bar.set_position((fraction * 1000.0) as u64);
        let phase = match (p.phase, p.shot) {
            (Phase::TakeOff, _) => "taking off".to_string(),
            (Phase::Approach, _) => "approach".to_string(),
            (Phase::Shots, Some(i)) => format!("shot {}/{}", i + 1, p.shots),
            (Phase::Shots, None) => "shots".to_string(),
            (Phase::Landing, _) => "landing".to_string(),
        };
        let error = p
            .position_error_m
            .map_or("—".to_string(), |e| format!("{:.1} cm", e * 100.0));
        bar.set_message(format!(
            "{phase} · t {:.1}/{:.1} s · tracking error {error}",
            p.script_t_s, p.script_duration_s
        ));
    }
}

impl Observer for Display {
    fn progress(&mut self, p: &Progress) {
        if self.bar.is_some() {
            self.show(p, Instant::now());
        }
    }

    fn event(&mut self, e: &Event) {
        // Quiet keeps the errors: a failsafe's reason, why a flight ended early.
        if self.quiet && e.level != "error" {
            return;
        }
        let Some(line) = self.told.text(e) else {
            return;
        };
        match &self.bar {
            Some(bar) => bar.println(line),
            None => errln!("{line}"),
        }
    }
}

/// An event as the terminal shows it (`shoot` as it happens, `replay` from the log): its
/// level, time and message; for a finding of the director's, the script's line quoted as
/// `compile` points at it, and the fix.
///
/// ```text
/// error at 70.51 s: shot 10: the drone needs 4.8 s to fly to this shot's first framing (…)
///   --> shots/scene.psl:27
///    27 │ at 67s cut to path orbit around Alice radius 2m altitude 1.6m turns 0.5 clockwise …
///   help: pin the shot at `at 71.3s` or later, or shorten the shot before it by 3.5 s
/// ```
pub fn event_text(e: &Event, script_name: &str, script_text: &str) -> String {
    use std::fmt::Write;
    let mut s = format!("{} at {:.2} s: {}", e.level, e.t_s, e.message);
    if let Some(line) = e.line {
        let _ = write!(s, "\n  --> {script_name}:{line}");
        let quoted = usize::try_from(line)
            .ok()
            .and_then(|n| script_text.lines().nth(n.checked_sub(1)?));
        if let Some(quoted) = quoted {
            let _ = write!(s, "\n  {line:>4} │ {}", quoted.trim_end());
        }
    }
    if let Some(help) = &e.help {
        let _ = write!(s, "\n  help: {help}");
    }
    s
}

/// How many events of one kind the terminal shows. A loop that keeps missing its deadline on a
/// loaded machine, or a controller refusing tick after tick, raises one event a tick: shown
/// all, they would scroll the rest out of sight. The log keeps every one and the report
/// counts them.
const SHOWN_PER_KIND: u32 = 10;

/// What the terminal shows of a flight's events (`shoot` as they happen, `replay` from the
/// log): its warnings and errors, [`SHOWN_PER_KIND`] of each kind at most, a finding of the
/// director's quoting its line of the script.
pub struct EventTally {
    script_name: String,
    script_text: String,
    /// Per kind, how many were shown.
    shown: Vec<(String, u32)>,
}

impl EventTally {
    pub fn new(script_name: &str, script_text: &str) -> EventTally {
        EventTally {
            script_name: script_name.to_string(),
            script_text: script_text.to_string(),
            shown: Vec::new(),
        }
    }

    /// The text to print for `e` ([`event_text`]), `None` for an info event: the first
    /// [`SHOWN_PER_KIND`] of its kind, the last of them saying that the rest are in the log
    /// only; then `None`.
    pub fn text(&mut self, e: &Event) -> Option<String> {
        if e.level == "info" {
            return None;
        }
        let at = match self.shown.iter().position(|(k, _)| *k == e.kind) {
            Some(at) => at,
            None => {
                self.shown.push((e.kind.clone(), 0));
                self.shown.len() - 1
            }
        };
        let n = &mut self.shown[at].1;
        if *n >= SHOWN_PER_KIND {
            return None;
        }
        *n += 1;
        let mut text = event_text(e, &self.script_name, &self.script_text);
        if *n == SHOWN_PER_KIND {
            use std::fmt::Write;
            let _ = write!(
                text,
                "\n  (further `{}` events are not shown: the log's /events has every one)",
                e.kind
            );
        }
        Some(text)
    }
}

#[cfg(test)]
mod tests {
    use super::{civil_from_days, effects_off_phrase, first_free, sim_effects};
    use super::{Display, EventTally, DISPLAY_PERIOD};
    use dronecine_flight::Progress;
    use dronecine_mcap::record::{Event, Phase};
    use dronecine_sim::Effects;
    use std::path::Path;
    use std::time::{Duration, Instant};

    /// The progress line's text is set at most every `DISPLAY_PERIOD` within a phase and a
    /// shot (the loop offers it every tick), and at once when either changes.
    #[test]
    fn the_progress_line_is_set_at_most_every_period_and_at_once_on_a_new_shot() {
        let mut d = Display {
            bar: Some(indicatif::ProgressBar::hidden()),
            quiet: false,
            told: EventTally::new("", ""),
            shown: None,
        };
        let at = |t_s: f64, phase: Phase, shot: Option<usize>| Progress {
            t_s,
            phase,
            shot,
            shots: 2,
            script_t_s: t_s,
            script_duration_s: 10.0,
            position_error_m: Some(0.01),
        };
        let message = |d: &Display| d.bar.as_ref().unwrap().message();
        let t0 = Instant::now();
        let wall = |ms: u64| t0 + Duration::from_millis(ms);
        d.show(&at(1.0, Phase::Shots, Some(0)), wall(0));
        assert!(message(&d).contains("t 1.0/10.0 s"), "{}", message(&d));
        // The next ticks, within the period: not set.
        for k in 1..50 {
            d.show(&at(1.0 + k as f64 * 0.01, Phase::Shots, Some(0)), wall(k));
        }
        assert!(message(&d).contains("t 1.0/10.0 s"), "{}", message(&d));
        // A new shot: at once.
        d.show(&at(2.5, Phase::Shots, Some(1)), wall(60));
        assert!(
            message(&d).starts_with("shot 2/2 · t 2.5/"),
            "{}",
            message(&d)
        );
        d.show(&at(2.6, Phase::Shots, Some(1)), wall(60 + 49));
        assert!(message(&d).contains("t 2.5/10.0 s"), "{}", message(&d));
        // A period after it was set: set.
        d.show(&at(2.7, Phase::Shots, Some(1)), wall(60) + DISPLAY_PERIOD);
        assert!(message(&d).contains("t 2.7/10.0 s"), "{}", message(&d));
    }

    /// A finding of the director's quotes its line and gives its fix; the flight's own events
    /// are one line; a line past the script's end (a log of another script) is named, not
    /// quoted.
    #[test]
    fn a_director_finding_quotes_its_line_and_gives_the_fix() {
        let text =
            "stage 8m x 6m x 3m\r\nMS on A front for 4s  \nat 9s cut to MS on A back for 4s\n";
        let mut e = Event {
            t_s: 12.345,
            level: "error".into(),
            kind: "compile::cut_too_short".into(),
            message: "shot 2: the drone needs 4.8 s".into(),
            line: Some(3),
            help: Some("pin the shot at `at 10.2s` or later".into()),
        };
        assert_eq!(
            super::event_text(&e, "shots/x.psl", text),
            "error at 12.35 s: shot 2: the drone needs 4.8 s\n  --> shots/x.psl:3\n     3 │ at 9s \
             cut to MS on A back for 4s\n  help: pin the shot at `at 10.2s` or later"
        );
        e.line = Some(2);
        e.help = None;
        assert_eq!(
            super::event_text(&e, "x.psl", text),
            "error at 12.35 s: shot 2: the drone needs 4.8 s\n  --> x.psl:2\n     2 │ MS on A \
             front for 4s"
        );
        e.line = Some(40);
        assert!(super::event_text(&e, "x.psl", text).ends_with("  --> x.psl:40"));
        e.line = None;
        assert_eq!(
            super::event_text(&e, "x.psl", text),
            "error at 12.35 s: shot 2: the drone needs 4.8 s"
        );
    }

    /// Ten events of a kind are shown, the tenth saying that the rest are in the log; other
    /// kinds are counted apart; info events are not shown.
    #[test]
    fn events_of_one_kind_are_shown_ten_times_at_most() {
        let event = |kind: &str, k: u32| Event {
            t_s: f64::from(k),
            level: "warning".into(),
            kind: kind.into(),
            message: format!("number {k}"),
            line: None,
            help: None,
        };
        let mut told = EventTally::new("x.psl", "");
        let shown: Vec<String> = (1..=25)
            .filter_map(|k| told.text(&event("deadline_missed", k)))
            .collect();
        assert_eq!(shown.len(), 10);
        assert!(shown[8].ends_with("number 9"), "{}", shown[8]);
        assert!(
            shown[9].starts_with("warning at 10.00 s: number 10\n")
                && shown[9].ends_with("events are not shown: the log's /events has every one)"),
            "{}",
            shown[9]
        );
        assert!(told.text(&event("fault", 26)).is_some());
        // Info events are the log's only.
        let info = Event {
            level: "info".into(),
            ..event("shot_start", 27)
        };
        assert_eq!(told.text(&info), None);
    }

    #[test]
    fn sim_off_names_effects_and_skips_empty_ones() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(sim_effects(false, &[]), Ok(Effects::all()));
        assert_eq!(sim_effects(true, &[]), Ok(Effects::none()));
        let e = sim_effects(false, &names(&["wind", " battery", ""])).unwrap();
        assert_eq!(e.off(), ["wind", "battery"]);
        assert_eq!(effects_off_phrase::<&str>(&[]), "every effect on");
        assert_eq!(effects_off_phrase(&e.off()), "wind, battery off");
        assert_eq!(
            effects_off_phrase(&Effects::none().off()),
            "every effect off"
        );
        let err = sim_effects(false, &names(&["wind", "latncy"])).unwrap_err();
        assert!(
            err.starts_with("--sim-off: no simulator effect `latncy` (did you mean `latency`?)"),
            "{err}"
        );
    }

    /// A default log name already taken (two flights in one second) is numbered, never
    /// overwritten; other errors come back as they are.
    #[test]
    fn a_taken_default_log_name_is_numbered() {
        let dir = std::env::temp_dir().join(format!("dronecine-first-free-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let base = dir.join("x-20261123-023000.mcap");
        let create = |p: &Path| {
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(p)
        };
        let (first, r) = first_free(&base, create);
        assert!(r.is_ok());
        assert_eq!(first, base);
        std::fs::write(&base, b"the first flight").unwrap();
        let (second, r) = first_free(&base, create);
        assert!(r.is_ok());
        assert_eq!(second, dir.join("x-20261123-023000-2.mcap"));
        let (third, _) = first_free(&base, create);
        assert_eq!(third, dir.join("x-20261123-023000-3.mcap"));
        assert_eq!(std::fs::read(&base).unwrap(), b"the first flight");
        let (_, r) = first_free(&dir.join("no/such/dir/y.mcap"), create);
        assert_eq!(r.unwrap_err().kind(), std::io::ErrorKind::NotFound);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(19_723), (2024, 1, 1));
        assert_eq!(civil_from_days(20_414), (2025, 11, 22));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
    }
}
