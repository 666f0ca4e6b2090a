//! The AVR kernels checked against their twins, bit for bit, in simavr: the harness that streams
//! argument pairs through a kernel of the test harness firmware (`harness.elf`,
//! `firmware_avr::harness`) from memory, and the twins.
//!
//! The harness ([`Harness`]) writes up to 128 pairs straight into the firmware's
//! `KERNEL_BATCH` in simavr's memory, sends one 4-byte `K` request,
//! and reads the results back from memory: the UART carries no arguments, so the emulator's
//! time goes to the kernel. The kernels and their twins ([`Kernel`]):
//!
//! | kernel | what runs on the AVR | its twin |
//! |---|---|---|
//! | `atan2_fixed` | `AvrLibm::atan2_fixed` (asm) | `poly::atan2_fixed::<SoftFloat>` on the host |
//! | `sin_cos_fixed` | `AvrLibm::sin_cos_fixed` (asm core) | `poly::sin_cos_fixed::<SoftFloat>` on the host |
//! | `atan2_fixed portable`, `sin_cos_fixed portable` | the portable kernels compiled for the AVR | the same on the host |
//! | `add`, `sub`, `mul`, `sqrt` | the firmware's float primitives (`avr_libc_math::float`, `sqrt`) | avr-libc's own routines, in the same record |
//!
//! The classes of arguments each kernel is checked on are in [`crate::kernel_edges`].

use kin_core::math::{poly, SoftFloat};
use quad_host::emu::{build, elf, Mega2560};
use std::time::{Duration, Instant};

/// Argument pairs of one batch: `firmware_avr::harness::KERNEL_BATCH_LEN`.
pub const BATCH_LEN: usize = 128;

/// Records of one pose batch: `firmware_avr::harness::POSE_BATCH_LEN` (52-byte records in the
/// same 1,024 bytes).
pub const POSE_BATCH_LEN: usize = BATCH_LEN * 8 / 52;

/// Cycles allowed for one batch (128 evaluations of the slowest kernel, with a wide margin).
const BATCH_TIMEOUT_CYCLES: u64 = 50_000_000;

/// A kernel of the harness, by its id in the harness firmware's table (`KERNELS`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// The firmware's arctangent, `AvrLibm::atan2_fixed` (asm); arguments `(y, x)`.
    Atan2Fixed = 0,
    /// `poly::atan2_fixed` compiled for the AVR.
    Atan2FixedPortable = 1,
    /// The firmware's sine and cosine, `AvrLibm::sin_cos_fixed`; argument `x`.
    SinCosFixed = 2,
    /// `poly::sin_cos_fixed` compiled for the AVR.
    SinCosFixedPortable = 3,
    /// The firmware's `__addsf3` (fast path in front of avr-libc's).
    Add = 4,
    /// The firmware's `__subsf3`.
    Sub = 5,
    /// The firmware's `__mulsf3`.
    Mul = 6,
    /// The firmware's `sqrt` (avr-libc's bits, in fewer cycles).
    Sqrt = 7,
}

impl Kernel {
    /// Every kernel, in id order.
    pub const ALL: [Kernel; 8] = [
        Kernel::Atan2Fixed,
        Kernel::Atan2FixedPortable,
        Kernel::SinCosFixed,
        Kernel::SinCosFixedPortable,
        Kernel::Add,
        Kernel::Sub,
        Kernel::Mul,
        Kernel::Sqrt,
    ];

    /// Its name in reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Atan2Fixed => "atan2_fixed",
            Kernel::Atan2FixedPortable => "atan2_fixed_portable",
            Kernel::SinCosFixed => "sin_cos_fixed",
            Kernel::SinCosFixedPortable => "sin_cos_fixed_portable",
            Kernel::Add => "add",
            Kernel::Sub => "sub",
            Kernel::Mul => "mul",
            Kernel::Sqrt => "sqrt",
        }
    }

    /// The kernel called `name` ([`Kernel::name`]).
    pub fn named(name: &str) -> Option<Kernel> {
        Kernel::ALL.into_iter().find(|k| k.name() == name)
    }

    /// How many results the kernel has: the sine and cosine two, the others one (the rest of
    /// a record is not compared).
    pub fn results(self) -> usize {
        match self {
            Kernel::SinCosFixed | Kernel::SinCosFixedPortable => 2,
            _ => 1,
        }
    }

    /// What the AVR's results `got` must equal, bit for bit, for the arguments `(a, b)`:
    /// the twin's results (the first [`Kernel::results`] words count).
    pub fn twin(self, [a, b]: [u32; 2], got: [u32; 2]) -> [u32; 2] {
        let (fa, fb) = (f32::from_bits(a), f32::from_bits(b));
        match self {
            Kernel::Atan2Fixed | Kernel::Atan2FixedPortable => {
                [poly::atan2_fixed::<SoftFloat>(fa, fb).to_bits(), 0]
            }
            Kernel::SinCosFixed | Kernel::SinCosFixedPortable => {
                let (s, c) = poly::sin_cos_fixed::<SoftFloat>(fa);
                [s.to_bits(), c.to_bits()]
            }
            // The record holds avr-libc's result beside the firmware's.
            Kernel::Add | Kernel::Sub | Kernel::Mul | Kernel::Sqrt => [got[1], 0],
        }
    }
}

