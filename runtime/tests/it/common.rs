//! What the runtime's tests share: shipped scripts and scripts written in a test, checked.

use dronecine_grammar::Script;

/// A shipped script (`path` from the workspace's root), checked: it must be valid.
pub fn load(path: &str) -> (String, Script) {
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path);
    let text = std::fs::read_to_string(&full).unwrap();
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: full.parent(),
    };
    let checked = dronecine_grammar::check(&text, &opts);
    assert!(!checked.has_errors(), "{path}: {:?}", checked.diagnostics);
    (text, checked.script.expect("the shipped script is valid"))
}

/// A script written in the test, checked: it must be valid.
pub fn parse(text: &str) -> Script {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(text, &opts);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.expect("a valid script")
}
