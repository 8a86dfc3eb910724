//! `dronecine explain`: every word of the language and every diagnostic code has an
//! explanation with an example; every example it prints for a word, and every example of
//! `docs/language.md`, passes `dronecine check` with no warning; the mistakes the reference
//! lists are refused with their codes; `docs/diagnostics.md` quotes each `tests/bad/` file as
//! `dronecine check` renders it.

use std::path::Path;

use dronecine_diag::docs;
use dronecine_grammar::reference::{self, BlockKind};

use crate::common::{dronecine, stderr, stdout, temp_dir, workspace};

const EXAMPLE_HEAD: &str = "Example, a whole script (`dronecine check` takes it):\n\n";

/// The examples in an explanation: the indented lines after each example heading.
fn examples_in(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for part in text.split(EXAMPLE_HEAD).skip(1) {
        let lines: Vec<&str> = part
            .lines()
            .take_while(|l| l.is_empty() || l.starts_with("    "))
            .map(|l| l.strip_prefix("    ").unwrap_or(l))
            .collect();
        out.push(lines.join("\n").trim_end().to_string() + "\n");
    }
    out
}

/// A folder with the files the reference's examples name (a profile file, a waypoints file).
fn examples_folder(name: &str) -> crate::common::Scratch {
    let dir = temp_dir(name);
    std::fs::create_dir_all(dir.join("profiles")).unwrap();
    std::fs::create_dir_all(dir.join("waypoints")).unwrap();
    let root = workspace();
    std::fs::copy(
        root.join("compiler/profile/profiles/ardrone2.toml"),
        dir.join("profiles/mine.toml"),
    )
    .unwrap();
    std::fs::copy(
        root.join("shots/waypoints/flyover.csv"),
        dir.join("waypoints/flyover.csv"),
    )
    .unwrap();
    dir
}

