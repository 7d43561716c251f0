//! Entropy coding of the symbol streams (paper 003 §5.3): once every cell's symbols are known,
//! one probability table per context (family × kd level) is computed from the whole file's counts,
//! written once, and each cell's stream is range-coded on its own, so that a reader can decode any
//! cell it reaches through the index without touching the others. The range coder is
//! `constriction`'s; the tables are plain counts, turned into fixed-point probabilities the same
//! way on both sides.

use constriction::stream::model::DefaultContiguousCategoricalEntropyModel;
use constriction::stream::queue::{DefaultRangeDecoder, DefaultRangeEncoder};
use constriction::stream::{Decode, Encode};

use crate::error::CodecError;
use crate::symbols::{CONTEXTS, MAX_ALPHABET, Symbol, family_of};
use crate::varint;

/// Fixed-point precision of constriction's default models.
const PRECISION: u32 = 24;

/// How often each value of each context occurs.
#[derive(Clone, Debug)]
pub struct Counts(Vec<u64>);

impl Default for Counts {
    fn default() -> Self {
        Counts(vec![0; CONTEXTS * MAX_ALPHABET])
    }
}

impl Counts {
    /// Counts the symbols of one stream.
    pub fn add(&mut self, symbols: &[Symbol]) {
        for s in symbols {
            self.0[s.context() * MAX_ALPHABET + s.value() as usize] += 1;
        }
    }

    /// Number of symbols counted.
    pub fn total(&self) -> u64 {
        self.0.iter().sum()
    }

    /// Adds another table's counts.
    pub fn merge(&mut self, other: &Counts) {
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a += b;
        }
    }

    fn of(&self, ctx: usize) -> &[u64] {
        let n = family_of(ctx).alphabet();
        &self.0[ctx * MAX_ALPHABET..ctx * MAX_ALPHABET + n]
    }

    /// Bits the symbols of each family cost under these counts' own models (the ideal code
    /// length, which the range coder reaches within a few bytes per cell).
    pub fn family_bits(&self) -> [f64; crate::symbols::FAMILIES] {
        let mut out = [0.0; crate::symbols::FAMILIES];
        for c in 0..CONTEXTS {
            let probs = fixed_point(self.of(c));
            for (&n, &p) in self.of(c).iter().zip(&probs) {
                if n > 0 {
                    out[family_of(c) as usize] += n as f64 * (PRECISION as f64 - (p as f64).log2());
                }
            }
        }
        out
    }

    /// The counts scaled to one byte each (the largest to 255, a non-zero count to at least
    /// 1): what the file stores and what both sides build their models from. A context whose
    /// table would cost more bytes than it saves over a uniform model is left out (both sides
    /// then use the uniform model): small meshes would otherwise pay more for their tables than
    /// for their codes.
    pub fn quantised(&self) -> Counts {
        let mut q = Counts::default();
        for c in 0..CONTEXTS {
            let counts = self.of(c);
            let max = counts.iter().copied().max().unwrap_or(0) as u128;
            if max == 0 {
                continue;
            }
            let table: Vec<u64> = counts
                .iter()
                .map(|&n| (n as u128 * 255).div_ceil(max) as u64)
                .collect();
            let probs = fixed_point(&table);
            let uniform = fixed_point(&vec![0; counts.len()]);
            let cost = |p: &[u32]| -> f64 {
                counts
                    .iter()
                    .zip(p)
                    .map(|(&n, &p)| n as f64 * (PRECISION as f64 - (p as f64).log2()))
                    .sum()
            };
            let saved = cost(&uniform) - cost(&probs);
            if saved <= 8.0 * (1 + counts.len()) as f64 {
                continue;
            }
            q.0[c * MAX_ALPHABET..c * MAX_ALPHABET + counts.len()].copy_from_slice(&table);
        }
        q
    }

    /// Symbols of each family.
    pub fn family_symbols(&self) -> [u64; crate::symbols::FAMILIES] {
        let mut out = [0; crate::symbols::FAMILIES];
        for c in 0..CONTEXTS {
            out[family_of(c) as usize] += self.of(c).iter().sum::<u64>();
        }
        out
    }

    /// The table as written to the file: the used contexts, each with its counts (one byte each
    /// once [`Counts::quantised`]).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let used: Vec<usize> = (0..CONTEXTS)
            .filter(|&c| self.of(c).iter().any(|&n| n > 0))
            .collect();
        varint::put(&mut out, used.len() as u64);
        let mut last = 0;
        for c in used {
            varint::put(&mut out, (c - last) as u64);
            last = c;
            for &n in self.of(c) {
                out.push(n.min(255) as u8);
            }
        }
        out
    }

    /// Reads a table written by [`Counts::to_bytes`]; `base` is its offset in the file.
    pub fn from_bytes(bytes: &[u8], base: u64) -> Result<Self, CodecError> {
        let mut counts = Counts::default();
        let mut at = 0usize;
        let used = varint::get(bytes, &mut at, base)?;
        if used > CONTEXTS as u64 {
            return Err(CodecError::corrupt(
                base,
                format!("{used} probability tables"),
            ));
        }
        let mut c = 0usize;
        for k in 0..used {
            let delta = varint::get(bytes, &mut at, base)?;
            if delta == 0 && k > 0 {
                return Err(CodecError::corrupt(
                    base + at as u64,
                    "a probability table listed twice",
                ));
            }
            c = c.saturating_add(usize::try_from(delta).unwrap_or(usize::MAX));
            if c >= CONTEXTS {
                return Err(CodecError::corrupt(
                    base + at as u64,
                    format!("context {c}"),
                ));
            }
            for v in 0..family_of(c).alphabet() {
                let Some(&n) = bytes.get(at) else {
                    return Err(CodecError::corrupt(
                        base + at as u64,
                        "truncated probability table",
                    ));
                };
                counts.0[c * MAX_ALPHABET + v] = n as u64;
                at += 1;
            }
        }
        Ok(counts)
    }

    /// The models both sides build from these counts.
    pub fn models(&self) -> Models {
        Models(
            (0..CONTEXTS)
                .map(|c| {
                    let probs = fixed_point(self.of(c));
                    DefaultContiguousCategoricalEntropyModel::from_nonzero_fixed_point_probabilities(
                        &probs, false,
                    )
                    .expect("probabilities are non-zero and sum to 2^24")
                })
                .collect(),
        )
    }
}

