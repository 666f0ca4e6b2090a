//! Sources of inertial readings for simulators: the in-process simulated device pushes what a
//! source reads into [`Device::on_imu`](crate::Device::on_imu); the emulator's virtual
//! MPU-6050 (quad-host) encodes it into its registers at the scales the firmware configured;
//! the physics twin feeds its own through [`Feed`]. One trait, so that every target sees the
//! same sensor.
//!
//! ## The trait
//! [`ImuSource::read`]`(t_s)` gives the reading at simulated time `t_s` (seconds since the
//! target's power-on; callers pass non-decreasing times): an [`ImuReading::Sample`] in the
//! body frame, SI units, or an [`ImuReading::Fault`] meaning what the sensor does instead —
//!
//! | fault | the virtual MPU-6050 | the in-process device |
//! |---|---|---|
//! | `Absent` | no ACK to its address | the fault pushed |
//! | `Nak` | no ACK to its address | the fault pushed |
//! | `Stuck` | its data registers keep their values | the fault pushed |
//! | `BusHeld` | no ACK, and SDA held low | the fault pushed |
//! | `WrongId { who_am_i }` | `WHO_AM_I` reads `who_am_i` | the fault pushed |
//!
//! ## Sources
//! - [`LevelStill`]: `(0, 0, +g)` and no rotation.
//! - [`Scripted`]: a CSV script of attitude and body rates over time, interpolated linearly;
//!   the accelerometer sees gravity only (the script has no linear acceleration).
//! - [`Feed`]: a closure (the twin's physics).
//! - Wrappers: [`Noisy`] (seeded Gaussian noise), [`Biased`] (constant offsets), [`Faulty`]
//!   (faults over time windows).

use crate::imu::mpu6050::STANDARD_GRAVITY_M_S2;
use crate::imu::{ImuFault, ImuReading, ImuSample};
use alloc::boxed::Box;
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;
use seeded_rng::SplitMix64;

/// Something that gives inertial readings over simulated time (module docs).
pub trait ImuSource {
    /// The reading at `t_s` seconds since power-on (non-decreasing between calls).
    fn read(&mut self, t_s: f64) -> ImuReading;
}

impl<S: ImuSource + ?Sized> ImuSource for Box<S> {
    fn read(&mut self, t_s: f64) -> ImuReading {
        (**self).read(t_s)
    }
}

impl<S: ImuSource + ?Sized> ImuSource for &mut S {
    fn read(&mut self, t_s: f64) -> ImuReading {
        (**self).read(t_s)
    }
}

/// Level and still: the accelerometer reads `(0, 0, +g)`, the gyro nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LevelStill;

/// The sample of a body at rest at `roll_rad`, `pitch_rad` (rotation order zyx: yaw, then
/// pitch about the new y, then roll about the new x; yaw does not change what the sensor
/// sees) turning at `rate_rad_s` about the body axes: the specific force is the reaction to
/// gravity in the body frame, `g · (−sin θ, sin φ cos θ, cos φ cos θ)`.
pub fn at_attitude(roll_rad: f64, pitch_rad: f64, rate_rad_s: [f64; 3]) -> ImuSample {
    let g = f64::from(STANDARD_GRAVITY_M_S2);
    let (sr, cr) = (libm::sin(roll_rad), libm::cos(roll_rad));
    let (sp, cp) = (libm::sin(pitch_rad), libm::cos(pitch_rad));
    let a = [-g * sp, g * sr * cp, g * cr * cp];
    ImuSample {
        accel_m_s2: a.map(|v| v as f32),
        gyro_rad_s: rate_rad_s.map(|v| v as f32),
    }
}

impl ImuSource for LevelStill {
    fn read(&mut self, _t_s: f64) -> ImuReading {
        ImuReading::Sample(at_attitude(0.0, 0.0, [0.0; 3]))
    }
}

/// The closure `f(t_s)` as a source (the twin's physics, a test's script).
pub struct Feed<F>(pub F);

impl<F: FnMut(f64) -> ImuReading> ImuSource for Feed<F> {
    fn read(&mut self, t_s: f64) -> ImuReading {
        (self.0)(t_s)
    }
}

impl<F> fmt::Debug for Feed<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Feed(..)")
    }
}

/// One row of a [`Scripted`] source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Time, s.
    pub t_s: f64,
    /// Roll, pitch, yaw, rad (rotation order zyx).
    pub attitude_rad: [f64; 3],
    /// Angular rate about the body axes x, y, z, rad/s (what the gyro reads).
    pub rate_rad_s: [f64; 3],
}

