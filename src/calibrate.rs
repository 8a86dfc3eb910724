//! `dronecine calibrate` and `dronecine identify`: measure the servo's model (K and τ per
//! axis, K_ψ) by flying doublets and steps on each input around hover (on the embedded
//! simulator by default, or on a real AR.Drone 2.0 with NatNet positions, `--drone/--mocap`),
//! or from any flight log; print each fitted value with its 95 % interval, the fit's R² and
//! the previous profile's value; write the profile (`Profile::to_toml`) only when every fit is
//! good, else exit 1 naming the test to repeat.

use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::AtomicU32;

use dronecine_backend::Backends;
use dronecine_grammar::script::{Scene, Stage};
use dronecine_identify::calibrate::{self as cal, Plan};
use dronecine_identify::{self as identify, Axis, FitError, ModelFit, Segment};
use dronecine_mcap::log::FlightLog;
use dronecine_profile::{Profile, DEFAULT_NAME};
use dronecine_sim::{Effects, SimConfig, Simulator};

static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

#[derive(clap::Args, Debug)]
pub struct CalibrateArgs {
    /// The profile file to write.
    #[arg(short, long, value_name = "PROFILE.toml")]
    output: std::path::PathBuf,
    /// Which axis to test: roll, pitch, vz, yaw or all.
    #[arg(long, value_name = "AXIS", default_value = "all")]
    axis: String,
    /// The previous profile (a built-in name or a TOML file): the prior, and every section
    /// the calibration does not measure.
    #[arg(long, value_name = "NAME|FILE", default_value = DEFAULT_NAME)]
    profile: String,
    /// The profile the simulated drone truly has [default: --profile] (simulator only).
    #[arg(long, value_name = "NAME|FILE")]
    plant: Option<String>,
    /// The stage the tests must stay in: width (x), depth (y), height (z), metres.
    #[arg(long, value_name = "X,Y,Z", default_value = "6,6,3")]
    stage: String,
    /// The simulator's seed [default: 1] (simulator only).
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// Simulate the servo's own model only, mocap noise kept on (simulator only).
    #[arg(long)]
    ideal: bool,
    /// Control rate, Hz.
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 100.0,
        allow_negative_numbers = true
    )]
    rate: f64,
    /// Tests per axis [default: 12 on roll and pitch, 4 on vz and yaw]. Each sign in turn; roll
    /// and pitch fly doublets, the last two short steps; vz and yaw doublets then steps.
    #[arg(long, value_name = "N")]
    repeats: Option<usize>,
    /// Write the calibration report (per axis the measured response against the fitted
    /// model's and the previous profile's, SVG and PNG, and every test's samples as
    /// `tests.json`) to this folder.
    #[arg(long, value_name = "DIR")]
    report: Option<std::path::PathBuf>,
    /// Calibrate a real AR.Drone 2.0 (or `dronecine emulate`) instead of the simulator:
    /// `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`. Needs --mocap. The tests fly around the
    /// point where it takes off, inside --stage (centred on the mocap's origin).
    #[arg(long, value_name = "URL")]
    drone: Option<String>,
    /// Its positions from OptiTrack NatNet:
    /// `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`.
    #[arg(long, value_name = "URL")]
    mocap: Option<String>,
    /// The drone's rigid-body id and the mocap's up axis (TOML, as `shoot --rig`)
    /// [default: drone 1, Y up].
    #[arg(long, value_name = "FILE")]
    rig: Option<std::path::PathBuf>,
}

#[derive(clap::Args, Debug)]
pub struct IdentifyArgs {
    /// The flight log (`dronecine shoot --log`).
    #[arg(value_name = "LOG.mcap")]
    log: std::path::PathBuf,
    /// The profile file to write.
    #[arg(short, long, value_name = "PROFILE.toml")]
    output: std::path::PathBuf,
    /// The previous profile [default: the one the log was flown with].
    #[arg(long, value_name = "NAME|FILE")]
    profile: Option<String>,
    /// Which axes to fit: roll, pitch, vz, yaw or all.
    #[arg(long, value_name = "AXIS", default_value = "all")]
    axis: String,
    /// Write the report (as `calibrate --report`) on the four most excited windows per axis.
    #[arg(long, value_name = "DIR")]
    report: Option<std::path::PathBuf>,
    /// Length of the windows the log is cut into (each with its own initial state), seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 20.0,
        allow_negative_numbers = true
    )]
    window: f64,
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

fn axes(arg: &str) -> Result<Vec<Axis>, String> {
    if arg == "all" {
        return Ok(Axis::ALL.to_vec());
    }
    arg.split(',')
        .map(|a| {
            Axis::parse(a.trim())
                .ok_or_else(|| format!("--axis `{a}`: expected roll, pitch, vz, yaw or all"))
        })
        .collect()
}

