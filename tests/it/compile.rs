//! The compiler on the shipped scripts and on purpose-made ones: compiled paths (snapshots),
//! framing where PSL says on screen, mirror symmetry, consistent derivatives, one evaluator
//! for batch and online, and feasibility errors whose fix works.

use dronecine_compiler::blocking::Blocking;
use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::compile::{compile, Compiled, Options, FRAMING_TOLERANCE};
use dronecine_compiler::director::Director;
use dronecine_compiler::framing;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_compiler::CompileCode;
use dronecine_grammar::script::{Scene, Script, ShotContent};
use dronecine_profile::Profile;
use serde::Serialize;

fn ardrone() -> Profile {
    Profile::builtin("ardrone2").unwrap()
}

fn run(script: &Script) -> (Compiled, Vec<Sample>, Vec<Vec<ActorPose>>) {
    run_with(script, &ardrone())
}

/// [`run`] with another drone.
fn run_with(script: &Script, profile: &Profile) -> (Compiled, Vec<Sample>, Vec<Vec<ActorPose>>) {
    let mut samples = Vec::new();
    let mut actors = Vec::new();
    let c = compile::<()>(script, profile, &Options::default(), |s, a| {
        samples.push(*s);
        actors.push(a.to_vec());
        Ok(())
    })
    .unwrap();
    (c, samples, actors)
}

/// The largest step of the reference's position from one sample to the next.
fn largest_step_m(samples: &[Sample]) -> f64 {
    samples
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].position_m, w[1].position_m);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0f64, f64::max)
}

fn script_of(src: &str) -> Script {
    let checked = dronecine_grammar::check(src, &Default::default());
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.unwrap()
}

/// The shipped scenes as the AR.Drone flies them: their coverages expanded for it.
fn shipped() -> Vec<(String, Script)> {
    crate::common::scripts("shots")
        .into_iter()
        .filter_map(|p| {
            let (_, checked) = crate::common::check_path(&p);
            let script = checked.script.unwrap();
            script.scene.is_some().then(|| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                let (flown, _) = dronecine_compiler::coverage::expand(&script, &ardrone());
                (name, flown)
            })
        })
        .collect()
}

/// The diagnostics of one kind.
fn with_code(
    c: &Compiled,
    code: impl Into<dronecine_diag::Code>,
) -> Vec<&dronecine_diag::Diagnostic> {
    let code = code.into();
    c.diagnostics.iter().filter(|d| d.code == code).collect()
}

fn lens_of(script: &Script) -> Lens {
    let p = ardrone();
    match script.scene.as_ref().unwrap().lens {
        Some(l) => Lens::new(l.fov_x_rad, l.aspect),
        None => Lens::new(p.camera.fov_x_rad, p.camera.aspect),
    }
}

#[derive(Serialize)]
struct Row {
    t_s: f64,
    shot: usize,
    p: [f64; 3],
    heading: f64,
}

fn r3(x: f64) -> f64 {
    let r = (x * 1000.0).round() / 1000.0;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

#[test]
fn every_shipped_script_compiles_without_errors_and_its_path_is_stable() {
    for (name, script) in shipped() {
        let (c, samples, _) = run(&script);
        let errors: Vec<_> = c.diagnostics.iter().filter(|d| d.is_error()).collect();
        assert!(errors.is_empty(), "{name}: {errors:#?}");
        // Down-sampled to 2 Hz, rounded to mm and mrad.
        let rows: Vec<Row> = samples
            .iter()
            .step_by(50)
            .map(|s| Row {
                t_s: r3(s.t_s),
                shot: s.shot,
                p: s.position_m.map(r3),
                heading: r3(s.heading_rad),
            })
            .collect();
        let timings: Vec<_> = c
            .timings
            .iter()
            .map(|t| {
                (
                    t.index,
                    r3(t.start_s),
                    r3(t.end_s),
                    t.reposition.map(|(a, b)| (r3(a), r3(b))),
                )
            })
            .collect();
        insta::with_settings!({snapshot_suffix => name.clone(), prepend_module_to_snapshot => false}, {
            insta::assert_yaml_snapshot!("compiled", (timings, rows));
        });
    }
}

#[test]
fn velocity_and_acceleration_are_the_derivatives_of_position() {
    for (name, script) in shipped() {
        let (_, s, _) = run(&script);
        for k in 1..s.len() - 1 {
            let dt = s[k + 1].t_s - s[k - 1].t_s;
            for i in 0..3 {
                let v_num = (s[k + 1].position_m[i] - s[k - 1].position_m[i]) / dt;
                let a_num = (s[k + 1].velocity_mps[i] - s[k - 1].velocity_mps[i]) / dt;
                assert!(
                    (v_num - s[k].velocity_mps[i]).abs() < 1e-3,
                    "{name} t={} axis {i}: v {} vs {v_num}",
                    s[k].t_s,
                    s[k].velocity_mps[i]
                );
                assert!(
                    (a_num - s[k].acceleration_mps2[i]).abs() < 0.05,
                    "{name} t={} axis {i}: a {} vs {a_num}",
                    s[k].t_s,
                    s[k].acceleration_mps2[i]
                );
            }
        }
    }
}

/// Screen errors of every framed actor, during holds, from 0.5 s into the shot.
fn hold_framing_errors(script: &Script) -> Vec<(String, f64, f64, f64)> {
    let profile = ardrone();
    let lens = lens_of(script);
    let scene = script.scene.as_ref().unwrap();
    let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
    let (c, samples, actors) = run(script);
    let mut out = Vec::new();
    for (s, poses) in samples.iter().zip(&actors) {
        let shot = &script.timeline[s.shot];
        let Some(t) = c.timings.iter().find(|t| t.index == s.shot) else {
            continue;
        };
        let ShotContent::Composition(comp) = &shot.content else {
            continue;
        };
        let hold = !script.moves_camera(s.shot);
        if !hold || s.t_s < t.start_s + 0.5 || s.t_s > t.end_s {
            continue;
        }
        let v = framing::solve(comp, &names, poses, &lens, &profile.camera.gimbal).unwrap();
        let pose = CameraPose {
            position_m: Vec3::from(s.position_m),
            heading_rad: s.heading_rad,
            pitch_rad: s.camera_pitch_rad,
        };
        for target in
            framing::screen_targets(&v, poses, &lens, &profile.camera.gimbal, &pose.position_m)
        {
            let got = pose.project(&lens, &target.point_m).unwrap();
            out.push((
                names[target.actor].clone(),
                s.t_s,
                (got[0] - target.screen[0]).abs(),
                (got[1] - target.screen[1]).abs(),
            ));
        }
    }
    out
}

#[test]
fn holds_put_the_actors_where_psl_says_on_screen() {
    // One actor, moving and turning; the shot size's band fills the frame.
    let script = script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (-1, 0) facing 0deg\n\
         at 1s A walks to (0.5, 0.5) over 6s\nat 8s A turns to 40deg over 4s\n\
         MS on A 34left screen left for 14s\n",
    );
    let errs = hold_framing_errors(&script);
    assert!(errs.len() > 1000);
    let worst = errs.iter().map(|e| e.2.max(e.3)).fold(0.0, f64::max);
    assert!(worst < 0.02, "worst screen error {worst}");

    // Two moving actors (the shipped scene). Without roll only the aimed actor lands
    // exactly; the other one lands exactly only when both aim points are at the camera's
    // height and the camera sits on its toric position. Per sample, the aimed actor is held
    // to 0.02; the other actor is held to 0.02 RMS in x (1.80 m and 1.65 m actors; the camera
    // lags its moving target a little). In y the level AR.Drone camera (no gimbal) frames the
    // aimed actor's band by altitude alone, so the other actor, at another distance and
    // height, sits about 0.09 off: held to 0.10 RMS.
    let (_, checked) =
        crate::common::check_path(&crate::common::workspace().join("shots/two-actors.psl"));
    let errs = hold_framing_errors(&checked.script.unwrap());
    let (mut aimed_worst, mut other_x, mut other_y, mut n) = (0.0f64, 0.0, 0.0, 0.0);
    for pair in errs.chunks(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let (aimed, other) = if a.2.max(a.3) <= b.2.max(b.3) {
            (a, b)
        } else {
            (b, a)
        };
        aimed_worst = aimed_worst.max(aimed.2.max(aimed.3));
        other_x += other.2 * other.2;
        other_y += other.3 * other.3;
        n += 1.0;
    }
    let (rms_x, rms_y) = ((other_x / n).sqrt(), (other_y / n).sqrt());
    assert!(
        aimed_worst < 0.02,
        "aimed actor: worst screen error {aimed_worst}"
    );
    assert!(rms_x < 0.02, "other actor: RMS screen x error {rms_x}");
    assert!(rms_y < 0.10, "other actor: RMS screen y error {rms_y}");
    eprintln!("two actors: aimed worst {aimed_worst:.4}, other RMS x {rms_x:.4} y {rms_y:.4}");
}

