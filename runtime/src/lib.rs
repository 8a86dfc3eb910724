//! The runtime: the LQG servo, the `Drone` and `Mocap` backends (embedded simulator,
//! AR.Drone 2.0, OptiTrack NatNet) and the flight loop behind `dronecine shoot`.
//!
//! Empty until issue 4; the crate exists so that the workspace has its final shape and the
//! dependency direction grammar → compiler → runtime is fixed from the start.
