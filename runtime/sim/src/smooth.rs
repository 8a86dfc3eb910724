//! Smooth random processes: an Ornstein–Uhlenbeck process sampled exactly at knots and
//! interpolated between them by a Catmull–Rom spline, so the path is continuous with a
//! continuous derivative (wind gusts and actors' deviations have no steps), and can be read
//! at any time without drawing a number per read.
//!
//! Knot `j` sits at `j·spacing`, `spacing = τ/k` (k knots per correlation time, the caller's
//! choice: it sets how much of the OU's rough high-frequency tail the path keeps — the path's
//! RMS rate grows about as √k and its RMS acceleration about as k^1.5, while σ and τ stay);
//! knot values follow the OU recursion
//! `x[j+1] = a·x[j] + σ·√(1 − a²)·N(0, 1)` with `a = exp(−spacing/τ)`, started from the
//! stationary law N(0, σ²). An optional bound `b` clamps the knots the spline goes through
//! to ±b/1.25 (the OU recursion itself runs unclamped): a uniform Catmull–Rom segment is a
//! weighted sum of four knots whose absolute weights add up to at most 1.25, so the path
//! stays within ±b and stays smooth. Each process owns its random stream, so its path is a function of
//! the seed alone, however often and whenever it is read. Reads must not go back in time by
//! more than one knot spacing (the simulator reads forward only).

use super::rng::{Rng, Ziggurat};
use dronecine_math as math;

#[derive(Clone, Debug)]
pub struct SmoothOu {
    rng: Rng,
    a: f64,
    s: f64,
    spacing_s: f64,
    inv_spacing: f64,
    /// Index of the knot at the start of the current segment, the segment's start and end.
    j: u64,
    start_s: f64,
    end_s: f64,
    /// The segment's cubic in u ∈ [0, 1): `c[0] + u·(c[1] + u·(c[2] + u·c[3]))`.
    c: [f64; 4],
    /// Knots j−1, j, j+1, j+2 as the spline uses them (clamped).
    knots: [f64; 4],
    /// The OU state at knot j+2 (unclamped).
    state: f64,
    knot_max: f64,
    active: bool,
}

impl SmoothOu {
    /// σ (stationary standard deviation), τ (correlation time, > 0), the bound on the path
    /// (`f64::INFINITY` for none) and the knots per correlation time (> 0; 8 keeps the OU's
    /// spectrum up to about 8/τ, as wind turbulence has it; 2 gives a drift that changes on
    /// the scale of τ). σ = 0 gives the zero process and draws nothing.
    pub fn new(
        rng: Rng,
        sigma: f64,
        tau_s: f64,
        bound: f64,
        knots_per_tau: f64,
        z: &Ziggurat,
    ) -> SmoothOu {
        let spacing_s = tau_s / knots_per_tau;
        let a = math::exp(-spacing_s / tau_s);
        let s = sigma * (1.0 - a * a).sqrt();
        let mut p = SmoothOu {
            rng,
            a,
            s,
            spacing_s,
            inv_spacing: 1.0 / spacing_s,
            j: 0,
            start_s: 0.0,
            end_s: spacing_s,
            c: [0.0; 4],
            knots: [0.0; 4],
            state: 0.0,
            knot_max: bound / 1.25,
            active: sigma > 0.0 && bound > 0.0,
        };
        if p.active {
            p.state = sigma * p.rng.normal(z);
            p.knots[0] = p.state.clamp(-p.knot_max, p.knot_max);
            for i in 1..4 {
                p.knots[i] = p.next_knot(z);
            }
            p.coefficients();
        }
        p
    }

