//! `--live`: the flight served to Foxglove as it happens (`shoot`), or a flight log played to
//! it (`replay`), through `dronecine-live`. What the terminal says: where to connect, and at
//! the end what was served and what the loop's ticks cost with a client connected.

use std::net::SocketAddr;
use std::path::Path;

use dronecine_flight::lateness::Lateness;
use dronecine_live::{LiveServer, LiveSummary};

/// Binds the live view's server and says where to connect; `Err` says why it cannot serve
/// there, and how to fix it.
pub fn serve(addr: SocketAddr) -> Result<LiveServer, String> {
    let server = LiveServer::bind(addr).map_err(|e| {
        format!("{e}\n  help: give --live another ADDR:PORT (`--live 127.0.0.1:8766`)")
    })?;
    errln!(
        "live view: {} (in Foxglove: Open connection → Foxglove WebSocket)",
        server.url()
    );
    Ok(server)
}

/// `p99 0.41 ms, max 1.20 ms over 2,300 ticks`.
fn lateness_phrase(l: &Lateness) -> String {
    format!(
        "p99 {:.2} ms, max {:.2} ms over {} ticks",
        l.p99_s * 1e3,
        l.max_s * 1e3,
        l.ticks
    )
}

/// The live view's closing line: the ticks served and dropped, the clients, and the loop's
/// lateness with a client connected and without.
pub fn summary_line(s: &LiveSummary) -> String {
    let clients = match s.clients_max {
        0 => "no client connected".to_string(),
        1 => "1 client".to_string(),
        n => format!("up to {n} clients at once"),
    };
    let mut line = format!(
        "live view: {} ticks served, {} dropped ({clients})",
        s.ticks_served, s.ticks_dropped
    );
    if s.events_dropped > 0 {
        line += &format!(", {} events dropped", s.events_dropped);
    }
    if let Some(l) = &s.with_client {
        line += &format!(
            "; the loop's lateness with a client connected: {}",
            lateness_phrase(l)
        );
        if let Some(w) = &s.without_client {
            line += &format!(" (without: {})", lateness_phrase(w));
        }
    }
    line
}

/// `replay --live`: plays the log at `file` to the clients of a server on `addr`, at `speed`
/// times real time, from the first client's subscription on. `Err` says what went wrong.
pub fn play(file: &Path, addr: SocketAddr, speed: f64) -> Result<(), String> {
    let bytes =
        std::fs::read(file).map_err(|e| format!("cannot read `{}`: {e}", file.display()))?;
    let server = serve(addr)?;
    errln!(
        "live view: playing `{}` at {speed}× once a client subscribes (Ctrl-C to stop)",
        file.display()
    );
    let played = dronecine_live::play(&server, &bytes, speed)?;
    errln!(
        "live view: played {:.1} s of flight, {} messages",
        played.duration_s,
        played.messages
    );
    if let Some(d) = played.damage {
        errln!(
            "warning: the playback stops where `{}` is damaged ({d})",
            file.display()
        );
    }
    server.stop();
    Ok(())
}
