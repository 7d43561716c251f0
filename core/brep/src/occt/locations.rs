//! Step 2: the `Locations` section and the algebra of locations.
//!
//! OCCT places every sub-shape and representation with a `TopLoc_Location`: a chain of
//! elementary transformations ("datums", the section's type-1 records) raised to integer
//! powers. Two shapes are the same (`IsSame`, what `TopExp::MapShapes` numbers by) only when
//! their chains are equal item by item, and a pcurve belongs to a face only when its stored
//! location equals the face's location pre-divided by the edge's — so locations are kept here
//! as reduced chains, interned to small ids, exactly as OCCT compares them; matrices are only
//! computed to place geometry.

use std::collections::{HashMap, HashSet};

use super::lexer::Lexer;
use super::{OcctError, OcctErrorKind};
use crate::vector::Point;
use crate::vector::Point3;
use glam::DMat3;

/// An interned location (0 is the identity).
pub(crate) type LocId = u32;

/// The identity location.
pub(crate) const IDENTITY: LocId = 0;

/// The longest chain accepted: real assemblies nest a few dozen levels; hostile texts could
/// otherwise build chains (and matrices products) without bound.
const MAX_CHAIN: usize = 1024;

/// The largest power of a composed location expanded by repeated products.
const MAX_REPEAT: i64 = 1024;

/// A rigid motion `x ↦ R·x + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Trsf {
    /// The rotation (glam's products sum `r[i][0]·v[0] + r[i][1]·v[1] + r[i][2]·v[2]` in
    /// that order, as OCCT's `gp_Trsf` does).
    pub r: DMat3,
    /// The translation.
    pub t: Point3,
}

impl Trsf {
    /// The identity.
    pub const IDENTITY: Trsf = Trsf {
        r: DMat3::IDENTITY,
        t: Point3::ZERO,
    };

    /// `R·v` (a vector: no translation).
    pub fn vector(&self, v: Point3) -> Point3 {
        self.r * v
    }

    /// `R·p + t`.
    pub fn point(&self, p: Point3) -> Point3 {
        self.vector(p) + self.t
    }

    /// `R·d`, renormalised (as `gp_Dir::Transform` does).
    pub fn dir(&self, d: Point3) -> Point3 {
        normalized(self.vector(d))
    }

    /// `self ∘ o` (`o` applied first), OCCT's `gp_Trsf` product.
    pub fn then_after(&self, o: &Trsf) -> Trsf {
        Trsf {
            r: self.r * o.r,
            t: self.point(o.t),
        }
    }

    /// The inverse of a rigid motion.
    pub fn inverse(&self) -> Trsf {
        let r = self.r.transpose();
        let t = (r * self.t) * -1.0;
        Trsf { r, t }
    }

    /// `self^p` by repeated squaring (negative powers through the inverse).
    pub fn pow(&self, p: i64) -> Trsf {
        let (mut base, mut e) = if p < 0 {
            (self.inverse(), p.unsigned_abs())
        } else {
            (*self, p as u64)
        };
        let mut out = Trsf::IDENTITY;
        while e > 0 {
            if e & 1 == 1 {
                out = out.then_after(&base);
            }
            base = base.then_after(&base);
            e >>= 1;
        }
        out
    }
}

/// `v / |v|` (`gp_Dir`'s normalisation).
pub(crate) fn normalized<V: Point>(v: V) -> V {
    let n = v.length();
    v * (1.0 / n)
}

/// An elementary location (a type-1 record).
#[derive(Clone, Debug)]
pub(crate) struct Datum {
    /// Its matrix as written.
    pub trsf: Trsf,
    /// `None` for a rigid motion; else why the exchange format cannot take it.
    pub not_rigid: Option<String>,
    /// Its line in the text.
    pub line: u32,
}

/// The section's records and every location built from them, interned.
pub(crate) struct Locations {
    datums: Vec<Datum>,
    /// Reduced chains `[(datum, power)]` in product order: chain `[a, b]` is `a · b`
    /// (`b` applied first). `chains[0]` is the identity.
    chains: Vec<Vec<(u32, i64)>>,
    ids: HashMap<Vec<(u32, i64)>, LocId>,
    products: HashMap<(LocId, LocId), LocId>,
    inverses: HashMap<LocId, LocId>,
    /// The file's location numbers (1-based) → ids, after OCCT's de-duplication.
    table: Vec<LocId>,
}

impl Locations {
    fn empty() -> Locations {
        let mut ids = HashMap::new();
        ids.insert(Vec::new(), IDENTITY);
        Locations {
            datums: Vec::new(),
            chains: vec![Vec::new()],
            ids,
            products: HashMap::new(),
            inverses: HashMap::new(),
            table: Vec::new(),
        }
    }

