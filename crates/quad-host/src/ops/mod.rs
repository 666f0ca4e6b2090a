//! The operations behind the `quadctl` commands, one module each, as functions that take a
//! request and return a typed result: the command line, a server or a test call the same code.

pub mod accuracy;
pub mod batch;
pub mod calibrate;
pub mod check;
pub mod defaults;
pub mod demo;
pub mod demo_motions;
pub mod drive;
pub mod motion;
pub mod onboard;
pub mod play;
pub mod plot;
pub mod robot;
pub mod session;
pub mod stream;
