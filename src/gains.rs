//! `dronecine gains`: the LQG servo's gains for a drone profile at one tick length and
//! heading — the Riccati solution P, the feedback K1, the pre-filter N1, the closed-loop pole
//! magnitudes, the steady-state Kalman gain (the filter's dual DARE), the heading pole k2 and
//! the DARE residual — as aligned text or JSON. Model and weights can be overridden from the
//! command line to try values before writing them into a profile.

use std::process::ExitCode;

use dronecine_profile::DEFAULT_NAME;
use dronecine_servo::lqg::{GainsReport, LqgServo, ServoOptions};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A built-in profile name or a profile TOML file.
    #[arg(long, value_name = "NAME|FILE", default_value = DEFAULT_NAME)]
    profile: String,
    /// The tick length Δ, seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.01,
        allow_hyphen_values = true
    )]
    dt: f64,
    /// The heading c the world-frame gains are given at, radians.
    #[arg(
        long,
        value_name = "RAD",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    heading: f64,
    /// Override the model's time constants τ, seconds.
    #[arg(long, value_name = "PHI,THETA,ZDOT", allow_hyphen_values = true)]
    tau: Option<String>,
    /// Override the model's gains K.
    #[arg(long, value_name = "PHI,THETA,ZDOT", allow_hyphen_values = true)]
    gain: Option<String>,
    /// Override the state weights Q on [vx, vy, vz, x, y, z].
    #[arg(long, value_name = "Q1,...,Q6", allow_hyphen_values = true)]
    q: Option<String>,
    /// Override the input weights R on [roll, pitch, vz].
    #[arg(long, value_name = "R1,R2,R3", allow_hyphen_values = true)]
    r: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

/// `N` comma-separated numbers given to `--flag`.
fn numbers<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!(
            "--{flag} takes {N} comma-separated numbers, got {} (`{text}`)",
            parts.len()
        ));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse::<f64>()
            .map_err(|_| format!("--{flag}: `{p}` is not a number"))?;
    }
    Ok(out)
}

pub fn run(a: &Args, color: bool) -> ExitCode {
    let mut p = match crate::compile::profile_arg("--profile", &a.profile, color) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let overrides = (|| -> Result<Vec<&'static str>, String> {
        let mut given = Vec::new();
        if let Some(t) = &a.tau {
            let [phi, theta, zdot] = numbers::<3>("tau", t)?;
            (p.model.tau_roll_s, p.model.tau_pitch_s, p.model.tau_vz_s) = (phi, theta, zdot);
            given.push("model.tau");
        }
        if let Some(t) = &a.gain {
            let [phi, theta, zdot] = numbers::<3>("gain", t)?;
            (
                p.model.gain_roll_mps_per_rad,
                p.model.gain_pitch_mps_per_rad,
                p.model.gain_vz,
            ) = (phi, theta, zdot);
            given.push("model.gain");
        }
        if let Some(t) = &a.q {
            p.servo.q = numbers::<6>("q", t)?;
            given.push("servo.q");
        }
        if let Some(t) = &a.r {
            p.servo.r = numbers::<3>("r", t)?;
            given.push("servo.r");
        }
        // The profile's own ranges hold for the overrides too.
        let m = &p.model;
        let index = |i: usize| format!("[{i}]");
        let values = [
            ("model", "tau_roll_s", m.tau_roll_s, "tau"),
            ("model", "tau_pitch_s", m.tau_pitch_s, "tau"),
            ("model", "tau_vz_s", m.tau_vz_s, "tau"),
            (
                "model",
                "gain_roll_mps_per_rad",
                m.gain_roll_mps_per_rad,
                "gain",
            ),
            (
                "model",
                "gain_pitch_mps_per_rad",
                m.gain_pitch_mps_per_rad,
                "gain",
            ),
            ("model", "gain_vz", m.gain_vz, "gain"),
        ]
        .into_iter()
        .map(|(s, k, x, f)| (s, k, String::new(), x, f))
        .chain(
            p.servo
                .q
                .iter()
                .enumerate()
                .map(|(i, &x)| ("servo", "q", index(i), x, "q")),
        )
        .chain(
            p.servo
                .r
                .iter()
                .enumerate()
                .map(|(i, &x)| ("servo", "r", index(i), x, "r")),
        );
        for (section, key, what, x, flag) in values {
            let overridden = given.iter().any(|g| g.rsplit('.').next() == Some(flag));
            if let Some(why) = overridden
                .then(|| dronecine_profile::out_of_range(section, key, &what, x))
                .flatten()
            {
                return Err(format!("--{flag}: {why}"));
            }
        }
        Ok(given)
    })();
    let given = match overrides {
        Ok(g) => g,
        Err(e) => return fail(e),
    };
    if !(a.heading.is_finite()) {
        return fail(format!("--heading {} is not a finite angle", a.heading));
    }
    let options = ServoOptions {
        nominal_dt_s: a.dt,
        ..ServoOptions::default()
    };
    let report = LqgServo::new(&p, options).and_then(|s| s.gains_at(a.dt, a.heading));
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            let from = given
                .iter()
                .find(|g| e.key.starts_with(**g))
                .map(|g| format!(" (as set by --{})", g.rsplit('.').next().unwrap_or(g)))
                .unwrap_or_default();
            return fail(format!("{e}{from}"));
        }
    };
    if a.json {
        outln!("{}", json(&report));
    } else {
        out!("{}", text(&p.name, &report));
    }
    ExitCode::SUCCESS
}

