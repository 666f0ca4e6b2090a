//! The firmware's IK benchmark in simavr: cycles per leg IK and per body-pose solve on the
//! release ELFs, the angle error against an f64 reference computed here, flash, static SRAM
//! and the stack high-water mark.
//!
//! - `bench.elf` (avr-libc float primitives) serves several math backends; `bench-libm.elf`
//!   is the straightforward build (Rust `libm` on compiler-builtins' soft-float), measured in
//!   the same run for comparison.
//! - Cycles are counted by the host between the edges of the firmware's marker pin (PA0),
//!   which is high exactly around the solve; the cost of an empty marker window is
//!   subtracted. Figures are the **maximum** over the seeded targets (the frame budget is a
//!   worst case); means are printed beside them.
//! - The f64 reference is independent of kin-core's closed form: Newton iterations on an f64
//!   forward kinematics (written from the chain formula in kin-core's crate docs), started
//!   from the host's f32 solution, to a residual below [`REFERENCE_RESIDUAL_M`].

use kin_core::math::Libm;
use kin_core::{body, BodyConfig, LegId, Pose, ReachPolicy, Robot, Vec3};
use nalgebra::{Matrix3, Rotation3, Vector3};
use quad_host::client::{Client, ClientConfig};
use quad_host::emu::{build, elf, Mega2560, MARKER_PIN};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::{DeviceToHost, PoseConfig, Request};
use seeded_rng::SplitMix64;
use serde::Serialize;
use std::path::Path;

/// Stance height of the benchmark, m; must equal `firmware_avr::bench::STANCE_HEIGHT_M`.
pub const STANCE_HEIGHT_M: f32 = 0.277;

/// The benchmark robot; must equal `firmware_avr::bench::ROBOT`.
pub fn robot() -> Robot {
    Robot::shahriar2023()
}

/// Seed of the targets.
pub const SEED: u64 = 0x000D_EC0D_E5EE_D000;

/// Number of body poses (and of leg targets).
pub const N_TARGETS: usize = 50;

/// Seed 000's body-pose ranges (§4.2): roll ±28°, pitch ±21°, yaw ±21°.
pub const POSE_RANGE_DEG: [f64; 3] = [28.0, 21.0, 21.0];

/// Body translation range of the targets, ± m on each axis.
pub const TRANSLATION_RANGE_M: f64 = 0.02;

/// The f64 reference stops when the foot residual is below this, m.
pub const REFERENCE_RESIDUAL_M: f64 = 1e-12;

/// Cycles allowed for one request and its answer.
const REQUEST_TIMEOUT_CYCLES: u64 = 20_000_000;

/// The math backends the benchmark firmware serves (its backend ids).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// avr-libc's `sqrt` (its bits), `atan2`, `sin`, `cos` (`avr_libc_math::AvrLibm`).
    AvrLibm = 0,
    /// kin-core's polynomial backend `Fast` on avr-libc's float primitives.
    Fast = 1,
    /// kin-core's `Libm` backend (Rust libm); soft-float primitives from whichever ELF.
    Libm = 2,
    /// The firmware's backend (`avr_libc_math::AvrFast`): `sqrt` with avr-libc's bits, kin-core's
    /// `poly::atan2_fixed` and `poly::sin_cos_fixed` (both in `AvrLibm`'s assembly forms).
    AvrFast = 3,
    /// [`Backend::AvrFast`] with its solver built from the robot inside every timed call (the
    /// others, as the firmware, build theirs once at boot).
    AvrFastPerCall = 4,
}

impl Backend {
    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Backend::AvrLibm => "avr-libc",
            Backend::Fast => "kin-core Fast",
            Backend::Libm => "kin-core Libm",
            Backend::AvrFast => "AvrFast",
            Backend::AvrFastPerCall => "AvrFast, solver per call",
        }
    }
}

/// The backend the firmware uses (reported as `leg_ik_cycles`, `body_pose_cycles`,
/// `max_angle_err_deg`).
pub const FIRMWARE_BACKEND: Backend = Backend::AvrFast;