#[test]
fn mirror_profiles_give_mirror_paths() {
    let make = |a: &str, b: &str| {
        script_of(&format!(
            "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
             MS on A {a} for 3s\nthen dolly to MLS on A {b} over 6s\ncut to FS on A {a} for 3s\n"
        ))
    };
    for (l, r) in [
        ("34left", "34right"),
        ("left", "right"),
        ("34backleft", "34backright"),
    ] {
        for (a, b) in [(l, "front"), ("front", l)] {
            let mirror = |p: &'static str| -> &'static str {
                if p == l {
                    r
                } else {
                    p
                }
            };
            let (_, left, _) = run(&make(a, b));
            let (_, right, _) = run(&make(mirror(a), mirror(b)));
            assert_eq!(left.len(), right.len());
            for (p, q) in left.iter().zip(&right) {
                let (pm, qm) = (p.position_m, q.position_m);
                assert!(
                    (pm[0] - qm[0]).abs() < 1e-6
                        && (pm[1] + qm[1]).abs() < 1e-6
                        && (pm[2] - qm[2]).abs() < 1e-6,
                    "{a}→{b} at {}: {pm:?} vs {qm:?}",
                    p.t_s
                );
                let dh = dronecine_math::wrap_angle_rad(p.heading_rad + q.heading_rad);
                assert!(dh.abs() < 1e-6, "{a}→{b} heading at {}", p.t_s);
            }
        }
    }
}

#[test]
fn batch_and_online_give_the_same_samples() {
    for (name, script) in shipped() {
        let (_, batch, _) = run(&script);
        // Online: a director stepped by hand with poses from elsewhere (here: the blocking).
        let scene = script.scene.as_ref().unwrap();
        let blocking = Blocking::new(scene);
        let mut director = Director::new(&script, scene, &ardrone());
        let mut online = Vec::new();
        let mut k = 0u64;
        loop {
            let t = k as f64 / 100.0;
            let s = director.step(t, &blocking.poses(t));
            if director.finished() {
                break;
            }
            online.push(s);
            k += 1;
        }
        assert_eq!(batch.len(), online.len(), "{name}");
        for (a, b) in batch.iter().zip(&online) {
            assert_eq!(
                serde_json::to_string(a).unwrap(),
                serde_json::to_string(b).unwrap(),
                "{name}"
            );
        }
    }
}

/// The camera does not depend on the rate it is sampled at: the steering integrates a long
/// tick in 10 ms sub-steps, and compares its target with where the camera is at the step's
/// end, not its start (one step's travel, ten times longer at 100 Hz than at 1000 Hz). At
/// 10, 30 and 1000 Hz every shipped script gets the verdict it gets at 100 Hz, its path
/// within 1.5 cm of the 100 Hz one.
#[test]
fn the_path_and_the_verdict_do_not_depend_on_the_sample_rate() {
    let compile_at = |script: &Script, rate_hz: f64| {
        let mut samples = Vec::new();
        let c = compile::<()>(script, &ardrone(), &Options { rate_hz }, |s, _| {
            samples.push(*s);
            Ok(())
        })
        .unwrap();
        let codes: Vec<_> = c
            .diagnostics
            .iter()
            .map(|d| (d.code, d.is_error()))
            .collect();
        (codes, samples)
    };
    for (name, script) in shipped() {
        let (codes_100, fine) = compile_at(&script, 100.0);
        for rate_hz in [10.0, 30.0, 1000.0] {
            let (codes, coarse) = compile_at(&script, rate_hz);
            assert_eq!(
                codes, codes_100,
                "{name} at {rate_hz} Hz: not the same verdict"
            );
            let mut compared = 0;
            for s in &coarse {
                // The 100 Hz sample at the same instant, where there is one.
                let k = (s.t_s * 100.0).round();
                if (k / 100.0 - s.t_s).abs() > 1e-9 {
                    continue;
                }
                let Some(f) = fine.get(k as usize) else {
                    continue;
                };
                assert!((f.t_s - s.t_s).abs() < 1e-9, "{name}");
                compared += 1;
                let d = (Vec3::from(f.position_m) - Vec3::from(s.position_m)).norm();
                assert!(
                    d < 0.015,
                    "{name} at {rate_hz} Hz: {d:.4} m from the 100 Hz path at {:.2} s",
                    s.t_s
                );
            }
            assert!(
                compared * 4 > coarse.len().min(fine.len()),
                "{name} at {rate_hz} Hz: {compared} compared"
            );
        }
    }
}

#[test]
fn a_path_too_fast_is_an_error_whose_fix_works() {
    let src = |secs: f64| {
        format!(
            "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
             path square side 4m center (0, 0) altitude 1.5m for {secs}s\n"
        )
    };
    let (c, _, _) = run(&script_of(&src(6.0)));
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == CompileCode::Infeasible)
        .expect("too fast");
    assert!(d.message.contains("m/s"), "{}", d.message);
    let help = d.help.as_deref().unwrap();
    let secs: f64 = help
        .trim_start_matches("make it at least ")
        .trim_end_matches(" s")
        .parse()
        .unwrap_or_else(|_| panic!("help names a duration: {help}"));
    assert!(secs > 6.0);
    let (c, _, _) = run(&script_of(&src(secs)));
    assert!(
        !c.diagnostics
            .iter()
            .any(|d| d.code == CompileCode::Infeasible),
        "the suggested {secs} s still fails: {:?}",
        c.diagnostics
    );
}

#[test]
fn cuts_insert_repositioning_flights_and_pinned_cuts_that_do_not_fit_are_errors() {
    let base = "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
                MS on A front for 4s\n";
    let (c, samples, _) = run(&script_of(&format!("{base}cut to MS on A back for 4s\n")));
    let t = &c.timings[1];
    let (a, b) = t.reposition.expect("a repositioning flight");
    assert!((a - 4.0).abs() < 1e-9 && b > a + 1.0 && (t.start_s - b).abs() < 1e-9);
    assert!(c
        .diagnostics
        .iter()
        .any(|d| d.code == CompileCode::Reposition && !d.is_error()));
    // The flight stays out of the actor's safety distance (it goes round).
    for s in &samples {
        let d = s.position_m[0].hypot(s.position_m[1]);
        assert!(
            d > ardrone().safety.actor_distance_m,
            "{} m at {}",
            d,
            s.t_s
        );
    }
    let (c, _, _) = run(&script_of(&format!(
        "{base}at 4.5s cut to MS on A back for 4s\n"
    )));
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == CompileCode::CutTooShort)
        .expect("error");
    assert!(
        d.is_error() && d.help.as_deref().unwrap().contains("at "),
        "{d:?}"
    );
    let (c, _, _) = run(&script_of(&format!(
        "{base}at 12s cut to MS on A back for 4s\n"
    )));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    assert!(
        (c.timings[1].start_s - 12.0).abs() < 1e-9,
        "a pinned shot starts on time"
    );
}

