//! The shipped example scripts: each resolves without a diagnostic, its resolved `Script` is
//! pinned by a snapshot, and the scripts mean what their comments say.

use dronecine_grammar::script::*;
use dronecine_grammar::vocab::{MoveKind, Profile, Size};

fn script(name: &str) -> Script {
    let path = crate::common::workspace().join("shots").join(name);
    let (src, checked) = crate::common::check_path(&path);
    assert!(
        checked.diagnostics.is_empty(),
        "{name}:\n{}",
        dronecine_diag::render(name, &src, &checked.diagnostics, false, 100)
    );
    checked.script.expect("no errors, so a script")
}

#[test]
fn every_shot_script_resolves_and_matches_its_snapshot() {
    insta::glob!("../../shots", "*.psl", |path| {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        insta::assert_yaml_snapshot!(script(&name));
    });
}

#[test]
fn the_paper_test_flights_are_paths() {
    let s = script("square.psl");
    assert_eq!(s.timeline.len(), 1);
    match &s.timeline[0].content {
        ShotContent::Path(Path {
            shape:
                PathShape::Square {
                    side_m,
                    center_m,
                    altitude_m,
                    clockwise,
                },
            looking_at: None,
        }) => {
            assert_eq!(
                (*side_m, *center_m, *altitude_m, *clockwise),
                (2.0, [0.0, 0.0], 1.5, false)
            );
        }
        other => panic!("expected a square, got {other:?}"),
    }
    assert_eq!(s.duration_s, 20.0);

    let s = script("helix.psl");
    match &s.timeline[0].content {
        ShotContent::Path(Path {
            shape:
                PathShape::Helix {
                    radius_m,
                    from_m,
                    to_m,
                    turns,
                    ..
                },
            ..
        }) => {
            assert_eq!((*radius_m, *from_m, *to_m, *turns), (1.5, 1.0, 2.5, 2.0));
        }
        other => panic!("expected a helix, got {other:?}"),
    }
}

#[test]
fn the_paper_transition_goes_from_front_to_34backright() {
    let s = script("transition.psl");
    let comp = |i: usize| match &s.timeline[i].content {
        ShotContent::Composition(c) => c.clone(),
        other => panic!("expected a composition, got {other:?}"),
    };
    let first = comp(0);
    assert_eq!(first.framings[0].size, Size::MS);
    assert_eq!(first.framings[0].subjects[0].profile, Some(Profile::Front));
    let second = comp(1);
    assert_eq!(
        second.framings[0].subjects[0].profile,
        Some(Profile::ThreeQuarterBackRight)
    );
    assert!(matches!(
        s.timeline[1].transition,
        Transition::Move {
            kind: MoveKind::Dolly,
            ..
        }
    ));
    assert_eq!((s.timeline[1].start_s, s.timeline[1].end_s), (4.0, 10.0));
    // `then hold` keeps the composition it continues.
    assert_eq!(comp(2), second);
}

#[test]
fn two_actors_move_while_the_two_shot_holds() {
    let s = script("two-actors.psl");
    let scene = s.scene.as_ref().unwrap();
    assert_eq!(scene.actors.len(), 2);
    let walkers: std::collections::BTreeSet<&str> = scene
        .blocking
        .iter()
        .filter(|m| matches!(m.action, Action::Walk { .. }))
        .map(|m| m.actor.as_str())
        .collect();
    assert_eq!(walkers, ["A", "B"].into_iter().collect());
    let hold = &s.timeline[0];
    let last_move_end = scene.blocking.iter().map(|m| m.end_s).fold(0.0, f64::max);
    assert!(
        hold.end_s >= last_move_end,
        "the framing is held through every movement"
    );
    match &hold.content {
        ShotContent::Composition(c) => {
            assert_eq!(c.framings.len(), 1);
            assert_eq!(c.actors().collect::<Vec<_>>(), ["A", "B"]);
        }
        other => panic!("expected a two-shot, got {other:?}"),
    }
}

