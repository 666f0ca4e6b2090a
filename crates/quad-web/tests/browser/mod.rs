//! What the browser tests share: the server in-process, chromedriver and a headless Debian
//! Chromium, and waiting on the page's state (`window.panel`).

#![allow(dead_code)]

use fantoccini::{Client, ClientBuilder};
use quad_host::link::emulator::EmulatorConfig;
use quad_host::link::sim::SimConfig;
use quad_host::link::Target;
use quad_protocol::RobotPreset;
use quad_web::device::DeviceSetup;
use quad_web::{Running, ServeConfig};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// The headless flags that work in a root container, plus a fixed window.
const CHROME_ARGS: [&str; 10] = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=1400,850",
    "--disable-dev-shm-usage",
];

/// The simulated device of seed 000's robot, its EEPROM in `storage`.
pub fn sim(storage: Option<PathBuf>) -> Target {
    Target::Sim {
        preset: RobotPreset::Shahriar2023,
        config: SimConfig::default(),
        storage,
    }
}

/// The firmware in simavr, its EEPROM in `storage`.
pub fn emulator(storage: Option<PathBuf>) -> Target {
    Target::Emulator {
        elf: None,
        config: EmulatorConfig::new(115_200),
        storage,
    }
}

/// `quadctl serve` in-process on a free port.
pub fn serve(target: Target) -> Running {
    let config = ServeConfig {
        device: DeviceSetup {
            target,
            robot: Some(kin_core::Robot::shahriar2023()),
            retries: 10,
            poll: Duration::from_millis(50),
        },
        listen: "127.0.0.1:0".parse().unwrap(),
    };
    quad_web::start(config, false).expect("the server starts")
}

/// A scratch directory under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Longest a browser may live: past it the watchdog kills chromedriver and the browser (the
/// test then fails on its next WebDriver call) so that a stuck test cannot keep Chromium
/// burning CPU.
const BROWSER_LIFETIME: Duration = Duration::from_secs(600);

/// Runs chromedriver (which starts Chromium) in a process group of its own, led by a shell that
/// waits for its stdin to close and then kills the whole group. The pipe's write end is held
/// only by this process, so the group dies when the [`Driver`] is dropped (a test's end or its
/// panic), when the watchdog fires, and when the test process itself dies — even by SIGKILL,
/// where no destructor runs. chromedriver's own shutdown is not relied on: a killed
/// chromedriver leaves its browser running.
const DRIVER_SCRIPT: &str = "chromedriver --port=0 & read -r _; kill -KILL 0";

/// The chromedriver process group; killed on drop.
struct Driver {
    leader: Child,
    /// Closing it ends the group (see [`DRIVER_SCRIPT`]); shared with the watchdog.
    hold: Arc<Mutex<Option<ChildStdin>>>,
    /// Dropping it tells the watchdog the group is gone.
    _alive: mpsc::Sender<()>,
}

impl Driver {
    /// Starts chromedriver on a port of the system's choice (`--port=0`, read back from its
    /// banner: parallel tests cannot collide) and returns it with that port.
    fn start() -> (Driver, u16) {
        let mut leader = Command::new("sh")
            .args(["-c", DRIVER_SCRIPT])
            .process_group(0)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("sh runs");
        let hold = Arc::new(Mutex::new(leader.stdin.take()));
        let stdout = leader.stdout.take().expect("piped");
        let (port_tx, port_rx) = mpsc::channel();
        // Reads the banner, then drains chromedriver's output until the group is gone.
        std::thread::spawn(move || {
            let mut port_tx = Some(port_tx);
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Some(port) = line
                    .split_once("started successfully on port ")
                    .and_then(|(_, p)| p.trim_end_matches('.').parse::<u16>().ok())
                {
                    if let Some(tx) = port_tx.take() {
                        let _ = tx.send(port);
                    }
                }
            }
        });
        let (alive, watched) = mpsc::channel::<()>();
        let watchdog_hold = Arc::clone(&hold);
        std::thread::spawn(move || {
            if let Err(mpsc::RecvTimeoutError::Timeout) = watched.recv_timeout(BROWSER_LIFETIME) {
                eprintln!(
                    "browser test still running after {} s: killing chromedriver and Chromium",
                    BROWSER_LIFETIME.as_secs()
                );
                watchdog_hold.lock().unwrap().take();
            }
        });
        let driver = Driver {
            leader,
            hold,
            _alive: alive,
        };
        let port = port_rx.recv_timeout(Duration::from_secs(30)).expect(
            "chromedriver starts (Debian: apt-get install chromium chromium-driver; \
             scripts/install-deps.sh)",
        );
        (driver, port)
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        self.hold.lock().unwrap_or_else(|e| e.into_inner()).take();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(10) {
            if let Ok(Some(_)) | Err(_) = self.leader.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        eprintln!("the chromedriver group did not end within 10 s");
    }
}

