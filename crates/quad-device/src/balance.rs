//! The balance functions: the attitude from the inertial sensor, body leveling, fall detection,
//! the start check and the sensor's health ([`Device::on_imu`](crate::Device::on_imu) feeds
//! it; the protocol's [`BalanceConfig`] configures it and [`ImuReport`] reports it).
//!
//! ## Start-up: the gyro bias
//! The first readings measure the gyro's bias: the robot must stay **still for
//! [`BIAS_WINDOW_MS`] (1 s)** from its first sample. A sample whose specific force differs from
//! `g` by more than [`STILL_ACCEL_SHARE`] or whose rate exceeds [`STILL_RATE_RAD_S`] on an axis
//! restarts that second. The mean rate is the bias, the mean accelerometer reading the first
//! attitude ([`kin_core::attitude::Estimator::reset`]); the estimator's integral term then
//! follows the bias as it drifts. Meanwhile the health is
//! [`ImuHealth::Starting`]: leveling and the tilt's fall
//! detection wait (a leveling switched on meanwhile starts when the second is over), the open
//! loop motions run as without a sensor, and the start check reads the accelerometer alone.
//!
//! ## Estimation
//! Every sample runs kin-core's Mahony filter ([`Estimator`]) with `dt` from the device clock
//! (the time since the previous sample, within [`DT_MIN_S`]…[`DT_MAX_S`]: two samples in one
//! millisecond, or a gap after a fault, integrate a bounded step).
//!
//! ## Leveling (a PI on the attitude)
//! While leveling is on, the sensor is ok, and either no motion runs with a body pose held (the
//! stance after a stand-up or a motion, or a `SetBodyPose`) or a sway runs, each servo frame
//! corrects the body's commanded roll and pitch: with the error `e` = measured − intended
//! attitude (the intended one is the held pose's, or the sway's at that frame),
//! `c = −(k_P·e + k_I·∫e dt + k_ω·dz(ω))`, each axis within `±max_correction_rad` (the
//! integral held within the same bound: no wind-up); the last term is the rate term below.
//! The correction goes through the same body IK and the one joint-speed limiter as every
//! target; when the IK cannot reach it, the largest share of
//! it that is reachable is applied ([`crate::engine::LEVEL_SHARES`]) and the report says
//! `correction_limited`. On a slope of `s` the body's measured roll is `s + c` (the feet stand
//! on the slope), so the integral settles at `c = −s`: level.
//!
//! ## The rate term
//! A sideways push tips the robot over the feet on one side within 0.2–0.3 s, faster than
//! the PI moves (and the accelerometer first reads the push's own force as a tilt the other
//! way). The gyro sees the tip at once: the body's rate `ω` about x and y (the bias
//! removed), beyond a dead band of [`RATE_DEAD_BAND_RAD_S`] (`dz`), adds [`RATE_GAIN_S`] of
//! correction per rad/s. It acts on a set point held for [`RATE_HELD_FRAMES`]: a sway, or a
//! new pose the body is still turning to, runs the PI alone. It is part of the leveling and
//! switched with it (`SetBalance`'s `leveling`: off with it, and after a sensor fault; a
//! sway's set point moves every frame, so only a held pose gets it); its share of the correction is bounded, reduced
//! to what the legs reach, and rate limited exactly as the PI's, since it is one sum `c`.
//! Tipping toward +y (roll falling), it lengthens the legs on the side the robot stands on
//! and shortens the lifted ones: the loaded feet push the body back up, a torque against the
//! fall, and the lifted feet reach down. A body that turns slowly adds nothing. Shifting the
//! body sideways instead (toward the lifted side) was measured and not kept: the sideways
//! force at the feet first turns the body further toward the fall, and it felled the robot at
//! pushes the leveling alone survives (`docs/benchmark-journal.md`, "A push with balance").
//!
//! ## Fall detection
//! While the outputs are driven and fall detection is on: `|roll|` or `|pitch|` beyond
//! `fall_angle_rad` ([`FallKind::Tilt`]), or a specific force below [`FREE_FALL_SHARE`] of `g`
//! for [`FREE_FALL_MS`] ([`FallKind::FreeFall`]) → the motion stops and the outputs go to the
//! safe state at that sample, within the servo frame: [`SafeState::Off`] switches them off,
//! [`SafeState::Rest`] makes the rest pose the held target (the limiter approaches it). The
//! fall is latched (reported, [`quad_protocol::Flags::FALL_DETECTED`]) and nothing moves again
//! until an explicit motion request (`StartMotion`, a direct setpoint, `SetOutputs` on) clears
//! it; a `StartMotion` is refused while the body is not upright.
//!
//! ## Faults
//! A fault pushed while the sensor was healthy (NAK, stuck data, a held bus) switches leveling
//! off (the correction drops to zero through the limiter: no joint steps by more than the
//! limiter's step) and reports the fault; a running motion continues open loop or stops, as
//! [`BalanceConfig::on_fault`] says. Leveling stays off until a `SetBalance` switches it on
//! again. No sensor (an [`ImuFault::Absent`] at boot, or no reading at all): leveling is refused
//! with a typed nack and the health is absent.

