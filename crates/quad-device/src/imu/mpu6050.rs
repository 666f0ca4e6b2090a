//! The MPU-6050 (InvenSense, register map rev. 4.2; product specification rev. 3.4), once for
//! every user: the firmware's driver writes [`CONFIG_SEQUENCE`] and decodes each
//! [`BURST_LEN`]-byte burst with [`decode`]; the emulator's virtual sensor answers the same
//! registers and encodes its source's readings with [`encode`], at the scales the firmware
//! configured.
//!
//! ## Configuration, and why
//! | register | value | meaning |
//! |---|---|---|
//! | `PWR_MGMT_1` 0x6B | 0x01 | awake (SLEEP clear; it resets to 0x40, asleep), clock from the X gyro's PLL (more stable than the internal 8 MHz oscillator, register map §4.28) |
//! | `SMPLRT_DIV` 0x19 | 3 | sample rate 1 kHz / (1 + 3) = [`SAMPLE_RATE_HZ`] (the gyro output rate is 1 kHz with the DLPF on, §4.2) |
//! | `CONFIG` 0x1A | 3 | DLPF_CFG 3: accelerometer 44 Hz, gyro 42 Hz bandwidth, 4.9 / 4.8 ms delay (§4.3): below half the firmware's read rate, so reads do not alias |
//! | `GYRO_CONFIG` 0x1B | 0x08 | FS_SEL 1: ±500 °/s (65.5 LSB per °/s, §4.4); a small robot tipping over turns at 200–400 °/s, which ±250 °/s would clip |
//! | `ACCEL_CONFIG` 0x1C | 0x10 | AFS_SEL 2: ±8 g (4,096 LSB per g, §4.5); foot strikes of a trot reach several g, which ±2 g would clip, and 2.4 mg per LSB still resolves 0.14° of tilt |
//!
//! The firmware reads a burst every [`READ_PERIOD_MS`] ms ([`READ_RATE_HZ`]), half the sample
//! rate: each read finds a fresh sample.
//!
//! ## Mounting
//! The GY-521 breakout lies flat on the robot's body, component side up, the arrow printed
//! "X" on it pointing forward: its axes are the body frame's (x forward, y left, z up), which
//! [`MOUNTING`] states. Another mounting changes that one constant (a signed permutation of the
//! axes); [`decode`] and [`encode`] both go through it.
//!
//! ## Stuck data
//! A live sensor's 14 bytes never repeat exactly for long: the accelerometer's noise alone is
//! about ten LSB at ±8 g with the 44 Hz filter (400 µg/√Hz, product specification §6.2), and
//! the temperature word moves too. [`StuckDetector`] calls the data stuck when a burst has
//! repeated unchanged [`STUCK_REPEATS`] times in a row. (So a noiseless simulated source reads as stuck
//! too: give it noise, as the real chip has.)

use super::ImuSample;

/// The sensor's 7-bit bus address with AD0 low (the GY-521 pulls AD0 low).
pub const ADDRESS: u8 = 0x68;

/// The registers used (register map rev. 4.2, chapter 3).
pub mod reg {
    /// Sample rate divider (§4.2).
    pub const SMPLRT_DIV: u8 = 0x19;
    /// DLPF and external sync (§4.3).
    pub const CONFIG: u8 = 0x1A;
    /// Gyro full-scale range (§4.4).
    pub const GYRO_CONFIG: u8 = 0x1B;
    /// Accelerometer full-scale range (§4.5).
    pub const ACCEL_CONFIG: u8 = 0x1C;
    /// First byte of the measurement burst: accelerometer X, high byte (§4.17).
    pub const ACCEL_XOUT_H: u8 = 0x3B;
    /// Temperature, high byte (§4.18).
    pub const TEMP_OUT_H: u8 = 0x41;
    /// Gyro X, high byte (§4.19).
    pub const GYRO_XOUT_H: u8 = 0x43;
    /// Last byte of the measurement burst: gyro Z, low byte.
    pub const GYRO_ZOUT_L: u8 = 0x48;
    /// Power management 1: SLEEP (bit 6), CLKSEL (bits 2:0) (§4.28).
    pub const PWR_MGMT_1: u8 = 0x6B;
    /// Identity (§4.32).
    pub const WHO_AM_I: u8 = 0x75;
}

