//! The preflight report of a motion CSV or of a motion law (`kin_core::preflight`): the
//! operation behind `quadctl check`.

use super::motion::{self, param_err, Law, Params, Progress};
use crate::csv::motion::MotionCsv;
use crate::{csv, robot_file};
use kin_core::leg::Unreachable;
use kin_core::motion::{Contact, Frame, Motion};
use kin_core::preflight::{Checker, Extremum, Report};
use kin_core::{BodyConfig, DefaultMath, Joint, JointAngles, LegId, RotationOrder};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Errors of a check: those of the motion operations, and a status cell that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Building the law, the robot, reading the CSV.
    #[error(transparent)]
    Motion(#[from] motion::Error),
    /// A row without angles, feet and pose whose status does not name the leg and reason.
    #[error(
        "{input}:{line}: status `{status}` without angles, feet and pose: expected \
         `<leg>:<reason>` (too_far, too_close, inside_offset, non_finite, joint_limit (<joint>))"
    )]
    Status {
        /// Input name.
        input: String,
        /// 1-based line.
        line: usize,
        /// The status found.
        status: String,
    },
}

impl From<csv::Error> for Error {
    fn from(e: csv::Error) -> Self {
        Error::Motion(e.into())
    }
}

impl From<robot_file::Error> for Error {
    fn from(e: robot_file::Error) -> Self {
        Error::Motion(e.into())
    }
}

/// What to check.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A motion CSV (`-`: stdin).
    File(PathBuf),
    /// A law, sampled here.
    Law(Law),
}

/// What [`run`] is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The motion.
    pub source: Source,
    /// The law's parameters, or with a file only its robot and rotation order.
    pub params: Params,
    /// With a law: duration, s [default: one period of the law, or 10 s].
    pub duration_s: Option<f32>,
    /// With a law: sampling rate, Hz [default: 100].
    pub rate_hz: Option<f32>,
    /// Joint speed limit per joint (abduction, hip, knee), rad/s.
    pub max_joint_speed_rad_s: [f32; 3],
}

/// The report and what it is of; serialised as `quadctl check --json`'s last line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Checked {
    /// The file, or `quadctl motion <law>`.
    pub source: String,
    /// The robot as given.
    pub robot: String,
    /// Time span, s (of the file when it has two samples or more).
    pub duration_s: Option<f32>,
    /// Sampling rate, Hz (of the file: samples over its time span).
    pub rate_hz: Option<f32>,
    /// The preflight report.
    pub report: Report,
}

/// `quadctl check --json`'s object: keys in alphabetical order, as printed since the first
/// release.
#[derive(Debug, Serialize)]
pub struct Summary<'a> {
    /// See [`Checked::duration_s`].
    pub duration_s: Option<f32>,
    /// Every sample passed.
    pub ok: bool,
    /// See [`Checked::rate_hz`].
    pub rate_hz: Option<f32>,
    /// See [`Checked::report`].
    pub report: &'a Report,
    /// See [`Checked::robot`].
    pub robot: &'a str,
    /// See [`Checked::source`].
    pub source: &'a str,
}

impl Checked {
    /// The JSON summary.
    pub fn summary(&self) -> Summary<'_> {
        Summary {
            duration_s: self.duration_s,
            ok: self.report.ok(),
            rate_hz: self.rate_hz,
            report: &self.report,
            robot: &self.robot,
            source: &self.source,
        }
    }
}

/// Runs the check. `progress` follows the sampling of a law.
///
/// # Errors
/// See [`Error`].
pub fn run(args: &Request, progress: &mut dyn FnMut(Progress)) -> Result<Checked, Error> {
    match &args.source {
        Source::Law(law) => check_law(args, *law, progress),
        Source::File(file) => check_file(args, file),
    }
}

/// The reason of a status cell (`too_far`, …, `joint_limit (knee)`); `None` when it cannot be
/// told (a `joint_limit` without its joint, or an unknown code).
fn unreachable_code(code: &str) -> Option<Unreachable> {
    let code = code.trim();
    Some(match code {
        "too_far" => Unreachable::TooFar,
        "too_close" => Unreachable::TooClose,
        "inside_offset" => Unreachable::InsideOffset,
        "non_finite" => Unreachable::NonFinite,
        other => {
            let joint = other
                .strip_prefix("joint_limit")?
                .trim()
                .strip_prefix('(')?
                .strip_suffix(')')?;
            Unreachable::JointLimit(Joint::ALL.into_iter().find(|j| j.name() == joint.trim())?)
        }
    })
}

