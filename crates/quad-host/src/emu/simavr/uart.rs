//! USART0 as strict as the chip (see the module docs of [`super`]): the bytes handed to the
//! receiver paced one per byte time, the chip's data overrun, the bytes sent; and the longest
//! stretches with interrupts off, while bytes arrive or otherwise.

use super::{Hooks, Mega2560, F_CPU_HZ};
use simavr_ffi as ffi;
use std::ffi::c_void;

/// Data-space addresses of USART0's registers.
const UCSR0A: u16 = 0xC0;

const UDR0: u16 = 0xC6;

/// UCSR0A's data-overrun flag.
const UCSR0A_DOR0: u8 = 1 << 3;

/// Slots of simavr's USART receive FIFO (`DECLARE_FIFO(uint16_t, uart_fifo, 64)`).
const RX_FIFO_SLOTS: u16 = 64;

/// The global interrupt flag's bit in SREG (simavr's `sreg[S_I]`).
const SREG_I_BIT: usize = 7;

const UCSR0B: u16 = 0xC1;
/// UCSR0B's receiver-enable bit.
const UCSR0B_RXEN0: u8 = 1 << 4;

const UBRR0L: u16 = 0xC4;

const UBRR0H: u16 = 0xC5;

/// The longest stretches with interrupts off (SREG.I clear, interrupt handlers included).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct InterruptsOff {
    /// The longest, cycles.
    pub longest_cycles: u64,
    /// The longest part of a stretch during which the receiver was on and bytes were arriving
    /// or waiting unread in it, cycles: what can cost bytes (from reset until the firmware
    /// turns the receiver on, the chip hears nothing).
    pub longest_receiving_cycles: u64,
    /// Where that part began ([`Mega2560::cycle`]).
    pub longest_receiving_at_cycle: u64,
    /// The program counter (byte address) at which its stretch began.
    pub longest_receiving_pc: u32,
}

pub(super) unsafe extern "C" fn on_uart_output(
    _: *mut ffi::avr_irq_t,
    value: u32,
    param: *mut c_void,
) {
    // SAFETY: `param` is the `Hooks` allocation registered in `Mega2560::new`, alive until the
    // simulator is dropped; simavr calls hooks only from within `avr_run`/`avr_raise_irq`,
    // during which no Rust reference to it exists.
    let hooks = unsafe { &mut *param.cast::<Hooks>() };
    // SAFETY: the avr_t outlives its hooks.
    let raw = unsafe { (*hooks.avr).cycle };
    hooks.out.push_back((hooks.base + raw, value as u8));
}

pub(super) unsafe extern "C" fn on_uart_xon(_: *mut ffi::avr_irq_t, _: u32, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    unsafe { (*param.cast::<Hooks>()).xon = true };
}

pub(super) unsafe extern "C" fn on_uart_xoff(_: *mut ffi::avr_irq_t, _: u32, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    unsafe { (*param.cast::<Hooks>()).xon = false };
}

impl Mega2560 {
    /// Hands bytes to USART0's receiver: they go on the line back to back at the firmware's
    /// line rate, starting now (or when the bytes before them are through), and reach the
    /// receiver as the chip's would (see the module docs: a byte the firmware is too slow for
    /// is lost).
    pub fn uart_write(&mut self, bytes: &[u8]) {
        self.input.extend(bytes);
        self.feed_uart();
    }

    /// Bytes handed to [`Mega2560::uart_write`] that have not started on the line yet.
    pub fn uart_input_pending(&self) -> usize {
        self.input.len()
    }

    /// Bytes the receive buffer lost since power-on because the firmware did not read them in
    /// time (data overruns, see the module docs).
    pub fn rx_overruns(&self) -> u64 {
        self.rx_overruns
    }

    /// The longest interrupts-off stretches seen since power-on (or the last
    /// [`Mega2560::reset_interrupts_off`]).
    pub fn interrupts_off(&self) -> InterruptsOff {
        self.interrupts_off
    }

    /// Forgets the interrupts-off stretches seen so far (e.g. those of the boot code).
    pub fn reset_interrupts_off(&mut self) {
        self.interrupts_off = InterruptsOff::default();
        self.cli_since = None;
    }

    /// simavr's USART0 (the parameter of its UDR0 read handler).
    fn uart0(&self) -> *mut ffi::avr_uart_t {
        // SAFETY: the I/O table is part of the live simulator; UDR0 has a read handler
        // registered by simavr's USART0 module, whose parameter is its `avr_uart_t`.
        unsafe {
            (*self.avr.as_ptr()).io[usize::from(UDR0) - 0x20]
                .r
                .param
                .cast()
        }
    }

    /// simavr's receive FIFO: bytes in it (received or arriving, not yet read by the firmware)
    /// and its read index.
    fn rx_fifo(&self) -> (u16, u16) {
        let uart = self.uart0();
        if uart.is_null() {
            return (0, 0);
        }
        // SAFETY: a live `avr_uart_t`; nothing runs inside simavr now.
        let fifo = unsafe { &(*uart).input };
        let len = fifo.write.wrapping_sub(fifo.read) & (RX_FIFO_SLOTS - 1);
        (len, fifo.read)
    }

    /// One byte time on the line as simavr's receiver counts it, cycles (0 before the firmware
    /// configured USART0).
    fn rx_byte_cycles(&self) -> u64 {
        let uart = self.uart0();
        if uart.is_null() {
            return 0;
        }
        // SAFETY: as in `rx_fifo`.
        unsafe { (*uart).cycles_per_byte }
    }

