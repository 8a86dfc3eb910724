//! The fast line parser (`fast.rs`) against the pest path (`parser::parse_line_with_pest`):
//! whenever the fast path accepts a line, pest accepts it too and builds the same `Line`
//! (spans, borrowed text, values); and on ASCII lines the fast path accepts every line pest
//! accepts (it gives up only on Unicode questions), so the whole corpus of `shots/` and the
//! lines a generator writes from the vocabulary and the shapes of `psl.pest` take the fast
//! path. Mutated lines (tokens dropped, inserted, swapped, bytes deleted) probe the
//! rejections.

use std::path::{Path, PathBuf};

use dronecine_grammar::ast::Line;
use dronecine_grammar::parser::{parse, parse_line_with_pest, parse_with_pest};
use dronecine_grammar::vocab::{KEYWORDS, MOVE_NAMES, PROFILE_NAMES, SIZE_NAMES};
use dronecine_grammar::{fast, Diagnostic};
use proptest::prelude::*;

/// Compare both paths on one line; returns whether the fast path accepted it.
fn compare(text: &str, offset: usize, number: usize) -> bool {
    let fast = fast::parse_line(text, offset, number);
    let (slow, diagnostics) = parse_line_with_pest(text, offset, number);
    let pest_accepts = diagnostics.is_empty() && !slow.error;
    if let Some(f) = &fast {
        assert!(
            pest_accepts,
            "the fast path accepts a line pest rejects: {text:?}\n{diagnostics:?}"
        );
        assert_eq!(f, &slow, "the two paths build different lines for {text:?}");
    }
    if pest_accepts && text.is_ascii() {
        assert!(
            fast.is_some(),
            "the fast path gives up on an ASCII line pest accepts: {text:?}"
        );
    }
    fast.is_some()
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_path_buf()
}

fn psl_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "psl") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Per file: `parse` equals `parse_with_pest` (tree and diagnostics), and per line the two
/// paths agree. Returns (lines pest accepts, of which the fast path took).
fn corpus(dir: &str) -> (usize, usize, Vec<String>) {
    let files = psl_files(&workspace().join(dir));
    assert!(files.len() >= 5, "{dir}: too few scripts found");
    let (mut accepted, mut fast_taken) = (0, 0);
    let mut missed = Vec::new();
    for path in files {
        let bytes = std::fs::read(&path).expect("read script");
        let Ok(src) = std::str::from_utf8(&bytes) else {
            continue;
        };
        let (fast_file, fast_diags) = parse(src);
        let (slow_file, slow_diags): (_, Vec<Diagnostic>) = parse_with_pest(src);
        assert_eq!(fast_file, slow_file, "{}", path.display());
        assert_eq!(fast_diags, slow_diags, "{}", path.display());
        for line in &slow_file.lines {
            let text = &src[line.span.start..line.span.end];
            let took = compare(text, line.span.start, line.number);
            if !line.error {
                accepted += 1;
                if took {
                    fast_taken += 1;
                } else {
                    missed.push(format!("{}:{}: {text:?}", path.display(), line.number));
                }
            }
        }
    }
    (accepted, fast_taken, missed)
}

#[test]
fn every_line_of_the_shots_takes_the_fast_path() {
    let (accepted, taken, missed) = corpus("shots");
    assert!(accepted > 50, "only {accepted} lines");
    assert!(
        missed.is_empty(),
        "lines left to pest:\n{}",
        missed.join("\n")
    );
    assert_eq!(accepted, taken);
}

#[test]
fn bad_scripts_agree_with_pest() {
    // Errors and all: the diagnostics of `parse` are pest's, byte for byte.
    let (accepted, taken, _) = corpus("tests/bad");
    assert!(taken > 0 && taken <= accepted);
}

