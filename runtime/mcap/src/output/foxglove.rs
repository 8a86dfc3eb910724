//! Foxglove's well-known schemas, so that the MCAP file plays in Foxglove's 3D panel: the
//! schemas themselves and the messages the writer publishes. The transforms are CDR with
//! their `ros2msg` schema (`foxglove_msgs/msg/FrameTransforms`: the topics with the most
//! messages, so the encoding that costs least to write and to store); the scene, written
//! once, and the calibration are JSON.
//!
//! Frames: `world` (the stage: origin at the centre of the floor, z up); `drone` (at the
//! reference position, turned by the heading: x forward, y left, z up); `camera` (the
//! camera's *optical* frame as Foxglove expects it for a `CameraCalibration`: z forward,
//! x right, y down, pitched by the camera pitch); `actor/NAME` (at the actor's feet, turned
//! by the facing). Entities that ride a moving frame are `frame_locked`, so an actor or the
//! drone moves by its transform alone and its entity is published once.
//!
//! Topics (each topic's latest message is self-contained, so seeking in Foxglove, which
//! back-fills the latest message of every topic, shows the whole scene):
//! `/tf/drone`, `/tf/camera`, `/tf/actor/NAME` (`foxglove_msgs/msg/FrameTransforms`, one topic per
//! frame, published when the frame's transform changes: see [`FrameTopic`]), `/scene/stage`,
//! `/scene/drone`, `/scene/actors`, `/scene/path` (`foxglove.SceneUpdate`) and
//! `/camera_calibration` (`foxglove.CameraCalibration`).

use dronecine_math as math;
use serde_json::{json, Value};

use super::cdr;
use dronecine_compiler::camera::Lens;
use dronecine_grammar::script::Stage;

pub const SCENE_UPDATE: &str = "foxglove.SceneUpdate";
/// In CDR with a `ros2msg` schema ([`frame_transforms_schema`]): the topics with the most
/// messages (one per moving frame, 30 a second) cost a third of the bytes and none of the
/// float formatting of JSON.
pub const FRAME_TRANSFORMS: &str = "foxglove_msgs/msg/FrameTransforms";
pub const CAMERA_CALIBRATION: &str = "foxglove.CameraCalibration";

pub const WORLD: &str = "world";
pub const DRONE: &str = "drone";
pub const CAMERA: &str = "camera";

/// The frame an actor's entity rides.
pub fn actor_frame(name: &str) -> String {
    format!("actor/{name}")
}

/// Image size the camera calibration declares (the frustum's shape only depends on the
/// field of view and the aspect; the width just has to be plausible).
const IMAGE_WIDTH_PX: u32 = 1920;

// ---------------------------------------------------------------------------------------
// JSON schemas
// ---------------------------------------------------------------------------------------

fn time(title: &str, description: &str) -> Value {
    json!({
        "type": "object",
        "title": title,
        "description": description,
        "properties": {
            "sec": { "type": "integer", "minimum": 0 },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        }
    })
}

fn numbers(title: &str, description: &str, keys: &[&str]) -> Value {
    let props: serde_json::Map<String, Value> = keys
        .iter()
        .map(|k| (k.to_string(), json!({ "type": "number" })))
        .collect();
    json!({ "type": "object", "title": title, "description": description, "properties": props })
}

fn vector3(description: &str) -> Value {
    numbers("foxglove.Vector3", description, &["x", "y", "z"])
}

fn point3(description: &str) -> Value {
    numbers("foxglove.Point3", description, &["x", "y", "z"])
}

fn quaternion(description: &str) -> Value {
    numbers("foxglove.Quaternion", description, &["x", "y", "z", "w"])
}

fn color(description: &str) -> Value {
    numbers("foxglove.Color", description, &["r", "g", "b", "a"])
}

fn pose(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "foxglove.Pose",
        "description": description,
        "properties": {
            "position": vector3("Position"),
            "orientation": quaternion("Orientation")
        }
    })
}

fn array(items: Value, description: &str) -> Value {
    json!({ "type": "array", "items": items, "description": description })
}

fn object(title: &str, description: &str, properties: Value) -> Value {
    json!({ "type": "object", "title": title, "description": description, "properties": properties })
}

