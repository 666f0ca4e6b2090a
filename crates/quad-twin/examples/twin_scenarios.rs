//! The open-loop baselines of the balance figures, both presets, the device in-process
//! host-driven, `stand`:
//!
//! ```sh
//! cargo run --release -p quad-twin --example twin_scenarios [-- --out-dir DIR] [--balance] [--push-only]
//! cargo run --release -p quad-twin --example twin_scenarios -- --push-compare [--scan-steps N]
//! ```
//!
//! - standing on a 10° slope, roll then pitch: the body's settled roll and pitch;
//! - the floor tilting by 10° over 1 s (roll, then pitch): largest and settled tilt, settling
//!   time;
//! - the largest sideways impulse survived standing: a bisection over the impulse (to
//!   [`RELATIVE_TOLERANCE`] of it) between one the robot survives and one that fells it.
//!
//! With `--balance` the device's balance functions are on (leveling and fall detection, the
//! protocol's defaults; the figures of the closed loop); `--push-only` runs only the push's
//! bisection. `--push-compare` runs only the push, in one run: the bisection open loop and with
//! balance, then a scan of `N` impulses ([`SCAN_STEPS`] unless given) evenly up to the larger of the two largest
//! survived, each with balance and without, naming every impulse that fells the robot with
//! balance but not open loop. With `--out-dir DIR`, each slope and tilt run, and the push runs at the largest impulse
//! survived and the smallest that fells, keep their files (plots, pictures) in
//! `DIR/PRESET-CASE`.

use quad_device::Config;
use quad_model::Physical;
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::{run, MotionKind, RunOptions, Summary};
use std::path::PathBuf;
use std::process::ExitCode;

/// The slope and the tilt of the baselines, degrees.
const SLOPE_DEG: f32 = 10.0;
/// The bisection stops when the bracket is narrower than this share of its upper end.
const RELATIVE_TOLERANCE: f32 = 0.03;
/// Impulses of `--push-compare`'s scan unless `--scan-steps` says, evenly from 1/`SCAN_STEPS`
/// to all of the larger largest survived.
const SCAN_STEPS: u16 = 20;
/// First impulse tried, per kilogram of the robot, N·s/kg (then doubled until the robot falls).
const FIRST_IMPULSE_N_S_PER_KG: f32 = 0.25;

fn stand(
    config: &Config,
    physical: &Physical,
    scenario: Scenario,
    out_dir: Option<PathBuf>,
    balance: bool,
) -> Result<Summary, String> {
    let options = RunOptions {
        render: out_dir.is_some(),
        out_dir,
        scenario,
        balance: balance.then_some(quad_protocol::BalanceConfig {
            leveling: true,
            ..quad_protocol::BalanceConfig::DEFAULT
        }),
        ..RunOptions::default()
    };
    run(config, physical, MotionKind::Stand, &options)
        .map(|r| r.summary)
        .map_err(|e| e.to_string())
}