/// The seeded targets.
#[derive(Debug, Clone)]
pub struct Targets {
    /// Body poses, all reachable at the stance.
    pub poses: Vec<Pose>,
    /// Leg targets: the foot of leg `i mod 4` in its hip frame for pose `i`.
    pub legs: Vec<(LegId, Vec3)>,
}

/// [`N_TARGETS`] reachable body poses in seed 000's ranges with small translations, and one
/// leg target per pose.
pub fn targets() -> Targets {
    let robot = robot();
    let config = BodyConfig::default();
    let mut rng = SplitMix64::new(SEED);
    let mut poses = Vec::new();
    while poses.len() < N_TARGETS {
        let [r, p, y] = POSE_RANGE_DEG.map(|d| rng.range(-d, d).to_radians() as f32);
        let [tx, ty, tz] =
            [0; 3].map(|_| rng.range(-TRANSLATION_RANGE_M, TRANSLATION_RANGE_M) as f32);
        let pose = Pose {
            roll_rad: r,
            pitch_rad: p,
            yaw_rad: y,
            x_m: tx,
            y_m: ty,
            z_m: tz,
        };
        if body::Solver::<Libm>::with_math(&robot)
            .inverse_at_stance(&pose, &config, STANCE_HEIGHT_M, ReachPolicy::Reject)
            .is_ok()
        {
            poses.push(pose);
        }
    }
    let legs = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| {
            let leg = LegId::ALL[i % 4];
            let local = body::Solver::<Libm>::with_math(&robot).feet_in_hips(
                pose,
                &config,
                &robot.stance_feet(STANCE_HEIGHT_M),
            );
            (leg, local[leg.index()])
        })
        .collect();
    Targets { poses, legs }
}

/// f64 forward kinematics of one leg (kin-core's canonical chain):
/// `Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L1] + Ry(h+k)·[0,0,−L2])`.
pub fn fk64(robot: &Robot, leg: LegId, q: Vector3<f64>) -> Vector3<f64> {
    let g = &robot.leg;
    let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
    let (a, h, k) = (q.x, q.y, q.z);
    let u = -l1 * h.sin() - l2 * (h + k).sin();
    let w = -(g.d_ax_m as f64) - l1 * h.cos() - l2 * (h + k).cos();
    let y = leg.side() as f64 * g.d_lat_m as f64;
    Vector3::new(u, a.cos() * y - a.sin() * w, a.sin() * y + a.cos() * w)
}

/// The f64 joint angles that put the foot of `leg` at `foot_in_hip` (f64), by Newton
/// iterations from `start` (the same IK branch).
///
/// # Panics
/// When the iterations do not converge ([`reference_leg_checked`] returns `None`).
pub fn reference_leg(
    robot: &Robot,
    leg: LegId,
    foot_in_hip: Vector3<f64>,
    start: [f32; 3],
) -> [f64; 3] {
    reference_leg_checked(robot, leg, foot_in_hip, start)
        .unwrap_or_else(|| panic!("f64 reference did not converge for {leg} at {foot_in_hip:?}"))
}

/// [`reference_leg`], `None` when 60 iterations leave a residual of at least
/// [`REFERENCE_RESIDUAL_M`] or meet a singular Jacobian (a target at a singularity, where the
/// iterations converge slowly or not at all).
pub fn reference_leg_checked(
    robot: &Robot,
    leg: LegId,
    foot_in_hip: Vector3<f64>,
    start: [f32; 3],
) -> Option<[f64; 3]> {
    let mut q = Vector3::new(start[0] as f64, start[1] as f64, start[2] as f64);
    const H: f64 = 1e-6;
    for _ in 0..60 {
        let r = fk64(robot, leg, q) - foot_in_hip;
        if r.norm() < REFERENCE_RESIDUAL_M {
            return Some([q.x, q.y, q.z]);
        }
        let mut j = Matrix3::zeros();
        for c in 0..3 {
            let mut dq = Vector3::zeros();
            dq[c] = H;
            let col = (fk64(robot, leg, q + dq) - fk64(robot, leg, q - dq)) / (2.0 * H);
            j.set_column(c, &col);
        }
        q -= j.try_inverse()? * r;
    }
    None
}

