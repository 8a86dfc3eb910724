//! Streaming writers for the compiled reference: an MCAP file that opens and plays in
//! Foxglove ([`McapWriter`]) and a plain CSV table ([`CsvWriter`]).
//!
//! Both writers take samples one at a time and keep nothing per sample beyond the MCAP chunk
//! buffer (about 1 MiB) and a decimated copy of the path (10 Hz by default) for the 3D
//! view's line strip, so a one-hour reference costs a few megabytes of memory at most.
//!
//! Both write to a temporary file next to the destination (`.NAME.PID.tmp`) and rename it to
//! the destination on `finish()`: a crash never leaves a file under the destination's name
//! that looks complete, and dropping a writer without `finish()` removes the temporary file.
//! The rename is not preceded by an `fsync` (the compile stays fast); a power cut right after
//! `finish()` may lose the file, never leave a truncated one that claims to be whole (an MCAP
//! file without its summary and closing magic is recognisably incomplete).
//!
//! The MCAP's per-sample topics (`/reference`, `/actors`) are CDR ([`cdr`]), every number
//! exact; `/camera` (JSON) is quantised to 1e-6 ([`json::micro`]); Foxglove's visual topics
//! to the millimetre (orientations to 1e-6); the CSV keeps every number exact (shortest
//! round-trip).
//!
//! Errors are `std::io::Error`s whose message names the destination path, so that the CLI
//! can show them as they are. Non-finite numbers are written as `null` in JSON (valid JSON;
//! the runtime's flight logs may contain them) and as `NaN`/`inf` in CSV.

pub mod cdr;
mod csv;
pub mod foxglove;
pub mod mcap;

use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use dronecine_grammar::script::Stage;

use dronecine_compiler::camera::Lens;

pub use self::csv::{CsvWriter, CSV_COLUMNS};
pub use self::mcap::{Compression, McapOptions, McapWriter};

/// What the MCAP file records about the run besides the samples.
#[derive(Clone, Copy, Debug)]
pub struct RunInfo<'a> {
    /// The script's file name (no directory): the attachment's name.
    pub script_name: &'a str,
    /// The script's text, attached verbatim; its sha256 goes in the metadata record.
    pub script_text: &'a str,
    /// The drone profile the reference was compiled for.
    pub profile_name: &'a str,
    /// Sample rate of the reference.
    pub rate_hz: f64,
    pub lens: Lens,
    pub stage: Stage,
    /// The actors, in the order of the `actors` slice given to every `write`.
    pub actor_names: &'a [String],
}

/// A temporary file next to its destination, renamed onto the destination by [`commit`]
/// and removed when dropped uncommitted.
///
/// [`commit`]: AtomicFile::commit
#[derive(Debug)]
pub(crate) struct AtomicFile {
    dest: PathBuf,
    temp: PathBuf,
    committed: bool,
}

impl AtomicFile {
    /// Creates (truncating) the temporary file for `dest`.
    pub(crate) fn create(dest: &Path) -> io::Result<(Self, File)> {
        let name = dest.file_name().ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("cannot write {}: not a file name", dest.display()),
            )
        })?;
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}.tmp", std::process::id()));
        let temp = dest.with_file_name(temp_name);
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&temp)
            .map_err(|e| annotate(dest, e))?;
        Ok((
            Self {
                dest: dest.to_path_buf(),
                temp,
                committed: false,
            },
            file,
        ))
    }

    pub(crate) fn dest(&self) -> &Path {
        &self.dest
    }

    /// Renames the temporary file onto the destination. The caller has flushed and closed
    /// its handle.
    pub(crate) fn commit(&mut self) -> io::Result<()> {
        std::fs::rename(&self.temp, &self.dest).map_err(|e| annotate(&self.dest, e))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// The same error, its message prefixed with the destination path.
pub(crate) fn annotate(dest: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("cannot write {}: {e}", dest.display()))
}

/// Nanoseconds from seconds: rounded, negative and non-finite times clamp to 0.
pub fn ns_from_s(t_s: f64) -> u64 {
    if t_s.is_finite() && t_s > 0.0 {
        let ns = t_s * 1e9;
        if ns < 9.0e15 {
            round_half_away(ns) as u64
        } else {
            // `as` saturates at u64::MAX.
            ns.round() as u64
        }
    } else {
        0
    }
}

/// `y.round() as i64` for |y| < 2^53, without the call to libm's `round` that baseline x86-64
/// (no SSE4.1) makes of it: the truncation and the fraction it leaves are both exact.
#[inline]
pub(crate) fn round_half_away(y: f64) -> i64 {
    let t = y as i64;
    let r = y - t as f64;
    t + (r >= 0.5) as i64 - (r <= -0.5) as i64
}

/// Hand-written JSON: appends to a byte buffer without intermediate allocations.
pub mod json {
    /// A number in its shortest round-trip form (`null` if not finite).
    #[inline]
    pub fn f64(out: &mut Vec<u8>, x: f64) {
        if x.is_finite() {
            let mut b = zmij::Buffer::new();
            out.extend_from_slice(b.format_finite(x).as_bytes());
        } else {
            out.extend_from_slice(b"null");
        }
    }

