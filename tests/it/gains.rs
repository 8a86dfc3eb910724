//! `dronecine gains`: the JSON keys and shapes, the numbers' properties (symmetric P,
//! stable poles, the rotation of K1 with the heading, the overrides taking effect), the text
//! layout, and the errors (bad weights, bad lists, unknown profiles) with exit code 1.

use crate::common::{dronecine, stderr, stdout};

fn json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["gains", "--json"];
    all.extend_from_slice(args);
    let o = dronecine(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("JSON")
}

fn matrix(v: &serde_json::Value, rows: usize, cols: usize) -> Vec<Vec<f64>> {
    let m: Vec<Vec<f64>> = serde_json::from_value(v.clone()).expect("array of rows");
    assert_eq!(m.len(), rows);
    assert!(m.iter().all(|r| r.len() == cols));
    m
}

#[test]
fn json_has_the_documented_keys_and_shapes() {
    let v = json(&[]);
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    let mut want = vec![
        "P",
        "K1",
        "N1",
        "closed_loop_pole_magnitudes",
        "kalman_gain",
        "k2",
        "residual",
    ];
    want.sort();
    let mut got = keys.clone();
    got.sort();
    assert_eq!(got, want);
    let p = matrix(&v["P"], 6, 6);
    for (i, row) in p.iter().enumerate() {
        assert!(row[i] > 0.0);
        for (j, v) in row.iter().enumerate() {
            assert!((v - p[j][i]).abs() <= 1e-9 * row[i].abs().max(1.0));
        }
    }
    matrix(&v["K1"], 3, 6);
    matrix(&v["N1"], 3, 6);
    let l = matrix(&v["kalman_gain"], 6, 3);
    assert!(l[3][0] > 0.0 && l[3][0] < 1.0);
    let poles: Vec<f64> = serde_json::from_value(v["closed_loop_pole_magnitudes"].clone()).unwrap();
    assert_eq!(poles.len(), 6);
    assert!(poles.iter().all(|&m| m > 0.0 && m < 1.0), "{poles:?}");
    assert!(v["residual"].as_f64().unwrap() < 1e-9);
    // ardrone2: γ = 0.05, τ = 0.5 s, Δ = Δ̄ = 0.01 s.
    let k2 = 0.05f64.powf(0.01 / 0.49);
    assert!((v["k2"].as_f64().unwrap() - k2).abs() < 1e-12);
}

/// K1 at heading c is K1 at heading 0 rotated: K1(c) = K1(0)·S(c)ᵀ.
#[test]
fn heading_rotates_the_gain() {
    let k0 = matrix(&json(&[])["K1"], 3, 6);
    let c = 0.8f64;
    let kc = matrix(&json(&["--heading", "0.8"])["K1"], 3, 6);
    let (s, co) = c.sin_cos();
    for i in 0..3 {
        for block in [0, 3] {
            // Row times blockdiag(Rz, Rz)ᵀ on the x/y columns.
            let (a, b) = (k0[i][block], k0[i][block + 1]);
            let want = [a * co - b * s, a * s + b * co];
            assert!((kc[i][block] - want[0]).abs() < 1e-9, "{kc:?}");
            assert!((kc[i][block + 1] - want[1]).abs() < 1e-9, "{kc:?}");
        }
    }
    let kn = matrix(&json(&["--heading", "-0.8"])["K1"], 3, 6);
    assert!((kn[0][0] - kc[0][0]).abs() > 1e-3);
}

#[test]
fn overrides_change_the_gains() {
    let base = json(&[]);
    // Heavier position weights: stiffer position gains.
    let stiff = json(&["--q", "1,1,1,100,100,100"]);
    let k = |v: &serde_json::Value, i: usize, j: usize| v["K1"][i][j].as_f64().unwrap().abs();
    assert!(k(&stiff, 0, 4) > k(&base, 0, 4));
    // Cheaper tilt: larger gains.
    let cheap = json(&["--r", "5,5,5"]);
    assert!(k(&cheap, 1, 3) > k(&base, 1, 3));
    // A different time step and model change P.
    let other = json(&[
        "--dt",
        "0.02",
        "--tau",
        "1.2,1.7,1.0",
        "--gain",
        "15,17.5,1",
    ]);
    assert_ne!(other["P"], base["P"]);
    let k2 = 0.05f64.powf(0.02 / 0.48);
    assert!((other["k2"].as_f64().unwrap() - k2).abs() < 1e-12);
}

