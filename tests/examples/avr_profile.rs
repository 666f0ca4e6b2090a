//! Where the firmware's cycles go while it serves one kind of request: runs the release
//! firmware in simavr, sends the request `N` times (one at a time, after `Hello`), and charges
//! every instruction's cycles from the request's last byte (handed to the emulated UART) to
//! the answer's first byte to the function that holds its program counter (the ELF's symbols, by `avr-nm`). Prints the
//! functions by cycles per request.
//!
//! ```text
//! cargo run -p integration-tests --example avr_profile -- [set-body-pose|set-feet|get-state] [N]
//! cargo run -p integration-tests --example avr_profile -- bench-body [roll pitch yaw x y z]
//! ```
//!
//! Interrupt handlers are charged as functions of their own; idle polling in the main loop
//! while bytes are still on the line is charged to the loop's functions.

use kin_core::body::Pose;
use quad_host::emu::{build, Mega2560};
use quad_protocol::{encode_frame, HostToDevice, Request, MAX_FRAME_LEN, PROTOCOL_VERSION};
use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

/// The ELF's function symbols: (start byte address, size, demangled name), sorted.
fn symbols(elf: &Path) -> Vec<(u32, u32, String)> {
    let out = Command::new("avr-nm")
        .args(["-n", "-S", "-C", "--defined-only"])
        .arg(elf)
        .output()
        .expect("avr-nm runs (Debian binutils-avr)");
    let mut syms = Vec::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let mut parts = line.splitn(4, ' ');
        let (Some(addr), Some(size), Some(kind), Some(name)) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        if !matches!(kind, "t" | "T" | "W" | "w") {
            continue;
        }
        let (Ok(addr), Ok(size)) = (u32::from_str_radix(addr, 16), u32::from_str_radix(size, 16))
        else {
            continue;
        };
        syms.push((
            addr,
            size,
            short_name(&format!("{:#}", rustc_demangle::demangle(name))),
        ));
    }
    syms.sort();
    syms
}

/// `<a::B<generic args>>::method` as `a::B::method` (the firmware's types carry long generic
/// arguments); other names as they are.
fn short_name(name: &str) -> String {
    match name.rsplit_once(">::") {
        Some((head, method)) if head.starts_with('<') => {
            let base = head[1..].split(['<', ' ']).next().unwrap_or(head);
            format!("{base}::{method}")
        }
        _ => name.to_owned(),
    }
}

/// True when `pc` is the first instruction of a function of `syms` (a call's entry).
fn is_entry(syms: &[(u32, u32, String)], pc: u32) -> bool {
    syms.binary_search_by_key(&pc, |s| s.0).is_ok()
}

fn name_at(syms: &[(u32, u32, String)], pc: u32) -> &str {
    let i = syms.partition_point(|s| s.0 <= pc);
    match i.checked_sub(1).map(|i| &syms[i]) {
        Some((a, s, n)) if pc < a + s.max(&2) => n,
        _ => "?",
    }
}

fn frame(seq: u16, request: Request) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    encode_frame(&HostToDevice { seq, request }, &mut buf)
        .expect("encodes")
        .to_vec()
}

/// The name of the function at `pc`; inside avr-libc's `memcpy`/`memset` (leaf routines that
/// push nothing: the return address, a word address high byte first, is at SP + 1), with
/// their caller's.
fn charged_name(mcu: &Mega2560, syms: &[(u32, u32, String)], pc: u32) -> String {
    let name = name_at(syms, pc);
    if matches!(name, "memcpy" | "memset") {
        let sp = mcu.sp();
        let ret = (u32::from(mcu.data(sp + 1)) << 16
            | u32::from(mcu.data(sp + 2)) << 8
            | u32::from(mcu.data(sp + 3)))
            * 2;
        format!("{name} from {}", name_at(syms, ret))
    } else {
        name.to_owned()
    }
}

fn print_rows(
    title: &str,
    by_fn: HashMap<String, u64>,
    calls: &HashMap<String, u64>,
    total: u64,
    per: u64,
) {
    let mut rows: Vec<_> = by_fn.into_iter().collect();
    rows.sort_by_key(|r| std::cmp::Reverse(r.1));
    println!(
        "{title}: {} cycles, by function (cycles, share, calls):",
        total / per
    );
    for (name, cycles) in rows.iter().take(40) {
        let short: String = name.chars().take(120).collect();
        let entered = calls.get(name).copied().unwrap_or(0) as f64 / per as f64;
        println!(
            "{:>8}  {:>5.1}%  {entered:>6.1}  {short}",
            cycles / per,
            100.0 * *cycles as f64 / total as f64
        );
    }
}