fn stage(arg: &str) -> Result<Stage, String> {
    let v: Vec<f64> = arg
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--stage `{arg}`: expected three numbers X,Y,Z"))?;
    match v.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|s| s.is_finite() && **s > 0.0) => Ok(Stage {
            size_m: [*x, *y, *z],
        }),
        _ => Err(format!(
            "--stage `{arg}`: expected three positive numbers X,Y,Z"
        )),
    }
}

/// The table: per axis the fitted values ± CI, R², and the previous values.
fn render(fit: &ModelFit, errors: &[FitError], prev: &Profile, axes: &[Axis]) -> String {
    let m = &prev.model;
    let mut out = String::new();
    out.push_str("axis   parameter        fitted ± 95% CI            previous   R²\n");
    for &axis in axes {
        let f = fit
            .get(axis)
            .or_else(|| errors.iter().find(|e| e.axis == axis)?.fit.as_deref());
        let (kname, kprev, tname, tprev) = match axis {
            Axis::Roll => ("K_phi", m.gain_roll_mps_per_rad, "tau_phi", m.tau_roll_s),
            Axis::Pitch => (
                "K_theta",
                m.gain_pitch_mps_per_rad,
                "tau_theta",
                m.tau_pitch_s,
            ),
            Axis::Vz => ("K_zdot", m.gain_vz, "tau_zdot", m.tau_vz_s),
            Axis::Yaw => ("K_psi", m.gain_yaw, "", 0.0),
        };
        let Some(f) = f else {
            out.push_str(&format!("{:<6} (not excited)\n", axis.name()));
            continue;
        };
        out.push_str(&format!(
            "{:<6} {:<16} {:>10.4} ± {:<10.4} {:>14.4}   {:.4}\n",
            axis.name(),
            kname,
            f.gain.value,
            f.gain.ci95,
            kprev,
            f.r2
        ));
        if let Some(t) = f.tau_s {
            out.push_str(&format!(
                "{:<6} {:<16} {:>10.4} ± {:<10.4} {:>14.4}\n",
                "",
                format!("{tname} (s)"),
                t.value,
                t.ci95,
                tprev
            ));
        }
        if let (Some(t), Some(written)) = (f.tau_s, f.servo_tau_s()) {
            if written != t.value {
                out.push_str(&format!(
                    "{:<6} {:<16} {:>10.4} {:>27}\n",
                    "",
                    format!("{tname} written"),
                    written,
                    "(the delay folded in)"
                ));
            }
        }
        // Found by the fit, not in the servo's model: reported, not written.
        if let Some(d) = f.descent_gain {
            out.push_str(&format!(
                "{:<6} {:<16} {:>10.4} ± {:<10.4} {:>14}\n",
                "", "K_zdot descent", d.value, d.ci95, "(not in model)"
            ));
        }
        for (name, value) in [
            ("attitude lag (s)", f.attitude_lag_s),
            ("latency (s)", f.latency_s),
        ] {
            if let Some(v) = value {
                out.push_str(&format!(
                    "{:<6} {:<16} {:>10.4} {:>27}\n",
                    "", name, v, "(not in model)"
                ));
            }
        }
    }
    out
}

/// Writes `<axis>.svg` and `<axis>.png` per fitted axis (passed or refused) into `dir`.
fn write_report(
    dir: &Path,
    fit: &ModelFit,
    errors: &[FitError],
    prev: &Profile,
    tests: &[(Axis, Vec<&Segment>)],
) -> Result<Vec<std::path::PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    let mut written = Vec::new();
    for (axis, segs) in tests {
        let Some(f) = fit
            .get(*axis)
            .or_else(|| errors.iter().find(|e| e.axis == *axis)?.fit.as_deref())
        else {
            continue;
        };
        let Some(svg) = cal::report_svg(*axis, segs, f, prev) else {
            continue;
        };
        let svg_path = dir.join(format!("{}.svg", axis.name()));
        crate::files::write_atomic(&svg_path, &svg)
            .map_err(|e| format!("cannot write `{}`: {e}", svg_path.display()))?;
        let png = dronecine_preview::svg_to_png(&svg)
            .map_err(|e| format!("cannot render the {} report: {e}", axis.name()))?;
        let png_path = dir.join(format!("{}.png", axis.name()));
        std::fs::write(&png_path, png)
            .map_err(|e| format!("cannot write `{}`: {e}", png_path.display()))?;
        written.push(svg_path);
        written.push(png_path);
    }
    Ok(written)
}

