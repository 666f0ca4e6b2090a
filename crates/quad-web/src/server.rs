//! The web server: the embedded page, one WebSocket per page (`/ws`), and the device's state
//! as JSON for scripts (`GET /api/state`: the WebSocket's `state` message without its `type`).
//!
//! Every page receives the device's state on each change. One page at a time controls: it
//! sends `take_control` first; a second page asking gets a refusal naming the one in control,
//! and its device commands are refused until it controls. When the controlling page's socket
//! closes (tab closed, network gone), the device thread applies the device's link-loss rule
//! ([`crate::device`]).

use crate::assets;
use crate::device::{self, DeviceSetup, Event, Job};
use crate::msg::{self, ClientMsg, ServerMsg, State};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State as AxumState;
use axum::http::{header, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use kin_core::RotationOrder;
use quad_host::link::Target;
use quad_protocol::{LinkLossAction, ServoId};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// What `quadctl serve` serves.
#[derive(Debug, Clone)]
pub struct ServeConfig {
    /// The device and the robot.
    pub device: DeviceSetup,
    /// Where to listen (127.0.0.1 by default; port 0 picks a free one).
    pub listen: SocketAddr,
}

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The address could not be bound.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// The device could not be reached or refused the session.
    #[error("device: {0}")]
    Device(#[from] device::Error),
    /// The device or server thread stopped unexpectedly.
    #[error("the {0} thread stopped unexpectedly")]
    Thread(&'static str),
    /// The async runtime or the server failed.
    #[error("server: {0}")]
    Io(#[from] std::io::Error),
}

/// What every connection shares.
struct Shared {
    events: Mutex<std::sync::mpsc::Sender<Event>>,
    state: watch::Receiver<State>,
    state_tx: watch::Sender<State>,
    controller: Mutex<Option<u64>>,
    next_page: AtomicU64,
    welcome: Welcome,
    /// True once the server stops: every page's connection ends (graceful shutdown waits for
    /// open WebSockets otherwise).
    closing: watch::Receiver<bool>,
}

#[derive(Clone)]
struct Welcome {
    robot: kin_core::Robot,
    robot_name: String,
    rotation_order: u8,
    link_loss_action: &'static str,
    target: &'static str,
}

/// A running server.
pub struct Running {
    /// The address it listens on.
    pub addr: SocketAddr,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<Result<(), Error>>>,
}

impl Running {
    /// Stops the server and the device thread, and waits for them.
    ///
    /// # Errors
    /// The server's.
    pub fn stop(mut self) -> Result<(), Error> {
        self.stop_inner()
    }

    fn stop_inner(&mut self) -> Result<(), Error> {
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
        match self.thread.take() {
            Some(t) => t.join().unwrap_or(Err(Error::Thread("server"))),
            None => Ok(()),
        }
    }

    /// Serves until Ctrl-C.
    ///
    /// # Errors
    /// The server's.
    pub fn wait(mut self) -> Result<(), Error> {
        match self.thread.take() {
            Some(t) => t.join().unwrap_or(Err(Error::Thread("server"))),
            None => Ok(()),
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.stop_inner();
    }
}

fn initial_state() -> State {
    State {
        t_ms: 0.0,
        angles_rad: [0.0; 12],
        pulses_us: [0.0; 12],
        flags: msg::FlagsMsg::default(),
        link: msg::LinkMsg::default(),
        pose: None,
        pose_id: 0,
        stance_height_m: 0.0,
        calibration: [quad_protocol::servo::Calibration::STANDARD; 12],
        poses_sent: 0,
        controller: None,
        pages: 0,
        link_up: false,
        motion: crate::motion::MotionState::default(),
        imu: None,
        guide: None,
    }
}

/// Opens the device (in its own thread), binds `config.listen` and serves in a background
/// thread until [`Running::stop`], or Ctrl-C when `ctrl_c` is true.
///
/// # Errors
/// [`Error::Device`] when the device cannot be reached, [`Error::Bind`].
pub fn start(config: ServeConfig, ctrl_c: bool) -> Result<Running, Error> {
    let started = Instant::now();
    let (events_tx, events_rx) = std::sync::mpsc::channel();
    let (state_tx, state_rx) = watch::channel(initial_state());
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let setup = config.device.clone();
    let device_state = state_tx.clone();
    let device_thread = std::thread::Builder::new()
        .name("device".to_owned())
        .spawn(move || device::run(setup, events_rx, device_state, ready_tx, started))?;
    let ready = ready_rx.recv().map_err(|_| Error::Thread("device"))??;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    // Bound here, outside the runtime, so that `start` may be called from async code too.
    let listener = std::net::TcpListener::bind(config.listen).map_err(|source| Error::Bind {
        addr: config.listen,
        source,
    })?;
    listener.set_nonblocking(true)?;
    let addr = listener.local_addr()?;
    let (closing_tx, closing) = watch::channel(false);
    let shared = Arc::new(Shared {
        closing,
        events: Mutex::new(events_tx),
        state: state_rx,
        state_tx,
        controller: Mutex::new(None),
        next_page: AtomicU64::new(1),
        welcome: Welcome {
            robot: ready.robot,
            robot_name: ready.robot_name.clone(),
            rotation_order: RotationOrder::ALL
                .iter()
                .position(|&o| o == ready.info.pose_config.order)
                .unwrap_or(0) as u8,
            link_loss_action: match ready.info.link_timeout.action {
                LinkLossAction::Hold => "hold",
                LinkLossAction::Disable => "disable",
            },
            target: match config.device.target {
                Target::Sim { .. } => "sim",
                Target::Emulator { .. } => "emulator",
                _ => "serial",
            },
        },
    });
    let app = Router::new()
        .route("/ws", get(ws_upgrade))
        .route(STATE_PATH, get(api_state))
        .fallback(get(asset))
        .with_state(shared.clone());
    let (shutdown_tx, shutdown_rx) = tokio::sync::oneshot::channel::<()>();
    let thread = std::thread::Builder::new()
        .name("server".to_owned())
        .spawn(move || {
            let result = runtime.block_on(async move {
                let listener = tokio::net::TcpListener::from_std(listener)?;
                let stop = async move {
                    if ctrl_c {
                        tokio::select! {
                            _ = shutdown_rx => {}
                            _ = tokio::signal::ctrl_c() => {}
                        }
                    } else {
                        let _ = shutdown_rx.await;
                    }
                    let _ = closing_tx.send(true);
                };
                axum::serve(listener, app)
                    .with_graceful_shutdown(stop)
                    .await
            });
            // Closing the event channel stops the device thread (link-loss rule, then the
            // link is dropped: an emulated EEPROM image is written back).
            drop(shared);
            runtime.shutdown_timeout(Duration::from_secs(1));
            let _ = device_thread.join();
            result.map_err(Error::Io)
        })?;
    Ok(Running {
        addr,
        shutdown: Some(shutdown_tx),
        thread: Some(thread),
    })
}

/// The path of the state for scripts.
pub const STATE_PATH: &str = "/api/state";

/// `GET /api/state`: the device's state as the pages last received it ([`State`]), one JSON
/// object; read-only (commands go through a controlling page's WebSocket).
async fn api_state(AxumState(shared): AxumState<Arc<Shared>>) -> Response {
    let state = shared.state.borrow().clone();
    match serde_json::to_string(&state) {
        Ok(json) => (
            [
                (header::CONTENT_TYPE, "application/json"),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            json,
        )
            .into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

async fn asset(uri: Uri) -> Response {
    match assets::get(uri.path()) {
        Some(a) => (
            [
                (header::CONTENT_TYPE, a.content_type),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            a.bytes,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "not found").into_response(),
    }
}

async fn ws_upgrade(ws: WebSocketUpgrade, AxumState(shared): AxumState<Arc<Shared>>) -> Response {
    // Frames up to 64 KiB reach the handler, which refuses anything above
    // msg::MAX_MESSAGE_BYTES with an error message and keeps the connection; beyond 64 KiB
    // the WebSocket layer closes the connection.
    ws.max_message_size(64 * 1024)
        .max_frame_size(64 * 1024)
        .on_upgrade(move |socket| page(socket, shared))
}

/// How often a page is pinged (browsers answer WebSocket pings by themselves).
const PING_PERIOD: Duration = Duration::from_millis(500);

/// A page silent this long (no message, no pong) is dropped: a closed tab whose socket was not
/// closed, a network gone. For the controlling page this is the link loss.
/// Generous enough for a browser on a busy machine (its pongs come from its network thread).
const SILENCE_LIMIT: Duration = Duration::from_millis(3000);

fn log(page: u64, what: &str) {
    eprintln!("quadctl serve: page {page}: {what}");
}

/// Sends `msg`; false when the page is gone or does not take it within [`SILENCE_LIMIT`] (a
/// peer that vanished without closing fills the socket's buffer, and a send would wait for
/// ever).
async fn send(socket: &mut WebSocket, msg: &ServerMsg) -> bool {
    match serde_json::to_string(msg) {
        Ok(text) => matches!(
            tokio::time::timeout(SILENCE_LIMIT, socket.send(Message::Text(text.into()))).await,
            Ok(Ok(()))
        ),
        Err(_) => false,
    }
}

fn set_pages(shared: &Shared, delta: i32) {
    shared.state_tx.send_modify(|s| {
        s.pages = s.pages.saturating_add_signed(delta);
    });
}

fn set_controller(shared: &Shared, controller: Option<u64>) {
    shared.state_tx.send_modify(|s| s.controller = controller);
}

async fn page(mut socket: WebSocket, shared: Arc<Shared>) {
    let id = shared.next_page.fetch_add(1, Ordering::Relaxed);
    log(id, "connected");
    set_pages(&shared, 1);
    let w = shared.welcome.clone();
    let welcome = ServerMsg::Welcome {
        page_id: id,
        robot: w.robot,
        robot_name: w.robot_name,
        rotation_order: w.rotation_order,
        servos: ServoId::ALL
            .iter()
            .map(|&s| quad_host::ops::calibrate::servo_name(s))
            .collect(),
        link_loss_action: w.link_loss_action,
        target: w.target,
    };
    let mut state = shared.state.clone();
    if send(&mut socket, &welcome).await {
        let first = ServerMsg::State(Box::new(state.borrow_and_update().clone()));
        if send(&mut socket, &first).await {
            serve_page(&mut socket, &shared, &mut state, id).await;
        }
    }
    set_pages(&shared, -1);
    let was_controller = {
        let mut c = shared.controller.lock().unwrap_or_else(|e| e.into_inner());
        if *c == Some(id) {
            *c = None;
            true
        } else {
            false
        }
    };
    if was_controller {
        set_controller(&shared, None);
        log(
            id,
            "the controlling page went away: applying the device's link-loss rule",
        );
        let events = shared.events.lock().unwrap_or_else(|e| e.into_inner());
        let _ = events.send(Event::ControlLost);
    }
    log(id, "disconnected");
}

async fn serve_page(
    socket: &mut WebSocket,
    shared: &Shared,
    state: &mut watch::Receiver<State>,
    id: u64,
) {
    let mut closing = shared.closing.clone();
    let mut ping = tokio::time::interval(PING_PERIOD);
    let mut last_heard = tokio::time::Instant::now();
    loop {
        tokio::select! {
            _ = closing.changed() => return,
            _ = ping.tick() => {
                if last_heard.elapsed() > SILENCE_LIMIT {
                    log(id, &format!("no answer for {} ms: dropped", SILENCE_LIMIT.as_millis()));
                    return;
                }
                if socket.send(Message::Ping(Default::default())).await.is_err() {
                    return;
                }
            }
            changed = state.changed() => {
                if changed.is_err() {
                    return;
                }
                let s = ServerMsg::State(Box::new(state.borrow_and_update().clone()));
                if !send(socket, &s).await {
                    return;
                }
            }
            incoming = socket.recv() => {
                last_heard = tokio::time::Instant::now();
                let text = match incoming {
                    None | Some(Err(_)) | Some(Ok(Message::Close(_))) => return,
                    Some(Ok(Message::Text(t))) => t,
                    Some(Ok(Message::Binary(_))) => {
                        let e = msg::Error::Binary;
                        log(id, &format!("refused: {e}"));
                        if !send(socket, &ServerMsg::Error { message: e.to_string(), field: None }).await {
                            return;
                        }
                        continue;
                    }
                    Some(Ok(_)) => continue,
                };
                let reply = match ClientMsg::parse(text.as_str()) {
                    Err(e) => {
                        log(id, &format!("refused: {e}"));
                        ServerMsg::Error { message: e.to_string(), field: None }
                    }
                    Ok(cmd) => {
                        let reply = command(shared, id, cmd).await;
                        // The page's pongs waited unread while the device worked (a dozen
                        // requests on an emulated device take seconds): no silence to count.
                        last_heard = tokio::time::Instant::now();
                        reply
                    }
                };
                if !send(socket, &reply).await {
                    return;
                }
            }
        }
    }
}

async fn command(shared: &Shared, id: u64, cmd: ClientMsg) -> ServerMsg {
    let refuse_field = |message: String, field: Option<&'static str>| {
        log(id, &format!("{}: {message}", cmd.name()));
        ServerMsg::Error { message, field }
    };
    let refuse = |message: String| refuse_field(message, None);
    let done = ServerMsg::Done {
        command: cmd.name(),
    };
    {
        let mut c = shared.controller.lock().unwrap_or_else(|e| e.into_inner());
        match (cmd, *c) {
            (ClientMsg::TakeControl, None) => {
                *c = Some(id);
                drop(c);
                set_controller(shared, Some(id));
                log(id, "takes control");
                return done;
            }
            (ClientMsg::TakeControl, Some(other)) if other == id => return done,
            (ClientMsg::TakeControl, Some(other)) => {
                return refuse(format!(
                    "page {other} controls the robot; release it there first (this page watches)"
                ))
            }
            (ClientMsg::ReleaseControl, Some(other)) if other == id => {
                *c = None;
                drop(c);
                set_controller(shared, None);
                log(id, "releases control");
                return done;
            }
            (ClientMsg::ReleaseControl, _) => {
                return refuse("this page does not control".to_owned())
            }
            (_, Some(other)) if other == id => {}
            (_, Some(other)) => {
                return refuse(format!(
                    "refused: page {other} controls the robot (this page watches)"
                ))
            }
            (_, None) => {
                return refuse("refused: take control first (this page watches)".to_owned())
            }
        }
    }
    let (reply, result) = tokio::sync::oneshot::channel();
    let sent = {
        let events = shared.events.lock().unwrap_or_else(|e| e.into_inner());
        events.send(Event::Job(Job { cmd, reply })).is_ok()
    };
    if !sent {
        return refuse("the device thread has stopped".to_owned());
    }
    match result.await {
        Ok(Ok(())) => done,
        Ok(Err(e)) => refuse_field(e.to_string(), e.field()),
        Err(_) => refuse("the device thread has stopped".to_owned()),
    }
}
