//! [`LogThread`]: the flight log written on a thread of its own, so that formatting and disk
//! writes never sit on the control loop (a disk that stalls does not stall the drone, and a
//! simulated flight uses the machine's second core).
//!
//! The loop copies each [`TickRecord`] into a preallocated batch ([`OwnedTick`], its vectors
//! reused from batch to batch: no allocation per tick) and hands a full batch to the writer
//! thread over a bounded channel; the writer thread writes it with [`FlightLogWriter`] and
//! sends the emptied batch back. Events, the ticks that record nothing (their time closes the
//! writer's chunks and hands batches over as ticks do) and key frames keep their place among
//! the ticks. The loop's side steps a copy of the writer's chunk schedule with the same
//! ticks: it knows, after a tick, that the writer starts a chunk there, and asks the loop for
//! the controller's state (the chunk's key frame) without waiting for the writer.
//!
//! The writer thread polls for full batches (sleeping 0.1 ms, doubling up to 20 ms while none
//! comes) instead of blocking on the channel: a blocked receiver makes every hand-over wake
//! it, a system call and a cross-core wake-up on the loop's thread. In a real-time flight the
//! writer wakes about 50 times a second and writes a batch at most 20 ms after it is full.
//!
//! For a log forced to the disk as it is written ([`LogOptions::durable`]: a flight paced by
//! the wall clock, or `shoot --sync-log`), a third thread, which mostly waits on the disk,
//! syncs the file's data (`sync_data`) when the writer thread asks it (waking it is a system
//! call: not one the loop makes): every two seconds of flight when two seconds of wall-clock
//! time have passed since the last sync (a flight in real time: every two seconds), and every
//! 32 s of flight whatever the clock says (a simulated flight, thousands of times faster
//! than real time). A power cut loses less, and the disk writes while the flight goes on, so
//! the final `fsync` has only the tail left. Syncing every two seconds of flight whatever the
//! clock says costs a simulated flight more than it saves; syncing only at the end costs more
//! too, not less: the dirty pages pile up until the kernel throttles the writer. A log left
//! to the OS, `shoot`'s for a simulated flight as fast as it goes, has neither the syncer nor
//! the final `fsync`: its writeback is the OS's, after the flight.
//!
//! Both threads lower their own scheduling priority ([`LOG_NICE`]): the loop comes first
//! when the machine's cores are all busy.
//!
//! The writer keeps the chunks it closes while more batches wait and hands them to the OS in
//! one write of up to [`HAND_OVER_BYTES`] ([`FlightLogWriter::defer_hand_over`]), or as soon
//! as no batch waits, before it sleeps. A flight in real time leaves it idle after every
//! batch, so each chunk reaches the OS as it closes; a simulated flight keeps it
//! busy, and the kernel's cost per byte falls with the write's size.
//!
//! What a crash may lose: a batch is handed over every [`BATCH_PERIOD_S`] of flight time and
//! the writer, polling, takes it up within [`POLL_MAX_S`] and closes a chunk every
//! `flush_period_s` (the caller's [`LogOptions`]), so a process that dies in a flight in real
//! time loses at most their sum; `shoot` uses 0.25 s + 0.02 s + 0.73 s. A flight faster than
//! real time may also have up to [`BATCHES`] batches waiting for the writer and up to
//! [`HAND_OVER_BYTES`] of closed chunks (about six seconds of flight) not yet written: the
//! last few milliseconds of the run, in wall-clock time. A panic of the
//! loop unwinds through [`Drop`], which hands the last batch over and waits for the writer. A
//! write error reaches the loop on the next tick after the writer met it (the loop then
//! lands), and [`LogThread::finish`] returns it. The loop learns of it from a flag it reads
//! each tick, not from the error channel: an empty channel's `try_recv` is a full memory
//! fence.
//!
//! [`LogOptions`]: super::LogOptions
//! [`LogOptions::durable`]: super::LogOptions::durable

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::writer::ChunkClock;
use super::FlightLogWriter;
use crate::record::FlightSink;
use crate::record::{Event, FramingRecord, GimbalRecord, Phase, TickRecord};
use dronecine_backend::frames::Command;
use dronecine_backend::{FlightState, MocapFrame};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_servo::control::{ControllerState, TickFault, TickInput, TickOutput};

