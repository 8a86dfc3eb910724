//! An emulator's loop on a thread of its own, paced on the wall clock, and the handle that
//! reads the status the loop publishes and stops it. Shared by the AR.Drone and the
//! Crazyflie emulators.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::EmulatorError;

/// An emulator's loop, run every [`Paced::step_s`] of wall time on a thread of its own.
pub(crate) trait Paced {
    /// One step: drain the sockets, advance the world, send what is due.
    fn step(&mut self);
    fn step_s(&self) -> f64;
    /// Wall seconds since the loop started.
    fn now_s(&self) -> f64;
}

/// Refuses a loop step (wall clock) an emulator cannot keep: outside 0.1 to 50 ms.
pub(crate) fn check_step_s(step_s: f64) -> Result<(), EmulatorError> {
    if step_s.is_finite() && (1e-4..=0.05).contains(&step_s) {
        Ok(())
    } else {
        Err(EmulatorError::Config(format!(
            "the emulator's step {step_s} s is outside 0.1–50 ms"
        )))
    }
}

/// Runs `lp` until `stop` is set, step k at k·step_s; far behind (the process was
/// suspended), it skips ahead rather than spin.
fn run_paced(lp: &mut impl Paced, stop: &AtomicBool) {
    let step = lp.step_s();
    let mut k: u64 = 0;
    while !stop.load(Ordering::SeqCst) {
        lp.step();
        k += 1;
        let now = lp.now_s();
        let mut next = k as f64 * step;
        if next < now - 0.1 {
            k = (now / step).ceil() as u64;
            next = k as f64 * step;
        }
        let wait = next - now;
        if wait > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(wait));
        }
    }
}

/// Where a loop publishes its status `S` for the handle to read.
pub(crate) type Published<S> = Arc<Mutex<S>>;

/// A running loop that publishes `S`. Dropping it stops the loop and waits for it.
pub(crate) struct Running<S> {
    status: Published<S>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl<S: Clone + Default + Send + 'static> Running<S> {
    /// Starts the loop's thread: `make` builds the loop there (the simulator is not `Send`)
    /// with where it publishes, and the loop runs until stopped; `make`'s error comes back.
    pub(crate) fn spawn<L: Paced>(
        make: impl FnOnce(Published<S>) -> Result<L, EmulatorError> + Send + 'static,
    ) -> Result<Running<S>, EmulatorError> {
        let status = Arc::new(Mutex::new(S::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (ready_tx, ready_rx) = mpsc::channel();
        let (published, stopped) = (Arc::clone(&status), Arc::clone(&stop));
        let thread = std::thread::Builder::new()
            .name("dronecine-emulator".into())
            .spawn(move || match make(published) {
                Ok(mut lp) => {
                    let _ = ready_tx.send(Ok(()));
                    run_paced(&mut lp, &stopped);
                }
                Err(e) => {
                    let _ = ready_tx.send(Err(e));
                }
            })
            .map_err(|e| EmulatorError::Thread(e.to_string()))?;
        let mut running = Running {
            status,
            stop,
            thread: Some(thread),
        };
        let ready = ready_rx
            .recv()
            .unwrap_or_else(|_| Err(EmulatorError::Thread("it ended before starting".into())));
        match ready {
            Ok(()) => Ok(running),
            Err(e) => {
                let _ = running.join();
                Err(e)
            }
        }
    }

    /// What the loop published last (the default if it panicked while publishing).
    pub(crate) fn read<R: Default>(&self, f: impl FnOnce(&S) -> R) -> R {
        self.status.lock().map(|s| f(&s)).unwrap_or_default()
    }
}

impl<S> Running<S> {
    /// Whether the loop still runs.
    pub(crate) fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Stops the loop and waits for it.
    pub(crate) fn stop(&mut self) -> Result<(), EmulatorError> {
        self.stop.store(true, Ordering::SeqCst);
        self.join()
    }

    /// Waits until the loop ends.
    pub(crate) fn join(&mut self) -> Result<(), EmulatorError> {
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| EmulatorError::Thread("it panicked".into())),
            None => Ok(()),
        }
    }
}

impl<S> Drop for Running<S> {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}
