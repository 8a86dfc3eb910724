//! CDR, the encoding of ROS 2 messages (OMG XCDR1, little-endian), which Foxglove decodes
//! with a `ros2msg` schema: the writer ([`Cdr`]) and reader ([`CdrReader`]) the MCAP topics
//! written in it share, and the `ros2msg` schemas of Foxglove's messages written so.
//!
//! A message is a 4-byte encapsulation header (`00 01 00 00`: plain CDR, little-endian),
//! then its fields in order, each aligned to its own size (at most 8) counted from the end
//! of the header. A `string` is a `uint32` length that counts its NUL, the bytes, the NUL; a
//! sequence (`T[]`) a `uint32` count, then the elements; a nested message is its fields, in
//! place. `bool` is one byte, 0 or 1.

/// The encapsulation header: plain CDR, little-endian.
pub const HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// The MCAP message encoding of CDR channels.
pub const MESSAGE_ENCODING: &str = "cdr";
/// The MCAP schema encoding of their schemas.
pub const SCHEMA_ENCODING: &str = "ros2msg";

/// The line that separates a `ros2msg` definition from the definitions it uses (each of
/// which starts with `MSG: package/Type`), as ROS 2's recorders write them.
pub const SEPARATOR: &str =
    "================================================================================";

/// `builtin_interfaces/Time`, for schemas that use it.
pub const TIME_DEFINITION: &str = "\
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
";

/// Appends a CDR message to a buffer: [`Cdr::new`] writes the header, each call one field.
pub struct Cdr<'a> {
    buf: &'a mut Vec<u8>,
    /// Where the message's body starts in `buf` (alignment counts from there).
    origin: usize,
}

impl<'a> Cdr<'a> {
    /// Starts a message at the end of `buf`.
    pub fn new(buf: &'a mut Vec<u8>) -> Self {
        buf.extend_from_slice(&HEADER);
        let origin = buf.len();
        Self { buf, origin }
    }

    fn align(&mut self, size: usize) {
        let pad = (size - (self.buf.len() - self.origin) % size) % size;
        self.buf.resize(self.buf.len() + pad, 0);
    }

    pub fn u8(&mut self, x: u8) -> &mut Self {
        self.buf.push(x);
        self
    }

    pub fn bool(&mut self, x: bool) -> &mut Self {
        self.u8(u8::from(x))
    }

    /// A primitive's little-endian bytes, aligned to its size.
    fn put<const N: usize>(&mut self, bytes: [u8; N]) -> &mut Self {
        self.align(N);
        self.buf.extend_from_slice(&bytes);
        self
    }

    pub fn u32(&mut self, x: u32) -> &mut Self {
        self.put(x.to_le_bytes())
    }

    pub fn i32(&mut self, x: i32) -> &mut Self {
        self.put(x.to_le_bytes())
    }

    pub fn u64(&mut self, x: u64) -> &mut Self {
        self.put(x.to_le_bytes())
    }

    pub fn f64(&mut self, x: f64) -> &mut Self {
        self.put(x.to_le_bytes())
    }

    /// Consecutive `float64`s (a fixed array, or fields in a row).
    pub fn f64s(&mut self, xs: &[f64]) -> &mut Self {
        self.align(8);
        for x in xs {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
        self
    }

    /// A sequence's count (its elements follow).
    pub fn count(&mut self, n: usize) -> &mut Self {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX))
    }

    pub fn string(&mut self, s: &str) -> &mut Self {
        self.count(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        self
    }

    /// Strings encoded once ([`Strings`]), appended again.
    pub fn strings(&mut self, pre: &Strings) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&pre.0);
        self
    }

    /// `builtin_interfaces/Time` of a time in nanoseconds.
    pub fn time(&mut self, ns: u64) -> &mut Self {
        let sec = i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX);
        self.i32(sec).u32((ns % 1_000_000_000) as u32)
    }
}

/// Consecutive `string` fields encoded once, for messages that repeat them ([`Cdr::strings`]).
/// A string is 4-aligned (its length) and then bytes, so a run of strings encoded from a
/// 4-aligned start has the same bytes, padding included, at any 4-aligned position.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Strings(Vec<u8>);

