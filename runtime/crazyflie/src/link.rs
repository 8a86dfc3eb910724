//! The link to one Crazyflie ([`Link`]): the transport (UDP, or a Crazyradio through
//! `crazyflie-link`), a reader that applies every packet to the shared [`LinkState`], and
//! request/answer exchanges that wait for the state to show the answer.
//!
//! Sending encodes on the stack and writes one datagram (UDP) or queues a fixed-size packet
//! for the radio's thread: the per-tick path allocates nothing. The state's lock is held only
//! while one packet is applied. A datagram that is not a CRTP packet, or a packet that is
//! not the message its port says, is counted ([`LinkState::rejected`]) and dropped.

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use dronecine_backend::clock::wait_until;
use dronecine_backend::BackendError;

use crate::crtp::{Packet, ToDrone};
use crate::log::Layout;
pub use crate::state::LinkState;
use crate::state::Shared;
use crate::url::{CrazyflieLink, CrazyflieUrl};

/// How long a UDP read waits before the reader looks whether the link was closed.
const READ_TIMEOUT: Duration = Duration::from_millis(100);
/// How often [`Link::request`] looks at the state.
const POLL: Duration = Duration::from_millis(2);
/// A request not answered within this is sent again (a datagram may be lost).
const RESEND: Duration = Duration::from_millis(150);

enum Transport {
    Udp(UdpSocket),
    #[cfg(feature = "radio")]
    Radio(crate::radio::Radio),
}

/// An open link to one Crazyflie.
pub struct Link {
    url: CrazyflieUrl,
    transport: Transport,
    shared: Arc<Shared>,
    opened: Instant,
    reader: Option<JoinHandle<()>>,
    /// Set-points sent (altHold, position, stop), for the rate a flight achieved.
    setpoints: AtomicU64,
}

impl Link {
    /// Opens the transport: UDP from `local` (any free port when `None`), or the radio.
    pub fn open(url: &CrazyflieUrl, local: Option<SocketAddr>) -> Result<Link, BackendError> {
        let shared = Arc::new(Shared {
            state: Mutex::new(LinkState::default()),
            closed: AtomicBool::new(false),
        });
        let fail = |e: io::Error| BackendError::Link(format!("cannot open {url}: {e}"));
        let (transport, reader) = match &url.link {
            CrazyflieLink::Udp { host, port } => {
                let remote = dronecine_backend::address::resolve(host, *port)
                    .map_err(|e| BackendError::Link(format!("cannot open {url}: {e}")))?;
                let socket = udp_socket(remote, local).map_err(fail)?;
                let reader = {
                    let (socket, shared) = (socket.try_clone().map_err(fail)?, Arc::clone(&shared));
                    std::thread::Builder::new()
                        .name("crazyflie-reader".into())
                        .spawn(move || read_loop(&socket, &shared))
                        .map_err(fail)?
                };
                (Transport::Udp(socket), Some(reader))
            }
            CrazyflieLink::Radio(_) => (radio(url, &shared)?, None),
        };
        Ok(Link {
            url: url.clone(),
            transport,
            shared,
            opened: Instant::now(),
            reader,
            setpoints: AtomicU64::new(0),
        })
    }

    pub fn url(&self) -> &CrazyflieUrl {
        &self.url
    }

    /// Sends one packet.
    pub fn send(&self, packet: &Packet) -> Result<(), BackendError> {
        let sent = match &self.transport {
            Transport::Udp(s) => s
                .send(packet.as_bytes())
                .map(|_| ())
                .map_err(|e| e.to_string()),
            #[cfg(feature = "radio")]
            Transport::Radio(r) => r.send(packet),
        };
        sent.map_err(|e| BackendError::Link(format!("cannot send to {}: {e}", self.url)))
    }

    /// Encodes and sends one message.
    pub fn send_message(&self, message: &ToDrone) -> Result<(), BackendError> {
        let packet = message
            .encode()
            .map_err(|e| BackendError::Refused(format!("cannot encode {message:?}: {e}")))?;
        self.send(&packet)
    }

