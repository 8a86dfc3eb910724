//! A drone with a camera gimbal (`tests/data/ardrone2-gimbal.toml`: the AR.Drone's model with
//! a pitch gimbal, -90° to +30° at 90°/s): the compiler frames with the camera's pitch free
//! (a high angle, of one actor or of two of different heights), the
//! reference's pitch turns no faster than the gimbal, the simulator's gimbal follows the
//! flight's commands, and the flight measures the framing with the pitch the gimbal reports
//! and logs it on `/gimbal`.

use std::path::{Path, PathBuf};

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::compile::{compile, Options};
use dronecine_compiler::framing;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::{Script, ShotContent};
use dronecine_mcap::log::plots::decode_gimbal;
use dronecine_mcap::record::GimbalRecord;
use dronecine_profile::{Gimbal, Profile};

use crate::common::workspace;

const HIGH_ANGLE: &str = "stage 8m x 6m x 3m\n\
    actor A height 1.80m at (0, 0) facing 0deg\n\
    at 2s A walks to (1, 1) over 5s\n\
    high angle MS on A for 10s\n";

fn profile_path() -> PathBuf {
    workspace().join("tests/data/ardrone2-gimbal.toml")
}

fn gimbal_profile() -> Profile {
    let (profile, _, warnings) = Profile::load(&profile_path()).expect("the test profile loads");
    assert!(warnings.is_empty(), "{warnings:?}");
    profile
}

/// `text` flown by the gimbal profile: its `drone` line replaced (or one added after the
/// stage).
fn with_gimbal(text: &str) -> String {
    let line = format!("drone \"{}\"", profile_path().display());
    let mut out: Vec<String> = Vec::new();
    let mut placed = false;
    for l in text.lines() {
        if l.starts_with("drone ") {
            out.push(line.clone());
            placed = true;
        } else {
            out.push(l.to_string());
            if l.starts_with("stage ") && !text.contains("\ndrone ") {
                out.push(line.clone());
                placed = true;
            }
        }
    }
    assert!(placed, "no place for the drone line");
    out.join("\n") + "\n"
}

fn script_of(src: &str) -> Script {
    let checked = dronecine_grammar::check(src, &Default::default());
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.unwrap()
}

fn two_heights() -> String {
    std::fs::read_to_string(workspace().join("shots/two-heights.psl")).unwrap()
}

/// The compiled reference's samples and the actors at each.
fn run(script: &Script, profile: &Profile) -> (Vec<Sample>, Vec<Vec<ActorPose>>) {
    let (mut samples, mut actors) = (Vec::new(), Vec::new());
    compile::<()>(script, profile, &Options::default(), |s, a| {
        samples.push(*s);
        actors.push(a.to_vec());
        Ok(())
    })
    .unwrap();
    (samples, actors)
}

/// Each framed actor's screen error (the larger of x and y) in the compiled reference, during
/// its holds from 1 s into the shot on: the camera at the sample's position, heading and
/// pitch, against where the script puts the actor.
fn compiled_framing_errors(script: &Script, profile: &Profile) -> Vec<(usize, f64)> {
    let lens = Lens::new(profile.camera.fov_x_rad, profile.camera.aspect);
    let names: Vec<String> = script
        .scene
        .as_ref()
        .unwrap()
        .actors
        .iter()
        .map(|a| a.name.clone())
        .collect();
    let gimbal = &profile.camera.gimbal;
    let (samples, actors) = run(script, profile);
    let mut out = Vec::new();
    for (s, poses) in samples.iter().zip(&actors) {
        let ShotContent::Composition(comp) = &script.timeline[s.shot].content else {
            continue;
        };
        if script.moves_camera(s.shot) || s.t_s < script.timeline[s.shot].start_s + 1.0 {
            continue;
        }
        let v = framing::solve(comp, &names, poses, &lens, gimbal).unwrap();
        let pose = CameraPose {
            position_m: Vec3::from(s.position_m),
            heading_rad: s.heading_rad,
            pitch_rad: s.camera_pitch_rad,
        };
        for t in framing::screen_targets(&v, poses, &lens, gimbal, &pose.position_m) {
            let got = pose.project(&lens, &t.point_m).unwrap();
            let e = (got[0] - t.screen[0])
                .abs()
                .max((got[1] - t.screen[1]).abs());
            out.push((t.actor, e));
        }
    }
    out
}

fn worst(errors: &[(usize, f64)]) -> f64 {
    errors.iter().map(|e| e.1).fold(0.0, f64::max)
}

