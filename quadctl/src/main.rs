//! `quadctl`: command-line front end of the quadruped kinematics. See `quadctl --help`.

mod args;
mod cmd;
mod progress;

use clap::{Parser, Subcommand};
use quad_protocol::MotionCommand::{Rest, Sit, StandUp};
use std::process::ExitCode;

const ABOUT: &str = "Kinematics of a 12-DoF quadruped: leg IK/FK and body poses, as CSV batches.

Units: metres and radians in every CSV (degrees only in human-readable tables). Frames: body
frame at the body centre, x forward, y left, z up; hip frame of a leg at its hip mount, axes
parallel to the body frame. Run `quadctl <command> --help` for the columns of each command.";

#[derive(Debug, Parser)]
#[command(name = "quadctl", version, about = ABOUT)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Ik(cmd::ik::Args),
    Fk(cmd::fk::Args),
    Pose(cmd::pose::Args),
    Motion(cmd::motion::Args),
    Check(cmd::check::Args),
    Plot(cmd::plot::Args),
    Accuracy(cmd::accuracy::Args),
    Stream(cmd::stream::Args),
    Calibrate(cmd::calibrate::Args),
    Robot(cmd::robot::Args),
    Demo(cmd::demo::Args),
    Serve(cmd::serve::Args),
    Play(cmd::play::Args),
    Sim(cmd::sim::Args),
    Export(cmd::export::Args),
    Port(cmd::port::Args),
    /// Stand up: outputs on at the rest pose, then up to the stance (onboard motion).
    #[command(after_help = cmd::onboard::STAND_EXAMPLES)]
    Stand(cmd::onboard::PostureArgs),
    /// Sit: down to the rest pose, held (onboard motion).
    #[command(after_help = cmd::onboard::SIT_EXAMPLES)]
    Sit(cmd::onboard::PostureArgs),
    /// Rest: down to the rest pose, then the outputs off (onboard motion).
    #[command(after_help = cmd::onboard::REST_EXAMPLES)]
    Rest(cmd::onboard::PostureArgs),
    /// Run one of the device's own motions: sways, yaw turn, foot paths, trot, walk.
    Run(cmd::onboard::RunArgs),
    Drive(cmd::drive::Args),
    /// The device's state with its inertial sensor: health, attitude, leveling, fall.
    Status(cmd::balance::StatusArgs),
    /// The device's state with its inertial sensor, live.
    Watch(cmd::balance::WatchArgs),
    /// The balance switch: leveling, fall detection, safe state, action on a sensor fault.
    Balance(cmd::balance::BalanceArgs),
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Ik(args) => {
            args::run_batch(&args.input.input, |i, o, d| cmd::ik::run(&args, i, o, d))
        }
        Command::Fk(args) => {
            args::run_batch(&args.input.input, |i, o, d| cmd::fk::run(&args, i, o, d))
        }
        Command::Pose(args) => {
            args::run_batch(&args.input.input, |i, o, d| cmd::pose::run(&args, i, o, d))
        }
        Command::Motion(args) => cmd::motion::run(&args),
        Command::Check(args) => cmd::check::run(&args),
        Command::Plot(args) => cmd::plot::run(&args),
        Command::Accuracy(args) => cmd::accuracy::run(&args),
        Command::Stream(args) => cmd::stream::main(&args),
        Command::Calibrate(args) => cmd::calibrate::main(&args),
        Command::Robot(args) => cmd::robot::main(&args),
        Command::Demo(args) => cmd::demo::main(&args),
        Command::Serve(args) => cmd::serve::main(&args),
        Command::Play(args) => cmd::play::main(&args),
        Command::Sim(args) => cmd::sim::run(&args),
        Command::Export(args) => cmd::export::run(&args),
        Command::Port(args) => cmd::port::main(&args),
        Command::Stand(args) => cmd::onboard::posture(&args, StandUp),
        Command::Sit(args) => cmd::onboard::posture(&args, Sit),
        Command::Rest(args) => cmd::onboard::posture(&args, Rest),
        Command::Run(args) => cmd::onboard::run(&args),
        Command::Drive(args) => cmd::drive::main(&args),
        Command::Status(args) => cmd::balance::status(&args),
        Command::Watch(args) => cmd::balance::watch(&args),
        Command::Balance(args) => cmd::balance::balance(&args),
    }
}
