//! Drone profiles. The built-in ones are named here; their parameters arrive with the
//! compiler (issue 3).

/// Names accepted by `drone NAME` in a script.
pub const BUILTIN_NAMES: &[&str] = &["ardrone2", "ardrone2-outdoor"];

/// The profile used when a script names none.
pub const DEFAULT_NAME: &str = "ardrone2";

#[cfg(test)]
mod tests {
    #[test]
    fn default_is_builtin() {
        assert!(super::BUILTIN_NAMES.contains(&super::DEFAULT_NAME));
    }
}
