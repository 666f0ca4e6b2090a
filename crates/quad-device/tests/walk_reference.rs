//! The walk and the trot as docs/motion.md defines them ("The walk and the trot on the
//! device"), computed here from the document alone — in f64, apart from the gait phase, which
//! the document fixes in single precision — and compared with every frame the device runs: a
//! trot and a walk with velocity changes (forward, lateral, turning) and a stop, every frame's
//! twelve angles from the device's readback (its target) against the body IK of the
//! reference's feet. Also the multi-leg foot path ("Foot paths on the device").
//!
//! This is the one second formulation of the walker in the project, kept apart on purpose: it
//! is the conformance check of the document, what a client written from it computes.

mod common;

use common::*;
use kin_core::body::{BodyConfig, Solver};
use kin_core::motion::gait::Pattern;
use kin_core::motion::path::PathKind;
use kin_core::{LegId, Pose, ReachPolicy, Robot, Vec3};
use quad_device::Config;
use quad_protocol::{
    DeviceToHost, LegSet, MotionCommand, MotionStage, MotionStatus, Readback, Request,
    PROTOCOL_VERSION,
};

/// The reference and the device agree to this, rad (f64 against the device's f32 and its
/// order of operations, through the IK; measured: ≈ 1e-6 rad over a trot and a walk).
const TOLERANCE_RAD: f32 = 1e-5;

/// One servo frame, s (docs/motion.md: Δt).
const DT_S: f64 = 0.02;

/// A velocity command: forward, lateral (m/s), yaw rate (rad/s, counter-clockwise).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Cmd {
    vx: f64,
    vy: f64,
    w: f64,
}

#[derive(Debug, Clone, Copy)]
struct P {
    x: f64,
    y: f64,
    z: f64,
}

/// `X_v(s)·p`: the body's displacement over `s` seconds of the constant command `v`.
fn displace(v: Cmd, s: f64, p: P) -> P {
    let th = v.w * s;
    let (a, b) = if v.w.abs() < 1e-9 {
        (s, 0.0)
    } else {
        (th.sin() / v.w, (1.0 - th.cos()) / v.w)
    };
    P {
        x: v.vx * a - v.vy * b + th.cos() * p.x - th.sin() * p.y,
        y: v.vx * b + v.vy * a + th.sin() * p.x + th.cos() * p.y,
        z: p.z,
    }
}

/// The quintic Bézier swing of the document at progress `s`, stride `l`, apex `h`, duty `d`:
/// (x along the chord, z up).
fn bezier(l: f64, h: f64, d: f64, s: f64) -> (f64, f64) {
    let c = (1.0 - d) * l / (5.0 * d);
    let px = [
        -l / 2.0,
        -l / 2.0 - c,
        -l / 2.0 - c,
        l / 2.0 + c,
        l / 2.0 + c,
        l / 2.0,
    ];
    let pz = [0.0, 0.0, 1.6 * h, 1.6 * h, 0.0, 0.0];
    let binom = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let (mut x, mut z) = (0.0, 0.0);
    for k in 0..6 {
        let w = binom[k] * s.powi(k as i32) * (1.0 - s).powi(5 - k as i32);
        x += w * px[k];
        z += w * pz[k];
    }
    (x, z)
}

#[derive(Debug, Clone, Copy)]
struct Leg {
    foot: P,
    lift_off: P,
    touch_down: P,
    parked: bool,
}

/// The walker of the document.
struct Reference {
    offsets: [f64; 4],
    d: f64,
    t: f64,
    h: f64,
    /// R / f.
    stance_radius: f64,
    neutral: [P; 4],
    /// The gait phase, single precision (the document's rule).
    phase: f32,
    v: Cmd,
    stopping: bool,
    legs: [Leg; 4],
}

fn off_sq(p: P, n: P) -> f64 {
    (p.x - n.x).powi(2) + (p.y - n.y).powi(2)
}

fn frac32(x: f32) -> f32 {
    x - x.floor()
}