/// The f64 reference of a body pose at the stance (rotation order zyx about the body centre).
pub fn reference_body(robot: &Robot, pose: &Pose, start: &[f32; 12]) -> [f64; 12] {
    let rot = Rotation3::from_euler_angles(
        pose.roll_rad as f64,
        pose.pitch_rad as f64,
        pose.yaw_rad as f64,
    );
    let t = Vector3::new(pose.x_m as f64, pose.y_m as f64, pose.z_m as f64);
    let mut out = [0.0; 12];
    for leg in LegId::ALL {
        let hip = robot.hip_in_body(leg);
        let hip = Vector3::new(hip.x as f64, hip.y as f64, hip.z as f64);
        let foot_world = hip
            + Vector3::new(
                0.0,
                leg.side() as f64 * robot.leg.d_lat_m as f64,
                -(STANCE_HEIGHT_M as f64),
            );
        let local = rot.inverse() * (foot_world - t) - hip;
        let i = leg.index();
        let q = reference_leg(
            robot,
            leg,
            local,
            [start[3 * i], start[3 * i + 1], start[3 * i + 2]],
        );
        out[3 * i..3 * i + 3].copy_from_slice(&q);
    }
    out
}

/// Largest |a − b| over the angles, rad (angles wrapped to (−π, π]).
pub fn max_abs_diff(a: &[f32], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| {
            let mut d = (x as f64 - y).rem_euclid(std::f64::consts::TAU);
            if d > std::f64::consts::PI {
                d = std::f64::consts::TAU - d;
            }
            d
        })
        .fold(0.0, f64::max)
}

/// A benchmark firmware (`bench.elf` or `bench-libm.elf`) running in simavr.
pub struct BenchFirmware {
    emu: Mega2560,
    /// Cycles of an empty marker window, subtracted from every measurement.
    pub overhead_cycles: u64,
}

impl BenchFirmware {
    /// Boots `elf` and waits for its ready byte.
    pub fn boot(elf: &Path) -> BenchFirmware {
        let mut emu = Mega2560::new(elf).unwrap_or_else(|e| panic!("{e}"));
        let ready = emu
            .read_exact(1, 1_000_000)
            .expect("benchmark firmware sends 'R' at boot");
        assert_eq!(ready, b"R", "benchmark firmware boot byte");
        let mut fw = BenchFirmware {
            emu,
            overhead_cycles: 0,
        };
        let (c, answer) = fw.timed(b"E", 1);
        assert_eq!(answer, b"e");
        fw.overhead_cycles = c;
        fw
    }

    /// Sends `request`, runs until `answer_len` bytes came back, and returns the cycles the
    /// marker pin was high.
    fn timed(&mut self, request: &[u8], answer_len: usize) -> (u64, Vec<u8>) {
        self.emu.uart_write(request);
        let (port, bit) = MARKER_PIN;
        let end = self.emu.cycle() + REQUEST_TIMEOUT_CYCLES;
        let mut rise = None;
        let mut cycles = None;
        let mut high = self.emu.pin(port, bit);
        let mut out = Vec::new();
        while out.len() < answer_len || cycles.is_none() {
            assert!(self.emu.cycle() < end, "benchmark request timed out");
            self.emu.step().unwrap_or_else(|e| panic!("{e}"));
            let now = self.emu.pin(port, bit);
            if now != high {
                if now {
                    rise = Some(self.emu.cycle());
                } else if let Some(r) = rise {
                    cycles = Some(self.emu.cycle() - r);
                }
                high = now;
            }
            out.extend(self.emu.uart_take().into_iter().map(|(_, b)| b));
        }
        assert_eq!(out.len(), answer_len, "benchmark answer length");
        (cycles.unwrap_or(0), out)
    }

    fn angles<const N: usize>(answer: &[u8]) -> Option<[f32; N]> {
        (answer[1] == 0).then(|| {
            std::array::from_fn(|i| {
                let b = &answer[2 + 4 * i..6 + 4 * i];
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            })
        })
    }