    /// Sends a set-point (counted: [`Link::setpoints_sent`]).
    pub fn send_setpoint(&self, message: &ToDrone) -> Result<(), BackendError> {
        self.send_message(message)?;
        self.setpoints.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    /// Set-points sent since the link opened.
    pub fn setpoints_sent(&self) -> u64 {
        self.setpoints.load(Ordering::Relaxed)
    }

    /// The state, locked: keep the guard short (the reader waits for it).
    pub fn state(&self) -> MutexGuard<'_, LinkState> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Seconds since the Crazyflie was last heard (since the link opened when never).
    pub fn link_age_s(&self) -> f64 {
        let last = self.state().last_heard.unwrap_or(self.opened);
        last.elapsed().as_secs_f64()
    }

    /// Sends `message` and waits until `answer` finds its answer in the state (returned),
    /// sending it again every 150 ms; `None` after `timeout`.
    pub fn request<T>(
        &self,
        message: &ToDrone,
        timeout: Duration,
        mut answer: impl FnMut(&mut LinkState) -> Option<T>,
    ) -> Result<Option<T>, BackendError> {
        let deadline = Instant::now() + timeout;
        let mut next_send = Instant::now();
        loop {
            if let Some(v) = answer(&mut self.state()) {
                return Ok(Some(v));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            if now >= next_send {
                self.send_message(message)?;
                next_send = now + RESEND;
            }
            std::thread::sleep(POLL);
        }
    }

    /// Waits until `done` holds (`true`) or `timeout` passes (`false`), calling `tick`
    /// between looks.
    pub fn wait_for(
        &self,
        timeout: Duration,
        tick: impl FnMut() -> Result<(), BackendError>,
        mut done: impl FnMut(&LinkState) -> bool,
    ) -> Result<bool, BackendError> {
        wait_until(timeout, POLL, tick, || done(&self.state()))
    }

    /// The log layouts of [`BLOCKS`](crate::log::BLOCKS), installed for the reader to decode their samples.
    pub fn set_layouts(&self, layouts: [Option<Layout>; 2]) {
        self.state().layouts = layouts;
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        if let Some(h) = self.reader.take() {
            let _ = h.join();
        }
    }
}

/// A UDP socket from `local` (or a free port of `remote`'s family) connected to `remote`,
/// its reads waking every [`READ_TIMEOUT`].
fn udp_socket(remote: SocketAddr, local: Option<SocketAddr>) -> io::Result<UdpSocket> {
    let any: SocketAddr = if remote.is_ipv4() {
        "0.0.0.0:0".parse().expect("an address")
    } else {
        "[::]:0".parse().expect("an address")
    };
    let socket = UdpSocket::bind(local.unwrap_or(any))?;
    socket.connect(remote)?;
    socket.set_read_timeout(Some(READ_TIMEOUT))?;
    Ok(socket)
}

/// The UDP reader: every datagram into the state until the link closes.
fn read_loop(socket: &UdpSocket, shared: &Shared) {
    let mut buf = [0u8; 64];
    while !shared.closed.load(Ordering::Relaxed) {
        match socket.recv(&mut buf) {
            Ok(n) => shared.apply(&buf[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) => {}
            Err(e) => {
                // Nothing listens there (yet): the peer's silence is what the link age shows.
                shared.fail(e.to_string());
                std::thread::sleep(READ_TIMEOUT);
            }
        }
    }
}

#[cfg(feature = "radio")]
fn radio(url: &CrazyflieUrl, shared: &Arc<Shared>) -> Result<Transport, BackendError> {
    crate::radio::Radio::open(url, Arc::clone(shared)).map(Transport::Radio)
}

#[cfg(not(feature = "radio"))]
fn radio(url: &CrazyflieUrl, _shared: &Arc<Shared>) -> Result<Transport, BackendError> {
    Err(BackendError::Link(format!(
        "cannot open {url}: this build has no Crazyradio link (dronecine-crazyflie's `radio` \
         feature)"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crtp::{log_type, FromDrone};
    use crate::log::{all_vars, Field, BLOCKS};

    fn datagram(m: FromDrone) -> Vec<u8> {
        m.encode().unwrap().as_bytes().to_vec()
    }

    #[test]
    fn the_state_reads_the_toc_the_samples_and_the_console() {
        let mut s = LinkState::default();
        let now = Instant::now();
        s.apply(&datagram(FromDrone::LogTocInfo { count: 3, crc: 7 }), now);
        s.apply(
            &datagram(FromDrone::LogTocItem {
                index: 2,
                kind: log_type::UINT16,
                group: "supervisor",
                name: "info",
            }),
            now,
        );
        assert_eq!(s.toc_seen, [false, false, true]);
        let supervisor = all_vars().position(|v| v.name == "info").unwrap();
        assert_eq!(s.toc_found[supervisor], Some((2, log_type::UINT16)));
        let kinds = [
            log_type::FLOAT,
            log_type::UINT8,
            log_type::INT8,
            log_type::UINT16,
        ];
        s.layouts[1] = Layout::new(&BLOCKS[1], &kinds);
        let mut sample = Vec::new();
        sample.extend(3.9f32.to_le_bytes());
        sample.extend([80, 0, 0x1B, 0]);
        let data = FromDrone::LogData {
            block: 2,
            timestamp_ms: 1,
            data: &sample,
        };
        s.apply(&datagram(data), now);
        assert_eq!(s.values.get(Field::BatteryLevel), 80.0);
        assert_eq!(s.values.supervisor(), Some(0x1B));
        assert!(s.sampled_at[1].is_some());
        // A sample of the wrong length, a datagram too long, a malformed answer: counted.
        let short = FromDrone::LogData {
            block: 2,
            timestamp_ms: 1,
            data: &sample[..5],
        };
        s.apply(&datagram(short), now);
        s.apply(&[0u8; 40], now);
        s.apply(&[0x5D, 3], now);
        assert_eq!(s.rejected, 3);
        s.apply(&datagram(FromDrone::Console(b"SYS: hello\nSYS: wo")), now);
        s.apply(&datagram(FromDrone::Console(b"rld\n")), now);
        let lines: Vec<&str> = s.messages.iter().map(|m| m.text.as_str()).collect();
        assert_eq!(lines, ["crazyflie: SYS: hello", "crazyflie: SYS: world"]);
    }
}