use crate::imu::{ImuFault, ImuReading, ImuSample};
use kin_core::attitude::{Attitude, Estimator, Gains, G_M_S2};
use kin_core::Math;
#[cfg(doc)]
use quad_protocol::SafeState;
use quad_protocol::{BalanceConfig, FallKind, ImuFaultKind, ImuHealth, ImuReport, NackReason};

/// How long the robot must stay still from its first sample while the gyro bias is measured,
/// ms.
pub const BIAS_WINDOW_MS: u32 = 1000;

/// The fewest samples of a bias measurement (10 at the sensor's slowest rate of 10 Hz… a
/// driver at ≥ 100 Hz gives 100).
pub const BIAS_MIN_SAMPLES: u16 = 10;

/// The largest `| |a|/g − 1 |` of a still sample during the bias measurement.
pub const STILL_ACCEL_SHARE: f32 = 0.1;

/// The largest rate on any axis of a still sample during the bias measurement, rad/s (the
/// MPU-6050's bias stays below it; a robot being moved does not).
pub const STILL_RATE_RAD_S: f32 = 0.35;

/// The shortest and the longest time step of one sample, s.
pub const DT_MIN_S: f32 = 0.001;
/// See [`DT_MIN_S`].
pub const DT_MAX_S: f32 = 0.1;

/// The specific force below which the robot is falling, a share of `g`.
pub const FREE_FALL_SHARE: f32 = 0.3;

/// How long the specific force must stay below [`FREE_FALL_SHARE`] of `g` for a free fall, ms
/// (a 60 ms fall is 1.8 cm: beyond a trot's bounce, short of a drop from the table).
pub const FREE_FALL_MS: u32 = 60;

/// The largest `|roll|` or `|pitch|` at which a motion may start, rad (35°: a robot standing
/// on any slope it can stand on; lying on its side or back it is refused). A fall angle set
/// below it is the limit instead.
pub const START_TILT_MAX_RAD: f32 = 0.61;

/// The dead band of the leveling's rate term, rad/s (module docs, "The rate term"): a body
/// turning slower than this against its set point adds nothing (a floor tilting by 10° in
/// 1 s turns it at 0.17 rad/s; a push that tips it over, at 0.6–1 rad/s within 50 ms).
pub const RATE_DEAD_BAND_RAD_S: f32 = 0.3;

/// The leveling's correction per rad/s of rate beyond [`RATE_DEAD_BAND_RAD_S`], s (module
/// docs, "The rate term"; measured in the physics twin: 0.3 s and 0.8 s both keep every push
/// the leveling alone survives, 0.8 s survives the larger ones).
pub const RATE_GAIN_S: f32 = 0.8;

/// How many servo frames the set point must have stayed the same before the rate term acts
/// (25: 0.5 s; module docs, "The rate term").
pub const RATE_HELD_FRAMES: u8 = 25;

/// What the device must do after a reading ([`Balance::push`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// Nothing.
    None,
    /// A fall was detected (and latched): stop, outputs to the safe state.
    Fall(FallKind),
    /// The sensor failed while it was healthy: leveling is off; the motion continues or stops
    /// as configured.
    Fault,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// No reading yet, or the sensor is absent.
    Absent,
    /// Measuring the gyro bias since `since_ms`.
    Starting {
        since_ms: u32,
        n: u16,
        gyro_sum: [f32; 3],
        accel_sum: [f32; 3],
    },
    /// Estimating.
    Running,
}