/// An over-the-shoulder held while the foreground actor walks toward the other: its two
/// possible cameras come to miss the profile equally, and a solve that flipped from one to
/// the other would take the camera target across the stage in one tick, to B's side. The
/// framing keeps its camera: no error, and the reference moves as smoothly as the actors.
#[test]
fn an_over_the_shoulder_does_not_jump_between_its_two_cameras() {
    let src = "stage 8m x 8m x 3m\nlens 84deg 16:9\ndrone ardrone2\n\
               actor A height 1.82m at (-1.04, 0.21) facing 19deg\n\
               actor B height 1.82m at (0.5, -0.3) facing -167deg\n\
               at 0s B walks to (-0.24, -0.45) over 3s\n\
               high angle MLS on B 34left MLS on A 34backright for 2s\n";
    let (c, samples, _) = run(&script_of(src));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let step_m = largest_step_m(&samples);
    assert!(step_m < 0.005, "{step_m} m in one sample");
}

/// A move from one actor's framing to another's, while the first turns round: the shorter
/// way round the actors changes side, and a move that took it would jump metres in one tick.
/// The move keeps the way round it went (`framing::BlendWay`): as with A standing still, a
/// move too fast for its length, whose help retimes it (longer with the turn, whose swing
/// adds acceleration: 43.4 s against 35.0 s).
#[test]
fn a_move_keeps_its_way_round_the_actors_when_one_turns_round() {
    let src = "stage 14m x 10m x 3m\ndrone ardrone2\n\
               actor A height 1.98m at (-2.71, 0.47) facing -118deg\n\
               actor B height 2.01m at (1.39, 0.16) facing -7deg\n\
               at 6s A turns to -30deg over 1s\n\
               at 12s A turns to 149deg over 1s\n\
               low angle MS on A 34right for 3s\n\
               then follow B to LS on B over 12s\n";
    let still = src.replace("at 12s A turns to 149deg over 1s\n", "");
    for (src, help) in [
        (src, "make it at least 43.4 s"),
        (&still, "make it at least 35.0 s"),
    ] {
        let (c, _, _) = run(&script_of(src));
        let d = with_code(&c, CompileCode::Infeasible);
        assert!(
            d.len() == 1
                && d[0].message.starts_with("this shot needs 3.01 m/s")
                && d[0].help.as_deref() == Some(help),
            "{src}: {:?}",
            c.diagnostics
        );
    }
}

/// A two-shot of two actors walking apart: another of its roots comes to be nearer the
/// symmetric θ, and a camera that switched to it would jump metres across the arc in one
/// sample. Held from tick to tick, the two-shot follows its root: it compiles clean, and the
/// camera never steps more than the walk moves it.
#[test]
fn a_two_shot_of_walking_actors_follows_them_without_a_jump() {
    let src = "stage 20m x 16m x 4m\ndrone ardrone2\n\
               actor A height 1.69m at (-0.16, -1.77) facing 0deg\n\
               actor B height 1.72m at (-1.78, 0.96) facing 172deg\n\
               at 0s A walks to (-1.96, -3.57) over 4s\n\
               at 0s B walks to (-2.24, 1.37) over 4s\n\
               LS on A and B for 6s\n";
    let (c, samples, _) = run(&script_of(src));
    assert!(c.diagnostics.is_empty(), "{:?}", c.diagnostics);
    let step_m = largest_step_m(&samples);
    assert!(step_m < 0.02, "{step_m} m in one sample");
}

/// `then hold to` another composition moves there as every `then … to` does: the framing
/// never steps (under 1 cm a sample), and no error blames the actors' movements for a drone
/// that falls behind a framing that jumped, of an actor who stands still.
#[test]
fn a_then_hold_to_another_composition_moves_there() {
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\n\
               MS on A front for 4s\n\
               then hold to MS on A 34backright over 6s\n";
    let (c, samples, _) = run(&script_of(src));
    assert!(c.diagnostics.is_empty(), "{:?}", c.diagnostics);
    assert!(largest_step_m(&samples) < 0.01);
    // It ends on the new framing: behind A's right shoulder, at the size's distance.
    let end = samples.last().unwrap().position_m;
    let bearing_deg = end[1].atan2(end[0]).to_degrees();
    assert!((bearing_deg + 135.0).abs() < 1.0, "{bearing_deg}°");
}

/// A shot that the shot before left behind its framing is told only for what it adds: the
/// shot before, a move too fast for the drone, is the error, and the hold after it is not
/// told that the drone falls behind, with a help to slow an actor who stands still.
#[test]
fn a_shot_left_behind_by_the_one_before_is_not_blamed_for_it() {
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\n\
               MS on A front for 4s\n\
               then dolly to MS on A back over 2s\n\
               then hold for 5s\n";
    let script = script_of(src);
    let (c, _, _) = run(&script);
    let d = with_code(&c, CompileCode::Infeasible);
    assert!(
        d.len() == 1
            && d[0].message.starts_with("this shot needs 2.35 m/s")
            && src[d[0].span.start..d[0].span.end].starts_with("then dolly"),
        "{:?}",
        c.diagnostics
    );
}

/// A framing outside the stage is told on its shot only: the shots that continue it (`then
/// hold for`, and a move while it comes back in from there) start with that framing, and
/// telling each would say the same error three times. A move that goes further out than it
/// started is still told.
#[test]
fn a_framing_outside_the_stage_is_told_once_not_on_the_shots_that_continue_it() {
    let src = "stage 10m x 8m x 4m\ndrone ardrone2\n\
               actor B height 1.58m at (1.94, -0.92) facing -5deg\n\
               LS on B for 8s\n\
               then hold for 12s\n\
               then crane to eye level MLS on B over 15s\n\
               then hold for 10s\n";
    let (c, _, _) = run(&script_of(src));
    let d = with_code(&c, CompileCode::LeavesStage);
    assert!(
        d.len() == 1
            && d[0].message.contains("outside the stage")
            && src[d[0].span.start..d[0].span.end].starts_with("LS on B"),
        "{:?}",
        c.diagnostics
    );
    // Going further out than where it starts is the move's own.
    let further = src.replace("eye level MLS on B", "ELS on B");
    let (c, _, _) = run(&script_of(&further));
    let d = with_code(&c, CompileCode::LeavesStage);
    assert!(
        d.iter()
            .any(|d| further[d.span.start..d.span.end].starts_with("then crane")),
        "{:?}",
        c.diagnostics
    );
}

/// An over-the-shoulder whose foreground actor turns round: once B faces away, no camera
/// stands both on B's 34left side and behind A's right shoulder, and compile says so,
/// naming both profiles, instead of flying the camera across the stage to a shot it does not
/// name; never as a speed ("needs 2000 m/s", which no length fixes).
#[test]
fn an_over_the_shoulder_whose_actor_turns_away_is_refused_naming_both_profiles() {
    let src = "stage 14m x 10m x 3m\ndrone ardrone2\n\
               actor A height 1.82m at (-1.04, 0.21) facing 19deg\n\
               actor B height 1.82m at (0.2, -0.35) facing -168deg\n\
               at 2s B turns to 12deg over 2s\n\
               MLS on B 34left MLS on A 34backright for 8s\n";
    let (c, _, _) = run(&script_of(src));
    let refused = with_code(&c, CompileCode::Unframeable);
    assert_eq!(refused.len(), 1, "{:?}", c.diagnostics);
    assert!(
        refused[0].is_error()
            && refused[0].message.contains("34left")
            && refused[0].message.contains("34backright"),
        "{:?}",
        refused[0]
    );
    assert!(
        with_code(&c, CompileCode::Infeasible)
            .iter()
            .all(|d| !d.message.contains("m/s ")),
        "{:?}",
        c.diagnostics
    );
    // B standing still: nothing to tell.
    let still = src.replace("at 2s B turns to 12deg over 2s\n", "");
    let (c, _, _) = run(&script_of(&still));
    assert!(
        with_code(&c, CompileCode::Infeasible).is_empty()
            && with_code(&c, CompileCode::Unframeable).is_empty(),
        "{:?}",
        c.diagnostics
    );
}

