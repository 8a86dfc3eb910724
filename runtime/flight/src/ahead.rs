//! The director stepped ahead of the flight's loop, on a thread of its own, when the motion
//! capture knows the actors' future ([`Mocap::actors_ahead`](dronecine_backend::Mocap): the
//! simulator's actors do not depend on the drone).
//!
//! During the shots the director needs only the script's clock and the tracked actors, and
//! the loop needs from it only what [`direct`] puts in a [`DirectedTick`]: the sample, where
//! the shots are on the script's clock, the held framing (the aim and the framing figures
//! from where the drone is), what it found this tick and the findings of a shot that ended.
//! So a second thread ([`Ahead`]) reads the actors' frames from the feed, tracks them as the
//! loop does and steps the director, tick after tick, filling batches of [`DirectedTick`]s
//! that the loop takes in order; the loop flies the drone meanwhile. The same [`direct`] runs
//! on the loop's thread when the mocap knows nothing ahead (hardware) or the simulator is
//! not asked to (the simulator's `SimConfig::actors_ahead`), so both fly the same flight to
//! the bit: `runtime/tests/it/ahead.rs` flies the shipped scripts and flights cut short both
//! ways and compares every tick's record and every event, `random_flights.rs` there the logs
//! of the random scenes that fly, byte for byte.
//!
//! The loop takes the actors of each tick's frame from the director's tick ([`FeedFrame`]: the
//! feed's frames are the mocap's, so the simulator need not compute its actors a second time;
//! `Mocap::actors_from_feed`), and its tracked actors too (the director's tracker folded the
//! same frames in: the loop's becomes it rather than folding them in again). It checks each
//! tick against its own: the frame the mocap gave the loop and the director's tick time must
//! be the director's, bit for bit, or the loop lands the drone (a failsafe that says so; it
//! would be a bug). A flight cut short mid-shot (a failsafe) tells that
//! shot's findings as the director had them at that tick, not as the thread, ticks ahead,
//! has them: [`Ahead::rewound`] steps a copy taken at "action!" to that tick, on the loop's
//! thread (once per flight, only when it is cut short).
//!
//! Batches of [`BATCH_TICKS`] go back and forth over two bounded channels, as the flight
//! log's do (`dronecine_mcap::log::LogThread`); their vectors are reused, so neither thread
//! allocates per tick once the batches have grown (a tick with a finding allocates its
//! messages, as on the loop's thread). The `flight` bench measures the hour both ways
//! (`docs/benchmarks.md`).

use std::sync::mpsc::{self, Receiver, SyncSender};
use std::thread::JoinHandle;
use std::time::Duration;

use dronecine_compiler::director::{Director, Held};
use dronecine_compiler::reference::Sample;
use dronecine_diag::Diagnostic;

use crate::tracker::{take_newer, ActorTracker};
use dronecine_backend::{ActorFeed, BodyPose, MocapFrame};
use dronecine_compiler::reference::ActorPose;

/// Ticks per batch: 2.56 s of flight at 100 Hz.
const BATCH_TICKS: usize = 256;
/// Batches the thread may fill ahead of the loop.
const BATCHES: usize = 4;

/// One tick of the director, as the loop uses it.
#[derive(Clone, Debug, Default)]
pub(crate) struct DirectedTick {
    /// The flight clock's time of the tick.
    pub t_s: f64,
    pub sample: Sample,
    /// [`Director::written_t_s`] of the tick.
    pub written_t_s: f64,
    /// [`Director::finished`] after the tick.
    pub finished: bool,
    /// [`Director::held`] after the tick.
    pub held: Option<Held>,
    /// What the director found this tick ([`Director::diagnostics_so_far`], the new ones).
    pub diagnostics: Vec<Diagnostic>,
    /// When this tick's shot is another than the last tick's: the monitor's findings over
    /// that one, now over ([`Director::shot_findings`]).
    pub over_findings: Vec<Diagnostic>,
    /// When the director finished this tick: the findings over the last shot.
    pub last_findings: Vec<Diagnostic>,
    /// On the director's thread: its tracker after this tick's frame, whose poses it stepped
    /// with (the loop's becomes it). Empty on the loop's thread.
    pub tracker: ActorTracker,
    /// On the director's thread: the frame the feed gave at this tick, if any (the loop
    /// takes its actors from it: [`Mocap::actors_from_feed`](dronecine_backend::Mocap)).
    pub feed: FeedFrame,
}

/// The actors' part of the frame the feed gave at a tick, as the loop takes it.
#[derive(Clone, Debug, Default)]
pub(crate) struct FeedFrame {
    /// Whether the feed gave a frame at this tick (then the rest is that frame's).
    pub polled: bool,
    pub frame: u64,
    pub t_s: f64,
    pub actors: Vec<Option<BodyPose>>,
}

