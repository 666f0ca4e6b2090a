//! Framing: `0x00 ‖ COBS(postcard(message) ‖ CRC-16 big-endian) ‖ 0x00`.
//!
//! - [`encode_frame`] serializes a message into the output buffer, appends the CRC
//!   ([`crate::crc`]) and COBS-encodes the bytes in place, between two `0x00` delimiters.
//! - [`Accumulator`] takes received bytes in any chunking, decodes COBS on the fly into a
//!   bounded buffer of `N` bytes, feeding the CRC as the bytes come, and at each delimiter
//!   checks the CRC and deserializes. The caller loops on [`Feed::remaining`] until
//!   [`Feed::NeedMore`] so that back-to-back frames in one read are all seen.
//!
//! Empty frames (two delimiters in a row) are ignored. Every frame **starts** with a delimiter
//! too: it ends whatever a receiver holds from line noise or a truncated frame, so the next good
//! frame is never merged with garbage. Back-to-back frames thus show `00 00` between them.

use crate::crc;
use core::fmt;
use postcard::ser_flavors::{Flavor, Slice};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Frame delimiter.
pub const DELIMITER: u8 = 0x00;

/// Length of the CRC trailer, bytes.
pub const CRC_LEN: usize = 2;

/// Largest decoded frame (postcard bytes + CRC) a receiver must accept, bytes. Every message of
/// this version fits (the largest, an [`crate::DeviceToHost::Ack`], takes at most
/// [`crate::DEVICE_TO_HOST_MAX_LEN`]); the rest is headroom for later minor versions.
pub const MAX_DECODED_LEN: usize = 128;

/// Largest frame on the wire, COBS overhead and both delimiters included, bytes.
pub const MAX_FRAME_LEN: usize = encoded_len_max(MAX_DECODED_LEN);

/// Upper bound of the wire size (COBS + two delimiters) of `decoded_len` decoded bytes:
/// `n + ⌈n/254⌉ + 2` (one COBS code byte per started block of 254 bytes, at least one). Exact
/// for `n < 254`.
pub const fn encoded_len_max(decoded_len: usize) -> usize {
    let blocks = if decoded_len == 0 {
        1
    } else {
        decoded_len.div_ceil(254)
    };
    decoded_len + blocks + 2
}

/// Why a frame could not be built or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The output buffer is too small for the encoded frame.
    BufferFull,
    /// The serializer failed for another reason (never for this crate's messages).
    Serialize,
    /// The COBS encoding is broken: a block runs past the delimiter.
    Cobs,
    /// The decoded frame is shorter than one byte plus the CRC.
    TooShort,
    /// The CRC does not match.
    BadCrc,
    /// The decoded frame exceeds the receiver's buffer.
    Oversize,
    /// The message ends before all its fields.
    Truncated,
    /// An enum discriminant this version does not know (e.g. a message of a newer minor).
    UnknownVariant,
    /// A malformed value: a varint that does not terminate, a bool or option tag not 0/1.
    BadEncoding,
    /// Bytes are left after the message (before the CRC).
    TrailingBytes,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Error::BufferFull => "output buffer too small",
            Error::Serialize => "serializer error",
            Error::Cobs => "broken COBS encoding",
            Error::TooShort => "frame too short",
            Error::BadCrc => "CRC mismatch",
            Error::Oversize => "frame exceeds the receive buffer",
            Error::Truncated => "message truncated",
            Error::UnknownVariant => "unknown enum variant",
            Error::BadEncoding => "malformed value",
            Error::TrailingBytes => "bytes left after the message",
        })
    }
}

impl core::error::Error for Error {}

