//! Backend addresses as the command line takes them:
//!
//! - `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`: an AR.Drone 2.0 (protocols.md §1.1; AT
//!   commands default to UDP 5556, navdata to UDP 5554). The drone's own Wi-Fi puts it at
//!   `192.168.1.1`.
//! - `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`: an OptiTrack Motive
//!   server (protocols.md §4.1; command port 1510, data port 1511, multicast group
//!   239.255.42.99 unless `unicast` is given).
//!
//! HOST / SERVER is a name, an IPv4 address or a bracketed IPv6 address (`[::1]`). Parsing
//! checks the form only; names are resolved when the backend connects.

use std::fmt;
use std::net::{Ipv4Addr, SocketAddr, ToSocketAddrs};

use crate::natnet::frame::{COMMAND_PORT, DATA_PORT, MULTICAST_GROUP};

/// The AR.Drone's AT command port.
pub const ARDRONE_AT_PORT: u16 = 5556;
/// The AR.Drone's navdata port.
pub const ARDRONE_NAVDATA_PORT: u16 = 5554;

/// Why an address was refused; the message says what form is expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UrlError(pub String);

impl fmt::Display for UrlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UrlError {}

/// `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArDroneUrl {
    /// Without brackets for IPv6.
    pub host: String,
    pub at_port: u16,
    pub navdata_port: u16,
}

/// How the NatNet client receives frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NatNetTransport {
    /// Join this group on the data port.
    Multicast(Ipv4Addr),
    /// The server sends frames to this client directly.
    Unicast,
}

/// `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NatNetUrl {
    pub server: String,
    /// The server's command port (the handshake).
    pub command_port: u16,
    /// The data port frames are streamed to.
    pub data_port: u16,
    pub transport: NatNetTransport,
}

const ARDRONE_FORM: &str = "ardrone://HOST[:AT_PORT[:NAVDATA_PORT]], e.g. ardrone://192.168.1.1";
const NATNET_FORM: &str =
    "natnet://SERVER[:PORT][?multicast=GROUP|unicast], e.g. natnet://192.168.1.10";

/// Splits `HOST[:a[:b]]` (HOST possibly `[v6]`) into the host and the port fields.
fn split_host_ports<'a>(rest: &'a str, form: &str) -> Result<(&'a str, Vec<&'a str>), UrlError> {
    let (host, ports) = if let Some(r) = rest.strip_prefix('[') {
        let close = r
            .find(']')
            .ok_or_else(|| UrlError(format!("`[` without `]` in the host: expected {form}")))?;
        let after = &r[close + 1..];
        let ports = match after.strip_prefix(':') {
            Some(p) => p.split(':').collect(),
            None if after.is_empty() => Vec::new(),
            None => {
                return Err(UrlError(format!(
                    "unexpected `{after}` after the host: expected {form}"
                )))
            }
        };
        (&r[..close], ports)
    } else {
        let mut it = rest.split(':');
        let host = it.next().unwrap_or("");
        (host, it.collect())
    };
    if host.is_empty() {
        return Err(UrlError(format!("no host: expected {form}")));
    }
    if host.contains(['/', '?', '@', ' ']) {
        return Err(UrlError(format!("`{host}` is not a host: expected {form}")));
    }
    Ok((host, ports))
}

fn port(text: &str, what: &str) -> Result<u16, UrlError> {
    match text.parse::<u16>() {
        Ok(p) if p > 0 => Ok(p),
        _ => Err(UrlError(format!(
            "{what} `{text}` is not a port number (1–65535)"
        ))),
    }
}

fn strip_scheme<'a>(text: &'a str, scheme: &str, form: &str) -> Result<&'a str, UrlError> {
    match text.split_once("://") {
        Some((s, rest)) if s.eq_ignore_ascii_case(scheme) => Ok(rest),
        Some((s, _)) => Err(UrlError(format!(
            "unknown scheme `{s}://` in `{text}`: expected {form}"
        ))),
        None => Err(UrlError(format!("`{text}` has no scheme: expected {form}"))),
    }
}

