//! `coverage A and B for Ns` expanded ([`dronecine_compiler::coverage::expand`]) and
//! compiled: the parts frame what they say, on one side of the line, and fill the line's
//! duration with the flights between them.

use dronecine_compiler::camera::Vec3;
use dronecine_compiler::compile::{compile, Compiled, Options};
use dronecine_compiler::coverage::expand;
use dronecine_compiler::framing::Side;
use dronecine_compiler::line;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_compiler::size;
use dronecine_compiler::CompileCode;
use dronecine_grammar::script::{Composition, Script, ShotContent, COVERAGE_PARTS};
use dronecine_math::wrap_angle_rad;
use dronecine_profile::Profile;

/// A dialogue: two actors 1.4 m apart facing each other (`shots/coverage.psl`).
const DIALOGUE: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
    actor Rick height 1.80m at (-0.7, 0) facing 0deg\n\
    actor Ilsa height 1.70m at (0.7, 0) facing 180deg\n";

fn script(text: &str) -> Script {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(text, &opts);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.expect("a script")
}

/// A script expanded and compiled: the expansion, its warnings, the compilation, and every
/// sample with the actors at its time.
struct Flown {
    expanded: Script,
    warnings: Vec<dronecine_diag::Diagnostic>,
    compiled: Compiled,
    samples: Vec<(Sample, Vec<ActorPose>)>,
}

fn flown(text: &str) -> Flown {
    let written = script(text);
    let profile = Profile::builtin("ardrone2").unwrap();
    let (expanded, warnings) = expand(&written, &profile);
    let mut samples = Vec::new();
    let compiled = compile(&expanded, &profile, &Options::default(), |s, a| {
        samples.push((*s, a.to_vec()));
        Ok::<(), ()>(())
    })
    .unwrap();
    Flown {
        expanded,
        warnings,
        compiled,
        samples,
    }
}

impl Flown {
    /// The expanded script's parts of the coverage whose first part is shot `first`.
    fn parts(&self, first: usize) -> Vec<(usize, &Composition)> {
        (first..first + COVERAGE_PARTS)
            .map(|i| match &self.expanded.timeline[i].content {
                ShotContent::Composition(c) => (i, c),
                other => panic!("shot {i} is {other:?}"),
            })
            .collect()
    }

    /// The samples of shot `index`'s hold, after its first half second (the settle).
    fn held(&self, index: usize) -> impl Iterator<Item = &(Sample, Vec<ActorPose>)> {
        let t = self
            .compiled
            .timings
            .iter()
            .find(|t| t.index == index)
            .expect("flown");
        let (from, to) = (t.start_s + 0.5, t.end_s);
        self.samples
            .iter()
            .filter(move |(s, _)| s.t_s >= from && s.t_s <= to && s.shot == index)
    }

    /// How long the coverage whose first part is shot `first` lasted as flown.
    fn length_s(&self, first: usize) -> f64 {
        let at = |i: usize| self.compiled.timings.iter().find(|t| t.index == i).unwrap();
        at(first + COVERAGE_PARTS - 1).end_s - at(first).start_s
    }
}

fn index(names: &[&str], name: &str) -> usize {
    names.iter().position(|n| *n == name).unwrap()
}

/// The side of the line from `a` to `b` a camera at `c` stands on.
fn side(a: usize, b: usize, actors: &[ActorPose], c: &Vec3) -> Option<Side> {
    let s = line::side_of((a.min(b), a.max(b)), actors, c)?;
    Some(if a <= b { s } else { s.swapped() })
}

