//! [`McapFile`]: the flight log's MCAP writer, written for its hot path.
//!
//! The flight log writes every tick's messages into a chunk held in memory and writes the chunk
//! whole when a flush is due (see the `log` module doc). This writer does exactly that and no
//! more: each message is copied once, into the chunk buffer; the chunk is hashed once (its
//! `uncompressed_crc`), and written to the file with its header in one write (uncompressed:
//! the header is filled into room kept before the records). A caller that keeps up with a
//! flight faster than real time may keep closed chunks in that buffer, one after the other,
//! and write them together ([`McapFile::set_hand_over_bytes`], [`McapFile::hand_over`]): the
//! same bytes in fewer, larger writes. A chunk is indexed once it is written.
//!
//! On Linux the file's disk space is reserved ahead of the writes, [`RESERVE_STEP`] at a time
//! (`fallocate` keeping the size, best effort): the kernel then copies each chunk into blocks
//! already allocated instead of reserving them chunk by chunk. [`McapFile::finish`] truncates
//! the file to its data, which frees what was reserved and not written; a file cut by a crash
//! keeps its size (its data) and up to [`RESERVE_STEP`] of reserved space after it, freed when
//! the file is truncated or copied.
//!
//! Why not the `mcap` crate's writer, which `compile` uses: for an uncompressed chunk (0.26)
//! it copies every byte into two hashing buffers and the chunk buffer and hashes it twice (the
//! second hash feeds the data section CRC even when that is turned off), and it serialises
//! each record field by field through those layers. Reading stays with the crate
//! ([`FlightLog`](super::FlightLog) streams it and checks every chunk's CRC), so the tests
//! read back what this writes with an independent implementation.
//!
//! # What it writes (the MCAP spec's records, little-endian)
//!
//! Magic; Header (profile, library); then, in the order called: Schema and Channel records
//! (outside chunks, each once, and again inside the open chunk when asked:
//! [`McapFile::repeat_schemas_and_channels`]), Metadata and Attachment records (the open chunk
//! is closed first, so the file keeps the calls' order), and Chunks (no compression or LZ4
//! frames, `uncompressed_crc` always set, no message indexes); at [`McapFile::finish`]: Data End
//! (`data_section_crc` 0: not computed; a crash-cut log has no Data End to hold one), the
//! summary section (schemas, channels, statistics, chunk indexes, attachment indexes,
//! metadata indexes, each a group with its Summary Offset), the Footer with the summary's
//! CRC, and the closing magic.

use std::fs::File;
use std::io::{self, BufWriter, Write};

use mcap::records::MessageHeader;

/// The MCAP magic, at both ends of the file.
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Record opcodes (MCAP spec).
mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const ATTACHMENT: u8 = 0x09;
    pub const ATTACHMENT_INDEX: u8 = 0x0A;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// A message record's fixed part after opcode and length: channel id, sequence, log time,
/// publish time.
const MESSAGE_HEADER_LEN: u64 = 2 + 4 + 8 + 8;

/// A closed chunk's index entry, kept until the chunk is handed to the OS.
#[derive(Clone, Copy, Debug)]
struct ClosedChunk {
    start_ns: u64,
    end_ns: u64,
    /// File offset of the Chunk record, and its whole length.
    offset: u64,
    length: u64,
    compressed_size: u64,
    uncompressed_size: u64,
}

/// How chunks are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChunkCompression {
    None,
    /// LZ4 frames, as MCAP readers expect (`"lz4"`).
    Lz4,
}

impl ChunkCompression {
    fn name(self) -> &'static str {
        match self {
            ChunkCompression::None => "",
            ChunkCompression::Lz4 => "lz4",
        }
    }
}

/// A record appended to `buf`: the opcode, the content's length, then what `content` writes.
fn record(buf: &mut Vec<u8>, opcode: u8, content: impl FnOnce(&mut Vec<u8>)) {
    buf.push(opcode);
    let len_at = buf.len();
    buf.extend_from_slice(&[0; 8]);
    content(buf);
    let len = (buf.len() - len_at - 8) as u64;
    buf[len_at..len_at + 8].copy_from_slice(&len.to_le_bytes());
}

fn put_u16(buf: &mut Vec<u8>, v: u16) {
    buf.extend_from_slice(&v.to_le_bytes());
}

fn put_u32(buf: &mut Vec<u8>, v: u32) {
    buf.extend_from_slice(&v.to_le_bytes());
}

fn put_u64(buf: &mut Vec<u8>, v: u64) {
    buf.extend_from_slice(&v.to_le_bytes());
}

/// A string: its byte length (u32), then its UTF-8 bytes.
fn put_str(buf: &mut Vec<u8>, s: &str) {
    put_u32(buf, s.len() as u32);
    buf.extend_from_slice(s.as_bytes());
}

/// A `Map<string, string>`: the byte length of the entries (u32), then each key and value.
fn put_map<'a>(buf: &mut Vec<u8>, entries: impl IntoIterator<Item = (&'a str, &'a str)>) {
    let len_at = buf.len();
    put_u32(buf, 0);
    for (k, v) in entries {
        put_str(buf, k);
        put_str(buf, v);
    }
    let len = (buf.len() - len_at - 4) as u32;
    buf[len_at..len_at + 4].copy_from_slice(&len.to_le_bytes());
}

