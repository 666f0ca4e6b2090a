//! CRC-16/IBM-3740 (better known as CRC-16/CCITT-FALSE), bitwise and table-free.
//!
//! Parameters (Rocksoft/reveng model): width 16, poly `0x1021`, init `0xFFFF`, refin false,
//! refout false, xorout `0x0000`, check (`"123456789"`) `0x29B1`. No lookup table: eight
//! shift/xor steps per byte cost no SRAM on the ATmega2560 (whose default linker script copies
//! read-only tables into RAM) and about 100 cycles per byte.
//!
//! On the wire the CRC follows the postcard bytes **most significant byte first**, so that the
//! CRC computed over payload and CRC together is `0x0000` (the residue of this model).

/// Initial register value.
pub const INIT: u16 = 0xFFFF;

/// Generator polynomial (x¹⁶ + x¹² + x⁵ + 1, normal form).
pub const POLY: u16 = 0x1021;

/// Feeds one byte into the CRC register `crc`.
#[inline]
pub const fn update(crc: u16, byte: u8) -> u16 {
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

/// CRC of a whole buffer.
pub const fn checksum(data: &[u8]) -> u16 {
    let mut crc = INIT;
    let mut i = 0;
    while i < data.len() {
        crc = update(crc, data[i]);
        i += 1;
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_check_value() {
        assert_eq!(checksum(b"123456789"), 0x29B1);
    }

    #[test]
    fn empty_input_is_init() {
        assert_eq!(checksum(&[]), INIT);
    }

    #[test]
    fn residue_of_payload_and_big_endian_crc_is_zero() {
        let mut data = *b"123456789\0\0";
        let crc = checksum(&data[..9]).to_be_bytes();
        data[9..].copy_from_slice(&crc);
        assert_eq!(checksum(&data), 0);
    }
}