/// One argument pair whose results differ from the twin's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Finding {
    /// The kernel.
    pub kernel: Kernel,
    /// The class of arguments it came from.
    pub class: &'static str,
    /// The arguments' bits.
    pub args: [u32; 2],
    /// The AVR's results' bits.
    pub avr: [u32; 2],
    /// The twin's.
    pub twin: [u32; 2],
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b] = self.args;
        let fl = |w: u32| f32::from_bits(w);
        write!(
            f,
            "{} [{}]: args {a:#010x} ({:e}), {b:#010x} ({:e}): AVR {:#010x} {:#010x} ({:e}, {:e}), twin {:#010x} {:#010x} ({:e}, {:e})",
            self.kernel.name(),
            self.class,
            fl(a),
            fl(b),
            self.avr[0],
            self.avr[1],
            fl(self.avr[0]),
            fl(self.avr[1]),
            self.twin[0],
            self.twin[1],
            fl(self.twin[0]),
            fl(self.twin[1]),
        )
    }
}

/// The test harness firmware (`harness.elf`), booted.
pub struct Harness {
    emu: Mega2560,
    batch_addr: u16,
    /// Evaluations run so far.
    pub evaluations: u64,
    /// Wall time spent in batches.
    pub busy: Duration,
}

impl Harness {
    /// Builds (once per process) and boots `harness.elf`.
    ///
    /// # Panics
    /// When the firmware cannot be built or booted, or lacks the batch.
    pub fn boot() -> Harness {
        let path = build::firmware_elf(build::HARNESS).unwrap_or_else(|e| panic!("{e}"));
        let batch_addr = elf::Elf::read(&path)
            .unwrap_or_else(|e| panic!("{e}"))
            .data_symbol("KERNEL_BATCH")
            .expect("harness.elf exports KERNEL_BATCH");
        let mut emu = Mega2560::new(&path).unwrap_or_else(|e| panic!("{e}"));
        let ready = emu
            .read_exact(1, 1_000_000)
            .expect("the harness firmware sends 'R' at boot");
        assert_eq!(ready, b"R", "harness firmware boot byte");
        Harness {
            emu,
            batch_addr,
            evaluations: 0,
            busy: Duration::ZERO,
        }
    }

    /// The AVR's results of `kernel` for every pair of `args`, in order.
    ///
    /// # Panics
    /// When the firmware does not answer a batch.
    pub fn run(&mut self, kernel: Kernel, args: &[[u32; 2]]) -> Vec<[u32; 2]> {
        let started = Instant::now();
        let mut out = Vec::with_capacity(args.len());
        for chunk in args.chunks(BATCH_LEN) {
            let bytes: Vec<u8> = chunk
                .iter()
                .flat_map(|[a, b]| a.to_le_bytes().into_iter().chain(b.to_le_bytes()))
                .collect();
            self.emu.write_data(self.batch_addr, &bytes);
            let n = chunk.len() as u16;
            let [lo, hi] = n.to_le_bytes();
            self.emu.uart_write(&[b'K', kernel as u8, lo, hi]);
            let answer = self
                .emu
                .read_exact(2, BATCH_TIMEOUT_CYCLES)
                .unwrap_or_else(|got| panic!("no answer to a {} batch: {got:?}", kernel.name()));
            assert_eq!(answer, b"k\0", "{} batch refused", kernel.name());
            let results = self.emu.data_bytes(self.batch_addr, 8 * chunk.len());
            out.extend(results.chunks_exact(8).map(|r| {
                [
                    u32::from_le_bytes([r[0], r[1], r[2], r[3]]),
                    u32::from_le_bytes([r[4], r[5], r[6], r[7]]),
                ]
            }));
        }
        self.evaluations += args.len() as u64;
        self.busy += started.elapsed();
        out
    }