fn too_long(what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{what} is longer than an MCAP length field holds"),
    )
}

/// The chunk buffer's room for the open chunk (a second of flight's log is about 80 kB),
/// allocated up front; closed chunks kept for one write ([`McapFile::set_hand_over_bytes`])
/// get their room on top of it.
const CHUNK_ROOM: usize = 1 << 18;

/// Disk space reserved ahead of the writes at a time (see the module doc).
pub const RESERVE_STEP: u64 = 8 << 20;

/// Bytes of an uncompressed Chunk record before its records: the opcode, the length, the
/// start and end times, the uncompressed size and CRC, the compression's (empty) name with
/// its length, the records' length.
const CHUNK_PREFIX: usize = 1 + 8 + 8 + 8 + 8 + 4 + 4 + 8;

/// A schema as registered: its id is its index + 1.
struct Schema {
    name: String,
    encoding: String,
    data: Vec<u8>,
}

/// A streaming MCAP writer (see the module doc). Errors are the file's I/O errors; after one,
/// the file is as far as it got.
pub struct McapFile {
    out: BufWriter<File>,
    /// Bytes handed to `out` so far: the file offset of the next record.
    pos: u64,
    compression: ChunkCompression,
    /// The closed chunks not yet handed to `out` (the first `closed` bytes, whole records),
    /// then room for the open chunk's header ([`CHUNK_PREFIX`] bytes), then its records: an
    /// uncompressed chunk is closed in place, and the closed chunks go to the OS in one write.
    chunk: Vec<u8>,
    /// Bytes of closed chunks at the start of `chunk`.
    closed: usize,
    /// Their chunk indexes, put in the summary once they are handed over.
    closed_indexes: Vec<ClosedChunk>,
    /// Closed chunks are handed to the OS once they reach this many bytes (0: each one as it
    /// closes); [`McapFile::hand_over`] hands them over whatever their size.
    hand_over_bytes: usize,
    /// The open chunk's least and greatest message log time.
    chunk_times: Option<(u64, u64)>,
    /// The LZ4 frame of a chunk, reused.
    compressed: Vec<u8>,
    schemas: Vec<Schema>,
    /// The channel records, serialised (repeated in the summary).
    channel_records: Vec<u8>,
    /// Messages written per channel (index: channel id).
    channel_messages: Vec<u64>,
    chunk_indexes: Vec<u8>,
    attachment_indexes: Vec<u8>,
    metadata_indexes: Vec<u8>,
    message_times: Option<(u64, u64)>,
    chunk_count: u32,
    attachment_count: u32,
    metadata_count: u32,
    /// Scratch for records written outside chunks.
    scratch: Vec<u8>,
    finished: bool,
    /// The file's disk space reserved so far (from 0); `None` once the file system said it
    /// cannot reserve (no more tries).
    reserved: Option<u64>,
}

impl McapFile {
    /// Starts the file: the magic and the Header record (written through on the first flush).
    pub fn new(
        file: File,
        profile: &str,
        library: &str,
        compression: ChunkCompression,
    ) -> io::Result<McapFile> {
        let mut f = McapFile {
            out: BufWriter::with_capacity(1 << 16, file),
            pos: 0,
            compression,
            chunk: {
                let mut c = Vec::with_capacity(CHUNK_ROOM);
                c.resize(CHUNK_PREFIX, 0);
                c
            },
            closed: 0,
            closed_indexes: Vec::new(),
            hand_over_bytes: 0,
            chunk_times: None,
            compressed: Vec::new(),
            schemas: Vec::new(),
            channel_records: Vec::new(),
            channel_messages: Vec::new(),
            chunk_indexes: Vec::new(),
            attachment_indexes: Vec::new(),
            metadata_indexes: Vec::new(),
            message_times: None,
            chunk_count: 0,
            attachment_count: 0,
            metadata_count: 0,
            scratch: Vec::new(),
            finished: false,
            reserved: Some(0),
        };
        f.scratch.extend_from_slice(MAGIC);
        record(&mut f.scratch, op::HEADER, |b| {
            put_str(b, profile);
            put_str(b, library);
        });
        f.put_scratch()?;
        Ok(f)
    }

    /// Writes `scratch` to the file (outside any chunk) and empties it, written or not.
    fn put_scratch(&mut self) -> io::Result<()> {
        let result = self.out.write_all(&self.scratch);
        if result.is_ok() {
            self.pos += self.scratch.len() as u64;
        }
        self.scratch.clear();
        result
    }

    /// Closes the open chunk and writes one record after it; returns the record's offset
    /// and its whole length (opcode and length prefix included), as the indexes want them.
    fn put_record(
        &mut self,
        opcode: u8,
        content: impl FnOnce(&mut Vec<u8>),
    ) -> io::Result<(u64, u64)> {
        self.close_chunk()?;
        self.write_closed()?;
        let offset = self.pos;
        self.scratch.clear();
        record(&mut self.scratch, opcode, content);
        let length = self.scratch.len() as u64;
        self.put_scratch()?;
        Ok((offset, length))
    }