impl Reference {
    fn new(robot: &Robot, pattern: Pattern, body_height_m: f32, step_m: f32, cycle_s: f32) -> Self {
        let (offsets, d) = match pattern {
            Pattern::Trot => ([0.0, 0.5, 0.5, 0.0], 0.75),
            Pattern::Walk => ([0.25, 0.75, 0.0, 0.5], 0.75),
        };
        let hh = f64::from(body_height_m);
        let neutral = LegId::ALL.map(|leg| {
            let (sx, sy) = match leg {
                LegId::FL => (1.0, 1.0),
                LegId::FR => (1.0, -1.0),
                LegId::RL => (-1.0, 1.0),
                LegId::RR => (-1.0, -1.0),
            };
            P {
                x: sx * f64::from(robot.body_length_m) / 2.0,
                y: sy * (f64::from(robot.body_width_m) / 2.0 + f64::from(robot.leg.d_lat_m)),
                z: -hh,
            }
        });
        let r = 0.2 * hh;
        let f = 1.0 + 2.0 * (1.0 - d) / (5.0 * d);
        Reference {
            offsets,
            d,
            t: f64::from(cycle_s),
            h: f64::from(step_m),
            stance_radius: r / f,
            neutral,
            phase: 0.0,
            v: Cmd::default(),
            stopping: false,
            legs: neutral.map(|n| Leg {
                foot: n,
                lift_off: n,
                touch_down: n,
                parked: false,
            }),
        }
    }

    fn carry(&self, p: P, s: f64, rate: f64) -> P {
        if self.v != Cmd::default() && s > 0.0 {
            displace(self.v, rate * s, p)
        } else {
            p
        }
    }

    /// One frame: phase, each leg (lift-off, stance, swing, touch-down), saturation.
    fn step(&mut self, cycle_s: f32) {
        let sigma = 1.0 - self.d;
        let old = self.phase;
        let new = frac32(old + 0.02f32 / cycle_s);
        let mut scale = 1.0;
        let mut next = self.legs;
        for _ in 0..5 {
            let mut inside = true;
            for (i, slot) in next.iter_mut().enumerate() {
                let (leg, ok) = self.advance(i, old, new, scale, sigma);
                *slot = leg;
                inside &= ok;
            }
            if inside || scale == 0.0 {
                break;
            }
            scale = if scale > 0.2 { 0.5 * scale } else { 0.0 };
        }
        self.legs = next;
        self.phase = new;
    }

    fn advance(&self, i: usize, old: f32, new: f32, scale: f64, sigma: f64) -> (Leg, bool) {
        let mut l = self.legs[i];
        if l.parked {
            return (l, true);
        }
        let n = self.neutral[i];
        let before = off_sq(l.foot, n);
        let o = self.offsets[i] as f32;
        let q0 = f64::from(frac32(old + o));
        let q1 = f64::from(frac32(new + o));
        let lift = q1 < q0;
        let stance_only = !lift && q0 >= sigma;
        if lift || stance_only {
            let s = if lift {
                ((1.0 - q0) * self.t).min(DT_S)
            } else {
                DT_S
            };
            l.foot = self.carry(l.foot, s, -scale);
        }
        if lift {
            if self.stopping && off_sq(l.foot, n) == 0.0 && l.foot.z == n.z {
                l.parked = true;
                return (l, true);
            }
            l.lift_off = l.foot;
            l.touch_down = self.carry(n, self.d * self.t / 2.0, 1.0);
        }
        if !stance_only {
            if q1 < sigma {
                let (a, b) = (l.lift_off, l.touch_down);
                let (cx, cy) = (b.x - a.x, b.y - a.y);
                let len = (cx * cx + cy * cy).sqrt();
                let (ux, uy) = if len > 0.0 {
                    (cx / len, cy / len)
                } else {
                    (1.0, 0.0)
                };
                let (x, z) = bezier(len, self.h, self.d, q1 / sigma);
                l.foot = P {
                    x: (a.x + b.x) / 2.0 + ux * x,
                    y: (a.y + b.y) / 2.0 + uy * x,
                    z: (a.z + b.z) / 2.0 + z,
                };
                return (l, true);
            }
            l.foot = self.carry(l.touch_down, ((q1 - sigma) * self.t).min(DT_S), -scale);
        }
        let after = off_sq(l.foot, n);
        let r2 = self.stance_radius * self.stance_radius;
        (l, !(after > r2 && after > before))
    }

