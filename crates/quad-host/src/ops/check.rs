//! `quadctl check`: the preflight report of a motion CSV or of a motion law
//! (`kin_core::preflight`).

use super::motion::{self, param_err, Error, Law, LawArgs, MotionCsv};
use super::pose::Order;
use kin_core::leg::Unreachable;
use kin_core::motion::{Contact, Frame, Motion};
use kin_core::preflight::{Checker, Extremum, Report};
use kin_core::{BodyConfig, Joint, JointAngles, LegId, RotationOrder};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Preflight report of a motion: sweeps it and reports, per leg and overall,
  - reachability: samples the IK refuses, and the first one (time, leg, reason);
  - minimum workspace margin (m): distance of the foot target to the nearest workspace boundary,
    min(L1 + L2 − r, r − |L1 − L2|, r_yz − d_lat), r the hip-joint-to-foot distance in the leg
    plane, r_yz the foot's distance from the abduction axis; negative = out of reach;
  - minimum joint-limit margin (rad): distance of the tightest joint to its limit;
  - minimum singularity measure: inverse condition number σmin/σmax of the leg Jacobian
    (1 = isotropic, 0 = singular), failing below 0.05;
  - maximum joint speed (rad/s), finite differences between samples, against
    --max-joint-speed-rad-s.

Source: a CSV written by `quadctl motion` (FILE, `-` for stdin; rows with feet and pose are
solved again, rows with angles only are checked as they are; the rotation order is read from the
file's `# quadctl motion … rotation_order=…` line, else --rotation-order, else zyx), or
--motion LAW with the same options as `quadctl motion`.

Output: a table (angles in rad with degrees in brackets); with --json, also one JSON object as
the last line (SI units). Exit status: 0 all samples pass, 1 some fail, 2 bad input.";

/// Arguments of `quadctl check`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Preflight report of a motion (file or law): reach, margins, singularity, joint speed",
    long_about = LONG_ABOUT,
    allow_negative_numbers = true
)]
pub struct Args {
    /// Motion CSV written by `quadctl motion` (`-` for stdin).
    #[arg(
        value_name = "FILE",
        required_unless_present = "motion",
        conflicts_with = "motion"
    )]
    pub file: Option<PathBuf>,
    /// Check this law instead of a file.
    #[arg(long, value_enum, value_name = "LAW")]
    pub motion: Option<Law>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub law_args: LawArgs,
    /// With --motion: duration, s [default: one period of the law, or 10 s].
    #[arg(long, value_name = "T")]
    pub duration_s: Option<f32>,
    /// With --motion: sampling rate, Hz [default: 100].
    #[arg(long, value_name = "F")]
    pub rate_hz: Option<f32>,
    /// Joint speed limit, rad/s: one value for all joints or ABDUCTION,HIP,KNEE.
    #[arg(long, value_name = "RAD_S", default_value = "6")]
    pub max_joint_speed_rad_s: String,
    /// Also print the report as one JSON object on the last line.
    #[arg(long)]
    pub json: bool,
}

fn speed_limits(s: &str) -> Result<[f32; 3], Error> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| {
            x.trim().parse::<f32>().map_err(|_| Error::Csv {
                at: "--max-joint-speed-rad-s".to_owned(),
                message: format!("`{}` is not a number", x.trim()),
            })
        })
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [a] => Ok([*a; 3]),
        [a, b, c] => Ok([*a, *b, *c]),
        _ => Err(Error::Csv {
            at: "--max-joint-speed-rad-s".to_owned(),
            message: format!("expected one value or three (abduction,hip,knee), got `{s}`"),
        }),
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

/// What was checked, for the header and the JSON.
struct Source {
    label: String,
    robot: String,
    duration_s: Option<f32>,
    rate_hz: Option<f32>,
}

/// `quadctl check`.
pub fn run(args: &Args) -> ExitCode {
    match run_inner(args) {
        Ok(true) => ExitCode::from(super::EXIT_OK),
        Ok(false) => ExitCode::from(super::EXIT_MALFORMED),
        Err(e) => {
            eprintln!("quadctl: error: {e}");
            ExitCode::from(super::EXIT_FATAL)
        }
    }
}