/// The reference's pitch turns no faster than the gimbal, and stays in its range.
fn assert_pitch_within_the_gimbal(samples: &[Sample], gimbal: &Gimbal) {
    let Gimbal::Pitch {
        min_rad,
        max_rad,
        rate_radps,
    } = *gimbal
    else {
        panic!("a gimbal profile");
    };
    for w in samples.windows(2) {
        let dt = w[1].t_s - w[0].t_s;
        let turn = (w[1].camera_pitch_rad - w[0].camera_pitch_rad).abs();
        assert!(
            turn <= rate_radps * dt + 1e-12,
            "at {} s the pitch turns {turn} rad in {dt} s",
            w[1].t_s
        );
        let p = w[1].camera_pitch_rad;
        assert!(
            (min_rad..=max_rad).contains(&p),
            "pitch {p} at {} s",
            w[1].t_s
        );
    }
}

#[test]
fn the_test_profile_is_the_ardrone_with_a_gimbal() {
    let p = gimbal_profile();
    let ardrone = Profile::builtin("ardrone2").unwrap();
    assert_eq!(p.model, ardrone.model);
    assert_eq!(p.limits, ardrone.limits);
    assert_eq!(p.servo, ardrone.servo);
    assert_eq!(
        p.camera.gimbal,
        Gimbal::Pitch {
            min_rad: (-90f64).to_radians(),
            max_rad: 30f64.to_radians(),
            rate_radps: 90f64.to_radians(),
        }
    );
}

/// A high angle on one actor: the camera rises to the angle and the gimbal tilts it down, and
/// the compiled reference frames the actor where the script says.
#[test]
fn a_high_angle_is_framed_with_the_gimbal() {
    let profile = gimbal_profile();
    let script = script_of(&with_gimbal(HIGH_ANGLE));
    let errors = compiled_framing_errors(&script, &profile);
    assert!(errors.len() > 500, "{}", errors.len());
    let w = worst(&errors);
    assert!(w < 0.01, "worst screen error {w}");
    let (samples, actors) = run(&script, &profile);
    assert_pitch_within_the_gimbal(&samples, &profile.camera.gimbal);
    // Looking down at the actor from above the framed band's centre (an MS: 0.60 to 1.05 of
    // the actor's height).
    let s = &samples[samples.len() / 2];
    assert!(s.camera_pitch_rad < -0.2, "pitch {}", s.camera_pitch_rad);
    let a = &actors[samples.len() / 2][0];
    assert!(
        s.position_m[2] > 0.825 * a.height_m + 0.2,
        "{:?}",
        s.position_m
    );
}

/// Two actors of different heights (`shots/two-heights.psl`): the two-shot frames them as
/// they stand, both on their screen points with a level camera as with the gimbal; the high
/// angle that follows is rendered by the gimbal (the camera pitched down in its hold), where
/// the level camera can only say it is not (`compile::angle_not_rendered`).
#[test]
fn two_heights_are_both_framed_with_the_gimbal() {
    let text = two_heights();
    let level_profile = Profile::builtin("ardrone2").unwrap();
    let level = compiled_framing_errors(&script_of(&text), &level_profile);
    let level_worst = worst(&level);
    assert!(level_worst < 0.02, "the level camera: {level_worst}");
    let c = compile::<()>(
        &script_of(&text),
        &level_profile,
        &Options::default(),
        |_, _| Ok(()),
    )
    .unwrap();
    assert!(
        c.diagnostics
            .iter()
            .any(|d| d.code == dronecine_compiler::CompileCode::AngleNotRendered),
        "{:?}",
        c.diagnostics
    );

    let profile = gimbal_profile();
    let script = script_of(&with_gimbal(&text));
    let errors = compiled_framing_errors(&script, &profile);
    assert!(errors.len() > 1000, "{}", errors.len());
    for actor in [0, 1] {
        let w = worst(
            &errors
                .iter()
                .copied()
                .filter(|e| e.0 == actor)
                .collect::<Vec<_>>(),
        );
        // The reference lags its moving target a little, as for any framing.
        assert!(w < 0.02, "actor {actor}: worst screen error {w}");
    }
    let (samples, _) = run(&script, &profile);
    assert_pitch_within_the_gimbal(&samples, &profile.camera.gimbal);
    // The high angle's hold (the last shot): the camera pitched down.
    let last = samples.last().unwrap().shot;
    let held: Vec<_> = samples.iter().filter(|s| s.shot == last).collect();
    assert!(
        held.iter().all(|s| s.camera_pitch_rad < -0.1),
        "{:?}",
        held.last()
    );
}

