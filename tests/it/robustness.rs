//! No input panics: arbitrary bytes, soups of PSL words, generated scripts, and the named
//! pathological cases (empty, binary, 10 MB lines, thousands of nested or repeated tokens).
//! Generated valid scripts also check the formatter: idempotent and meaning-preserving.

use dronecine_diag as diag;
use dronecine_grammar::PslCode;
use dronecine_grammar::{check, decode, format, Options};
use proptest::prelude::*;

/// Everything a user-facing command does with a file's bytes.
fn exercise(bytes: &[u8]) {
    let (text, diags) = match decode(bytes) {
        Ok(src) => {
            let checked = check(src, &Options::default());
            for d in &checked.diagnostics {
                assert!(d.span.start <= d.span.end && d.span.end <= src.len());
                assert!(src.is_char_boundary(d.span.start) && src.is_char_boundary(d.span.end));
            }
            if let Ok(once) = format(src) {
                assert_eq!(
                    format(&once).as_deref(),
                    Ok(once.as_str()),
                    "fmt not idempotent"
                );
            }
            (src.to_string(), checked.diagnostics)
        }
        Err((lossy, diags)) => (lossy, diags),
    };
    let _ = diag::render("fuzz.psl", &text, &diags, false, 100);
    let _ = diag::to_json("fuzz.psl", &text, &diags);
}

const WORDS: &[&str] = &[
    "MS",
    "CU",
    "ECU",
    "MLS",
    "on",
    "and",
    "A",
    "B",
    "front",
    "34backright",
    "left",
    "screen",
    "center",
    "cut",
    "to",
    "then",
    "as",
    "dolly",
    "follow",
    "hold",
    "for",
    "over",
    "4s",
    "0s",
    "-1s",
    "2m",
    "90deg",
    "(",
    ")",
    ",",
    "(0, 0)",
    "stage",
    "8m",
    "x",
    "lens",
    "drone",
    "ardrone2",
    "\"f.toml\"",
    "actor",
    "height",
    "at",
    "facing",
    "walks",
    "turns",
    "path",
    "coverage",
    "square",
    "helix",
    "orbit",
    "waypoints",
    "side",
    "radius",
    "altitude",
    "from",
    "turns",
    "2",
    "around",
    "looking",
    "high",
    "angle",
    "eye",
    "level",
    "#",
    "12",
    "00:01:03",
    "-->",
    "00:01:60",
    "\n",
    "\r\n",
    "\t",
    "é",
    "\u{0}",
    "\u{feff}",
    "1e999",
    "9999999999999999999999",
];

fn soup() -> impl Strategy<Value = String> {
    prop::collection::vec(prop::sample::select(WORDS), 0..60).prop_map(|w| w.join(" "))
}

