//! The NatNet backend's tests: the codec byte for byte, and the client against a server played
//! over loopback.

mod client;
mod codec;
