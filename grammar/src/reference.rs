//! The language reference, `docs/language.md`, as data for `dronecine explain`: the entries
//! of a word (the headings and table rows that name it), each with an example completed into
//! a whole script, and the vocabulary by kind ([`crate::vocab`] for the words, the reference's
//! keyword table for the kind of the others).
//!
//! An entry is a heading or a table row whose code span names the word: `### \`stage\``,
//! `### Pinned shots: \`at T\``, a row `| \`MS\` | medium shot | … |`. The span names the word
//! as a whole (`eye level`) or as its first word (`at T`); a keyword further in a span
//! (`to` in `from Z1 to Z2`) makes a lesser entry, shown in full only when the word has no
//! other. An entry's example is its row's `example` cell, or else the first `psl` block of
//! its section that holds the word.

use dronecine_diag::docs::{self, Section};

use crate::vocab::{self, CameraAngle, Profile};

/// `docs/language.md`, built in.
pub const LANGUAGE_MD: &str = include_str!("../../docs/language.md");

/// The title of the section whose `psl` block is the set-up of the examples that have none.
const EXAMPLES_SETUP: &str = "The examples on this page";

/// How strongly an entry names its word.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Naming {
    /// The span is the word, or starts with it (`at T`).
    Primary,
    /// The word is a keyword further in the span (`to` in `from Z1 to Z2`).
    Secondary,
}

/// One entry of a word.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The heading the entry is, or the table stands under (Markdown kept).
    pub section: String,
    /// The code span that names the word (`at T`, `MS`).
    pub names: String,
    pub naming: Naming,
    /// The row's other cells with their column names; empty for a heading.
    pub cells: Vec<(String, String)>,
    /// The section's first paragraph (Markdown).
    pub meaning: String,
    /// The example as written in the reference.
    pub example: Option<String>,
}

impl Entry {
    /// The example as a whole script ([`complete`]).
    pub fn whole_example(&self) -> Option<String> {
        self.example.as_deref().map(complete)
    }
}

/// The words of a span that can name a word: all of them when the span is one word, else the
/// keywords among them (`NAME`, `L` and `(x, y)` are placeholders).
fn words(span: &str) -> Vec<&str> {
    span.split(|c: char| c.is_whitespace() || "(),…/".contains(c))
        .filter(|w| !w.is_empty())
        .collect()
}

/// How `span` names `term`, if it does.
fn naming(span: &str, term: &str) -> Option<Naming> {
    let span = span.trim();
    let w = words(span);
    if span == term || w.first() == Some(&term) {
        return Some(Naming::Primary);
    }
    (vocab::is_keyword(term) && w.contains(&term)).then_some(Naming::Secondary)
}

/// Whether `text` holds `term` as a word or a run of words.
fn holds(text: &str, term: &str) -> bool {
    let t: Vec<&str> = term.split_whitespace().collect();
    let w: Vec<&str> = text
        .split(|c: char| c.is_whitespace() || "(),".contains(c))
        .filter(|w| !w.is_empty())
        .collect();
    !t.is_empty() && w.windows(t.len()).any(|win| win == t.as_slice())
}

/// The first `psl` block of `body` that holds `term`, or else its first `psl` block.
fn example_in(body: &str, term: &str) -> Option<String> {
    let psl: Vec<&str> = docs::blocks(body)
        .into_iter()
        .filter(|b| b.info == "psl")
        .map(|b| b.text)
        .collect();
    psl.iter()
        .find(|b| holds(b, term))
        .or(psl.first())
        .map(|b| b.to_string())
}

/// The section titled `title` (the first of that title).
fn section<'a>(all: &[Section<'a>], title: &str) -> Option<Section<'a>> {
    all.iter().find(|s| s.title == title).copied()
}