impl ArDroneUrl {
    pub fn parse(text: &str) -> Result<Self, UrlError> {
        let rest = strip_scheme(text.trim(), "ardrone", ARDRONE_FORM)?;
        let rest = rest.strip_suffix('/').unwrap_or(rest);
        let (host, ports) = split_host_ports(rest, ARDRONE_FORM)?;
        if ports.len() > 2 {
            return Err(UrlError(format!(
                "too many ports in `{text}`: expected {ARDRONE_FORM}"
            )));
        }
        Ok(ArDroneUrl {
            host: host.to_string(),
            at_port: match ports.first() {
                Some(p) => port(p, "AT port")?,
                None => ARDRONE_AT_PORT,
            },
            navdata_port: match ports.get(1) {
                Some(p) => port(p, "navdata port")?,
                None => ARDRONE_NAVDATA_PORT,
            },
        })
    }

    /// The AT and navdata socket addresses (the first address the host resolves to).
    pub fn resolve(&self) -> Result<(SocketAddr, SocketAddr), UrlError> {
        Ok((
            resolve(&self.host, self.at_port)?,
            resolve(&self.host, self.navdata_port)?,
        ))
    }
}

impl fmt::Display for ArDroneUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "ardrone://{}:{}:{}",
            bracket(&self.host),
            self.at_port,
            self.navdata_port
        )
    }
}

impl NatNetUrl {
    pub fn parse(text: &str) -> Result<Self, UrlError> {
        let rest = strip_scheme(text.trim(), "natnet", NATNET_FORM)?;
        let (addr, query) = match rest.split_once('?') {
            Some((a, q)) => (a, Some(q)),
            None => (rest, None),
        };
        let addr = addr.strip_suffix('/').unwrap_or(addr);
        let (server, ports) = split_host_ports(addr, NATNET_FORM)?;
        if ports.len() > 1 {
            return Err(UrlError(format!(
                "too many ports in `{text}`: expected {NATNET_FORM} (the data port is \
                 `?data_port=N`)"
            )));
        }
        let mut url = NatNetUrl {
            server: server.to_string(),
            command_port: match ports.first() {
                Some(p) => port(p, "command port")?,
                None => COMMAND_PORT,
            },
            data_port: DATA_PORT,
            transport: NatNetTransport::Multicast(Ipv4Addr::from(MULTICAST_GROUP)),
        };
        let mut transport_given = false;
        for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
            let (key, value) = match pair.split_once('=') {
                Some((k, v)) => (k, Some(v)),
                None => (pair, None),
            };
            match (key, value) {
                ("multicast", Some(group)) if !transport_given => {
                    let g: Ipv4Addr = group.parse().map_err(|_| {
                        UrlError(format!("multicast group `{group}` is not an IPv4 address"))
                    })?;
                    if !g.is_multicast() {
                        return Err(UrlError(format!(
                            "`{g}` is not a multicast address (224.0.0.0–239.255.255.255); \
                             Motive's default is 239.255.42.99"
                        )));
                    }
                    url.transport = NatNetTransport::Multicast(g);
                    transport_given = true;
                }
                ("unicast", None | Some("" | "1" | "true")) if !transport_given => {
                    url.transport = NatNetTransport::Unicast;
                    transport_given = true;
                }
                ("multicast" | "unicast", _) if transport_given => {
                    return Err(UrlError(format!(
                        "`{text}` asks for the transport twice: give either \
                         `multicast=GROUP` or `unicast`"
                    )))
                }
                ("data_port", Some(p)) => url.data_port = port(p, "data port")?,
                _ => {
                    return Err(UrlError(format!(
                        "unknown option `{pair}` in `{text}`: the options are \
                         multicast=GROUP, unicast, data_port=N"
                    )))
                }
            }
        }
        Ok(url)
    }

    /// The server's command address (the first address the name resolves to).
    pub fn command_addr(&self) -> Result<SocketAddr, UrlError> {
        resolve(&self.server, self.command_port)
    }
}

