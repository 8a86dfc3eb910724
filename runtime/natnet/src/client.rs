//! The OptiTrack NatNet backend: the frame codec wired to non-blocking UDP sockets
//! ([`NatNetClient`], a [`Mocap`]).
//!
//! **Connect**: a command socket (ephemeral port) sends `NAT_CONNECT` to the server's
//! command port, re-sent every 250 ms until `NAT_SERVERINFO` answers (the NatNet version
//! decides the frame layout; 3.0–4.1 are supported). When the server says how it streams
//! (`sSender_Server`, NatNet ≥ 3), a transport that disagrees with the URL is an error that
//! says which URL to use. Multicast: a data socket bound to the data port joins the group
//! (on [`NatNetOptions::interface`]). Unicast: frames are read from the command socket (the
//! address the server knows) and, when the data port can be bound, from a data socket on it
//! too; a `NAT_KEEPALIVE` goes to the command port every second.
//!
//! **Poll**: drains every socket until `WouldBlock`, decodes each frame with the learned
//! version (two buffers swapped: no allocation once warm) and keeps the newest; datagrams
//! from other hosts (unicast), other messages, malformed frames and frames not newer than the
//! last one returned are counted and skipped, never a panic. The newest frame is mapped by
//! the [`Rig`]: rigid body ids → the drone and the scene's actors in the scene's order, a body
//! missing or with its tracking-valid bit clear → `None`, Motive's axes → world → stage.
//!
//! **Time**: `t_s` is the frame's *capture* time on the flight clock, estimated as its
//! arrival time (the monotonic clock, minus [`NatNetOptions::epoch`], the instant the flight
//! clock reads 0 — for a `WallClock` created at that instant, the same seconds) minus the
//! latency Motive reports in the frame (transmit − mid-exposure ticks ÷ the server's clock
//! rate, when known; clamped to 0–0.5 s). The server's own timestamp is not used: it starts
//! when Motive starts streaming and drifts from this computer's clock, while the arrival
//! time only errs by the network delay (sub-millisecond on a wired link).

use std::io::ErrorKind;
use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::frame::{
    decode_frame, decode_server_info, encode_connect, split_message, Frame, ServerInfo, Version,
    NAT_FRAMEOFDATA, NAT_KEEPALIVE, NAT_SERVERINFO,
};
use crate::rig::Rig;
use crate::url::{NatNetTransport, NatNetUrl};
use dronecine_backend::{BackendError, BodyPose, Mocap, MocapFrame};

/// Largest datagram read (NatNet's `MAX_PACKETSIZE` is 65503).
const RX_LEN: usize = 65_536;
const CONNECT_RESEND: Duration = Duration::from_millis(250);
const KEEP_ALIVE: Duration = Duration::from_secs(1);
const POLL_SLEEP: Duration = Duration::from_millis(2);
/// Largest latency taken from the frame's tick stamps (beyond, the stamps are not trusted).
const MAX_LATENCY_S: f64 = 0.5;

/// Connection settings.
#[derive(Clone, Debug)]
pub struct NatNetOptions {
    /// How long to wait for `NAT_SERVERINFO`.
    pub handshake_timeout: Duration,
    /// The instant the flight clock reads 0 (module docs, "Time").
    pub epoch: Instant,
    /// The NatNet version asked for in `NAT_CONNECT` (the server answers with its own).
    pub requested_version: Version,
    /// The local interface to join the multicast group on (`0.0.0.0`: the system's choice).
    pub interface: Ipv4Addr,
}

impl Default for NatNetOptions {
    fn default() -> Self {
        NatNetOptions {
            handshake_timeout: Duration::from_secs(2),
            epoch: Instant::now(),
            requested_version: Version::V4_1,
            interface: Ipv4Addr::UNSPECIFIED,
        }
    }
}

