//! Entropy coding of a cell's symbols (paper 003 §5.3), in one pass: each symbol is cut into
//! binary decisions, each decision coded with the adaptive model of its context
//! (`adaptive`) by the binary range coder (`binary_coder`).
//!
//! The paper computes one probability table per (family, level) context from the whole file and
//! writes it once; here every context of a cell starts from a built-in start of its family (or
//! where the same context one level coarser stands in the cell) and learns as it goes, so a cell
//! is coded as soon as its symbols are known, in its own thread, and no table is stored.
//! Models never cross cells: a reader decodes any cell it reaches through the index on its own,
//! which progressive prefixes, view sessions (§6.2) and thread-count independence rely on.
//!
//! Binarisation (the alphabets of [`crate::symbols::Family`]):
//! - three values (split, once-held triangle, point, split ahead: 0 = predicted, 1 = other,
//!   2 = both): "both?", then "which?" (two models per context);
//! - masks of four candidates (twice and thrice held: value = mask − 1): the four mask bits in
//!   turn, each conditioned on the ones before (a binary tree of 15 models), the last bit not
//!   coded when the first three are zero (a mask is never empty).

use std::borrow::Cow;
use std::sync::LazyLock;

use crate::adaptive::Model;
use crate::binary_coder::{Decoder, Encoder, PROB_BITS};
use crate::error::CodecError;
use crate::symbols::{CONTEXTS, FAMILIES, Family, MAX_LEVELS, Symbol, coarser, family_of};

/// Binary models per context of a three-valued family.
const TERNARY_MODELS: u32 = 2;
/// Binary models per context of a mask family (the tree's inner nodes).
const MASK_MODELS: u32 = 15;

/// Every context's models for one cell, made when a context is first used.
///
/// A new context's models start where the same family and sub-context one level coarser stand
/// in this cell, if it was used (with their count capped at [`INHERITED_COUNT`], so they adapt
/// fast): the decoder reaches a level after the coarser one, and a level's statistics are close
/// to its neighbour's. On the v1 symbol streams of the 43-cell bunny this took the split codes
/// from 14.92 to 14.43 bits/vertex (static tables: 14.50), fandisk from 19.98 to 18.52.
struct Contexts {
    /// Per page of [`MAX_LEVELS`] contexts (one family and sub-context at every level): 0 if
    /// unused, else 1 + the page's first entry in `slots`.
    pages: Vec<u32>,
    /// Per context of a used page: 0 if unused, else `(first model + 1) << 4 | family`.
    slots: Vec<u32>,
    models: Vec<Model>,
    /// The family of a context ([`family_of`]; another alphabet's in the tests).
    family_of: fn(usize) -> Family,
}

/// Where the two models of a three-valued family's new context start when no coarser level
/// lends its own: the probabilities of "not both" and of "the predicted one" over all the bunny's
/// (bun_zipper, 12 bits, one cell, issue 34's contexts) decisions of that family, counted as one
/// decision seen. Masks start at even odds (their mean start cost them 0.005–0.02 b/v). Trained
/// on the bunny alone, tested on the others (b/v, none → these): bunny one cell 17.078 → 17.064,
/// 43 cells 19.771 → 19.480, fandisk 17.721 → 17.638 (180 cells: 26.565 → 24.783), spot
/// 23.414 → 23.237. Split ahead takes the split's.
const START: [Option<[u16; 2]>; FAMILIES] = [
    Some([61662, 50003]),
    Some([63640, 53036]),
    None,
    None,
    Some([51589, 32720]),
    Some([61662, 50003]),
];

/// The most decisions a model inherited from the coarser level counts as having seen.
const INHERITED_COUNT: u32 = 8;

impl Contexts {
    fn new() -> Self {
        Contexts::of_alphabet(CONTEXTS, family_of)
    }

    fn of_alphabet(contexts: usize, family_of: fn(usize) -> Family) -> Self {
        Contexts {
            pages: vec![0; contexts.div_ceil(MAX_LEVELS)],
            slots: Vec::new(),
            models: Vec::new(),
            family_of,
        }
    }

