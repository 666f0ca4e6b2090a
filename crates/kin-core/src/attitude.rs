//! Attitude from a six-axis inertial sensor: roll and pitch of the body against gravity.
//!
//! [`Estimator`] is Mahony's nonlinear complementary filter (R. Mahony, T. Hamel, J.-M.
//! Pflimlin, *Nonlinear Complementary Filters on the Special Orthogonal Group*, IEEE TAC 53(5),
//! 2008, eq. 32: `ω̂ = ω_y − b̂ + k_P·e`, `ḃ = −k_I·e`, `e = v_y × v̂`), written on the one
//! direction it can observe without a magnetometer: the world's **up** in the body frame, a
//! unit vector `v̂`. Its state is that vector and the gyro bias, six numbers.
//!
//! ## Why this form
//! - **Mahony rather than a complementary filter on angles**: the angle filter
//!   (`θ = α·(θ + ω·dt) + (1−α)·θ_acc`) mixes Euler angles, which wrap at ±180° roll and are
//!   singular at ±90° pitch; it needs a separate bias estimate. Mahony's correction is a cross
//!   product of two unit vectors, has no singular attitude (upside down and ±90° pitch are
//!   ordinary states; the tests run them) and its integral term tracks the gyro bias, which the
//!   MPU-6050 lets drift with temperature.
//! - **The up vector rather than a quaternion**: yaw is unobservable from gravity alone, and
//!   roll and pitch depend on the up vector only. Propagating three numbers instead of four
//!   saves a third of the software-float work on the ATmega2560, and the vector is renormalised
//!   by one Newton step (`v·(3 − |v|²)/2`, no square root, no division): the propagation keeps
//!   `|v|` within 1e-4 of 1 per step at the rates a servo robot turns.
//! - **No crate**: the maintained no_std filters (`ahrs`, Madgwick/Mahony on quaternions) are
//!   built on nalgebra, whose trigonometry goes through libm's f64 `sincosf` on the AVR (see the
//!   crate docs, "Why not nalgebra inside") and cannot use the firmware's [`Math`] backend; this
//!   one takes its square root and arctangent from `M`, like the rest of kin-core.
//!
//! ## Frames and signs
//! Body frame of kin-core (x forward, y left, z up). The accelerometer reads the specific force,
//! `(0, 0, +g)` level and still. Roll and pitch are those of the zyx order
//! (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`, body to world): with the up vector in the body frame
//! `v = Rᵀ·(0, 0, 1) = (−sin p, sin r·cos p, cos r·cos p)`,
//! `roll = atan2(v_y, v_z)` and `pitch = atan2(−v_x, √(v_y² + v_z²))`. Roll is in `[−π, π]`
//! (upside down is ±π), pitch in `[−π/2, π/2]`.
//!
//! ## Accelerometer weighting
//! The accelerometer tells the up direction only on average: a walking body accelerates
//! back and forth, up and down, and its specific force swings around `g` within each stride.
//! Three refinements of the plain filter keep that from reading as tilt:
//! - **The correction is linear in the reading**: `e = (a/g) × v̂`, not `(a/|a|) × v̂`. The
//!   mean of the specific force over a stride is gravity (the body's mean acceleration is
//!   zero at a steady gait); the mean of its *direction* is not, because the samples of the
//!   push-off (small `|a|`, body accelerating forward) weigh as much as those of the
//!   touchdown. Normalised, the physics twin's trot read 1.2–1.3° of pitch that was not there
//!   (`docs/benchmark-journal.md`, "Attitude estimator during the trot").
//! - **An adaptive gain** (R. G. Valenti, I. Dryanovski, J. Xiao, *Keeping a Good Attitude: A
//!   Quaternion-Based Orientation Filter for IMUs and MARGs*, Sensors 15(8), 2015, its
//!   adaptive gain): the correction's weight is 1 while `| |a|/g − 1 |` is within
//!   [`Gains::accel_trust_share`], falls linearly to 0 at [`Gains::accel_reject_share`] and is
//!   0 beyond (free fall, a landing, a kick): the gyro alone carries the estimate through
//!   such a sample. Its thresholds are wider than the paper's (0.1 and 0.2): a trot's
//!   readings spread ±25 % around `g`, and a narrow band keeps the samples of one phase of
//!   the stride and drops the other's, which biases the mean as normalising does.
//! - **The same weight on the rate**: full below [`Gains::rate_trust_rad_s`], none from
//!   [`Gains::rate_reject_rad_s`]. A sensor off the centre of a fast turn (a fall, a tumble)
//!   reads its centripetal and tangential acceleration as tilt: in the twin's fall the
//!   estimate crossed 60° one sample before the body. The thresholds lie far above a trot's
//!   rates (at most 0.8 rad/s in the twin's): at 1–2 rad/s the rate follows the stride's
//!   phase, the weight selects a phase, and the trot's error grew.
//!
//! A zero or non-finite sample corrects nothing; nothing here produces a NaN from finite
//! input.