/// What `WHO_AM_I` reads on an MPU-6050.
pub const WHO_AM_I_VALUE: u8 = 0x68;

/// `PWR_MGMT_1` after power-on: SLEEP set.
pub const PWR_MGMT_1_RESET: u8 = 0x40;

/// `PWR_MGMT_1`'s SLEEP bit.
pub const SLEEP: u8 = 0x40;

/// `PWR_MGMT_1`'s CLKSEL value for the X gyro's PLL.
pub const CLKSEL_PLL_X_GYRO: u8 = 0x01;

/// Bytes of one burst: accelerometer X/Y/Z, temperature, gyro X/Y/Z, each big-endian `i16`.
pub const BURST_LEN: usize = (reg::GYRO_ZOUT_L - reg::ACCEL_XOUT_H + 1) as usize;

const _: () = assert!(BURST_LEN == 14);

/// Standard gravity, m/s² (the unit `g` of the accelerometer's ranges).
pub const STANDARD_GRAVITY_M_S2: f32 = 9.806_65;

/// Gyro full-scale range (`GYRO_CONFIG.FS_SEL`, §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroRange {
    /// ±250 °/s, 131 LSB per °/s.
    Dps250,
    /// ±500 °/s, 65.5 LSB per °/s.
    Dps500,
    /// ±1000 °/s, 32.8 LSB per °/s.
    Dps1000,
    /// ±2000 °/s, 16.4 LSB per °/s.
    Dps2000,
}

impl GyroRange {
    /// The range selected by a `GYRO_CONFIG` value (bits 4:3).
    pub const fn from_register(value: u8) -> GyroRange {
        match (value >> 3) & 0b11 {
            0 => GyroRange::Dps250,
            1 => GyroRange::Dps500,
            2 => GyroRange::Dps1000,
            _ => GyroRange::Dps2000,
        }
    }

    /// The `GYRO_CONFIG` value that selects it (self-test off).
    pub const fn register(self) -> u8 {
        (self as u8) << 3
    }

    /// Sensitivity, LSB per °/s (the datasheet's rounded figures, as the chip is trimmed to).
    pub const fn lsb_per_deg_s(self) -> f32 {
        match self {
            GyroRange::Dps250 => 131.0,
            GyroRange::Dps500 => 65.5,
            GyroRange::Dps1000 => 32.8,
            GyroRange::Dps2000 => 16.4,
        }
    }

    /// Angular rate per LSB, rad/s.
    pub const fn rad_s_per_lsb(self) -> f32 {
        core::f32::consts::PI / 180.0 / self.lsb_per_deg_s()
    }
}

/// Accelerometer full-scale range (`ACCEL_CONFIG.AFS_SEL`, §4.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelRange {
    /// ±2 g, 16,384 LSB per g.
    G2,
    /// ±4 g, 8,192 LSB per g.
    G4,
    /// ±8 g, 4,096 LSB per g.
    G8,
    /// ±16 g, 2,048 LSB per g.
    G16,
}

impl AccelRange {
    /// The range selected by an `ACCEL_CONFIG` value (bits 4:3).
    pub const fn from_register(value: u8) -> AccelRange {
        match (value >> 3) & 0b11 {
            0 => AccelRange::G2,
            1 => AccelRange::G4,
            2 => AccelRange::G8,
            _ => AccelRange::G16,
        }
    }

    /// The `ACCEL_CONFIG` value that selects it (self-test off).
    pub const fn register(self) -> u8 {
        (self as u8) << 3
    }

    /// Sensitivity, LSB per g.
    pub const fn lsb_per_g(self) -> f32 {
        match self {
            AccelRange::G2 => 16_384.0,
            AccelRange::G4 => 8_192.0,
            AccelRange::G8 => 4_096.0,
            AccelRange::G16 => 2_048.0,
        }
    }

    /// Specific force per LSB, m/s².
    pub const fn m_s2_per_lsb(self) -> f32 {
        STANDARD_GRAVITY_M_S2 / self.lsb_per_g()
    }
}

/// The gyro range the firmware selects (see the module docs).
pub const GYRO_RANGE: GyroRange = GyroRange::Dps500;

/// The accelerometer range the firmware selects (see the module docs).
pub const ACCEL_RANGE: AccelRange = AccelRange::G8;

