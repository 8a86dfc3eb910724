//! [`LiveFeed`]: the flight loop's side of the live view, a [`FlightSink`] that never waits.
//!
//! Each tick the loop takes an emptied slot from a pool ([`SLOTS`] of them, allocated up
//! front), copies the tick in ([`OwnedTick::fill`]: no allocation) and hands it to the live
//! thread; both hand-overs are `try_` calls on bounded channels. When the pool is empty (the
//! live thread, at a lower priority, has fallen [`SLOTS`] ticks behind) the tick is dropped and
//! counted: the loop never waits for the live view. Events go the same way (a full queue drops
//! and counts them). A key frame the log asked for rides with the next tick.
//!
//! The live thread polls (sleeping [`POLL_MIN`], doubling up to [`POLL_MAX`] while nothing
//! comes) rather than block on the channel: a blocked receiver would make every hand-over a
//! system call to wake it, on the loop's thread. It writes each tick with [`FlightTopics`], the
//! log's own schedule and encoders, to the server's channels, and gives the slot back.
//!
//! The loop tells the feed how late each tick ran ([`FlightSink::tick_lateness`]); the feed
//! counts it in one of two histograms, a client connected or not, for the report.

use std::io;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TryRecvError, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use dronecine_flight::lateness::{Lateness, LatenessHistogram};
use dronecine_mcap::log::{FlightTopics, LogOptions, LogScene, OwnedTick};
use dronecine_mcap::record::{Event, FlightSink, TickRecord};
use dronecine_servo::control::ControllerState;

use crate::server::{LiveOut, LiveServer, Shared};

/// Ticks in flight between the loop and the live thread (2.5 s at 100 Hz): the live thread
/// may fall this far behind before a tick is dropped.
pub const SLOTS: usize = 256;
/// Events queued besides the ticks.
const EVENTS: usize = 64;
/// The live thread's first sleep when nothing is queued…
const POLL_MIN: Duration = Duration::from_micros(250);
/// …doubled while nothing comes, up to this: how long a tick may wait to be served.
pub const POLL_MAX: Duration = Duration::from_millis(4);

/// A tick on its way to the live thread, with the key frame that comes before it.
struct Slot {
    key_frame: Option<ControllerState>,
    tick: OwnedTick,
}

enum Item {
    Tick(Box<Slot>),
    Event(Event),
}

/// Counted by the live thread.
#[derive(Default)]
struct Served {
    ticks: AtomicU64,
}

/// What the live view did over a flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveSummary {
    /// Ticks written to the server's channels.
    pub ticks_served: u64,
    /// Ticks the loop dropped: the live thread was [`SLOTS`] behind.
    pub ticks_dropped: u64,
    /// Events dropped for a full queue.
    pub events_dropped: u64,
    /// Messages logged to the channels (those with a subscriber, and the latched ones).
    pub messages: u64,
    /// The most clients connected at once.
    pub clients_max: usize,
    /// The loop's lateness over the ticks that ran with a client connected…
    pub with_client: Option<Lateness>,
    /// …and over those without.
    pub without_client: Option<Lateness>,
}

/// The flight loop's side of the live view (see the module doc).
pub struct LiveFeed {
    items: Option<SyncSender<Item>>,
    slots: Receiver<Box<Slot>>,
    /// A slot the queue would not take (full of events), reused for the next tick.
    spare: Option<Box<Slot>>,
    key_frame: Option<ControllerState>,
    shared: Arc<Shared>,
    served: Arc<Served>,
    ticks_dropped: u64,
    events_dropped: u64,
    with_client: LatenessHistogram,
    without_client: LatenessHistogram,
    thread: Option<JoinHandle<u64>>,
}

impl LiveFeed {
    /// Registers the flight's topics on `server`, writes the static scene, and starts the
    /// live thread. `gimbal`: the profile has a camera gimbal (`/gimbal`).
    pub fn start(server: &LiveServer, scene: &LogScene, gimbal: bool) -> io::Result<LiveFeed> {
        let topics = FlightTopics::open(server.out(), scene, gimbal, LogOptions::default())?;
        let (items_tx, items_rx) = mpsc::sync_channel::<Item>(SLOTS + EVENTS);
        let (slots_tx, slots_rx) = mpsc::sync_channel::<Box<Slot>>(SLOTS);
        for _ in 0..SLOTS {
            let slot = Box::new(Slot {
                key_frame: None,
                tick: OwnedTick::empty(),
            });
            let _ = slots_tx.try_send(slot);
        }
        let served = Arc::new(Served::default());
        let counted = Arc::clone(&served);
        let thread = std::thread::Builder::new()
            .name("flight-live".into())
            .spawn(move || {
                dronecine_mcap::log::lower_priority();
                serve(topics, &items_rx, &slots_tx, &counted)
            })?;
        Ok(LiveFeed {
            items: Some(items_tx),
            slots: slots_rx,
            spare: None,
            key_frame: None,
            shared: Arc::clone(&server.shared),
            served,
            ticks_dropped: 0,
            events_dropped: 0,
            with_client: LatenessHistogram::default(),
            without_client: LatenessHistogram::default(),
            thread: Some(thread),
        })
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.shared.clients.load(Ordering::Relaxed)
    }

