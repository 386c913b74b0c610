//! The live view (crate feature `live`): a run served over Foxglove's WebSocket protocol as
//! it happens, paced at a multiple of real time, so that Foxglove's *Open connection →
//! Foxglove WebSocket* shows it.
//!
//! [`LiveView`] is a [`Tap`] of the [`RunLogger`](super::RunLogger): it publishes the same
//! messages as the log, on the same six topics with the same schemas and encodings, stamped
//! with the simulated time, through Foxglove's SDK (its `WebSocketServer`, a `Context` and
//! typed channels). The log file is still written, byte for byte as without the live view.
//!
//! - **Pacing**: at each sample the simulation's thread sleeps until the wall clock reaches
//!   `start + (t − t₀)/speed` (never when it is behind); between samples it runs at full
//!   speed.
//! - **Clock**: the server has the `time` capability and broadcasts the simulated time at
//!   each sample, so the viewer's clock is the simulation's.
//! - **A client that connects in the middle** still gets the bodies: `/geometry` is sent once
//!   in the log, and again over the connection each time a client subscribes to it (a
//!   server listener raises a flag that the next sample reads).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use foxglove::websocket::{Capability, ChannelView, Client, ServerListener};
use foxglove::{Channel, Context, RawChannel, Schema, WebSocketServer, WebSocketServerHandle};

use super::LogError;
use super::foxglove::{FrameTransforms, Log, SceneUpdate, nanoseconds};
use super::records::{ImpactRecord, StateRecord};
use super::run::Tap;
use super::schemas::{self, Topic};
use super::sink::append_json;

/// Where and how fast to serve a run.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveOptions {
    /// The address to listen on (`127.0.0.1`: this machine only).
    pub host: String,
    /// The TCP port (0: any free port; [`LiveView::port`] tells which).
    pub port: u16,
    /// Simulated seconds per wall-clock second, finite and > 0.
    pub speed: f64,
    /// How long to keep serving after the run, so that the last messages reach the clients.
    pub linger: Duration,
}

impl Default for LiveOptions {
    fn default() -> Self {
        Self {
            host: "127.0.0.1".to_owned(),
            port: 8765,
            speed: 1.0,
            linger: Duration::from_secs(1),
        }
    }
}

/// Raises a flag when a client subscribes to `/geometry`.
struct GeometryWanted(Arc<AtomicBool>);

