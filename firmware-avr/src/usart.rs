//! USART0 (the Mega's USB serial, pins D0/D1): 8N1, double speed (U2X); receive and transmit
//! by interrupt through two lock-free single-producer/single-consumer rings.
//!
//! - **Receive**: the `USART0_RX` interrupt ([`on_rx_interrupt`]) moves each byte from UDR0 into
//!   the receive ring; the main loop takes them out ([`Usart0::read_into`]). Neither side turns
//!   interrupts off: the chip holds only two received bytes plus the one in its shift register,
//!   so at 1 Mbaud (160 cycles per byte) an interrupts-off stretch on the read path would lose
//!   bytes. Bytes that arrive while the ring is full are dropped and counted
//!   ([`Usart0::rx_dropped`]), bytes the chip itself lost (data overrun, DOR0) or received
//!   with a framing error are counted too ([`Usart0::line_errors`]); the frame layer above
//!   detects the damage by its CRC.
//! - **Transmit**: [`Usart0::send`] puts an answer into the transmit ring and returns; the
//!   `USART0_UDRE` interrupt ([`on_udre_interrupt`]) feeds UDR0 from it, so the device computes
//!   the next request while the previous answer is on the wire. `send` waits only when the
//!   ring is full (interrupts on).
//!
//! The binary forwards both interrupts (`forward_interrupts!` in [`crate::app`]). The cycle
//! benchmark instead transmits by polling ([`Usart0::write`]), which must not be mixed with
//! [`Usart0::send`].

use crate::{pac, F_CPU_HZ};
use avr_device::interrupt;
use core::cell::UnsafeCell;
use core::sync::atomic::{compiler_fence, Ordering};

/// Capacity of each ring, bytes (a power of two that divides 256: the ring indices are `u8`
/// that wrap).
pub const RING_CAPACITY: usize = 128;

/// Capacity of the receive buffer, bytes.
pub const RX_CAPACITY: usize = RING_CAPACITY;

/// Capacity of the transmit buffer, bytes: the longest answer frame fits.
pub const TX_CAPACITY: usize = RING_CAPACITY;

const _: () = assert!(RING_CAPACITY.is_power_of_two() && RING_CAPACITY <= 128);
const _: () = assert!(quad_device::device::TX_LEN <= TX_CAPACITY);

/// UCSR0B with the receiver, the transmitter and the receive interrupt on, and the
/// data-register-empty interrupt on when `sending` (bytes waiting); datasheet §22.10.3.
#[inline(always)]
fn ucsr0b(w: &mut pac::usart0::ucsr0b::W, sending: bool) -> &mut pac::usart0::ucsr0b::W {
    w.rxcie0()
        .set_bit()
        .rxen0()
        .set_bit()
        .txen0()
        .set_bit()
        .udrie0()
        .bit(sending)
}

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

/// A byte shared between the main loop and one interrupt handler, read and written whole.
///
/// A `u8` load or store is one instruction on the AVR, so it cannot tear. Not an `AtomicU8`:
/// LLVM's AVR backend brackets every atomic access with `cli` and a restore of SREG, the very
/// interrupts-off stretches this module avoids. Volatile accesses plus compiler fences give
/// the ordering a single core needs.
pub(crate) struct SharedU8(UnsafeCell<u8>);

// SAFETY: single-core MCU; each `SharedU8` has one writer (documented at its use) and its
// accesses are single-instruction volatile loads and stores.
unsafe impl Sync for SharedU8 {}

impl SharedU8 {
    pub(crate) const fn new(v: u8) -> SharedU8 {
        SharedU8(UnsafeCell::new(v))
    }

    #[inline(always)]
    pub(crate) fn load(&self) -> u8 {
        // SAFETY: a valid, aligned byte; see the `Sync` impl.
        unsafe { self.0.get().read_volatile() }
    }

    #[inline(always)]
    pub(crate) fn store(&self, v: u8) {
        // SAFETY: as in `load`.
        unsafe { self.0.get().write_volatile(v) }
    }
}

