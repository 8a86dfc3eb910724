//! Backend addresses as the command line takes them (`ardrone://…`, `natnet://…`): the pieces
//! every scheme's parser shares. Each backend crate parses its own scheme with these.
//!
//! HOST is a name, an IPv4 address or a bracketed IPv6 address (`[::1]`). Parsing checks
//! the form only; names are resolved when the backend connects.

use std::fmt;
use std::net::{SocketAddr, ToSocketAddrs};

/// Why an address was refused; the message says what form is expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UrlError(pub String);

impl fmt::Display for UrlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UrlError {}

/// Splits `HOST[:a[:b]]` (HOST possibly `[v6]`) into the host and the port fields.
pub fn split_host_ports<'a>(
    rest: &'a str,
    form: &str,
) -> Result<(&'a str, Vec<&'a str>), UrlError> {
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

/// A port number, 1–65535, or an error naming `what`.
pub fn port(text: &str, what: &str) -> Result<u16, UrlError> {
    match text.parse::<u16>() {
        Ok(p) if p > 0 => Ok(p),
        _ => Err(UrlError(format!(
            "{what} `{text}` is not a port number (1–65535)"
        ))),
    }
}

/// The text after `scheme://` (the scheme in any case), or an error that names `form`.
pub fn strip_scheme<'a>(text: &'a str, scheme: &str, form: &str) -> Result<&'a str, UrlError> {
    match text.split_once("://") {
        Some((s, rest)) if s.eq_ignore_ascii_case(scheme) => Ok(rest),
        Some((s, _)) => Err(UrlError(format!(
            "unknown scheme `{s}://` in `{text}`: expected {form}"
        ))),
        None => Err(UrlError(format!("`{text}` has no scheme: expected {form}"))),
    }
}

/// A host as written in an address: an IPv6 address in brackets.
pub fn bracket(host: &str) -> String {
    if host.contains(':') {
        format!("[{host}]")
    } else {
        host.to_string()
    }
}

/// The first socket address `host:port` resolves to.
pub fn resolve(host: &str, port: u16) -> Result<SocketAddr, UrlError> {
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
    fn hosts_ports_and_schemes() {
        assert_eq!(
            split_host_ports("h:1:2", "F").unwrap(),
            ("h", vec!["1", "2"])
        );
        assert_eq!(
            split_host_ports("[::1]:7", "F").unwrap(),
            ("::1", vec!["7"])
        );
        assert!(split_host_ports("[::1", "F")
            .unwrap_err()
            .0
            .contains("without `]`"));
        assert!(split_host_ports("", "F").unwrap_err().0.contains("no host"));
        assert_eq!(port("65535", "p"), Ok(65535));
        assert!(port("0", "p").is_err() && port("x", "p").is_err());
        assert_eq!(strip_scheme("ArDrone://h", "ardrone", "F"), Ok("h"));
        assert!(strip_scheme("h", "ardrone", "F")
            .unwrap_err()
            .0
            .contains("no scheme"));
        assert_eq!(bracket("::1"), "[::1]");
    }
}
