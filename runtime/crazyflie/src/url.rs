//! `crazyflie+…://`: a Crazyflie's address, the link URI its users already write with the
//! scheme prefixed by `crazyflie+` (the scheme names the drone; the rest is the link's).
//!
//! - `crazyflie+radio://N/CHANNEL[/RATE[/ADDRESS]][?OPTIONS]`: through the N-th Crazyradio
//!   (0 for the first), on radio channel 0–125, at 250K, 1M or 2M (2M when not given), to the
//!   five-byte address written as ten hex digits (E7E7E7E7E7 when not given). OPTIONS are
//!   `crazyflie-link`'s: `safelink=0|1`, `ackfilter=0|1`, `timeout=MS`.
//! - `crazyflie+udp://HOST[:PORT]`: one CRTP packet per datagram to HOST:PORT, as cflib's
//!   UDP driver sends them (the simulators' link, and `dronecine emulate crazyflie`); PORT
//!   19850 when not given (cflib's first).

use std::fmt;

use dronecine_backend::address::{bracket, port, split_host_ports, UrlError};

/// The UDP port a Crazyflie simulator listens on when the address names none (cflib scans
/// from it).
pub const DEFAULT_UDP_PORT: u16 = 19850;

const FORM: &str = "crazyflie+radio://N/CHANNEL/RATE/ADDRESS (e.g. \
                    crazyflie+radio://0/80/2M/E7E7E7E7E7) or crazyflie+udp://HOST:PORT";

/// A radio's data rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataRate {
    Kbps250,
    Mbps1,
    Mbps2,
}

impl DataRate {
    pub fn as_str(self) -> &'static str {
        match self {
            DataRate::Kbps250 => "250K",
            DataRate::Mbps1 => "1M",
            DataRate::Mbps2 => "2M",
        }
    }
}

/// A Crazyradio link's settings (the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RadioLink {
    /// Which Crazyradio (0 for the first found).
    pub radio: u8,
    /// Radio channel, 0–125.
    pub channel: u8,
    pub rate: DataRate,
    /// The Crazyflie's radio address.
    pub address: [u8; 5],
    /// `crazyflie-link`'s options, in the order written (`safelink`, `ackfilter`, `timeout`).
    pub options: Vec<(String, u32)>,
}

/// How this computer reaches the Crazyflie.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CrazyflieLink {
    Radio(RadioLink),
    /// UDP to HOST:PORT, one CRTP packet per datagram.
    Udp {
        host: String,
        port: u16,
    },
}

/// A parsed `crazyflie+…://` address (module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CrazyflieUrl {
    pub link: CrazyflieLink,
}

impl CrazyflieUrl {
    /// Parses either form; the error says which form is expected.
    pub fn parse(text: &str) -> Result<Self, UrlError> {
        let text = text.trim();
        let Some((scheme, rest)) = text.split_once("://") else {
            return Err(UrlError(format!("`{text}` has no scheme: expected {FORM}")));
        };
        match scheme.to_ascii_lowercase().as_str() {
            "crazyflie+radio" => parse_radio(rest).map(|r| CrazyflieUrl {
                link: CrazyflieLink::Radio(r),
            }),
            "crazyflie+udp" => parse_udp(rest),
            "radio" | "udp" => Err(UrlError(format!(
                "`{text}` is a link without the drone: write `crazyflie+{text}`"
            ))),
            _ => Err(UrlError(format!(
                "unknown scheme `{scheme}://` in `{text}`: expected {FORM}"
            ))),
        }
    }