/// A counter written only by an interrupt handler (saturating).
struct IsrCounter(UnsafeCell<u16>);

// SAFETY: written only inside one interrupt handler (no nesting of that handler); read by the
// main code with interrupts off (a `u16` takes two loads).
unsafe impl Sync for IsrCounter {}

impl IsrCounter {
    const fn new() -> IsrCounter {
        IsrCounter(UnsafeCell::new(0))
    }

    /// Adds one; call only from the owning interrupt handler.
    #[inline(always)]
    fn bump(&self) {
        // SAFETY: only the owning handler writes, and nothing preempts it.
        unsafe {
            let p = self.0.get();
            p.write_volatile(p.read_volatile().saturating_add(1));
        }
    }

    /// The count (interrupts off for the two loads: a few cycles, outside the read path).
    fn get(&self) -> u16 {
        // SAFETY: interrupts are off: the handler cannot write between the two byte loads.
        interrupt::free(|_| unsafe { self.0.get().read_volatile() })
    }
}

/// A single-producer/single-consumer byte ring: the producer only writes `head` and the slot
/// at `head`, the consumer only writes `tail`; each publishes its index after (producer) or
/// before reusing (consumer) the slot, so neither needs interrupts off.
struct Ring {
    buf: UnsafeCell<[u8; RING_CAPACITY]>,
    /// Next slot to write (free-running, wraps at 256); written by the producer only.
    head: SharedU8,
    /// Next slot to read (free-running); written by the consumer only.
    tail: SharedU8,
}

// SAFETY: see the type's docs: one producer context and one consumer context, each touching
// only its own index and the slots the other has published to it.
unsafe impl Sync for Ring {}

const MASK: u8 = (RING_CAPACITY - 1) as u8;

impl Ring {
    const fn new() -> Ring {
        Ring {
            buf: UnsafeCell::new([0; RING_CAPACITY]),
            head: SharedU8::new(0),
            tail: SharedU8::new(0),
        }
    }

    /// Bytes waiting (producer or consumer side).
    #[inline(always)]
    fn len(&self) -> u8 {
        self.head.load().wrapping_sub(self.tail.load())
    }

    /// Producer: appends `byte`; false when the ring is full.
    #[inline(always)]
    fn push(&self, byte: u8) -> bool {
        let head = self.head.load();
        if usize::from(head.wrapping_sub(self.tail.load())) >= RING_CAPACITY {
            return false;
        }
        // SAFETY: the slot at `head` is not published to the consumer until `head` moves.
        unsafe { (*self.buf.get())[usize::from(head & MASK)] = byte };
        compiler_fence(Ordering::Release);
        self.head.store(head.wrapping_add(1));
        true
    }

    /// Consumer: hands the waiting bytes that lie in one piece (from the oldest up to the
    /// newest or the end of the buffer, whichever comes first), at most `max`, to `f` where
    /// they lie, then drops them from the ring.
    #[inline(always)]
    fn consume<R>(&self, max: usize, f: impl FnOnce(&[u8]) -> R) -> R {
        let tail = self.tail.load();
        let waiting = usize::from(self.head.load().wrapping_sub(tail));
        compiler_fence(Ordering::Acquire);
        let start = usize::from(tail & MASK);
        let n = waiting.min(RING_CAPACITY - start).min(max);
        // SAFETY: `start + n <= RING_CAPACITY`; the producer published these `n` slots and
        // does not write them until `tail` moves past them, after `f` returns.
        let bytes =
            unsafe { core::slice::from_raw_parts(self.buf.get().cast::<u8>().add(start), n) };
        let r = f(bytes);
        compiler_fence(Ordering::Release);
        self.tail.store(tail.wrapping_add(n as u8));
        r
    }

