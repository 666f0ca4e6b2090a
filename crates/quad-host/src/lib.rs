//! The host side of the quadruped, as a library: the device links ([`link`]: serial port,
//! simulated UART, the firmware in simavr, opened by one factory), the [`client`] (handshake,
//! retries, the readback-checked pose stream), the firmware emulator ([`emu`]), CSV I/O
//! ([`csv`], with the motion CSV in [`csv::motion`]), robot files ([`robot_file`]), plots
//! ([`plot`]), the frame-by-frame replay of the device's onboard motions ([`replay`]: its own
//! engine, quad-device's, on the host) and the operations behind each `quadctl` command
//! ([`ops`]).
//!
//! All kinematics is `kin-core`'s; this crate reads, validates, talks to the device and writes.
//! The `quadctl` binary only parses arguments, calls these functions and prints.

pub mod client;
pub mod csv;
pub mod emu;
pub mod link;
pub mod names;
pub mod ops;
pub mod plot;
pub mod replay;
pub mod robot_file;
