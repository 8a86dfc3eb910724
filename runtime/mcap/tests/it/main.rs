//! The MCAP files' tests: the compiled reference's writers and the flight log, each read back
//! by the mcap crate's reader.

mod log;
mod output;
