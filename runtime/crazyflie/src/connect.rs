//! The exchanges that set a Crazyflie up for a flight, each a request and its answer over
//! the [`Link`]: the protocol version, the log TOC (read until every logged variable is
//! found), the log blocks (`log`), and parameter writes by name.

use std::time::{Duration, Instant};

use dronecine_backend::BackendError;

use crate::crtp::{log_cmd, LogOps, ToDrone, PARAM_UINT8};
use crate::link::Link;
use crate::log::{all_vars, Layout, BLOCKS};

/// The lowest protocol version the backend speaks: version 4 brought the TOC and log
/// commands of 16-bit ids (firmware 2020 on).
pub const MIN_PROTOCOL: u8 = 4;
/// TOC entries asked for at once.
const TOC_WINDOW: usize = 8;
/// A TOC entry not answered within this is asked for again.
const TOC_RESEND: Duration = Duration::from_millis(150);
/// The firmware's errno for a block that exists already (a create sent twice).
const EEXIST: u8 = 17;

/// An errno as the firmware means it.
pub fn errno_text(e: u8) -> String {
    match e {
        2 => "no such entry (ENOENT)".into(),
        7 => "too large (E2BIG)".into(),
        8 => "not a command it knows (ENOEXEC)".into(),
        12 => "out of memory (ENOMEM)".into(),
        13 => "read-only (EACCES)".into(),
        17 => "exists already (EEXIST)".into(),
        22 => "the wrong type (EINVAL)".into(),
        e => format!("errno {e}"),
    }
}

/// The Crazyflie's CRTP protocol version; an error naming the address when it does not
/// answer within `timeout`, or when it is older than [`MIN_PROTOCOL`].
pub fn protocol_version(link: &Link, timeout: Duration) -> Result<u8, BackendError> {
    let v = link.request(&ToDrone::ProtocolVersion, timeout, |s| s.protocol_version)?;
    let Some(v) = v else {
        let why = link
            .state()
            .link_error
            .clone()
            .map_or(String::new(), |e| format!(" ({e})"));
        return Err(BackendError::Link(format!(
            "no answer from a Crazyflie at {} within {:.1} s{why}: is it on, and the address \
             right?",
            link.url(),
            timeout.as_secs_f64()
        )));
    };
    if v < MIN_PROTOCOL {
        return Err(BackendError::Refused(format!(
            "the Crazyflie speaks CRTP protocol {v}; dronecine needs {MIN_PROTOCOL} or newer: \
             update its firmware"
        )));
    }
    Ok(v)
}

