//! The numbers of dronecine that must come out the same on every machine: the transcendental
//! functions, and the one angle wrap.
//!
//! `+ − × ÷` and `sqrt` are correctly rounded by IEEE 754 everywhere, and Rust never fuses
//! them, but `f64::sin`, `atan2`, `exp`… come from the platform's libm, and libms disagree in
//! the last bit (glibc even picks a variant at run time). A last bit is enough for two runs
//! to part ways: a seeded simulated flight feeds each tick's numbers into the next, and
//! `dronecine replay` requires every command to come out bit for bit as logged.
//!
//! So every crate calls these instead of the `f64` methods: the pure-Rust `libm` crate, a
//! port of musl's, which is ordinary Rust arithmetic and hence the same result on every
//! target. The workspace's architecture test scans every crate's sources for a platform call
//! ([`platform_calls`]); the servo's tests pin a closed-loop flight's commands to a checksum.
//!
//! To add a function: wrap the `libm` crate's here, and add the `f64` method's call to
//! [`PLATFORM`].

/// `sin x`.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// `cos x`.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// `tan x`.
#[inline]
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}

/// `asin x`, in [−π/2, π/2].
#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}

/// `acos x`, in [0, π].
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

/// `atan x`, in (−π/2, π/2).
#[inline]
pub fn atan(x: f64) -> f64 {
    libm::atan(x)
}

/// The angle of `(x, y)` from the x axis, in (−π, π] (`y.atan2(x)`).
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// `eˣ`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `eˣ − 1`, accurate near 0.
#[inline]
pub fn exp_m1(x: f64) -> f64 {
    libm::expm1(x)
}

