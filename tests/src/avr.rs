//! The ATmega2560 firmware on the host: building its release ELFs and running them in simavr
//! in-process (through `avr-simulator`, the engine of `avr-tester`).
//!
//! [`firmware_elf`] builds `firmware-avr` (its own workspace, nightly + `build-std`) the way a
//! developer does, `cd firmware-avr && cargo build --release`, and fails loudly when that is
//! impossible: an emulator test never skips. [`Emu`] runs one ELF at 16 MHz, instruction by
//! instruction, with a cycle counter, USART0 in both directions and every digital pin of
//! ports A–L (including the Timer5 servo outputs on port L).

use avr_simulator::{AvrSimulator, AvrState};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// CPU clock of the Mega 2560, Hz.
pub const F_CPU_HZ: u32 = 16_000_000;

/// CPU cycles per servo timer tick (prescaler 8: 0.5 µs).
pub const CYCLES_PER_TICK: u64 = 8;

/// CPU cycles per microsecond.
pub const CYCLES_PER_US: u64 = 16;

/// Servo period, timer ticks (20 ms).
pub const PERIOD_TICKS: u64 = 40_000;

/// The twelve servo outputs in channel order (`3·leg + joint`, legs FL, FR, RL, RR): port
/// letter and bit (OC1A/B/C = PB5-7, OC3A/B/C = PE3-5, OC4A/B/C = PH3-5, OC5A/B/C = PL3-5).
pub const SERVO_PINS: [(char, u8); 12] = [
    ('B', 5),
    ('B', 6),
    ('B', 7),
    ('E', 3),
    ('E', 4),
    ('E', 5),
    ('H', 3),
    ('H', 4),
    ('H', 5),
    ('L', 3),
    ('L', 4),
    ('L', 5),
];

/// Time from reset until the firmware listens on USART0, with margin, µs (painting the free
/// SRAM for the stack measurement takes about 5 ms). Bytes sent earlier are lost, as on the
/// real board.
pub const BOOT_US: u64 = 10_000;

/// The benchmark's marker pin (PA0).
pub const MARKER_PIN: (char, u8) = ('A', 0);

/// Directory of the firmware workspace.
pub fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lies inside the workspace")
        .join("firmware-avr")
}

/// Environment variables that a cargo running this program sets for its children and that
/// would make the inner build use the outer toolchain, target directory or flags.
fn leaks_from_outer_cargo(key: &str) -> bool {
    (key.starts_with("CARGO_") && key != "CARGO_HOME")
        || key.starts_with("RUSTC")
        || key.starts_with("RUSTDOC")
        || key == "RUSTFLAGS"
        || key == "RUSTUP_TOOLCHAIN"
        || key == "CARGO"
        || key == "__CARGO_FIX_PLZ"
}

/// The rustup `cargo` proxy, which honours `firmware-avr/rust-toolchain.toml`.
fn cargo_proxy() -> PathBuf {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    if let Some(p) = home.map(|h| h.join("bin").join("cargo")) {
        if p.is_file() {
            return p;
        }
    }
    PathBuf::from("cargo")
}

/// Builds the firmware workspace (`cargo build --release` in `firmware-avr/`, nightly via its
/// `rust-toolchain.toml`) once per process and returns the path of the ELF of binary `bin`
/// (`firmware`, `bench` or `bench-libm`). Panics with the build's output when the build
/// fails: a missing toolchain or Debian package must fail the test, never skip it.
pub fn firmware_elf(bin: &str) -> PathBuf {
    static BUILT: OnceLock<Result<(), String>> = OnceLock::new();
    let dir = firmware_dir();
    let result = BUILT.get_or_init(|| {
        let mut cmd = Command::new(cargo_proxy());
        cmd.current_dir(&dir).args(["build", "--release"]);
        for (key, _) in std::env::vars_os() {
            if let Some(k) = key.to_str() {
                if leaks_from_outer_cargo(k) {
                    cmd.env_remove(k);
                }
            }
        }
        match cmd.output() {
            Ok(out) if out.status.success() => Ok(()),
            Ok(out) => Err(format!(
                "`cd firmware-avr && cargo build --release` failed ({}):\n{}{}",
                out.status,
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            )),
            Err(e) => Err(format!("cannot run cargo for firmware-avr: {e}")),
        }
    });
    if let Err(msg) = result {
        panic!("{msg}\n(install the prerequisites with scripts/install-deps.sh)");
    }
    let elf = dir
        .join("target/avr-none/release")
        .join(format!("{bin}.elf"));
    assert!(elf.is_file(), "{} was not produced", elf.display());
    elf
}

/// simavr's C state is global per simulator but its logging setup is process-wide; creating
/// simulators from several test threads at once is serialised here.
static CREATE: Mutex<()> = Mutex::new(());

/// One high pulse observed on a pin, in CPU cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pulse {
    /// Cycle of the rising edge.
    pub rise_cycle: u64,
    /// Cycles the pin stayed high.
    pub high_cycles: u64,
    /// Cycles from this rising edge to the next one (`None` when not observed).
    pub period_cycles: Option<u64>,
}

