//! [`Mega2560`]: simavr driven directly through its C API (`simavr-ffi`).
//!
//! Direct access (rather than through a higher-level wrapper) gives what the tests and the
//! emulator link need: every servo pin sampled after each instruction from the port registers
//! (cheap: no ioctl per pin), UART bytes time-stamped in cycles by an IRQ hook, SRAM and I/O
//! registers, the EEPROM, reset detection and setting the program counter.
//!
//! Simulator facts that matter (simavr as vendored by `simavr-ffi` 1.2):
//! - USART receive, **as strict as the chip**: simavr itself holds received bytes in a 64-byte
//!   FIFO and never overruns; the ATmega2560 holds two plus the one in its shift register.
//!   [`Mega2560`] therefore paces the bytes handed to [`Mega2560::uart_write`] itself, one per
//!   byte time (simavr's `cycles_per_byte`, back to back), handing each to simavr when it starts
//!   on the line; simavr raises RXC one byte time later, when its stop bit has arrived. When a
//!   byte starts while the two-byte buffer is full and the previous byte waits in the shift
//!   register — three complete bytes unread in simavr's FIFO — that previous byte is lost as
//!   the chip loses it: removed from the FIFO, counted ([`Mega2560::rx_overruns`]), and the
//!   data-overrun flag DOR0 set in UCSR0A until the firmware next reads UDR0 (simavr would
//!   clear it on any write to UCSR0A; the chip does not, so it is set again after every step).
//!   A transmitted byte is reported when the firmware writes it to UDR; it has crossed the line
//!   one byte time later.
//! - Interrupt latency: after every step the global interrupt flag (SREG.I) is read — from
//!   simavr's own flag array, as the SREG byte of the data space is only updated when the
//!   program reads it; the longest stretch with interrupts off — interrupt handlers included,
//!   which run with I clear — is kept, overall and while bytes are arriving or waiting unread
//!   ([`Mega2560::interrupts_off`]).
//! - Output-compare pins are driven through the port registers, so the PORT bits show the pin
//!   levels; a pin whose DDR bit is clear is not driven (reads as low here).
//! - The watchdog resets the MCU (MCUSR.WDRF set) and simavr restarts its cycle counter at 0;
//!   [`Mega2560::cycle`] keeps counting.
//! - The EEPROM completes a write at once but raises the EEPROM-ready interrupt 3.4 ms later
//!   (the firmware waits for that interrupt, so saves take their real time here too).
//! - A 16-bit output-compare register (OCRnx) takes effect in simavr when its low byte is
//!   written, and only if the value changed — judged with the high byte already written, so a
//!   change of the high byte alone is missed (the pin keeps the old width). The chip has no
//!   such gap: the high byte waits in the timer's TEMP register and the low-byte write commits
//!   both. [`Mega2560`] models that: it wraps simavr's write handler of the twelve servo OCR
//!   low bytes and, when a low-byte write leaves the value unchanged while the high byte
//!   changed since the last one, has simavr take the new value there and then. The commit
//!   happens at the program's own low-byte write, whatever runs between the two bytes (an
//!   interrupt entered between them used to make a guess one instruction later commit a
//!   half-written value: a runt pulse of a few cycles).
//! - simavr applies a compare register at once, not at the next period as the chip does (the
//!   firmware writes them between pulses, where both agree).
//!
//! - TWI: simavr's master runs the firmware's transfers; a slave answers through IRQ hooks.
//!   [`Mega2560::attach_imu`] puts a virtual MPU-6050 at 0x68 on it (`twi.rs`); without one
//!   nothing answers there, as on a board without the sensor.
//!
//! Files: this one the simulator itself (set-up, stepping, resets, memory, the EEPROM);
//! `uart.rs` USART0 as strict as the chip and the interrupts-off stretches; `pins.rs` the pins
//! and the servo pulses on them, with the compare-register commit; `twi.rs` the virtual
//! MPU-6050 on the TWI.

mod pins;
mod twi;
mod uart;

pub use pins::Pulse;
pub use twi::{ImuBus, SharedImuSource};
pub use uart::InterruptsOff;

use super::CYCLES_PER_US;
use super::F_CPU_HZ;
use pins::{on_ocr_low_write, OcrWrite, OCR_LOW};
use simavr_ffi as ffi;
use std::collections::VecDeque;
use std::ffi::{c_char, c_int, c_void, CString};
use std::path::{Path, PathBuf};
use std::ptr::NonNull;
use std::sync::{Arc, Mutex};
use uart::{on_uart_output, on_uart_xoff, on_uart_xon};