/// Lines at the edges of the grammar: trailing blanks (which pest keeps inside the spans of
/// rules ending in an absent optional part), tabs, comments, events that end at a move word,
/// keywords as names, numbers without digits after the dot, Unicode.
#[test]
fn edge_lines_agree() {
    let lines = [
        "MS on A",
        "MS on A  ",
        "MS on A \t # note",
        "  \tMS A#c",
        "MS A and B  MLS C screen (0.2, -.1)  for 2s   ",
        "MS A and",
        "MS A and B and",
        "MS on-x",
        "MS onward",
        "MS on",
        "MS A-b",
        "MSS A",
        "MS A 34left screen centre",
        "MS A left screen left",
        "MS A screen",
        "high  angle MS A",
        "high\tangle MS A",
        "highangle MS A",
        "eye level  CU A",
        "then hold",
        "then hold  ",
        "then hold for 2s",
        "then as A sits down pan to MCU on A left over 3s",
        "then as A pan B dolly to MS A",
        "then as A pan-to dolly to MS A",
        "then as \"A sits\" hold for 1s",
        "then as \"unclosed hold for 1s",
        "then as A#b hold",
        "then as é hold",
        "then asé hold",
        "then as A panéx dolly to MS A",
        "then as A pan\u{2014} dolly to MS A",
        "then as A holdé hold",
        "then follow B to MS A",
        "then follow to MS A",
        "then follow follow to MS A",
        "cut to path orbit around A radius 2m altitude 1.5m turns 1 for 20s",
        "cut to path square side 2m center (0, 0) altitude 1.5m for 20s looking at A",
        "path square looking at A side 2m for 3s looking at B",
        "path helix radius 1.5m centre ( 0 ,0 ) from 1m to 2.5m turns 2 counterclockwise",
        "path waypoints \"f.csv\" for 30s  ",
        "path waypoints f.csv",
        "path orbit",
        "path orbit   ",
        "at 30s cut to MS A",
        "at 30s A walks to (1, 1.5) over 4s",
        "at 6s A walks to (1, 1.5)  ",
        "at 12s B turns to 90deg over 1s",
        "at 12s B turns to 90deg over",
        "at 6sA walks to (1, 2)",
        "at x",
        "stage 8m x 6m x 3m",
        "stage 8m x 6m x 3m  ",
        "stage 8 m x 6m x 3m",
        "stage 8m x 6m",
        "lens 84deg",
        "lens 84deg  ",
        "lens 84deg 16:9",
        "lens 84deg 16.:9",
        "lens 84 4.5:3.25 # wide",
        "lens 16:9",
        "drone ardrone2",
        "drone \"profiles/mine.toml\"",
        "drone \"unclosed",
        "drone",
        "actor A",
        "actor A   ",
        "actor A height 1.80m at (0, 0) facing 0deg",
        "actor A facing 0deg height 2m height 3m  # twice",
        "actor A at (0 0)",
        "actor MS",
        "actor é",
        "actor Aé",
        "1 00:00:01 --> 00:00:05 LS on Rick 34left screen left",
        "12 00:01:03,250 --> 1:00:01:09.5  cut to low angle MCU Bob 34right",
        "5 00:00:20 --> 00:00:26 then as Ilsa looks away dolly to MS on Rick and Ilsa",
        "3 00:00 --> 00:01 then hold",
        "3 00:00 --> 00:01 path orbit",
        "3a 00:00 --> 00:01 MS A",
        "3 00: --> 00:01 MS A",
        "MS A\r",
        "MS A # c\r",
        "MS \"A\"",
        "-",
        "MS A # ünïcode comment",
        "MS Ａ",
        "MS A\u{a0}",
        "MS 1.e5",
        "cut to MS A for 99999999999999999999999999999999999999999999s",
    ];
    let mut taken = 0;
    for l in lines {
        if compare(l, 1000, 42) {
            taken += 1;
        }
    }
    assert!(taken > 40, "only {taken} edge lines took the fast path");
}

// ------------------------------------------------------------------------------------------
// Generated lines

fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        16 => prop::sample::select(vec!["A", "B", "Bob", "Rick", "onward", "x1", "a_b", "Zed9"]),
        1 => prop::sample::select(KEYWORDS.to_vec()),
    ]
    .prop_map(String::from)
}