/// Every entry of `term` in the reference, the primary ones first, each kind in the
/// reference's order.
pub fn entries(term: &str) -> Vec<Entry> {
    let term = term.trim();
    let all = docs::sections(LANGUAGE_MD);
    let mut out = Vec::new();
    for s in &all {
        for span in docs::code_spans(s.title) {
            if let Some(naming) = naming(span, term) {
                out.push(Entry {
                    section: s.title.to_string(),
                    names: span.to_string(),
                    naming,
                    cells: Vec::new(),
                    meaning: docs::first_paragraph(s.body),
                    example: example_in(s.body, term),
                });
                break;
            }
        }
    }
    for t in docs::tables(LANGUAGE_MD) {
        let body = section(&all, t.heading).map_or("", |s| s.body);
        let example_column = t.columns.iter().position(|c| *c == "example");
        for row in &t.rows {
            let Some(first) = row.first() else { continue };
            let Some((span, naming)) = docs::code_spans(first)
                .into_iter()
                .find_map(|span| naming(span, term).map(|n| (span, n)))
            else {
                continue;
            };
            let example = example_column
                .and_then(|i| row.get(i))
                .and_then(|cell| docs::code_spans(cell).first().map(|e| e.to_string()))
                .or_else(|| example_in(body, term));
            let cells = (t.columns.iter().zip(row).skip(1))
                .filter(|(c, _)| **c != "example")
                .map(|(c, v)| (c.to_string(), v.to_string()))
                .collect();
            out.push(Entry {
                section: t.heading.to_string(),
                names: span.to_string(),
                naming,
                cells,
                meaning: docs::first_paragraph(body),
                example,
            });
        }
    }
    out.sort_by_key(|e| e.naming);
    out
}

/// The vocabulary by kind: sizes, profiles (with their camera azimuth), camera moves,
/// camera angles and transitions from [`crate::vocab`], then every other keyword.
pub fn vocabulary() -> Vec<(&'static str, Vec<String>)> {
    let strings = |w: &[&str]| w.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let angles: Vec<String> = CameraAngle::ALL
        .iter()
        .map(|a| a.as_str().to_string())
        .collect();
    let profiles = Profile::ALL
        .iter()
        .map(|p| format!("{} ({})", p.as_str(), azimuth_text(*p)))
        .collect();
    let listed: Vec<&str> = (vocab::SIZE_NAMES.iter())
        .chain(vocab::PROFILE_NAMES)
        .chain(vocab::MOVE_NAMES)
        .chain(vocab::TRANSITION_NAMES)
        .copied()
        .chain(angles.iter().flat_map(|a| a.split(' ')))
        .collect();
    let others: Vec<&str> = (vocab::KEYWORDS.iter())
        .filter(|w| !listed.contains(w))
        .copied()
        .collect();
    vec![
        ("shot sizes", strings(vocab::SIZE_NAMES)),
        ("profiles", profiles),
        ("camera moves", strings(vocab::MOVE_NAMES)),
        ("camera angles", angles),
        ("transitions", strings(vocab::TRANSITION_NAMES)),
        ("other keywords", strings(&others)),
    ]
}

/// A profile's camera azimuth as the reference writes it: `0°`, `+45°`, `180°`, `−135°`.
fn azimuth_text(p: Profile) -> String {
    let deg = p.azimuth_rad().to_degrees().round();
    let sign = if deg > 0.0 && deg < 180.0 { "+" } else { "" };
    format!("{sign}{deg}°").replace('-', "−")
}

/// Every word `dronecine explain` knows: the vocabulary's words (a profile without its
/// azimuth) and every keyword.
pub fn words_known() -> Vec<String> {
    let mut out: Vec<String> = vocabulary()
        .into_iter()
        .flat_map(|(_, w)| w)
        .map(|w| w.split(" (").next().unwrap_or(&w).to_string())
        .collect();
    for k in vocab::KEYWORDS {
        if !out.iter().any(|w| w == k) {
            out.push(k.to_string());
        }
    }
    out
}

/// What a `psl` block of the reference is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    /// A script or a part of one: [`complete`] makes it whole.
    Example,
    /// Timed entries only: a film annotation, whole as it is.
    Annotation,
    /// Lines each marked `# error: CODE`: mistakes, each refused with its code.
    Mistakes,
}