extern "C" {
    fn free(ptr: *mut c_void);
}

/// An `AVR_IOCTL_DEF(a, b, c, d)` request code.
const fn ioctl(a: u8, b: u8, c: u8, d: u8) -> u32 {
    u32::from_be_bytes([a, b, c, d])
}

const IOCTL_UART_GET_FLAGS: u32 = ioctl(b'u', b'a', b'g', b'0');

const IOCTL_UART_SET_FLAGS: u32 = ioctl(b'u', b'a', b's', b'0');

const IOCTL_UART_GET_IRQ: u32 = ioctl(b'u', b'a', b'r', b'0');

const IOCTL_EEPROM_GET: u32 = ioctl(b'e', b'e', b'g', b'p');

const IOCTL_EEPROM_SET: u32 = ioctl(b'e', b'e', b's', b'p');

/// Bytes of EEPROM.
pub const EEPROM_LEN: usize = 4096;

/// `out A, Rr` with the register bits masked out (`1011 1AAr rrrr AAAA`).
const OUT_IO_MASK: u16 = 0xFE0F;

/// `out 0x3e, Rr`: a write of SPH.
const OUT_SPH: u16 = 0xBE0E;

/// `out 0x3d, Rr`: a write of SPL.
const OUT_SPL: u16 = 0xBE0D;

/// Watchdog control and MCU status registers.
const WDTCSR: u16 = 0x60;

const MCUSR: u16 = 0x54;

/// simavr's state is per simulator, but creating simulators and its logger are not
/// thread-safe: creation is serialised.
static CREATE: Mutex<()> = Mutex::new(());

/// Discards simavr's log messages (they would go to stdout/stderr).
unsafe extern "C" fn quiet_logger(
    _: *mut ffi::avr_t,
    _: c_int,
    _: *const c_char,
    _: *mut ffi::__va_list_tag,
) {
}

/// Why the simulator could not run.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum EmuError {
    /// The firmware file could not be read (shared: the error is cloned with the value).
    #[error("firmware: cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: Arc<std::io::Error>,
    },
    /// The firmware file is not an AVR ELF.
    #[error("firmware: {} is not an AVR ELF file", .0.display())]
    NotAvrElf(PathBuf),
    /// The path cannot be passed to simavr.
    #[error("firmware: path contains a NUL byte")]
    NulInPath,
    /// simavr could not create or initialise the MCU.
    #[error("simavr: {0}")]
    Init(&'static str),
    /// The CPU stopped (crash, or sleep with interrupts off) at this cycle.
    #[error("the AVR stopped ({state}) at cycle {cycle}, pc {pc:#x}")]
    Stopped {
        /// simavr's state.
        state: &'static str,
        /// Cycle count ([`Mega2560::cycle`]).
        cycle: u64,
        /// Program counter, byte address.
        pc: u32,
    },
}

/// Resets seen since the simulator was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Resets {
    /// How many.
    pub count: u32,
    /// Cycle ([`Mega2560::cycle`]) of the last one.
    pub last_cycle: Option<u64>,
    /// MCUSR right after the last one (its reset-cause flags; the firmware clears it at boot).
    pub last_mcusr: u8,
}

/// State shared with simavr's IRQ hooks (reached through a raw pointer).
struct Hooks {
    avr: *mut ffi::avr_t,
    /// Cycles before the current simavr epoch (simavr restarts at 0 after a reset).
    base: u64,
    /// Bytes written to UDR0, with the cycle.
    out: VecDeque<(u64, u8)>,
    /// simavr's receiver has room.
    xon: bool,
    /// The wrapped write handlers of the servo compare registers' low bytes, in channel order.
    ocr: [OcrWrite; 12],
}