/// Checks every part of the coverage of `a` and `b` whose first part is shot `first`: held
/// on one side of the line (`want`, or the establishing two-shot's; a single may stand on
/// the line), the two-shot on the bisector, each over-the-shoulder's camera within 22.5° of
/// both profiles from each actor. The side.
fn check_parts(
    f: &Flown,
    first: usize,
    names: &[&str],
    (a, b): (&str, &str),
    want: Option<Side>,
) -> Side {
    let (ia, ib) = (index(names, a), index(names, b));
    let want = want.unwrap_or_else(|| {
        let (s, actors) = f.held(first).next().unwrap();
        side(ia, ib, actors, &Vec3::from(s.position_m)).unwrap()
    });
    let heights: Vec<f64> = f
        .expanded
        .scene
        .as_ref()
        .unwrap()
        .actors
        .iter()
        .map(|x| x.height_m)
        .collect();
    for (i, comp) in f.parts(first) {
        let subjects: Vec<_> = comp.framings.iter().flat_map(|fr| &fr.subjects).collect();
        let mut ticks = 0;
        for (s, actors) in f.held(i) {
            ticks += 1;
            let c = Vec3::from(s.position_m);
            let got = side(ia, ib, actors, &c);
            if subjects.len() == 2 {
                assert_eq!(got, Some(want), "shot {i} ({comp}) at {:.2} s", s.t_s);
            } else {
                assert_ne!(
                    got,
                    Some(want.swapped()),
                    "shot {i} ({comp}) at {:.2} s",
                    s.t_s
                );
            }
            for subject in &subjects {
                let Some(p) = subject.profile else { continue };
                let k = index(names, &subject.actor);
                let x = &actors[k];
                let bearing = (c.y - x.position_m[1]).atan2(c.x - x.position_m[0]);
                let off = wrap_angle_rad(bearing - x.facing_rad - p.azimuth_rad()).abs();
                assert!(
                    off.to_degrees() <= 22.5,
                    "shot {i} ({comp}): {} seen {:.1}° from {}",
                    subject.actor,
                    off.to_degrees(),
                    p.as_str()
                );
            }
            if comp.framings.len() == 1 && subjects.len() == 2 {
                let size = comp.framings[0].size;
                let centre = |k: usize| {
                    let (lo, hi) = size::band(size, heights[k]);
                    let p = actors[k].position_m;
                    Vec3::new(p[0], p[1], (lo + hi) / 2.0)
                };
                let (da, db) = ((c - centre(ia)).norm(), (c - centre(ib)).norm());
                assert!(
                    (da - db).abs() < 0.03,
                    "two-shot {da:.3} m and {db:.3} m from the two"
                );
            }
        }
        assert!(ticks > 50, "shot {i} held {ticks} ticks");
    }
    want
}

#[test]
fn a_dialogues_coverage_frames_what_it_says_on_one_side_of_the_line() {
    let f = flown(&format!("{DIALOGUE}coverage Rick and Ilsa for 30s\n"));
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert_eq!(f.expanded.timeline.len(), COVERAGE_PARTS);
    // Facing each other, nothing before or after: the right side of Rick → Ilsa.
    check_parts(
        &f,
        0,
        &["Rick", "Ilsa"],
        ("Rick", "Ilsa"),
        Some(Side::Right),
    );
    let length_s = f.length_s(0);
    assert!((length_s - 30.0).abs() <= 0.05, "{length_s} s");
    let others: Vec<_> = (f.compiled.diagnostics.iter())
        .filter(|d| d.code != CompileCode::Reposition)
        .collect();
    assert!(others.is_empty(), "{others:#?}");
    // The five shots the classic pattern names, each once.
    let kinds: Vec<(usize, usize)> = f
        .parts(0)
        .iter()
        .map(|(_, c)| (c.framings.len(), c.framings[0].subjects.len()))
        .collect();
    let count = |k| kinds.iter().filter(|x| **x == k).count();
    assert_eq!(
        kinds[0],
        (1, 2),
        "the establishing two-shot first: {kinds:?}"
    );
    assert_eq!((count((1, 2)), count((2, 1)), count((1, 1))), (1, 2, 2));
    // Mirrored profiles: over Rick's shoulder his back three-quarter and her front one.
    let ots: Vec<String> = f
        .parts(0)
        .iter()
        .filter(|(_, c)| c.framings.len() == 2)
        .map(|(_, c)| {
            c.framings
                .iter()
                .map(|fr| {
                    format!(
                        "{} {}",
                        fr.subjects[0].actor,
                        fr.subjects[0].profile.unwrap().as_str()
                    )
                })
                .collect::<Vec<_>>()
                .join(" / ")
        })
        .collect();
    assert!(
        ots.contains(&"Rick 34backright / Ilsa 34left".to_string()),
        "{ots:?}"
    );
    assert!(
        ots.contains(&"Ilsa 34backleft / Rick 34right".to_string()),
        "{ots:?}"
    );
}

/// A coverage after a shot that fixes the other side of the line keeps to it.
#[test]
fn a_coverage_keeps_to_the_side_the_shot_before_established() {
    let f = flown(&format!(
        "{DIALOGUE}MS on Rick 34left for 4s\ncut to coverage Rick and Ilsa for 32s\n"
    ));
    let (s, actors) = f.held(0).next().unwrap();
    assert_eq!(
        side(0, 1, actors, &Vec3::from(s.position_m)),
        Some(Side::Left)
    );
    check_parts(&f, 1, &["Rick", "Ilsa"], ("Rick", "Ilsa"), Some(Side::Left));
    let length_s = f.length_s(1);
    assert!((length_s - 32.0).abs() <= 0.05, "{length_s} s");
    assert!(
        !f.compiled
            .diagnostics
            .iter()
            .any(|d| d.code == CompileCode::SizeOff),
        "{:#?}",
        f.compiled.diagnostics
    );
}

