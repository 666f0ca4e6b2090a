//! `quadctl`, the command-line front end of the quadruped kinematics, as a library: robot files,
//! the CSV batch format and one module per subcommand. The binary (`src/main.rs`) only parses
//! the command line and dispatches here.
//!
//! All kinematics is `kin-core`'s; this crate only reads, validates and prints.

pub mod client;
pub mod cmd;
pub mod csv_io;
pub mod emu;
pub mod link;
pub mod plot;
pub mod robot_file;