/// Flight time covered by one batch at most.
pub const BATCH_PERIOD_S: f64 = 0.25;
/// Batches in flight: the loop waits only when the writer is this many batches behind
/// (eight seconds of flight: a disk that stalls for less never stalls the loop). A
/// simulated flight makes two seconds of flight in the writer's longest poll (20 ms), so
/// with a quarter of these the loop would wait for it; many more crowd the caches.
const BATCHES: usize = 32;
/// The file's data is synced to the disk (`sync_data`, on a third thread that mostly waits)
/// after every this many batches (two seconds of flight)…
const SYNC_EVERY_BATCHES: u64 = 8;
/// …once this much wall-clock time has passed since the last one…
const SYNC_PERIOD: Duration = Duration::from_secs(2);
/// …and after every this many batches whatever the clock says (32 s of flight).
const SYNC_ANYWAY_BATCHES: u64 = 128;
/// The writer thread's first sleep when no batch is waiting…
const POLL_MIN: Duration = Duration::from_micros(100);
/// …doubled while none comes, up to this: how long a full batch may wait for the writer.
pub const POLL_MAX_S: f64 = 0.02;
const POLL_MAX: Duration = Duration::from_micros((POLL_MAX_S * 1e6) as u64);
/// The writer thread keeps closed chunks until they reach this many bytes, or until it has no
/// batch waiting, and hands them to the OS in one write ([`FlightLogWriter::defer_hand_over`];
/// about six seconds of a simulated flight's log): fewer, larger writes cost the kernel less
/// per byte, and chunks kept up to this size still fit the second-level cache the writer and
/// the kernel read them from. The file is the same bytes.
const HAND_OVER_BYTES: usize = 512 << 10;
/// How much the log's threads lower their priority (nice value, Linux): when a third thread
/// (the syncer, the kernel's writeback) wants a core, the scheduler takes it from them rather
/// than from the loop. On set it keeps a slow disk's writer from delaying a tick.
const LOG_NICE: i32 = 10;
/// How long the loop sleeps between looks for an emptied batch when the writer holds them
/// all (it has fallen [`BATCHES`] behind). In a simulated flight with the director ahead the
/// writer, at `nice` +10, falls behind while the loop and the director have the cores, and
/// the loop waits for it about a thousand times an hour: each look that finds nothing is a
/// wake-up and a context switch, and a longer sleep lets the writer and the director work in
/// longer stretches. A sleep longer than the director's batches ahead last would leave both
/// threads waiting and a core idle; blocking on the channel would wake the loop at every
/// batch returned. On set the loop waits only when the disk has stalled for [`BATCHES`]
/// batches (eight seconds).
const WAIT_FOR_BATCH: Duration = Duration::from_micros(200);

/// A [`TickRecord`] with its borrowed parts copied, kept from batch to batch (and in the
/// live view's ring): filled again, it reuses its vectors' room.
#[derive(Clone, Debug)]
pub struct OwnedTick {
    phase: Phase,
    shot: Option<usize>,
    sample: Sample,
    input: TickInput,
    output: Result<TickOutput, TickFault>,
    command_sent: Command,
    has_mocap: bool,
    mocap: MocapFrame,
    actors: Vec<ActorPose>,
    framing: Vec<FramingRecord>,
    drone_state: FlightState,
    latency_s: Option<f64>,
    gimbal: Option<GimbalRecord>,
}

/// Room for this many actors in each preallocated tick (more grow a tick's vectors once).
const ACTORS: usize = 8;

impl OwnedTick {
    /// A blank tick with room for eight actors (more grow its vectors once).
    pub fn empty() -> OwnedTick {
        OwnedTick {
            phase: Phase::TakeOff,
            shot: None,
            sample: Sample::default(),
            input: TickInput::default(),
            output: Ok(TickOutput::default()),
            command_sent: Command::HOVER,
            has_mocap: false,
            mocap: MocapFrame {
                actors: Vec::with_capacity(ACTORS),
                ..MocapFrame::default()
            },
            actors: Vec::with_capacity(ACTORS),
            framing: Vec::with_capacity(ACTORS),
            drone_state: FlightState::Landed,
            latency_s: None,
            gimbal: None,
        }
    }