fn number(description: &str) -> Value {
    json!({ "type": "number", "description": description })
}

fn boolean(description: &str) -> Value {
    json!({ "type": "boolean", "description": description })
}

fn string(description: &str) -> Value {
    json!({ "type": "string", "description": description })
}

fn integer_array(description: &str) -> Value {
    array(json!({ "type": "integer", "minimum": 0 }), description)
}

fn scene_entity() -> Value {
    let arrow = object(
        "foxglove.ArrowPrimitive",
        "An arrow",
        json!({
            "pose": pose("Tail position; identity orientation points along +x"),
            "shaft_length": number("Shaft length"),
            "shaft_diameter": number("Shaft diameter"),
            "head_length": number("Head length"),
            "head_diameter": number("Head diameter"),
            "color": color("Colour")
        }),
    );
    let cube = object(
        "foxglove.CubePrimitive",
        "A box",
        json!({ "pose": pose("Centre and orientation"), "size": vector3("Size along each axis"), "color": color("Colour") }),
    );
    let sphere = object(
        "foxglove.SpherePrimitive",
        "A sphere or ellipsoid",
        json!({ "pose": pose("Centre and orientation"), "size": vector3("Diameter along each axis"), "color": color("Colour") }),
    );
    let cylinder = object(
        "foxglove.CylinderPrimitive",
        "A cylinder, cone or truncated cone along z",
        json!({
            "pose": pose("Centre and orientation"),
            "size": vector3("Bounding box size"),
            "bottom_scale": number("Bottom face scale (0 = point)"),
            "top_scale": number("Top face scale (0 = point)"),
            "color": color("Colour")
        }),
    );
    let line_type = json!({
        "title": "foxglove.LineType",
        "description": "How points are joined",
        "oneOf": [
            { "title": "LINE_STRIP", "const": 0, "description": "Each point joined to the next" },
            { "title": "LINE_LOOP", "const": 1, "description": "A strip, last point joined to the first" },
            { "title": "LINE_LIST", "const": 2, "description": "Each pair of points is a segment" }
        ]
    });
    let line = object(
        "foxglove.LinePrimitive",
        "A line strip, loop or list",
        json!({
            "type": line_type,
            "pose": pose("Origin of the points"),
            "thickness": number("Width (pixels if scale_invariant, else metres)"),
            "scale_invariant": boolean("Whether thickness is in pixels"),
            "points": array(point3("A point"), "Points"),
            "color": color("Colour of the whole line (when colors is empty)"),
            "colors": array(color("A point's colour"), "Per-point colours"),
            "indices": integer_array("Indices into points (empty: all, in order)")
        }),
    );
    let triangles = object(
        "foxglove.TriangleListPrimitive",
        "A set of triangles",
        json!({
            "pose": pose("Origin of the points"),
            "points": array(point3("A vertex"), "Vertices, three per triangle"),
            "color": color("Colour of the whole list"),
            "colors": array(color("A vertex colour"), "Per-vertex colours"),
            "indices": integer_array("Indices into points")
        }),
    );
    let text = object(
        "foxglove.TextPrimitive",
        "A text label",
        json!({
            "pose": pose("Position and orientation"),
            "billboard": boolean("Whether the text faces the camera"),
            "font_size": number("Font size (pixels if scale_invariant, else metres)"),
            "scale_invariant": boolean("Whether font_size is in pixels"),
            "color": color("Colour"),
            "text": string("The text")
        }),
    );
    let model = object(
        "foxglove.ModelPrimitive",
        "A 3D model",
        json!({
            "pose": pose("Origin and orientation"),
            "scale": vector3("Scale along each axis"),
            "color": color("Colour override"),
            "override_color": boolean("Whether to use the colour"),
            "url": string("URL of the model"),
            "media_type": string("Media type of data"),
            "data": { "type": "string", "contentEncoding": "base64", "description": "Embedded model" }
        }),
    );
    let key_value = object(
        "foxglove.KeyValuePair",
        "A key and its value",
        json!({ "key": string("Key"), "value": string("Value") }),
    );
    object(
        "foxglove.SceneEntity",
        "A visual element of the 3D scene, made of primitives sharing a frame",
        json!({
            "timestamp": time("time", "Timestamp of the entity"),
            "frame_id": string("Frame of reference"),
            "id": string("Identifier; replaces an earlier entity with the same id on the topic"),
            "lifetime": {
                "type": "object",
                "title": "duration",
                "description": "How long the entity lives (0: until replaced or deleted)",
                "properties": {
                    "sec": { "type": "integer" },
                    "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
                }
            },
            "frame_locked": boolean("Whether the entity follows its frame as that frame moves"),
            "metadata": array(key_value, "User metadata"),
            "arrows": array(arrow, "Arrows"),
            "cubes": array(cube, "Boxes"),
            "spheres": array(sphere, "Spheres"),
            "cylinders": array(cylinder, "Cylinders"),
            "lines": array(line, "Lines"),
            "triangles": array(triangles, "Triangles"),
            "texts": array(text, "Texts"),
            "models": array(model, "Models")
        }),
    )
}

