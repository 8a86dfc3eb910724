//! "Did you mean …?": the closest words of a vocabulary to a misspelt one.

/// The candidates closest to `word`: an exact match ignoring case wins alone; otherwise all
/// candidates at the smallest edit distance, if that distance is small for the word's length.
pub fn closest<'c>(word: &str, candidates: impl IntoIterator<Item = &'c str>) -> Vec<&'c str> {
    if word.is_empty() || word.len() > 64 {
        return Vec::new();
    }
    let lower = word.to_lowercase();
    let mut best: Vec<&str> = Vec::new();
    let mut best_d = usize::MAX;
    for c in candidates {
        if c == word {
            continue;
        }
        if c.to_lowercase() == lower {
            return vec![c];
        }
        let d = strsim::damerau_levenshtein(&lower, &c.to_lowercase());
        let limit = match c.chars().count().max(word.chars().count()) {
            0..=2 => 1,
            3..=5 => 2,
            _ => 3,
        };
        if d > limit {
            continue;
        }
        if d < best_d {
            best_d = d;
            best.clear();
        }
        if d == best_d && !best.contains(&c) {
            best.push(c);
        }
    }
    best.truncate(3);
    best
}

/// A word cut to 40 characters for a message ("…" marks the cut).
pub fn shorten(w: &str) -> String {
    if w.chars().count() > 40 {
        format!("{}…", w.chars().take(37).collect::<String>())
    } else {
        w.to_string()
    }
}

/// "`a`", "`a` or `b`", "`a`, `b` or `c`".
pub fn or_list(words: &[&str]) -> String {
    let quoted: Vec<String> = words.iter().map(|w| format!("`{w}`")).collect();
    match quoted.len() {
        0 => String::new(),
        1 => quoted[0].clone(),
        n => format!("{} or {}", quoted[..n - 1].join(", "), quoted[n - 1]),
    }
}

/// "did you mean `front`?" or None.
pub fn did_you_mean<'c>(
    word: &str,
    candidates: impl IntoIterator<Item = &'c str>,
) -> Option<String> {
    let best = closest(word, candidates);
    if best.is_empty() {
        None
    } else {
        Some(format!("did you mean {}?", or_list(&best)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_typos_and_case_slips() {
        let words = ["front", "back", "34left", "MS", "MLS"];
        assert_eq!(closest("frnt", words), ["front"]);
        assert_eq!(closest("ms", words), ["MS"]);
        assert_eq!(closest("34lft", words), ["34left"]);
        assert!(closest("elephant", words).is_empty());
        assert_eq!(or_list(&["a", "b", "c"]), "`a`, `b` or `c`");
    }
}