    /// Copies `r` in, reusing the vectors' room.
    pub fn fill(&mut self, r: &TickRecord) {
        self.phase = r.phase;
        self.shot = r.shot;
        self.sample = *r.sample;
        self.input = r.input;
        self.output = r.output;
        self.command_sent = r.command_sent;
        self.has_mocap = r.mocap.is_some();
        if let Some(m) = r.mocap {
            self.mocap.t_s = m.t_s;
            self.mocap.received_s = m.received_s;
            self.mocap.frame = m.frame;
            self.mocap.drone = m.drone;
            self.mocap.actors.clear();
            self.mocap.actors.extend_from_slice(&m.actors);
        }
        self.actors.clear();
        self.actors.extend_from_slice(r.actors);
        self.framing.clear();
        self.framing.extend_from_slice(r.framing);
        self.drone_state = r.drone_state;
        self.latency_s = r.latency_s;
        self.gimbal = r.gimbal;
    }

    /// Asks the cache for the lines that [`OwnedTick::fill`] will write with a record of
    /// `actors` actors: the tick itself and its vectors' first elements. The batch was last
    /// read by the writer's core; without this the loop would wait for each line in turn.
    fn prefetch(&self, actors: usize) {
        prefetch_for_write(self, std::mem::size_of::<OwnedTick>());
        prefetch_for_write(
            self.actors.as_ptr(),
            actors * std::mem::size_of::<ActorPose>(),
        );
        prefetch_for_write(
            self.mocap.actors.as_ptr(),
            actors * std::mem::size_of::<Option<dronecine_backend::BodyPose>>(),
        );
        prefetch_for_write(
            self.framing.as_ptr(),
            actors * std::mem::size_of::<FramingRecord>(),
        );
    }

    /// The tick as a record, borrowing its parts.
    pub fn record(&self) -> TickRecord<'_> {
        TickRecord {
            phase: self.phase,
            shot: self.shot,
            sample: &self.sample,
            input: self.input,
            output: self.output,
            command_sent: self.command_sent,
            mocap: self.has_mocap.then_some(&self.mocap),
            actors: &self.actors,
            framing: &self.framing,
            drone_state: self.drone_state,
            latency_s: self.latency_s,
            gimbal: self.gimbal,
        }
    }
}

/// A hint that the `bytes` from `start` are about to be written: their cache lines are
/// fetched, for writing, into this core's cache, so that the loop does not wait for them. A
/// no-op off x86-64.
#[inline]
fn prefetch_for_write<T>(start: *const T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_ET0};
        // From the start of the first line.
        let misalign = start.addr() % 64;
        let (start, bytes) = (start.cast::<i8>().wrapping_sub(misalign), bytes + misalign);
        let mut offset = 0;
        while offset < bytes {
            // SAFETY: a prefetch is a hint: it reads nothing the program can observe and
            // never faults, whatever the address (`wrapping_add` keeps the pointer
            // arithmetic defined), and SSE is part of every x86-64 processor.
            unsafe { _mm_prefetch::<_MM_HINT_ET0>(start.wrapping_add(offset)) };
            offset += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, bytes);
}

/// What comes between the ticks of a batch.
enum Mark {
    Event(Event),
    /// A tick that records nothing, at this flight time.
    Idle(f64),
    /// The controller's state after the tick before it: `Batch::key_frames[i]`.
    KeyFrame(usize),
}

/// Room for this many key frames in each batch (a chunk closes at most every few batches,
/// whatever the ticks' clocks say, one key frame each; more grow the batch once).
const KEY_FRAMES: usize = 2;

/// Ticks (the first `len` of `ticks` are live) and what comes among them: `(i, mark)` comes
/// before tick `i`, in order.
struct Batch {
    ticks: Vec<OwnedTick>,
    len: usize,
    marks: Vec<(usize, Mark)>,
    /// The idle ticks among `marks`.
    idles: usize,
    key_frames: Vec<ControllerState>,
}

impl Batch {
    /// A batch whose ticks, marks and key frames are all allocated up front: filling it
    /// allocates nothing (but the events' own text).
    fn new(ticks: usize) -> Batch {
        Batch {
            ticks: (0..ticks).map(|_| OwnedTick::empty()).collect(),
            len: 0,
            marks: Vec::with_capacity(ticks + 4),
            idles: 0,
            key_frames: Vec::with_capacity(KEY_FRAMES),
        }
    }

    fn clear(&mut self) {
        self.len = 0;
        self.marks.clear();
        self.idles = 0;
        self.key_frames.clear();
    }

