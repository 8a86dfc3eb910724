//! The live view: the flight as it happens, served over the Foxglove WebSocket protocol with
//! the `foxglove` crate's server (`shoot --live`, `replay --live`). Its topics, schemas and
//! message bytes are the flight log's: the log's own schedule and encoders
//! ([`FlightTopics`](dronecine_mcap::log::FlightTopics)) write them to the server's channels,
//! so the flight log and the live view look the same in Foxglove.
//!
//! Invariant: the loop never waits for the live view. The loop's side ([`LiveFeed`], a
//! [`FlightSink`](dronecine_mcap::record::FlightSink), beside the log through [`Tee`]) copies
//! each tick into a preallocated slot and hands it over with `try_send`; a tick the live
//! thread has no room for is dropped and counted. The live thread encodes and logs the
//! messages; the server runs on a tokio runtime of its own; both at a lower priority than the
//! loop. A client that reads slower than the flight loses the oldest of the messages queued
//! for it ([`LiveServer`]), never the loop's time. The feed measures the loop's lateness with
//! a client connected and without ([`LiveSummary`]).
//!
//! - [`LiveServer`]: the WebSocket server, bound to an address (`shoot --live` binds
//!   `127.0.0.1:8765`, Foxglove's default, unless told), its channels, the latched topics (the scene, the lens) that each
//!   client gets when it subscribes.
//! - [`LiveFeed`] and [`Tee`]: a flight served as it is flown.
//! - [`play`]: a flight log played back, paced by its log times (`replay --live`).
//! - [`LiveWorld`]: the world without a flight loop, the simulator's truth (`emulate --live`).

mod feed;
mod player;
mod server;
mod world;

use std::fmt;
use std::net::SocketAddr;

pub use feed::{LiveFeed, LiveSummary, Tee, POLL_MAX, SLOTS};
pub use player::{check_speed, play, Playback, SPEEDS};
pub use server::LiveServer;
pub use world::LiveWorld;

/// Why the live view could not start.
#[derive(Debug)]
pub enum LiveError {
    /// The address could not be served (in use, not this machine's).
    Bind { addr: SocketAddr, detail: String },
}

impl fmt::Display for LiveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LiveError::Bind { addr, detail } => {
                write!(f, "cannot serve the live view on {addr}: {detail}")
            }
        }
    }
}

impl std::error::Error for LiveError {}
