//! Whole flights on the embedded simulator: the flight loop's phases and failsafes, the
//! director ahead, allocation, replay, random scenes, calibration and the paper's experiments.

mod ahead;
mod alloc_flight;
mod calibrate;
mod common;
mod crazyflie;
mod experiments;
mod flight;
mod random_flights;
mod replay;