    /// One leg IK on `backend`: cycles (overhead removed) and the angles (`None`:
    /// unreachable).
    pub fn leg(&mut self, backend: Backend, leg: LegId, foot: Vec3) -> (u64, Option<[f32; 3]>) {
        let mut req = vec![b'L', backend as u8, leg.index() as u8];
        for v in foot.to_array() {
            req.extend(v.to_le_bytes());
        }
        let (c, answer) = self.timed(&req, 2 + 12);
        assert_eq!(answer[0], b'l');
        assert_ne!(answer[1], 2, "firmware lacks backend {backend:?}");
        (c - self.overhead_cycles, Self::angles(&answer))
    }

    /// One body pose on `backend`: cycles (overhead removed) and the twelve angles.
    pub fn body(&mut self, backend: Backend, pose: &Pose) -> (u64, Option<[f32; 12]>) {
        let mut req = vec![b'B', backend as u8];
        for v in pose.to_array() {
            req.extend(v.to_le_bytes());
        }
        let (c, answer) = self.timed(&req, 2 + 48);
        assert_eq!(answer[0], b'b');
        assert_ne!(answer[1], 2, "firmware lacks backend {backend:?}");
        (c - self.overhead_cycles, Self::angles(&answer))
    }

    /// One float primitive `op(a, b)` of the firmware's table: cycles (overhead removed) and
    /// the result.
    pub fn primitive(&mut self, op: u8, a: f32, b: f32) -> (u64, f32) {
        let mut req = vec![b'F', op];
        req.extend(a.to_le_bytes());
        req.extend(b.to_le_bytes());
        let (c, answer) = self.timed(&req, 6);
        assert_eq!(&answer[..2], b"f\0", "firmware lacks primitive {op}");
        (
            c - self.overhead_cycles,
            f32::from_le_bytes([answer[2], answer[3], answer[4], answer[5]]),
        )
    }

    /// Starts onboard motion `motion` of the firmware's engine (untimed; see
    /// `firmware_avr::bench`): true when it started.
    pub fn start_motion(&mut self, motion: u8) -> bool {
        self.emu.uart_write(&[b'M', motion]);
        let a = self
            .emu
            .read_exact(2, REQUEST_TIMEOUT_CYCLES * 20)
            .expect("motion start answer");
        assert_eq!(a[0], b'm');
        a[1] == 0
    }

    /// One servo frame of the running motion: cycles (overhead removed) and the stage.
    pub fn motion_frame(&mut self) -> (u64, u8) {
        let (c, answer) = self.timed(b"N", 3);
        assert_eq!(&answer[..2], b"n\0", "the firmware runs no motion");
        (c - self.overhead_cycles, answer[2])
    }

    /// Static SRAM and the stack high-water mark, bytes.
    pub fn memory(&mut self) -> (u16, u16) {
        self.emu.uart_write(b"S");
        let a = self
            .emu
            .read_exact(5, REQUEST_TIMEOUT_CYCLES)
            .expect("memory answer");
        assert_eq!(a[0], b's');
        (
            u16::from_le_bytes([a[1], a[2]]),
            u16::from_le_bytes([a[3], a[4]]),
        )
    }
}

/// Figures of one backend over all targets.
#[derive(Debug, Clone, Serialize)]
pub struct BackendFigures {
    /// Backend name and the ELF it ran in.
    pub name: String,
    /// Worst leg IK, cycles.
    pub leg_max_cycles: u64,
    /// Mean leg IK, cycles.
    pub leg_mean_cycles: f64,
    /// Worst body pose, cycles.
    pub body_max_cycles: u64,
    /// Mean body pose, cycles.
    pub body_mean_cycles: f64,
    /// Largest angle error vs the f64 reference, degrees.
    pub max_angle_err_deg: f64,
    /// Largest difference to the host's kin-core `Libm` result (x86, f32), rad.
    pub max_diff_to_host_libm_rad: f64,
}

