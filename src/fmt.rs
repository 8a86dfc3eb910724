//! `dronecine fmt`: rewrite scripts in canonical form, or `--check` that they are; or
//! `--expand` one script's coverages into the shots the compiler flies.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use dronecine_diag as diag;

use crate::files;

pub fn run(inputs: &[PathBuf], check: bool, color: bool) -> ExitCode {
    let paths = files::expand(inputs);
    let mut failed = false;
    let stderr = std::io::stderr();
    for path in &paths {
        let name = path.display().to_string();
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) => {
                errln!("error: cannot read `{name}`: {e}");
                failed = true;
                continue;
            }
        };
        let src = match dronecine_grammar::decode(&bytes) {
            Ok(s) => s,
            Err((lossy, diags)) => {
                let _ = stderr
                    .lock()
                    .write_all(diag::render(&name, &lossy, &diags, color, 100).as_bytes());
                failed = true;
                continue;
            }
        };
        match dronecine_grammar::format(src) {
            Err(diags) => {
                let _ = stderr
                    .lock()
                    .write_all(diag::render(&name, src, &diags, color, 100).as_bytes());
                errln!("error: `{name}` was not formatted: fix the errors above first");
                failed = true;
            }
            Ok(formatted) if formatted == src => {}
            Ok(formatted) => {
                if check {
                    outln!("would reformat {name}");
                    failed = true;
                } else if let Err(e) = files::write_atomic(path, &formatted) {
                    errln!("error: cannot write `{name}`: {e}");
                    failed = true;
                } else {
                    outln!("formatted {name}");
                }
            }
        }
    }
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// `fmt --expand FILE`: the script, its coverages expanded for its drone, on standard output.
pub fn expand(inputs: &[PathBuf], color: bool) -> ExitCode {
    let [path] = inputs else {
        errln!(
            "error: --expand prints one script; give one FILE, not {}",
            inputs.len()
        );
        return ExitCode::FAILURE;
    };
    let loaded = match crate::compile::load_scene(path, color, "expanded", true) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let r = &loaded.file;
    match dronecine_grammar::format::expanded_text(&r.text, loaded.script()) {
        Ok(text) => {
            out!("{text}");
            ExitCode::SUCCESS
        }
        Err(diags) => {
            err!("{}", diag::render(&r.name, &r.text, &diags, color, 100));
            ExitCode::FAILURE
        }
    }
}
