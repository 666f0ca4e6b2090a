//! Runs one motion of the twin's catalogue on a preset robot and prints its summary:
//!
//! ```sh
//! cargo run --release -p quad-twin --example twin_run -- shahriar2023 trot target/twin/shahriar2023-trot --render
//! # options: --servo NAME (another servo preset), --stance-height-m H (another stance),
//! #          --emulator (the firmware in simavr instead of the in-process device);
//! #          the trot's shape: --cycle-s T, --duty D, --step-height-fraction F (of H),
//! #          --speed-heights-per-s V (kin-core's own trot: --duty 0.5 --cycle-s 0.8);
//! #          the world: --slope-deg D, --slope-axis roll|pitch, --tilt-floor, --push-n-s I;
//! #          --balance (the device levels the body and detects falls)
//! ```
//!
//! `quadctl sim` is the command; this example keeps the parameter studies scriptable.

use quad_device::Config;
use quad_model::Physical;
use quad_protocol::RobotPreset;
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::{run_plan, MotionKind, Plan, RunOptions, TrotShape};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(robot), Some(motion)) = (args.first(), args.get(1)) else {
        eprintln!(
            "usage: twin_run ROBOT MOTION [OUT_DIR] [--render] [--servo NAME] [--stance-height-m H]\n  robots: {}\n  motions: {}",
            Physical::PRESETS.join(", "),
            MotionKind::ALL.map(MotionKind::name).join(", ")
        );
        return ExitCode::from(2);
    };
    let config = match RobotPreset::from_name(robot).and_then(Config::for_preset) {
        Some(c) => c,
        None => {
            eprintln!(
                "unknown robot `{robot}` (known: {})",
                Physical::PRESETS.join(", ")
            );
            return ExitCode::from(2);
        }
    };
    let Some(kind) = MotionKind::parse(motion) else {
        eprintln!("unknown motion `{motion}`");
        return ExitCode::from(2);
    };
    let mut config = config;
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    if let Some(h) = value("--stance-height-m") {
        match h.parse::<f32>() {
            Ok(h) => config.pose_config.stance_height_m = h,
            Err(_) => {
                eprintln!("--stance-height-m: `{h}` is not a number");
                return ExitCode::from(2);
            }
        }
    }
    let physical = match Physical::preset(robot).and_then(|p| match value("--servo") {
        Some(name) => p.with_servo(name),
        None => Ok(p),
    }) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let scenario = (|| -> Result<Scenario, String> {
        let number = |flag: &str| -> Result<Option<f32>, String> {
            value(flag)
                .map(|v| {
                    v.parse::<f32>()
                        .map_err(|_| format!("{flag}: `{v}` is not a number"))
                })
                .transpose()
        };
        let axis = match value("--slope-axis").map(String::as_str) {
            None | Some("roll") => SlopeAxis::Roll,
            Some("pitch") => SlopeAxis::Pitch,
            Some(other) => return Err(format!("--slope-axis: `{other}` is not roll or pitch")),
        };
        Scenario::new(
            axis,
            number("--slope-deg")?.unwrap_or(0.0),
            args.iter().any(|a| a == "--tilt-floor"),
            number("--push-n-s")?,
        )
        .map_err(|e| e.to_string())
    })();
    let scenario = match scenario {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let options = RunOptions {
        out_dir: args.get(2).filter(|a| !a.starts_with("--")).map(Into::into),
        render: args.iter().any(|a| a == "--render"),
        driver: if args.iter().any(|a| a == "--emulator") {
            quad_twin::Driver::Emulator { elf: None }
        } else {
            quad_twin::Driver::Device
        },
        onboard: args.iter().any(|a| a == "--onboard"),
        scenario,
        balance: args
            .iter()
            .any(|a| a == "--balance")
            .then_some(quad_protocol::BalanceConfig {
                leveling: true,
                ..quad_protocol::BalanceConfig::DEFAULT
            }),
        ..RunOptions::default()
    };
    let number = |flag: &str| -> Result<Option<f32>, String> {
        value(flag)
            .map(|v| {
                v.parse::<f32>()
                    .map_err(|_| format!("{flag}: `{v}` is not a number"))
            })
            .transpose()
    };
    let mut shape = TrotShape::default();
    let plan = (|| -> Result<Plan, String> {
        for (flag, field) in [
            ("--cycle-s", &mut shape.cycle_s),
            ("--duty", &mut shape.duty_factor),
            ("--step-height-fraction", &mut shape.step_height_fraction),
            ("--speed-heights-per-s", &mut shape.speed_heights_per_s),
        ] {
            if let Some(v) = number(flag)? {
                *field = v;
            }
        }
        let plan = match kind {
            MotionKind::Trot => Plan::trot(&config, shape),
            MotionKind::TrotTurn => Plan::trot_turn(&config, shape),
            _ => Plan::new(kind, &config),
        };
        plan.map_err(|e| e.to_string())
    })();
    let plan = match plan {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    match run_plan(&config, &physical, &plan, &options) {
        Ok(r) => {
            print!("{r}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("twin_run: {e}");
            ExitCode::FAILURE
        }
    }
}