    /// Registers a schema and returns its id; a schema registered before (same name,
    /// encoding and data) keeps its id and is not written again.
    pub fn add_schema(&mut self, name: &str, encoding: &str, data: &[u8]) -> io::Result<u16> {
        if let Some(i) = self
            .schemas
            .iter()
            .position(|s| s.name == name && s.encoding == encoding && s.data == data)
        {
            return Ok(i as u16 + 1);
        }
        let id = u16::try_from(self.schemas.len() + 1).map_err(|_| too_long("the schema list"))?;
        u32::try_from(data.len()).map_err(|_| too_long("a schema"))?;
        self.schemas.push(Schema {
            name: name.to_string(),
            encoding: encoding.to_string(),
            data: data.to_vec(),
        });
        let schema = self.schemas.last().expect("just pushed");
        write_schema(&mut self.scratch, id, schema);
        self.put_scratch()?;
        Ok(id)
    }

    /// Registers a channel on schema `schema_id` and returns its id.
    pub fn add_channel(
        &mut self,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
    ) -> io::Result<u16> {
        let id =
            u16::try_from(self.channel_messages.len()).map_err(|_| too_long("the channel list"))?;
        let start = self.channel_records.len();
        record(&mut self.channel_records, op::CHANNEL, |b| {
            put_u16(b, id);
            put_u16(b, schema_id);
            put_str(b, topic);
            put_str(b, message_encoding);
            put_map(b, []);
        });
        self.channel_messages.push(0);
        self.scratch
            .extend_from_slice(&self.channel_records[start..]);
        self.put_scratch()?;
        Ok(id)
    }