/// Two actors facing each other, framed from between them: each camera stands there, looking
/// at one of them, so a cut from one to the other is nearly all a 180° turn.
const FACING_ACTORS: &str = "stage 10m x 8m x 3m\ndrone ardrone2\n\
                             actor A height 1.80m at (-1.2, 0) facing 0deg\n\
                             actor B height 1.80m at (1.2, 0) facing 180deg\n\
                             MS on A front for 3s\n";

/// A short repositioning flight that takes seconds is a turn at the yaw-rate limit: the
/// diagnostic says so, and a turn that does not set the time is not mentioned.
#[test]
fn a_repositioning_flight_that_is_a_turn_says_so() {
    let base = FACING_ACTORS;
    let (c, _, _) = run(&script_of(&format!("{base}cut to MS on B front for 3s\n")));
    let d = with_code(&c, CompileCode::Reposition);
    assert_eq!(d.len(), 1, "{:?}", c.diagnostics);
    assert!(
        d[0].message.contains("(0.8 m and a 180° turn)"),
        "{}",
        d[0].message
    );
    let (c, _, _) = run(&script_of(&format!(
        "{base}at 4s cut to MS on B front for 3s\n"
    )));
    let d = with_code(&c, CompileCode::CutTooShort);
    assert_eq!(d.len(), 1, "{:?}", c.diagnostics);
    assert!(d[0].message.contains("and a 180° turn"), "{}", d[0].message);
    // A flight along the actor's line, hardly turning: the distance alone.
    let (c, _, _) = run(&script_of(&format!("{base}cut to LS on A front for 3s\n")));
    let d = with_code(&c, CompileCode::Reposition);
    assert_eq!(d.len(), 1, "{:?}", c.diagnostics);
    assert!(
        d[0].message.contains(" m) is inserted") && !d[0].message.contains("turn"),
        "{}",
        d[0].message
    );
}

/// A cut pinned where the drone is late as planned (80 % of its limits) but in time at its
/// full limits is flown in the time there is: on time, with no error, and the reference's
/// turn faster than planned but within the profile's yaw rate. Pinned sooner than that, it
/// is an error whose fix is the pin the full limits make.
#[test]
fn a_pinned_cut_the_drone_makes_at_its_full_limits_starts_on_time() {
    let base = FACING_ACTORS;
    let yaw_max = ardrone().limits.yaw_rate_max_radps;
    // A 180° turn: 5.2 s as planned, 4.2 s at the full limits; 4.5 s are left.
    let (c, samples, _) = run(&script_of(&format!(
        "{base}at 7.5s cut to MS on B front for 3s\n"
    )));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    assert!((c.timings[1].start_s - 7.5).abs() < 1e-9, "{:?}", c.timings);
    let fastest = samples
        .iter()
        .map(|s| s.heading_rate_radps.abs())
        .fold(0.0, f64::max);
    assert!(
        fastest > 0.8 * yaw_max && fastest <= yaw_max + 1e-9,
        "{fastest} rad/s against {yaw_max}"
    );
    // 3.5 s left: late even at the full limits, by 0.7 s.
    let (c, _, _) = run(&script_of(&format!(
        "{base}at 6.5s cut to MS on B front for 3s\n"
    )));
    let d = with_code(&c, CompileCode::CutTooShort);
    assert_eq!(d.len(), 1, "{:?}", c.diagnostics);
    assert!(
        d[0].message.contains("4.2 s at its full limits")
            && d[0].help.as_deref()
                == Some(
                    "pin the shot at `at 7.3s` or later, or shorten the shot before it by 0.7 s"
                ),
        "{d:?}"
    );
}

/// A repositioning flight whose way grazes an actor (from a medium long shot of A to B)
/// keeps A's distance: the steering brakes for A's body as for a wall, and the director
/// holds its goal outside it: the flight keeps A's distance to the millimetre, not only to
/// the 2 cm the monitor tells, and passes within 0.1 m of it.
#[test]
fn a_repositioning_flight_that_grazes_an_actor_keeps_their_distance() {
    let (c, samples, actors) = run(&script_of(
        "stage 10m x 12m x 3m\ndrone ardrone2\nlens 92deg\n\
         actor A height 1.99m at (-1.58, -0.76) facing -119deg\n\
         actor B height 1.68m at (1.86, -0.63) facing 64deg\n\
         MLS on A 34right for 10s\n\
         cut to MS on B 34backleft screen left for 5s\n",
    ));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let (from_s, to_s) = c.timings[1].reposition.expect("a repositioning flight");
    let closest = samples
        .iter()
        .zip(&actors)
        .filter(|(s, _)| s.t_s >= from_s && s.t_s <= to_s)
        .map(|(s, a)| framing::body_axis_distance_m(&Vec3::from(s.position_m), &a[0]))
        .fold(f64::INFINITY, f64::min);
    let safety_m = ardrone().safety.actor_distance_m;
    assert!(closest > safety_m - 1e-3, "{closest} m from A");
    assert!(
        closest < safety_m + 0.1,
        "{closest} m: the way no longer grazes A"
    );
}

/// A repositioning flight that still comes too close to an actor (here it arrives on a
/// framing by A while swinging round them) is told as such, with a fix for a
/// flight: which side to frame from, or a framing that stands further off; not "move the
/// path away from the actors", a help for a path shot.
#[test]
fn too_close_on_a_repositioning_flight_says_the_flight_passes_the_actor() {
    let outdoor = Profile::builtin("ardrone2-outdoor").unwrap();
    let (c, _, _) = run_with(
        &script_of(
            "stage 16m x 10m x 3m\ndrone ardrone2-outdoor\n\
         actor A height 1.74m at (-2.04, -1.76) facing 43deg\n\
         actor B height 1.94m at (-0.82, -0.23) facing 79deg\n\
         at 20.3s B walks to (-1.16, -0.44) over 8s\n\
         MCU on B back MS on A 34backright for 15s\n\
         cut to low angle MCU on A 34backright screen center for 5s\n\
         then pan to MS on B back FS on A 34backleft over 5s\n",
        ),
        &outdoor,
    );
    let d = with_code(&c, CompileCode::TooClose);
    assert_eq!(d.len(), 1, "{:?}", c.diagnostics);
    assert!(
        d[0].message.contains("of A (on the repositioning flight,")
            && d[0]
                .help
                .as_deref()
                .is_some_and(|h| h.starts_with("the drone passes A on its way to this framing")),
        "{:?}",
        d[0]
    );
}

/// A repositioning flight that arrives on a moving framing falls behind it on the way (the
/// merge, `route::merge_m_per_mps`), here by metres: A turns round as the drone arrives to
/// frame them from their left. The route is chosen for clearance with the merge: checked
/// without that offset, it would bring the flight inside A's distance. The flight keeps A's
/// distance. (The shot then starts faster than the drone accelerates, A turning: that error
/// stays.)
#[test]
fn a_flight_that_merges_into_a_moving_framing_keeps_clear_of_the_actors() {
    let script = script_of(
        "stage 16m x 12m x 3m\ndrone ardrone2\n\
         actor A height 1.84m at (2.83, 2.27) facing -28deg\n\
         actor B height 1.86m at (-2.95, -0.97) facing -82deg\n\
         at 7.5s B walks to (-1.79, -0.25) over 8s\n\
         at 11.5s A turns to 1deg over 4s\n\
         at 16.2s A turns to 171deg over 3s\n\
         at 22.7s A turns to -87deg over 3s\n\
         MCU on A and B for 15s\n\
         cut to FS on A 34left for 15s\n",
    );
    let (c, samples, actors) = run(&script);
    assert!(
        with_code(&c, CompileCode::TooClose).is_empty(),
        "{:?}",
        c.diagnostics
    );
    let safety_m = ardrone().safety.actor_distance_m;
    let (start_s, arrive_s) = c.timings[1].reposition.expect("a repositioning flight");
    assert!(arrive_s > start_s + 5.0, "{:?}", c.timings);
    let closest_m = samples
        .iter()
        .zip(&actors)
        .filter(|(s, _)| s.t_s > start_s && s.t_s < arrive_s)
        .flat_map(|(s, actors)| {
            let p = s.position_m;
            actors
                .iter()
                .filter(move |a| p[2] <= a.position_m[2] + a.height_m + safety_m)
                .map(move |a| (p[0] - a.position_m[0]).hypot(p[1] - a.position_m[1]))
        })
        .fold(f64::INFINITY, f64::min);
    // Within the monitor's 2 cm (what it tells as too close).
    assert!(closest_m > safety_m - 0.02, "{closest_m:.3} m");
}