/// What is wrong with a script's row.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CsvProblem {
    /// Not the seven columns `t_s,roll_rad,pitch_rad,yaw_rad,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s`.
    Columns {
        /// Columns found.
        found: usize,
    },
    /// A field that is not a finite number.
    NotANumber {
        /// The column (1-based).
        column: usize,
        /// The field as written.
        field: String,
    },
    /// A time not after the previous row's.
    TimeNotIncreasing,
    /// No data rows at all.
    Empty,
}

/// A script that cannot be used, naming the file and the line (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CsvError {
    /// The file's name as given.
    pub file: String,
    /// The line (1-based; the last line for [`CsvProblem::Empty`]).
    pub line: usize,
    /// What is wrong.
    pub problem: CsvProblem,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: ", self.file, self.line)?;
        match &self.problem {
            CsvProblem::Columns { found } => write!(
                f,
                "{found} columns; a row is t_s,roll_rad,pitch_rad,yaw_rad,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s"
            ),
            CsvProblem::NotANumber { column, field } => {
                write!(f, "column {column}: {field:?} is not a finite number")
            }
            CsvProblem::TimeNotIncreasing => f.write_str("time not after the previous row's"),
            CsvProblem::Empty => f.write_str("no data rows"),
        }
    }
}

impl core::error::Error for CsvError {}

/// The header a script may start with (any first line that is not all numbers is taken as a
/// header; lines starting with `#` and blank lines are skipped).
pub const CSV_HEADER: &str =
    "t_s,roll_rad,pitch_rad,yaw_rad,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s";

/// Attitude and body rates over time from a CSV script, interpolated linearly between rows
/// and held before the first and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct Scripted {
    rows: Vec<Row>,
}

impl Scripted {
    /// Parses `text` (the contents of `file`, named in errors); see [`CSV_HEADER`].
    ///
    /// # Errors
    /// The first bad row, with its file and line.
    pub fn parse(file: &str, text: &str) -> Result<Scripted, CsvError> {
        let err = |line: usize, problem| CsvError {
            file: String::from(file),
            line,
            problem,
        };
        let mut rows: Vec<Row> = Vec::new();
        let mut seen_first = false;
        let mut last_line = 0;
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            last_line = line;
            let trimmed = raw.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = trimmed.split(',').map(str::trim).collect();
            let first = !seen_first;
            seen_first = true;
            if first && fields.iter().any(|f| f.parse::<f64>().is_err()) {
                continue;
            }
            if fields.len() != 7 {
                return Err(err(
                    line,
                    CsvProblem::Columns {
                        found: fields.len(),
                    },
                ));
            }
            let mut v = [0.0f64; 7];
            for (k, f) in fields.iter().enumerate() {
                match f.parse::<f64>() {
                    Ok(x) if x.is_finite() => v[k] = x,
                    _ => {
                        return Err(err(
                            line,
                            CsvProblem::NotANumber {
                                column: k + 1,
                                field: String::from(*f),
                            },
                        ))
                    }
                }
            }
            if rows.last().is_some_and(|r| v[0] <= r.t_s) {
                return Err(err(line, CsvProblem::TimeNotIncreasing));
            }
            rows.push(Row {
                t_s: v[0],
                attitude_rad: [v[1], v[2], v[3]],
                rate_rad_s: [v[4], v[5], v[6]],
            });
        }
        if rows.is_empty() {
            return Err(err(last_line.max(1), CsvProblem::Empty));
        }
        Ok(Scripted { rows })
    }

    /// The script's rows.
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    /// The row interpolated at `t_s`.
    pub fn at(&self, t_s: f64) -> Row {
        let rows = &self.rows;
        let k = rows.partition_point(|r| r.t_s <= t_s);
        if k == 0 {
            return rows[0];
        }
        if k == rows.len() {
            return rows[k - 1];
        }
        let (a, b) = (rows[k - 1], rows[k]);
        let u = (t_s - a.t_s) / (b.t_s - a.t_s);
        let mix = |x: [f64; 3], y: [f64; 3]| core::array::from_fn(|i| x[i] + u * (y[i] - x[i]));
        Row {
            t_s,
            attitude_rad: mix(a.attitude_rad, b.attitude_rad),
            rate_rad_s: mix(a.rate_rad_s, b.rate_rad_s),
        }
    }
}

impl ImuSource for Scripted {
    fn read(&mut self, t_s: f64) -> ImuReading {
        let r = self.at(t_s);
        ImuReading::Sample(at_attitude(
            r.attitude_rad[0],
            r.attitude_rad[1],
            r.rate_rad_s,
        ))
    }
}