/// Runs every target through one backend of one firmware.
pub fn measure_backend(
    fw: &mut BenchFirmware,
    backend: Backend,
    elf_name: &str,
    targets: &Targets,
) -> BackendFigures {
    let robot = robot();
    let config = BodyConfig::default();
    let (mut leg_max, mut leg_sum, mut body_max, mut body_sum) = (0u64, 0u64, 0u64, 0u64);
    let (mut err, mut host_diff) = (0.0f64, 0.0f64);
    for &(leg, foot) in &targets.legs {
        let (c, angles) = fw.leg(backend, leg, foot);
        let angles = angles.unwrap_or_else(|| panic!("{elf_name}: leg target unreachable"));
        let host = kin_core::leg::Solver::<Libm>::with_math(&robot)
            .inverse(leg, foot, ReachPolicy::Reject)
            .expect("host solves the leg target")
            .angles
            .to_array();
        let f = Vector3::new(foot.x as f64, foot.y as f64, foot.z as f64);
        let reference = reference_leg(&robot, leg, f, host);
        err = err.max(max_abs_diff(&angles, &reference));
        host_diff = host_diff.max(max_abs_diff(&angles, &host.map(|v| v as f64)));
        leg_max = leg_max.max(c);
        leg_sum += c;
    }
    for pose in &targets.poses {
        let (c, angles) = fw.body(backend, pose);
        let angles = angles.unwrap_or_else(|| panic!("{elf_name}: pose unreachable"));
        let host = body::Solver::<Libm>::with_math(&robot)
            .inverse_at_stance(pose, &config, STANCE_HEIGHT_M, ReachPolicy::Reject)
            .expect("host solves the pose")
            .flat();
        let reference = reference_body(&robot, pose, &host);
        err = err.max(max_abs_diff(&angles, &reference));
        host_diff = host_diff.max(max_abs_diff(&angles, &host.map(|v| v as f64)));
        body_max = body_max.max(c);
        body_sum += c;
    }
    BackendFigures {
        name: format!("{} ({elf_name})", backend.name()),
        leg_max_cycles: leg_max,
        leg_mean_cycles: leg_sum as f64 / targets.legs.len() as f64,
        body_max_cycles: body_max,
        body_mean_cycles: body_sum as f64 / targets.poses.len() as f64,
        max_angle_err_deg: err.to_degrees(),
        max_diff_to_host_libm_rad: host_diff,
    }
}

pub use quad_host::emu::elf::ElfSizes;

/// Flash and static SRAM of an ELF (`quad_host::emu::elf`).
pub fn elf_sizes(path: &Path) -> ElfSizes {
    elf::sizes(path).unwrap_or_else(|e| panic!("{e}"))
}

/// The stack paint byte of the firmware (`firmware_avr::stack::PAINT`).
pub const STACK_PAINT: u8 = 0xC5;

/// Boots the release firmware in the emulator, sets the benchmark's stance (height
/// [`STANCE_HEIGHT_M`], order zyx), runs body poses through its IK over the wire protocol,
/// and returns its static SRAM (from the ELF) and its stack high-water mark by the firmware's
/// own method (the SRAM painted at boot, read here), bytes.
pub fn firmware_memory(elf_path: &Path, poses: &[Pose]) -> (u16, u16) {
    let link = EmulatorLink::boot(elf_path, EmulatorConfig::new(115_200))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut client = Client::new(link, ClientConfig::emulator());
    client.hello().unwrap_or_else(|e| panic!("{e}"));
    client
        .ack(Request::SetPoseConfig(PoseConfig {
            stance_height_m: STANCE_HEIGHT_M,
            order: kin_core::RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        }))
        .unwrap_or_else(|e| panic!("{e}"));
    for pose in poses {
        let answer = client
            .request(Request::SetBodyPose(*pose))
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            matches!(answer, DeviceToHost::Ack { .. }),
            "firmware solves the pose: {answer:?}"
        );
    }
    let image = elf::Elf::read(elf_path).unwrap_or_else(|e| panic!("{e}"));
    let heap_start = image
        .data_symbol("__heap_start")
        .expect("the ELF defines __heap_start");
    let sizes = image.sizes();
    let stack = client
        .link()
        .mcu()
        .painted_stack_bytes(heap_start, STACK_PAINT);
    (sizes.sram_static_bytes as u16, stack)
}

