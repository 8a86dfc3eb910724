//! The AR.Drone 2.0 backend: the AT and navdata codecs wired to two non-blocking UDP
//! sockets ([`ArDroneClient`], a [`Drone`]).
//!
//! **Start-up** ([`ArDroneClient::connect`]):
//! 1. the navdata trigger `01 00 00 00` to the navdata port, re-sent every 100 ms until a
//!    valid packet arrives (a freshly booted drone answers with bootstrap packets);
//! 2. unless the drone already streams demo navdata: `AT*CONFIG "general:navdata_demo"
//!    "TRUE"` with the acknowledgement handshake, then wait for a packet with the demo option;
//! 3. the profile's limits to `control:euler_angle_max`, `control:control_vz_max` and
//!    `control:control_yaw` ([`PcmdLimits::config_lines`]), each with the handshake.
//!
//! The **handshake** of one CONFIG: if the command-ACK state bit is still set, `AT*CTRL=…,5,0`
//! until it clears; the CONFIG (preceded in the same datagram by `AT*CONFIG_IDS` when
//! [`ArDroneOptions::config_ids`] is given) re-sent every 200 ms until the ACK bit is set;
//! then `AT*CTRL=…,5,0` every 30 ms until it clears. Each wait has a deadline and fails with
//! a [`BackendError::Link`] naming the drone's address and what it did not do.
//!
//! **Flying**: every datagram carries `AT*REF` with what was last asked (take off / land /
//! emergency) — so the REF is repeated until navdata shows the change, as the protocol wants —
//! followed by the command of the call (`AT*PCMD` progressive with the mapped values for
//! [`Drone::send`], flag 0 for [`Drone::hover`]) and `AT*COMWDG` whenever the last navdata
//! had the com-watchdog bit. [`Drone::take_off`] sends `AT*FTRIM` first when the drone is on
//! the ground. [`Drone::telemetry`] drains navdata and, when no datagram went out for 30 ms,
//! sends a keep-alive (the REF, and COMWDG when asked), so the take-off and landing waits of
//! the flight loop, which only read telemetry, keep the REF going at ≥ 30 Hz. A client opened
//! with [`ArDroneClient::monitor`] sends no REF until asked to fly (only COMWDG).
//!
//! One [`AtEncoder`]: one global, strictly increasing sequence number, starting at 1.
//! Navdata: packets from another address, rejected ones (by kind: [`NavdataReject`]) and old
//! ones ([`NavdataSequence`]) are counted and dropped; when none arrived for 200 ms the
//! trigger is re-sent and the sequence rule reset. A drone whose packets all arrive rejected
//! fails the start-up with the count of each kind, not as a silent drone. Nothing blocks:
//! sockets are non-blocking, reads drain until `WouldBlock`, a send that would block drops the
//! datagram (counted) — the next tick sends the set-points again. The per-tick path (`send`,
//! `hover`, `telemetry`) allocates nothing.
//!
//! **Status** ([`ArDroneClient::status`]): the last values, the packets received and rejected
//! since the previous read-out, and the problems that make the read-out untrustworthy:
//! rejected packets, fields no working AR.Drone sends ([`implausible`]) and a silent link.

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use dronecine_profile::Profile;
use serde::Serialize;

use crate::at::{AtCommand, AtEncoder, Datagram, Pcmd, PcmdLimits, REF_BASE};
use crate::navdata::{
    self, Demo, DroneState, MajorState, Navdata, NavdataError, NavdataSequence, CHECKSUM_SIZE,
    DEMO_MIN_SIZE, TAG_CHECKSUM, TAG_DEMO, TAG_TIME, TIME_SIZE,
};
use crate::url::ArDroneUrl;
use dronecine_backend::frames::Command;
use dronecine_backend::{BackendError, Drone, FlightState, Telemetry};

/// The navdata trigger: int32 1 = unicast.
pub const NAVDATA_TRIGGER: [u8; 4] = [1, 0, 0, 0];
/// Keep-alive period: commands go out at least this often while `telemetry` is called.
pub const KEEP_ALIVE: Duration = Duration::from_millis(30);
/// Navdata silence after which the trigger is re-sent.
pub const NAVDATA_RETRIGGER: Duration = Duration::from_millis(200);
const TRIGGER_PERIOD: Duration = Duration::from_millis(100);
const CONFIG_RESEND: Duration = Duration::from_millis(200);
const POLL_SLEEP: Duration = Duration::from_millis(2);
/// AT datagram buffer: REF + PCMD + COMWDG is ~120 bytes, CONFIG_IDS + CONFIG a few hundred.
const AT_BUF_LEN: usize = 2048;

