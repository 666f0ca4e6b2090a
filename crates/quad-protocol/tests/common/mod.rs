//! Independent reference implementations for the tests: a table-driven CRC-16/GENIBUS and a
//! batch COBS encoder/decoder written from the COBS paper (Cheshire & Baker 1999), sharing no
//! code with the crate.

#![allow(dead_code)]

pub mod cases;

/// Parses `"01 0a ff"` into bytes.
pub fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
        .collect()
}

/// Formats bytes as `"01 0a ff"`.
pub fn to_hex(b: &[u8]) -> String {
    b.iter()
        .map(|x| format!("{x:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// CRC-16/GENIBUS (poly 0x1021, init 0xFFFF, no reflection, xorout 0xFFFF) with a 256-entry
/// table.
pub fn ref_crc(data: &[u8]) -> u16 {
    let table: Vec<u16> = (0..256u16)
        .map(|i| {
            let mut c = i << 8;
            for _ in 0..8 {
                c = if c & 0x8000 != 0 {
                    (c << 1) ^ 0x1021
                } else {
                    c << 1
                };
            }
            c
        })
        .collect();
    let register = data.iter().fold(0xFFFF, |crc, &b| {
        (crc << 8) ^ table[usize::from((crc >> 8) as u8 ^ b)]
    });
    register ^ 0xFFFF
}

/// COBS encoding of `data` (without delimiter): split at zeros into runs of ≤ 254 bytes.
pub fn ref_cobs_encode(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut run: Vec<u8> = Vec::new();
    for &b in data {
        if b == 0 {
            out.push(run.len() as u8 + 1);
            out.append(&mut run);
        } else {
            run.push(b);
            if run.len() == 254 {
                out.push(0xFF);
                out.append(&mut run);
            }
        }
    }
    out.push(run.len() as u8 + 1);
    out.append(&mut run);
    out
}

/// COBS decoding of one frame body (no delimiter); `None` when malformed.
pub fn ref_cobs_decode(enc: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < enc.len() {
        let code = enc[i] as usize;
        if code == 0 || i + code > enc.len() {
            return None;
        }
        out.extend_from_slice(&enc[i + 1..i + code]);
        i += code;
        if code < 0xFF && i < enc.len() {
            out.push(0);
        }
    }
    Some(out)
}

/// The expected wire frame of postcard bytes `payload`:
/// 00 ‖ COBS(payload ‖ CRC big-endian) ‖ 00.
pub fn ref_frame(payload: &[u8]) -> Vec<u8> {
    let mut data = payload.to_vec();
    data.extend_from_slice(&ref_crc(payload).to_be_bytes());
    let mut out = vec![0];
    out.extend(ref_cobs_encode(&data));
    out.push(0);
    out
}
