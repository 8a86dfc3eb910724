//! `mavlink://…`: a MAVLink vehicle's address, in one of four forms.
//!
//! - `mavlink://udp:HOST:PORT`: this computer sends to the vehicle at HOST:PORT from a port
//!   of its own, and the vehicle answers there (a UDP server on the vehicle's side, such as
//!   a companion computer's router or a telemetry bridge).
//! - `mavlink://udpin:HOST:PORT`: this computer listens on HOST:PORT and answers whoever
//!   sent the last datagram (a vehicle that sends out to a ground station, such as ArduCopter
//!   SITL started with `--serial0 udpclient:127.0.0.1:14550`). Nothing goes out until the
//!   vehicle's first datagram arrives.
//! - `mavlink://tcp:HOST:PORT`: this computer connects to the vehicle (ArduCopter SITL
//!   listens on TCP 5760).
//! - `mavlink:///dev/ttyACM0?baud=115200`: a serial port (a USB or radio link), 115200 baud
//!   unless `baud` says otherwise.
//!
//! Any form takes `origin=LAT,LON[,ALT]` (`?origin=…`, or `&origin=…` after `baud`): where on
//! Earth the stage is (degrees, and metres above mean sea level), which the EKF's origin is
//! set to. The autopilot checks its compass against the Earth's field there, and takes its
//! magnetic declination from it: a simulator's origin is its home.

use std::fmt;

use dronecine_backend::address::{bracket, port, split_host_ports, strip_scheme, UrlError};

/// The serial link's speed when the address gives none.
pub const DEFAULT_BAUD: u32 = 115_200;

const MAVLINK_FORM: &str = "mavlink://udp:HOST:PORT, mavlink://udpin:HOST:PORT, \
                            mavlink://tcp:HOST:PORT or mavlink:///dev/PORT?baud=N, e.g. \
                            mavlink://tcp:127.0.0.1:5760";

/// How this computer reaches the vehicle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MavlinkLink {
    /// UDP, sending to the vehicle's address.
    Udp { host: String, port: u16 },
    /// UDP, listening on this address for the vehicle.
    UdpIn { host: String, port: u16 },
    /// TCP, connecting to the vehicle.
    Tcp { host: String, port: u16 },
    /// A serial port at `baud` bits per second.
    Serial { path: String, baud: u32 },
}

/// A parsed `mavlink://` address (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct MavlinkUrl {
    pub link: MavlinkLink,
    /// `origin=`: latitude and longitude in degrees, altitude in metres (0 unless given).
    pub origin: Option<[f64; 3]>,
}

/// The options an address's query holds.
#[derive(Default)]
struct Query {
    baud: Option<u32>,
    origin: Option<[f64; 3]>,
}

/// `baud=N` (serial ports only) and `origin=LAT,LON[,ALT]`, joined by `&`.
fn parse_query(query: Option<&str>, serial: bool) -> Result<Query, UrlError> {
    let mut q = Query::default();
    for pair in query.into_iter().flat_map(|q| q.split('&')) {
        match pair.split_once('=') {
            Some(("baud", value)) if serial => q.baud = Some(parse_baud(value)?),
            Some(("origin", value)) => q.origin = Some(parse_origin(value)?),
            _ => {
                return Err(UrlError(format!(
                    "unknown option `{pair}`: expected {}origin=LAT,LON[,ALT]",
                    if serial { "baud=N or " } else { "" }
                )))
            }
        }
    }
    Ok(q)
}

/// `LAT,LON[,ALT]`: degrees within ±90 and ±180, metres.
fn parse_origin(text: &str) -> Result<[f64; 3], UrlError> {
    let bad = || {
        UrlError(format!(
            "origin `{text}` is not LAT,LON[,ALT] (degrees, and metres above sea level), e.g. \
             origin=-35.363261,149.165230,584"
        ))
    };
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let (lat, lon, alt) = match parts.as_slice() {
        [lat, lon] => (*lat, *lon, 0.0),
        [lat, lon, alt] => (*lat, *lon, *alt),
        _ => return Err(bad()),
    };
    let ok = lat.abs() <= 90.0 && lon.abs() <= 180.0 && alt.is_finite() && alt.abs() < 1e5;
    if !ok || (lat == 0.0 && lon == 0.0) {
        return Err(bad());
    }
    Ok([lat, lon, alt])
}

