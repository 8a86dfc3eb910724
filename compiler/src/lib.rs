//! The compiler: from a resolved PSL `Script` to the timed 6D reference a drone flies.
//!
//! Issue 3 builds it (manifold keyframes, transitions, steering, feasibility, MCAP output).
//! Today it holds what the language front end already needs from it: the names of the
//! built-in drone profiles, so that `dronecine check` can reject `drone ardron2`.

pub mod profiles;