    /// The uniform Catmull–Rom cubic through knots 1 and 2 of the window.
    fn coefficients(&mut self) {
        let [p0, p1, p2, p3] = self.knots;
        self.c = [
            p1,
            0.5 * (p2 - p0),
            0.5 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3),
            0.5 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3),
        ];
    }

    #[inline]
    fn next_knot(&mut self, z: &Ziggurat) -> f64 {
        self.state = self.a * self.state + self.s * self.rng.normal(z);
        self.state.clamp(-self.knot_max, self.knot_max)
    }

    /// Moves the window forward to the segment holding `t_s`; returns u ∈ [0, 1).
    #[inline]
    fn advance(&mut self, t_s: f64, z: &Ziggurat) -> f64 {
        if t_s >= self.end_s {
            while t_s >= self.end_s {
                let next = self.next_knot(z);
                self.knots = [self.knots[1], self.knots[2], self.knots[3], next];
                self.j += 1;
                self.end_s = (self.j + 1) as f64 * self.spacing_s;
            }
            self.start_s = self.j as f64 * self.spacing_s;
            self.coefficients();
        }
        ((t_s - self.start_s) * self.inv_spacing).max(0.0)
    }

    /// The value at `t_s` (≥ 0).
    #[inline]
    pub fn value(&mut self, t_s: f64, z: &Ziggurat) -> f64 {
        if !self.active {
            return 0.0;
        }
        let u = self.advance(t_s, z);
        let c = &self.c;
        c[0] + u * (c[1] + u * (c[2] + u * c[3]))
    }

    /// The value and its time derivative at `t_s` (≥ 0).
    #[inline]
    pub fn value_rate(&mut self, t_s: f64, z: &Ziggurat) -> (f64, f64) {
        if !self.active {
            return (0.0, 0.0);
        }
        let u = self.advance(t_s, z);
        let c = &self.c;
        let value = c[0] + u * (c[1] + u * (c[2] + u * c[3]));
        let rate = (c[1] + u * (2.0 * c[2] + 3.0 * u * c[3])) * self.inv_spacing;
        (value, rate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_is_continuous_with_its_derivative_and_has_the_ou_spread() {
        let z = Ziggurat::get();
        let (sigma, tau) = (0.3, 2.0);
        // Spread: 4000 s = 2000 τ, read every 10 ms.
        let mut p = SmoothOu::new(Rng::stream(5, 9), sigma, tau, f64::INFINITY, 8.0, z);
        let n = 400_000;
        let sum2: f64 = (0..n).map(|k| p.value(k as f64 * 0.01, z).powi(2)).sum();
        let sd = (sum2 / n as f64).sqrt();
        assert!((sd - sigma).abs() < 0.1 * sigma, "sd {sd}");
        // Continuity and the derivative: read every 0.1 ms for 40 s (160 knots).
        let mut p = SmoothOu::new(Rng::stream(5, 10), sigma, tau, f64::INFINITY, 8.0, z);
        let dt = 1e-4;
        let (mut prev, mut prev_rate) = p.value_rate(0.0, z);
        let mut max_step: f64 = 0.0;
        let mut max_rate: f64 = 0.0;
        let mut max_rate_err: f64 = 0.0;
        for k in 1..400_000 {
            let (x, rate) = p.value_rate(k as f64 * dt, z);
            max_step = max_step.max((x - prev).abs());
            max_rate = max_rate.max(rate.abs());
            // The slope over the interval is the mean of the end rates (trapezoid): the rate
            // is the path's derivative, with no kink at the knots.
            max_rate_err = max_rate_err.max(((x - prev) / dt - 0.5 * (rate + prev_rate)).abs());
            prev = x;
            prev_rate = rate;
        }
        assert!(max_step < 1e-3 * sigma, "largest step {max_step}");
        assert!(
            max_rate_err < 1e-3 * max_rate,
            "slope mismatch {max_rate_err} of {max_rate}"
        );
    }

    #[test]
    fn the_path_depends_on_the_seed_only() {
        let z = Ziggurat::get();
        let mut a = SmoothOu::new(Rng::stream(1, 2), 1.0, 1.0, f64::INFINITY, 8.0, z);
        let mut b = SmoothOu::new(Rng::stream(1, 2), 1.0, 1.0, f64::INFINITY, 8.0, z);
        // a is read often, b rarely: same values at the common times.
        for k in 0..1000 {
            let va = a.value(k as f64 * 0.01, z);
            if k % 97 == 0 {
                assert_eq!(va.to_bits(), b.value(k as f64 * 0.01, z).to_bits());
            }
        }
    }

    #[test]
    fn a_bounded_path_stays_within_its_bound() {
        let z = Ziggurat::get();
        // σ twice the bound: the knots clamp often.
        let mut p = SmoothOu::new(Rng::stream(3, 3), 0.2, 1.0, 0.1, 8.0, z);
        let mut largest: f64 = 0.0;
        for k in 0..200_000 {
            largest = largest.max(p.value(k as f64 * 1e-3, z).abs());
        }
        assert!(largest <= 0.1 && largest > 0.07, "{largest}");
    }

    /// RMS value, rate and acceleration (rate differenced every 10 ms) over 4000 s.
    fn spread(knots_per_tau: f64) -> (f64, f64, f64) {
        let z = Ziggurat::get();
        let mut p = SmoothOu::new(
            Rng::stream(5, 11),
            0.06,
            2.5,
            f64::INFINITY,
            knots_per_tau,
            z,
        );
        let (dt, n) = (0.01, 400_000);
        let (mut x2, mut r2, mut a2) = (0.0, 0.0, 0.0);
        let mut prev = p.value_rate(0.0, z).1;
        for k in 1..=n {
            let (x, r) = p.value_rate(k as f64 * dt, z);
            x2 += x * x;
            r2 += r * r;
            a2 += ((r - prev) / dt).powi(2);
            prev = r;
        }
        let n = n as f64;
        ((x2 / n).sqrt(), (r2 / n).sqrt(), (a2 / n).sqrt())
    }

    #[test]
    fn knots_per_tau_set_the_roughness_not_the_spread() {
        // The actors' defaults (σ 6 cm, τ 2.5 s) at 2 and 8 knots per τ.
        let (sd2, rate2, acc2) = spread(2.0);
        let (sd8, rate8, acc8) = spread(8.0);
        // The spread stays σ (the spline through sparser knots averages a little more).
        for sd in [sd2, sd8] {
            assert!((sd - 0.06).abs() < 0.1 * 0.06, "sd {sd}");
        }
        // Rate ∝ √k and acceleration ∝ k^1.5 (4× the knots: 2× and 8×).
        assert!((rate8 / rate2 - 2.0).abs() < 0.3, "{rate8} / {rate2}");
        assert!((acc8 / acc2 - 8.0).abs() < 1.5, "{acc8} / {acc2}");
        // The actors' setting: a drift of a person shifting weight, not a fidget.
        assert!(acc2 < 0.12 && acc8 > 0.5, "{acc2}, {acc8}");
    }
}
