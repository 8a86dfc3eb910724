//! The JSON schemas of the flight log's own channels (compile's schemas for `/reference`,
//! `/actors`, `/camera` and Foxglove's for `/tf`, `/scene/*`, `/camera_calibration`).

use dronecine_compiler::output::mcap::{number_schema, vec3_schema};
use serde_json::{json, Value};

pub const ESTIMATE: &str = "dronecine.Estimate";
pub const MEASUREMENT: &str = "dronecine.Measurement";
pub const COMMAND: &str = "dronecine.Command";
pub const FRAMING: &str = "dronecine.Framing";
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

fn t_s() -> Value {
    number_schema("Flight clock (s)")
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

fn nullable(mut schema: Value) -> Value {
    let inner = schema.take();
    json!({ "oneOf": [inner, { "type": "null" }] })
}

fn screen(description: &str) -> Value {
    nullable(json!({
        "type": "array",
        "items": { "type": "number" },
        "minItems": 2,
        "maxItems": 2,
        "description": description
    }))
}

fn body_pose(description: &str) -> Value {
    json!({
        "type": "object",
        "description": description,
        "properties": {
            "position_m": vec3_schema("Position (m)"),
            "heading_rad": number_schema("Heading, counter-clockwise from +x (rad)")
        },
        "required": ["position_m", "heading_rad"]
    })
}

pub fn estimate() -> String {
    top(
        ESTIMATE,
        "The controller's state estimate after the tick",
        json!({
            "t_s": t_s(),
            "position_m": vec3_schema("Position (m)"),
            "velocity_mps": vec3_schema("Velocity (m/s)"),
            "heading_rad": number_schema("Heading, counter-clockwise from +x (rad)")
        }),
        &["t_s", "position_m", "velocity_mps", "heading_rad"],
    )
}

pub fn measurement() -> String {
    top(
        MEASUREMENT,
        "One motion-capture frame (null: body not tracked)",
        json!({
            "t_s": number_schema("Capture time on the flight clock (s)"),
            "frame": { "type": "integer", "minimum": 0, "description": "Frame counter" },
            "drone": nullable(body_pose("The drone")),
            "actors": {
                "type": "array",
                "items": nullable(body_pose("An actor (script order)")),
                "description": "The actors, in the script's order"
            }
        }),
        &["t_s", "frame", "drone", "actors"],
    )
}

fn command_properties(exact_numbers: bool) -> Value {
    let n = |d: &str| {
        if exact_numbers {
            exact(d)
        } else {
            number_schema(d)
        }
    };
    json!({
        "roll_rad": n("Roll, positive moves right (rad)"),
        "pitch_rad": n("Pitch, positive (nose up) moves backward (rad)"),
        "yaw_rate_radps": n("Yaw rate, positive clockwise seen from above (rad/s)"),
        "vz_mps": n("Vertical speed, positive up (m/s)")
    })
}

pub fn command() -> String {
    let mut properties = command_properties(false);
    properties["t_s"] = t_s();
    properties["saturated"] = json!({ "type": "boolean", "description": "A set-point was clamped to the profile's limits" });
    properties["failsafe"] = json!({ "type": "boolean", "description": "The command sent is not the controller's (fault or failsafe)" });
    top(
        COMMAND,
        "The command sent to the drone",
        properties,
        &[
            "t_s",
            "roll_rad",
            "pitch_rad",
            "yaw_rate_radps",
            "vz_mps",
            "saturated",
            "failsafe",
        ],
    )
}

pub fn framing() -> String {
    top(
        FRAMING,
        "Where each actor is on screen and where the script puts it (screen coordinates)",
        json!({
            "t_s": t_s(),
            "shot": nullable(json!({ "type": "integer", "minimum": 0, "description": "Index of the shot" })),
            "actors": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "actor": { "type": "integer", "minimum": 0, "description": "Index of the actor" },
                        "name": { "type": "string" },
                        "screen": screen("Where the actor is on screen (null: behind the camera)"),
                        "requested": screen("Where the script puts it (null: no framing)")
                    },
                    "required": ["actor", "name", "screen", "requested"]
                }
            }
        }),
        &["t_s", "shot", "actors"],
    )
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
