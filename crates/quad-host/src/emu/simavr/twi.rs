//! A virtual MPU-6050 at 0x68 on simavr's TWI, fed by an [`ImuSource`].
//!
//! simavr's TWI master (vendored by `simavr-ffi` 1.2) tells a slave what happens on the bus
//! through `TWI_IRQ_OUTPUT` (`avr_twi_msg_irq_t`: START with the address byte, WRITE with a
//! data byte, READ asking for one, STOP) and expects the slave to answer at once on
//! `TWI_IRQ_INPUT` (an ACK, a data byte); no answer is a NAK. Each byte's status then reaches
//! the firmware nine bus clocks later, at the rate its TWBR set.
//!
//! The register file follows the register map (rev. 4.2): `WHO_AM_I` 0x75 reads 0x68,
//! `PWR_MGMT_1` resets to 0x40 (SLEEP: the data registers keep their values, zeros after
//! power-on, as the chip's do; bit 7 resets the register file), `SMPLRT_DIV` and `CONFIG`'s
//! DLPF_CFG set the sample rate (1 kHz or 8 kHz / (1 + div)), `GYRO_CONFIG` and
//! `ACCEL_CONFIG` the ranges at which the source's readings are encoded
//! (`quad_device::imu::mpu6050::encode`, the firmware's own scales), `ACCEL_XOUT_H` …
//! `GYRO_ZOUT_L` big-endian with `TEMP_OUT` (25 °C). A write sets the register pointer with its
//! first byte and writes from there on; reads auto-increment. The data registers are refreshed
//! at each sample instant, never during a read (the chip's burst reads are consistent too).
//!
//! The source's faults act on the bus (see `quad_device::sim::imu`): no ACK for `Absent` and
//! `Nak`, no ACK and SDA (PD1) held low for `BusHeld`, frozen data for `Stuck`, another
//! identity for `WrongId`. With a sensor attached, SDA and SCL are pulled up (the GY-521's
//! resistors, simavr's external pull-ups on PD0/PD1); without one the bus has nothing at 0x68.

use quad_device::imu::mpu6050::{
    self, reg, AccelRange, GyroRange, ADDRESS, BURST_LEN, PWR_MGMT_1_RESET, SLEEP, WHO_AM_I_VALUE,
};
use quad_device::imu::{ImuFault, ImuReading};
use quad_device::sim::imu::ImuSource;
use simavr_ffi as ffi;
use std::ffi::c_void;
use std::fmt;
use std::sync::{Arc, Mutex};

/// An inertial source shared between its owner and the emulated sensor (clones share one
/// source; equal when they are the same one).
#[derive(Clone)]
pub struct SharedImuSource(Arc<Mutex<dyn ImuSource + Send>>);

impl SharedImuSource {
    /// Shares `source`.
    pub fn new(source: impl ImuSource + Send + 'static) -> SharedImuSource {
        SharedImuSource(Arc::new(Mutex::new(source)))
    }

    /// The source's reading at `t_s` (see [`ImuSource::read`]).
    pub fn read(&self, t_s: f64) -> ImuReading {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).read(t_s)
    }
}

impl fmt::Debug for SharedImuSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("SharedImuSource(..)")
    }
}

impl PartialEq for SharedImuSource {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// What the virtual sensor saw on the bus since power-on.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImuBus {
    /// The cycle of each burst read: a read that starts at `ACCEL_XOUT_H`.
    pub burst_cycles: Vec<u64>,
    /// Register writes, `(register, value)`, in order.
    pub writes: Vec<(u8, u8)>,
    /// Reads of `WHO_AM_I`.
    pub who_am_i_reads: u64,
    /// Address bytes for 0x68 left without an ACK (the sensor absent or faulted).
    pub unanswered: u64,
    /// Samples taken from the source (one per sample instant while awake).
    pub refreshes: u64,
}

/// The `ioctl` code of `AVR_IOCTL_DEF(a, b, c, d)`.
const fn ioctl(a: u8, b: u8, c: u8, d: u8) -> u32 {
    u32::from_be_bytes([a, b, c, d])
}

/// `AVR_IOCTL_TWI_GETIRQ(0)`.
const IOCTL_TWI_GETIRQ: u32 = ioctl(b't', b'w', b'i', 0);

/// `AVR_IOCTL_IOPORT_GETIRQ('D')`.
const IOCTL_IOPORT_GETIRQ_D: u32 = ioctl(b'i', b'o', b'g', b'D');

