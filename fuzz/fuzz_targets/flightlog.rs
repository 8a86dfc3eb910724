//! Fuzz the flight-log reader on arbitrary files: `FlightLog::open` never panics, and what it
//! returns is consistent: the damage it met is in file order, each skip resumes after the
//! place it started, only the last entry may end the reading (and a log without its footer
//! has one that does), and each damage's tick index lies within the ticks read. Seed it with
//! real logs (`dronecine shoot … --log`), whole and damaged, so that it explores chunk framing
//! and the search for the next intact chunk.
#![no_main]

use std::io::Write;

use dronecine_mcap::log::FlightLog;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The reader takes a path: one file per process, rewritten for each input (in RAM when
    // /dev/shm exists).
    thread_local! {
        static PATH: std::path::PathBuf = {
            let dir = if std::path::Path::new("/dev/shm").is_dir() {
                std::path::PathBuf::from("/dev/shm")
            } else {
                std::env::temp_dir()
            };
            dir.join(format!("dronecine-fuzz-{}.mcap", std::process::id()))
        };
    }
    PATH.with(|path| {
        let mut f = std::fs::File::create(path).unwrap();
        f.write_all(data).unwrap();
        drop(f);
        let Ok(log) = FlightLog::open(path) else {
            return;
        };
        let mut last_offset = 0u64;
        for (i, d) in log.damage.iter().enumerate() {
            assert!(d.offset >= last_offset, "damage out of file order");
            assert!(d.tick <= log.ticks.len());
            match d.resumed_at {
                Some(p) => assert!(p > d.offset && p < data.len() as u64),
                None => assert_eq!(i, log.damage.len() - 1, "only the last damage ends it"),
            }
            last_offset = d.resumed_at.unwrap_or(d.offset);
        }
        // A log without its footer says where it ends (one with its footer may still have
        // a bad closing magic after it: an end that is not a cut).
        if log.truncated {
            assert!(log.damage.last().is_some_and(|d| d.resumed_at.is_none()));
        }
    });
});
