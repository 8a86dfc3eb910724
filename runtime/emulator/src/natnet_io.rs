//! The emulators' motion capture on the network: the NatNet command socket answered by
//! [`Motive`], and the simulator's frames sent to the data address. Shared by the AR.Drone
//! and the Crazyflie emulators.

use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};

use dronecine_backend::MocapFrame;

use crate::{bind, EmulatorError, Motive, NatNetConfig, NatNetData, MAX_DATAGRAMS_PER_STEP};

/// What the NatNet side did in one call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct NatNetCounts {
    /// Command datagrams answered (or accepted, keep-alives).
    pub requests: u64,
    /// Command datagrams that are not NatNet messages.
    pub rejected: u64,
    pub frames: u64,
    pub send_errors: u64,
}

pub(crate) struct NatNetIo {
    command: UdpSocket,
    data: UdpSocket,
    dest: SocketAddr,
    motive: Motive,
}

impl NatNetIo {
    /// Binds the command port on `host` and a data socket of the destination's family.
    pub(crate) fn bind(host: IpAddr, n: &NatNetConfig) -> Result<NatNetIo, EmulatorError> {
        let command = bind("NatNet command", SocketAddr::new(host, n.command_port))?;
        let dest = n.data.addr();
        if dest.port() == 0 || dest.ip().is_unspecified() {
            return Err(EmulatorError::Config(format!(
                "NatNet frames cannot be sent to {dest}: give an address and a port"
            )));
        }
        let data_bind = match dest {
            SocketAddr::V4(_) if host.is_ipv4() => SocketAddr::new(host, 0),
            SocketAddr::V4(_) => SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0),
            SocketAddr::V6(_) if host.is_ipv6() => SocketAddr::new(host, 0),
            SocketAddr::V6(_) => SocketAddr::new(IpAddr::V6(Ipv6Addr::UNSPECIFIED), 0),
        };
        let data = bind("NatNet data", data_bind)?;
        if let NatNetData::Multicast(_) = n.data {
            let _ = data.set_multicast_loop_v4(true);
        }
        let (multicast, group) = match n.data {
            NatNetData::Multicast(a) => (true, a.ip().octets()),
            NatNetData::Unicast(_) => (false, [0; 4]),
        };
        let motive = Motive::new(n.version, n.up_axis, dest.port(), multicast, group)
            .map_err(EmulatorError::NatNet)?;
        Ok(NatNetIo {
            command,
            data,
            dest,
            motive,
        })
    }

    /// The NatNet side an emulator is configured with, if any, and its bound command address.
    pub(crate) fn bind_configured(
        host: IpAddr,
        n: Option<&NatNetConfig>,
    ) -> Result<(Option<NatNetIo>, Option<SocketAddr>), EmulatorError> {
        let Some(n) = n else { return Ok((None, None)) };
        let io = NatNetIo::bind(host, n)?;
        let addr = io.command_addr()?;
        Ok((Some(io), Some(addr)))
    }

    /// The bound command address.
    pub(crate) fn command_addr(&self) -> Result<SocketAddr, EmulatorError> {
        self.command
            .local_addr()
            .map_err(|error| EmulatorError::Socket {
                what: "NatNet command",
                addr: self.dest,
                error,
            })
    }

    /// Answers every request waiting on the command port (at most a step's worth).
    pub(crate) fn drain(&mut self, rx: &mut [u8], tx: &mut [u8], counts: &mut NatNetCounts) {
        for _ in 0..MAX_DATAGRAMS_PER_STEP {
            let (n, from) = match self.command.recv_from(rx) {
                Ok(r) => r,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(_) => continue,
            };
            match self.motive.command(&rx[..n], tx) {
                Ok(reply) => {
                    counts.requests += 1;
                    if let crate::motive::Reply::Send(len) = reply {
                        if self.command.send_to(&tx[..len], from).is_err() {
                            counts.send_errors += 1;
                        }
                    }
                }
                Err(_) => counts.rejected += 1,
            }
        }
    }

    /// Sends `frame` as frame `number`, captured at `capture_s` and sent at `now_s` (wall
    /// seconds since the start).
    pub(crate) fn send_frame(
        &mut self,
        frame: &MocapFrame,
        number: u64,
        capture_s: f64,
        now_s: f64,
        tx: &mut [u8],
        counts: &mut NatNetCounts,
    ) {
        match self.motive.frame(frame, number, capture_s, now_s, tx) {
            Ok(len) => match self.data.send_to(&tx[..len], self.dest) {
                Ok(_) => counts.frames += 1,
                Err(_) => counts.send_errors += 1,
            },
            Err(_) => counts.send_errors += 1,
        }
    }
}
