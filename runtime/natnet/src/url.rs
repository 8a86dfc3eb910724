//! `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`: an OptiTrack Motive
//! server's address (command port 1510, data port 1511, multicast group 239.255.42.99 unless
//! `unicast` is given).

use std::fmt;
use std::net::{Ipv4Addr, SocketAddr};

use dronecine_backend::address::{
    bracket, port, resolve, split_host_ports, strip_scheme, UrlError,
};

use crate::frame::{COMMAND_PORT, DATA_PORT, MULTICAST_GROUP};

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

const NATNET_FORM: &str =
    "natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N], e.g. natnet://192.168.1.10";

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

#[cfg(test)]
mod tests {
    use super::*;

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
