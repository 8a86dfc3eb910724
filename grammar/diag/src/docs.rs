//! The reference docs as data, for `dronecine explain`: `docs/diagnostics.md` built in (one
//! `### namespace::code` entry per code, under its namespace's `## namespace:: — …` heading),
//! and the Markdown readings it and the language reference share: headings and their
//! sections, tables, fenced blocks, code spans, and a section's text as a terminal shows it.
//!
//! The docs are the one source of what a code or a word means: a code documented there is
//! explained, whichever crate declares it, with no change here.

/// `docs/diagnostics.md`, built in.
pub const DIAGNOSTICS_MD: &str = include_str!("../../../docs/diagnostics.md");

/// A heading and its section: the text after the heading line up to the next heading of the
/// same or a higher level (headings inside fenced blocks are text).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Section<'a> {
    /// 1 for `#`, 2 for `##`, …
    pub level: usize,
    pub title: &'a str,
    pub body: &'a str,
}

/// The lines of `md` with their byte offsets and whether each is a fence line or inside a
/// fenced block (then it is not Markdown structure).
fn lines(md: &str) -> Vec<(usize, &str, bool)> {
    let mut out = Vec::new();
    let mut fenced = false;
    let mut at = 0;
    for line in md.split_inclusive('\n') {
        let text = line.trim_end_matches(['\n', '\r']);
        let fence = text.trim_start().starts_with("```");
        out.push((at, text, fenced || fence));
        if fence {
            fenced = !fenced;
        }
        at += line.len();
    }
    out
}

/// A heading line's level and title.
fn heading(line: &str) -> Option<(usize, &str)> {
    let level = line.bytes().take_while(|&b| b == b'#').count();
    let title = line[level..].strip_prefix(' ')?;
    (1..=6).contains(&level).then(|| (level, title.trim()))
}

/// Every heading of `md` with its section, in order.
pub fn sections(md: &str) -> Vec<Section<'_>> {
    let lines = lines(md);
    let found: Vec<(usize, usize, usize, &str)> = lines
        .iter()
        .filter(|(_, _, fenced)| !fenced)
        .filter_map(|&(at, text, _)| heading(text).map(|(l, t)| (at, at + text.len(), l, t)))
        .collect();
    found
        .iter()
        .enumerate()
        .map(|(i, &(_, end, level, title))| {
            let next = found[i + 1..]
                .iter()
                .find(|h| h.2 <= level)
                .map_or(md.len(), |h| h.0);
            let start = (end + 1).min(next);
            Section {
                level,
                title,
                body: &md[start..next],
            }
        })
        .collect()
}

/// A Markdown table: its column names and its rows of cells (trimmed, Markdown kept), with
/// the title of the heading it stands under.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Table<'a> {
    pub heading: &'a str,
    pub columns: Vec<&'a str>,
    pub rows: Vec<Vec<&'a str>>,
}

/// The cells of a table line: split at `|` outside code spans (`\|` is a `|` in a cell).
fn cells(line: &str) -> Vec<&str> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let (mut out, mut start, mut in_code, mut escaped) = (Vec::new(), 0, false, false);
    for (i, c) in inner.char_indices() {
        match c {
            _ if escaped => escaped = false,
            '\\' => escaped = true,
            '`' => in_code = !in_code,
            '|' if !in_code => {
                out.push(inner[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(inner[start..].trim());
    out
}

/// Every table of `md` outside fenced blocks, in order.
pub fn tables(md: &str) -> Vec<Table<'_>> {
    let mut out = Vec::new();
    let mut under = "";
    let mut current: Option<Table> = None;
    for (_, text, fenced) in lines(md) {
        let row = !fenced && text.trim_start().starts_with('|');
        if !row {
            out.extend(current.take());
            if let Some((_, title)) = heading(text).filter(|_| !fenced) {
                under = title;
            }
            continue;
        }
        match current.as_mut() {
            None => {
                current = Some(Table {
                    heading: under,
                    columns: cells(text),
                    rows: Vec::new(),
                })
            }
            // The line under the column names.
            Some(t) if t.rows.is_empty() && text.chars().all(|c| "|-: ".contains(c)) => {}
            Some(t) => t.rows.push(cells(text)),
        }
    }
    out.extend(current);
    out
}

/// A fenced block: its info string (`psl`, `text`, or empty) and its text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block<'a> {
    pub info: &'a str,
    pub text: &'a str,
}

/// The fenced blocks of `md`, in order.
pub fn blocks(md: &str) -> Vec<Block<'_>> {
    let mut out = Vec::new();
    let mut open: Option<(&str, usize)> = None;
    for (at, text, fenced) in lines(md) {
        let Some(rest) = text.trim_start().strip_prefix("```").filter(|_| fenced) else {
            continue;
        };
        match open.take() {
            None => open = Some((rest.trim(), at + text.len() + 1)),
            Some((info, start)) => out.push(Block {
                info,
                text: &md[start.min(at)..at],
            }),
        }
    }
    out
}

/// The code spans of a line of Markdown, without their backticks.
pub fn code_spans(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// The first paragraph of a section's body: its first run of prose lines (not a table, a
/// fenced block or a list), joined.
pub fn first_paragraph(body: &str) -> String {
    let mut words = Vec::new();
    for (_, text, fenced) in lines(body) {
        let t = text.trim();
        let prose = !fenced && !t.is_empty() && !t.starts_with(['|', '-', '#']);
        if prose {
            words.push(t);
        } else if !words.is_empty() {
            break;
        }
    }
    words.join(" ")
}

/// Markdown as a terminal shows it: fenced blocks indented by four spaces (their fences
/// dropped), `**` dropped, links as their text, prose wrapped at `width` columns.
pub fn to_terminal(md: &str, width: usize) -> String {
    let mut out = String::new();
    for (_, text, fenced) in lines(md) {
        if fenced {
            if !text.trim_start().starts_with("```") {
                out.push_str(format!("    {text}").trim_end());
                out.push('\n');
            }
            continue;
        }
        let plain = unlink(&text.replace("**", ""));
        // A list item's lines align after its dash; an indented line's hang under it.
        let spaces = plain.len() - plain.trim_start_matches(' ').len();
        let indent = match plain[spaces..].starts_with("- ") {
            true => spaces + 2,
            false if spaces > 0 => spaces + 2,
            false => 0,
        };
        wrap(&plain, width, indent, &mut out);
    }
    out
}

/// `[text](target)` as `text`.
fn unlink(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find("](").map(|c| open + c) else {
            break;
        };
        let Some(end) = rest[close..].find(')').map(|e| close + e) else {
            break;
        };
        out.push_str(&rest[..open]);
        out.push_str(&rest[open + 1..close]);
        rest = &rest[end + 1..];
    }
    out.push_str(rest);
    out
}

/// `line` wrapped at `width` columns onto `out`, continuation lines indented by `indent`.
fn wrap(line: &str, width: usize, indent: usize, out: &mut String) {
    let mut column = 0;
    for (i, word) in line.split(' ').enumerate() {
        let n = word.chars().count();
        if i > 0 && column + 1 + n > width && column > indent {
            out.push('\n');
            out.push_str(&" ".repeat(indent));
            column = indent;
        } else if i > 0 {
            out.push(' ');
            column += 1;
        }
        out.push_str(word);
        column += n;
    }
    out.push('\n');
}

/// One code's entry in `docs/diagnostics.md`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeEntry {
    /// `psl::unknown_actor`.
    pub code: &'static str,
    /// The title of its namespace's heading: `psl:: — the language`.
    pub namespace: &'static str,
    /// The entry: meaning, example, fix (Markdown).
    pub body: &'static str,
}

