//! How long the device takes to answer each kind of request, and how long a host should wait.
//!
//! An answer time runs from the request's first byte on the line to the answer's last byte: it
//! holds both frames' time on the wire and the device's work in between (a body pose's IK, a
//! motion's preflight, an EEPROM write). [`Kind::worst_us`] is the longest the ATmega2560
//! firmware takes at each supported line rate, measured on the emulated chip over cases that
//! include each kind's slowest (the test `avr_answer_times`, which fails when a measurement
//! exceeds its bound or falls far below it, so that the table stays tight). A host waits
//! [`Kind::timeout`] before it resends: the worst time with half again as margin, plus
//! [`HOST_LATENCY`] for the host's side of the line.
//!
//! `docs/protocol.md` ("Answer times") prints this table; a test checks that the two agree.

use crate::msg::{MotionCommand, Request};
use core::time::Duration;

/// The line rates the firmware is built for, bit/s: [`Kind::worst_us`]'s columns.
pub const BAUDS: [u32; 2] = [115_200, 1_000_000];

/// Added to every suggested timeout for the host's side of the line: a USB serial adapter
/// delivers bytes in USB frames (1 ms on the Mega's own USB bridge, up to 16 ms on adapters
/// whose latency timer is at its default), and a host scheduler can add a few ms more.
pub const HOST_LATENCY: Duration = Duration::from_millis(20);

/// Added to every suggested timeout for a motion frame in progress: a request that arrives
/// while the device computes a servo frame of a running motion waits for it, and the frame
/// budget bounds that at half of the 20 ms frame (BENCHMARKS.md, onboard motions). The
/// measured worst times include some such waits, not necessarily the longest.
pub const FRAME_ALLOWANCE: Duration = Duration::from_millis(10);

/// A row of the answer-time table: a request kind, with `StartMotion` split by motion (their
/// preflights differ by an order of magnitude).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[allow(missing_docs)] // The names are the requests' (and the motions').
pub enum Kind {
    Hello,
    GetState,
    SetBodyPose,
    SetFeet,
    SetJoints,
    SetOutputs,
    SetLinkTimeout,
    SetCalibration,
    GetCalibration,
    SaveCalibration,
    SetPoseConfig,
    StartStandUp,
    StartSit,
    StartRest,
    StartSway,
    StartYawTurn,
    StartFootPath,
    StartWalk,
    StartStableTurn,
    StopMotion,
    GetMotion,
    SetVelocity,
    SetJointSpeedLimit,
    SetBalance,
    GetImu,
    SetRobot,
    GetRobot,
    SaveRobot,
}

impl Kind {
    /// Every row, in the order of the table.
    pub const ALL: [Kind; 28] = [
        Kind::Hello,
        Kind::GetState,
        Kind::SetBodyPose,
        Kind::SetFeet,
        Kind::SetJoints,
        Kind::SetOutputs,
        Kind::SetLinkTimeout,
        Kind::SetCalibration,
        Kind::GetCalibration,
        Kind::SaveCalibration,
        Kind::SetPoseConfig,
        Kind::StartStandUp,
        Kind::StartSit,
        Kind::StartRest,
        Kind::StartSway,
        Kind::StartYawTurn,
        Kind::StartFootPath,
        Kind::StartWalk,
        Kind::StartStableTurn,
        Kind::StopMotion,
        Kind::GetMotion,
        Kind::SetVelocity,
        Kind::SetJointSpeedLimit,
        Kind::SetBalance,
        Kind::GetImu,
        Kind::SetRobot,
        Kind::GetRobot,
        Kind::SaveRobot,
    ];