    /// Lets the live thread write what is queued, stops it, and says what the live view did.
    pub fn finish(mut self) -> LiveSummary {
        self.items = None;
        let messages = self.thread.take().map_or(0, |t| t.join().unwrap_or(0));
        LiveSummary {
            ticks_served: self.served.ticks.load(Ordering::Relaxed),
            ticks_dropped: self.ticks_dropped,
            events_dropped: self.events_dropped,
            messages,
            clients_max: self.shared.clients_max.load(Ordering::Relaxed),
            with_client: self.with_client.summary(),
            without_client: self.without_client.summary(),
        }
    }
}

impl Drop for LiveFeed {
    fn drop(&mut self) {
        self.items = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl FlightSink for LiveFeed {
    fn tick(&mut self, record: &TickRecord) -> io::Result<()> {
        let Some(items) = &self.items else {
            return Ok(());
        };
        let slot = match self.spare.take() {
            Some(s) => Some(s),
            None => self.slots.try_recv().ok(),
        };
        let Some(mut slot) = slot else {
            self.ticks_dropped += 1;
            // A key frame is the state after the tick before the one it rides with.
            self.key_frame = None;
            return Ok(());
        };
        slot.tick.fill(record);
        slot.key_frame = self.key_frame.take();
        match items.try_send(Item::Tick(slot)) {
            Ok(()) => {}
            Err(TrySendError::Full(Item::Tick(slot))) => {
                self.ticks_dropped += 1;
                self.spare = Some(slot);
            }
            // The live thread is gone (it cannot fail on its own): the view is over.
            Err(_) => self.items = None,
        }
        Ok(())
    }

    fn event(&mut self, event: &Event) -> io::Result<()> {
        if let Some(items) = &self.items {
            if items.try_send(Item::Event(event.clone())).is_err() {
                self.events_dropped += 1;
            }
        }
        Ok(())
    }

    fn key_frame(&mut self, state: &ControllerState) -> io::Result<()> {
        self.key_frame = Some(*state);
        Ok(())
    }

    fn tick_lateness(&mut self, late_s: f64) {
        if self.shared.clients.load(Ordering::Relaxed) > 0 {
            self.with_client.add(late_s);
        } else {
            self.without_client.add(late_s);
        }
    }
}

/// The live thread: writes each tick and event as it comes, gives each slot back; returns
/// the messages logged once the loop's side is gone.
fn serve(
    mut topics: FlightTopics<LiveOut>,
    items: &Receiver<Item>,
    slots: &SyncSender<Box<Slot>>,
    served: &Served,
) -> u64 {
    let mut idle = POLL_MIN;
    loop {
        match items.try_recv() {
            Ok(Item::Tick(mut slot)) => {
                if let Some(state) = slot.key_frame.take() {
                    topics.set_key_frame(&state);
                }
                // The live channels cannot fail a write.
                let _ = topics.write_tick(&slot.tick.record());
                served.ticks.fetch_add(1, Ordering::Relaxed);
                let _ = slots.try_send(slot);
                idle = POLL_MIN;
            }
            Ok(Item::Event(e)) => {
                let _ = topics.write_event(&e);
                idle = POLL_MIN;
            }
            Err(TryRecvError::Empty) => {
                std::thread::sleep(idle);
                idle = (idle * 2).min(POLL_MAX);
            }
            Err(TryRecvError::Disconnected) => break,
        }
    }
    topics.out().messages
}

/// The log and the live view, both fed every tick: the log first (its error lands the
/// drone), then the live view, which never fails. The log decides the key frames.
pub struct Tee<'a> {
    pub log: &'a mut dyn FlightSink,
    pub live: &'a mut LiveFeed,
}

impl FlightSink for Tee<'_> {
    fn tick(&mut self, record: &TickRecord) -> io::Result<()> {
        let logged = self.log.tick(record);
        self.live.tick(record)?;
        logged
    }
    fn event(&mut self, event: &Event) -> io::Result<()> {
        let logged = self.log.event(event);
        self.live.event(event)?;
        logged
    }
    fn idle(&mut self, t_s: f64) -> io::Result<()> {
        self.log.idle(t_s)
    }
    fn wants_key_frame(&self) -> bool {
        self.log.wants_key_frame()
    }
    fn key_frame(&mut self, state: &ControllerState) -> io::Result<()> {
        let logged = self.log.key_frame(state);
        self.live.key_frame(state)?;
        logged
    }
    fn tick_lateness(&mut self, late_s: f64) {
        self.log.tick_lateness(late_s);
        self.live.tick_lateness(late_s);
    }
}