impl From<postcard::Error> for Error {
    fn from(e: postcard::Error) -> Self {
        match e {
            postcard::Error::SerializeBufferFull => Error::BufferFull,
            postcard::Error::DeserializeUnexpectedEnd => Error::Truncated,
            // serde's derived enum visitor reports an unknown variant index as a custom error.
            postcard::Error::SerdeDeCustom | postcard::Error::DeserializeBadEnum => {
                Error::UnknownVariant
            }
            postcard::Error::DeserializeBadVarint
            | postcard::Error::DeserializeBadBool
            | postcard::Error::DeserializeBadOption
            | postcard::Error::DeserializeBadChar
            | postcard::Error::DeserializeBadUtf8
            | postcard::Error::DeserializeBadEncoding
            | postcard::Error::DeserializeBadCrc => Error::BadEncoding,
            _ => Error::Serialize,
        }
    }
}

/// A postcard flavor that writes the message's bytes into a slice; [`encode_frame`] then adds
/// the CRC and the COBS encoding in one pass over them. postcard's own [`Slice`] flavor does
/// the stores; this one only decides what is inlined where.
struct PlainSlice<'b>(Slice<'b>);

impl Flavor for PlainSlice<'_> {
    type Output = usize;

    // Out of line: serde writes a message field by field, and each field's bytes come here; one
    // copy of the store serves them all instead of one inlined per field (on the AVR the
    // inlined copies were most of the answer encoder's code).
    #[inline(never)]
    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.0.try_push(data)
    }

    // postcard writes every multi-byte value (an `f32`'s four bytes, a varint) through this:
    // one bounds check and one copy per value ([`PlainSlice::extend`]) instead of the
    // default's `try_push` per byte. Inline, so that a value known to take one byte (the
    // index of most enum variants) still goes straight to `try_push`.
    #[inline(always)]
    fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        match *data {
            [byte] => self.try_push(byte),
            [a, b] => self.extend_array([a, b]),
            [a, b, c, d] => self.extend_array([a, b, c, d]),
            _ => self.extend(data),
        }
    }

    fn finalize(self) -> postcard::Result<usize> {
        self.0.finalize().map(|written| written.len())
    }
}

impl PlainSlice<'_> {
    /// Appends `data` (out of line: one copy serves every multi-byte value).
    #[inline(never)]
    fn extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        self.0.try_extend(data)
    }

    /// [`PlainSlice::extend`] for the common lengths (an `f32`, a two-byte varint): the bytes
    /// arrive in registers and are stored without a copy loop.
    #[inline(never)]
    fn extend_array<const N: usize>(&mut self, data: [u8; N]) -> postcard::Result<()> {
        self.0.try_extend(&data)
    }
}

/// The longest COBS block: a frame of fewer decoded bytes needs no code byte but the first.
const COBS_BLOCK: usize = 254;

/// Serializes `msg`, appends its CRC, COBS-encodes everything and puts it between two `0x00`
/// delimiters, in `out`. Returns the frame (a prefix of `out`).
///
/// [`encode_frame_in_pieces`] with nobody to hand the pieces to: the same bytes.
///
/// # Errors
/// [`Error::BufferFull`] when `out` is too small ([`MAX_FRAME_LEN`] is always enough for this
/// crate's messages); [`Error::Oversize`] when the decoded frame would exceed
/// [`MAX_DECODED_LEN`] (no receiver of this protocol takes it).
pub fn encode_frame<'b, T: Serialize + ?Sized>(
    msg: &T,
    out: &'b mut [u8],
) -> Result<&'b [u8], Error> {
    let len = encode_frame_in_pieces(msg, out, |_| {})?;
    Ok(&out[..len])
}