    fn feet(&self) -> [Vec3; 4] {
        self.legs
            .map(|l| Vec3::new(l.foot.x as f32, l.foot.y as f32, l.foot.z as f32))
    }
}

fn motion(a: DeviceToHost) -> (MotionStatus, Readback) {
    match a {
        DeviceToHost::MotionAck {
            status, readback, ..
        } => (status, readback),
        other => panic!("not a motion ack: {other:?}"),
    }
}

fn run_frame(s: &MotionStatus) -> u32 {
    (s.t_s / 0.02).round() as u32
}

fn biggest_difference(a: &[f32; 12], b: &[f32; 12]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// Runs `pattern` on the device with `commands` (run frame, command) and a stop at
/// `stop_at`, comparing every frame of the run with the reference; returns the frames
/// compared and the largest difference.
fn compare(pattern: Pattern, commands: &[(u32, Cmd)], stop_at: u32) -> (u32, f32) {
    let config = Config::fernando2025();
    let robot = config.robot;
    let order = config.pose_config.order;
    let h = config.pose_config.stance_height_m;
    let (mut dev, clock) = clocked_device();
    ask(
        &mut dev,
        0,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    );
    ask(&mut dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 400);
    let walk = MotionCommand::walk(pattern, h);
    let MotionCommand::Walk {
        step_height_m,
        cycle_s,
        ..
    } = walk
    else {
        unreachable!()
    };
    ask(&mut dev, 2, Request::StartMotion(walk));
    let mut reference = Reference::new(&robot, pattern, h, step_height_m, cycle_s);
    let solver = Solver::new(&robot);
    let angles = |r: &Reference| {
        solver
            .inverse(
                &Pose::default(),
                &BodyConfig::about_centre(order),
                &r.feet(),
                ReachPolicy::Reject,
            )
            .unwrap()
            .flat()
    };
    // The approach, to run frame 0.
    let mut seq = 3u16;
    let mut status = loop {
        frames(&mut dev, &clock, 1);
        let (s, _) = motion(ask(&mut dev, seq, Request::GetMotion));
        seq = seq.wrapping_add(1);
        if s.stage == MotionStage::Run {
            break s;
        }
    };
    assert_eq!(run_frame(&status), 0);
    let (mut compared, mut worst) = (0u32, 0.0f32);
    let mut pending = commands.iter().peekable();
    let mut current = None;
    loop {
        let frame = run_frame(&status);
        // The commands of this frame: sent now, they apply from the step to the next; the
        // one in effect is sent again every 10 frames (within the velocity timeout).
        let mut due = Vec::new();
        while let Some(&&(at, c)) = pending.peek() {
            if at != frame {
                break;
            }
            due.push(c);
            current = Some(c);
            pending.next();
        }
        if due.is_empty() && frame.is_multiple_of(10) && frame < stop_at {
            due.extend(current);
        }
        for c in due {
            let (s, _) = motion(ask(
                &mut dev,
                seq,
                Request::SetVelocity {
                    forward_m_s: c.vx as f32,
                    lateral_m_s: c.vy as f32,
                    yaw_rate_rad_s: c.w as f32,
                },
            ));
            seq = seq.wrapping_add(1);
            assert_eq!(run_frame(&s), frame);
            reference.v = c;
        }
        if frame == stop_at {
            motion(ask(&mut dev, seq, Request::StopMotion));
            seq = seq.wrapping_add(1);
            reference.stopping = true;
            reference.v = Cmd::default();
        }
        frames(&mut dev, &clock, 1);
        let (s, rb) = motion(ask(&mut dev, seq, Request::GetMotion));
        seq = seq.wrapping_add(1);
        status = s;
        if !matches!(s.stage, MotionStage::Run | MotionStage::Stopping) {
            // The step into this frame parked the last leg: the reference's too.
            reference.step(cycle_s);
            assert!(reference.legs.iter().all(|l| l.parked), "{s:?}");
            break;
        }
        reference.step(cycle_s);
        assert_eq!(run_frame(&s), frame + 1);
        let want = angles(&reference);
        let err = biggest_difference(&rb.angles_rad, &want);
        assert!(
            err <= TOLERANCE_RAD,
            "{pattern:?} run frame {}: device {:?}, reference {:?} ({err} rad)",
            frame + 1,
            rb.angles_rad,
            want
        );
        worst = worst.max(err);
        compared += 1;
    }
    (compared, worst)
}

fn cmd(vx: f64, vy: f64, w: f64) -> Cmd {
    Cmd { vx, vy, w }
}

#[test]
fn the_trot_of_the_document_is_the_device_s_frame_by_frame() {
    let (n, worst) = compare(
        Pattern::Trot,
        &[
            (0, cmd(0.03, 0.0, 0.0)),
            (37, cmd(0.06, 0.0, 0.1)),
            (101, cmd(0.0, 0.02, -0.1)),
            (150, cmd(0.04, 0.0, 0.0)),
        ],
        203,
    );
    // The stop finishes the strides: up to two cycles more.
    assert!(n > 203, "{n}");
    eprintln!("trot: {n} frames, largest |device − reference| {worst:e} rad");
}

#[test]
fn the_walk_of_the_document_is_the_device_s_frame_by_frame() {
    let (n, worst) = compare(
        Pattern::Walk,
        &[(5, cmd(0.02, 0.0, 0.0)), (80, cmd(0.03, 0.0, -0.1))],
        160,
    );
    assert!(n > 160, "{n}");
    eprintln!("walk: {n} frames, largest |device − reference| {worst:e} rad");
}

#[test]
fn a_foot_path_on_all_legs_is_the_document_s_frame_by_frame() {
    // docs/motion.md, "Foot paths on the device": every foot the path's offset (x along the
    // body's x axis) around its stance point at the device's stance height, all in phase.
    let config = Config::fernando2025();
    let robot = config.robot;
    let h = f64::from(config.pose_config.stance_height_m);
    let (mut dev, clock) = clocked_device();
    ask(
        &mut dev,
        0,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    );
    ask(&mut dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 400);
    let (l, hs, d, t) = (0.08, 0.04, 0.6, 2.0);
    let request = MotionCommand::FootPath {
        path: PathKind::Bezier,
        legs: LegSet::All,
        stride_m: l as f32,
        step_height_m: hs as f32,
        duty_factor: d as f32,
        cycle_s: t as f32,
        duration_s: None,
    };
    motion(ask(&mut dev, 2, Request::StartMotion(request)));
    let solver = Solver::new(&robot);
    let mut compared = 0;
    for seq in 3..400u16 {
        frames(&mut dev, &clock, 1);
        let (s, rb) = motion(ask(&mut dev, seq, Request::GetMotion));
        if s.stage != MotionStage::Run {
            continue;
        }
        let phase = (f64::from(s.t_s) / t).fract();
        let sigma = 1.0 - d;
        let (x, z) = if phase < sigma {
            bezier(l, hs, d, phase / sigma)
        } else {
            (l * (0.5 - (phase - sigma) / d), 0.0)
        };
        let feet = robot
            .stance_feet(h as f32)
            .map(|n| Vec3::new(n.x + x as f32, n.y, n.z + z as f32));
        let want = solver
            .inverse(
                &Pose::default(),
                &BodyConfig::about_centre(config.pose_config.order),
                &feet,
                ReachPolicy::Reject,
            )
            .unwrap()
            .flat();
        let err = biggest_difference(&rb.angles_rad, &want);
        assert!(err <= TOLERANCE_RAD, "t {} s: {err} rad", s.t_s);
        compared += 1;
    }
    assert!(compared > 300, "{compared}");
}
