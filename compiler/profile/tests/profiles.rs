//! Drone profiles in TOML: the built-in profiles, user profile files, and the bad-input
//! corpus (`tests/bad-profiles/`). Every corpus file has one mistake (one has several) and
//! names, on its first line (`# expect: profile::…`), exactly the codes it must produce; the
//! rendered diagnostics are pinned by snapshots.

use dronecine_profile::ProfileCode;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use dronecine_diag::{self as diag, Span};
use dronecine_profile::{
    builtin_source, Gimbal, Profile, ProfileError, BUILTIN_NAMES, DEFAULT_NAME,
};

fn expected_codes(src: &str) -> BTreeSet<String> {
    let first = src.lines().next().unwrap_or("");
    let list = first
        .strip_prefix("# expect: ")
        .expect("corpus file starts with `# expect: profile::…`");
    list.split(',').map(|c| c.trim().to_string()).collect()
}

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-profiles");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("corpus folder")
        .map(|e| e.expect("corpus entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("profiles-test");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

#[test]
fn bad_profiles_produce_exactly_the_expected_codes() {
    insta::glob!("bad-profiles/*.toml", |path| {
        let src = std::fs::read_to_string(path).expect("corpus file is UTF-8");
        let name = format!(
            "bad-profiles/{}",
            path.file_name().unwrap().to_string_lossy()
        );
        let diagnostics = match Profile::from_toml("bad", &src) {
            Ok((_, warnings)) => panic!("{name} must be rejected; warnings: {warnings:?}"),
            Err(d) => d,
        };
        let got: BTreeSet<String> = diagnostics
            .iter()
            .map(|d| d.code.as_str().to_string())
            .collect();
        assert_eq!(got, expected_codes(&src), "{name}");
        for d in &diagnostics {
            assert!(
                d.span.start <= d.span.end && d.span.end <= src.len(),
                "{name}: span {:?}",
                d.span
            );
            assert!(src.is_char_boundary(d.span.start) && src.is_char_boundary(d.span.end));
            assert!(d.help.is_some(), "{name}: {} has no help line", d.code);
        }
        // The header comment is fine: every diagnostic points below it, at the mistake.
        let json = diag::to_json(&name, &src, &diagnostics);
        assert!(
            json.iter().all(|j| j.line >= 2),
            "{name}: a diagnostic points at the header line: {json:?}"
        );
        insta::assert_snapshot!(diag::render(&name, &src, &diagnostics, false, 100));
    });
}

/// Diagnostics point at the key or value at fault: the text under each span.
#[test]
fn diagnostics_point_at_the_offending_text() {
    let cases: &[(&str, &str)] = &[
        ("unknown-key-typo.toml", "tua_vz_s"),
        ("unknown-key-radians.toml", "tilt_max_rad"),
        ("unknown-key-wrong-section.toml", "gain_yaw"),
        ("unknown-section.toml", "saftey"),
        ("missing-key.toml", "[model]"),
        ("tilt-out-of-range.toml", "60"),
        ("negative-time-constant.toml", "-1.7"),
        ("number-as-text.toml", "\"0.7 m/s\""),
        ("speed-above-derived.toml", "3.0"),
        ("q-position-weight-zero.toml", "0.0"),
        ("r-too-short.toml", "[50.0, 50.0]"),
        ("noise-not-positive.toml", "-1e-6"),
        ("gimbal-without-range.toml", "\"pitch\""),
        ("gimbal-range-reversed.toml", "-90"),
        ("fov-given-twice.toml", "84"),
        ("aspect-with-slash.toml", "\"16/9\""),
        ("heading-gamma-above-one.toml", "1.5"),
        ("not-finite.toml", "nan"),
        ("section-not-a-table.toml", "0.5"),
    ];
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-profiles");
    for (file, text) in cases {
        let src = std::fs::read_to_string(dir.join(file)).unwrap();
        let d = Profile::from_toml("bad", &src).unwrap_err();
        assert_eq!(d.len(), 1, "{file}: {d:#?}");
        assert_eq!(&src[d[0].span.start..d[0].span.end], *text, "{file}");
    }
}

#[test]
fn unknown_keys_suggest_the_known_ones() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-profiles");
    let help = |file: &str| {
        let src = std::fs::read_to_string(dir.join(file)).unwrap();
        Profile::from_toml("bad", &src).unwrap_err()[0]
            .help
            .clone()
            .unwrap()
    };
    assert!(help("unknown-key-typo.toml").contains("did you mean `tau_vz_s`?"));
    assert!(help("unknown-key-radians.toml").contains("`tilt_max_deg = 12.032`"));
    assert!(help("unknown-key-wrong-section.toml").contains("belongs in [model]"));
    assert!(help("unknown-section.toml").contains("did you mean `safety`?"));
}

#[test]
fn a_limit_above_the_derived_bound_names_the_bound() {
    let src = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-profiles/speed-above-derived.toml"),
    )
    .unwrap();
    let d = Profile::from_toml("bad", &src).unwrap_err();
    // 17.5 m/s per rad × 12° × 0.5.
    let bound = 17.5 * 12f64.to_radians() * 0.5;
    assert!(
        d[0].message.contains(&format!("{bound:.3} m/s")),
        "{}",
        d[0].message
    );
}

