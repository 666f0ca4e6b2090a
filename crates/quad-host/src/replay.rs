//! Replaying an onboard motion on the host: every frame the device computes, recomputed with
//! the device's own engine (quad-device's [`Engine`], its walker, laws, foot paths, ramps and
//! limiter, on the host's kin-core math), from the motion request, the velocity commands and
//! the stop with the run frames they took effect at (protocol 2.3's [`MotionFrames`]), the
//! robot, the calibration and the joint-speed limit.
//!
//! The device ticks once per servo frame; the replay does the same, one frame per tick, so
//! its frames are the device's whenever the device's loop kept up (a tick that catches up
//! several frames makes the device skip the setpoints in between; the pin check below lets a
//! frame be skipped or shown twice, never changed). Each replayed [`Frame`] carries the label
//! the device reports for it — the stage and [`MotionFrames::frame`] — so that an answer's
//! readback is compared with the frame of its label ([`Replay::check_readback`]), and the
//! outputs' pulses of every frame are what the pins must show, in order
//! ([`Replay::check_pins`]).
//!
//! The checks name the first wrong frame and joint ([`Mismatch`]).

use crate::emu::{Pulse, CYCLES_PER_TICK};
use kin_core::body;
use kin_core::motion::gait::Velocity;
use kin_core::{DefaultMath, Robot, RotationOrder};
use quad_device::engine::{self, Engine, Limiter, PulseMaps, Setup};
use quad_protocol::servo::Calibration;
use quad_protocol::{MotionCommand, MotionFrames, MotionStage, MotionStatus, Readback, ServoId};
use std::fmt;

/// Most frames a replay runs (20 min of motion) before it gives up.
pub const MAX_FRAMES: usize = 60_000;

/// What the device is set up with.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// The robot.
    pub robot: Robot,
    /// The twelve servo calibrations, canonical order.
    pub calibration: [Calibration; 12],
    /// The stance height of the device's pose configuration, m.
    pub stance_height_m: f32,
    /// Its rotation order.
    pub order: RotationOrder,
    /// The joint-speed limit, rad/s.
    pub joint_speed_limit_rad_s: f32,
}

/// What the host asked for and when it took effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Commands {
    /// The motion.
    pub request: MotionCommand,
    /// The angles on the outputs when it started (`None`: the outputs were off).
    pub outputs_rad: Option<[f32; 12]>,
    /// The velocity commands, in the order sent, each with the run frame it applies from.
    pub velocities: Vec<(u32, Velocity)>,
    /// The run frame at which the stop took effect, if one did.
    pub stop_frame: Option<u32>,
}

/// One replayed frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// The stage the device reports after this frame.
    pub stage: MotionStage,
    /// The frame number it reports ([`MotionFrames::frame`], unwrapped).
    pub frame: u32,
    /// The engine's target (what a readback reports).
    pub target_rad: [f32; 12],
    /// The outputs after this frame's limiter step (what the pins show next).
    pub outputs_rad: [f32; 12],
    /// The outputs' pulses, half-µs.
    pub pulses_half_us: [u16; 12],
}

/// Why a replay could not be made.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A calibration is invalid.
    Calibration(ServoId),
    /// The engine refused the motion or a velocity command, or a frame failed.
    Engine(engine::Error),
    /// The motion ran for more than [`MAX_FRAMES`] frames.
    NoEnd,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Calibration(s) => write!(f, "the calibration of {s:?} is invalid"),
            Error::Engine(e) => write!(f, "the replay's engine: {e}"),
            Error::NoEnd => write!(f, "the replay ran past {MAX_FRAMES} frames"),
        }
    }
}

impl std::error::Error for Error {}

/// A frame of the device that differs from the replay.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// What was compared: "readback" or "pins".
    pub what: &'static str,
    /// The stage and frame number of the replayed frame expected.
    pub stage: MotionStage,
    /// Its frame number.
    pub frame: u32,
    /// The index of the pin record (pins) or answer (readback).
    pub index: usize,
    /// The first joint that differs (`None`: no replayed frame has this label).
    pub joint: Option<ServoId>,
    /// The device's value and the replay's (rad for a readback, µs for pins).
    pub device: f64,
    /// The replay's value.
    pub host: f64,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.joint {
            Some(j) => write!(
                f,
                "{} {}: {:?} frame {}: {:?} {:?} is {} on the device, {} in the replay",
                self.what,
                self.index,
                self.stage,
                self.frame,
                j.leg,
                j.joint,
                self.device,
                self.host
            ),
            None => write!(
                f,
                "{} {}: the replay has no {:?} frame {}",
                self.what, self.index, self.stage, self.frame
            ),
        }
    }
}

