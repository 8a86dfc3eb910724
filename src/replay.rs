//! `dronecine replay`: re-run the controller of a flight log on its logged inputs, check that
//! it gives the logged commands bit for bit, and print the flight's report again. After damage
//! in the log it resumes at the next key frame (the controller's state the log keeps at the
//! start of each chunk) and says so.

use std::path::Path;
use std::process::ExitCode;

use dronecine_flight::replay;
use dronecine_mcap::log::FlightLog;

/// `live`: then play the log to Foxglove on this address, at this speed (`--live`).
pub fn run(file: &Path, json: bool, live: Option<(std::net::SocketAddr, f64)>) -> ExitCode {
    if let Some((_, speed)) = live {
        if let Err(e) = dronecine_live::check_speed(speed) {
            errln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }
    let log = match FlightLog::open(file) {
        Ok(l) => l,
        Err(e) => {
            errln!(
                "error: cannot read the flight log `{}`: {e}",
                file.display()
            );
            return ExitCode::FAILURE;
        }
    };
    for line in damage_warnings(file, &log) {
        errln!("{line}");
    }
    let r = match replay::replay(&log) {
        Ok(r) => r,
        Err(e) => {
            errln!("error: cannot replay `{}`: {e}", file.display());
            return ExitCode::FAILURE;
        }
    };
    if json {
        let value = serde_json::json!({
            "ticks": r.ticks,
            "unreplayed": r.unreplayed,
            "resumed": r.resumed,
            "state_mismatches": r.state_mismatches,
            "damage": log.damage.iter().map(|d| serde_json::json!({
                "offset": d.offset,
                "detail": d.detail,
                "cut": d.cut,
                "tick": d.tick,
                "resumed_at": d.resumed_at,
            })).collect::<Vec<_>>(),
            "mismatches": r.mismatches,
            "backend": log.header.backend,
            "seed": log.header.seed,
            "sim_effects_off": log.header.sim_effects_off,
            "report": r.report,
        });
        outln!(
            "{}",
            serde_json::to_string_pretty(&value).unwrap_or_default()
        );
    } else {
        // The flight's warnings and errors, as `shoot` told them (its events; the script's
        // text is in the log, so a finding of the director's quotes its line).
        let script_name = format!("{}.psl", log.header.script_name);
        let mut told = crate::shoot::EventTally::new(&script_name, &log.header.script_text);
        for text in log.events.iter().filter_map(|e| told.text(e)) {
            errln!("{text}");
        }
        // A log cut before the flight's end does not say how the flight ended.
        use crate::report::{render, Ending, Next};
        let ended = log.events.iter().any(|e| e.kind == "flight_end");
        let ending = match ended {
            false => Ending::Unfinished,
            true => Ending::of(&r.report),
        };
        out!(
            "{}",
            render(
                &r.report,
                ending,
                &log.header.profile_name,
                &log.header.controller.kind,
                Next::Replayed(file)
            )
        );
    }
    let mut ok = true;
    match &r.first_mismatch {
        None => {
            if r.ticks > 0 {
                errln!(
                    "replay: {} controller ticks reproduce the logged commands exactly ({} {}; {})",
                    r.ticks,
                    log.header.controller.kind,
                    log.header.profile_name,
                    flown_on(&log.header)
                );
            } else if r.unreplayed == 0 {
                // Nothing was checked: say so rather than "0 ticks reproduce exactly".
                errln!(
                    "replay: the log holds no controller tick (the flight never reached its \
                     first tick, or the log was cut before it): nothing to check"
                );
            }
        }
        Some(m) => {
            ok = false;
            errln!(
                "error: replay differs from the log on {} of {} ticks; first at tick {} \
                 (t = {:.3} s): logged {:?}, replayed {:?}",
                r.mismatches,
                r.ticks,
                m.tick,
                m.t_s,
                m.logged,
                m.replayed
            );
        }
    }
    if r.resumed > 0 {
        errln!(
            "replay: resumed after {} {} in the log from the controller's state logged at the \
             start of the next intact chunk (the ticks lost in the damage are not checked)",
            r.resumed,
            if r.resumed == 1 { "gap" } else { "gaps" }
        );
    }
    if r.state_mismatches > 0 {
        ok = false;
        errln!(
            "error: the replayed controller's state differs from the state the log keeps at {} \
             of its chunk starts",
            r.state_mismatches
        );
    }
    if let Some(k) = r.first_unreplayed {
        ok = false;
        let at = log.ticks.get(k).map_or(f64::NAN, |t| t.input.t_s);
        errln!(
            "error: {} ticks after damage (the first at t = {at:.3} s) are in the report but \
             were not replayed: the controller's state after a gap depends on the ticks lost in \
             it, and no key frame after the gap gives it (a log written without key frames)",
            r.unreplayed
        );
    }
    if let Some((addr, speed)) = live {
        if let Err(e) = crate::live::play(file, addr, speed) {
            errln!("error: {e}");
            ok = false;
        }
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// One warning line per stretch of `log` the reader skipped and one for a log that ends
/// early: where, why, and what it costs (shared by `replay` and `identify`).
pub fn damage_warnings(file: &Path, log: &FlightLog) -> Vec<String> {
    let name = file.display();
    let t = |k: usize| log.ticks.get(k).map(|t| t.input.t_s);
    log.damage
        .iter()
        .map(|d| match d.resumed_at {
            Some(resumed) => {
                // Consecutive ticks on either side, or the flight's first tick after it (its
                // start mark read): no tick was in what was skipped.
                let period_s = 1.0 / log.header.rate_hz;
                let first = log
                    .key_frames
                    .first()
                    .is_some_and(|f| f.tick == 0 && f.state.is_none());
                let lost = match (d.tick.checked_sub(1).and_then(t), t(d.tick)) {
                    (Some(a), Some(b)) if b - a < 1.5 * period_s => "no tick is lost".to_string(),
                    (None, Some(_)) if first => "no tick is lost".to_string(),
                    (Some(a), Some(b)) => {
                        format!("the ticks between t = {a:.3} s and {b:.3} s are lost")
                    }
                    (None, Some(b)) => format!("the ticks before t = {b:.3} s are lost"),
                    (Some(a), None) => format!("the ticks after t = {a:.3} s are lost"),
                    (None, None) => "no tick was read around it".to_string(),
                };
                format!(
                    "warning: `{name}` is damaged at byte {} ({}): skipped {} bytes to the next \
                     intact record, at byte {resumed}; {lost}",
                    d.offset,
                    d.detail,
                    resumed - d.offset
                )
            }
            None if d.cut => format!(
                "warning: `{name}` ends early, at byte {} ({}): the flight was cut short, or the \
                 copy did not finish; read {} ticks",
                d.offset,
                d.detail,
                log.ticks.len()
            ),
            None => format!(
                "warning: `{name}` is damaged from byte {} on ({}), with no intact chunk after \
                 it; read {} ticks",
                d.offset,
                d.detail,
                log.ticks.len()
            ),
        })
        .collect()
}

/// Where the logged flight was flown, as a reader wants it to fly it again: the drone's URL,
/// or the simulator's seed and the effects that were off (`shoot --seed N --sim-off …`).
fn flown_on(h: &dronecine_mcap::record::FlightHeader) -> String {
    if h.backend != "sim" {
        return format!("flown on {}", h.backend);
    }
    let seed = h.seed.map_or(String::new(), |s| format!(", seed {s}"));
    let effects = h.sim_effects_off.as_deref().map_or(String::new(), |off| {
        format!(", {}", crate::shoot::effects_off_phrase(off))
    });
    format!("flown on the simulator{seed}{effects}")
}