impl ServerListener for GeometryWanted {
    fn on_subscribe(&self, _client: Client, channel: ChannelView) {
        if channel.topic() == Topic::Geometry.name() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// The clock of the pacing: the wall-clock instant of simulated time `t0`.
#[derive(Clone, Copy, Debug)]
#[doc(hidden)]
pub struct Pace {
    pub start: Instant,
    pub t0: f64,
    pub speed: f64,
}

impl Pace {
    /// How long to wait at simulated time `t` (s), `now` on the wall clock: until
    /// `start + (t − t₀)/speed`; zero when behind.
    pub fn wait(&self, t: f64, now: Instant) -> Duration {
        let due = Duration::try_from_secs_f64((t - self.t0) / self.speed).unwrap_or_default();
        (self.start + due).saturating_duration_since(now)
    }
}

/// A run served live (see the module doc).
pub struct LiveView {
    /// The context that binds the channels to the server; dropping it would disconnect them.
    _context: Arc<Context>,
    server: Option<WebSocketServerHandle>,
    geometry: Channel<SceneUpdate>,
    scene: Channel<SceneUpdate>,
    tf: Channel<FrameTransforms>,
    log: Channel<Log>,
    state: Arc<RawChannel>,
    impacts: Arc<RawChannel>,
    speed: f64,
    linger: Duration,
    /// Set at the first message.
    pace: Option<Pace>,
    /// The drawing of the scene, sent again to clients that subscribe later.
    drawing: SceneUpdate,
    geometry_wanted: Arc<AtomicBool>,
    /// JSON of `/state` and `/impacts`, reused.
    json: Vec<u8>,
}

impl LiveView {
    /// Starts the server. Errors when `speed` is not finite and positive, or when the
    /// address cannot be listened on (a port in use).
    pub fn start(options: &LiveOptions) -> Result<LiveView, LogError> {
        if !(options.speed.is_finite() && options.speed > 0.0) {
            return Err(LogError::Live {
                address: format!("{}:{}", options.host, options.port),
                message: format!("the speed must be a positive number, not {}", options.speed),
            });
        }
        let ctx = Context::new();
        let json = |topic: Topic, schema: &'static str| {
            ctx.channel_builder(topic.name())
                .message_encoding(schemas::JSON)
                .schema(Schema::new(
                    topic.schema_name(),
                    schemas::JSON_SCHEMA,
                    schema.as_bytes(),
                ))
                .build_raw()
        };
        let channel_error = |e: foxglove::FoxgloveError| LogError::Live {
            address: format!("{}:{}", options.host, options.port),
            message: e.to_string(),
        };
        let state = json(Topic::State, schemas::STATE).map_err(channel_error)?;
        let impacts = json(Topic::Impacts, schemas::IMPACT).map_err(channel_error)?;
        let geometry = ctx.channel_builder(Topic::Geometry.name()).build();
        let scene = ctx.channel_builder(Topic::Scene.name()).build();
        let tf = ctx.channel_builder(Topic::Tf.name()).build();
        let log = ctx.channel_builder(Topic::Log.name()).build();
        let geometry_wanted = Arc::new(AtomicBool::new(false));
        let server = WebSocketServer::new()
            .name("ricochet")
            .bind(options.host.clone(), options.port)
            .capabilities([Capability::Time])
            .listener(Arc::new(GeometryWanted(Arc::clone(&geometry_wanted))))
            .context(&ctx)
            .start_blocking()
            .map_err(|e| LogError::Live {
                address: format!("{}:{}", options.host, options.port),
                message: e.to_string(),
            })?;
        Ok(LiveView {
            _context: ctx,
            server: Some(server),
            geometry,
            scene,
            tf,
            log,
            state,
            impacts,
            speed: options.speed,
            linger: options.linger,
            pace: None,
            drawing: SceneUpdate::default(),
            geometry_wanted,
            json: Vec::new(),
        })
    }

    /// The port the server listens on.
    pub fn port(&self) -> u16 {
        self.server.as_ref().map_or(0, WebSocketServerHandle::port)
    }

    /// Sleeps until simulated time `t` (s) is due on the wall clock, and tells the clients
    /// the time.
    fn pace(&mut self, t: f64) {
        let speed = self.speed;
        let pace = *self.pace.get_or_insert_with(|| Pace {
            start: Instant::now(),
            t0: t,
            speed,
        });
        let wait = pace.wait(t, Instant::now());
        if !wait.is_zero() {
            std::thread::sleep(wait);
        }
        if let (Some(server), Ok(ns)) = (&self.server, nanoseconds(t)) {
            server.broadcast_time(ns);
        }
    }

    /// Publishes `message` as JSON on `channel` at simulated time `t` (s).
    fn publish_json<M: serde::Serialize>(&mut self, channel: Topic, t: f64, message: &M) {
        let Ok(ns) = nanoseconds(t) else { return };
        self.json.clear();
        if append_json(&mut self.json, channel, message).is_ok() {
            let raw = if channel == Topic::State {
                &self.state
            } else {
                &self.impacts
            };
            raw.log_with_meta(&self.json, foxglove::PartialMetadata::with_log_time(ns));
        }
    }
}

impl Tap for LiveView {
    fn geometry(&mut self, t: f64, update: &SceneUpdate) {
        self.drawing = update.clone();
        if let Ok(ns) = nanoseconds(t) {
            self.geometry.log_with_time(update, ns);
        }
    }

    fn sample(&mut self, state: &StateRecord, transforms: &FrameTransforms) {
        self.pace(state.t);
        let Ok(ns) = nanoseconds(state.t) else { return };
        if self.geometry_wanted.swap(false, Ordering::AcqRel) {
            self.geometry.log_with_time(&self.drawing, ns);
        }
        self.publish_json(Topic::State, state.t, state);
        self.tf.log_with_time(transforms, ns);
    }

    fn impact(&mut self, impact: &ImpactRecord, drawing: &SceneUpdate) {
        self.pace(impact.t);
        self.publish_json(Topic::Impacts, impact.t, impact);
        if let Ok(ns) = nanoseconds(impact.t) {
            self.scene.log_with_time(drawing, ns);
        }
    }

    fn log(&mut self, log: &Log) {
        if let Some(time) = &log.timestamp {
            self.log.log_with_time(log, *time);
        }
    }

    /// Serves on for the linger time, then stops the server and waits for it.
    fn finish(&mut self) {
        std::thread::sleep(self.linger);
        if let Some(server) = self.server.take() {
            server.stop().wait_blocking();
        }
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        if let Some(server) = self.server.take() {
            server.stop().wait_blocking();
        }
    }
}
