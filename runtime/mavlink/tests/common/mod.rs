//! The Python peers of this folder, on pymavlink (`dronecine-pypeer`).

#![allow(dead_code)]

use std::path::PathBuf;

pub use dronecine_pypeer::{close, num, Peer};

/// The Python with pymavlink, or `None` (after saying why) when the test is to be skipped.
pub fn python(test: &str) -> Option<String> {
    dronecine_pypeer::python(test, "pymavlink")
}

/// Starts this folder's `script` with `args`.
pub fn peer(python: &str, script: &str, args: &[&str]) -> Peer {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join(script);
    Peer::start(python, &path, args)
}