impl fmt::Display for NatNetUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "natnet://{}:{}",
            bracket(&self.server),
            self.command_port
        )?;
        match self.transport {
            NatNetTransport::Multicast(g) => write!(f, "?multicast={g}")?,
            NatNetTransport::Unicast => write!(f, "?unicast")?,
        }
        if self.data_port != DATA_PORT {
            write!(f, "&data_port={}", self.data_port)?;
        }
        Ok(())
    }
}

fn bracket(host: &str) -> String {
    if host.contains(':') {
        format!("[{host}]")
    } else {
        host.to_string()
    }
}

fn resolve(host: &str, port: u16) -> Result<SocketAddr, UrlError> {
    (host, port)
        .to_socket_addrs()
        .map_err(|e| UrlError(format!("cannot resolve `{host}`: {e}")))?
        .next()
        .ok_or_else(|| UrlError(format!("`{host}` resolves to no address")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ardrone_defaults_and_ports() {
        let u = ArDroneUrl::parse("ardrone://192.168.1.1").unwrap();
        assert_eq!(
            (u.host.as_str(), u.at_port, u.navdata_port),
            ("192.168.1.1", 5556, 5554)
        );
        let u = ArDroneUrl::parse("ardrone://127.0.0.1:7000:7001").unwrap();
        assert_eq!((u.at_port, u.navdata_port), (7000, 7001));
        let u = ArDroneUrl::parse("ardrone://[::1]:7000").unwrap();
        assert_eq!(
            (u.host.as_str(), u.at_port, u.navdata_port),
            ("::1", 7000, 5554)
        );
        assert_eq!(u.to_string(), "ardrone://[::1]:7000:5554");
    }

    #[test]
    fn ardrone_errors_say_what_is_expected() {
        for (text, needle) in [
            ("192.168.1.1", "no scheme"),
            ("natnet://x", "unknown scheme"),
            ("ardrone://", "no host"),
            ("ardrone://h:0", "not a port"),
            ("ardrone://h:70000", "not a port"),
            ("ardrone://h:1:2:3", "too many ports"),
            ("ardrone://[::1", "without `]`"),
        ] {
            let e = ArDroneUrl::parse(text).unwrap_err().0;
            assert!(e.contains(needle), "{text}: {e}");
        }
    }

    #[test]
    fn natnet_defaults_multicast_unicast() {
        let u = NatNetUrl::parse("natnet://10.0.0.5").unwrap();
        assert_eq!(u.command_port, 1510);
        assert_eq!(u.data_port, 1511);
        assert_eq!(
            u.transport,
            NatNetTransport::Multicast(Ipv4Addr::new(239, 255, 42, 99))
        );
        let u = NatNetUrl::parse("natnet://10.0.0.5:2000?unicast&data_port=2001").unwrap();
        assert_eq!((u.command_port, u.data_port), (2000, 2001));
        assert_eq!(u.transport, NatNetTransport::Unicast);
        let u = NatNetUrl::parse("natnet://srv?multicast=239.1.2.3").unwrap();
        assert_eq!(
            u.transport,
            NatNetTransport::Multicast(Ipv4Addr::new(239, 1, 2, 3))
        );
        assert_eq!(u.to_string(), "natnet://srv:1510?multicast=239.1.2.3");
        for (text, needle) in [
            ("natnet://srv?multicast=10.0.0.1", "not a multicast"),
            ("natnet://srv?multicast=abc", "not an IPv4"),
            ("natnet://srv?unicast&multicast=239.1.2.3", "twice"),
            ("natnet://srv?speed=3", "unknown option"),
            ("natnet://srv:1:2", "too many ports"),
        ] {
            let e = NatNetUrl::parse(text).unwrap_err().0;
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