fn quantity() -> impl Strategy<Value = String> {
    (
        prop_oneof![
            12 => prop::sample::select(vec!["0", "1", "2.5", "-1", "1.", "-.5", ".5", "1.80", "007"]),
            1 => prop::sample::select(vec!["1e3", "-", ".", "1.2.3"]),
        ],
        prop::sample::select(vec!["", "", "s", "m", "deg", "cm", "rad", "ms"]),
    )
        .prop_map(|(n, u)| format!("{n}{u}"))
}

fn point() -> impl Strategy<Value = String> {
    (
        quantity(),
        quantity(),
        prop::sample::select(vec!["", " ", "\t", "  "]),
    )
        .prop_map(|(x, y, w)| format!("({w}{x}{w},{w} {y}{w})"))
}

fn event() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        Just(vec!["as".to_string(), "\"Bob sits down\"".to_string()]),
        prop::collection::vec(
            prop::sample::select(vec!["Bob", "sits", "down", "A's", "hold-up", "x", "pan"]),
            1..4
        )
        .prop_map(|ws| {
            let mut v = vec!["as".to_string()];
            v.extend(ws.into_iter().map(String::from));
            v
        }),
    ]
}

fn duration() -> impl Strategy<Value = Vec<String>> {
    (prop::sample::select(vec!["for", "over"]), quantity())
        .prop_map(|(k, q)| vec![k.to_string(), q])
}

fn opt<T: std::fmt::Debug + Clone>(
    s: impl Strategy<Value = Vec<T>>,
) -> impl Strategy<Value = Vec<T>> {
    prop_oneof![1 => Just(Vec::new()), 2 => s]
}

fn subject() -> impl Strategy<Value = Vec<String>> {
    (
        name(),
        opt(prop::sample::select(PROFILE_NAMES.to_vec()).prop_map(|p| vec![p.to_string()])),
        opt(prop_oneof![
            prop::sample::select(vec!["left", "center", "centre", "right"])
                .prop_map(|t| vec!["screen".to_string(), t.to_string()]),
            point().prop_map(|p| vec!["screen".to_string(), p]),
        ]),
    )
        .prop_map(|(n, p, s)| [vec![n], p, s].concat())
}

fn framing() -> impl Strategy<Value = Vec<String>> {
    (
        prop::sample::select(SIZE_NAMES.to_vec()),
        prop::bool::ANY,
        prop::collection::vec(subject(), 1..3),
    )
        .prop_map(|(size, on, subjects)| {
            let mut v = vec![size.to_string()];
            if on {
                v.push("on".into());
            }
            for (i, s) in subjects.into_iter().enumerate() {
                if i > 0 {
                    v.push("and".into());
                }
                v.extend(s);
            }
            v
        })
}

fn composition() -> impl Strategy<Value = Vec<String>> {
    (
        opt(
            prop::sample::select(vec!["high angle", "low angle", "eye level"])
                .prop_map(|a| vec![a.to_string()]),
        ),
        prop::collection::vec(framing(), 1..3),
    )
        .prop_map(|(a, fs)| [a, fs.concat()].concat())
}

fn transition() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        Just(vec!["cut".to_string(), "to".to_string()]),
        Just(vec!["dissolve".to_string(), "to".to_string()]),
        (
            opt(event()),
            prop_oneof![
                prop::sample::select(MOVE_NAMES[..5].to_vec()).prop_map(|m| vec![m.to_string()]),
                name().prop_map(|n| vec!["follow".to_string(), n]),
            ]
        )
            .prop_map(|(e, m)| [vec!["then".to_string()], e, m, vec!["to".to_string()]].concat()),
    ]
}

fn path_param() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        quantity().prop_map(|q| vec!["side".into(), q]),
        (prop::sample::select(vec!["center", "centre"]), point())
            .prop_map(|(c, p)| vec![c.to_string(), p]),
        quantity().prop_map(|q| vec!["altitude".into(), q]),
        quantity().prop_map(|q| vec!["radius".into(), q]),
        (quantity(), quantity()).prop_map(|(a, b)| vec!["from".into(), a, "to".into(), b]),
        quantity().prop_map(|q| vec!["turns".into(), q]),
        name().prop_map(|n| vec!["around".into(), n]),
        prop::sample::select(vec!["clockwise", "counterclockwise"])
            .prop_map(|d| vec![d.to_string()]),
        name().prop_map(|n| vec!["looking".into(), "at".into(), n]),
    ]
}

