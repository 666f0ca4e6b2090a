//! The inertial sensor and the balance functions on the panel (protocol 2.3): the device's
//! `Imu` report as the pages get it ([`ImuState`]), how often the server reads it
//! ([`IMU_PERIOD`]), and the balance switch's request ([`request`]).
//!
//! The page draws an artificial horizon from the report's roll and pitch, the sensor's health
//! (absent, starting, ok, or the fault with its kind), the leveling (off, on and waiting, or on
//! with its correction) and a latched fall. The switch turns the device's **leveling** on or off
//! (`SetBalance`, the other settings as the device last reported them, as `quadctl balance
//! --leveling on|off` does); a device without a working sensor refuses it with a typed nack,
//! which comes back in words.

use quad_host::ops::onboard;
use quad_protocol::{
    BalanceConfig, FallKind, ImuFaultKind, ImuHealth, ImuReport, NackReason, Ranges, Request,
    SafeState,
};
use serde::Serialize;
use std::time::Duration;

/// How often the server reads the device's `Imu` report (`GetImu`), whatever else it does.
///
/// 10 Hz: a `GetImu` takes 4.9 ms of a 115,200 baud line there and back (the simulated line,
/// `tests/session.rs`; a `GetMotion` takes 7.8 ms), so the reads hold the line about 5 % of
/// the time and a pose or motion request waits at most one of them. The state read
/// (`--poll-ms`, 20 Hz by default) pauses while the page sends (each command's answer carries
/// the state); the sensor read does not, so the horizon keeps moving during a stream of poses.
/// Ten frames a second moves a horizon smoothly to the eye, and a fall the device latches
/// shows on the page within about 0.1 s.
pub const IMU_PERIOD: Duration = Duration::from_millis(100);

/// The device's inertial sensor and balance functions, from its last `Imu` report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImuState {
    /// The sensor's health: `absent` (nothing on the bus, or no reading since the boot),
    /// `starting` (the gyro bias is being measured: the robot must stay still), `ok` or
    /// `fault`.
    pub health: &'static str,
    /// With `fault`: its kind, `wrong_id`, `nak`, `stuck` or `bus_held`; else `None`.
    pub fault_kind: Option<&'static str>,
    /// The estimated roll of the body, rad (0 while the health is not `ok`).
    pub roll_rad: f32,
    /// The estimated pitch of the body, rad (0 while the health is not `ok`).
    pub pitch_rad: f32,
    /// Leveling is switched on (the setting).
    pub leveling: bool,
    /// The leveling correction is being applied now (on, the sensor ok, a stance held or a
    /// sway running).
    pub leveling_active: bool,
    /// The leveling's correction of the body's roll in effect, rad.
    pub correction_roll_rad: f32,
    /// The leveling's correction of the body's pitch in effect, rad.
    pub correction_pitch_rad: f32,
    /// The correction was bounded (its limit, or the robot's reach) since the last report.
    pub correction_limited: bool,
    /// The fall latched: `tilt` or `free_fall`; `None`: none. Cleared by an explicit motion
    /// request (a started motion, a body pose, the outputs switched on).
    pub fall: Option<&'static str>,
    /// Fall detection is switched on.
    pub fall_detection: bool,
    /// |roll| or |pitch| beyond which the device detects a fall, rad.
    pub fall_angle_rad: f32,
    /// Where the outputs go on a fall: `rest` or `off`.
    pub safe_state: &'static str,
    /// Sensor samples since the device's boot (wrapping).
    pub samples: u32,
}

/// The name of a health, and of its fault's kind.
pub fn health_name(h: ImuHealth) -> (&'static str, Option<&'static str>) {
    match h {
        ImuHealth::Absent => ("absent", None),
        ImuHealth::Starting => ("starting", None),
        ImuHealth::Ok => ("ok", None),
        ImuHealth::Fault(kind) => (
            "fault",
            Some(match kind {
                ImuFaultKind::WrongId => "wrong_id",
                ImuFaultKind::Nak => "nak",
                ImuFaultKind::Stuck => "stuck",
                ImuFaultKind::BusHeld => "bus_held",
            }),
        ),
    }
}