/// `AVR_IOCTL_IOPORT_SET_EXTERNAL('D')`.
const IOCTL_IOPORT_SET_EXTERNAL_D: u32 = ioctl(b'i', b'o', b'p', b'D');

/// SCL = PD0, SDA = PD1.
const BUS_PINS_MASK: u8 = 0b11;

/// The die temperature the sensor reports, °C.
const TEMPERATURE_C: f32 = 25.0;

/// A TWI message (`avr_twi_msg_irq_t`: bits 8–15 the conditions, 16–23 the address byte,
/// 24–31 the data).
fn msg(conditions: u32, addr: u8, data: u8) -> u32 {
    (conditions << 8) | (u32::from(addr) << 16) | (u32::from(data) << 24)
}

/// The chip's logic, apart from simavr: the register file, the bus protocol, the source's
/// readings applied.
struct Chip {
    regs: [u8; 128],
    /// Acknowledges its address.
    present: bool,
    /// Holds SDA low.
    sda_low: bool,
    who_am_i: u8,
    /// The address byte of the transfer addressed to it, while it lasts.
    selected: Option<u8>,
    /// Bytes written in this transfer.
    written: u32,
    pointer: u8,
    bus: ImuBus,
}

impl Chip {
    fn new() -> Chip {
        Chip {
            regs: power_on_registers(),
            present: true,
            sda_low: false,
            who_am_i: WHO_AM_I_VALUE,
            selected: None,
            written: 0,
            pointer: 0,
            bus: ImuBus::default(),
        }
    }

    /// The sample period as configured, cycles.
    fn period_cycles(&self) -> u64 {
        let rate = mpu6050::gyro_output_rate_hz(self.regs[usize::from(reg::CONFIG)])
            / (1 + u32::from(self.regs[usize::from(reg::SMPLRT_DIV)]));
        u64::from(super::F_CPU_HZ) / u64::from(rate.max(1))
    }

    /// True while a read addressed to it is in progress (the data must not change).
    fn reading(&self) -> bool {
        self.selected.is_some_and(|a| a & 1 == 1)
    }

    /// Takes a reading of the source (module docs): the data registers, presence, SDA.
    fn apply(&mut self, reading: ImuReading) {
        let (present, sda_low) = match reading {
            ImuReading::Sample(s) => {
                self.who_am_i = WHO_AM_I_VALUE;
                if self.regs[usize::from(reg::PWR_MGMT_1)] & SLEEP == 0 {
                    let burst = mpu6050::encode(
                        &s,
                        TEMPERATURE_C,
                        AccelRange::from_register(self.regs[usize::from(reg::ACCEL_CONFIG)]),
                        GyroRange::from_register(self.regs[usize::from(reg::GYRO_CONFIG)]),
                    );
                    let at = usize::from(reg::ACCEL_XOUT_H);
                    self.regs[at..at + BURST_LEN].copy_from_slice(&burst);
                    self.bus.refreshes += 1;
                }
                (true, false)
            }
            ImuReading::Fault(ImuFault::Stuck) => (true, false),
            ImuReading::Fault(ImuFault::WrongId { who_am_i }) => {
                self.who_am_i = who_am_i;
                (true, false)
            }
            ImuReading::Fault(ImuFault::Absent | ImuFault::Nak) => (false, false),
            ImuReading::Fault(ImuFault::BusHeld) => (false, true),
        };
        self.present = present;
        self.sda_low = sda_low;
    }

    fn read_register(&mut self) -> u8 {
        let r = self.pointer & 0x7F;
        self.pointer = self.pointer.wrapping_add(1);
        if r == reg::WHO_AM_I {
            self.bus.who_am_i_reads += 1;
            self.who_am_i
        } else {
            self.regs[usize::from(r)]
        }
    }

    fn write_register(&mut self, value: u8) {
        let r = self.pointer & 0x7F;
        self.pointer = self.pointer.wrapping_add(1);
        self.bus.writes.push((r, value));
        match r {
            // Read-only: the data registers and the identity.
            0x3B..=0x48 | reg::WHO_AM_I => {}
            reg::PWR_MGMT_1 if value & 0x80 != 0 => self.regs = power_on_registers(),
            _ => self.regs[usize::from(r)] = value,
        }
    }