fn check_law(
    args: &Request,
    law: Law,
    progress: &mut dyn FnMut(Progress),
) -> Result<Checked, Error> {
    let limits = args.max_joint_speed_rad_s;
    let m = args.params.build(law)?;
    let duration = args
        .duration_s
        .unwrap_or_else(|| m.period_s().unwrap_or(10.0));
    let rate = args.rate_hz.unwrap_or(100.0);
    let sweep = motion::sweep(duration, rate)?;
    // The static stability margin with the robot's masses: a preset's physical preset, a
    // robot file's `[physical]` table.
    let mass = robot_file::resolve_description(&args.params.robot)?
        .physical
        .mass_model();
    let mut c = Checker::new(m.robot(), m.body_config(), limits)
        .and_then(|c| c.with_mass(&mass))
        .map_err(param_err)?;
    progress(Progress::Start(u64::from(sweep.samples())));
    for k in 0..sweep.samples() {
        let t = sweep.time_s(k);
        let frame = m.frame::<DefaultMath>(t).map_err(param_err)?;
        let _ = c.push_frame(t, &frame);
        if k % 4096 == 4095 {
            progress(Progress::Done(u64::from(k) + 1));
        }
    }
    progress(Progress::Finished);
    Ok(Checked {
        report: c.finish(),
        source: format!("quadctl motion {}", law.name()),
        robot: args.params.robot.clone(),
        duration_s: Some(duration),
        rate_hz: Some(rate),
    })
}

fn check_file(args: &Request, file: &Path) -> Result<Checked, Error> {
    let limits = args.max_joint_speed_rad_s;
    if let Some(opt) = args.params.law_option_given() {
        return Err(motion::Error::NotApplicable {
            option: opt,
            law: "a motion file",
        }
        .into());
    }
    if args.duration_s.is_some() || args.rate_hz.is_some() {
        return Err(motion::Error::NotApplicable {
            option: "--duration-s/--rate-hz",
            law: "a motion file",
        }
        .into());
    }
    let robot = robot_file::resolve(&args.params.robot)?;
    let mut csv = MotionCsv::open(file)?;
    let order: RotationOrder = args
        .params
        .rotation_order
        .or(csv.rotation_order)
        .unwrap_or_default();
    let config = BodyConfig {
        order,
        pivot_m: kin_core::Vec3::ZERO,
    };
    let mut c = Checker::new(&robot, config, limits).map_err(param_err)?;
    let mut span: Option<(f64, f64)> = None;
    while let Some(row) = csv.next_row()? {
        let t = row.t_s as f32;
        span = Some(span.map_or((row.t_s, row.t_s), |(a, _)| (a, row.t_s)));
        match (row.feet, row.pose, row.angles) {
            (Some(feet), Some(pose), _) => {
                let _ = c.push_frame(
                    t,
                    &Frame {
                        pose,
                        feet_in_world: feet,
                        contact: [Contact::Stance; 4],
                    },
                );
            }
            (_, _, Some(a)) => {
                let q: [JointAngles; 4] = core::array::from_fn(|l| {
                    JointAngles::new(a[3 * l], a[3 * l + 1], a[3 * l + 2])
                });
                c.push_angles(t, &q);
            }
            _ => {
                // "FR:too_far": the leg and reason as `quadctl motion` wrote them. Without the
                // feet and pose the sample cannot be solved again, so the reason must be known.
                let parsed = row
                    .status
                    .split_once(':')
                    .and_then(|(leg, code)| Some((LegId::parse(leg)?, unreachable_code(code)?)));
                let Some(failure) = parsed else {
                    return Err(Error::Status {
                        input: file.display().to_string(),
                        line: row.line,
                        status: row.status,
                    });
                };
                c.push_unreachable(t, &[failure]);
            }
        }
    }
    let report = c.finish();
    let (duration_s, rate_hz) = match span {
        Some((a, b)) if report.samples > 1 && b > a => (
            Some((b - a) as f32),
            Some(((report.samples - 1) as f64 / (b - a)) as f32),
        ),
        _ => (None, None),
    };
    Ok(Checked {
        report,
        source: file.display().to_string(),
        robot: args.params.robot.clone(),
        duration_s,
        rate_hz,
    })
}