fn path_shot() -> impl Strategy<Value = Vec<String>> {
    (
        opt(transition()),
        prop_oneof![
            prop::sample::select(vec!["square", "helix", "orbit"])
                .prop_map(|k| vec![k.to_string()]),
            Just(vec!["waypoints".to_string(), "\"route.csv\"".to_string()]),
        ],
        prop::collection::vec(path_param(), 0..4),
        opt(duration()),
        opt(name().prop_map(|n| vec!["looking".into(), "at".into(), n])),
    )
        .prop_map(|(t, k, ps, d, l)| [t, vec!["path".to_string()], k, ps.concat(), d, l].concat())
}

fn framed_or_hold() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        3 => (opt(transition()), composition(), opt(duration()))
            .prop_map(|(t, c, d)| [t, c, d].concat()),
        1 => (opt(event()), opt(duration())).prop_map(|(e, d)| {
            [vec!["then".to_string()], e, vec!["hold".to_string()], d].concat()
        }),
    ]
}

fn statement() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        6 => (
            opt(quantity().prop_map(|q| vec!["at".to_string(), q])),
            prop_oneof![3 => framed_or_hold(), 1 => path_shot()],
        )
            .prop_map(|(p, b)| [p, b].concat()),
        1 => (
            quantity(),
            name(),
            prop_oneof![
                point().prop_map(|p| vec!["walks".into(), "to".into(), p]),
                quantity().prop_map(|q| vec!["turns".into(), "to".into(), q]),
            ],
            opt(duration()),
        )
            .prop_map(|(q, n, a, d)| [vec!["at".to_string(), q, n], a, d].concat()),
        1 => (quantity(), quantity(), quantity())
            .prop_map(|(x, y, z)| vec!["stage".into(), x, "x".into(), y, "x".into(), z]),
        1 => (
            quantity(),
            opt(prop::sample::select(vec!["16:9", "4:3", "2.39:1", "1.:2"])
                .prop_map(|a| vec![a.to_string()])),
        )
            .prop_map(|(q, a)| [vec!["lens".to_string(), q], a].concat()),
        1 => prop::sample::select(vec!["ardrone2", "\"profiles/mine.toml\"", "my-drone_v1.2"])
            .prop_map(|d| vec!["drone".to_string(), d.to_string()]),
        1 => (
            name(),
            prop::collection::vec(
                prop_oneof![
                    quantity().prop_map(|q| vec!["height".into(), q]),
                    point().prop_map(|p| vec!["at".into(), p]),
                    quantity().prop_map(|q| vec!["facing".into(), q]),
                ],
                0..4
            ),
        )
            .prop_map(|(n, attrs)| [vec!["actor".to_string(), n], attrs.concat()].concat()),
        1 => (
            prop::sample::select(vec!["1", "12", "007"]),
            prop::sample::select(vec!["00:00:01", "00:01:03,250", "1:02", "00:00:05.5"]),
            prop::sample::select(vec!["00:00:05", "00:01:09", "2:00"]),
            framed_or_hold(),
        )
            .prop_map(|(i, a, b, body)| {
                [vec![i.to_string(), a.to_string(), "-->".to_string(), b.to_string()], body]
                    .concat()
            }),
    ]
}

/// What a mutation may insert.
const NOISE: &[&str] = &[
    "#", "\"", "-", "(", ")", ",", ":", "to", "and", "on", "at", "hold", "pan", "MS", "A", "1s",
    "é", "\r", "\t", "  ", "x", "-->", "0", ".", "Ａ", "\u{a0}", "_", "screen", "looking", "path",
    "orbit", "\u{2014}",
];