    fn is_empty(&self) -> bool {
        self.len == 0 && self.marks.is_empty()
    }
}

/// The flight log on its own thread (see the module doc). A [`FlightSink`].
pub struct LogThread {
    /// `None` once the thread has been told to stop.
    full: Option<SyncSender<Batch>>,
    empty: Receiver<Batch>,
    /// The writer thread's errors, as they happen.
    errors: Receiver<io::Error>,
    /// Set by the writer thread once it has sent an error: the loop reads this flag each tick
    /// (a plain load of a line nobody writes) rather than the channel, whose empty `try_recv`
    /// costs a full memory fence.
    failed: Arc<AtomicBool>,
    batch: Batch,
    /// Flight time of the batch's first tick (or tick that records nothing).
    batch_start_s: Option<f64>,
    max_ticks: usize,
    handle: Option<JoinHandle<io::Result<()>>>,
    /// The writer's schedule of chunk closes, stepped with the same ticks: where the writer
    /// starts a chunk, which starts with a key frame.
    clock: ChunkClock,
    /// The last tick closes a chunk: the loop is asked for the controller's state.
    key_frame_due: bool,
}

/// The writer thread's side of syncing: asks the syncer thread to `sync_data` (never
/// blocks: a sync under way absorbs the ask) as batches are written. Asked from the writer,
/// not the loop: waking the syncer is a system call and a cross-core wake-up.
struct SyncAsk {
    tx: Option<SyncSender<()>>,
    /// When a sync was last asked for.
    last: Option<Instant>,
    batches: u64,
}

impl SyncAsk {
    /// One more batch written: whether a sync is due (the caller hands its chunks to the OS,
    /// then [`SyncAsk::ask`]s).
    fn batch_written(&mut self) -> bool {
        self.batches += 1;
        self.tx.is_some()
            && self.batches.is_multiple_of(SYNC_EVERY_BATCHES)
            && (self.batches.is_multiple_of(SYNC_ANYWAY_BATCHES)
                || self.last.is_none_or(|t| t.elapsed() >= SYNC_PERIOD))
    }

    fn ask(&mut self) {
        if let Some(tx) = &self.tx {
            self.last = Some(Instant::now());
            let _ = tx.try_send(());
        }
    }
}

impl LogThread {
    /// Moves `writer` to a new thread; ticks at `rate_hz` (the batch holds
    /// [`BATCH_PERIOD_S`] of them, whatever their clocks say).
    pub fn spawn(writer: FlightLogWriter, rate_hz: f64) -> io::Result<LogThread> {
        let max_ticks = if rate_hz.is_finite() && rate_hz > 0.0 {
            ((rate_hz * BATCH_PERIOD_S).ceil() as usize).clamp(1, 10_000)
        } else {
            25
        };
        let (full_tx, full_rx) = mpsc::sync_channel::<Batch>(BATCHES);
        let (empty_tx, empty_rx) = mpsc::sync_channel::<Batch>(BATCHES + 1);
        let (err_tx, err_rx) = mpsc::sync_channel::<io::Error>(1);
        for _ in 0..BATCHES {
            let _ = empty_tx.send(Batch::new(max_ticks));
        }
        // The syncer: data reaches the disk while the flight goes on. It ends when the
        // LogThread drops its sender; a failed sync is left to `finish`'s own `fsync`.
        let sync = writer.sync_handle().and_then(|file| {
            let (tx, rx) = mpsc::sync_channel::<()>(1);
            std::thread::Builder::new()
                .name("flight-log-sync".into())
                .spawn(move || {
                    lower_priority();
                    while rx.recv().is_ok() {
                        let _ = file.sync_data();
                    }
                })
                .ok()
                .map(|_| tx)
        });
        let sync = SyncAsk {
            tx: sync,
            last: None,
            batches: 0,
        };
        let failed = Arc::new(AtomicBool::new(false));
        let clock = writer.chunk_clock();
        let errors = Errors {
            tx: err_tx,
            failed: Arc::clone(&failed),
        };
        let handle = std::thread::Builder::new()
            .name("flight-log".into())
            .spawn(move || {
                lower_priority();
                write_batches(writer, full_rx, empty_tx, errors, sync)
            })?;
        Ok(LogThread {
            full: Some(full_tx),
            empty: empty_rx,
            errors: err_rx,
            failed,
            batch: Batch::new(max_ticks),
            batch_start_s: None,
            max_ticks,
            handle: Some(handle),
            clock,
            key_frame_due: false,
        })
    }