    /// Appends a message to the open chunk (nothing reaches the file before the next
    /// [`flush`](Self::flush)), its data written by `encode` straight into the chunk
    /// (appending to the buffer it is given; no copy through a message buffer), its length
    /// filled in after. `header.channel_id` must be a registered channel.
    pub fn write_message_with(
        &mut self,
        header: &MessageHeader,
        encode: impl FnOnce(&mut Vec<u8>),
    ) -> io::Result<()> {
        let count = self
            .channel_messages
            .get_mut(usize::from(header.channel_id))
            .ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("no channel {} in this MCAP file", header.channel_id),
                )
            })?;
        *count += 1;
        let c = &mut self.chunk;
        let start = c.len();
        // Opcode, the length (filled in below), channel, sequence, log and publish times: one
        // copy into the chunk.
        let mut head = [0u8; 31];
        head[0] = op::MESSAGE;
        head[9..11].copy_from_slice(&header.channel_id.to_le_bytes());
        head[11..15].copy_from_slice(&header.sequence.to_le_bytes());
        head[15..23].copy_from_slice(&header.log_time.to_le_bytes());
        head[23..31].copy_from_slice(&header.publish_time.to_le_bytes());
        c.extend_from_slice(&head);
        let data_start = c.len();
        encode(c);
        let len = MESSAGE_HEADER_LEN + (c.len() - data_start) as u64;
        c[start + 1..start + 9].copy_from_slice(&len.to_le_bytes());
        let t = header.log_time;
        self.chunk_times = Some(match self.chunk_times {
            None => (t, t),
            Some((lo, hi)) => (lo.min(t), hi.max(t)),
        });
        Ok(())
    }

    /// [`write_message_with`](Self::write_message_with) of bytes already encoded.
    #[cfg(test)]
    fn write_message(&mut self, header: &MessageHeader, data: &[u8]) -> io::Result<()> {
        self.write_message_with(header, |c| c.extend_from_slice(data))
    }

    /// Writes every schema and channel registered so far into the open chunk: a second copy
    /// of them under the chunk's CRC (the first, outside chunks, has none), for a reader
    /// whose first copy is damaged.
    pub fn repeat_schemas_and_channels(&mut self) {
        for (i, s) in self.schemas.iter().enumerate() {
            write_schema(&mut self.chunk, i as u16 + 1, s);
        }
        self.chunk.extend_from_slice(&self.channel_records);
    }

    /// Closes the open chunk (if it holds anything) in place, after the closed chunks before
    /// it; they are all handed to `out` once they reach [`McapFile::hand_over_bytes`].
    fn close_chunk(&mut self) -> io::Result<()> {
        if self.chunk.len() == self.closed + CHUNK_PREFIX {
            return Ok(());
        }
        // A chunk of schemas and channels only has no message time: 0.
        let (start_ns, end_ns) = self.chunk_times.take().unwrap_or((0, 0));
        let at = self.closed;
        let uncompressed = &self.chunk[at + CHUNK_PREFIX..];
        let uncompressed_crc = crc32fast::hash(uncompressed);
        let uncompressed_size = uncompressed.len() as u64;
        if self.compression == ChunkCompression::Lz4 {
            self.compressed.clear();
            let mut enc = lz4::EncoderBuilder::new()
                .block_checksum(lz4::liblz4::BlockChecksum::NoBlockChecksum)
                .build(std::mem::take(&mut self.compressed))?;
            let written = enc.write_all(uncompressed);
            let (frame, result) = enc.finish();
            self.compressed = frame;
            if let Err(e) = written.and(result) {
                // The chunk is lost; the next one starts afresh.
                self.chunk.truncate(at + CHUNK_PREFIX);
                return Err(e);
            }
        }
        let compression = self.compression;
        let records_len = match compression {
            ChunkCompression::None => uncompressed_size,
            ChunkCompression::Lz4 => self.compressed.len() as u64,
        };
        let name = compression.name();
        let content_len = 8 + 8 + 8 + 4 + 4 + name.len() as u64 + 8 + records_len;
        self.scratch.clear();
        self.scratch.push(op::CHUNK);
        put_u64(&mut self.scratch, content_len);
        put_u64(&mut self.scratch, start_ns);
        put_u64(&mut self.scratch, end_ns);
        put_u64(&mut self.scratch, uncompressed_size);
        put_u32(&mut self.scratch, uncompressed_crc);
        put_str(&mut self.scratch, name);
        put_u64(&mut self.scratch, records_len);
        match compression {
            // The header in the room before the records.
            ChunkCompression::None => {
                self.chunk[at..at + CHUNK_PREFIX].copy_from_slice(&self.scratch);
            }
            ChunkCompression::Lz4 => {
                self.chunk.truncate(at);
                self.chunk.extend_from_slice(&self.scratch);
                self.chunk.extend_from_slice(&self.compressed);
            }
        }
        self.scratch.clear();
        self.closed_indexes.push(ClosedChunk {
            start_ns,
            end_ns,
            offset: self.pos + at as u64,
            length: 9 + content_len,
            compressed_size: records_len,
            uncompressed_size,
        });
        self.closed = self.chunk.len();
        // The next chunk's header room.
        self.chunk.resize(self.closed + CHUNK_PREFIX, 0);
        if self.closed >= self.hand_over_bytes {
            self.write_closed()?;
        }
        Ok(())
    }

    /// Hands the closed chunks to `out` in one write and indexes them. After an error the
    /// file is as far as it got and they are not indexed; the open chunk is kept.
    fn write_closed(&mut self) -> io::Result<()> {
        if self.closed == 0 {
            return Ok(());
        }
        let closed = std::mem::replace(&mut self.closed, 0);
        self.reserve(self.pos + closed as u64);
        let written = self.out.write_all(&self.chunk[..closed]);
        // The open chunk to the front (right after a close, only its header's room).
        self.chunk.drain(..closed);
        if let Err(e) = written {
            self.closed_indexes.clear();
            return Err(e);
        }
        self.pos += closed as u64;
        let name = self.compression.name();
        for c in self.closed_indexes.drain(..) {
            record(&mut self.chunk_indexes, op::CHUNK_INDEX, |b| {
                put_u64(b, c.start_ns);
                put_u64(b, c.end_ns);
                put_u64(b, c.offset);
                put_u64(b, c.length);
                put_u32(b, 0); // no message indexes
                put_u64(b, 0);
                put_str(b, name);
                put_u64(b, c.compressed_size);
                put_u64(b, c.uncompressed_size);
            });
            self.chunk_count += 1;
            self.message_times = Some(match self.message_times {
                None => (c.start_ns, c.end_ns),
                Some((lo, hi)) => (lo.min(c.start_ns), hi.max(c.end_ns)),
            });
        }
        Ok(())
    }

    /// Closed chunks are kept until they reach `bytes` and then handed to the OS in one write
    /// (0, the default: each chunk as it closes). Fewer, larger writes cost the kernel less
    /// per byte; what waits is what a crash of the process may lose, so a caller that sets
    /// this calls [`McapFile::hand_over`] whenever it has nothing else to write.
    pub fn set_hand_over_bytes(&mut self, bytes: usize) {
        self.hand_over_bytes = bytes;
        let room = bytes + CHUNK_ROOM;
        self.chunk.reserve(room.saturating_sub(self.chunk.len()));
    }

    /// Hands the closed chunks to the OS (no `fsync`); the open chunk stays open.
    pub fn hand_over(&mut self) -> io::Result<()> {
        self.write_closed()?;
        self.out.flush()
    }

    /// Reserves the file's disk space up to at least `end` (see the module doc); best effort.
    fn reserve(&mut self, end: u64) {
        let Some(reserved) = self.reserved else {
            return;
        };
        if end <= reserved {
            return;
        }
        let step = (end - reserved).div_ceil(RESERVE_STEP) * RESERVE_STEP;
        self.reserved =
            reserve_space(self.out.get_ref(), reserved, step).then_some(reserved + step);
    }

    /// Closes the open chunk and hands everything written to the OS (no `fsync`).
    pub fn flush(&mut self) -> io::Result<()> {
        self.close_chunk()?;
        self.hand_over()
    }

    /// Closes the open chunk; hands the closed chunks to the OS when they reach
    /// [`McapFile::set_hand_over_bytes`]'s size (each one, by default).
    pub fn close_and_hand_over_when_due(&mut self) -> io::Result<()> {
        self.close_chunk()?;
        self.out.flush()
    }

    /// Writes a Metadata record (after closing the open chunk).
    pub fn write_metadata<'a>(
        &mut self,
        name: &str,
        entries: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> io::Result<()> {
        let (offset, length) = self.put_record(op::METADATA, |b| {
            put_str(b, name);
            put_map(b, entries);
        })?;
        record(&mut self.metadata_indexes, op::METADATA_INDEX, |b| {
            put_u64(b, offset);
            put_u64(b, length);
            put_str(b, name);
        });
        self.metadata_count += 1;
        Ok(())
    }

    /// Writes an Attachment record with its CRC (after closing the open chunk).
    pub fn attach(
        &mut self,
        log_time: u64,
        create_time: u64,
        name: &str,
        media_type: &str,
        data: &[u8],
    ) -> io::Result<()> {
        let (offset, length) = self.put_record(op::ATTACHMENT, |b| {
            let fields_at = b.len();
            put_u64(b, log_time);
            put_u64(b, create_time);
            put_str(b, name);
            put_str(b, media_type);
            put_u64(b, data.len() as u64);
            b.extend_from_slice(data);
            // The CRC of the preceding fields.
            let crc = crc32fast::hash(&b[fields_at..]);
            put_u32(b, crc);
        })?;
        record(&mut self.attachment_indexes, op::ATTACHMENT_INDEX, |b| {
            put_u64(b, offset);
            put_u64(b, length);
            put_u64(b, log_time);
            put_u64(b, create_time);
            put_u64(b, data.len() as u64);
            put_str(b, name);
            put_str(b, media_type);
        });
        self.attachment_count += 1;
        Ok(())
    }

    /// Closes the open chunk, writes Data End, the summary, the footer and the closing
    /// magic, and flushes. Once only: later calls do nothing.
    pub fn finish(&mut self) -> io::Result<()> {
        if self.finished {
            return Ok(());
        }
        self.put_record(op::DATA_END, |b| put_u32(b, 0))?;

        let summary_start = self.pos;
        let mut summary = std::mem::take(&mut self.scratch);
        summary.clear();
        let mut offsets: Vec<(u8, u64, u64)> = Vec::new();
        let mut group = |summary: &mut Vec<u8>, opcode: u8, fill: &dyn Fn(&mut Vec<u8>)| {
            let start = summary.len();
            fill(summary);
            if summary.len() > start {
                offsets.push((
                    opcode,
                    summary_start + start as u64,
                    (summary.len() - start) as u64,
                ));
            }
        };
        group(&mut summary, op::SCHEMA, &|b| {
            for (i, s) in self.schemas.iter().enumerate() {
                write_schema(b, i as u16 + 1, s);
            }
        });
        group(&mut summary, op::CHANNEL, &|b| {
            b.extend_from_slice(&self.channel_records)
        });
        let (start_ns, end_ns) = self.message_times.unwrap_or((0, 0));
        group(&mut summary, op::STATISTICS, &|b| {
            record(b, op::STATISTICS, |b| {
                put_u64(b, self.channel_messages.iter().sum());
                put_u16(b, self.schemas.len() as u16);
                put_u32(b, self.channel_messages.len() as u32);
                put_u32(b, self.attachment_count);
                put_u32(b, self.metadata_count);
                put_u32(b, self.chunk_count);
                put_u64(b, start_ns);
                put_u64(b, end_ns);
                let len_at = b.len();
                put_u32(b, 0);
                for (id, &n) in self.channel_messages.iter().enumerate() {
                    if n > 0 {
                        put_u16(b, id as u16);
                        put_u64(b, n);
                    }
                }
                let len = (b.len() - len_at - 4) as u32;
                b[len_at..len_at + 4].copy_from_slice(&len.to_le_bytes());
            })
        });
        group(&mut summary, op::CHUNK_INDEX, &|b| {
            b.extend_from_slice(&self.chunk_indexes)
        });
        group(&mut summary, op::ATTACHMENT_INDEX, &|b| {
            b.extend_from_slice(&self.attachment_indexes)
        });
        group(&mut summary, op::METADATA_INDEX, &|b| {
            b.extend_from_slice(&self.metadata_indexes)
        });
        let summary_offset_start = summary_start + summary.len() as u64;
        for (opcode, start, length) in offsets {
            record(&mut summary, op::SUMMARY_OFFSET, |b| {
                b.push(opcode);
                put_u64(b, start);
                put_u64(b, length);
            });
        }
        // The footer; its CRC covers the summary up to and including summary_offset_start.
        summary.push(op::FOOTER);
        put_u64(&mut summary, 8 + 8 + 4);
        put_u64(&mut summary, summary_start);
        put_u64(&mut summary, summary_offset_start);
        let crc = crc32fast::hash(&summary);
        put_u32(&mut summary, crc);
        summary.extend_from_slice(MAGIC);
        self.scratch = summary;
        self.put_scratch()?;
        self.out.flush()?;
        if self.reserved.is_some_and(|r| r > self.pos) {
            // Frees the space reserved after the data (the size does not change).
            self.out.get_ref().set_len(self.pos)?;
        }
        self.finished = true;
        Ok(())
    }

    /// The file (after [`finish`](Self::finish): everything written).
    pub fn into_file(self) -> io::Result<File> {
        self.out.into_inner().map_err(|e| e.into_error())
    }
}