    /// Reads the `Locations` section.
    ///
    /// OCCT reads into an indexed map: a record equal to an earlier one (or the identity) adds
    /// no entry, so later numbers refer to the map's entries; the same is done here, so a
    /// text OCCT reads is numbered as OCCT numbers it.
    pub fn read(lx: &mut Lexer) -> Result<Locations, OcctError> {
        lx.at("Locations", None);
        lx.expect("Locations")?;
        let n = lx.count("location count", 3)?;
        let mut locs = Locations::empty();
        let mut listed = HashSet::new();
        for i in 1..=n {
            lx.at("Locations", Some(i));
            let id = match lx.int("location type")? {
                1 => {
                    let line = lx.token_line();
                    let mut m = [[0.0; 4]; 3];
                    for row in &mut m {
                        *row = lx.reals::<4>("a matrix coefficient")?;
                    }
                    let datum = datum(m, line).map_err(|e| lx.error_at(line, e))?;
                    locs.datums.push(datum);
                    let d = (locs.datums.len() - 1) as u32;
                    locs.intern(vec![(d, 1)]).map_err(|e| lx.error(e))?
                }
                2 => {
                    let mut l = IDENTITY;
                    loop {
                        let k = lx.int("a location number")?;
                        if k == 0 {
                            break;
                        }
                        let base = locs.number(k).ok_or_else(|| {
                            lx.error(format!("location {k} out of range 1..{}", locs.table.len()))
                        })?;
                        let p = lx.int("a power")?;
                        let powered = locs.pow(base, p).map_err(|e| lx.error(e))?;
                        l = locs.mul(powered, l).map_err(|e| lx.error(e))?;
                    }
                    l
                }
                t => return Err(lx.error(format!("unknown location type {t}"))),
            };
            if id != IDENTITY && listed.insert(id) {
                locs.table.push(id);
            }
        }
        Ok(locs)
    }

    /// The id of the file's location number `k` (0: the identity), `None` out of range.
    pub fn number(&self, k: i64) -> Option<LocId> {
        match k {
            0 => Some(IDENTITY),
            k if k > 0 => self.table.get(k as usize - 1).copied(),
            _ => None,
        }
    }

    /// How many location numbers the text may use (1..=this).
    pub fn count(&self) -> usize {
        self.table.len()
    }

    fn intern(&mut self, chain: Vec<(u32, i64)>) -> Result<LocId, String> {
        if let Some(&id) = self.ids.get(&chain) {
            return Ok(id);
        }
        if chain.len() > MAX_CHAIN {
            return Err(format!(
                "a location composed of more than {MAX_CHAIN} parts"
            ));
        }
        let id = self.chains.len() as LocId;
        self.chains.push(chain.clone());
        self.ids.insert(chain, id);
        Ok(id)
    }

    /// `a · b` (`b` applied first): the chains joined, a datum meeting itself merged and
    /// dropped when its powers cancel (what `TopLoc_Location::Multiplied` does, so equal
    /// products get equal ids).
    pub fn mul(&mut self, a: LocId, b: LocId) -> Result<LocId, String> {
        if a == IDENTITY {
            return Ok(b);
        }
        if b == IDENTITY {
            return Ok(a);
        }
        if let Some(&id) = self.products.get(&(a, b)) {
            return Ok(id);
        }
        let mut out = self.chains[a as usize].clone();
        for &(d, p) in &self.chains[b as usize] {
            match out.last_mut() {
                Some(last) if last.0 == d => {
                    let q = last.1.checked_add(p).ok_or("a location power overflows")?;
                    if q == 0 {
                        out.pop();
                    } else {
                        last.1 = q;
                    }
                }
                _ => out.push((d, p)),
            }
        }
        let id = self.intern(out)?;
        self.products.insert((a, b), id);
        Ok(id)
    }

    /// The inverse location.
    pub fn inv(&mut self, a: LocId) -> Result<LocId, String> {
        if let Some(&id) = self.inverses.get(&a) {
            return Ok(id);
        }
        let chain = self.chains[a as usize]
            .iter()
            .rev()
            .map(|&(d, p)| (d, -p))
            .collect();
        let id = self.intern(chain)?;
        self.inverses.insert(a, id);
        Ok(id)
    }

    /// `a^p` (`TopLoc_Location::Powered`).
    pub fn pow(&mut self, a: LocId, p: i64) -> Result<LocId, String> {
        if a == IDENTITY || p == 1 {
            return Ok(a);
        }
        if p == 0 {
            return Ok(IDENTITY);
        }
        if let [(d, q)] = self.chains[a as usize][..] {
            let r = q.checked_mul(p).ok_or("a location power overflows")?;
            return self.intern(vec![(d, r)]);
        }
        if p.abs() > MAX_REPEAT {
            return Err(format!("a composed location raised to the power {p}"));
        }
        let base = if p < 0 { self.inv(a)? } else { a };
        let mut out = IDENTITY;
        for _ in 0..p.abs() {
            out = self.mul(out, base)?;
        }
        Ok(out)
    }

