//! The reference as CSV: one header line, then one row per sample, the fields of
//! [`Sample`] in order with vectors split into `_x`, `_y`, `_z` columns. Numbers are in
//! their shortest round-trip form, so a row parses back to the very same values.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use super::{annotate, AtomicFile};
use dronecine_compiler::reference::Sample;

/// The header's columns, in order.
pub const CSV_COLUMNS: [&str; 14] = [
    "t_s",
    "position_m_x",
    "position_m_y",
    "position_m_z",
    "velocity_mps_x",
    "velocity_mps_y",
    "velocity_mps_z",
    "acceleration_mps2_x",
    "acceleration_mps2_y",
    "acceleration_mps2_z",
    "heading_rad",
    "heading_rate_radps",
    "camera_pitch_rad",
    "shot",
];

/// Streams a reference into a CSV file, written to a temporary name and renamed onto the
/// destination by [`finish`](CsvWriter::finish).
pub struct CsvWriter {
    out: Option<BufWriter<File>>,
    file: AtomicFile,
    line: Vec<u8>,
}

impl CsvWriter {
    /// Creates the temporary file next to `path` and writes the header.
    pub fn create(path: &Path) -> io::Result<Self> {
        let (file, handle) = AtomicFile::create(path)?;
        let mut out = BufWriter::with_capacity(1 << 16, handle);
        let header = CSV_COLUMNS.join(",");
        writeln!(out, "{header}").map_err(|e| annotate(path, e))?;
        Ok(Self {
            out: Some(out),
            file,
            line: Vec::with_capacity(512),
        })
    }

    /// Writes one row.
    pub fn write(&mut self, s: &Sample) -> io::Result<()> {
        let line = &mut self.line;
        line.clear();
        let num = |line: &mut Vec<u8>, x: f64| {
            // zmij prints NaN/inf/-inf for non-finite values, which Rust's parser reads back.
            let mut b = zmij::Buffer::new();
            line.extend_from_slice(b.format(x).as_bytes());
            line.push(b',');
        };
        num(line, s.t_s);
        for v in [&s.position_m, &s.velocity_mps, &s.acceleration_mps2] {
            for &x in v {
                num(line, x);
            }
        }
        num(line, s.heading_rad);
        num(line, s.heading_rate_radps);
        num(line, s.camera_pitch_rad);
        let mut b = itoa::Buffer::new();
        line.extend_from_slice(b.format(s.shot).as_bytes());
        line.push(b'\n');
        let dest = self.file.dest();
        match self.out.as_mut() {
            Some(out) => out.write_all(line).map_err(|e| annotate(dest, e)),
            None => Err(io::Error::other(format!(
                "cannot write {}: writer finished",
                dest.display()
            ))),
        }
    }

    /// Flushes and renames the temporary file onto the destination.
    pub fn finish(mut self) -> io::Result<()> {
        if let Some(out) = self.out.take() {
            let file = out
                .into_inner()
                .map_err(|e| annotate(self.file.dest(), e.into_error()))?;
            drop(file);
        }
        self.file.commit()
    }
}