    /// Puts the bytes whose line slot has come into simavr's receiver, applying the chip's
    /// overrun (see the module docs).
    pub(super) fn feed_uart(&mut self) {
        let now = self.cycle();
        let byte_cycles = self.rx_byte_cycles().max(1);
        while !self.input.is_empty() && self.rx_line_free <= now {
            let (unread, read_index) = self.rx_fifo();
            if unread >= 3 {
                // Two bytes in the buffer, one complete in the shift register, and a new start
                // bit: the shift register's byte — the newest in the FIFO — is lost.
                let uart = self.uart0();
                // SAFETY: as in `rx_fifo`; the newest entry is dropped by moving the write
                // index back one slot.
                unsafe {
                    let fifo = &mut (*uart).input;
                    fifo.write = fifo.write.wrapping_sub(1) & (RX_FIFO_SLOTS - 1);
                }
                self.rx_overruns += 1;
                self.dor_owed = Some(read_index);
            }
            let Some(b) = self.input.pop_front() else {
                break;
            };
            // SAFETY: a valid IRQ of this simulator.
            unsafe { ffi::avr_raise_irq(self.uart_in.as_ptr(), u32::from(b)) };
            self.rx_line_free = self.rx_line_free.max(now) + byte_cycles;
        }
        self.owe_dor();
    }

    /// Keeps DOR0 set after an overrun until the firmware reads UDR0 (see the module docs).
    pub(super) fn owe_dor(&mut self) {
        let Some(read_at_overrun) = self.dor_owed else {
            return;
        };
        if self.rx_fifo().1 != read_at_overrun {
            self.dor_owed = None;
            return;
        }
        let avr = self.avr.as_ptr();
        // SAFETY: UCSR0A is within the data space; nothing runs inside simavr now.
        unsafe { *(*avr).data.add(usize::from(UCSR0A)) |= UCSR0A_DOR0 };
    }

    /// True while USART0's receiver is on (RXEN0) and bytes are on their way to it or wait
    /// unread in it. With the receiver off (from reset until the firmware sets the USART up)
    /// the chip hears nothing, so no byte can be lost to a stretch with interrupts off.
    fn receiving(&self) -> bool {
        self.data(UCSR0B) & UCSR0B_RXEN0 != 0
            && (!self.input.is_empty() || self.cycle() < self.rx_line_free || self.rx_fifo().0 > 0)
    }

    /// Follows SREG.I after a step that started at cycle `before` at program counter `pc`.
    pub(super) fn track_interrupts_off(&mut self, before: u64, pc: u32) {
        // simavr keeps the flags in `sreg[]` and updates SREG's data byte only when the program
        // reads it.
        let off = self.avr().sreg[SREG_I_BIT] == 0;
        let receiving = self.receiving();
        let now = self.cycle();
        match (&mut self.cli_since, off) {
            (None, true) => self.cli_since = Some((before, pc, receiving.then_some(before))),
            (Some((_, _, since)), true) => {
                if receiving && since.is_none() {
                    *since = Some(before);
                }
            }
            (Some((start, at_pc, since)), false) => {
                let (start, at_pc, since) = (*start, *at_pc, *since);
                self.cli_since = None;
                let s = &mut self.interrupts_off;
                s.longest_cycles = s.longest_cycles.max(now - start);
                // Only the part with the receiver listening and bytes coming can lose them.
                if let Some(since) = since {
                    let len = now - since;
                    if len > s.longest_receiving_cycles {
                        s.longest_receiving_cycles = len;
                        s.longest_receiving_at_cycle = since;
                        s.longest_receiving_pc = at_pc;
                    }
                }
            }
            (None, false) => {}
        }
    }

    /// Bytes USART0 has sent and nobody has taken, with the cycle each was written to UDR0.
    pub fn uart_take(&mut self) -> Vec<(u64, u8)> {
        self.output.drain(..).collect()
    }

    /// The oldest byte USART0 has sent and nobody has taken.
    pub fn uart_pop(&mut self) -> Option<(u64, u8)> {
        self.output.pop_front()
    }

    /// Number of sent bytes not yet taken.
    pub fn uart_available(&self) -> usize {
        self.output.len()
    }

    /// Runs until USART0 has sent `n` more bytes (returned without their cycles), or
    /// `timeout_cycles` elapsed (then `Err` with what came).
    ///
    /// # Errors
    /// A timeout (the bytes so far) — a stopped CPU panics, as it is a firmware bug.
    pub fn read_exact(&mut self, n: usize, timeout_cycles: u64) -> Result<Vec<u8>, Vec<u8>> {
        let end = self.cycle() + timeout_cycles;
        while self.output.len() < n {
            if self.cycle() >= end {
                return Err(self.uart_take().into_iter().map(|(_, b)| b).collect());
            }
            if let Err(e) = self.step() {
                panic!("{e}");
            }
        }
        Ok(self.output.drain(..n).map(|(_, b)| b).collect())
    }

    /// USART0's line rate as the firmware configured it (UBRR0, U2X0), bit/s; `None` while
    /// the receiver is off.
    pub fn uart_baud(&self) -> Option<f64> {
        if self.data(UCSR0B) & UCSR0B_RXEN0 == 0 {
            return None;
        }
        let ubrr = u32::from(self.data(UBRR0L)) | u32::from(self.data(UBRR0H) & 0x0F) << 8;
        let per_bit = if self.data(UCSR0A) & (1 << 1) != 0 {
            8
        } else {
            16
        } * (ubrr + 1);
        Some(f64::from(F_CPU_HZ) / f64::from(per_bit))
    }
}