/// Reserves `len` bytes of disk space for `file` from `offset`, its size unchanged; whether
/// the file system did (elsewhere than Linux: never).
#[cfg(target_os = "linux")]
fn reserve_space(file: &File, offset: u64, len: u64) -> bool {
    use std::os::fd::AsRawFd;
    let (Ok(offset), Ok(len)) = (libc::off_t::try_from(offset), libc::off_t::try_from(len)) else {
        return false;
    };
    // SAFETY: `fallocate` on a descriptor this `File` owns and keeps open for the call; it
    // reads and writes no memory of the program.
    unsafe { libc::fallocate(file.as_raw_fd(), libc::FALLOC_FL_KEEP_SIZE, offset, len) == 0 }
}

#[cfg(not(target_os = "linux"))]
fn reserve_space(_file: &File, _offset: u64, _len: u64) -> bool {
    false
}

fn write_schema(buf: &mut Vec<u8>, id: u16, s: &Schema) {
    record(buf, op::SCHEMA, |b| {
        put_u16(b, id);
        put_str(b, &s.name);
        put_str(b, &s.encoding);
        put_u32(b, s.data.len() as u32);
        b.extend_from_slice(&s.data);
    });
}

#[cfg(test)]
mod tests {
    use std::borrow::Cow;
    use std::collections::BTreeMap;