/// The JSON schema of `foxglove.SceneUpdate`.
pub fn scene_update_schema() -> String {
    let deletion = object(
        "foxglove.SceneEntityDeletion",
        "Removes earlier entities",
        json!({
            "timestamp": time("time", "Only entities older than this are deleted"),
            "type": {
                "title": "foxglove.SceneEntityDeletionType",
                "description": "What to delete",
                "oneOf": [
                    { "title": "MATCHING_ID", "const": 0, "description": "The entity with the given id" },
                    { "title": "ALL", "const": 1, "description": "Every entity on the topic" }
                ]
            },
            "id": string("Entity id (MATCHING_ID)")
        }),
    );
    let mut schema = object(
        SCENE_UPDATE,
        "An update to the entities of a 3D scene",
        json!({
            "deletions": array(deletion, "Entities to delete"),
            "entities": array(scene_entity(), "Entities to add or replace")
        }),
    );
    schema["$schema"] = json!("https://json-schema.org/draft/2020-12/schema");
    schema.to_string()
}

/// The `ros2msg` definition of `foxglove_msgs/msg/FrameTransforms` (Foxglove's own
/// schema in its ROS 2 form, with the definitions it uses, as ROS 2's recorders write them).
pub fn frame_transforms_schema() -> String {
    let sep = cdr::SEPARATOR;
    format!(
        "\
# A list of frame transforms (Foxglove's FrameTransforms)
foxglove_msgs/FrameTransform[] transforms
{sep}
MSG: foxglove_msgs/FrameTransform
# The pose of a child frame in its parent frame
builtin_interfaces/Time timestamp
string parent_frame_id
string child_frame_id
geometry_msgs/Vector3 translation
geometry_msgs/Quaternion rotation
{sep}
{time}{sep}
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
{sep}
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
",
        time = cdr::TIME_DEFINITION
    )
}

/// The JSON schema of `foxglove.CameraCalibration`.
pub fn camera_calibration_schema() -> String {
    let fixed = |n: usize, description: &str| json!({ "type": "array", "items": { "type": "number" }, "minItems": n, "maxItems": n, "description": description });
    let mut schema = object(
        CAMERA_CALIBRATION,
        "Pinhole camera intrinsics",
        json!({
            "timestamp": time("time", "Timestamp of the calibration"),
            "frame_id": string("Optical frame: x right, y down, z forward"),
            "width": { "type": "integer", "minimum": 0, "description": "Image width (px)" },
            "height": { "type": "integer", "minimum": 0, "description": "Image height (px)" },
            "distortion_model": string("Distortion model name"),
            "D": array(json!({ "type": "number" }), "Distortion parameters"),
            "K": fixed(9, "Intrinsic matrix, 3×3 row-major"),
            "R": fixed(9, "Rectification matrix, 3×3 row-major"),
            "P": fixed(12, "Projection matrix, 3×4 row-major")
        }),
    );
    schema["$schema"] = json!("https://json-schema.org/draft/2020-12/schema");
    schema.to_string()
}

// ---------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------

/// A quaternion `[x, y, z, w]`.
pub type Quat = [f64; 4];