/// The replayed frames of one motion, from the state at its start (frame 0 of the approach)
/// to its end.
#[derive(Debug, Clone, PartialEq)]
pub struct Replay {
    /// The frames, the start first.
    pub frames: Vec<Frame>,
}

fn pulses(maps: &PulseMaps, angles: &[f32; 12]) -> Result<[u16; 12], Error> {
    let mut out = [0u16; 12];
    for (i, (m, &a)) in maps.iter().zip(angles).enumerate() {
        out[i] = m.pulse_half_us(a).map_err(|fault| {
            Error::Engine(engine::Error::ServoRange {
                servo: ServoId::ALL[i],
                fault,
            })
        })?;
    }
    Ok(out)
}

/// Replays `commands` on a device set up with `config` (module docs).
///
/// # Errors
/// See [`Error`].
pub fn replay(config: &Config, commands: &Commands) -> Result<Replay, Error> {
    let mut maps = [Calibration::default()
        .pulse_map()
        .map_err(|_| Error::Calibration(ServoId::ALL[0]))?; 12];
    for (i, c) in config.calibration.iter().enumerate() {
        maps[i] = c
            .pulse_map()
            .map_err(|_| Error::Calibration(ServoId::ALL[i]))?;
    }
    let limiter = Limiter::new(config.joint_speed_limit_rad_s).map_err(Error::Engine)?;
    let solver = body::Solver::<DefaultMath>::with_math(&config.robot);
    let mut engine = Engine::<DefaultMath>::new(limiter);
    let setup = Setup {
        robot: &config.robot,
        solver: &solver,
        stance_height_m: config.stance_height_m,
        order: config.order,
        pulse_maps: &maps,
        outputs: commands.outputs_rad.as_ref(),
        now_ms: 0,
    };
    let mut out = engine
        .start(&commands.request, &setup)
        .map_err(Error::Engine)?;
    // The held target: the outputs (converged on the last target) or, when the device enables
    // them, the start.
    let mut target = out;
    let mut frames = vec![Frame {
        stage: MotionStage::Approach,
        frame: 0,
        target_rad: target,
        outputs_rad: out,
        pulses_half_us: pulses(&maps, &out)?,
    }];
    let mut velocities = commands.velocities.iter().peekable();
    let mut stopped = false;
    while engine.is_active() {
        if frames.len() > MAX_FRAMES {
            return Err(Error::NoEnd);
        }
        let status = engine.status();
        // The commands that apply from this run frame, as the device took them between two
        // ticks. The device's clock is not replayed (now = 0): the walk's velocity timeout
        // does not fire here; its stop is the reported stop frame.
        let run_frame = match status.stage {
            MotionStage::Run | MotionStage::Stopping => Some(status.frame),
            MotionStage::Approach => Some(0),
            _ => None,
        };
        while let Some(&&(f, v)) = velocities.peek() {
            if run_frame != Some(f) || status.stage == MotionStage::Stopping {
                break;
            }
            engine.set_velocity(v, 0).map_err(Error::Engine)?;
            velocities.next();
        }
        if !stopped && status.stage == MotionStage::Run && commands.stop_frame == Some(status.frame)
        {
            engine.stop();
            stopped = true;
        }
        let tick = engine.tick(1, 0, &out, &solver, None);
        if let Some(q) = tick.target {
            pulses(&maps, &q)?;
            target = q;
        }
        engine.limiter().step(&mut out, &target);
        let after = engine.status();
        if let Some(e) = after.fault {
            return Err(Error::Engine(e));
        }
        frames.push(Frame {
            stage: after.stage,
            frame: after.frame,
            target_rad: target,
            outputs_rad: out,
            pulses_half_us: pulses(&maps, &out)?,
        });
        if tick.disable_outputs {
            break;
        }
    }
    Ok(Replay { frames })
}

/// The label an answer reports: its stage and its frame number, the run frame from `t_s`
/// (exact: `t_s` is the frame count times 20 ms), a ramp's from [`MotionFrames::frame`].
pub fn label(status: &MotionStatus, frames: &MotionFrames) -> (MotionStage, u32) {
    let frame = match status.stage {
        MotionStage::Run | MotionStage::Stopping => (status.t_s / engine::FRAME_S).round() as u32,
        _ => u32::from(frames.frame),
    };
    (status.stage, frame)
}

/// The run frame a wrapped frame number `wrapped` stands for, at or before the run frame
/// `now` (the numbers are sent modulo [`MotionFrames::MODULUS`]).
pub fn unwrap_frame(wrapped: u16, now: u32) -> u32 {
    let m = MotionFrames::MODULUS;
    let back = (now % m + m - u32::from(wrapped) % m) % m;
    now - back.min(now)
}

