//! `dronecine shoot` and `dronecine replay` from the command line: the JSON report, the
//! flight log, bit-exact replay, seeded determinism, and bad input.

use crate::common::{dronecine, stderr, stdout, temp_dir};

use std::process::{Command, Output};

fn report(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

#[test]
fn shoot_reports_json_logs_the_flight_and_replay_reproduces_it() {
    let dir = temp_dir("json");
    let log = dir.join("transition.mcap");
    let log_s = log.to_str().unwrap();
    let o = dronecine(&[
        "shoot",
        "shots/transition.psl",
        "--log",
        log_s,
        "--report",
        "json",
        "--seed",
        "5",
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&o);
    for key in [
        "rms_position_error_m",
        "max_position_error_m",
        "rms_heading_error_rad",
        "rms_framing_error",
        "saturated_fraction",
    ] {
        assert!(r[key].is_number(), "{key}: {r}");
    }
    assert_eq!(r["completed"], true);
    let shots = r["shots"].as_array().unwrap();
    assert_eq!(shots.len(), 3, "{r}");
    for s in shots {
        assert!(
            s["rms_position_error_m"].is_number() && s["label"].is_string(),
            "{s}"
        );
    }
    assert!(shots[0]["label"]
        .as_str()
        .unwrap()
        .starts_with("MS on A front"));
    assert!(r["rms_position_error_m"].as_f64().unwrap() < 0.1);
    assert!(log.exists());

    // Replay: the same commands bit for bit, the same report.
    let o = dronecine(&["replay", log_s, "--report", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("reproduce the logged commands exactly"));
    let replayed = report(&o);
    assert_eq!(replayed["mismatches"], 0);
    assert_eq!(replayed["unreplayed"], 0);
    assert_eq!(replayed["report"], r, "replay gives the flight's report");

    // One flipped bit in a chunk in the middle: the rest of the log is still read, the
    // damage named with the ticks it cost, and the replay resumes after it from the next
    // chunk's key frame and checks every tick it read (exit 0) and says so.
    let damaged = dir.join("damaged.mcap");
    let offset = crate::common::damage_middle_chunk(&log, &damaged);
    let o = dronecine(&["replay", damaged.to_str().unwrap(), "--report", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "is damaged at byte {offset} (a chunk whose CRC does not match"
        )),
        "{err}"
    );
    assert!(err.contains("intact record, at byte"), "{err}");
    assert!(err.contains("s are lost"), "{err}");
    assert!(err.contains("resumed after 1 gap"), "{err}");
    let replayed = report(&o);
    assert_eq!(replayed["mismatches"], 0);
    assert_eq!(replayed["unreplayed"], 0, "{replayed}");
    assert_eq!(replayed["resumed"], 1, "{replayed}");
    assert!(replayed["ticks"].as_u64().unwrap() > 1000, "{replayed}");
    assert_eq!(replayed["damage"][0]["offset"], offset);
    assert_eq!(
        replayed["report"]["completed"], true,
        "read past the damage"
    );

    // One flipped bit in the header's metadata record, before the first tick: the header is
    // read from its copy under a CRC, and every tick is replayed.
    let bytes = std::fs::read(&log).unwrap();
    let at = bytes
        .windows(21)
        .position(|w| w == b"gain_roll_mps_per_rad")
        .unwrap();
    let mut flipped = bytes.clone();
    flipped[at] ^= 0x20;
    let header = dir.join("header.mcap");
    std::fs::write(&header, &flipped).unwrap();
    let o = dronecine(&["replay", header.to_str().unwrap(), "--report", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("no tick is lost"), "{}", stderr(&o));
    let replayed = report(&o);
    assert_eq!(
        (&replayed["unreplayed"], &replayed["mismatches"]),
        (&0.into(), &0.into())
    );
    assert_eq!(replayed["report"], r, "the flight's report, whole");

    // Cut inside its first chunk: no tick to check, and replay says so.
    let (first, _) = crate::common::chunks(&log)[0];
    let bytes = std::fs::read(&log).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..(first + 20) as usize]).unwrap();
    let o = dronecine(&["replay", cut.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("ends early"), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("holds no controller tick"),
        "{}",
        stderr(&o)
    );
    let out = stdout(&o);
    assert!(
        out.starts_with("The log ends before the first shot.")
            && out.contains("\n\nunfinished log of a flight"),
        "{out}"
    );
}

#[test]
fn the_same_seed_flies_the_same_flight() {
    let run = |seed: &str, controller: &str| {
        let dir = temp_dir(&format!("seed{seed}{controller}"));
        let log = dir.join("f.mcap");
        let o = dronecine(&[
            "shoot",
            "shots/square.psl",
            "--log",
            log.to_str().unwrap(),
            "--report",
            "json",
            "--seed",
            seed,
            "--controller",
            controller,
            "-q",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        report(&o)
    };
    assert_eq!(run("3", "lqg"), run("3", "lqg"));
    assert_ne!(run("3", "lqg"), run("4", "lqg"));
    // The baseline flies the same seeded flight, worse.
    let (lqg, pid) = (run("3", "lqg"), run("3", "pid"));
    assert!(
        lqg["rms_position_error_m"].as_f64().unwrap()
            < pid["rms_position_error_m"].as_f64().unwrap()
    );
}

#[test]
fn shoot_text_report_and_default_log_location() {
    let dir = temp_dir("text");
    std::fs::copy(
        crate::common::workspace().join("shots/square.psl"),
        dir.join("square.psl"),
    )
    .unwrap();
    // `dronecine ARGS` run in `dir`.
    let run_in_dir = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_dronecine"))
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap()
    };
    let o = run_in_dir(&["shoot", "square.psl", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    // The take in words first (a path frames nobody), then the figures, then the next step.
    assert!(
        out.starts_with("The take is complete: no shot framed an actor; the drone within "),
        "{out}"
    );
    assert!(
        out.contains("\n\ncompleted flight with ardrone2 (lqg)"),
        "{out}"
    );
    assert!(out.contains("path square side 2m"), "{out}");
    let logs: Vec<_> = std::fs::read_dir(dir.join("flights"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(logs.len(), 1, "{logs:?}");
    assert!(
        logs[0].starts_with("square-") && logs[0].ends_with(".mcap"),
        "{logs:?}"
    );

    // A flight never overwrites a recording. Two more flights, in the same second or not:
    // three logs (a default name already taken is numbered `-2`, `-3`).
    for _ in 0..2 {
        let o = run_in_dir(&["shoot", "square.psl", "-q", "--seed", "9"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(std::fs::read_dir(dir.join("flights")).unwrap().count(), 3);
    // An explicit --log that exists is refused before take-off, the file untouched.
    let first = dir.join("flights").join(&logs[0]);
    let before = std::fs::read(&first).unwrap();
    let o = run_in_dir(&[
        "shoot",
        "square.psl",
        "-q",
        "--log",
        first.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("already exists; a flight does not overwrite a recording"),
        "{e}"
    );
    assert!(o.stdout.is_empty(), "nothing flown: {}", stdout(&o));
    assert_eq!(std::fs::read(&first).unwrap(), before);
    // `--log DIR`: the time-stamped name, in that folder.
    std::fs::create_dir(dir.join("day2")).unwrap();
    let o = run_in_dir(&["shoot", "square.psl", "-q", "--log", "day2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let day2: Vec<_> = std::fs::read_dir(dir.join("day2"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert!(
        day2.len() == 1 && day2[0].starts_with("square-") && day2[0].ends_with(".mcap"),
        "{day2:?}"
    );
    let log = format!("day2/{}", day2[0]);
    assert!(
        stdout(&o).ends_with(&format!(
            "\n\nflight log: {log}\n  replay it: dronecine replay {log}\n  see it: open it in \
             Foxglove (https://foxglove.dev): the flight in 3D and every figure over time\n"
        )),
        "{}",
        stdout(&o)
    );
}

#[test]
fn bad_input_is_a_clear_error() {
    let o = dronecine(&["shoot", "shots/no-such.psl"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot read"), "{}", stderr(&o));

    let dir = temp_dir("bad");
    let infeasible = dir.join("fast.psl");
    std::fs::write(
        &infeasible,
        "stage 8m x 6m x 3m\ndrone ardrone2\npath square side 4m center (0, 0) altitude 1.5m for 4s\n",
    )
    .unwrap();
    let o = dronecine(&["shoot", infeasible.to_str().unwrap(), "-q", "--rate", "50"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot be flown"), "{}", stderr(&o));
    // The help's command draws the flight: at the flight's rate, and with
    // `--allow-infeasible`, without which `compile --preview` writes nothing for such a script.
    let help = format!(
        "`dronecine compile {} --rate 50 --allow-infeasible -o OUT.mcap --preview DIR`",
        infeasible.display()
    );
    assert!(stderr(&o).contains(&help), "{}", stderr(&o));
    // An existing --log is refused before the compile (which, for an hour's script, takes a
    // quarter of a second): the refusal is the log's, not the compiler's verdict.
    let taken = dir.join("taken.mcap");
    std::fs::write(&taken, "a recording").unwrap();
    let o = dronecine(&[
        "shoot",
        infeasible.to_str().unwrap(),
        "-q",
        "--rate",
        "50",
        "--log",
        taken.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("already exists"), "{e}");
    assert!(
        !e.contains("cannot be flown"),
        "refused before the compile: {e}"
    );
    assert_eq!(std::fs::read(&taken).unwrap(), b"a recording");
    let (out, previews) = (dir.join("fast.mcap"), dir.join("fast-previews"));
    let o = dronecine(&[
        "compile",
        infeasible.to_str().unwrap(),
        "--rate",
        "50",
        "--allow-infeasible",
        "-o",
        out.to_str().unwrap(),
        "--preview",
        previews.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(previews.join("top.png").exists() && out.exists());

    let o = dronecine(&["shoot", "shots/square.psl", "--rate", "0", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--rate"), "{}", stderr(&o));
    // A negative number is the option's value, checked as such (not an unknown flag `-5`
    // with clap's advice to write `-- -5`, which would make it the script's name).
    let o = dronecine(&["shoot", "shots/square.psl", "--rate", "-5", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("--rate -5 is outside 10–1000 Hz"),
        "{}",
        stderr(&o)
    );

    let o = dronecine(&[
        "shoot",
        "shots/square.psl",
        "--drone",
        "ardrone://127.0.0.1",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("--drone needs --mocap"),
        "{}",
        stderr(&o)
    );
    // A rig file without the drone it describes: refused, not a silently simulated flight.
    let o = dronecine(&["shoot", "shots/square.psl", "--rig", "rig.toml", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("--rig rig.toml needs --drone and --mocap"),
        "{}",
        stderr(&o)
    );
    assert!(!stdout(&o).contains("flight log"), "{}", stdout(&o));
    // A rig file with three mistakes: all three told, not only the first, each pointing into
    // the file, before any connection is tried.
    let rig = dir.join("rig.toml");
    std::fs::write(
        &rig,
        "up = \"x\"\ndrone = 1\norgin_m = [0, 0, 0]\n[actors]\nA = 1\n",
    )
    .unwrap();
    let o = dronecine(&[
        "shoot",
        "shots/square.psl",
        "--drone",
        "ardrone://127.0.0.1",
        "--mocap",
        "natnet://127.0.0.1",
        "--rig",
        rig.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    for (code, at) in [
        ("rig::bad_value", "rig.toml:1:6"),
        ("rig::unknown_key", "rig.toml:3:1"),
        ("rig::bad_value", "rig.toml:5:5"),
    ] {
        assert!(e.contains(code) && e.contains(at), "{code} at {at}: {e}");
    }
    assert!(e.contains("did you mean `origin_m`?"), "{e}");
    assert!(
        e.contains("the rig file") && e.contains("is not valid"),
        "{e}"
    );
    let o = dronecine(&[
        "shoot",
        "shots/square.psl",
        "--drone",
        "udp://x",
        "--mocap",
        "natnet://127.0.0.1",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--drone"), "{}", stderr(&o));

    let garbage = dir.join("garbage.mcap");
    std::fs::write(&garbage, b"not an mcap file at all").unwrap();
    let o = dronecine(&["replay", garbage.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("garbage.mcap"), "{}", stderr(&o));
}

/// `cmd` with a file size limit on its process: writes past it fail with `EFBIG`, as a full
/// disk's fail with `ENOSPC`.
#[cfg(target_os = "linux")]
fn on_a_disk_of(cmd: &mut Command, limit_bytes: u64) {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec the closure only calls `setrlimit` and `signal`, both
    // async-signal-safe, on the child's own limits and dispositions; it touches no memory
    // shared with the parent. (An ignored SIGXFSZ stays ignored across exec.)
    unsafe {
        cmd.pre_exec(move || {
            let limit = libc::rlimit {
                rlim_cur: limit_bytes as libc::rlim_t,
                rlim_max: limit_bytes as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
}

/// A disk that fills during the flight: the drone is landed, `shoot` prints the flight's
/// report, says why it ended and exits 1, and the log keeps the flight up to the failure,
/// readable by `replay`.
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_lands_the_drone_and_keeps_what_was_written() {
    const LIMIT_BYTES: u64 = 1_000_000;
    let dir = temp_dir("full-disk");
    let log = dir.join("two-actors.mcap");
    let log_s = log.to_str().unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dronecine"));
    cmd.args(["shoot", "shots/two-actors.psl", "--log", log_s, "-q"])
        .current_dir(crate::common::workspace())
        .env("NO_COLOR", "1");
    on_a_disk_of(&mut cmd, LIMIT_BYTES);
    let o = cmd.output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("error: the flight log could not be written")
            && err.contains(log_s)
            && err.contains("the drone was landed")
            && err.contains(&format!("dronecine replay {log_s}")),
        "{err}"
    );
    let out = stdout(&o);
    assert!(
        out.starts_with("The take was ABORTED in shot ")
            && out.contains("\n\nABORTED flight with ardrone2"),
        "the report: {out}"
    );
    // The error names the log and how to read it: the report does not say it again.
    assert!(!out.contains("flight log:"), "{out}");
    assert!(
        err.contains("the flight log cannot be written: landing"),
        "-q tells failsafes: {err}"
    );
    assert_eq!(std::fs::metadata(&log).unwrap().len(), LIMIT_BYTES);

    // What was written is a flight: replay reads it, says it ends early, and reproduces
    // every command it holds.
    let o = dronecine(&["replay", log_s, "--report", "json"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("ends early"), "{err}");
    let r = report(&o);
    assert_eq!(r["damage"][0]["cut"], true, "{r}");
    assert_eq!(r["mismatches"], 0, "{r}");
    assert!(r["ticks"].as_u64().unwrap() > 100, "{r}");
    assert_eq!(r["report"]["completed"], false, "{r}");
}

/// A disk too full to start the log: `shoot` refuses before take-off and leaves no file, so
/// that the same command runs at once when there is room.
#[cfg(target_os = "linux")]
#[test]
fn a_start_refused_for_a_full_disk_leaves_nothing_in_the_way() {
    let dir = temp_dir("full-at-start");
    let log = dir.join("square.mcap");
    let log_s = log.to_str().unwrap();
    let shoot = || {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_dronecine"));
        cmd.args(["shoot", "shots/square.psl", "--log", log_s, "-q"])
            .current_dir(crate::common::workspace());
        cmd
    };
    let mut cmd = shoot();
    on_a_disk_of(&mut cmd, 256);
    let o = cmd.output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains(log_s), "{}", stderr(&o));
    assert!(!log.exists(), "a partial log is left in the way");
    let o = shoot().output().unwrap();
    assert!(o.status.success(), "the retry: {}", stderr(&o));
    assert!(log.exists());
}

/// What the director finds against the live actors during a flight is told as it arises, as
/// events in the log (and on the terminal): each repositioning flight, and an error such as a
/// framing that takes the camera too close to an actor, so that a flight that says
/// "completed" does not hide it. On seed 9, `scene.psl`'s shot 2 (a framing that follows
/// Alice as she stops) takes the camera 0.49 m from Bob at a moment, where the drone keeps
/// 0.50 m: told once, counted in the report, and counted again by the replay. The monitor's
/// checks of what the framing demands, and of how far the reference is from it, are not told
/// on set: against live actors the framing's motion is their noise differentiated, and would
/// give an error on every shot that moves. The default seed has no director error.
#[test]
fn shoot_tells_what_the_director_finds_on_set_and_flies_on() {
    let dir = temp_dir("director-events");
    let log = dir.join("scene.mcap");
    let log_s = log.to_str().unwrap();
    let o = dronecine(&[
        "shoot",
        "shots/scene.psl",
        "--seed",
        "9",
        "--log",
        log_s,
        "--report",
        "json",
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("flown as written"),
        "-q: {}",
        stderr(&o)
    );
    let r = report(&o);
    // The flight's events, read back by the log reader.
    let events = dronecine_mcap::log::FlightLog::open(&log).unwrap().events;
    assert!(
        events
            .iter()
            .any(|e| e.kind == "compile::reposition" && e.message.starts_with("shot ")),
        "{events:#?}"
    );
    let errors: Vec<_> = events.iter().filter(|e| e.is_director_error()).collect();
    assert_eq!(errors.len(), 1, "told once: {events:#?}");
    assert!(
        !events.iter().any(|e| e.kind == "compile::infeasible"),
        "{events:#?}"
    );
    assert!(
        errors[0].kind == "compile::too_close"
            && errors[0]
                .message
                .starts_with("shot 2: this framing puts the camera 0.49 m from Bob"),
        "{:?}",
        errors[0]
    );
    // With the script's line of the shot and the fix, as `compile` gives them.
    let line = std::fs::read_to_string("shots/scene.psl")
        .unwrap()
        .lines()
        .position(|l| l.starts_with("cut to FS on Alice 34right"))
        .unwrap()
        + 1;
    assert_eq!(errors[0].line, Some(line as u32), "{:?}", errors[0]);
    assert!(
        (errors[0].help.as_deref()).is_some_and(|h| h.starts_with("use a wider size")),
        "{:?}",
        errors[0]
    );
    // The report counts it (a flight that says "completed" with good figures came too close
    // to an actor for a moment), and the replay counts it again from the log.
    assert_eq!(r["completed"], true, "{r}");
    assert_eq!(r["director_errors"], 1, "{r}");
    let o = dronecine(&["replay", log_s, "--report", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(report(&o)["report"]["director_errors"], 1);
    let o = dronecine(&["replay", log_s]);
    assert!(
        stdout(&o).contains("1 director error against the live actors"),
        "{}",
        stdout(&o)
    );
    // And tells it again, from the log, as `shoot` did: the line quoted, the fix.
    let told = format!("  --> scene.psl:{line}\n  {line:>4} │ cut to FS on Alice 34right");
    assert!(
        stderr(&o).contains("error at ")
            && stderr(&o).contains(&told)
            && stderr(&o).contains("  help: use a wider size"),
        "{}",
        stderr(&o)
    );

    // The default seed: the reverse shot is framed throughout, and measured.
    let log = dir.join("scene-default.mcap");
    let o = dronecine(&[
        "shoot",
        "shots/scene.psl",
        "--log",
        log.to_str().unwrap(),
        "--report",
        "json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Before take-off, one line for the warnings `compile` tells in full, so that none is
    // flown without a word: each code `compile` prints, counted, but the repositioning
    // flights, which are the plan working as written.
    let compiled = dronecine(&[
        "compile",
        "shots/scene.psl",
        "-o",
        dir.join("scene-compiled.mcap").to_str().unwrap(),
    ]);
    assert!(compiled.status.success(), "{}", stderr(&compiled));
    let mut expected: Vec<(String, usize)> = Vec::new();
    for code in stderr(&compiled)
        .lines()
        .filter(|l| l.starts_with("compile::") || l.starts_with("psl::") || l.starts_with("film::"))
    {
        if code == "compile::reposition" {
            continue;
        }
        match expected.iter_mut().find(|(c, _)| c == code) {
            Some((_, n)) => *n += 1,
            None => expected.push((code.to_string(), 1)),
        }
    }
    let total: usize = expected.iter().map(|(_, n)| n).sum();
    assert!(total >= 2, "{}", stderr(&compiled));
    let line = stderr(&o)
        .lines()
        .find(|l| l.contains("is flown as written with"))
        .map(str::to_string)
        .unwrap_or_else(|| panic!("{}", stderr(&o)));
    assert!(line.contains(&format!("with {total} warnings (")), "{line}");
    for (code, n) in &expected {
        let named = if *n > 1 {
            format!("{code} ×{n}")
        } else {
            code.clone()
        };
        assert!(line.contains(&named), "{named} in {line}");
    }
    // The help's command works, as written, and tells them.
    let help = stderr(&o)
        .lines()
        .find_map(|l| l.strip_prefix("  help: `dronecine "))
        .and_then(|l| l.split('`').next())
        .map(str::to_string)
        .unwrap_or_else(|| panic!("{}", stderr(&o)));
    assert_eq!(help, "compile shots/scene.psl -o OUT.mcap");
    let out = dir.join("OUT.mcap");
    let args: Vec<&str> = help
        .split(' ')
        .map(|w| {
            if w == "OUT.mcap" {
                out.to_str().unwrap()
            } else {
                w
            }
        })
        .collect();
    let told = dronecine(&args);
    assert!(told.status.success(), "{}", stderr(&told));
    assert_eq!(stderr(&told), stderr(&compiled));
    let r = report(&o);
    assert_eq!(r["director_errors"], 0, "{r}");
    let shot5 = &r["shots"][4];
    assert!(
        shot5["rms_framing_error"].as_f64().is_some_and(|e| e < 0.5),
        "{shot5}"
    );
}

/// `--sim-off` switches simulator effects off by name, and the log's header records which
/// were off, so that a seeded flight can be flown again from its log; `replay` says how it
/// was flown. Every effect off is `--ideal`, bit for bit. A name that is no effect is
/// refused with the names that are (nothing flown, no log), and the simulator's options are
/// refused with a real drone rather than ignored.
#[test]
fn sim_off_switches_effects_by_name_and_the_log_says_which() {
    let dir = temp_dir("sim-off");
    let fly = |name: &str, extra: &[&str]| {
        let log = dir.join(name);
        let mut args = vec![
            "shoot",
            "shots/square.psl",
            "--log",
            log.to_str().unwrap(),
            "--report",
            "json",
            "-q",
        ];
        args.extend_from_slice(extra);
        let o = dronecine(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        (log, report(&o))
    };
    let header = |log: &std::path::Path| dronecine_mcap::log::FlightLog::open(log).unwrap().header;
    let (default_log, default) = fly("default.mcap", &[]);
    assert_eq!(header(&default_log).sim_effects_off, Some(vec![]));
    let (log, no_wind) = fly("calm.mcap", &["--sim-off", "wind,battery", "--seed", "3"]);
    let h = header(&log);
    assert_eq!(
        (h.seed, h.sim_effects_off),
        (
            Some(3),
            Some(vec!["wind".to_string(), "battery".to_string()])
        )
    );
    assert_ne!(
        default["rms_position_error_m"],
        no_wind["rms_position_error_m"]
    );
    let o = dronecine(&["replay", log.to_str().unwrap()]);
    assert!(
        stderr(&o).contains("flown on the simulator, seed 3, wind, battery off"),
        "{}",
        stderr(&o)
    );

    // Every effect by name is --ideal.
    let all = [
        "attitude-lag,tilt-saturation,drag,asymmetric-vz,yaw-lag,latency,radio-loss,",
        "mocap-noise,mocap-dropouts,wind,actor-deviation,battery",
    ]
    .concat();
    let (_, by_name) = fly("all-off.mcap", &["--sim-off", &all]);
    let (_, ideal) = fly("ideal.mcap", &["--ideal"]);
    assert_eq!(by_name, ideal);

    let refused = dir.join("refused.mcap");
    let o = dronecine(&[
        "shoot",
        "shots/square.psl",
        "--sim-off",
        "wnd",
        "--log",
        refused.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("no simulator effect `wnd` (did you mean `wind`?)")
            && stderr(&o).contains("actor-deviation, battery"),
        "{}",
        stderr(&o)
    );
    assert!(!refused.exists());
    let o = dronecine(&[
        "shoot",
        "shots/square.psl",
        "--seed",
        "3",
        "--sim-off",
        "wind",
        "--drone",
        "ardrone://127.0.0.1:1",
        "--mocap",
        "natnet://127.0.0.1:1",
        "--log",
        refused.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--seed, --sim-off are simulator options"),
        "{}",
        stderr(&o)
    );
    assert!(!refused.exists());
}
