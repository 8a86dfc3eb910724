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