/// Rotation by `angle_rad` about +z.
pub fn yaw(angle_rad: f64) -> Quat {
    let (s, c) = math::sin_cos(angle_rad / 2.0);
    [0.0, 0.0, s, c]
}

/// Hamilton product `a·b` (apply `b`, then `a`).
pub fn mul(a: Quat, b: Quat) -> Quat {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// The camera's optical frame (x right, y down, z forward) in the drone frame (x forward,
/// y left, z up) for a camera pitched up by `pitch_rad`.
pub fn camera_in_drone(pitch_rad: f64) -> Quat {
    // Pitch up = rotation by −τ about +y (left).
    let (s, c) = math::sin_cos(-pitch_rad / 2.0);
    let pitch = [0.0, s, 0.0, c];
    // Optical axes in a level forward-left-up frame: x = −y, y = −z, z = +x.
    const OPTICAL: Quat = [-0.5, 0.5, -0.5, 0.5];
    mul(pitch, OPTICAL)
}

// ---------------------------------------------------------------------------------------
// Messages
// ---------------------------------------------------------------------------------------

/// Millimetres are plenty for the 3D view.
const POS_SCALE: f64 = 1e3;
/// Quaternion components to 1e-6 (≈ 2e-6 rad).
const ROT_SCALE: f64 = 1e6;

fn time_value(ns: u64) -> Value {
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

fn xyz(v: [f64; 3]) -> Value {
    let r = |x: f64| (x * POS_SCALE).round() / POS_SCALE;
    json!({ "x": r(v[0]), "y": r(v[1]), "z": r(v[2]) })
}

fn rgba(c: [f64; 4]) -> Value {
    json!({ "r": c[0], "g": c[1], "b": c[2], "a": c[3] })
}

fn pose_value(position: [f64; 3], q: Quat) -> Value {
    json!({ "position": xyz(position), "orientation": { "x": q[0], "y": q[1], "z": q[2], "w": q[3] } })
}

const IDENTITY: Quat = [0.0, 0.0, 0.0, 1.0];

/// Distinct, readable colours for actors and shots.
const PALETTE: [[f64; 4]; 6] = [
    [0.90, 0.33, 0.25, 1.0],
    [0.25, 0.55, 0.90, 1.0],
    [0.30, 0.75, 0.35, 1.0],
    [0.95, 0.70, 0.20, 1.0],
    [0.65, 0.40, 0.85, 1.0],
    [0.20, 0.80, 0.80, 1.0],
];

fn entity(ns: u64, frame_id: &str, id: &str, frame_locked: bool) -> Value {
    json!({
        "timestamp": time_value(ns),
        "frame_id": frame_id,
        "id": id,
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": frame_locked,
        "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [],
        "lines": [], "triangles": [], "texts": [], "models": []
    })
}

fn scene_update(entities: Vec<Value>) -> Vec<u8> {
    json!({ "deletions": [], "entities": entities })
        .to_string()
        .into_bytes()
}

/// The stage: its twelve edges and a translucent floor.
pub fn stage_scene(ns: u64, stage: &Stage) -> Vec<u8> {
    let (lo, hi) = (stage.min_m(), stage.max_m());
    let corner = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let mut points = Vec::with_capacity(24);
    for a in 0..8usize {
        for bit in [1usize, 2, 4] {
            if a & bit == 0 {
                points.push(xyz(corner(a)));
                points.push(xyz(corner(a | bit)));
            }
        }
    }
    let mut e = entity(ns, WORLD, "stage", false);
    e["lines"] = json!([{
        "type": 2,
        "pose": pose_value([0.0; 3], IDENTITY),
        "thickness": 2.0,
        "scale_invariant": true,
        "points": points,
        "color": rgba([0.8, 0.8, 0.8, 1.0]),
        "colors": [],
        "indices": []
    }]);
    e["cubes"] = json!([{
        "pose": pose_value([0.0, 0.0, -0.005], IDENTITY),
        "size": xyz([stage.size_m[0], stage.size_m[1], 0.01]),
        "color": rgba([0.5, 0.5, 0.5, 0.25])
    }]);
    scene_update(vec![e])
}

/// The drone: a flat body and an arrow along its heading (in the `drone` frame).
pub fn drone_scene(ns: u64) -> Vec<u8> {
    let mut e = entity(ns, DRONE, "drone", true);
    e["cubes"] = json!([{
        "pose": pose_value([0.0; 3], IDENTITY),
        "size": xyz([0.35, 0.35, 0.08]),
        "color": rgba([0.15, 0.15, 0.15, 0.9])
    }]);
    e["arrows"] = json!([{
        "pose": pose_value([0.0; 3], IDENTITY),
        "shaft_length": 0.3, "shaft_diameter": 0.03,
        "head_length": 0.1, "head_diameter": 0.08,
        "color": rgba([1.0, 1.0, 1.0, 1.0])
    }]);
    scene_update(vec![e])
}

/// Every actor (in its own frame, feet at the origin, facing +x): a body, a head, an arrow
/// for the facing and the name above the head.
pub fn actors_scene(ns: u64, names: &[String], heights_m: &[f64]) -> Vec<u8> {
    let entities = names
        .iter()
        .zip(heights_m)
        .enumerate()
        .map(|(i, (name, &h))| {
            let h = if h.is_finite() && h > 0.1 { h } else { 0.1 };
            let head = (h / 8.0).clamp(0.05, 0.25);
            let body = h - head;
            let c = PALETTE[i % PALETTE.len()];
            let mut e = entity(ns, &actor_frame(name), &format!("actor/{name}"), true);
            e["cylinders"] = json!([{
                "pose": pose_value([0.0, 0.0, body / 2.0], IDENTITY),
                "size": xyz([0.4, 0.4, body]),
                "bottom_scale": 1.0, "top_scale": 1.0,
                "color": rgba([c[0], c[1], c[2], 0.8])
            }]);
            e["spheres"] = json!([{
                "pose": pose_value([0.0, 0.0, h - head / 2.0], IDENTITY),
                "size": xyz([head; 3]),
                "color": rgba([0.95, 0.85, 0.75, 1.0])
            }]);
            e["arrows"] = json!([{
                "pose": pose_value([0.0, 0.0, 0.75 * h], IDENTITY),
                "shaft_length": 0.4, "shaft_diameter": 0.04,
                "head_length": 0.15, "head_diameter": 0.1,
                "color": rgba(c)
            }]);
            e["texts"] = json!([{
                "pose": pose_value([0.0, 0.0, h + 0.2], IDENTITY),
                "billboard": true, "font_size": 14.0, "scale_invariant": true,
                "color": rgba([1.0, 1.0, 1.0, 1.0]),
                "text": name
            }]);
            e
        })
        .collect();
    scene_update(entities)
}

/// The whole path: one line strip per shot, in alternating colours.
///
/// The points are written straight into the message text (a one-hour reference has tens of
/// thousands of them: as a JSON tree they cost about 1.5 kB each, the compile's peak memory):
/// the message is serialized with empty `points` arrays, and each line's points are spliced
/// into its array, formatted exactly as `xyz` values are.
pub fn path_scene(ns: u64, segments: &[(usize, Vec<[f64; 3]>)]) -> Vec<u8> {
    const EMPTY: &[u8] = b"\"points\":[]";
    let kept: Vec<&(usize, Vec<[f64; 3]>)> = segments
        .iter()
        .filter(|(_, points)| points.len() >= 2)
        .collect();
    let lines: Vec<Value> = kept
        .iter()
        .map(|(shot, _)| {
            json!({
                "type": 0,
                "pose": pose_value([0.0; 3], IDENTITY),
                "thickness": 3.0,
                "scale_invariant": true,
                "points": [],
                "color": rgba(PALETTE[shot % PALETTE.len()]),
                "colors": [],
                "indices": []
            })
        })
        .collect();
    let mut e = entity(ns, WORLD, "path", false);
    e["lines"] = Value::Array(lines);
    let skeleton = scene_update(vec![e]);
    let total: usize = kept.iter().map(|(_, p)| p.len()).sum();
    let mut out = Vec::with_capacity(skeleton.len() + total * 40);
    let mut rest = &skeleton[..];
    for (_, points) in &kept {
        // Only the lines have a `points` key, one each, in order.
        let Some(at) = rest.windows(EMPTY.len()).position(|w| w == EMPTY) else {
            break;
        };
        let split = at + EMPTY.len() - 1;
        out.extend_from_slice(&rest[..split]);
        for (i, p) in points.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            let r = |x: f64| (x * POS_SCALE).round() / POS_SCALE;
            out.extend_from_slice(b"{\"x\":");
            let _ = serde_json::to_writer(&mut out, &r(p[0]));
            out.extend_from_slice(b",\"y\":");
            let _ = serde_json::to_writer(&mut out, &r(p[1]));
            out.extend_from_slice(b",\"z\":");
            let _ = serde_json::to_writer(&mut out, &r(p[2]));
            out.push(b'}');
        }
        rest = &rest[split..];
    }
    out.extend_from_slice(rest);
    out
}

/// A pinhole calibration whose frustum has exactly the lens's horizontal and vertical
/// fields of view.
pub fn camera_calibration(ns: u64, lens: &Lens) -> Vec<u8> {
    let w = IMAGE_WIDTH_PX;
    let aspect = if lens.aspect().is_finite() && lens.aspect() > 0.0 {
        lens.aspect()
    } else {
        16.0 / 9.0
    };
    let h = ((w as f64 / aspect).round() as u32).max(1);
    let (wf, hf) = (w as f64, h as f64);
    // fx = (w/2)·Sx, fy = (h/2)·Sy with Sy = Sx·aspect: the rounded height keeps fovY exact.
    let sx = lens.sx();
    let fx = wf / 2.0 * sx;
    let fy = hf / 2.0 * sx * aspect;
    let (cx, cy) = (wf / 2.0, hf / 2.0);
    json!({
        "timestamp": time_value(ns),
        "frame_id": CAMERA,
        "width": w,
        "height": h,
        "distortion_model": "plumb_bob",
        "D": [0.0, 0.0, 0.0, 0.0, 0.0],
        "K": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        "R": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        "P": [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    })
    .to_string()
    .into_bytes()
}

/// One frame's transform topic: publishes the transform when it changes.
///
/// Each tick, [`FrameTopic::message`] rounds the transform (translation to the millimetre,
/// quaternion components to 1e-6) and compares it, bit for bit, with the last one published:
/// unchanged, nothing is written. Changed after one or more silent ticks, the message holds
/// two transforms: the unchanged value stamped at the previous tick, then the new one, so
/// that Foxglove (which interpolates between a frame's stamped transforms) keeps the frame
/// still until it moves instead of sliding it over the silent stretch. The topic's latest
/// message is always the frame's current transform, which keeps seeking (Foxglove back-fills
/// the latest message of each topic) exact; a frame that never moves is published once, at
/// the first tick. Messages are `foxglove_msgs/msg/FrameTransforms` in CDR.
pub struct FrameTopic {
    /// `parent_frame_id` and `child_frame_id`, encoded once.
    names: cdr::Strings,
    /// The rounded transform last published (`None`: never).
    last: Option<[f64; 7]>,
    /// Time of the last publication.
    last_ns: u64,
}

/// `x` rounded to a multiple of `1 / scale`, half away from zero (as `f64::round`, without
/// its library call: this is most of the writer's `/tf` arithmetic), never `-0` (a frame
/// hovering about zero is not a change); values too large to be rounded exactly,
/// infinities and NaN as they are.
#[inline]
fn round_to(x: f64, scale: f64) -> f64 {
    let y = x * scale;
    if y.abs() < 9.0e15 {
        super::round_half_away(y) as f64 / scale
    } else {
        x
    }
}

/// A transform rounded for the 3D view: translation, then rotation `[x, y, z, w]`.
fn rounded(t: [f64; 3], q: Quat) -> [f64; 7] {
    let pos = |x: f64| round_to(x, POS_SCALE);
    let rot = |x: f64| round_to(x, ROT_SCALE);
    [
        pos(t[0]),
        pos(t[1]),
        pos(t[2]),
        rot(q[0]),
        rot(q[1]),
        rot(q[2]),
        rot(q[3]),
    ]
}

impl FrameTopic {
    pub fn new(parent: &str, child: &str) -> Self {
        Self {
            names: cdr::Strings::new(&[parent, child]),
            last: None,
            last_ns: 0,
        }
    }

    /// Writes into `out` (cleared) the `FrameTransforms` message for the tick at `ns` (the
    /// previous tick at `prev_ns`) if the transform changed; returns whether it did.
    pub fn message(
        &mut self,
        out: &mut Vec<u8>,
        prev_ns: Option<u64>,
        ns: u64,
        t: [f64; 3],
        q: Quat,
    ) -> bool {
        let now = rounded(t, q);
        let held = match self.last {
            Some(last) if last.map(f64::to_bits) == now.map(f64::to_bits) => return false,
            Some(last) => match prev_ns {
                Some(prev) if prev > self.last_ns && prev < ns => Some((prev, last)),
                _ => None,
            },
            None => None,
        };
        out.clear();
        let mut m = cdr::Cdr::new(out);
        m.count(1 + usize::from(held.is_some()));
        if let Some((prev, last)) = held {
            self.transform(&mut m, prev, &last);
        }
        self.transform(&mut m, ns, &now);
        self.last = Some(now);
        self.last_ns = ns;
        true
    }

    fn transform(&self, m: &mut cdr::Cdr, ns: u64, pose: &[f64; 7]) {
        m.time(ns).strings(&self.names).f64s(pose);
    }
}

/// One transform of a `FrameTransforms` message, as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTransform {
    pub timestamp_ns: u64,
    pub parent_frame_id: String,
    pub child_frame_id: String,
    pub translation: [f64; 3],
    /// `[x, y, z, w]`.
    pub rotation: Quat,
}

/// Reads a `foxglove_msgs/msg/FrameTransforms` CDR message (tests and tools; a damaged
/// message is an error naming the field).
pub fn decode_frame_transforms(data: &[u8]) -> Result<Vec<FrameTransform>, String> {
    let mut r = cdr::CdrReader::new(data)?;
    // Each transform at least: a time, two empty strings, seven floats.
    let n = r.count("transforms", 8 + 2 * 5 + 7 * 8)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        out.push(FrameTransform {
            timestamp_ns: r.time("timestamp")?,
            parent_frame_id: r.string("parent_frame_id")?.to_string(),
            child_frame_id: r.string("child_frame_id")?.to_string(),
            translation: r.f64s("translation")?,
            rotation: r.f64s("rotation")?,
        });
    }
    r.finish("FrameTransforms")?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_compiler::camera::{CameraPose, Vec3};

    /// Rotates `v` by the unit quaternion `q`.
    fn rotate(q: Quat, v: [f64; 3]) -> Vec3 {
        let p = mul(mul(q, [v[0], v[1], v[2], 0.0]), [-q[0], -q[1], -q[2], q[3]]);
        Vec3::new(p[0], p[1], p[2])
    }

    #[test]
    fn optical_frame_matches_the_camera_conventions() {
        for (heading, pitch) in [(0.0, 0.0), (0.7, -0.3), (-2.5, 0.4), (3.0, -1.2)] {
            let pose = CameraPose {
                position_m: Vec3::zeros(),
                heading_rad: heading,
                pitch_rad: pitch,
            };
            // world ← drone ← camera.
            let q = mul(yaw(heading), camera_in_drone(pitch));
            let z = rotate(q, [0.0, 0.0, 1.0]);
            let x = rotate(q, [1.0, 0.0, 0.0]);
            let y = rotate(q, [0.0, 1.0, 0.0]);
            assert!((z - pose.forward()).norm() < 1e-12, "optical z is forward");
            assert!((x - pose.right()).norm() < 1e-12, "optical x is right");
            assert!((y + pose.up()).norm() < 1e-12, "optical y is down");
        }
    }

    #[test]
    fn transforms_round_as_f64_round() {
        let mut x = 0.377f64;
        for _ in 0..100_000 {
            x = (x * 1.618_033_988_749_895).fract();
            for v in [
                x * 20.0 - 10.0,
                x - 0.5,
                (x * 2000.0).trunc() / 1000.0 + 0.0005,
            ] {
                for scale in [POS_SCALE, ROT_SCALE] {
                    // `+ 0.0`: never -0 (a frame that hovers about zero does not flicker).
                    let expected = (v * scale).round() / scale + 0.0;
                    assert_eq!(
                        round_to(v, scale).to_bits(),
                        expected.to_bits(),
                        "{v} {scale}"
                    );
                }
            }
        }
        assert!(round_to(f64::NAN, POS_SCALE).is_nan());
        assert_eq!(round_to(f64::INFINITY, POS_SCALE), f64::INFINITY);
        assert_eq!(round_to(1e300, POS_SCALE), 1e300);
    }

    #[test]
    fn a_transform_message_has_the_schemas_layout() {
        let mut topic = FrameTopic::new(WORLD, DRONE);
        let mut out = Vec::new();
        let q = yaw(0.5);
        assert!(topic.message(&mut out, None, 3_250_000_000, [1.23456, -2.0, 0.4], q));
        // After the header: the count, the stamp (4 and 8), "world" at 12 (its length, the
        // bytes and the NUL), two bytes of padding, "drone" at 24, the floats 8-aligned at 40.
        let body = &out[4..];
        assert_eq!(&out[..4], &cdr::HEADER);
        assert_eq!(&body[0..4], &1u32.to_le_bytes());
        assert_eq!(&body[4..8], &3i32.to_le_bytes());
        assert_eq!(&body[8..12], &250_000_000u32.to_le_bytes());
        assert_eq!(&body[12..16], &6u32.to_le_bytes());
        assert_eq!(&body[16..22], b"world\0");
        assert_eq!(&body[24..28], &6u32.to_le_bytes());
        assert_eq!(&body[28..34], b"drone\0");
        assert_eq!(&body[40..48], &1.235f64.to_le_bytes(), "to the millimetre");
        assert_eq!(&body[88..96], &((q[3] * 1e6).round() / 1e6).to_le_bytes());
        assert_eq!(body.len(), 96);

        let read = decode_frame_transforms(&out).unwrap();
        assert_eq!(read.len(), 1);
        assert_eq!(read[0].timestamp_ns, 3_250_000_000);
        assert_eq!(
            (
                read[0].parent_frame_id.as_str(),
                read[0].child_frame_id.as_str()
            ),
            (WORLD, DRONE)
        );
        assert_eq!(read[0].translation, [1.235, -2.0, 0.4]);

        // Less than the rounding: nothing. Moved after a silent tick: the held transform at
        // the previous tick, then the new one.
        assert!(!topic.message(
            &mut out,
            Some(3_250_000_000),
            3_260_000_000,
            [1.2351, -2.0, 0.4],
            q
        ));
        assert!(topic.message(
            &mut out,
            Some(3_260_000_000),
            3_270_000_000,
            [1.3, -2.0, 0.4],
            q
        ));
        let read = decode_frame_transforms(&out).unwrap();
        assert_eq!(read.len(), 2);
        assert_eq!(
            (read[0].timestamp_ns, read[0].translation[0]),
            (3_260_000_000, 1.235)
        );
        assert_eq!(
            (read[1].timestamp_ns, read[1].translation[0]),
            (3_270_000_000, 1.3)
        );
        for cut in 0..out.len() - 1 {
            assert!(
                decode_frame_transforms(&out[..cut]).is_err(),
                "cut at {cut}"
            );
        }
    }

    #[test]
    fn calibration_frustum_has_the_lens_fields_of_view() {
        let lens = Lens::new(84f64.to_radians(), 4.0 / 3.0);
        let v: Value = serde_json::from_slice(&camera_calibration(0, &lens)).unwrap();
        let (w, h) = (v["width"].as_f64().unwrap(), v["height"].as_f64().unwrap());
        let k: Vec<f64> = serde_json::from_value(v["K"].clone()).unwrap();
        let fov_x = 2.0 * (w / 2.0 / k[0]).atan();
        let fov_y = 2.0 * (h / 2.0 / k[4]).atan();
        assert!((fov_x - lens.fov_x_rad()).abs() < 1e-12);
        assert!((fov_y - lens.fov_y_rad()).abs() < 1e-12);
        assert_eq!(v["frame_id"], CAMERA);
    }
}