/// The natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// The decimal logarithm.
#[inline]
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// `xʸ`.
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// `√(x² + y²)` without undue overflow (`x.hypot(y)`).
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// √(x² + y²) without libm's `hypot` (which guards against overflow at a cost the per-tick
/// code pays twenty times a sample): stage-sized lengths and speeds never come near it.
#[inline]
pub fn norm_xy(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// An angle wrapped to (−π, π]: **the one angle wrap** of dronecine, for headings, facings,
/// their differences and the filters' innovations. An angle already in (−π, π] comes back
/// bit for bit (and without the cost of `fmod`).
pub fn wrap_angle_rad(a: f64) -> f64 {
    use std::f64::consts::PI;
    if a > -PI && a <= PI {
        return a;
    }
    let w = a.rem_euclid(2.0 * PI); // [0, 2π)
    if w > PI {
        w - 2.0 * PI
    } else {
        w
    }
}

/// The calls that reach the platform's libm: `f64` methods (`powi` does not: it
/// multiplies), then nalgebra's that call them inside (the compiler's `camera::angle` stands in for
/// `angle`).
pub const PLATFORM: [&str; 31] = [
    ".sin(",
    ".cos(",
    ".sin_cos(",
    ".tan(",
    ".asin(",
    ".acos(",
    ".atan(",
    ".atan2(",
    ".sinh(",
    ".cosh(",
    ".tanh(",
    ".asinh(",
    ".acosh(",
    ".atanh(",
    ".exp(",
    ".exp2(",
    ".exp_m1(",
    ".ln(",
    ".log(",
    ".log2(",
    ".log10(",
    ".ln_1p(",
    ".powf(",
    ".hypot(",
    ".cbrt(",
    ".angle(",
    "from_axis_angle(",
    "from_scaled_axis(",
    "from_euler_angles(",
    ".euler_angles(",
    ".slerp(",
];

/// The calls to the platform's functions ([`PLATFORM`]) in Rust source `text`, up to its
/// `#[cfg(test)] mod tests` (tests may compare against the platform): `(line, call)`, lines
/// counted from 1. Comments are skipped. The crates' tests run it over their sources.
pub fn platform_calls(text: &str) -> Vec<(usize, &'static str)> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or(text);
    let mut found = Vec::new();
    for (n, line) in code.lines().enumerate() {
        let line = line.split("//").next().unwrap_or(line);
        found.extend(
            PLATFORM
                .iter()
                .filter(|c| line.contains(*c))
                .map(|&c| (n + 1, c)),
        );
    }
    found
}

/// [`platform_calls`] over every `.rs` file under `dir`: how many
/// files were read, and each call (or unreadable file) as `path:line: call`. The crates'
/// tests assert there are none.
#[doc(hidden)]
pub fn platform_calls_under(dir: &std::path::Path) -> (usize, Vec<String>) {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut found = Vec::new();
    for f in &files {
        match std::fs::read_to_string(f) {
            Ok(text) => {
                for (line, call) in platform_calls(&text) {
                    found.push(format!("{}:{line}: `{call}`", f.display()));
                }
            }
            Err(e) => found.push(format!("{}: unreadable: {e}", f.display())),
        }
    }
    (files.len(), found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    fn ulps(a: f64, b: f64) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    /// Within an ulp of the platform's: both are within an ulp of the exact value.
    #[test]
    fn agrees_with_the_platform_to_the_last_bits() {
        for k in -400..=400 {
            let x = k as f64 * 0.0079;
            let (s, c) = sin_cos(x);
            assert!(
                ulps(s, x.sin()) <= 1 && ulps(c, x.cos()) <= 1,
                "sin_cos {x}"
            );
            assert!(
                ulps(sin(x), x.sin()) <= 1 && ulps(cos(x), x.cos()) <= 1,
                "{x}"
            );
            assert_eq!((sin(x), cos(x)), (s, c), "sin and cos are sin_cos's");
            assert!(ulps(tan(x * 0.49), (x * 0.49).tan()) <= 1, "tan {x}");
            assert!(ulps(atan(x), x.atan()) <= 1, "atan {x}");
            assert!(ulps(atan2(x, 1.3 - x), x.atan2(1.3 - x)) <= 1, "atan2 {x}");
            assert!(ulps(exp(x), x.exp()) <= 1, "exp {x}");
            assert!(ulps(exp_m1(x), x.exp_m1()) <= 1, "exp_m1 {x}");
            assert!(ulps(powf(0.9, x), 0.9f64.powf(x)) <= 1, "powf {x}");
            assert!(ulps(hypot(x, 0.7), x.hypot(0.7)) <= 1, "hypot {x}");
            let u = x / 3.2;
            assert!(
                ulps(asin(u), u.asin()) <= 1 && ulps(acos(u), u.acos()) <= 1,
                "{u}"
            );
            let y = (x + 3.2) * 7.0 + 1e-3;
            assert!(
                ulps(ln(y), y.ln()) <= 1 && ulps(log10(y), y.log10()) <= 1,
                "{y}"
            );
        }
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert_eq!(exp_m1(0.0), 0.0);
        assert_eq!(atan2(0.0, -1.0), std::f64::consts::PI);
    }

    #[test]
    fn the_scan_finds_platform_calls_outside_tests_and_comments() {
        let text = "let a = x.sin();\n// y.exp()\nlet b = math::atan2(y, x).abs();\n\
                    let c = (a + b).hypot(c); // z.ln()\nlet d = u.angle(&v);\n\
                    #[cfg(test)]\nmod tests {\n x.cos();\n}\n";
        assert_eq!(
            platform_calls(text),
            vec![(1, ".sin("), (4, ".hypot("), (5, ".angle(")]
        );
    }

    #[test]
    fn wrap_takes_the_short_way() {
        let e = wrap_angle_rad(-170f64.to_radians() - 170f64.to_radians());
        assert!((e - 20f64.to_radians()).abs() < 1e-12);
        assert_eq!(wrap_angle_rad(-PI), PI);
        assert_eq!(wrap_angle_rad(PI), PI);
        assert_eq!(wrap_angle_rad(3.0 * PI), PI);
        for k in -50..=50 {
            let a = f64::from(k) * 0.37;
            let w = wrap_angle_rad(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(
                ((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-9,
                "{a} -> {w}"
            );
        }
    }
}