/// What the client skipped (for logs and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct MocapStats {
    /// Frames decoded.
    pub frames: u64,
    /// Frames returned by `poll`.
    pub frames_returned: u64,
    /// Frame datagrams that did not decode, and datagrams with no valid message header.
    pub malformed: u64,
    /// Valid messages other than frames (server info repeats, echoes, strings).
    pub other_messages: u64,
    /// Datagrams from a host other than the server (unicast).
    pub foreign: u64,
    /// Frames not newer than the last one returned (duplicates, reordering).
    pub stale: u64,
}

/// A Motive server over UDP (module docs).
pub struct NatNetClient {
    url: NatNetUrl,
    server: SocketAddr,
    command: UdpSocket,
    data: Option<UdpSocket>,
    /// Why the unicast data port could not be bound (frames then come on the command socket).
    data_bind_error: Option<String>,
    info: ServerInfo,
    version: Version,
    clock_hz: u64,
    rig: Rig,
    actor_ids: Vec<i32>,
    rx: Vec<u8>,
    scratch: Frame,
    newest: Frame,
    newest_arrival: Instant,
    /// `newest` holds a frame not yet returned.
    pending: bool,
    last_returned: Option<i32>,
    last_keep_alive: Instant,
    epoch: Instant,
    stats: MocapStats,
}

impl std::fmt::Debug for NatNetClient {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NatNetClient")
            .field("url", &self.url)
            .field("version", &self.version)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

fn link(msg: String) -> BackendError {
    BackendError::Link(msg)
}

/// What `recv_from` gave: a datagram, nothing more for now, or a failure.
enum Recv {
    Got(usize, SocketAddr),
    Empty,
    Failed(std::io::Error),
}

fn recv(socket: &UdpSocket, buf: &mut [u8]) -> Recv {
    loop {
        match socket.recv_from(buf) {
            Ok((n, from)) => return Recv::Got(n, from),
            Err(e) if e.kind() == ErrorKind::WouldBlock => return Recv::Empty,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            // The ICMP echo of an earlier send (Windows reports it on unconnected sockets).
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::ConnectionRefused | ErrorKind::ConnectionReset
                ) =>
            {
                continue
            }
            Err(e) => return Recv::Failed(e),
        }
    }
}