impl MavlinkUrl {
    /// Parses one of the four forms; the error says which form is expected.
    pub fn parse(text: &str) -> Result<Self, UrlError> {
        let rest = strip_scheme(text.trim(), "mavlink", MAVLINK_FORM)?;
        if rest.starts_with('/') {
            return parse_serial(rest);
        }
        let (rest, query) = match rest.split_once('?') {
            Some((r, q)) => (r, Some(q)),
            None => (rest, None),
        };
        let origin = parse_query(query, false)?.origin;
        let Some((kind, addr)) = rest.split_once(':') else {
            return Err(UrlError(format!(
                "`{text}` names no link: expected {MAVLINK_FORM}"
            )));
        };
        let addr = addr.strip_suffix('/').unwrap_or(addr);
        let (host, ports) = split_host_ports(addr, MAVLINK_FORM)?;
        let port = match ports.as_slice() {
            [p] => port(p, "port")?,
            [] => {
                return Err(UrlError(format!(
                    "no port in `{text}`: expected {MAVLINK_FORM}"
                )))
            }
            _ => {
                return Err(UrlError(format!(
                    "too many ports in `{text}`: expected {MAVLINK_FORM}"
                )))
            }
        };
        let host = host.to_string();
        let link = match kind.to_ascii_lowercase().as_str() {
            "udp" | "udpout" => MavlinkLink::Udp { host, port },
            "udpin" => MavlinkLink::UdpIn { host, port },
            "tcp" => MavlinkLink::Tcp { host, port },
            other => {
                return Err(UrlError(format!(
                    "unknown link `{other}` in `{text}`: expected {MAVLINK_FORM}"
                )))
            }
        };
        Ok(MavlinkUrl { link, origin })
    }

    /// The address in the `mavlink` crate's own form (`udpout:HOST:PORT`, `tcpout:…`,
    /// `serial:PATH:BAUD`).
    pub fn connection_string(&self) -> String {
        match &self.link {
            MavlinkLink::Udp { host, port } => format!("udpout:{}:{port}", bracket(host)),
            MavlinkLink::UdpIn { host, port } => format!("udpin:{}:{port}", bracket(host)),
            MavlinkLink::Tcp { host, port } => format!("tcpout:{}:{port}", bracket(host)),
            MavlinkLink::Serial { path, baud } => format!("serial:{path}:{baud}"),
        }
    }
}

/// `/dev/PORT[?baud=N]`.
fn parse_serial(rest: &str) -> Result<MavlinkUrl, UrlError> {
    let (path, query) = match rest.split_once('?') {
        Some((p, q)) => (p, Some(q)),
        None => (rest, None),
    };
    if path.len() < 2 || path.ends_with('/') || path.contains([' ', ':']) {
        return Err(UrlError(format!(
            "`{path}` is not a serial port: expected {MAVLINK_FORM}"
        )));
    }
    let q = parse_query(query, true)?;
    Ok(MavlinkUrl {
        link: MavlinkLink::Serial {
            path: path.to_string(),
            baud: q.baud.unwrap_or(DEFAULT_BAUD),
        },
        origin: q.origin,
    })
}

/// A baud rate: a positive whole number of bits per second.
fn parse_baud(text: &str) -> Result<u32, UrlError> {
    match text.parse::<u32>() {
        Ok(b) if b > 0 => Ok(b),
        _ => Err(UrlError(format!(
            "baud `{text}` is not a speed in bits per second (e.g. 57600, 115200, 921600)"
        ))),
    }
}

