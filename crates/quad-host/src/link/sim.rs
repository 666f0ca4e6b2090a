//! A simulated UART with the `quad-device` controller on its far end, in-process, on a virtual
//! clock.
//!
//! ## Timing model
//! Time is virtual (nanoseconds); nothing sleeps. Each direction is a line that carries one
//! byte per `10 / baud` s (8N1; [`super::byte_time`], truncated to whole ns: 86,805 ns at
//! 115200 baud, 10,000 ns at 1 Mbaud). A byte arrives when its last bit has been sent.
//!
//! - **Host → device**: [`Link::send`] queues a frame on the line at the host's current time;
//!   it does not advance the host's clock (a write to a driver buffer).
//! - **Device**: the received bytes go into a receive FIFO of [`SimConfig::rx_fifo_len`] bytes
//!   (the firmware's USART interrupt ring; a byte arriving when it is full is lost) and are fed
//!   to [`Device::receive`] one at a time, in order. Feeding a byte that does not end a frame
//!   takes no time. A frame's answer is ready [`SimConfig::compute`] after its last byte was
//!   taken (**modelled**, not measured: a fixed time per answered frame, 0 by default, so that
//!   the rates are wire-limited; set it from the firmware's measured IK time to model the
//!   ATmega2560). The device has one transmit buffer: an answer starts on the line when the
//!   previous one has left it, and the device takes no further byte from its FIFO until its
//!   answer has started.
//! - **Device → host**: [`Link::recv`] advances the host's clock to the arrival of the next byte
//!   (or to the timeout) and returns the bytes up to the end of that frame, each no earlier
//!   than it arrived.
//! - [`Device::poll`] (the link-loss failsafe, the servo frames of the motion engine) runs
//!   before every byte and whenever the host's clock advances, at every millisecond boundary
//!   in between. The device's millisecond clock is the virtual clock.
//! - **Inertial sensor** ([`SimLink::attach_imu`]): the device gets the source's reading every
//!   [`READ_PERIOD_MS`] ms of virtual time, at the millisecond boundary, before that
//!   millisecond's poll, as the firmware's driver reads its MPU-6050 (the same sources as the
//!   emulator's virtual sensor, `quad_device::sim::imu`; a fault reading is pushed as the
//!   fault). A new link's sensor is level and still (`LevelStill`): its health reads ok once
//!   the start-up second has passed.
//!
//! ## Faults
//! [`Faults`] apply to both directions, drawn from one seeded generator (the same seed, the
//! same run): per frame a stall (the line idles `stall_ms` first), a cut (the frame ends after a
//! random number of bytes) and a duplication (the frame is sent twice); then per byte a drop
//! (its line time passes, nothing arrives) and a bit flip.

use super::{byte_time, Error, Faults, LineStats, Link};
use crate::emu::SharedImuSource;
use kin_core::DefaultMath;
use quad_device::imu::mpu6050::READ_PERIOD_MS;
use quad_device::sim::imu::LevelStill;
use quad_device::sim::{EepromError, Outputs, RamEeprom, VirtualClock, EEPROM_LEN};
use quad_device::{Config, ConfigError, Device, Storage};
use std::collections::VecDeque;
use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

/// Default receive FIFO of the simulated device, bytes.
pub const DEFAULT_RX_FIFO_LEN: usize = 64;

use seeded_rng::SplitMix64;

/// Why the simulated EEPROM failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum ImageError {
    /// The in-memory EEPROM refused the access (out of range).
    RamEeprom(EepromError),
    /// The image file could not be written.
    File(std::io::Error),
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImageError::RamEeprom(e) => write!(f, "{e}"),
            ImageError::File(e) => write!(f, "EEPROM image file: {e}"),
        }
    }
}

impl std::error::Error for ImageError {}

/// The simulated device's EEPROM: the shared in-memory [`RamEeprom`], erased or loaded from an
/// image file that every write updates, so that a calibration saved in one run is there in the
/// next.
#[derive(Debug, Clone)]
pub struct EepromImage {
    eeprom: RamEeprom,
    file: Option<PathBuf>,
}

impl EepromImage {
    /// An erased EEPROM, in memory only.
    pub fn erased() -> EepromImage {
        EepromImage {
            eeprom: RamEeprom::erased(),
            file: None,
        }
    }

