//! The joint-speed limiter every output of the device passes.

use super::{Error, FRAME_S};
use kin_core::motion;

/// Default joint-speed limit, rad/s: half of an MG996R-class servo's no-load speed
/// (0.17 s/60° ≈ 6.2 rad/s at 4.8 V, kin-core's
/// [`DEFAULT_MAX_JOINT_SPEED_RAD_S`](kin_core::preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S)). A
/// servo that carries the body is slower than its no-load figure; at half of it a loaded servo
/// still follows its setpoint, so the commanded pose stays the real one and the servo's own
/// controller never runs at full current against a step. 0.06 rad (3.4°) per 20 ms frame.
pub const DEFAULT_JOINT_SPEED_LIMIT_RAD_S: f32 = 3.0;

/// The share of a servo's no-load speed that the limiter allows: the rule behind
/// [`DEFAULT_JOINT_SPEED_LIMIT_RAD_S`] (for MG996R-class servos), for other servos.
pub const NO_LOAD_SPEED_SHARE: f32 = 0.5;

/// The joint-speed limit, rad/s, for servos whose no-load speed is `no_load_speed_rad_s`:
/// [`NO_LOAD_SPEED_SHARE`] of it (what `SetJointSpeedLimit` or
/// [`crate::Config::joint_speed_limit_rad_s`] should be set to for such servos).
pub fn limit_for_servo(no_load_speed_rad_s: f32) -> f32 {
    NO_LOAD_SPEED_SHARE * no_load_speed_rad_s
}

/// Moves each of twelve outputs toward its target by at most `limit · frame` per frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limiter {
    speed_rad_s: f32,
    max_step_rad: f32,
}

impl Limiter {
    /// A limiter of `speed_rad_s` (finite, > 0) per joint.
    ///
    /// # Errors
    /// [`Error::Parameter`] naming `joint_speed_limit_rad_s`.
    pub const fn new(speed_rad_s: f32) -> Result<Limiter, Error> {
        if !speed_rad_s.is_finite() {
            return Err(Error::Parameter(motion::Error::NonFinite(
                motion::Param::JointSpeedLimitRadS,
            )));
        }
        if !(speed_rad_s > 0.0) {
            return Err(Error::Parameter(motion::Error::NotPositive(
                motion::Param::JointSpeedLimitRadS,
            )));
        }
        Ok(Limiter {
            speed_rad_s,
            max_step_rad: speed_rad_s * FRAME_S,
        })
    }

    /// The limit, rad/s.
    pub const fn speed_rad_s(&self) -> f32 {
        self.speed_rad_s
    }

    /// The largest change of one output in one frame, rad.
    pub const fn max_step_rad(&self) -> f32 {
        self.max_step_rad
    }

    /// One frame: each of `out` moves to its `target` when that is within
    /// [`Limiter::max_step_rad`], else by exactly that much toward it. True when some output
    /// changed (the caller then writes them), in place: no copy of the twelve outputs to
    /// compare.
    pub fn step(&self, out: &mut [f32; 12], target: &[f32; 12]) -> bool {
        const ABS: u32 = 0x7fff_ffff;
        const INF_BITS: u32 = 0x7f80_0000;
        let b = self.max_step_rad;
        let mut changed = false;
        for (o, &t) in out.iter_mut().zip(target) {
            let d = t - *o;
            // `d > b` and `d < −b` for the bound `b > 0` by the magnitude's bits and the sign
            // (a NaN `d` fails both, as the float comparisons it stands for): no software-float
            // comparison calls on CPUs without floating-point hardware, twelve per servo frame.
            let m = d.to_bits() & ABS;
            let beyond = m > b.to_bits() && m <= INF_BITS;
            if beyond && d.to_bits() == m {
                *o += b;
                changed = true;
            } else if beyond {
                *o -= b;
                changed = true;
            } else if o.to_bits() != t.to_bits() {
                *o = t;
                changed = true;
            }
        }
        changed
    }
}

/// A straight line in joint space from `from` to `to` in whole frames, no joint moving more
/// than one limiter step per frame: all joints start and arrive together (a synchronised ramp),
/// and every point lies between the two ends, so within any joint limits and servo travel that
/// admit both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    from: [f32; 12],
    to: [f32; 12],
    frames: u32,
    done: u32,
}

impl Ramp {
    /// A finished ramp at the zero angles (an idle engine's).
    pub const fn idle() -> Ramp {
        Ramp {
            from: [0.0; 12],
            to: [0.0; 12],
            frames: 0,
            done: 0,
        }
    }

    /// A ramp at `limiter`'s speed.
    pub fn new(from: [f32; 12], to: [f32; 12], limiter: &Limiter) -> Ramp {
        let mut ramp = Ramp::idle();
        ramp.restart(&from, &to, limiter);
        ramp
    }