#[test]
fn a_size_inside_the_safety_distance_is_an_error() {
    let (c, _, _) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\nlens 92deg\nactor A height 1.80m at (0, 0) facing 0deg\n\
         CU on A front for 4s\n",
    ));
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == CompileCode::TooClose)
        .expect("too close");
    assert!(d.message.contains("0.50 m"), "{}", d.message);
    // Too close for the whole shot: told with when it first is (the closest, here).
    assert!(
        d.message.contains(" m from A (0.0 s into the shot); "),
        "{}",
        d.message
    );
    // The paper's MS with the AR.Drone's own lens (the profile's) is allowed.
    let (c, _, _) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
         MS on A front for 4s\n",
    ));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
}

/// An actor who walks through the camera's spot: the error says how close the framing puts
/// the camera at the closest, and when, not only the first moment it is too close: the first
/// tick inside 0.50 m would say "0.49 m from C", which reads as a centimetre to spare, for an
/// actor who passes 0.10 m from the camera's spot. The monitor's own report of the closest
/// approach is dropped as its repeat.
#[test]
fn an_actor_walking_through_the_framing_is_told_at_their_closest() {
    // MS on A front puts the camera at (0.80, 0); C walks along x = 0.9, crossing y = 0 at
    // 6 s (the walk's middle).
    let (c, _, _) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 0deg\n\
         actor C height 1.70m at (0.9, -3) facing 90deg\n\
         at 2s C walks to (0.9, 3) over 8s\n\
         MS on A front for 12s\n",
    ));
    let close = with_code(&c, CompileCode::TooClose);
    assert_eq!(close.len(), 1, "{close:#?}");
    let m = &close[0].message;
    assert!(
        m.starts_with("this framing puts the camera 0.10 m from C at the closest, 6.0 s into the shot (too close from 5."),
        "{m}"
    );
    assert!(
        m.ends_with(
            "ardrone2 keeps 0.50 m from actors: the camera is held at that distance, off its framing"
        ),
        "{m}"
    );
}

/// A framing the stage's margin holds the drone off is a warning that says by how much and
/// what it does to the shot: on a 2 m stage an MS from 0.80 m is flown from 0.70 m, A 12 %
/// larger than written.
#[test]
fn a_framing_into_the_stages_margin_is_told_with_what_it_costs() {
    let src = |side_m: f64, lens: &str| {
        format!(
            "stage {side_m}m x {side_m}m x 2m\ndrone ardrone2\n{lens}\
             actor A height 1.80m at (0, 0) facing 0deg\nMS on A front for 4s\n"
        )
    };
    let (c, samples, _) = run(&script_of(&src(2.0, "")));
    let warned = with_code(&c, CompileCode::InMargin);
    assert_eq!(warned.len(), 1, "{:#?}", c.diagnostics);
    assert!(!warned[0].is_error());
    let m = &warned[0].message;
    assert!(
        m.starts_with("this framing puts the camera 0.10 m into the stage's 0.30 m margin at (0.80, 0.00, ")
            && m.ends_with("the drone is held at the margin, up to 0.10 m off its framing (12 % of its 0.80 m to A)"),
        "{m}"
    );
    // As it says: flown from the margin, 1 − 0.30 m.
    for s in &samples {
        assert!((s.position_m[0] - 0.70).abs() < 1e-9, "{s:?}");
    }
    // With room, nothing to tell.
    let (c, _, _) = run(&script_of(&src(3.0, "")));
    assert!(
        c.diagnostics
            .iter()
            .all(|d| d.code != CompileCode::InMargin),
        "{:#?}",
        c.diagnostics
    );
    // A framing beyond the stage is its error alone.
    let (c, _, _) = run(&script_of(&src(2.0, "lens 40deg\n")));
    let codes: Vec<_> = c.diagnostics.iter().map(|d| d.code).collect();
    assert!(
        codes.contains(&CompileCode::LeavesStage.into()),
        "{codes:?}"
    );
    assert!(!codes.contains(&CompileCode::InMargin.into()), "{codes:?}");
}

/// A cut from beside B to a wide two-shot of A and B: the repositioning flight's short way
/// round the pair's midpoint would sweep through B and out of the stage; it flies another
/// way, inside the stage and clear of both actors all along: the clear routes weighed by
/// length, the straight line (5.7 m, 7.7 s), not the long way round (10.2 m, 15.1 s).
#[test]
fn a_repositioning_flight_keeps_inside_the_stage_and_clear_of_every_actor() {
    let (c, samples, actors) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 0deg\n\
         actor B height 1.65m at (2.5, 0) facing 180deg\n\
         MCU on B 34right for 4s\n\
         cut to FS on A and B for 3s\n",
    ));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let (start, end) = c.timings[1].reposition.expect("a repositioning flight");
    let safety = ardrone().safety.actor_distance_m;
    let mut flown = 0;
    for (s, poses) in samples.iter().zip(&actors) {
        let p = s.position_m;
        assert!(
            p[0].abs() <= 4.0 && p[1].abs() <= 3.0 && (0.0..=3.0).contains(&p[2]),
            "outside the stage at {} s: {p:?}",
            s.t_s
        );
        for a in poses {
            let d = (p[0] - a.position_m[0]).hypot(p[1] - a.position_m[1]);
            assert!(d >= safety - 0.02, "{d:.2} m from an actor at {} s", s.t_s);
        }
        flown += usize::from(s.t_s > start && s.t_s < end);
    }
    assert!(flown > 100, "{flown} samples on the repositioning flight");
    // The shortest clear route: the path flown is barely longer than the chord between its
    // ends (steering rounds its start and end), and the flight takes half the long way's time.
    let on_flight: Vec<[f64; 3]> = samples
        .iter()
        .filter(|s| s.t_s >= start && s.t_s <= end)
        .map(|s| s.position_m)
        .collect();
    let dist = |p: &[f64; 3], q: &[f64; 3]| {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let path_m: f64 = on_flight.windows(2).map(|w| dist(&w[0], &w[1])).sum();
    let chord_m = dist(&on_flight[0], on_flight.last().unwrap());
    assert!(
        path_m < 1.1 * chord_m,
        "flew {path_m:.2} m between ends {chord_m:.2} m apart"
    );
    assert!(end - start < 9.0, "a {:.1} s flight", end - start);
}