/// chromedriver and a browser session on it; both end on drop.
pub struct Browser {
    pub client: Client,
    _driver: Driver,
}

impl Browser {
    /// A headless Chromium with its profile in `profile`.
    pub async fn start(profile: &Path) -> Browser {
        let (driver, port) = Driver::start();
        let mut args: Vec<String> = CHROME_ARGS.iter().map(|s| (*s).to_owned()).collect();
        args.push(format!("--user-data-dir={}", profile.display()));
        let caps = json!({
            "goog:chromeOptions": { "binary": "/usr/bin/chromium", "args": args }
        });
        let caps = match caps {
            Value::Object(m) => m,
            _ => unreachable!(),
        };
        let url = format!("http://127.0.0.1:{port}");
        let t0 = Instant::now();
        let client = loop {
            let connector = hyper_util::client::legacy::connect::HttpConnector::new();
            match ClientBuilder::new(connector)
                .capabilities(caps.clone())
                .connect(&url)
                .await
            {
                Ok(c) => break c,
                Err(e) if t0.elapsed() < Duration::from_secs(20) => {
                    let _ = e;
                    tokio::time::sleep(Duration::from_millis(200)).await;
                }
                Err(e) => panic!("no browser session through chromedriver: {e}"),
            }
        };
        Browser {
            client,
            _driver: driver,
        }
    }

    /// Evaluates `expr` in the page.
    pub async fn js(&self, expr: &str) -> Value {
        self.client
            .execute(&format!("return ({expr});"), vec![])
            .await
            .unwrap_or_else(|e| panic!("{expr}: {e}"))
    }

    /// Waits until `expr` is truthy in the page, at most `timeout`; returns its value.
    pub async fn wait(&self, expr: &str, timeout: Duration) -> Value {
        let t0 = Instant::now();
        loop {
            let v = self.js(expr).await;
            let truthy = match &v {
                Value::Null => false,
                Value::Bool(b) => *b,
                Value::Number(n) => n.as_f64() != Some(0.0),
                Value::String(s) => !s.is_empty(),
                _ => true,
            };
            if truthy {
                return v;
            }
            if t0.elapsed() > timeout {
                let errors = self.js("window.panel && window.panel.errors").await;
                panic!("timed out waiting for `{expr}` (page errors: {errors})");
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Loads the panel at `addr` and waits for its first state.
    pub async fn open(&self, addr: std::net::SocketAddr) {
        self.client.goto(&format!("http://{addr}/")).await.unwrap();
        self.wait(
            "window.panel && panel.ready && panel.state !== null && panel.preview !== null",
            Duration::from_secs(20),
        )
        .await;
    }

    /// Clicks the element with `id`.
    pub async fn click(&self, id: &str) {
        self.client
            .find(fantoccini::Locator::Id(id))
            .await
            .unwrap_or_else(|e| panic!("#{id}: {e}"))
            .click()
            .await
            .unwrap_or_else(|e| panic!("click #{id}: {e}"));
    }

    /// Sends keys to the element with `id` (a slider: arrows step it, Home/End jump).
    pub async fn keys(&self, id: &str, keys: &str) {
        self.client
            .find(fantoccini::Locator::Id(id))
            .await
            .unwrap()
            .send_keys(keys)
            .await
            .unwrap_or_else(|e| panic!("keys to #{id}: {e}"));
    }

    /// A PNG of the page.
    pub async fn screenshot(&self) -> Vec<u8> {
        self.client.screenshot().await.unwrap()
    }

    /// Ends the WebDriver session, then the browser and chromedriver.
    pub async fn close(self) {
        let _ = self.client.clone().close().await;
    }
}

/// Writes a screenshot to docs/img/ (when `QUAD_WEB_SCREENSHOTS` is set) and to the scratch
/// directory.
pub fn keep_screenshot(png: &[u8], name: &str, scratch: &Path) {
    assert!(png.starts_with(b"\x89PNG"), "a PNG");
    std::fs::write(scratch.join(name), png).unwrap();
    if std::env::var_os("QUAD_WEB_SCREENSHOTS").is_some() {
        let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/img");
        std::fs::create_dir_all(&docs).unwrap();
        std::fs::write(docs.join(name), png).unwrap();
    }
}
