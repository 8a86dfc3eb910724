//! The compiler's tests: the manifolds and framings against their geometry, and steering that
//! follows any feasible minimum-jerk flight.

mod coverage;
mod manifold;
mod steering;