impl FeedFrame {
    /// Puts this tick's actors into the frame the loop `polled` (if it did): true when the
    /// loop's poll and the feed's agree (both gave the same frame, or neither a frame).
    pub(crate) fn fill(&self, polled: bool, frame: &mut MocapFrame) -> bool {
        if polled != self.polled {
            return false;
        }
        if !polled {
            return true;
        }
        if frame.frame != self.frame || frame.t_s.to_bits() != self.t_s.to_bits() {
            return false;
        }
        frame.actors.clone_from(&self.actors);
        true
    }
}

/// What [`direct`] keeps from tick to tick besides the director.
#[derive(Clone, Debug, Default)]
pub(crate) struct Directing {
    /// The director's diagnostics already handed on.
    told: usize,
    /// The shot of the last tick.
    current: Option<usize>,
}

/// Steps `director` at script time `script_t_s` with the tracked `actors` and writes what the
/// loop needs of the tick into `out` (its vectors reused). The one place that says what a
/// directed tick is, for both threads.
pub(crate) fn direct(
    director: &mut Director,
    state: &mut Directing,
    t_s: f64,
    script_t_s: f64,
    actors: &[ActorPose],
    out: &mut DirectedTick,
) {
    let sample = director.step(script_t_s, actors);
    out.t_s = t_s;
    out.sample = sample;
    out.written_t_s = director.written_t_s(script_t_s);
    out.finished = director.finished();
    out.held = director.held();
    out.diagnostics.clear();
    let found = director.diagnostics_so_far();
    if let Some(new) = found.get(state.told..) {
        out.diagnostics.extend_from_slice(new);
    }
    state.told = found.len();
    out.over_findings.clear();
    if state.current != Some(sample.shot) {
        if let Some(over) = state.current.replace(sample.shot) {
            out.over_findings = director.shot_findings(over);
        }
    }
    out.last_findings.clear();
    if out.finished {
        out.last_findings = director.shot_findings(sample.shot);
    }
}

/// The director's side of a flight ahead: the actors' feed, the tracker, the director, and
/// the flight's clock, as the loop has them at "action!".
#[derive(Clone)]
struct Side {
    director: Director,
    directing: Directing,
    tracker: ActorTracker,
    frame: MocapFrame,
    last_frame_t_s: Option<f64>,
    /// The last tick's time on the flight clock, and "action!"'s.
    t_s: f64,
    action_s: f64,
    period_s: f64,
}

impl Side {
    /// The next tick, as the loop will have it: its clock one period on, the frame the mocap
    /// gives then, the tracker and the director stepped.
    fn tick(&mut self, feed: &mut dyn ActorFeed, out: &mut DirectedTick) {
        self.t_s += self.period_s;
        let t = self.t_s;
        let polled = feed.poll_at(t, &mut self.frame);
        out.feed.polled = polled;
        if polled {
            out.feed.frame = self.frame.frame;
            out.feed.t_s = self.frame.t_s;
            out.feed.actors.clone_from(&self.frame.actors);
            if take_newer(&mut self.last_frame_t_s, &self.frame) {
                self.tracker.update(&self.frame);
            }
        }
        let script_t = t - self.action_s;
        let actors = &self.tracker.poses;
        direct(
            &mut self.director,
            &mut self.directing,
            t,
            script_t,
            actors,
            out,
        );
        out.tracker.copy_from(&self.tracker);
    }
}

/// std's channels allocate the first time a thread blocks on one (the thread's waiter, once
/// per thread) and the first time a receiver waits on a given channel (its list of waiting
/// receivers). The loop blocks when it catches up with the director, which happens only on
/// a loaded machine: it blocks here once, for 20 µs, on the channel it will read, before the
/// thread that fills it exists (nothing can arrive), so that its first wait mid-flight
/// allocates nothing. (Warming the waiter on another channel left the list's allocation to
/// the first wait: the alloc test failed once under the whole suite's load.)
fn warm_waiter<T>(rx: &Receiver<T>) {
    let _ = rx.recv_timeout(Duration::from_micros(20));
}

/// The director stepping ahead of the loop on its own thread.
pub(crate) struct Ahead {
    full: Option<Receiver<Vec<DirectedTick>>>,
    empty: Option<SyncSender<Vec<DirectedTick>>>,
    thread: Option<JoinHandle<()>>,
    /// The batch being read, and the next tick in it.
    batch: Vec<DirectedTick>,
    next: usize,
    /// The director's side as at "action!", and a second feed from there, to rewind to a
    /// tick ([`Ahead::rewound`]).
    start: Side,
    rewind_feed: Box<dyn ActorFeed>,
    /// Ticks taken by the loop.
    taken: u64,
}

/// What the loop hands over at "action!" to step the director ahead.
pub(crate) struct AheadStart<'a> {
    pub director: Director,
    pub tracker: &'a ActorTracker,
    pub frame: &'a MocapFrame,
    pub last_frame_t_s: Option<f64>,
    /// The tick before the first shot tick, and "action!", on the flight clock.
    pub t_s: f64,
    pub action_s: f64,
    pub period_s: f64,
}

