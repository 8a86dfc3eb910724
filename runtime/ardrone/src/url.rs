//! `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`: an AR.Drone 2.0's address (AT commands default
//! to UDP 5556, navdata to UDP 5554). The drone's own Wi-Fi puts it at `192.168.1.1`.

use std::fmt;
use std::net::SocketAddr;

use dronecine_backend::address::{
    bracket, port, resolve, split_host_ports, strip_scheme, UrlError,
};

/// The AR.Drone's AT command port.
pub const ARDRONE_AT_PORT: u16 = 5556;
/// The AR.Drone's navdata port.
pub const ARDRONE_NAVDATA_PORT: u16 = 5554;

/// `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArDroneUrl {
    /// Without brackets for IPv6.
    pub host: String,
    pub at_port: u16,
    pub navdata_port: u16,
}

const ARDRONE_FORM: &str = "ardrone://HOST[:AT_PORT[:NAVDATA_PORT]], e.g. ardrone://192.168.1.1";
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
}