/// The figures of the firmware issue, in its JSON field order.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Worst one-leg IK of the firmware's backend, cycles.
    pub leg_ik_cycles: u64,
    /// Worst body-pose solve (rotation + 4 legs) of the firmware's backend, cycles.
    pub body_pose_cycles: u64,
    /// Worst one-leg IK of the straightforward build, cycles.
    pub leg_ik_cycles_libm: u64,
    /// Worst body-pose solve of the straightforward build, cycles.
    pub body_pose_cycles_libm: u64,
    /// Largest angle error of the firmware's backend vs the f64 reference, degrees.
    pub max_angle_err_deg: f64,
    /// Flash of the release firmware ELF, bytes.
    pub flash_bytes: u64,
    /// Static SRAM of the release firmware ELF, bytes.
    pub sram_static_bytes: u64,
    /// Stack high-water mark of the release firmware after body-pose solves, bytes.
    pub max_stack_bytes: u64,
    /// Worst servo frame of an onboard trot (motion, body IK, limiter, pulses), cycles.
    pub trot_frame_cycles: u64,
    /// Its share of the 20 ms servo frame at 16 MHz, %.
    pub trot_frame_share_pct: f64,
}

/// Cycles of one 20 ms servo frame at 16 MHz.
pub const SERVO_FRAME_CYCLES: u64 = 16_000_000 / 50;

/// Onboard motions of the benchmark firmware, by id (`firmware_avr::bench`).
pub const MOTIONS: [&str; 4] = ["trot", "roll sway", "yaw turn", "rectangle (4 legs)"];

/// Servo frames timed per motion: 150 frames (3 s) cover several gait cycles of the trot,
/// the yaw turn's swings and the rectangle's loop at every phase class.
pub const MOTION_FRAMES: usize = 150;

/// Per-frame cycles of one onboard motion.
#[derive(Debug, Clone, Serialize)]
pub struct MotionFigures {
    /// The motion.
    pub name: &'static str,
    /// Worst frame, cycles.
    pub max_cycles: u64,
    /// Mean frame, cycles.
    pub mean_cycles: f64,
}

/// Times [`MOTION_FRAMES`] frames of each of [`MOTIONS`] on `fw`.
pub fn measure_motions(fw: &mut BenchFirmware) -> Vec<MotionFigures> {
    MOTIONS
        .iter()
        .enumerate()
        .map(|(id, &name)| {
            assert!(fw.start_motion(id as u8), "{name} refused by the firmware");
            let cycles: Vec<u64> = (0..MOTION_FRAMES).map(|_| fw.motion_frame().0).collect();
            MotionFigures {
                name,
                max_cycles: cycles.iter().copied().max().unwrap_or(0),
                mean_cycles: cycles.iter().sum::<u64>() as f64 / cycles.len() as f64,
            }
        })
        .collect()
}

/// Names of the primitives of `bench.elf` and `bench-libm.elf`, by op id.
pub const PRIMITIVES: [&str; 27] = [
    "add",
    "mul",
    "div",
    "sqrt",
    "atan2",
    "sin",
    "cos",
    "lt",
    "Fast::atan2",
    "Fast::sin_cos",
    "rotation matrix",
    "feet in hips",
    "poly::atan2_fixed",
    "poly::atan2_deg9",
    "poly::sin_cos_deg5",
    "poly::sin_cos_fixed",
    "AvrLibm::atan2_fixed",
    "AvrLibm::sin_cos_fixed",
    "poly::sin_cos_fixed sin|cos",
    "AvrLibm::sin_cos_fixed sin|cos",
    "sub",
    "avr-libc add",
    "avr-libc sub",
    "avr-libc mul",
    "avr-libc sqrt",
    "attitude update",
    "attitude update + roll, pitch",
];

/// The op id of a primitive of `bench.elf`, by its name in [`PRIMITIVES`].
///
/// # Panics
/// When the firmware has no primitive of that name.
pub fn primitive_op(name: &str) -> u8 {
    PRIMITIVES
        .iter()
        .position(|&n| n == name)
        .unwrap_or_else(|| panic!("bench.elf lacks {name}")) as u8
}