impl Ahead {
    /// Starts the thread with `feed`; `rewind_feed` is a second feed from the same moment.
    /// Gives the director back if the thread cannot be started (the loop then steps it
    /// itself).
    pub(crate) fn spawn(
        start: AheadStart,
        feed: Box<dyn ActorFeed>,
        rewind_feed: Box<dyn ActorFeed>,
    ) -> Result<Ahead, Box<Director>> {
        let side = Side {
            director: start.director,
            directing: Directing::default(),
            tracker: start.tracker.clone(),
            frame: start.frame.clone(),
            last_frame_t_s: start.last_frame_t_s,
            t_s: start.t_s,
            action_s: start.action_s,
            period_s: start.period_s,
        };
        let (full_tx, full_rx) = mpsc::sync_channel::<Vec<DirectedTick>>(BATCHES);
        warm_waiter(&full_rx);
        let (empty_tx, empty_rx) = mpsc::sync_channel::<Vec<DirectedTick>>(BATCHES + 1);
        for _ in 0..BATCHES {
            let _ = empty_tx.send(Vec::with_capacity(BATCH_TICKS));
        }
        let mut thread_side = side.clone();
        let mut feed = feed;
        let spawned = std::thread::Builder::new()
            .name("flight-director".into())
            .spawn(move || {
                // Each batch: up to BATCH_TICKS ticks, fewer at the last (the director
                // finished). Ends when the loop drops its ends of the channels.
                let mut done = false;
                while let Ok(mut batch) = empty_rx.recv() {
                    if done {
                        break;
                    }
                    let mut n = 0;
                    while n < BATCH_TICKS && !done {
                        if batch.len() <= n {
                            batch.push(DirectedTick::default());
                        }
                        thread_side.tick(feed.as_mut(), &mut batch[n]);
                        done = batch[n].finished;
                        n += 1;
                    }
                    batch.truncate(n);
                    if full_tx.send(batch).is_err() {
                        break;
                    }
                }
            });
        match spawned {
            Ok(thread) => Ok(Ahead {
                full: Some(full_rx),
                empty: Some(empty_tx),
                thread: Some(thread),
                batch: Vec::new(),
                next: 0,
                start: side,
                rewind_feed,
                taken: 0,
            }),
            Err(_) => Err(Box::new(side.director)),
        }
    }

    /// The next tick, in order; `None` if the thread is gone (it panicked: a bug) or the
    /// director finished before.
    pub(crate) fn next(&mut self) -> Option<&DirectedTick> {
        if self.next >= self.batch.len() {
            let full = self.full.as_ref()?;
            let batch = full.recv().ok()?;
            let spent = std::mem::replace(&mut self.batch, batch);
            if spent.capacity() > 0 {
                if let Some(empty) = &self.empty {
                    let _ = empty.send(spent);
                }
            }
            self.next = 0;
            if self.batch.is_empty() {
                return None;
            }
        }
        self.next += 1;
        self.taken += 1;
        self.batch.get(self.next - 1)
    }

    /// The director as it was after the last tick the loop took: the copy taken at
    /// "action!", stepped again to there on this thread (the thread's own is ahead). Stops
    /// the thread.
    pub(crate) fn rewound(mut self) -> Director {
        self.stop();
        let mut side = self.start.clone();
        let mut scratch = DirectedTick::default();
        for _ in 0..self.taken {
            side.tick(self.rewind_feed.as_mut(), &mut scratch);
        }
        side.director
    }

    fn stop(&mut self) {
        self.full = None;
        self.empty = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for Ahead {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(x: f64) -> Option<BodyPose> {
        Some(BodyPose {
            position_m: [x, 0.0, 0.0],
            heading_rad: 0.0,
        })
    }

    /// The loop's frame takes the director's actors only when both polls gave the same frame
    /// (its number and time, bit for bit); no frame on both sides agrees and changes nothing;
    /// any other case disagrees (the loop then lands) and leaves the loop's frame as it was.
    #[test]
    fn a_frame_takes_the_feeds_actors_only_when_the_polls_agree() {
        let feed = FeedFrame {
            polled: true,
            frame: 7,
            t_s: 0.07,
            actors: vec![body(1.0), None],
        };
        let mine = MocapFrame {
            t_s: 0.07,
            received_s: 0.07,
            frame: 7,
            drone: body(5.0),
            actors: vec![None, None],
        };
        let mut f = mine.clone();
        assert!(feed.fill(true, &mut f));
        assert_eq!(f.actors, feed.actors);
        assert_eq!(
            (f.frame, f.drone),
            (7, body(5.0)),
            "the drone is the loop's own"
        );

        for (polled, frame, t_s) in [(false, 7, 0.07), (true, 8, 0.07), (true, 7, 0.08)] {
            let mut f = MocapFrame {
                frame,
                t_s,
                ..mine.clone()
            };
            let before = f.clone();
            assert!(!feed.fill(polled, &mut f), "{polled} {frame} {t_s}");
            assert_eq!(f, before);
        }
        let none = FeedFrame::default();
        let mut f = mine.clone();
        assert!(none.fill(false, &mut f));
        assert!(
            !none.fill(true, &mut f),
            "the loop had a frame, the feed none"
        );
        assert_eq!(f, mine);
    }
}
