//! The twin's IMU readings on their way to the device.
//!
//! The twin samples MuJoCo's accelerometer and gyroscope on the body's `imu` site every
//! [`IMU_PERIOD_S`] of simulated time (four samples a 20 ms servo frame) and answers each frame
//! with that frame's samples, each with its time and the body's true attitude
//! ([`crate::link::ImuSampleAt`]). They reach the device by two routes:
//!
//! - **In-process** ([`crate::source::HostDriven`], [`crate::source::Onboard`]): before the
//!   device's next frame boundary, its virtual clock is advanced to each sample's time within
//!   the frame the twin has just simulated and the sample pushed through
//!   [`quad_device::Device::on_imu`] ([`crate::device::InProcess::tick_with_imu`]).
//! - **Emulated firmware** ([`crate::emulated::Emulated`]): the samples go into a [`TwinImu`],
//!   timed on the emulated MCU's clock, for the emulated MPU-6050 to read as the MCU runs:
//!   [`TwinImu::read`] is the callback a sensor source calls with the MCU's time (see
//!   [`TwinImu`]).
//!
//! Readings are in the body frame of kin-core (x forward, y left, z up), SI units: level and
//! still the accelerometer reads `(0, 0, +g)`, and a roll that lowers the right side reads a
//! positive rate about +x.

use quad_device::{ImuReading, ImuSample};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

/// The twin's IMU sample period, s (200 Hz: four samples in each 20 ms servo frame; the
/// MPU-6050 is read at ≥ 100 Hz on the board).
pub const IMU_PERIOD_S: f32 = 0.005;

/// Standard gravity, m/s²: MuJoCo's default gravity, which the twin's models keep.
pub const GRAVITY_M_S2: f32 = 9.81;

/// Samples a [`TwinImu`] keeps when nothing reads them (5 s at [`IMU_PERIOD_S`]); the oldest
/// goes first.
pub const TWIN_IMU_CAPACITY: usize = 1024;

#[derive(Debug)]
struct Queue {
    /// Samples in time order, `(t_s, sample)`.
    samples: VecDeque<(f64, ImuSample)>,
    /// What the sensor reads before the first sample.
    at_rest: ImuSample,
    /// Samples dropped because the queue was full.
    dropped: u64,
    /// Samples replaced by an earlier one pushed later.
    replaced: u64,
    /// The latest time a [`TwinImu::sample_at`] asked for: samples up to it have been read.
    read_up_to_s: f64,
}

/// The twin's IMU samples as a sensor source reads them: a queue of samples timed on the
/// reader's clock (for the emulated firmware: the MCU's time since its reset, its cycle
/// count over its clock frequency), filled frame by frame as the physics advances.
/// [`TwinImu::read`] answers with the latest sample at or before the time asked; before the
/// first sample, with the robot at rest on the run's floor (the accelerometer reading
/// gravity's reaction, [`crate::scenario::Scenario::at_rest_accel_m_s2`]; the gyroscope zero).
///
/// Clones share one queue (as [`quad_device::sim::VirtualClock`]'s clones share one time): the
/// frame source pushes into one clone, the emulated sensor reads another (the emulator's
/// sensor sources are `Send`: the queue is behind a mutex). The emulator's sensor source
/// reads it without consuming it ([`TwinImu::sample_at`]; `Feed(move |t_s|
/// feed.sample_at(t_s))`); reading is
/// infallible (the twin's sensor has no bus faults of its own: faults are the emulated
/// chip's).
///
/// Reads must come in time order (an MCU's clock only advances): a read drops the samples
/// before the one it answers with. A sample pushed earlier than queued ones replaces them
/// ([`TwinImu::push`]): where two frames overlap on the reader's clock, the later physics
/// wins.
#[derive(Debug, Clone)]
pub struct TwinImu(Arc<Mutex<Queue>>);

/// A sample's time is not a finite number ([`TwinImu::push`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotFinite {
    /// The time given, s.
    pub t_s: f64,
}

impl core::fmt::Display for NotFinite {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "an IMU sample's time {} is not finite", self.t_s)
    }
}

impl std::error::Error for NotFinite {}

impl TwinImu {
    /// An empty feed that reads `at_rest` until the first sample.
    pub fn new(at_rest: ImuSample) -> TwinImu {
        TwinImu(Arc::new(Mutex::new(Queue {
            samples: VecDeque::new(),
            at_rest,
            dropped: 0,
            replaced: 0,
            read_up_to_s: f64::NEG_INFINITY,
        })))
    }

    /// The queue, locked (a panic while it was held left it consistent: every change is a
    /// single push or pop).
    fn queue(&self) -> MutexGuard<'_, Queue> {
        self.0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Appends `sample`, taken at `t_s` on the reader's clock; queued samples at or after
    /// `t_s` are replaced by it (they came from physics that a later frame has overtaken).
    ///
    /// # Errors
    /// [`NotFinite`] when `t_s` is not a finite number.
    pub fn push(&self, t_s: f64, sample: ImuSample) -> Result<(), NotFinite> {
        if !t_s.is_finite() {
            return Err(NotFinite { t_s });
        }
        let mut q = self.queue();
        while q.samples.back().is_some_and(|&(last_s, _)| last_s >= t_s) {
            q.samples.pop_back();
            q.replaced += 1;
        }
        if q.samples.len() == TWIN_IMU_CAPACITY {
            if let Some((oldest_s, _)) = q.samples.pop_front() {
                // Unread unless a later read passed it.
                if oldest_s > q.read_up_to_s {
                    q.dropped += 1;
                }
            }
        }
        q.samples.push_back((t_s, sample));
        Ok(())
    }