/// Adds seeded Gaussian noise to every sample of `inner` (faults pass unchanged): the same
/// seed gives the same noise on every platform.
#[derive(Clone, Debug)]
pub struct Noisy<S> {
    /// The source.
    pub inner: S,
    /// Standard deviation per accelerometer axis, m/s².
    pub accel_sd_m_s2: f32,
    /// Standard deviation per gyro axis, rad/s.
    pub gyro_sd_rad_s: f32,
    rng: SplitMix64,
}

/// About the MPU-6050's own noise in the configured 44 Hz band: 400 µg/√Hz → 0.026 m/s² per
/// accelerometer axis (product specification §6.2).
pub const MPU6050_ACCEL_SD_M_S2: f32 = 0.026;

/// About the MPU-6050's gyro noise in the 42 Hz band: 0.005 °/s/√Hz → 0.000 57 rad/s.
pub const MPU6050_GYRO_SD_RAD_S: f32 = 0.000_57;

impl<S> Noisy<S> {
    /// `inner` with noise of the given standard deviations, drawn from `seed`.
    pub fn new(inner: S, accel_sd_m_s2: f32, gyro_sd_rad_s: f32, seed: u64) -> Noisy<S> {
        Noisy {
            inner,
            accel_sd_m_s2,
            gyro_sd_rad_s,
            rng: SplitMix64::new(seed),
        }
    }

    /// `inner` with the MPU-6050's datasheet noise ([`MPU6050_ACCEL_SD_M_S2`],
    /// [`MPU6050_GYRO_SD_RAD_S`]).
    pub fn mpu6050(inner: S, seed: u64) -> Noisy<S> {
        Noisy::new(inner, MPU6050_ACCEL_SD_M_S2, MPU6050_GYRO_SD_RAD_S, seed)
    }

    /// One standard normal draw (Box–Muller).
    fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.rng.unit();
        let u2 = self.rng.unit();
        libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(2.0 * core::f64::consts::PI * u2)
    }
}

impl<S: ImuSource> ImuSource for Noisy<S> {
    fn read(&mut self, t_s: f64) -> ImuReading {
        match self.inner.read(t_s) {
            ImuReading::Sample(mut s) => {
                for i in 0..3 {
                    s.accel_m_s2[i] += self.accel_sd_m_s2 * self.normal() as f32;
                    s.gyro_rad_s[i] += self.gyro_sd_rad_s * self.normal() as f32;
                }
                ImuReading::Sample(s)
            }
            fault => fault,
        }
    }
}

/// Adds constant offsets to every sample of `inner` (a sensor's zero-rate and zero-g offsets).
#[derive(Clone, Debug, PartialEq)]
pub struct Biased<S> {
    /// The source.
    pub inner: S,
    /// Accelerometer offset, m/s², body frame.
    pub accel_m_s2: [f32; 3],
    /// Gyro offset, rad/s, body frame.
    pub gyro_rad_s: [f32; 3],
}

impl<S: ImuSource> ImuSource for Biased<S> {
    fn read(&mut self, t_s: f64) -> ImuReading {
        match self.inner.read(t_s) {
            ImuReading::Sample(mut s) => {
                for i in 0..3 {
                    s.accel_m_s2[i] += self.accel_m_s2[i];
                    s.gyro_rad_s[i] += self.gyro_rad_s[i];
                }
                ImuReading::Sample(s)
            }
            fault => fault,
        }
    }
}

/// A fault over a span of time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultWindow {
    /// From, s (inclusive).
    pub from_s: f64,
    /// Until, s (exclusive; `None`: for good).
    pub until_s: Option<f64>,
    /// The fault.
    pub fault: ImuFault,
}

impl FaultWindow {
    fn covers(&self, t_s: f64) -> bool {
        t_s >= self.from_s && self.until_s.is_none_or(|u| t_s < u)
    }
}

/// `inner`, but the first of `windows` that covers the time replaces its reading by its
/// fault (injected faults: a NAK from a time, stuck values, an absent sensor, a held bus).
#[derive(Clone, Debug, PartialEq)]
pub struct Faulty<S> {
    /// The source.
    pub inner: S,
    /// The faults, by time.
    pub windows: Vec<FaultWindow>,
}