/// Custom configuration ids (multi-configuration mode): each CONFIG is preceded by
/// `AT*CONFIG_IDS` with these, in the same datagram.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigIds {
    pub session: String,
    pub user: String,
    pub application: String,
}

/// Timeouts and the configuration mode.
#[derive(Clone, Debug, PartialEq)]
pub struct ArDroneOptions {
    /// How long to wait for the first navdata packet (and for demo navdata after
    /// `general:navdata_demo` was set).
    pub navdata_timeout: Duration,
    /// How long each CONFIG's acknowledgement handshake may take.
    pub ack_timeout: Duration,
    /// `None`: plain CONFIG (the drone's default configuration).
    pub config_ids: Option<ConfigIds>,
}

impl Default for ArDroneOptions {
    fn default() -> Self {
        ArDroneOptions {
            navdata_timeout: Duration::from_secs(3),
            ack_timeout: Duration::from_secs(2),
            config_ids: None,
        }
    }
}

/// What the client asks of the drone in every `AT*REF`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RefGoal {
    Land,
    Fly,
    Emergency,
}

/// The kinds of navdata packet the decoder rejects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NavdataReject {
    /// The checksum option does not match the bytes before it.
    BadChecksum,
    /// The datagram ends before the packet does: inside the header or an option, before the
    /// checksum option, or an option shorter than its fields.
    Truncated,
    /// Not navdata: an unknown header word.
    Unknown,
    /// A layout the protocol does not allow: an option size under 4, a time or checksum
    /// option over 8 bytes, data after the checksum, a packet over 4096 bytes.
    Malformed,
}

impl NavdataReject {
    pub const ALL: [NavdataReject; 4] = [
        NavdataReject::BadChecksum,
        NavdataReject::Truncated,
        NavdataReject::Unknown,
        NavdataReject::Malformed,
    ];

    /// The kind of the decoder's error on a packet of `len` bytes.
    pub fn of(e: &NavdataError, len: usize) -> Self {
        match *e {
            NavdataError::ChecksumMismatch { .. } => NavdataReject::BadChecksum,
            NavdataError::Truncated
            | NavdataError::TruncatedOption { .. }
            | NavdataError::MissingChecksum => NavdataReject::Truncated,
            NavdataError::BadOptionSize { size, offset, .. }
                if size >= 4 && offset + usize::from(size) > len =>
            {
                NavdataReject::Truncated
            }
            NavdataError::BadKnownOptionSize { tag, size }
                if size
                    < match tag {
                        TAG_DEMO => DEMO_MIN_SIZE,
                        TAG_TIME => TIME_SIZE,
                        TAG_CHECKSUM => CHECKSUM_SIZE,
                        _ => 0,
                    } =>
            {
                NavdataReject::Truncated
            }
            NavdataError::BadHeader(_) => NavdataReject::Unknown,
            NavdataError::BadOptionSize { .. }
            | NavdataError::BadKnownOptionSize { .. }
            | NavdataError::TooLarge
            | NavdataError::DataAfterChecksum
            | NavdataError::BufferFull
            | NavdataError::BadOption => NavdataReject::Malformed,
        }
    }

    /// What happened to `n` packets of this kind, after "N of M packets received".
    fn says(self, n: u64) -> &'static str {
        match (self, n == 1) {
            (NavdataReject::BadChecksum, _) => "had a bad checksum",
            (NavdataReject::Truncated, true) => "was truncated",
            (NavdataReject::Truncated, false) => "were truncated",
            (NavdataReject::Unknown, true) => "was not navdata",
            (NavdataReject::Unknown, false) => "were not navdata",
            (NavdataReject::Malformed, true) => "was malformed",
            (NavdataReject::Malformed, false) => "were malformed",
        }
    }
}

/// Rejected navdata packets, by kind ([`NavdataReject`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct NavdataRejected {
    pub bad_checksum: u64,
    pub truncated: u64,
    pub unknown: u64,
    pub malformed: u64,
}

impl NavdataRejected {
    pub fn count(&self, kind: NavdataReject) -> u64 {
        match kind {
            NavdataReject::BadChecksum => self.bad_checksum,
            NavdataReject::Truncated => self.truncated,
            NavdataReject::Unknown => self.unknown,
            NavdataReject::Malformed => self.malformed,
        }
    }

    fn add(&mut self, kind: NavdataReject) {
        let n = match kind {
            NavdataReject::BadChecksum => &mut self.bad_checksum,
            NavdataReject::Truncated => &mut self.truncated,
            NavdataReject::Unknown => &mut self.unknown,
            NavdataReject::Malformed => &mut self.malformed,
        };
        *n += 1;
    }

    pub fn total(&self) -> u64 {
        self.bad_checksum + self.truncated + self.unknown + self.malformed
    }