/// [`encode_frame`], handing the frame to `emit` as soon as its first bytes are final: when
/// the message holds a `0x00`, in two consecutive pieces — the leading delimiter, the first
/// COBS code byte and the message's bytes before its first zero, then the rest — else in one.
/// Returns the frame's length; the whole frame is also in `out`. Nothing is emitted when
/// encoding fails.
///
/// Why: a COBS code byte is the distance to the next `0x00`, so the first byte after the
/// delimiter is known as soon as the message's first zero is found, before the CRC. A
/// transmitter can start with the first piece while the CRC and the rest of the COBS are
/// computed: on the ATmega2560 the first answer byte leaves after a scan for the first zero
/// instead of after the CRC of the whole message.
///
/// The message's bytes go into `out` as they are; a scan finds the first zero; then one pass
/// over them computes the CRC and replaces each `0x00` with the distance to the next (COBS for
/// a frame of fewer than 254 decoded bytes, which every frame of this protocol is:
/// [`MAX_DECODED_LEN`]). One tight loop over the bytes instead of the CRC and COBS steps per
/// serialized byte: fewer cycles per answer on the ATmega2560.
///
/// # Errors
/// As [`encode_frame`].
pub fn encode_frame_in_pieces<T: Serialize + ?Sized>(
    msg: &T,
    out: &mut [u8],
    mut emit: impl FnMut(&[u8]),
) -> Result<usize, Error> {
    const { assert!(MAX_DECODED_LEN < COBS_BLOCK) };
    // 0x00, the first code byte, the message, the CRC, 0x00.
    let body = out.get_mut(2..).ok_or(Error::BufferFull)?;
    let n = postcard::serialize_with_flavor(msg, PlainSlice(Slice::new(body)))?;
    let end = 2 + n + CRC_LEN;
    if n + CRC_LEN > MAX_DECODED_LEN {
        return Err(Error::Oversize);
    }
    if end >= out.len() {
        return Err(Error::BufferFull);
    }
    out[0] = DELIMITER;
    // The message's first zero: the first block ends there, and the first code byte is its
    // distance (below 254: the assertion above).
    let first = out[2..2 + n].iter().position(|&b| b == 0);
    if let Some(zero_at) = first {
        out[1] = zero_at as u8 + 1;
        emit(&out[..2 + zero_at]);
    }
    // One pass from the start computes the CRC and does the COBS of the message's bytes: each
    // zero becomes the distance to the next zero (or the delimiter), written into the code
    // byte that waits for it (`code`) when that zero is met (the first code byte again, with
    // the same value, when it was emitted already). The distance is counted along, an 8-bit
    // count per byte on the AVR.
    let (head, tail) = out.split_at_mut(2 + n);
    let [_, first_code, message @ ..] = head else {
        unreachable!("out holds 2 + n bytes and more")
    };
    let [crc_hi, crc_lo, stop, ..] = tail else {
        unreachable!("end < out.len()")
    };
    let [mut hi, mut lo] = crc::INIT.to_be_bytes();
    let mut code = first_code;
    let mut distance: u8 = 1;
    for byte in message.iter_mut() {
        (hi, lo) = crc::step(hi, lo, *byte);
        if *byte == 0 {
            *code = distance;
            code = byte;
            distance = 0;
        }
        distance += 1;
    }
    [*crc_hi, *crc_lo] = crc::finish(u16::from_be_bytes([hi, lo])).to_be_bytes();
    for byte in [crc_hi, crc_lo] {
        if *byte == 0 {
            *code = distance;
            code = byte;
            distance = 0;
        }
        distance += 1;
    }
    *code = distance;
    *stop = DELIMITER;
    emit(&out[first.map_or(0, |zero_at| 2 + zero_at)..=end]);
    Ok(end + 1)
}

/// Checks the CRC of a decoded frame (postcard bytes ‖ CRC) and deserializes its message.
///
/// # Errors
/// [`Error::TooShort`], [`Error::BadCrc`], or a decode error ([`Error::Truncated`],
/// [`Error::UnknownVariant`], [`Error::BadEncoding`], [`Error::TrailingBytes`]).
pub fn decode_payload<T: DeserializeOwned>(decoded: &[u8]) -> Result<T, Error> {
    let body = check_crc(decoded)?;
    let (msg, rest) = postcard::take_from_bytes::<T>(body)?;
    if !rest.is_empty() {
        return Err(Error::TrailingBytes);
    }
    Ok(msg)
}

