//! The rig file: which Motive rigid body is the drone and which is each actor, which axis
//! Motive streams as up, and where the mocap origin sits on the stage.
//!
//! ```toml
//! up = "y"              # Motive's up axis: "y" (its default) or "z"
//! drone = 1             # the drone's rigid-body streaming id
//! origin_m = [0.5, -1.0, 0.0]  # optional: the mocap origin in stage coordinates
//! yaw_deg = 90.0        # optional: the mocap x axis, counter-clockwise from stage x
//!
//! [actors]              # one rigid body per scene actor, by the script's names
//! Alice = 2
//! Bob = 3
//! ```
//!
//! A pose goes mocap → world (`natnet::frame::to_world`, by `up`) → stage:
//! `p_stage = origin_m + Rz(yaw)·p_world`, `heading_stage = wrap(heading + yaw)`.
//! Ids must be distinct; unknown keys are refused (a misspelt `orgin_m` is an error, not a
//! silently ignored offset). A bad rig file gets every mistake at once, as diagnostics that
//! point into the TOML (`rig::syntax`, `rig::bad_value`, `rig::unknown_key`,
//! `rig::missing_key`), rendered like the script's and the profile's.

use dronecine_math as math;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use dronecine_diag::suggest;
use dronecine_diag::toml::{self as toml_text, eof_span, error_span, kind_of};
use dronecine_diag::{Diagnostic, Span};
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::frame::UpAxis;
use dronecine_backend::BodyPose;
use dronecine_math::wrap_angle_rad;

dronecine_diag::codes! {
    /// A rig file's diagnostic codes (`rig::`).
    pub enum RigCode {
        Syntax => "rig::syntax": "A rig file is not valid TOML.",
        BadValue => "rig::bad_value": "A rig file value has the wrong type or range, or gives two things one rigid body.",
        UnknownKey => "rig::unknown_key": "A rig file has a key dronecine does not know.",
        MissingKey => "rig::missing_key": "A rig file lacks a required key.",
    }
}

/// A parsed, checked rig file.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    pub up: UpAxis,
    pub drone_id: i32,
    /// Actor name → rigid-body id.
    pub actors: BTreeMap<String, i32>,
    pub origin_m: [f64; 3],
    pub yaw_rad: f64,
}

/// Why a rig was refused.
#[derive(Debug)]
pub enum RigError {
    /// The file cannot be read.
    Unreadable {
        path: PathBuf,
        error: std::io::Error,
    },
    /// The text is not a valid rig: the text and its diagnostics (spans into it, at least one
    /// an error).
    Invalid {
        source: String,
        diagnostics: Vec<Diagnostic>,
    },
    /// The rig and the script disagree (an actor without a rigid body).
    Mismatch(String),
}