    /// The slot entry of `ctx` (0 if unused).
    #[inline]
    fn slot(&self, ctx: usize) -> u32 {
        match self.pages[ctx / MAX_LEVELS] {
            0 => 0,
            page => self.slots[page as usize - 1 + ctx % MAX_LEVELS],
        }
    }

    /// The first model of `ctx` and its family.
    #[inline]
    fn of(&mut self, ctx: usize) -> (usize, Family) {
        let slot = self.slot(ctx);
        if slot != 0 {
            return ((slot >> 4) as usize - 1, FAMILY_OF[(slot & 15) as usize]);
        }
        self.open(ctx)
    }

    /// Makes the models of `ctx`, at its first use.
    #[cold]
    fn open(&mut self, ctx: usize) -> (usize, Family) {
        let family = (self.family_of)(ctx);
        let first = self.models.len();
        let n = if is_mask(family) {
            MASK_MODELS
        } else {
            TERNARY_MODELS
        } as usize;
        match coarser(ctx).map(|c| self.slot(c)).unwrap_or(0) {
            0 => match START[family as usize] {
                Some(start) => self
                    .models
                    .extend(start.map(|p0| Model::starting_at(p0 as u32, 1))),
                None => self.models.extend((0..n).map(|_| Model::new())),
            },
            from => {
                let at = (from >> 4) as usize - 1;
                for j in at..at + n {
                    let m = self.models[j].with_count_at_most(INHERITED_COUNT);
                    self.models.push(m);
                }
            }
        }
        let page = ctx / MAX_LEVELS;
        if self.pages[page] == 0 {
            self.pages[page] = self.slots.len() as u32 + 1;
            self.slots.extend([0; MAX_LEVELS]);
        }
        let at = self.pages[page] as usize - 1 + ctx % MAX_LEVELS;
        self.slots[at] = ((first as u32 + 1) << 4) | family as u32;
        (first, family)
    }
}

/// Families by number.
const FAMILY_OF: [Family; FAMILIES] = crate::symbols::ALL;

fn is_mask(family: Family) -> bool {
    family.alphabet() > 3
}

/// The bit the last decision must take after tree node `node` (three bits in), if forced: a
/// mask is never empty. (Coding the value mask − 1 highest bit first instead, where the value
/// 15 is the one never met, cost 0.002–0.011 bits/vertex more on the bunny, fandisk and spot.)
#[inline]
fn forced_last(node: usize) -> Option<bool> {
    (node == 8).then_some(true)
}

/// The decisions of a mask value `value` as (tree node − 1, bit), at most four, the fourth left
/// out when forced.
#[inline]
fn mask_decisions(value: u8, mut f: impl FnMut(usize, bool)) {
    // bit i of the word is the mask's bit i
    let word = value + 1;
    let mut node = 1usize;
    for i in 0..4 {
        let bit = word >> i & 1 != 0;
        if i < 3 || forced_last(node).is_none() {
            f(node - 1, bit);
        }
        node = 2 * node + bit as usize;
    }
}

/// Cost in bits of a decision by its probability, as `2^-16` bits, indexed by the
/// probability's top 12 bits (for the report only: floating point never reaches the bytes).
static COST: LazyLock<[u32; 4096]> = LazyLock::new(|| {
    std::array::from_fn(|i| {
        let p = (i as f64 * 16.0 + 8.0) / 65536.0;
        (-p.log2() * 65536.0).round() as u32
    })
});

/// One cell's chunk and what it cost.
#[derive(Clone, Debug, Default)]
pub struct CellCode {
    /// The range-coded chunk.
    pub bytes: Vec<u8>,
    /// Bits spent on each family: the sum of `−log2 p` over its coded decisions (the chunk is
    /// this total rounded up to bytes, less the zeros its end leaves out).
    pub family_bits: [f64; FAMILIES],
    /// Symbols of each family.
    pub family_symbols: [u64; FAMILIES],
}