impl<S: ImuSource> ImuSource for Faulty<S> {
    fn read(&mut self, t_s: f64) -> ImuReading {
        // The inner source is read in any case: its time (and a noise sequence) runs on.
        let reading = self.inner.read(t_s);
        match self.windows.iter().find(|w| w.covers(t_s)) {
            Some(w) => ImuReading::Fault(w.fault),
            None => reading,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(r: ImuReading) -> ImuSample {
        match r {
            ImuReading::Sample(s) => s,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn level_still_reads_plus_g_on_z() {
        let s = sample(LevelStill.read(3.0));
        assert_eq!(s.accel_m_s2, [0.0, 0.0, STANDARD_GRAVITY_M_S2]);
        assert_eq!(s.gyro_rad_s, [0.0; 3]);
    }

    #[test]
    fn a_positive_roll_puts_gravity_on_plus_y_and_a_nose_down_pitch_on_minus_x() {
        let g = STANDARD_GRAVITY_M_S2;
        let r = at_attitude(0.3, 0.0, [0.0; 3]);
        assert!((r.accel_m_s2[1] - g * libm::sinf(0.3)).abs() < 1e-5);
        let p = at_attitude(0.0, 0.3, [0.0; 3]);
        assert!((p.accel_m_s2[0] + g * libm::sinf(0.3)).abs() < 1e-5);
    }

    #[test]
    fn a_script_interpolates_and_holds_its_ends() {
        let text = "# a roll ramp\nt_s,roll_rad,pitch_rad,yaw_rad,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s\n\
                    0,0,0,0,0.2,0,0\n1.0,0.2,0,0,0.2,0,0\n";
        let s = Scripted::parse("ramp.csv", text).unwrap();
        assert_eq!(s.rows().len(), 2);
        assert!((s.at(0.5).attitude_rad[0] - 0.1).abs() < 1e-12);
        assert_eq!(s.at(-1.0).attitude_rad[0], 0.0);
        assert_eq!(s.at(9.0).attitude_rad[0], 0.2);
    }

    #[test]
    fn a_bad_row_names_the_file_and_the_line() {
        let text = "t_s,roll_rad,pitch_rad,yaw_rad,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s\n\
                    0,0,0,0,0,0,0\n\n0.5,0,zero,0,0,0,0\n";
        let e = Scripted::parse("tilt.csv", text).unwrap_err();
        assert_eq!(e.file, "tilt.csv");
        assert_eq!(e.line, 4);
        assert!(matches!(
            e.problem,
            CsvProblem::NotANumber { column: 3, .. }
        ));
        assert!(alloc::format!("{e}").starts_with("tilt.csv:4: column 3"));
        let e = Scripted::parse("short.csv", "0,0,0,0,0,0,0\n1,0,0\n").unwrap_err();
        assert_eq!((e.line, e.problem), (2, CsvProblem::Columns { found: 3 }));
        let e = Scripted::parse("back.csv", "0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n").unwrap_err();
        assert_eq!((e.line, e.problem), (2, CsvProblem::TimeNotIncreasing));
        let e = Scripted::parse("empty.csv", "# nothing\n").unwrap_err();
        assert_eq!(e.problem, CsvProblem::Empty);
    }

    #[test]
    fn noise_is_seeded_and_faults_cover_their_window() {
        let mut a = Noisy::mpu6050(LevelStill, 5);
        let mut b = Noisy::mpu6050(LevelStill, 5);
        let (x, y) = (sample(a.read(0.0)), sample(b.read(0.0)));
        assert_eq!(x, y);
        assert_ne!(x, sample(LevelStill.read(0.0)));
        let mut biased = Biased {
            inner: LevelStill,
            accel_m_s2: [0.1, 0.0, 0.0],
            gyro_rad_s: [0.0, 0.0, 0.01],
        };
        let s = sample(biased.read(0.0));
        assert_eq!((s.accel_m_s2[0], s.gyro_rad_s[2]), (0.1, 0.01));
        let mut f = Faulty {
            inner: LevelStill,
            windows: alloc::vec![FaultWindow {
                from_s: 1.0,
                until_s: Some(2.0),
                fault: ImuFault::Nak,
            }],
        };
        assert!(matches!(f.read(0.5), ImuReading::Sample(_)));
        assert_eq!(f.read(1.0), ImuReading::Fault(ImuFault::Nak));
        assert!(matches!(f.read(2.0), ImuReading::Sample(_)));
        let mut feed = Feed(|t: f64| ImuReading::Sample(at_attitude(t, 0.0, [0.0; 3])));
        assert!(sample(feed.read(0.1)).accel_m_s2[1] > 0.0);
    }
}