    fn since(&self, base: &NavdataRejected) -> NavdataRejected {
        NavdataRejected {
            bad_checksum: self.bad_checksum - base.bad_checksum,
            truncated: self.truncated - base.truncated,
            unknown: self.unknown - base.unknown,
            malformed: self.malformed - base.malformed,
        }
    }
}

/// The last rejected packet of each kind, indexed by `NavdataReject as usize` (the order of
/// [`NavdataReject::ALL`]): the decoder's error and the packet's length.
type LastRejects = [Option<(NavdataError, usize)>; 4];

/// One sentence per kind of rejected packet: "N of M packets received had a bad checksum
/// (the last, 180 bytes: …)".
fn reject_sentences(rejected: &NavdataRejected, received: u64, last: &LastRejects) -> Vec<String> {
    NavdataReject::ALL
        .iter()
        .zip(last)
        .filter(|(k, _)| rejected.count(**k) > 0)
        .map(|(&k, last)| {
            let n = rejected.count(k);
            let packets = if received == 1 { "packet" } else { "packets" };
            let detail = match last {
                Some((e, len)) => {
                    let e = e.to_string();
                    let e = e.strip_prefix("navdata: ").unwrap_or(&e).to_string();
                    format!(" (the last, {len} bytes: {e})")
                }
                None => String::new(),
            };
            format!("{n} of {received} {packets} received {}{detail}", k.says(n))
        })
        .collect()
}

/// Counters of what the client dropped (for logs and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LinkStats {
    /// Navdata packets accepted.
    pub navdata_accepted: u64,
    /// Navdata packets that did not decode, of every kind (`navdata_rejected` has them by
    /// kind).
    pub navdata_malformed: u64,
    /// The packets of `navdata_malformed`, by kind.
    pub navdata_rejected: NavdataRejected,
    /// Navdata packets not newer than the last one (the sequence rule).
    pub navdata_stale: u64,
    /// Datagrams from an address other than the drone's.
    pub foreign: u64,
    /// AT datagrams sent.
    pub at_sent: u64,
    /// AT datagrams dropped because the socket would block.
    pub at_dropped: u64,
    /// Navdata triggers sent.
    pub triggers: u64,
}

impl LinkStats {
    /// Navdata packets from the drone's address: accepted, old and rejected.
    pub fn navdata_received(&self) -> u64 {
        self.navdata_accepted + self.navdata_stale + self.navdata_malformed
    }
}

/// Largest plausible battery charge: a percentage.
pub const BATTERY_MAX_PERCENT: u32 = 100;
/// Largest plausible |θ|, |φ|, |ψ|: an Euler angle names an attitude within half a turn
/// either way (the firmware sends ψ in ±180°).
pub const ANGLE_MAX_DEG: f64 = 180.0;
/// Largest plausible |altitude|: the AR.Drone measures it with an ultrasound sensor (to about
/// 6 m) and a barometer, and flies within reach of its Wi-Fi (about 100 m); a kilometre is
/// beyond it.
pub const ALTITUDE_MAX_M: f64 = 1000.0;
/// Largest plausible |vx|, |vy|, |vz|: ten times the AR.Drone 2.0's top speed (about 5 m/s),
/// and more than a fall from 100 m reaches (44 m/s).
pub const SPEED_MAX_MPS: f64 = 50.0;
/// Oldest plausible navdata: the drone sends demo navdata at 15 Hz (a packet every 67 ms),
/// so half a second without a valid packet (seven missed) is a broken link, and the values
/// shown are not the drone's present state.
pub const NAVDATA_AGE_MAX_S: f64 = 0.5;

/// A field of the demo option with a value no working AR.Drone sends.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Implausible {
    /// The field's key in [`ArDroneStatus`] (`theta_deg`, `velocity_mps[2]`, …).
    pub field: &'static str,
    /// The value as read, as text (JSON has no NaN or infinity).
    pub value: String,
    /// Why no drone sends it (`not a number`, `over 100 %`, …).
    pub reason: String,
}

