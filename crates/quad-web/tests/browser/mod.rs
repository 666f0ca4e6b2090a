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
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
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
            robot: kin_core::Robot::shahriar2023(),
            preset: RobotPreset::Shahriar2023,
            retries: 10,
            poll: Duration::from_millis(50),
        },
        robot_name: "shahriar2023".to_owned(),
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

/// chromedriver and a browser session on it; both end on drop.
pub struct Browser {
    pub client: Client,
    driver: Child,
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

impl Browser {
    pub async fn start(profile: &Path) -> Browser {
        let port = free_port();
        let driver = Command::new("chromedriver")
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver runs (Debian: apt-get install chromium chromium-driver; scripts/install-deps.sh)");
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
        Browser { client, driver }
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

    pub async fn close(mut self) {
        let _ = self.client.clone().close().await;
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.driver.kill();
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
