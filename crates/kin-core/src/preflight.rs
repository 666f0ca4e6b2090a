//! Preflight: sweep a motion (or a recorded sequence of joint angles) and report, per leg and
//! overall, whether the robot can do it and how close it comes to its limits.
//!
//! Per leg, over all samples:
//! - **reachability**: the samples the IK refuses, with the first one (time, leg, kind);
//! - **workspace margin** (m): the distance of the foot target to the nearest workspace
//!   boundary, `min(L1 + L2 − r, r − |L1 − L2|, r_yz − d_lat)` with `r` the hip-joint-to-foot
//!   distance in the leg plane and `r_yz` the foot's distance from the abduction axis (see
//!   [`workspace_margin`]); negative when out of reach;
//! - **joint-limit margin** (rad): [`JointLimits::margin`](crate::JointLimits::margin) of the
//!   tightest joint; negative when a limit is exceeded;
//! - **singularity measure**: [`jacobian::leg_inverse_condition`], of the leg Jacobian (1 =
//!   isotropic, 0 = singular), failing below [`SINGULARITY_THRESHOLD`];
//! - **joint speed** (rad/s): finite differences between consecutive samples, against a per-joint
//!   limit.
//!
//! Overall, when the checker has the robot's masses ([`Checker::with_mass`], [`check_with_mass`]):
//! - **static stability margin** (m): [`stability::frame_margin`] of every frame whose four legs
//!   solve, its minimum and when it happens (≤ 0: the centre of mass is not inside the support
//!   polygon of the feet in stance; reported, not counted as a failure).
//!
//! No allocation: the [`Report`] has fixed arrays. [`check`] sweeps a [`Motion`]; a [`Checker`]
//! takes samples one at a time (frames or joint angles) for callers that stream them.

use crate::body::{self, BodyConfig};
use crate::jacobian::{self, SINGULARITY_THRESHOLD};
use crate::leg::{self, Unreachable};
use crate::math::wrap_pi;
use crate::motion::{finite, positive, Error, Expected, Frame, Motion, Param};
use crate::robot::{Joint, JointAngles, JointLimits, LegId, Robot};
use crate::stability::{self, MassModel};
use crate::vec::Vec3;
use crate::ReachPolicy;

/// Default per-joint speed limit, rad/s (about a standard hobby servo's no-load speed, 60° in
/// 0.17 s).
pub const DEFAULT_MAX_JOINT_SPEED_RAD_S: f32 = 6.0;

/// Most samples a [`Sweep`] may have: the sample index must stay exact in f32 (2²⁴).
pub const MAX_SWEEP_SAMPLES: u32 = 1 << 24;

/// Times at which a motion is sampled: `start + k/rate` for `k = 0 ..= ⌊duration·rate⌋`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sweep {
    start_s: f32,
    duration_s: f32,
    rate_hz: f32,
    samples: u32,
}

impl Sweep {
    /// Validates: `start_s` finite, `duration_s ≥ 0`, `rate_hz > 0`, at most
    /// [`MAX_SWEEP_SAMPLES`] samples.
    pub fn new(start_s: f32, duration_s: f32, rate_hz: f32) -> Result<Sweep, Error> {
        finite(start_s, Param::StartS)?;
        if !(finite(duration_s, Param::DurationS)? >= 0.0) {
            return Err(Error::Negative(Param::DurationS));
        }
        positive(rate_hz, Param::RateHz)?;
        // The small allowance absorbs rounding of products such as 0.3 s × 10 Hz.
        let n = crate::math::floor(duration_s * rate_hz + 1e-3) + 1.0;
        if !(n <= MAX_SWEEP_SAMPLES as f32) {
            return Err(Error::OutOfRange {
                parameter: Param::DurationS,
                expected: Expected::SweepSamples,
            });
        }
        Ok(Sweep {
            start_s,
            duration_s,
            rate_hz,
            samples: n as u32,
        })
    }

    /// Number of samples.
    pub const fn samples(&self) -> u32 {
        self.samples
    }

    /// Time of sample `k`, s.
    pub fn time_s(&self, k: u32) -> f32 {
        self.start_s + k as f32 / self.rate_hz
    }

    /// Start time, s.
    pub const fn start_s(&self) -> f32 {
        self.start_s
    }

    /// Duration, s.
    pub const fn duration_s(&self) -> f32 {
        self.duration_s
    }

