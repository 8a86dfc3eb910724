//! Drone profiles: the model, limits, camera, safety distance and servo settings of a drone.
//!
//! The types here are the one description of a drone that the compiler (limits, camera,
//! safety) and the runtime (model, servo weights, noise) read. SI units inside, with the unit
//! in every field name.
//!
//! Profiles are written in TOML for people (`profiles/*.toml` are the built-in ones,
//! embedded in the binary): angles in degrees (`_deg`, `_degps` keys, turned into radians
//! here), other units in the key names, sections `[model]`, `[limits]`, `[camera]`,
//! `[safety]`, `[servo]`. `Profile::from_toml` walks the spanned TOML tree and checks every
//! key against the schema below, reporting every mistake of a file at once with spans into
//! the TOML (`profile::syntax`, `profile::bad_value`, `profile::unknown_key` with a
//! did-you-mean, `profile::missing_key`); `Profile::load` reads a file (`profile::not_found`).
//! The horizontal speed and acceleration limits follow from tilt and model
//! (`derived_motion_limits`); a profile may set them lower, never higher.

use dronecine_math as math;
use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use dronecine_diag::suggest::{closest, did_you_mean, or_list};
use dronecine_diag::toml::{eof_span, error_span, kind_of, span as sp};
use dronecine_diag::{Diagnostic, LineIndex, Span};
use serde::{Deserialize, Serialize};
use toml::de::{DeTable, DeValue};
use toml::Spanned;

dronecine_diag::codes! {
    /// A drone profile's diagnostic codes (`profile::`).
    pub enum ProfileCode {
        Syntax => "profile::syntax": "A drone profile is not valid TOML.",
        BadValue => "profile::bad_value": "A drone profile value has the wrong type or lies outside its range.",
        UnknownKey => "profile::unknown_key": "A drone profile has a key dronecine does not know.",
        MissingKey => "profile::missing_key": "A drone profile lacks a required key.",
        NotFound => "profile::not_found": "The drone profile file cannot be read.",
    }
}

/// Names accepted by `drone NAME` in a script.
pub const BUILTIN_NAMES: &[&str] = &[
    "ardrone2",
    "ardrone2-outdoor",
    "arducopter-quad",
    "crazyflie21",
];

/// The profile used when a script names none.
pub const DEFAULT_NAME: &str = "ardrone2";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    pub name: String,
    pub description: String,
    pub model: Model,
    pub limits: Limits,
    pub camera: Camera,
    pub safety: Safety,
    pub servo: Servo,
}

/// The servo's plant model: per axis `v̇ = (K·u − v)/τ`, heading `ċ = K_ψ·ψ̇`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// K_φ: lateral speed per radian of roll, m/s per rad.
    pub gain_roll_mps_per_rad: f64,
    /// K_θ: longitudinal speed per radian of pitch, m/s per rad.
    pub gain_pitch_mps_per_rad: f64,
    /// K_ż: vertical speed per commanded vertical speed.
    pub gain_vz: f64,
    pub tau_roll_s: f64,
    pub tau_pitch_s: f64,
    pub tau_vz_s: f64,
    /// K_ψ: heading rate per commanded yaw rate.
    pub gain_yaw: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Largest roll or pitch command (AR.Drone `euler_angle_max`).
    pub tilt_max_rad: f64,
    /// AR.Drone `control_vz_max`.
    pub vz_max_mps: f64,
    /// AR.Drone `control_yaw`.
    pub yaw_rate_max_radps: f64,
    /// Horizontal speed the reference may ask for; follows from tilt and the model
    /// (`K·tilt_max·authority`), leaving the rest of the tilt to the servo's corrections.
    pub speed_max_mps: f64,
    /// Horizontal acceleration the reference may ask for (`K·tilt_max·(1 − authority)/τ`).
    pub accel_max_mps2: f64,
    /// Jerk bound of the reference (smoothness).
    pub jerk_max_mps3: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Whether the drone carries a camera. Without one (`mounted = false`) the shots are
    /// framed for the lens below, a nominal camera looking along the heading: the path is
    /// the one a camera there would need, and nothing is filmed. A flight log's profile
    /// without the field (its format predates it) had a camera.
    #[serde(default = "mounted_default")]
    pub mounted: bool,
    /// Horizontal field of view.
    pub fov_x_rad: f64,
    /// Frame width over height.
    pub aspect: f64,
    pub gimbal: Gimbal,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Gimbal {
    /// A camera fixed to the body, looking along the heading, level (AR.Drone front camera).
    None,
    /// A pitch gimbal with its range (up positive) and the rate it turns at.
    Pitch {
        min_rad: f64,
        max_rad: f64,
        /// How fast the gimbal turns the camera's pitch. A flight log's profile without it
        /// (its format predates the field) reads as infinite: the camera was taken to be at
        /// the pitch asked of it at once, which is how such a flight was measured.
        #[serde(default = "unlimited_rate")]
        rate_radps: f64,
    },
}

fn mounted_default() -> bool {
    true
}

fn unlimited_rate() -> f64 {
    f64::INFINITY
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Safety {
    /// No part of the reference comes closer than this to an actor's body axis.
    pub actor_distance_m: f64,
    /// The reference stays this far inside the stage walls, floor and ceiling.
    pub stage_margin_m: f64,
    /// On set, the reference keeps `actor_distance_m` plus this from the actors, so that the
    /// drone itself, which strays from its reference by its tracking error, keeps
    /// `actor_distance_m` (the director, against measured actors). A compiled reference, a
    /// perfect drone's, keeps `actor_distance_m` only. A flight log whose profile has no
    /// margin (its format predates the field) reads as 0, how such a flight flew.
    #[serde(default)]
    pub tracking_margin_m: f64,
}

impl Safety {
    /// The distance the reference keeps from the actors' bodies on set:
    /// `actor_distance_m + tracking_margin_m`.
    pub fn on_set_m(&self) -> f64 {
        self.actor_distance_m + self.tracking_margin_m
    }
}

/// Settings of the runtime's LQG servo and Kalman filters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Servo {
    /// Diagonal of Q on the state [vx, vy, vz, x, y, z].
    pub q: [f64; 6],
    /// Diagonal of R on the input [roll, pitch, vz].
    pub r: [f64; 3],
    /// Heading loop: the error falls to `heading_gamma` after `heading_tau_s`.
    pub heading_gamma: f64,
    pub heading_tau_s: f64,
    /// Kalman process noise (F1 diagonal, state [vx, vy, vz, x, y, z]).
    pub process_noise: [f64; 6],
    /// Kalman measurement noise (H1 diagonal, position [x, y, z]), m².
    pub measurement_noise_m2: [f64; 3],
    /// Heading process noise f2 and measurement noise h2, rad².
    pub heading_process_noise_rad2: f64,
    pub heading_measurement_noise_rad2: f64,
}

/// The share of the tilt the reference may use for cruising speed when a profile names none.
pub const DEFAULT_AUTHORITY: f64 = 0.5;

/// The tracking margin of a profile that names none ([`Safety::tracking_margin_m`]): the
/// larger of the built-in AR.Drone profiles' (0.10 m with the indoor limits, 0.15 m with the
/// outdoor ones).
pub const DEFAULT_TRACKING_MARGIN_M: f64 = 0.15;

const ARDRONE2_TOML: &str = include_str!("../profiles/ardrone2.toml");
const ARDRONE2_OUTDOOR_TOML: &str = include_str!("../profiles/ardrone2-outdoor.toml");
const ARDUCOPTER_QUAD_TOML: &str = include_str!("../profiles/arducopter-quad.toml");
const CRAZYFLIE21_TOML: &str = include_str!("../profiles/crazyflie21.toml");

/// The TOML text of a built-in profile (what `Profile::builtin` parses).
pub fn builtin_source(name: &str) -> Option<&'static str> {
    match name {
        "ardrone2" => Some(ARDRONE2_TOML),
        "ardrone2-outdoor" => Some(ARDRONE2_OUTDOOR_TOML),
        "arducopter-quad" => Some(ARDUCOPTER_QUAD_TOML),
        "crazyflie21" => Some(CRAZYFLIE21_TOML),
        _ => None,
    }
}

/// The horizontal speed and acceleration limits that follow from the model and the tilt
/// limit: `K·tilt_max·authority` and `K·tilt_max·(1 − authority)/τ`, each the smaller over
/// the roll and pitch axes. `authority` is the share of the tilt the reference may spend on
/// speed; the rest is left to accelerating and to the servo's corrections.
pub fn derived_motion_limits(model: &Model, tilt_max_rad: f64, authority: f64) -> (f64, f64) {
    let axes = [
        (model.gain_roll_mps_per_rad, model.tau_roll_s),
        (model.gain_pitch_mps_per_rad, model.tau_pitch_s),
    ];
    let speed = axes
        .iter()
        .map(|&(k, _)| k * tilt_max_rad * authority)
        .fold(f64::INFINITY, f64::min);
    let accel = axes
        .iter()
        .map(|&(k, tau)| k * tilt_max_rad * (1.0 - authority) / tau)
        .fold(f64::INFINITY, f64::min);
    (speed, accel)
}

