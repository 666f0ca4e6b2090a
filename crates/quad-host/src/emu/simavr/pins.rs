//! The pins and the servo pulses on them (see the module docs of [`super`]), and the commit of
//! a servo compare register's two bytes as the chip does it.

use super::super::{CYCLES_PER_US, SERVO_PINS};
use super::Mega2560;
use simavr_ffi as ffi;
use std::ffi::c_void;

/// Data addresses of the low bytes of the twelve servo compare registers (OCR1A/B/C,
/// OCR3A/B/C, OCR4A/B/C, OCR5A/B/C), in channel order.
pub(super) const OCR_LOW: [u16; 12] = [
    0x88, 0x8A, 0x8C, 0x98, 0x9A, 0x9C, 0xA8, 0xAA, 0xAC, 0x128, 0x12A, 0x12C,
];

/// Data addresses of (DDRx, PORTx) of the ports A–L.
fn port_regs(port: char) -> Option<(u16, u16)> {
    let base = match port.to_ascii_uppercase() {
        'A' => 0x20,
        'B' => 0x23,
        'C' => 0x26,
        'D' => 0x29,
        'E' => 0x2C,
        'F' => 0x2F,
        'G' => 0x32,
        'H' => 0x100,
        'J' => 0x103,
        'K' => 0x106,
        'L' => 0x109,
        _ => return None,
    };
    Some((base + 1, base + 2))
}

/// One high pulse seen on a servo pin.
///
/// The pins are read after every simavr step (one instruction, or an interrupt entry and its
/// first instruction): an edge is seen at the end of the step in which it happened, up to that
/// step's length late. [`Pulse::width_could_be`] takes this into account.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pulse {
    /// Channel (index into [`SERVO_PINS`]).
    pub channel: usize,
    /// Cycle at which the rising edge was seen.
    pub rise_cycle: u64,
    /// Cycles between seeing the rising and the falling edge.
    pub high_cycles: u64,
    /// Length of the step in which the rising edge was seen, cycles.
    pub rise_step_cycles: u64,
    /// Length of the step in which the falling edge was seen, cycles.
    pub fall_step_cycles: u64,
}

impl Pulse {
    /// High time as seen, µs.
    pub fn high_us(&self) -> f64 {
        self.high_cycles as f64 / CYCLES_PER_US as f64
    }

    /// True when the real width (within the steps' uncertainty) can be within `tolerance` of
    /// `want` cycles.
    pub fn width_could_be(&self, want: u64, tolerance: u64) -> bool {
        let lo = self.high_cycles.saturating_sub(self.fall_step_cycles);
        let hi = self.high_cycles + self.rise_step_cycles;
        want + tolerance >= lo && want <= hi + tolerance
    }
}

/// simavr's write handler of one OCR low byte, and the value the register had after the
/// previous low-byte write.
pub(super) struct OcrWrite {
    pub(super) handler: ffi::avr_io_write_t,
    pub(super) param: *mut c_void,
    pub(super) committed: u16,
}

/// The write handler installed on a servo OCR low byte: simavr's own, then — when that one
/// saw no change because only the high byte changed — simavr's again with the low byte
/// perturbed before the call, so that it reconfigures the timer with the committed value.
pub(super) unsafe extern "C" fn on_ocr_low_write(
    avr: *mut ffi::avr_t,
    addr: ffi::avr_io_addr_t,
    v: u8,
    param: *mut c_void,
) {
    // SAFETY: `param` points into the `Hooks` allocation (see `on_uart_output`); `avr` is the
    // running simulator and `addr`, `addr + 1` are the register's bytes in its data space.
    unsafe {
        let w = &mut *param.cast::<OcrWrite>();
        let data = (*avr).data;
        let lo = usize::from(addr);
        let before = u16::from_le_bytes([*data.add(lo), *data.add(lo + 1)]);
        if let Some(handler) = w.handler {
            handler(avr, addr, v, w.param);
            let after = u16::from_le_bytes([*data.add(lo), *data.add(lo + 1)]);
            if after == before && after != w.committed {
                *data.add(lo) ^= 1;
                handler(avr, addr, v, w.param);
            }
            w.committed = after;
        }
    }
}

impl Mega2560 {
    /// The level driven on pin `bit` of `port` ('A'..='L'): its PORT bit when DDR makes it an
    /// output, low otherwise. Unknown ports read low.
    pub fn pin(&self, port: char, bit: u8) -> bool {
        port_regs(port).is_some_and(|(ddr, p)| {
            let m = 1u8 << (bit & 7);
            self.data(ddr) & m != 0 && self.data(p) & m != 0
        })
    }

    /// True when pin `bit` of `port` is configured as an output.
    pub fn is_output(&self, port: char, bit: u8) -> bool {
        port_regs(port).is_some_and(|(ddr, _)| self.data(ddr) & (1 << (bit & 7)) != 0)
    }

    /// Levels of the twelve servo pins, bit `i` = channel `i`.
    pub fn servo_levels(&self) -> u16 {
        let level = |(ddr, port): (u16, u16)| self.data(ddr) & self.data(port);
        let (b, e, h, l) = (
            level((0x24, 0x25)),
            level((0x2D, 0x2E)),
            level((0x101, 0x102)),
            level((0x10A, 0x10B)),
        );
        let mut out = 0u16;
        for (i, &(port, bit)) in SERVO_PINS.iter().enumerate() {
            let v = match port {
                'B' => b,
                'E' => e,
                'H' => h,
                _ => l,
            };
            if v & (1 << bit) != 0 {
                out |= 1 << i;
            }
        }
        out
    }

    /// Starts (or stops) recording the servo pulses ([`Mega2560::take_pulses`]). Edges are
    /// tracked after every instruction either way.
    pub fn capture_pulses(&mut self, on: bool) {
        self.capture = on;
        if !on {
            self.pulses.clear();
        }
    }

    /// The servo pulses completed since the last call (capture on), in order of their
    /// falling edges.
    pub fn take_pulses(&mut self) -> Vec<Pulse> {
        self.pulses.drain(..).collect()
    }

    /// The oldest servo pulse completed and not yet taken (capture on).
    pub fn pop_pulse(&mut self) -> Option<Pulse> {
        self.pulses.pop_front()
    }

    /// True while a pulse is in progress on `channel`.
    pub fn pulse_in_progress(&self, channel: usize) -> bool {
        self.rise.get(channel).is_some_and(Option::is_some)
    }

    pub(super) fn track_servos(&mut self, step: u64) {
        let now = self.servo_levels();
        let changed = now ^ self.levels;
        if changed == 0 {
            return;
        }
        let cycle = self.cycle();
        for ch in 0..12 {
            let bit = 1u16 << ch;
            if changed & bit == 0 {
                continue;
            }
            if now & bit != 0 {
                self.rise[ch] = Some((cycle, step));
            } else if let Some((r, rise_step)) = self.rise[ch].take() {
                if self.capture {
                    self.pulses.push_back(Pulse {
                        channel: ch,
                        rise_cycle: r,
                        high_cycles: cycle - r,
                        rise_step_cycles: rise_step,
                        fall_step_cycles: step,
                    });
                }
            }
        }
        self.levels = now;
    }
}