    /// The row of `request`.
    pub const fn of(request: &Request) -> Kind {
        match request {
            Request::Hello { .. } => Kind::Hello,
            Request::GetState => Kind::GetState,
            Request::SetBodyPose(_) => Kind::SetBodyPose,
            Request::SetFeet { .. } => Kind::SetFeet,
            Request::SetJoints { .. } => Kind::SetJoints,
            Request::SetOutputs { .. } => Kind::SetOutputs,
            Request::SetLinkTimeout(_) => Kind::SetLinkTimeout,
            Request::SetCalibration { .. } => Kind::SetCalibration,
            Request::GetCalibration { .. } => Kind::GetCalibration,
            Request::SaveCalibration => Kind::SaveCalibration,
            Request::SetPoseConfig(_) => Kind::SetPoseConfig,
            Request::StartMotion(m) => match m {
                MotionCommand::StandUp => Kind::StartStandUp,
                MotionCommand::Sit => Kind::StartSit,
                MotionCommand::Rest => Kind::StartRest,
                MotionCommand::Sway { .. } => Kind::StartSway,
                MotionCommand::YawTurn { .. } => Kind::StartYawTurn,
                MotionCommand::FootPath { .. } => Kind::StartFootPath,
                MotionCommand::Walk { .. } => Kind::StartWalk,
                MotionCommand::StableTurn { .. } => Kind::StartStableTurn,
            },
            Request::StopMotion => Kind::StopMotion,
            Request::GetMotion => Kind::GetMotion,
            Request::SetVelocity { .. } => Kind::SetVelocity,
            Request::SetJointSpeedLimit { .. } => Kind::SetJointSpeedLimit,
            Request::SetBalance(_) => Kind::SetBalance,
            Request::GetImu => Kind::GetImu,
            Request::SetRobot(_) => Kind::SetRobot,
            Request::GetRobot => Kind::GetRobot,
            Request::SaveRobot => Kind::SaveRobot,
        }
    }