    /// Writes the sign of `n` (when negative) and the integer part of `|n| / scale` (at most
    /// `max_digits` digits) from the start of `buf`; returns the length written and the
    /// remainder `|n| % scale`, the decimals still to write (for [`micro`]).
    #[inline(always)]
    fn sign_and_integer(buf: &mut [u8; 32], n: i64, scale: u64, max_digits: usize) -> (usize, u64) {
        let mut len = 0;
        if n < 0 {
            buf[0] = b'-';
            len = 1;
        }
        let n = n.unsigned_abs();
        let (mut int, frac) = (n / scale, n % scale);
        let mut digits = 1;
        let mut p = 10;
        while digits < max_digits && int >= p {
            digits += 1;
            p *= 10;
        }
        for i in (len..len + digits).rev() {
            buf[i] = b'0' + (int % 10) as u8;
            int /= 10;
        }
        (len + digits, frac)
    }

    /// Two-digit pairs `00`…`99`.
    const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
        2021222324252627282930313233343536373839\
        4041424344454647484950515253545556575859\
        6061626364656667686970717273747576777879\
        8081828384858687888990919293949596979899";

    /// A number quantised to 1e-6 (six decimals, rounded half away from zero): integer
    /// arithmetic, trailing zeros trimmed (`12.34`, `-0.000001`, `3`; never `-0`), `null` if
    /// not finite. Magnitudes beyond 9·10⁹ (no longer exact at this resolution) are written
    /// in their shortest round-trip form.
    ///
    /// The text is built in a stack buffer and appended with one fixed-size copy, then cut to
    /// length, so that no call (`round`, `memcpy` of a variable length) is left in it.
    #[inline]
    pub fn micro(out: &mut Vec<u8>, x: f64) {
        let scaled = x * 1e6;
        // Also false for NaN.
        if !(scaled.abs() < 9.0e15) {
            f64(out, x);
            return;
        }
        // Sign, up to 10 integer digits, the point and 6 decimals.
        let mut buf = [0u8; 32];
        let (mut len, frac) =
            sign_and_integer(&mut buf, super::round_half_away(scaled), 1_000_000, 10);
        let frac = frac as usize;
        if frac != 0 {
            let (hi, rest) = (frac / 10_000, frac % 10_000);
            let (mid, lo) = (rest / 100, rest % 100);
            buf[len] = b'.';
            buf[len + 1] = PAIRS[2 * hi];
            buf[len + 2] = PAIRS[2 * hi + 1];
            buf[len + 3] = PAIRS[2 * mid];
            buf[len + 4] = PAIRS[2 * mid + 1];
            buf[len + 5] = PAIRS[2 * lo];
            buf[len + 6] = PAIRS[2 * lo + 1];
            len += 7;
            while buf[len - 1] == b'0' {
                len -= 1;
            }
        }
        let start = out.len();
        out.extend_from_slice(&buf);
        out.truncate(start + len);
    }

    #[inline]
    pub fn u64(out: &mut Vec<u8>, x: u64) {
        let mut b = itoa::Buffer::new();
        out.extend_from_slice(b.format(x).as_bytes());
    }

    /// A JSON string literal (quotes included), escaped.
    pub fn string(out: &mut Vec<u8>, s: &str) {
        // serde_json cannot fail writing a str into a Vec.
        let _ = serde_json::to_writer(&mut *out, s);
    }
}

#[cfg(test)]
mod tests {
    use super::json;

    #[test]
    fn round_half_away_is_f64_round() {
        let mut x = 0.3f64;
        let mut cases = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.49999999999999994,
            4503599627370495.5,
        ];
        for _ in 0..200_000 {
            // A spread of magnitudes and fractions, halves included.
            x = (x * 1.618_033_988_749_895).fract() * 1e6;
            cases.extend([x, -x, x.trunc() + 0.5, -(x.trunc() + 0.5), x * 1e8]);
        }
        for y in cases {
            assert_eq!(super::round_half_away(y), y.round() as i64, "{y}");
        }
        assert_eq!(super::ns_from_s(1.0000000005), 1_000_000_001);
    }

    #[test]
    fn micro_numbers_are_the_value_rounded_to_six_decimals() {
        let text = |x: f64| {
            let mut out = Vec::new();
            json::micro(&mut out, x);
            String::from_utf8(out).unwrap()
        };
        let cases = [
            (0.0, "0"),
            (-0.0, "0"),
            (-4e-7, "0"),
            (5e-7, "0.000001"),
            (-6e-7, "-0.000001"),
            (3599.99, "3599.99"),
            (1.8, "1.8"),
            (-12.3456789, "-12.345679"),
            (0.1000004, "0.1"),
            (2.0000005, "2.000001"),
            (1e9 + 0.25, "1000000000.25"),
            (1e12, "1000000000000.0"),
            (f64::NAN, "null"),
            (f64::NEG_INFINITY, "null"),
        ];
        for (x, expected) in cases {
            assert_eq!(text(x), expected, "{x}");
        }
        // Within half a unit of the value, at most six decimals, no trailing zero.
        for i in -20_000..20_000 {
            let x = i as f64 * 0.012345678901 + 1e-9 * i as f64;
            let t = text(x);
            let back: f64 = t.parse().unwrap();
            assert!((back - x).abs() <= 0.5e-6 + 1e-12, "{x} → {t}");
            assert!(t
                .split('.')
                .nth(1)
                .is_none_or(|d| d.len() <= 6 && !d.ends_with('0')));
        }
        // Every time of a 100 Hz reference is exact.
        for k in 0..400_000u64 {
            let t = k as f64 / 100.0;
            assert_eq!(text(t).parse::<f64>().unwrap(), t);
        }
    }
}
