//! CRC-16/GENIBUS, bitwise and table-free.
//!
//! Parameters (Rocksoft/reveng model): width 16, poly `0x1021`, init `0xFFFF`, refin false,
//! refout false, xorout `0xFFFF`, check (`"123456789"`) `0xD64E`, residue `0x1D0F`. No lookup
//! table: a few shifts per byte ([`update`]) cost no SRAM on the ATmega2560 (whose default
//! linker script copies read-only tables into RAM). Hand-written rather than taken from the
//! `crc` crate for that reason: its algorithms are table-driven.
//!
//! Why a final XOR: without one (CRC-16/IBM-3740, protocol 1.x) the register over a payload and
//! its own CRC is `0x0000`, and zero bytes fed into a zero register keep it at zero — so a frame
//! with `0x00` bytes added after its CRC (one flipped closing delimiter does that) still passed
//! the check. With xorout `0xFFFF` the register after payload and CRC is the residue `0x1D0F`,
//! which a zero byte changes.
//!
//! On the wire the CRC follows the postcard bytes **most significant byte first**.

/// Initial register value.
pub const INIT: u16 = 0xFFFF;

/// Generator polynomial (x¹⁶ + x¹² + x⁵ + 1, normal form).
pub const POLY: u16 = 0x1021;

/// Final XOR applied to the register to give the CRC ([`finish`]).
pub const XOROUT: u16 = 0xFFFF;

/// The register after a message and its CRC (big-endian) were fed in ([`INIT`], then
/// [`update`] per byte): the same for every message, so a receiver that feeds the CRC along
/// with the message checks it by comparing the register with this value.
pub const RESIDUE: u16 = 0x1D0F;

/// The CRC of the bytes fed into the register `crc` so far ([`INIT`], then [`update`] per
/// byte): the register with [`XOROUT`] applied.
#[inline]
pub const fn finish(crc: u16) -> u16 {
    crc ^ XOROUT
}

/// Feeds one byte into the CRC register `crc`.
///
/// The byte-at-a-time form of the definition (eight steps of "shift left, xor [`POLY`] when the
/// top bit was set", [`update_bitwise`]): for `x = (crc >> 8) ^ byte` folded as `x ^= x >> 4`,
/// the eight steps xor `x·0x1021 = (x << 12) ^ (x << 5) ^ x` into `crc << 8`. Same bits, a few
/// shifts instead of eight conditional steps: about 6× faster on the ATmega2560, where the
/// CRC of every frame sits between a request's last byte and its answer's first.
#[inline]
pub const fn update(crc: u16, byte: u8) -> u16 {
    let [hi, lo] = crc.to_be_bytes();
    let (hi, lo) = step(hi, lo, byte);
    u16::from_be_bytes([hi, lo])
}

/// [`update`] on the register's two bytes `hi`, `lo`: `x << 12` and `x << 5` split into
/// `x << 4`, `x >> 3` (high byte) and `x << 5` (low byte), all 8-bit operations, which the
/// 8-bit AVR does in one instruction each where the 16-bit shifts take two or more.
#[inline(always)]
pub(crate) const fn step(hi: u8, lo: u8, byte: u8) -> (u8, u8) {
    let x = hi ^ byte;
    let x = x ^ (x >> 4);
    (lo ^ (x << 4) ^ (x >> 3), (x << 5) ^ x)
}

/// [`update`] written as the definition: eight shift/xor steps. The tests hold [`update`] to
/// it for every register value and byte.
#[inline]
pub const fn update_bitwise(crc: u16, byte: u8) -> u16 {
    let mut crc = crc ^ ((byte as u16) << 8);
    let mut bit = 0;
    while bit < 8 {
        crc = if crc & 0x8000 != 0 {
            (crc << 1) ^ POLY
        } else {
            crc << 1
        };
        bit += 1;
    }
    crc
}

/// [`update`] with every byte of `data` in turn. Out of line: one copy of the loop for every
/// buffer the firmware checks (frames, storage records).
#[inline(never)]
pub const fn update_slice(crc: u16, data: &[u8]) -> u16 {
    // The register as two bytes throughout: joined into a `u16` at every byte, it was swapped
    // and rebuilt at every byte on the AVR.
    let [mut hi, mut lo] = crc.to_be_bytes();
    let mut i = 0;
    while i < data.len() {
        (hi, lo) = step(hi, lo, data[i]);
        i += 1;
    }
    u16::from_be_bytes([hi, lo])
}

/// CRC of a whole buffer.
pub const fn checksum(data: &[u8]) -> u16 {
    finish(update_slice(INIT, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_byte_wise_update_is_the_bitwise_definition() {
        for crc in 0..=u16::MAX {
            for byte in [0u8, 1, 0x10, 0x7F, 0x80, 0xA5, 0xFF, crc as u8] {
                assert_eq!(
                    update(crc, byte),
                    update_bitwise(crc, byte),
                    "{crc:#x} {byte:#x}"
                );
            }
        }
    }

    #[test]
    fn the_slice_update_is_the_bitwise_definition_byte_after_byte() {
        let mut rng = seeded_rng::SplitMix64::new(5);
        let mut data = [0u8; 130];
        for case in 0..2000 {
            let crc = rng.next_u64() as u16;
            let len = case % data.len();
            for b in &mut data[..len] {
                *b = rng.next_u64() as u8;
            }
            let want = data[..len].iter().fold(crc, |c, &b| update_bitwise(c, b));
            assert_eq!(update_slice(crc, &data[..len]), want, "{crc:#x} {len}");
        }
    }

    #[test]
    fn catalogue_check_value() {
        assert_eq!(checksum(b"123456789"), 0xD64E);
    }

    #[test]
    fn empty_input_is_init_xored() {
        assert_eq!(checksum(&[]), INIT ^ XOROUT);
    }

    #[test]
    fn register_over_payload_and_big_endian_crc_is_the_residue() {
        let mut data = *b"123456789\0\0";
        let crc = checksum(&data[..9]).to_be_bytes();
        data[9..].copy_from_slice(&crc);
        let register = data.iter().fold(INIT, |c, &b| update(c, b));
        assert_eq!(register, RESIDUE);
    }

    #[test]
    fn zero_bytes_after_the_crc_change_the_check() {
        // The weakness of a CRC without final XOR: payload ‖ CRC ‖ 00 00 split as
        // (payload ‖ CRC) + trailer 00 00 passed. Here it does not.
        let payload = [0x02u8, 0x01, 0x05, 0x01];
        let mut longer = [0u8; 10];
        longer[..4].copy_from_slice(&payload);
        longer[4..6].copy_from_slice(&checksum(&payload).to_be_bytes());
        for extra in 1..=4 {
            let (body, trailer) = longer[..6 + extra].split_at(4 + extra);
            assert_ne!(
                checksum(body).to_be_bytes(),
                [trailer[0], trailer[1]],
                "{extra} zeros"
            );
        }
    }
}