    /// Producer: appends as many of `bytes` as there is room for and returns how many; the
    /// room is computed once, and each byte is published as soon as it is stored.
    #[inline(always)]
    fn push_from(&self, bytes: &[u8]) -> usize {
        let mut head = self.head.load();
        let room = RING_CAPACITY - usize::from(head.wrapping_sub(self.tail.load()));
        let n = room.min(bytes.len());
        for &byte in &bytes[..n] {
            // SAFETY: the slot at `head` is not published to the consumer until `head` moves.
            unsafe { (*self.buf.get())[usize::from(head & MASK)] = byte };
            head = head.wrapping_add(1);
            compiler_fence(Ordering::Release);
            self.head.store(head);
        }
        n
    }

    /// Consumer: takes the oldest byte.
    #[inline(always)]
    fn pop(&self) -> Option<u8> {
        let tail = self.tail.load();
        if self.head.load() == tail {
            return None;
        }
        compiler_fence(Ordering::Acquire);
        // SAFETY: the producer published the slot at `tail` and does not touch it until
        // `tail` moves past it.
        let byte = unsafe { (*self.buf.get())[usize::from(tail & MASK)] };
        compiler_fence(Ordering::Release);
        self.tail.store(tail.wrapping_add(1));
        Some(byte)
    }

    /// Consumer: moves the bytes waiting (as many as fit in `out`), oldest first, into `out`
    /// and returns how many; the indices are read and written once for all of them.
    #[inline(always)]
    fn pop_into(&self, out: &mut [u8]) -> usize {
        let tail = self.tail.load();
        let n = usize::from(self.head.load().wrapping_sub(tail)).min(out.len());
        compiler_fence(Ordering::Acquire);
        let mut at = tail;
        for slot in &mut out[..n] {
            // SAFETY: the producer published the slots from `tail` to `head` and does not
            // touch them until `tail` moves past them.
            *slot = unsafe { (*self.buf.get())[usize::from(at & MASK)] };
            at = at.wrapping_add(1);
        }
        compiler_fence(Ordering::Release);
        self.tail.store(at);
        n
    }
}