    /// One message of simavr's TWI master at `cycle`; `answer` takes the chip's replies.
    fn on_message(&mut self, value: u32, cycle: u64, mut answer: impl FnMut(u32)) {
        let conditions = (value >> 8) & 0xFF;
        let addr = (value >> 16) as u8;
        let data = (value >> 24) as u8;
        if conditions & ffi::TWI_COND_STOP != 0 {
            self.selected = None;
        }
        if conditions & ffi::TWI_COND_START != 0 {
            self.selected = None;
            if addr >> 1 == ADDRESS {
                if self.present {
                    self.selected = Some(addr);
                    self.written = 0;
                    if addr & 1 == 1 && self.pointer == reg::ACCEL_XOUT_H {
                        self.bus.burst_cycles.push(cycle);
                    }
                    answer(msg(ffi::TWI_COND_ACK, addr, 1));
                } else {
                    self.bus.unanswered += 1;
                }
            }
        }
        let Some(sel) = self.selected else { return };
        if conditions & ffi::TWI_COND_WRITE != 0 {
            answer(msg(ffi::TWI_COND_ACK, sel, 1));
            if self.written == 0 {
                self.pointer = data;
            } else {
                self.write_register(data);
            }
            self.written += 1;
        }
        if conditions & ffi::TWI_COND_READ != 0 {
            let byte = self.read_register();
            answer(msg(ffi::TWI_COND_READ, sel, byte));
        }
    }
}

/// The virtual chip on simavr (module docs); reached by simavr's hook through a raw pointer.
pub(super) struct VirtualMpu {
    avr: *mut ffi::avr_t,
    twi_in: *mut ffi::avr_irq_t,
    sda: *mut ffi::avr_irq_t,
    pub(super) source: SharedImuSource,
    chip: Chip,
    /// SDA as last driven on the port.
    sda_low: bool,
    next_refresh_cycle: u64,
    /// The cycle of the instruction being run (for the hook's time stamps).
    pub(super) now_cycle: u64,
}

impl VirtualMpu {
    /// A powered-on sensor on `avr`'s TWI fed by `source`, its hook registered; boxed for its
    /// address.
    ///
    /// # Safety
    /// `avr` is a live, initialised ATmega2560; the box must outlive the simulator's use of
    /// the hook (drop it only after `avr_terminate`).
    pub(super) unsafe fn attach(avr: *mut ffi::avr_t, source: SharedImuSource) -> Box<VirtualMpu> {
        // SAFETY (this block): `avr` is live (caller); the IRQs exist on the ATmega2560
        // (TWI and port D are part of its core description).
        unsafe {
            let out = ffi::avr_io_getirq(avr, IOCTL_TWI_GETIRQ, ffi::TWI_IRQ_OUTPUT as i32);
            let twi_in = ffi::avr_io_getirq(avr, IOCTL_TWI_GETIRQ, ffi::TWI_IRQ_INPUT as i32);
            let sda = ffi::avr_io_getirq(avr, IOCTL_IOPORT_GETIRQ_D, ffi::IOPORT_IRQ_PIN1 as i32);
            let scl = ffi::avr_io_getirq(avr, IOCTL_IOPORT_GETIRQ_D, ffi::IOPORT_IRQ_PIN0 as i32);
            let mut mpu = Box::new(VirtualMpu {
                avr,
                twi_in,
                sda,
                source,
                chip: Chip::new(),
                sda_low: false,
                next_refresh_cycle: 0,
                now_cycle: 0,
            });
            mpu.set_pull_ups();
            ffi::avr_raise_irq(scl, 1);
            ffi::avr_raise_irq(sda, 1);
            let param: *mut c_void = (&mut *mpu as *mut VirtualMpu).cast();
            ffi::avr_irq_register_notify(out, Some(on_twi_output), param);
            mpu.refresh(0);
            mpu
        }
    }

    /// What it saw on the bus.
    pub(super) fn bus(&self) -> &ImuBus {
        &self.chip.bus
    }

    /// simavr's external pull-ups on the bus pins: both high, or SDA held low.
    fn set_pull_ups(&mut self) {
        let value = if self.sda_low { 0b01 } else { BUS_PINS_MASK };
        // `avr_ioport_external_t`: name (7 bits), mask (8), value (8), in an unsigned long.
        let mut external: std::ffi::c_ulong = (std::ffi::c_ulong::from(b'D'))
            | (std::ffi::c_ulong::from(BUS_PINS_MASK) << 7)
            | (std::ffi::c_ulong::from(value) << 15);
        // SAFETY: the ioctl reads an `avr_ioport_external_t` from the pointer; `avr` is live.
        unsafe {
            ffi::avr_ioctl(
                self.avr,
                IOCTL_IOPORT_SET_EXTERNAL_D,
                (&mut external as *mut std::ffi::c_ulong).cast(),
            );
        }
    }