use crate::math::Math;
use core::marker::PhantomData;

/// Standard gravity, m/s².
pub const G_M_S2: f32 = 9.806_65;

/// The filter's gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    /// Proportional gain `k_P`, rad/s per unit of direction error (the crossover of the
    /// accelerometer against the gyro: below `k_P / 2π` Hz the accelerometer wins).
    pub kp_per_s: f32,
    /// Integral gain `k_I`, rad/s² per unit of error (how fast the bias estimate follows).
    pub ki_per_s2: f32,
    /// The largest `| |a|/g − 1 |` of a sample that corrects the estimate with its full
    /// weight (module docs, "Accelerometer weighting").
    pub accel_trust_share: f32,
    /// The `| |a|/g − 1 |` from which a sample corrects nothing; between the two shares its
    /// weight falls linearly. Greater than [`Gains::accel_trust_share`].
    pub accel_reject_share: f32,
    /// The largest rate (the bias removed) at which a sample corrects the estimate with its
    /// full weight, rad/s (module docs, "Accelerometer weighting").
    pub rate_trust_rad_s: f32,
    /// The rate from which a sample corrects nothing, rad/s; between the two the weight falls
    /// linearly. Greater than [`Gains::rate_trust_rad_s`].
    pub rate_reject_rad_s: f32,
    /// The largest bias estimate per axis, rad/s (the MPU-6050's datasheet allows ±20 °/s at
    /// 25 °C): the integral is held within it.
    pub max_bias_rad_s: f32,
}

impl Gains {
    /// The gains the device uses: a crossover of 0.16 Hz (`k_P` = 1 rad/s), a bias time
    /// constant of about 20 s, samples within 30 % of `g` trusted fully, beyond 60 % not at
    /// all. Measured in the tests (`tests/attitude.rs`: still, sway, trot-like vibration with
    /// noise and bias) and on the physics twin's trot of both robots.
    pub const DEFAULT: Gains = Gains {
        kp_per_s: 1.0,
        ki_per_s2: 0.05,
        accel_trust_share: 0.3,
        accel_reject_share: 0.6,
        rate_trust_rad_s: 2.0,
        rate_reject_rad_s: 4.0,
        max_bias_rad_s: 0.35,
    };
}

impl Default for Gains {
    fn default() -> Self {
        Gains::DEFAULT
    }
}

/// Roll and pitch of the body, rad (zyx order; module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attitude {
    /// Roll about the body's x axis, `[−π, π]`.
    pub roll_rad: f32,
    /// Pitch about the body's y axis, `[−π/2, π/2]`.
    pub pitch_rad: f32,
}