impl Replay {
    /// Compares `readback`, the `index`-th answer's, labelled `(stage, frame)` ([`label`]),
    /// with the replayed frames of that label, within `tolerance_rad`; returns the largest
    /// difference.
    ///
    /// # Errors
    /// The [`Mismatch`]: no frame of the label, or the first joint beyond the tolerance.
    pub fn check_readback(
        &self,
        index: usize,
        (stage, frame): (MotionStage, u32),
        readback: &Readback,
        tolerance_rad: f32,
    ) -> Result<f32, Mismatch> {
        let mut best: Option<(f32, usize, &Frame)> = None;
        // The answer to a stop comes between two frames: stage `Stopping` already, the
        // target still the run's frame.
        let same = |f: &&Frame| {
            f.frame == frame
                && (f.stage == stage
                    || (stage == MotionStage::Stopping && f.stage == MotionStage::Run))
        };
        for f in self.frames.iter().filter(same) {
            let (err, joint) = readback
                .angles_rad
                .iter()
                .zip(&f.target_rad)
                .map(|(a, b)| (a - b).abs())
                .enumerate()
                .fold(
                    (0.0f32, 0),
                    |(m, j), (i, e)| if e > m { (e, i) } else { (m, j) },
                );
            if best.is_none_or(|(b, _, _)| err < b) {
                best = Some((err, joint, f));
            }
        }
        match best {
            None => Err(Mismatch {
                what: "readback",
                stage,
                frame,
                index,
                joint: None,
                device: 0.0,
                host: 0.0,
            }),
            Some((err, _, _)) if err <= tolerance_rad => Ok(err),
            Some((_, j, f)) => Err(Mismatch {
                what: "readback",
                stage,
                frame,
                index,
                joint: Some(ServoId::ALL[j]),
                device: f64::from(readback.angles_rad[j]),
                host: f64::from(f.target_rad[j]),
            }),
        }
    }

    /// Follows `pins`, the twelve pulses of consecutive PWM periods seen from the start of the
    /// motion on (`None`: a channel without a pulse), through the replayed frames in order:
    /// each period shows the frame of the period before, the next one, or — after a late tick
    /// of the device, which catches up frames — one of the two after it; every channel within
    /// `tolerance_cycles` of the frame's pulse. Returns the frames the record went through.
    ///
    /// # Errors
    /// The first period that no such frame explains, naming the frame expected (the next one)
    /// and the first channel that differs from it.
    pub fn check_pins(
        &self,
        pins: &[[Option<Pulse>; 12]],
        tolerance_cycles: u64,
    ) -> Result<usize, Mismatch> {
        let fits = |p: &[Option<Pulse>; 12], f: &Frame| {
            p.iter().zip(&f.pulses_half_us).all(|(p, &w)| {
                p.is_some_and(|p| {
                    p.width_could_be(u64::from(w) * CYCLES_PER_TICK, tolerance_cycles)
                })
            })
        };
        let mut k = 0usize;
        for (i, p) in pins.iter().enumerate() {
            let last = self.frames.len() - 1;
            let next = [k + 1, k, k + 2, k + 3]
                .into_iter()
                .map(|j| j.min(last))
                .find(|&j| fits(p, &self.frames[j]));
            match next {
                Some(j) => k = j,
                None => {
                    let want = &self.frames[(k + 1).min(last)];
                    let j = p
                        .iter()
                        .zip(&want.pulses_half_us)
                        .position(|(p, &w)| {
                            !p.is_some_and(|p| {
                                p.width_could_be(u64::from(w) * CYCLES_PER_TICK, tolerance_cycles)
                            })
                        })
                        .unwrap_or(0);
                    return Err(Mismatch {
                        what: "pins",
                        stage: want.stage,
                        frame: want.frame,
                        index: i,
                        joint: Some(ServoId::ALL[j]),
                        device: p[j].map_or(0.0, |p| p.high_us()),
                        host: f64::from(want.pulses_half_us[j]) / 2.0,
                    });
                }
            }
        }
        Ok(k)
    }
}

#[cfg(test)]
mod tests {
    use super::unwrap_frame;

    #[test]
    fn a_wrapped_frame_number_unwraps_at_or_before_now() {
        assert_eq!(unwrap_frame(5, 5), 5);
        assert_eq!(unwrap_frame(3, 20), 3);
        assert_eq!(unwrap_frame(16_380, 16_390), 16_380);
        assert_eq!(unwrap_frame(2, 16_390), 16_386);
        // Never before the run began.
        assert_eq!(unwrap_frame(9, 4), 0);
    }
}