impl fmt::Display for RigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RigError::Unreadable { path, error } => {
                write!(f, "cannot read the rig file {}: {error}", path.display())
            }
            RigError::Invalid { diagnostics, .. } => {
                let first = diagnostics.iter().find(|d| d.is_error());
                match first {
                    Some(d) => write!(f, "not a valid rig: {}", d.message)?,
                    None => f.write_str("not a valid rig")?,
                }
                let more = diagnostics.iter().filter(|d| d.is_error()).count();
                if more > 1 {
                    write!(f, " (and {} more mistakes)", more - 1)?;
                }
                Ok(())
            }
            RigError::Mismatch(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for RigError {}

/// The keys of a rig file, in the order they are documented.
const KEYS: [&str; 5] = ["up", "drone", "actors", "origin_m", "yaw_deg"];
/// An example of each key, for the help lines.
const EXAMPLE: &str = "up = \"y\", drone = 1, origin_m = [0.5, -1.0, 0.0], yaw_deg = 90.0, \
                       and `[actors]` with one `Name = id` line per actor";

fn sp<T>(v: &Spanned<T>) -> Span {
    toml_text::span(v.span())
}

/// Reads a rig's keys into diagnostics; `None` for a value that is bad (reported).
struct Reader {
    diags: Vec<Diagnostic>,
}

impl Reader {
    fn bad(&mut self, span: Span, message: String, label: &str, help: String) {
        self.diags.push(
            Diagnostic::error(RigCode::BadValue, span, message)
                .with_label(label.to_string())
                .with_help(help),
        );
    }

    /// A rigid-body id: an integer Motive can stream (32-bit).
    fn id(&mut self, what: &str, v: &Spanned<DeValue<'_>>) -> Option<i32> {
        let parsed = match v.get_ref() {
            DeValue::Integer(i) => i64::from_str_radix(&i.as_str().replace('_', ""), i.radix())
                .ok()
                .map(i32::try_from),
            _ => None,
        };
        match parsed {
            Some(Ok(id)) => Some(id),
            Some(Err(_)) | None if matches!(v.get_ref(), DeValue::Integer(_)) => {
                self.bad(
                    sp(v),
                    format!(
                        "{what}: rigid-body id out of range (Motive's streaming ids are 32-bit)"
                    ),
                    "not a 32-bit id",
                    "use the streaming id Motive shows for the rigid body (1, 2, …)".into(),
                );
                None
            }
            _ => {
                self.bad(
                    sp(v),
                    format!(
                        "{what} must be a rigid-body id (an integer), found {}",
                        kind_of(v.get_ref())
                    ),
                    "expected an integer",
                    "write the streaming id Motive shows for the rigid body, bare: `drone = 1`"
                        .into(),
                );
                None
            }
        }
    }

    /// A finite number.
    fn number(&mut self, what: &str, v: &Spanned<DeValue<'_>>) -> Option<f64> {
        match toml_text::number(v.get_ref()) {
            Some(x) if x.is_finite() => Some(x),
            Some(_) => {
                self.bad(
                    sp(v),
                    format!("{what} must be a finite number"),
                    "not finite",
                    format!("for example {EXAMPLE}"),
                );
                None
            }
            None => {
                self.bad(
                    sp(v),
                    format!("{what} must be a number, found {}", kind_of(v.get_ref())),
                    "expected a number",
                    format!(
                        "write numbers bare, the unit is in the key's name; for example {EXAMPLE}"
                    ),
                );
                None
            }
        }
    }
}

/// The value of `key` at the top of the rig file, if any.
fn get<'t, 'i>(root: &'t DeTable<'i>, key: &str) -> Option<&'t Spanned<DeValue<'i>>> {
    root.iter()
        .find(|(k, _)| k.get_ref().as_ref() == key)
        .map(|(_, v)| v)
}

/// The `rig::syntax` diagnostics of a text that is not valid TOML (the first 20 errors).
fn syntax_diagnostics(src: &str, errors: &[toml::de::Error]) -> Vec<Diagnostic> {
    errors
        .iter()
        .take(20)
        .map(|e| {
            let span = error_span(src, e, 0);
            let first = e
                .message()
                .trim()
                .lines()
                .next()
                .unwrap_or("invalid TOML")
                .to_string();
            Diagnostic::error(RigCode::Syntax, span, format!("invalid TOML: {first}"))
                .with_label(first)
                .with_help(format!(
                    "a rig file is TOML, one `key = value` per line: {EXAMPLE}"
                ))
        })
        .collect()
}

impl Reader {
    /// Reports every top-level key a rig file does not have, with the closest one it does.
    fn unknown_keys(&mut self, root: &DeTable<'_>) {
        for (k, _) in root.iter() {
            let name = k.get_ref().as_ref();
            if KEYS.contains(&name) {
                continue;
            }
            let guess = suggest::closest(name, KEYS);
            let help = match guess.first() {
                Some(g) => format!("did you mean `{g}`? A rig file has {}", KEYS.join(", ")),
                None => format!("a rig file has {} (for example {EXAMPLE})", KEYS.join(", ")),
            };
            self.diags.push(
                Diagnostic::error(RigCode::UnknownKey, sp(k), format!("unknown key `{name}`"))
                    .with_label("not a rig key")
                    .with_help(help),
            );
        }
    }

    /// The `up` axis, if given and valid.
    fn up(&mut self, root: &DeTable<'_>) -> Option<UpAxis> {
        let v = get(root, "up")?;
        match v.get_ref() {
            DeValue::String(t) if t.eq_ignore_ascii_case("y") => Some(UpAxis::Y),
            DeValue::String(t) if t.eq_ignore_ascii_case("z") => Some(UpAxis::Z),
            other => {
                self.bad(
                    sp(v),
                    format!(
                        "`up` is {}: Motive streams \"y\" (its default) or \"z\" as up",
                        kind_of(other)
                    ),
                    "\"y\" or \"z\"",
                    "write `up = \"y\"` unless Motive's streaming settings say Z up".into(),
                );
                None
            }
        }
    }

    /// Reports `up` and `drone` when missing (at the end of the file).
    fn missing_keys(&mut self, src: &str, root: &DeTable<'_>) {
        for (key, example) in [("up", "up = \"y\""), ("drone", "drone = 1")] {
            if get(root, key).is_none() {
                self.diags.push(
                    Diagnostic::error(RigCode::MissingKey, eof_span(src), format!("the rig has no `{key}`"))
                        .with_label(format!("`{key}` is required"))
                        .with_help(format!("add `{example}` (the drone's streaming id and Motive's up axis are always needed)")),
                );
            }
        }
    }

    /// The `[actors]` table, each id distinct from the drone's (`drone`: its id and where it
    /// is written) and the others'.
    fn actors(&mut self, root: &DeTable<'_>, drone: Option<(i32, Span)>) -> BTreeMap<String, i32> {
        let mut actors = BTreeMap::new();
        let mut seen: Vec<(i32, String, Span)> = Vec::new();
        if let Some((id, span)) = drone {
            seen.push((id, "the drone".into(), span));
        }
        let Some(v) = get(root, "actors") else {
            return actors;
        };
        match v.get_ref() {
            DeValue::Table(t) => {
                for (k, v) in t.iter() {
                    let name = k.get_ref().as_ref();
                    let Some(id) = self.id(&format!("`actors.{name}`"), v) else {
                        continue;
                    };
                    if let Some((_, other, at)) = seen.iter().find(|(i, _, _)| *i == id) {
                        let d = Diagnostic::error(
                            RigCode::BadValue,
                            sp(v),
                            format!("`actors.{name}` = {id}: rigid body {id} is already {other}"),
                        )
                        .with_label(format!("{other}'s body"))
                        .with_related(*at, format!("{other} is body {id}"))
                        .with_help("each rigid body tracks one thing: give each actor the id Motive streams for their own body");
                        self.diags.push(d);
                        continue;
                    }
                    seen.push((id, format!("actor `{name}`"), sp(v)));
                    actors.insert(name.to_string(), id);
                }
            }
            other => self.bad(
                sp(v),
                format!("`actors` must be a table, found {}", kind_of(other)),
                "expected `[actors]`",
                "write a section `[actors]` with one `Name = id` line per actor, by the script's names".into(),
            ),
        }
        actors
    }

    /// `origin_m` (the origin when absent), if valid.
    fn origin(&mut self, root: &DeTable<'_>) -> Option<[f64; 3]> {
        let Some(v) = get(root, "origin_m") else {
            return Some([0.0; 3]);
        };
        match v.get_ref().as_array() {
            Some(items) if items.len() == 3 => {
                let xs: Vec<Option<f64>> = items
                    .iter()
                    .enumerate()
                    .map(|(i, item)| self.number(&format!("`origin_m[{i}]`"), item))
                    .collect();
                match xs[..] {
                    [Some(x), Some(y), Some(z)] => Some([x, y, z]),
                    _ => None,
                }
            }
            _ => {
                self.bad(
                    sp(v),
                    format!(
                        "`origin_m` must be a list of 3 numbers [x, y, z] in metres, found {}",
                        kind_of(v.get_ref())
                    ),
                    "expected [x, y, z]",
                    "write where the mocap origin sits on the stage: `origin_m = [0.5, -1.0, 0.0]`"
                        .into(),
                );
                None
            }
        }
    }
}

impl Rig {
    /// Parses and checks a rig file's text: the rig, or every mistake in it.
    pub fn from_toml(src: &str) -> Result<Rig, RigError> {
        let invalid = |diagnostics: Vec<Diagnostic>| RigError::Invalid {
            source: src.to_string(),
            diagnostics,
        };
        let (doc, errors) = DeTable::parse_recoverable(src);
        if !errors.is_empty() {
            return Err(invalid(syntax_diagnostics(src, &errors)));
        }
        let mut r = Reader { diags: Vec::new() };
        let root = doc.get_ref();
        r.unknown_keys(root);
        let up = r.up(root);
        let drone = get(root, "drone").and_then(|v| r.id("`drone`", v).map(|id| (id, sp(v))));
        r.missing_keys(src, root);
        let actors = r.actors(root, drone);
        let origin_m = r.origin(root);
        let yaw_deg = match get(root, "yaw_deg") {
            None => Some(0.0),
            Some(v) => r.number("`yaw_deg`", v),
        };

        r.diags.sort_by_key(|d| (d.span.start, d.span.end));
        match (up, drone, origin_m, yaw_deg) {
            (Some(up), Some((drone_id, _)), Some(origin_m), Some(yaw_deg))
                if r.diags.is_empty() =>
            {
                Ok(Rig {
                    up,
                    drone_id,
                    actors,
                    origin_m,
                    yaw_rad: wrap_angle_rad(yaw_deg.to_radians()),
                })
            }
            _ => Err(invalid(r.diags)),
        }
    }

    /// Reads and parses a rig file.
    pub fn load(path: &Path) -> Result<Rig, RigError> {
        let src = std::fs::read_to_string(path).map_err(|error| RigError::Unreadable {
            path: path.to_path_buf(),
            error,
        })?;
        Rig::from_toml(&src)
    }

    /// The layout `dronecine emulate` streams: the drone is rigid body 1, the actors 2, 3, …
    /// in the script's order, Y up, the mocap's origin at the stage's.
    pub fn numbered<S: AsRef<str>>(actor_names: &[S]) -> Rig {
        Rig {
            up: UpAxis::Y,
            drone_id: 1,
            actors: actor_names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.as_ref().to_string(), i as i32 + 2))
                .collect(),
            origin_m: [0.0; 3],
            yaw_rad: 0.0,
        }
    }

    /// The rigid-body ids of `names` (the scene's actors, in its order); an actor without a
    /// body is an error naming it and the bodies the rig has.
    pub fn actor_ids<I>(&self, names: I) -> Result<Vec<i32>, RigError>
    where
        I: IntoIterator,
        I::Item: AsRef<str>,
    {
        names
            .into_iter()
            .map(|n| {
                let n = n.as_ref();
                self.actors.get(n).copied().ok_or_else(|| {
                    let known: Vec<&str> = self.actors.keys().map(String::as_str).collect();
                    RigError::Mismatch(format!(
                        "actor `{n}` has no rigid body in the rig (its [actors] are: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ))
                })
            })
            .collect()
    }

    /// A world-frame pose (mocap origin) in stage coordinates.
    pub fn to_stage(&self, pose: BodyPose) -> BodyPose {
        let (s, c) = math::sin_cos(self.yaw_rad);
        let [x, y, z] = pose.position_m;
        BodyPose {
            position_m: [
                self.origin_m[0] + c * x - s * y,
                self.origin_m[1] + s * x + c * y,
                self.origin_m[2] + z,
            ],
            heading_rad: wrap_angle_rad(pose.heading_rad + self.yaw_rad),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn parses_a_full_rig() {
        let rig = Rig::from_toml(
            "up = \"Z\"\ndrone = 7\norigin_m = [1.0, 2.0, 0.0]\nyaw_deg = 90\n\
             [actors]\nAlice = 2\nBob = 3\n",
        )
        .unwrap();
        assert_eq!(rig.up, UpAxis::Z);
        assert_eq!(rig.drone_id, 7);
        assert_eq!(rig.actor_ids(["Bob", "Alice"]).unwrap(), vec![3, 2]);
        // Mocap +x is stage +y after a 90° yaw; the origin is added.
        let p = rig.to_stage(BodyPose {
            position_m: [1.0, 0.0, 0.5],
            heading_rad: 0.0,
        });
        assert!((p.position_m[0] - 1.0).abs() < 1e-12);
        assert!((p.position_m[1] - 3.0).abs() < 1e-12);
        assert_eq!(p.position_m[2], 0.5);
        assert!((p.heading_rad - FRAC_PI_2).abs() < 1e-12);
    }

    /// The messages of a refused rig's diagnostics, with the text each points at.
    fn mistakes(src: &str) -> Vec<(dronecine_diag::Code, String, String)> {
        match Rig::from_toml(src) {
            Err(RigError::Invalid {
                source,
                diagnostics,
            }) => {
                assert_eq!(source, src);
                diagnostics
                    .iter()
                    .map(|d| {
                        assert!(d.help.is_some(), "{}: no help", d.message);
                        (
                            d.code,
                            d.message.clone(),
                            src[d.span.start..d.span.end].to_string(),
                        )
                    })
                    .collect()
            }
            other => panic!("{src:?} was not refused: {other:?}"),
        }
    }

    #[test]
    fn refuses_bad_rigs_with_clear_messages() {
        for (src, code, needle, at) in [
            (
                "up = \"x\"\ndrone = 1\n",
                RigCode::BadValue,
                "\"y\" (its default) or \"z\"",
                "\"x\"",
            ),
            ("drone = 1\n", RigCode::MissingKey, "no `up`", ""),
            (
                "up = \"y\"\ndrone = 1\n[actors]\nA = 1\n",
                RigCode::BadValue,
                "already the drone",
                "1",
            ),
            (
                "up = \"y\"\ndrone = 1\n[actors]\nA = 2\nB = 2\n",
                RigCode::BadValue,
                "already actor `A`",
                "2",
            ),
            (
                "up = \"y\"\ndrone = 1\norgin_m = [0, 0, 0]\n",
                RigCode::UnknownKey,
                "`orgin_m`",
                "orgin_m",
            ),
            (
                "up = \"y\"\ndrone = 5000000000\n",
                RigCode::BadValue,
                "out of range",
                "5000000000",
            ),
            (
                "up = \"y\"\ndrone = 1\nyaw_deg = nan\n",
                RigCode::BadValue,
                "finite",
                "nan",
            ),
            (
                "up = \"y\"\ndrone = \"1\"\n",
                RigCode::BadValue,
                "found the text",
                "\"1\"",
            ),
            (
                "up = \"y\"\ndrone = 1\norigin_m = [0, 0]\n",
                RigCode::BadValue,
                "3 numbers",
                "[0, 0]",
            ),
            (
                "up = \"y\"\ndrone = 1\nactors = 3\n",
                RigCode::BadValue,
                "must be a table",
                "3",
            ),
            (
                "up = \"y\"\ndrone = = 1\n",
                RigCode::Syntax,
                "invalid TOML",
                "=",
            ),
        ] {
            let found = mistakes(src);
            assert!(
                found
                    .iter()
                    .any(|(c, m, a)| *c == code && m.contains(needle) && a == at),
                "{src:?}: {found:?}"
            );
        }
        // Every mistake at once, in file order.
        let found = mistakes("up = \"x\"\ndrone = 1\norgin_m = [0, 0, 0]\n[actors]\nA = 1\n");
        let codes: Vec<dronecine_diag::Code> = found.iter().map(|f| f.0).collect();
        assert_eq!(
            codes,
            [RigCode::BadValue, RigCode::UnknownKey, RigCode::BadValue].map(RigCode::code),
            "{found:?}"
        );
        assert!(found[1].1.contains("orgin_m"));
        // TOML's other integer forms are numbers too.
        let rig = Rig::from_toml("up = \"y\"\ndrone = 0x10\nyaw_deg = 0x5A\n").unwrap();
        assert_eq!(rig.drone_id, 16);
        assert!((rig.yaw_rad - FRAC_PI_2).abs() < 1e-12);
        let rig = Rig::from_toml("up = \"y\"\ndrone = 1\n[actors]\nAlice = 2\n").unwrap();
        let e = rig.actor_ids(["Alice", "Bob"]).unwrap_err().to_string();
        assert!(e.contains("actor `Bob`") && e.contains("Alice"), "{e}");
    }
}
