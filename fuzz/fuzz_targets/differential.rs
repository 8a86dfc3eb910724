//! Differential fuzzing of the parser's fast path (`fast.rs`) against pest: on any UTF-8
//! input, `parse` (fast path first) equals `parse_with_pest` (tree and diagnostics), so the
//! fast path never accepts a line pest rejects nor builds a different `Line`; and on an
//! ASCII line pest accepts, the fast path does not give up.
#![no_main]

use dronecine_grammar::{fast, parser};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let (fast_file, fast_diags) = parser::parse(src);
    let (pest_file, pest_diags) = parser::parse_with_pest(src);
    assert_eq!(fast_file, pest_file, "trees differ for {src:?}");
    assert_eq!(fast_diags, pest_diags, "diagnostics differ for {src:?}");
    for line in &pest_file.lines {
        let text = &src[line.span.start..line.span.end];
        let fast_line = fast::parse_line(text, line.span.start, line.number);
        if let Some(f) = &fast_line {
            assert!(!line.error, "fast path accepts a rejected line {text:?}");
            assert_eq!(f, line, "lines differ for {text:?}");
        }
        if !line.error && text.is_ascii() {
            assert!(
                fast_line.is_some(),
                "fast path gives up on an accepted ASCII line {text:?}"
            );
        }
    }
});
