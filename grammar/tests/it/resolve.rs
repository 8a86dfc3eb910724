//! The semantic pass on small scripts: what it resolves to and what it rejects.

use dronecine_grammar::script::*;
use dronecine_grammar::PslCode;
use dronecine_grammar::{check, Options};

const HEAD: &str = "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0) facing 90deg\nactor B height 1.65m at (2, 0) facing 180deg\n";

fn ok(body: &str) -> Script {
    let src = format!("{HEAD}{body}");
    let c = check(&src, &Options::default());
    assert!(!c.has_errors(), "{body}: {:?}", c.diagnostics);
    c.script.unwrap()
}

fn codes(body: &str) -> Vec<PslCode> {
    let src = format!("{HEAD}{body}");
    check(&src, &Options::default())
        .diagnostics
        .iter()
        .map(|d| {
            let psl = PslCode::ALL.iter().find(|c| d.code == **c);
            *psl.unwrap_or_else(|| panic!("{} is not a psl:: code", d.code))
        })
        .collect()
}

fn composition(s: &Script, i: usize) -> &Composition {
    match &s.timeline[i].content {
        ShotContent::Composition(c) => c,
        other => panic!("{other:?}"),
    }
}

#[test]
fn units_become_si_and_angles_radians() {
    let s = ok("MS on A for 4s\n");
    let scene = s.scene.unwrap();
    assert_eq!(scene.stage.size_m, [8.0, 6.0, 3.0]);
    assert_eq!(scene.stage.min_m(), [-4.0, -3.0, 0.0]);
    assert!((scene.actors[0].facing_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // 180deg wraps to +π, never −π.
    assert_eq!(scene.actors[1].facing_rad, std::f64::consts::PI);
}

#[test]
fn lens_defaults_to_16_9() {
    let s = ok("lens 84deg\nMS on A for 1s\n");
    let lens = s.scene.unwrap().lens.unwrap();
    assert!((lens.fov_x_rad.to_degrees() - 84.0).abs() < 1e-9);
    assert!((lens.aspect - 16.0 / 9.0).abs() < 1e-12);
    let s = ok("lens 60deg 4:3\nMS on A for 1s\n");
    assert!((s.scene.unwrap().lens.unwrap().aspect - 4.0 / 3.0).abs() < 1e-12);
}

#[test]
fn shots_run_back_to_back_and_pins_leave_gaps() {
    let s =
        ok("MS on A for 4s\nthen dolly to MS on A back over 6s\nat 12s cut to CU on B for 2s\n");
    let t: Vec<(f64, f64, bool)> = s
        .timeline
        .iter()
        .map(|x| (x.start_s, x.end_s, x.pinned))
        .collect();
    assert_eq!(
        t,
        [(0.0, 4.0, false), (4.0, 10.0, false), (12.0, 14.0, true)]
    );
    assert_eq!(s.duration_s, 14.0);
}

#[test]
fn screen_thirds_and_points() {
    let s =
        ok("MS on A screen left and B screen right for 4s\nMS on A screen (0.25, -0.5) for 1s\n");
    let c = composition(&s, 0);
    assert_eq!(c.framings[0].subjects[0].screen_x, Some(-1.0 / 3.0));
    assert_eq!(c.framings[0].subjects[1].screen_x, Some(1.0 / 3.0));
    let c = composition(&s, 1);
    assert_eq!(
        (
            c.framings[0].subjects[0].screen_x,
            c.framings[0].subjects[0].screen_y
        ),
        (Some(0.25), Some(-0.5))
    );
}

#[test]
fn hold_copies_the_composition_and_follow_names_the_actor() {
    let s = ok("high angle MS on A 34left for 4s\nthen as B enters follow B to MS on B for 2s\nthen hold for 3s\n");
    assert!(matches!(
        &s.timeline[1].transition,
        Transition::Move { follow: Some(b), event: Some(e), .. } if b == "B" && e == "B enters"
    ));
    assert_eq!(composition(&s, 2), composition(&s, 1));
    assert_eq!(
        composition(&s, 0).camera_angle,
        dronecine_grammar::vocab::CameraAngle::High
    );
}

#[test]
fn blocking_is_sorted_and_checked() {
    let s = ok("at 6s A walks to (1, 1.5) over 4s\nat 1s B turns to -90deg over 1s\nat 10s A turns to 0deg over 1s\nMS on A for 12s\n");
    let b = s.scene.unwrap().blocking;
    assert_eq!(
        b.iter().map(|m| m.start_s).collect::<Vec<_>>(),
        [1.0, 6.0, 10.0]
    );
    assert!(
        matches!(b[0].action, Action::Turn { to_rad } if (to_rad + std::f64::consts::FRAC_PI_2).abs() < 1e-12)
    );
    // Back to back is not an overlap.
    assert!(codes(
        "at 2s A walks to (1, 1) over 2s\nat 4s A turns to 0deg over 1s\nMS on A for 5s\n"
    )
    .is_empty());
    assert_eq!(
        codes("at 2s A walks to (1, 1) over 2s\nat 3.9s A turns to 0deg over 1s\nMS on A for 5s\n"),
        [PslCode::OverlappingMovement]
    );
    // Different actors may move at once.
    assert!(codes(
        "at 2s A walks to (1, 1) over 2s\nat 2s B walks to (1, -1) over 2s\nMS on A for 5s\n"
    )
    .is_empty());
}

#[test]
fn timecodes_tolerate_sixty_seconds() {
    let c = check(
        "1 00:00:58 --> 00:00:60 MS on X\n2 00:01:00 --> 00:01:02,500 cut to MS on Y\n",
        &Options::default(),
    );
    let s = c.script.unwrap();
    assert_eq!((s.timeline[0].start_s, s.timeline[0].end_s), (58.0, 60.0));
    assert_eq!(s.timeline[1].end_s, 62.5);
    assert!(s.is_annotation());
    assert_eq!(s.cast, ["X", "Y"]);
}

#[test]
fn annotations_may_frame_three_actors_but_scenes_may_not() {
    let c = check(
        "1 00:00:01 --> 00:00:02 LS on X and Y and Z\n",
        &Options::default(),
    );
    assert!(!c.has_errors());
    assert_eq!(
        codes("actor C height 1.7m at (-2, 0) facing 0deg\nLS on A and B and C for 4s\n"),
        [PslCode::TooManyActors]
    );
}

#[test]
fn paths_resolve_with_defaults() {
    let s = ok("path orbit around A radius 2m altitude 1.5m for 10s\npath helix radius 1m from 0.5m to 2m for 10s\n");
    match &s.timeline[0].content {
        ShotContent::Path(p) => assert_eq!(
            p.shape,
            PathShape::Orbit {
                center: OrbitCenter::Actor { name: "A".into() },
                radius_m: 2.0,
                altitude_m: 1.5,
                turns: 1.0,
                clockwise: false
            }
        ),
        other => panic!("{other:?}"),
    }
    match &s.timeline[1].content {
        ShotContent::Path(p) => assert!(
            matches!(p.shape, PathShape::Helix { center_m: [0.0, 0.0], turns, .. } if turns == 1.0)
        ),
        other => panic!("{other:?}"),
    }
}

#[test]
fn known_drones_are_checked_only_when_given() {
    let src = format!("{HEAD}drone mavic\nMS on A for 1s\n");
    assert!(!check(&src, &Options::default()).has_errors());
    let known = ["ardrone2"];
    let opts = Options {
        known_drones: &known,
        base_dir: None,
    };
    let c = check(&src, &opts);
    assert_eq!(
        c.diagnostics.iter().map(|d| d.code).collect::<Vec<_>>(),
        [PslCode::UnknownDrone]
    );
}

#[test]
fn diagnostics_come_in_source_order() {
    let c = check(
        &format!("{HEAD}MS on Q for 1s\nMS on A for 0s\nMS on R for 1s\n"),
        &Options::default(),
    );
    let starts: Vec<usize> = c.diagnostics.iter().map(|d| d.span.start).collect();
    let mut sorted = starts.clone();
    sorted.sort();
    assert_eq!(starts, sorted);
    assert_eq!(c.diagnostics.len(), 3);
}

/// Which shots move the camera (`script::moves_camera`): every `then … to` another
/// composition, `hold` included (`then <move> to <composition> over Ns` interpolates);
/// `then hold for`, a `then hold to` the same composition, cuts and the first shot hold. The
/// duration keyword follows: a `then hold to` another composition is timed with `over`.
#[test]
fn a_then_hold_to_another_composition_is_a_move() {
    let s = ok("MS on A front for 4s\n\
                then hold to MS on A 34backright over 6s\n\
                then hold for 2s\n\
                then hold to MS on A 34backright for 2s\n\
                then dolly to MLS on A over 3s\n\
                cut to MS on B for 2s\n");
    let moves: Vec<bool> = (0..s.timeline.len()).map(|i| s.moves_camera(i)).collect();
    assert_eq!(moves, [false, true, false, false, true, false]);
    assert!(!s.moves_camera(99));
    // Timed as moves are, and as holds are.
    assert!(
        codes("MS on A front for 4s\nthen hold to MS on A 34backright for 6s\n")
            .contains(&PslCode::DurationKeyword)
    );
    assert!(
        !codes("MS on A front for 4s\nthen hold to MS on A 34backright over 6s\n")
            .contains(&PslCode::DurationKeyword)
    );
    assert!(
        !codes("MS on A front for 4s\nthen hold to MS on A front for 6s\n")
            .contains(&PslCode::DurationKeyword)
    );
}

/// Every duration is at least one tick at the fastest control rate (1 ms): shots, moves,
/// holds, paths and actor movements alike; 1 ms itself is a duration.
#[test]
fn durations_shorter_than_a_millisecond_are_refused() {
    use dronecine_grammar::resolve::MIN_DURATION_S;
    assert_eq!(MIN_DURATION_S, 0.001);
    for body in [
        "MS on A for 0.0009s\n",
        "MS on A for 0.000000001s\n",
        "MS on A for 4s\nthen dolly to MS on A back over 0.0005s\n",
        "MS on A for 4s\nthen hold for 0.0001s\n",
        "path square side 2m altitude 1.5m for 0.000000001s\n",
        "path helix radius 1m from 1m to 2m for 0.0009999s\n",
        "path orbit around A radius 1m altitude 1.5m for 0.0009s\n",
        "at 1s A walks to (1, 1) over 0.0001s\nMS on A for 4s\n",
        "at 1s A turns to 90deg over 0.000000001s\nMS on A for 4s\n",
    ] {
        assert_eq!(codes(body), [PslCode::TooShort], "{body}");
    }
    let s = ok("MS on A for 0.001s\nat 1s cut to MS on B for 4s\n");
    assert_eq!(s.timeline[0].end_s, 0.001);
    // Zero and below keep their own code.
    assert_eq!(codes("MS on A for 0s\n"), [PslCode::NonPositiveDuration]);
    assert_eq!(codes("MS on A for -0s\n"), [PslCode::NonPositiveDuration]);
}

/// A number other than 0 is at least 0.000000001 in size, wherever it stands; 0 and -0 are
/// 0.
#[test]
fn numbers_too_close_to_zero_are_refused() {
    let subnormal = format!("0.{}5", "0".repeat(320));
    for body in [
        "actor C height 1.8m at (0.0000000001, 1) facing 0deg\nMS on C for 4s\n".to_string(),
        "actor C height 1.8m at (1, 1) facing -0.0000000001deg\nMS on C for 4s\n".into(),
        format!("actor C height 1.8m at (1, {subnormal}) facing 0deg\nMS on C for 4s\n"),
        "MS on A screen (0.00000000001, 0) for 4s\n".into(),
        format!("at {subnormal}s A walks to (1, 1) over 1s\nMS on A for 4s\n"),
        "at 0.0000000001s MS on A for 4s\n".into(),
        format!("path orbit around A radius 1m altitude 1.5m turns {subnormal} for 10s\n"),
    ] {
        assert_eq!(codes(&body), [PslCode::OutOfRange], "{body}");
    }
    let s = ok("actor C height 1.8m at (-1, 0.000000001) facing -0deg\nMS on C for 4s\n");
    let c = &s.scene.unwrap().actors[2];
    assert_eq!(c.position_m, [-1.0, 0.000000001]);
}

/// A path's side, radius and altitude are at least 1 cm.
#[test]
fn path_lengths_are_at_least_a_centimetre() {
    for body in [
        "path square side 0.009m altitude 1.5m for 20s\n",
        "path square side 2m altitude 0.000000001m for 20s\n",
        "path helix radius 0.0099m from 1m to 2m for 20s\n",
        "path orbit around A radius 0.001m altitude 1.5m for 20s\n",
    ] {
        assert_eq!(codes(body), [PslCode::OutOfRange], "{body}");
    }
    let s = ok("path square side 0.01m altitude 0.01m for 20s\n");
    assert!(matches!(
        s.timeline[0].content,
        ShotContent::Path(Path { shape: PathShape::Square { side_m, altitude_m, .. }, .. })
            if side_m == 0.01 && altitude_m == 0.01
    ));
}

/// A timecode past a day is refused: the script's clock runs a day at most.
#[test]
fn timecodes_past_a_day_are_refused() {
    let c = check(
        "1 00:00:01 --> 24:00:00 MS on Rick front\n2 24:00:00 --> 999999:00:00 MS on Ilsa\n",
        &Options::default(),
    );
    let got: Vec<_> = c.diagnostics.iter().map(|d| d.code).collect();
    assert_eq!(got, [PslCode::BadTimecode], "{:?}", c.diagnostics);
    assert!(c.diagnostics[0].message.contains("999999:00:00"));
    assert!(c.diagnostics[0].help.is_some());
}

/// A waypoint number closer to 0 than 0.000000001 (a subnormal among them) is refused; 0
/// and -0 are 0.
#[test]
fn waypoint_numbers_too_close_to_zero_are_refused() {
    let dir = std::env::temp_dir().join(format!("dronecine-wp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tiny.csv"), "0, 0, 1\n1e-320, 1, 1\n").unwrap();
    std::fs::write(dir.join("zero.csv"), "-0, 0, 1\n1e-9, 1, 1\n").unwrap();
    let opts = Options {
        known_drones: &[],
        base_dir: Some(&dir),
    };
    let run = |file: &str| check(&format!("{HEAD}path waypoints \"{file}\" for 10s\n"), &opts);
    let tiny = run("tiny.csv");
    let got: Vec<_> = tiny.diagnostics.iter().map(|d| d.code).collect();
    assert_eq!(got, [PslCode::OutOfRange], "{:?}", tiny.diagnostics);
    assert!(tiny.diagnostics[0].message.contains("line 2"));
    let zero = run("zero.csv");
    assert!(!zero.has_errors(), "{:?}", zero.diagnostics);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_coverage_resolves_to_one_shot_of_its_pair() {
    let s = ok(
        "MS on A for 4s\nat 6s cut to coverage FS on A and B for 24s\ncoverage B and A for 20s\n",
    );
    assert_eq!(s.timeline.len(), 3);
    let ShotContent::Coverage(c) = &s.timeline[1].content else {
        panic!("{:?}", s.timeline[1].content);
    };
    assert_eq!(
        (c.a.as_str(), c.b.as_str(), c.size),
        ("A", "B", Some(dronecine_grammar::vocab::Size::FS))
    );
    let shot = &s.timeline[1];
    assert_eq!((shot.start_s, shot.end_s, shot.pinned), (6.0, 30.0, true));
    assert_eq!(shot.transition, Transition::Cut);
    assert_eq!(shot.coverage, None);
    let ShotContent::Coverage(c) = &s.timeline[2].content else {
        panic!("{:?}", s.timeline[2].content);
    };
    assert_eq!((c.a.as_str(), c.b.as_str(), c.size), ("B", "A", None));
    assert_eq!((s.timeline[2].start_s, s.timeline[2].end_s), (30.0, 50.0));
    let d = ok("MS on A for 4s\ndissolve to coverage A and B for 20s\n");
    assert_eq!(d.timeline[1].transition, Transition::Dissolve);
}

#[test]
fn a_coverage_is_checked() {
    use PslCode as P;
    assert_eq!(codes("coverage A and C for 20s\n"), [P::UnknownActor]);
    assert_eq!(codes("coverage A and A for 20s\n"), [P::TwoShotSameActor]);
    assert_eq!(codes("coverage A and B for 10s\n"), [P::CoverageTooShort]);
    assert!(COVERAGE_MIN_S > COVERAGE_PARTS as f64 * COVERAGE_MIN_HOLD_S);
    let at_least = format!("coverage A and B for {COVERAGE_MIN_S}s\n");
    assert!(codes(&at_least).is_empty());
    assert_eq!(codes("coverage A and B\n"), [P::MissingDuration]);
    assert_eq!(codes("coverage A and B over 20s\n"), [P::DurationKeyword]);
    assert_eq!(
        codes("MS on A for 4s\nthen dolly to coverage A and B for 20s\n"),
        [P::ThenToCoverage]
    );
    assert_eq!(
        codes("coverage A and B for 20s\nthen hold for 2s\n"),
        [P::ThenAfterCoverage]
    );
    assert_eq!(
        codes("coverage A and B for 20s\nthen dolly to MS on A over 2s\n"),
        [P::ThenAfterCoverage]
    );
    // `coverage` is reserved: it names no actor.
    assert_eq!(
        codes("actor coverage height 1.7m at (1, 1)\nMS on A for 2s\n"),
        [P::KeywordAsName]
    );
}

/// A composition printed as PSL text reads back as the same composition.
#[test]
fn a_composition_prints_as_the_psl_it_resolves_from() {
    let lines = [
        "MS on Rick 34backright MS on Ilsa 34left screen right",
        "MS on A",
        "high angle MLS on A and B",
        "low angle CU on B front screen (0.2, 0.1)",
        "MS on A screen left and B screen (0.4, -0.25)",
        "FS on A 34right screen center",
        "ECU on B back screen (-0.3333333333333333, 0)",
    ];
    let head =
        "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0)\nactor B height 1.65m at (2, 0)\n\
                actor Rick height 1.8m at (-1, 1)\nactor Ilsa height 1.6m at (1, 1)\n";
    for line in lines {
        let src = format!("{head}{line} for 4s\n");
        let c = check(&src, &Options::default());
        assert!(!c.has_errors(), "{line}: {:?}", c.diagnostics);
        let s = c.script.unwrap();
        let ShotContent::Composition(comp) = &s.timeline[0].content else {
            panic!("{line}");
        };
        let printed = comp.to_string();
        let again = check(&format!("{head}{printed} for 4s\n"), &Options::default());
        assert!(!again.has_errors(), "{printed}: {:?}", again.diagnostics);
        let s2 = again.script.unwrap();
        assert_eq!(
            &s2.timeline[0].content, &s.timeline[0].content,
            "{line} → {printed}"
        );
    }
    // The thirds are written as thirds.
    let s = ok("MS on A screen right and B screen left for 2s\n");
    assert_eq!(
        composition(&s, 0).to_string(),
        "MS on A screen right and B screen left"
    );
}