/// A framing inside an actor's safety distance is one error, with its fix: not also "the
/// drone falls behind the framing" (it keeps its distance, by design) with a help about the
/// actors' movements when nobody moves, nor a closeness error on the next shot's
/// repositioning flight for starting where the first shot left the drone.
#[test]
fn a_framing_too_close_is_told_once_not_with_its_consequences() {
    let (c, _, _) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 0deg\n\
         actor B height 1.65m at (2.5, 0) facing 180deg\n\
         ECU on A front for 4s\n\
         cut to MS on B front for 4s\n",
    ));
    let errors: Vec<_> = c.diagnostics.iter().filter(|d| d.is_error()).collect();
    assert_eq!(errors.len(), 1, "{errors:#?}");
    assert_eq!(errors[0].code, CompileCode::TooClose);
    assert!(
        errors[0].message.contains("puts the camera"),
        "{}",
        errors[0].message
    );
    // Its fix leaves nothing to report.
    let (c, _, _) = run(&script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 0deg\n\
         actor B height 1.65m at (2.5, 0) facing 180deg\n\
         MS on A front for 4s\n\
         cut to MS on B front for 4s\n",
    ));
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    // The shots that continue it (`then`) start where it left the camera: not told again,
    // neither on the hold nor on the move after it.
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\n\
               actor A height 1.80m at (0, 0) facing 0deg\n\
               ECU on A front for 4s\n\
               then hold for 3s\n\
               then dolly to MS on A front over 6s\n";
    let (c, _, _) = run(&script_of(src));
    let close: Vec<_> = c
        .diagnostics
        .iter()
        .filter(|d| d.code == CompileCode::TooClose)
        .collect();
    assert!(
        close.len() == 1 && src[close[0].span.start..close[0].span.end].starts_with("ECU on A"),
        "{close:#?}"
    );
    // A move that comes nearer than where it starts is told.
    let nearer = src.replace(
        "then dolly to MS on A front",
        "then dolly to ECU on A 34left",
    );
    let nearer = nearer.replace("ECU on A front for 4s", "BCU on A front for 4s");
    let (c, _, _) = run(&script_of(&nearer));
    assert!(
        c.diagnostics.iter().any(|d| d.code == CompileCode::TooClose
            && nearer[d.span.start..d.span.end].starts_with("then dolly")),
        "{:#?}",
        c.diagnostics
    );
}

/// A hold whose actors land away from their screen points is a warning on the shot, with
/// the RMS screen distance that the test's own re-solve and projection find. Here B stands
/// right behind A (each faces the other, the profiles ask for the camera on their line), so
/// B is hidden behind A: a shot `compile` must not write without a word.
#[test]
fn a_hold_that_misses_its_screen_points_is_a_warning_with_the_figure() {
    let script = script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 0deg\n\
         actor B height 1.65m at (2.5, 0) facing 180deg\n\
         MS on B front MS A back for 3s\n",
    );
    let (c, _, _) = run(&script);
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let off = with_code(&c, CompileCode::FramingOff);
    assert_eq!(off.len(), 1, "{:?}", c.diagnostics);
    assert!(!off[0].is_error());
    assert_eq!(off[0].span, script.timeline[0].span);
    let rms_said: f64 = off[0]
        .message
        .split("; ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("an RMS figure: {}", off[0].message));
    let errs = hold_framing_errors(&script);
    let rms = (errs.iter().map(|e| e.2 * e.2 + e.3 * e.3).sum::<f64>() / errs.len() as f64).sqrt();
    assert!(rms > FRAMING_TOLERANCE);
    assert!(
        (rms - rms_said).abs() <= 0.006,
        "said {rms_said}, measured {rms}"
    );

    // The shipped two-actor scenes hold their framing: no warning.
    for name in ["two-actors.psl", "two-heights.psl"] {
        let (_, checked) =
            crate::common::check_path(&crate::common::workspace().join("shots").join(name));
        let (c, _, _) = run(&checked.script.unwrap());
        assert!(
            !c.diagnostics
                .iter()
                .any(|d| d.code == CompileCode::FramingOff),
            "{name}: {:?}",
            c.diagnostics
        );
    }
}

/// The dialogue of film grammar's contract, over Bob's right shoulder onto Alice, the actors
/// 2 m apart facing each other: the camera stands behind Bob's right shoulder and sees Alice
/// from her front-left (both bearings within 22.5° of the profiles, measured on the compiled
/// reference, a test's own geometry), Alice at her screen point; her MS cannot be had from
/// behind Bob, so the shot keeps the shoulder and one warning names the size she gets and
/// the size to write, and written, it compiles with nothing to tell.
#[test]
fn an_over_the_shoulder_keeps_the_shoulder_it_names() {
    let text = |alice: &str| {
        format!(
            "stage 8m x 6m x 3m\ndrone ardrone2\n\
             actor Bob height 1.82m at (1.5, 0.5) facing 180deg\n\
             actor Alice height 1.66m at (-0.5, 0.5) facing 0deg\n\
             MS on Bob 34backright {alice} on Alice 34left screen right for 4s\n"
        )
    };
    let script = script_of(&text("MS"));
    let (c, samples, actors) = run(&script);
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let (s, poses) = (samples.last().unwrap(), actors.last().unwrap());
    let off_deg = |who: usize, azimuth_deg: f64| {
        let a = &poses[who];
        let bearing = (s.position_m[1] - a.position_m[1]).atan2(s.position_m[0] - a.position_m[0]);
        dronecine_math::wrap_angle_rad(bearing - a.facing_rad - azimuth_deg.to_radians())
            .abs()
            .to_degrees()
    };
    assert!(
        off_deg(0, -135.0) <= 22.5,
        "Bob's 34backright {}° off",
        off_deg(0, -135.0)
    );
    assert!(
        off_deg(1, 45.0) <= 22.5,
        "Alice's 34left {}° off",
        off_deg(1, 45.0)
    );
    let told: Vec<_> = c
        .diagnostics
        .iter()
        .filter(|d| d.code == CompileCode::SizeOff)
        .collect();
    assert_eq!(told.len(), 1, "{told:?}");
    assert!(
        told[0].code == CompileCode::SizeOff
            && told[0].message.starts_with("Alice is framed as an LS"),
        "{}",
        told[0].message
    );
    let help = told[0].help.as_deref().unwrap();
    let size = help
        .strip_prefix("write ")
        .and_then(|h| h.split([';', ',', ' ']).next())
        .unwrap_or_else(|| panic!("{help}"));
    let (fixed, _, _) = run(&script_of(&text(size)));
    assert!(
        fixed
            .diagnostics
            .iter()
            .all(|d| d.code != CompileCode::SizeOff && !d.is_error()),
        "{size}: {:?}",
        fixed.diagnostics
    );
    // Both actors on their screen points.
    let errs = hold_framing_errors(&script);
    let rms = (errs.iter().map(|e| e.2 * e.2 + e.3 * e.3).sum::<f64>() / errs.len() as f64).sqrt();
    assert!(rms < FRAMING_TOLERANCE, "{rms}");
}

/// The shipped scripts have nothing to report in size or profile.
#[test]
fn the_shipped_scripts_frame_the_sizes_and_profiles_they_write() {
    for (name, script) in shipped() {
        let (c, _, _) = run(&script);
        let off: Vec<_> = c
            .diagnostics
            .iter()
            .filter(|d| d.code == CompileCode::SizeOff || d.code == CompileCode::BeyondReach)
            .collect();
        assert!(off.is_empty(), "{name}: {off:?}");
    }
}

/// The closest distance between actors `a` and `b` over `[0, end_s]`, by a brute-force scan
/// of the blocking every 0.1 ms (independent of `Blocking::contacts`' search).
fn closest_scan(blocking: &Blocking, a: usize, b: usize, end_s: f64) -> (f64, f64) {
    let mut best = (f64::INFINITY, 0.0);
    for k in 0..=(end_s * 1e4) as usize {
        let t = k as f64 * 1e-4;
        let (p, q) = (
            blocking.pose(a, t).position_m,
            blocking.pose(b, t).position_m,
        );
        let d = (p[0] - q[0]).hypot(p[1] - q[1]);
        if d < best.0 {
            best = (d, t);
        }
    }
    best
}

