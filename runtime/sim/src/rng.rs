//! The simulator's random numbers: a small seeded generator (xoshiro256++, seeded through
//! SplitMix64, Blackman & Vigna 2018) and normal deviates by the ziggurat method (Marsaglia &
//! Tsang 2000, in Doornik's 128-layer form, 2005).
//!
//! Every random process of the simulator draws from its own stream ([`Rng::stream`]), so a
//! process's draws do not depend on whether another process ran, was switched off, or was
//! looked at: turning one effect off leaves every other effect's draws as they were.

use dronecine_math as math;
use std::sync::OnceLock;

/// xoshiro256++: 256 bits of state, period 2²⁵⁶ − 1, a few ns per draw.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
}

fn splitmix64(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

const TWO_POW_M53: f64 = 1.0 / (1u64 << 53) as f64;

impl Rng {
    /// Stream `stream` of the run seeded by `seed`: the two are mixed through SplitMix64, so
    /// neighbouring seeds and streams give unrelated sequences.
    pub fn stream(seed: u64, stream: u64) -> Rng {
        let mut x = seed;
        let a = splitmix64(&mut x);
        let mut y = a ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03);
        let mut s = [0u64; 4];
        for v in &mut s {
            *v = splitmix64(&mut y);
        }
        if s == [0; 4] {
            s[0] = 1;
        }
        Rng { s }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * TWO_POW_M53
    }

    /// Uniform in (0, 1] (safe to take the logarithm of).
    #[inline]
    fn uniform_open(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * TWO_POW_M53
    }

    /// A standard normal deviate.
    #[inline]
    pub fn normal(&mut self, z: &Ziggurat) -> f64 {
        loop {
            let bits = self.next_u64();
            let i = (bits & 0x7F) as usize;
            // Bits 11..63 for the abscissa, disjoint from the layer's 7 low bits.
            let u = 2.0 * ((bits >> 11) as f64 * TWO_POW_M53) - 1.0;
            if u.abs() < z.r[i] {
                return u * z.x[i];
            }
            if i == 0 {
                return self.normal_tail(u < 0.0);
            }
            let x = u * z.x[i];
            let f0 = math::exp(-0.5 * (z.x[i] * z.x[i] - x * x));
            let f1 = math::exp(-0.5 * (z.x[i + 1] * z.x[i + 1] - x * x));
            if f1 + self.uniform() * (f0 - f1) < 1.0 {
                return x;
            }
        }
    }

    /// The tail beyond the base layer's edge R (Marsaglia 1964).
    #[cold]
    fn normal_tail(&mut self, negative: bool) -> f64 {
        loop {
            let x = math::ln(self.uniform_open()) / ZIG_R;
            let y = math::ln(self.uniform_open());
            if -2.0 * y >= x * x {
                return if negative { x - ZIG_R } else { ZIG_R - x };
            }
        }
    }
}

const ZIG_LAYERS: usize = 128;
/// Right edge of the base layer and the area of each layer (Doornik 2005, 128 layers).
const ZIG_R: f64 = 3.442_619_855_899;
const ZIG_V: f64 = 9.912_563_035_262_17e-3;

/// The ziggurat's layer edges `x` and the ratios `r[i] = x[i+1]/x[i]`.
#[derive(Debug)]
pub struct Ziggurat {
    x: [f64; ZIG_LAYERS + 1],
    r: [f64; ZIG_LAYERS],
}

impl Ziggurat {
    /// The tables, computed once per process.
    pub fn get() -> &'static Ziggurat {
        static TABLES: OnceLock<Ziggurat> = OnceLock::new();
        TABLES.get_or_init(|| {
            let mut x = [0.0; ZIG_LAYERS + 1];
            let mut r = [0.0; ZIG_LAYERS];
            let mut f = math::exp(-0.5 * ZIG_R * ZIG_R);
            x[0] = ZIG_V / f;
            x[1] = ZIG_R;
            for i in 2..ZIG_LAYERS {
                x[i] = (-2.0 * math::ln(ZIG_V / x[i - 1] + f)).sqrt();
                f = math::exp(-0.5 * x[i] * x[i]);
            }
            x[ZIG_LAYERS] = 0.0;
            for i in 0..ZIG_LAYERS {
                r[i] = x[i + 1] / x[i];
            }
            Ziggurat { x, r }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The deviates have the standard normal's moments and tails (the ziggurat's layers and
    /// its tail branch are both exercised by 2·10⁶ draws).
    #[test]
    fn normal_deviates_are_standard_normal() {
        let z = Ziggurat::get();
        let mut rng = Rng::stream(7, 3);
        let n = 2_000_000;
        let (mut s1, mut s2, mut s4) = (0.0, 0.0, 0.0);
        let (mut beyond2, mut beyond_r) = (0usize, 0usize);
        for _ in 0..n {
            let x = rng.normal(z);
            s1 += x;
            s2 += x * x;
            s4 += x * x * x * x;
            beyond2 += (x.abs() > 2.0) as usize;
            beyond_r += (x.abs() > ZIG_R) as usize;
        }
        let nf = n as f64;
        let (mean, var, kurt) = (s1 / nf, s2 / nf, s4 / nf);
        assert!(mean.abs() < 0.004, "mean {mean}");
        assert!((var - 1.0).abs() < 0.005, "variance {var}");
        assert!((kurt - 3.0).abs() < 0.03, "fourth moment {kurt}");
        // P(|x| > 2) = 0.04550; P(|x| > 3.4426) = 5.76e-4.
        let p2 = beyond2 as f64 / nf;
        assert!((p2 - 0.0455).abs() < 0.0008, "P(|x|>2) = {p2}");
        let pr = beyond_r as f64 / nf;
        assert!((pr - 5.76e-4).abs() < 1.0e-4, "P(|x|>R) = {pr}");
    }

    #[test]
    fn uniforms_fill_the_unit_interval_and_streams_differ() {
        let mut a = Rng::stream(1, 0);
        let mut b = Rng::stream(1, 1);
        let mut c = Rng::stream(2, 0);
        let n = 100_000;
        let mut mean = 0.0;
        for _ in 0..n {
            let u = a.uniform();
            assert!((0.0..1.0).contains(&u));
            mean += u;
        }
        assert!((mean / n as f64 - 0.5).abs() < 0.005);
        let x: Vec<u64> = (0..4).map(|_| b.next_u64()).collect();
        let y: Vec<u64> = (0..4).map(|_| c.next_u64()).collect();
        assert_ne!(x, y);
        let mut b2 = Rng::stream(1, 1);
        let x2: Vec<u64> = (0..4).map(|_| b2.next_u64()).collect();
        assert_eq!(x, x2);
    }
}
