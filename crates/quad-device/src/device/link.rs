//! The link: bytes in, requests decoded in place, exact repeats answered again, answers
//! encoded out.

use super::*;

impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// Feeds received bytes (any chunking) and sends one answer frame through `tx` for every
    /// frame that ends in them, in order (nacks of unreadable frames rate-limited, see
    /// [`FRAMING_NACK_INTERVAL_MS`]). Each answer frame reaches `tx` in consecutive pieces
    /// ([`encode_frame_in_pieces`]): its first bytes as soon as they are final, so that a
    /// transmitter starts while the rest is encoded; one frame's pieces all come before the
    /// next frame's.
    ///
    /// Every request is safe to retry: an exact repeat of the last request answered here (the
    /// same `seq` and the same frame CRC, so the same bytes) is answered with the same answer
    /// again and does not act again — a `StartMotion` resent because its `MotionAck` was lost
    /// gets that `MotionAck`, not `MotionRunning`. A repeated `seq` with other bytes is a new
    /// request. ([`Device::handle`], which sees no frame, always acts.)
    pub fn receive(&mut self, mut bytes: &[u8], mut tx: impl FnMut(&[u8])) {
        while let Some(remaining) = self.receive_one(bytes, &mut tx) {
            bytes = remaining;
        }
    }

    /// The answer to replay when the request `seq` of a frame whose CRC is `crc` is an exact
    /// repeat of the last request answered (a retry whose answer was lost), `None` for a new
    /// request. A repeat feeds the link timer as any frame does.
    pub(super) fn repeated(&mut self, seq: u16, crc: Option<u16>) -> Option<DeviceToHost> {
        let last = self.last_answered.as_ref()?;
        if last.seq != seq || Some(last.crc) != crc {
            return None;
        }
        self.last_valid_ms = self.clock.now_ms();
        self.failsafe_armed = true;
        Some(last.answer)
    }

    /// Remembers `answer` to the request `seq` of a frame whose CRC is `crc`, for
    /// [`Device::repeated`]; unless it is a `Busy` nack, which asks for the same request again
    /// once the device is free.
    pub(super) fn remember(&mut self, seq: u16, crc: Option<u16>, answer: &DeviceToHost) {
        let busy = matches!(
            answer,
            DeviceToHost::Nack {
                reason: NackReason::Busy,
                ..
            }
        );
        self.last_answered = crc.filter(|_| !busy).map(|crc| Answered {
            seq,
            crc,
            answer: *answer,
        });
    }

    /// Consumes `bytes` up to the end of the first frame in them, handles it and sends its
    /// answer through `tx` (encoded in the accumulator's buffer, free between frames): the
    /// bytes left, `None` when no frame ended in `bytes`. Not generic over the caller's
    /// closure, so that the firmware has one instance of it.
    pub(super) fn receive_one<'a>(
        &mut self,
        bytes: &'a [u8],
        tx: &mut dyn FnMut(&[u8]),
    ) -> Option<&'a [u8]> {
        // The request is decoded into this local and read there (never moved).
        let mut request = HostToDevice {
            seq: 0,
            request: Request::GetState,
        };
        let msg = &mut request;
        let (reason, remaining) = match feed_request(&mut self.acc, bytes, msg) {
            Feed::NeedMore => return None,
            Feed::Frame { remaining, .. } => {
                let (seq, crc) = (msg.seq, self.acc.frame_crc());
                if let Some(answer) = self.repeated(seq, crc) {
                    self.encode(&answer, tx);
                    return Some(remaining);
                }
                let answer = self.handle_ref(msg);
                self.encode(&answer, tx);
                // Remembered once the answer's first bytes are on their way.
                self.remember(seq, crc, &answer);
                return Some(remaining);
            }
            Feed::BadCrc { remaining } => (NackReason::BadCrc, remaining),
            Feed::BadFrame { remaining, .. } => (NackReason::BadFrame, remaining),
            Feed::Oversize { remaining } => (NackReason::Oversize, remaining),
        };
        let now = self.clock.now_ms();
        let due = self
            .last_framing_nack_ms
            .is_none_or(|t| now.wrapping_sub(t) >= FRAMING_NACK_INTERVAL_MS);
        if due {
            self.last_framing_nack_ms = Some(now);
            self.encode(&nack(None, reason), tx);
        }
        Some(remaining)
    }

    /// Encodes `answer` into the accumulator's buffer (free between frames) and sends it
    /// through `tx`, in pieces; nothing is sent when it cannot be encoded.
    pub(super) fn encode(&mut self, answer: &DeviceToHost, tx: &mut dyn FnMut(&[u8])) {
        // The buffer holds the largest answer (`TX_LEN`); a failure would only drop this answer.
        if let Some(buf) = self.acc.scratch() {
            encode_answer(answer, buf, tx);
        }
    }
}

/// The device's receive path: the protocol's frame decoder (postcard) on the accumulator,
/// decoding a request into `request` ([`Accumulator::feed_in_place`]: a [`Feed::Frame`] means
/// `request` holds the frame's request).
pub fn feed_request<'a>(
    acc: &mut Accumulator<RX_LEN>,
    bytes: &'a [u8],
    request: &mut HostToDevice,
) -> Feed<'a, ()> {
    acc.feed_in_place(bytes, request)
}

/// The device's answer encoder: [`encode_frame_in_pieces`] (postcard) of `answer` into `out`,
/// handed to `tx` in pieces as they are final; the frame's length, 0 (and nothing sent) when
/// it does not fit.
pub fn encode_answer(answer: &DeviceToHost, out: &mut [u8], tx: &mut dyn FnMut(&[u8])) -> usize {
    encode_frame_in_pieces(answer, out, tx).unwrap_or(0)
}

/// A request answered over the link: its sequence number, its frame's CRC, the answer.
#[derive(Debug, Clone, Copy)]
pub(super) struct Answered {
    pub(super) seq: u16,
    pub(super) crc: u16,
    pub(super) answer: DeviceToHost,
}
