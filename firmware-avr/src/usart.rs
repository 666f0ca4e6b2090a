//! USART0 (the Mega's USB serial, pins D0/D1): 8N1, double speed (U2X), interrupt-driven
//! receive into a bounded ring buffer, polled transmit.
//!
//! The binary forwards the `USART0_RX` interrupt to [`on_rx_interrupt`]. Bytes that arrive
//! while the buffer is full are dropped and counted ([`Usart0::rx_dropped`]); the frame layer
//! above detects the damage by its CRC.

use crate::{pac, F_CPU_HZ};
use avr_device::interrupt::{self, Mutex};
use core::cell::RefCell;

/// Capacity of the receive buffer, bytes.
pub const RX_CAPACITY: usize = 128;

/// Supported line rates. With U2X at 16 MHz, 1,000,000 baud is exact and 115,200 baud is
/// 2.1 % fast (UBRR 16), within the receivers' tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Baud {
    /// 115,200 baud (UBRR = 16).
    B115200,
    /// 1,000,000 baud (UBRR = 1).
    B1000000,
}

impl Baud {
    /// Bits per second.
    pub const fn bits_per_s(self) -> u32 {
        match self {
            Baud::B115200 => 115_200,
            Baud::B1000000 => 1_000_000,
        }
    }

    /// UBRR0 value with U2X: `round(F_CPU / (8·baud)) − 1`.
    pub const fn ubrr(self) -> u16 {
        let div = 8 * self.bits_per_s();
        ((F_CPU_HZ + div / 2) / div - 1) as u16
    }
}

struct Ring {
    buf: [u8; RX_CAPACITY],
    head: u8,
    len: u8,
    dropped: u16,
    line_errors: u16,
}

static RX: Mutex<RefCell<Ring>> = Mutex::new(RefCell::new(Ring {
    buf: [0; RX_CAPACITY],
    head: 0,
    len: 0,
    dropped: 0,
    line_errors: 0,
}));

/// USART0 in 8N1 at a [`Baud`].
pub struct Usart0 {
    usart: pac::USART0,
    sent: bool,
}

impl Usart0 {
    /// Configures USART0 and enables the receiver, its interrupt and the transmitter
    /// (interrupts must be enabled by the caller).
    pub fn new(usart: pac::USART0, baud: Baud) -> Usart0 {
        // U2X before UBRR: the chip does not care, but simavr derives the line rate when UBRR
        // is written and would otherwise run at half the rate.
        usart.ucsr0a().write(|w| w.u2x0().set_bit());
        usart.ubrr0().write(|w| w.set(baud.ubrr()));
        usart
            .ucsr0c()
            .write(|w| w.ucsz0().chr8().usbs0().stop1().upm0().disabled());
        usart
            .ucsr0b()
            .write(|w| w.rxen0().set_bit().txen0().set_bit().rxcie0().set_bit());
        Usart0 { usart, sent: false }
    }

    /// The oldest received byte, if any.
    pub fn read(&mut self) -> Option<u8> {
        interrupt::free(|cs| {
            let mut r = RX.borrow(cs).borrow_mut();
            if r.len == 0 {
                return None;
            }
            let b = r.buf[r.head as usize];
            r.head = ((r.head as usize + 1) % RX_CAPACITY) as u8;
            r.len -= 1;
            Some(b)
        })
    }

    /// Moves the received bytes, oldest first, into `buf` (as many as fit); returns how many.
    pub fn read_into(&mut self, buf: &mut [u8]) -> usize {
        interrupt::free(|cs| {
            let mut r = RX.borrow(cs).borrow_mut();
            let n = (r.len as usize).min(buf.len());
            for b in buf.iter_mut().take(n) {
                *b = r.buf[r.head as usize];
                r.head = ((r.head as usize + 1) % RX_CAPACITY) as u8;
            }
            r.len -= n as u8;
            n
        })
    }

    /// Sends one byte, waiting for room in the transmit register.
    pub fn write(&mut self, byte: u8) {
        while self.usart.ucsr0a().read().udre0().bit_is_clear() {}
        // Writing 1 to TXC0 clears it (U2X0 written again to keep double speed).
        self.usart
            .ucsr0a()
            .write(|w| w.u2x0().set_bit().txc0().set_bit());
        self.usart.udr0().write(|w| w.set(byte));
        self.sent = true;
    }

    /// Sends all bytes.
    pub fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write(b);
        }
    }

    /// Waits until the last byte written has left the shift register.
    pub fn flush(&mut self) {
        if self.sent {
            while self.usart.ucsr0a().read().txc0().bit_is_clear() {}
        }
    }

    /// Bytes dropped because the receive buffer was full, since boot (saturating).
    pub fn rx_dropped(&self) -> u16 {
        interrupt::free(|cs| RX.borrow(cs).borrow().dropped)
    }

    /// Bytes received with a framing or overrun error, since boot (saturating).
    pub fn line_errors(&self) -> u16 {
        interrupt::free(|cs| RX.borrow(cs).borrow().line_errors)
    }
}

/// Moves the received byte into the ring buffer; call from the `USART0_RX` interrupt.
#[inline(always)]
pub fn on_rx_interrupt() {
    // SAFETY: only UCSR0A and UDR0 are read, which the main code never reads concurrently
    // (it only writes UDR0/reads UDRE0 and TXC0: reading UCSR0A has no side effect).
    let usart = unsafe { pac::USART0::steal() };
    let status = usart.ucsr0a().read();
    let line_error = status.fe0().bit_is_set() || status.dor0().bit_is_set();
    let byte = usart.udr0().read().bits();
    interrupt::free(|cs| {
        let mut r = RX.borrow(cs).borrow_mut();
        if line_error {
            r.line_errors = r.line_errors.saturating_add(1);
        }
        if (r.len as usize) < RX_CAPACITY {
            let tail = (r.head as usize + r.len as usize) % RX_CAPACITY;
            r.buf[tail] = byte;
            r.len += 1;
        } else {
            r.dropped = r.dropped.saturating_add(1);
        }
    });
}