    /// The rigid motion of a location, or why it is none (a mirror or a scaling, which the
    /// exchange format's frames cannot carry).
    pub fn trsf(&self, a: LocId) -> Result<Trsf, OcctError> {
        let mut out = Trsf::IDENTITY;
        for &(d, p) in &self.chains[a as usize] {
            let datum = &self.datums[d as usize];
            if let Some(why) = &datum.not_rigid {
                return Err(OcctError {
                    kind: OcctErrorKind::Unsupported,
                    message: format!(
                        "line {}: Locations: {why}, not a rigid motion (the exchange \
                         format's frames cannot carry it)",
                        datum.line
                    ),
                });
            }
            out = out.then_after(&datum.trsf.pow(p));
        }
        Ok(out)
    }
}

/// A type-1 record's matrix as a datum; a singular or non-finite matrix is a syntax error
/// (OCCT refuses it too), a mirror, scaling or shear is kept but marked.
fn datum(m: [[f64; 4]; 3], line: u32) -> Result<Datum, String> {
    let r = [
        [m[0][0], m[0][1], m[0][2]],
        [m[1][0], m[1][1], m[1][2]],
        [m[2][0], m[2][1], m[2][2]],
    ];
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if !det.is_finite() || det.abs() <= 1e-300 {
        return Err(format!("singular matrix (determinant {det})"));
    }
    let scale = det.abs().cbrt();
    let not_rigid = if det < 0.0 {
        Some(format!("location with a mirror (determinant {det})"))
    } else if (scale - 1.0).abs() > 1e-9 {
        Some(format!("location scaling by {scale}"))
    } else {
        let sheared = (0..3).any(|i| {
            (0..3).any(|j| {
                let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                (dot - f64::from(u8::from(i == j))).abs() > 1e-9
            })
        });
        sheared.then(|| "location with a non-orthogonal matrix".to_string())
    };
    Ok(Datum {
        trsf: Trsf {
            r: DMat3::from_cols_array_2d(&r).transpose(),
            t: Point3::new(m[0][3], m[1][3], m[2][3]),
        },
        not_rigid,
        line,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Locations, OcctError> {
        Locations::read(&mut Lexer::new(text, 0, 1))
    }

    const ROT_Z90_AND_MOVE_X10: &str = "Locations 3\n1\n0 -1 0 0\n1 0 0 0\n0 0 1 0\n\
        1\n1 0 0 10\n0 1 0 0\n0 0 1 0\n2 1 1 2 1 0\n";

    #[test]
    fn composed_records_apply_their_first_pair_first() {
        // OCCT writes `box.Moved(rotation).Moved(translation)` as `2 1 1 2 1 0`: the
        // rotation first, then the translation.
        let locs = read(ROT_Z90_AND_MOVE_X10).unwrap();
        let l = locs.number(3).unwrap();
        let p = locs.trsf(l).unwrap().point(Point3::new(1.0, 2.0, 3.0));
        assert_eq!(p, Point3::new(8.0, 1.0, 3.0));
    }

    #[test]
    fn products_reduce_like_occt_so_equal_locations_are_equal_ids() {
        let mut locs = read(ROT_Z90_AND_MOVE_X10).unwrap();
        let (a, b, ab) = (
            locs.number(1).unwrap(),
            locs.number(2).unwrap(),
            locs.number(3).unwrap(),
        );
        assert_eq!(locs.mul(b, a).unwrap(), ab);
        let ia = locs.inv(a).unwrap();
        assert_eq!(locs.mul(ab, ia).unwrap(), b);
        let ib = locs.inv(b).unwrap();
        let back = locs.mul(ib, ab).unwrap();
        assert_eq!(back, a);
        assert_eq!(locs.pow(a, 4).unwrap(), locs.pow(a, 4).unwrap());
        let a4 = locs.pow(a, 4).unwrap();
        let t = locs.trsf(a4).unwrap().point(Point3::new(1.0, 2.0, 3.0));
        assert!((t[0] - 1.0).abs() < 1e-12 && (t[1] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn mirrors_and_scalings_are_marked_bad_records_refused() {
        let locs =
            read("Locations 2\n1\n-1 0 0 0\n0 1 0 0\n0 0 1 0\n1\n2 0 0 0\n0 2 0 0\n0 0 2 0\n")
                .unwrap();
        let e = locs.trsf(locs.number(1).unwrap()).unwrap_err();
        assert_eq!(e.kind, OcctErrorKind::Unsupported);
        assert!(e.message.contains("mirror"), "{e}");
        assert!(locs.trsf(2).unwrap_err().message.contains("scaling by 2"));
        let e = read("Locations 2\n1\n0 0 0 0\n0 0 0 0\n0 0 0 0\n")
            .err()
            .unwrap();
        assert!(
            e.message.starts_with("line 2: Locations[1]: singular"),
            "{e}"
        );
        let e = read("Locations 1\n2 1 1 0\n").err().unwrap();
        assert_eq!(
            e.message,
            "line 2: Locations[1]: location 1 out of range 1..0"
        );
    }
}