    /// Sampling rate, Hz.
    pub const fn rate_hz(&self) -> f32 {
        self.rate_hz
    }
}

/// Which workspace boundary a foot is nearest to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Boundary {
    /// The outer sphere of the leg plane, `r = L1 + L2` (leg stretched).
    Far,
    /// The inner sphere, `r = |L1 − L2|` (leg folded).
    Near,
    /// The cylinder of radius `d_lat` around the abduction axis.
    Offset,
}

impl Boundary {
    /// `far`, `near` or `offset`.
    pub const fn name(self) -> &'static str {
        match self {
            Boundary::Far => "far",
            Boundary::Near => "near",
            Boundary::Offset => "offset",
        }
    }
}

/// Distance (m) of `foot_in_hip` to the nearest boundary of the leg's workspace (ignoring joint
/// limits), and which boundary: `min(L1 + L2 − r, r − |L1 − L2|, r_yz − d_lat)`, where
/// `r_yz = √(y² + z²)`, `w = −√(r_yz² − d_lat²)` and `r = √(x² + (w + d_ax)²)`. Negative outside.
/// `None` for a non-finite foot.
pub fn workspace_margin(robot: &Robot, foot_in_hip: Vec3) -> Option<(f32, Boundary)> {
    if !foot_in_hip.is_finite() {
        return None;
    }
    let g = &robot.leg;
    let Vec3 { x, y, z } = foot_in_hip;
    let r_yz2 = y * y + z * z;
    let r_yz = libm::sqrtf(r_yz2);
    let w2 = r_yz2 - g.d_lat_m * g.d_lat_m;
    let w = -libm::sqrtf(if w2 > 0.0 { w2 } else { 0.0 });
    let v = w + g.d_ax_m;
    let r = libm::sqrtf(x * x + v * v);
    let far = g.femur_m + g.tibia_m - r;
    let near = r - libm::fabsf(g.femur_m - g.tibia_m);
    let offset = r_yz - g.d_lat_m;
    let mut best = (far, Boundary::Far);
    if near < best.0 {
        best = (near, Boundary::Near);
    }
    if offset < best.0 {
        best = (offset, Boundary::Offset);
    }
    Some(best)
}

/// A value and the time at which it occurred.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Extremum {
    /// The value (unit per field).
    pub value: f32,
    /// When, s.
    pub t_s: f32,
}

/// Keeps the smaller (`min = true`) or larger value.
fn update(slot: &mut Option<Extremum>, value: f32, t_s: f32, min: bool) -> bool {
    let better = match slot {
        None => true,
        Some(e) => {
            if min {
                value < e.value
            } else {
                value > e.value
            }
        }
    };
    if better {
        *slot = Some(Extremum { value, t_s });
    }
    better
}

/// What failed at a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FailureKind {
    /// The IK refused the foot target (outside the workspace, or a joint limit).
    Unreachable(Unreachable),
    /// The inverse condition number fell below [`SINGULARITY_THRESHOLD`].
    Singular {
        /// The inverse condition number found.
        inverse_condition: f32,
    },
    /// A joint moved faster than its limit.
    JointSpeed {
        /// The joint.
        joint: Joint,
        /// Its speed, rad/s.
        speed_rad_s: f32,
    },
}

impl core::fmt::Display for FailureKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FailureKind::Unreachable(u) => write!(f, "{u}"),
            FailureKind::Singular { inverse_condition } => {
                write!(f, "singular (inverse condition {inverse_condition:.4})")
            }
            FailureKind::JointSpeed { joint, speed_rad_s } => {
                write!(f, "{joint} speed {speed_rad_s:.3} rad/s")
            }
        }
    }
}

/// A failing sample.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Failure {
    /// Sample index (0-based).
    pub sample: u32,
    /// Sample time, s.
    pub t_s: f32,
    /// The leg.
    pub leg: LegId,
    /// What failed.
    pub kind: FailureKind,
}