/// Cycles charged by function while the benchmark firmware's marker pin is high, until
/// `answer_len` bytes of its answer have come: (total, cycles by function, calls by function).
fn charge_marked(
    mcu: &mut Mega2560,
    syms: &[(u32, u32, String)],
    answer_len: usize,
) -> (u64, HashMap<String, u64>, HashMap<String, u64>) {
    let (port, bit) = quad_host::emu::MARKER_PIN;
    let mut by_fn: HashMap<String, u64> = HashMap::new();
    let mut calls: HashMap<String, u64> = HashMap::new();
    let mut total = 0;
    let mut got = 0;
    while got < answer_len {
        let pc = mcu.pc();
        let high = mcu.pin(port, bit);
        let cycles = mcu.step().expect("runs");
        if high {
            let name = charged_name(mcu, syms, pc);
            if is_entry(syms, pc) {
                *calls.entry(name.clone()).or_default() += 1;
            }
            *by_fn.entry(name).or_default() += cycles;
            total += cycles;
        }
        got += mcu.uart_take().len();
    }
    (total, by_fn, calls)
}

/// The benchmark firmware (`bench.elf`) booted in simavr, with its symbols.
fn boot_bench() -> (Mega2560, Vec<(u32, u32, String)>) {
    let elf = build::firmware_elf(build::BENCH).unwrap_or_else(|e| panic!("{e}"));
    let syms = symbols(&elf);
    let mut mcu = Mega2560::new(&elf).unwrap_or_else(|e| panic!("{e}"));
    mcu.read_exact(1, 16_000_000).expect("boots");
    (mcu, syms)
}

/// The worst frame of an onboard motion in the benchmark firmware (`bench.elf`, motion ids of
/// `firmware_avr::bench`), charged by function while its marker pin is high.
fn profile_motion(motion: u8, frames: u32) {
    let (mut mcu, syms) = boot_bench();
    mcu.uart_write(&[b'M', motion]);
    let started = mcu.read_exact(2, 16_000_000 * 20).expect("starts");
    assert_eq!(started, b"m\0", "motion {motion} refused");
    let mut worst: (u64, HashMap<String, u64>, HashMap<String, u64>) =
        (0, HashMap::new(), HashMap::new());
    for _ in 0..frames {
        mcu.uart_write(b"N");
        // `n`, the status and the stage.
        let frame = charge_marked(&mut mcu, &syms, 3);
        if frame.0 > worst.0 {
            worst = frame;
        }
    }
    print_rows(
        &format!("motion {motion}, worst of {frames} frames"),
        worst.1,
        &worst.2,
        worst.0,
        1,
    );
}