    /// The row's name as `docs/protocol.md` prints it.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::Hello => "Hello",
            Kind::GetState => "GetState",
            Kind::SetBodyPose => "SetBodyPose",
            Kind::SetFeet => "SetFeet",
            Kind::SetJoints => "SetJoints",
            Kind::SetOutputs => "SetOutputs",
            Kind::SetLinkTimeout => "SetLinkTimeout",
            Kind::SetCalibration => "SetCalibration",
            Kind::GetCalibration => "GetCalibration",
            Kind::SaveCalibration => "SaveCalibration",
            Kind::SetPoseConfig => "SetPoseConfig",
            Kind::StartStandUp => "StartMotion StandUp",
            Kind::StartSit => "StartMotion Sit",
            Kind::StartRest => "StartMotion Rest",
            Kind::StartSway => "StartMotion Sway",
            Kind::StartYawTurn => "StartMotion YawTurn",
            Kind::StartFootPath => "StartMotion FootPath",
            Kind::StartWalk => "StartMotion Walk",
            Kind::StartStableTurn => "StartMotion StableTurn",
            Kind::StopMotion => "StopMotion",
            Kind::GetMotion => "GetMotion",
            Kind::SetVelocity => "SetVelocity",
            Kind::SetJointSpeedLimit => "SetJointSpeedLimit",
            Kind::SetBalance => "SetBalance",
            Kind::GetImu => "GetImu",
            Kind::SetRobot => "SetRobot",
            Kind::GetRobot => "GetRobot",
            Kind::SaveRobot => "SaveRobot",
        }
    }

    /// The longest answer time of this kind at each of [`BAUDS`], µs: the firmware's measured
    /// worst when the table was made, rounded up to the next 0.1 ms. The firmware may drift
    /// from it by a little (test `avr_answer_times`: at most 15 % + 1 ms above, 30 % + 2 ms
    /// below), and a request that meets a motion frame in progress waits up to
    /// [`FRAME_ALLOWANCE`] more; [`Kind::timeout`]'s margin covers both.
    pub const fn worst_us(self) -> [u32; 2] {
        match self {
            Kind::Hello => [9_800, 7_600],
            Kind::GetState => [7_600, 1_400],
            Kind::SetBodyPose => [13_600, 4_700],
            Kind::SetFeet => [16_000, 5_000],
            Kind::SetJoints => [13_900, 3_000],
            Kind::SetOutputs => [9_500, 2_300],
            Kind::SetLinkTimeout => [8_100, 1_500],
            Kind::SetCalibration => [12_800, 2_700],
            Kind::GetCalibration => [3_500, 800],
            Kind::SaveCalibration => [659_800, 652_600],
            Kind::SetPoseConfig => [8_900, 1_600],
            Kind::StartStandUp => [13_900, 5_700],
            Kind::StartSit => [11_600, 2_900],
            Kind::StartRest => [11_600, 2_900],
            Kind::StartSway => [40_500, 31_300],
            Kind::StartYawTurn => [44_500, 34_800],
            Kind::StartFootPath => [46_000, 35_800],
            Kind::StartWalk => [67_500, 57_600],
            Kind::StartStableTurn => [47_200, 37_400],
            Kind::StopMotion => [13_300, 2_100],
            Kind::GetMotion => [16_900, 6_900],
            Kind::SetVelocity => [25_900, 17_100],
            Kind::SetJointSpeedLimit => [9_200, 1_700],
            Kind::SetBalance => [9_200, 2_200],
            Kind::GetImu => [5_500, 1_100],
            Kind::SetRobot => [22_500, 9_100],
            Kind::GetRobot => [8_900, 1_500],
            Kind::SaveRobot => [297_900, 291_500],
        }
    }

    /// How long a host waits for this kind's answer at `baud` before it resends: the worst
    /// time at the nearest of [`BAUDS`] at or below `baud` (the slower line for a rate between
    /// them, 115,200's for a slower one, scaled up), times 1.5, plus [`FRAME_ALLOWANCE`] and
    /// [`HOST_LATENCY`], rounded up to whole milliseconds.
    pub fn timeout(self, baud: u32) -> Duration {
        self.timeout_with(baud, HOST_LATENCY)
    }

    /// [`Kind::timeout`] with `host_latency` in place of [`HOST_LATENCY`] (a line without a USB
    /// bridge, e.g. the emulated chip's).
    pub fn timeout_with(self, baud: u32, host_latency: Duration) -> Duration {
        let [slow_us, fast_us] = self.worst_us();
        let worst_us = if baud >= BAUDS[1] {
            u64::from(fast_us)
        } else if baud >= BAUDS[0] {
            u64::from(slow_us)
        } else {
            // Slower than the slowest row: the whole answer time scaled by the rate, an
            // overestimate (the device's own work does not slow down).
            u64::from(slow_us) * u64::from(BAUDS[0]) / u64::from(baud.max(1))
        };
        let us =
            worst_us * 3 / 2 + FRAME_ALLOWANCE.as_micros() as u64 + host_latency.as_micros() as u64;
        Duration::from_millis(us.div_ceil(1000))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_names_itself_once_and_maps_back() {
        for (i, k) in Kind::ALL.iter().enumerate() {
            assert!(Kind::ALL[..i].iter().all(|o| o.name() != k.name()));
        }
        assert_eq!(Kind::of(&Request::GetMotion), Kind::GetMotion);
        assert_eq!(
            Kind::of(&Request::StartMotion(MotionCommand::Sit)),
            Kind::StartSit
        );
    }

    #[test]
    fn the_timeout_covers_the_worst_with_margin_at_every_rate() {
        for k in Kind::ALL {
            let [slow, fast] = k.worst_us();
            for (baud, worst) in [(115_200, slow), (1_000_000, fast), (2_000_000, fast)] {
                let t = k.timeout(baud);
                let least = Duration::from_micros(u64::from(worst) * 3 / 2)
                    + FRAME_ALLOWANCE
                    + HOST_LATENCY;
                assert!(t >= least);
                assert!(t < least + Duration::from_millis(1));
            }
            assert!(k.timeout(57_600) >= k.timeout(115_200));
        }
    }
}