/// The postcard bytes of a decoded frame (postcard bytes ‖ CRC) whose CRC matches.
///
/// # Errors
/// [`Error::TooShort`], [`Error::BadCrc`].
fn check_crc(decoded: &[u8]) -> Result<&[u8], Error> {
    if decoded.len() < CRC_LEN + 1 {
        return Err(Error::TooShort);
    }
    let (body, trailer) = decoded.split_at(decoded.len() - CRC_LEN);
    if crc::checksum(body).to_be_bytes() != [trailer[0], trailer[1]] {
        return Err(Error::BadCrc);
    }
    Ok(body)
}

/// postcard's deserializer over a frame's bytes.
type Decoder<'b> = postcard::Deserializer<'b, postcard::de_flavors::Slice<'b>>;

/// What [`Accumulator::feed`] found. Every variant but `NeedMore` carries the bytes after the
/// delimiter that ended the frame: feed them again.
#[derive(Debug, Clone, PartialEq)]
pub enum Feed<'a, T> {
    /// All input consumed; no frame ended in it.
    NeedMore,
    /// A frame with a good CRC and a valid message.
    Frame {
        /// The message.
        msg: T,
        /// Input not yet consumed.
        remaining: &'a [u8],
    },
    /// A frame whose CRC did not match.
    BadCrc {
        /// Input not yet consumed.
        remaining: &'a [u8],
    },
    /// A frame with a good structure but broken COBS, too short, or not a valid message.
    BadFrame {
        /// The decode error.
        error: Error,
        /// Input not yet consumed.
        remaining: &'a [u8],
    },
    /// A frame longer than the buffer; its bytes were dropped up to its delimiter.
    Oversize {
        /// Input not yet consumed.
        remaining: &'a [u8],
    },
}

impl<'a, T> Feed<'a, T> {
    /// The unconsumed input (empty for [`Feed::NeedMore`]).
    pub fn remaining(&self) -> &'a [u8] {
        match self {
            Feed::NeedMore => &[],
            Feed::Frame { remaining, .. }
            | Feed::BadCrc { remaining }
            | Feed::BadFrame { remaining, .. }
            | Feed::Oversize { remaining } => remaining,
        }
    }
}

/// [`crc::INIT`] as the accumulator keeps it.
const CRC_INIT: (u8, u8) = (crc::INIT.to_be_bytes()[0], crc::INIT.to_be_bytes()[1]);

/// Receives a byte stream and yields one [`Feed`] per delimiter-terminated frame, with `N`
/// bytes of buffer for the decoded frame (postcard bytes + CRC). Memory: `N` bytes plus 15 bytes
/// of state on the AVR (16-bit `usize`).
///
/// ```
/// use quad_protocol::{encode_frame, Accumulator, Feed, HostToDevice, Request, MAX_FRAME_LEN};
///
/// let mut wire = [0u8; 2 * MAX_FRAME_LEN];
/// let mut n = 0;
/// for seq in [7, 8] {
///     let msg = HostToDevice { seq, request: Request::GetState };
///     n += encode_frame(&msg, &mut wire[n..]).unwrap().len();
/// }
///
/// let mut acc = Accumulator::<128>::new();
/// let mut seen = 0;
/// let mut input = &wire[..n]; // one read returned both frames back-to-back
/// loop {
///     match acc.feed::<HostToDevice>(input) {
///         Feed::NeedMore => break,
///         Feed::Frame { msg, remaining } => {
///             assert_eq!(msg.seq, 7 + seen);
///             seen += 1;
///             input = remaining;
///         }
///         other => input = other.remaining(), // count or nack, then go on
///     }
/// }
/// assert_eq!(seen, 2);
/// ```
#[derive(Debug, Clone)]
pub struct Accumulator<const N: usize> {
    buf: [u8; N],
    len: usize,
    /// Data bytes left in the current COBS block; 0 = the next byte is a code byte.
    block_left: u8,
    /// Code byte of the current block; 0 = no byte of this frame seen yet.
    code: u8,
    overflow: bool,
    /// The CRC register over the decoded bytes so far (high, low byte), fed as they come:
    /// at the delimiter it is [`crc::RESIDUE`] when the frame's CRC matches.
    crc: (u8, u8),
    frames_ok: u32,
    frames_bad: u32,
    /// The CRC of the last good frame ([`Accumulator::frame_crc`]).
    frame_crc: Option<u16>,
}

