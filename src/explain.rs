//! `dronecine explain [TERM]`: what a word of the shot language or a diagnostic code means,
//! with an example, read from the reference docs built into the binary (`docs/language.md`
//! through `dronecine_grammar::reference`, `docs/diagnostics.md` through
//! `dronecine_diag::docs`); without a term, the vocabulary by kind and the codes by
//! namespace. A code the docs document is explained, whichever crate declares it.

use std::process::ExitCode;

use dronecine_diag::docs::{self, CodeEntry};
use dronecine_diag::suggest;
use dronecine_grammar::reference::{self, Entry, Naming};

/// The column prose is wrapped at.
const WIDTH: usize = 100;

pub fn run(term: &[String]) -> ExitCode {
    let term = term.join(" ");
    let term = term.trim();
    if term.is_empty() {
        out!("{}", listing());
        return ExitCode::SUCCESS;
    }
    let codes: Vec<CodeEntry> = (docs::code_entries().into_iter())
        .filter(|e| e.code == term || e.code.split("::").nth(1) == Some(term))
        .collect();
    let words = shown(term);
    if codes.is_empty() && words.is_empty() {
        let known = reference::words_known();
        let entries = docs::code_entries();
        let candidates = (known.iter().map(String::as_str)).chain(entries.iter().map(|e| e.code));
        let hint =
            suggest::did_you_mean(term, candidates).map_or(String::new(), |d| format!(" ({d})"));
        errln!(
            "error: `{}` is neither a word of the shot language nor a diagnostic code{hint}\n  \
             help: `dronecine explain` lists every word and every code",
            suggest::shorten(term)
        );
        return ExitCode::FAILURE;
    }
    let mut parts: Vec<String> = codes.iter().map(code_text).collect();
    parts.extend(words.iter().map(|e| word_text(term, e)));
    if let Some(more) = see_also(term) {
        parts.push(more);
    }
    out!("{}", parts.join("\n"));
    ExitCode::SUCCESS
}

/// The entries of `term` shown in full: the ones that name it first, or else all.
fn shown(term: &str) -> Vec<Entry> {
    let all = reference::entries(term);
    match all.iter().any(|e| e.naming == Naming::Primary) {
        true => (all.into_iter())
            .filter(|e| e.naming == Naming::Primary)
            .collect(),
        false => all,
    }
}

/// The sections that name `term` further in a span, when others name it first.
fn see_also(term: &str) -> Option<String> {
    let all = reference::entries(term);
    if !all.iter().any(|e| e.naming == Naming::Primary) {
        return None;
    }
    let also: Vec<String> = (all.iter())
        .filter(|e| e.naming == Naming::Secondary)
        .map(|e| match e.section.contains(&format!("`{}`", e.names)) {
            true => e.section.clone(),
            false => format!("{} (`{}`)", e.section, e.names),
        })
        .collect();
    (!also.is_empty()).then(|| docs::to_terminal(&format!("See also: {}.", also.join("; ")), WIDTH))
}

fn code_text(e: &CodeEntry) -> String {
    format!(
        "{} (docs/diagnostics.md, {})\n\n{}",
        e.code,
        e.namespace,
        docs::to_terminal(e.body.trim(), WIDTH)
    )
}

fn word_text(term: &str, e: &Entry) -> String {
    let mut s = format!("{term}: {} (docs/language.md)\n\n", e.section);
    for (column, cell) in &e.cells {
        if !cell.is_empty() {
            s.push_str(&docs::to_terminal(&format!("  {column}: {cell}"), WIDTH));
        }
    }
    if !e.cells.is_empty() {
        s.push('\n');
    }
    if !e.meaning.is_empty() {
        s.push_str(&docs::to_terminal(&e.meaning, WIDTH));
        s.push('\n');
    }
    if let Some(example) = e.whole_example() {
        s.push_str("Example, a whole script (`dronecine check` takes it):\n\n");
        for line in example.lines() {
            s.push_str(&format!("    {line}\n").replace("    \n", "\n"));
        }
    }
    s
}

/// The vocabulary by kind and the codes by namespace.
fn listing() -> String {
    let mut s = String::from(
        "The words of the shot language (`dronecine explain WORD`; docs/language.md):\n",
    );
    for (kind, words) in reference::vocabulary() {
        s.push_str(&docs::to_terminal(
            &format!("  {kind}: {}", words.join(", ")),
            WIDTH,
        ));
    }
    s.push_str("\nThe diagnostic codes (`dronecine explain CODE`; docs/diagnostics.md):\n");
    let entries = docs::code_entries();
    let mut namespaces: Vec<&str> = entries.iter().map(|e| e.namespace).collect();
    namespaces.dedup();
    for ns in namespaces {
        let codes: Vec<&str> = (entries.iter())
            .filter(|e| e.namespace == ns)
            .map(|e| e.code)
            .collect();
        s.push_str(&docs::to_terminal(
            &format!("  {ns}: {}", codes.join(", ")),
            WIDTH,
        ));
    }
    s
}
