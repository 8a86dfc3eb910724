//! The `dronecine` command, end to end: every subcommand as a user runs it, the diagnostics
//! corpus, the compiled shipped scripts, robustness against any input, and the architecture
//! the build enforces.

mod architecture;
mod calibrate;
mod cli;
mod common;
mod compile;
mod coverage;
mod diagnostics;
mod e2e;
mod explain;
mod fmt;
mod gains;
mod gimbal;
mod live;
mod robustness;
mod shoot;
mod shots;
#[cfg(unix)]
mod signals;
#[cfg(unix)]
mod sitl;
mod status;
mod status_mavlink;
mod storyboard;