#[test]
fn text_output_is_aligned() {
    let o = dronecine(&["gains", "--heading", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for title in [
        "P, the Riccati solution",
        "K1, the feedback gain",
        "N1, the pre-filter",
        "Closed-loop pole magnitudes",
        "Steady-state Kalman gain",
        "k2, the heading pole",
        "DARE residual",
    ] {
        assert!(out.contains(title), "{title}\n{out}");
    }
    // The rows of K1 have the same width and their numbers end in the same columns.
    let lines: Vec<&str> = out.lines().collect();
    let at = lines.iter().position(|l| l.starts_with("K1")).unwrap();
    let block = &lines[at + 1..at + 5];
    assert!(
        block
            .iter()
            .all(|l| l.chars().count() == block[0].chars().count()),
        "{block:?}"
    );
    assert!(block[1].trim_start().starts_with("roll"));
}

/// A tick far shorter than the model's time constants puts every pole within 1e-8 of 1: the
/// text says how far below 1 (`1.000000` would read as on the stability limit), and the
/// JSON's magnitudes are all below 1.
#[test]
fn poles_next_to_one_print_their_distance_below_it() {
    let o = dronecine(&["gains", "--dt", "1e-9"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("Closed-loop pole"))
        .unwrap();
    let poles = lines[at + 1];
    assert_eq!(poles.matches("1 − ").count(), 6, "{poles}");
    assert!(!poles.contains("1.000000"), "{poles}");
    assert!(out.contains("heading pole per tick: 1 − "), "{out}");
    let j = json(&["--dt", "1e-9"]);
    let magnitudes = j["closed_loop_pole_magnitudes"].as_array().unwrap();
    assert!(magnitudes.iter().all(|m| m.as_f64().unwrap() < 1.0), "{j}");
    // At the servo's rates, six decimals.
    let o = dronecine(&["gains"]);
    let out = stdout(&o);
    let poles = out
        .lines()
        .skip_while(|l| !l.starts_with("Closed-loop pole"))
        .nth(1)
        .unwrap();
    assert!(
        !poles.contains(" − ") && out.contains("heading pole per tick: 0."),
        "{out}"
    );
}

#[test]
fn profile_files_are_read() {
    let o = dronecine(&[
        "gains",
        "--json",
        "--profile",
        "compiler/profile/profiles/ardrone2-outdoor.toml",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = dronecine(&["gains", "--profile", "ardrone2-outdoor"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("`ardrone2-outdoor`"));
}

#[test]
fn bad_weights_fail_with_exit_code_1() {
    let o = dronecine(&["gains", "--q", "1,1,1,0,0,0"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("servo.q[3] = 0"), "{err}");
    assert!(err.contains("--q"), "{err}");
    assert!(stdout(&o).is_empty());

    let o = dronecine(&["gains", "--r", "50,-1,5"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("--r: `r[1]` is -1, outside its range: it must be > 0"),
        "{}",
        stderr(&o)
    );
    // The overrides are held to the profile's own ranges: `--tau 1000,1,1` would give gains
    // for a model no profile file may have.
    for (args, says) in [
        (
            ["--tau", "1000,1,1"],
            "--tau: `tau_roll_s` is 1000 s, outside its range: it must be > 0 and ≤ 30 s",
        ),
        (
            ["--gain", "17.5,17.5,0"],
            "--gain: `gain_vz` is 0, outside its range: it must be > 0 and ≤ 10",
        ),
        (
            ["--q", "1,-1,1,30,30,30"],
            "--q: `q[1]` is -1, outside its range: it must be ≥ 0",
        ),
        (
            ["--tau", "1,nan,1"],
            "--tau: `tau_pitch_s` must be a finite number, not NaN",
        ),
    ] {
        let o = dronecine(&["gains", args[0], args[1]]);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(stdout(&o).is_empty());
    }

    let o = dronecine(&["gains", "--q", "1,1,1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--q takes 6"), "{}", stderr(&o));

    let o = dronecine(&["gains", "--tau", "1,x,1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("`x` is not a number"), "{}", stderr(&o));

    let o = dronecine(&["gains", "--dt", "-0.01"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--dt"), "{}", stderr(&o));
}

#[test]
fn unknown_profiles_fail_with_exit_code_1() {
    let o = dronecine(&["gains", "--profile", "ardrone3"]);
    assert_eq!(o.status.code(), Some(1));
    // The fix comes with the error: the closest name, every built-in one, and the file form.
    for part in [
        "--profile `ardrone3` is not a built-in drone profile, nor a file",
        "did you mean `ardrone2`?",
        "`ardrone2`, `ardrone2-outdoor`, `arducopter-quad` or `crazyflie21`",
        "`--profile mine.toml`",
    ] {
        assert!(stderr(&o).contains(part), "{part}: {}", stderr(&o));
    }
    let o = dronecine(&["gains", "--profile", "zz"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!stderr(&o).contains("did you mean"), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("built-in profiles are `ardrone2`, `ardrone2-outdoor`, `arducopter-quad` or `crazyflie21`"),
        "{}",
        stderr(&o)
    );
    let o = dronecine(&["gains", "--profile", "no/such/file.toml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot be read"), "{}", stderr(&o));
}