    /// The link URI as Crazyflie software writes it (`radio://0/80/2M/E7E7E7E7E7`,
    /// `udp://127.0.0.1:19850`): what `crazyflie-link` and cflib open.
    pub fn link_uri(&self) -> String {
        match &self.link {
            CrazyflieLink::Radio(r) => {
                let address: String = r.address.iter().map(|b| format!("{b:02X}")).collect();
                let mut uri = format!(
                    "radio://{}/{}/{}/{address}",
                    r.radio,
                    r.channel,
                    r.rate.as_str()
                );
                for (i, (key, value)) in r.options.iter().enumerate() {
                    uri.push(if i == 0 { '?' } else { '&' });
                    uri.push_str(&format!("{key}={value}"));
                }
                uri
            }
            CrazyflieLink::Udp { host, port } => format!("udp://{}:{port}", bracket(host)),
        }
    }
}

/// `N/CHANNEL[/RATE[/ADDRESS]][?OPTIONS]`.
fn parse_radio(rest: &str) -> Result<RadioLink, UrlError> {
    let (path, query) = match rest.split_once('?') {
        Some((p, q)) => (p, Some(q)),
        None => (rest, None),
    };
    let path = path.strip_suffix('/').unwrap_or(path);
    let parts: Vec<&str> = path.split('/').collect();
    if parts.len() < 2 || parts.len() > 4 || parts.iter().any(|p| p.is_empty()) {
        return Err(UrlError(format!(
            "`{rest}` is not N/CHANNEL[/RATE[/ADDRESS]]: expected {FORM}"
        )));
    }
    let radio = parts[0].parse::<u8>().map_err(|_| {
        UrlError(format!(
            "radio `{}` is not a Crazyradio's number (0 for the first)",
            parts[0]
        ))
    })?;
    let channel = match parts[1].parse::<u8>() {
        Ok(c) if c <= 125 => c,
        _ => {
            return Err(UrlError(format!(
                "channel `{}` is not a radio channel (0–125)",
                parts[1]
            )))
        }
    };
    let rate = match parts.get(2).map(|r| r.to_ascii_uppercase()) {
        None => DataRate::Mbps2,
        Some(r) => match r.as_str() {
            "250K" => DataRate::Kbps250,
            "1M" => DataRate::Mbps1,
            "2M" => DataRate::Mbps2,
            _ => {
                return Err(UrlError(format!(
                    "data rate `{}` is not 250K, 1M or 2M",
                    parts[2]
                )))
            }
        },
    };
    let address = match parts.get(3) {
        None => [0xE7; 5],
        Some(a) => parse_address(a)?,
    };
    let mut options = Vec::new();
    for pair in query.into_iter().flat_map(|q| q.split('&')) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        let key = key.to_ascii_lowercase();
        let value = match (key.as_str(), value.parse::<u32>()) {
            ("safelink" | "ackfilter", Ok(v @ 0..=1)) => v,
            ("timeout", Ok(v)) if v > 0 => v,
            ("safelink" | "ackfilter" | "timeout", _) => {
                return Err(UrlError(format!(
                    "`{pair}`: safelink and ackfilter are 0 or 1, timeout is milliseconds"
                )))
            }
            _ => {
                return Err(UrlError(format!(
                    "unknown option `{pair}` for a radio link: expected safelink=0|1, \
                     ackfilter=0|1 or timeout=MS"
                )))
            }
        };
        options.push((key, value));
    }
    Ok(RadioLink {
        radio,
        channel,
        rate,
        address,
        options,
    })
}

