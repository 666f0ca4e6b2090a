//! Stack high-water mark: SRAM between the end of the static data and the stack pointer is
//! painted with [`PAINT`] at boot; the lowest overwritten byte later tells how deep the stack
//! went.
//!
//! The ATmega2560's SRAM spans 0x0200..=0x21FF; avr-gcc's linker script puts `.data`,
//! `.bss` and `.noinit` at the bottom (ending at `__heap_start`) and the stack grows down from
//! RAMEND. There is no heap.

/// First SRAM address.
pub const RAM_START: u16 = 0x0200;
/// Last SRAM address.
pub const RAM_END: u16 = 0x21FF;
/// The paint byte.
pub const PAINT: u8 = 0xC5;
/// Bytes below the stack pointer left unpainted (room for the painting code's own calls).
const MARGIN: u16 = 16;

extern "C" {
    /// End of `.data` + `.bss` + `.noinit` (avr-gcc linker script).
    static __heap_start: u8;
}

fn heap_start() -> u16 {
    // SAFETY: only the address of the linker symbol is taken.
    core::ptr::addr_of!(__heap_start) as u16
}

fn stack_pointer() -> u16 {
    let (lo, hi): (u8, u8);
    // SAFETY: reads SPL and SPH.
    unsafe {
        core::arch::asm!("in {}, 0x3d", "in {}, 0x3e", out(reg) lo, out(reg) hi,
            options(nostack, nomem, preserves_flags));
    }
    u16::from_le_bytes([lo, hi])
}

/// Bytes of static data in SRAM (`.data` + `.bss` + `.noinit`).
pub fn static_bytes() -> u16 {
    heap_start() - RAM_START
}

/// Paints the free SRAM; call first thing in `main`.
#[inline(never)]
pub fn paint() {
    let end = stack_pointer().saturating_sub(MARGIN);
    let mut p = heap_start();
    while p < end {
        // SAFETY: the addresses lie between the static data and the live stack: unused SRAM.
        unsafe { core::ptr::write_volatile(p as *mut u8, PAINT) };
        p += 1;
    }
}

/// The deepest the stack has been since [`paint`], bytes from RAMEND (includes the bytes the
/// C runtime and `main` use).
pub fn max_used_bytes() -> u16 {
    let mut p = heap_start();
    // SAFETY: reads SRAM between the static data and the stack pointer.
    while p < RAM_END && unsafe { core::ptr::read_volatile(p as *const u8) } == PAINT {
        p += 1;
    }
    RAM_END + 1 - p
}
