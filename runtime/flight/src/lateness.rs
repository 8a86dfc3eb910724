//! How late the flight loop's ticks ran: each tick's lateness (the time it ran past its due
//! time) counted in a histogram fixed at the start, so that counting allocates nothing; the
//! median, the 99th percentile and the maximum for the report.

use serde::Serialize;

/// Bins per decade of lateness, from [`FLOOR_S`] up: a percentile is known to within
/// 10^(1/64) ≈ 3.7 %.
const PER_DECADE: usize = 64;
/// Below this a tick counts as on time (the first bin).
const FLOOR_S: f64 = 1e-6;
/// Decades counted above [`FLOOR_S`] (up to 10 s; later ticks count in the last bin).
const DECADES: usize = 7;
const BINS: usize = 1 + PER_DECADE * DECADES;

/// The lateness of every tick of a flight.
pub struct LatenessHistogram {
    counts: Box<[u32; BINS]>,
    ticks: u64,
    max_s: f64,
}

/// What a flight's report says of its ticks' lateness.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lateness {
    pub ticks: u64,
    pub p50_s: f64,
    pub p99_s: f64,
    pub max_s: f64,
}

impl Default for LatenessHistogram {
    fn default() -> Self {
        LatenessHistogram {
            counts: Box::new([0; BINS]),
            ticks: 0,
            max_s: 0.0,
        }
    }
}

impl LatenessHistogram {
    /// Counts one tick that ran `late_s` after its due time.
    pub fn add(&mut self, late_s: f64) {
        let late_s = if late_s.is_finite() {
            late_s.max(0.0)
        } else {
            0.0
        };
        self.counts[bin(late_s)] += 1;
        self.ticks += 1;
        self.max_s = self.max_s.max(late_s);
    }

    /// The median, the 99th percentile (each the upper edge of its bin, at most the maximum)
    /// and the maximum; `None` before any tick.
    pub fn summary(&self) -> Option<Lateness> {
        (self.ticks > 0).then(|| Lateness {
            ticks: self.ticks,
            p50_s: self.percentile(0.50),
            p99_s: self.percentile(0.99),
            max_s: self.max_s,
        })
    }

    fn percentile(&self, p: f64) -> f64 {
        let rank = (p * self.ticks as f64).ceil().max(1.0) as u64;
        let mut seen = 0u64;
        for (i, &n) in self.counts.iter().enumerate() {
            seen += u64::from(n);
            if seen >= rank {
                return upper_edge_s(i).min(self.max_s);
            }
        }
        self.max_s
    }
}

/// The bin of a lateness (≥ 0).
fn bin(late_s: f64) -> usize {
    if late_s < FLOOR_S {
        return 0;
    }
    let decades = dronecine_math::log10(late_s / FLOOR_S);
    (1 + (decades * PER_DECADE as f64) as usize).min(BINS - 1)
}

/// The largest lateness bin `i` holds.
fn upper_edge_s(i: usize) -> f64 {
    if i == 0 {
        return FLOOR_S;
    }
    FLOOR_S * dronecine_math::powf(10.0, i as f64 / PER_DECADE as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 990 ticks 0.1 ms late and 10 at 5 ms: the median is 0.1 ms and the 99th percentile
    /// too, within a bin; the maximum is exact. One more at 5 ms moves the 99th percentile.
    #[test]
    fn percentiles_land_within_a_bin_of_the_truth() {
        let mut h = LatenessHistogram::default();
        assert_eq!(h.summary(), None);
        for _ in 0..990 {
            h.add(1e-4);
        }
        for _ in 0..10 {
            h.add(5e-3);
        }
        let s = h.summary().unwrap();
        let within = |got: f64, want: f64| got >= want && got <= want * 1.04;
        assert_eq!(s.ticks, 1000);
        assert!(within(s.p50_s, 1e-4), "{s:?}");
        assert!(within(s.p99_s, 1e-4), "{s:?}");
        assert_eq!(s.max_s, 5e-3);
        h.add(5e-3);
        let s = h.summary().unwrap();
        assert!(within(s.p99_s, 5e-3) || s.p99_s == 5e-3, "{s:?}");
    }

    /// On time, early (a clock that returned before the due time), not a number, and later
    /// than the histogram's range all count without a panic.
    #[test]
    fn any_lateness_counts() {
        let mut h = LatenessHistogram::default();
        for x in [0.0, -1.0, f64::NAN, f64::INFINITY, 100.0, 1e-7] {
            h.add(x);
        }
        let s = h.summary().unwrap();
        assert_eq!(s.ticks, 6);
        assert_eq!(s.max_s, 100.0);
        assert!(s.p50_s <= FLOOR_S, "{s:?}");
    }
}
