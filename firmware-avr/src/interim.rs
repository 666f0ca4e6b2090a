//! INTERIM command set, to be replaced by the device controller and the wire protocol. It only
//! exists so that the hardware layer can be tested end to end in simavr.
//!
//! Binary requests (little-endian) and answers:
//!
//! | request | bytes | answer |
//! |---|---|---|
//! | enable outputs | `E` | `e` |
//! | disable outputs | `D` | `d` |
//! | write pulses | `W`, 12 × u16 ticks (0.5 µs) | `w`, status u8 (0 = set, 1 = refused) |
//! | body-pose IK (outputs untouched) | `P`, roll pitch yaw x y z f32 | `p`, status u8 (0 = solved), 12 × f32 rad |
//! | status | `S` | `s`, static SRAM u16, max stack u16, MCUSR u8, rx dropped u16, ms u32 |
//!
//! A request whose bytes stop arriving for [`PARTIAL_TIMEOUT_MS`] is discarded.

use avr_libc_math::AvrFast;
use firmware_avr::bench;
use firmware_avr::clock::Clock;
use firmware_avr::servo::{Servos, CHANNELS};
use firmware_avr::usart::Usart0;
use firmware_avr::watchdog::ResetCause;
use kin_core::Pose;

/// Time after which an incomplete request is dropped, ms.
pub const PARTIAL_TIMEOUT_MS: u32 = 100;

const MAX_REQUEST: usize = 1 + 2 * CHANNELS;

/// The interim command interpreter.
pub struct Interim {
    buf: [u8; MAX_REQUEST],
    len: usize,
    last_byte_ms: u32,
    reset_cause: ResetCause,
}

fn request_len(opcode: u8) -> Option<usize> {
    match opcode {
        b'E' | b'D' | b'S' => Some(1),
        b'W' => Some(1 + 2 * CHANNELS),
        b'P' => Some(1 + 6 * 4),
        _ => None,
    }
}

impl Interim {
    /// A fresh interpreter.
    pub fn new(reset_cause: ResetCause) -> Interim {
        Interim {
            buf: [0; MAX_REQUEST],
            len: 0,
            last_byte_ms: 0,
            reset_cause,
        }
    }

    /// Consumes the received bytes and executes complete requests.
    pub fn poll(&mut self, usart: &mut Usart0, servos: &mut Servos, clock: &Clock) {
        let now_ms = clock.now_ms();
        if self.len > 0 && now_ms.wrapping_sub(self.last_byte_ms) > PARTIAL_TIMEOUT_MS {
            self.len = 0;
        }
        while let Some(byte) = usart.read() {
            self.last_byte_ms = now_ms;
            if self.len == 0 && request_len(byte).is_none() {
                continue;
            }
            self.buf[self.len] = byte;
            self.len += 1;
            if Some(self.len) == request_len(self.buf[0]) {
                self.len = 0;
                self.execute(usart, servos, clock);
            }
        }
    }

    fn execute(&mut self, usart: &mut Usart0, servos: &mut Servos, clock: &Clock) {
        let b = &self.buf;
        match b[0] {
            b'E' => {
                servos.enable();
                usart.write(b'e');
            }
            b'D' => {
                servos.disable();
                usart.write(b'd');
            }
            b'W' => {
                let ticks: [u16; CHANNELS] =
                    core::array::from_fn(|i| u16::from_le_bytes([b[1 + 2 * i], b[2 + 2 * i]]));
                let ok = servos.set_all_pulse_ticks(&ticks).is_ok();
                usart.write_all(&[b'w', if ok { 0 } else { 1 }]);
            }
            b'P' => {
                let pose = Pose::from_array(core::array::from_fn(|i| {
                    f32::from_le_bytes([b[1 + 4 * i], b[2 + 4 * i], b[3 + 4 * i], b[4 + 4 * i]])
                }));
                let r = bench::body_with::<AvrFast>(&bench::ROBOT, &pose);
                usart.write(b'p');
                usart.write(if r.is_ok() { 0 } else { 1 });
                for a in r.unwrap_or([0.0; 12]) {
                    usart.write_all(&a.to_le_bytes());
                }
            }
            b'S' => {
                usart.write(b's');
                usart.write_all(&firmware_avr::stack::static_bytes().to_le_bytes());
                usart.write_all(&firmware_avr::stack::max_used_bytes().to_le_bytes());
                usart.write(self.reset_cause.mcusr);
                usart.write_all(&usart.rx_dropped().to_le_bytes());
                usart.write_all(&clock.now_ms().to_le_bytes());
            }
            _ => {}
        }
    }
}
