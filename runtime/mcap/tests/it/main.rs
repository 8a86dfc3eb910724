//! The MCAP files' tests: the compiled reference's writers and the flight log, each read back
//! by the mcap crate's reader, and the flight log's damage, each kind costing at most the
//! chunk it hits.

mod damage;
mod log;
mod output;