/// Codes one cell's symbols, given in the decoder's order, with models fresh for the cell.
pub fn encode(symbols: &[Symbol]) -> CellCode {
    encode_in(symbols, Contexts::new())
}

/// Codes one decision with model `m` and adds its cost to `spent`.
#[inline(always)]
fn put(coder: &mut Encoder, m: &mut Model, bit: bool, spent: &mut u64, cost: &[u32; 4096]) {
    let p0 = m.p0();
    let p = if bit { (1 << PROB_BITS) - p0 } else { p0 };
    *spent += cost[(p >> 4) as usize & 4095] as u64;
    coder.encode(bit, p0);
    m.update(bit);
}

fn encode_in(symbols: &[Symbol], mut cx: Contexts) -> CellCode {
    // a decision costs well under a bit on average (about 0.5 on the bunny): a sixteenth of a
    // byte a symbol, grown when short
    let mut coder = Encoder::new(Vec::with_capacity(symbols.len() / 16 + 16));
    let cost = &*COST;
    let mut bits = [0u64; FAMILIES];
    let mut counts = [0u64; FAMILIES];
    for s in symbols {
        let (first, family) = cx.of(s.context());
        // the symbol's cost summed here, added to its family's once (not through memory at
        // every decision)
        let mut spent = 0u64;
        let v = s.value();
        if is_mask(family) {
            let models = &mut cx.models[first..first + MASK_MODELS as usize];
            mask_decisions(v, |node, bit| {
                put(&mut coder, &mut models[node], bit, &mut spent, cost)
            });
        } else {
            let [both, which] = &mut cx.models[first..first + 2] else {
                unreachable!("two models")
            };
            put(&mut coder, both, v == 2, &mut spent, cost);
            if v != 2 {
                put(&mut coder, which, v == 1, &mut spent, cost);
            }
        }
        bits[family as usize] += spent;
        counts[family as usize] += 1;
    }
    CellCode {
        bytes: coder.finish(),
        family_bits: bits.map(|b| b as f64 / 65536.0),
        family_symbols: counts,
    }
}

/// Decodes one decision with model `m`.
#[inline(always)]
fn get(d: &mut Decoder<'_>, m: &mut Model) -> bool {
    let bit = d.decode(m.p0());
    m.update(bit);
    bit
}

/// Reads one cell's symbols back, in the order the kd coder asks for them.
pub struct SymbolReader {
    decoder: Decoder<'static>,
    contexts: Contexts,
    /// Offset of the cell's code chunk in the file, for error messages.
    pub offset: u64,
    /// Symbols read so far.
    pub read: u64,
}

impl SymbolReader {
    /// A reader over one cell's chunk, which starts at `offset` in the file.
    pub fn new(chunk: Cow<'_, [u8]>, offset: u64) -> Self {
        SymbolReader {
            decoder: Decoder::new(Cow::Owned(chunk.into_owned())),
            contexts: Contexts::new(),
            offset,
            read: 0,
        }
    }

    /// Bytes of the chunk the decoder has read so far (its four-byte look-ahead included):
    /// what a decode that stops inside this cell needed of the file.
    pub fn consumed_bytes(&self) -> u64 {
        self.decoder.consumed() as u64
    }