/// Figures of one leg over a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LegReport {
    /// The leg.
    pub leg: LegId,
    /// Samples at which this leg failed (any [`FailureKind`]).
    pub failures: u32,
    /// The first of them.
    pub first_failure: Option<Failure>,
    /// Minimum workspace margin, m ([`workspace_margin`]).
    pub workspace_margin_m: Option<Extremum>,
    /// The boundary at that minimum.
    pub workspace_boundary: Option<Boundary>,
    /// Minimum joint-limit margin over the three joints, rad.
    pub joint_margin_rad: Option<Extremum>,
    /// The joint at that minimum.
    pub joint_margin_joint: Option<Joint>,
    /// Minimum inverse condition number of the leg Jacobian.
    pub inverse_condition: Option<Extremum>,
    /// Maximum |joint speed| per joint `[abduction, hip, knee]`, rad/s.
    pub joint_speed_rad_s: [Option<Extremum>; 3],
}

impl LegReport {
    const fn empty(leg: LegId) -> LegReport {
        LegReport {
            leg,
            failures: 0,
            first_failure: None,
            workspace_margin_m: None,
            workspace_boundary: None,
            joint_margin_rad: None,
            joint_margin_joint: None,
            inverse_condition: None,
            joint_speed_rad_s: [None; 3],
        }
    }
}

/// The preflight report.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Report {
    /// Samples checked.
    pub samples: u32,
    /// (sample, leg) pairs that failed.
    pub failures: u32,
    /// The earliest failure (lowest sample, then leg order FL, FR, RL, RR).
    pub first_failure: Option<Failure>,
    /// Per-leg figures, order FL, FR, RL, RR.
    pub legs: [LegReport; 4],
    /// The per-joint speed limits used, rad/s.
    pub max_joint_speed_limit_rad_s: [f32; 3],
    /// The singularity threshold used ([`SINGULARITY_THRESHOLD`]).
    pub singularity_threshold: f32,
    /// Minimum static stability margin (m) and its time, over the frames whose four legs
    /// solve ([`stability::frame_margin`]); `None` without a mass model or such a frame.
    pub static_margin_m: Option<Extremum>,
}

/// Smallest (or largest) of the legs' extrema, with its leg.
fn over_legs(
    legs: &[LegReport; 4],
    get: impl Fn(&LegReport) -> Option<Extremum>,
    min: bool,
) -> Option<(LegId, Extremum)> {
    let mut best: Option<(LegId, Extremum)> = None;
    for l in legs {
        if let Some(e) = get(l) {
            let better = match best {
                None => true,
                Some((_, b)) => {
                    if min {
                        e.value < b.value
                    } else {
                        e.value > b.value
                    }
                }
            };
            if better {
                best = Some((l.leg, e));
            }
        }
    }
    best
}

impl Report {
    /// True when no sample failed.
    pub const fn ok(&self) -> bool {
        self.failures == 0
    }

    /// Overall minimum workspace margin (m) and its leg.
    pub fn min_workspace_margin(&self) -> Option<(LegId, Extremum)> {
        over_legs(&self.legs, |l| l.workspace_margin_m, true)
    }

    /// Overall minimum joint-limit margin (rad) and its leg.
    pub fn min_joint_margin(&self) -> Option<(LegId, Extremum)> {
        over_legs(&self.legs, |l| l.joint_margin_rad, true)
    }

    /// Overall minimum singularity measure and its leg.
    pub fn min_inverse_condition(&self) -> Option<(LegId, Extremum)> {
        over_legs(&self.legs, |l| l.inverse_condition, true)
    }

    /// Overall maximum speed of `joint` (rad/s) and its leg.
    pub fn max_joint_speed(&self, joint: Joint) -> Option<(LegId, Extremum)> {
        over_legs(&self.legs, |l| l.joint_speed_rad_s[joint as usize], false)
    }
}

/// Incremental preflight: push samples in time order, then [`Checker::finish`].
#[derive(Debug, Clone, Copy)]
pub struct Checker {
    robot: Robot,
    geometric: Robot,
    config: BodyConfig,
    mass: Option<MassModel>,
    max_speed: [f32; 3],
    prev: [Option<(f32, JointAngles)>; 4],
    report: Report,
}