/// Probabilities summing to `2^24`, every value at least 1 so that no symbol is undecodable,
/// the rest shared in proportion to the counts (integer arithmetic: identical on every machine).
fn fixed_point(counts: &[u64]) -> Vec<u32> {
    let n = counts.len() as u128;
    let total: u128 = counts.iter().map(|&c| c as u128).sum();
    let spare = (1u128 << PRECISION) - n;
    let mut probs: Vec<u32> = counts
        .iter()
        .map(|&c| {
            let share = (c as u128 * spare).checked_div(total).unwrap_or(spare / n);
            (1 + share) as u32
        })
        .collect();
    let sum: u64 = probs.iter().map(|&p| p as u64).sum();
    let largest = (0..probs.len())
        .max_by_key(|&i| (counts[i], usize::MAX - i))
        .unwrap_or(0);
    probs[largest] += ((1u64 << PRECISION) - sum) as u32;
    probs
}

/// One model per context.
pub struct Models(Vec<DefaultContiguousCategoricalEntropyModel>);

/// Range-codes one cell's symbols.
pub fn encode(symbols: &[Symbol], models: &Models) -> Vec<u8> {
    let mut coder = DefaultRangeEncoder::new();
    for s in symbols {
        coder
            .encode_symbol(s.value() as usize, &models.0[s.context()])
            .expect("every value has a non-zero probability");
    }
    let words = coder.into_compressed().expect("Vec backend cannot fail");
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Reads one cell's symbols back, in the order the kd coder asks for them.
pub struct SymbolReader {
    decoder: DefaultRangeDecoder,
    models: std::sync::Arc<Models>,
    /// Offset of the cell's code chunk in the file, for error messages.
    pub offset: u64,
    /// Symbols read so far.
    pub read: u64,
}

impl SymbolReader {
    /// A reader over one cell's chunk, which starts at `offset` in the file.
    pub fn new(
        chunk: &[u8],
        models: std::sync::Arc<Models>,
        offset: u64,
    ) -> Result<Self, CodecError> {
        if !chunk.len().is_multiple_of(4) {
            return Err(CodecError::corrupt(
                offset,
                format!(
                    "a code chunk of {} bytes (not whole 32-bit words)",
                    chunk.len()
                ),
            ));
        }
        let words: Vec<u32> = chunk
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let decoder = DefaultRangeDecoder::from_compressed(words).map_err(|_| {
            CodecError::corrupt(offset, "the code chunk cannot start a range decoder")
        })?;
        Ok(SymbolReader {
            decoder,
            models,
            offset,
            read: 0,
        })
    }

    /// Bytes of the chunk the decoder has read so far (whole 32-bit words, the look-ahead
    /// included): what a decode that stops inside this cell needed of the file.
    pub fn consumed_bytes(&self) -> u64 {
        use constriction::Pos;
        let (cursor, _, _) = self.decoder.clone().into_raw_parts();
        4 * cursor.pos() as u64
    }

    /// The next value in context `ctx`.
    pub fn next(&mut self, ctx: usize) -> Result<u8, CodecError> {
        let v = self
            .decoder
            .decode_symbol(&self.models.0[ctx])
            .map_err(|_| {
                CodecError::corrupt(
                    self.offset,
                    format!(
                        "symbol {} of this cell's code chunk cannot be decoded",
                        self.read
                    ),
                )
            })?;
        self.read += 1;
        Ok(v as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probabilities_sum_to_one_and_are_never_zero() {
        for counts in [
            vec![0u64, 0, 0],
            vec![5, 0, 1_000_000],
            vec![u64::MAX, 1, 0],
        ] {
            let p = fixed_point(&counts);
            assert_eq!(p.iter().map(|&x| x as u64).sum::<u64>(), 1 << PRECISION);
            assert!(p.iter().all(|&x| x > 0));
        }
    }

    #[test]
    fn symbols_round_trip_through_the_range_coder() {
        use crate::symbols::{Family, context};
        let syms: Vec<Symbol> = (0..1000)
            .map(|i| Symbol::new(context(Family::Split, i % 8, i % 5), (i % 3) as u8))
            .chain((0..300).map(|i| Symbol::new(context(Family::Thrice, 0, 7), (i % 15) as u8)))
            .collect();
        let mut counts = Counts::default();
        counts.add(&syms);
        let counts = Counts::from_bytes(&counts.quantised().to_bytes(), 0).unwrap();
        let models = std::sync::Arc::new(counts.models());
        let bytes = encode(&syms, &models);
        let mut r = SymbolReader::new(&bytes, models, 0).unwrap();
        for s in &syms {
            assert_eq!(r.next(s.context()).unwrap(), s.value());
        }
    }
}
