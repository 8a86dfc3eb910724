//! Fuzz the whole front end on arbitrary bytes: UTF-8 decoding, parse + semantic pass,
//! the diagnostic renderer, and the formatter (which must be idempotent).
#![no_main]

use dronecine_diag as diag;
use dronecine_grammar::{check, decode, format, Options};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let src = match decode(data) {
        Ok(src) => src,
        Err((text, diags)) => {
            // Invalid UTF-8: the display copy and its diagnostics must still render.
            let _ = diag::render("fuzz.psl", &text, &diags, false, 100);
            return;
        }
    };

    let checked = check(src, &Options::default());
    let _ = checked.has_errors();
    let _ = diag::render("fuzz.psl", src, &checked.diagnostics, false, 100);

    match format(src) {
        Ok(text) => match format(&text) {
            Ok(again) => assert_eq!(
                again, text,
                "format is not idempotent\n--- input\n{src:?}\n--- format(input)\n{text:?}\n--- format(format(input))\n{again:?}"
            ),
            Err(diags) => panic!(
                "format(input) does not parse\n--- input\n{src:?}\n--- format(input)\n{text:?}\n--- diagnostics\n{}",
                diag::render("formatted.psl", &text, &diags, false, 100)
            ),
        },
        Err(diags) => {
            let _ = diag::render("fuzz.psl", src, &diags, false, 100);
        }
    }
});
