//! The WebSocket server ([`LiveServer`]) and the live view's [`MessageOut`] ([`LiveOut`]): the
//! flight's topics as Foxglove channels, each message logged to the clients subscribed to it.
//!
//! The server runs on a tokio runtime of its own (one worker thread, its priority lowered as
//! the log's threads lower theirs). A topic written once (the scene, the lens:
//! [`topic::is_latched`]) or only when it changes (a `/tf` frame that moved) keeps its last
//! message, which each client gets when it subscribes: a client that connects after take-off
//! sees the stage, the actors and a camera that has not moved all the same, and gets each such
//! message once.

use std::collections::HashMap;
use std::io;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use dronecine_mcap::log::{topic, MessageOut, TopicSpec};
use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{ChannelBuilder, ChannelId, Context, PartialMetadata, RawChannel, Schema, SinkId};

use crate::LiveError;

/// Messages queued for each client: a client that reads slower than the flight writes loses
/// the oldest of them (the server drops them rather than wait), about three seconds of the
/// flight's 330 messages a second.
const BACKLOG: usize = 1024;

/// What the server's listener and the writers share.
#[derive(Default)]
pub(crate) struct Shared {
    /// Clients connected now.
    pub(crate) clients: AtomicUsize,
    /// The most clients connected at once.
    pub(crate) clients_max: AtomicUsize,
    /// Subscriptions, all clients together.
    pub(crate) subscriptions: AtomicUsize,
    latched: Mutex<HashMap<ChannelId, Latched>>,
}

/// A topic written once: its last message, and the clients subscribed to it.
struct Latched {
    channel: Arc<RawChannel>,
    last: Option<(u64, Vec<u8>)>,
    sinks: Vec<SinkId>,
}

impl Shared {
    fn latched(&self) -> std::sync::MutexGuard<'_, HashMap<ChannelId, Latched>> {
        // A panic while the map was held left it whole: each entry is replaced in one step.
        self.latched.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

struct Listener(Arc<Shared>);

impl ServerListener for Listener {
    fn on_client_connect(&self) {
        let now = self.0.clients.fetch_add(1, Ordering::Relaxed) + 1;
        self.0.clients_max.fetch_max(now, Ordering::Relaxed);
    }

    fn on_client_disconnect(&self) {
        let _ = (self.0.clients).fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
            Some(n.saturating_sub(1))
        });
    }

    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        self.0.subscriptions.fetch_add(1, Ordering::Relaxed);
        let Some(sink) = client.sink_id() else {
            return;
        };
        if let Some(l) = self.0.latched().get_mut(&channel.id()) {
            l.sinks.push(sink);
            if let Some((ns, data)) = &l.last {
                l.channel.log_with_meta_to_sink(data, meta(*ns), Some(sink));
            }
        }
    }

    fn on_unsubscribe(&self, client: Client, channel: ChannelView) {
        let _ = (self.0.subscriptions).fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
            Some(n.saturating_sub(1))
        });
        if let (Some(sink), Some(l)) = (client.sink_id(), self.0.latched().get_mut(&channel.id())) {
            l.sinks.retain(|s| *s != sink);
        }
    }
}

fn meta(ns: u64) -> PartialMetadata {
    PartialMetadata { log_time: Some(ns) }
}

/// The live view's WebSocket server (Foxglove's protocol), bound and serving; the flight's
/// channels are added by the writers (`LiveOut`). Stopped when dropped.
pub struct LiveServer {
    context: Arc<Context>,
    pub(crate) shared: Arc<Shared>,
    addr: SocketAddr,
    handle: Option<foxglove::WebSocketServerHandle>,
    /// Kept after the handle, which needs it to stop.
    runtime: Option<tokio::runtime::Runtime>,
}

impl LiveServer {
    /// Binds `addr` (port 0: a free port) and serves. An address that cannot be bound (in
    /// use, not this machine's) is an error that names it.
    pub fn bind(addr: SocketAddr) -> Result<LiveServer, LiveError> {
        let bind_error = |detail: String| LiveError::Bind { addr, detail };
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("flight-live-ws")
            .on_thread_start(dronecine_mcap::log::lower_priority)
            .enable_all()
            .build()
            .map_err(|e| bind_error(e.to_string()))?;
        let context = Context::new();
        let shared = Arc::new(Shared::default());
        let host = match addr {
            SocketAddr::V4(a) => a.ip().to_string(),
            SocketAddr::V6(a) => format!("[{}]", a.ip()),
        };
        let server = foxglove::WebSocketServer::new()
            .name("dronecine")
            .context(&context)
            .bind(host, addr.port())
            .message_backlog_size(BACKLOG)
            .listener(Arc::new(Listener(Arc::clone(&shared))));
        let handle = runtime
            .block_on(server.start())
            .map_err(|e| bind_error(bind_detail(e)))?;
        let addr = SocketAddr::new(addr.ip(), handle.port());
        Ok(LiveServer {
            context,
            shared,
            addr,
            handle: Some(handle),
            runtime: Some(runtime),
        })
    }