/// Every `psl` block of the reference, with the title of the innermost section it stands in
/// and its kind.
pub fn blocks() -> Vec<(String, BlockKind, String)> {
    // One binding: each use of a `const` may be its own copy, at its own address.
    let md: &str = LANGUAGE_MD;
    let offset = |s: &str| s.as_ptr() as usize - md.as_ptr() as usize;
    let all = docs::sections(md);
    docs::blocks(md)
        .into_iter()
        .filter(|b| b.info == "psl")
        .map(|b| {
            let at = offset(b.text);
            let title = (all.iter().rev())
                .find(|s| (offset(s.body)..offset(s.body) + s.body.len()).contains(&at))
                .map_or("", |s| s.title);
            (title.to_string(), block_kind(b.text), b.text.to_string())
        })
        .collect()
}

fn statements(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
}

fn block_kind(text: &str) -> BlockKind {
    if text.contains("# error: ") {
        BlockKind::Mistakes
    } else if statements(text).all(|l| l.starts_with(|c: char| c.is_ascii_digit())) {
        BlockKind::Annotation
    } else {
        BlockKind::Example
    }
}

/// What a line of a script is, for [`complete`].
#[derive(Clone, Copy, PartialEq, Eq)]
enum Line {
    Setup,
    Movement,
    Shot,
    Comment,
}

fn line_kind(line: &str) -> Line {
    let w: Vec<&str> = line.split_whitespace().collect();
    match w.as_slice() {
        [] => Line::Comment,
        [first, ..] if first.starts_with('#') => Line::Comment,
        ["stage" | "lens" | "drone" | "actor", ..] => Line::Setup,
        ["at", _, _, "walks" | "turns", ..] => Line::Movement,
        _ => Line::Shot,
    }
}

/// An example of the reference as a whole script, as the reference says (section "The
/// examples on this page"): a film annotation, and a scene with its own `stage` and a shot,
/// as they are; any other example gets the set-up's `stage` line if it has none, the set-up's
/// actors it does not declare, and the set-up's shot: before its first shot when that is a
/// `then`, after it when it has no shot.
pub fn complete(example: &str) -> String {
    let lines: Vec<&str> = example.lines().collect();
    let is = |l: &&str, k: Line| line_kind(l) == k;
    let has_stage = lines.iter().any(|l| l.trim_start().starts_with("stage "));
    let has_shot = lines.iter().any(|l| is(l, Line::Shot));
    let whole = block_kind(example) == BlockKind::Annotation || (has_stage && has_shot);
    let Some(setup) = examples_setup().filter(|_| !whole) else {
        return with_newline(example);
    };
    let declared: Vec<&str> = (lines.iter())
        .filter(|l| l.trim_start().starts_with("actor "))
        .filter_map(|l| l.split_whitespace().nth(1))
        .collect();
    let mut out: Vec<&str> = Vec::new();
    let mut setup_shot = None;
    for l in setup.lines() {
        let name = l.split_whitespace().nth(1).unwrap_or("");
        match line_kind(l) {
            Line::Comment => {}
            Line::Setup if l.starts_with("stage ") => {
                if !has_stage {
                    out.push(l);
                }
            }
            Line::Setup if l.starts_with("actor ") => {
                if !declared.contains(&name) {
                    out.push(l);
                }
            }
            Line::Setup => out.push(l),
            _ => setup_shot = setup_shot.or(Some(l)),
        }
    }
    out.extend(lines.iter().filter(|l| is(l, Line::Setup)));
    // The stage first, then the rest of the set-up in order.
    out.sort_by_key(|l| !l.starts_with("stage "));
    let rest: Vec<&str> = lines
        .iter()
        .filter(|l| !is(l, Line::Setup))
        .copied()
        .collect();
    let first_shot = rest.iter().position(|l| is(l, Line::Shot));
    match (first_shot, setup_shot) {
        (Some(i), Some(shot)) if opens_with_then(rest[i]) => {
            out.extend(&rest[..i]);
            out.push(shot);
            out.extend(&rest[i..]);
        }
        (None, Some(shot)) => {
            out.extend(&rest);
            out.push(shot);
        }
        _ => out.extend(&rest),
    }
    with_newline(&out.join("\n"))
}

/// Whether a shot line is a `then` (pinned or not).
fn opens_with_then(line: &str) -> bool {
    let w: Vec<&str> = line.split_whitespace().collect();
    matches!(w.as_slice(), ["at", _, "then", ..] | ["then", ..])
}

fn with_newline(text: &str) -> String {
    let mut s = text.trim_end().to_string();
    s.push('\n');
    s
}