/// An ATmega2560 at 16 MHz running one ELF in simavr.
pub struct Mega2560 {
    avr: NonNull<ffi::avr_t>,
    hooks: NonNull<Hooks>,
    uart_in: NonNull<ffi::avr_irq_t>,
    /// Bytes for USART0's receiver not yet on the line.
    input: VecDeque<u8>,
    /// Cycle from which the next byte may start on the host → device line.
    rx_line_free: u64,
    /// Bytes the receive buffer lost (overruns).
    rx_overruns: u64,
    /// simavr's FIFO read index when the last overrun happened, while its DOR0 is owed.
    dor_owed: Option<u16>,
    /// The interrupts-off stretch in progress: its first cycle, the program counter there and
    /// the cycle from which bytes were arriving during it (if they were).
    cli_since: Option<(u64, u32, Option<u64>)>,
    interrupts_off: InterruptsOff,
    /// simavr's cycle counter after the last step.
    last_raw: u64,
    resets: Resets,
    /// Levels of the twelve servo pins after the last step, bit `i` = channel `i`.
    levels: u16,
    /// Cycle and step length of the rising edge of the pulse in progress, per channel.
    rise: [Option<(u64, u64)>; 12],
    capture: bool,
    pulses: VecDeque<Pulse>,
    /// Bytes sent by USART0 (with the cycle they were written to UDR0), not yet taken.
    output: VecDeque<(u64, u8)>,
    /// Lowest stack pointer seen after an instruction since the C runtime set it up.
    min_sp: u16,
    /// True between a write of SPH and the write of SPL that completes a stack-pointer update:
    /// the stack pointer read in between mixes the new high byte with the old low byte.
    sp_half_written: bool,
    /// The virtual MPU-6050 on the TWI, when attached.
    imu: Option<Box<twi::VirtualMpu>>,
}

