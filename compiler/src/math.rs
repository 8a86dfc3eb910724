//! The transcendental functions of dronecine, the same bits on every machine.
//!
//! `+ − × ÷` and `sqrt` are correctly rounded by IEEE 754 everywhere, and Rust never fuses
//! them, but `f64::sin`, `atan2`, `exp`… come from the platform's libm, and libms disagree in
//! the last bit: glibc picks an FMA or an SSE2 variant at run time, macOS and Windows ship
//! their own. Measured on 4,096 angles in (−π, π): glibc's `sin_cos` differs from this
//! module's in the last bit on 187. A last bit is enough to make two runs part ways: a
//! seeded simulated flight feeds each tick's numbers into the next for an hour, and
//! `dronecine replay` requires every command to come out bit for bit as logged.
//!
//! So the compiler (framings, toric and sphere placements, steering, previews), the
//! simulator and the controllers call these instead: the pure-Rust `libm` crate, a port of
//! musl's, which is ordinary Rust arithmetic and hence the same result on every target. A
//! compiled path, a seeded flight, a calibration fit and a replayed log are then the same
//! numbers on any machine. Each crate has a test that its sources call no platform function
//! outside tests ([`platform_calls`]); `runtime/tests/servo.rs` pins a flight's commands to
//! a checksum.
//!
//! Speed, against glibc 2.36 on the development machine (ns per call, independent calls /
//! each call waiting for the last): `sin` 4.0 / 11.2 against 4.3 / 14.0, `sin_cos` 5.6 / 16.2
//! against 6.5 / 17.2, `atan2` 7.8 / 27.7 against 11.0 / 28.3, `acos` 3.8 / 20.0 against 5.2 /
//! 18.4; `exp` 4.5 / 24.9 against 4.0 / 12.0 and `ln` 5.5 / 23.9 against 3.6 / 14.9 are
//! slower, and rare in a tick. The hour's simulated flight (`runtime/benches/flight.rs`,
//! without its log) took 0.417 s with the platform's functions and 0.405 s with these.
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

/// The angle between `a` and `b`, in [0, π] (nalgebra's `a.angle(&b)`, whose `acos` is the
/// platform's): 0 when either is zero.
#[inline]
pub fn angle(a: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>) -> f64 {
    let (na, nb) = (a.norm(), b.norm());
    if na == 0.0 || nb == 0.0 {
        return 0.0;
    }
    let c = a.dot(b) / (na * nb);
    if c > 1.0 {
        0.0
    } else if c < -1.0 {
        std::f64::consts::PI
    } else {
        acos(c)
    }
}

/// The calls that reach the platform's libm: `f64` methods (`powi` does not: it
/// multiplies), then nalgebra's that call them inside (`angle` has [`angle`]).
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

/// [`platform_calls`] over every `.rs` file under `dir` but the `math.rs` modules: how many
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
            } else if p.extension().is_some_and(|x| x == "rs") && !p.ends_with("math.rs") {
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

    /// nalgebra's `angle`, with the portable `acos`: within an ulp, the same edge cases.
    #[test]
    fn angle_is_nalgebras() {
        use nalgebra::Vector3;
        for k in 0..500 {
            let t = k as f64 * 0.0127;
            let a = Vector3::new(cos(t), 0.3 * t - 1.0, 0.7);
            let b = Vector3::new(-0.4, t.sin(), 1.0 - t);
            assert!(ulps(angle(&a, &b), a.angle(&b)) <= 1, "{t}");
        }
        let (x, z) = (Vector3::x(), Vector3::zeros());
        assert_eq!(angle(&x, &z), 0.0);
        assert_eq!(angle(&x, &x), 0.0);
        assert_eq!(angle(&x, &-x), std::f64::consts::PI);
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

    /// The compiler calls none of the platform's transcendental functions: only this
    /// module's.
    #[test]
    fn the_compiler_calls_no_platform_math() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let (files, found) = platform_calls_under(&dir);
        assert!(files > 20, "only {files} sources under {}", dir.display());
        assert!(
            found.is_empty(),
            "the platform's functions; use dronecine_compiler::math instead:\n{}",
            found.join("\n")
        );
    }
}
