//! Runs one motion of the twin's catalogue on a preset robot and prints its summary:
//!
//! ```sh
//! cargo run --release -p quad-twin --example twin_run -- shahriar2023 trot target/twin/shahriar2023-trot --render
//! # options: --servo NAME (another servo preset), --stance-height-m H (another stance)
//! ```
//!
//! (the `quadctl sim` command will do the same once the host library exists).

use quad_device::Config;
use quad_model::Physical;
use quad_protocol::RobotPreset;
use quad_twin::{run, MotionKind, RunOptions};
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
    let options = RunOptions {
        out_dir: args.get(2).filter(|a| !a.starts_with("--")).map(Into::into),
        render: args.iter().any(|a| a == "--render"),
    };
    match run(&config, &physical, kind, &options) {
        Ok(r) => {
            let s = &r.summary;
            println!(
                "{robot} {motion}: fell={} min_height={:.3} m max_tilt={:.3} rad",
                s.fell, s.min_height_m, s.max_tilt_rad
            );
            if let Some(reason) = &s.fall_reason {
                println!("  fall: {reason}");
            }
            if let Some(y) = &s.yaw {
                println!(
                    "  yaw: commanded {:.3} rad, achieved {:.3} rad, ratio {:.2}",
                    y.commanded_rad, y.achieved_rad, y.ratio
                );
            }
            if let Some(t) = &s.travel {
                println!(
                    "  travel: commanded {:.3} m, achieved {:.3} m, ratio {:.2}, heading error {:.3} rad",
                    t.commanded_m, t.achieved_m, t.ratio, t.heading_error_rad
                );
            }
            println!(
                "  slip: max {:.4} m per stance {:?}",
                s.slip.max_stance_slip_m, s.slip.per_leg_max_m
            );
            println!(
                "  torque: peak {:.3} N·m at {} (stall {:.2}), saturated {:.1} % of steps",
                s.torque.peak_nm,
                s.torque.peak_joint,
                s.torque.stall_nm,
                100.0 * s.torque.saturated_fraction
            );
            for j in &s.torque.joints {
                print!(" {}={:.2}/{:.2}", j.name, j.peak_nm, j.rms_nm);
            }
            println!();
            println!(
                "  tracking: roll rms {:.4} rad, pitch rms {:.4} rad, amplitude ratio {:?}",
                s.tracking.roll_rms_error_rad,
                s.tracking.pitch_rms_error_rad,
                s.tracking.amplitude_ratio
            );
            println!(
                "  speed: physics {:.1} sim s / wall s; whole loop {:.1} sim s / wall s ({:.2} s wall)",
                s.sim_per_wall, r.sim_per_wall, r.wall_s
            );
            for f in &s.files {
                println!("  wrote {}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("twin_run: {e}");
            ExitCode::FAILURE
        }
    }
}