fn line(name: &str, case: &str, s: &Summary) {
    let sc = s.scenario.expect("a scenario run");
    println!(
        "{name:13} {case:26} fell={:5} |roll| max {:6.2}° |pitch| max {:6.2}° settled roll {:6.2}° pitch {:6.2}° settling {}",
        s.fell,
        sc.max_abs_roll_rad.to_degrees(),
        sc.max_abs_pitch_rad.to_degrees(),
        sc.settled_roll_rad.to_degrees(),
        sc.settled_pitch_rad.to_degrees(),
        sc.settling_time_s
            .map_or_else(|| "-".to_owned(), |t| format!("{t:.2} s"))
    );
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out_dir = args
        .iter()
        .position(|a| a == "--out-dir")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from);
    let balance = args.iter().any(|a| a == "--balance");
    let push_compare = args.iter().any(|a| a == "--push-compare");
    let scan_steps = match args.iter().position(|a| a == "--scan-steps") {
        Some(i) => match args.get(i + 1).and_then(|n| n.parse::<u16>().ok()) {
            Some(n) if n > 0 => n,
            _ => {
                eprintln!("twin_scenarios: --scan-steps takes a count > 0");
                return ExitCode::FAILURE;
            }
        },
        None => SCAN_STEPS,
    };
    let push_only = push_compare || args.iter().any(|a| a == "--push-only");
    let dir = |name: &str, case: &str| out_dir.as_ref().map(|d| d.join(format!("{name}-{case}")));
    let presets = [
        (
            "shahriar2023",
            Config::shahriar2023(),
            Physical::shahriar2023(),
        ),
        (
            "fernando2025",
            Config::fernando2025(),
            Physical::fernando2025(),
        ),
    ];
    let result = (|| -> Result<(), String> {
        for (name, config, physical) in &presets {
            for axis in SlopeAxis::ALL.into_iter().filter(|_| !push_only) {
                let case = format!("slope-{}", axis.name());
                let scenario =
                    Scenario::new(axis, SLOPE_DEG, false, None).map_err(|e| e.to_string())?;
                let s = stand(config, physical, scenario, dir(name, &case), balance)?;
                line(name, &format!("slope {SLOPE_DEG}° {}", axis.name()), &s);
                let case = format!("tilt-{}", axis.name());
                let scenario = Scenario::new(axis, 0.0, true, None).map_err(|e| e.to_string())?;
                let s = stand(config, physical, scenario, dir(name, &case), balance)?;
                line(name, &format!("floor tilting 10° {}", axis.name()), &s);
            }
            let push = |impulse: f32, balance: bool, out: Option<PathBuf>| {
                let scenario = Scenario::new(SlopeAxis::Roll, 0.0, false, Some(impulse))
                    .map_err(|e| e.to_string())?;
                stand(config, physical, scenario, out, balance)
            };
            let largest = |balance: bool| -> Result<f32, String> {
                let mut lo = 0.0_f32;
                let mut hi = FIRST_IMPULSE_N_S_PER_KG * physical.total_mass_kg();
                let mut runs = 0;
                while !push(hi, balance, None)?.fell {
                    lo = hi;
                    hi *= 2.0;
                    runs += 1;
                }
                while hi - lo > RELATIVE_TOLERANCE * hi {
                    let mid = 0.5 * (lo + hi);
                    runs += 1;
                    if push(mid, balance, None)?.fell {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                let suffix = if balance { "-balance" } else { "" };
                let survived = push(lo, balance, dir(name, &format!("push-survived{suffix}")))?;
                line(name, &format!("push {lo:.2} N·s (survived)"), &survived);
                let fell = push(hi, balance, dir(name, &format!("push-fell{suffix}")))?;
                line(name, &format!("push {hi:.2} N·s (fell)"), &fell);
                println!(
                    "{name:13} largest sideways impulse survived standing, balance {}: {lo:.2} N·s ({:.2} m/s given to the whole robot; {hi:.2} N·s fells it; {} runs)",
                    if balance { "on" } else { "off" },
                    lo / physical.total_mass_kg(),
                    runs + 2
                );
                Ok(lo)
            };
            if !push_compare {
                largest(balance)?;
                continue;
            }
            let open = largest(false)?;
            let closed = largest(true)?;
            let top = open.max(closed);
            let mut worse = Vec::new();
            // With balance: the largest scanned impulse up to which every one was survived,
            // and every one that fell the robot.
            let mut unbroken = 0.0_f32;
            let mut fell_on = Vec::new();
            for k in 1..=scan_steps {
                let impulse = top * f32::from(k) / f32::from(scan_steps);
                let off = push(impulse, false, None)?.fell;
                let on = push(impulse, true, None)?.fell;
                println!(
                    "{name:13} scan {impulse:6.2} N·s: fell open loop {off:5}, with balance {on:5}"
                );
                if on && !off {
                    worse.push(impulse);
                }
                if on {
                    fell_on.push(impulse);
                } else if fell_on.is_empty() {
                    unbroken = impulse;
                }
            }
            println!(
                "{name:13} push, same run: largest survived {closed:.2} N·s with balance, {open:.2} N·s open loop ({:+.1} %); impulses up to {top:.2} N·s that fell the robot with balance and not open loop: {worse:.2?}; with balance every scanned impulse up to {unbroken:.2} N·s survived ({:+.1} % on open loop), falls at {fell_on:.2?}",
                100.0 * (closed / open - 1.0),
                100.0 * (unbroken / open - 1.0)
            );
        }
        Ok(())
    })();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("twin_scenarios: {e}");
            ExitCode::FAILURE
        }
    }
}
