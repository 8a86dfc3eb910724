//! Damage to a flight log costs at most the chunk it hits: what the records at the file's start
//! hold is kept twice (the schemas and channels in the first chunk too, under its CRC; the
//! header as an attachment too, under its CRC), a damaged length does not hide the record after
//! it, and the summary and the footer hold nothing the ticks need (a finished log's summary
//! gives the schemas and channels a third time).

use std::path::Path;

use dronecine_mcap::log::{FlightLog, LogError, HEADER_ATTACHMENT, HEADER_METADATA};

use crate::log::{chunks_of, header, reference_log};

/// The log in `bytes`, read (it must open).
fn read(bytes: &[u8], case: &str) -> FlightLog {
    FlightLog::from_bytes(Path::new("damaged.mcap"), bytes)
        .unwrap_or_else(|e| panic!("{case}: {e}"))
}

/// The top-level records of an intact MCAP file, up to and with the footer: offset, opcode and
/// whole length (opcode and length field included).
fn records(bytes: &[u8]) -> Vec<(u64, u8, u64)> {
    let mut out = Vec::new();
    let mut at = 8usize;
    while at + 9 <= bytes.len() {
        let n = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap());
        out.push((at as u64, bytes[at], 9 + n));
        if bytes[at] == 0x02 {
            break;
        }
        at += 9 + n as usize;
    }
    out
}

/// Everything in `log` is the intact log's.
fn assert_whole(log: &FlightLog, whole: &FlightLog, case: &str) {
    assert_eq!(log.header, whole.header, "{case}");
    assert_eq!(log.ticks, whole.ticks, "{case}: {:?}", log.damage);
    assert_eq!(log.key_frames, whole.key_frames, "{case}");
    assert_eq!(log.events.len(), whole.events.len(), "{case}");
}

/// Each record before the first tick (the magic, the MCAP header, the schemas and channels,
/// the header's metadata, the script and header attachments, the first chunk with the scene),
/// damaged in its opcode, in each byte of its length, in its middle and in its last byte: no
/// tick, key frame or event is lost, and the header is the flight's.
#[test]
fn damage_to_any_record_before_the_first_tick_loses_nothing() {
    let bytes = reference_log();
    let whole = read(bytes, "intact");
    assert!(whole.damage.is_empty() && !whole.key_frames.is_empty());
    let recs = records(bytes);
    let first_ticks = recs
        .iter()
        .filter(|r| r.1 == 0x06)
        .nth(1)
        .expect("the scene's chunk, then the first ticks'")
        .0;
    let mut places: Vec<u64> = (0..8).collect();
    for &(at, _, len) in recs.iter().filter(|r| r.0 < first_ticks) {
        places.extend(at..at + 9);
        places.extend([at + len / 2, at + len - 1]);
    }
    let mut damaged = bytes.to_vec();
    for &p in &places {
        for mask in [0xff, 0x01, 0x80] {
            damaged[p as usize] ^= mask;
            let case = format!("byte {p} ^ {mask:#04x}");
            let log = read(&damaged, &case);
            damaged[p as usize] ^= mask;
            assert_whole(&log, &whole, &case);
            assert!(!log.truncated, "{case}: {:?}", log.damage);
        }
    }
}

/// A flipped bit in the header's metadata record (which has no CRC), in a field name or in a
/// number: the header is read from its attachment, and the damage is told. A damaged header
/// attachment: read from the metadata record.
#[test]
fn the_header_survives_damage_to_either_of_its_copies() {
    let bytes = reference_log();
    let whole = read(bytes, "intact");
    let recs = records(bytes);
    let find = |needle: &[u8], from: usize| {
        from + bytes[from..]
            .windows(needle.len())
            .position(|w| w == needle)
            .unwrap()
    };
    let metadata = recs.iter().find(|r| r.1 == 0x0c).unwrap();
    let attachment = find(HEADER_ATTACHMENT.as_bytes(), 0);
    for (what, p) in [
        ("a field's name", find(b"gain_roll_mps_per_rad", 0)),
        ("a number", find(b"\"tau_roll_s\":", 0) + 14),
        (
            "the script's text",
            find(b"ardrone2\\n", metadata.0 as usize),
        ),
        (
            "the header attachment",
            find(b"gain_roll_mps_per_rad", attachment),
        ),
    ] {
        let mut damaged = bytes.to_vec();
        damaged[p] ^= 0x01;
        let log = read(&damaged, what);
        assert_whole(&log, &whole, what);
        assert_eq!(log.header, header(), "{what}");
        assert_eq!(log.damage.len(), 1, "{what}: {:?}", log.damage);
        let d = &log.damage[0];
        assert!(d.resumed_at.is_some() && !d.cut, "{what}: {d:?}");
        if what == "the header attachment" {
            assert!(d.detail.contains("CRC"), "{what}: {d:?}");
        } else {
            assert_eq!(d.offset, metadata.0, "{what}");
            assert!(d.detail.contains(HEADER_METADATA), "{what}: {d:?}");
        }
    }
}

