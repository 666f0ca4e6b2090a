//! # quad-web — the browser control panel
//!
//! `quadctl serve` runs this: a local web server (axum, WebSocket on tokio) that owns the link
//! to the device ([`quad_host::link::open`]) and serves one page, embedded in the binary:
//!
//! - a 3D view (three.js) of the robot from the device's **readback**, the commanded pose as a
//!   ghost, orbit and zoom, a ground grid and the feet's traces;
//! - sliders for the body pose and the stance height, previewed at once by kin-core compiled
//!   to WebAssembly (`crates/kin-wasm`), each leg coloured by its reachability and joint-limit
//!   margin; an unreachable position is drawn, not sent;
//! - the device's onboard motions (its motion engine): start, stop, a walk's velocity from a
//!   joystick, the engine's status live, its refusals named by field;
//! - live plots of the twelve joints and pulses, link health and device state;
//! - a calibration tab: pick a servo, jog its pulse, set its centre and direction, save;
//! - the inertial sensor (protocol 2.3): an artificial horizon from the device's attitude, the
//!   sensor's health, the leveling and a latched fall, and the leveling switch.
//!
//! Modules: [`msg`] (the WebSocket messages and their validation), [`balance`] (the sensor's
//! report for the pages and the leveling switch), [`device`] (the thread
//! that owns the link and the checks every command passes), [`motion`] (the Motion tab's
//! commands and their device requests), [`server`] (HTTP, WebSockets, who
//! controls, the state as JSON for scripts at `GET /api/state`), [`assets`] (the embedded files).

pub mod assets;
pub mod balance;
pub mod device;
pub mod motion;
pub mod msg;
pub mod server;

pub use server::{start, Running, ServeConfig};