/// The balance functions' state (module docs), on kin-core math backend `M`.
#[derive(Debug, Clone, Copy)]
pub struct Balance<M> {
    config: BalanceConfig,
    estimator: Estimator<M>,
    phase: Phase,
    /// The last fault pushed, cleared by the next sample.
    fault: Option<ImuFaultKind>,
    attitude: Attitude,
    last_sample_ms: Option<u32>,
    free_fall_since_ms: Option<u32>,
    integral_rad: [f32; 2],
    correction_rad: [f32; 2],
    /// The roll and pitch the held pose or the sway commands (the leveling's set point).
    intended_rad: [f32; 2],
    active: bool,
    limited: bool,
    fall: Option<FallKind>,
    samples: u32,
    /// The body's roll and pitch rates of the last sample, the gyro bias removed, rad/s.
    rate_rad_s: [f32; 2],
    /// The set point of the frame before the last.
    intended_before_rad: [f32; 2],
    /// Frames the set point has stayed the same, up to [`RATE_HELD_FRAMES`].
    held_frames: u8,
}

fn clamp_abs(x: f32, m: f32) -> f32 {
    if x > m {
        m
    } else if x < -m {
        -m
    } else {
        x
    }
}

impl<M: Math> Balance<M> {
    /// No reading yet; the power-on settings ([`BalanceConfig::DEFAULT`]).
    pub const fn new() -> Self {
        Balance {
            config: BalanceConfig::DEFAULT,
            estimator: Estimator::new(Gains::DEFAULT),
            phase: Phase::Absent,
            fault: None,
            attitude: Attitude {
                roll_rad: 0.0,
                pitch_rad: 0.0,
            },
            last_sample_ms: None,
            free_fall_since_ms: None,
            integral_rad: [0.0; 2],
            correction_rad: [0.0; 2],
            intended_rad: [0.0; 2],
            active: false,
            limited: false,
            fall: None,
            samples: 0,
            rate_rad_s: [0.0; 2],
            intended_before_rad: [0.0; 2],
            held_frames: 0,
        }
    }

    /// The settings in effect.
    pub fn config(&self) -> &BalanceConfig {
        &self.config
    }

    /// The sensor's health.
    pub fn health(&self) -> ImuHealth {
        match (self.fault, self.phase) {
            (Some(kind), _) => ImuHealth::Fault(kind),
            (None, Phase::Absent) => ImuHealth::Absent,
            (None, Phase::Starting { .. }) => ImuHealth::Starting,
            (None, Phase::Running) => ImuHealth::Ok,
        }
    }

    /// The estimated attitude while the health is ok (`None` otherwise).
    pub fn attitude(&self) -> Option<Attitude> {
        (self.health() == ImuHealth::Ok).then_some(self.attitude)
    }

    /// The fall latched, if any.
    pub fn fall(&self) -> Option<FallKind> {
        self.fall
    }

    /// Clears the fall latch (an explicit motion request).
    pub fn clear_fall(&mut self) {
        self.fall = None;
    }

    /// Applies `config` (its numbers range-checked by the protocol's check already).
    ///
    /// # Errors
    /// [`NackReason::ImuAbsent`] or [`NackReason::ImuFault`] when leveling is asked without a
    /// working sensor; nothing changes then.
    pub fn configure(&mut self, config: BalanceConfig) -> Result<(), NackReason> {
        if config.leveling {
            match self.health() {
                ImuHealth::Absent => return Err(NackReason::ImuAbsent),
                ImuHealth::Fault(kind) => return Err(NackReason::ImuFault(kind)),
                _ => {}
            }
        }
        if !config.leveling || config != self.config {
            self.integral_rad = [0.0; 2];
        }
        self.config = config;
        Ok(())
    }