    /// An EEPROM backed by an image file: read when it exists (shorter files are padded with
    /// 0xFF), written on every change.
    ///
    /// # Errors
    /// When the file exists but cannot be read.
    pub fn with_file(path: PathBuf) -> std::io::Result<EepromImage> {
        let mut bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(e),
        };
        bytes.resize(EEPROM_LEN, 0xFF);
        Ok(EepromImage {
            eeprom: RamEeprom::with_bytes(bytes),
            file: Some(path),
        })
    }

    /// The EEPROM's bytes.
    pub fn eeprom(&self) -> &RamEeprom {
        &self.eeprom
    }
}

impl Storage for EepromImage {
    type Error = ImageError;

    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), ImageError> {
        self.eeprom.read(addr, buf).map_err(ImageError::RamEeprom)
    }

    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), ImageError> {
        self.eeprom
            .write(addr, data)
            .map_err(ImageError::RamEeprom)?;
        if let Some(path) = &self.file {
            std::fs::write(path, &self.eeprom.bytes).map_err(ImageError::File)?;
        }
        Ok(())
    }
}

/// The device as simulated: host math backend, the shared in-memory outputs and clock, the
/// EEPROM image.
type Simulated = Device<Outputs, VirtualClock, EepromImage, DefaultMath>;

/// Line and device parameters of a [`SimLink`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Line rate, bit/s.
    pub baud: u32,
    /// Fault injection.
    pub faults: Faults,
    /// Seed of the fault generator.
    pub seed: u64,
    /// Modelled device time per answered frame (see the module docs).
    pub compute: Duration,
    /// Receive FIFO of the device, bytes.
    pub rx_fifo_len: usize,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            baud: 115_200,
            faults: Faults::NONE,
            seed: 1,
            compute: Duration::ZERO,
            rx_fifo_len: DEFAULT_RX_FIFO_LEN,
        }
    }
}

#[derive(Debug, Default)]
struct Line {
    /// Bytes on their way, with their arrival time (ns).
    queue: VecDeque<(u64, u8)>,
    /// When the line is next free, ns.
    free_ns: u64,
}

/// Puts one frame on `line` from `start_ns`, applying the faults.
fn transmit(
    line: &mut Line,
    rng: &mut SplitMix64,
    faults: &Faults,
    stats: &mut LineStats,
    byte_ns: u64,
    mut start_ns: u64,
    frame: &[u8],
) -> u64 {
    let plan = faults.plan_frame(rng, frame, stats);
    if plan.stall {
        start_ns += (faults.stall_ms * 1e6) as u64;
    }
    let mut t = start_ns.max(line.free_ns);
    for _ in 0..plan.copies {
        for &b in plan.bytes {
            t += byte_ns;
            if let Some(b) = faults.pass_byte(rng, b, stats) {
                line.queue.push_back((t, b));
            }
        }
    }
    line.free_ns = t;
    t
}

/// The simulated UART link (see the module docs).
pub struct SimLink {
    config: SimConfig,
    device_config: Config,
    byte_ns: u64,
    rng: SplitMix64,
    now_ns: u64,
    h2d: Line,
    d2h: Line,
    /// The device takes no byte before this time (its answer waits for the transmit buffer).
    dev_free_ns: u64,
    /// Times at which the bytes in the device's receive FIFO are taken, oldest first.
    fifo: VecDeque<u64>,
    clock: VirtualClock,
    device: Simulated,
    stats: LineStats,
    /// The inertial sensor's source, when attached.
    imu: Option<SharedImuSource>,
}

impl SimLink {
    /// A line to a freshly powered-on device built with `device_config` on `storage`, at
    /// time 0.
    ///
    /// # Errors
    /// The device's configuration error.
    pub fn new(
        config: SimConfig,
        device_config: Config,
        storage: EepromImage,
    ) -> Result<SimLink, ConfigError> {
        let clock = VirtualClock::default();
        let device = Device::new(device_config, Outputs::default(), clock.clone(), storage)?;
        Ok(SimLink {
            config,
            device_config,
            byte_ns: byte_time(config.baud).as_nanos() as u64,
            rng: SplitMix64::new(config.seed),
            now_ns: 0,
            h2d: Line::default(),
            d2h: Line::default(),
            dev_free_ns: 0,
            fifo: VecDeque::new(),
            clock,
            device,
            stats: LineStats::default(),
            imu: Some(SharedImuSource::new(LevelStill)),
        })
    }