    /// Drives SDA as the chip wants it (after a reading was applied).
    fn drive_sda(&mut self) {
        let low = self.chip.sda_low;
        if low == self.sda_low {
            return;
        }
        self.sda_low = low;
        self.set_pull_ups();
        // SAFETY: a port D pin IRQ of a live simulator.
        unsafe { ffi::avr_raise_irq(self.sda, u32::from(!low)) };
    }

    /// Takes the source's reading when a sample instant has come (after each instruction).
    pub(super) fn tick(&mut self, cycle: u64) {
        if cycle < self.next_refresh_cycle || self.chip.reading() {
            return;
        }
        self.refresh(cycle);
    }

    fn refresh(&mut self, cycle: u64) {
        let period = self.chip.period_cycles();
        self.next_refresh_cycle = (self.next_refresh_cycle + period).max(cycle + 1);
        let t_s = cycle as f64 / f64::from(super::F_CPU_HZ);
        self.chip.apply(self.source.read(t_s));
        self.drive_sda();
    }

    fn on_message(&mut self, value: u32) {
        let twi_in = self.twi_in;
        self.chip.on_message(value, self.now_cycle, |answer| {
            // SAFETY: the TWI input IRQ of a live simulator; simavr takes the answer
            // synchronously.
            unsafe { ffi::avr_raise_irq(twi_in, answer) };
        });
    }
}

/// The register file after power-on (register map: all zero but `PWR_MGMT_1` 0x40 and
/// `WHO_AM_I`).
fn power_on_registers() -> [u8; 128] {
    let mut r = [0u8; 128];
    r[usize::from(reg::PWR_MGMT_1)] = PWR_MGMT_1_RESET;
    r[usize::from(reg::WHO_AM_I)] = WHO_AM_I_VALUE;
    r
}

unsafe extern "C" fn on_twi_output(_: *mut ffi::avr_irq_t, value: u32, param: *mut c_void) {
    // SAFETY: `param` is the boxed `VirtualMpu` registered in `attach`, alive until the
    // simulator is dropped; simavr calls the hook only from within `avr_run`, during which no
    // Rust reference to the box is used.
    let chip = unsafe { &mut *param.cast::<VirtualMpu>() };
    chip.on_message(value);
}

#[cfg(test)]
mod tests {
    use super::*;
    use quad_device::imu::mpu6050::{CONFIG_SEQUENCE, STANDARD_GRAVITY_M_S2};
    use quad_device::sim::imu::at_attitude;

    const W: u8 = ADDRESS << 1;
    const R: u8 = W | 1;

    /// A host that drives the chip as simavr's master does; returns the chip's answers.
    struct Master(Chip);

    impl Master {
        fn send(&mut self, conditions: u32, addr: u8, data: u8) -> Vec<u32> {
            let mut out = Vec::new();
            self.0
                .on_message(msg(conditions, addr, data), 0, |a| out.push(a));
            out
        }

        fn write(&mut self, bytes: &[u8]) -> bool {
            let acked = !self.send(ffi::TWI_COND_START, W, 0).is_empty();
            for &b in bytes {
                self.send(ffi::TWI_COND_WRITE, W, b);
            }
            self.send(ffi::TWI_COND_STOP, W, 0);
            acked
        }

        fn read(&mut self, register: u8, n: usize) -> Option<Vec<u8>> {
            self.send(ffi::TWI_COND_START, W, 0);
            self.send(ffi::TWI_COND_WRITE, W, register);
            if self.send(ffi::TWI_COND_START, R, 0).is_empty() {
                return None;
            }
            let bytes = (0..n)
                .map(|_| (self.send(ffi::TWI_COND_READ, R, 0)[0] >> 24) as u8)
                .collect();
            self.send(ffi::TWI_COND_STOP, R, 0);
            Some(bytes)
        }
    }

    fn tilted() -> ImuReading {
        ImuReading::Sample(at_attitude(0.0, 0.2, [0.1, 0.0, -0.3]))
    }

