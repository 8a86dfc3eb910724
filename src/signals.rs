//! The operator's signals, counted for the flight loop: Ctrl-C (SIGINT) lands the drone and a
//! second Ctrl-C cuts its motors; SIGTERM and SIGHUP (a stop asked by the system, a terminal or
//! an SSH connection lost) land it like one Ctrl-C, and never cut the motors.

use std::sync::atomic::{AtomicU32, Ordering};

/// Counts the operator's signals into `interrupts` from now on, on a thread of its own (the
/// flight loop reads the count every tick).
#[cfg(unix)]
pub fn count_interrupts(interrupts: &'static AtomicU32) -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                match signal {
                    SIGINT => interrupts.fetch_add(1, Ordering::SeqCst),
                    _ => interrupts.fetch_max(1, Ordering::SeqCst),
                };
            }
        })?;
    Ok(())
}

/// Counts Ctrl-C into `interrupts` from now on (where there are no Unix signals).
#[cfg(not(unix))]
pub fn count_interrupts(interrupts: &'static AtomicU32) -> std::io::Result<()> {
    ctrlc::set_handler(move || {
        interrupts.fetch_add(1, Ordering::SeqCst);
    })
    .map_err(std::io::Error::other)
}