/// Whether a heading's title is a code: `namespace::name`, lower case.
fn is_code(title: &str) -> bool {
    let ok = |s: &str| {
        !s.is_empty()
            && s.bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
    };
    title
        .split_once("::")
        .is_some_and(|(ns, n)| ok(ns) && ok(n))
}

/// Every code `docs/diagnostics.md` documents, in its order.
pub fn code_entries() -> Vec<CodeEntry> {
    let mut namespace = "";
    let mut out = Vec::new();
    for s in sections(DIAGNOSTICS_MD) {
        match s.level {
            2 => namespace = s.title,
            3 if is_code(s.title) => out.push(CodeEntry {
                code: s.title,
                namespace,
                body: s.body,
            }),
            _ => {}
        }
    }
    out
}

/// The entry of `code` (`psl::unknown_actor`), if documented.
pub fn code_entry(code: &str) -> Option<CodeEntry> {
    code_entries().into_iter().find(|e| e.code == code)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MD: &str = "# Title\n\nIntro line one\nand two.\n\n## First\n\n| word | means |\n|---|---|\n\
                      | `a` | the \\| pipe `x|y` |\n| `b c` | **bold** |\n\n```psl\n# not a heading\nMS on A\n```\n\n\
                      ### Sub\n\nText [link](other.md#x).\n\n## Second\n\nlast\n";

    #[test]
    fn sections_end_at_the_next_heading_of_their_level_and_skip_fences() {
        let s = sections(MD);
        let titles: Vec<(usize, &str)> = s.iter().map(|s| (s.level, s.title)).collect();
        assert_eq!(
            titles,
            [(1, "Title"), (2, "First"), (3, "Sub"), (2, "Second")]
        );
        assert!(s[1].body.contains("### Sub") && !s[1].body.contains("last"));
        assert_eq!(s[2].body, "\nText [link](other.md#x).\n\n");
        assert_eq!(s[3].body, "\nlast\n");
        assert_eq!(first_paragraph(s[0].body), "Intro line one and two.");
    }

    #[test]
    fn tables_split_cells_outside_code_spans() {
        let t = tables(MD);
        assert_eq!(t.len(), 1);
        assert_eq!(t[0].heading, "First");
        assert_eq!(t[0].columns, ["word", "means"]);
        assert_eq!(
            t[0].rows,
            [vec!["`a`", "the \\| pipe `x|y`"], vec!["`b c`", "**bold**"]]
        );
        assert_eq!(code_spans(t[0].rows[1][0]), ["b c"]);
    }

    #[test]
    fn blocks_keep_their_info_and_text() {
        let b = blocks(MD);
        assert_eq!(
            b,
            [Block {
                info: "psl",
                text: "# not a heading\nMS on A\n"
            }]
        );
    }

    #[test]
    fn the_terminal_text_drops_markup_and_wraps() {
        let t = to_terminal(
            "**Error.** see [the docs](a.md) now\n```text\ncode\n```\n",
            80,
        );
        assert_eq!(t, "Error. see the docs now\n    code\n");
        let long = "word ".repeat(30);
        let t = to_terminal(&format!("- {long}"), 40);
        assert!(t.lines().all(|l| l.chars().count() <= 40), "{t}");
        assert!(t.lines().skip(1).all(|l| l.starts_with("  word")), "{t}");
    }

    #[test]
    fn every_documented_code_has_a_namespace_and_a_body() {
        let entries = code_entries();
        assert!(entries.len() > 50, "{} codes", entries.len());
        let e = code_entry("psl::unknown_actor").expect("documented");
        assert_eq!(e.namespace, "psl:: — the language");
        assert!(e.body.contains("tests/bad/unknown-actor.psl"));
        assert!(code_entry("psl::no_such_code").is_none());
        assert!(!is_code("How a diagnostic looks") && is_code("compile::too_close"));
    }
}