/// A number as text: exponent notation from a million on, so that a huge value stays short.
fn number(v: f64) -> String {
    if v.is_finite() && v.abs() >= 1e6 {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The fields of a demo option no working AR.Drone sends, field by field: NaN or infinite
/// numbers, a battery over [`BATTERY_MAX_PERCENT`], angles beyond [`ANGLE_MAX_DEG`], an
/// altitude beyond [`ALTITUDE_MAX_M`], speeds beyond [`SPEED_MAX_MPS`], a control state the
/// SDK does not name.
pub fn implausible(demo: &Demo) -> Vec<Implausible> {
    let mut out = Vec::new();
    if let MajorState::Unknown(v) = demo.ctrl_state.major {
        out.push(Implausible {
            field: "ctrl_state",
            value: format!("unknown({v})"),
            reason: "not a control state the SDK names (0 to 9)".into(),
        });
    }
    if demo.battery_percent > BATTERY_MAX_PERCENT {
        out.push(Implausible {
            field: "battery_percent",
            value: demo.battery_percent.to_string(),
            reason: format!("over {BATTERY_MAX_PERCENT} %"),
        });
    }
    let [vx, vy, vz] = demo.velocity_mps();
    let fields = [
        ("theta_deg", demo.pitch_deg(), ANGLE_MAX_DEG, "°"),
        ("phi_deg", demo.roll_deg(), ANGLE_MAX_DEG, "°"),
        ("psi_deg", demo.yaw_deg(), ANGLE_MAX_DEG, "°"),
        ("altitude_m", demo.altitude_m(), ALTITUDE_MAX_M, " m"),
        ("velocity_mps[0]", vx, SPEED_MAX_MPS, " m/s"),
        ("velocity_mps[1]", vy, SPEED_MAX_MPS, " m/s"),
        ("velocity_mps[2]", vz, SPEED_MAX_MPS, " m/s"),
    ];
    for (field, v, max, unit) in fields {
        let reason = if v.is_nan() {
            "not a number".to_string()
        } else if v.is_infinite() {
            "infinite".to_string()
        } else if v.abs() > max {
            format!("beyond ±{max}{unit}")
        } else {
            continue;
        };
        out.push(Implausible {
            field,
            value: number(v),
            reason,
        });
    }
    out
}

/// What a person checks before a flight (`dronecine status`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArDroneStatus {
    /// The major control state (`landed`, `hovering`, `taking_off`, …).
    pub ctrl_state: String,
    /// The minor control state (its meaning depends on the major).
    pub ctrl_minor: u16,
    pub battery_percent: u32,
    /// Pitch θ, roll φ, yaw ψ, degrees.
    pub theta_deg: f64,
    pub phi_deg: f64,
    pub psi_deg: f64,
    pub altitude_m: f64,
    /// The drone's own velocity estimate, m/s, body-horizontal frame.
    pub velocity_mps: [f64; 3],
    /// The set drone-state bits, by name, lowest bit first.
    pub flags: Vec<&'static str>,
    /// The flight state the flight loop would see.
    pub flight_state: FlightState,
    /// Sequence number of the last packet used.
    pub navdata_sequence: u32,
    /// Seconds since the last valid navdata.
    pub link_age_s: f64,
    /// Navdata packets from the drone's address since the previous read-out (the first:
    /// since connecting): used, old and rejected.
    pub navdata_received: u64,
    /// The rejected ones among them, by kind.
    pub navdata_rejected: NavdataRejected,
    /// The fields of the values above that no working AR.Drone sends ([`implausible`]).
    pub implausible: Vec<Implausible>,
    /// What makes this read-out untrustworthy, one sentence each: rejected packets (how
    /// many, of how many received), implausible fields, navdata older than
    /// [`NAVDATA_AGE_MAX_S`]. Empty when all is well.
    pub problems: Vec<String>,
}

/// The name of a major control state.
pub fn major_state_name(m: MajorState) -> String {
    match m {
        MajorState::Default => "default".into(),
        MajorState::Init => "init".into(),
        MajorState::Landed => "landed".into(),
        MajorState::Flying => "flying".into(),
        MajorState::Hovering => "hovering".into(),
        MajorState::Test => "test".into(),
        MajorState::TransTakeoff => "taking_off".into(),
        MajorState::TransGotofix => "goto_fix".into(),
        MajorState::TransLanding => "landing".into(),
        MajorState::TransLooping => "looping".into(),
        MajorState::Unknown(v) => format!("unknown({v})"),
    }
}

/// The flight state of a navdata packet: the emergency bit first, then the demo option's
/// control state, else (bootstrap packets, unnamed states) the flying bit.
pub fn flight_state(state: DroneState, demo: Option<&Demo>) -> FlightState {
    if state.emergency() {
        return FlightState::Emergency;
    }
    let by_bit = if state.flying() {
        FlightState::Flying
    } else {
        FlightState::Landed
    };
    match demo.map(|d| d.ctrl_state.major) {
        Some(MajorState::Default | MajorState::Init | MajorState::Landed) => FlightState::Landed,
        Some(
            MajorState::Flying
            | MajorState::Hovering
            | MajorState::TransGotofix
            | MajorState::TransLooping,
        ) => FlightState::Flying,
        Some(MajorState::TransTakeoff) => FlightState::TakingOff,
        Some(MajorState::TransLanding) => FlightState::Landing,
        Some(MajorState::Test | MajorState::Unknown(_)) | None => by_bit,
    }
}

/// An AR.Drone 2.0 over UDP (module docs).
pub struct ArDroneClient {
    url: ArDroneUrl,
    at_addr: SocketAddr,
    nav_addr: SocketAddr,
    at_socket: UdpSocket,
    nav_socket: UdpSocket,
    encoder: AtEncoder,
    at_buf: Box<[u8; AT_BUF_LEN]>,
    rx_buf: Box<[u8; navdata::NAVDATA_MAX_SIZE + 1]>,
    sequence: NavdataSequence,
    scratch: Navdata,
    /// The last packet used.
    navdata: Navdata,
    /// The last demo option seen.
    demo: Option<Demo>,
    last_navdata: Option<Instant>,
    last_trigger: Option<Instant>,
    last_sent: Option<Instant>,
    created: Instant,
    limits: Option<PcmdLimits>,
    goal: RefGoal,
    options: ArDroneOptions,
    stats: LinkStats,
    /// The counters at the previous status read-out.
    readout_stats: LinkStats,
    /// The last rejected packet of each kind since the previous status read-out.
    last_rejects: LastRejects,
}

impl std::fmt::Debug for ArDroneClient {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArDroneClient")
            .field("url", &self.url)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

fn link(msg: String) -> BackendError {
    BackendError::Link(msg)
}

fn bind_nonblocking(remote: SocketAddr, what: &str) -> Result<UdpSocket, BackendError> {
    let local: SocketAddr = if remote.is_ipv4() {
        ([0, 0, 0, 0], 0).into()
    } else {
        (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
    };
    let s = UdpSocket::bind(local)
        .map_err(|e| link(format!("cannot open the {what} socket for {remote}: {e}")))?;
    s.set_nonblocking(true)
        .map_err(|e| link(format!("cannot make the {what} socket non-blocking: {e}")))?;
    Ok(s)
}

impl ArDroneClient {
    /// Connects, starts navdata (demo mode) and writes the profile's limits to the drone
    /// (module docs). The profile's limits must be in the firmware's ranges.
    pub fn connect(
        url: &ArDroneUrl,
        profile: &Profile,
        options: &ArDroneOptions,
    ) -> Result<Self, BackendError> {
        let limits = PcmdLimits::from_profile(&profile.limits).map_err(|e| {
            BackendError::Refused(format!(
                "profile `{}` cannot be given to the AR.Drone: {e}",
                profile.name
            ))
        })?;
        let mut client = Self::monitor(url, options)?;
        for line in limits.config_lines() {
            client.configure(line.key, line.value())?;
        }
        client.limits = Some(limits);
        Ok(client)
    }

    /// Connects and starts navdata (demo mode) without touching the drone's control limits:
    /// for reading its state (`dronecine status`). [`Drone::send`] is refused until limits are
    /// given ([`ArDroneClient::connect`] does).
    pub fn monitor(url: &ArDroneUrl, options: &ArDroneOptions) -> Result<Self, BackendError> {
        let (at_addr, nav_addr) = url.resolve().map_err(|e| link(format!("{url}: {e}")))?;
        let now = Instant::now();
        let mut client = ArDroneClient {
            url: url.clone(),
            at_addr,
            nav_addr,
            at_socket: bind_nonblocking(at_addr, "AT command")?,
            nav_socket: bind_nonblocking(nav_addr, "navdata")?,
            encoder: AtEncoder::new(),
            at_buf: Box::new([0; AT_BUF_LEN]),
            rx_buf: Box::new([0; navdata::NAVDATA_MAX_SIZE + 1]),
            sequence: NavdataSequence::new(),
            scratch: Navdata::default(),
            navdata: Navdata::default(),
            demo: None,
            last_navdata: None,
            last_trigger: None,
            last_sent: None,
            created: now,
            limits: None,
            goal: RefGoal::Land,
            options: options.clone(),
            stats: LinkStats::default(),
            readout_stats: LinkStats::default(),
            last_rejects: [None; 4],
        };
        client.start_navdata()?;
        Ok(client)
    }

    /// The address the client was given.
    pub fn url(&self) -> &ArDroneUrl {
        &self.url
    }

    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// The limits the drone was given (`None` for [`ArDroneClient::monitor`]).
    pub fn limits(&self) -> Option<PcmdLimits> {
        self.limits
    }

    /// The last navdata packet used.
    pub fn navdata(&self) -> &Navdata {
        &self.navdata
    }

    /// Drains navdata and returns what a person checks before a flight, with the packets
    /// received since the previous read-out (the first: since connecting) and the problems.
    pub fn status(&mut self) -> ArDroneStatus {
        let telemetry = self.telemetry();
        let demo = self.demo.unwrap_or_default();
        let received = self.stats.navdata_received() - self.readout_stats.navdata_received();
        let rejected = self
            .stats
            .navdata_rejected
            .since(&self.readout_stats.navdata_rejected);
        let implausible = implausible(&demo);
        let mut problems: Vec<String> = reject_sentences(&rejected, received, &self.last_rejects)
            .into_iter()
            .map(|s| format!("navdata: {s}"))
            .collect();
        problems.extend(
            implausible
                .iter()
                .map(|i| format!("implausible {} {}: {}", i.field, i.value, i.reason)),
        );
        if telemetry.link_age_s > NAVDATA_AGE_MAX_S {
            problems.push(format!(
                "navdata: no valid packet for {:.1} s (over {NAVDATA_AGE_MAX_S} s): the values \
                 shown are that old",
                telemetry.link_age_s
            ));
        }
        self.readout_stats = self.stats;
        self.last_rejects = [None; 4];
        ArDroneStatus {
            ctrl_state: major_state_name(demo.ctrl_state.major),
            ctrl_minor: demo.ctrl_state.minor,
            battery_percent: demo.battery_percent,
            theta_deg: demo.pitch_deg(),
            phi_deg: demo.roll_deg(),
            psi_deg: demo.yaw_deg(),
            altitude_m: demo.altitude_m(),
            velocity_mps: demo.velocity_mps(),
            flags: self.navdata.state.flags().collect(),
            flight_state: telemetry.state,
            navdata_sequence: self.navdata.sequence,
            link_age_s: telemetry.link_age_s,
            navdata_received: received,
            navdata_rejected: rejected,
            implausible,
            problems,
        }
    }

    /// The packets rejected so far, one sentence per kind, joined; empty when none was.
    fn rejects_so_far(&self) -> String {
        reject_sentences(
            &self.stats.navdata_rejected,
            self.stats.navdata_received(),
            &self.last_rejects,
        )
        .join("; ")
    }

    // -----------------------------------------------------------------------------------
    // Sockets.

    /// Encodes `commands` (plus COMWDG when the last navdata asked for it) into one datagram
    /// and sends it. A send that would block drops the datagram.
    fn send_commands(&mut self, commands: &[AtCommand<'_>]) -> Result<(), BackendError> {
        let mut dg = Datagram::new(&mut self.at_buf[..]);
        for c in commands {
            self.encoder
                .push(&mut dg, c)
                .map_err(|e| BackendError::Refused(format!("AT*{}: {e}", c.name())))?;
        }
        if self.navdata.state.com_watchdog() {
            // Fits: the buffer holds far more than the commands used here.
            self.encoder
                .push(&mut dg, &AtCommand::Comwdg)
                .map_err(|e| BackendError::Refused(format!("AT*COMWDG: {e}")))?;
        }
        let len = dg.len();
        self.last_sent = Some(Instant::now());
        match self.at_socket.send_to(&self.at_buf[..len], self.at_addr) {
            Ok(_) => {
                self.stats.at_sent += 1;
                Ok(())
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                self.stats.at_dropped += 1;
                Ok(())
            }
            Err(e) => Err(link(format!(
                "sending AT commands to {}: {e}",
                self.at_addr
            ))),
        }
    }

    fn send_trigger(&mut self) -> Result<(), BackendError> {
        self.last_trigger = Some(Instant::now());
        match self.nav_socket.send_to(&NAVDATA_TRIGGER, self.nav_addr) {
            Ok(_) => {
                self.stats.triggers += 1;
                Ok(())
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(()),
            Err(e) => Err(link(format!(
                "sending the navdata trigger to {}: {e}",
                self.nav_addr
            ))),
        }
    }

    /// Reads every waiting navdata packet; returns how many were used.
    fn drain_navdata(&mut self) -> usize {
        let mut used = 0;
        // Until WouldBlock (or an ICMP error of an earlier send: read again next call).
        while let Ok((n, from)) = self.nav_socket.recv_from(&mut self.rx_buf[..]) {
            if from.ip() != self.nav_addr.ip() {
                self.stats.foreign += 1;
                continue;
            }
            if let Err(e) = navdata::decode(&self.rx_buf[..n], &mut self.scratch) {
                self.stats.navdata_malformed += 1;
                let kind = NavdataReject::of(&e, n);
                self.stats.navdata_rejected.add(kind);
                self.last_rejects[kind as usize] = Some((e, n));
                continue;
            }
            if !self
                .sequence
                .accept(self.scratch.sequence, self.scratch.state)
            {
                self.stats.navdata_stale += 1;
                continue;
            }
            self.navdata = self.scratch;
            if let Some(d) = self.navdata.demo {
                self.demo = Some(d);
            }
            self.last_navdata = Some(Instant::now());
            self.stats.navdata_accepted += 1;
            used += 1;
        }
        used
    }

    /// Re-sends the trigger when navdata went quiet.
    fn retrigger_if_quiet(&mut self) -> Result<(), BackendError> {
        let now = Instant::now();
        let quiet = self
            .last_navdata
            .is_none_or(|t| now.duration_since(t) >= NAVDATA_RETRIGGER);
        let due = self
            .last_trigger
            .is_none_or(|t| now.duration_since(t) >= TRIGGER_PERIOD);
        if quiet && due {
            self.sequence.reset();
            self.send_trigger()?;
        }
        Ok(())
    }

    // -----------------------------------------------------------------------------------
    // Start-up.

    /// Polls (navdata, `tick` every 30 ms) until `done` holds or the deadline passes.
    fn wait_until(
        &mut self,
        timeout: Duration,
        mut tick: impl FnMut(&mut Self, bool) -> Result<(), BackendError>,
        done: impl Fn(&Self) -> bool,
    ) -> Result<bool, BackendError> {
        let deadline = Instant::now() + timeout;
        let mut first = true;
        let mut last_tick: Option<Instant> = None;
        loop {
            self.drain_navdata();
            if done(self) {
                return Ok(true);
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(false);
            }
            if last_tick.is_none_or(|t| now.duration_since(t) >= KEEP_ALIVE) {
                tick(self, first)?;
                first = false;
                last_tick = Some(now);
            }
            std::thread::sleep(POLL_SLEEP);
        }
    }

    fn start_navdata(&mut self) -> Result<(), BackendError> {
        let timeout = self.options.navdata_timeout;
        let got = self.wait_until(
            timeout,
            |c, _| c.retrigger_if_quiet(),
            |c| c.last_navdata.is_some(),
        )?;
        if !got && self.stats.navdata_malformed > 0 {
            return Err(link(format!(
                "navdata arrives from the AR.Drone at {} but no packet was valid within {:.1} s: \
                 {} ({})",
                self.nav_addr,
                timeout.as_secs_f64(),
                self.rejects_so_far(),
                self.url
            )));
        }
        if !got {
            return Err(link(format!(
                "no navdata from the AR.Drone at {} within {:.1} s (trigger sent {} times): is \
                 it switched on, and this computer on its Wi-Fi? ({})",
                self.nav_addr,
                timeout.as_secs_f64(),
                self.stats.triggers,
                self.url
            )));
        }
        let demo_mode =
            |c: &Self| c.navdata.demo.is_some() && c.navdata.state.has(DroneState::NAVDATA_DEMO);
        if !demo_mode(self) {
            self.configure("general:navdata_demo", "TRUE")?;
            let got = self.wait_until(timeout, |c, _| c.keep_alive(), demo_mode)?;
            if !got {
                let rejects = self.rejects_so_far();
                return Err(link(format!(
                    "the AR.Drone at {} acknowledged general:navdata_demo but sent no demo \
                     navdata within {:.1} s{}{rejects}",
                    self.nav_addr,
                    timeout.as_secs_f64(),
                    if rejects.is_empty() { "" } else { ": " },
                )));
            }
        }
        Ok(())
    }

    /// Writes one configuration key with the acknowledgement handshake (module docs).
    pub fn configure(&mut self, key: &str, value: &str) -> Result<(), BackendError> {
        let timeout = self.options.ack_timeout;
        let ack = |c: &Self| c.navdata.state.command_ack();
        let addr = self.at_addr;
        let fail = |what: &str| {
            link(format!(
                "the AR.Drone at {addr} {what} within {:.1} s (CONFIG \"{key}\" = \"{value}\")",
                timeout.as_secs_f64()
            ))
        };
        if ack(self) && !self.wait_until(timeout, |c, _| c.send_ctrl_ack(), |c| !ack(c))? {
            return Err(fail("kept the command-ACK bit of an earlier command"));
        }
        let mut last_config: Option<Instant> = None;
        let sent = self.wait_until(
            timeout,
            |c, _| {
                if last_config.is_none_or(|t| t.elapsed() >= CONFIG_RESEND) {
                    last_config = Some(Instant::now());
                    c.send_config(key, value)
                } else {
                    c.keep_alive_now()
                }
            },
            ack,
        )?;
        if !sent {
            return Err(fail(
                "did not acknowledge the configuration (no command-ACK bit)",
            ));
        }
        if !self.wait_until(timeout, |c, _| c.send_ctrl_ack(), |c| !ack(c))? {
            return Err(fail(
                "did not clear the command-ACK bit after AT*CTRL=…,5,0",
            ));
        }
        Ok(())
    }

    fn send_config(&mut self, key: &str, value: &str) -> Result<(), BackendError> {
        let config = AtCommand::Config { key, value };
        match self.options.config_ids.take() {
            Some(ids) => {
                let r = self.send_commands(&[
                    AtCommand::ConfigIds {
                        session: &ids.session,
                        user: &ids.user,
                        application: &ids.application,
                    },
                    config,
                ]);
                self.options.config_ids = Some(ids);
                r
            }
            None => self.send_commands(&[config]),
        }
    }

    fn send_ctrl_ack(&mut self) -> Result<(), BackendError> {
        self.send_commands(&[AtCommand::ACK])
    }

    // -----------------------------------------------------------------------------------
    // Flying.

    fn ref_command(&self) -> AtCommand<'static> {
        match self.goal {
            RefGoal::Land => AtCommand::LAND,
            RefGoal::Fly => AtCommand::TAKE_OFF,
            // The emergency bit toggles: set it until navdata shows the emergency, then
            // plain REF (so the next REF does not clear it again).
            RefGoal::Emergency if self.navdata.state.emergency() => {
                AtCommand::Ref { input: REF_BASE }
            }
            RefGoal::Emergency => AtCommand::EMERGENCY,
        }
    }

    /// The REF of the current goal, at once. A monitoring client (no limits) never sends a
    /// REF of its own (another pilot may be flying the drone): only COMWDG when asked.
    fn keep_alive_now(&mut self) -> Result<(), BackendError> {
        if self.limits.is_none() && self.goal == RefGoal::Land {
            if self.navdata.state.com_watchdog() {
                return self.send_commands(&[]);
            }
            return Ok(());
        }
        let r = self.ref_command();
        self.send_commands(&[r])
    }

    /// The REF of the current goal when nothing went out for [`KEEP_ALIVE`].
    fn keep_alive(&mut self) -> Result<(), BackendError> {
        if self.last_sent.is_none_or(|t| t.elapsed() >= KEEP_ALIVE) {
            self.keep_alive_now()?;
        }
        Ok(())
    }

    fn current_state(&self) -> FlightState {
        flight_state(
            self.navdata.state,
            self.navdata.demo.as_ref().or(self.demo.as_ref()),
        )
    }

    fn send_pcmd(&mut self, pcmd: Pcmd) -> Result<(), BackendError> {
        let r = self.ref_command();
        self.send_commands(&[r, AtCommand::Pcmd(pcmd)])
    }
}

impl Drone for ArDroneClient {
    /// `AT*FTRIM` (twice, in two datagrams) when the drone is on the ground, then `AT*REF`
    /// take-off, repeated by every later datagram until navdata shows the drone flying.
    fn take_off(&mut self) -> Result<(), BackendError> {
        self.drain_navdata();
        match self.current_state() {
            FlightState::Emergency => {
                return Err(BackendError::Refused(format!(
                    "the AR.Drone at {} is in emergency (flags: {}): clear it (restart the \
                     drone) before taking off",
                    self.at_addr,
                    self.navdata.state.flags().collect::<Vec<_>>().join(", ")
                )))
            }
            FlightState::Landed => {
                for _ in 0..2 {
                    self.send_commands(&[AtCommand::Ftrim])?;
                }
            }
            _ => {}
        }
        self.goal = RefGoal::Fly;
        self.send_pcmd(Pcmd::HOVER)
    }

    fn land(&mut self) -> Result<(), BackendError> {
        self.goal = RefGoal::Land;
        self.send_pcmd(Pcmd::HOVER)
    }

    /// `AT*REF` with the emergency bit (repeated until navdata shows the emergency).
    fn emergency(&mut self) -> Result<(), BackendError> {
        self.goal = RefGoal::Emergency;
        self.keep_alive_now()
    }

    fn send(&mut self, command: &Command) -> Result<(), BackendError> {
        let Some(limits) = self.limits else {
            return Err(BackendError::Refused(
                "the AR.Drone client was opened for monitoring only (no limits written): \
                 connect with a profile to fly"
                    .into(),
            ));
        };
        self.send_pcmd(limits.pcmd(command))
    }

    fn hover(&mut self) -> Result<(), BackendError> {
        self.send_pcmd(Pcmd::HOVER)
    }

    fn telemetry(&mut self) -> Telemetry {
        self.drain_navdata();
        // Errors here are the socket's; the link age shows them to the loop's failsafes.
        let _ = self.retrigger_if_quiet();
        let _ = self.keep_alive();
        let now = Instant::now();
        Telemetry {
            state: self.current_state(),
            battery_percent: self.demo.map_or(0.0, |d| f64::from(d.battery_percent)),
            link_age_s: now
                .duration_since(self.last_navdata.unwrap_or(self.created))
                .as_secs_f64(),
        }
    }
}