    /// The next value in context `ctx`.
    pub fn next(&mut self, ctx: usize) -> Result<u8, CodecError> {
        let (first, family) = self.contexts.of(ctx);
        let d = &mut self.decoder;
        let v = if is_mask(family) {
            let models = &mut self.contexts.models[first..first + MASK_MODELS as usize];
            let mut node = 1usize;
            let mut word = 0u8;
            for i in 0..4 {
                let forced = if i == 3 { forced_last(node) } else { None };
                let bit = match forced {
                    Some(bit) => bit,
                    None => get(d, &mut models[node - 1]),
                };
                word |= (bit as u8) << i;
                node = 2 * node + bit as usize;
            }
            word - 1
        } else {
            let [both, which] = &mut self.contexts.models[first..first + 2] else {
                unreachable!("two models")
            };
            if get(d, both) {
                2
            } else {
                u8::from(get(d, which))
            }
        };
        if self.decoder.overrun() > 4 {
            return Err(CodecError::corrupt(
                self.offset,
                format!(
                    "symbol {} of this cell's code chunk lies past the chunk's end",
                    self.read
                ),
            ));
        }
        self.read += 1;
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binary_coder::tests::rng;
    use crate::symbols::{Family, context};

    /// A stream over every family, skewed as the real ones are.
    fn stream(n: usize, seed: u64) -> Vec<Symbol> {
        let mut next = rng(seed);
        (0..n)
            .map(|i| {
                let r = next();
                match i % 6 {
                    0 | 1 => Symbol::new(
                        context(Family::Split, (r % 14) as usize, (r >> 8) as usize % 36),
                        [0, 0, 0, 0, 1, 2][(r >> 16) as usize % 6],
                    ),
                    2 => Symbol::new(
                        context(Family::TriangleOnce, (r % 16) as usize, 3),
                        [0, 0, 0, 1, 2][(r >> 16) as usize % 5],
                    ),
                    3 => Symbol::new(
                        context(Family::Twice, (r % 9) as usize, 30),
                        [0, 2, 2, 2, 5, 14][(r >> 16) as usize % 6],
                    ),
                    4 => Symbol::new(
                        context(Family::Thrice, (r % 4) as usize, 30),
                        ((r >> 16) % 15) as u8,
                    ),
                    _ => Symbol::new(context(Family::Point, 0, 12), ((r >> 16) % 3) as u8),
                }
            })
            .collect()
    }

    #[test]
    fn symbols_round_trip_and_costs_match_the_chunk() {
        let syms = stream(60_000, 5);
        let code = encode(&syms);
        let mut r = SymbolReader::new(Cow::Borrowed(&code.bytes[..]), 0);
        for s in &syms {
            assert_eq!(r.next(s.context()).unwrap(), s.value());
        }
        let ideal: f64 = code.family_bits.iter().sum();
        let real = 8.0 * code.bytes.len() as f64;
        assert!(
            (real - ideal).abs() < ideal * 0.005 + 40.0,
            "{real} {ideal}"
        );
        assert_eq!(code.family_symbols.iter().sum::<u64>(), syms.len() as u64);
    }

    #[test]
    fn a_new_context_starts_where_the_coarser_level_stands() {
        let mut cx = Contexts::new();
        let coarse = context(Family::Split, 3, 10);
        let (first, _) = cx.of(coarse);
        for _ in 0..200 {
            cx.models[first].update(false);
            cx.models[first + 1].update(true);
        }
        let learnt = (cx.models[first].p0(), cx.models[first + 1].p0());
        let (next, family) = cx.of(context(Family::Split, 3, 11));
        assert_eq!(family, Family::Split);
        assert_ne!(next, first);
        assert_eq!((cx.models[next].p0(), cx.models[next + 1].p0()), learnt);
        // another sub-context, or a level with no coarser one used, starts at its family's start
        for ctx in [context(Family::Split, 4, 11), context(Family::Split, 3, 13)] {
            let (other, _) = cx.of(ctx);
            assert_eq!(cx.models[other].p0(), 61662);
        }
        let (mask, _) = cx.of(context(Family::Twice, 0, 30));
        assert!(cx.models[mask..mask + 15].iter().all(|m| m.p0() == 1 << 15));
    }

    #[test]
    fn garbage_reads_fail_or_decode_without_panic() {
        let syms = stream(2_000, 6);
        let mut next = rng(7);
        for len in [0usize, 1, 7, 100, 3000] {
            let bytes: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            let mut r = SymbolReader::new(Cow::Borrowed(&bytes[..]), 0);
            let mut failed = false;
            for s in &syms {
                match r.next(s.context()) {
                    Ok(v) => assert!((v as usize) < family_of(s.context()).alphabet()),
                    Err(e) => {
                        assert!(e.to_string().contains("past the chunk's end"), "{e}");
                        failed = true;
                        break;
                    }
                }
            }
            assert!(failed || len > 100, "{len} bytes decoded 2000 symbols");
        }
    }
}