/// The benchmark's body pose (`bench.elf`, request `B` on the firmware's backend, id 3, its
/// solver built at boot) at the rotation `(roll, pitch, yaw)` and translation `(x, y, z)`,
/// charged by function while its marker pin is high.
fn profile_bench_body(pose: [f32; 6]) {
    let (mut mcu, syms) = boot_bench();
    let mut req = vec![b'B', 3];
    for v in pose {
        req.extend(v.to_le_bytes());
    }
    mcu.uart_write(&req);
    // `b`, the status and twelve angles.
    let (total, by_fn, calls) = charge_marked(&mut mcu, &syms, 2 + 12 * 4);
    print_rows(
        &format!("bench body pose {pose:?}"),
        by_fn,
        &calls,
        total,
        1,
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let kind = args.next().unwrap_or_else(|| "set-body-pose".to_owned());
    if kind == "bench-body" {
        let mut pose = [0.1, -0.05, 0.08, 0.02, -0.01, 0.01];
        for (v, a) in pose.iter_mut().zip(args) {
            *v = a.parse().expect("a number");
        }
        profile_bench_body(pose);
        return;
    }
    if let Some(motion) = kind.strip_prefix("motion-") {
        let frames = args
            .next()
            .map_or(150, |s| s.parse().expect("a frame count"));
        profile_motion(motion.parse().expect("a motion id"), frames);
        return;
    }
    let n: u32 = args.next().map_or(5, |s| s.parse().expect("N is a count"));
    let request = match kind.as_str() {
        "set-body-pose" => Request::SetBodyPose(Pose::rotation(0.1, -0.05, 0.08)),
        "set-feet" => Request::SetFeet {
            feet_in_body_m: [
                [0.3, 0.184, -0.27],
                [0.3, -0.184, -0.27],
                [-0.3, 0.184, -0.27],
                [-0.3, -0.184, -0.27],
            ],
        },
        "get-state" => Request::GetState,
        other => panic!("unknown request kind {other}"),
    };
    // `AVR_PROFILE_1MBAUD=1`: the 1 Mbaud build; `AVR_PROFILE_OUTPUTS=1`: the outputs on (the
    // request first held, then `SetOutputs`), as while a host streams poses.
    let flag = |name| std::env::var(name).is_ok_and(|v| v == "1");
    let bin = if flag("AVR_PROFILE_1MBAUD") {
        build::FIRMWARE_1MBAUD
    } else {
        build::FIRMWARE
    };
    let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
    let syms = symbols(&elf);
    let mut mcu = Mega2560::new(&elf).unwrap_or_else(|e| panic!("{e}"));
    while mcu.uart_baud().is_none() {
        mcu.step().expect("boots");
    }
    mcu.run_cycles(16_000 * 30).expect("runs");
    let mut by_fn: HashMap<String, u64> = HashMap::new();
    let mut calls: HashMap<String, u64> = HashMap::new();
    let mut total = 0u64;
    let mut setup = vec![Request::Hello {
        version: PROTOCOL_VERSION,
    }];
    if flag("AVR_PROFILE_OUTPUTS") {
        setup.extend([request, Request::SetOutputs { enabled: true }]);
    }
    let first = setup.len() as u32;
    // `AVR_PROFILE_BACK_TO_BACK=1`: each request as soon as the previous answer ended (as a
    // host waiting for each answer sends), else after 5 ms of quiet; `AVR_PROFILE_TIMES=1`:
    // each request's times printed.
    let back_to_back = flag("AVR_PROFILE_BACK_TO_BACK");
    let times = flag("AVR_PROFILE_TIMES");
    mcu.run_cycles(16_000 * 5).expect("runs");
    for seq in 0..first + n {
        let counted = seq >= first;
        let request = if counted {
            request
        } else {
            setup[seq as usize]
        };
        if !back_to_back {
            mcu.run_cycles(16_000 * 5).expect("runs");
        }
        let _ = mcu.uart_take();
        mcu.uart_write(&frame(seq as u16, request));
        let start = mcu.cycle();
        let (mut last_in, mut first_out, mut end) = (None, None, None);
        let mut zeros = 0;
        // From the request's last byte on the line until the answer's first byte (profiled),
        // then until the answer's closing delimiter.
        while end.is_none() && mcu.cycle() < start + 16_000_000 {
            let pc = mcu.pc();
            let counting = mcu.uart_input_pending() == 0 && first_out.is_none();
            if counting && last_in.is_none() {
                last_in = Some(mcu.cycle());
            }
            let cycles = mcu.step().expect("runs");
            if counted && counting {
                let name = charged_name(&mcu, &syms, pc);
                if is_entry(&syms, pc) {
                    *calls.entry(name.clone()).or_default() += 1;
                }
                *by_fn.entry(name).or_default() += cycles;
                total += cycles;
            }
            for (cycle, b) in mcu.uart_take() {
                // The first byte after the leading delimiter (which may go out early).
                if b != 0 && first_out.is_none() {
                    first_out = Some(cycle);
                }
                if b == 0 {
                    zeros += 1;
                    if zeros == 2 {
                        end = Some(cycle);
                    }
                }
            }
        }
        if times && counted {
            let (l, f, e) = (
                last_in.unwrap_or(start),
                first_out.unwrap_or(0),
                end.unwrap_or(0),
            );
            println!(
                "request {seq}: bytes in {}, last byte → first answer byte {}, answer out {} cycles",
                l - start,
                f.saturating_sub(l),
                e.saturating_sub(f)
            );
        }
    }
    print_rows(
        &format!(
            "{kind}, per request from its last byte handed to the UART to the answer's first byte"
        ),
        by_fn,
        &calls,
        total,
        u64::from(n),
    );
}