/// Mahony's filter on the up vector (module docs), on math backend `M`.
#[derive(Debug, Clone, Copy)]
pub struct Estimator<M> {
    gains: Gains,
    /// The world's up in the body frame, unit length.
    up: [f32; 3],
    /// The gyro bias, rad/s.
    bias_rad_s: [f32; 3],
    _math: PhantomData<fn() -> M>,
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn finite3(v: [f32; 3]) -> bool {
    v[0].is_finite() && v[1].is_finite() && v[2].is_finite()
}

impl<M: Math> Estimator<M> {
    /// An estimator at the level attitude with no bias.
    pub const fn new(gains: Gains) -> Self {
        Estimator {
            gains,
            up: [0.0, 0.0, 1.0],
            bias_rad_s: [0.0; 3],
            _math: PhantomData,
        }
    }

    /// Starts from a measured state: the up vector from a (mean) accelerometer reading, and a
    /// gyro bias measured at rest. A zero or non-finite accelerometer reading keeps the level
    /// attitude; a non-finite bias keeps zero; the bias is held within
    /// [`Gains::max_bias_rad_s`].
    pub fn reset(&mut self, accel_m_s2: [f32; 3], bias_rad_s: [f32; 3]) {
        self.up = [0.0, 0.0, 1.0];
        let n2 = dot(accel_m_s2, accel_m_s2);
        if finite3(accel_m_s2) && n2 > 1e-6 && n2.is_finite() {
            let inv = 1.0 / M::sqrt(n2);
            self.up = [
                accel_m_s2[0] * inv,
                accel_m_s2[1] * inv,
                accel_m_s2[2] * inv,
            ];
        }
        self.bias_rad_s = [0.0; 3];
        if finite3(bias_rad_s) {
            let m = self.gains.max_bias_rad_s;
            self.bias_rad_s = bias_rad_s.map(|b| b.clamp(-m, m));
        }
    }

    /// One sample: the gyro's rates and the accelerometer's specific force (body frame, SI)
    /// after `dt_s` seconds. A sample with a non-finite rate, or a `dt_s` that is not finite and
    /// positive, changes nothing; an accelerometer reading outside
    /// [`Gains::accel_reject_share`], or taken at a rate beyond [`Gains::rate_reject_rad_s`]
    /// (module docs), does not correct. Returns true when the accelerometer corrected the
    /// estimate.
    pub fn update(&mut self, gyro_rad_s: [f32; 3], accel_m_s2: [f32; 3], dt_s: f32) -> bool {
        if !(finite3(gyro_rad_s) && dt_s > 0.0 && dt_s.is_finite()) {
            return false;
        }
        let Gains {
            kp_per_s,
            ki_per_s2,
            accel_trust_share: trust,
            accel_reject_share: reject,
            rate_trust_rad_s,
            rate_reject_rad_s,
            max_bias_rad_s,
        } = self.gains;
        let mut omega = [
            gyro_rad_s[0] - self.bias_rad_s[0],
            gyro_rad_s[1] - self.bias_rad_s[1],
            gyro_rad_s[2] - self.bias_rad_s[2],
        ];
        let n2 = dot(accel_m_s2, accel_m_s2);
        let g2 = G_M_S2 * G_M_S2;
        let (lo, hi) = (1.0 - reject, 1.0 + reject);
        // |a| short of the rejecting share, compared squared (no square root for a rejected
        // sample).
        let w2 = dot(omega, omega);
        let trusted = finite3(accel_m_s2)
            && n2 > lo * lo * g2
            && n2 < hi * hi * g2
            && w2 < rate_reject_rad_s * rate_reject_rad_s;
        if trusted {
            let off = (M::sqrt(n2) * (1.0 / G_M_S2) - 1.0).abs();
            // Valenti et al. 2015's adaptive gain: full weight within `trust`, linearly to 0 at
            // `reject`.
            let mut weight = if off <= trust {
                1.0
            } else {
                (reject - off) / (reject - trust)
            };
            // The same on the rate (no square root below `rate_trust_rad_s`).
            if w2 > rate_trust_rad_s * rate_trust_rad_s {
                weight *=
                    (rate_reject_rad_s - M::sqrt(w2)) / (rate_reject_rad_s - rate_trust_rad_s);
            }
            // The correction linear in the reading (module docs): a/g, not a/|a|.
            let k = weight * (1.0 / G_M_S2);
            let measured = accel_m_s2.map(|a| a * k);
            // Mahony eq. 32: the error rotates the estimate toward the measurement.
            let e = cross(measured, self.up);
            for i in 0..3 {
                let b = self.bias_rad_s[i] - ki_per_s2 * e[i] * dt_s;
                self.bias_rad_s[i] = b.clamp(-max_bias_rad_s, max_bias_rad_s);
                omega[i] += kp_per_s * e[i];
            }
        }
        // v̇ = v × ω for a world-fixed vector seen from a body turning at ω.
        let d = cross(self.up, omega);
        let v = [
            self.up[0] + d[0] * dt_s,
            self.up[1] + d[1] * dt_s,
            self.up[2] + d[2] * dt_s,
        ];
        // One Newton step toward unit length (module docs); a large step (a huge rate) is
        // renormalised exactly instead.
        let n2 = dot(v, v);
        let scale = if (0.5..2.0).contains(&n2) {
            0.5 * (3.0 - n2)
        } else if n2 > 0.0 && n2.is_finite() {
            1.0 / M::sqrt(n2)
        } else {
            return trusted;
        };
        self.up = v.map(|x| x * scale);
        trusted
    }