    /// The address served (its port the one bound).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Where Foxglove connects: `ws://127.0.0.1:8765`.
    pub fn url(&self) -> String {
        format!("ws://{}", self.addr)
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.shared.clients.load(Ordering::Relaxed)
    }

    /// Waits until a client has subscribed to a channel (for `replay --live`, whose flight
    /// starts for its first viewer), and a little more for the rest of its subscriptions.
    pub fn wait_for_subscriber(&self) {
        while self.shared.subscriptions.load(Ordering::Relaxed) == 0 {
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_millis(250));
    }

    /// A writer of channels on this server.
    pub(crate) fn out(&self) -> LiveOut {
        LiveOut {
            context: Arc::clone(&self.context),
            shared: Arc::clone(&self.shared),
            channels: Vec::new(),
            buf: Vec::with_capacity(4096),
            messages: 0,
        }
    }

    /// Serves what is queued for half a second more (the flight's last messages reach the
    /// clients), then closes every connection and stops.
    pub fn stop(mut self) {
        self.shut_down();
    }

    fn shut_down(&mut self) {
        if let Some(handle) = self.handle.take() {
            if self.clients() > 0 {
                std::thread::sleep(Duration::from_millis(500));
            }
            handle.stop().wait_blocking();
        }
        if let Some(runtime) = self.runtime.take() {
            runtime.shutdown_timeout(Duration::from_secs(1));
        }
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shut_down();
    }
}

/// The bind error's cause, as an operator reads it.
fn bind_detail(e: foxglove::FoxgloveError) -> String {
    match e {
        foxglove::FoxgloveError::Bind(io) => io.to_string(),
        e => e.to_string(),
    }
}

/// The live view's [`MessageOut`]: each topic a Foxglove channel. A message is encoded only
/// when a client is subscribed to its channel (or it is a latched topic's, kept for the
/// clients to come).
pub(crate) struct LiveOut {
    context: Arc<Context>,
    shared: Arc<Shared>,
    /// By id: the channel, and its id in the latched map when it is a latched topic's.
    channels: Vec<(Arc<RawChannel>, bool)>,
    buf: Vec<u8>,
    /// Messages logged.
    pub(crate) messages: u64,
}

impl LiveOut {
    /// Adds a channel: `schema` is `(name, encoding, data)`.
    pub(crate) fn channel(
        &mut self,
        topic: &str,
        message_encoding: &str,
        schema: Option<(&str, &str, &[u8])>,
    ) -> io::Result<u16> {
        let id = u16::try_from(self.channels.len())
            .map_err(|_| io::Error::other("more than 65,536 live channels"))?;
        let schema =
            schema.map(|(name, encoding, data)| Schema::new(name, encoding, data.to_vec()));
        let channel = ChannelBuilder::new(topic)
            .context(&self.context)
            .message_encoding(message_encoding)
            .schema(schema)
            .build_raw()
            .map_err(|e| io::Error::other(format!("the live channel {topic}: {e}")))?;
        let latched = topic::is_latched(topic) || topic.starts_with(topic::TF_PREFIX);
        if latched {
            self.shared.latched().insert(
                channel.id(),
                Latched {
                    channel: Arc::clone(&channel),
                    last: None,
                    sinks: Vec::new(),
                },
            );
        }
        self.channels.push((channel, latched));
        Ok(id)
    }

    /// Logs `data` on channel `id` at `ns`.
    pub(crate) fn publish(&mut self, id: u16, ns: u64, data: &[u8]) {
        self.put_with(id, ns, |b| b.extend_from_slice(data));
    }

    fn put_with(&mut self, id: u16, ns: u64, encode: impl FnOnce(&mut Vec<u8>)) {
        let Some((channel, latched)) = self.channels.get(usize::from(id)) else {
            return;
        };
        if !latched && !channel.has_sinks() {
            return;
        }
        self.buf.clear();
        encode(&mut self.buf);
        self.messages += 1;
        if !latched {
            channel.log_with_meta(&self.buf, meta(ns));
            return;
        }
        let mut map = self.shared.latched();
        if let Some(l) = map.get_mut(&channel.id()) {
            for sink in &l.sinks {
                channel.log_with_meta_to_sink(&self.buf, meta(ns), Some(*sink));
            }
            l.last = Some((ns, self.buf.clone()));
        }
    }
}

impl MessageOut for LiveOut {
    fn add_channel(&mut self, t: &TopicSpec) -> io::Result<u16> {
        let schema = (t.schema_name, t.encoding.schema(), t.schema.as_bytes());
        self.channel(t.topic, t.encoding.message(), Some(schema))
    }

    fn put(&mut self, channel: u16, ns: u64, encode: impl FnOnce(&mut Vec<u8>)) -> io::Result<()> {
        self.put_with(channel, ns, encode);
        Ok(())
    }
}