    /// What the sensor reads at `t_s`: the latest sample at or before `t_s`; before the first
    /// sample, the robot at rest. Drops the samples before the one it answers with.
    pub fn read(&self, t_s: f64) -> ImuReading {
        let mut q = self.queue();
        // Keep the latest sample at or before t_s at the front.
        while q.samples.len() > 1 && q.samples[1].0 <= t_s {
            q.samples.pop_front();
        }
        let sample = match q.samples.front() {
            Some(&(t0, sample)) if t0 <= t_s => sample,
            _ => q.at_rest,
        };
        ImuReading::Sample(sample)
    }

    /// What the sensor reads at `t_s`, as [`TwinImu::read`], but keeping the queue: the
    /// emulated MPU-6050's source (`Feed(move |t_s| feed.sample_at(t_s))`), so that the
    /// queue's count stays what the twin pushed (the oldest go only when it is full, and
    /// count as [`TwinImu::dropped`] only when no read had passed them).
    pub fn sample_at(&self, t_s: f64) -> ImuReading {
        let mut q = self.queue();
        if t_s > q.read_up_to_s {
            q.read_up_to_s = t_s;
        }
        // Samples at or before t_s form a prefix (the queue is in time order).
        let n = q.samples.partition_point(|&(t, _)| t <= t_s);
        let sample = match n {
            0 => q.at_rest,
            _ => q.samples[n - 1].1,
        };
        ImuReading::Sample(sample)
    }

    /// Samples waiting (the one a read last answered with included).
    pub fn len(&self) -> usize {
        self.queue().samples.len()
    }

    /// True when no sample waits.
    pub fn is_empty(&self) -> bool {
        self.queue().samples.is_empty()
    }

    /// Samples dropped unread because the queue was full ([`TWIN_IMU_CAPACITY`]).
    pub fn dropped(&self) -> u64 {
        self.queue().dropped
    }

    /// Samples replaced by an earlier one pushed after them (overlapping frames).
    pub fn replaced(&self) -> u64 {
        self.queue().replaced
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(x: f32) -> ImuSample {
        ImuSample {
            accel_m_s2: [x, 0.0, GRAVITY_M_S2],
            gyro_rad_s: [0.0; 3],
        }
    }

    #[test]
    fn a_read_answers_the_latest_sample_at_or_before_its_time() {
        let feed = TwinImu::new(sample(-1.0));
        let reader = feed.clone();
        assert_eq!(reader.read(0.0), ImuReading::Sample(sample(-1.0)));
        for (i, t) in [0.004, 0.009, 0.014, 0.019].into_iter().enumerate() {
            feed.push(t, sample(i as f32)).unwrap();
        }
        assert_eq!(reader.read(0.003), ImuReading::Sample(sample(-1.0)));
        assert_eq!(reader.read(0.004), ImuReading::Sample(sample(0.0)));
        assert_eq!(reader.read(0.0135), ImuReading::Sample(sample(1.0)));
        assert_eq!(reader.len(), 3);
        assert_eq!(reader.read(1.0), ImuReading::Sample(sample(3.0)));
        assert_eq!(reader.len(), 1);
        // The last sample stays until a later one replaces it.
        assert_eq!(reader.read(2.0), ImuReading::Sample(sample(3.0)));
    }

    #[test]
    fn sample_at_keeps_the_queue_and_a_full_queue_drops_read_samples_uncounted() {
        let feed = TwinImu::new(sample(-1.0));
        for i in 0..TWIN_IMU_CAPACITY {
            feed.push(i as f64, sample(i as f32)).unwrap();
        }
        assert_eq!(feed.sample_at(-0.5), ImuReading::Sample(sample(-1.0)));
        assert_eq!(feed.sample_at(2.5), ImuReading::Sample(sample(2.0)));
        assert_eq!(feed.len(), TWIN_IMU_CAPACITY);
        // The oldest, read, goes uncounted; then an unread one goes counted.
        for i in 0..4 {
            feed.push((TWIN_IMU_CAPACITY + i) as f64, sample(0.0))
                .unwrap();
        }
        assert_eq!(feed.dropped(), 1);
    }

    #[test]
    fn an_earlier_sample_replaces_later_ones_and_a_full_queue_drops_the_oldest() {
        let feed = TwinImu::new(sample(0.0));
        feed.push(0.4, sample(0.4)).unwrap();
        feed.push(1.0, sample(1.0)).unwrap();
        feed.push(1.1, sample(1.1)).unwrap();
        feed.push(0.5, sample(2.0)).unwrap();
        assert_eq!(feed.len(), 2);
        assert_eq!(feed.replaced(), 2);
        assert_eq!(feed.read(1.05), ImuReading::Sample(sample(2.0)));
        assert!(feed.push(f64::NAN, sample(2.0)).is_err());
        assert!(feed.push(f64::INFINITY, sample(2.0)).is_err());
        for i in 0..TWIN_IMU_CAPACITY {
            feed.push(2.0 + i as f64, sample(0.0)).unwrap();
        }
        assert_eq!(feed.len(), TWIN_IMU_CAPACITY);
        assert_eq!(feed.dropped(), 1);
    }
}