/// A chunk's length damaged in any way (one more, one less, over the next chunk exactly, far
/// beyond the file), or the length of its records inside it: that chunk's ticks are lost, and
/// reading resumes at the next chunk, which is not.
#[test]
fn a_damaged_chunk_length_costs_that_chunk_and_not_the_next() {
    let bytes = reference_log();
    let whole = read(bytes, "intact");
    let chunks = chunks_of(bytes);
    let k = chunks.len() / 2;
    let (start, len, t0_ns, t1_ns) = chunks[k];
    let next = chunks[k + 1];
    let n = len - 9;
    // Its ticks (a key frame, before them, holds the time of the first).
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    let here: Vec<u64> = summary
        .stream_chunk(bytes, &summary.chunk_indexes[k])
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/servo/tick")
        .map(|m| m.log_time)
        .collect();
    assert_eq!((here[0], here[here.len() - 1]), (t0_ns, t1_ns));
    let in_chunk = |t_s: f64| here.contains(&((t_s * 1e9).round() as u64));
    let lost_here = here.len();
    assert!(lost_here > 10);
    let at = start as usize;
    // The records' length: the last field of the chunk's header (no compression name).
    let records_len_at = at + 9 + 8 + 8 + 8 + 4 + 4;
    for (what, field_at, value) in [
        ("one more", at + 1, n + 1),
        ("one less", at + 1, n - 1),
        ("over the next chunk", at + 1, n + next.1),
        ("a little beyond", at + 1, n + 4096),
        ("beyond the file", at + 1, n + (1 << 40)),
        ("the records' one more", records_len_at, n - 40 + 1),
        ("the records' one less", records_len_at, n - 40 - 1),
    ] {
        let mut damaged = bytes.to_vec();
        damaged[field_at..field_at + 8].copy_from_slice(&value.to_le_bytes());
        let log = read(&damaged, what);
        assert_eq!(log.damage.len(), 1, "{what}: {:?}", log.damage);
        let d = &log.damage[0];
        assert_eq!(
            (d.offset, d.resumed_at, d.cut),
            (start, Some(next.0), false),
            "{what}: {d:?}"
        );
        assert!(!log.truncated, "{what}");
        let missing: Vec<_> = whole
            .ticks
            .iter()
            .filter(|t| !log.ticks.contains(t))
            .collect();
        assert_eq!(missing.len(), lost_here, "{what}");
        assert!(missing.iter().all(|t| in_chunk(t.input.t_s)), "{what}");
        assert_eq!(log.header, whole.header, "{what}");
    }
}

/// Damage after the data (in the summary, the footer, the closing magic) loses nothing; it is
/// told, and only a cut magic marks the log as cut.
#[test]
fn damage_after_the_data_loses_nothing() {
    let bytes = reference_log();
    let whole = read(bytes, "intact");
    let recs = records(bytes);
    let data_end = recs.iter().find(|r| r.1 == 0x0f).unwrap().0;
    let mut damaged = bytes.to_vec();
    for p in data_end..bytes.len() as u64 {
        damaged[p as usize] ^= 0x01;
        let case = format!("byte {p}");
        let log = read(&damaged, &case);
        damaged[p as usize] ^= 0x01;
        assert_whole(&log, &whole, &case);
        assert!(log.damage.len() <= 1, "{case}: {:?}", log.damage);
        assert!(
            log.damage.iter().all(|d| !d.cut),
            "{case}: {:?}",
            log.damage
        );
    }
}

/// Two faults at the start: the `/servo/tick` schema's name damaged in its first copy, and the
/// first chunk (the second copy) damaged too. A finished log's summary, checked against the
/// footer's CRC, still names the schema: read whole. The same damage in a log cut before its
/// summary leaves only the damaged name, and the log is refused rather than misread.
#[test]
fn a_finished_logs_summary_names_what_its_damaged_start_does_not() {
    let bytes = reference_log();
    let whole = read(bytes, "intact");
    let recs = records(bytes);
    let name = b"dronecine/msg/ServoTick";
    let schema = bytes.windows(name.len()).position(|w| w == name).unwrap();
    let scene = recs.iter().find(|r| r.1 == 0x06).unwrap();
    let mut damaged = bytes.to_vec();
    damaged[schema + name.len() - 1] ^= 0x01;
    damaged[(scene.0 + scene.2 / 2) as usize] ^= 0x01;
    let log = read(&damaged, "both copies");
    assert_eq!(log.ticks, whole.ticks);
    assert_eq!(log.key_frames, whole.key_frames);
    let data_end = recs.iter().find(|r| r.1 == 0x0f).unwrap().0 as usize;
    match FlightLog::from_bytes(Path::new("cut.mcap"), &damaged[..data_end]) {
        Err(LogError::BadMessage { topic, detail, .. }) => {
            assert_eq!(topic, "/servo/tick");
            assert!(detail.contains("ServoTicj"), "{detail}");
        }
        other => panic!("{other:?}"),
    }
}