#[derive(Clone, Debug)]
enum Mutation {
    None,
    DropToken(usize),
    InsertToken(usize, &'static str),
    ReplaceToken(usize, &'static str),
    SwapTokens(usize, usize),
    GlueTokens(usize),
    DeleteChar(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let noise = || prop::sample::select(NOISE.to_vec());
    prop_oneof![
        10 => Just(Mutation::None),
        1 => any::<usize>().prop_map(Mutation::DropToken),
        1 => (any::<usize>(), noise()).prop_map(|(i, t)| Mutation::InsertToken(i, t)),
        1 => (any::<usize>(), noise()).prop_map(|(i, t)| Mutation::ReplaceToken(i, t)),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(i, j)| Mutation::SwapTokens(i, j)),
        1 => any::<usize>().prop_map(Mutation::GlueTokens),
        1 => any::<usize>().prop_map(Mutation::DeleteChar),
    ]
}

/// A line: leading blanks, tokens with varied separators, trailing blanks, a comment.
fn line() -> impl Strategy<Value = String> {
    (
        statement(),
        prop::collection::vec(prop::sample::select(vec![" ", " ", "  ", "\t", " \t"]), 48),
        prop::sample::select(vec!["", "", " ", "\t"]),
        prop::sample::select(vec!["", "", " ", "  ", "\t "]),
        prop::sample::select(vec!["", "", "# a note", "#", "#  trailing  "]),
        mutation(),
    )
        .prop_map(|(mut tokens, seps, lead, trail, comment, m)| {
            let n = tokens.len().max(1);
            let mut glue = None;
            match m {
                Mutation::None | Mutation::DeleteChar(_) => {}
                Mutation::DropToken(i) => {
                    tokens.remove(i % n);
                }
                Mutation::InsertToken(i, t) => tokens.insert(i % (n + 1), t.to_string()),
                Mutation::ReplaceToken(i, t) => tokens[i % n] = t.to_string(),
                Mutation::SwapTokens(i, j) => tokens.swap(i % n, j % n),
                Mutation::GlueTokens(i) => glue = Some(i % n),
            }
            let mut s = String::from(lead);
            for (i, t) in tokens.iter().enumerate() {
                if i > 0 && glue != Some(i) {
                    s.push_str(seps[i % seps.len()]);
                }
                s.push_str(t);
            }
            s.push_str(trail);
            if !comment.is_empty() {
                if !trail.is_empty() || s.is_empty() {
                    s.push_str(comment);
                } else {
                    s.push(' ');
                    s.push_str(comment);
                }
            }
            if let Mutation::DeleteChar(i) = m {
                let chars: Vec<(usize, char)> = s.char_indices().collect();
                if !chars.is_empty() {
                    let (at, c) = chars[i % chars.len()];
                    s.replace_range(at..at + c.len_utf8(), "");
                }
            }
            s
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    /// Fast path ⇒ pest accepts, same `Line`; ASCII line pest accepts ⇒ fast path.
    #[test]
    fn generated_lines_agree(l in line(), offset in 0usize..10_000, number in 1usize..500) {
        compare(&l, offset, number);
    }

    /// Whole scripts of generated lines: `parse` is `parse_with_pest`, diagnostics included.
    #[test]
    fn generated_scripts_agree(
        lines in prop::collection::vec(line(), 1..12),
        crlf in prop::bool::ANY,
        bom in prop::bool::ANY,
    ) {
        let mut src = String::new();
        if bom {
            src.push('\u{feff}');
        }
        src.push_str(&lines.join(if crlf { "\r\n" } else { "\n" }));
        let (fast_file, fast_diags) = parse(&src);
        let (slow_file, slow_diags) = parse_with_pest(&src);
        prop_assert_eq!(fast_file, slow_file);
        prop_assert_eq!(fast_diags, slow_diags);
    }
}

#[test]
fn the_generator_writes_mostly_accepted_lines() {
    // Guard against a generator drifting away from the grammar: sample it and check that
    // a good share of its lines are accepted (and so exercise the equality of trees).
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let strategy = line();
    let (mut accepted, total) = (0, 2000);
    for _ in 0..total {
        let l = strategy.new_tree(&mut runner).expect("value").current();
        let (slow, diags): (Line<'_>, _) = parse_line_with_pest(&l, 0, 1);
        if diags.is_empty() && !slow.error {
            accepted += 1;
        }
        compare(&l, 0, 1);
    }
    assert!(
        accepted * 3 > total,
        "only {accepted} of {total} generated lines parse"
    );
}