fn json(r: &GainsReport) -> serde_json::Value {
    serde_json::json!({
        "P": r.p,
        "K1": r.k1,
        "N1": r.n1,
        "closed_loop_pole_magnitudes": r.closed_loop_pole_magnitudes,
        "kalman_gain": r.kalman_gain,
        "k2": r.k2,
        "residual": r.residual,
    })
}

/// A matrix as aligned rows, with row and column labels.
fn matrix<const C: usize>(out: &mut String, rows: &[[f64; C]], row_names: &[&str], cols: &[&str]) {
    use std::fmt::Write;
    let max = rows.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    // Rounding dust of the rotations (≈ 1e-16 of the largest entry) is shown as 0.
    let clean = |v: f64| if v.abs() <= 1e-12 * max { 0.0 } else { v };
    let min = rows
        .iter()
        .flatten()
        .map(|&v| clean(v))
        .filter(|v| *v != 0.0)
        .fold(f64::INFINITY, |m, v| m.min(v.abs()));
    let fixed = max < 1e5 && min >= 1e-3;
    let cell = |v: f64| {
        let v = clean(v);
        if fixed {
            format!("{v:>13.6}")
        } else {
            format!("{v:>13.4e}")
        }
    };
    let _ = write!(out, "{:>8}", "");
    for c in cols {
        let _ = write!(out, "{c:>13}");
    }
    out.push('\n');
    for (row, name) in rows.iter().zip(row_names) {
        let _ = write!(out, "{name:>8}");
        for &v in row {
            out.push_str(&cell(v));
        }
        out.push('\n');
    }
}

fn text(name: &str, r: &GainsReport) -> String {
    use std::fmt::Write;
    let state = ["vx", "vy", "vz", "x", "y", "z"];
    let input = ["roll", "pitch", "vz"];
    let mut out = String::new();
    let _ = writeln!(
        out,
        "LQG servo gains for `{name}` at Δ = {} s, heading {} rad ({:.1}°)\n",
        r.dt_s,
        r.heading_rad,
        r.heading_rad.to_degrees()
    );
    let _ = writeln!(out, "P, the Riccati solution (state × state):");
    matrix(&mut out, &r.p, &state, &state);
    let _ = writeln!(
        out,
        "\nK1, the feedback gain, u = −K1 (x̂ − r) + … (input × state):"
    );
    matrix(&mut out, &r.k1, &input, &state);
    let _ = writeln!(
        out,
        "\nN1, the pre-filter, u = −K1 x̂ + N1 r (input × state):"
    );
    matrix(&mut out, &r.n1, &input, &state);
    let _ = writeln!(out, "\nClosed-loop pole magnitudes |eig(A1 − B1 K1)|:");
    let mut poles = r.closed_loop_pole_magnitudes;
    poles.sort_by(|a, b| b.total_cmp(a));
    let _ = write!(out, "{:>8}", "");
    for p in poles {
        let _ = write!(out, "{:>13}", pole_text(p));
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "\nSteady-state Kalman gain (state × measured position):"
    );
    matrix(&mut out, &r.kalman_gain, &state, &["x", "y", "z"]);
    let _ = writeln!(out, "\nk2, the heading pole per tick: {}", pole_text(r.k2));
    let _ = writeln!(
        out,
        "DARE residual: {:.3e} (relative, {} doublings)",
        r.residual, r.iterations
    );
    out
}

/// A pole magnitude as printed: six decimals, or, within 5e-7 of 1 (a tick far shorter than
/// the model's time constants: `--dt 1e-6`), its distance below 1 (`1 − 3.2e-9`), so that a
/// stable pole never reads as `1.000000`, on the stability limit.
fn pole_text(m: f64) -> String {
    let below = 1.0 - m;
    if m.is_finite() && below > 0.0 && below < 5e-7 {
        format!("1 − {below:.1e}")
    } else {
        format!("{m:.6}")
    }
}