impl Profile {
    /// A built-in profile by name (`BUILTIN_NAMES`), parsed from its embedded TOML.
    pub fn builtin(name: &str) -> Option<Profile> {
        static CACHE: OnceLock<Vec<(&'static str, Option<Profile>)>> = OnceLock::new();
        let cache = CACHE.get_or_init(|| {
            BUILTIN_NAMES
                .iter()
                .map(|&n| {
                    let parsed = builtin_source(n)
                        .and_then(|src| Profile::from_toml(n, src).ok())
                        .map(|(p, _)| p);
                    (n, parsed)
                })
                .collect()
        });
        cache
            .iter()
            .find(|(n, _)| *n == name)
            .and_then(|(_, p)| p.clone())
    }

    /// Parse and validate a profile written in TOML. `name` becomes the profile's name.
    ///
    /// On success, the profile and its warnings; otherwise every diagnostic found (at least
    /// one an error), sorted by position, with spans into `src`. Never panics.
    pub fn from_toml(name: &str, src: &str) -> Result<(Profile, Vec<Diagnostic>), Vec<Diagnostic>> {
        let (doc, errors) = DeTable::parse_recoverable(src);
        if !errors.is_empty() {
            return Err(syntax_diagnostics(src, &errors));
        }
        let mut r = Reader {
            src,
            diags: Vec::new(),
            explained: Vec::new(),
            missing_sections: Vec::new(),
        };
        let profile = r.profile(name, doc.get_ref());
        let mut diags = r.diags;
        diags.sort_by_key(|d| (d.span.start, d.span.end));
        match profile {
            Some(p) if !diags.iter().any(Diagnostic::is_error) => Ok((p, diags)),
            _ => {
                if !diags.iter().any(Diagnostic::is_error) {
                    // Every failure path reports; this keeps the promise if one did not.
                    diags.push(Diagnostic::error(
                        ProfileCode::BadValue,
                        eof_span(src),
                        "the profile is incomplete",
                    )
                    .with_help("this is a bug in dronecine's profile reader; please report it with the profile"));
                }
                Err(diags)
            }
        }
    }

    /// Read and validate a profile file. The profile is named after the file's stem
    /// (`profiles/mine.toml` → `mine`).
    ///
    /// Returns the profile, the file's text and the warnings, or a `ProfileError`.
    pub fn load(path: &Path) -> Result<(Profile, String, Vec<Diagnostic>), ProfileError> {
        let bytes = std::fs::read(path).map_err(|error| ProfileError::Unreadable {
            path: path.to_path_buf(),
            error,
        })?;
        let src = match dronecine_diag::decode_utf8(
            &bytes,
            ProfileCode::Syntax,
            "save the profile as UTF-8 text",
        ) {
            Ok(s) => s.to_string(),
            Err((source, diagnostics)) => {
                return Err(ProfileError::Invalid {
                    source,
                    diagnostics,
                });
            }
        };
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        match Profile::from_toml(&name, &src) {
            Ok((profile, warnings)) => Ok((profile, src, warnings)),
            Err(diagnostics) => Err(ProfileError::Invalid {
                source: src,
                diagnostics,
            }),
        }
    }

    /// The profile as TOML in the form `from_toml` reads (angles in degrees; the speed and
    /// acceleration limits written out, with the authority they imply).
    pub fn to_toml(&self) -> String {
        let m = &self.model;
        let l = &self.limits;
        let c = &self.camera;
        let s = &self.servo;
        let k_min = m.gain_roll_mps_per_rad.min(m.gain_pitch_mps_per_rad);
        let authority = l.speed_max_mps / (k_min * l.tilt_max_rad);
        let mut out = String::new();
        let mut line = |key: &str, value: String| {
            out.push_str(key);
            out.push_str(" = ");
            out.push_str(&value);
            out.push('\n');
        };
        line("description", toml_string(&self.description));
        line(
            "\n[model]\ngain_roll_mps_per_rad",
            num(m.gain_roll_mps_per_rad),
        );
        line("gain_pitch_mps_per_rad", num(m.gain_pitch_mps_per_rad));
        line("gain_vz", num(m.gain_vz));
        line("tau_roll_s", num(m.tau_roll_s));
        line("tau_pitch_s", num(m.tau_pitch_s));
        line("tau_vz_s", num(m.tau_vz_s));
        line("gain_yaw", num(m.gain_yaw));
        line("\n[limits]\ntilt_max_deg", num(l.tilt_max_rad.to_degrees()));
        line("vz_max_mps", num(l.vz_max_mps));
        line("yaw_rate_max_degps", num(l.yaw_rate_max_radps.to_degrees()));
        line("authority", num(authority));
        line("speed_max_mps", num(l.speed_max_mps));
        line("accel_max_mps2", num(l.accel_max_mps2));
        line("jerk_max_mps3", num(l.jerk_max_mps3));
        line("\n[camera]\nfov_x_deg", num(c.fov_x_rad.to_degrees()));
        if !c.mounted {
            line("mounted", "false".into());
        }
        line("aspect", num(c.aspect));
        line(
            "gimbal",
            match c.gimbal {
                Gimbal::None => "\"none\"".to_string(),
                Gimbal::Pitch {
                    min_rad,
                    max_rad,
                    rate_radps,
                } => format!(
                    "{{ pitch_min_deg = {}, pitch_max_deg = {}, rate_degps = {} }}",
                    num(min_rad.to_degrees()),
                    num(max_rad.to_degrees()),
                    num(rate_radps.to_degrees())
                ),
            },
        );
        line(
            "\n[safety]\nactor_distance_m",
            num(self.safety.actor_distance_m),
        );
        line("stage_margin_m", num(self.safety.stage_margin_m));
        line("tracking_margin_m", num(self.safety.tracking_margin_m));
        line("\n[servo]\nq", list(&s.q));
        line("r", list(&s.r));
        line("heading_gamma", num(s.heading_gamma));
        line("heading_tau_s", num(s.heading_tau_s));
        line("process_noise", list(&s.process_noise));
        line("measurement_noise_m2", list(&s.measurement_noise_m2));
        line(
            "heading_process_noise_rad2",
            num(s.heading_process_noise_rad2),
        );
        line(
            "heading_measurement_noise_rad2",
            num(s.heading_measurement_noise_rad2),
        );
        out
    }
}

/// A profile file that could not be used.
#[derive(Debug)]
pub enum ProfileError {
    /// The file cannot be read (missing, a folder, no permission).
    Unreadable {
        path: PathBuf,
        error: std::io::Error,
    },
    /// The file was read but is not a valid profile: its text (bytes that are not UTF-8
    /// shown as U+FFFD) and the diagnostics, spans into that text, at least one an error.
    Invalid {
        source: String,
        diagnostics: Vec<Diagnostic>,
    },
}

impl ProfileError {
    /// For an unreadable file, the `profile::not_found` diagnostic, placed at `span` (where
    /// the script names the file: the file itself has no text to point into).
    pub fn not_found(&self, span: Span) -> Option<Diagnostic> {
        let ProfileError::Unreadable { path, error } = self else {
            return None;
        };
        let why = match error.kind() {
            std::io::ErrorKind::NotFound => "no such file".to_string(),
            std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
            _ => error.to_string(),
        };
        Some(
            Diagnostic::error(
                ProfileCode::NotFound,
                span,
                format!(
                    "drone profile `{}` cannot be read: {why}",
                    path.display()
                ),
            )
            .with_label(why)
            .with_help(format!(
                "give the path of a TOML profile file, relative to the script's folder, or a built-in profile: {}",
                or_list(BUILTIN_NAMES)
            )),
        )
    }
}

impl fmt::Display for ProfileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ProfileError::Unreadable { path, error } => {
                write!(f, "cannot read drone profile {}: {error}", path.display())
            }
            ProfileError::Invalid { diagnostics, .. } => {
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                write!(f, "the drone profile has {errors} error(s)")
            }
        }
    }
}

impl std::error::Error for ProfileError {}

// ---------------------------------------------------------------------------------------
// The schema: every key, its range, an example (the AR.Drone 2.0's value) and its meaning.

#[derive(Clone, Copy, Debug)]
enum Lo {
    Any,
    Gt(f64),
    Ge(f64),
}

#[derive(Clone, Copy, Debug)]
enum Hi {
    Any,
    Lt(f64),
    Le(f64),
}

#[derive(Clone, Copy, Debug)]
struct Range {
    lo: Lo,
    hi: Hi,
}

impl Range {
    const fn new(lo: Lo, hi: Hi) -> Range {
        Range { lo, hi }
    }

    fn contains(self, x: f64) -> bool {
        let lo = match self.lo {
            Lo::Any => true,
            Lo::Gt(a) => x > a,
            Lo::Ge(a) => x >= a,
        };
        let hi = match self.hi {
            Hi::Any => true,
            Hi::Lt(b) => x < b,
            Hi::Le(b) => x <= b,
        };
        lo && hi
    }

    /// "> 0 and ≤ 100 m/s per rad".
    fn describe(self, unit: &str) -> String {
        let lo = match self.lo {
            Lo::Any => None,
            Lo::Gt(a) => Some(format!("> {a}")),
            Lo::Ge(a) => Some(format!("≥ {a}")),
        };
        let hi = match self.hi {
            Hi::Any => None,
            Hi::Lt(b) => Some(format!("< {b}")),
            Hi::Le(b) => Some(format!("≤ {b}")),
        };
        let text = match (lo, hi) {
            (Some(a), Some(b)) => format!("{a} and {b}"),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => "a finite number".to_string(),
        };
        format!("{text}{unit}")
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Text,
    /// A number in the unit of its key (`_deg` keys are converted to radians).
    Num(Range),
    /// A fixed-length list of numbers; the names of its entries.
    List(&'static [&'static str], Range),
    /// Read by dedicated code (section tables, field of view, aspect, gimbal).
    Special,
}

#[derive(Debug)]
struct KeySpec {
    name: &'static str,
    kind: Kind,
    required: bool,
    /// Unit shown after numbers ("" when none), with its leading space.
    unit: &'static str,
    /// The AR.Drone 2.0's value, as TOML.
    example: &'static str,
    meaning: &'static str,
}

const fn key(
    name: &'static str,
    kind: Kind,
    unit: &'static str,
    example: &'static str,
    meaning: &'static str,
) -> KeySpec {
    KeySpec {
        name,
        kind,
        required: true,
        unit,
        example,
        meaning,
    }
}

const fn optional(spec: KeySpec) -> KeySpec {
    KeySpec {
        required: false,
        ..spec
    }
}

struct SectionSpec {
    /// "" for the top level.
    name: &'static str,
    keys: &'static [KeySpec],
}

impl SectionSpec {
    fn spec(&self, name: &str) -> &'static KeySpec {
        self.keys
            .iter()
            .find(|k| k.name == name)
            .unwrap_or(&FALLBACK_KEY)
    }

    fn title(&self) -> String {
        if self.name.is_empty() {
            "the top level".to_string()
        } else {
            format!("[{}]", self.name)
        }
    }
}

const FALLBACK_KEY: KeySpec = optional(key("?", Kind::Special, "", "", ""));

const POSITIVE: Lo = Lo::Gt(0.0);
const XYZ6: &[&str] = &["vx", "vy", "vz", "x", "y", "z"];

const ROOT: SectionSpec = SectionSpec {
    name: "",
    keys: &[
        optional(key(
            "description",
            Kind::Text,
            "",
            "\"Parrot AR.Drone 2.0, indoor firmware limits\"",
            "a line saying which drone this is",
        )),
        key("model", Kind::Special, "", "", "the plant model"),
        key("limits", Kind::Special, "", "", "the flight limits"),
        key("camera", Kind::Special, "", "", "the camera"),
        key("safety", Kind::Special, "", "", "the safety distances"),
        key("servo", Kind::Special, "", "", "the servo settings"),
    ],
};