impl From<&ImuReport> for ImuState {
    fn from(r: &ImuReport) -> ImuState {
        let (health, fault_kind) = health_name(r.health);
        ImuState {
            health,
            fault_kind,
            roll_rad: r.roll_rad,
            pitch_rad: r.pitch_rad,
            leveling: r.config.leveling,
            leveling_active: r.leveling_active,
            correction_roll_rad: r.correction_roll_rad,
            correction_pitch_rad: r.correction_pitch_rad,
            correction_limited: r.correction_limited,
            fall: r.fall.map(|f| match f {
                FallKind::Tilt => "tilt",
                FallKind::FreeFall => "free_fall",
            }),
            fall_detection: r.config.fall_detection,
            fall_angle_rad: r.config.fall_angle_rad,
            safe_state: match r.config.safe_state {
                SafeState::Rest => "rest",
                SafeState::Off => "off",
            },
            samples: r.samples,
        }
    }
}

/// The `SetBalance` that switches leveling on or off, the other settings kept as `current`
/// (the device's last report), range checked for the robot of `ranges`.
///
/// # Errors
/// The protocol's range check's refusal (a current setting the host finds out of range, which
/// a device of the same protocol does not report): nothing to send.
pub fn request(
    current: &BalanceConfig,
    leveling: bool,
    ranges: &Ranges,
) -> Result<Request, NackReason> {
    let request = Request::SetBalance(BalanceConfig {
        leveling,
        ..*current
    });
    quad_protocol::check_request_in(&request, ranges)?;
    Ok(request)
}

/// A refused `SetBalance` in the page's words: the reason, and what to do about it.
pub fn words(reason: &NackReason) -> String {
    match reason {
        NackReason::ImuAbsent => "no sensor: the device has no inertial sensor (nothing answers \
             on its bus), so leveling stays off"
            .to_owned(),
        NackReason::ImuFault(kind) => format!(
            "sensor fault ({}): leveling stays off until the sensor reads again",
            health_name(ImuHealth::Fault(*kind)).1.unwrap_or("fault")
        ),
        other => onboard::words_in(other, &crate::motion::PANEL),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kin_core::Robot;

    fn report(health: ImuHealth) -> ImuReport {
        ImuReport {
            health,
            roll_rad: 0.1,
            pitch_rad: -0.05,
            correction_roll_rad: -0.02,
            correction_pitch_rad: 0.01,
            leveling_active: true,
            correction_limited: false,
            fall: Some(FallKind::Tilt),
            samples: 42,
            config: BalanceConfig {
                leveling: true,
                ..BalanceConfig::DEFAULT
            },
        }
    }

    #[test]
    fn the_report_reaches_the_page_by_name() {
        let s = ImuState::from(&report(ImuHealth::Fault(ImuFaultKind::BusHeld)));
        let v = serde_json::to_value(s).unwrap();
        assert_eq!(v["health"], "fault");
        assert_eq!(v["fault_kind"], "bus_held");
        assert_eq!(v["fall"], "tilt");
        assert_eq!(v["safe_state"], "rest");
        assert_eq!(v["leveling"], true);
        assert_eq!(v["samples"], 42);
        assert!((v["roll_rad"].as_f64().unwrap() - 0.1).abs() < 1e-6);
        for (h, name) in [
            (ImuHealth::Absent, "absent"),
            (ImuHealth::Starting, "starting"),
            (ImuHealth::Ok, "ok"),
        ] {
            let v = serde_json::to_value(ImuState::from(&report(h))).unwrap();
            assert_eq!(v["health"], name);
            assert_eq!(v["fault_kind"], serde_json::Value::Null);
        }
        let free = ImuState::from(&ImuReport {
            fall: Some(FallKind::FreeFall),
            ..report(ImuHealth::Ok)
        });
        assert_eq!(free.fall, Some("free_fall"));
        assert_eq!(
            ImuState::from(&ImuReport {
                fall: None,
                ..report(ImuHealth::Ok)
            })
            .fall,
            None
        );
    }

    #[test]
    fn the_switch_keeps_the_other_settings() {
        let ranges = Ranges::of(&Robot::shahriar2023());
        let current = BalanceConfig {
            fall_angle_rad: 0.9,
            safe_state: SafeState::Off,
            ..BalanceConfig::DEFAULT
        };
        assert_eq!(
            request(&current, true, &ranges).unwrap(),
            Request::SetBalance(BalanceConfig {
                leveling: true,
                ..current
            })
        );
        // A setting out of its range is not sent.
        let bad = BalanceConfig {
            level_kp: 5.0,
            ..current
        };
        assert!(matches!(
            request(&bad, true, &ranges),
            Err(NackReason::InvalidParameter { .. })
        ));
    }

    #[test]
    fn a_refusal_says_why() {
        assert!(words(&NackReason::ImuAbsent).starts_with("no sensor"));
        assert!(words(&NackReason::ImuFault(ImuFaultKind::Nak)).contains("sensor fault (nak)"));
    }
}
