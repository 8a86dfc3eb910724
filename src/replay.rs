//! `dronecine replay`: re-run the controller of a flight log on its logged inputs, check that
//! it gives the logged commands bit for bit, and print the flight's report again.

use std::path::Path;
use std::process::ExitCode;

use dronecine_runtime::log::FlightLog;
use dronecine_runtime::replay;

pub fn run(file: &Path, json: bool) -> ExitCode {
    let log = match FlightLog::open(file) {
        Ok(l) => l,
        Err(e) => {
            eprintln!(
                "error: cannot read the flight log `{}`: {e}",
                file.display()
            );
            return ExitCode::FAILURE;
        }
    };
    if log.truncated {
        eprintln!(
            "warning: `{}` ends early (the flight was cut short); replaying the {} ticks it holds",
            file.display(),
            log.ticks.len()
        );
    }
    let r = match replay::replay(&log) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot replay `{}`: {e}", file.display());
            return ExitCode::FAILURE;
        }
    };
    if json {
        let value = serde_json::json!({
            "ticks": r.ticks,
            "mismatches": r.mismatches,
            "report": r.report,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&value).unwrap_or_default()
        );
    } else {
        print!(
            "{}",
            crate::shoot::render_report(
                &r.report,
                &log.header.profile_name,
                &log.header.controller.kind
            )
        );
    }
    match &r.first_mismatch {
        None => {
            eprintln!(
                "replay: {} controller ticks reproduce the logged commands exactly ({} {})",
                r.ticks, log.header.controller.kind, log.header.profile_name
            );
            ExitCode::SUCCESS
        }
        Some(m) => {
            eprintln!(
                "error: replay differs from the log on {} of {} ticks; first at tick {} \
                 (t = {:.3} s): logged {:?}, replayed {:?}",
                r.mismatches, r.ticks, m.tick, m.t_s, m.logged, m.replayed
            );
            ExitCode::FAILURE
        }
    }
}
