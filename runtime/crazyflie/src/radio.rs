//! The Crazyradio transport: Bitcraze's `crazyflie-link` (asynchronous, on tokio) run on a
//! thread of its own, which applies every packet received to the link's state and sends the
//! packets queued by [`Radio::send`].
//!
//! The queue holds fixed-size packets (a bounded channel: the caller's send allocates
//! nothing); `crazyflie-link` makes its own packet of each on the radio's thread. A radio
//! address with no Crazyradio attached, or a Crazyflie that does not answer, fails
//! [`Radio::open`] with the link's reason.

use std::sync::atomic::Ordering;
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use dronecine_backend::BackendError;
use tokio::sync::Notify;

use crate::crtp::Packet;
use crate::state::Shared;
use crate::url::{CrazyflieLink, CrazyflieUrl};

/// The Crazyradio's USB vendor and product ids (the 2.0's are the same).
const CRAZYRADIO_USB: (u16, u16) = (0x1915, 0x7777);

/// Packets waiting for the radio's thread; a send beyond is refused.
const QUEUE: usize = 256;
/// How often the radio's thread looks whether the link was closed.
const WAKE: Duration = Duration::from_millis(100);

/// An open Crazyradio link.
pub struct Radio {
    tx: SyncSender<Packet>,
    wake: Arc<Notify>,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Radio {
    /// Opens the radio link of `url` (waits for `crazyflie-link` to connect).
    pub(crate) fn open(url: &CrazyflieUrl, shared: Arc<Shared>) -> Result<Radio, BackendError> {
        if let CrazyflieLink::Radio(r) = &url.link {
            find_radio(usize::from(r.radio))
                .map_err(|why| BackendError::Link(format!("cannot open {url}: {why}")))?;
        }
        let uri = url.link_uri();
        let (tx, rx) = mpsc::sync_channel(QUEUE);
        let (ready_tx, ready_rx) = mpsc::channel::<Result<(), String>>();
        let wake = Arc::new(Notify::new());
        let thread = {
            let (wake, shared) = (Arc::clone(&wake), Arc::clone(&shared));
            std::thread::Builder::new()
                .name("crazyflie-radio".into())
                .spawn(move || run(&uri, rx, &wake, &shared, ready_tx))
                .map_err(|e| BackendError::Link(format!("cannot start the radio's thread: {e}")))?
        };
        let radio = Radio {
            tx,
            wake,
            shared,
            thread: Some(thread),
        };
        match ready_rx.recv() {
            Ok(Ok(())) => Ok(radio),
            Ok(Err(why)) => Err(BackendError::Link(format!(
                "cannot open {url}: {why} (is a Crazyradio plugged in, may this user open it, \
                 and is the Crazyflie on, on this channel and address?)"
            ))),
            Err(_) => Err(BackendError::Link(format!(
                "cannot open {url}: the radio's thread ended"
            ))),
        }
    }

    /// Queues one packet for the radio.
    pub(crate) fn send(&self, packet: &Packet) -> Result<(), String> {
        match self.tx.try_send(*packet) {
            Ok(()) => {
                self.wake.notify_one();
                Ok(())
            }
            Err(TrySendError::Full(_)) => Err("the radio's queue is full".into()),
            Err(TrySendError::Disconnected(_)) => Err("the radio link is closed".into()),
        }
    }
}

impl Drop for Radio {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        self.wake.notify_one();
        if let Some(h) = self.thread.take() {
            let _ = h.join();
        }
    }
}

/// Whether the `n`-th Crazyradio is plugged in, asked of libusb before `crazyflie-link`
/// opens it (whose USB layer panics where libusb cannot start, as on a machine without USB).
fn find_radio(n: usize) -> Result<(), String> {
    use rusb::UsbContext;
    let context = rusb::Context::new().map_err(|e| {
        format!("USB cannot be used on this machine ({e}): no Crazyradio can be reached")
    })?;
    let devices = context
        .devices()
        .map_err(|e| format!("the USB devices cannot be listed ({e})"))?;
    let found = (devices.iter())
        .filter_map(|d| d.device_descriptor().ok())
        .filter(|d| (d.vendor_id(), d.product_id()) == CRAZYRADIO_USB)
        .count();
    match found {
        0 => Err("no Crazyradio is plugged in (USB 1915:7777)".into()),
        f if n >= f => Err(format!(
            "radio {n} asked, but {f} Crazyradio{} plugged in (the first is 0)",
            if f == 1 { " is" } else { "s are" }
        )),
        _ => Ok(()),
    }
}

/// The radio's thread: connect, say so, then move packets both ways until closed.
fn run(
    uri: &str,
    rx: Receiver<Packet>,
    wake: &Notify,
    shared: &Shared,
    ready: mpsc::Sender<Result<(), String>>,
) {
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            let _ = ready.send(Err(format!("cannot start the radio's runtime: {e}")));
            return;
        }
    };
    runtime.block_on(async {
        let context = crazyflie_link::LinkContext::new();
        let connection = match context.open_link(uri).await {
            Ok(c) => c,
            Err(e) => {
                let _ = ready.send(Err(e.to_string()));
                return;
            }
        };
        let _ = ready.send(Ok(()));
        while !shared.closed.load(Ordering::Relaxed) {
            tokio::select! {
                received = connection.recv_packet() => match received {
                    Ok(p) => shared.apply(&Vec::from(p)),
                    Err(e) => {
                        shared.fail(format!("the radio link failed: {e}"));
                        break;
                    }
                },
                () = wake.notified() => {}
                () = tokio::time::sleep(WAKE) => {}
            }
            while let Ok(p) = rx.try_recv() {
                let packet = crazyflie_link::Packet::from(p.as_bytes().to_vec());
                if let Err(e) = connection.send_packet(packet).await {
                    shared.fail(format!("the radio link failed: {e}"));
                    return;
                }
            }
        }
        connection.close().await;
    });
}