const MODEL: SectionSpec = SectionSpec {
    name: "model",
    keys: &[
        key(
            "gain_roll_mps_per_rad",
            Kind::Num(Range::new(POSITIVE, Hi::Le(100.0))),
            " m/s per rad",
            "17.5",
            "K_φ, the lateral speed one radian of roll settles at",
        ),
        key(
            "gain_pitch_mps_per_rad",
            Kind::Num(Range::new(POSITIVE, Hi::Le(100.0))),
            " m/s per rad",
            "17.5",
            "K_θ, the longitudinal speed one radian of pitch settles at",
        ),
        key(
            "gain_vz",
            Kind::Num(Range::new(POSITIVE, Hi::Le(10.0))),
            "",
            "1.0",
            "K_ż, the vertical speed per commanded vertical speed",
        ),
        key(
            "tau_roll_s",
            Kind::Num(Range::new(POSITIVE, Hi::Le(30.0))),
            " s",
            "1.7",
            "τ_φ, the time constant of the lateral speed",
        ),
        key(
            "tau_pitch_s",
            Kind::Num(Range::new(POSITIVE, Hi::Le(30.0))),
            " s",
            "1.7",
            "τ_θ, the time constant of the longitudinal speed",
        ),
        key(
            "tau_vz_s",
            Kind::Num(Range::new(POSITIVE, Hi::Le(30.0))),
            " s",
            "1.25",
            "τ_ż, the time constant of the vertical speed",
        ),
        key(
            "gain_yaw",
            Kind::Num(Range::new(POSITIVE, Hi::Le(10.0))),
            "",
            "1.0",
            "K_ψ, the heading rate per commanded yaw rate",
        ),
    ],
};

const LIMITS: SectionSpec = SectionSpec {
    name: "limits",
    keys: &[
        key(
            "tilt_max_deg",
            Kind::Num(Range::new(POSITIVE, Hi::Le(45.0))),
            "°",
            "12.03211",
            "the largest roll or pitch command, the AR.Drone firmware's `euler_angle_max`",
        ),
        key(
            "vz_max_mps",
            Kind::Num(Range::new(POSITIVE, Hi::Le(10.0))),
            " m/s",
            "0.7",
            "the largest vertical speed command, the AR.Drone firmware's `control_vz_max`",
        ),
        key(
            "yaw_rate_max_degps",
            Kind::Num(Range::new(POSITIVE, Hi::Le(720.0))),
            "°/s",
            "100.26761",
            "the largest yaw rate command, the AR.Drone firmware's `control_yaw`",
        ),
        optional(key(
            "authority",
            Kind::Num(Range::new(POSITIVE, Hi::Lt(1.0))),
            "",
            "0.5",
            "the share of the tilt the reference may spend on speed; the rest is left to accelerating and to the servo",
        )),
        optional(key(
            "speed_max_mps",
            Kind::Num(Range::new(POSITIVE, Hi::Any)),
            " m/s",
            "1.5",
            "a horizontal speed limit below the one that follows from tilt and model",
        )),
        optional(key(
            "accel_max_mps2",
            Kind::Num(Range::new(POSITIVE, Hi::Any)),
            " m/s²",
            "1.0",
            "a horizontal acceleration limit below the one that follows from tilt and model",
        )),
        key(
            "jerk_max_mps3",
            Kind::Num(Range::new(POSITIVE, Hi::Le(100.0))),
            " m/s³",
            "5.0",
            "the jerk bound that keeps the reference smooth",
        ),
    ],
};

const FOV: Range = Range::new(POSITIVE, Hi::Lt(180.0));

const CAMERA: SectionSpec = SectionSpec {
    name: "camera",
    keys: &[
        optional(key(
            "mounted",
            Kind::Special,
            "",
            "false",
            "whether the drone carries a camera (`false`: none, the shots are framed for the nominal lens below)",
        )),
        optional(key(
            "fov_x_deg",
            Kind::Num(FOV),
            "°",
            "84.1",
            "the lens's horizontal field of view",
        )),
        optional(key(
            "fov_diagonal_deg",
            Kind::Num(FOV),
            "°",
            "92.0",
            "the lens's diagonal field of view",
        )),
        key(
            "aspect",
            Kind::Special,
            "",
            "\"16:9\"",
            "the frame's width over its height",
        ),
        key(
            "gimbal",
            Kind::Special,
            "",
            "\"none\"",
            "the camera mount: `\"none\"` (fixed, level) or `{ pitch_min_deg = -90, pitch_max_deg = 30, rate_degps = 90 }`",
        ),
    ],
};

const GIMBAL_PITCH: Range = Range::new(Lo::Ge(-90.0), Hi::Le(90.0));

const GIMBAL: SectionSpec = SectionSpec {
    name: "camera.gimbal",
    keys: &[
        key(
            "pitch_min_deg",
            Kind::Num(GIMBAL_PITCH),
            "°",
            "-90",
            "the lowest camera pitch of the gimbal (up positive)",
        ),
        key(
            "pitch_max_deg",
            Kind::Num(GIMBAL_PITCH),
            "°",
            "30",
            "the highest camera pitch of the gimbal (up positive)",
        ),
        key(
            "rate_degps",
            Kind::Num(Range::new(POSITIVE, Hi::Le(1800.0))),
            "°/s",
            "90",
            "how fast the gimbal turns the camera's pitch",
        ),
    ],
};

const SAFETY: SectionSpec = SectionSpec {
    name: "safety",
    keys: &[
        key(
            "actor_distance_m",
            Kind::Num(Range::new(Lo::Ge(0.0), Hi::Le(100.0))),
            " m",
            "0.5",
            "how close the drone may come to an actor's body axis",
        ),
        key(
            "stage_margin_m",
            Kind::Num(Range::new(Lo::Ge(0.0), Hi::Le(100.0))),
            " m",
            "0.3",
            "how far inside the stage's walls, floor and ceiling the drone stays",
        ),
        optional(key(
            "tracking_margin_m",
            Kind::Num(Range::new(Lo::Ge(0.0), Hi::Le(10.0))),
            " m",
            "0.10",
            "how far the drone strays from its reference (a flight reports it as `cut_in_m`): on set the reference keeps this much more than `actor_distance_m` from the actors",
        )),
    ],
};

const SERVO: SectionSpec = SectionSpec {
    name: "servo",
    keys: &[
        key(
            "q",
            Kind::List(XYZ6, Range::new(Lo::Ge(0.0), Hi::Any)),
            "",
            "[1.0, 1.0, 1.0, 30.0, 30.0, 30.0]",
            "the LQG state weights on [vx, vy, vz, x, y, z]",
        ),
        key(
            "r",
            Kind::List(&["roll", "pitch", "vz"], Range::new(POSITIVE, Hi::Any)),
            "",
            "[30.0, 30.0, 5.0]",
            "the LQG input weights on [roll, pitch, vz]; they must be positive for the regulator's gain to exist",
        ),
        key(
            "heading_gamma",
            Kind::Num(Range::new(POSITIVE, Hi::Lt(1.0))),
            "",
            "0.05",
            "the share of a heading error left after heading_tau_s",
        ),
        key(
            "heading_tau_s",
            Kind::Num(Range::new(POSITIVE, Hi::Le(60.0))),
            " s",
            "0.5",
            "the time in which the heading error falls to heading_gamma of itself",
        ),
        key(
            "process_noise",
            Kind::List(XYZ6, Range::new(POSITIVE, Hi::Any)),
            "",
            "[1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5]",
            "the Kalman filter's process noise variances on [vx, vy, vz, x, y, z]",
        ),
        key(
            "measurement_noise_m2",
            Kind::List(&["x", "y", "z"], Range::new(POSITIVE, Hi::Any)),
            " m²",
            "[1e-6, 1e-6, 1e-6]",
            "the Kalman filter's measurement noise variances on the position [x, y, z]",
        ),
        key(
            "heading_process_noise_rad2",
            Kind::Num(Range::new(POSITIVE, Hi::Any)),
            " rad²",
            "1e-4",
            "the heading filter's process noise variance",
        ),
        key(
            "heading_measurement_noise_rad2",
            Kind::Num(Range::new(POSITIVE, Hi::Any)),
            " rad²",
            "1e-5",
            "the heading filter's measurement noise variance",
        ),
    ],
};

const ALL_SECTIONS: &[&SectionSpec] = &[&ROOT, &MODEL, &LIMITS, &CAMERA, &GIMBAL, &SAFETY, &SERVO];

/// Above this tilt the linear model (speed ∝ tilt, not sin(tilt)) is off by more than 5 %.
const SMALL_ANGLE_TILT_DEG: f64 = 30.0;

// ---------------------------------------------------------------------------------------
// Reading: a walk over the spanned TOML tree that reports every mistake it meets.

fn num(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        format!("{x:?}")
    }
}