/// `dronecine shoot` of a script on the simulator, seeded: the report and the log's path.
fn shoot(dir: &Path, name: &str, text: &str, seed: u32) -> (serde_json::Value, PathBuf) {
    let script = dir.join(format!("{name}.psl"));
    std::fs::write(&script, text).unwrap();
    let log = dir.join(format!("{name}-{seed}.mcap"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(["shoot", script.to_str().unwrap(), "-q", "--report", "json"])
        .args(["--seed", &seed.to_string(), "--log", log.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (serde_json::from_slice(&out.stdout).unwrap(), log)
}

fn framing_error(report: &serde_json::Value) -> f64 {
    assert_eq!(report["completed"], true, "{report}");
    report["rms_framing_error"].as_f64().unwrap()
}

/// The `/gimbal` messages of a flight log, and how many `/servo/tick` messages it has.
fn gimbal_topic(log: &Path) -> (Vec<(f64, GimbalRecord)>, usize) {
    let bytes = std::fs::read(log).unwrap();
    let (mut gimbal, mut ticks) = (Vec::new(), 0);
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        match m.channel.topic.as_str() {
            "/gimbal" => {
                let schema = m.channel.schema.as_ref().unwrap();
                assert_eq!(schema.name, "dronecine/msg/Gimbal");
                assert_eq!(m.channel.message_encoding, "cdr");
                gimbal.push(decode_gimbal(&m.data).unwrap());
            }
            "/servo/tick" => ticks += 1,
            _ => {}
        }
    }
    (gimbal, ticks)
}

fn replays_exactly(log: &Path) {
    let out = crate::common::dronecine(&["replay", log.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}{}",
        crate::common::stdout(&out),
        crate::common::stderr(&out)
    );
}

/// `shots/two-heights.psl` flown with the gimbal profile frames both actors within 0.02 of
/// their screen points (RMS, seeds 1 and 7), and flown as shipped (a level camera) too, the
/// high angle then flown level. The gimbal's log holds the pitch asked and the pitch reported at
/// every tick, the reported one following the asked one at most at the gimbal's rate; and the
/// flight replays exactly.
#[test]
fn two_heights_flies_within_two_hundredths_with_the_gimbal() {
    let dir = crate::common::temp_dir("gimbal-two-heights");
    let text = two_heights();
    let rate_radps = 90f64.to_radians();
    for seed in [1, 7] {
        let (report, log) = shoot(dir.path(), "gimballed", &with_gimbal(&text), seed);
        let e = framing_error(&report);
        eprintln!("two-heights with the gimbal, seed {seed}: RMS framing error {e:.4}");
        assert!(e <= 0.02, "seed {seed}: {e}");
        let (gimbal, ticks) = gimbal_topic(&log);
        assert_eq!(gimbal.len(), ticks);
        assert!(gimbal.iter().all(|(_, g)| g.reported_rad.is_some()));
        for w in gimbal.windows(2) {
            let ((t0, g0), (t1, g1)) = (w[0], w[1]);
            let turn = (g1.reported_rad.unwrap() - g0.reported_rad.unwrap()).abs();
            assert!(
                turn <= rate_radps * (t1 - t0) + 1e-9,
                "at {t1} s: {turn} rad"
            );
        }
        // The gimbal pitches the camera during the shots (reported, not only asked).
        assert!(gimbal
            .iter()
            .any(|(_, g)| g.reported_rad.unwrap().abs() > 0.02));
        replays_exactly(&log);
    }
    let (report, log) = shoot(dir.path(), "level", &text, 1);
    let e = framing_error(&report);
    eprintln!("two-heights with a level camera, seed 1: RMS framing error {e:.4}");
    assert!(e <= 0.02, "{e}");
    assert_eq!(gimbal_topic(&log).0.len(), 0, "no gimbal, no /gimbal");
}

/// A high angle on one actor, flown with the gimbal profile: within 0.02 of the script's
/// framing (RMS, seed 1).
#[test]
fn a_high_angle_flies_within_two_hundredths_with_the_gimbal() {
    let dir = crate::common::temp_dir("gimbal-high-angle");
    let (report, log) = shoot(dir.path(), "high", &with_gimbal(HIGH_ANGLE), 1);
    let e = framing_error(&report);
    eprintln!("high angle with the gimbal, seed 1: RMS framing error {e:.4}");
    assert!(e <= 0.02, "{e}");
    replays_exactly(&log);
}
