//! The MAVLink link ([`Link`]): the `mavlink` crate's connection, a reader thread that
//! applies every message to the shared [`VehicleState`], and a thread that sends our
//! HEARTBEAT at 1 Hz.
//!
//! The connection has one lock for reading and another for writing, so a send from the
//! flight loop never waits for the reader's blocking read; the state's lock is held only
//! while one message is applied. Sending builds the message and its frame on the stack: the
//! per-tick path allocates nothing. UDP and TCP reads wake every 100 ms so the reader sees
//! the link closed; a serial port's reader ends with its next message.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use dronecine_backend::clock::wait_until;
use dronecine_backend::BackendError;
use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{Connectable, Connection, MavConnection, MavHeader, TcpConfig, TcpMode};
use mavlink::{UdpConfig, UdpMode};

use crate::messages::{self, Target, GCS_COMPONENT_ID, GCS_SYSTEM_ID};
use crate::state::VehicleState;
use crate::url::{MavlinkLink, MavlinkUrl};

/// How often our HEARTBEAT goes out.
pub const HEARTBEAT_PERIOD: Duration = Duration::from_secs(1);
/// How long a UDP read waits before the reader looks whether the link was closed.
const READ_TIMEOUT: Duration = Duration::from_millis(100);
/// The reader's pause after a read error (a closed connection), so it does not spin.
const ERROR_PAUSE: Duration = Duration::from_millis(100);
/// How often [`Link::wait_for`] looks at the state.
const POLL: Duration = Duration::from_millis(5);

type Conn = Connection<MavMessage>;

/// What the threads share with the link.
struct Shared {
    state: Mutex<VehicleState>,
    closed: AtomicBool,
}

/// An open link to one MAVLink vehicle.
pub struct Link {
    url: MavlinkUrl,
    conn: Arc<Conn>,
    shared: Arc<Shared>,
    opened: Instant,
    reader: Option<JoinHandle<()>>,
    heartbeat: Option<JoinHandle<()>>,
}

impl Link {
    /// Opens the link and starts its two threads (the first HEARTBEAT goes out at once).
    pub fn open(url: &MavlinkUrl) -> Result<Link, BackendError> {
        let mut conn = connect(url)?;
        conn.set_allow_recv_any_version(true);
        let conn = Arc::new(conn);
        let shared = Arc::new(Shared {
            state: Mutex::new(VehicleState::default()),
            closed: AtomicBool::new(false),
        });
        let reader = {
            let (conn, shared) = (Arc::clone(&conn), Arc::clone(&shared));
            spawn("mavlink-reader", move || read_loop(&conn, &shared))?
        };
        let heartbeat = {
            let (conn, shared) = (Arc::clone(&conn), Arc::clone(&shared));
            spawn("mavlink-heartbeat", move || heartbeat_loop(&conn, &shared))?
        };
        Ok(Link {
            url: url.clone(),
            conn,
            shared,
            opened: Instant::now(),
            reader: Some(reader),
            heartbeat: Some(heartbeat),
        })
    }

    pub fn url(&self) -> &MavlinkUrl {
        &self.url
    }

    /// Sends one message from this ground station (nothing goes out on a `udpin` link before
    /// the vehicle was heard).
    pub fn send(&self, msg: &MavMessage) -> Result<(), BackendError> {
        send(&self.conn, msg).map_err(|e| {
            BackendError::Link(format!("cannot send to the vehicle at {}: {e}", self.url))
        })
    }

    /// The vehicle's state, locked: keep the guard short (the reader waits for it).
    pub fn state(&self) -> MutexGuard<'_, VehicleState> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The autopilot, once its heartbeat was heard.
    pub fn vehicle(&self) -> Option<Target> {
        self.state().vehicle
    }

    /// Milliseconds since the link opened (SET_ATTITUDE_TARGET's `time_boot_ms`).
    pub fn time_ms(&self) -> u32 {
        self.opened.elapsed().as_millis() as u32
    }

    /// Seconds since the vehicle was last heard (since the link opened when never).
    pub fn link_age_s(&self) -> f64 {
        let last = self.state().last_heard.unwrap_or(self.opened);
        last.elapsed().as_secs_f64()
    }

    /// Polls the state until `done` holds (`true`) or `timeout` passes (`false`), calling
    /// `tick` between looks.
    pub fn wait_for(
        &self,
        timeout: Duration,
        tick: impl FnMut() -> Result<(), BackendError>,
        mut done: impl FnMut(&VehicleState) -> bool,
    ) -> Result<bool, BackendError> {
        wait_until(timeout, POLL, tick, || done(&self.state()))
    }