    /// Takes one reading at `now_ms`; `outputs_on` tells whether fall detection acts.
    pub fn push(&mut self, reading: ImuReading, now_ms: u32, outputs_on: bool) -> Event {
        let sample = match reading {
            ImuReading::Sample(s) => s,
            ImuReading::Fault(f) => return self.fault(f),
        };
        self.samples = self.samples.wrapping_add(1);
        self.fault = None;
        let dt_s = match self.last_sample_ms {
            Some(t) => (now_ms.wrapping_sub(t) as f32 * 0.001).clamp(DT_MIN_S, DT_MAX_S),
            None => DT_MIN_S,
        };
        self.last_sample_ms = Some(now_ms);
        match self.phase {
            Phase::Absent => self.restart(now_ms, &sample),
            Phase::Starting { since_ms, .. } => {
                if !still(&sample) {
                    self.restart(now_ms, &sample);
                } else if let Phase::Starting {
                    n,
                    gyro_sum,
                    accel_sum,
                    ..
                } = &mut self.phase
                {
                    *n = n.saturating_add(1);
                    for i in 0..3 {
                        gyro_sum[i] += sample.gyro_rad_s[i];
                        accel_sum[i] += sample.accel_m_s2[i];
                    }
                    let n = *n;
                    if now_ms.wrapping_sub(since_ms) >= BIAS_WINDOW_MS && n >= BIAS_MIN_SAMPLES {
                        let k = 1.0 / f32::from(n);
                        let (g, a) = (gyro_sum.map(|x| x * k), accel_sum.map(|x| x * k));
                        self.estimator.reset(a, g);
                        self.attitude = self.estimator.attitude();
                        self.phase = Phase::Running;
                    }
                }
            }
            Phase::Running => {
                self.estimator
                    .update(sample.gyro_rad_s, sample.accel_m_s2, dt_s);
                self.attitude = self.estimator.attitude();
                let b = self.estimator.bias_rad_s();
                self.rate_rad_s = [sample.gyro_rad_s[0] - b[0], sample.gyro_rad_s[1] - b[1]];
            }
        }
        if !outputs_on || !self.config.fall_detection || self.fall.is_some() {
            self.free_fall_since_ms = None;
            return Event::None;
        }
        let a = sample.accel_m_s2;
        let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        let limit = FREE_FALL_SHARE * G_M_S2;
        // A non-finite reading is no fall (and no free fall's start).
        if a2 < limit * limit {
            let since = *self.free_fall_since_ms.get_or_insert(now_ms);
            if now_ms.wrapping_sub(since) >= FREE_FALL_MS {
                return self.fell(FallKind::FreeFall);
            }
        } else {
            self.free_fall_since_ms = None;
        }
        if self.phase == Phase::Running {
            let m = self.config.fall_angle_rad;
            if self.attitude.roll_rad.abs() > m || self.attitude.pitch_rad.abs() > m {
                return self.fell(FallKind::Tilt);
            }
        }
        Event::None
    }

    fn fell(&mut self, kind: FallKind) -> Event {
        self.fall = Some(kind);
        self.free_fall_since_ms = None;
        self.stop_leveling();
        Event::Fall(kind)
    }

    fn restart(&mut self, now_ms: u32, sample: &ImuSample) {
        let still = still(sample);
        self.phase = Phase::Starting {
            since_ms: now_ms,
            n: u16::from(still),
            gyro_sum: if still { sample.gyro_rad_s } else { [0.0; 3] },
            accel_sum: if still { sample.accel_m_s2 } else { [0.0; 3] },
        };
    }

    fn fault(&mut self, f: ImuFault) -> Event {
        let kind = match f {
            ImuFault::Absent => {
                self.phase = Phase::Absent;
                self.fault = None;
                self.config.leveling = false;
                self.stop_leveling();
                return Event::None;
            }
            ImuFault::WrongId { .. } => ImuFaultKind::WrongId,
            ImuFault::Nak => ImuFaultKind::Nak,
            ImuFault::Stuck => ImuFaultKind::Stuck,
            ImuFault::BusHeld => ImuFaultKind::BusHeld,
        };
        let was_healthy = self.fault.is_none() && self.phase != Phase::Absent;
        self.fault = Some(kind);
        self.free_fall_since_ms = None;
        if !was_healthy {
            return Event::None;
        }
        self.config.leveling = false;
        self.stop_leveling();
        Event::Fault
    }

    fn stop_leveling(&mut self) {
        self.held_frames = 0;
        self.integral_rad = [0.0; 2];
        self.correction_rad = [0.0; 2];
        self.active = false;
        self.limited = false;
    }

    /// True when leveling is to run now: switched on, the sensor ok, no fall latched.
    pub fn leveling_ready(&self) -> bool {
        self.config.leveling && self.health() == ImuHealth::Ok && self.fall.is_none()
    }