    /// Makes this the ramp [`Ramp::new`] builds, in place (no copy of a ramp on the way).
    pub fn restart(&mut self, from: &[f32; 12], to: &[f32; 12], limiter: &Limiter) {
        // `f32::max` by comparison, NaN skipped as `max` does: `max` links a libm routine on
        // the AVR.
        let mut widest = 0.0f32;
        for (a, b) in from.iter().zip(to) {
            let d = libm::fabsf(b - a);
            if d > widest {
                widest = d;
            }
        }
        // Non-finite input cannot occur (the ends are validated angles); 0 frames if it did.
        let frames = frame_count(kin_core::math::ceil(widest / limiter.max_step_rad()));
        self.from = *from;
        self.to = *to;
        self.frames = frames;
        self.done = 0;
    }

    /// Advances one frame and returns the new point (`to` exactly at the end).
    pub fn advance(&mut self) -> [f32; 12] {
        if self.done < self.frames {
            self.done += 1;
        }
        self.point()
    }

    /// The current point.
    pub fn point(&self) -> [f32; 12] {
        // One copy, of `to`, for both branches: each array copy is a call on the AVR.
        let mut p = self.to;
        if self.done < self.frames {
            let s = self.done as f32 / self.frames as f32;
            for (p, &a) in p.iter_mut().zip(&self.from) {
                *p = a + (*p - a) * s;
            }
        }
        p
    }

    /// Steps taken so far ([`Ramp::advance`] calls that moved; 0 after a restart).
    pub const fn steps_done(&self) -> u32 {
        self.done
    }

    /// True once the end is reached.
    pub fn finished(&self) -> bool {
        self.done >= self.frames
    }

    /// The end point.
    pub const fn to(&self) -> &[f32; 12] {
        &self.to
    }
}

/// A ramp's frame count from its whole number of frames: 0 unless finite and positive.
fn frame_count(frames: f32) -> u32 {
    // NaN fails the comparison, and the cast takes every negative to 0.
    if frames < f32::INFINITY {
        frames as u32
    } else {
        0
    }
}

#[cfg(test)]
mod tests {

    /// [`Limiter::step`] with the float comparisons it stands for.
    fn step_float_form(b: f32, out: &mut [f32; 12], target: &[f32; 12]) -> bool {
        let mut changed = false;
        for (o, &t) in out.iter_mut().zip(target) {
            let d = t - *o;
            if d > b {
                *o += b;
                changed = true;
            } else if d < -b {
                *o -= b;
                changed = true;
            } else if o.to_bits() != t.to_bits() {
                *o = t;
                changed = true;
            }
        }
        changed
    }

    /// The bit-pattern comparisons move every output as the float comparisons do, bit for
    /// bit: random and edge outputs and targets (zeros of both signs, steps of exactly the
    /// bound, infinities, NaN).
    #[test]
    fn step_equals_the_float_form() {
        let mut rng = seeded_rng::SplitMix64::new(5);
        let edge = [
            0.0,
            -0.0,
            0.06,
            -0.06,
            0.06 + 1e-7,
            1.0,
            -3.0,
            f32::INFINITY,
            f32::NAN,
        ];
        for case in 0..20_000 {
            let limiter = Limiter::new(rng.range(0.1, 20.0) as f32).unwrap();
            let b = limiter.max_step_rad();
            let pick = |rng: &mut seeded_rng::SplitMix64| {
                if case % 3 == 0 {
                    edge[(rng.next_u64() % edge.len() as u64) as usize]
                } else {
                    rng.range(-0.5, 0.5) as f32
                }
            };
            let out: [f32; 12] = core::array::from_fn(|_| pick(&mut rng));
            let mut target: [f32; 12] = core::array::from_fn(|_| pick(&mut rng));
            // Steps of exactly ±b.
            target[0] = out[0] + b;
            target[1] = out[1] - b;
            let (mut a, mut f) = (out, out);
            let changed = limiter.step(&mut a, &target);
            let changed_float = step_float_form(b, &mut f, &target);
            assert_eq!(changed, changed_float, "{out:?} → {target:?}");
            assert_eq!(
                a.map(f32::to_bits),
                f.map(f32::to_bits),
                "{out:?} → {target:?}"
            );
        }
    }

    use super::{frame_count, Limiter, Ramp};

    #[test]
    fn a_nan_joint_does_not_set_the_ramp_length() {
        let limiter = Limiter::new(3.0).unwrap();
        let mut to = [0.0; 12];
        to[0] = 0.3;
        to[1] = f32::NAN;
        to[2] = -0.2;
        let frames = |to: [f32; 12]| {
            let mut ramp = Ramp::new([0.0; 12], to, &limiter);
            let mut frames = 0;
            while !ramp.finished() {
                ramp.advance();
                frames += 1;
            }
            frames
        };
        let mut finite = to;
        finite[1] = 0.0;
        // As `f32::max` would: the NaN skipped, the widest finite change sets the length.
        assert!(frames(finite) > 1);
        assert_eq!(frames(to), frames(finite));
    }

    #[test]
    fn frame_count_is_zero_unless_finite_and_positive() {
        for x in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -1.0,
            -0.0,
            0.0,
            1.0,
            3.0,
            1e9,
            1e12,
        ] {
            let reference = if x.is_finite() && x > 0.0 {
                x as u32
            } else {
                0
            };
            assert_eq!(frame_count(x), reference, "{x}");
        }
    }
}