    /// The writer's error, once (the writer sets the flag once); the loop lands on it.
    fn check_writer(&mut self) -> io::Result<()> {
        if self.failed.load(Ordering::Acquire) {
            self.failed.store(false, Ordering::Relaxed);
            return Err(self.thread_error());
        }
        Ok(())
    }

    /// Hands the batch over once it holds [`BATCH_PERIOD_S`] of flight, or as many ticks
    /// (those that record nothing included) as it has room for.
    fn hand_over_when_due(&mut self, t_s: f64) -> io::Result<()> {
        let start = *self.batch_start_s.get_or_insert(t_s);
        if self.batch.len + self.batch.idles >= self.max_ticks || !(t_s - start < BATCH_PERIOD_S) {
            self.hand_over()?;
        }
        Ok(())
    }

    /// Hands the current batch to the writer (waiting only when it is [`BATCHES`] behind)
    /// and takes an emptied one back.
    fn hand_over(&mut self) -> io::Result<()> {
        if self.batch.is_empty() {
            return Ok(());
        }
        let Some(full) = &self.full else {
            return Err(io::Error::other("the flight log is closed"));
        };
        // When the writer holds every batch, poll for one rather than block in the channel:
        // the channel's blocking path allocates its waker on a thread's first wait, which
        // would put an allocation in the loop at whatever tick that first happens.
        let next = loop {
            match self.empty.try_recv() {
                Ok(mut b) => {
                    b.clear();
                    break b;
                }
                Err(TryRecvError::Empty) => std::thread::sleep(WAIT_FOR_BATCH),
                Err(TryRecvError::Disconnected) => return Err(self.thread_error()),
            }
        };
        let batch = std::mem::replace(&mut self.batch, next);
        self.batch_start_s = None;
        full.send(batch).map_err(|_| self.thread_error())
    }

    /// The writer thread's error (it stopped).
    fn thread_error(&mut self) -> io::Error {
        match self.errors.try_recv() {
            Ok(e) => e,
            Err(_) => io::Error::other("the flight log's writer thread stopped"),
        }
    }

    /// Hands the last batch over, waits for the writer to finish the file (summary, closing
    /// magic, `fsync`); the first write error if there was one.
    pub fn finish(mut self) -> io::Result<()> {
        self.close()
    }

    fn close(&mut self) -> io::Result<()> {
        let handed = self.hand_over();
        self.full = None; // the writer sees the channel close, finishes the file and returns
        let joined = match self.handle.take() {
            Some(h) => h
                .join()
                .unwrap_or_else(|_| Err(io::Error::other("the flight log's writer panicked"))),
            None => Ok(()),
        };
        match (handed, joined) {
            (Err(e), _) => Err(e),
            // The writer's own error, unless the loop was already given it.
            (Ok(()), Err(e)) => Err(self.errors.try_recv().unwrap_or(e)),
            (Ok(()), Ok(())) => Ok(()),
        }
    }
}

impl FlightSink for LogThread {
    fn tick(&mut self, record: &TickRecord) -> io::Result<()> {
        self.check_writer()?;
        let b = &mut self.batch;
        if b.len == b.ticks.len() {
            // Only after a failed hand-over (the batch was kept): the loop is landing.
            b.ticks.push(OwnedTick::empty());
        }
        b.ticks[b.len].fill(record);
        b.len += 1;
        // The tick after next: its lines arrive while this tick and the next are flown.
        if let Some(ahead) = b.ticks.get(b.len + 1) {
            ahead.prefetch(record.actors.len());
        }
        let t_s = record.input.t_s;
        self.key_frame_due = self.clock.step(t_s);
        self.hand_over_when_due(t_s)
    }

    fn event(&mut self, event: &Event) -> io::Result<()> {
        let at = self.batch.len;
        self.batch.marks.push((at, Mark::Event(event.clone())));
        Ok(())
    }

    fn idle(&mut self, t_s: f64) -> io::Result<()> {
        self.check_writer()?;
        let b = &mut self.batch;
        b.marks.push((b.len, Mark::Idle(t_s)));
        b.idles += 1;
        self.clock.step(t_s);
        self.hand_over_when_due(t_s)
    }

