//! The AR.Drone 2.0 backend: its wire codecs, pure functions with byte-layout tests, and the
//! [`Drone`](dronecine_backend::Drone) over UDP.
//!
//! - [`at`]: AT commands (client → drone, UDP 5556): the encoder with its one sequence
//!   counter, the generic command → `AT*PCMD` mapping with a profile's limits, the
//!   start-up `AT*CONFIG` lines, and a tolerant parser for the emulator.
//! - [`navdata`]: navdata packets (drone → client, UDP 5554): the decoder (header, state
//!   bits, options, checksum, demo option), a packet writer, and the sequence rule.
//! - [`client`]: the drone over UDP (the navdata kick and `general:navdata_demo` handshake,
//!   CONFIG with its ACK, the limits written at start, FTRIM before take-off, non-blocking
//!   sockets), and the `status` read-out.
//! - [`url`]: the address, `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`.

pub mod at;
pub mod client;
pub mod navdata;
pub mod url;