/// Walks that take two actors through each other are an error on the walk (the grammar sees
/// only where actors start, and the shot's speed or framing errors would not name the walk),
/// and walks that pass apart, or cross the same spot at different times, are not.
#[test]
fn walks_that_take_actors_through_each_other_are_errors() {
    let scene = "stage 10m x 8m x 3m\nactor A height 1.80m at (-2, 0) facing 0deg\n\
                 actor B height 1.70m at (0, 0.4) facing 180deg\n";
    let collide = |src: &str| {
        let text = format!("{scene}{src}LS on A and B for 12s\n");
        let script = script_of(&text);
        let (c, _, _) = run(&script);
        let found: Vec<_> = c
            .diagnostics
            .iter()
            .filter(|d| d.code == CompileCode::ActorsCollide)
            .cloned()
            .collect();
        (text, script, found)
    };

    // A walks through where B stands (0.40 m off A's line: B's centre 0.4 m away, then B
    // steps onto the line).
    let (_, _, found) = collide("at 1s A walks to (2, 0) over 4s\n");
    assert!(found.is_empty(), "0.40 m apart is a pass: {found:?}");
    let (text2, script2, found2) =
        collide("at 0s B walks to (0, 0.1) over 1s\nat 1s A walks to (2, 0) over 4s\n");
    assert_eq!(found2.len(), 1, "{found2:?}");
    let d = &found2[0];
    let line = |t: &str, span: dronecine_diag::Span| t[span.start..span.end].to_string();
    assert_eq!(line(&text2, d.span), "at 1s A walks to (2, 0) over 4s");
    assert_eq!(
        line(&text2, d.related[0].span),
        "at 0s B walks to (0, 0.1) over 1s",
        "B stands where its walk left them"
    );
    assert!(
        d.message
            .starts_with("`A` walks into `B`: 0.10 m apart at 3.0 s"),
        "{}",
        d.message
    );
    // The closest approach, against a brute-force scan of the blocking.
    let blocking = Blocking::new(script2.scene.as_ref().unwrap());
    let (d_scan, t_scan) = closest_scan(&blocking, 0, 1, 12.0);
    let contact = &blocking.contacts()[0];
    assert!(
        (contact.distance_m - d_scan).abs() < 1e-6,
        "{contact:?} vs {d_scan}"
    );
    assert!(
        (contact.t_s - t_scan).abs() < 1e-3,
        "{contact:?} vs {t_scan}"
    );

    // Head on, both walking: the error sits on the later walk, the other's is quoted.
    let (text, _, found) = collide(
        "at 0s B walks to (0, 0) over 1s\nat 2s A walks to (1, 0) over 4s\n\
         at 3s B walks to (-1, 0) over 4s\n",
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(
        line(&text, found[0].span),
        "at 3s B walks to (-1, 0) over 4s"
    );
    assert_eq!(
        line(&text, found[0].related[0].span),
        "at 2s A walks to (1, 0) over 4s"
    );
    assert!(
        found[0]
            .message
            .contains("`B` and `A` walk into each other"),
        "{}",
        found[0].message
    );

    // The same paths, crossing the same spot at different times: no error. So the help's
    // fix (start the walk when the other is out of the way) works.
    let (_, _, found) = collide(
        "at 0s B walks to (0, 0) over 1s\nat 1s B walks to (0, -2) over 2s\n\
         at 3s A walks to (2, 0) over 4s\n",
    );
    assert!(found.is_empty(), "{found:?}");
    // The threshold: 0.29 m is a collision, 0.31 m a pass.
    for (y, collides) in [(0.29, true), (0.31, false)] {
        let (_, _, found) = collide(&format!(
            "at 0s B walks to (0, {y}) over 1s\nat 1s A walks to (2, 0) over 4s\n"
        ));
        assert_eq!(!found.is_empty(), collides, "{y}: {found:?}");
    }
}

/// A framing that puts the camera beyond the stage's wall is an error that says so, and the
/// reference does not follow it: the director keeps its target inside the stage less the
/// profile's margin (the flight's stage failsafe would land a drone sent to the wall).
#[test]
fn a_framing_beyond_the_wall_is_refused_and_not_followed() {
    let script = script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (2.5, 0) facing 0deg\n\
         FS on A front for 3s\n",
    );
    let (c, samples, _) = run(&script);
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == CompileCode::LeavesStage)
        .unwrap_or_else(|| panic!("{:?}", c.diagnostics));
    assert!(d.is_error());
    assert!(
        d.message.starts_with("this framing puts the camera")
            && d.message.contains("outside the stage"),
        "{}",
        d.message
    );
    let margin = ardrone().safety.stage_margin_m;
    let x_max = samples
        .iter()
        .map(|s| s.position_m[0])
        .fold(f64::MIN, f64::max);
    assert!(
        x_max <= 4.0 - margin + 1e-9,
        "the reference reached x = {x_max}"
    );
}

/// The blocking's poses with B moved to `b_x_m` on the x axis, walking toward A at
/// `toward_mps` (as a tracker's velocity says).
fn b_at(scene: &Scene, b_x_m: f64, toward_mps: f64) -> Vec<ActorPose> {
    let mut p = Blocking::new(scene).poses(0.0);
    p[1].position_m = [b_x_m, 0.0, 0.0];
    p[1].velocity_mps = [-toward_mps, 0.0, 0.0];
    p
}