/// Ten hex digits: the five bytes of a radio address.
fn parse_address(text: &str) -> Result<[u8; 5], UrlError> {
    let bad = || {
        UrlError(format!(
            "address `{text}` is not ten hex digits (a five-byte radio address, e.g. E7E7E7E7E7)"
        ))
    };
    let digits = text
        .strip_prefix("0x")
        .or_else(|| text.strip_prefix("0X"))
        .unwrap_or(text);
    if digits.len() != 10 || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(bad());
    }
    let mut out = [0u8; 5];
    for (i, byte) in out.iter_mut().enumerate() {
        *byte = u8::from_str_radix(&digits[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
    }
    Ok(out)
}

/// `HOST[:PORT]`.
fn parse_udp(rest: &str) -> Result<CrazyflieUrl, UrlError> {
    let rest = rest.strip_suffix('/').unwrap_or(rest);
    let (host, ports) = split_host_ports(rest, FORM)?;
    let port = match ports.as_slice() {
        [] => DEFAULT_UDP_PORT,
        [p] => port(p, "port")?,
        _ => {
            return Err(UrlError(format!(
                "too many ports in `{rest}`: expected {FORM}"
            )))
        }
    };
    Ok(CrazyflieUrl {
        link: CrazyflieLink::Udp {
            host: host.to_string(),
            port,
        },
    })
}

impl fmt::Display for CrazyflieUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "crazyflie+{}", self.link_uri())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radio_form_with_its_defaults() {
        let u = CrazyflieUrl::parse("crazyflie+radio://0/80/2M/E7E7E7E7E7").unwrap();
        let CrazyflieLink::Radio(r) = &u.link else {
            panic!("{u:?}")
        };
        assert_eq!((r.radio, r.channel, r.rate), (0, 80, DataRate::Mbps2));
        assert_eq!(r.address, [0xE7; 5]);
        assert_eq!(u.link_uri(), "radio://0/80/2M/E7E7E7E7E7");
        // Rate and address may be left out; the display writes them.
        let short = CrazyflieUrl::parse("CRAZYFLIE+RADIO://1/125").unwrap();
        assert_eq!(short.to_string(), "crazyflie+radio://1/125/2M/E7E7E7E7E7");
        let slow =
            CrazyflieUrl::parse("crazyflie+radio://0/10/250k/0xE7E7E7E701?safelink=0").unwrap();
        assert_eq!(slow.link_uri(), "radio://0/10/250K/E7E7E7E701?safelink=0");
    }

    #[test]
    fn the_udp_form_and_round_trips() {
        for (text, uri) in [
            ("crazyflie+udp://127.0.0.1:19850", "udp://127.0.0.1:19850"),
            ("crazyflie+udp://[::1]:7", "udp://[::1]:7"),
            ("crazyflie+udp://sim.local", "udp://sim.local:19850"),
            (
                "crazyflie+radio://0/80/1M/E7E7E7E7E7?ackfilter=1&timeout=500",
                "radio://0/80/1M/E7E7E7E7E7?ackfilter=1&timeout=500",
            ),
        ] {
            let u = CrazyflieUrl::parse(text).unwrap();
            assert_eq!(u.link_uri(), uri);
            assert_eq!(CrazyflieUrl::parse(&u.to_string()).unwrap(), u);
        }
    }

    #[test]
    fn errors_say_what_is_expected() {
        for (text, needle) in [
            ("radio://0/80/2M/E7E7E7E7E7", "without the drone"),
            ("udp://127.0.0.1:19850", "without the drone"),
            ("crazyflie://0/80", "unknown scheme"),
            ("crazyflie+radio", "no scheme"),
            ("crazyflie+radio://0", "not N/CHANNEL"),
            ("crazyflie+radio://0//2M", "not N/CHANNEL"),
            ("crazyflie+radio://0/80/2M/E7/x", "not N/CHANNEL"),
            ("crazyflie+radio://x/80", "not a Crazyradio's number"),
            ("crazyflie+radio://0/126", "not a radio channel"),
            ("crazyflie+radio://0/80/3M", "not 250K, 1M or 2M"),
            ("crazyflie+radio://0/80/2M/E7E7", "not ten hex digits"),
            ("crazyflie+radio://0/80/2M/E7E7E7E7EG", "not ten hex digits"),
            ("crazyflie+radio://0/80?safelink=2", "0 or 1"),
            ("crazyflie+radio://0/80?timeout=0", "milliseconds"),
            ("crazyflie+radio://0/80?power=1", "unknown option"),
            ("crazyflie+udp://:19850", "no host"),
            ("crazyflie+udp://h:0", "not a port"),
            ("crazyflie+udp://h:1:2", "too many ports"),
        ] {
            let e = CrazyflieUrl::parse(text).unwrap_err().0;
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
