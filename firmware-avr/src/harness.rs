//! The test harness firmware's request loop (`harness` binary): the firmware's kernels and its
//! IK run over batches that the host writes straight into SRAM, in simavr, so that the host can
//! check them against their twins at the speed of the emulator rather than of the UART (the
//! host side: `integration_tests::kernels` and `integration_tests::end_to_end`).
//!
//! A binary of its own rather than requests of the benchmark firmware: the benchmark measures
//! cycles, and code added to its image moves its figures.
//!
//! Wire format (little-endian):
//!
//! | request | bytes | answer |
//! |---|---|---|
//! | a kernel over the batch | `K`, kernel u8, count u16 | `k`, status u8 |
//! | the IK over the batch | `P`, count u8 | `p`, status u8 |
//!
//! `K`: the host writes up to [`KERNEL_BATCH_LEN`] argument pairs into [`KERNEL_BATCH`], the
//! firmware replaces each pair by the two results of kernel `kernel` of its table
//! ([`KernelFn`]). `P`: up to [`POSE_BATCH_LEN`] records ([`PoseRecord`]) in the same memory,
//! each replaced by its solution. Status 0 done, 2 an unknown kernel or a count beyond the
//! batch. Boot sends `R` once ready.

use crate::usart::Usart0;
use kin_core::{body, BodyConfig, LegId, Math, Pose, ReachPolicy, RotationOrder, Vec3};

/// One kernel under test: the two results of its arguments `(a, b)`, as bits (a kernel of one
/// result, or of one argument, ignores the rest).
pub type KernelFn = fn(u32, u32) -> (u32, u32);

/// Argument pairs of one batch ([`KERNEL_BATCH`]).
pub const KERNEL_BATCH_LEN: usize = 128;

/// The batch: argument pairs written by the host, replaced by the results. Exported under its
/// own name, so that the host finds it in the ELF's symbols.
#[no_mangle]
pub static mut KERNEL_BATCH: [[u32; 2]; KERNEL_BATCH_LEN] = [[0; 2]; KERNEL_BATCH_LEN];

/// One record of a pose batch (`P`): word 0 the bytes `[target, order, policy, status]`, then
/// twelve floats. `target` 0–3 is a leg (its foot in the hip frame in floats 0–2, its three
/// angles out), 255 the body (roll pitch yaw x y z and the stance height in floats 0–6, the
/// twelve angles out, about the body centre); `order` indexes [`RotationOrder::ALL`],
/// `policy` is 0 reject or 1 clamp; `status` out: bit 0 refused, bits 4–7 the legs clamped.
pub type PoseRecord = [u32; 13];

/// Pose records of one batch: as many as fit in [`KERNEL_BATCH`], whose memory they share.
pub const POSE_BATCH_LEN: usize =
    core::mem::size_of::<[[u32; 2]; KERNEL_BATCH_LEN]>() / core::mem::size_of::<PoseRecord>();

/// Runs `kernel` over the first `count` pairs of [`KERNEL_BATCH`], in place.
fn run_kernel_batch(kernel: KernelFn, count: usize) {
    let batch = core::ptr::addr_of_mut!(KERNEL_BATCH).cast::<[u32; 2]>();
    for i in 0..count.min(KERNEL_BATCH_LEN) {
        // SAFETY: `i` is within the batch; volatile, because the host writes the pairs behind
        // the program's back; nothing else uses the batch.
        unsafe {
            let slot = batch.add(i);
            let [a, b] = core::ptr::read_volatile(slot);
            let (r0, r1) = kernel(a, b);
            core::ptr::write_volatile(slot, [r0, r1]);
        }
    }
}

/// Solves the first `count` records of the pose batch with `solver`, in place.
fn run_pose_batch<M: Math>(solver: &body::Solver<M>, count: usize) {
    let batch = core::ptr::addr_of_mut!(KERNEL_BATCH).cast::<PoseRecord>();
    for i in 0..count.min(POSE_BATCH_LEN) {
        // SAFETY: record `i` lies within the batch's memory (`POSE_BATCH_LEN`); volatile, as
        // in `run_kernel_batch`.
        unsafe {
            let slot = batch.add(i);
            let mut record = core::ptr::read_volatile(slot);
            let (status, angles) = solve(solver, &record);
            record[0] = (record[0] & 0x00ff_ffff) | u32::from(status) << 24;
            for (w, a) in record[1..].iter_mut().zip(angles) {
                *w = a.to_bits();
            }
            core::ptr::write_volatile(slot, record);
        }
    }
}