impl NatNetClient {
    /// Connects (module docs) and checks that the rig has a rigid body for every actor of
    /// the scene (`actor_names`, in the scene's order — the order of `MocapFrame::actors`).
    pub fn connect<I>(
        url: &NatNetUrl,
        rig: &Rig,
        actor_names: I,
        options: &NatNetOptions,
    ) -> Result<Self, BackendError>
    where
        I: IntoIterator,
        I::Item: AsRef<str>,
    {
        let actor_ids = rig
            .actor_ids(actor_names)
            .map_err(|e| BackendError::Refused(e.to_string()))?;
        let server = url
            .command_addr()
            .map_err(|e| link(format!("{url}: {e}")))?;
        let local: SocketAddr = if server.is_ipv4() {
            ([0, 0, 0, 0], 0).into()
        } else {
            (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let command = UdpSocket::bind(local)
            .and_then(|s| s.set_nonblocking(true).map(|()| s))
            .map_err(|e| link(format!("cannot open the NatNet command socket: {e}")))?;
        let mut rx = vec![0u8; RX_LEN];
        let info = handshake(&command, server, url, options, &mut rx)?;
        let version = info.natnet_version;
        if !version.is_supported() {
            return Err(BackendError::Refused(format!(
                "Motive at {server} streams NatNet {version}; this client reads 3.0–4.1 \
                 (set the NatNet version in Motive's streaming settings)"
            )));
        }
        if let Some(d) = info.details {
            match (url.transport, d.multicast) {
                (NatNetTransport::Unicast, true) => {
                    return Err(link(format!(
                        "Motive at {server} streams multicast to {}: use natnet://{}?multicast={}",
                        Ipv4Addr::from(d.multicast_group),
                        url.server,
                        Ipv4Addr::from(d.multicast_group)
                    )))
                }
                (NatNetTransport::Multicast(_), false) => {
                    return Err(link(format!(
                        "Motive at {server} streams unicast: use natnet://{}?unicast",
                        url.server
                    )))
                }
                _ => {}
            }
        }
        let bind_data = || -> std::io::Result<UdpSocket> {
            let s = UdpSocket::bind((Ipv4Addr::UNSPECIFIED, url.data_port))?;
            s.set_nonblocking(true)?;
            Ok(s)
        };
        let (data, data_bind_error) = match url.transport {
            NatNetTransport::Multicast(group) => {
                let s = bind_data()
                    .and_then(|s| s.join_multicast_v4(&group, &options.interface).map(|()| s))
                    .map_err(|e| {
                        link(format!(
                            "cannot receive multicast {group} on port {}: {e} (another \
                             program on this port? try natnet://{}?unicast)",
                            url.data_port, url.server
                        ))
                    })?;
                (Some(s), None)
            }
            NatNetTransport::Unicast => match bind_data() {
                Ok(s) => (Some(s), None),
                Err(e) => (None, Some(format!("port {}: {e}", url.data_port))),
            },
        };
        let now = Instant::now();
        Ok(NatNetClient {
            url: url.clone(),
            server,
            command,
            data,
            data_bind_error,
            clock_hz: info.details.map_or(0, |d| d.high_res_clock_hz),
            info,
            version,
            rig: rig.clone(),
            actor_ids,
            rx,
            scratch: Frame::default(),
            newest: Frame::default(),
            newest_arrival: now,
            pending: false,
            last_returned: None,
            last_keep_alive: now,
            epoch: options.epoch,
            stats: MocapStats::default(),
        })
    }

    /// The NatNet version the server announced (the frame layout read).
    pub fn version(&self) -> Version {
        self.version
    }

    pub fn server_info(&self) -> &ServerInfo {
        &self.info
    }

    pub fn stats(&self) -> MocapStats {
        self.stats
    }

    /// Unicast: why the data port could not be bound (frames are then read from the command
    /// socket only).
    pub fn data_bind_error(&self) -> Option<&str> {
        self.data_bind_error.as_deref()
    }

    /// Reads one socket until it is empty; a newer frame sets `pending`.
    fn drain(&mut self, use_data: bool) -> Result<(), BackendError> {
        loop {
            let socket = if use_data {
                match &self.data {
                    Some(s) => s,
                    None => return Ok(()),
                }
            } else {
                &self.command
            };
            let (n, from) = match recv(socket, &mut self.rx) {
                Recv::Got(n, from) => (n, from),
                Recv::Empty => return Ok(()),
                Recv::Failed(e) => {
                    return Err(link(format!(
                        "reading NatNet frames from {}: {e}",
                        self.url
                    )))
                }
            };
            // Unicast frames come from the server; multicast ones may leave by another of
            // its interfaces, so only the command socket is filtered.
            if (!use_data || self.url.transport == NatNetTransport::Unicast)
                && from.ip() != self.server.ip()
            {
                self.stats.foreign += 1;
                continue;
            }
            let dg = &self.rx[..n];
            match split_message(dg) {
                Ok((NAT_FRAMEOFDATA, _)) => {}
                Ok(_) => {
                    self.stats.other_messages += 1;
                    continue;
                }
                Err(_) => {
                    self.stats.malformed += 1;
                    continue;
                }
            }
            if decode_frame(dg, self.version, &mut self.scratch).is_err() {
                self.stats.malformed += 1;
                continue;
            }
            self.stats.frames += 1;
            let number = self.scratch.frame_number;
            let newer_than = |last: i32| {
                // Newer, or far older: Motive restarted its numbering.
                number > last || number < last.saturating_sub(10_000)
            };
            let base = if self.pending {
                Some(self.newest.frame_number)
            } else {
                self.last_returned
            };
            if base.is_some_and(|last| !newer_than(last)) {
                self.stats.stale += 1;
                continue;
            }
            std::mem::swap(&mut self.scratch, &mut self.newest);
            self.newest_arrival = Instant::now();
            self.pending = true;
        }
    }

    fn keep_alive(&mut self) {
        if self.url.transport == NatNetTransport::Unicast
            && self.last_keep_alive.elapsed() >= KEEP_ALIVE
        {
            self.last_keep_alive = Instant::now();
            let id = NAT_KEEPALIVE.to_le_bytes();
            let msg = [id[0], id[1], 0, 0];
            // Lost or refused keep-alives show as missing frames.
            let _ = self.command.send_to(&msg, self.server);
        }
    }

    /// Motive's reported latency of the newest frame, seconds.
    fn latency_s(&self) -> f64 {
        let f = &self.newest;
        if self.clock_hz == 0 || f.transmit_ticks < f.camera_mid_exposure_ticks {
            return 0.0;
        }
        let s = (f.transmit_ticks - f.camera_mid_exposure_ticks) as f64 / self.clock_hz as f64;
        if s.is_finite() {
            s.clamp(0.0, MAX_LATENCY_S)
        } else {
            0.0
        }
    }

    fn pose(&self, id: i32) -> Option<BodyPose> {
        self.newest
            .rigid_body(id)
            .and_then(|b| b.body_pose(self.rig.up))
            .map(|p| self.rig.to_stage(p))
    }
}

fn handshake(
    command: &UdpSocket,
    server: SocketAddr,
    url: &NatNetUrl,
    options: &NatNetOptions,
    rx: &mut [u8],
) -> Result<ServerInfo, BackendError> {
    let mut connect = [0u8; 512];
    let len = encode_connect(options.requested_version, &mut connect)
        .map_err(|e| link(format!("encoding NAT_CONNECT: {e}")))?;
    let deadline = Instant::now() + options.handshake_timeout;
    let mut last_sent: Option<Instant> = None;
    let mut bad = 0u32;
    loop {
        let now = Instant::now();
        if last_sent.is_none_or(|t| now.duration_since(t) >= CONNECT_RESEND) {
            match command.send_to(&connect[..len], server) {
                Ok(_) => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(e) => return Err(link(format!("sending NAT_CONNECT to {server}: {e}"))),
            }
            last_sent = Some(now);
        }
        loop {
            match recv(command, rx) {
                Recv::Got(n, from) if from.ip() == server.ip() => {
                    let dg = &rx[..n];
                    if let Ok((NAT_SERVERINFO, _)) = split_message(dg) {
                        match decode_server_info(dg) {
                            Ok(info) => return Ok(info),
                            Err(_) => bad += 1,
                        }
                    }
                }
                Recv::Got(..) => {}
                Recv::Empty => break,
                Recv::Failed(e) => {
                    return Err(link(format!("reading from NatNet server {server}: {e}")))
                }
            }
        }
        if Instant::now() >= deadline {
            return Err(link(format!(
                "no NatNet server info from {server} within {:.1} s{}: is Motive running with \
                 streaming on, and {} its address? ({url})",
                options.handshake_timeout.as_secs_f64(),
                if bad > 0 {
                    format!(" ({bad} malformed replies)")
                } else {
                    String::new()
                },
                url.server
            )));
        }
        std::thread::sleep(POLL_SLEEP);
    }
}

impl Mocap for NatNetClient {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        self.keep_alive();
        self.drain(false)?;
        self.drain(true)?;
        if !self.pending {
            return Ok(false);
        }
        self.pending = false;
        let arrival_s = self
            .newest_arrival
            .checked_duration_since(self.epoch)
            .map_or(0.0, |d| d.as_secs_f64());
        frame.t_s = arrival_s - self.latency_s();
        frame.received_s = arrival_s;
        frame.frame = u64::from(self.newest.frame_number as u32);
        frame.drone = self.pose(self.rig.drone_id);
        frame.actors.resize(self.actor_ids.len(), None);
        for i in 0..self.actor_ids.len() {
            frame.actors[i] = self.pose(self.actor_ids[i]);
        }
        self.last_returned = Some(self.newest.frame_number);
        self.stats.frames_returned += 1;
        Ok(true)
    }
}
