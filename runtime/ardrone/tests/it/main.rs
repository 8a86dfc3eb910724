//! The AR.Drone backend's tests: the codecs byte for byte, and the client against a drone
//! played over loopback.

mod client;
mod codec;