fn list(xs: &[f64]) -> String {
    let items: Vec<String> = xs.iter().map(|&x| num(x)).collect();
    format!("[{}]", items.join(", "))
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A number for a message: as written when short, else to five significant digits.
fn show(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 10 {
        plain
    } else if x != 0.0 && x.abs() < 1e-3 {
        format!("{x:.4e}")
    } else {
        let decimals = (4 - math::log10(x.abs()).floor() as i32).clamp(0, 12) as usize;
        let fixed = format!("{x:.decimals$}");
        if fixed.contains('.') {
            fixed
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        } else {
            fixed
        }
    }
}

/// The syntax errors of a file as diagnostics: the first of each line, and an error on a
/// line that is valid TOML by itself (a cascade: an array, table or string left open above
/// runs into it) is moved to the line above that is not valid by itself.
fn syntax_diagnostics(src: &str, errors: &[toml::de::Error]) -> Vec<Diagnostic> {
    let index = LineIndex::new(src);
    let line_of = |offset: usize| index.line_col(src, offset).0;
    let line_count = line_of(src.len());
    let line_text = |line: usize| {
        let s = index.line_span(src, line);
        (s.start, &src[s.start..s.end])
    };
    // Per line (1-based): the nearest line at or above it that is not valid TOML alone.
    let mut last_invalid = vec![None; line_count + 1];
    for line in 1..=line_count {
        last_invalid[line] = if DeTable::parse(line_text(line).1).is_err() {
            Some(line)
        } else {
            last_invalid[line - 1]
        };
    }
    let mut found: Vec<Diagnostic> = errors.iter().map(|e| syntax(src, e, 0)).collect();
    found.sort_by_key(|d| (d.span.start, d.span.end));
    let error_lines: BTreeSet<usize> = found.iter().map(|d| line_of(d.span.start)).collect();
    let mut reported_lines = BTreeSet::new();
    let mut out = Vec::new();
    for d in found {
        let line = line_of(d.span.start);
        if !reported_lines.insert(line) {
            continue;
        }
        if last_invalid[line] == Some(line) {
            out.push(d);
            continue;
        }
        match last_invalid[line] {
            Some(l) if !error_lines.contains(&l) => {
                if !reported_lines.insert(l) {
                    continue;
                }
                let (offset, text) = line_text(l);
                let (_, own) = DeTable::parse_recoverable(text);
                match own.first() {
                    Some(e) => out.push(syntax(src, e, offset)),
                    None => out.push(d),
                }
            }
            _ => out.push(d),
        }
    }
    out.sort_by_key(|d| (d.span.start, d.span.end));
    if out.len() > MAX_SYNTAX_DIAGNOSTICS {
        let more = out.len() - MAX_SYNTAX_DIAGNOSTICS;
        out.truncate(MAX_SYNTAX_DIAGNOSTICS);
        if let Some(last) = out.last_mut() {
            last.message
                .push_str(&format!(" (and {more} more syntax errors below)"));
        }
    }
    out
}

/// Syntax errors reported for one file at most (a binary file would give thousands).
const MAX_SYNTAX_DIAGNOSTICS: usize = 20;

/// One TOML error as a diagnostic; `offset` shifts a span found by parsing a single line.
fn syntax(src: &str, e: &toml::de::Error, offset: usize) -> Diagnostic {
    let span = error_span(src, e, offset);
    if let Some(d) = unit_after_number(src, span.start) {
        return d;
    }
    let message = e.message().trim();
    let first = message.lines().next().unwrap_or("invalid TOML");
    let first = first.strip_suffix(", expected nothing").unwrap_or(first);
    let help = if message.contains("duplicate key") {
        "each key appears once in its section, and each section once in the file: delete or merge the second one"
    } else if message.contains("string") || message.contains("invalid") {
        "TOML writes `key = value`: numbers bare (`tau_roll_s = 1.7`, the unit is in the key's name), text in double quotes (`gimbal = \"none\"`)"
    } else {
        "TOML writes one `key = value` per line and sections as `[model]`; lists as `[1.0, 2.0]`, closed on the same line or a later one"
    };
    Diagnostic::error(ProfileCode::Syntax, span, format!("invalid TOML: {first}"))
        .with_label(first.to_string())
        .with_help(help)
}

/// `tau_roll_s = 1.7s`: a value that is a number followed by a unit, on the line of `at`.
fn unit_after_number(src: &str, at: usize) -> Option<Diagnostic> {
    let line_start = src[..at.min(src.len())].rfind('\n').map_or(0, |i| i + 1);
    let line_end = src[line_start..]
        .find('\n')
        .map_or(src.len(), |i| line_start + i);
    let line = &src[line_start..line_end];
    let eq = line.find('=')?;
    let key = line[..eq].trim();
    let after = &line[eq + 1..];
    let value_text = after.split('#').next()?.trim_end();
    let lead = value_text.len() - value_text.trim_start().len();
    let value = value_text.trim_start();
    let number_len = (1..=value.len())
        .rev()
        .filter(|&n| value.is_char_boundary(n))
        .find(|&n| parse_float(&value[..n]).is_some_and(f64::is_finite))?;
    let (number, rest) = value.split_at(number_len);
    let unit = rest.trim();
    if !unit.starts_with(|c: char| c.is_alphabetic() || c == '°' || c == '%') {
        return None;
    }
    let start = line_start + eq + 1 + lead;
    let span = Span::new(start, start + value.len());
    Some(
        Diagnostic::error(
            ProfileCode::Syntax,
            span,
            format!("invalid TOML: `{value}` is a number followed by a unit"),
        )
        .with_label("a unit after the number")
        .with_help(format!(
            "write the number alone, `{key} = {}`: the unit is in the key's name",
            number.trim()
        )),
    )
}

enum Got<T> {
    Absent,
    Bad,
    Ok(T, Span),
}

impl<T> Got<T> {
    fn ok(self) -> Option<T> {
        match self {
            Got::Ok(v, _) => Some(v),
            _ => None,
        }
    }
}

struct Reader<'s> {
    src: &'s str,
    diags: Vec<Diagnostic>,
    /// Keys an unknown-key diagnostic already points to (a typo or a misplaced key): not
    /// reported again as missing.
    explained: Vec<&'static str>,
    /// Sections absent from the file, reported together at the end.
    missing_sections: Vec<&'static SectionSpec>,
}

/// One table of the profile being read, with the required keys found missing so far.
struct Section<'a, 'i> {
    spec: &'static SectionSpec,
    table: Option<&'a DeTable<'i>>,
    /// Where missing keys are reported: the `[section]` header or the inline table.
    span: Span,
    missing: Vec<&'static str>,
}

type Value<'i> = Spanned<DeValue<'i>>;

impl<'a, 'i> Section<'a, 'i> {
    /// A section that was absent or not a table (reported once already): reads nothing.
    fn dead(spec: &'static SectionSpec) -> Section<'a, 'i> {
        Section {
            spec,
            table: None,
            span: Span::default(),
            missing: Vec::new(),
        }
    }

    fn entry(&self, key: &str) -> Option<(Span, &'a Value<'i>)> {
        self.table?
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == key)
            .map(|(k, v)| (sp(k.span()), v))
    }

    fn absent(&mut self, key: &'static str) {
        if self.table.is_some() && self.spec.spec(key).required && !self.missing.contains(&key) {
            self.missing.push(key);
        }
    }

    /// A required number, in the unit of its key.
    fn num(&mut self, r: &mut Reader<'_>, key: &'static str) -> Option<f64> {
        match self.opt_num(r, key) {
            Got::Absent => {
                self.absent(key);
                None
            }
            got => got.ok(),
        }
    }

    /// A number that may be absent, checked against its key's range.
    fn opt_num(&mut self, r: &mut Reader<'_>, key: &'static str) -> Got<f64> {
        let Some((_, v)) = self.entry(key) else {
            return Got::Absent;
        };
        let spec = self.spec.spec(key);
        let Some(x) = r.number(spec, v, "") else {
            return Got::Bad;
        };
        let span = sp(v.span());
        if let Kind::Num(range) = spec.kind {
            if !r.in_range(spec, x, span, range, "") {
                return Got::Bad;
            }
        }
        Got::Ok(x, span)
    }

    /// A required list of numbers of its key's length, each in its key's range.
    fn list<const N: usize>(&mut self, r: &mut Reader<'_>, key: &'static str) -> Got<[f64; N]> {
        let Some((_, v)) = self.entry(key) else {
            self.absent(key);
            return Got::Absent;
        };
        let spec = self.spec.spec(key);
        let (names, range) = match spec.kind {
            Kind::List(names, range) => (names, range),
            _ => (&[][..], Range::new(Lo::Any, Hi::Any)),
        };
        let span = sp(v.span());
        let Some(items) = v.get_ref().as_array() else {
            r.bad(
                span,
                format!(
                    "`{}` must be a list of {N} numbers, found {}",
                    spec.name,
                    kind_of(v.get_ref())
                ),
                format!("a list [{}]", names.join(", ")),
                spec,
            );
            return Got::Bad;
        };
        if items.len() != N {
            r.bad(
                span,
                format!(
                    "`{}` must hold {N} numbers, one for each of [{}], found {}",
                    spec.name,
                    names.join(", "),
                    items.len()
                ),
                format!("{} numbers, expected {N}", items.len()),
                spec,
            );
            return Got::Bad;
        }
        let mut out = [0.0; N];
        let mut ok = true;
        for (i, item) in items.iter().enumerate() {
            let name = names.get(i).copied().unwrap_or("?");
            let what = format!("[{i}] ({name})");
            match r.number(spec, item, &what) {
                Some(x) if r.in_range(spec, x, sp(item.span()), range, &what) => {
                    out[i] = x;
                }
                _ => ok = false,
            }
        }
        if ok {
            Got::Ok(out, span)
        } else {
            Got::Bad
        }
    }

    /// Report the required keys that were never found, in one diagnostic.
    fn finish(mut self, r: &mut Reader<'_>) {
        self.missing.retain(|k| !r.explained.contains(k));
        if self.missing.is_empty() {
            return;
        }
        let names: Vec<String> = self.missing.iter().map(|k| format!("`{k}`")).collect();
        let lines: Vec<String> = self
            .missing
            .iter()
            .map(|k| format!("`{k} = {}`", self.spec.spec(k).example))
            .collect();
        let meanings: Vec<String> = self
            .missing
            .iter()
            .map(|k| format!("{k}: {}", self.spec.spec(k).meaning))
            .collect();
        let (what, values) = if names.len() == 1 {
            ("key", "value")
        } else {
            ("keys", "values")
        };
        r.diags.push(
            Diagnostic::error(
                ProfileCode::MissingKey,
                self.span,
                format!(
                    "{} lacks the {what} {}",
                    self.spec.title(),
                    names.join(", ")
                ),
            )
            .with_label(format!("{} missing here", names.join(", ")))
            .with_help(format!(
                "add {} (the AR.Drone 2.0's {values}) — {}",
                lines.join(", "),
                meanings.join("; ")
            )),
        );
    }
}

fn parse_float(s: &str) -> Option<f64> {
    s.replace('_', "").parse::<f64>().ok()
}

/// Why `x` cannot be the value of `[section] key` (its entry `what`, `"[1]"`, for a list), in
/// the words of the profile's own range check; `None` when it can, or when the key is not a
/// number. For values that come from elsewhere than a profile file (`dronecine gains --tau`).
pub fn out_of_range(section: &str, key: &str, what: &str, x: f64) -> Option<String> {
    let spec = [&ROOT, &MODEL, &LIMITS, &CAMERA, &GIMBAL, &SAFETY, &SERVO]
        .into_iter()
        .find(|s| s.name == section)?
        .keys
        .iter()
        .find(|k| k.name == key)?;
    let range = match spec.kind {
        Kind::Num(r) | Kind::List(_, r) => r,
        Kind::Text | Kind::Special => return None,
    };
    if !x.is_finite() {
        return Some(format!("`{key}{what}` must be a finite number, not {x}"));
    }
    (!range.contains(x)).then(|| {
        format!(
            "`{key}{what}` is {x}{}, outside its range: it must be {}",
            spec.unit,
            range.describe(spec.unit)
        )
    })
}