    /// Waits for the vehicle's first heartbeat.
    pub fn wait_for_vehicle(&self, timeout: Duration) -> Result<Target, BackendError> {
        self.wait_for(timeout, || Ok(()), |s| s.vehicle.is_some())?;
        let state = self.state();
        if let Some(v) = state.vehicle {
            return Ok(v);
        }
        let why = match (&state.link_error, state.ignored) {
            (Some(e), _) => format!(" (the link failed: {e})"),
            (None, 0) => String::new(),
            (None, n) => format!(" ({n} messages arrived, none from an autopilot)"),
        };
        Err(BackendError::Link(format!(
            "no heartbeat from an autopilot at {} within {:.1} s{why}: is the vehicle on, and \
             the address right?",
            self.url,
            timeout.as_secs_f64()
        )))
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        if let Some(h) = self.heartbeat.take() {
            h.thread().unpark();
            let _ = h.join();
        }
        // A serial read returns only with a message: that reader is left to end by itself.
        if !matches!(self.url.link, MavlinkLink::Serial { .. }) {
            if let Some(h) = self.reader.take() {
                let _ = h.join();
            }
        }
    }
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) -> Result<JoinHandle<()>, BackendError> {
    std::thread::Builder::new()
        .name(name.into())
        .spawn(f)
        .map_err(|e| BackendError::Link(format!("cannot start the {name} thread: {e}")))
}

/// The `mavlink` crate's connection for an address.
fn connect(url: &MavlinkUrl) -> Result<Conn, BackendError> {
    let fail = |e: std::io::Error| BackendError::Link(format!("cannot open {url}: {e}"));
    let addr =
        |host: &str, port: u16| format!("{}:{port}", dronecine_backend::address::bracket(host));
    match &url.link {
        MavlinkLink::Udp { host, port } => UdpConfig::new(addr(host, *port), UdpMode::Udpout)
            .read_timeout(READ_TIMEOUT)
            .connect::<MavMessage>()
            .map_err(fail),
        MavlinkLink::UdpIn { host, port } => UdpConfig::new(addr(host, *port), UdpMode::Udpin)
            .read_timeout(READ_TIMEOUT)
            .connect::<MavMessage>()
            .map_err(fail),
        MavlinkLink::Tcp { host, port } => TcpConfig::new(addr(host, *port), TcpMode::TcpOut)
            .connect::<MavMessage>()
            .map_err(fail),
        MavlinkLink::Serial { path, baud } => connect_serial(url, path, *baud),
    }
}

#[cfg(feature = "serial")]
fn connect_serial(url: &MavlinkUrl, path: &str, baud: u32) -> Result<Conn, BackendError> {
    mavlink::SerialConfig::new(path.to_string(), baud)
        .connect::<MavMessage>()
        .map_err(|e| BackendError::Link(format!("cannot open {url}: {e}")))
}

#[cfg(not(feature = "serial"))]
fn connect_serial(url: &MavlinkUrl, _path: &str, _baud: u32) -> Result<Conn, BackendError> {
    Err(BackendError::Link(format!(
        "cannot open {url}: this build has no serial link (dronecine-mavlink's `serial` feature)"
    )))
}

fn send(conn: &Conn, msg: &MavMessage) -> Result<(), mavlink::error::MessageWriteError> {
    let header = MavHeader {
        system_id: u32::from(GCS_SYSTEM_ID),
        component_id: GCS_COMPONENT_ID,
        sequence: 0,
    };
    conn.send(&header, msg).map(|_| ())
}

/// The reader thread: every message into the state until the link closes.
fn read_loop(conn: &Conn, shared: &Shared) {
    while !shared.closed.load(Ordering::Relaxed) {
        match conn.recv() {
            Ok((header, msg)) => {
                let now = Instant::now();
                let mut state = shared.state.lock().unwrap_or_else(|p| p.into_inner());
                state.apply(&header, &msg, now);
            }
            Err(MessageReadError::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(MessageReadError::Io(e)) => {
                shared
                    .state
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .link_error = Some(e.to_string());
                std::thread::sleep(ERROR_PAUSE);
            }
            Err(_) => {
                shared
                    .state
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .ignored += 1
            }
        }
    }
}

/// The heartbeat thread: ours at once, then every [`HEARTBEAT_PERIOD`].
fn heartbeat_loop(conn: &Conn, shared: &Shared) {
    let hb = messages::heartbeat();
    let mut next = Instant::now();
    while !shared.closed.load(Ordering::Relaxed) {
        let now = Instant::now();
        if now >= next {
            // A failed send shows as the vehicle's silence (its link age), not here.
            let _ = send(conn, &hb);
            next = now + HEARTBEAT_PERIOD;
        }
        std::thread::park_timeout(next.saturating_duration_since(Instant::now()));
    }
}