fn run_inner(args: &Args) -> Result<bool, Error> {
    let limits = speed_limits(&args.max_joint_speed_rad_s)?;
    let (report, source) = match (&args.file, args.motion) {
        (_, Some(law)) => check_law(args, law, limits)?,
        (Some(file), None) => check_file(args, file, limits)?,
        (None, None) => {
            return Err(Error::NotApplicable {
                option: "(no FILE and no --motion)",
                law: "check: give a motion CSV or --motion LAW",
            })
        }
    };
    print!("{}", table(&report, &source));
    if args.json {
        let json = serde_json::json!({
            "source": source.label,
            "robot": source.robot,
            "duration_s": source.duration_s,
            "rate_hz": source.rate_hz,
            "ok": report.ok(),
            "report": report,
        });
        println!("{json}");
    }
    Ok(report.ok())
}

fn check_law(args: &Args, law: Law, limits: [f32; 3]) -> Result<(Report, Source), Error> {
    let m = args.law_args.build(law)?;
    let duration = args
        .duration_s
        .unwrap_or_else(|| m.period_s().unwrap_or(10.0));
    let rate = args.rate_hz.unwrap_or(100.0);
    let sweep = motion::sweep(duration, rate)?;
    let mut c = Checker::new(m.robot(), m.body_config(), limits).map_err(param_err)?;
    let bar = motion::progress(u64::from(sweep.samples()), "check");
    for k in 0..sweep.samples() {
        let t = sweep.time_s(k);
        let frame = m.frame(t).map_err(param_err)?;
        let _ = c.push_frame(t, &frame);
        if k % 4096 == 4095 {
            bar.inc(4096);
        }
    }
    bar.finish_and_clear();
    Ok((
        c.finish(),
        Source {
            label: format!("quadctl motion {}", law.name()),
            robot: args.law_args.robot.robot.clone(),
            duration_s: Some(duration),
            rate_hz: Some(rate),
        },
    ))
}

fn check_file(args: &Args, file: &Path, limits: [f32; 3]) -> Result<(Report, Source), Error> {
    if let Some(opt) = args.law_args.law_option_given() {
        return Err(Error::NotApplicable {
            option: opt,
            law: "a motion file",
        });
    }
    if args.duration_s.is_some() || args.rate_hz.is_some() {
        return Err(Error::NotApplicable {
            option: "--duration-s/--rate-hz",
            law: "a motion file",
        });
    }
    let robot = crate::robot_file::resolve(&args.law_args.robot.robot).map_err(Error::Robot)?;
    let mut csv = MotionCsv::open(file)?;
    let order: RotationOrder = args
        .law_args
        .rotation_order
        .map(Order::into)
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
                    return Err(Error::Csv {
                        at: format!("{}:{}", file.display(), row.line),
                        message: format!(
                            "status `{}` without angles, feet and pose: expected `<leg>:<reason>` \
                             (too_far, too_close, inside_offset, non_finite, joint_limit (<joint>))",
                            row.status
                        ),
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
    Ok((
        report,
        Source {
            label: file.display().to_string(),
            robot: args.law_args.robot.robot.clone(),
            duration_s,
            rate_hz,
        },
    ))
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
fn table(r: &Report, s: &Source) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "preflight: {} (robot {}), {} samples{}",
        s.label,
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
    use kin_core::preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S;

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

    #[test]
    fn the_default_speed_limit_is_kin_cores() {
        let default: f32 = "6".parse().unwrap();
        assert_eq!(default, DEFAULT_MAX_JOINT_SPEED_RAD_S);
        assert_eq!(speed_limits("1,2,3").unwrap(), [1.0, 2.0, 3.0]);
        assert_eq!(speed_limits("4").unwrap(), [4.0; 3]);
        assert!(speed_limits("1,2").is_err() && speed_limits("x").is_err());
    }
}