/// Received bytes: produced by `USART0_RX`, consumed by the main loop.
static RX: Ring = Ring::new();
/// Bytes to send: produced by the main loop, consumed by `USART0_UDRE`.
static TX: Ring = Ring::new();
static RX_DROPPED: IsrCounter = IsrCounter::new();
static LINE_ERRORS: IsrCounter = IsrCounter::new();

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
        usart.ucsr0b().write(|w| ucsr0b(w, false));
        Usart0 { usart, sent: false }
    }

    /// The oldest received byte, if any.
    pub fn read(&mut self) -> Option<u8> {
        RX.pop()
    }

    /// Moves the received bytes, oldest first, into `buf` (as many as fit); returns how many.
    /// Lock-free: the receive interrupt stays enabled throughout. The bytes that arrive while
    /// it copies are left for the next call.
    pub fn read_into(&mut self, buf: &mut [u8]) -> usize {
        RX.pop_into(buf)
    }

    /// Hands up to `max` received bytes to `f` where they lie in the receive ring, oldest
    /// first, and then drops them (when the waiting bytes wrap around the ring's end, the part
    /// up to it: the rest comes with the next call). No copy; lock-free as
    /// [`Usart0::read_into`]. The bytes keep their slots while `f` runs: `max` bounds the
    /// room they take from bytes that arrive meanwhile. An associated function, so that `f`
    /// may send through the [`Usart0`]: the main loop is the ring's only consumer (do not
    /// call it from an interrupt handler).
    pub fn with_received<R>(max: usize, f: impl FnOnce(&[u8]) -> R) -> R {
        RX.consume(max, f)
    }

    /// Queues `bytes` for the transmit interrupt and returns; waits (interrupts on) only while
    /// the transmit ring is full.
    ///
    /// Never inlined: the answer encoder hands its frame over in pieces from two places
    /// (`quad_protocol::encode_frame_in_pieces`), and the compiler, which sees the one sender,
    /// would otherwise copy this function into each.
    #[inline(never)]
    pub fn send(&mut self, bytes: &[u8]) {
        let Some((&first, mut rest)) = bytes.split_first() else {
            return;
        };
        while !TX.push(first) {
            // Full: make sure the transmitter is draining it.
            self.start_transmitter();
        }
        // The first byte leaves while the others are queued.
        self.start_transmitter();
        while !rest.is_empty() {
            let n = TX.push_from(rest);
            rest = &rest[n..];
            // Draining (and, when the ring was full, waited on: the loop comes back as soon as
            // the interrupt has made room).
            self.start_transmitter();
        }
    }

    fn start_transmitter(&mut self) {
        self.sent = true;
        // One store, not a read-modify-write: the interrupt handler, which writes the same
        // register when the ring runs empty, cannot come between a read and a write.
        self.usart.ucsr0b().write(|w| ucsr0b(w, true));
    }

    /// Bytes queued by [`Usart0::send`] and not yet handed to the transmitter.
    pub fn tx_pending(&self) -> usize {
        usize::from(TX.len())
    }

    /// Sends one byte by polling, waiting for room in the transmit register (the benchmark's
    /// transmitter; not to be mixed with [`Usart0::send`]).
    pub fn write(&mut self, byte: u8) {
        while self.usart.ucsr0a().read().udre0().bit_is_clear() {}
        // Writing 1 to TXC0 clears it (U2X0 written again to keep double speed).
        self.usart
            .ucsr0a()
            .write(|w| w.u2x0().set_bit().txc0().set_bit());
        self.usart.udr0().write(|w| w.set(byte));
        self.sent = true;
    }

    /// Sends all bytes by polling ([`Usart0::write`]).
    pub fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write(b);
        }
    }

    /// Waits until every byte queued or written has left the shift register.
    pub fn flush(&mut self) {
        while TX.len() != 0 {}
        if self.sent {
            while self.usart.ucsr0a().read().txc0().bit_is_clear() {}
        }
    }

    /// Bytes dropped because the receive ring was full, since boot (saturating).
    pub fn rx_dropped(&self) -> u16 {
        RX_DROPPED.get()
    }

    /// Bytes received with a framing error or after a data overrun of the chip's own
    /// two-byte buffer (bytes lost before the interrupt could read them), since boot
    /// (saturating).
    pub fn line_errors(&self) -> u16 {
        LINE_ERRORS.get()
    }
}

/// Moves the received byte into the receive ring; call from the `USART0_RX` interrupt.
#[inline(always)]
pub fn on_rx_interrupt() {
    // SAFETY: only UCSR0A and UDR0 are read here; the main code reads UCSR0A (no side effect)
    // and never reads UDR0.
    let usart = unsafe { pac::USART0::steal() };
    // The status belongs to the byte at the head of the chip's buffer: read it before UDR0.
    let status = usart.ucsr0a().read();
    let line_error = status.fe0().bit_is_set() || status.dor0().bit_is_set();
    let byte = usart.udr0().read().bits();
    if line_error {
        LINE_ERRORS.bump();
    }
    if !RX.push(byte) {
        RX_DROPPED.bump();
    }
}

/// Hands the next queued byte to the transmitter, or turns this interrupt off when none is
/// left; call from the `USART0_UDRE` interrupt.
#[inline(always)]
pub fn on_udre_interrupt() {
    // SAFETY: UDR0 (write) and UCSR0A/B: the main code writes UCSR0B only with single stores
    // and UCSR0A only in the polled `write`, which is not used together with `send`.
    let usart = unsafe { pac::USART0::steal() };
    match TX.pop() {
        Some(byte) => {
            // Clears TXC0 (written 1) so that `flush` waits for this byte; keeps U2X0.
            usart
                .ucsr0a()
                .write(|w| w.u2x0().set_bit().txc0().set_bit());
            usart.udr0().write(|w| w.set(byte));
        }
        None => {
            usart.ucsr0b().write(|w| ucsr0b(w, false));
        }
    }
}