#[test]
fn the_long_scene_uses_most_of_the_language() {
    let s = script("scene.psl");
    let scene = s.scene.as_ref().unwrap();
    assert!(scene.lens.is_some() && scene.drone.is_some());
    assert!(scene
        .blocking
        .iter()
        .any(|m| matches!(m.action, Action::Walk { .. })));
    assert!(scene
        .blocking
        .iter()
        .any(|m| matches!(m.action, Action::Turn { .. })));
    let mut moves = std::collections::BTreeSet::new();
    let (mut cut, mut dissolve, mut pinned, mut ots, mut two, mut orbit, mut waypoints) =
        (false, false, false, false, false, false, false);
    let mut angles = std::collections::BTreeSet::new();
    let mut screen = false;
    for shot in &s.timeline {
        pinned |= shot.pinned;
        match &shot.transition {
            Transition::Cut => cut = true,
            Transition::Dissolve => dissolve = true,
            Transition::Move { kind, .. } => {
                moves.insert(kind.as_str());
            }
        }
        match &shot.content {
            ShotContent::Composition(c) => {
                angles.insert(c.camera_angle.as_str());
                ots |= c.framings.len() == 2;
                two |= c.framings.iter().any(|f| f.subjects.len() == 2);
                screen |= c
                    .framings
                    .iter()
                    .flat_map(|f| &f.subjects)
                    .any(|x| x.screen_x.is_some());
            }
            ShotContent::Path(p) => match p.shape {
                PathShape::Orbit { .. } => orbit = true,
                PathShape::Waypoints { ref points_m, .. } => waypoints = points_m.len() == 5,
                _ => {}
            },
            ShotContent::Coverage(_) => {}
        }
    }
    assert!(cut && dissolve && pinned && ots && two && orbit && waypoints && screen);
    assert!(moves.len() >= 4, "moves used: {moves:?}");
    assert_eq!(angles.len(), 3, "all three camera angles: {angles:?}");
}

#[test]
fn the_annotation_needs_no_scene_and_takes_times_from_timecodes() {
    let s = script("annotation.psl");
    assert!(s.is_annotation());
    assert_eq!(s.cast, ["Rick", "Ilsa"]);
    assert_eq!((s.timeline[0].start_s, s.timeline[0].end_s), (1.0, 5.0));
    // 00:01:00 ends the last entry, which started at 00:00:26.
    assert_eq!(s.timeline.last().unwrap().end_s, 60.0);
}

/// The psl blocks of `docs/language.md`.
fn language_examples() -> Vec<String> {
    let doc = std::fs::read_to_string(crate::common::workspace().join("docs/language.md")).unwrap();
    doc.split("```psl\n")
        .skip(1)
        .filter_map(|b| b.split("```").next().map(str::to_string))
        .collect()
}

/// Every whole scene of the language's page (a block with a `stage` line) checks without
/// an error, its files found next to the shipped scripts; its coverage example is the
/// shipped one, and the expansion the page prints is the one `fmt --expand` prints.
#[test]
fn the_language_pages_scenes_check_and_its_coverage_expands_as_it_says() {
    let scenes: Vec<String> = language_examples()
        .into_iter()
        .filter(|b| b.lines().any(|l| l.starts_with("stage ")))
        .collect();
    assert!(scenes.len() >= 4, "{}", scenes.len());
    let base = crate::common::workspace().join("shots");
    for text in &scenes {
        let opts = dronecine_grammar::Options {
            known_drones: dronecine_profile::BUILTIN_NAMES,
            base_dir: Some(&base),
        };
        let c = dronecine_grammar::check(text, &opts);
        assert!(!c.has_errors(), "{text}\n{:?}", c.diagnostics);
    }
    let coverage = scenes
        .iter()
        .find(|b| b.contains("\ncoverage "))
        .expect("a coverage example");
    let shipped =
        std::fs::read_to_string(crate::common::workspace().join("shots/coverage.psl")).unwrap();
    let statements = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
            .map(str::to_string)
            .collect()
    };
    assert_eq!(statements(coverage), statements(&shipped));
    let doc = std::fs::read_to_string(crate::common::workspace().join("docs/language.md")).unwrap();
    let o = crate::common::dronecine(&["fmt", "--expand", "shots/coverage.psl"]);
    assert!(o.status.success(), "{}", crate::common::stderr(&o));
    let printed = crate::common::stdout(&o);
    let from = printed
        .find("# coverage Rick and Ilsa")
        .expect("the expansion's comment");
    assert!(
        doc.contains(&printed[from..]),
        "docs/language.md does not show:\n{}",
        &printed[from..]
    );
}
