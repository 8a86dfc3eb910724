//! Printing that never panics. `println!` and `eprintln!` panic when their stream fails: a
//! pipe closed by its reader (`dronecine gains --json | head -1`), a full disk behind `>`, a
//! terminal that went away. In `shoot` that panic would end the flight. These macros write
//! instead and keep the first stdout error: a closed pipe is the reader's choice and is let
//! go, as other Unix tools do; any other failure is reported by `main` at exit (exit 1), so a
//! truncated output file is never taken for a whole one. Errors on stderr have nowhere to be
//! reported and are dropped.

use std::io;
use std::sync::OnceLock;

static STDOUT_FAILED: OnceLock<String> = OnceLock::new();

/// Keeps the first stdout error that is not a closed pipe.
pub fn stdout_result(result: io::Result<()>) {
    if let Err(e) = result {
        if e.kind() != io::ErrorKind::BrokenPipe {
            let _ = STDOUT_FAILED.set(e.to_string());
        }
    }
}

/// The first stdout error worth reporting, if any.
pub fn stdout_failure() -> Option<&'static str> {
    STDOUT_FAILED.get().map(String::as_str)
}

/// `print!` to stdout, without the panic.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::stdout_result({
            use std::io::Write as _;
            write!(std::io::stdout(), $($arg)*)
        })
    };
}

/// `println!` to stdout, without the panic.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::out::stdout_result({
            use std::io::Write as _;
            writeln!(std::io::stdout(), $($arg)*)
        })
    };
}

/// `eprint!`, without the panic.
macro_rules! err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stderr(), $($arg)*);
    }};
}

/// `eprintln!`, without the panic.
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
