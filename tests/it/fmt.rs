//! `fmt`: canonical, idempotent, meaning-preserving, comments kept.

fn fmt(src: &str) -> String {
    dronecine_grammar::format(src).unwrap_or_else(|d| panic!("does not format: {d:?}"))
}

fn resolved(src: &str) -> serde_json::Value {
    let checked = dronecine_grammar::check(src, &dronecine_grammar::Options::default());
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    crate::common::without_spans(serde_json::to_value(checked.script.unwrap()).unwrap())
}

fn comments(src: &str) -> Vec<&str> {
    src.lines()
        .filter_map(|l| l.find('#').map(|i| l[i..].trim_end()))
        .collect()
}

#[test]
fn shipped_scripts_are_canonical() {
    for path in crate::common::scripts("shots") {
        let src = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            fmt(&src),
            src,
            "{} is not in canonical form: run `dronecine fmt shots`",
            path.display()
        );
    }
}

const MESSY: &str = "  # set-up, indented\r
stage 8m   x 6m x\t3m\r
actor A   facing 0deg at (0,0) height 1.80m   # attributes out of order\r
actor B height 1.65m at (2.5,0) facing 180deg\r
\r
\r
\r
at 6s   A walks to (1,1.5) over 4s\r
MS A front for 4s\r
then   as  A   looks up   dolly to MS A 34backright over 6s\r
MS on A and B screen centre for 5s\r
MS B 34backright MLS A 34left screen right for 3s   # over the shoulder\r
path square altitude 1.5m center (0, 0) side 2m looking at A for 20s\r
coverage   A and   B for 20s\r
at 80s  dissolve to coverage MLS  A and B for 20s\r
coverage on B and A for 20s\r
\r
";

#[test]
fn messy_input_gets_the_canonical_form() {
    let expected = "# set-up, indented
stage 8m x 6m x 3m
actor A height 1.80m at (0, 0) facing 0deg  # attributes out of order
actor B height 1.65m at (2.5, 0) facing 180deg

at 6s A walks to (1, 1.5) over 4s
MS on A front for 4s
then as A looks up dolly to MS on A 34backright over 6s
cut to MS on A and B screen center for 5s
cut to MS on B 34backright MLS on A 34left screen right for 3s  # over the shoulder
path square side 2m center (0, 0) altitude 1.5m for 20s looking at A
cut to coverage A and B for 20s
at 80s dissolve to coverage MLS on A and B for 20s
cut to coverage B and A for 20s
";
    assert_eq!(fmt(MESSY), expected);
}

#[test]
fn formatting_is_idempotent_keeps_comments_and_meaning() {
    let mut inputs: Vec<String> = crate::common::scripts("shots")
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    inputs.push(MESSY.to_string());
    for src in &inputs {
        let once = fmt(src);
        assert_eq!(fmt(&once), once, "not idempotent on:\n{src}");
        assert_eq!(comments(&once), comments(src), "comments changed");
        // Waypoint files resolve against the script folder; compare without reading them.
        assert_eq!(resolved(&once), resolved(src), "meaning changed");
    }
}

#[test]
fn trailing_comments_on_consecutive_lines_are_aligned() {
    let out =
        fmt("stage 8m x 6m x 3m # volume\ndrone ardrone2 # the default\n\nlens 84deg # alone\n");
    assert_eq!(
        out,
        "stage 8m x 6m x 3m  # volume\ndrone ardrone2      # the default\n\nlens 84deg  # alone\n"
    );
}

#[test]
fn a_file_with_syntax_errors_is_not_formatted() {
    let errs = dronecine_grammar::format("stage 8m x 6m x 3m\nMS on A frnt for 4s\n").unwrap_err();
    assert_eq!(errs.len(), 1);
    assert_eq!(errs[0].code, dronecine_grammar::PslCode::Syntax);
}