fn at(e: &Option<Extremum>, unit: &str, deg: bool) -> String {
    match e {
        None => "-".to_owned(),
        Some(e) if deg => format!(
            "{:.4} {unit} ({:.2}°) @ {:.3} s",
            e.value,
            e.value.to_degrees(),
            e.t_s
        ),
        Some(e) => format!("{:.4} {unit} @ {:.3} s", e.value, e.t_s),
    }
}

/// The human-readable report.
pub fn table(checked: &Checked) -> String {
    let (r, s) = (&checked.report, checked);
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "preflight: {} (robot {}), {} samples{}",
        s.source,
        s.robot,
        r.samples,
        match (s.duration_s, s.rate_hz) {
            (Some(d), Some(f)) => format!(" over {d} s at {f} Hz"),
            _ => String::new(),
        }
    );
    let _ = writeln!(
        out,
        "joint speed limit (abduction, hip, knee): {:?} rad/s; singularity threshold {}",
        r.max_joint_speed_limit_rad_s, r.singularity_threshold
    );
    for l in &r.legs {
        let _ = writeln!(out, "\n{}  failures: {}", l.leg, l.failures);
        let _ = writeln!(
            out,
            "    workspace margin (min): {}{}",
            at(&l.workspace_margin_m, "m", false),
            l.workspace_boundary
                .map(|b| format!(" [{}]", b.name()))
                .unwrap_or_default()
        );
        let _ = writeln!(
            out,
            "    joint-limit margin (min): {}{}",
            at(&l.joint_margin_rad, "rad", true),
            l.joint_margin_joint
                .map(|j| format!(" [{j}]"))
                .unwrap_or_default()
        );
        let _ = writeln!(
            out,
            "    inverse condition (min):  {}",
            at(&l.inverse_condition, "", false)
        );
        for j in Joint::ALL {
            let _ = writeln!(
                out,
                "    {:<9} speed (max):    {}",
                j.name(),
                at(&l.joint_speed_rad_s[j as usize], "rad/s", false)
            );
        }
        if let Some(f) = l.first_failure {
            let _ = writeln!(
                out,
                "    first failure: sample {} at t = {} s: {}",
                f.sample, f.t_s, f.kind
            );
        }
    }
    let _ = writeln!(out);
    let overall = |name: &str, v: Option<(LegId, Extremum)>, unit: &str| match v {
        Some((leg, e)) => format!("{name} {:.4} {unit} ({leg} @ {:.3} s)", e.value, e.t_s),
        None => format!("{name} -"),
    };
    let _ = writeln!(
        out,
        "overall: {}; {}; {}",
        overall("min workspace margin", r.min_workspace_margin(), "m"),
        overall("min joint margin", r.min_joint_margin(), "rad"),
        overall("min inverse condition", r.min_inverse_condition(), "")
    );
    // A motion file has no contact column: the margin needs the law's stance and swing.
    if let Some(m) = r.static_margin_m {
        let _ = writeln!(
            out,
            "static stability margin (min): {:.4} m @ {:.3} s{}",
            m.value,
            m.t_s,
            if m.value > 0.0 {
                ""
            } else {
                " (the centre of mass leaves the support polygon)"
            }
        );
    }
    match r.first_failure {
        None => {
            let _ = writeln!(out, "result: PASS (all {} samples)", r.samples);
        }
        Some(f) => {
            let _ = writeln!(
                out,
                "result: FAIL: {} failing (sample, leg) pairs; first at sample {} (t = {} s), {}: {}",
                r.failures, f.sample, f.t_s, f.leg, f.kind
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_reasons_parse_or_are_refused() {
        assert_eq!(unreachable_code("too_far"), Some(Unreachable::TooFar));
        assert_eq!(
            unreachable_code("joint_limit (knee)"),
            Some(Unreachable::JointLimit(Joint::Knee))
        );
        assert_eq!(unreachable_code("joint_limit"), None);
        assert_eq!(unreachable_code("tired"), None);
    }
}
