//! The inertial sensor and the balance functions on the wire (since 2.3): what
//! [`Request::SetBalance`](crate::Request::SetBalance) configures and what
//! [`DeviceToHost::Imu`](crate::DeviceToHost::Imu) reports.
//!
//! Every type of 2.3 is here, so that the additions of the version stay in one place: the
//! configuration [`BalanceConfig`] (leveling on/off and its PI gains, the correction's bound,
//! fall detection and its angle, the safe state, the action on a sensor fault) and the report
//! [`ImuReport`] (the sensor's health, the attitude, the leveling correction, the latched fall,
//! the configuration as applied).

use crate::wire::wire_enum;
use serde::{Deserialize, Serialize};

wire_enum! {
    /// Where the outputs go when a fall is detected.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum SafeState {
        /// The motion stops and the held target becomes the rest pose (the legs folded under
        /// the body), approached through the joint-speed limiter; the outputs stay driven.
        0 => Rest,
        /// The motion stops and the outputs are switched off at once (no pulse: the servos go
        /// limp).
        1 => Off,
    }
}

wire_enum! {
    /// What a running motion does when the sensor fails mid-run (leveling is switched off in
    /// either case).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum FaultAction {
        /// The motion continues open loop.
        0 => OpenLoop,
        /// The motion stops cleanly (as `StopMotion`: at the end of its period, then a ramp to
        /// the stance).
        1 => Stop,
    }
}

wire_enum! {
    /// Why the sensor gives no reading.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum ImuFaultKind {
        /// Something answers at the sensor's address, but its identity register is not the
        /// expected one.
        0 => WrongId,
        /// The sensor stopped acknowledging.
        1 => Nak,
        /// The sensor answers with the same data for longer than its noise allows.
        2 => Stuck,
        /// The bus is held (SDA low, or a transfer that never completes).
        3 => BusHeld,
    }
}

wire_enum! {
    /// The sensor as the device sees it.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum ImuHealth {
        /// No sensor: nothing answered at boot, or no reading has arrived since the boot.
        0 => Absent,
        /// Readings arrive; the gyro bias is being measured (the robot must stay still).
        1 => Starting,
        /// Readings arrive and the attitude is estimated.
        2 => Ok,
        /// The last reading failed: why.
        3 => Fault(ImuFaultKind),
    }
}

wire_enum! {
    /// Why a fall was detected.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum FallKind {
        /// |roll| or |pitch| beyond the configured fall angle.
        0 => Tilt,
        /// The specific force far below `g` for a while: the robot falls or is dropped.
        1 => FreeFall,
    }
}

/// The balance functions' settings ([`Request::SetBalance`](crate::Request::SetBalance)); the
/// ranges of its numbers are in [`crate::range`] (`LEVEL_KP`, `LEVEL_KI_PER_S`,
/// `MAX_CORRECTION_RAD`, `FALL_ANGLE_RAD`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BalanceConfig {
    /// Level the body: correct its roll and pitch from the measured attitude while a stance
    /// is held or a sway runs.
    pub leveling: bool,
    /// The leveling's proportional gain, rad of correction per rad of tilt.
    pub level_kp: f32,
    /// The leveling's integral gain, rad of correction per rad of tilt and second, 1/s.
    pub level_ki_per_s: f32,
    /// The largest correction of roll and of pitch, rad.
    pub max_correction_rad: f32,
    /// Detect falls (a tilt beyond `fall_angle_rad`, or free fall).
    pub fall_detection: bool,
    /// |roll| or |pitch| beyond which the robot has fallen, rad.
    pub fall_angle_rad: f32,
    /// Where the outputs go on a fall.
    pub safe_state: SafeState,
    /// What a running motion does on a sensor fault.
    pub on_fault: FaultAction,
}

impl BalanceConfig {
    /// The settings at power-on: leveling off (`level_kp` 0.3, `level_ki_per_s` 4 1/s,
    /// `max_correction_rad` 0.26 ≈ 15° when switched on), fall detection on at 60° with the
    /// rest pose as the safe state, a motion continuing open loop on a sensor fault.
    pub const DEFAULT: BalanceConfig = BalanceConfig {
        leveling: false,
        level_kp: 0.3,
        level_ki_per_s: 4.0,
        max_correction_rad: 0.26,
        fall_detection: true,
        fall_angle_rad: core::f32::consts::FRAC_PI_3,
        safe_state: SafeState::Rest,
        on_fault: FaultAction::OpenLoop,
    };
}

impl Default for BalanceConfig {
    fn default() -> Self {
        BalanceConfig::DEFAULT
    }
}

/// The sensor, the attitude and the balance functions as the device reports them
/// ([`DeviceToHost::Imu`](crate::DeviceToHost::Imu)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImuReport {
    /// The sensor's health.
    pub health: ImuHealth,
    /// The estimated roll of the body, rad (zyx order; 0 while the health is not `Ok`).
    pub roll_rad: f32,
    /// The estimated pitch of the body, rad (zyx order; 0 while the health is not `Ok`).
    pub pitch_rad: f32,
    /// The leveling's correction of the body's roll in effect, rad (0 when not leveling).
    pub correction_roll_rad: f32,
    /// The leveling's correction of the body's pitch in effect, rad.
    pub correction_pitch_rad: f32,
    /// The correction is being applied now (leveling on, the sensor ok, a stance held or a
    /// sway running).
    pub leveling_active: bool,
    /// The correction was bounded since the last report: by `max_correction_rad`, or by the
    /// robot's reach (the largest reachable share of it was applied).
    pub correction_limited: bool,
    /// The fall detected, latched until an explicit motion request (`None`: none).
    pub fall: Option<FallKind>,
    /// Samples taken since the boot (wrapping).
    #[serde(with = "crate::wire::shared")]
    pub samples: u32,
    /// The settings as applied.
    pub config: BalanceConfig,
}

/// Largest [`ImuReport`] in postcard bytes: health (≤ 2) + four f32 (16) + two bools (2) + fall
/// (≤ 2) + samples (≤ 5) + [`BalanceConfig`] (2 bools, 4 f32, 2 enums: 20).
pub const IMU_REPORT_MAX_LEN: usize = 2 + 16 + 2 + 2 + 5 + 20;