impl<const N: usize> Default for Accumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Accumulator<N> {
    /// An empty accumulator.
    pub const fn new() -> Self {
        Accumulator {
            buf: [0; N],
            len: 0,
            block_left: 0,
            code: 0,
            overflow: false,
            crc: CRC_INIT,
            frames_ok: 0,
            frames_bad: 0,
            frame_crc: None,
        }
    }

    /// Drops a partial frame (the counters stay).
    pub fn reset(&mut self) {
        self.len = 0;
        self.block_left = 0;
        self.code = 0;
        self.overflow = false;
        self.crc = CRC_INIT;
    }

    /// The CRC (as its trailer carries it) of the last frame [`Accumulator::feed`] reported as
    /// [`Feed::Frame`]: what, with the sequence number, tells an exact repeat of a request
    /// from a new one. `None` before the first.
    pub const fn frame_crc(&self) -> Option<u16> {
        self.frame_crc
    }

    /// Frames that ended in [`Feed::Frame`] (wrapping).
    pub const fn frames_ok(&self) -> u32 {
        self.frames_ok
    }

    /// Frames that ended in [`Feed::BadCrc`], [`Feed::BadFrame`] or [`Feed::Oversize`]
    /// (wrapping).
    pub const fn frames_bad(&self) -> u32 {
        self.frames_bad
    }

    /// True while a frame is partly received.
    pub const fn in_frame(&self) -> bool {
        self.code != 0
    }

    /// The buffer as scratch space between frames (`None` while a frame is partly received):
    /// a device with little RAM encodes its answer here, since a frame's bytes are no longer
    /// needed once [`Accumulator::feed`] has reported it.
    pub fn scratch(&mut self) -> Option<&mut [u8; N]> {
        if self.in_frame() {
            None
        } else {
            Some(&mut self.buf)
        }
    }

