//! The cycle benchmark's request loop, shared by the `bench` (avr-libc) and `bench-libm`
//! (plain Rust soft-float) binaries.
//!
//! The host sends targets over USART0 and times each solve by the cycles between the rising
//! and the falling edge of the marker pin [`MARKER`] (PA0, Mega header D22), which is high
//! exactly around the call. In simavr the host counts the cycles between the two edges; on a
//! real board a logic analyser does the same.
//!
//! Wire format (all little-endian, f32 as IEEE-754 bits):
//!
//! | request | bytes | answer |
//! |---|---|---|
//! | empty call (marker overhead) | `E` | `e` |
//! | one leg IK | `L`, backend u8, leg u8, x y z f32 (hip frame, m) | `l`, status u8, abduction hip knee f32 |
//! | body pose at the stance | `B`, backend u8, roll pitch yaw x y z f32 | `b`, status u8, 12 × f32 |
//! | memory | `S` | `s`, static SRAM u16, max stack u16 |
//! | one primitive | `F`, op u8, a b f32 | `f`, status u8, result f32 |
//! | start an onboard motion (untimed) | `M`, motion u8 | `m`, status u8 |
//! | one servo frame of it | `N` | `n`, status u8, stage u8 |
//!
//! Motions of `M` ([`EngineBench`]): 0 = trot at a forward speed and yaw rate within the
//! gait's reach, 1 = seed 001's roll sway, 2 = seed 001's yaw turn (its rate and period, a lift
//! this robot reaches), 3 = seed 000's rectangle on all four legs; each starts from the stance of [`quad_device::Config::shahriar2023`] (the
//! firmware's configuration) and its approach ramp is run before the timed frames. A timed
//! frame is what `Device::poll` does at a servo frame boundary: the engine's tick (the motion
//! and its body IK), the limiter step of the twelve outputs and their calibrated pulses.
//!
//! Status 0 = solved, 1 = unreachable, 2 = unknown backend. Boot sends `R` once ready.
//! Robot: [`kin_core::Robot::shahriar2023`] with its knee bend and limits; body poses about
//! the body centre in rotation order zyx, feet held at the stance of height
//! [`STANCE_HEIGHT_M`]; [`kin_core::ReachPolicy::Reject`]. Each backend's solver is built once
//! at boot, as the firmware builds its own ([`Prepared`]), except the one of [`PerCall`].

use crate::pac;
use crate::usart::Usart0;
use core::marker::PhantomData;
use kin_core::motion::gait::{GaitParams, Pattern, Velocity};
use kin_core::motion::laws::Axis;
use kin_core::{body, BodyConfig, IkError, LegId, Math, Pose, ReachPolicy, Robot, Vec3};
use quad_device::engine::{self, Engine, Limiter, PulseMaps, Setup, FRAME_MS};
use quad_device::{default_calibration, Config};
use quad_protocol::{LegSet, MotionCommand as Request, MotionStage};

/// Stance height of the body-pose benchmark: seed 000 Table 4 body height, m.
pub const STANCE_HEIGHT_M: f32 = 0.277;

/// The marker pin: PA0 (D22), written as `pa0` (the PAC's field); this is its bit.
pub const MARKER: u8 = 0;

/// The robot of the benchmark.
pub const ROBOT: Robot = Robot::shahriar2023();

/// One float primitive under test, `op(a, b)` (unary ones ignore `b`).
pub type PrimFn = fn(f32, f32) -> f32;

/// The IK of one math backend under test.
pub trait Solve {
    /// One leg IK under [`ReachPolicy::Reject`]: the abduction, hip and knee angles.
    fn leg(&self, leg_id: LegId, foot_in_hip: Vec3) -> Result<[f32; 3], IkError>;
    /// One body pose at the stance of [`STANCE_HEIGHT_M`] under [`ReachPolicy::Reject`]: the
    /// twelve angles.
    fn body(&self, pose: &Pose) -> Result<[f32; 12], IkError>;
}

/// A math backend under test: the id the host selects it by, and its IK.
pub struct Backend<'a> {
    /// The id the host selects it by.
    pub id: u8,
    /// Its IK.
    pub solve: &'a dyn Solve,
}

/// kin-core's IK on backend `M` as the firmware runs it: the solver built once (the device
/// builds its own at boot), its constants read from memory at every solve.
pub struct Prepared<M: Math> {
    solver: body::Solver<M>,
}

impl<M: Math> Prepared<M> {
    /// The solver of `robot`, built now.
    pub fn new(robot: &Robot) -> Self {
        Prepared {
            solver: body::Solver::with_math(robot),
        }
    }
}

impl<M: Math> Solve for Prepared<M> {
    #[inline(never)]
    fn leg(&self, leg_id: LegId, foot_in_hip: Vec3) -> Result<[f32; 3], IkError> {
        self.solver
            .leg()
            .inverse(leg_id, foot_in_hip, ReachPolicy::Reject)
            .map(|s| s.angles.to_array())
    }