/// Reads the log TOC until every logged variable is found: each one's (TOC id, type code),
/// in [`all_vars`]' order.
pub fn read_toc(link: &Link, timeout: Duration) -> Result<Vec<(u16, u8)>, BackendError> {
    let Some((count, _)) = link.request(&ToDrone::LogTocInfo, timeout, |s| s.toc_info)? else {
        return Err(BackendError::Link(format!(
            "the Crazyflie at {} did not tell its log TOC within {:.1} s",
            link.url(),
            timeout.as_secs_f64()
        )));
    };
    let count = usize::from(count);
    let mut asked: Vec<Option<Instant>> = vec![None; count];
    let deadline = Instant::now() + timeout + Duration::from_millis(20) * count as u32;
    loop {
        let (seen, found) = {
            let s = link.state();
            let found: Option<Vec<(u16, u8)>> = s.toc_found.iter().copied().collect();
            (s.toc_seen.clone(), found)
        };
        if let Some(found) = found {
            return Ok(found);
        }
        if seen.len() == count && seen.iter().all(|&s| s) {
            return Err(missing(link));
        }
        if Instant::now() >= deadline {
            return Err(BackendError::Link(format!(
                "the Crazyflie at {} did not give its log TOC ({count} entries) in time",
                link.url()
            )));
        }
        ask_toc(link, &seen, &mut asked)?;
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Asks for the next TOC entries (at most [`TOC_WINDOW`] unanswered), again for those
/// unanswered for [`TOC_RESEND`].
fn ask_toc(link: &Link, seen: &[bool], asked: &mut [Option<Instant>]) -> Result<(), BackendError> {
    let now = Instant::now();
    let mut waiting = 0;
    for (i, at) in asked.iter_mut().enumerate() {
        if seen.get(i).copied().unwrap_or(false) {
            continue;
        }
        match *at {
            Some(t) if now.duration_since(t) < TOC_RESEND => waiting += 1,
            _ if waiting < TOC_WINDOW => {
                link.send_message(&ToDrone::LogTocItem(i as u16))?;
                *at = Some(now);
                waiting += 1;
            }
            _ => break,
        }
    }
    Ok(())
}

/// The refusal naming the variables a TOC read to its end lacks.
fn missing(link: &Link) -> BackendError {
    let s = link.state();
    let names: Vec<String> = all_vars()
        .zip(s.toc_found.iter())
        .filter(|(_, f)| f.is_none())
        .map(|(v, _)| format!("{}.{}", v.group, v.name))
        .collect();
    BackendError::Refused(format!(
        "the Crazyflie's log has no {}: update its firmware (supervisor.info came with \
         2023.06)",
        names.join(", ")
    ))
}

/// Deletes every log block, then creates and starts [`BLOCKS`] with the TOC's ids and
/// types; their layouts go to the link's reader.
pub fn start_blocks(link: &Link, toc: &[(u16, u8)], timeout: Duration) -> Result<(), BackendError> {
    log_command(link, &ToDrone::LogReset, log_cmd::RESET, 0, timeout)?;
    let mut layouts = [None; 2];
    let mut at = 0;
    for (i, block) in BLOCKS.iter().enumerate() {
        let vars: Vec<(u8, u16)> = toc[at..at + block.vars.len()]
            .iter()
            .map(|&(id, kind)| (kind, id))
            .collect();
        at += block.vars.len();
        let kinds: Vec<u8> = vars.iter().map(|&(k, _)| k).collect();
        layouts[i] = Some(Layout::new(block, &kinds).ok_or_else(|| {
            BackendError::Refused(format!(
                "the Crazyflie's log types {kinds:?} do not make log block {}",
                block.id
            ))
        })?);
        let mut buf = [0u8; 27];
        let ops = LogOps::encode(&vars, &mut buf)
            .map_err(|e| BackendError::Refused(format!("log block {}: {e}", block.id)))?;
        let create = ToDrone::LogCreate {
            block: block.id,
            ops,
        };
        log_command(link, &create, log_cmd::CREATE_BLOCK_V2, block.id, timeout)?;
    }
    link.set_layouts(layouts);
    for block in &BLOCKS {
        let start = ToDrone::LogStart {
            block: block.id,
            period_10ms: block.period_10ms,
        };
        log_command(link, &start, log_cmd::START, block.id, timeout)?;
    }
    Ok(())
}

/// Sends a log command and waits for its answer; a refusal names the firmware's errno (a
/// create answered "exists already" is done).
fn log_command(
    link: &Link,
    message: &ToDrone,
    command: u8,
    block: u8,
    timeout: Duration,
) -> Result<(), BackendError> {
    link.state().log_acks.clear();
    let answer = link.request(message, timeout, |s| {
        (s.log_acks.iter())
            .find(|&&(c, b, _)| c == command && (b == block || command == log_cmd::RESET))
            .map(|&(_, _, e)| e)
    })?;
    match answer {
        Some(0) => Ok(()),
        Some(EEXIST) if command == log_cmd::CREATE_BLOCK_V2 => Ok(()),
        Some(e) => Err(BackendError::Refused(format!(
            "the Crazyflie refused log command {command} for block {block}: {}",
            errno_text(e)
        ))),
        None => Err(BackendError::Link(format!(
            "the Crazyflie at {} did not answer log command {command} within {:.1} s",
            link.url(),
            timeout.as_secs_f64()
        ))),
    }
}

/// Writes the byte parameter `group.name` by name and waits for the Crazyflie's answer.
pub fn set_u8_param(
    link: &Link,
    group: &str,
    name: &str,
    value: u8,
    timeout: Duration,
) -> Result<(), BackendError> {
    let full = format!("{group}.{name}");
    link.state().param_acks.retain(|(n, _)| *n != full);
    let message = ToDrone::SetParam {
        group,
        name,
        kind: PARAM_UINT8,
        value: &[value],
    };
    let answer = link.request(&message, timeout, |s| {
        s.param_acks
            .iter()
            .find(|(n, _)| *n == full)
            .map(|&(_, e)| e)
    })?;
    match answer {
        Some(0) => Ok(()),
        Some(e) => Err(BackendError::Refused(format!(
            "the Crazyflie refused {full} = {value}: {}",
            errno_text(e)
        ))),
        None => Err(BackendError::Link(format!(
            "the Crazyflie at {} did not answer {full} = {value} within {:.1} s",
            link.url(),
            timeout.as_secs_f64()
        ))),
    }
}