/// A framing that solves now but not a moment ahead (live actors at the edge of what the
/// composition can frame) gives the camera no feed-forward: the look-ahead difference would
/// be the jump between where the camera is held and the framing solved now, hundreds of
/// metres a second, and would carry the camera away from its framing at full speed. Live
/// actors meet that edge only now and then, so it is made here: a two-shot seen from A's
/// 34right, B walking toward A (as a tracker's velocity says) into the direction the
/// profile looks along, where the two-shot is refused (one actor would stand in front of the
/// other), B standing just outside it, so that a millisecond ahead it cannot. The camera,
/// which was framing the pair from further apart, goes to the new framing and stays on it.
#[test]
fn a_framing_that_fails_a_moment_ahead_gives_no_feed_forward() {
    let script = script_of(
        "stage 10m x 8m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 90deg\n\
         actor B height 1.65m at (3, 0.8) facing 180deg\n\
         MLS on A 34right and B for 12s\n",
    );
    let scene = script.scene.as_ref().unwrap();
    let poses = |b_x_m: f64, toward_mps: f64| {
        let mut p = b_at(scene, b_x_m, toward_mps);
        p[1].position_m[1] = 0.8;
        p
    };
    let frames = |b_x_m: f64| {
        let mut d = Director::new(&script, scene, &ardrone());
        d.step(0.0, &poses(b_x_m, 0.0));
        !d.diagnostics_so_far().iter().any(|x| x.is_error())
    };
    // The nearest B frames at (to 0.1 mm).
    let (mut lo, mut hi) = (1.0, 3.0);
    assert!(frames(hi) && !frames(lo));
    while hi - lo > 1e-4 {
        let mid = (lo + hi) / 2.0;
        if frames(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let edge_m = hi;
    let mut d = Director::new(&script, scene, &ardrone());
    let mut k = 0;
    let mut t = || {
        k += 1;
        f64::from(k - 1) / 100.0
    };
    for _ in 0..200 {
        d.step(t(), &poses(edge_m + 0.5, 0.0));
    }
    let mut fastest: f64 = 0.0;
    let mut last = None;
    for _ in 0..800 {
        // 1 m/s toward A: a millisecond ahead B is 1 mm closer, past the edge.
        let s = d.step(t(), &poses(edge_m, 1.0));
        fastest = fastest.max(Vec3::from(s.velocity_mps).norm());
        last = Some(s);
    }
    assert!(
        d.diagnostics_so_far()
            .iter()
            .any(|x| x.code == CompileCode::Unframeable),
        "the look-ahead never failed: {:?}",
        d.diagnostics_so_far()
    );
    let off = (Vec3::from(last.unwrap().position_m) - d.solved_target_m()).norm();
    // Within 2 cm of its framing, never as fast as 1 m/s: a feed-forward would carry it
    // metres away.
    assert!(off < 0.02, "{off} m from its framing");
    assert!(fastest < 1.0, "{fastest} m/s");
}

/// A first framing that does not solve leaves the camera unplaced (offline: nowhere, held at
/// the origin): nothing is checked against that position, and when the framing solves the
/// camera starts on it, framed, as a first shot does. On set the flight says where the
/// camera is (`Director::start_from`, where the approach left the drone, not the origin,
/// which is A's mark): it is held there, and steers from there when the framing solves,
/// without a jump.
#[test]
fn an_unplaced_camera_is_held_then_starts_framed_and_a_started_one_steers() {
    let script = script_of(
        "stage 10m x 8m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (0, 0) facing 90deg\n\
         actor B height 1.65m at (3, 0.8) facing 180deg\n\
         MLS on A 34right and B for 12s\n",
    );
    let scene = script.scene.as_ref().unwrap();
    // B at (1.5, 0.8) stands where A's 34right looks: the two-shot is refused there; at
    // (3, 0.8) it frames.
    let poses = |b_x_m: f64| {
        let mut p = b_at(scene, b_x_m, 0.0);
        p[1].position_m[1] = 0.8;
        p
    };
    let t = |k: u32| f64::from(k) / 100.0;

    // Offline: unplaced, then framed at once.
    let mut d = Director::new(&script, scene, &ardrone());
    for k in 0..50 {
        d.step(t(k), &poses(1.5));
        assert!(!d.placed(), "tick {k}");
    }
    let s = d.step(t(50), &poses(3.0));
    assert!(d.placed());
    let target = d.solved_target_m();
    let off = (Vec3::from(s.position_m) - target).norm();
    assert!(off < 1e-9, "{off} m from the framing");
    let codes: Vec<dronecine_diag::Code> = d.diagnostics_so_far().iter().map(|x| x.code).collect();
    assert_eq!(
        codes,
        [CompileCode::Unframeable],
        "nothing about the origin"
    );

    // On set: held where it starts, then steered from there.
    let start = Vec3::new(-2.0, 1.5, 1.2);
    let mut d = Director::new(&script, scene, &ardrone());
    d.start_from(start, Vec3::zeros(), 0.3);
    assert!(d.placed());
    for k in 0..50 {
        let s = d.step(t(k), &poses(1.5));
        assert_eq!(Vec3::from(s.position_m), start, "tick {k}");
        assert_eq!(Vec3::from(s.velocity_mps), Vec3::zeros(), "tick {k}");
    }
    let s = d.step(t(50), &poses(3.0));
    let moved = (Vec3::from(s.position_m) - start).norm();
    assert!(moved < 0.01, "no jump: {moved} m in a tick");
    let mut s = s;
    for k in 51..1000 {
        s = d.step(t(k), &poses(3.0));
    }
    let off = (Vec3::from(s.position_m) - d.solved_target_m()).norm();
    assert!(off < 0.02, "{off} m from the framing after 9.5 s");
    // A second start_from, once stepped, changes nothing.
    d.start_from(start, Vec3::zeros(), 0.3);
    let s2 = d.step(t(1000), &poses(3.0));
    assert!((Vec3::from(s2.position_m) - Vec3::from(s.position_m)).norm() < 0.01);
    let codes: Vec<dronecine_diag::Code> = d.diagnostics_so_far().iter().map(|x| x.code).collect();
    assert_eq!(codes, [CompileCode::Unframeable], "nothing about the start");
}

/// Before 0 s the director's clock is held at the script's start: a camera placed off the
/// first framing (the flight: where its approach's glide ended) steers onto it, without a
/// jump, and on into the first shot; the shot does not start early. This is the flight's
/// settle before "action!".
#[test]
fn before_its_clock_starts_a_placed_camera_steers_onto_the_first_framing() {
    let script = script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
         MS on A front for 2s\ncut to MS on A 34left for 2s\n",
    );
    let scene = script.scene.as_ref().unwrap();
    let poses = Blocking::new(scene).poses(0.0);
    let framed = Director::new(&script, scene, &ardrone()).step(0.0, &poses);
    let target = Vec3::from(framed.position_m);
    let start = target + Vec3::new(0.3, 0.4, 0.0);
    let mut d = Director::new(&script, scene, &ardrone());
    d.start_from(start, Vec3::zeros(), framed.heading_rad);
    let mut last = start;
    let mut at_zero = None;
    for k in -100..=150 {
        let t = f64::from(k) / 100.0;
        let s = d.step(t, &poses);
        let p = Vec3::from(s.position_m);
        assert!(
            (p - last).norm() < 0.02,
            "a jump at {t} s: {} m",
            (p - last).norm()
        );
        assert_eq!(s.shot, 0, "{t} s");
        if k < 0 {
            assert_eq!(d.written_t_s(t), 0.0);
        }
        if k == 0 {
            at_zero = Some((p - target).norm());
        }
        last = p;
    }
    // Closing as e^(−t/1 s) from 0.5 m: about 0.18 m at 0 s, and on the framing 1.5 s later.
    let at_zero = at_zero.unwrap();
    assert!((0.1..0.3).contains(&at_zero), "{at_zero} m off at 0 s");
    assert!(
        (last - target).norm() < 0.05,
        "{} m off at 1.5 s",
        (last - target).norm()
    );
    // The first shot still ends at 2 s, as written.
    let s = d.step(2.01, &poses);
    assert_eq!(s.shot, 1);
}

/// A shot shorter than one control period at the compile's rate is an error on its line,
/// whose help names the rate that gives it a tick: there it compiles. A shot of exactly one
/// period is flown for its tick.
#[test]
fn a_shot_shorter_than_a_tick_is_an_error_on_its_line() {
    let src = "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
               MS on A front for 4s\n\
               cut to path square side 2m center (0, 0) altitude 1.5m for 0.004s\n\
               cut to MS on A front for 0.01s\n";
    let script = script_of(src);
    let compile_at = |rate_hz: f64| {
        compile::<()>(&script, &ardrone(), &Options { rate_hz }, |s, _| {
            assert!(s.position_m.iter().all(|x| x.is_finite()), "{s:?}");
            Ok(())
        })
        .unwrap()
    };
    let c = compile_at(100.0);
    let told = with_code(&c, CompileCode::TooShortForRate);
    assert_eq!(told.len(), 1, "{:?}", c.diagnostics);
    let d = told[0];
    assert!(d.is_error());
    assert_eq!(
        &src[d.span.start..d.span.end],
        "cut to path square side 2m center (0, 0) altitude 1.5m for 0.004s"
    );
    assert!(d.message.contains("0.004 s"), "{}", d.message);
    let help = d.help.as_deref().unwrap();
    assert!(help.contains("`--rate 250`"), "{help}");
    // At 250 Hz the path has its tick (and the 10 ms shot too); at 50 Hz neither has.
    let c = compile_at(250.0);
    assert!(
        with_code(&c, CompileCode::TooShortForRate).is_empty(),
        "{:?}",
        c.diagnostics
    );
    let c = compile_at(50.0);
    assert_eq!(with_code(&c, CompileCode::TooShortForRate).len(), 2);
    // The shortest shot the language takes has its tick at 1000 Hz, and no suggested rate
    // below it.
    let one_ms = script_of(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n\
         MS on A front for 0.001s\n",
    );
    let c = compile::<()>(&one_ms, &ardrone(), &Options { rate_hz: 1000.0 }, |_, _| {
        Ok(())
    })
    .unwrap();
    assert!(
        with_code(&c, CompileCode::TooShortForRate).is_empty(),
        "{:?}",
        c.diagnostics
    );
    let c = compile::<()>(&one_ms, &ardrone(), &Options::default(), |_, _| Ok(())).unwrap();
    let help = with_code(&c, CompileCode::TooShortForRate)[0]
        .help
        .clone()
        .unwrap();
    assert!(help.contains("`--rate 1000`"), "{help}");
}
