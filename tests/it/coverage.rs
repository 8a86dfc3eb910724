//! A `coverage` line from the command line: `fmt --expand` prints PSL that flies the same
//! flight, the shipped dialogue compiles with nothing to report but its flights, the
//! storyboard names each part, and a flight of it replays bit for bit.

use crate::common::{dronecine, stderr, stdout, temp_dir, workspace};
use dronecine_compiler::compile::Options;
use dronecine_compiler::reference::Sample;
use dronecine_grammar::script::{Script, COVERAGE_PARTS};
use dronecine_profile::Profile;

fn script(text: &str) -> Script {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(text, &opts);
    assert!(!checked.has_errors(), "{text}\n{:?}", checked.diagnostics);
    checked.script.unwrap()
}

/// The samples of `script` as the AR.Drone flies it (its coverages expanded), with the
/// compiler's diagnostic codes.
fn flown(script: &Script) -> (Vec<Sample>, Vec<String>) {
    let profile = Profile::builtin("ardrone2").unwrap();
    let (expanded, _) = dronecine_compiler::coverage::expand(script, &profile);
    let mut samples = Vec::new();
    let c = dronecine_film::compile(&expanded, &profile, &Options::default(), |s, _| {
        samples.push(*s);
        Ok::<(), ()>(())
    })
    .unwrap();
    let codes = c.diagnostics.iter().map(|d| d.code.to_string()).collect();
    (samples, codes)
}

/// `fmt --expand` prints the coverage's shots, and the text it prints flies the flight the
/// coverage line does, sample for sample: a pinned coverage after a shot, a dissolve into
/// another, and a shot after both.
#[test]
fn fmt_expand_prints_psl_that_flies_the_same_flight() {
    let dir = temp_dir("expand");
    let path = dir.join("scene.psl");
    let text = "stage 8m x 6m x 3m\ndrone ardrone2\n\
        actor Rick height 1.80m at (-0.7, 0) facing 0deg\n\
        actor Ilsa height 1.70m at (0.7, 0) facing 180deg\n\
        MS on Rick front for 3s\n\
        at 6s cut to coverage Ilsa and Rick for 30s  # the talk\n\
        dissolve to coverage MLS on Rick and Ilsa for 28s\n\
        cut to MS on Ilsa front for 3s\n";
    std::fs::write(&path, text).unwrap();
    let o = dronecine(&["fmt", "--expand", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let expanded = stdout(&o);
    assert!(
        expanded.contains(
            "# at 6s cut to coverage Ilsa and Rick for 30s: expanded into 5 shots the talk\n"
        ),
        "{expanded}"
    );
    assert!(
        expanded.contains("\nat 6s cut to MLS on Ilsa and Rick for "),
        "{expanded}"
    );
    assert!(expanded.contains("\ndissolve to "), "{expanded}");
    assert!(expanded.contains("# 5/5: "), "{expanded}");
    let statements = expanded.lines().map(|l| l.split('#').next().unwrap_or(""));
    assert!(
        statements.clone().all(|l| !l.contains("coverage")),
        "{expanded}"
    );
    // Canonical: `fmt` leaves it as it is.
    assert_eq!(dronecine_grammar::format(&expanded).unwrap(), expanded);
    let written = script(text);
    let printed = script(&expanded);
    assert_eq!(printed.timeline.len(), 2 + 2 * COVERAGE_PARTS);
    let (a, codes_a) = flown(&written);
    let (b, codes_b) = flown(&printed);
    // The same to the rounding: after the first coverage the written starts move (its parts
    // are written back to back, the line after it started where the line ended), and a
    // shot's duration is its end less its start, the same number to a few ulps.
    assert_eq!(a.len(), b.len());
    let mut worst_m = 0.0f64;
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((x.t_s, x.shot), (y.t_s, y.shot));
        for i in 0..3 {
            worst_m = worst_m.max((x.position_m[i] - y.position_m[i]).abs());
        }
        assert!(
            (x.heading_rad - y.heading_rad).abs() < 1e-9,
            "at {} s",
            x.t_s
        );
    }
    assert!(worst_m < 1e-9, "{worst_m} m apart");
    // Up to the second coverage, where nothing moved, bit for bit.
    let second = a.iter().position(|s| s.shot == 1 + COVERAGE_PARTS).unwrap();
    assert_eq!(a[..second], b[..second]);
    assert_eq!(codes_a, codes_b);
    // The file is not changed.
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
    // One script at a time.
    let o = dronecine(&["fmt", "--expand", "shots/coverage.psl", "shots/square.psl"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--expand prints one script"),
        "{}",
        stderr(&o)
    );
}

/// The shipped dialogue: no warning but the repositioning flights' (no `film::` finding,
/// no size off), and the storyboard says which part of the coverage each shot is.
#[test]
fn the_shipped_coverage_flies_clean_and_its_storyboard_names_the_parts() {
    let text = std::fs::read_to_string(workspace().join("shots/coverage.psl")).unwrap();
    let (_, codes) = flown(&script(&text));
    assert!(codes.len() >= COVERAGE_PARTS - 1, "{codes:?}");
    assert!(
        codes.iter().all(|c| c == "compile::reposition"),
        "{codes:?}"
    );
    let dir = temp_dir("coverage-preview");
    let out = dir.join("coverage.mcap");
    let preview = dir.join("preview");
    let o = dronecine(&[
        "compile",
        "shots/coverage.psl",
        "-o",
        out.to_str().unwrap(),
        "--preview",
        preview.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("5 shots"), "{}", stdout(&o));
    let storyboard = std::fs::read_to_string(preview.join("storyboard.svg")).unwrap();
    for part in 1..=COVERAGE_PARTS {
        let caption = format!("part {part}/{COVERAGE_PARTS} of the coverage of Rick and Ilsa: ");
        assert_eq!(storyboard.matches(&caption).count(), 1, "{caption}");
    }
}

/// A flight of a coverage: its report names each part, and replay, which expands the
/// logged script again, reproduces every tick and gives the same report.
#[test]
fn a_flown_coverage_replays_bit_for_bit() {
    let dir = temp_dir("coverage-shoot");
    let log = dir.join("coverage.mcap");
    let log_s = log.to_str().unwrap();
    let o = dronecine(&[
        "shoot",
        "shots/coverage.psl",
        "--log",
        log_s,
        "--report",
        "json",
        "--seed",
        "3",
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["completed"], true, "{r}");
    let labels: Vec<&str> = (r["shots"].as_array().unwrap().iter())
        .map(|s| s["label"].as_str().unwrap())
        .collect();
    assert_eq!(labels.len(), COVERAGE_PARTS, "{labels:?}");
    for (k, label) in labels.iter().enumerate() {
        let part = format!(
            "part {}/{COVERAGE_PARTS} of the coverage of Rick and Ilsa: ",
            k + 1
        );
        assert!(label.starts_with(&part), "{label}");
    }
    let o = dronecine(&["replay", log_s, "--report", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("reproduce the logged commands exactly"));
    let replayed: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(replayed["mismatches"], 0);
    assert_eq!(replayed["unreplayed"], 0);
    assert!(replayed["ticks"].as_u64().unwrap() > 3000, "{replayed}");
    assert_eq!(replayed["report"], r, "replay gives the flight's report");
}