    /// Gives the device an inertial sensor fed by `source` (see the module docs); replaces an
    /// earlier one. It stays attached across [`SimLink::reset_device`].
    pub fn attach_imu(&mut self, source: SharedImuSource) {
        self.imu = Some(source);
    }

    /// The simulated device, for inspection.
    pub fn device(&self) -> &Device<Outputs, VirtualClock, EepromImage, DefaultMath> {
        &self.device
    }

    /// Resets the device (a power cycle or a watchdog reset): it powers on again from its
    /// storage, with the outputs off and no handshake; bytes in its receive FIFO are lost.
    ///
    /// # Errors
    /// The device's configuration error (not for a configuration it already accepted).
    pub fn reset_device(&mut self) -> Result<(), ConfigError> {
        let placeholder = Device::new(
            self.device_config,
            Outputs::default(),
            VirtualClock::default(),
            EepromImage::erased(),
        )?;
        let old = std::mem::replace(&mut self.device, placeholder);
        let (_, clock, storage) = old.into_parts();
        self.device = Device::new(self.device_config, Outputs::default(), clock, storage)?;
        self.fifo.clear();
        Ok(())
    }

    /// What the lines did so far.
    pub fn stats(&self) -> LineStats {
        self.stats
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Runs the device on every byte it takes up to time `t_ns`.
    fn run_device_until(&mut self, t_ns: u64) {
        let compute_ns = self.config.compute.as_nanos() as u64;
        while let Some(&(t_arr, byte)) = self.h2d.queue.front() {
            let t_take = t_arr.max(self.dev_free_ns);
            if t_take > t_ns {
                break;
            }
            self.h2d.queue.pop_front();
            while self.fifo.front().is_some_and(|&t| t <= t_arr) {
                self.fifo.pop_front();
            }
            if self.fifo.len() >= self.config.rx_fifo_len {
                self.stats.rx_overflow += 1;
                continue;
            }
            self.fifo.push_back(t_take);
            self.poll_at(t_take);
            // One byte ends at most one frame: every piece sent is of the same answer.
            let mut answer = Vec::new();
            self.device
                .receive(&[byte], |piece| answer.extend_from_slice(piece));
            if !answer.is_empty() {
                let start = (t_take + compute_ns).max(self.d2h.free_ns);
                self.dev_free_ns = start;
                self.stats.d2h_bytes += answer.len() as u64;
                transmit(
                    &mut self.d2h,
                    &mut self.rng,
                    &self.config.faults,
                    &mut self.stats,
                    self.byte_ns,
                    start,
                    &answer,
                );
            }
        }
        if t_ns >= self.dev_free_ns {
            self.poll_at(t_ns);
        }
    }

    /// Runs the device's main loop up to `t_ns`: a poll at every millisecond boundary since its
    /// clock's time, then one at `t_ns`, so that its servo frames and its failsafe see the
    /// time pass as the firmware's loop does, however long the host waits at once.
    fn poll_at(&mut self, t_ns: u64) {
        const MS_NS: u64 = 1_000_000;
        let mut t = (self.clock.now_ns() / MS_NS + 1) * MS_NS;
        while t < t_ns {
            self.clock.set_ns(t);
            if let Some(imu) = &self.imu {
                if (t / MS_NS).is_multiple_of(u64::from(READ_PERIOD_MS)) {
                    self.device.on_imu(imu.read(t as f64 * 1e-9));
                }
            }
            self.device.poll();
            t += MS_NS;
        }
        self.set_device_time(t_ns);
        self.device.poll();
    }

    fn set_device_time(&mut self, t_ns: u64) {
        if t_ns > self.clock.now_ns() {
            self.clock.set_ns(t_ns);
        }
    }

    /// The next time something happens: the device takes a byte or a byte reaches the host.
    fn next_event(&self) -> Option<u64> {
        let take = self
            .h2d
            .queue
            .front()
            .map(|&(t, _)| t.max(self.dev_free_ns));
        let arrive = self.d2h.queue.front().map(|&(t, _)| t);
        match (take, arrive) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

impl Link for SimLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.stats.h2d_bytes += bytes.len() as u64;
        transmit(
            &mut self.h2d,
            &mut self.rng,
            &self.config.faults,
            &mut self.stats,
            self.byte_ns,
            self.now_ns,
            bytes,
        );
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
        let deadline = self.now_ns + timeout.as_nanos() as u64;
        let mut n = 0;
        loop {
            self.run_device_until(self.now_ns);
            while n < buf.len() {
                match self.d2h.queue.front() {
                    Some(&(t, b)) if t <= self.now_ns => {
                        self.d2h.queue.pop_front();
                        buf[n] = b;
                        n += 1;
                        // A delimiter after frame bytes ends a frame: hand it over.
                        if b == 0 && n > 1 {
                            return Ok(n);
                        }
                    }
                    _ => break,
                }
            }
            if n == buf.len() {
                return Ok(n);
            }
            match self.next_event() {
                Some(t) if t <= deadline => self.now_ns = self.now_ns.max(t),
                _ => {
                    if n == 0 {
                        self.now_ns = deadline;
                        self.run_device_until(deadline);
                    }
                    return Ok(n);
                }
            }
        }
    }

    fn now(&self) -> Duration {
        Duration::from_nanos(self.now_ns)
    }

    fn baud(&self) -> u32 {
        self.config.baud
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quad_protocol::{encode_frame, HostToDevice, Request, MAX_FRAME_LEN, PROTOCOL_VERSION};

    fn frame(seq: u16, request: Request) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME_LEN];
        encode_frame(&HostToDevice { seq, request }, &mut buf)
            .unwrap()
            .to_vec()
    }