    /// The world's up in the body frame (unit vector).
    pub fn up(&self) -> [f32; 3] {
        self.up
    }

    /// The gyro bias estimate, rad/s.
    pub fn bias_rad_s(&self) -> [f32; 3] {
        self.bias_rad_s
    }

    /// Roll and pitch (module docs); finite for every state.
    pub fn attitude(&self) -> Attitude {
        let [x, y, z] = self.up;
        let yz = M::sqrt(y * y + z * z);
        Attitude {
            roll_rad: M::atan2(y, z),
            pitch_rad: M::atan2(-x, yz),
        }
    }

    /// The tilt of the body from upright, as the cosine of the angle between its z axis and
    /// the world's up (1 upright, 0 on its side, −1 upside down): no arctangent, for a cheap
    /// per-sample threshold.
    pub fn cos_tilt(&self) -> f32 {
        self.up[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{DefaultMath, Libm, SoftFloat};

    #[test]
    fn level_and_still_reads_zero() {
        let mut e = Estimator::<DefaultMath>::new(Gains::DEFAULT);
        for _ in 0..100 {
            e.update([0.0; 3], [0.0, 0.0, G_M_S2], 0.01);
        }
        let a = e.attitude();
        assert!(a.roll_rad.abs() < 1e-6 && a.pitch_rad.abs() < 1e-6, "{a:?}");
    }

    #[test]
    fn reset_takes_the_accelerometer_direction() {
        let mut e = Estimator::<SoftFloat>::new(Gains::DEFAULT);
        let (r, p) = (0.3f32, -0.2f32);
        let up = [-p.sin(), r.sin() * p.cos(), r.cos() * p.cos()];
        e.reset(up.map(|x| x * G_M_S2), [0.01, -0.02, 0.0]);
        let a = e.attitude();
        assert!((a.roll_rad - r).abs() < 1e-4 && (a.pitch_rad - p).abs() < 1e-4);
        assert_eq!(e.bias_rad_s(), [0.01, -0.02, 0.0]);
    }

    #[test]
    fn non_finite_input_changes_nothing() {
        let mut e = Estimator::<Libm>::new(Gains::DEFAULT);
        let before = e.up();
        assert!(!e.update([f32::NAN, 0.0, 0.0], [0.0, 0.0, G_M_S2], 0.01));
        assert!(!e.update([0.0; 3], [0.0, 0.0, G_M_S2], f32::NAN));
        assert!(!e.update([0.0; 3], [0.0, 0.0, G_M_S2], 0.0));
        assert!(!e.update([0.0; 3], [f32::INFINITY, 0.0, 0.0], 0.01));
        assert_eq!(e.up(), before);
    }
}