/// `SMPLRT_DIV` written: 1 kHz / (1 + 3).
pub const SMPLRT_DIV_VALUE: u8 = 3;

/// `CONFIG.DLPF_CFG` written: 44 Hz accelerometer, 42 Hz gyro bandwidth.
pub const DLPF_CFG: u8 = 3;

/// The sensor's sample rate as configured, Hz.
pub const SAMPLE_RATE_HZ: u32 = gyro_output_rate_hz(DLPF_CFG) / (1 + SMPLRT_DIV_VALUE as u32);

/// The firmware reads one burst every this many milliseconds.
pub const READ_PERIOD_MS: u8 = 8;

/// The firmware's read rate, Hz (125: above the 100 Hz the estimator needs).
pub const READ_RATE_HZ: u32 = 1000 / READ_PERIOD_MS as u32;

const _: () = assert!(READ_RATE_HZ >= 100 && SAMPLE_RATE_HZ >= READ_RATE_HZ);

/// The gyro output rate for a `DLPF_CFG` (§4.2): 8 kHz with the filter off (0 or 7), else
/// 1 kHz. The sample rate is this over `1 + SMPLRT_DIV`.
pub const fn gyro_output_rate_hz(dlpf_cfg: u8) -> u32 {
    match dlpf_cfg & 0b111 {
        0 | 7 => 8_000,
        _ => 1_000,
    }
}

/// What the firmware writes after `WHO_AM_I` checked, in order: `(register, value)`.
pub const CONFIG_SEQUENCE: [(u8, u8); 5] = [
    (reg::PWR_MGMT_1, CLKSEL_PLL_X_GYRO),
    (reg::SMPLRT_DIV, SMPLRT_DIV_VALUE),
    (reg::CONFIG, DLPF_CFG),
    (reg::GYRO_CONFIG, GYRO_RANGE.register()),
    (reg::ACCEL_CONFIG, ACCEL_RANGE.register()),
];

/// One body axis as a sensor axis: `body[i] = sign · sensor[axis]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxisMap {
    /// The sensor axis (0 x, 1 y, 2 z).
    pub axis: u8,
    /// True when the body axis points against the sensor axis.
    pub negated: bool,
}

/// The sensor's mounting: body axis `i` (x forward, y left, z up) is `MOUNTING[i]` of the
/// sensor. The GY-521 lies flat, component side up, its X arrow forward: the identity.
pub const MOUNTING: [AxisMap; 3] = [
    AxisMap {
        axis: 0,
        negated: false,
    },
    AxisMap {
        axis: 1,
        negated: false,
    },
    AxisMap {
        axis: 2,
        negated: false,
    },
];

/// The raw words of one burst: accelerometer X/Y/Z, temperature, gyro X/Y/Z (sensor axes).
pub fn words(burst: &[u8; BURST_LEN]) -> [i16; 7] {
    core::array::from_fn(|i| i16::from_be_bytes([burst[2 * i], burst[2 * i + 1]]))
}

/// The sensor axes of a body vector, through [`MOUNTING`] (f32 in, raw `i16` out, see
/// [`encode`]).
fn to_body(sensor: [f32; 3]) -> [f32; 3] {
    core::array::from_fn(|i| {
        let m = MOUNTING[i];
        let v = sensor[usize::from(m.axis)];
        if m.negated {
            -v
        } else {
            v
        }
    })
}

/// Decodes one burst (from `ACCEL_XOUT_H` on) into a sample in the body frame, SI units, at
/// the ranges the firmware configures ([`ACCEL_RANGE`], [`GYRO_RANGE`]).
pub fn decode(burst: &[u8; BURST_LEN]) -> ImuSample {
    decode_with(burst, ACCEL_RANGE, GYRO_RANGE)
}

/// [`decode`] at given ranges.
pub fn decode_with(burst: &[u8; BURST_LEN], accel: AccelRange, gyro: GyroRange) -> ImuSample {
    let w = words(burst);
    let a = accel.m_s2_per_lsb();
    let g = gyro.rad_s_per_lsb();
    ImuSample {
        accel_m_s2: to_body([
            f32::from(w[0]) * a,
            f32::from(w[1]) * a,
            f32::from(w[2]) * a,
        ]),
        gyro_rad_s: to_body([
            f32::from(w[4]) * g,
            f32::from(w[5]) * g,
            f32::from(w[6]) * g,
        ]),
    }
}