impl Strings {
    pub fn new(strings: &[&str]) -> Strings {
        let mut buf = Vec::new();
        let mut m = Cdr::new(&mut buf);
        for s in strings {
            m.string(s);
        }
        buf.drain(..HEADER.len());
        Strings(buf)
    }
}

/// Reads a CDR message field by field; every read checks the bounds, and a damaged message
/// is an error that says which field and where, never a panic.
pub struct CdrReader<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> CdrReader<'a> {
    /// A reader after the header, which must be plain little-endian CDR.
    pub fn new(data: &'a [u8]) -> Result<Self, String> {
        match data.get(..4) {
            Some(h) if h == HEADER => Ok(Self {
                data: &data[4..],
                at: 0,
            }),
            Some(h) => Err(format!(
                "not a little-endian CDR message (header {h:02x?}, expected {HEADER:02x?})"
            )),
            None => Err(format!(
                "a CDR message of {} bytes has no header",
                data.len()
            )),
        }
    }

    fn take(&mut self, size: usize, align: usize, what: &str) -> Result<&'a [u8], String> {
        let start = self.at.div_ceil(align) * align;
        let end = start + size;
        let bytes = self.data.get(start..end).ok_or_else(|| {
            format!(
                "the message ends at byte {} before `{what}` (bytes {start}..{end} after the header)",
                self.data.len()
            )
        })?;
        self.at = end;
        Ok(bytes)
    }

    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, 1, what)?[0])
    }

    pub fn bool(&mut self, what: &str) -> Result<bool, String> {
        match self.u8(what)? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(format!("`{what}` is {b}, not a bool (0 or 1)")),
        }
    }

    /// A primitive's bytes, aligned to its size.
    fn get<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let mut bytes = [0u8; N];
        bytes.copy_from_slice(self.take(N, N, what)?);
        Ok(bytes)
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.get(what).map(u32::from_le_bytes)
    }

    pub fn i32(&mut self, what: &str) -> Result<i32, String> {
        self.get(what).map(i32::from_le_bytes)
    }

    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.get(what).map(u64::from_le_bytes)
    }

    pub fn f64(&mut self, what: &str) -> Result<f64, String> {
        self.get(what).map(f64::from_le_bytes)
    }

    pub fn f64s<const N: usize>(&mut self, what: &str) -> Result<[f64; N], String> {
        let mut out = [0.0; N];
        for x in &mut out {
            *x = self.f64(what)?;
        }
        Ok(out)
    }

    /// A sequence's count, checked against the bytes left (each element at least
    /// `min_element_len` bytes), so that a damaged count cannot ask for a huge allocation.
    pub fn count(&mut self, what: &str, min_element_len: usize) -> Result<usize, String> {
        let n = self.u32(what)? as usize;
        let left = self.data.len() - self.at;
        if n.saturating_mul(min_element_len.max(1)) > left {
            return Err(format!(
                "`{what}` counts {n} elements but only {left} bytes are left"
            ));
        }
        Ok(n)
    }

    pub fn string(&mut self, what: &str) -> Result<&'a str, String> {
        let n = self.count(what, 1)?;
        if n == 0 {
            return Err(format!(
                "`{what}` has length 0 (a CDR string counts its NUL)"
            ));
        }
        let bytes = self.take(n, 1, what)?;
        let (text, nul) = bytes.split_at(n - 1);
        if nul != [0] {
            return Err(format!("`{what}` does not end with a NUL"));
        }
        std::str::from_utf8(text).map_err(|e| format!("`{what}` is not UTF-8: {e}"))
    }

    /// `builtin_interfaces/Time`, in nanoseconds.
    pub fn time(&mut self, what: &str) -> Result<u64, String> {
        let sec = self.i32(what)?;
        let nsec = self.u32(what)?;
        if sec < 0 || nsec >= 1_000_000_000 {
            return Err(format!("`{what}` is not a time: {sec} s {nsec} ns"));
        }
        Ok(sec as u64 * 1_000_000_000 + u64::from(nsec))
    }

    /// An error if more than padding is left unread: at most 7 bytes may follow the last
    /// field (a writer may pad a message's end to its alignment).
    pub fn finish(&self, what: &str) -> Result<(), String> {
        let left = self.data.len() - self.at;
        if left >= 8 {
            return Err(format!("{left} bytes left over after a whole {what}"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_aligned_from_the_end_of_the_header() {
        let mut buf = vec![0xAA]; // a message need not start the buffer
        let mut m = Cdr::new(&mut buf);
        m.u8(7).f64(1.5).bool(true).u32(9).string("ab").f64(-0.0);
        let body = &buf[5..];
        assert_eq!(&buf[1..5], &HEADER);
        assert_eq!(body[0], 7);
        assert_eq!(&body[1..8], &[0; 7], "the f64 pads to 8");
        assert_eq!(&body[8..16], &1.5f64.to_le_bytes());
        assert_eq!(body[16], 1);
        assert_eq!(&body[17..20], &[0; 3]);
        assert_eq!(&body[20..24], &9u32.to_le_bytes());
        assert_eq!(
            &body[24..28],
            &3u32.to_le_bytes(),
            "the length counts the NUL"
        );
        assert_eq!(&body[28..31], b"ab\0");
        assert_eq!(&body[31..32], &[0]);
        assert_eq!(&body[32..40], &(-0.0f64).to_le_bytes());
        assert_eq!(body.len(), 40);

        let mut r = CdrReader::new(&buf[1..]).unwrap();
        assert_eq!(r.u8("a").unwrap(), 7);
        assert_eq!(r.f64("b").unwrap(), 1.5);
        assert!(r.bool("c").unwrap());
        assert_eq!(r.u32("d").unwrap(), 9);
        assert_eq!(r.string("e").unwrap(), "ab");
        assert_eq!(r.f64("f").unwrap().to_bits(), (-0.0f64).to_bits());
        r.finish("message").unwrap();
    }

    #[test]
    fn damaged_messages_are_errors_not_panics() {
        let mut buf = Vec::new();
        Cdr::new(&mut buf).string("world").f64(2.0);
        for cut in 0..buf.len() {
            let r = CdrReader::new(&buf[..cut]).and_then(|mut r| {
                r.string("s")?;
                r.f64("x")
            });
            assert!(r.is_err(), "cut at {cut}");
        }
        let mut huge = buf.clone();
        huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = CdrReader::new(&huge).unwrap().string("s").unwrap_err();
        assert!(err.contains("counts 4294967295"), "{err}");
        let mut big_endian = buf.clone();
        big_endian[1] = 0;
        assert!(CdrReader::new(&big_endian).is_err());
        let mut no_nul = buf.clone();
        no_nul[8 + 5] = b'!';
        assert!(CdrReader::new(&no_nul).unwrap().string("s").is_err());
    }

    #[test]
    fn strings_encoded_once_are_the_strings_at_any_aligned_place() {
        let pre = Strings::new(&["world", "actor/Bo"]);
        for lead in 0..8u8 {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            let mut m = Cdr::new(&mut a);
            (0..lead).for_each(|_| {
                m.u8(7);
            });
            m.strings(&pre).f64(1.0);
            let mut m = Cdr::new(&mut b);
            (0..lead).for_each(|_| {
                m.u8(7);
            });
            m.string("world").string("actor/Bo").f64(1.0);
            assert_eq!(a, b, "after {lead} bytes");
        }
    }

    #[test]
    fn times_split_into_seconds_and_nanoseconds() {
        let mut buf = Vec::new();
        Cdr::new(&mut buf).time(3_250_000_001);
        assert_eq!(&buf[4..8], &3i32.to_le_bytes());
        assert_eq!(&buf[8..12], &250_000_001u32.to_le_bytes());
        assert_eq!(
            CdrReader::new(&buf).unwrap().time("t").unwrap(),
            3_250_000_001
        );
    }
}