/// Writes `tests.json` into `dir`: every test flown, as the fit read it (the axis and its
/// samples), so that a calibration can be studied or fitted again without flying it again.
fn write_tests(dir: &Path, tests: &[(Axis, Segment)]) -> Result<std::path::PathBuf, String> {
    let records: Vec<serde_json::Value> = tests
        .iter()
        .map(|(axis, seg)| serde_json::json!({ "axis": axis.name(), "samples": seg }))
        .collect();
    let path = dir.join("tests.json");
    let text = serde_json::to_string(&records).map_err(|e| e.to_string())?;
    crate::files::write_atomic(&path, &text)
        .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    Ok(path)
}

/// The `n` segments with the most input on `axis`.
fn most_excited(segments: &[Segment], axis: Axis, n: usize) -> Vec<&Segment> {
    let energy = |s: &Segment| -> f64 {
        s.iter()
            .map(|x| {
                let c = &x.command;
                match axis {
                    Axis::Roll => c.roll_rad.powi(2),
                    Axis::Pitch => c.pitch_rad.powi(2),
                    Axis::Vz => c.vz_mps.powi(2),
                    Axis::Yaw => c.yaw_rate_radps.powi(2),
                }
            })
            .filter(|e| e.is_finite())
            .sum()
    };
    let mut v: Vec<(f64, &Segment)> = segments.iter().map(|s| (energy(s), s)).collect();
    v.sort_by(|a, b| b.0.total_cmp(&a.0));
    v.into_iter()
        .filter(|(e, _)| *e > 0.0)
        .take(n)
        .map(|(_, s)| s)
        .collect()
}

/// Prints the table; writes the profile on a good fit, else names what to repeat.
fn finish(
    fit: &ModelFit,
    errors: &[FitError],
    prev: &Profile,
    axes: &[Axis],
    output: &Path,
    note: &str,
) -> ExitCode {
    out!("{}", render(fit, errors, prev, axes));
    if !errors.is_empty() {
        for e in errors {
            errln!("error: {e}");
        }
        errln!(
            "error: no profile written to `{}` (a poor fit)",
            output.display()
        );
        return ExitCode::FAILURE;
    }
    let mut p = fit.apply(prev);
    p.description = format!("{} ({note})", prev.description);
    let toml = p.to_toml();
    if let Err(e) = crate::files::write_atomic(output, &toml) {
        // The fit is not lost with the file: it is printed, to be saved by hand.
        errln!("{toml}");
        return fail(format!(
            "cannot write `{}`: {e}; the fitted profile is printed above, to save by hand",
            output.display()
        ));
    }
    outln!("wrote {}", output.display());
    ExitCode::SUCCESS
}

pub fn run_calibrate(a: &CalibrateArgs, color: bool) -> ExitCode {
    let (axes, stage) = match calibrate_options(a) {
        Ok(x) => x,
        Err(e) => return fail(e),
    };
    let target = match crate::hardware::target(
        "calibrate",
        a.drone.as_deref(),
        a.mocap.as_deref(),
        a.rig.as_deref(),
        None,
        color,
    ) {
        Ok(t) => t,
        Err(e) => return fail(e),
    };
    let prior = match crate::compile::profile_arg("--profile", &a.profile, color) {
        Ok(p) => p,
        Err(c) => return c,
    };
    // Ahead of the flight: minutes of tests are not flown for a profile with nowhere to go.
    if let Err(e) = crate::files::prepare_output(&a.output, "-o") {
        return fail(e);
    }
    // Ctrl-C lands, a second Ctrl-C cuts the motors; SIGTERM and SIGHUP land (the
    // calibration reads the count).
    if let Err(e) = crate::signals::count_interrupts(&INTERRUPTS) {
        errln!("warning: Ctrl-C cannot be caught ({e}); it will stop dronecine without landing");
    }
    let (sim, mut sim_backends, mut hardware);
    let (backends, note) = match &target {
        None => {
            let (simulated, seed) = match simulator(a, &prior, stage, color) {
                Ok(s) => s,
                Err(c) => return c,
            };
            sim = simulated;
            sim_backends = (sim.drone(), sim.mocap(), sim.clock());
            let (drone, mocap, clock) = &mut sim_backends;
            (
                Backends {
                    drone,
                    mocap,
                    clock,
                },
                format!("calibrated on the simulator, seed {seed}"),
            )
        }
        Some(t) => {
            hardware = match dronecine_runtime::connect_hardware(t, None, &prior) {
                Ok(h) => h,
                Err(e) => return fail(e),
            };
            (hardware.backends(), format!("calibrated on {}", t.drone))
        }
    };
    fly_and_fit(a, backends, &stage, &prior, &axes, &note)
}

/// The options `calibrate` checks before anything is loaded or flown: the axes to test and
/// the stage.
fn calibrate_options(a: &CalibrateArgs) -> Result<(Vec<Axis>, Stage), String> {
    if a.drone.is_some() {
        let given = [
            (a.seed.is_some(), "--seed"),
            (a.ideal, "--ideal"),
            (a.plant.is_some(), "--plant"),
        ];
        crate::shoot::refuse_sim_options(&given)?;
    }
    crate::shoot::check_servo_rate(a.rate)?;
    if a.repeats == Some(0) {
        return Err("--repeats must be at least 1 (tests per axis)".to_string());
    }
    Ok((axes(&a.axis)?, stage(&a.stage)?))
}