/// `(the AR.Drone 2.0 has `key = value`)` when the built-in profile sets the key (the
/// example is its value: a test pins it), `(for example `key = value`)` when it does not.
fn example(spec: &KeySpec) -> String {
    let set = ARDRONE2_TOML
        .lines()
        .any(|l| l.split('=').next().map(str::trim) == Some(spec.name));
    if set {
        format!("(the AR.Drone 2.0 has `{} = {}`)", spec.name, spec.example)
    } else {
        format!("(for example `{} = {}`)", spec.name, spec.example)
    }
}

impl<'s> Reader<'s> {
    fn bad(&mut self, span: Span, message: String, label: String, spec: &KeySpec) {
        let help = if spec.example.is_empty() {
            spec.meaning.to_string()
        } else {
            format!("{}: {} {}", spec.name, spec.meaning, example(spec))
        };
        self.diags.push(
            Diagnostic::error(ProfileCode::BadValue, span, message)
                .with_label(label)
                .with_help(help),
        );
    }

    /// The value as a finite number, or a diagnostic. `what` names a list entry.
    fn number(&mut self, spec: &KeySpec, v: &Value<'_>, what: &str) -> Option<f64> {
        let span = sp(v.span());
        let x = match v.get_ref() {
            n @ (DeValue::Integer(_) | DeValue::Float(_)) => dronecine_diag::toml::number(n),
            DeValue::String(s) => {
                let t = s.trim();
                let bare = t
                    .trim_end_matches(|c: char| c.is_alphabetic() || c == '°' || c == '/')
                    .trim();
                let help = if parse_float(t).is_some() {
                    format!("write the number without quotes: `{} = {t}`", spec.name)
                } else if !bare.is_empty() && parse_float(bare).is_some() {
                    format!(
                        "write the number alone, without quotes or unit: `{} = {bare}` (the unit,{}, is in the key's name)",
                        spec.name,
                        if spec.unit.is_empty() { " none here" } else { spec.unit }
                    )
                } else {
                    format!("{}: {} {}", spec.name, spec.meaning, example(spec))
                };
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        span,
                        format!(
                            "`{}{what}` must be a number, found {}",
                            spec.name,
                            kind_of(v.get_ref())
                        ),
                    )
                    .with_label("expected a number")
                    .with_help(help),
                );
                return None;
            }
            other => {
                self.bad(
                    span,
                    format!(
                        "`{}{what}` must be a number, found {}",
                        spec.name,
                        kind_of(other)
                    ),
                    "expected a number".to_string(),
                    spec,
                );
                return None;
            }
        };
        match x {
            Some(x) if x.is_finite() => Some(x),
            _ => {
                self.bad(
                    span,
                    format!("`{}{what}` must be a finite number", spec.name),
                    "not a finite number".to_string(),
                    spec,
                );
                None
            }
        }
    }

    fn in_range(&mut self, spec: &KeySpec, x: f64, span: Span, range: Range, what: &str) -> bool {
        if range.contains(x) {
            return true;
        }
        let allowed = range.describe(spec.unit);
        let mut help = format!("{}: {} {}", spec.name, spec.meaning, example(spec));
        if spec.name == "q" {
            help = format!("Q weighs the state [vx, vy, vz, x, y, z]; a negative weight rewards errors, so the LQG regulator would not exist {}", example(spec));
        }
        self.diags.push(
            Diagnostic::error(
                ProfileCode::BadValue,
                span,
                format!(
                    "`{}{what}` is {}{}, outside its range: it must be {allowed}",
                    spec.name,
                    show(x),
                    spec.unit
                ),
            )
            .with_label(format!("must be {allowed}"))
            .with_help(help),
        );
        false
    }

    /// Report the keys of a table its spec does not know.
    fn unknown_keys(&mut self, spec: &'static SectionSpec, table: &DeTable<'_>) {
        for (k, v) in table.iter() {
            let name = k.get_ref().as_ref();
            if spec.keys.iter().any(|s| s.name == name) {
                continue;
            }
            let (help, explains) = unknown_key_help(spec, name, self.number_silent(v));
            self.explained.extend(explains);
            let shown = dronecine_diag::suggest::shorten(name);
            let message = if !spec.name.is_empty() {
                format!("unknown key `{shown}` in {}", spec.title())
            } else if v.get_ref().is_table() {
                format!("unknown section `[{shown}]`")
            } else {
                format!("unknown top-level key `{shown}`")
            };
            let label = if spec.name.is_empty() && v.get_ref().is_table() {
                "unknown section"
            } else {
                "unknown key"
            };
            self.diags.push(
                Diagnostic::error(ProfileCode::UnknownKey, sp(k.span()), message)
                    .with_label(label)
                    .with_help(help),
            );
        }
    }

    fn number_silent(&self, v: &Value<'_>) -> Option<f64> {
        match v.get_ref() {
            DeValue::Integer(i) => parse_float(i.as_str()).filter(|_| i.radix() == 10),
            DeValue::Float(f) => parse_float(f.as_str()),
            _ => None,
        }
        .filter(|x| x.is_finite())
    }

    /// Open a table-valued key of `parent` as a section (reporting its unknown keys).
    fn open<'a, 'i>(
        &mut self,
        parent: &mut Section<'a, 'i>,
        spec: &'static SectionSpec,
        key: &'static str,
    ) -> Section<'a, 'i> {
        let Some((_, v)) = parent.entry(key) else {
            if parent.table.is_some() {
                if parent.spec.name.is_empty() {
                    if !self.explained.contains(&spec.name) {
                        self.missing_sections.push(spec);
                    }
                } else {
                    parent.absent(key);
                }
            }
            return Section::dead(spec);
        };
        let span = sp(v.span());
        match v.get_ref() {
            DeValue::Table(t) => Section {
                spec,
                table: Some(t),
                span,
                missing: Vec::new(),
            },
            other => {
                let header = format!("[{}]", spec.name);
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        span,
                        format!("`{key}` must be a table, found {}", kind_of(other)),
                    )
                    .with_label("expected a table")
                    .with_help(format!(
                        "write the section as a header `{header}` followed by its keys, one per line"
                    )),
                );
                Section::dead(spec)
            }
        }
    }

    /// One diagnostic for the sections the file lacks, at the end of the file.
    fn report_missing_sections(&mut self) {
        let span = eof_span(self.src);
        let missing = std::mem::take(&mut self.missing_sections);
        match missing.as_slice() {
            [] => {}
            [spec] => {
                let mut keys: Vec<&str> = Vec::new();
                if spec.name == "camera" {
                    keys.push("fov_diagonal_deg (or fov_x_deg)");
                }
                keys.extend(spec.keys.iter().filter(|k| k.required).map(|k| k.name));
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::MissingKey,
                        span,
                        format!("the profile has no [{}] section", spec.name),
                    )
                    .with_label(format!("the file ends here without [{}]", spec.name))
                    .with_help(format!(
                        "add a `[{}]` section with the keys {}",
                        spec.name,
                        keys.join(", ")
                    )),
                );
            }
            several => {
                let names: Vec<String> = several.iter().map(|s| format!("[{}]", s.name)).collect();
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::MissingKey,
                        span,
                        format!("the profile lacks the sections {}", names.join(", ")),
                    )
                    .with_label("the file ends here")
                    .with_help(
                        "a profile has the sections [model], [limits], [camera], [safety] and [servo]; start from a copy of a built-in profile (dronecine's compiler/profile/profiles/ardrone2.toml)",
                    ),
                );
            }
        }
    }

    /// Report the unknown keys of every table first, so that a key found misspelt or in
    /// the wrong section is not reported missing as well.
    fn scan_unknown(&mut self, root: &DeTable<'_>) {
        self.unknown_keys(&ROOT, root);
        for spec in [&MODEL, &LIMITS, &CAMERA, &SAFETY, &SERVO] {
            let table = root
                .iter()
                .find(|(k, _)| k.get_ref().as_ref() == spec.name)
                .and_then(|(_, v)| v.get_ref().as_table());
            if let Some(t) = table {
                self.unknown_keys(spec, t);
                if spec.name == "camera" {
                    let gimbal = t
                        .iter()
                        .find(|(k, _)| k.get_ref().as_ref() == "gimbal")
                        .and_then(|(_, v)| v.get_ref().as_table());
                    if let Some(g) = gimbal {
                        self.unknown_keys(&GIMBAL, g);
                    }
                }
            }
        }
    }

    fn profile(&mut self, name: &str, root: &DeTable<'_>) -> Option<Profile> {
        self.scan_unknown(root);
        let mut top = Section {
            spec: &ROOT,
            table: Some(root),
            span: eof_span(self.src),
            missing: Vec::new(),
        };
        let description = match top.entry("description") {
            None => Some(String::new()),
            Some((_, v)) => match v.get_ref() {
                DeValue::String(s) => Some(s.to_string()),
                other => {
                    self.bad(
                        sp(v.span()),
                        format!("`description` must be text, found {}", kind_of(other)),
                        "expected text in double quotes".to_string(),
                        ROOT.spec("description"),
                    );
                    None
                }
            },
        };
        let model = self.model(&mut top);
        let limits = self.limits(&mut top, model.as_ref());
        let camera = self.camera(&mut top);
        let safety = self.safety(&mut top);
        let servo = self.servo(&mut top);
        self.report_missing_sections();
        Some(Profile {
            name: name.to_string(),
            description: description?,
            model: model?,
            limits: limits?,
            camera: camera?,
            safety: safety?,
            servo: servo?,
        })
    }

    fn model(&mut self, top: &mut Section<'_, '_>) -> Option<Model> {
        let mut s = self.open(top, &MODEL, "model");
        let m = (
            s.num(self, "gain_roll_mps_per_rad"),
            s.num(self, "gain_pitch_mps_per_rad"),
            s.num(self, "gain_vz"),
            s.num(self, "tau_roll_s"),
            s.num(self, "tau_pitch_s"),
            s.num(self, "tau_vz_s"),
            s.num(self, "gain_yaw"),
        );
        s.finish(self);
        Some(Model {
            gain_roll_mps_per_rad: m.0?,
            gain_pitch_mps_per_rad: m.1?,
            gain_vz: m.2?,
            tau_roll_s: m.3?,
            tau_pitch_s: m.4?,
            tau_vz_s: m.5?,
            gain_yaw: m.6?,
        })
    }

    fn limits(&mut self, top: &mut Section<'_, '_>, model: Option<&Model>) -> Option<Limits> {
        let mut s = self.open(top, &LIMITS, "limits");
        let tilt_deg = s.opt_num(self, "tilt_max_deg");
        if let Got::Ok(t, span) = tilt_deg {
            if t > SMALL_ANGLE_TILT_DEG {
                self.diags.push(
                    Diagnostic::warning(
                        ProfileCode::BadValue,
                        span,
                        format!(
                            "`tilt_max_deg` is {}°, beyond the {SMALL_ANGLE_TILT_DEG}° the linear model is good for",
                            show(t)
                        ),
                    )
                    .with_label(format!("above {SMALL_ANGLE_TILT_DEG}°"))
                    .with_help(
                        "the model takes the speed a tilt settles at as K·tilt, not K·sin(tilt); above 30° it is more than 5 % too fast, so the derived speed limit is optimistic: calibrate K at the tilts you fly",
                    ),
                );
            }
        }
        if let Got::Absent = tilt_deg {
            s.absent("tilt_max_deg");
        }
        let vz = s.num(self, "vz_max_mps");
        let yaw_deg = s.num(self, "yaw_rate_max_degps");
        let authority = match s.opt_num(self, "authority") {
            Got::Absent => Some(DEFAULT_AUTHORITY),
            got => got.ok(),
        };
        let speed = s.opt_num(self, "speed_max_mps");
        let accel = s.opt_num(self, "accel_max_mps2");
        let jerk = s.num(self, "jerk_max_mps3");
        s.finish(self);

        let tilt = tilt_deg.ok().map(f64::to_radians);
        let (model, tilt, authority) = (model?, tilt?, authority?);
        let (speed_bound, accel_bound) = derived_motion_limits(model, tilt, authority);
        let roll_limits = model.gain_roll_mps_per_rad <= model.gain_pitch_mps_per_rad;
        let speed = self.at_most_derived(
            speed,
            speed_bound,
            "speed_max_mps",
            " m/s",
            if roll_limits {
                format!(
                    "K·tilt_max·authority = {} × {} rad × {}",
                    show(model.gain_roll_mps_per_rad),
                    show(tilt),
                    show(authority)
                )
            } else {
                format!(
                    "K·tilt_max·authority = {} × {} rad × {}",
                    show(model.gain_pitch_mps_per_rad),
                    show(tilt),
                    show(authority)
                )
            },
        );
        let accel_axes = [
            (model.gain_roll_mps_per_rad, model.tau_roll_s),
            (model.gain_pitch_mps_per_rad, model.tau_pitch_s),
        ];
        let (k, tau) = if accel_axes[0].0 / accel_axes[0].1 <= accel_axes[1].0 / accel_axes[1].1 {
            accel_axes[0]
        } else {
            accel_axes[1]
        };
        let accel = self.at_most_derived(
            accel,
            accel_bound,
            "accel_max_mps2",
            " m/s²",
            format!(
                "K·tilt_max·(1 − authority)/τ = {} × {} rad × {} / {} s",
                show(k),
                show(tilt),
                show(1.0 - authority),
                show(tau)
            ),
        );
        Some(Limits {
            tilt_max_rad: tilt,
            vz_max_mps: vz?,
            yaw_rate_max_radps: yaw_deg?.to_radians(),
            speed_max_mps: speed?,
            accel_max_mps2: accel?,
            jerk_max_mps3: jerk?,
        })
    }

    /// An explicit limit if it stays below the derived one (within rounding), else the derived.
    fn at_most_derived(
        &mut self,
        got: Got<f64>,
        bound: f64,
        key: &str,
        unit: &str,
        formula: String,
    ) -> Option<f64> {
        match got {
            Got::Absent => Some(bound),
            Got::Bad => None,
            Got::Ok(x, _) if x <= bound * (1.0 + 1e-9) => Some(x),
            Got::Ok(x, span) => {
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        span,
                        format!(
                            "`{key}` is {}{unit}, above the {:.3}{unit} that follows from the model and tilt_max_deg",
                            show(x),
                            bound
                        ),
                    )
                    .with_label(format!("at most {:.3}{unit}", bound))
                    .with_help(format!(
                        "the bound is {formula} = {:.3}{unit}; a drone asked for more would run out of tilt. Lower `{key}` or delete it to use the bound (raising `tilt_max_deg` or `authority` raises it)",
                        bound
                    )),
                );
                None
            }
        }
    }

    fn camera(&mut self, top: &mut Section<'_, '_>) -> Option<Camera> {
        let mut s = self.open(top, &CAMERA, "camera");
        let fov_x = s.opt_num(self, "fov_x_deg");
        let fov_diag = s.opt_num(self, "fov_diagonal_deg");
        let aspect = self.aspect(&mut s);
        let gimbal = self.gimbal(&mut s);
        let mounted = self.mounted(&s);
        let fov = match (fov_x, fov_diag) {
            (Got::Ok(_, a), Got::Ok(_, b)) => {
                let (first, second, second_key) = if a.start < b.start {
                    (a, b, "fov_diagonal_deg")
                } else {
                    (b, a, "fov_x_deg")
                };
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        second,
                        format!("`{second_key}` gives the field of view a second time"),
                    )
                    .with_label("second field of view")
                    .with_related(first, "first given here")
                    .with_help(
                        "give either the horizontal (`fov_x_deg`) or the diagonal (`fov_diagonal_deg`) field of view, not both",
                    ),
                );
                None
            }
            (Got::Ok(x, _), Got::Absent) => Some((x, false)),
            (Got::Absent, Got::Ok(d, _)) => Some((d, true)),
            (Got::Absent, Got::Absent) => {
                if s.table.is_some() {
                    s.missing.push("fov_diagonal_deg");
                }
                None
            }
            _ => None,
        };
        s.finish(self);
        let aspect = aspect?;
        let (fov_deg, diagonal) = fov?;
        let half = math::tan(fov_deg.to_radians() / 2.0);
        let fov_x_rad = if diagonal {
            2.0 * math::atan(half * aspect / math::hypot(aspect, 1.0))
        } else {
            fov_deg.to_radians()
        };
        Some(Camera {
            mounted: mounted?,
            fov_x_rad,
            aspect,
            gimbal: gimbal?,
        })
    }

    /// `mounted`: `true` when absent.
    fn mounted(&mut self, s: &Section<'_, '_>) -> Option<bool> {
        let Some((_, v)) = s.entry("mounted") else {
            return Some(true);
        };
        match v.get_ref() {
            DeValue::Boolean(b) => Some(*b),
            other => {
                self.bad(
                    sp(v.span()),
                    format!("`mounted` must be true or false, found {}", kind_of(other)),
                    "expected true or false".into(),
                    CAMERA.spec("mounted"),
                );
                None
            }
        }
    }

    fn aspect(&mut self, s: &mut Section<'_, '_>) -> Option<f64> {
        let spec = CAMERA.spec("aspect");
        let range = Range::new(POSITIVE, Hi::Le(10.0));
        let Some((_, v)) = s.entry("aspect") else {
            s.absent("aspect");
            return None;
        };
        let span = sp(v.span());
        let x = match v.get_ref() {
            DeValue::String(text) => {
                let parts: Vec<Option<f64>> =
                    text.split(':').map(|p| parse_float(p.trim())).collect();
                match parts.as_slice() {
                    [Some(w), Some(h)]
                        if w.is_finite() && h.is_finite() && *w > 0.0 && *h > 0.0 =>
                    {
                        w / h
                    }
                    _ => {
                        self.diags.push(
                            Diagnostic::error(
                                ProfileCode::BadValue,
                                span,
                                format!(
                                    "`aspect` \"{}\" is not a width and a height",
                                    dronecine_diag::suggest::shorten(text)
                                ),
                            )
                            .with_label("expected \"W:H\" or a number")
                            .with_help(
                                "write the frame's width over its height as two positive numbers, `aspect = \"16:9\"`, or as one number, `aspect = 1.778`",
                            ),
                        );
                        return None;
                    }
                }
            }
            _ => self.number(spec, v, "")?,
        };
        if self.in_range(spec, x, span, range, "") {
            Some(x)
        } else {
            None
        }
    }

    fn gimbal(&mut self, s: &mut Section<'_, '_>) -> Option<Gimbal> {
        let Some((_, v)) = s.entry("gimbal") else {
            s.absent("gimbal");
            return None;
        };
        let span = sp(v.span());
        let shape_help = "write `gimbal = \"none\"` for a camera fixed to the body, or `gimbal = { pitch_min_deg = -90, pitch_max_deg = 30, rate_degps = 90 }` for a pitch gimbal, its range and its rate";
        match v.get_ref() {
            DeValue::String(text) if text.as_ref() == "none" => Some(Gimbal::None),
            DeValue::String(text) => {
                let mean = if text.eq_ignore_ascii_case("pitch") {
                    "a pitch gimbal needs its range and rate: ".to_string()
                } else if let Some(m) = did_you_mean(text, ["none"]) {
                    format!("{m} Otherwise, ")
                } else {
                    String::new()
                };
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        span,
                        format!(
                            "unknown gimbal \"{}\"",
                            dronecine_diag::suggest::shorten(text)
                        ),
                    )
                    .with_label("expected \"none\" or a pitch range")
                    .with_help(format!("{mean}{shape_help}")),
                );
                None
            }
            DeValue::Table(_) => {
                let mut g = self.open(s, &GIMBAL, "gimbal");
                let lo = g.opt_num(self, "pitch_min_deg");
                let hi = g.opt_num(self, "pitch_max_deg");
                for (got, k) in [(&lo, "pitch_min_deg"), (&hi, "pitch_max_deg")] {
                    if let Got::Absent = got {
                        g.absent(k);
                    }
                }
                let rate = g.num(self, "rate_degps");
                g.finish(self);
                match (lo, hi) {
                    (Got::Ok(lo, lo_span), Got::Ok(hi, hi_span)) => {
                        if lo < hi {
                            rate.map(|rate| Gimbal::Pitch {
                                min_rad: lo.to_radians(),
                                max_rad: hi.to_radians(),
                                rate_radps: rate.to_radians(),
                            })
                        } else {
                            self.diags.push(
                                Diagnostic::error(
                                    ProfileCode::BadValue,
                                    hi_span,
                                    format!(
                                        "the gimbal's `pitch_max_deg` ({}°) is not above its `pitch_min_deg` ({}°)",
                                        show(hi),
                                        show(lo)
                                    ),
                                )
                                .with_label("not above the minimum")
                                .with_related(lo_span, "the minimum")
                                .with_help(
                                    "the range runs from the lowest pitch (down negative) to the highest; a fixed camera is `gimbal = \"none\"`",
                                ),
                            );
                            None
                        }
                    }
                    _ => None,
                }
            }
            other => {
                self.diags.push(
                    Diagnostic::error(
                        ProfileCode::BadValue,
                        span,
                        format!("`gimbal` cannot be {}", kind_of(other)),
                    )
                    .with_label("expected \"none\" or a pitch range")
                    .with_help(shape_help),
                );
                None
            }
        }
    }

    fn safety(&mut self, top: &mut Section<'_, '_>) -> Option<Safety> {
        let mut s = self.open(top, &SAFETY, "safety");
        let actor = s.opt_num(self, "actor_distance_m");
        if let Got::Ok(d, span) = actor {
            if d == 0.0 {
                self.diags.push(
                    Diagnostic::warning(
                        ProfileCode::BadValue,
                        span,
                        "`actor_distance_m` is 0: nothing keeps the drone off the actors",
                    )
                    .with_label("no safety distance")
                    .with_help(
                        "give at least the drone's radius plus a margin (the AR.Drone 2.0 with its indoor hull: 0.5 m)",
                    ),
                );
            }
        }
        if let Got::Absent = actor {
            s.absent("actor_distance_m");
        }
        let margin = s.num(self, "stage_margin_m");
        let tracking = match s.opt_num(self, "tracking_margin_m") {
            Got::Absent => Some(DEFAULT_TRACKING_MARGIN_M),
            got => got.ok(),
        };
        s.finish(self);
        Some(Safety {
            actor_distance_m: actor.ok()?,
            stage_margin_m: margin?,
            tracking_margin_m: tracking?,
        })
    }

    fn servo(&mut self, top: &mut Section<'_, '_>) -> Option<Servo> {
        let mut s = self.open(top, &SERVO, "servo");
        let q = s.list::<6>(self, "q");
        let q = match q {
            Got::Ok(q, span) => {
                let mut ok = true;
                let items = s.entry("q").and_then(|(_, v)| v.get_ref().as_array());
                for i in 3..6 {
                    if q[i] <= 0.0 {
                        ok = false;
                        let at = items
                            .and_then(|a| a.get(i))
                            .map(|v| sp(v.span()))
                            .unwrap_or(span);
                        let axis = XYZ6[i];
                        self.diags.push(
                            Diagnostic::error(
                                ProfileCode::BadValue,
                                at,
                                format!("the position weight `q[{i}]` ({axis}) is 0; the three position weights must be positive"),
                            )
                            .with_label("must be > 0")
                            .with_help(format!(
                                "with no weight on the {axis} position the LQG regulator is not stabilising: nothing pulls the drone back to the reference along {axis}, and it drifts. Use a positive weight {}", example(SERVO.spec("q"))
                            )),
                        );
                    }
                }
                ok.then_some(q)
            }
            _ => None,
        };
        let r = s.list::<3>(self, "r").ok();
        let gamma = s.num(self, "heading_gamma");
        let tau = s.num(self, "heading_tau_s");
        let process = s.list::<6>(self, "process_noise").ok();
        let measurement = s.list::<3>(self, "measurement_noise_m2").ok();
        let hp = s.num(self, "heading_process_noise_rad2");
        let hm = s.num(self, "heading_measurement_noise_rad2");
        s.finish(self);
        Some(Servo {
            q: q?,
            r: r?,
            heading_gamma: gamma?,
            heading_tau_s: tau?,
            process_noise: process?,
            measurement_noise_m2: measurement?,
            heading_process_noise_rad2: hp?,
            heading_measurement_noise_rad2: hm?,
        })
    }
}