/// The status byte and the angles of one record (see [`PoseRecord`]).
fn solve<M: Math>(solver: &body::Solver<M>, record: &PoseRecord) -> (u8, [f32; 12]) {
    let [target, order, policy, _] = record[0].to_le_bytes();
    let f = |k: usize| f32::from_bits(record[1 + k]);
    let policy = if policy == 1 {
        ReachPolicy::Clamp
    } else {
        ReachPolicy::Reject
    };
    let mut angles = [0.0; 12];
    if target == 255 {
        // As the device solves a pose: into a solution of its own, read in place.
        let pose = Pose::from_array([f(0), f(1), f(2), f(3), f(4), f(5)]);
        let config = BodyConfig::about_centre(RotationOrder::ALL[usize::from(order) % 6]);
        let mut solution = body::BodySolution::default();
        match solver.inverse_at_stance_into(&pose, &config, f(6), policy, &mut solution) {
            Ok(()) => {
                let clamped = solution
                    .clamped
                    .iter()
                    .enumerate()
                    .fold(0u8, |m, (i, c)| m | u8::from(c.is_some()) << i);
                (clamped << 4, solution.angles_rad)
            }
            Err(_) => (1, angles),
        }
    } else {
        let leg = LegId::from_index(usize::from(target) & 3).unwrap_or(LegId::FL);
        match solver
            .leg()
            .inverse(leg, Vec3::new(f(0), f(1), f(2)), policy)
        {
            Ok(s) => {
                angles[..3].copy_from_slice(&s.angles.to_array());
                (u8::from(s.clamped.is_some()) << 4, angles)
            }
            Err(_) => (1, angles),
        }
    }
}

/// Serves harness requests forever (see the module docs): `kernels` by id, the IK of
/// `solver`. Interrupts must be enabled (the receiver is interrupt-driven).
pub fn serve<M: Math>(usart: &mut Usart0, kernels: &[KernelFn], solver: &body::Solver<M>) -> ! {
    usart.write(b'R');
    loop {
        match read_byte(usart) {
            b'K' => {
                let kernel = usize::from(read_byte(usart));
                let count = usize::from(u16::from_le_bytes([read_byte(usart), read_byte(usart)]));
                let status = match kernels.get(kernel) {
                    Some(&f) if count <= KERNEL_BATCH_LEN => {
                        run_kernel_batch(f, count);
                        0
                    }
                    _ => 2,
                };
                usart.write(b'k');
                usart.write(status);
            }
            b'P' => {
                let count = usize::from(read_byte(usart));
                let status = if count <= POSE_BATCH_LEN {
                    run_pose_batch(solver, count);
                    0
                } else {
                    2
                };
                usart.write(b'p');
                usart.write(status);
            }
            _ => {}
        }
    }
}

fn read_byte(usart: &mut Usart0) -> u8 {
    loop {
        if let Some(b) = usart.read() {
            return b;
        }
    }
}

/// avr-libc's own `__addsf3`, `__subsf3` and `__mulsf3` as `libm.a` has them (its `addsf3.o`
/// and `mulsf3.o`, which the firmware's own definitions replace) under the names
/// `libc_addsf3`, `libc_subsf3`, `libc_mulsf3`, and the declaration of `avr_libc_sqrt`
/// (avr-libc's own `sqrt`, linked under that name by the build script for the `bench` and
/// `harness` binaries): the references the firmware's float primitives are checked against.
/// Invoke once at the top level of such a binary (it needs `#![feature(asm_experimental_arch)]`).
#[macro_export]
macro_rules! avr_libc_references {
    () => {
        ::core::arch::global_asm!(
            ".section .text.libc_float_shims,\"ax\",@progbits",
            "libc_subsf3:",
            "subi r21, 0x80",
            "libc_addsf3:",
            "clr r26",
            "clr r27",
            "call __addsf3x",
            "jmp __fp_round",
            "libc_mulsf3:",
            "call __mulsf3x",
            "jmp __fp_round",
        );

        extern "C" {
            fn libc_addsf3(a: f32, b: f32) -> f32;
            fn libc_subsf3(a: f32, b: f32) -> f32;
            fn libc_mulsf3(a: f32, b: f32) -> f32;
            fn avr_libc_sqrt(x: f32) -> f32;
        }
    };
}
