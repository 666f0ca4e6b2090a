//! The `quadctl` subcommands, one module each: an `Args` struct (`clap::Args`) and a function
//! that calls the library ([`quad_host`]) and prints. What several commands share lives in
//! [`crate::args`]; commands do not import each other's arguments.
//!
//! A new subcommand is a module here, an operation in `quad_host::ops` (the physics twin's:
//! `quad_twin::command`), and one variant in `main.rs`.

pub mod accuracy;
pub mod balance;
pub mod calibrate;
pub mod check;
pub mod demo;
pub mod drive;
pub mod export;
pub mod fk;
pub mod ik;
pub mod motion;
pub mod onboard;
pub mod play;
pub mod plot;
pub mod port;
pub mod pose;
pub mod robot;
pub mod serve;
pub mod sim;
pub mod stream;