/// A valid script from pieces, with random spacing and optional `on`.
fn valid_script() -> impl Strategy<Value = String> {
    let shot = (
        prop::sample::select(&["MS", "CU", "MCU", "FS", "LS"][..]),
        any::<bool>(),
        prop::sample::select(&["A", "B", "A and B", "B and A"][..]),
        prop::sample::select(&["", " front", " 34left", " back", " 34backright"][..]),
        prop::sample::select(&["", " screen left", " screen (0.2, -0.1)"][..]),
        1u32..20,
        prop::sample::select(
            &[
                "cut to ",
                "dissolve to ",
                "then dolly to ",
                "then as A sits pan to ",
                "",
            ][..],
        ),
    )
        .prop_map(|(size, on, actors, profile, screen, secs, trans)| {
            let on = if on { " on " } else { " " };
            let actors = if actors.contains(" and ") {
                actors.to_string()
            } else {
                format!("{actors}{profile}")
            };
            let kw = if trans.starts_with("then") {
                "over"
            } else {
                "for"
            };
            format!("{trans}{size}{on}{actors}{screen} {kw} {secs}s")
        });
    (prop::collection::vec(shot, 1..12), prop::sample::select(&[" ", "  ", "\t"][..])).prop_map(|(shots, sp)| {
        let mut s = format!("stage 8m{sp}x 6m x 3m\nactor A height 1.8m at (0, 0) facing 0deg  # A\nactor B height 1.6m at (2, 0) facing 180deg\n");
        for (i, shot) in shots.iter().enumerate() {
            let shot = if i == 0 { shot.replace("then dolly to ", "").replace("then as A sits pan to ", "") } else { shot.clone() };
            let shot = if i == 0 { shot.replace(" over ", " for ") } else { shot };
            s.push_str(&shot.replace(' ', sp));
            s.push('\n');
        }
        s
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        exercise(&bytes);
    }

    #[test]
    fn arbitrary_text_never_panics(s in "\\PC{0,300}") {
        exercise(s.as_bytes());
    }

    #[test]
    fn word_soup_never_panics(s in soup()) {
        exercise(s.as_bytes());
    }

    #[test]
    fn generated_scripts_check_and_format_round_trip(src in valid_script()) {
        let checked = check(&src, &Options::default());
        prop_assert!(!checked.has_errors(), "{src}\n{:?}", checked.diagnostics);
        let once = format(&src).expect("parses");
        prop_assert_eq!(format(&once).expect("parses"), once.clone());
        let again = check(&once, &Options::default());
        prop_assert_eq!(
            crate::common::without_spans(serde_json::to_value(checked.script).unwrap()),
            crate::common::without_spans(serde_json::to_value(again.script).unwrap())
        );
    }
}

#[test]
fn empty_and_blank_files() {
    for src in ["", "\n", "   \n\t\n", "# only a comment\n", "\u{feff}"] {
        let c = check(src, &Options::default());
        assert!(!c.has_errors(), "{src:?}: {:?}", c.diagnostics);
        exercise(src.as_bytes());
    }
}

#[test]
fn a_ten_megabyte_line() {
    let mut s = String::from(
        "stage 8m x 6m x 3m\nactor A height 1.8m at (0, 0) facing 0deg\nMS on A front for 4s ",
    );
    s.push_str(&"x".repeat(10 << 20));
    let c = check(&s, &Options::default());
    assert_eq!(c.diagnostics.len(), 1);
    let out = diag::render("big.psl", &s, &c.diagnostics, false, 100);
    assert!(
        out.len() < 4_000,
        "the rendering quotes a window, not 10 MB ({} bytes)",
        out.len()
    );

    let digits = format!("MS on A front for {}s", "9".repeat(10 << 20));
    exercise(digits.as_bytes());
    let name = format!("actor {} height 1.8m at (0, 0)", "N".repeat(10 << 20));
    exercise(name.as_bytes());
}

#[test]
fn thousands_of_nested_or_repeated_tokens() {
    let header = "stage 8m x 6m x 3m\nactor A height 1.8m at (0, 0) facing 0deg\nactor B height 1.8m at (1, 0) facing 0deg\n";
    let nested = format!(
        "{header}actor C height 1m at {}0, 0{} facing 0deg\n",
        "(".repeat(50_000),
        ")".repeat(50_000)
    );
    exercise(nested.as_bytes());
    let ands = format!("{header}MS on A{} for 4s\n", " and B".repeat(50_000));
    let c = check(&ands, &Options::default());
    assert!(c.has_errors(), "B appears many times");
    exercise(ands.as_bytes());
    let framings = format!("{header}{} for 4s\n", "MS on A ".repeat(50_000));
    exercise(framings.as_bytes());
    let lines = format!("{header}{}", "then hold for 1s\n".repeat(50_000));
    exercise(lines.as_bytes());
    let thens = format!("{header}{}", "then as ".repeat(50_000));
    exercise(thens.as_bytes());
    let quotes = "\"".repeat(100_000);
    exercise(quotes.as_bytes());
}

#[test]
fn binary_input_is_reported_not_parsed() {
    let bytes: Vec<u8> = (0..=255u8).cycle().take(4096).collect();
    let err = decode(&bytes).unwrap_err();
    assert!(!err.1.is_empty() && err.1.len() <= 10);
    assert!(err.1.iter().all(|d| d.code == PslCode::InvalidUtf8));
    exercise(&bytes);
}

/// Numbers as a script may write them at the extremes: 0 and -0, subnormals, 1e-12, the
/// edges of each range (1 ms, 1 cm, 1000 m, a day, nine digits) and past them, 1e308.
fn extreme_number() -> impl Strategy<Value = String> {
    let subnormal = format!("0.{}5", "0".repeat(323));
    let huge = format!("1{}", "0".repeat(308));
    let fixed: Vec<String> = [
        "0",
        "-0",
        "0.000000000001",
        "0.000000001",
        "0.0009999",
        "0.001",
        "0.002",
        "0.0099",
        "0.01",
        "0.05",
        "1",
        "2",
        "4",
        "100",
        "100.5",
        "999.999",
        "1000",
        "1000.001",
        "86400",
        "86400.001",
        "999999999",
        "1000000000",
        "-1",
        "-0.000000001",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([subnormal, huge])
    .collect();
    prop_oneof![
        3 => prop::sample::select(fixed),
        // Any number between, written as Rust writes it: in full, never with an exponent.
        1 => (-2000.0f64..2000.0).prop_map(|v| format!("{v}")),
    ]
}

/// A scene whose durations and path numbers are ordinary but for one to three, which come
/// from [`extreme_number`].
fn extreme_script() -> impl Strategy<Value = String> {
    // side or radius, centre x and y, altitude or start height, end height, turns, the
    // path's duration, the first shot's, the walk's start and its duration, A's facing.
    const ORDINARY: [&str; 11] = [
        "2", "0.5", "-0.5", "1.5", "2.5", "1", "10", "4", "1", "2", "0",
    ];
    (
        prop::sample::select(&["8m x 6m x 3m", "1000m x 1000m x 1000m"][..]),
        0usize..6,
        prop::collection::vec((0..ORDINARY.len(), extreme_number()), 1..=3),
    )
        .prop_map(|(stage, shape, extremes)| {
            let mut n: Vec<String> = ORDINARY.iter().map(|s| s.to_string()).collect();
            for (slot, value) in extremes {
                n[slot] = value;
            }
            let [a, b, c, d, e, f, t0, t1, t2, t3, facing] = &n[..] else {
                unreachable!()
            };
            let path = match shape {
                0 => format!("path square side {a}m center ({b}, {c}) altitude {d}m for {t0}s"),
                1 => format!(
                    "path helix radius {a}m center ({b}, {c}) from {d}m to {e}m turns {f} for {t0}s"
                ),
                2 => format!(
                    "path orbit around A radius {a}m altitude {d}m turns {f} clockwise for {t0}s"
                ),
                3 => format!(
                    "path orbit radius {a}m center ({b}, {c}) altitude {d}m turns {f} for {t0}s"
                ),
                4 => format!("MS on A front for {t0}s\nthen dolly to MS on A back over {t3}s"),
                _ => format!("MS on A front screen ({b}, {c}) for {t0}s\nthen hold for {t3}s"),
            };
            format!(
                "stage {stage}\ndrone ardrone2\nactor A height 1.8m at (0, 0) facing {facing}deg\n\
                 at {t2}s A walks to ({b}, {c}) over {t3}s\n\
                 MS on A front for {t1}s\ncut to {path}\n"
            )
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// A script with extreme durations and path numbers is refused with diagnostics (each
    /// with a place and a help line), or it compiles without a panic, at every rate a
    /// command takes, to finite samples; a shot shorter than one tick at the rate is an
    /// error on its line.
    #[test]
    fn extreme_numbers_are_refused_or_compile(src in extreme_script(), rate in prop::sample::select(&[1.0, 10.0, 100.0, 1000.0][..])) {
        use dronecine_compiler::compile::{compile, Options as Rate};
        use dronecine_compiler::CompileCode;
        let checked = check(&src, &Options::default());
        let script = if checked.has_errors() { None } else { checked.script.clone() };
        let Some(script) = script else {
            prop_assert!(checked.has_errors(), "{src}");
            for d in &checked.diagnostics {
                prop_assert!(d.span.end <= src.len() && d.help.is_some(), "{src}\n{d:?}");
            }
            return Ok(());
        };
        // Compiled at the rates a command takes, where that stays quick.
        if script.duration_s * rate > 50_000.0 {
            return Ok(());
        }
        let profile = dronecine_profile::Profile::builtin("ardrone2").unwrap();
        let c = compile(&script, &profile, &Rate { rate_hz: rate }, |s, _| {
            let all = s.position_m.iter().chain(&s.velocity_mps).chain(&s.acceleration_mps2);
            assert!(all.copied().all(f64::is_finite), "{src}\n{s:?}");
            assert!(s.heading_rad.is_finite() && s.camera_pitch_rad.is_finite(), "{src}\n{s:?}");
            Ok::<(), ()>(())
        })
        .unwrap();
        for shot in &script.timeline {
            let short = (shot.end_s - shot.start_s) * rate < 1.0 - 1e-9;
            let told = c.diagnostics.iter().any(|d| {
                d.code == CompileCode::TooShortForRate && d.span == shot.span && d.is_error()
            });
            prop_assert_eq!(short, told, "{}\n{:?}", src, c.diagnostics);
        }
    }
}

/// Coverages where no framing of the classic pattern fits (a 1 m stage, actors at their
/// closest or a metre and a half apart in a corner, one of them 0.2 m tall, facings any
/// way) expand and compile without a panic, to finite samples, every diagnostic with a
/// help line.
#[test]
fn coverages_that_cannot_be_framed_expand_and_compile_without_a_panic() {
    let profile = dronecine_profile::Profile::builtin("ardrone2").unwrap();
    let cases = [
        (
            "1m x 1m x 1m",
            "(-0.45, -0.45)",
            "(-0.15, -0.45)",
            "0.2m",
            "-90deg",
        ),
        (
            "3m x 3m x 1m",
            "(-1.4, -1.4)",
            "(0.1, -1.4)",
            "1.8m",
            "45deg",
        ),
        ("8m x 6m x 3m", "(0, 0)", "(0.3, 0)", "3m", "180deg"),
    ];
    for (stage, a, b, h, facing) in cases {
        let src = format!(
            "stage {stage}\nactor A height 1.8m at {a} facing 0deg\n\
             actor B height {h} at {b} facing {facing}\ncoverage A and B for 16s\n"
        );
        let checked = check(&src, &Options::default());
        assert!(!checked.has_errors(), "{src}\n{:?}", checked.diagnostics);
        let script = checked.script.unwrap();
        let (expanded, told) = dronecine_compiler::coverage::expand(&script, &profile);
        assert_eq!(expanded.timeline.len(), 5, "{src}");
        let c = dronecine_compiler::compile::compile(
            &expanded,
            &profile,
            &Default::default(),
            |s, _| {
                assert!(s.position_m.iter().all(|x| x.is_finite()), "{src}\n{s:?}");
                Ok::<(), ()>(())
            },
        )
        .unwrap();
        for d in told.iter().chain(&c.diagnostics) {
            assert!(d.help.is_some(), "{src}\n{d:?}");
        }
    }
}
