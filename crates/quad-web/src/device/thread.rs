//! The device thread: opens the link, connects a [`Session`], carries out the pages' jobs one
//! at a time and publishes the state between them.

use super::{Error, Session};
use crate::balance;
use crate::msg::{self, State};
use kin_core::Robot;
use quad_host::client::{AngleCheck, Client, ClientConfig};
use quad_host::link::{self, Link, Target};
use quad_protocol::DeviceInfo;
use std::time::{Duration, Instant};

/// Where the device is and what the server expects of it.
#[derive(Debug, Clone)]
pub struct DeviceSetup {
    /// The device.
    pub target: Target,
    /// The robot the host was given (`--robot`), which the device's must be; `None`: the
    /// device's own ([`quad_host::robot_file::device_robot`]).
    pub robot: Option<Robot>,
    /// Resends per request.
    pub retries: u32,
    /// How often the state is read between commands.
    pub poll: Duration,
}

/// A page command for the device thread, and where its result goes.
pub struct Job {
    /// The command (validated).
    pub cmd: msg::ClientMsg,
    /// The result.
    pub reply: tokio::sync::oneshot::Sender<Result<(), Error>>,
}

/// What the device thread tells the server.
pub enum Event {
    /// A job for the device.
    Job(Job),
    /// The controlling page went away.
    ControlLost,
}

/// What the server learns when the device thread is up.
#[derive(Debug, Clone)]
pub struct Ready {
    /// The device's `HelloAck`.
    pub info: DeviceInfo,
    /// The robot the device runs, which the server plans and checks with.
    pub robot: Robot,
    /// Its name (the description's, or the preset's).
    pub robot_name: String,
}

/// The device's clock runs this much at a time while it is behind the wall clock: a command
/// that arrives meanwhile waits for at most one slice (an emulated device may need several
/// times its length of wall time).
const IDLE_SLICE: Duration = Duration::from_millis(2);

/// Longest wait for an event while the device's clock is up to the wall clock.
const WAIT_SLICE: Duration = Duration::from_millis(10);

/// The device thread's next event: a job, a lost page, the server's end, or (as a timeout) a
/// state read due at `poll_due`.
///
/// The device's clock follows the server's meanwhile: a simulated or emulated device's time
/// (and its motion) runs only while its link is read, so the link idles in [`IDLE_SLICE`]s up
/// to the wall clock, checking for events and a due state read between slices. A device slower
/// than real time (simavr on a busy machine) thus runs its motions slower rather than delaying
/// the pages' commands.
fn next_event<L: Link>(
    events: &std::sync::mpsc::Receiver<Event>,
    session: &mut Session<L>,
    link_up: &mut bool,
    wall_epoch: Instant,
    poll_due: Instant,
) -> Result<Event, std::sync::mpsc::RecvTimeoutError> {
    use std::sync::mpsc::{RecvTimeoutError, TryRecvError};
    loop {
        match events.try_recv() {
            Ok(e) => return Ok(e),
            Err(TryRecvError::Disconnected) => return Err(RecvTimeoutError::Disconnected),
            Err(TryRecvError::Empty) => {}
        }
        let now = Instant::now();
        if now >= poll_due {
            return Err(RecvTimeoutError::Timeout);
        }
        let behind = wall_epoch.elapsed().saturating_sub(session.link_elapsed());
        if *link_up && behind >= IDLE_SLICE {
            if let Err(e) = session.idle(IDLE_SLICE) {
                eprintln!("quadctl serve: device link failed: {e}");
                *link_up = false;
            }
            continue;
        }
        match events.recv_timeout((poll_due - now).min(WAIT_SLICE)) {
            Ok(e) => return Ok(e),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return Err(RecvTimeoutError::Disconnected),
        }
    }
}

/// Runs the device thread: opens the link, connects, then serves `events` and publishes the
/// state to `state` until `events` closes. The result of the connection goes to `ready` first.
pub fn run(
    setup: DeviceSetup,
    events: std::sync::mpsc::Receiver<Event>,
    state: tokio::sync::watch::Sender<State>,
    ready: std::sync::mpsc::Sender<Result<Ready, Error>>,
    started: Instant,
) {
    let connect = || -> Result<Session<Box<dyn Link>>, Error> {
        let link = link::open(&setup.target)?;
        let config = ClientConfig::for_target(&setup.target, setup.retries);
        let client = Client::new(link, config);
        Session::connect(client, setup.robot, AngleCheck::for_target(&setup.target))
    };
    let mut session = match connect() {
        Ok(s) => s,
        Err(e) => {
            let _ = ready.send(Err(e));
            return;
        }
    };
    let _ = ready.send(Ok(Ready {
        info: *session.info(),
        robot: session.robot,
        robot_name: session.robot_name.clone(),
    }));
    let now_ms = || started.elapsed().as_secs_f64() * 1e3;
    let publish = |session: &Session<Box<dyn Link>>, link_up: bool| {
        state.send_modify(|s| {
            let (controller, pages) = (s.controller, s.pages);
            *s = State {
                controller,
                pages,
                link_up,
                ..session.state(now_ms())
            };
        });
    };
    publish(&session, true);
    let mut link_up = true;
    let wall_epoch = Instant::now();
    let mut last_state = Instant::now();
    let mut imu_due = Instant::now() + balance::IMU_PERIOD;
    loop {
        // The sensor's report on its own schedule: a stream of commands, which holds off the
        // state read (each command's answer carries the state), does not hold it off.
        if Instant::now() >= imu_due {
            imu_due += balance::IMU_PERIOD;
            if imu_due < Instant::now() {
                imu_due = Instant::now() + balance::IMU_PERIOD;
            }
            if link_up {
                match session.read_imu() {
                    Ok(()) => {}
                    Err(Error::Link(e)) => {
                        eprintln!("quadctl serve: device link failed: {e}");
                        link_up = false;
                    }
                    Err(e) => eprintln!("quadctl serve: sensor read failed: {e}"),
                }
                publish(&session, link_up);
            }
        }
        let event = next_event(
            &events,
            &mut session,
            &mut link_up,
            wall_epoch,
            (last_state + setup.poll).min(imu_due),
        );
        if matches!(event, Err(std::sync::mpsc::RecvTimeoutError::Timeout))
            && Instant::now() < last_state + setup.poll
        {
            // The sensor's read is due, not the state's.
            continue;
        }
        last_state = Instant::now();
        match event {
            Ok(Event::Job(job)) => {
                let result = if link_up {
                    match job.cmd {
                        msg::ClientMsg::GuideStart | msg::ClientMsg::GuideKey { .. } => session
                            .guide_command(&job.cmd, &|s: &Session<Box<dyn Link>>| {
                                publish(s, true)
                            }),
                        _ => session.command(&job.cmd),
                    }
                } else {
                    Err(Error::LinkDown)
                };
                publish(&session, link_up);
                let _ = job.reply.send(result);
            }
            Ok(Event::ControlLost) => {
                if link_up {
                    if let Err(e) = session.control_lost() {
                        eprintln!("quadctl serve: link-loss action failed: {e}");
                    }
                }
                publish(&session, link_up);
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if link_up {
                    match session.poll() {
                        Ok(()) => {}
                        Err(Error::Link(e)) => {
                            eprintln!("quadctl serve: device link failed: {e}");
                            link_up = false;
                        }
                        Err(e) => eprintln!("quadctl serve: state read failed: {e}"),
                    }
                }
                publish(&session, link_up);
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                // The server stopped: leave the device as the link-loss rule says.
                if link_up {
                    let _ = session.control_lost();
                }
                return;
            }
        }
    }
}