    fn wants_key_frame(&self) -> bool {
        self.key_frame_due
    }

    fn key_frame(&mut self, state: &ControllerState) -> io::Result<()> {
        self.key_frame_due = false;
        let b = &mut self.batch;
        b.marks.push((b.len, Mark::KeyFrame(b.key_frames.len())));
        b.key_frames.push(*state);
        Ok(())
    }
}

impl Drop for LogThread {
    fn drop(&mut self) {
        // Dropped without `finish()` (an error path or a panic's unwinding): hand over what
        // is recorded and let the writer close the file; errors have nowhere to go.
        if self.handle.is_some() {
            let _ = self.close();
        }
    }
}

/// The writer thread: writes each batch, returns it emptied; at the end finishes the file.
/// After a write error it reports it, stops writing (the file keeps every whole chunk before
/// it) and keeps returning batches so that the loop never waits for one.
fn write_batches(
    mut writer: FlightLogWriter,
    full: Receiver<Batch>,
    empty: SyncSender<Batch>,
    errors: Errors,
    mut sync: SyncAsk,
) -> io::Result<()> {
    let mut failed = false;
    let report = |e: io::Error, failed: &mut bool| {
        if !*failed {
            *failed = true;
            let _ = errors.tx.try_send(io::Error::new(e.kind(), e.to_string()));
            errors.failed.store(true, Ordering::Release);
        }
    };
    if let Err(e) = writer.defer_hand_over(HAND_OVER_BYTES) {
        report(e, &mut failed);
    }
    let mut idle = POLL_MIN;
    loop {
        let batch = match full.try_recv() {
            Ok(b) => {
                idle = POLL_MIN;
                b
            }
            Err(TryRecvError::Empty) => {
                // Nothing to write: what is written goes to the OS before the thread sleeps.
                if !failed {
                    if let Err(e) = writer.hand_over() {
                        report(e, &mut failed);
                    }
                }
                std::thread::sleep(idle);
                idle = (idle * 2).min(POLL_MAX);
                continue;
            }
            Err(TryRecvError::Disconnected) => break,
        };
        if !failed {
            let written = write_batch(&mut writer, &batch).and_then(|()| {
                if sync.batch_written() {
                    // The sync covers what is written so far.
                    writer.hand_over()?;
                    sync.ask();
                }
                Ok(())
            });
            if let Err(e) = written {
                report(e, &mut failed);
            }
        }
        let _ = empty.send(batch);
    }
    // The syncer ends after the sync under way, if any; `finish` syncs the rest itself.
    drop(sync);
    if failed {
        // Drop closes what it can; the error was reported.
        return Err(io::Error::other("the flight log could not be written"));
    }
    writer.finish()
}

/// How the writer thread tells the loop of a write error: the error on the channel, then the
/// flag the loop reads.
struct Errors {
    tx: SyncSender<io::Error>,
    failed: Arc<AtomicBool>,
}

/// Lowers the calling thread's scheduling priority by 10 (the log's threads, the live
/// view's), so that when the loop, the writer, the syncer and the kernel's writeback want more
/// cores than there are, the loop keeps its own. Best effort (a failure leaves the priority as it was), on Linux only,
/// where the nice value belongs to the thread (elsewhere it is the whole process's, the
/// loop's included).
pub fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: `nice` only changes the calling thread's scheduling weight (a thread attribute
    // on Linux); it touches no memory of the program. Raising it needs no privilege.
    unsafe {
        libc::nice(LOG_NICE);
    }
}

fn write_batch(writer: &mut FlightLogWriter, batch: &Batch) -> io::Result<()> {
    let write_mark = |writer: &mut FlightLogWriter, mark: &Mark| match mark {
        Mark::Event(e) => writer.write_event(e),
        Mark::Idle(t_s) => writer.idle(*t_s),
        Mark::KeyFrame(i) => {
            writer.write_key_frame(&batch.key_frames[*i]);
            Ok(())
        }
    };
    let mut marks = batch.marks.iter().peekable();
    for (i, tick) in batch.ticks[..batch.len].iter().enumerate() {
        while let Some((_, mark)) = marks.next_if(|(at, _)| *at <= i) {
            write_mark(writer, mark)?;
        }
        writer.write_tick(&tick.record())?;
    }
    for (_, mark) in marks {
        write_mark(writer, mark)?;
    }
    Ok(())
}
