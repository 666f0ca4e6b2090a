//! Seed 000's robot standing up on a 10° roll slope, balance off and then on: the body's
//! settled roll and pitch of each run on stdout, and the pictures:
//!
//! ```sh
//! cargo run --release -p quad-twin --example twin_slope_balance [-- DIR]
//! ```
//!
//! `DIR` (default `target/twin/slope-balance`) gets each run's files in `off/` and `on/`
//! (summary, plots, trace, the strip of frames `strip.png`) and `roll-pitch.png`: the body's
//! roll and pitch of both runs over time (`python -m quadtwin.compare`; docs/twin.md,
//! "The loop closed").

use quad_device::Config;
use quad_model::Physical;
use quad_protocol::BalanceConfig;
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::{run, MotionKind, RunOptions};
use std::path::PathBuf;
use std::process::ExitCode;

/// The slope, degrees.
const SLOPE_DEG: f32 = 10.0;

fn main() -> ExitCode {
    let dir = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("target/twin/slope-balance"), PathBuf::from);
    match slope(&dir) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("twin_slope_balance: {e}");
            ExitCode::FAILURE
        }
    }
}

fn slope(dir: &std::path::Path) -> Result<(), String> {
    let scenario =
        Scenario::new(SlopeAxis::Roll, SLOPE_DEG, false, None).map_err(|e| e.to_string())?;
    let mut args = vec![dir.join("roll-pitch.png").into_os_string()];
    for (name, balance) in [("off", None), ("on", Some(true))] {
        let out = dir.join(name);
        let options = RunOptions {
            out_dir: Some(out.clone()),
            render: true,
            scenario,
            balance: balance.map(|leveling| BalanceConfig {
                leveling,
                ..BalanceConfig::DEFAULT
            }),
            ..RunOptions::default()
        };
        let s = run(
            &Config::shahriar2023(),
            &Physical::shahriar2023(),
            MotionKind::Stand,
            &options,
        )
        .map_err(|e| e.to_string())?
        .summary;
        let sc = s.scenario.ok_or("no scenario metrics")?;
        println!(
            "balance {name:3}: fell={} settled roll {:.2}° pitch {:.2}°, strip {}",
            s.fell,
            sc.settled_roll_rad.to_degrees(),
            sc.settled_pitch_rad.to_degrees(),
            out.join("strip.png").display()
        );
        let mut arg = std::ffi::OsString::from(format!("balance {name}="));
        arg.push(std::path::absolute(&out).map_err(|e| e.to_string())?);
        args.push(arg);
    }
    let root = quad_model::venv::workspace_root();
    let status = quad_model::venv::python_module(&root, "compare")
        .map_err(|e| e.to_string())?
        .args(&args)
        .status()
        .map_err(|e| e.to_string())?;
    if !status.success() {
        return Err(format!("quadtwin.compare: {status}"));
    }
    println!("wrote {}", dir.join("roll-pitch.png").display());
    Ok(())
}
