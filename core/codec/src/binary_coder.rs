//! A binary range coder with integer state (paper 003 §5.3's "codeur arithmétique", here in its
//! binary form: every symbol is coded as a few yes/no decisions, each with its own adaptive
//! probability, see `adaptive`).
//!
//! The interval is 32 bits wide and renormalised a byte at a time; a carry out of the low end is
//! propagated into the bytes already waiting (the cached byte and a run of `0xFF`). Probabilities
//! are 16-bit integers, so the arithmetic is the same on every machine and thread count.
//!
//! Two details keep each cell's chunk short and its prefixes exact:
//! - the decoder reads zeros past the end of its chunk, so the encoder ends on the value of its
//!   final interval with the most trailing zero bits and drops those zero bytes (never more than
//!   the four it flushed, so a valid chunk is never read more than four bytes past its end);
//! - the decoder counts the bytes it has taken ([`Decoder::consumed`]): a decode that stops after
//!   some decisions needed exactly those bytes of the chunk and no others.

use std::borrow::Cow;

/// Bits of a probability: `p0` is the probability of a 0 in units of `2^-16`, in `1..2^16`.
pub const PROB_BITS: u32 = 16;

/// Renormalise when the range drops below this.
const TOP: u32 = 1 << 24;

/// The encoder: decisions in, bytes out.
#[derive(Debug)]
pub struct Encoder {
    /// Low end of the interval (33 bits: bit 32 is a carry not yet propagated).
    low: u64,
    range: u32,
    /// The last byte shifted out of `low`, not yet written (a carry may still reach it).
    cache: u8,
    /// `0xFF` bytes shifted out after `cache`, also waiting for a possible carry.
    pending: u64,
    /// Whether `cache` holds a real byte yet (the first shift only primes it).
    primed: bool,
    /// Bytes shifted out of `low` (the decoder reads the same number after its first four).
    shifts: u64,
    out: Vec<u8>,
}

impl Default for Encoder {
    fn default() -> Self {
        Encoder::new(Vec::new())
    }
}

impl Encoder {
    /// An encoder appending to `out`.
    pub fn new(out: Vec<u8>) -> Self {
        Encoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            pending: 0,
            primed: false,
            shifts: 0,
            out,
        }
    }

    /// Codes `bit` where a 0 has probability `p0 / 2^16` (`0 < p0 < 2^16`).
    #[inline]
    pub fn encode(&mut self, bit: bool, p0: u32) {
        debug_assert!(p0 > 0 && p0 < 1 << PROB_BITS);
        let bound = (self.range >> PROB_BITS) * p0;
        // selects rather than branches: the decisions are what the models could not predict
        let (add, range) = if bit {
            (bound, self.range - bound)
        } else {
            (0, bound)
        };
        self.low += add as u64;
        self.range = range;
        if range < TOP {
            self.renormalise();
        }
    }

    /// Shifts bytes out until the range is wide again (about once every two bytes' worth of
    /// decisions: out of line).
    #[inline(never)]
    fn renormalise(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
            self.shifts += 1;
        }
    }

    /// Moves the top byte of `low` out, into `cache`, writing what a carry can no longer change.
    #[inline]
    fn shift_low(&mut self) {
        if self.low < 0xFF00_0000 || self.low >= 1 << 32 {
            let carry = (self.low >> 32) as u8;
            if self.primed {
                self.out.push(self.cache.wrapping_add(carry));
            }
            for _ in 0..self.pending {
                self.out.push(0xFFu8.wrapping_add(carry));
            }
            self.pending = 0;
            self.cache = (self.low >> 24) as u8;
            self.primed = true;
        } else {
            self.pending += 1;
        }
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Ends the code and returns the bytes: enough of them for a decoder that reads zeros past
    /// the end to decode every decision.
    pub fn finish(mut self) -> Vec<u8> {
        // the value of the final interval with the most trailing zero bits
        let end = self.low + self.range as u64;
        for k in (0..=32).rev() {
            let mask = (1u64 << k) - 1;
            let v = (self.low + mask) & !mask;
            if v < end {
                self.low = v;
                break;
            }
        }
        for _ in 0..5 {
            self.shift_low();
        }
        // the decoder reads 4 + `shifts` bytes; the zeros after the first `shifts` it makes up
        let keep = self.shifts as usize;
        while self.out.len() > keep && self.out.last() == Some(&0) {
            self.out.pop();
        }
        self.out
    }
}

/// The decoder over one chunk; never fails, whatever the bytes (garbage decodes to garbage
/// decisions, which the kd coder's limits then catch).
#[derive(Clone, Debug)]
pub struct Decoder<'a> {
    code: u32,
    range: u32,
    bytes: Cow<'a, [u8]>,
    /// Bytes taken so far, counting the zeros made up past the end.
    pos: usize,
}

