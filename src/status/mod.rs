//! `dronecine status`: connect to a drone and print what a person checks before a flight.
//! This module reads the AR.Drone and holds what every read-out shares (the error, the
//! one-shot verdict, the `--watch` loop); `mavlink` reads an ArduPilot Copter, `crazyflie` a
//! Crazyflie.
//!
//! The AR.Drone read-out starts its navdata and prints — control state, battery, angles,
//! altitude, velocities, the set state flags — once or continuously (`--watch`), as text or
//! JSON (one object per line).
//!
//! Each read-out names what makes it untrustworthy (`ArDroneStatus::problems`): packets
//! rejected by kind (bad checksum, truncated, not navdata, malformed) with how many of how
//! many received, implausible fields one by one, a silent link. A single read-out with a
//! problem exits 1; `--watch` keeps going and prints the problems of each read-out.
//!
//! The drone is only read: no limits are written and no take-off / land command is sent
//! (`ArDroneClient::monitor`), so it is safe to watch a drone another program flies.

mod crazyflie;
mod mavlink;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use dronecine_ardrone::client::{ArDroneClient, ArDroneOptions, ArDroneStatus};
use dronecine_ardrone::url::ArDroneUrl;
use dronecine_backend::Drone;

/// How long the first read-out listens after the start-up: at the demo rate of 15 Hz about
/// seven packets, enough to count bad packets among good ones without making a check slow.
const FIRST_READOUT: Duration = Duration::from_millis(500);

pub struct Args<'a> {
    pub drone: &'a str,
    pub watch: bool,
    pub json: bool,
    pub timeout_s: f64,
    pub interval_s: f64,
}

/// Prints `msg` as the command's error: the exit code of a failed `status`.
fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

/// A single read-out's exit: success without a problem, else how many the read-out above
/// lists, with `of` (what has them) and `advice`.
fn verdict(problems: usize, of: &str, advice: &str) -> ExitCode {
    match problems {
        0 => ExitCode::SUCCESS,
        n => fail(format!(
            "{n} problem{} with {of} (listed above): {advice}",
            if n == 1 { "" } else { "s" }
        )),
    }
}

/// `--watch` on a drone read in the background: `each` prints a read-out every `interval_s`,
/// a blank line between text read-outs, until the command is interrupted.
fn watch(interval_s: f64, json: bool, mut each: impl FnMut()) -> ExitCode {
    let interval = Duration::from_secs_f64(interval_s);
    let mut next = Instant::now() + interval;
    loop {
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
        next += interval;
        if !json {
            outln!();
        }
        each();
    }
}

fn text(url: &ArDroneUrl, s: &ArDroneStatus) -> String {
    let mut warnings = Vec::new();
    for (flag, what) in [
        ("emergency", "EMERGENCY: restart the drone"),
        ("battery_low", "battery low"),
        ("motors_problem", "motor problem"),
        ("cutout_detected", "motor cut-out detected"),
        ("com_watchdog", "communication watchdog"),
        (
            "magnetometer_needs_calibration",
            "magnetometer needs calibration",
        ),
    ] {
        if s.flags.contains(&flag) {
            warnings.push(what);
        }
    }
    format!(
        "{url}\n  control state  {} (minor {})\n  battery        {} %\n  angles         \
         θ {:.1}°  φ {:.1}°  ψ {:.1}°\n  altitude       {:.3} m\n  velocity       \
         {:.3} {:.3} {:.3} m/s\n  flags          {}\n  navdata        #{} ({:.0} ms ago), {} \
         received\n{}{}",
        s.ctrl_state,
        s.ctrl_minor,
        s.battery_percent,
        s.theta_deg,
        s.phi_deg,
        s.psi_deg,
        s.altitude_m,
        s.velocity_mps[0],
        s.velocity_mps[1],
        s.velocity_mps[2],
        if s.flags.is_empty() {
            "none".to_string()
        } else {
            s.flags.join(", ")
        },
        s.navdata_sequence,
        s.link_age_s * 1000.0,
        packets(s.navdata_received),
        if warnings.is_empty() {
            String::new()
        } else {
            format!("  warning        {}\n", warnings.join("; "))
        },
        s.problems
            .iter()
            .map(|p| format!("  problem        {p}\n"))
            .collect::<String>(),
    )
}

fn packets(n: u64) -> String {
    if n == 1 {
        "1 packet".into()
    } else {
        format!("{n} packets")
    }
}

/// Reads navdata (and answers the watchdog) until `until`.
fn listen(client: &mut ArDroneClient, until: Instant) {
    while Instant::now() < until {
        client.telemetry();
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn print(url: &ArDroneUrl, s: &ArDroneStatus, json: bool) -> Result<(), String> {
    if json {
        let line = serde_json::to_string(s).map_err(|e| e.to_string())?;
        outln!("{line}");
    } else {
        out!("{}", text(url, s));
    }
    Ok(())
}

pub fn run(a: &Args) -> ExitCode {
    let mavlink = a.drone.starts_with("mavlink:");
    if mavlink || a.drone.starts_with("crazyflie") {
        let timeout_ok = a.timeout_s.is_finite() && a.timeout_s > 0.0 && a.timeout_s <= 60.0;
        let interval_ok = a.interval_s.is_finite() && (0.05..=60.0).contains(&a.interval_s);
        if !(timeout_ok && interval_ok) {
            return fail("--timeout must be in (0, 60] and --interval in [0.05, 60] seconds");
        }
        let args = mavlink::Args {
            watch: a.watch,
            json: a.json,
            timeout_s: a.timeout_s,
            interval_s: a.interval_s,
        };
        if !mavlink {
            return match dronecine_crazyflie::CrazyflieUrl::parse(a.drone) {
                Ok(url) => crazyflie::run(&args, &url),
                Err(e) => fail(format!("--drone: {e}")),
            };
        }
        return match dronecine_mavlink::MavlinkUrl::parse(a.drone) {
            Ok(url) => mavlink::run(&args, &url),
            Err(e) => fail(format!("--drone: {e}")),
        };
    }
    let url = match ArDroneUrl::parse(a.drone) {
        Ok(u) => u,
        Err(e) => return fail(format!("--drone: {e}")),
    };
    if !(a.timeout_s.is_finite() && a.timeout_s > 0.0 && a.timeout_s <= 60.0) {
        return fail(format!(
            "--timeout {} must be in (0, 60] seconds",
            a.timeout_s
        ));
    }
    if !(a.interval_s.is_finite() && (0.05..=60.0).contains(&a.interval_s)) {
        return fail(format!(
            "--interval {} must be in [0.05, 60] seconds",
            a.interval_s
        ));
    }
    let timeout = Duration::from_secs_f64(a.timeout_s);
    let options = ArDroneOptions {
        navdata_timeout: timeout,
        ack_timeout: timeout,
        config_ids: None,
    };
    let mut client = match ArDroneClient::monitor(&url, &options) {
        Ok(c) => c,
        Err(e) => return fail(e),
    };
    listen(&mut client, Instant::now() + FIRST_READOUT);
    let status = client.status();
    if let Err(e) = print(&url, &status, a.json) {
        return fail(e);
    }
    if !a.watch {
        return verdict(
            status.problems.len(),
            "the drone's navdata",
            "do not trust this read-out",
        );
    }
    let interval = Duration::from_secs_f64(a.interval_s);
    let mut next = Instant::now() + interval;
    loop {
        listen(&mut client, next);
        next += interval;
        let status = client.status();
        if !a.json {
            outln!();
        }
        if let Err(e) = print(&url, &status, a.json) {
            return fail(e);
        }
    }
}
