//! `dronecine check`: parse and resolve scripts, print a summary or the diagnostics. A script
//! whose `drone` line names a profile file has that file checked too (its diagnostics point
//! into the TOML), so a script that passes `check` does not fail `compile` on its profile.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use dronecine_diag::Severity;
use dronecine_diag::{self as diag, JsonDiagnostic};
use dronecine_grammar::script::DroneRef;
use dronecine_grammar::{Checked, Options, Script};
use dronecine_profile::{Profile, ProfileError};
use serde::Serialize;

use crate::files;

#[derive(Serialize)]
struct FileSummary {
    file: String,
    ok: bool,
    annotation: bool,
    actors: usize,
    shots: usize,
    duration_s: f64,
    errors: usize,
    warnings: usize,
}

#[derive(Serialize)]
struct JsonReport {
    files: Vec<FileSummary>,
    diagnostics: Vec<JsonDiagnostic>,
}

/// The outcome for one file, rendered or as records.
pub struct FileResult {
    pub name: String,
    /// The text the diagnostics' spans point into.
    pub text: String,
    pub checked: Checked,
}

/// Read, decode and check one script. A file that cannot be read or decoded yields a result
/// whose diagnostics say why.
pub fn check_file(path: &std::path::Path) -> FileResult {
    let name = path.display().to_string();
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) => {
            let d = dronecine_diag::Diagnostic::error(
                dronecine_grammar::PslCode::FileNotFound,
                Default::default(),
                format!("cannot read `{name}`: {e}"),
            )
            .with_help(
                "check the file name; `dronecine check` takes .psl files or folders of them",
            );
            return FileResult {
                name,
                text: String::new(),
                checked: Checked {
                    script: None,
                    diagnostics: vec![d],
                },
            };
        }
    };
    let (text, checked) = match dronecine_grammar::decode(&bytes) {
        Ok(src) => {
            let base = files::base_dir(path);
            let opts = Options {
                known_drones: dronecine_profile::BUILTIN_NAMES,
                base_dir: Some(&base),
            };
            let checked = dronecine_grammar::check(src, &opts);
            (src.to_string(), checked)
        }
        Err((lossy, diagnostics)) => (
            lossy,
            Checked {
                script: None,
                diagnostics,
            },
        ),
    };
    FileResult {
        name,
        text,
        checked,
    }
}

/// The diagnostics of the profile file a checked script names (`drone "mine.toml"`), with
/// the file's name and text for rendering.
struct ProfileCheck {
    name: String,
    text: String,
    diagnostics: Vec<dronecine_diag::Diagnostic>,
}

/// The [`ProfileCheck`] of `path`'s script; `None` when the script names no profile file,
/// when the profile has nothing to say, or when the script itself has errors (the profile is
/// checked once the script is).
fn check_profile(path: &std::path::Path, checked: &Checked) -> Option<ProfileCheck> {
    if checked.has_errors() {
        return None;
    }
    let scene = checked.script.as_ref()?.scene.as_ref()?;
    let Some(DroneRef::File { path: file }) = &scene.drone else {
        return None;
    };
    let full = files::base_dir(path).join(file);
    let name = full.display().to_string();
    let (text, diagnostics) = match Profile::load(&full) {
        Ok((_, source, warnings)) => (source, warnings),
        Err(ProfileError::Invalid {
            source,
            diagnostics,
        }) => (source, diagnostics),
        // Read a moment ago by the script's check, unreadable now: say so.
        Err(e @ ProfileError::Unreadable { .. }) => (
            String::new(),
            e.not_found(Default::default()).into_iter().collect(),
        ),
    };
    (!diagnostics.is_empty()).then_some(ProfileCheck {
        name,
        text,
        diagnostics,
    })
}

/// The command that lists every diagnostic of the script `name` (its profile's included).
pub fn lister(name: &str) -> String {
    format!("dronecine check --format json {name}")
}

fn summary_line(name: &str, s: &Script) -> String {
    let actors = s.cast.len();
    let shots = s.timeline.len();
    format!(
        "{name}: {} {}, {} {}, {:.1} s{}",
        actors,
        if actors == 1 { "actor" } else { "actors" },
        shots,
        if shots == 1 { "shot" } else { "shots" },
        s.duration_s,
        if s.is_annotation() && shots > 0 {
            " (film annotation)"
        } else {
            ""
        }
    )
}

pub fn run(inputs: &[PathBuf], json: bool, color: bool) -> ExitCode {
    let paths = files::expand(inputs);
    let mut failed = 0usize;
    let mut report = JsonReport {
        files: Vec::new(),
        diagnostics: Vec::new(),
    };
    let stdout = std::io::stdout();
    let stderr = std::io::stderr();
    if paths.is_empty() {
        errln!(
            "error: no .psl files found in {}",
            inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        return ExitCode::FAILURE;
    }
    for path in &paths {
        let r = check_file(path);
        let profile = check_profile(path, &r.checked);
        let all = || {
            r.checked
                .diagnostics
                .iter()
                .chain(profile.iter().flat_map(|p| &p.diagnostics))
        };
        let errors = all().filter(|d| d.severity == Severity::Error).count();
        let warnings = all().count() - errors;
        if errors > 0 {
            failed += 1;
        }
        if json {
            let script = r.checked.script.as_ref();
            report.files.push(FileSummary {
                file: r.name.clone(),
                ok: errors == 0,
                annotation: script.is_some_and(Script::is_annotation),
                actors: script.map_or(0, |s| s.cast.len()),
                shots: script.map_or(0, |s| s.timeline.len()),
                duration_s: script.map_or(0.0, |s| s.duration_s),
                errors,
                warnings,
            });
            report
                .diagnostics
                .extend(diag::to_json(&r.name, &r.text, &r.checked.diagnostics));
            if let Some(p) = &profile {
                report
                    .diagnostics
                    .extend(diag::to_json(&p.name, &p.text, &p.diagnostics));
            }
        } else {
            // Past the first diagnostics, `--format json` lists every one.
            let lister = lister(&r.name);
            if !r.checked.diagnostics.is_empty() {
                let text = diag::render_listed(
                    &r.name,
                    &r.text,
                    &r.checked.diagnostics,
                    color,
                    100,
                    Some(&lister),
                );
                let _ = stderr.lock().write_all(text.as_bytes());
            }
            if let Some(p) = &profile {
                let text = diag::render_listed(
                    &p.name,
                    &p.text,
                    &p.diagnostics,
                    color,
                    100,
                    Some(&lister),
                );
                let _ = stderr.lock().write_all(text.as_bytes());
            }
            let bad_profile = profile
                .as_ref()
                .filter(|p| p.diagnostics.iter().any(|d| d.severity == Severity::Error));
            if let Some(p) = bad_profile {
                let _ = writeln!(
                    stderr.lock(),
                    "error: the drone profile `{}` of `{}` is not valid",
                    p.name,
                    r.name
                );
            } else if let Some(s) = &r.checked.script {
                crate::out::stdout_result(writeln!(stdout.lock(), "{}", summary_line(&r.name, s)));
            }
        }
    }
    if json {
        crate::out::stdout_result(
            serde_json::to_writer_pretty(stdout.lock(), &report)
                .map_err(std::io::Error::from)
                .and_then(|()| writeln!(stdout.lock())),
        );
    } else if failed > 0 {
        let _ = writeln!(
            stderr.lock(),
            "error: {failed} of {} {} failed the check",
            paths.len(),
            if paths.len() == 1 { "file" } else { "files" }
        );
    }
    if failed > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