    #[inline(never)]
    fn body(&self, pose: &Pose) -> Result<[f32; 12], IkError> {
        // As the device solves a pose: into a solution in its own frame, read in place.
        let mut solution = body::BodySolution::default();
        self.solver.inverse_at_stance_into(
            pose,
            &BodyConfig::default(),
            STANCE_HEIGHT_M,
            ReachPolicy::Reject,
            &mut solution,
        )?;
        Ok(solution.angles_rad)
    }
}

/// kin-core's IK on backend `M` with the solver built from the robot inside every timed call
/// (the robot behind [`core::hint::black_box`], so that its constants are computed each time):
/// the benchmark's form before it measured the firmware's [`Prepared`] one.
pub struct PerCall<M: Math> {
    robot: Robot,
    math: PhantomData<M>,
}

impl<M: Math> PerCall<M> {
    /// The IK of `robot`, its solver built per call.
    pub const fn new(robot: Robot) -> Self {
        PerCall {
            robot,
            math: PhantomData,
        }
    }
}

impl<M: Math> Solve for PerCall<M> {
    #[inline(never)]
    fn leg(&self, leg_id: LegId, foot_in_hip: Vec3) -> Result<[f32; 3], IkError> {
        Prepared::<M>::new(core::hint::black_box(&self.robot)).leg(leg_id, foot_in_hip)
    }

    #[inline(never)]
    fn body(&self, pose: &Pose) -> Result<[f32; 12], IkError> {
        Prepared::<M>::new(core::hint::black_box(&self.robot)).body(pose)
    }
}

const STATUS_OK: u8 = 0;
const STATUS_UNREACHABLE: u8 = 1;
const STATUS_UNKNOWN_BACKEND: u8 = 2;

fn read_byte(usart: &mut Usart0) -> u8 {
    loop {
        if let Some(b) = usart.read() {
            return b;
        }
    }
}

fn read_f32(usart: &mut Usart0) -> f32 {
    let mut b = [0u8; 4];
    for x in &mut b {
        *x = read_byte(usart);
    }
    f32::from_le_bytes(b)
}

fn marker(porta: &pac::PORTA, high: bool) {
    porta.porta().modify(|_, w| w.pa0().bit(high));
}

/// Onboard motion frames under test (requests `M` and `N`).
pub trait MotionBench {
    /// Starts motion `motion` and runs its approach (untimed): a status.
    fn start(&mut self, motion: u8) -> u8;
    /// One servo frame: a status and the motion's stage.
    fn frame(&mut self) -> (u8, u8);
}

/// A firmware without the motion engine.
pub struct NoMotion;

impl MotionBench for NoMotion {
    fn start(&mut self, _: u8) -> u8 {
        STATUS_UNKNOWN_BACKEND
    }
    fn frame(&mut self) -> (u8, u8) {
        (STATUS_UNKNOWN_BACKEND, 0)
    }
}

/// The device's motion engine on backend `M` with the firmware's configuration.
pub struct EngineBench<M: Math> {
    config: Config,
    solver: body::Solver<M>,
    /// The calibration's pulse maps, as the device holds them.
    pulse_maps: PulseMaps,
    engine: Engine<M>,
    out: [f32; 12],
    pulses: [u16; 12],
    now_ms: u32,
}

impl<M: Math> EngineBench<M> {
    /// Idle, the outputs at the stance (zeros when it is out of reach).
    pub fn new() -> Self {
        let config = Config::shahriar2023();
        let calibration = default_calibration::<M>(&config.robot, &config.pose_config);
        let limiter = Limiter::new(config.joint_speed_limit_rad_s).unwrap_or_else(|_| {
            Limiter::new(engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S).unwrap_or_else(|_| panic!())
        });
        let out = calibration.map(|c| c.zero_rad);
        EngineBench {
            solver: body::Solver::with_math(&config.robot),
            config,
            pulse_maps: calibration.map(|c| c.pulse_map().unwrap_or_else(|_| panic!())),
            engine: Engine::new(limiter),
            out,
            pulses: [0; 12],
            now_ms: 0,
        }
    }

    fn tick(&mut self) -> MotionStage {
        self.now_ms += FRAME_MS;
        let tick = self
            .engine
            .tick(1, self.now_ms, &self.out, &self.solver, None);
        if let Some(target) = tick.target {
            self.engine.limiter().step(&mut self.out, &target);
        }
        for ((p, c), &a) in self.pulses.iter_mut().zip(&self.pulse_maps).zip(&self.out) {
            *p = c.pulse_half_us(a).unwrap_or(0);
        }
        core::hint::black_box(&self.pulses);
        self.engine.status().stage
    }
}

