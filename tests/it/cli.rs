//! The `dronecine` binary: exit codes, summary lines, JSON, fmt, completions, bad files.

use crate::common::{dronecine, stderr, stdout, temp_dir};

#[test]
fn check_prints_one_summary_line_per_valid_file() {
    let o = dronecine(&["check", "shots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let n = crate::common::scripts("shots").len();
    assert_eq!(out.lines().count(), n, "{out}");
    assert!(
        out.contains("shots/transition.psl: 1 actor, 3 shots, 14.0 s"),
        "{out}"
    );
    assert!(
        out.contains("shots/two-actors.psl: 2 actors, 1 shot, 16.0 s"),
        "{out}"
    );
    assert!(out.contains("(film annotation)"));
}

#[test]
fn check_exits_1_with_diagnostics_on_errors() {
    let o = dronecine(&[
        "check",
        "shots/square.psl",
        "tests/bad/unknown-actor-close.psl",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("psl::unknown_actor"), "{err}");
    assert!(err.contains("did you mean `Alice`?"), "{err}");
    assert!(
        err.contains("tests/bad/unknown-actor-close.psl:6:7"),
        "{err}"
    );
    assert!(
        stdout(&o).contains("shots/square.psl:"),
        "valid files still get their line"
    );
}

#[test]
fn check_json_gives_code_message_file_line_column_help() {
    let o = dronecine(&[
        "check",
        "--format",
        "json",
        "tests/bad/several-setup.psl",
        "shots/helix.psl",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    let diags = v["diagnostics"].as_array().unwrap();
    assert!(diags.len() >= 4);
    let missing_unit = diags
        .iter()
        .find(|d| d["code"] == "psl::missing_unit")
        .expect("missing unit");
    assert_eq!(missing_unit["file"], "tests/bad/several-setup.psl");
    assert_eq!(
        (
            missing_unit["line"].as_u64(),
            missing_unit["column"].as_u64()
        ),
        (Some(3), Some(16))
    );
    assert_eq!(missing_unit["help"], "write `1.80m`");
    assert_eq!(
        missing_unit["explain"],
        "dronecine explain psl::missing_unit"
    );
    assert_eq!(missing_unit["severity"], "error");
    let files = v["files"].as_array().unwrap();
    assert_eq!(files[0]["ok"], false);
    assert_eq!(files[1]["ok"], true);
    assert_eq!(files[1]["duration_s"], 42.0);
}

/// A script with hundreds of mistakes: `check` quotes the first 100 in the file's order and
/// ends with one line counting the others, by severity, and naming the command that lists
/// them; that command lists every one. `compile` says the same before refusing.
#[test]
fn many_diagnostics_show_the_first_100_and_count_the_rest() {
    let dir = temp_dir("many-diagnostics");
    let script = dir.join("many.psl");
    let mut text = String::from(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n",
    );
    for _ in 0..120 {
        // An error (psl::unknown_actor), then a warning (psl::duration_keyword).
        text.push_str("MS on Nobody for 4s\nthen dolly to MS on A back for 4s\n");
    }
    std::fs::write(&script, text).unwrap();
    let name = script.to_str().unwrap();
    let not_shown = format!(
        "… 70 more errors and 70 more warnings in `{name}` not shown; \
         `dronecine check --format json {name}` lists every one"
    );

    let o = dronecine(&["check", name]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    let codes: Vec<&str> = err.lines().filter(|l| l.starts_with("psl::")).collect();
    assert_eq!(codes.len(), 100, "{err}");
    assert_eq!(
        (codes[0], codes[1], codes[99]),
        (
            "psl::unknown_actor",
            "psl::duration_keyword",
            "psl::duration_keyword"
        )
    );
    assert!(err.contains(&format!("[{name}:102:")), "{err}");
    assert!(!err.contains(&format!("[{name}:104:")), "{err}");
    let tail: Vec<&str> = err.lines().rev().take(2).collect();
    assert_eq!(
        tail,
        ["error: 1 of 1 file failed the check", not_shown.as_str()],
        "{err}"
    );

    let o = dronecine(&["check", "--format", "json", name]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    assert_eq!(v["diagnostics"].as_array().unwrap().len(), 240);
    assert_eq!(
        (
            v["files"][0]["errors"].as_u64(),
            v["files"][0]["warnings"].as_u64()
        ),
        (Some(120), Some(120))
    );

    let out = dir.join("many.mcap");
    let o = dronecine(&["compile", name, "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert_eq!(
        err.lines().filter(|l| l.starts_with("psl::")).count(),
        100,
        "{err}"
    );
    let tail: Vec<&str> = err.lines().rev().take(2).collect();
    let refused = format!("error: `{name}` has errors; nothing was compiled");
    assert_eq!(tail, [refused.as_str(), not_shown.as_str()], "{err}");
}

#[test]
fn check_reports_unreadable_and_binary_files_without_panicking() {
    let o = dronecine(&["check", "no/such/file.psl"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("cannot read `no/such/file.psl`"),
        "{}",
        stderr(&o)
    );

    let dir = temp_dir("binary");
    let bin = dir.join("binary.psl");
    std::fs::write(&bin, b"MS on A front\xff\xfe for 4s\n\x00\x01\x02").unwrap();
    let o = dronecine(&["check", bin.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("psl::invalid_utf8") && err.contains("0xFF"),
        "{err}"
    );
    assert!(!err.contains("panicked"));

    let empty = dir.join("empty.psl");
    std::fs::write(&empty, b"").unwrap();
    let o = dronecine(&["check", empty.to_str().unwrap()]);
    assert!(
        o.status.success(),
        "an empty script is valid, with a warning"
    );
    assert!(stderr(&o).contains("psl::empty_script"));
}

/// `check` checks the profile file a script names, not only that it exists: a script whose
/// profile `compile` would refuse fails `check` with the profile's own diagnostic, not a
/// clean summary and exit 0. A folder named as a profile is called a folder.
#[test]
fn check_checks_the_profile_file_a_script_names() {
    let dir = temp_dir("check-profile");
    let script = dir.join("s.psl");
    std::fs::write(
        &script,
        "stage 8m x 6m x 3m\ndrone \"mine.toml\"\nactor A height 1.80m at (0, 0) facing 0deg\nMS on A for 2s\n",
    )
    .unwrap();
    let script = script.to_str().unwrap();
    std::fs::write(dir.join("mine.toml"), profile_text()).unwrap();
    let o = dronecine(&["check", script]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("s.psl: 1 actor, 1 shot, 2.0 s"));

    std::fs::write(
        dir.join("mine.toml"),
        profile_text().replace("tau_vz_s = 1.25", "tau_vz_s = nan"),
    )
    .unwrap();
    let o = dronecine(&["check", script]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("profile::bad_value"), "{e}");
    let line = (profile_text().lines())
        .position(|l| l.starts_with("tau_vz_s"))
        .expect("the profile sets tau_vz_s")
        + 1;
    assert!(
        e.contains(&format!("mine.toml:{line}:12")),
        "points into the profile: {e}"
    );
    assert!(
        e.contains("the drone profile") && e.contains("is not valid"),
        "{e}"
    );
    assert!(stdout(&o).is_empty(), "no summary line for a failed file");
    let o = dronecine(&["check", "--format", "json", script]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    assert_eq!(v["files"][0]["ok"], false);
    assert_eq!(v["files"][0]["errors"], 1);
    let d = &v["diagnostics"][0];
    assert_eq!(d["code"], "profile::bad_value");
    assert!(d["file"].as_str().unwrap().ends_with("mine.toml"), "{d}");
    assert_eq!(
        (d["line"].as_u64(), d["column"].as_u64()),
        (Some(line as u64), Some(12))
    );
    // As compile says it.
    let out = dir.join("x.mcap");
    let o = dronecine(&["compile", script, "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(&format!("mine.toml:{line}:12")),
        "{}",
        stderr(&o)
    );

    std::fs::remove_file(dir.join("mine.toml")).unwrap();
    std::fs::create_dir(dir.join("mine.toml")).unwrap();
    let o = dronecine(&["check", script]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("`mine.toml` is a folder, not a drone profile file"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn fmt_rewrites_and_check_mode_reports() {
    let dir = temp_dir("fmt");
    let f = dir.join("messy.psl");
    std::fs::write(
        &f,
        "stage 8m  x 6m x 3m\nactor A height 1.8m at (0,0) facing 0deg\nMS A front for 4s # go\n",
    )
    .unwrap();
    let path = f.to_str().unwrap();
    let o = dronecine(&["fmt", "--check", path]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains("would reformat"));
    assert!(
        std::fs::read_to_string(&f).unwrap().contains("8m  x"),
        "--check changes nothing"
    );

    let o = dronecine(&["fmt", path]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&f).unwrap(),
        "stage 8m x 6m x 3m\nactor A height 1.8m at (0, 0) facing 0deg\nMS on A front for 4s  # go\n"
    );
    let o = dronecine(&["fmt", "--check", path]);
    assert!(o.status.success(), "formatted file passes --check");

    std::fs::write(&f, "MS on A frnt for 4s\n").unwrap();
    let o = dronecine(&["fmt", path]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(&f).unwrap(),
        "MS on A frnt for 4s\n",
        "a bad file is left alone"
    );
}

#[test]
fn help_version_and_completions() {
    for args in [
        &["--help"][..],
        &["check", "--help"],
        &["fmt", "--help"],
        &["completions", "--help"],
    ] {
        let o = dronecine(args);
        assert!(o.status.success(), "{args:?}");
        assert!(stdout(&o).contains("Usage: dronecine"), "{args:?}");
    }
    let o = dronecine(&["--version"]);
    assert_eq!(
        stdout(&o).trim(),
        format!("dronecine {}", env!("CARGO_PKG_VERSION"))
    );
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let o = dronecine(&["completions", shell]);
        assert!(
            o.status.success() && stdout(&o).contains("dronecine"),
            "{shell}"
        );
        assert!(
            stdout(&o).contains("check") && stdout(&o).contains("fmt"),
            "{shell}"
        );
    }
    let o = dronecine(&["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2), "clap rejects an unknown shell");
}

#[test]
fn compile_writes_mcap_csv_and_previews() {
    let dir = temp_dir("compile-ok");
    // Folders that do not exist yet are made, as `shoot --log` makes its own.
    let out = dir.join("out/square.mcap");
    let csv = dir.join("tables/square.csv");
    let prev = dir.join("preview");
    let o = dronecine(&[
        "compile",
        "shots/square.psl",
        "-o",
        out.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--preview",
        prev.to_str().unwrap(),
        "--rate",
        "50",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    assert!(bytes.starts_with(b"\x89MCAP0\r\n") && bytes.ends_with(b"\x89MCAP0\r\n"));
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert_eq!(rows, 1 + 20 * 50 + 1, "header + 20 s at 50 Hz, both ends");
    for f in ["top", "side", "timeseries", "storyboard"] {
        assert!(prev.join(format!("{f}.png")).exists(), "{f}.png");
    }
    assert!(
        stdout(&o).contains(
            "square.psl: 1 shot for ardrone2, 20.0 s of reference (20.0 s as written; no \
             repositioning flight), 1001 samples at 50 Hz"
        ),
        "{}",
        stdout(&o)
    );
}

/// `compile` tells the language's warnings with its own, in the script's order, and `shoot`
/// counts them in its one line, so that a move timed with `for` is remarked on by every
/// command, not by `check` alone.
#[test]
fn compile_and_shoot_tell_the_languages_warnings_too() {
    let dir = temp_dir("compile-warnings");
    let script = dir.join("timed.psl");
    std::fs::write(
        &script,
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
         high angle MS on A front for 4s\nthen dolly to MS on A 34left for 6s\n",
    )
    .unwrap();
    let o = dronecine(&[
        "compile",
        script.to_str().unwrap(),
        "-o",
        dir.join("timed.mcap").to_str().unwrap(),
        "--color",
        "never",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let told = stderr(&o);
    let codes: Vec<&str> = told
        .lines()
        .filter(|l| l.starts_with("psl::") || l.starts_with("compile::"))
        .collect();
    // Line 4's camera angle (the compiler's), then line 5's `for` (the language's).
    assert_eq!(
        codes,
        ["compile::angle_not_rendered", "psl::duration_keyword"],
        "{told}"
    );
    let o = dronecine(&[
        "shoot",
        script.to_str().unwrap(),
        "--log",
        dir.join("timed-flight.mcap").to_str().unwrap(),
        "--color",
        "never",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "is flown as written with 2 warnings (compile::angle_not_rendered, \
             psl::duration_keyword)"
        ),
        "{}",
        stderr(&o)
    );
}

#[test]
fn compile_bad_inputs_are_clear_errors_not_panics() {
    let dir = temp_dir("compile-bad");
    let out = dir.join("x.mcap");
    let outs = out.to_str().unwrap();
    // A missing file.
    let o = dronecine(&["compile", "shots/nope.psl", "-o", outs]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot read"), "{}", stderr(&o));
    // A film annotation cannot be flown.
    let o = dronecine(&["compile", "shots/annotation.psl", "-o", outs]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("compile::no_scene"), "{}", stderr(&o));
    // A scene without shots, and an empty file: nothing to fly, said so (no panic in the
    // director for the first; the second is not called a film annotation).
    let no_shots = dir.join("no-shots.psl");
    std::fs::write(
        &no_shots,
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor Ann height 1.70m at (0, 0) facing 0deg\n",
    )
    .unwrap();
    let empty = dir.join("empty.psl");
    std::fs::write(&empty, "# nothing yet\n").unwrap();
    for (script, says) in [
        (
            &no_shots,
            "the script has no shots: there is nothing to fly",
        ),
        (&empty, "the script is empty"),
    ] {
        let script = script.to_str().unwrap();
        for args in [
            vec!["compile", script, "-o", outs],
            vec!["shoot", script, "-q", "--log", outs],
        ] {
            let o = dronecine(&args);
            assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
            let e = stderr(&o);
            assert!(e.contains("psl::empty_script") && e.contains(says), "{e}");
            assert!(e.contains("has nothing to fly"), "{e}");
        }
    }
    assert!(stderr(&dronecine(&[
        "compile",
        no_shots.to_str().unwrap(),
        "-o",
        outs
    ]))
    .contains("add a shot such as `MS on Ann front for 4s`"));
    // Both the check's warning and compile's error point where the first shot would go:
    // after the set-up's last line, not at line 1.
    let at = format!("{}:3:45", no_shots.display());
    let o = dronecine(&["check", no_shots.to_str().unwrap()]);
    assert!(
        stderr(&o).contains(&at) && stderr(&o).contains("`MS on Ann front for 4s`"),
        "{}",
        stderr(&o)
    );
    let o = dronecine(&["compile", no_shots.to_str().unwrap(), "-o", outs]);
    assert!(stderr(&o).contains(&at), "{}", stderr(&o));
    assert!(!out.exists(), "nothing compiled, nothing written");
    let o = dronecine(&["check", empty.to_str().unwrap()]);
    assert!(!stdout(&o).contains("film annotation"), "{}", stdout(&o));
    // Unwritable output paths: under a file (its folder cannot be made), a folder itself.
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let under_a_file = file.join("x.mcap");
    for (args, says) in [
        (
            vec!["-o", under_a_file.to_str().unwrap()],
            "cannot create the folder",
        ),
        (vec!["-o", dir.to_str().unwrap()], "is a folder"),
        (
            vec!["-o", outs, "--csv", under_a_file.to_str().unwrap()],
            "for --csv",
        ),
    ] {
        let o = dronecine(&[&["compile", "shots/square.psl"], &args[..]].concat());
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    // A bad TOML value: the diagnostic points into the profile.
    std::fs::write(
        dir.join("mine.toml"),
        profile_text().replace("tau_vz_s = 1.25", "tau_vz_s = -1.25"),
    )
    .unwrap();
    std::fs::write(
        dir.join("s.psl"),
        "stage 8m x 6m x 3m\ndrone \"mine.toml\"\nactor A height 1.80m at (0, 0) facing 0deg\nMS on A for 2s\n",
    )
    .unwrap();
    let o = dronecine(&["compile", dir.join("s.psl").to_str().unwrap(), "-o", outs]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("profile::bad_value") && e.contains("mine.toml"),
        "{e}"
    );
    // An infeasible script writes nothing, unless asked.
    std::fs::write(
        dir.join("fast.psl"),
        "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0) facing 0deg\npath square side 4m center (0, 0) altitude 1.5m for 4s\n",
    )
    .unwrap();
    let fast = dir.join("fast.psl");
    let o = dronecine(&["compile", fast.to_str().unwrap(), "-o", outs]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("compile::infeasible"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing written");
    let o = dronecine(&[
        "compile",
        fast.to_str().unwrap(),
        "-o",
        outs,
        "--allow-infeasible",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.exists());
    assert_eq!(
        std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e
                .as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .ends_with(".tmp"))
            .count(),
        0
    );
}

fn profile_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/compiler/profile/profiles/ardrone2.toml"
    ))
    .unwrap()
}

/// Output that cannot be written is never a panic. A pipe closed by its reader (`dronecine …
/// | head -1`) is let go, as other Unix tools do: the command finishes (a flight flies to its
/// end and its log is whole) and exits as it would have. A full disk behind stdout is an
/// error (exit 1), so that a cut output is not taken for a whole one.
#[test]
fn closed_pipes_and_full_disks_are_not_panics() {
    use std::process::{Command, Stdio};
    let dir = temp_dir("pipes");
    let log = dir.join("square.mcap");
    // stdout (and stderr when asked) closed before the command writes a byte.
    let run = |args: &[&str], close_stderr: bool| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dronecine"))
            .args(args)
            .current_dir(crate::common::workspace())
            .env("NO_COLOR", "1")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        if close_stderr {
            drop(child.stderr.take());
        }
        child.wait_with_output().unwrap()
    };

    let o = run(&["gains", "--json"], false);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));

    let o = run(&["completions", "bash"], false);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let o = run(
        &["shoot", "shots/square.psl", "--log", log.to_str().unwrap()],
        true,
    );
    assert_eq!(o.status.code(), Some(0), "the flight completes");
    let o = dronecine(&["replay", log.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("warning"),
        "a whole log: {}",
        stderr(&o)
    );

    let full = std::path::Path::new("/dev/full");
    if full.exists() {
        let sink = std::fs::OpenOptions::new().write(true).open(full).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_dronecine"))
            .args(["gains"])
            .current_dir(crate::common::workspace())
            .stdout(sink)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("error: cannot write the output"),
            "{}",
            stderr(&o)
        );
    }
}

/// `emulate --script` needs only the scene (stage, actors, blocking): a script without one is
/// refused for that, with a help that asks for a set-up and no shot (unlike `compile` and
/// `shoot`, which ask for a shot).
#[test]
fn emulate_refuses_a_script_without_a_scene_for_what_it_lacks() {
    let dir = temp_dir("emulate-bad");
    let empty = dir.join("empty.psl");
    std::fs::write(&empty, "# nothing yet\n").unwrap();
    for script in [empty.to_str().unwrap(), "shots/annotation.psl"] {
        let o = dronecine(&["emulate", "ardrone", "--script", script]);
        assert_eq!(o.status.code(), Some(1), "{script}");
        let e = stderr(&o);
        assert!(e.contains("no scene set-up"), "{script}: {e}");
        assert!(e.contains("shots are not needed here"), "{script}: {e}");
        assert!(e.contains("has no scene; nothing was emulated"), "{e}");
        assert!(!e.contains("a shot"), "{script}: {e}");
    }
}

/// `--sync-log` forces a simulated flight's log to the disk as it is written (as a real
/// flight's is); the log is the same bytes as the default one, which leaves the disk to the
/// OS, and replays.
#[test]
fn shoot_sync_log_writes_the_same_log() {
    let dir = temp_dir("sync-log");
    let (plain, synced) = (dir.join("plain.mcap"), dir.join("synced.mcap"));
    for (path, sync) in [(&plain, false), (&synced, true)] {
        let mut args = vec![
            "shoot",
            "shots/square.psl",
            "-q",
            "--log",
            path.to_str().unwrap(),
        ];
        if sync {
            args.push("--sync-log");
        }
        let o = dronecine(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
    let (a, b) = (
        std::fs::read(&plain).unwrap(),
        std::fs::read(&synced).unwrap(),
    );
    assert!(
        a == b,
        "the same log either way ({} and {} bytes)",
        a.len(),
        b.len()
    );
    let o = dronecine(&["replay", synced.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A compile that cannot write all its outputs writes none: previews under a file refuse the
/// command before the reference and the table are written.
#[test]
fn compile_writes_all_its_outputs_or_none() {
    let dir = temp_dir("all-or-none");
    let afile = dir.join("afile");
    std::fs::write(&afile, "x").unwrap();
    let (mcap, csv) = (dir.join("out/s.mcap"), dir.join("out/s.csv"));
    let o = dronecine(&[
        "compile",
        "shots/square.psl",
        "-o",
        mcap.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--preview",
        afile.join("prev").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--preview"), "{}", stderr(&o));
    assert!(!mcap.exists() && !csv.exists(), "partial outputs left");
}