    use super::*;

    fn header(channel_id: u16, sequence: u32, t: u64) -> MessageHeader {
        MessageHeader {
            channel_id,
            sequence,
            log_time: t,
            publish_time: t + 1,
        }
    }

    /// A file with two channels on one schema (added twice), metadata, an attachment and
    /// three chunks, read back by the mcap crate.
    fn sample(compression: ChunkCompression) -> Vec<u8> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.mcap");
        let mut f =
            McapFile::new(File::create(&path).unwrap(), "prof", "lib", compression).unwrap();
        let s = f.add_schema("S", "jsonschema", b"{}").unwrap();
        assert_eq!(f.add_schema("S", "jsonschema", b"{}").unwrap(), s);
        let t = f.add_schema("T", "ros2msg", b"float64 x").unwrap();
        let a = f.add_channel(s, "/a", "json").unwrap();
        let b = f.add_channel(t, "/b", "cdr").unwrap();
        f.write_metadata("meta", [("k", "v"), ("k2", "\"w\"")])
            .unwrap();
        f.attach(5, 6, "script.psl", "text/plain", b"MS on A")
            .unwrap();
        f.write_message(&header(a, 1, 30), b"{\"x\":1}").unwrap();
        f.write_message(&header(b, 1, 10), &[1, 2, 3]).unwrap();
        f.flush().unwrap();
        f.flush().unwrap(); // an empty chunk is not written
        f.write_message(&header(a, 2, 40), b"{\"x\":2}").unwrap();
        f.write_metadata("late", []).unwrap(); // closes the chunk
        f.write_message(&header(a, 3, 50), b"").unwrap();
        f.finish().unwrap();
        f.finish().unwrap();
        f.into_file().unwrap();
        std::fs::read(&path).unwrap()
    }

    #[test]
    fn the_mcap_crate_reads_back_every_record_and_the_summary() {
        for compression in [ChunkCompression::None, ChunkCompression::Lz4] {
            let bytes = sample(compression);
            assert_eq!(&bytes[..8], MAGIC);
            assert_eq!(&bytes[bytes.len() - 8..], MAGIC);

            let messages: Vec<_> = mcap::MessageStream::new(&bytes)
                .unwrap()
                .map(|m| m.unwrap())
                .map(|m| {
                    (
                        m.channel.topic.clone(),
                        m.sequence,
                        m.log_time,
                        m.publish_time,
                        m.data.to_vec(),
                    )
                })
                .collect();
            assert_eq!(
                messages,
                vec![
                    ("/a".to_string(), 1, 30, 31, b"{\"x\":1}".to_vec()),
                    ("/b".to_string(), 1, 10, 11, vec![1, 2, 3]),
                    ("/a".to_string(), 2, 40, 41, b"{\"x\":2}".to_vec()),
                    ("/a".to_string(), 3, 50, 51, vec![]),
                ]
            );

            let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
            let stats = summary.stats.as_ref().unwrap();
            assert_eq!(stats.message_count, 4);
            assert_eq!(stats.schema_count, 2);
            assert_eq!(stats.channel_count, 2);
            assert_eq!(stats.attachment_count, 1);
            assert_eq!(stats.metadata_count, 2);
            assert_eq!(stats.chunk_count, 3);
            assert_eq!((stats.message_start_time, stats.message_end_time), (10, 50));
            assert_eq!(
                stats.channel_message_counts,
                BTreeMap::from([(0, 3), (1, 1)])
            );
            assert_eq!(summary.channels.len(), 2);
            assert_eq!(summary.schemas.len(), 2);
            assert_eq!(
                summary.channels[&1].schema.as_ref().unwrap().encoding,
                "ros2msg"
            );
            assert_eq!(summary.chunk_indexes.len(), 3);
            let times: Vec<_> = summary
                .chunk_indexes
                .iter()
                .map(|c| (c.message_start_time, c.message_end_time))
                .collect();
            assert_eq!(times, vec![(10, 30), (40, 40), (50, 50)]);
            for index in &summary.chunk_indexes {
                assert_eq!(index.compression, compression.name());
                // The index points at the chunk record, its whole length.
                let at = index.chunk_start_offset as usize;
                assert_eq!(bytes[at], op::CHUNK);
                let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap());
                assert_eq!(9 + len, index.chunk_length);
                // The indexed read decompresses it and checks its CRC.
                let messages = summary.stream_chunk(&bytes, index).unwrap().count();
                assert!(messages >= 1);
            }

            assert_eq!(summary.attachment_indexes.len(), 1);
            let attachment =
                mcap::read::attachment(&bytes, &summary.attachment_indexes[0]).unwrap();
            assert_eq!(attachment.name, "script.psl");
            assert_eq!(attachment.media_type, "text/plain");
            assert_eq!((attachment.log_time, attachment.create_time), (5, 6));
            assert_eq!(attachment.data, Cow::Borrowed(b"MS on A".as_slice()));

            assert_eq!(summary.metadata_indexes.len(), 2);
            let meta = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).unwrap();
            assert_eq!(meta.name, "meta");
            assert_eq!(
                meta.metadata,
                BTreeMap::from([("k".into(), "v".into()), ("k2".into(), "\"w\"".into())])
            );
        }
    }

    /// Every record's opcode, in file order, from the crate's strict linear reader (chunk and
    /// summary CRCs checked, chunks opened).
    fn linear_opcodes(bytes: &[u8]) -> Vec<u8> {
        use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_validate_chunk_crcs(true)
                .with_prevalidate_chunk_crcs(true)
                .with_validate_summary_section_crc(true)
                .with_validate_data_section_crc(true),
        );
        let mut rest = bytes;
        let mut opcodes = Vec::new();
        while let Some(event) = reader.next_event() {
            match event.unwrap() {
                LinearReadEvent::ReadRequest(need) => {
                    let n = need.min(rest.len());
                    reader.insert(n).copy_from_slice(&rest[..n]);
                    reader.notify_read(n);
                    rest = &rest[n..];
                }
                LinearReadEvent::Record { opcode, data } => {
                    mcap::parse_record(opcode, data).unwrap();
                    opcodes.push(opcode);
                }
            }
        }
        opcodes
    }

    #[test]
    fn a_strict_linear_read_finds_the_records_in_call_order() {
        for compression in [ChunkCompression::None, ChunkCompression::Lz4] {
            let ops = linear_opcodes(&sample(compression));
            use op::*;
            #[rustfmt::skip]
            let expected = [
                HEADER, SCHEMA, SCHEMA, CHANNEL, CHANNEL, METADATA, ATTACHMENT,
                MESSAGE, MESSAGE, MESSAGE, METADATA, MESSAGE, DATA_END,
                SCHEMA, SCHEMA, CHANNEL, CHANNEL, STATISTICS, CHUNK_INDEX, CHUNK_INDEX,
                CHUNK_INDEX, ATTACHMENT_INDEX, METADATA_INDEX, METADATA_INDEX,
                SUMMARY_OFFSET, SUMMARY_OFFSET, SUMMARY_OFFSET, SUMMARY_OFFSET, SUMMARY_OFFSET,
                SUMMARY_OFFSET, FOOTER,
            ];
            assert_eq!(ops, expected);
        }
    }

    #[test]
    fn records_have_the_spec_byte_layout() {
        let bytes = sample(ChunkCompression::None);
        // Header: opcode 1, length, profile "prof", library "lib".
        let mut expected = vec![op::HEADER];
        expected.extend_from_slice(&(4 + 4 + 4 + 3u64).to_le_bytes());
        expected.extend_from_slice(&4u32.to_le_bytes());
        expected.extend_from_slice(b"prof");
        expected.extend_from_slice(&3u32.to_le_bytes());
        expected.extend_from_slice(b"lib");
        assert_eq!(&bytes[8..8 + expected.len()], expected.as_slice());

        // Footer: opcode 2, length 20, summary start, summary offset start, the CRC of the
        // summary through summary_offset_start.
        let footer = bytes.len() - 8 - 29;
        assert_eq!(bytes[footer], op::FOOTER);
        assert_eq!(&bytes[footer + 1..footer + 9], &20u64.to_le_bytes());
        let field = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
        let summary_start = field(footer + 9);
        let offsets_start = field(footer + 17);
        assert!(summary_start < offsets_start && offsets_start < footer);
        let crc = u32::from_le_bytes(bytes[footer + 25..footer + 29].try_into().unwrap());
        assert_eq!(crc, crc32fast::hash(&bytes[summary_start..footer + 25]));
        // Data End just before the summary, its CRC 0 (not computed).
        assert_eq!(
            &bytes[summary_start - 13..summary_start],
            &[op::DATA_END, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
        );
    }

    #[test]
    fn a_corrupt_chunk_fails_its_crc_in_the_mcap_crate() {
        let mut bytes = sample(ChunkCompression::None);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let index = summary.chunk_indexes[0].clone();
        // The last byte of the chunk's records: the end of a message's data.
        let last = (index.chunk_start_offset + index.chunk_length - 1) as usize;
        bytes[last] ^= 0x20;
        let err = summary
            .stream_chunk(&bytes, &index)
            .unwrap()
            .find_map(Result::err);
        assert!(err.is_some(), "a flipped bit must fail the chunk CRC");
    }

    /// A writer on a file opened for reading only: every write that reaches it fails
    /// (EBADF). The directory is kept with it.
    fn refusing_file() -> (tempfile::TempDir, McapFile) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.mcap");
        std::fs::write(&path, b"").unwrap();
        let file = File::open(&path).unwrap();
        let f = McapFile::new(file, "p", "l", ChunkCompression::None).unwrap();
        (dir, f)
    }

    #[test]
    fn a_file_that_refuses_writes_gives_errors_not_panics() {
        let (_dir, mut f) = refusing_file();
        // Larger than the write buffer: it goes to the file at once.
        f.add_schema("S", "jsonschema", &[b'x'; 1 << 17])
            .unwrap_err();
        assert!(f.flush().is_err());
        assert!(f.finish().is_err());
        assert!(
            f.finish().is_err(),
            "an unfinished file is not reported finished"
        );
    }

    /// Six chunks of three messages, closed as the flight log closes them; the file's
    /// length on disk after each close, after a hand-over at the end, and its final bytes.
    fn six_chunks(
        compression: ChunkCompression,
        keep_bytes: usize,
    ) -> (Vec<u64>, u64, Vec<u8>, Vec<u8>) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.mcap");
        let mut f = McapFile::new(File::create(&path).unwrap(), "p", "l", compression).unwrap();
        let s = f.add_schema("S", "ros2msg", b"float64 x").unwrap();
        let c = f.add_channel(s, "/c", "cdr").unwrap();
        f.set_hand_over_bytes(keep_bytes);
        let on_disk = || std::fs::metadata(&path).unwrap().len();
        let mut lengths = Vec::new();
        for chunk in 0..6u32 {
            for k in 0..3u32 {
                let n = chunk * 3 + k;
                let data: Vec<u8> = (0..200).map(|i| (i * 7 + n) as u8).collect();
                f.write_message(&header(c, n, u64::from(n) * 10), &data)
                    .unwrap();
            }
            f.close_and_hand_over_when_due().unwrap();
            lengths.push(on_disk());
        }
        f.hand_over().unwrap();
        let handed = on_disk();
        // What a crash now would leave: the file as it is, without its summary.
        let cut = std::fs::read(&path).unwrap();
        f.finish().unwrap();
        f.into_file().unwrap();
        (lengths, handed, cut, std::fs::read(&path).unwrap())
    }

    /// Closed chunks kept for one write (`set_hand_over_bytes`, as the log's writer thread
    /// keeps them while batches wait) make the same file as chunks written as they close;
    /// they reach the file when they reach the size or on `hand_over`, and what was handed
    /// over reads back from a file cut there, as a crash would cut it.
    #[test]
    fn chunks_kept_for_one_write_make_the_same_file_and_reach_it_when_handed_over() {
        for compression in [ChunkCompression::None, ChunkCompression::Lz4] {
            let (eager, eager_handed, _, eager_file) = six_chunks(compression, 0);
            assert!(
                eager.windows(2).all(|w| w[0] < w[1]),
                "each chunk on disk as it closes: {eager:?}"
            );
            assert_eq!(eager_handed, eager[5]);

            // Kept whatever their number: nothing reaches the file until the hand-over.
            let (kept, handed, cut, file) = six_chunks(compression, 1 << 20);
            assert!(kept.iter().all(|&l| l == kept[0]), "{kept:?}");
            assert!(kept[0] < eager[0], "{kept:?} against {eager:?}");
            assert_eq!(handed, eager[5], "the hand-over writes every closed chunk");
            assert!(file == eager_file, "the same bytes");
            let messages = mcap::MessageStream::new(&cut)
                .unwrap()
                .take_while(Result::is_ok)
                .count();
            assert_eq!(
                messages, 18,
                "a file cut after the hand-over keeps every message"
            );

            // Kept until they reach a size (the first chunk's and a byte): on disk as the
            // closes that reach it, and only those, wrote them.
            let threshold = (eager[0] - kept[0]) as usize + 1;
            let (by_size, _, _, file) = six_chunks(compression, threshold);
            let (mut expected, mut on_disk, mut waiting) = (Vec::new(), kept[0], 0);
            for (i, &end) in eager.iter().enumerate() {
                let previous = if i == 0 { kept[0] } else { eager[i - 1] };
                waiting += (end - previous) as usize;
                if waiting >= threshold {
                    (on_disk, waiting) = (end, 0);
                }
                expected.push(on_disk);
            }
            assert_eq!(by_size, expected, "against {eager:?}");
            assert!(
                by_size[0] == kept[0] && by_size[1] == eager[1],
                "{by_size:?}"
            );
            assert!(file == eager_file);
        }
    }

    /// A kept chunk that cannot be written is an error at the hand-over, not a panic, and is
    /// not indexed: the summary still describes the file.
    #[test]
    fn a_kept_chunk_the_file_refuses_is_an_error_at_the_hand_over() {
        let (_dir, mut f) = refusing_file();
        f.set_hand_over_bytes(1 << 20);
        let s = f.add_schema("S", "ros2msg", b"float64 x").unwrap();
        let c = f.add_channel(s, "/c", "cdr").unwrap();
        // Larger than the write buffer: its write goes to the file.
        f.write_message(&header(c, 1, 0), &[0; 1 << 17]).unwrap();
        // The chunk is kept; the records before it, flushed, are refused.
        assert!(f.close_and_hand_over_when_due().is_err());
        assert_eq!((f.closed_indexes.len(), f.chunk_count), (1, 0));
        assert!(f.hand_over().is_err());
        assert_eq!(f.chunk_count, 0, "no chunk reached the file");
        assert!(f.closed_indexes.is_empty() && f.closed == 0);
        assert!(f.finish().is_err());
    }

    #[test]
    fn an_unknown_channel_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let file = File::create(dir.path().join("t.mcap")).unwrap();
        let mut f = McapFile::new(file, "p", "l", ChunkCompression::None).unwrap();
        let e = f.write_message(&header(3, 1, 0), b"x").unwrap_err();
        assert!(e.to_string().contains("no channel 3"), "{e}");
    }
}