/// Actors who do not face each other, one of them walking during the coverage, written
/// with B first and a size for the two-shot: the profiles follow the facings, the two-shot
/// keeps its size, and the timing still fills the line.
#[test]
fn a_coverage_follows_any_facings_and_a_walk() {
    let f = flown(
        "stage 10m x 8m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (-1, 0.5) facing -20deg\n\
         actor B height 1.65m at (1, -0.2) facing 170deg\n\
         at 3s A walks to (-0.6, 0.3) over 3s\n\
         coverage FS on B and A for 36s\n",
    );
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let parts = f.parts(0);
    assert_eq!(parts[0].1.to_string(), "FS on B and A");
    check_parts(&f, 0, &["A", "B"], ("B", "A"), None);
    let length_s = f.length_s(0);
    assert!((length_s - 36.0).abs() <= 0.05, "{length_s} s");
    assert!(!f.compiled.has_errors(), "{:#?}", f.compiled.diagnostics);
}

/// Without a side established, a coverage takes the side whose cameras fit in the stage:
/// against a wall behind them, the side away from it (the left of Rick → Ilsa here), and
/// the side the actors face when both fit.
#[test]
fn a_coverage_takes_the_side_that_fits_else_the_one_the_actors_face() {
    let f = flown(
        "stage 8m x 6m x 3m
drone ardrone2
         actor Rick height 1.80m at (-0.7, -2.3) facing 0deg
         actor Ilsa height 1.70m at (0.7, -2.3) facing 180deg
         coverage Rick and Ilsa for 30s
",
    );
    check_parts(&f, 0, &["Rick", "Ilsa"], ("Rick", "Ilsa"), Some(Side::Left));
    let f = flown(
        "stage 8m x 6m x 3m
drone ardrone2
         actor Rick height 1.80m at (-0.8, 0) facing 90deg
         actor Ilsa height 1.70m at (0.8, 0) facing 90deg
         coverage Rick and Ilsa for 30s
",
    );
    // Both face +y, the left of Rick → Ilsa: the camera sees their faces.
    check_parts(&f, 0, &["Rick", "Ilsa"], ("Rick", "Ilsa"), Some(Side::Left));
}

/// Too short for the flights between its shots: each is held its shortest, and the warning
/// says how long the coverage needs.
#[test]
fn a_coverage_too_short_for_its_flights_says_how_long_it_needs() {
    let f = flown(&format!("{DIALOGUE}coverage Rick and Ilsa for 16s\n"));
    let holds: Vec<f64> = (f.expanded.timeline.iter())
        .map(|s| s.end_s - s.start_s)
        .collect();
    assert_eq!(holds, [1.5; COVERAGE_PARTS], "{holds:?}");
    let [w] = f.warnings.as_slice() else {
        panic!("{:?}", f.warnings);
    };
    assert_eq!(w.code, CompileCode::CoverageOverruns);
    let length_s = f.length_s(0);
    assert!(length_s > 16.05, "{length_s}");
    let needed = (length_s).ceil();
    let help = w.help.as_deref().unwrap();
    assert!(
        help.contains(&format!("`for {needed}s`")),
        "{help} ({length_s} s)"
    );
    assert!(
        w.message.contains(&format!("{length_s:.1} s")),
        "{}",
        w.message
    );
}

/// The expansion is a function of the script and the profile: twice the same, bit for bit
/// (a replay rebuilds it from the log's script), and a script without a coverage comes back
/// as it is.
#[test]
fn the_expansion_is_deterministic() {
    let profile = Profile::builtin("ardrone2").unwrap();
    let s = script(&format!(
        "{DIALOGUE}MS on Ilsa for 3s\ncoverage Ilsa and Rick for 30s\ncut to MS on Rick for 3s\n"
    ));
    let (x, _) = expand(&s, &profile);
    let (y, _) = expand(&s, &profile);
    assert_eq!(
        serde_json::to_string(&x).unwrap(),
        serde_json::to_string(&y).unwrap()
    );
    assert_eq!(x.timeline.len(), 2 + COVERAGE_PARTS);
    assert!(x
        .timeline
        .iter()
        .skip(1)
        .take(COVERAGE_PARTS)
        .all(|p| p.span == s.timeline[1].span));
    let plain = script(&format!("{DIALOGUE}MS on Ilsa for 3s\n"));
    assert_eq!(expand(&plain, &profile).0, plain);
}

/// A director given a coverage it was not expanded for flies its establishing two-shot,
/// without a panic.
#[test]
fn an_unexpanded_coverage_flies_its_two_shot() {
    let s = script(&format!(
        "{DIALOGUE}coverage MLS on Rick and Ilsa for 20s\n"
    ));
    let profile = Profile::builtin("ardrone2").unwrap();
    let c = compile(&s, &profile, &Options::default(), |_, _| Ok::<(), ()>(())).unwrap();
    assert!(!c.has_errors(), "{:#?}", c.diagnostics);
    assert_eq!(c.timings.len(), 1);
    assert!((c.timings[0].end_s - 20.0).abs() < 1e-9);
}