/// The simulated drone the tests fly (`--plant`, or the prior profile, on an empty `stage`)
/// and its seed; `Err` is the exit status once the reason is printed.
fn simulator(
    a: &CalibrateArgs,
    prior: &Profile,
    stage: Stage,
    color: bool,
) -> Result<(Simulator, u64), ExitCode> {
    let plant = match &a.plant {
        Some(name) => crate::compile::profile_arg("--plant", name, color)?,
        None => prior.clone(),
    };
    let seed = a.seed.unwrap_or(1);
    let mut cfg = SimConfig::new(seed);
    if a.ideal {
        cfg.effects = Effects {
            mocap_noise: true,
            ..Effects::none()
        };
    }
    let scene = Scene {
        stage,
        lens: None,
        drone: None,
        actors: Vec::new(),
        blocking: Vec::new(),
    };
    match Simulator::new(&cfg, &plant, &scene) {
        Ok(s) => Ok((s, seed)),
        Err(e) => Err(fail(e)),
    }
}

/// Flies the calibration's tests on `backends`, writes the report if asked, and [`finish`]es
/// with the fit; `note` goes into the written profile's description.
fn fly_and_fit(
    a: &CalibrateArgs,
    backends: Backends<'_>,
    stage: &Stage,
    prior: &Profile,
    axes: &[Axis],
    note: &str,
) -> ExitCode {
    let plan = Plan {
        axes: axes.to_vec(),
        rate_hz: a.rate,
        repeats: a.repeats.unwrap_or(Plan::default().repeats),
        tilt_repeats: a.repeats.unwrap_or(Plan::default().tilt_repeats),
        ..Plan::default()
    };
    let result = cal::calibrate(backends, stage, prior, &plan, Some(&INTERRUPTS));
    match result {
        Ok(c) => {
            if let Some(dir) = &a.report {
                let tests: Vec<(Axis, Vec<&Segment>)> = axes
                    .iter()
                    .map(|&ax| {
                        (
                            ax,
                            c.tests
                                .iter()
                                .filter(|(t, _)| *t == ax)
                                .map(|(_, s)| s)
                                .collect(),
                        )
                    })
                    .collect();
                match write_report(dir, &c.fit, &c.errors, prior, &tests).and_then(|mut files| {
                    write_tests(dir, &c.tests).map(|f| {
                        files.push(f);
                        files
                    })
                }) {
                    Ok(files) => outln!("report: {} files in {}", files.len(), dir.display()),
                    Err(e) => return fail(e),
                }
            }
            finish(&c.fit, &c.errors, prior, axes, &a.output, note)
        }
        Err(e) => fail(format!("calibration flight: {e}")),
    }
}

pub fn run_identify(a: &IdentifyArgs, color: bool) -> ExitCode {
    let axes = match axes(&a.axis) {
        Ok(x) => x,
        Err(e) => return fail(e),
    };
    if !(a.window > 0.0 && a.window.is_finite()) {
        return fail("--window must be a positive number of seconds");
    }
    let log = match FlightLog::open(&a.log) {
        Ok(l) => l,
        Err(e) => {
            return fail(format!(
                "cannot read the flight log `{}`: {e}",
                a.log.display()
            ))
        }
    };
    // Checked ahead of the fit, which may take a while on a long flight.
    if let Err(e) = crate::files::prepare_output(&a.output, "-o") {
        return fail(e);
    }
    // The fit uses what could be read; its segments never span a gap (identify splits them
    // where ticks are missing).
    for line in crate::replay::damage_warnings(&a.log, &log) {
        errln!("{line}");
    }
    let prev = match &a.profile {
        Some(name) => match crate::compile::profile_arg("--profile", name, color) {
            Ok(p) => p,
            Err(c) => return c,
        },
        None => log.header.profile.clone(),
    };
    let segments = identify::segments_from_log(&log.ticks, a.window);
    let (fit, errors) = identify::fit_model(&segments, &axes);
    if let Some(dir) = &a.report {
        let tests: Vec<(Axis, Vec<&Segment>)> = axes
            .iter()
            .map(|&ax| (ax, most_excited(&segments, ax, 4)))
            .collect();
        match write_report(dir, &fit, &errors, &prev, &tests) {
            Ok(files) => outln!("report: {} files in {}", files.len(), dir.display()),
            Err(e) => return fail(e),
        }
    }
    let name = a
        .log
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    finish(
        &fit,
        &errors,
        &prev,
        &axes,
        &a.output,
        &format!("identified from {name}"),
    )
}