/// The `psl` block of section [`EXAMPLES_SETUP`].
fn examples_setup() -> Option<&'static str> {
    let all = docs::sections(LANGUAGE_MD);
    let s = section(&all, EXAMPLES_SETUP)?;
    docs::blocks(s.body)
        .into_iter()
        .find(|b| b.info == "psl")
        .map(|b| b.text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The entries `dronecine explain` shows in full: the primary ones, or else all.
    fn shown(term: &str) -> Vec<Entry> {
        let all = entries(term);
        let primary: Vec<Entry> = (all.iter())
            .filter(|e| e.naming == Naming::Primary)
            .cloned()
            .collect();
        if primary.is_empty() {
            all
        } else {
            primary
        }
    }

    #[test]
    fn every_word_has_an_entry_whose_example_holds_it() {
        let mut missing = Vec::new();
        for word in words_known() {
            let shown = shown(&word);
            let ok = !shown.is_empty()
                && shown
                    .iter()
                    .all(|e| e.example.as_deref().is_some_and(|x| holds(x, &word)));
            if !ok {
                let found: Vec<(&str, Option<&str>)> = (shown.iter())
                    .map(|e| (e.section.as_str(), e.example.as_deref()))
                    .collect();
                missing.push(format!("{word}: {found:?}"));
            }
        }
        assert!(missing.is_empty(), "{}", missing.join("\n"));
    }

    #[test]
    fn a_part_of_a_script_is_completed_from_the_examples_setup() {
        let setup = "stage 8m x 6m x 3m\nactor A height 1.80m at (-1.5, -1) facing 0deg\n\
                     actor B height 1.65m at (1.5, -1) facing 180deg\n";
        assert_eq!(
            complete("# first\nLS on A front for 4s  # alone"),
            format!("{setup}# first\nLS on A front for 4s  # alone\n")
        );
        assert_eq!(
            complete("then dolly to MS on A back over 6s\nthen hold for 2s"),
            format!("{setup}MS on A front for 4s\nthen dolly to MS on A back over 6s\nthen hold for 2s\n")
        );
        assert_eq!(
            complete("lens 84deg 4:3"),
            format!("{setup}lens 84deg 4:3\nMS on A front for 4s\n")
        );
        assert_eq!(
            complete("actor A height 1.70m at (0, 0)\nat 6s A walks to (1, 1.5) over 4s"),
            "stage 8m x 6m x 3m\nactor B height 1.65m at (1.5, -1) facing 180deg\n\
             actor A height 1.70m at (0, 0)\nat 6s A walks to (1, 1.5) over 4s\nMS on A front for 4s\n"
        );
        // Whole already: a scene with its stage and a shot, and a film annotation.
        let scene = "stage 4m x 4m x 3m\nactor Z height 1.7m at (0, 0)\nMS on Z for 2s\n";
        assert_eq!(complete(scene), scene);
        let annotation = "1 00:00:01 --> 00:00:05 LS on Rick 34left\n";
        assert_eq!(complete(annotation), annotation);
    }

    #[test]
    fn the_blocks_are_examples_an_annotation_and_mistakes() {
        let b = blocks();
        let count = |k: BlockKind| b.iter().filter(|(_, kind, _)| *kind == k).count();
        assert!(count(BlockKind::Example) > 20, "{b:?}");
        assert_eq!(count(BlockKind::Annotation), 1);
        assert_eq!(count(BlockKind::Mistakes), 1);
        let (section, _, _) = b
            .iter()
            .find(|(_, _, t)| t.contains("34backright MS on B"))
            .unwrap();
        assert_eq!(section, "Over the shoulder");
    }

    /// The reference's profile table says the azimuths `vocab` defines.
    #[test]
    fn the_profile_angles_are_the_vocabularys() {
        for p in Profile::ALL {
            let e = entries(p.as_str());
            let row = e.iter().find(|e| e.section == "Profiles").expect("a row");
            let want = ("camera angle from the facing".into(), azimuth_text(p));
            assert_eq!(row.cells[0], want, "{p:?}");
        }
        let listed = &vocabulary()[1].1;
        assert_eq!(listed[5], "34backright (−135°)");
    }
}