    #[test]
    fn an_attached_sensor_is_read_at_the_firmware_s_rate_and_its_faults_reach_the_device() {
        use quad_device::imu::{ImuFault, ImuReading};
        use quad_device::sim::imu::{Feed, LevelStill};
        let mut link = SimLink::new(
            SimConfig::default(),
            Config::fernando2025(),
            EepromImage::erased(),
        )
        .unwrap();
        link.attach_imu(SharedImuSource::new(LevelStill));
        let mut buf = [0u8; 16];
        assert_eq!(link.recv(&mut buf, Duration::from_secs(1)).unwrap(), 0);
        let imu = *link.device().imu();
        // Reads at 8, 16, …, 992 ms: 124 in the first second.
        assert_eq!(imu.samples, 1000 / u32::from(READ_PERIOD_MS) - 1);
        assert_eq!(imu.fault, None);
        link.attach_imu(SharedImuSource::new(Feed(|_t: f64| {
            ImuReading::Fault(ImuFault::Nak)
        })));
        link.recv(&mut buf, Duration::from_millis(20)).unwrap();
        assert_eq!(link.device().imu().fault, Some(ImuFault::Nak));
    }

    #[test]
    fn an_answer_arrives_after_both_frames_crossed_the_line() {
        let cfg = SimConfig {
            baud: 1_000_000,
            compute: Duration::from_micros(500),
            ..SimConfig::default()
        };
        let mut link = SimLink::new(cfg, Config::fernando2025(), EepromImage::erased()).unwrap();
        let req = frame(
            1,
            Request::Hello {
                version: PROTOCOL_VERSION,
            },
        );
        link.send(&req).unwrap();
        let mut buf = [0u8; 256];
        let n = link.recv(&mut buf, Duration::from_secs(1)).unwrap();
        assert!(n > 2 && buf[0] == 0 && buf[n - 1] == 0);
        // 10 µs per byte: request, compute, answer.
        let expected_us = 10 * (req.len() + n) as u64 + 500;
        assert_eq!(link.now(), Duration::from_micros(expected_us));
        // Nothing else comes: the timeout passes in virtual time.
        assert_eq!(link.recv(&mut buf, Duration::from_millis(3)).unwrap(), 0);
        assert_eq!(link.now(), Duration::from_micros(expected_us + 3000));
    }

    #[test]
    fn the_same_seed_gives_the_same_faults() {
        let run = |seed| {
            let cfg = SimConfig {
                faults: "drop=0.05,flip=0.05,dup=0.2,trunc=0.2".parse().unwrap(),
                seed,
                ..SimConfig::default()
            };
            let mut link =
                SimLink::new(cfg, Config::fernando2025(), EepromImage::erased()).unwrap();
            let mut got = Vec::new();
            for seq in 0..50 {
                link.send(&frame(seq, Request::GetState)).unwrap();
                let mut buf = [0u8; 256];
                let n = link.recv(&mut buf, Duration::from_millis(30)).unwrap();
                got.extend_from_slice(&buf[..n]);
            }
            (got, link.stats())
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7).0, run(8).0);
        assert!(run(7).1.dropped > 0 && run(7).1.truncated > 0);
    }
}