impl fmt::Display for MavlinkUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.link {
            MavlinkLink::Udp { host, port } => write!(f, "mavlink://udp:{}:{port}", bracket(host))?,
            MavlinkLink::UdpIn { host, port } => {
                write!(f, "mavlink://udpin:{}:{port}", bracket(host))?
            }
            MavlinkLink::Tcp { host, port } => write!(f, "mavlink://tcp:{}:{port}", bracket(host))?,
            MavlinkLink::Serial { path, baud } => write!(f, "mavlink://{path}?baud={baud}")?,
        }
        if let Some([lat, lon, alt]) = self.origin {
            let sep = if matches!(self.link, MavlinkLink::Serial { .. }) {
                '&'
            } else {
                '?'
            };
            write!(f, "{sep}origin={lat},{lon},{alt}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link(text: &str) -> MavlinkLink {
        MavlinkUrl::parse(text).unwrap().link
    }

    #[test]
    fn the_four_forms() {
        let net = |host: &str, port| (host.to_string(), port);
        assert!(matches!(link("mavlink://udp:127.0.0.1:14550"),
            MavlinkLink::Udp { host, port } if (host.clone(), port) == net("127.0.0.1", 14550)));
        assert!(matches!(link("MAVLINK://UDPIN:0.0.0.0:14550/"),
            MavlinkLink::UdpIn { host, port } if (host.clone(), port) == net("0.0.0.0", 14550)));
        assert!(matches!(link("mavlink://tcp:[::1]:5760"),
            MavlinkLink::Tcp { host, port } if (host.clone(), port) == net("::1", 5760)));
        assert_eq!(
            link("mavlink:///dev/ttyACM0?baud=921600"),
            MavlinkLink::Serial {
                path: "/dev/ttyACM0".into(),
                baud: 921_600
            }
        );
        assert_eq!(
            link("mavlink:///dev/ttyUSB1"),
            MavlinkLink::Serial {
                path: "/dev/ttyUSB1".into(),
                baud: DEFAULT_BAUD
            }
        );
    }

    #[test]
    fn display_and_the_crates_form_round_trip() {
        for (text, crate_form) in [
            ("mavlink://udp:127.0.0.1:14550", "udpout:127.0.0.1:14550"),
            ("mavlink://udpin:0.0.0.0:14550", "udpin:0.0.0.0:14550"),
            ("mavlink://tcp:[::1]:5760", "tcpout:[::1]:5760"),
            (
                "mavlink:///dev/ttyACM0?baud=115200",
                "serial:/dev/ttyACM0:115200",
            ),
            (
                "mavlink://tcp:127.0.0.1:5760?origin=-35.363261,149.16523,584",
                "tcpout:127.0.0.1:5760",
            ),
            (
                "mavlink:///dev/ttyUSB0?baud=57600&origin=48.85,2.35,35",
                "serial:/dev/ttyUSB0:57600",
            ),
        ] {
            let u = MavlinkUrl::parse(text).unwrap();
            assert_eq!(u.to_string(), text);
            assert_eq!(u.connection_string(), crate_form);
            assert_eq!(MavlinkUrl::parse(&u.to_string()).unwrap(), u);
        }
    }

    #[test]
    fn errors_say_what_is_expected() {
        for (text, needle) in [
            ("tcp:127.0.0.1:5760", "no scheme"),
            ("ardrone://h", "unknown scheme"),
            ("mavlink://localhost", "names no link"),
            ("mavlink://serial:h:1", "unknown link `serial`"),
            ("mavlink://tcp:h", "no port"),
            ("mavlink://tcp::5760", "no host"),
            ("mavlink://udp:h:1:2", "too many ports"),
            ("mavlink://udp:h:0", "not a port"),
            ("mavlink://udp:h:99999", "not a port"),
            ("mavlink://udp:[::1:5", "without `]`"),
            ("mavlink:///dev/ttyACM0?baud=0", "not a speed"),
            ("mavlink:///dev/ttyACM0?baud=fast", "not a speed"),
            ("mavlink:///dev/ttyACM0?parity=odd", "unknown option"),
            ("mavlink://tcp:h:5760?baud=9600", "unknown option"),
            ("mavlink://tcp:h:5760?origin=91,0", "is not LAT,LON"),
            ("mavlink://tcp:h:5760?origin=0,0", "is not LAT,LON"),
            ("mavlink://tcp:h:5760?origin=1", "is not LAT,LON"),
            ("mavlink://tcp:h:5760?origin=a,b", "is not LAT,LON"),
            ("mavlink:///", "not a serial port"),
            ("mavlink:///dev/", "not a serial port"),
        ] {
            let e = MavlinkUrl::parse(text).unwrap_err().0;
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