#[test]
fn the_corpus_covers_the_toml_codes() {
    let files = corpus();
    assert!(files.len() >= 10, "{} corpus files", files.len());
    let mut seen = BTreeSet::new();
    let mut several = false;
    for path in &files {
        let src = std::fs::read_to_string(path).unwrap();
        let expected = expected_codes(&src);
        several |= expected.len() >= 3;
        seen.extend(expected);
    }
    assert!(several, "one corpus file has several mistakes");
    for code in [
        ProfileCode::Syntax,
        ProfileCode::BadValue,
        ProfileCode::UnknownKey,
        ProfileCode::MissingKey,
    ] {
        assert!(
            seen.contains(code.as_str()),
            "no corpus file expects {code}"
        );
    }
}

#[test]
fn builtins_parse_and_default_is_one() {
    assert!(BUILTIN_NAMES.contains(&DEFAULT_NAME));
    for name in BUILTIN_NAMES {
        let (p, warnings) = Profile::from_toml(name, builtin_source(name).unwrap())
            .unwrap_or_else(|d| panic!("{name}: {d:#?}"));
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        assert_eq!(Profile::builtin(name), Some(p));
    }
}

/// An MS frames 0.45·H, seen from `d = W/(2·tan(fovY/2))`. The built-in profiles fly the
/// AR.Drone's own lens (≈ 92° diagonal, 16:9), and their safety distance must leave an MS
/// possible with it — computed here from the lens alone, not the profile.
#[test]
fn builtin_safety_distance_allows_an_ms_of_a_180_cm_actor() {
    let half_diag = (92f64.to_radians() / 2.0).tan();
    let diag = 16f64.hypot(9.0);
    let tan_half_fov_y = half_diag * 9.0 / diag;
    let d_ms = 0.45 * 1.80 / (2.0 * tan_half_fov_y);
    assert!((d_ms - 0.798).abs() < 1e-3, "MS distance {d_ms}");
    // Seen from 20° above (a high angle), the horizontal distance to the body axis shrinks.
    let d_ms_high = d_ms * 20f64.to_radians().cos();
    for name in BUILTIN_NAMES.iter().filter(|n| n.starts_with("ardrone2")) {
        let p = Profile::builtin(name).unwrap();
        assert!(
            p.safety.actor_distance_m < d_ms_high,
            "{name}: safety distance {} m forbids an MS ({d_ms_high:.3} m)",
            p.safety.actor_distance_m
        );
        // The profile's lens is that lens.
        let fov_y = 2.0 * ((p.camera.fov_x_rad / 2.0).tan() / p.camera.aspect).atan();
        assert!((fov_y - 2.0 * tan_half_fov_y.atan()).abs() < 1e-9, "{name}");
    }
}

#[test]
fn derived_speed_follows_from_tilt_and_model() {
    let p = Profile::builtin("ardrone2").unwrap();
    // 17.5 m/s per rad × 0.21 rad × 0.5 ≈ 1.84 m/s; 17.5 × 0.21 × 0.5 / 1.7 ≈ 1.08 m/s².
    assert!((p.limits.speed_max_mps - 1.8375).abs() < 1e-4);
    assert!((p.limits.accel_max_mps2 - 1.8375 / 1.7).abs() < 1e-4);
    let outdoor = Profile::builtin("ardrone2-outdoor").unwrap();
    assert!((outdoor.limits.speed_max_mps - 3.0625).abs() < 1e-4);
}

