//! [`play`]: a flight log played to the live view's clients as it was flown, paced by its
//! messages' log times (in real time, or faster or slower): `replay --live`. Every message
//! goes out as the log holds it, on its own topic under its own schema: what the client sees
//! is the log.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use mcap::read::Options;

use crate::server::LiveServer;

/// What a playback served.
#[derive(Clone, Debug, PartialEq)]
pub struct Playback {
    /// Messages played (each to the clients subscribed to its topic).
    pub messages: u64,
    /// Flight time played, seconds.
    pub duration_s: f64,
    /// Where the log stops being readable, when it does before its end: the playback ends
    /// there.
    pub damage: Option<String>,
}

/// The slowest and fastest playback speeds.
pub const SPEEDS: std::ops::RangeInclusive<f64> = 0.01..=1000.0;

/// `Err` says why `speed` is not a playback speed ([`SPEEDS`]).
pub fn check_speed(speed: f64) -> Result<(), String> {
    if speed.is_finite() && SPEEDS.contains(&speed) {
        return Ok(());
    }
    Err(format!(
        "--speed {speed} is outside {}–{} (1: the flight in real time)",
        SPEEDS.start(),
        SPEEDS.end()
    ))
}

/// Plays the MCAP file's `bytes` to `server`'s clients at `speed` times real time, once a
/// client has subscribed (the flight starts for its first viewer). The log's channels are
/// advertised first, each with its schema. An error names what is not MCAP.
pub fn play(server: &LiveServer, bytes: &[u8], speed: f64) -> Result<Playback, String> {
    check_speed(speed)?;
    let stream = || {
        mcap::MessageStream::new_with_options(bytes, Options::IgnoreEndMagic.into())
            .map_err(|e| format!("not a readable MCAP file: {e}"))
    };
    // The channels, in the order their first messages come, and where the log stops.
    let mut out = server.out();
    let mut ids = BTreeMap::new();
    let mut damage = None;
    for m in stream()? {
        let m = match m {
            Ok(m) => m,
            Err(e) => {
                damage = Some(e.to_string());
                break;
            }
        };
        if ids.contains_key(&m.channel.id) {
            continue;
        }
        let c = &m.channel;
        let schema = c
            .schema
            .as_ref()
            .map(|s| (s.name.as_str(), s.encoding.as_str(), &s.data[..]));
        let id = out
            .channel(&c.topic, &c.message_encoding, schema)
            .map_err(|e| e.to_string())?;
        ids.insert(c.id, id);
    }
    server.wait_for_subscriber();
    let start = Instant::now();
    let mut last_ns = 0u64;
    for m in stream()?.map_while(Result::ok) {
        let Some(&id) = ids.get(&m.channel.id) else {
            break;
        };
        let due = Duration::from_secs_f64(m.log_time as f64 * 1e-9 / speed);
        if let Some(wait) = due.checked_sub(start.elapsed()) {
            std::thread::sleep(wait);
        }
        out.publish(id, m.log_time, &m.data);
        last_ns = last_ns.max(m.log_time);
    }
    Ok(Playback {
        messages: out.messages,
        duration_s: last_ns as f64 * 1e-9,
        damage,
    })
}