impl Pulse {
    /// High time in µs.
    pub fn high_us(&self) -> f64 {
        self.high_cycles as f64 / CYCLES_PER_US as f64
    }
}

/// A running ATmega2560 at 16 MHz.
pub struct Emu {
    sim: AvrSimulator,
    cycle: u64,
    rx: VecDeque<u8>,
}

impl Emu {
    /// Loads `elf` and resets the MCU (nothing runs yet).
    pub fn new(elf: &Path) -> Emu {
        let _guard = CREATE.lock().unwrap_or_else(|e| e.into_inner());
        Emu {
            sim: AvrSimulator::new("atmega2560", F_CPU_HZ, elf),
            cycle: 0,
            rx: VecDeque::new(),
        }
    }

    /// Cycles executed since reset.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Executes one instruction (or interrupt entry); returns its cycles. Panics when the
    /// MCU crashed or went to sleep (the firmware never sleeps).
    pub fn step(&mut self) -> u64 {
        let out = self.sim.step();
        match out.state {
            AvrState::Running => {}
            other => panic!("AVR stopped at cycle {}: {other:?}", self.cycle),
        }
        let n = out.tt.as_cycles();
        self.cycle += n;
        while let Some(b) = self.sim.read_uart('0') {
            self.rx.push_back(b);
        }
        n
    }

    /// Runs at least `cycles` cycles.
    pub fn run_cycles(&mut self, cycles: u64) {
        let end = self.cycle + cycles;
        while self.cycle < end {
            self.step();
        }
    }

    /// Runs for `us` microseconds.
    pub fn run_us(&mut self, us: u64) {
        self.run_cycles(us * CYCLES_PER_US);
    }

    /// Queues bytes for USART0's receiver (delivered at the configured baud rate).
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.sim.write_uart('0', b);
        }
    }

    /// Everything USART0 has sent so far and nobody has read.
    pub fn take_output(&mut self) -> Vec<u8> {
        self.rx.drain(..).collect()
    }

    /// Runs until USART0 has sent `n` more bytes, or `timeout_cycles` elapsed.
    pub fn read_exact(&mut self, n: usize, timeout_cycles: u64) -> Result<Vec<u8>, Vec<u8>> {
        let end = self.cycle + timeout_cycles;
        while self.rx.len() < n {
            if self.cycle >= end {
                return Err(self.take_output());
            }
            self.step();
        }
        Ok(self.rx.drain(..n).collect())
    }

    /// The output level of pin `bit` of port `port` ('A'..='L').
    pub fn pin(&mut self, port: char, bit: u8) -> bool {
        self.sim.get_digital_pin(port, bit)
    }

    /// True when pin `bit` of port `port` is configured as an output.
    pub fn is_output(&mut self, port: char, bit: u8) -> bool {
        self.sim.get_digital_pin_mode(port, bit).is_output()
    }

    /// Levels of the twelve servo pins, bit `i` = channel `i`.
    pub fn servo_levels(&mut self) -> u16 {
        let mut out = 0u16;
        for (i, &(port, bit)) in SERVO_PINS.iter().enumerate() {
            if self.sim.get_digital_pin(port, bit) {
                out |= 1 << i;
            }
        }
        out
    }

    /// Watches the twelve servo pins for `cycles` cycles and returns, per channel, the first
    /// complete high pulse (rising and falling edge seen) with the distance to the next
    /// rising edge, and whether the pin was ever high.
    pub fn watch_servos(&mut self, cycles: u64) -> [(Option<Pulse>, bool); 12] {
        let end = self.cycle + cycles;
        let mut result: [(Option<Pulse>, bool); 12] = [(None, false); 12];
        let mut rise: [Option<u64>; 12] = [None; 12];
        let mut prev = self.servo_levels();
        while self.cycle < end {
            self.step();
            let now = self.servo_levels();
            let changed = now ^ prev;
            if changed != 0 {
                for (ch, (pulse, ever_high)) in result.iter_mut().enumerate() {
                    let bit = 1u16 << ch;
                    if changed & bit == 0 {
                        continue;
                    }
                    let high = now & bit != 0;
                    if high {
                        *ever_high = true;
                        if let Some(p) = pulse.as_mut() {
                            if p.period_cycles.is_none() {
                                p.period_cycles = Some(self.cycle - p.rise_cycle);
                            }
                        }
                        rise[ch] = Some(self.cycle);
                    } else if let Some(r) = rise[ch].take() {
                        if pulse.is_none() {
                            *pulse = Some(Pulse {
                                rise_cycle: r,
                                high_cycles: self.cycle - r,
                                period_cycles: None,
                            });
                        }
                    }
                }
            }
            if now != 0 {
                for (ch, r) in result.iter_mut().enumerate() {
                    if now & (1 << ch) != 0 {
                        r.1 = true;
                    }
                }
            }
            prev = now;
        }
        result
    }
}