    /// Consumes `input` up to and including the first delimiter that ends a non-empty frame,
    /// and reports that frame; or consumes everything and returns [`Feed::NeedMore`].
    pub fn feed<'a, T: DeserializeOwned>(&mut self, input: &'a [u8]) -> Feed<'a, T> {
        self.feed_by(input, |de| T::deserialize(de))
    }

    /// [`Accumulator::feed`], decoding the message into `place` instead of returning it: a
    /// [`Feed::Frame`] means that `place` holds the frame's message (after any other result,
    /// `place` holds an unspecified valid value). The same bytes are read as by
    /// [`Accumulator::feed`] (serde's `deserialize_in_place`, which this crate's messages
    /// implement for that).
    ///
    /// Why: a message returned by value is moved at least twice on its way to its receiver
    /// (out of the deserializer's `Result`, into the message that holds it, into the
    /// [`Feed`]), each move a copy of the largest message on the ATmega2560; decoded where
    /// the receiver keeps it, only the fields read are stored.
    pub fn feed_in_place<'a, T: DeserializeOwned>(
        &mut self,
        input: &'a [u8],
        place: &mut T,
    ) -> Feed<'a, ()> {
        self.feed_by(input, |de| T::deserialize_in_place(de, place))
    }

    /// [`Accumulator::feed`] with `decode` reading the message from the frame's bytes.
    fn feed_by<'a, M>(
        &mut self,
        input: &'a [u8],
        decode: impl FnOnce(&mut Decoder<'_>) -> postcard::Result<M>,
    ) -> Feed<'a, M> {
        let Some(end) = self.scan(input) else {
            return Feed::NeedMore;
        };
        let feed = self.finish(&input[end + 1..], decode);
        if let Feed::Frame { .. } = feed {
            self.frame_crc = self.buf[..self.len]
                .last_chunk::<CRC_LEN>()
                .map(|&t| u16::from_be_bytes(t));
        }
        self.reset();
        if let Feed::Frame { .. } = feed {
            self.frames_ok = self.frames_ok.wrapping_add(1);
        } else {
            self.frames_bad = self.frames_bad.wrapping_add(1);
        }
        feed
    }

    /// Decodes the COBS of `input` into the buffer up to the first delimiter that ends a
    /// non-empty frame and returns that delimiter's index (the frame is then complete in the
    /// buffer), or decodes all of `input` and returns `None`.
    ///
    /// The state lives in locals through the loop and is stored back once: kept in the
    /// fields, it was loaded and stored at every byte on the AVR (every received byte passes
    /// here). The CRC is fed here too, byte by byte as the frame arrives, rather than over
    /// the whole frame once its delimiter is there: the work leaves the time between a
    /// request's last byte and its answer.
    fn scan(&mut self, input: &[u8]) -> Option<usize> {
        let mut len = self.len;
        let mut block_left = self.block_left;
        let mut code = self.code;
        let mut overflow = self.overflow;
        let (mut hi, mut lo) = self.crc;
        let mut end = None;
        for (i, &byte) in input.iter().enumerate() {
            if byte == DELIMITER {
                if code == 0 {
                    continue; // empty frame
                }
                end = Some(i);
                break;
            }
            if overflow {
                continue;
            }
            let decoded = if block_left == 0 {
                // A code byte. The block before it, unless it was a full 0xFF block, ended in
                // an implicit zero.
                let implicit_zero = code != 0 && code != 0xFF;
                code = byte;
                block_left = byte - 1;
                if !implicit_zero {
                    continue;
                }
                0
            } else {
                block_left -= 1;
                byte
            };
            // One place that stores a decoded byte (and one copy of the CRC step).
            match self.buf.get_mut(len) {
                Some(slot) => {
                    *slot = decoded;
                    len += 1;
                    (hi, lo) = crc::step(hi, lo, decoded);
                }
                None => overflow = true,
            }
        }
        self.len = len;
        self.block_left = block_left;
        self.code = code;
        self.overflow = overflow;
        self.crc = (hi, lo);
        end
    }

    /// What the frame in the buffer is, `remaining` the input after its delimiter, `decode`
    /// reading its message (by value, or into the caller's place). Builds the [`Feed`] where
    /// the message is decoded: it is not moved through another `Result` first, each move a
    /// copy on the AVR.
    fn finish<'a, M>(
        &self,
        remaining: &'a [u8],
        decode: impl FnOnce(&mut Decoder<'_>) -> postcard::Result<M>,
    ) -> Feed<'a, M> {
        if self.overflow {
            return Feed::Oversize { remaining };
        }
        let error = if self.block_left != 0 {
            Error::Cobs
        } else {
            // The register over the message and its CRC is the residue exactly when the CRC
            // matches (two bytes fed into a CRC register map one to one onto its values), as
            // `check_crc` finds it.
            let (hi, lo) = self.crc;
            let checked = match self.buf[..self.len].split_last_chunk::<CRC_LEN>() {
                Some((body @ [_, ..], _)) if u16::from_be_bytes([hi, lo]) == crc::RESIDUE => {
                    Ok(body)
                }
                Some(([_, ..], _)) => Err(Error::BadCrc),
                _ => Err(Error::TooShort),
            };
            match checked {
                Err(Error::BadCrc) => return Feed::BadCrc { remaining },
                Err(error) => error,
                Ok(body) => {
                    // postcard's `take_from_bytes` without its `(message, rest)` tuple, one
                    // more move of the message.
                    let mut de = postcard::Deserializer::from_bytes(body);
                    match decode(&mut de) {
                        Ok(msg) => match de.finalize() {
                            Ok([]) => return Feed::Frame { msg, remaining },
                            Ok(_) => Error::TrailingBytes,
                            Err(error) => error.into(),
                        },
                        Err(error) => error.into(),
                    }
                }
            }
        };
        Feed::BadFrame { error, remaining }
    }
}