/// `dronecine check --format json` over the scripts written in `dir`: each file's name, error
/// and warning counts, and the codes raised in it.
fn check_all(dir: &Path) -> Vec<(String, u64, u64, Vec<String>)> {
    let o = dronecine(&["check", "--format", "json", dir.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let diagnostics = v["diagnostics"].as_array().unwrap();
    (v["files"].as_array().unwrap().iter())
        .map(|f| {
            let file = f["file"].as_str().unwrap().to_string();
            let codes = (diagnostics.iter())
                .filter(|d| d["file"] == f["file"])
                .map(|d| d["code"].as_str().unwrap().to_string())
                .collect();
            let count = |k: &str| f[k].as_u64().unwrap();
            (file, count("errors"), count("warnings"), codes)
        })
        .collect()
}

/// Every word: an explanation whose examples hold it and pass `dronecine check`, with no
/// warning.
#[test]
fn every_word_is_explained_with_an_example_that_checks() {
    let dir = examples_folder("explain-words");
    let mut n = 0;
    for word in reference::words_known() {
        let o = dronecine(&["explain", &word]);
        assert!(o.status.success(), "{word}: {}", stderr(&o));
        let text = stdout(&o);
        let examples = examples_in(&text);
        assert!(!examples.is_empty(), "{word} has no example:\n{text}");
        for e in examples {
            assert!(
                e.split(|c: char| c.is_whitespace() || "(),".contains(c))
                    .any(|w| word.split(' ').any(|t| t == w)),
                "{word}'s example does not use it:\n{e}"
            );
            std::fs::write(dir.join(format!("{n}.psl")), e).unwrap();
            n += 1;
        }
    }
    assert!(n >= 70, "{n} examples");
    for (file, errors, warnings, codes) in check_all(&dir) {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        assert!(errors + warnings == 0, "{file}: {codes:?}\n{text}");
    }
}

/// Every code of every crate (architecture.rs's list): its entry in docs/diagnostics.md,
/// with an example (a quoted file and its rendering, or an `**Example:**` paragraph).
#[test]
fn every_code_is_explained_with_an_example() {
    for (code, _) in crate::architecture::every_code() {
        let o = dronecine(&["explain", code.as_str()]);
        assert!(o.status.success(), "{code}: {}", stderr(&o));
        let text = stdout(&o);
        assert!(
            text.starts_with(&format!("{code} (docs/diagnostics.md, ")),
            "{text}"
        );
        let body = docs::code_entry(code.as_str()).expect("documented").body;
        assert!(
            !docs::blocks(body).is_empty() || body.contains("**Example:**"),
            "{code}'s entry has no example"
        );
        assert!(text.contains("Fix:"), "{code}: no fix\n{text}");
    }
    // A code's name alone finds it.
    let o = dronecine(&["explain", "unknown_actor"]);
    assert!(
        stdout(&o).starts_with("psl::unknown_actor "),
        "{}",
        stdout(&o)
    );
}

/// Every `psl` block of docs/language.md: an example, made whole, passes `dronecine check`
/// with no warning; the film annotation passes as it is; each listed mistake is refused with
/// the code its comment names.
#[test]
fn the_language_references_examples_check() {
    let dir = examples_folder("explain-blocks");
    let mut expected: Vec<(String, Option<String>)> = Vec::new();
    for (i, (section, kind, text)) in reference::blocks().into_iter().enumerate() {
        let scripts: Vec<(String, Option<String>)> = match kind {
            BlockKind::Example | BlockKind::Annotation => vec![(reference::complete(&text), None)],
            BlockKind::Mistakes => (text.lines())
                .filter_map(|l| l.split_once("# error: "))
                .map(|(line, code)| (reference::complete(line), Some(code.trim().to_string())))
                .collect(),
        };
        for (j, (script, code)) in scripts.into_iter().enumerate() {
            let name = dir.join(format!("{i:02}-{j:02}.psl"));
            std::fs::write(&name, format!("# {section}\n{script}")).unwrap();
            expected.push((name.to_str().unwrap().to_string(), code));
        }
    }
    assert!(expected.len() >= 25, "{} scripts", expected.len());
    let checked = check_all(&dir);
    assert_eq!(checked.len(), expected.len());
    for ((file, errors, warnings, codes), (want_file, want_code)) in checked.iter().zip(&expected) {
        assert_eq!(file, want_file);
        let text = std::fs::read_to_string(file).unwrap();
        match want_code {
            None => assert!(errors + warnings == 0, "{codes:?}\n{text}"),
            Some(code) => assert!(codes.contains(code), "{code} not raised: {codes:?}\n{text}"),
        }
    }
}

#[test]
fn without_a_term_it_lists_the_vocabulary_and_the_codes() {
    let o = dronecine(&["explain"]);
    assert!(o.status.success());
    // Each kind on one line, however it is wrapped.
    let text = stdout(&o).replace("\n    ", " ");
    for line in [
        "  shot sizes: ECU, BCU, CU, MCU, MS, MLS, FS, LS, ELS",
        "  camera moves: hold, pan, dolly, crane, track, follow",
        "  camera angles: eye level, high angle, low angle",
        "  transitions: cut, dissolve, then",
    ] {
        assert!(text.contains(&format!("\n{line}\n")), "{line}:\n{text}");
    }
    assert!(text.contains("34backright (−135°)"), "{text}");
    for (code, _) in crate::architecture::every_code() {
        assert!(text.contains(code.as_str()), "{code} not listed");
    }
}

#[test]
fn an_unknown_term_is_an_error_with_a_suggestion() {
    let o = dronecine(&["explain", "frnt"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
    assert!(
        stderr(&o).starts_with(
            "error: `frnt` is neither a word of the shot language nor a diagnostic code \
             (did you mean `front`?)"
        ),
        "{}",
        stderr(&o)
    );
    let o = dronecine(&["explain", "psl::unknown_actr"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("(did you mean `psl::unknown_actor`?)"),
        "{}",
        stderr(&o)
    );
    // Two words are one term.
    let o = dronecine(&["explain", "high", "angle"]);
    assert!(
        stdout(&o).starts_with("high angle: Camera angles"),
        "{}",
        stdout(&o)
    );
}

/// docs/diagnostics.md quotes each `tests/bad/` file it names, and its rendering, as they are.
#[test]
fn the_diagnostics_reference_quotes_the_bad_files_as_rendered() {
    let mut n = 0;
    for entry in docs::code_entries() {
        let body = entry.body;
        for (at, _) in body.match_indices("`tests/bad/") {
            let name = &body[at + 1..];
            let name = &name[..name.find('`').unwrap()];
            if !name.ends_with(".psl") {
                continue;
            }
            // The file, then (after the files it reads, if any) its rendering.
            let blocks = docs::blocks(&body[at..]);
            let (src, checked) = crate::common::check_path(&workspace().join(name));
            assert_eq!(blocks[0].text, src, "{name} as quoted in {}", entry.code);
            let rendered = dronecine_diag::render(name, &src, &checked.diagnostics, false, 100);
            let quoted = (blocks.iter().skip(1))
                .find(|b| b.text.starts_with("psl::"))
                .expect("a rendering");
            assert_eq!(quoted.text, rendered, "{name} rendered in {}", entry.code);
            n += 1;
        }
    }
    assert!(n >= 30, "{n} files quoted");
}

/// docs/diagnostics.md's compiler and film examples (a script quoted as `NAME.psl`, then what
/// `compile` says of it) are what `compile --color never NAME.psl` prints for that code today.
#[test]
fn the_diagnostics_reference_quotes_compile_as_it_renders() {
    let dir = crate::common::temp_dir("diagnostics-examples");
    let mut n = 0;
    for entry in docs::code_entries() {
        let code = entry.code.to_string();
        if !(code.starts_with("compile::") || code.starts_with("film::")) {
            continue;
        }
        let body = entry.body;
        let Some(at) = body.find(".psl`:\n") else {
            continue;
        };
        let name_start = body[..at].rfind('`').unwrap() + 1;
        let name = &body[name_start..at + 4];
        let blocks = docs::blocks(&body[at..]);
        let path = dir.path().join(name);
        // The file as quoted, ending with its last line's newline or without one.
        let printed = |ending: &str| {
            std::fs::write(&path, format!("{}{ending}", blocks[0].text)).unwrap();
            let o = std::process::Command::new(env!("CARGO_BIN_EXE_dronecine"))
                .current_dir(dir.path())
                .args(["compile", name, "-o", "x.mcap", "--color", "never"])
                .output()
                .unwrap();
            String::from_utf8_lossy(&o.stderr).to_string()
        };
        let (with, without) = (printed("\n"), printed(""));
        let quoted = (blocks.iter().skip(1))
            .find(|b| b.text.starts_with(&code))
            .unwrap_or_else(|| panic!("{code}: no rendering quoted"));
        assert!(
            with.contains(quoted.text) || without.contains(quoted.text),
            "{code} ({name}): the docs quote\n{}\nbut compile prints\n{with}",
            quoted.text
        );
        n += 1;
    }
    assert!(n >= 6, "{n} examples checked");
}