/// A float of the given biased exponent (0: zero or subnormal, 255: infinity or NaN), random
/// mantissa (none at all one time in eight) and sign: the kernels' bit-exact tests' arguments.
pub fn random_float(rng: &mut SplitMix64, exponent: u32) -> f32 {
    let bits = rng.next_u64();
    let mantissa = if bits & 7 == 0 {
        0
    } else {
        (bits >> 8) as u32 & 0x7f_ffff
    };
    f32::from_bits(((bits >> 40) as u32 & 1) << 31 | exponent << 23 | mantissa)
}

/// Mean cycles of primitive `op` over a few arguments.
pub fn primitive_cycles(fw: &mut BenchFirmware, op: u8) -> f64 {
    let args = [
        (0.3f32, 0.2f32),
        (0.4, -0.2),
        (-0.05, 0.3),
        (0.21, 0.11),
        (-0.4, 0.35),
    ];
    let total: u64 = args.iter().map(|&(a, b)| fw.primitive(op, a, b).0).sum();
    total as f64 / args.len() as f64
}

/// Everything one run measured.
#[derive(Debug, Clone)]
pub struct Report {
    /// Mean cycles of each primitive: (name, `bench.elf`, `bench-libm.elf` when it has it).
    pub primitives: Vec<(&'static str, f64, Option<f64>)>,
    /// Per backend and ELF.
    pub backends: Vec<BackendFigures>,
    /// Stack high-water mark of `bench.elf` after all its solves, bytes.
    pub bench_stack_bytes: u16,
    /// Per-frame cycles of the onboard motions (`bench.elf`).
    pub motions: Vec<MotionFigures>,
    /// The JSON figures.
    pub summary: Summary,
}

/// Builds the release ELFs and measures everything.
pub fn run() -> Report {
    let targets = targets();
    let elf_of = |bin| build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
    let bench_elf = elf_of(build::BENCH);
    let libm_elf = elf_of(build::BENCH_LIBM);
    let firmware = elf_of(build::FIRMWARE);

    let mut fw = BenchFirmware::boot(&bench_elf);
    let mut backends = Vec::new();
    for b in [
        Backend::AvrLibm,
        Backend::Fast,
        Backend::Libm,
        Backend::AvrFast,
        Backend::AvrFastPerCall,
    ] {
        backends.push(measure_backend(&mut fw, b, "bench.elf", &targets));
    }
    let motions = measure_motions(&mut fw);
    let (_, bench_stack_bytes) = fw.memory();
    let mut fw_libm = BenchFirmware::boot(&libm_elf);
    let libm = measure_backend(&mut fw_libm, Backend::Libm, "bench-libm.elf", &targets);
    backends.push(libm.clone());

    let primitives = PRIMITIVES
        .iter()
        .enumerate()
        .map(|(op, &name)| {
            let op = op as u8;
            let libm = (op < 5).then(|| primitive_cycles(&mut fw_libm, op));
            (name, primitive_cycles(&mut fw, op), libm)
        })
        .collect();
    let chosen = backends
        .iter()
        .find(|b| b.name == format!("{} (bench.elf)", FIRMWARE_BACKEND.name()))
        .expect("the firmware's backend was measured");
    let sizes = elf_sizes(&firmware);
    let (_, stack) = firmware_memory(&firmware, &targets.poses[..4]);
    Report {
        summary: Summary {
            leg_ik_cycles: chosen.leg_max_cycles,
            body_pose_cycles: chosen.body_max_cycles,
            leg_ik_cycles_libm: libm.leg_max_cycles,
            body_pose_cycles_libm: libm.body_max_cycles,
            max_angle_err_deg: chosen.max_angle_err_deg,
            flash_bytes: sizes.flash_bytes,
            sram_static_bytes: sizes.sram_static_bytes,
            max_stack_bytes: stack as u64,
            trot_frame_cycles: motions[0].max_cycles,
            trot_frame_share_pct: 100.0 * motions[0].max_cycles as f64 / SERVO_FRAME_CYCLES as f64,
        },
        motions,
        backends,
        bench_stack_bytes,
        primitives,
    }
}