/// The help of an unknown key (a misplaced key, an angle in radians, a typo, or the list of
/// keys), and the known key it stands for when that is clear.
fn unknown_key_help(
    spec: &SectionSpec,
    name: &str,
    number: Option<f64>,
) -> (String, Option<&'static str>) {
    if let Some((home, k)) = ALL_SECTIONS.iter().find_map(|s| {
        let k = s.keys.iter().find(|k| k.name == name)?;
        (s.name != spec.name).then_some((s, k))
    }) {
        let help = if home.name.is_empty() {
            format!("`{name}` belongs at the top level, above the first [section] header")
        } else {
            format!(
                "`{name}` belongs in {}: move it under that header",
                home.title()
            )
        };
        return (help, Some(k.name));
    }
    for (rad, deg) in [("_radps", "_degps"), ("_rad", "_deg")] {
        if let Some(stem) = name.strip_suffix(rad) {
            let want = format!("{stem}{deg}");
            if let Some(k) = spec.keys.iter().find(|k| k.name == want) {
                let help = match number {
                    Some(x) => format!(
                        "angles are written in degrees here: `{want} = {}`",
                        show(x.to_degrees())
                    ),
                    None => format!("angles are written in degrees here: use `{want}`"),
                };
                return (help, Some(k.name));
            }
        }
    }
    let names: Vec<&'static str> = spec.keys.iter().map(|k| k.name).collect();
    let near = closest(name, names.iter().copied());
    if let Some(m) = did_you_mean(name, names.iter().copied()) {
        let explains = match near.as_slice() {
            [one] => names.iter().copied().find(|n| n == one),
            _ => None,
        };
        return (m, explains);
    }
    let elsewhere: Vec<&'static str> = ALL_SECTIONS
        .iter()
        .filter(|s| s.name != spec.name)
        .flat_map(|s| s.keys.iter().map(|k| k.name))
        .collect();
    let near = closest(name, elsewhere.iter().copied());
    if let [best] = near.as_slice() {
        if let Some(home) = ALL_SECTIONS
            .iter()
            .find(|s| s.keys.iter().any(|k| k.name == *best))
        {
            let explains = elsewhere.iter().copied().find(|n| n == best);
            return (
                format!("did you mean `{best}`? It belongs in {}", home.title()),
                explains,
            );
        }
    }
    (
        format!("the keys of {} are {}", spec.title(), or_list(&names)),
        None,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flight log's header holds its profile as JSON: one written before the tracking
    /// margin existed lacks it, and reads as no margin, which is how that flight flew.
    #[test]
    fn a_logged_profile_without_a_tracking_margin_reads_as_none() {
        let p = Profile::builtin("ardrone2").unwrap();
        let mut v = serde_json::to_value(&p).unwrap();
        let safety = v["safety"].as_object_mut().unwrap();
        assert!(safety.remove("tracking_margin_m").is_some());
        let back: Profile = serde_json::from_value(v).unwrap();
        assert_eq!(back.safety.tracking_margin_m, 0.0);
        assert_eq!(back.servo, p.servo);
    }

    /// Every example a help line gives as the AR.Drone 2.0's value is the built-in
    /// profile's value, so that the two cannot drift apart; keys the profile leaves out are
    /// given "for example".
    #[test]
    fn the_help_quotes_the_built_in_profile() {
        let builtin: toml::Table = toml::from_str(ARDRONE2_TOML).unwrap();
        let mut checked = 0;
        for spec in [&ROOT, &MODEL, &LIMITS, &CAMERA, &GIMBAL, &SAFETY, &SERVO] {
            let table = if spec.name.is_empty() {
                Some(&builtin)
            } else {
                builtin.get(spec.name).and_then(toml::Value::as_table)
            };
            for key in spec.keys {
                if matches!(key.kind, Kind::Special) || key.example.is_empty() {
                    continue;
                }
                let help = example(key);
                match table.and_then(|t| t.get(key.name)) {
                    Some(value) => {
                        let quoted: toml::Table =
                            toml::from_str(&format!("v = {}", key.example)).unwrap();
                        assert_eq!(&quoted["v"], value, "[{}] {}", spec.name, key.name);
                        assert!(help.starts_with("(the AR.Drone 2.0 has"), "{help}");
                        checked += 1;
                    }
                    None => assert!(help.starts_with("(for example"), "{help}"),
                }
            }
        }
        assert!(checked >= 20, "only {checked} keys compared");
    }

    fn ardrone2() -> Profile {
        Profile::builtin("ardrone2").expect("ardrone2 parses")
    }

    #[test]
    fn builtins_parse_without_diagnostics() {
        assert!(BUILTIN_NAMES.contains(&DEFAULT_NAME));
        for name in BUILTIN_NAMES {
            let src = builtin_source(name).expect("embedded");
            match Profile::from_toml(name, src) {
                Ok((p, warnings)) => {
                    assert!(warnings.is_empty(), "{name}: {warnings:?}");
                    assert_eq!(p.name, *name);
                    assert_eq!(Profile::builtin(name), Some(p));
                }
                Err(d) => panic!("{name}: {d:#?}"),
            }
        }
        assert!(Profile::builtin("ardrone3").is_none());
    }

    /// The built-in profiles' numbers: the firmware's limits, tum_ardrone's model priors and
    /// the lens.
    #[test]
    fn builtins_carry_the_documented_numbers() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * b.abs().max(1.0);
        for (name, tilt, vz, yaw) in [
            ("ardrone2", 0.21, 0.7, 1.75),
            ("ardrone2-outdoor", 0.35, 1.0, 3.49),
        ] {
            let p = Profile::builtin(name).unwrap();
            assert!(close(p.limits.tilt_max_rad, tilt), "{name}");
            assert!(close(p.limits.vz_max_mps, vz), "{name}");
            assert!(close(p.limits.yaw_rate_max_radps, yaw), "{name}");
            assert_eq!(p.model.gain_roll_mps_per_rad, 17.5);
            assert_eq!(p.model.gain_pitch_mps_per_rad, 17.5);
            assert_eq!(p.model.tau_roll_s, 1.7);
            assert_eq!(p.model.tau_vz_s, 1.25);
            assert!(close(p.limits.speed_max_mps, 17.5 * tilt * 0.5));
            assert!(close(p.limits.accel_max_mps2, 17.5 * tilt * 0.5 / 1.7));
            assert_eq!(p.camera.gimbal, Gimbal::None);
            assert!(close(p.camera.aspect, 16.0 / 9.0));
            // 92° across the diagonal of a 16:9 frame.
            let (tx, ty) = (
                (p.camera.fov_x_rad / 2.0).tan(),
                (p.camera.fov_x_rad / 2.0).tan() / p.camera.aspect,
            );
            assert!(close(tx.hypot(ty).atan().to_degrees() * 2.0, 92.0));
        }
    }

    #[test]
    fn the_tracking_margin_is_read_defaulted_and_checked() {
        assert_eq!(ardrone2().safety.tracking_margin_m, 0.10);
        let outdoor = Profile::builtin("ardrone2-outdoor").unwrap();
        assert_eq!(outdoor.safety.tracking_margin_m, 0.15);
        // Absent: the conservative default, without a word.
        let line = ARDRONE2_TOML
            .lines()
            .find(|l| l.starts_with("tracking_margin_m"))
            .unwrap();
        let (p, w) = Profile::from_toml("x", &ARDRONE2_TOML.replace(line, "")).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(p.safety.tracking_margin_m, DEFAULT_TRACKING_MARGIN_M);
        // Negative: refused, at the number.
        let src = ARDRONE2_TOML.replace(line, "tracking_margin_m = -0.1");
        let d = Profile::from_toml("x", &src).unwrap_err();
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(&src[d[0].span.start..d[0].span.end], "-0.1");
        assert!(
            d[0].message.contains("tracking_margin_m"),
            "{}",
            d[0].message
        );
    }

    #[test]
    fn derived_limits_take_the_weaker_axis() {
        let mut m = ardrone2().model;
        m.gain_pitch_mps_per_rad = 10.0;
        m.tau_roll_s = 4.0;
        let (v, a) = derived_motion_limits(&m, 0.2, 0.25);
        assert!((v - 10.0 * 0.2 * 0.25).abs() < 1e-12);
        // roll: 17.5·0.2·0.75/4 = 0.656; pitch: 10·0.2·0.75/1.7 = 0.882.
        assert!((a - 17.5 * 0.2 * 0.75 / 4.0).abs() < 1e-12);
    }

    #[test]
    fn explicit_limits_below_the_bound_are_kept() {
        let src = ARDRONE2_TOML.replace(
            "authority = 0.5",
            "authority = 0.5\nspeed_max_mps = 1.2\naccel_max_mps2 = 0.8",
        );
        let (p, w) = Profile::from_toml("x", &src).unwrap();
        assert!(w.is_empty());
        assert_eq!(p.limits.speed_max_mps, 1.2);
        assert_eq!(p.limits.accel_max_mps2, 0.8);
    }

    #[test]
    fn warnings_come_with_a_valid_profile() {
        let src = ARDRONE2_TOML
            .replace("tilt_max_deg = 12.03211", "tilt_max_deg = 35")
            .replace("actor_distance_m = 0.5", "actor_distance_m = 0");
        let (p, w) = Profile::from_toml("x", &src).expect("warnings only");
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w.iter().all(|d| !d.is_error()));
        assert_eq!(&src[w[0].span.start..w[0].span.end], "35");
        assert_eq!(&src[w[1].span.start..w[1].span.end], "0");
        assert!((p.limits.tilt_max_rad - 35f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn a_pitch_gimbal_and_a_horizontal_fov_are_read() {
        let src = ARDRONE2_TOML
            .replace("fov_diagonal_deg = 92.0", "fov_x_deg = 90")
            .replace("aspect = \"16:9\"", "aspect = 1.5")
            .replace(
                "gimbal = \"none\"",
                "gimbal = { pitch_min_deg = -90, pitch_max_deg = 30, rate_degps = 90 }",
            );
        let (p, _) = Profile::from_toml("x", &src).unwrap();
        assert!((p.camera.fov_x_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(p.camera.aspect, 1.5);
        assert_eq!(
            p.camera.gimbal,
            Gimbal::Pitch {
                min_rad: -std::f64::consts::FRAC_PI_2,
                max_rad: 30f64.to_radians(),
                rate_radps: std::f64::consts::FRAC_PI_2,
            }
        );
    }

    /// A gimbal's rate is required, positive and finite, and each mistake is told at its
    /// place: a missing rate at the gimbal's table, a bad one at its number, a misspelt key
    /// at the key.
    #[test]
    fn a_gimbal_needs_a_positive_rate() {
        let with = |gimbal: &str| ARDRONE2_TOML.replace("gimbal = \"none\"", gimbal);
        let src = with("gimbal = { pitch_min_deg = -90, pitch_max_deg = 30 }");
        let d = Profile::from_toml("x", &src).unwrap_err();
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].code, ProfileCode::MissingKey);
        assert!(d[0].message.contains("rate_degps"), "{}", d[0].message);
        assert!(src[d[0].span.start..d[0].span.end].starts_with("{ pitch_min_deg"));
        for bad in ["0", "-30", "2000", "nan", "\"fast\""] {
            let src = with(&format!(
                "gimbal = {{ pitch_min_deg = -90, pitch_max_deg = 30, rate_degps = {bad} }}"
            ));
            let d = Profile::from_toml("x", &src).unwrap_err();
            assert_eq!(d.len(), 1, "{bad}: {d:?}");
            assert_eq!(d[0].code, ProfileCode::BadValue, "{bad}");
            assert_eq!(&src[d[0].span.start..d[0].span.end], bad);
        }
        let src = with("gimbal = { pitch_min_deg = -90, pitch_max_deg = 30, rate_deg_s = 90 }");
        let d = Profile::from_toml("x", &src).unwrap_err();
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].code, ProfileCode::UnknownKey);
        assert_eq!(&src[d[0].span.start..d[0].span.end], "rate_deg_s");
        assert!(
            d[0].help.as_deref().unwrap_or("").contains("rate_degps"),
            "{d:?}"
        );
    }

    /// A flight log's profile with a pitch gimbal but no rate reads as an unlimited rate.
    #[test]
    fn a_logged_gimbal_without_a_rate_reads_as_unlimited() {
        let json = r#"{"kind":"pitch","min_rad":-1.0,"max_rad":0.5}"#;
        let g: Gimbal = serde_json::from_str(json).unwrap();
        assert_eq!(
            g,
            Gimbal::Pitch {
                min_rad: -1.0,
                max_rad: 0.5,
                rate_radps: f64::INFINITY
            }
        );
    }

    #[test]
    fn to_toml_round_trips() {
        let mut p = ardrone2();
        p.description = "a \"quoted\" drone".to_string();
        p.camera.gimbal = Gimbal::Pitch {
            min_rad: -1.2,
            max_rad: 0.4,
            rate_radps: 1.5,
        };
        p.limits.speed_max_mps = 1.1;
        let (q, w) = Profile::from_toml("ardrone2", &p.to_toml()).unwrap();
        assert!(w.is_empty());
        let text = format!("{q:?}");
        assert_eq!(q.description, p.description);
        // Degrees and back may move the last bit; nothing more.
        let a = serde_json::to_value(&p).unwrap();
        let b = serde_json::to_value(&q).unwrap();
        fn close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
            match (a, b) {
                (serde_json::Value::Number(x), serde_json::Value::Number(y)) => {
                    let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                    (x - y).abs() <= 1e-12 * x.abs().max(1.0)
                }
                (serde_json::Value::Array(x), serde_json::Value::Array(y)) => {
                    x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y))
                }
                (serde_json::Value::Object(x), serde_json::Value::Object(y)) => {
                    x.len() == y.len()
                        && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
                }
                _ => a == b,
            }
        }
        assert!(close(&a, &b), "{text}");
    }

    /// Deleting one line of a built-in profile: a required key's line gives exactly one
    /// `profile::missing_key`, at its section's header; an optional one leaves it valid.
    #[test]
    fn each_deleted_key_is_reported_missing_at_its_header() {
        let src = ARDRONE2_TOML;
        let mut header = "";
        let mut offset = 0;
        for line in src.split_inclusive('\n') {
            let start = offset;
            offset += line.len();
            let text = line.trim();
            if text.starts_with('[') {
                header = text;
                continue;
            }
            if text.starts_with('#') {
                continue;
            }
            let Some((key, _)) = text.split_once('=') else {
                continue;
            };
            let key = key.trim();
            let cut = format!("{}{}", &src[..start], &src[offset..]);
            let optional = [
                "description",
                "authority",
                "speed_max_mps",
                "accel_max_mps2",
                "tracking_margin_m",
            ];
            match Profile::from_toml("cut", &cut) {
                Ok(_) => assert!(optional.contains(&key), "{key} is required"),
                Err(d) => {
                    assert!(!optional.contains(&key), "{key}: {d:?}");
                    assert_eq!(d.len(), 1, "{key}: {d:#?}");
                    assert_eq!(d[0].code, ProfileCode::MissingKey);
                    assert_eq!(&cut[d[0].span.start..d[0].span.end], header, "{key}");
                    assert!(d[0].message.contains(key), "{key}: {}", d[0].message);
                }
            }
        }
    }

    /// A file of garbage: a bounded number of syntax diagnostics, each inside the text.
    #[test]
    fn garbage_gives_a_bounded_report() {
        let src: String = (0..5000u32)
            .map(|i| match i % 7 {
                0 => '[',
                1 => '=',
                2 => '\n',
                3 => '"',
                4 => 'é',
                5 => '{',
                _ => '1',
            })
            .collect();
        let d = Profile::from_toml("junk", &src).unwrap_err();
        assert!(
            !d.is_empty() && d.len() <= MAX_SYNTAX_DIAGNOSTICS,
            "{}",
            d.len()
        );
        assert!(d.iter().all(|d| d.code == ProfileCode::Syntax));
        assert!(d
            .iter()
            .all(|d| d.span.end <= src.len() && src.is_char_boundary(d.span.start)));
    }

    /// Every prefix of a valid profile (a file cut anywhere) is handled: no panic, every span
    /// inside the text on character boundaries, and an error unless the prefix is valid.
    #[test]
    fn truncated_files_never_panic() {
        let src = ARDRONE2_TOML;
        for end in (0..=src.len()).filter(|&i| src.is_char_boundary(i)) {
            let cut = &src[..end];
            let diags = match Profile::from_toml("cut", cut) {
                Ok((_, w)) => w,
                Err(d) => {
                    assert!(d.iter().any(Diagnostic::is_error), "at {end}");
                    d
                }
            };
            for d in &diags {
                assert!(
                    d.span.start <= d.span.end && d.span.end <= cut.len(),
                    "at {end}"
                );
                assert!(cut.is_char_boundary(d.span.start) && cut.is_char_boundary(d.span.end));
                assert!(d.help.is_some(), "at {end}: {d:?}");
            }
        }
    }
}