impl<M: Math> Default for EngineBench<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Math> MotionBench for EngineBench<M> {
    fn start(&mut self, motion: u8) -> u8 {
        self.engine.cancel();
        let h = self.config.pose_config.stance_height_m;
        let request = match motion {
            0 => Request::walk(Pattern::Trot, h),
            1 => Request::seed001_sway(Axis::Roll, None),
            // Seed 001's rate and period with a lift that this robot reaches (the paper's
            // 0.3 m is for its own, larger robot).
            2 => match Request::seed001_yaw_turn(None) {
                Request::YawTurn {
                    yaw_rate_rad_s,
                    step_period_s,
                    ..
                } => Request::YawTurn {
                    yaw_rate_rad_s,
                    step_period_s,
                    lift_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
                    duration_s: None,
                },
                other => other,
            },
            3 => Request::seed000_rectangle(LegSet::All, None),
            _ => return STATUS_UNKNOWN_BACKEND,
        };
        let setup = Setup {
            robot: &self.config.robot,
            solver: &self.solver,
            stance_height_m: h,
            order: self.config.pose_config.order,
            pulse_maps: &self.pulse_maps,
            outputs: Some(&self.out),
            now_ms: self.now_ms,
        };
        if self.engine.start(&request, &setup).is_err() {
            return STATUS_UNREACHABLE;
        }
        for _ in 0..500 {
            if self.tick() == MotionStage::Run {
                break;
            }
        }
        if motion == 0 {
            // Forward and turning within the gait's reach.
            let mut v = Velocity {
                forward_m_s: 0.2,
                lateral_m_s: 0.0,
                yaw_rad_s: 0.2,
            };
            while self.engine.set_velocity(v, self.now_ms).is_err() && v.forward_m_s > 1e-3 {
                v.forward_m_s *= 0.5;
                v.yaw_rad_s *= 0.5;
            }
        }
        STATUS_OK
    }

    fn frame(&mut self) -> (u8, u8) {
        let stage = self.tick();
        (STATUS_OK, stage as u8)
    }
}

/// Serves benchmark requests forever (see the module docs). Interrupts must be enabled (the
/// receiver is interrupt-driven).
pub fn serve(
    usart: &mut Usart0,
    porta: &pac::PORTA,
    backends: &[Backend<'_>],
    prims: &[PrimFn],
    motion: &mut dyn MotionBench,
) -> ! {
    // PA0 becomes an output, low.
    marker(porta, false);
    porta.ddra().modify(|_, w| w.pa0().set_bit());
    usart.write(b'R');
    loop {
        match read_byte(usart) {
            b'E' => {
                marker(porta, true);
                core::hint::black_box(());
                marker(porta, false);
                usart.write(b'e');
            }
            b'L' => {
                let backend = read_byte(usart);
                let leg_id = LegId::from_index(read_byte(usart) as usize & 3).unwrap_or(LegId::FL);
                let foot = Vec3::new(read_f32(usart), read_f32(usart), read_f32(usart));
                usart.write(b'l');
                match backends.iter().find(|b| b.id == backend) {
                    Some(b) => {
                        let solve = core::hint::black_box(b.solve);
                        marker(porta, true);
                        let r = solve.leg(leg_id, foot);
                        marker(porta, false);
                        send_result(usart, r.as_ref().map(|a| &a[..]), 3);
                    }
                    None => send_status(usart, STATUS_UNKNOWN_BACKEND, 3),
                }
            }
            b'B' => {
                let backend = read_byte(usart);
                let mut a = [0.0f32; 6];
                for v in &mut a {
                    *v = read_f32(usart);
                }
                let pose = Pose::from_array(a);
                usart.write(b'b');
                match backends.iter().find(|b| b.id == backend) {
                    Some(b) => {
                        let solve = core::hint::black_box(b.solve);
                        marker(porta, true);
                        let r = solve.body(&pose);
                        marker(porta, false);
                        send_result(usart, r.as_ref().map(|a| &a[..]), 12);
                    }
                    None => send_status(usart, STATUS_UNKNOWN_BACKEND, 12),
                }
            }
            b'F' => {
                let op = read_byte(usart) as usize;
                let (a, b) = (read_f32(usart), read_f32(usart));
                usart.write(b'f');
                match prims.get(op) {
                    Some(f) => {
                        let (a, b) = core::hint::black_box((a, b));
                        marker(porta, true);
                        let r = f(a, b);
                        marker(porta, false);
                        send_result(usart, Ok(&[r]), 1);
                    }
                    None => send_status(usart, STATUS_UNKNOWN_BACKEND, 1),
                }
            }
            b'M' => {
                let m = read_byte(usart);
                let status = motion.start(m);
                usart.write(b'm');
                usart.write(status);
            }
            b'N' => {
                marker(porta, true);
                let (status, stage) = motion.frame();
                marker(porta, false);
                usart.write(b'n');
                usart.write(status);
                usart.write(stage);
            }
            b'S' => {
                usart.write(b's');
                usart.write_all(&crate::stack::static_bytes().to_le_bytes());
                usart.write_all(&crate::stack::max_used_bytes().to_le_bytes());
            }
            _ => {}
        }
    }
}

fn send_result(usart: &mut Usart0, r: Result<&[f32], &IkError>, n: usize) {
    match r {
        Ok(angles) => {
            usart.write(STATUS_OK);
            for a in angles {
                usart.write_all(&a.to_le_bytes());
            }
        }
        Err(_) => send_status(usart, STATUS_UNREACHABLE, n),
    }
}

/// A failure status followed by `n` NaN-free zero angles (fixed answer length).
fn send_status(usart: &mut Usart0, status: u8, n: usize) {
    usart.write(status);
    for _ in 0..n {
        usart.write_all(&0.0f32.to_le_bytes());
    }
}
