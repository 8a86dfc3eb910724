//! The compiler: from a resolved PSL `Script` to the timed 6D reference a drone flies.
//!
//! Modules: `profile` (drone profiles), `camera` (lens, pose, projection, orientation: the
//! camera conventions), `reference` (the output samples), `size` (shot size → band →
//! distance), `sphere` and `toric` (the one- and two-actor manifolds), `framing` (composition →
//! visual parameters → camera placement).

pub mod blocking;
pub mod camera;
pub mod compile;
pub mod director;
pub mod feasibility;
pub mod framed_as;
pub mod framing;
pub mod math;
pub mod output;
pub mod paths;
pub mod preview;
pub mod profile;
pub mod reference;
pub mod route;
pub mod size;
pub mod sphere;
pub mod steering;
pub mod toml_text;
pub mod toric;

/// √(x² + y²) without libm's `hypot` (which guards against overflow at a cost the per-tick
/// code pays twenty times a sample): stage-sized lengths and speeds never come near it.
#[inline]
pub fn norm_xy(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}