impl Checker {
    /// A checker for `robot` with poses read in `config`, and per-joint speed limits
    /// `max_joint_speed_rad_s` (each > 0).
    pub fn new(
        robot: &Robot,
        config: BodyConfig,
        max_joint_speed_rad_s: [f32; 3],
    ) -> Result<Checker, Error> {
        robot.validate()?;
        for v in max_joint_speed_rad_s {
            positive(v, Param::MaxJointSpeedRadS)?;
        }
        let mut geometric = *robot;
        geometric.limits = JointLimits::FULL_TURN;
        Ok(Checker {
            robot: *robot,
            geometric,
            config,
            mass: None,
            max_speed: max_joint_speed_rad_s,
            prev: [None; 4],
            report: Report {
                samples: 0,
                failures: 0,
                first_failure: None,
                legs: LegId::ALL.map(LegReport::empty),
                max_joint_speed_limit_rad_s: max_joint_speed_rad_s,
                singularity_threshold: SINGULARITY_THRESHOLD,
                static_margin_m: None,
            },
        })
    }

    /// The same checker reporting the static stability margin of every frame with the masses
    /// `mass` ([`Report::static_margin_m`]).
    pub fn with_mass(mut self, mass: &MassModel) -> Result<Checker, Error> {
        mass.validate(&self.robot)?;
        self.mass = Some(*mass);
        Ok(self)
    }

    /// Checks one frame (body pose + feet in the world) at `t_s`: solves each leg and records
    /// its figures. Returns each leg's angles, or why it cannot reach (a joint-limit violation
    /// is reported as [`Unreachable::JointLimit`]).
    pub fn push_frame(&mut self, t_s: f32, frame: &Frame) -> [Result<JointAngles, Unreachable>; 4] {
        let sample = self.report.samples;
        self.report.samples = sample.saturating_add(1);
        let mut out = [Err(Unreachable::NonFinite); 4];
        let finite_input = t_s.is_finite() && frame.pose.is_finite();
        let local = body::Solver::new(&self.robot).feet_in_hips(
            &frame.pose,
            &self.config,
            &frame.feet_in_world,
        );
        for leg in LegId::ALL {
            let i = leg.index();
            let mut failure: Option<FailureKind> = None;
            if let Some((m, b)) = workspace_margin(&self.robot, local[i]).filter(|_| finite_input) {
                let l = &mut self.report.legs[i];
                if update(&mut l.workspace_margin_m, m, t_s, true) {
                    l.workspace_boundary = Some(b);
                }
            }
            let solved = if finite_input {
                leg::Solver::new(&self.geometric)
                    .inverse(leg, local[i], ReachPolicy::Reject)
                    .map(|s| s.angles)
                    .map_err(|e| e.kind)
            } else {
                Err(Unreachable::NonFinite)
            };
            match solved {
                Ok(q) => {
                    failure = self.angles_metrics(leg, t_s, q);
                    out[i] = match failure {
                        Some(FailureKind::Unreachable(u)) => Err(u),
                        _ => Ok(q),
                    };
                }
                Err(kind) => {
                    self.prev[i] = None;
                    failure.get_or_insert(FailureKind::Unreachable(kind));
                    out[i] = Err(kind);
                }
            }
            if let Some(kind) = failure {
                self.record(sample, t_s, leg, kind);
            }
        }
        if let (Some(mass), [Ok(a), Ok(b), Ok(c), Ok(d)]) = (&self.mass, out) {
            let margin = stability::frame_margin::<crate::DefaultMath>(
                &self.robot,
                mass,
                &self.config,
                frame,
                &[a, b, c, d],
            );
            update(&mut self.report.static_margin_m, margin, t_s, true);
        }
        out
    }

    /// Checks one sample of joint angles at `t_s` (e.g. read from a file), order FL, FR, RL, RR.
    /// The workspace margin is that of the feet the angles reach.
    pub fn push_angles(&mut self, t_s: f32, angles: &[JointAngles; 4]) {
        let sample = self.report.samples;
        self.report.samples = sample.saturating_add(1);
        for leg in LegId::ALL {
            let i = leg.index();
            let q = angles[i];
            if !(q.is_finite() && t_s.is_finite()) {
                self.prev[i] = None;
                self.record(
                    sample,
                    t_s,
                    leg,
                    FailureKind::Unreachable(Unreachable::NonFinite),
                );
                continue;
            }
            let foot = leg::forward(&self.robot.leg, leg, q);
            if let Some((m, b)) = workspace_margin(&self.robot, foot) {
                let l = &mut self.report.legs[i];
                if update(&mut l.workspace_margin_m, m, t_s, true) {
                    l.workspace_boundary = Some(b);
                }
            }
            if let Some(kind) = self.angles_metrics(leg, t_s, q) {
                self.record(sample, t_s, leg, kind);
            }
        }
    }

