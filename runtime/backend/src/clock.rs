//! Clocks for the flight loop: [`WallClock`] for hardware, and [`Paced`], which makes a
//! simulated flight keep to the wall clock (`shoot --realtime`) while the simulator's own
//! clock still advances its world.

use std::time::{Duration, Instant};

use crate::Clock;

/// Seconds since creation on the monotonic clock; `sleep_until` sleeps.
pub struct WallClock {
    start: Instant,
}

impl WallClock {
    pub fn new() -> Self {
        Self::starting_at(Instant::now())
    }

    /// A clock that reads 0 at `start` (backends that timestamp on arrival share it).
    pub fn starting_at(start: Instant) -> Self {
        WallClock { start }
    }

    /// The instant this clock reads 0.
    pub fn epoch(&self) -> Instant {
        self.start
    }
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for WallClock {
    fn now_s(&mut self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn sleep_until(&mut self, t_s: f64) {
        let wait = t_s - self.now_s();
        if wait > 0.0 && wait.is_finite() {
            std::thread::sleep(Duration::from_secs_f64(wait));
        }
    }
}

/// A clock (the simulator's) held to the wall clock: `sleep_until(t)` first waits until `t`
/// seconds of wall time have passed since creation, then lets the inner clock advance.
pub struct Paced<C: Clock> {
    inner: C,
    wall: WallClock,
}

impl<C: Clock> Paced<C> {
    pub fn new(inner: C) -> Self {
        Paced {
            inner,
            wall: WallClock::new(),
        }
    }
}

impl<C: Clock> Clock for Paced<C> {
    fn now_s(&mut self) -> f64 {
        self.inner.now_s()
    }

    fn sleep_until(&mut self, t_s: f64) {
        self.wall.sleep_until(t_s);
        self.inner.sleep_until(t_s);
    }

    /// On the wall clock: the simulator's clock is where it was told to be, whenever that is.
    fn lateness_s(&mut self, t_s: f64) -> f64 {
        self.wall.now_s() - t_s
    }
}

/// Waits on the wall clock until `done` holds (`Ok(true)`) or `timeout` passes (`Ok(false)`),
/// looking every `poll` and calling `tick` between looks (a backend's keep-alive, say); the
/// first error `tick` returns ends the wait.
pub fn wait_until<E>(
    timeout: Duration,
    poll: Duration,
    mut tick: impl FnMut() -> Result<(), E>,
    mut done: impl FnMut() -> bool,
) -> Result<bool, E> {
    let deadline = Instant::now() + timeout;
    loop {
        if done() {
            return Ok(true);
        }
        if Instant::now() >= deadline {
            return Ok(false);
        }
        tick()?;
        std::thread::sleep(poll);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Manual(f64);
    impl Clock for Manual {
        fn now_s(&mut self) -> f64 {
            self.0
        }
        fn sleep_until(&mut self, t_s: f64) {
            self.0 = self.0.max(t_s);
        }
    }

    #[test]
    fn paced_keeps_to_the_wall_and_advances_the_inner_clock() {
        let mut c = Paced::new(Manual(0.0));
        let t0 = Instant::now();
        c.sleep_until(0.03);
        assert!(t0.elapsed() >= Duration::from_millis(29));
        assert_eq!(c.now_s(), 0.03);
    }

    /// The paced clock's lateness is the wall's: a tick that returns late on the wall is late
    /// by that much, though the simulator's clock reads the tick's time.
    #[test]
    fn paced_lateness_is_on_the_wall_clock() {
        let mut c = Paced::new(Manual(0.0));
        c.sleep_until(0.01);
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(c.now_s(), 0.01);
        assert!(c.lateness_s(0.01) >= 0.019, "{}", c.lateness_s(0.01));
        assert_eq!(Manual(0.5).lateness_s(0.25), 0.25);
    }

    #[test]
    fn wall_clock_is_monotonic() {
        let mut c = WallClock::new();
        let a = c.now_s();
        c.sleep_until(a + 0.002);
        assert!(c.now_s() >= a + 0.002);
        // In the past or NaN: returns at once.
        c.sleep_until(f64::NAN);
        c.sleep_until(-1.0);
    }

    #[test]
    fn wait_until_ends_when_done_times_out_or_fails() {
        let ticks = std::cell::Cell::new(0);
        let got: Result<bool, ()> = wait_until(
            Duration::from_secs(5),
            Duration::from_millis(1),
            || {
                ticks.set(ticks.get() + 1);
                Ok(())
            },
            || ticks.get() == 3,
        );
        assert_eq!(got, Ok(true));
        assert_eq!(ticks.get(), 3);
        let start = Instant::now();
        let got: Result<bool, ()> = wait_until(
            Duration::from_millis(20),
            Duration::from_millis(1),
            || Ok(()),
            || false,
        );
        assert_eq!(got, Ok(false));
        assert!(start.elapsed() >= Duration::from_millis(20));
        let got = wait_until(
            Duration::from_secs(5),
            Duration::from_millis(1),
            || Err("gone"),
            || false,
        );
        assert_eq!(got, Err("gone"));
    }
}