    /// The records of the pose batch (`firmware_avr::harness::PoseRecord`) solved by the
    /// firmware's IK, in order.
    ///
    /// # Panics
    /// When the firmware does not answer a batch.
    pub fn run_poses(&mut self, records: &[[u32; 13]]) -> Vec<[u32; 13]> {
        let started = Instant::now();
        let mut out = Vec::with_capacity(records.len());
        for chunk in records.chunks(POSE_BATCH_LEN) {
            let bytes: Vec<u8> = chunk
                .iter()
                .flatten()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            self.emu.write_data(self.batch_addr, &bytes);
            self.emu.uart_write(&[b'P', chunk.len() as u8]);
            let answer = self
                .emu
                .read_exact(2, BATCH_TIMEOUT_CYCLES)
                .unwrap_or_else(|got| panic!("no answer to a pose batch: {got:?}"));
            assert_eq!(answer, b"p\0", "pose batch refused");
            let results = self.emu.data_bytes(self.batch_addr, 52 * chunk.len());
            out.extend(results.chunks_exact(52).map(|r| {
                std::array::from_fn(|i| {
                    u32::from_le_bytes([r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]])
                })
            }));
        }
        self.evaluations += records.len() as u64;
        self.busy += started.elapsed();
        out
    }

    /// The pairs of `args` whose AVR results differ from the twin's (`class` names them).
    pub fn check(
        &mut self,
        kernel: Kernel,
        class: &'static str,
        args: &[[u32; 2]],
    ) -> Vec<Finding> {
        let got = self.run(kernel, args);
        args.iter()
            .zip(got)
            .filter_map(|(&args, avr)| {
                let twin = kernel.twin(args, avr);
                let n = kernel.results();
                let same = avr[..n] == twin[..n];
                (!same).then_some(Finding {
                    kernel,
                    class,
                    args,
                    avr,
                    twin,
                })
            })
            .collect()
    }

    /// Evaluations per second of wall time so far.
    pub fn evaluations_per_s(&self) -> f64 {
        self.evaluations as f64 / self.busy.as_secs_f64().max(1e-9)
    }
}

/// What a run of one kernel over its classes found.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct KernelReport {
    /// The kernel's name.
    pub kernel: String,
    /// `(class, evaluations, mismatches)` per class, in class order.
    pub classes: Vec<(String, u64, u64)>,
    /// Evaluations in all.
    pub evaluations: u64,
    /// Mismatches in all.
    pub mismatches: u64,
    /// Evaluations per second of wall time (the AVR's and the twin's together).
    pub evaluations_per_s: f64,
    /// The first findings, as [`Finding`]'s display.
    pub first_findings: Vec<String>,
}

/// Runs `kernel` on `harness` over the share `plan` of `classes` ([`crate::kernel_edges`]),
/// calling `progress` after every 2¹⁶ evaluations and after each class; keeps the first 20
/// findings.
pub fn run_plan(
    harness: &mut Harness,
    kernel: Kernel,
    classes: &[crate::kernel_edges::Class],
    plan: &[crate::kernel_edges::Part],
    mut progress: impl FnMut(&KernelReport),
) -> KernelReport {
    let started = Instant::now();
    let mut report = KernelReport {
        kernel: kernel.name().to_string(),
        ..KernelReport::default()
    };
    for part in plan {
        let class = &classes[part.class];
        report.classes.push((class.name.to_string(), 0, 0));
        let mut values = crate::kernel_edges::sample(class, part).peekable();
        while values.peek().is_some() {
            let chunk: Vec<[u32; 2]> = values.by_ref().take(1 << 16).collect();
            let findings = harness.check(kernel, class.name, &chunk);
            let row = report.classes.last_mut().expect("pushed above");
            row.1 += chunk.len() as u64;
            row.2 += findings.len() as u64;
            report.evaluations += chunk.len() as u64;
            report.mismatches += findings.len() as u64;
            for f in findings {
                if report.first_findings.len() < 20 {
                    report.first_findings.push(f.to_string());
                }
            }
            report.evaluations_per_s =
                report.evaluations as f64 / started.elapsed().as_secs_f64().max(1e-9);
            progress(&report);
        }
    }
    report
}
