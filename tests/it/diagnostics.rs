//! The bad-input corpus (`tests/bad/`): every file is rejected, with the codes its header
//! names (`# expect: psl::…`), spans that point into the file, and a rendering pinned by a
//! snapshot. Together the files exercise every diagnostic code.

use dronecine_grammar::PslCode;
use std::collections::BTreeSet;

use dronecine_diag as diag;

fn expected_codes(src: &str) -> Vec<String> {
    let first = src.lines().next().unwrap_or("");
    let list = first
        .strip_prefix("# expect: ")
        .expect("corpus file starts with `# expect: psl::…`");
    list.split(',').map(|c| c.trim().to_string()).collect()
}

#[test]
fn bad_inputs_are_rejected_with_the_expected_codes() {
    insta::glob!("../bad", "*.psl", |path| {
        let (src, checked) = crate::common::check_path(path);
        let name = format!("bad/{}", path.file_name().unwrap().to_string_lossy());
        assert!(checked.has_errors(), "{name} must be rejected");
        assert!(checked.script.is_none());
        let got: BTreeSet<&str> = checked
            .diagnostics
            .iter()
            .map(|d| d.code.as_str())
            .collect();
        for code in expected_codes(&src) {
            assert!(
                got.contains(code.as_str()),
                "{name}: expected {code}, got {got:?}"
            );
        }
        for d in &checked.diagnostics {
            assert!(
                d.span.start <= d.span.end && d.span.end <= src.len(),
                "{name}: span {:?}",
                d.span
            );
            assert!(src.is_char_boundary(d.span.start) && src.is_char_boundary(d.span.end));
            assert!(d.help.is_some(), "{name}: {} has no help line", d.code);
            assert!(
                !d.message.contains("Rule::") && !d.message.contains("kw_"),
                "{name}: {}",
                d.message
            );
        }
        let json = diag::to_json(&name, &src, &checked.diagnostics);
        assert!(
            json.iter().all(|j| j.line >= 2 && j.column >= 1),
            "{name}: the header line is fine"
        );
        insta::assert_snapshot!(diag::render(&name, &src, &checked.diagnostics, false, 100));
    });
}

#[test]
fn the_corpus_exercises_every_code() {
    let mut seen = BTreeSet::new();
    for path in crate::common::scripts("tests/bad") {
        let (_, checked) = crate::common::check_path(&path);
        seen.extend(checked.diagnostics.iter().map(|d| d.code));
    }
    // Only the language's codes: `profile::` and `compile::` are the compiler's, tested there.
    // Not reachable from a UTF-8 file in this corpus: tested in cli.rs and robustness.rs.
    let elsewhere = [
        PslCode::InvalidUtf8,
        PslCode::EmptyScript,
        PslCode::Internal,
    ];
    let missing: Vec<&str> = PslCode::ALL
        .iter()
        .filter(|c| c.as_str().starts_with("psl::"))
        .filter(|c| !seen.contains(&c.code()) && !elsewhere.contains(c))
        .map(|c| c.as_str())
        .collect();
    assert!(missing.is_empty(), "no corpus file exercises {missing:?}");
}

#[test]
fn the_corpus_is_large_enough() {
    let files = crate::common::scripts("tests/bad");
    assert!(files.len() >= 30, "{} bad inputs", files.len());
    let several = files
        .iter()
        .filter(|p| expected_codes(&std::fs::read_to_string(p).unwrap()).len() >= 3)
        .count();
    assert!(several >= 3, "files with several mistakes: {several}");
}

#[test]
fn all_mistakes_of_a_file_come_out_in_one_run() {
    let path = crate::common::workspace().join("tests/bad/several-shots.psl");
    let (src, checked) = crate::common::check_path(&path);
    let index = dronecine_diag::LineIndex::new(&src);
    let lines: BTreeSet<usize> = checked
        .diagnostics
        .iter()
        .map(|d| index.line_col(&src, d.span.start).0)
        .collect();
    assert_eq!(
        lines,
        [5, 6, 7, 8, 9].into_iter().collect(),
        "one diagnostic per bad line"
    );
}