    #[test]
    fn asleep_after_power_on_the_data_stays_zero_and_wakes_with_the_configuration() {
        let mut m = Master(Chip::new());
        assert_eq!(m.read(reg::WHO_AM_I, 1), Some(vec![0x68]));
        assert_eq!(m.read(reg::PWR_MGMT_1, 1), Some(vec![0x40]));
        m.0.apply(tilted());
        assert_eq!(
            m.read(reg::ACCEL_XOUT_H, BURST_LEN),
            Some(vec![0; BURST_LEN])
        );
        // 8 kHz with the DLPF off at power-on: 2,000 cycles.
        assert_eq!(m.0.period_cycles(), 2_000);
        for (r, v) in CONFIG_SEQUENCE {
            assert!(m.write(&[r, v]));
        }
        assert_eq!(m.0.bus.writes, CONFIG_SEQUENCE.to_vec());
        assert_eq!(m.0.period_cycles(), 16_000_000 / 250);
        m.0.apply(tilted());
        let burst: [u8; BURST_LEN] = m
            .read(reg::ACCEL_XOUT_H, BURST_LEN)
            .unwrap()
            .try_into()
            .unwrap();
        let s = mpu6050::decode(&burst);
        let g = STANDARD_GRAVITY_M_S2;
        assert!((s.accel_m_s2[0] + g * 0.2f32.sin()).abs() < 0.005, "{s:?}");
        assert!((s.gyro_rad_s[2] + 0.3).abs() < 0.001, "{s:?}");
        assert_eq!(m.0.bus.burst_cycles.len(), 2);
        // Back to sleep: the data keeps its values.
        assert!(m.write(&[reg::PWR_MGMT_1, SLEEP]));
        m.0.apply(ImuReading::Sample(at_attitude(0.0, 0.0, [0.0; 3])));
        assert_eq!(
            m.read(reg::ACCEL_XOUT_H, BURST_LEN).unwrap(),
            burst.to_vec()
        );
        // DEVICE_RESET: the power-on registers.
        assert!(m.write(&[reg::PWR_MGMT_1, 0x80]));
        assert_eq!(m.read(reg::PWR_MGMT_1, 1), Some(vec![0x40]));
    }

    #[test]
    fn the_ranges_written_are_the_ranges_encoded() {
        let mut m = Master(Chip::new());
        m.write(&[reg::PWR_MGMT_1, 0x01]);
        m.write(&[reg::ACCEL_CONFIG, AccelRange::G2.register()]);
        m.0.apply(ImuReading::Sample(at_attitude(0.0, 0.0, [0.0; 3])));
        let b = m.read(reg::ACCEL_XOUT_H + 4, 2).unwrap();
        assert_eq!(i16::from_be_bytes([b[0], b[1]]), 16_384, "1 g at ±2 g");
        m.write(&[reg::ACCEL_CONFIG, AccelRange::G16.register()]);
        m.0.apply(ImuReading::Sample(at_attitude(0.0, 0.0, [0.0; 3])));
        let b = m.read(reg::ACCEL_XOUT_H + 4, 2).unwrap();
        assert_eq!(i16::from_be_bytes([b[0], b[1]]), 2_048, "1 g at ±16 g");
    }

    #[test]
    fn faults_act_on_the_bus() {
        let mut m = Master(Chip::new());
        m.0.apply(ImuReading::Fault(ImuFault::Nak));
        assert_eq!(m.read(reg::WHO_AM_I, 1), None);
        assert!(!m.0.sda_low);
        m.0.apply(ImuReading::Fault(ImuFault::BusHeld));
        assert_eq!(m.read(reg::WHO_AM_I, 1), None);
        assert!(m.0.sda_low);
        m.0.apply(ImuReading::Fault(ImuFault::WrongId { who_am_i: 0x70 }));
        assert_eq!(m.read(reg::WHO_AM_I, 1), Some(vec![0x70]));
        assert!(!m.0.sda_low);
        m.write(&[reg::PWR_MGMT_1, 0x01]);
        m.0.apply(tilted());
        let before = m.read(reg::ACCEL_XOUT_H, BURST_LEN);
        m.0.apply(ImuReading::Fault(ImuFault::Stuck));
        assert_eq!(
            m.read(reg::ACCEL_XOUT_H, BURST_LEN),
            before,
            "frozen while stuck"
        );
        m.0.apply(ImuReading::Sample(at_attitude(0.0, 0.0, [0.0; 3])));
        assert_ne!(
            m.read(reg::ACCEL_XOUT_H, BURST_LEN),
            before,
            "fresh data after"
        );
        assert!(m.0.bus.unanswered >= 2);
    }
}