/// The temperature of a burst, °C (§4.18: raw / 340 + 36.53).
pub fn temperature_c(burst: &[u8; BURST_LEN]) -> f32 {
    f32::from(words(burst)[3]) / 340.0 + 36.53
}

/// One quantity as the sensor's ADC gives it: the nearest step, saturated at the range's
/// ends as the chip saturates (a reading beyond full scale reads full scale).
fn quantise(value: f32, per_lsb: f32) -> i16 {
    let steps = libm::roundf(value / per_lsb);
    if steps.is_nan() {
        0
    } else if steps >= f32::from(i16::MAX) {
        i16::MAX
    } else if steps <= f32::from(i16::MIN) {
        i16::MIN
    } else {
        steps as i16
    }
}

/// The burst a sensor at `accel`/`gyro` ranges gives for `sample` (body frame) at
/// `temperature_c`: the inverse of [`decode_with`] up to quantisation, saturating at full
/// scale as the chip does.
pub fn encode(
    sample: &ImuSample,
    temperature_c: f32,
    accel: AccelRange,
    gyro: GyroRange,
) -> [u8; BURST_LEN] {
    let mut sensor_a = [0.0f32; 3];
    let mut sensor_g = [0.0f32; 3];
    for (i, m) in MOUNTING.iter().enumerate() {
        let sign = if m.negated { -1.0 } else { 1.0 };
        sensor_a[usize::from(m.axis)] = sign * sample.accel_m_s2[i];
        sensor_g[usize::from(m.axis)] = sign * sample.gyro_rad_s[i];
    }
    let a = accel.m_s2_per_lsb();
    let g = gyro.rad_s_per_lsb();
    let w: [i16; 7] = [
        quantise(sensor_a[0], a),
        quantise(sensor_a[1], a),
        quantise(sensor_a[2], a),
        quantise(temperature_c - 36.53, 1.0 / 340.0),
        quantise(sensor_g[0], g),
        quantise(sensor_g[1], g),
        quantise(sensor_g[2], g),
    ];
    let mut out = [0u8; BURST_LEN];
    for (i, v) in w.iter().enumerate() {
        out[2 * i..2 * i + 2].copy_from_slice(&v.to_be_bytes());
    }
    out
}

/// Unchanged repeats of a burst after which the data counts as stuck (80 ms at the read rate).
pub const STUCK_REPEATS: u8 = 10;

/// Watches bursts for stuck data (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StuckDetector {
    last: [u8; BURST_LEN],
    /// Bursts in a row equal to the last one.
    repeats: u8,
}

impl StuckDetector {
    /// A detector that has seen nothing.
    pub const fn new() -> StuckDetector {
        StuckDetector {
            last: [0; BURST_LEN],
            repeats: 0,
        }
    }

    /// Takes one burst; true while the data is stuck (the burst and the [`STUCK_REPEATS`]
    /// before it identical).
    pub fn is_stuck(&mut self, burst: &[u8; BURST_LEN]) -> bool {
        if *burst == self.last {
            self.repeats = self.repeats.saturating_add(1);
        } else {
            self.last = *burst;
            self.repeats = 0;
        }
        self.repeats >= STUCK_REPEATS
    }