impl Mega2560 {
    /// Loads `elf` into a fresh ATmega2560 at 16 MHz (reset state; nothing runs yet).
    ///
    /// # Errors
    /// When the file is not an AVR ELF or simavr cannot create the MCU.
    pub fn new(elf: &Path) -> Result<Mega2560, EmuError> {
        let head = std::fs::read(elf).map_err(|e| EmuError::Read {
            path: elf.to_owned(),
            source: Arc::new(e),
        })?;
        // simavr exits the process on a file it cannot load: check first (ELF, machine AVR).
        if head.len() < 20 || &head[..4] != b"\x7fELF" || head[18] != 0x53 {
            return Err(EmuError::NotAvrElf(elf.to_owned()));
        }
        let path =
            CString::new(elf.as_os_str().as_encoded_bytes()).map_err(|_| EmuError::NulInPath)?;
        let mcu = CString::new("atmega2560").expect("no NUL");
        let _guard = CREATE.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY (this block): the calls follow simavr's documented set-up sequence
        // (`avr_make_mcu_by_name`, `avr_init`, `sim_setup_firmware` into a zeroed
        // `elf_firmware_t`, `avr_load_firmware`); every pointer passed is valid for the call.
        unsafe {
            ffi::avr_global_logger_set(Some(quiet_logger));
            let avr = NonNull::new(ffi::avr_make_mcu_by_name(mcu.as_ptr()))
                .ok_or(EmuError::Init("unknown MCU atmega2560"))?;
            if ffi::avr_init(avr.as_ptr()) != 0 {
                free(avr.as_ptr().cast());
                return Err(EmuError::Init("avr_init failed"));
            }
            (*avr.as_ptr()).frequency = F_CPU_HZ;
            let mut fw: Box<ffi::elf_firmware_t> = Box::new(std::mem::zeroed());
            for (dst, &src) in fw.mmcu.iter_mut().zip(mcu.as_bytes_with_nul()) {
                *dst = src as c_char;
            }
            fw.frequency = F_CPU_HZ;
            let name = CString::new("quadctl").expect("no NUL");
            ffi::sim_setup_firmware(path.as_ptr(), 0, &mut *fw, name.as_ptr());
            ffi::avr_load_firmware(avr.as_ptr(), &mut *fw);

            // USART0: no stdio echo, no host-side sleeping while the firmware polls UCSR0A.
            let mut flags: u32 = 0;
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART_GET_FLAGS,
                (&mut flags as *mut u32).cast(),
            );
            flags &= !(ffi::AVR_UART_FLAG_STDIO | ffi::AVR_UART_FLAG_POLL_SLEEP);
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART_SET_FLAGS,
                (&mut flags as *mut u32).cast(),
            );
            let irq = |n: u32| {
                NonNull::new(ffi::avr_io_getirq(
                    avr.as_ptr(),
                    IOCTL_UART_GET_IRQ,
                    n as c_int,
                ))
            };
            let (Some(uart_in), Some(out), Some(xon), Some(xoff)) = (
                irq(ffi::UART_IRQ_INPUT),
                irq(ffi::UART_IRQ_OUTPUT),
                irq(ffi::UART_IRQ_OUT_XON),
                irq(ffi::UART_IRQ_OUT_XOFF),
            ) else {
                ffi::avr_terminate(avr.as_ptr());
                free(avr.as_ptr().cast());
                return Err(EmuError::Init("USART0 has no IRQs"));
            };
            let hooks = NonNull::from(Box::leak(Box::new(Hooks {
                avr: avr.as_ptr(),
                base: 0,
                out: VecDeque::new(),
                xon: true,
                ocr: std::array::from_fn(|_| OcrWrite {
                    handler: None,
                    param: std::ptr::null_mut(),
                    committed: 0,
                }),
            })));
            for (i, &lo) in OCR_LOW.iter().enumerate() {
                let slot = &mut (*avr.as_ptr()).io[usize::from(lo) - 0x20].w;
                let w = &mut (*hooks.as_ptr()).ocr[i];
                w.handler = slot.c;
                w.param = slot.param;
                slot.c = Some(on_ocr_low_write);
                slot.param = (w as *mut OcrWrite).cast();
            }
            let param: *mut c_void = hooks.as_ptr().cast();
            ffi::avr_irq_register_notify(out.as_ptr(), Some(on_uart_output), param);
            ffi::avr_irq_register_notify(xon.as_ptr(), Some(on_uart_xon), param);
            ffi::avr_irq_register_notify(xoff.as_ptr(), Some(on_uart_xoff), param);
            Ok(Mega2560 {
                avr,
                hooks,
                uart_in,
                input: VecDeque::new(),
                rx_line_free: 0,
                rx_overruns: 0,
                dor_owed: None,
                cli_since: None,
                interrupts_off: InterruptsOff::default(),
                last_raw: (*avr.as_ptr()).cycle,
                resets: Resets::default(),
                levels: 0,
                rise: [None; 12],
                capture: false,
                pulses: VecDeque::new(),
                output: VecDeque::new(),
                min_sp: u16::MAX,
                sp_half_written: false,
                imu: None,
            })
        }
    }

    fn avr(&self) -> &ffi::avr_t {
        // SAFETY: the pointer is valid for the simulator's life; simavr touches it only inside
        // calls made through `&mut self`.
        unsafe { self.avr.as_ref() }
    }

    /// Cycles executed since the simulator was created (resets do not restart it).
    pub fn cycle(&self) -> u64 {
        // SAFETY: see `avr`; no hook runs now.
        let base = unsafe { self.hooks.as_ref().base };
        base + self.avr().cycle
    }

    /// The resets (watchdog, or any other) since the simulator was created; the power-on
    /// reset is not counted.
    pub fn resets(&self) -> Resets {
        self.resets
    }

    /// The program counter, byte address.
    pub fn pc(&self) -> u32 {
        self.avr().pc
    }

    /// Executes one instruction (or an interrupt entry) and the peripherals' events due by
    /// then; returns the cycles it took.
    ///
    /// # Errors
    /// When the CPU stopped: a crash, or sleep with interrupts off (the firmware never
    /// sleeps).
    pub fn step(&mut self) -> Result<u64, EmuError> {
        self.feed_uart();
        let before = self.cycle();
        let pc_before = self.pc();
        if let Some(imu) = self.imu.as_deref_mut() {
            imu.now_cycle = before;
        }
        // SAFETY: a valid, initialised simulator; hooks registered with live parameters.
        let state = unsafe { ffi::avr_run(self.avr.as_ptr()) } as u32;
        let raw = self.avr().cycle;
        if raw < self.last_raw {
            // simavr reset the MCU and restarted its counter at 0.
            // SAFETY: no hook runs now; the allocation is live.
            let hooks = unsafe { self.hooks.as_mut() };
            hooks.base += self.last_raw;
            hooks.xon = true;
            self.resets.count += 1;
            self.resets.last_cycle = Some(hooks.base);
            self.resets.last_mcusr = self.data(MCUSR);
        }
        self.last_raw = raw;
        match state {
            ffi::cpu_Running | ffi::cpu_Sleeping | ffi::cpu_Step | ffi::cpu_StepDone => {}
            other => {
                return Err(EmuError::Stopped {
                    state: match other {
                        ffi::cpu_Crashed => "crashed",
                        ffi::cpu_Done => "done",
                        ffi::cpu_Stopped => "stopped",
                        _ => "limbo",
                    },
                    cycle: self.cycle(),
                    pc: self.pc(),
                })
            }
        }
        // SAFETY: no hook runs now.
        let hooks = unsafe { self.hooks.as_mut() };
        self.output.extend(hooks.out.drain(..));
        self.owe_dor();
        self.track_interrupts_off(before, pc_before);
        let now = self.cycle();
        if let Some(imu) = self.imu.as_deref_mut() {
            imu.tick(now);
        }
        let step = now.saturating_sub(before).max(1);
        self.track_servos(step);
        let sp = self.sp();
        // A frame is set up (or torn down) by `out SPH` then `out SPL`, interrupts held off in
        // between: the stack pointer between the two is no stack depth the program reached.
        match self.flash_word(pc_before) & OUT_IO_MASK {
            OUT_SPH => self.sp_half_written = true,
            OUT_SPL => self.sp_half_written = false,
            _ => {}
        }
        // SP starts at 0 until the C runtime loads RAMEND.
        if sp != 0 && sp < self.min_sp && !self.sp_half_written {
            self.min_sp = sp;
        }
        Ok(step)
    }

    /// Runs at least `cycles` cycles.
    ///
    /// # Errors
    /// As [`Mega2560::step`].
    pub fn run_cycles(&mut self, cycles: u64) -> Result<(), EmuError> {
        let end = self.cycle() + cycles;
        while self.cycle() < end {
            self.step()?;
        }
        Ok(())
    }

    /// Runs for `us` microseconds.
    ///
    /// # Errors
    /// As [`Mega2560::step`].
    pub fn run_us(&mut self, us: u64) -> Result<(), EmuError> {
        self.run_cycles(us * CYCLES_PER_US)
    }

    /// One byte of the data space (registers, I/O, SRAM); 0 beyond RAMEND.
    pub fn data(&self, addr: u16) -> u8 {
        let avr = self.avr();
        if u32::from(addr) > u32::from(avr.ramend) {
            return 0;
        }
        // SAFETY: `data` holds RAMEND + 1 bytes; the index is within.
        unsafe { *avr.data.add(usize::from(addr)) }
    }

    /// Writes `bytes` into the data space from `addr` on (SRAM, as a debugger would: no
    /// instruction runs).
    ///
    /// # Panics
    /// When the range extends beyond RAMEND.
    pub fn write_data(&mut self, addr: u16, bytes: &[u8]) {
        let avr = self.avr();
        let end = usize::from(addr) + bytes.len();
        assert!(
            end <= usize::from(avr.ramend) + 1,
            "write of {} bytes at {addr:#06x} beyond RAMEND {:#06x}",
            bytes.len(),
            avr.ramend
        );
        // SAFETY: `data` holds RAMEND + 1 bytes; the range is within (checked above), and no
        // instruction runs while the bytes are copied.
        unsafe {
            core::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                avr.data.add(usize::from(addr)),
                bytes.len(),
            );
        }
    }

    /// `len` bytes of the data space from `addr` on ([`Mega2560::data`] each).
    pub fn data_bytes(&self, addr: u16, len: usize) -> Vec<u8> {
        (0..len)
            .map(|i| self.data(addr.wrapping_add(i as u16)))
            .collect()
    }

    /// WDTCSR, the watchdog control register.
    pub fn wdtcsr(&self) -> u8 {
        self.data(WDTCSR)
    }

    /// MCUSR, the reset-cause flags.
    pub fn mcusr(&self) -> u8 {
        self.data(MCUSR)
    }

    /// Last SRAM address (RAMEND).
    pub fn ramend(&self) -> u16 {
        self.avr().ramend
    }

    /// The program word at byte address `pc` (0 beyond the flash).
    fn flash_word(&self, pc: u32) -> u16 {
        let avr = self.avr();
        let i = pc as usize;
        if avr.flash.is_null() || i + 1 > avr.flashend as usize {
            return 0;
        }
        // SAFETY: `flash` holds `flashend + 1` bytes for the simulator's lifetime; `i + 1` is
        // within them.
        unsafe { u16::from_le_bytes([*avr.flash.add(i), *avr.flash.add(i + 1)]) }
    }

    /// The stack pointer.
    pub fn sp(&self) -> u16 {
        u16::from_le_bytes([self.data(0x5D), self.data(0x5E)])
    }

    /// The deepest the stack has been since power-on, bytes below RAMEND (the stack pointer
    /// observed after every instruction, interrupt entries included; resets do not clear it).
    pub fn stack_peak_bytes(&self) -> u16 {
        if self.min_sp == u16::MAX {
            0
        } else {
            self.ramend() - self.min_sp
        }
    }

    /// The stack high-water mark by the firmware's own method: SRAM from `heap_start` (the
    /// end of the static data, symbol `__heap_start`) is painted with `paint` at boot; the
    /// lowest byte no longer holding it shows how deep the stack went. Bytes below RAMEND.
    pub fn painted_stack_bytes(&self, heap_start: u16, paint: u8) -> u16 {
        let end = self.ramend();
        let mut p = heap_start;
        while p < end && self.data(p) == paint {
            p += 1;
        }
        end + 1 - p
    }

    /// The EEPROM's bytes.
    pub fn eeprom(&mut self) -> Vec<u8> {
        let mut buf = vec![0xFFu8; EEPROM_LEN];
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: buf.as_mut_ptr(),
            offset: 0,
            size: EEPROM_LEN as u32,
        };
        // SAFETY: `desc` points to a buffer of `size` bytes.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                IOCTL_EEPROM_GET,
                (&mut desc as *mut ffi::avr_eeprom_desc_t).cast(),
            )
        };
        buf
    }

    /// Loads `bytes` into the EEPROM from address 0 (at most [`EEPROM_LEN`]; typically before
    /// the firmware runs, as if it had been written by an earlier run).
    pub fn set_eeprom(&mut self, bytes: &[u8]) {
        let mut data = bytes[..bytes.len().min(EEPROM_LEN)].to_vec();
        if data.is_empty() {
            return;
        }
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: data.as_mut_ptr(),
            offset: 0,
            size: data.len() as u32,
        };
        // SAFETY: `desc` points to a buffer of `size` bytes, which simavr copies.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                IOCTL_EEPROM_SET,
                (&mut desc as *mut ffi::avr_eeprom_desc_t).cast(),
            )
        };
    }

    /// Puts a virtual MPU-6050 at 0x68 on the TWI, fed by `source` (see `twi.rs`: the register
    /// file, the sample rate the firmware configures, the source's faults on the bus), and
    /// pulls the bus lines up as the GY-521 does. Attach before the firmware runs (it probes
    /// the sensor at boot); a second call replaces the first sensor's source.
    pub fn attach_imu(&mut self, source: SharedImuSource) {
        if let Some(imu) = self.imu.as_deref_mut() {
            imu.source = source;
            return;
        }
        // SAFETY: the simulator is live and initialised; the box is kept until `drop`, after
        // `avr_terminate`.
        self.imu = Some(unsafe { twi::VirtualMpu::attach(self.avr.as_ptr(), source) });
    }

    /// What the virtual MPU-6050 saw on the bus (`None`: no sensor attached).
    pub fn imu_bus(&self) -> Option<&ImuBus> {
        self.imu.as_deref().map(twi::VirtualMpu::bus)
    }

    /// Fault injection: moves the program counter to `byte_addr`, as a corrupted return
    /// address or a runaway jump would. The emulator tests use it to hang the CPU in the C
    /// runtime's final `cli; rjmp .` loop (`_exit`), where nothing feeds the watchdog.
    pub fn jump(&mut self, byte_addr: u32) {
        // SAFETY: between instructions simavr reads `pc` only at the next `avr_run`.
        unsafe { (*self.avr.as_ptr()).pc = byte_addr };
    }
}

impl Drop for Mega2560 {
    fn drop(&mut self) {
        // SAFETY: the simulator is not running; after `avr_terminate` (which frees its I/O
        // modules, IRQs, flash and data) the hooks are no longer referenced and the `avr_t`
        // allocation itself (malloc'd by `avr_make_mcu_by_name`) is freed.
        unsafe {
            ffi::avr_terminate(self.avr.as_ptr());
            free(self.avr.as_ptr().cast());
            drop(Box::from_raw(self.hooks.as_ptr()));
            drop(self.imu.take());
        }
    }
}