    /// One servo frame of the leveling PI (module docs) over `dt_s`: the correction to apply
    /// now, from the attitude against the set point of the last frame; `None` (and the
    /// integral reset) when leveling is not to run.
    pub fn level(&mut self, dt_s: f32) -> Option<[f32; 2]> {
        if !self.leveling_ready() {
            self.stop_leveling();
            return None;
        }
        let BalanceConfig {
            level_kp,
            level_ki_per_s,
            max_correction_rad: m,
            ..
        } = self.config;
        let measured = [self.attitude.roll_rad, self.attitude.pitch_rad];
        if self.intended_rad != self.intended_before_rad {
            self.held_frames = 0;
        } else if self.held_frames < RATE_HELD_FRAMES {
            self.held_frames += 1;
        }
        self.intended_before_rad = self.intended_rad;
        let rate_gain = if self.held_frames >= RATE_HELD_FRAMES {
            RATE_GAIN_S
        } else {
            0.0
        };
        let mut c = [0.0; 2];
        for i in 0..2 {
            let e = measured[i] - self.intended_rad[i];
            self.integral_rad[i] = clamp_abs(self.integral_rad[i] + level_ki_per_s * e * dt_s, m);
            let rate = beyond(self.rate_rad_s[i], RATE_DEAD_BAND_RAD_S);
            c[i] = clamp_abs(-(level_kp * e + self.integral_rad[i] + rate_gain * rate), m);
        }
        Some(c)
    }

    /// Records what a frame applied: the set point (the roll and pitch the pose or the motion
    /// commands), the correction applied and whether it was limited; `None` when no correction
    /// was taken this frame (leveling not active).
    pub fn applied(&mut self, applied: Option<([f32; 2], [f32; 2], bool)>, asked: [f32; 2]) {
        match applied {
            Some((intended, correction, reach_limited)) => {
                self.intended_rad = intended;
                self.correction_rad = correction;
                let m = self.config.max_correction_rad;
                let bounded = self.integral_rad.iter().any(|x| x.abs() >= m)
                    || asked.iter().any(|x| x.abs() >= m);
                self.limited = reach_limited || bounded;
                self.active = true;
            }
            None => {
                self.held_frames = 0;
                self.correction_rad = [0.0; 2];
                self.integral_rad = [0.0; 2];
                self.active = false;
                self.limited = false;
            }
        }
    }

    /// The correction in effect (roll, pitch), rad.
    pub fn correction_rad(&self) -> [f32; 2] {
        self.correction_rad
    }

    /// The start check: `Ok` when a motion may start — no sensor reading (nothing to check),
    /// a fault (the motion runs open loop), or the body within
    /// [`START_TILT_MAX_RAD`] (or the fall angle, if lower) of upright; during the bias
    /// measurement the accelerometer's own direction is checked.
    ///
    /// # Errors
    /// [`crate::engine::Error::NotUpright`].
    pub fn start_check(&self, last: Option<&ImuSample>) -> Result<(), crate::engine::Error> {
        let limit = if self.config.fall_angle_rad < START_TILT_MAX_RAD {
            self.config.fall_angle_rad
        } else {
            START_TILT_MAX_RAD
        };
        let attitude = match (self.health(), last) {
            (ImuHealth::Ok, _) => self.attitude,
            (ImuHealth::Starting, Some(s)) => {
                let mut e = Estimator::<M>::new(Gains::DEFAULT);
                e.reset(s.accel_m_s2, [0.0; 3]);
                e.attitude()
            }
            _ => return Ok(()),
        };
        if attitude.roll_rad.abs() > limit || attitude.pitch_rad.abs() > limit {
            Err(crate::engine::Error::NotUpright)
        } else {
            Ok(())
        }
    }

    /// The report of [`quad_protocol::DeviceToHost::Imu`].
    pub fn report(&self) -> ImuReport {
        let a = self.attitude().unwrap_or_default();
        ImuReport {
            health: self.health(),
            roll_rad: a.roll_rad,
            pitch_rad: a.pitch_rad,
            correction_roll_rad: self.correction_rad[0],
            correction_pitch_rad: self.correction_rad[1],
            leveling_active: self.active,
            correction_limited: self.limited,
            fall: self.fall,
            samples: self.samples,
            config: self.config,
        }
    }
}

impl<M: Math> Default for Balance<M> {
    fn default() -> Self {
        Self::new()
    }
}

/// `x` beyond a dead band of `±band`: 0 within it, `x ∓ band` outside.
fn beyond(x: f32, band: f32) -> f32 {
    if x > band {
        x - band
    } else if x < -band {
        x + band
    } else {
        0.0
    }
}

/// A sample of a robot at rest (module docs, start-up).
fn still(s: &ImuSample) -> bool {
    let a = s.accel_m_s2;
    let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    let (lo, hi) = (
        (1.0 - STILL_ACCEL_SHARE) * G_M_S2,
        (1.0 + STILL_ACCEL_SHARE) * G_M_S2,
    );
    a2 >= lo * lo && a2 <= hi * hi && s.gyro_rad_s.iter().all(|w| w.abs() <= STILL_RATE_RAD_S)
}