    /// Records a sample at `t_s` in which the listed legs could not reach (e.g. a recorded
    /// sample whose status says so); the other legs' figures are left as they are.
    pub fn push_unreachable(&mut self, t_s: f32, legs: &[(LegId, Unreachable)]) {
        let sample = self.report.samples;
        self.report.samples = sample.saturating_add(1);
        for &(leg, kind) in legs {
            self.prev[leg.index()] = None;
            self.record(sample, t_s, leg, FailureKind::Unreachable(kind));
        }
    }

    /// Joint margin, singularity and speed of one leg; the first failure among them.
    fn angles_metrics(&mut self, leg: LegId, t_s: f32, q: JointAngles) -> Option<FailureKind> {
        let i = leg.index();
        let mut failure = None;
        let limits = &self.robot.limits;
        let l = &mut self.report.legs[i];
        let mut tight = (f32::INFINITY, Joint::Abduction);
        for j in Joint::ALL {
            let m = limits.margin(j, q.get(j));
            if m < tight.0 {
                tight = (m, j);
            }
        }
        if update(&mut l.joint_margin_rad, tight.0, t_s, true) {
            l.joint_margin_joint = Some(tight.1);
        }
        if tight.0 < 0.0 {
            failure = Some(FailureKind::Unreachable(Unreachable::JointLimit(tight.1)));
        }
        let ic = jacobian::leg_inverse_condition(&self.robot.leg, leg, q);
        let ic = if ic.is_finite() { ic } else { 0.0 };
        update(&mut l.inverse_condition, ic, t_s, true);
        if ic < SINGULARITY_THRESHOLD {
            failure.get_or_insert(FailureKind::Singular {
                inverse_condition: ic,
            });
        }
        if let Some((t0, q0)) = self.prev[i] {
            let dt = t_s - t0;
            if dt > 0.0 {
                for j in Joint::ALL {
                    let speed = libm::fabsf(wrap_pi(q.get(j) - q0.get(j))) / dt;
                    update(&mut l.joint_speed_rad_s[j as usize], speed, t_s, false);
                    if speed > self.max_speed[j as usize] {
                        failure.get_or_insert(FailureKind::JointSpeed {
                            joint: j,
                            speed_rad_s: speed,
                        });
                    }
                }
            }
        }
        self.prev[i] = Some((t_s, q));
        failure
    }

    fn record(&mut self, sample: u32, t_s: f32, leg: LegId, kind: FailureKind) {
        let f = Failure {
            sample,
            t_s,
            leg,
            kind,
        };
        let l = &mut self.report.legs[leg.index()];
        l.failures = l.failures.saturating_add(1);
        l.first_failure.get_or_insert(f);
        self.report.failures = self.report.failures.saturating_add(1);
        self.report.first_failure.get_or_insert(f);
    }

    /// The report so far.
    pub const fn report(&self) -> &Report {
        &self.report
    }

    /// The final report.
    pub const fn finish(self) -> Report {
        self.report
    }
}

/// [`check`] with the static stability margin of every frame, for the masses `mass`
/// ([`Report::static_margin_m`]).
pub fn check_with_mass<T: Motion>(
    motion: &T,
    sweep: &Sweep,
    max_joint_speed_rad_s: [f32; 3],
    mass: &MassModel,
) -> Result<Report, Error> {
    let mut c = Checker::new(motion.robot(), motion.body_config(), max_joint_speed_rad_s)?
        .with_mass(mass)?;
    for k in 0..sweep.samples() {
        let t = sweep.time_s(k);
        let frame = motion.frame::<crate::DefaultMath>(t)?;
        let _ = c.push_frame(t, &frame);
    }
    Ok(c.finish())
}

/// Sweeps `motion` over `sweep` with per-joint speed limits `max_joint_speed_rad_s`.
pub fn check<T: Motion>(
    motion: &T,
    sweep: &Sweep,
    max_joint_speed_rad_s: [f32; 3],
) -> Result<Report, Error> {
    let mut c = Checker::new(motion.robot(), motion.body_config(), max_joint_speed_rad_s)?;
    for k in 0..sweep.samples() {
        let t = sweep.time_s(k);
        let frame = motion.frame::<crate::DefaultMath>(t)?;
        let _ = c.push_frame(t, &frame);
    }
    Ok(c.finish())
}