impl<'a> Decoder<'a> {
    /// A decoder over `bytes` (borrowed, or owned by the decoder).
    pub fn new(bytes: impl Into<Cow<'a, [u8]>>) -> Self {
        let mut d = Decoder {
            code: 0,
            range: u32::MAX,
            bytes: bytes.into(),
            pos: 0,
        };
        for _ in 0..4 {
            d.code = (d.code << 8) | d.byte();
        }
        d
    }

    #[inline]
    fn byte(&mut self) -> u32 {
        let b = self.bytes.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b as u32
    }

    /// The next decision, where a 0 has probability `p0 / 2^16`.
    #[inline]
    pub fn decode(&mut self, p0: u32) -> bool {
        let bound = (self.range >> PROB_BITS) * p0;
        let bit = self.code >= bound;
        // selects rather than branches, as the encoder
        let (sub, range) = if bit {
            (bound, self.range - bound)
        } else {
            (0, bound)
        };
        self.code -= sub;
        self.range = range;
        if range < TOP {
            self.renormalise();
        }
        bit
    }

    /// Takes bytes in until the range is wide again (out of line, as the encoder's).
    #[inline(never)]
    fn renormalise(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | self.byte();
        }
    }

    /// Bytes taken from the chunk so far, the four-byte look-ahead included, made-up zeros past
    /// its end excluded: a decode that stops here needed the chunk's first `consumed()` bytes.
    pub fn consumed(&self) -> usize {
        self.pos.min(self.bytes.len())
    }

    /// Bytes taken past the chunk's end (a valid chunk: at most 4).
    pub fn overrun(&self) -> usize {
        self.pos.saturating_sub(self.bytes.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), so the tests need no crate (the entropy
    /// tests use it too).
    pub(crate) fn rng(seed: u64) -> impl FnMut() -> u64 {
        let mut s = seed.max(1);
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        }
    }

    #[test]
    fn skewed_bits_round_trip_within_one_percent_of_their_entropy() {
        for (seed, p0) in [
            (1u64, 32768u32),
            (2, 60000),
            (3, 3000),
            (4, 65000),
            (5, 200),
        ] {
            let mut next = rng(seed);
            let n = 200_000;
            let bits: Vec<bool> = (0..n).map(|_| (next() & 0xFFFF) as u32 >= p0).collect();
            let mut e = Encoder::default();
            for &b in &bits {
                e.encode(b, p0);
            }
            let bytes = e.finish();
            let mut d = Decoder::new(&bytes);
            for (i, &b) in bits.iter().enumerate() {
                assert_eq!(d.decode(p0), b, "decision {i} at p0 {p0}");
            }
            assert!(d.overrun() <= 4, "read {} bytes past the end", d.overrun());
            let p = p0 as f64 / 65536.0;
            let ones = bits.iter().filter(|&&b| b).count() as f64;
            let ideal = -(ones * (1.0 - p).log2() + (n as f64 - ones) * p.log2());
            let real = 8.0 * bytes.len() as f64;
            assert!(
                real <= ideal * 1.01 + 64.0,
                "p0 {p0}: {real} bits for {ideal}"
            );
        }
    }

    #[test]
    fn varying_probabilities_round_trip_and_prefixes_need_only_consumed_bytes() {
        let mut next = rng(9);
        let decisions: Vec<(bool, u32)> = (0..50_000)
            .map(|_| {
                let p0 = 1 + (next() % 65535) as u32;
                (((next() & 0xFFFF) as u32) >= p0, p0)
            })
            .collect();
        let mut e = Encoder::default();
        for &(b, p0) in &decisions {
            e.encode(b, p0);
        }
        let bytes = e.finish();
        let mut d = Decoder::new(&bytes);
        let mut marks = Vec::new();
        for (i, &(b, p0)) in decisions.iter().enumerate() {
            assert_eq!(d.decode(p0), b);
            if i % 997 == 0 {
                marks.push((i + 1, d.consumed()));
            }
        }
        // a prefix decodes the same from the bytes it consumed alone
        for (count, used) in marks {
            let mut d = Decoder::new(&bytes[..used]);
            for &(b, p0) in &decisions[..count] {
                assert_eq!(d.decode(p0), b);
            }
        }
    }

    #[test]
    fn empty_and_tiny_codes() {
        assert!(Encoder::default().finish().is_empty());
        let mut e = Encoder::default();
        e.encode(false, 40000);
        let bytes = e.finish();
        assert!(bytes.len() <= 1, "{bytes:?}");
        assert!(!Decoder::new(&bytes).decode(40000));
    }

    #[test]
    fn garbage_never_panics() {
        let mut next = rng(77);
        for len in [0usize, 1, 3, 4, 5, 64, 1000] {
            for fill in [0u8, 0xFF, 0x80] {
                let bytes: Vec<u8> = (0..len)
                    .map(|i| if i % 3 == 0 { next() as u8 } else { fill })
                    .collect();
                let mut d = Decoder::new(&bytes);
                for _ in 0..10_000 {
                    let p0 = 1 + (next() % 65535) as u32;
                    d.decode(p0);
                }
                assert!(d.consumed() <= len);
            }
        }
    }
}