#[test]
fn a_user_profile_file_round_trips() {
    // The built-in text, saved as a user's file, loads as the same profile under its name.
    let path = scratch("my-ardrone.toml");
    std::fs::write(&path, builtin_source("ardrone2").unwrap()).unwrap();
    let (p, src, warnings) = Profile::load(&path).expect("loads");
    assert!(warnings.is_empty());
    assert_eq!(src, builtin_source("ardrone2").unwrap());
    assert_eq!(p.name, "my-ardrone");
    let builtin = Profile::builtin("ardrone2").unwrap();
    assert_eq!(
        Profile {
            name: builtin.name.clone(),
            ..p
        },
        builtin
    );

    // A profile written out by `to_toml`, with a gimbal and a lowered speed, reads back.
    let mut mine = builtin;
    mine.name = "gimballed".to_string();
    mine.description = "AR.Drone 2.0 with a pitch gimbal".to_string();
    mine.camera.gimbal = Gimbal::Pitch {
        min_rad: -90f64.to_radians(),
        max_rad: 30f64.to_radians(),
        rate_radps: 90f64.to_radians(),
    };
    mine.limits.speed_max_mps = 1.5;
    let path = scratch("gimballed.toml");
    std::fs::write(&path, mine.to_toml()).unwrap();
    let (back, _, warnings) = Profile::load(&path).expect("loads");
    assert!(warnings.is_empty());
    assert_eq!(back.limits.speed_max_mps, 1.5);
    assert_eq!(back.servo, mine.servo);
    assert_eq!(back.model, mine.model);
    match back.camera.gimbal {
        Gimbal::Pitch {
            min_rad,
            max_rad,
            rate_radps,
        } => {
            assert!((min_rad + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
            assert!((max_rad - 30f64.to_radians()).abs() < 1e-12);
            assert!((rate_radps - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        }
        Gimbal::None => panic!("gimbal lost"),
    }
    assert!((back.camera.fov_x_rad - mine.camera.fov_x_rad).abs() < 1e-12);
    assert!((back.limits.tilt_max_rad - mine.limits.tilt_max_rad).abs() < 1e-12);
    assert!((back.limits.accel_max_mps2 - mine.limits.accel_max_mps2).abs() < 1e-12);
}

#[test]
fn a_missing_file_is_a_not_found_diagnostic() {
    let path = scratch("no-such-profile.toml");
    let _ = std::fs::remove_file(&path);
    let err = Profile::load(&path).unwrap_err();
    assert!(matches!(err, ProfileError::Unreadable { .. }), "{err:?}");
    let at = Span::new(6, 28);
    let d = err.not_found(at).expect("a diagnostic");
    assert_eq!(d.code, ProfileCode::NotFound);
    assert_eq!(d.span, at);
    assert!(d.message.contains("no-such-profile.toml") && d.message.contains("no such file"));
    assert!(d.help.is_some());
    // A folder is not a profile either.
    let dir = Profile::load(Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap_err();
    assert!(dir.not_found(at).is_some());
}

#[test]
fn a_file_that_is_not_utf8_is_a_syntax_diagnostic() {
    let path = scratch("latin1.toml");
    let mut bytes = builtin_source("ardrone2").unwrap().as_bytes().to_vec();
    bytes.extend_from_slice(b"# caf\xe9\n");
    std::fs::write(&path, bytes).unwrap();
    match Profile::load(&path).unwrap_err() {
        ProfileError::Invalid {
            source,
            diagnostics,
        } => {
            assert_eq!(diagnostics.len(), 1);
            assert_eq!(diagnostics[0].code, ProfileCode::Syntax);
            assert_eq!(
                &source[diagnostics[0].span.start..diagnostics[0].span.end],
                "\u{fffd}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_empty_file_lacks_every_section() {
    let d = Profile::from_toml("empty", "").unwrap_err();
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, ProfileCode::MissingKey);
    assert_eq!(d[0].span, Span::new(0, 0));
    for section in ["[model]", "[limits]", "[camera]", "[safety]", "[servo]"] {
        assert!(d[0].message.contains(section), "{}", d[0].message);
    }
}

/// The ArduCopter quad keeps a metre from actors (uncaged propellers): with its own lens
/// (84° diagonal, 16:9) a medium long shot of a 1.80 m actor (0.775 of the height framed) is
/// possible, seen from 20° above too, and a medium shot is not.
#[test]
fn the_arducopter_quad_frames_a_medium_long_shot_outside_its_safety_distance() {
    let p = Profile::builtin("arducopter-quad").unwrap();
    let tan_half_fov_y = (p.camera.fov_x_rad / 2.0).tan() / p.camera.aspect;
    let distance = |band: f64| band * 1.80 / (2.0 * tan_half_fov_y);
    let mls_high = distance(1.06 - 0.285) * 20f64.to_radians().cos();
    assert!(
        p.safety.actor_distance_m < mls_high,
        "MLS at {mls_high:.2} m"
    );
    assert!(
        p.safety.actor_distance_m > distance(1.05 - 0.60),
        "an MS comes too close"
    );
    assert!(matches!(
        p.camera.gimbal,
        dronecine_profile::Gimbal::Pitch { .. }
    ));
}

/// The Crazyflie carries no camera, and says so explicitly; the others carry one. A profile
/// written out keeps it.
#[test]
fn a_drone_without_a_camera_says_so_and_keeps_saying_so() {
    for name in BUILTIN_NAMES {
        let p = Profile::builtin(name).unwrap();
        assert_eq!(p.camera.mounted, *name != "crazyflie21", "{name}");
    }
    let p = Profile::builtin("crazyflie21").unwrap();
    let path = scratch("no-camera.toml");
    std::fs::write(&path, p.to_toml()).unwrap();
    let (back, _, warnings) = Profile::load(&path).expect("loads");
    assert!(warnings.is_empty());
    assert!(!back.camera.mounted);
    // A profile that predates the key reads as carrying a camera.
    let old: Profile = serde_json::from_str(
        &serde_json::to_string(&p)
            .unwrap()
            .replace("\"mounted\":false,", ""),
    )
    .unwrap();
    assert!(old.camera.mounted);
}
