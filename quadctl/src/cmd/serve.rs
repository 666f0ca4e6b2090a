//! `quadctl serve`: the browser control panel on a local web server, owning the device link.

use crate::args::{self, DeviceRobotArgs, TargetArgs};
use quad_host::link::Target;
use quad_host::robot_file;
use quad_web::device::DeviceSetup;
use quad_web::ServeConfig;
use std::io::{self, Write};
use std::net::SocketAddr;
use std::process::ExitCode;
use std::time::Duration;

const LONG_ABOUT: &str = "\
Serves the control panel of the device (--sim, --emulator or --port) on a local web server and
prints its address; open it in a browser. Ctrl-C stops the server.

The page shows the robot in 3D from the device's readback (the commanded pose as a ghost), with
sliders for roll, pitch, yaw (DEGREES on the page, radians on the wire), x, y, z and the stance
height (millimetres on the page, metres on the wire), previewed at once by kin-core compiled to
WebAssembly; each leg is coloured by its reachability and joint-limit margin, and an unreachable
position is drawn, never sent. Live plots of the twelve joint angles and pulses, link health
and device state; a calibration tab jogs a servo's pulse (by moving its centre_us), sets its
centre and direction and saves to EEPROM. The Motion tab starts and stops the device's own
motions (stand, sit, rest, sways, yaw turn, foot paths, trot/walk) and shows the device's motion
status; while a walk runs, its joystick (keys W/S A/D Q/E, a gamepad) sends the velocity every
50 ms. The device checks a motion's parameters and its refusal names the field.
An artificial horizon shows the device's attitude from its inertial sensor (protocol 2.3; read
10 times a second), with the sensor's health (absent, starting, ok, fault and its kind), the
leveling and a latched fall; the leveling switch sends SetBalance, and a device without a
working sensor refuses it (the refusal is shown).

Several pages may watch; one controls at a time (`Take control` on the page). The outputs are
switched on only by the page's `Outputs on` button. Every command passes the same checks as the
command line's: a pose the host's kin-core or the device's calibration rejects is not sent, and
every answer passes stream's readback check. When the controlling page goes away, the server
applies the device's link-loss rule (hold: a running motion stops cleanly; or outputs off).

--listen sets the address (default 127.0.0.1:8080; port 0 picks a free one). Binding to
another interface exposes the robot to that network: there is no authentication.

--check does everything but serve: opens the device, binds the address, checks that this build
embeds the whole page (kin-core in WebAssembly, three.js), then stops; exit status 2 when the
page is incomplete (scripts/install-deps.sh installs what the build needs).";

const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl serve --emulator
  quadctl serve --sim --listen 127.0.0.1:0
  quadctl serve --sim --listen 127.0.0.1:0 --check";

/// Arguments of `quadctl serve`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Serve the browser control panel (3D view, pose sliders, onboard motions, calibration) of the device",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    /// Address to listen on.
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:8080")]
    pub listen: SocketAddr,
    /// How often the device's state is read between commands, ms.
    #[arg(long, value_name = "MS", default_value_t = 50, value_parser = clap::value_parser!(u64).range(5..=10_000))]
    pub poll_ms: u64,
    /// Check the device, the address and the embedded page, then stop instead of serving.
    #[arg(long)]
    pub check: bool,
}

/// Runs `quadctl serve` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let robot = match args
        .robot
        .robot
        .as_deref()
        .map(robot_file::resolve_description)
        .transpose()
    {
        Ok(r) => r.map(|d| d.robot),
        Err(e) => return args::fail("quadctl", &e),
    };
    let target = args.target.target(args.robot.sim_preset());
    if matches!(target, Target::Emulator { .. }) {
        eprintln!(
            "quadctl serve: booting the firmware in simavr (built from firmware-avr/ if needed)"
        );
    }
    let config = ServeConfig {
        device: DeviceSetup {
            target,
            robot,
            retries: args.target.retries,
            poll: Duration::from_millis(args.poll_ms),
        },
        listen: args.listen,
    };
    let running = match quad_web::start(config, true) {
        Ok(r) => r,
        Err(e) => return args::fail("quadctl", &e),
    };
    let page = quad_web::assets::check();
    let mut out = io::stdout().lock();
    if args.check {
        let _ = writeln!(
            out,
            "quadctl serve: device answered, http://{}/ bound, page {}; stopping (--check)",
            running.addr,
            if page.is_ok() {
                "complete"
            } else {
                "INCOMPLETE"
            }
        );
        drop(out);
        let stopped = running.stop();
        return match page {
            Err(e) => args::fail("quadctl", &e),
            Ok(()) => args::exit_status(stopped),
        };
    }
    if let Err(e) = page {
        eprintln!("quadctl serve: warning: {e}");
    }
    let _ = writeln!(
        out,
        "quadctl serve: http://{}/ (Ctrl-C stops)",
        running.addr
    );
    let _ = out.flush();
    drop(out);
    args::exit_status(running.wait())
}
