//! The transcendental functions of the runtime: the compiler's portable ones
//! ([`dronecine_compiler::math`], the pure-Rust `libm` crate), the same bits on every machine.
//!
//! `dronecine replay` re-runs the controller on a flight log and requires every command to
//! come out bit for bit as logged, on whatever machine reads the log; a seeded simulated
//! flight and a calibration fit are the same numbers on any machine. So the controllers, the
//! simulator, the identification and the protocols call these, never `f64::sin` and the
//! like: test `the_runtime_calls_no_platform_math` keeps it so, and `runtime/tests/servo.rs`
//! pins a closed-loop flight's commands to a checksum.

pub use dronecine_compiler::math::*;

#[cfg(test)]
mod tests {
    /// The runtime calls none of the platform's transcendental functions outside its tests
    /// (each would make a flight or a replay depend on the machine).
    #[test]
    fn the_runtime_calls_no_platform_math() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let (files, found) = super::platform_calls_under(&dir);
        assert!(files > 30, "only {files} sources under {}", dir.display());
        assert!(
            found.is_empty(),
            "the platform's functions; use crate::math instead:\n{}",
            found.join("\n")
        );
    }
}
