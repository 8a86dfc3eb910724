//! The JSON schema of the flight log's `/events` (the per-tick topics are CDR: `plots.rs`,
//! `cdr.rs` and the compiler's writers; the static ones are compile's).

use serde_json::{json, Value};

pub const EVENT: &str = "dronecine.Event";

const DRAFT: &str = "https://json-schema.org/draft/2020-12/schema";

fn top(title: &str, description: &str, properties: Value, required: &[&str]) -> String {
    json!({
        "$schema": DRAFT,
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": required
    })
    .to_string()
}

/// A number, or (non-finite) the string "NaN", "inf" or "-inf".
fn exact(description: &str) -> Value {
    json!({
        "description": description,
        "oneOf": [
            { "type": "number" },
            { "type": "string", "enum": ["NaN", "inf", "-inf"] }
        ]
    })
}

pub fn event() -> String {
    top(
        EVENT,
        "Something that happened during the flight",
        json!({
            "t_s": exact("Flight clock (s)"),
            "level": { "type": "string", "enum": ["info", "warning", "error"] },
            "kind": { "type": "string", "description": "take_off, shot_start, failsafe, …" },
            "message": { "type": "string" },
            "line": {
                "type": "integer",
                "minimum": 1,
                "description": "The script's line it is about (a finding of the director's)"
            },
            "help": { "type": "string", "description": "How to fix it, as compile says it" }
        }),
        &["t_s", "level", "kind", "message"],
    )
}