    /// Forgets the history (after a bus fault: the next burst starts a new run).
    pub fn reset(&mut self) {
        self.repeats = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn burst_of(words: [i16; 7]) -> [u8; BURST_LEN] {
        let mut b = [0u8; BURST_LEN];
        for (i, w) in words.iter().enumerate() {
            b[2 * i..2 * i + 2].copy_from_slice(&w.to_be_bytes());
        }
        b
    }

    #[test]
    fn the_configuration_is_the_documented_one() {
        assert_eq!(
            CONFIG_SEQUENCE,
            [
                (0x6B, 0x01),
                (0x19, 3),
                (0x1A, 3),
                (0x1B, 0x08),
                (0x1C, 0x10)
            ]
        );
        assert_eq!(SAMPLE_RATE_HZ, 250);
        assert_eq!(READ_RATE_HZ, 125);
        assert_eq!(GyroRange::from_register(0x08), GyroRange::Dps500);
        assert_eq!(AccelRange::from_register(0x10), AccelRange::G8);
        for r in [0u8, 0x08, 0x10, 0x18] {
            assert_eq!(GyroRange::from_register(r).register(), r);
            assert_eq!(AccelRange::from_register(r).register(), r);
        }
        // Self-test bits (7:5) do not change the range.
        assert_eq!(AccelRange::from_register(0xF0), AccelRange::G8);
    }

    #[test]
    fn big_endian_words_in_datasheet_order() {
        let b = [
            0x12, 0x34, 0x80, 0x00, 0x7F, 0xFF, 0xF2, 0xB0, 0x00, 0x01, 0xFF, 0xFF, 0x01, 0x00,
        ];
        assert_eq!(words(&b), [0x1234, -32768, 32767, -3408, 1, -1, 256]);
    }

    #[test]
    fn one_g_on_z_level_and_still() {
        let s = decode(&burst_of([0, 0, 4096, 0, 0, 0, 0]));
        assert_eq!(s.accel_m_s2, [0.0, 0.0, STANDARD_GRAVITY_M_S2]);
        assert_eq!(s.gyro_rad_s, [0.0; 3]);
    }

    #[test]
    fn full_scale_both_signs_and_the_extra_negative_step() {
        let s = decode(&burst_of([32767, -32768, -32767, 0, 32767, -32768, 1]));
        let g = STANDARD_GRAVITY_M_S2;
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * b.abs().max(1.0);
        assert!(close(s.accel_m_s2[0], 8.0 * g * 32767.0 / 32768.0));
        assert!(close(s.accel_m_s2[1], -8.0 * g));
        assert!(close(s.accel_m_s2[2], -8.0 * g * 32767.0 / 32768.0));
        let dps = core::f32::consts::PI / 180.0;
        assert!(close(s.gyro_rad_s[0], 32767.0 / 65.5 * dps));
        assert!(close(s.gyro_rad_s[1], -32768.0 / 65.5 * dps));
        assert!(close(s.gyro_rad_s[2], dps / 65.5));
        assert!(s.gyro_rad_s[1] < -8.7, "±500 °/s is ±8.73 rad/s");
    }

    #[test]
    fn encode_inverts_decode_and_saturates_at_full_scale() {
        let sample = ImuSample {
            accel_m_s2: [1.5, -2.25, 9.80665],
            gyro_rad_s: [0.5, -1.0, 3.0],
        };
        for (a, g) in [
            (AccelRange::G2, GyroRange::Dps250),
            (AccelRange::G8, GyroRange::Dps500),
            (AccelRange::G16, GyroRange::Dps2000),
        ] {
            let b = encode(&sample, 25.0, a, g);
            let back = decode_with(&b, a, g);
            for i in 0..3 {
                assert!((back.accel_m_s2[i] - sample.accel_m_s2[i]).abs() <= a.m_s2_per_lsb());
                assert!((back.gyro_rad_s[i] - sample.gyro_rad_s[i]).abs() <= g.rad_s_per_lsb());
            }
            assert!((temperature_c(&b) - 25.0).abs() < 0.01);
        }
        let huge = ImuSample {
            accel_m_s2: [1e6, -1e6, f32::NAN],
            gyro_rad_s: [100.0, -100.0, 0.0],
        };
        let w = words(&encode(&huge, 25.0, AccelRange::G8, GyroRange::Dps500));
        assert_eq!(
            [w[0], w[1], w[2], w[4], w[5]],
            [32767, -32768, 0, 32767, -32768]
        );
    }

    #[test]
    fn stuck_after_the_set_number_of_identical_bursts() {
        let mut d = StuckDetector::new();
        let a = burst_of([1, 2, 3, 4, 5, 6, 7]);
        let b = burst_of([1, 2, 3, 4, 5, 6, 8]);
        assert!(!d.is_stuck(&a));
        for _ in 1..STUCK_REPEATS {
            assert!(!d.is_stuck(&a));
        }
        assert!(d.is_stuck(&a));
        assert!(d.is_stuck(&a));
        assert!(!d.is_stuck(&b), "new data ends it");
        assert!(!d.is_stuck(&a));
    }
}
