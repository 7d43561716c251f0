//! A study of the connectivity contexts (tests only): every split's coarse simplices and their
//! masks are recorded while a mesh compresses, then candidate context designs are costed on the
//! records with adaptive binary models (the Krichevsky–Trofimov estimator per context), the way
//! an adaptive coder pays for its contexts, learning included. Run:
//! `cargo test --release -p tessd-codec connectivity_study -- --ignored --nocapture`.

use std::cell::RefCell;
use std::collections::HashMap;

use crate::complex::{Complex, POINT, Simplex, Vertex};
use crate::kd_cell::half;

/// One split as the encoder coded it.
#[derive(Clone, Debug)]
pub(crate) struct Split {
    level: usize,
    bits: u32,
    v: u32,
    corner: [u32; 3],
    coded: Vec<(Simplex, u8)>,
    /// The other vertices of the coarse simplices, as the decoder holds them.
    verts: Vec<(u32, Vertex)>,
}

thread_local! {
    static RESET: RefCell<bool> = const { RefCell::new(false) };
    static RECORD: RefCell<Option<Vec<Split>>> = const { RefCell::new(None) };
}

/// Records a split when recording is on (called by `code_connectivity`).
pub(crate) fn record(cx: &Complex, v: u32, level: usize, bits: u32, coded: &[(Simplex, u8)]) {
    RECORD.with(|r| {
        if let Some(rec) = r.borrow_mut().as_mut() {
            let mut verts: Vec<(u32, Vertex)> = Vec::new();
            for (s, _) in coded {
                for &x in &s.v {
                    if x != v && !verts.iter().any(|&(y, _)| y == x) {
                        verts.push((x, cx.vertices[x as usize]));
                    }
                }
            }
            rec.push(Split {
                level,
                bits,
                v,
                corner: cx.vertices[v as usize].corner,
                coded: coded.to_vec(),
                verts,
            });
        }
    });
}

/// Adaptive binary costs by (family, context).
#[derive(Default)]
struct Cost {
    counts: HashMap<(u8, u64), [u32; 2]>,
    bits: [f64; 6],
    /// bits and symbols by (family, tag) for diagnostics
    tagged: std::collections::BTreeMap<(u8, String), (f64, u64)>,
    tag: String,
}

impl Cost {
    fn bit(&mut self, fam: u8, ctx: u64, b: bool) {
        let c = self.counts.entry((fam, ctx)).or_insert([0, 0]);
        let p = (c[b as usize] as f64 + 0.4) / ((c[0] + c[1]) as f64 + 0.8);
        self.bits[fam as usize] -= p.log2();
        c[b as usize] += 1;
        self.tagged.entry((fam, self.tag.clone())).or_default().0 -= p.log2();
    }

    /// A three-valued symbol: "both?", then "which".
    fn three(&mut self, fam: u8, ctx: u64, value: u8) {
        self.bit(fam, ctx * 2, value == 2);
        if value != 2 {
            self.bit(fam, ctx * 2 + 1, value == 1);
        }
    }

    /// A mask of four candidates (1..=15): its bits in turn, each in the context of those before.
    fn mask(&mut self, fam: u8, ctx: u64, mask: u8) {
        let mut prefix = 1u64;
        for i in 0..4 {
            let b = mask >> i & 1 != 0;
            // the last bit is forced when the others are all zero
            if !(i == 3 && prefix == 8) {
                self.bit(fam, ctx * 16 + prefix, b);
            }
            prefix = prefix * 2 + b as u64;
        }
    }
}

/// Geometry of one split, in half-grid units along the split axis.
struct Geo<'a> {
    s: &'a Split,
    ax: usize,
    plane2: i64,
    h2: i64,
}

impl Geo<'_> {
    fn vert(&self, x: u32) -> Vertex {
        self.s.verts.iter().find(|&&(y, _)| y == x).unwrap().1
    }
    /// Centre's signed offset from the plane, half-grid units.
    fn off(&self, x: u32) -> i64 {
        let w = self.vert(x);
        2 * w.corner[self.ax] as i64 + w.extent(self.ax, self.s.bits) as i64 - 1 - self.plane2
    }
    fn class(&self, x: u32) -> u8 {
        let c = self.off(x);
        let e = self.vert(x).extent(self.ax, self.s.bits) as i64;
        let (lo, hi) = (c - e, c + e);
        if hi <= 0 {
            if hi > -self.h2 { 1 } else { 0 }
        } else if lo >= 0 {
            if lo < self.h2 { 4 } else { 5 }
        } else if c < 0 {
            2
        } else {
            3
        }
    }
    fn corner_side(&self, x: u32) -> bool {
        2 * self.vert(x).corner[self.ax] as i64 >= self.plane2
    }
}

fn others(c: &Simplex, v: u32) -> (u32, u32) {
    let i = c.v.iter().position(|&x| x == v).unwrap();
    (c.v[(i + 1) % 3], c.v[(i + 2) % 3])
}

/// The value of a once-held mask given the predicted child (`flip` = high).
fn once_value(mask: u8, flip: bool) -> u8 {
    match mask {
        3 => 2,
        m => u8::from((m == 2) != flip),
    }
}

fn swap_children(mask: u8) -> u8 {
    ((mask & 1) << 3) | ((mask & 8) >> 3) | ((mask & 2) << 1) | ((mask & 4) >> 1)
}

/// Everything a design may look at for one once-held triangle, from the decoder's state.
#[derive(Clone, Copy, Debug)]
struct OnceFeat {
    la: u8,
    lb: u8,
    pa: bool,
    pb: bool,
    sa: bool,
    sb: bool,
    /// midpoint offset of a and b from the plane, in units of the child's half side / 4
    mid: i64,
    far: bool,
    level: usize,
    n_once: usize,
    /// a once-held triangle coded before went to both children
    both_so_far: bool,
    /// once-held fine triangles of each child so far, and once-held triangles left to code
    ncs: [usize; 2],
    left: usize,
    /// once-held fine triangles of each child holding a, b
    na: [usize; 2],
    nb: [usize; 2],
    /// where a and b lie from the plane: 0 below and away, 1 below and touching, 2 straddling
    /// with the centre below, 3 straddling with the centre above, 4 above touching, 5 above away
    ca: u8,
    cb: u8,
    /// per child: c→x minus x→c over the once-held fine triangles so far, for a and b
    da: [i32; 2],
    db: [i32; 2],
    /// links of a and b from twice-held triangles coded before (twice-first designs)
    ta: u8,
    tb: u8,
}

/// Runs the once/twice/thrice codes of one split through `design`.
#[allow(clippy::type_complexity)]
fn run(
    s: &Split,
    cost: &mut Cost,
    once_ctx: &dyn Fn(&OnceFeat) -> (u64, bool),
    twice_ctx: &dyn Fn(&TwiceFeat) -> (u64, bool),
    thrice_ctx: &dyn Fn(&ThriceFeat) -> u64,
    twice_first: bool,
) {
    let ax = s.level % 3;
    let h = half(s.level, s.bits) as i64;
    let g = Geo {
        s,
        ax,
        plane2: 2 * (s.corner[ax] as i64 + h),
        h2: 2 * h,
    };
    let v = s.v;
    let mut once: Vec<(Simplex, u8)> = Vec::new();
    let mut twice: Vec<(Simplex, u8)> = Vec::new();
    let mut thrice: Vec<(Simplex, u8)> = Vec::new();
    for &(c, m) in &s.coded {
        if c.kind == POINT {
            cost.three(4, s.level as u64 / 3, once_value(m, false));
            // slot 5: the same with "the point is alone in the star" (then both children need it)
            let alone = u64::from(s.coded.len() == 1);
            cost.three(5, s.level as u64 / 3 * 2 + alone, once_value(m, false));
            continue;
        }
        match c.multiplicity(v) {
            1 => once.push((c, m)),
            2 => twice.push((c, m)),
            _ => thrice.push((c, m)),
        }
    }
    let pivots: Vec<u32> = twice
        .iter()
        .map(|(c, _)| *c.v.iter().find(|&&x| x != v).unwrap())
        .collect();
    let mut link: HashMap<u32, u8> = HashMap::new();
    let mut fine: Vec<Simplex> = Vec::new();
    // per other vertex: v1→x minus x→v1, and v2→x minus x→v2, over the once-held fine triangles
    let mut dir: HashMap<u32, [i32; 2]> = HashMap::new();
    let mut nc = [0usize; 2];
    let mut nx: HashMap<u32, [usize; 2]> = HashMap::new();
    let v2 = u32::MAX;
    let mut any_both = false;
    let (mut cl, mut ch) = (false, false);
    // links from the twice-held triangles, when they are coded first
    let mut tlink: HashMap<u32, u8> = HashMap::new();
    let mut code_twice = |cost: &mut Cost,
                          dir: &HashMap<u32, [i32; 2]>,
                          nc: [usize; 2],
                          nx: &HashMap<u32, [usize; 2]>,
                          link: &HashMap<u32, u8>,
                          fine: &[Simplex],
                          any_both: bool,
                          tlink: &mut HashMap<u32, u8>| {
        for &(c, m) in &twice {
            let x = *c.v.iter().find(|&&x| x != v).unwrap();
            let f = TwiceFeat {
                lx: link.get(&x).copied().unwrap_or(0),
                ev: orientation_evidence(fine, v, v2, x),
                d: dir.get(&x).copied().unwrap_or([0, 0]),
                seen: [cl, ch],
                nx: nx.get(&x).copied().unwrap_or([0, 0]),
                nc,
                vvv: !thrice.is_empty(),
                any_both,
                level: s.level,
                n_once: once.len(),
                n_twice: twice.len(),
                xq: (g.off(x) * 4).div_euclid(g.h2),
            };
            let (ctx, flip) = twice_ctx(&f);
            cost.tag = format!(
                "p{:02} l{}{} m{:02}",
                s.level / 3,
                f.lx,
                f.ev,
                if flip { swap_children(m) } else { m }
            );
            cost.tagged.entry((8, cost.tag.clone())).or_default().1 += 1;
            cost.mask(2, ctx, if flip { swap_children(m) } else { m });
            cl |= m & 1 != 0;
            ch |= m & 8 != 0;
            let t = if m & 6 != 0 {
                3
            } else {
                (m & 1) | ((m >> 2) & 2)
            };
            *tlink.entry(x).or_insert(0) |= t;
        }
    };
    if twice_first {
        code_twice(cost, &dir, nc, &nx, &link, &fine, false, &mut tlink);
    }
    for (done, &(c, m)) in once.iter().enumerate() {
        let (a, b) = others(&c, v);
        let la = link.get(&a).copied().unwrap_or(0);
        let lb = link.get(&b).copied().unwrap_or(0);
        let far = |x: u32| g.off(x).abs() >= g.h2 + g.vert(x).extent(ax, s.bits) as i64;
        let f = OnceFeat {
            la,
            lb,
            pa: pivots.contains(&a),
            pb: pivots.contains(&b),
            sa: g.corner_side(a),
            sb: g.corner_side(b),
            mid: ((g.off(a) + g.off(b)) * 4).div_euclid(2 * g.h2),
            far: far(a) && far(b),
            level: s.level,
            n_once: once.len(),
            both_so_far: any_both,
            ncs: nc,
            na: nx.get(&a).copied().unwrap_or([0, 0]),
            nb: nx.get(&b).copied().unwrap_or([0, 0]),
            left: once.len() - done,
            ca: g.class(a),
            cb: g.class(b),
            da: dir.get(&a).copied().unwrap_or([0, 0]),
            db: dir.get(&b).copied().unwrap_or([0, 0]),
            ta: tlink.get(&a).copied().unwrap_or(0),
            tb: tlink.get(&b).copied().unwrap_or(0),
        };
        let (ctx, flip) = once_ctx(&f);
        cost.tag = format!(
            "p{:02} e{}{} piv{}{} mid{:+}",
            s.level / 3,
            la.max(lb),
            la.min(lb),
            u8::from(f.pa),
            u8::from(f.pb),
            f.mid.clamp(-5, 5)
        );
        cost.three(1, ctx, once_value(m, flip));
        cost.tagged.entry((9, cost.tag.clone())).or_default().1 += 1;
        *link.entry(a).or_insert(0) |= m;
        *link.entry(b).or_insert(0) |= m;
        any_both |= m == 3;
        if m & 1 != 0 {
            fine.push(Simplex::triangle(v, a, b));
            dir.entry(a).or_default()[0] += 1;
            nx.entry(a).or_default()[0] += 1;
            nx.entry(b).or_default()[0] += 1;
            nc[0] += 1;
            dir.entry(b).or_default()[0] -= 1;
        }
        if m & 2 != 0 {
            fine.push(Simplex::triangle(v2, a, b));
            dir.entry(a).or_default()[1] += 1;
            nx.entry(a).or_default()[1] += 1;
            nx.entry(b).or_default()[1] += 1;
            nc[1] += 1;
            dir.entry(b).or_default()[1] -= 1;
        }
    }
    if !twice_first {
        code_twice(cost, &dir, nc, &nx, &link, &fine, any_both, &mut tlink);
    }
    let bridged = twice.iter().any(|&(_, m)| m & 6 != 0);
    for &(_, m) in &thrice {
        let f = ThriceFeat {
            nc,
            cl,
            ch,
            any_both,
            level: s.level,
            n_twice: twice.len(),
        };
        cost.mask(3, thrice_ctx(&f), m);
        // slot 0: the same with a fine (v1, v2, x) or (v2, v1, x) coded before
        cost.mask(0, thrice_ctx(&f) * 2 + u64::from(bridged), m);
    }
}

#[derive(Clone, Copy, Debug)]
struct TwiceFeat {
    lx: u8,
    ev: i32,
    vvv: bool,
    any_both: bool,
    level: usize,
    n_once: usize,
    n_twice: usize,
    /// the third vertex's centre from the plane, in quarters of a child's side
    xq: i64,
    /// v1→x minus x→v1 and v2→x minus x→v2 over the once-held fine triangles
    d: [i32; 2],
    /// (v1, v1, ·) and (v2, v2, ·) among the twice-held triangles coded before
    seen: [bool; 2],
    /// once-held fine triangles of each child
    nc: [usize; 2],
    /// once-held fine triangles of each child holding x
    nx: [usize; 2],
}

#[derive(Clone, Copy, Debug)]
struct ThriceFeat {
    /// once-held fine triangles of each child
    nc: [usize; 2],
    cl: bool,
    ch: bool,
    any_both: bool,
    level: usize,
    n_twice: usize,
}

fn orientation_evidence(once: &[Simplex], v1: u32, v2: u32, x: u32) -> i32 {
    let (mut e12, mut e21) = (0i32, 0i32);
    for t in once.iter().filter(|t| t.v.contains(&x)) {
        for i in 0..3 {
            let (a, b) = (t.v[i], t.v[(i + 1) % 3]);
            if (a == x && b == v2) || (a == v1 && b == x) {
                e12 += 1;
            }
            if (a == x && b == v1) || (a == v2 && b == x) {
                e21 += 1;
            }
        }
    }
    (e12 - e21).signum()
}

fn today_once(f: &OnceFeat) -> (u64, bool) {
    let e = f.la | f.lb;
    let flip = if e == 1 || e == 2 { e == 2 } else { f.sa };
    let same = f.sa == f.sb;
    let geometry_agrees = f.sa == flip;
    let remote = usize::from(f.far);
    let sub = match e {
        0 => usize::from(same) * 2 + remote,
        3 => 4 + usize::from(same) * 2 + remote,
        _ => {
            8 + usize::from(f.la == f.lb) * 4 + usize::from(same) * 2 + usize::from(geometry_agrees)
        }
    };
    ((sub * 64 + f.level / 3) as u64, flip)
}

fn today_twice(f: &TwiceFeat) -> (u64, bool) {
    let flip = f.lx == 2 || (f.lx != 1 && f.ev < 0);
    let ev = if flip { -f.ev } else { f.ev };
    let lx = if f.lx == 2 { 1 } else { f.lx.min(3) };
    let sub = [0, 1, 0, 2][lx as usize] * 3 + (ev + 1) as usize;
    ((sub * 64 + f.level / 3) as u64, flip)
}

fn today_thrice(f: &ThriceFeat) -> u64 {
    ((usize::from(f.cl) * 2 + usize::from(f.ch)) * 64 + f.level / 3) as u64
}

/// The first single link decides the predicted child, else the midpoint's side.
fn pred(f: &OnceFeat) -> bool {
    if f.la == 1 || f.la == 2 {
        f.la == 2
    } else if f.lb == 1 || f.lb == 2 {
        f.lb == 2
    } else {
        f.mid >= 0
    }
}

/// A link relative to the predicted child: none, it, the other, both.
fn rel(l: u8, flip: bool) -> u64 {
    match l {
        0 => 0,
        3 => 3,
        l => 1 + u64::from((l == 2) != flip),
    }
}

fn mid_band(f: &OnceFeat, flip: bool) -> u64 {
    crate::coding::midpoint_band(f.mid, flip) as u64
}

fn rich(f: &OnceFeat, lvl: u64) -> (u64, bool) {
    let flip = pred(f);
    let x = (rel(f.la, flip), u64::from(f.pa));
    let y = (rel(f.lb, flip), u64::from(f.pb));
    let (x, y) = if x >= y { (x, y) } else { (y, x) };
    let sub = ((x.0 * 2 + x.1) * 8 + y.0 * 2 + y.1) * 6 + mid_band(f, flip);
    (sub * 64 + lvl, flip)
}

fn load(path: &str, bits: u32, min_cell: u64) -> (Vec<Split>, f64) {
    let params = crate::Params {
        bits,
        min_cell,
        ..crate::Params::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let mut src = crate::source::open(std::path::Path::new(path)).expect("a mesh");
        RECORD.with(|r| *r.borrow_mut() = Some(Vec::new()));
        let mut out = std::io::Cursor::new(Vec::new());
        let rep = crate::compress_source(&mut *src, params, &mut out, &|_| true).unwrap();
        let mut rec = RECORD.with(|r| r.borrow_mut().take().unwrap());
        rec.reverse();
        (rec, rep.vertices as f64)
    })
}

type Design<'a> = (
    &'a str,
    bool,
    &'a dyn Fn(&OnceFeat) -> (u64, bool),
    &'a dyn Fn(&TwiceFeat) -> (u64, bool),
    &'a dyn Fn(&ThriceFeat) -> u64,
);

fn report(name: &str, splits: &[Split], nv: f64, designs: &[Design], diag: bool) {
    for (dn, first, o, t, th) in designs {
        let mut cost = Cost::default();
        let mut last = 0;
        for s in splits {
            if RESET.with(|r| *r.borrow()) && s.level < last {
                cost.counts.clear();
            }
            last = s.level;
            run(s, &mut cost, *o, *t, *th, *first);
        }
        let b = cost.bits.map(|x| x / nv);
        println!(
            "{name:<28} {dn:<16} once {:6.3} twice {:6.3} thrice {:6.3} point {:5.3} conn {:6.3}  ctx {} | thrice+bridged {:6.3} point+alone {:5.3}",
            b[1],
            b[2],
            b[3],
            b[4],
            b[1] + b[2] + b[3] + b[4],
            cost.counts.len(),
            b[0],
            b[5]
        );
        if diag {
            // group the tags by one field at a time
            for (fam, fields) in [(1u8, 0..4), (2u8, 0..3)] {
                for field in fields {
                    let mut by: std::collections::BTreeMap<String, (f64, u64)> = Default::default();
                    for ((f, tag), &(b, _)) in &cost.tagged {
                        if *f != fam {
                            continue;
                        }
                        let n = cost
                            .tagged
                            .get(&(if fam == 1 { 9 } else { 8 }, tag.clone()))
                            .map_or(0, |x| x.1);
                        let key = tag.split(' ').nth(field).unwrap().to_string();
                        let e = by.entry(key).or_default();
                        e.0 += b;
                        e.1 += n;
                    }
                    for (k, (b, n)) in by {
                        println!(
                            "    {k:<8} {:7.3} b/v {:8} sym {:6.3} b/sym",
                            b / nv,
                            n,
                            b / n as f64
                        );
                    }
                }
            }
        }
    }
}

#[test]
#[ignore]
fn connectivity_study() {
    let m = tessd_testdata::shared("mesh");
    let m = m.display();
    let reset = std::env::var("RESET").is_ok();
    RESET.with(|r| *r.borrow_mut() = reset);
    let meshes = [
        (format!("{m}/bun_zipper.ply"), 8000),
        (format!("{m}/bun_zipper.ply"), 80000),
        (format!("{m}/fandisk.obj"), 8000),
        (format!("{m}/spot_triangulated.obj"), 8000),
    ];
    // once-held: level/3 as today, four bands of precision (kept), and with the star's size
    let o1 = |f: &OnceFeat| rich(f, f.level as u64 / 3);
    let o2 = |f: &OnceFeat| rich(f, (f.level / 3).clamp(4, 7) as u64);
    let o3 = |f: &OnceFeat| {
        rich(
            f,
            (f.level / 3).clamp(4, 7) as u64 * 4 + f.n_once.min(15) as u64 / 4,
        )
    };
    // twice-held: today's, with (v, v, v) and "some once-held was both", level banded
    let t1 = |f: &TwiceFeat| {
        let (c, flip) = today_twice(f);
        (c * 4 + u64::from(f.vvv) * 2 + u64::from(f.any_both), flip)
    };
    let t2 = |f: &TwiceFeat| {
        let (c, flip) = today_twice(&TwiceFeat { level: 0, ..*f });
        let band = (f.level / 3).clamp(4, 7) as u64;
        (
            c * 64 + band * 4 + u64::from(f.vvv) * 2 + u64::from(f.any_both),
            flip,
        )
    };
    let t3 = |f: &TwiceFeat| {
        let (c, flip) = t2(f);
        (
            c * 4 + f.n_twice.min(7) as u64 / 2 + if f.n_once > 2 * f.n_twice { 4 } else { 0 },
            flip,
        )
    };
    let h1 = |f: &ThriceFeat| today_thrice(f) * 2 + u64::from(f.any_both);
    let h2 = |f: &ThriceFeat| {
        let band = (f.level / 3).clamp(4, 7) as u64;
        ((u64::from(f.cl) * 2 + u64::from(f.ch)) * 2 + u64::from(f.any_both)) * 4 + band
    };
    let h3 = |f: &ThriceFeat| h2(f) * 4 + f.n_twice.min(7) as u64 / 2;
    let xband = |q: i64, flip: bool| {
        let m = if flip { q } else { -1 - q };
        match m {
            ..=-5 => 0,
            -4..=-1 => 1,
            0..=3 => 2,
            _ => 3,
        }
    };
    let t4 = |f: &TwiceFeat| {
        let flip = f.lx == 2 || (f.lx != 1 && (f.ev < 0 || (f.ev == 0 && f.xq >= 0)));
        let (c, _) = today_twice(f);
        (
            (c * 4 + u64::from(f.vvv) * 2 + u64::from(f.any_both)) * 4 + xband(f.xq, flip),
            flip,
        )
    };
    // twice first: geometry of x only
    let tf = |f: &TwiceFeat| {
        let flip = f.xq >= 0;
        let band = (f.level / 3).clamp(4, 7) as u64 - 4;
        (
            ((band * 2 + u64::from(f.vvv)) * 4 + xband(f.xq, flip)) * 4 + f.n_twice.min(3) as u64,
            flip,
        )
    };
    let of = |f: &OnceFeat| {
        let flip = match (f.la, f.lb, f.ta, f.tb) {
            (1 | 2, _, _, _) => f.la == 2,
            (_, 1 | 2, _, _) => f.lb == 2,
            (_, _, 1 | 2, _) => f.ta == 2,
            (_, _, _, 1 | 2) => f.tb == 2,
            _ => f.mid >= 0,
        };
        let x = rel(f.la, flip) * 4 + rel(f.ta, flip);
        let y = rel(f.lb, flip) * 4 + rel(f.tb, flip);
        let (x, y) = (x.max(y), x.min(y));
        let band = (f.level / 3).clamp(4, 7) as u64 - 4;
        (
            ((x * (x + 1) / 2 + y) * 6 + mid_band(f, flip)) * 4 + band,
            flip,
        )
    };
    // twice: the unmatched directed edges of each child with x, and its links, made symmetric
    let t5 = |f: &TwiceFeat, geo: bool| {
        let st = |d: i32, l: u8| (d.signum() + 1) as u64 * 2 + u64::from(l != 0);
        let (s1, s2) = (st(f.d[0], f.lx & 1), st(f.d[1], f.lx & 2));
        let flip = s2 > s1 || (s1 == s2 && geo && f.xq >= 0);
        let (hi, lo) = (s1.max(s2), s1.min(s2));
        let sub = ((hi * 6 + lo) * 2 + u64::from(f.vvv)) * 2 + u64::from(f.any_both);
        let sub = if geo {
            sub * 4 + xband(f.xq, flip)
        } else {
            sub
        };
        (sub * 64 + f.level as u64 / 3, flip)
    };
    let t5a = |f: &TwiceFeat| t5(f, false);
    let t5b = |f: &TwiceFeat| t5(f, true);
    // once: how many unmatched directed edges the triangle (c, a, b) would close for each child c
    // (it holds c→a and b→c) minus how many it would double
    let od = |f: &OnceFeat, lvl: bool| {
        let (c, flip) = rich(f, (f.level / 3).clamp(4, 7) as u64);
        let score = |k: usize| {
            i32::from(f.da[k] < 0) + i32::from(f.db[k] > 0)
                - i32::from(f.da[k] > 0)
                - i32::from(f.db[k] < 0)
        };
        let (p, o) = if flip {
            (score(1), score(0))
        } else {
            (score(0), score(1))
        };
        let sc = (p - o).clamp(-2, 2) + 2;
        let c = if lvl {
            c
        } else {
            c / 64 * 64 + (f.level / 3).clamp(4, 7) as u64
        };
        (c * 5 + sc as u64, flip)
    };
    let od1 = |f: &OnceFeat| od(f, true);
    // once: per-vertex classes instead of the midpoint band
    let oc = |f: &OnceFeat, joint: bool| {
        let flip = pred(f);
        let cl = |c: u8| if flip { c as u64 } else { 5 - c as u64 };
        let x = (rel(f.la, flip) * 2 + u64::from(f.pa), cl(f.ca));
        let y = (rel(f.lb, flip) * 2 + u64::from(f.pb), cl(f.cb));
        let band = (f.level / 3).clamp(4, 7) as u64;
        let sub = if joint {
            let (x, y) = (x.0 * 6 + x.1, y.0 * 6 + y.1);
            let (x, y) = (x.max(y), x.min(y));
            x * (x + 1) / 2 + y
        } else {
            let (p, q) = (x.0.max(y.0), x.0.min(y.0));
            let (c, d) = (x.1.max(y.1), x.1.min(y.1));
            (p * (p + 1) / 2 + q) * 21 + c * (c + 1) / 2 + d
        };
        (sub * 64 + band, flip)
    };
    let oc1 = |f: &OnceFeat| oc(f, true);
    let oc2 = |f: &OnceFeat| oc(f, false);
    let t6 = |f: &TwiceFeat, which: u8| {
        let (c, flip) = today_twice(f);
        let (p, o) = if flip { (1, 0) } else { (0, 1) };
        let seen = u64::from(f.seen[p]) * 2 + u64::from(f.seen[o]);
        let r = |n: usize| match n {
            0 => 0,
            1..=2 => 1,
            3..=5 => 2,
            _ => 3,
        };
        let cnt = r(f.nc[p]) * 4 + r(f.nc[o]);
        let extra = match which {
            0 => seen,
            3 => {
                if f.lx == 3 {
                    seen
                } else {
                    0
                }
            }
            4 => u64::from(f.seen[p] || f.seen[o]),
            1 => cnt,
            _ => seen * 16 + cnt,
        };
        (
            (c * 4 + u64::from(f.vvv) * 2 + u64::from(f.any_both)) * 64 + extra,
            flip,
        )
    };
    let t6a = |f: &TwiceFeat| t6(f, 0);
    let t6b = |f: &TwiceFeat| t6(f, 1);
    let t6c = |f: &TwiceFeat| t6(f, 2);
    let t6d = |f: &TwiceFeat| t6(f, 3);
    let t6e = |f: &TwiceFeat| t6(f, 4);
    let ob = |f: &OnceFeat| {
        let (c, flip) = rich(f, (f.level / 3).clamp(4, 7) as u64);
        (c * 2 + u64::from(f.both_so_far), flip)
    };
    let obd = |f: &OnceFeat| {
        let (c, flip) = od(f, true);
        (c * 2 + u64::from(f.both_so_far), flip)
    };
    let on = |f: &OnceFeat, which: u8| {
        let (c, flip) = od(f, true);
        let (p, o) = if flip { (1, 0) } else { (0, 1) };
        let x = match which {
            0 => u64::from(f.ncs[p] > 0) * 2 + u64::from(f.ncs[o] > 0),
            1 => u64::from(f.ncs[o] == 0) * 2 + u64::from(f.left == 1),
            _ => {
                u64::from(f.ncs[o] == 0 && f.left == 1)
                    + 2 * u64::from(f.ncs[p] == 0 && f.left == 1)
            }
        };
        (c * 4 + x, flip)
    };
    let on0 = |f: &OnceFeat| on(f, 0);
    let on1 = |f: &OnceFeat| on(f, 1);
    let on2 = |f: &OnceFeat| on(f, 2);
    let t7 = |f: &TwiceFeat| {
        let (c, flip) = t6(f, 3);
        let (p, o) = if flip { (1, 0) } else { (0, 1) };
        let r = |n: usize| n.min(3) as u64;
        let x = if f.lx == 3 {
            r(f.nx[p]) * 4 + r(f.nx[o])
        } else {
            0
        };
        (c * 16 + x, flip)
    };
    let onx = |f: &OnceFeat| {
        let (c, flip) = on(f, 0);
        let (p, o) = if flip { (1, 0) } else { (0, 1) };
        let r = |n: usize| n.min(3) as u64;
        (
            c * 16 + r(f.na[p] + f.nb[p]) * 4 + r(f.na[o] + f.nb[o]),
            flip,
        )
    };
    let h4 = |f: &ThriceFeat| {
        let r = |n: usize| (n.min(11) / 4) as u64;
        h3(f) * 9 + r(f.nc[0]).max(r(f.nc[1])) * 3 + r(f.nc[0]).min(r(f.nc[1]))
    };
    let designs: Vec<Design> = vec![
        ("thrice nc", false, &on0, &t7, &h4),
        ("once nx", false, &onx, &t7, &h3),
        ("twice nx (kept)", false, &on0, &t7, &h3),
        ("once cov", false, &on0, &t6d, &h3),
        ("once cov", false, &on0, &t6d, &h3),
        ("once unc last", false, &on1, &t6d, &h3),
        ("once forced", false, &on2, &t6d, &h3),
        ("once both", false, &ob, &t6d, &h1),
        ("once both dir", false, &obd, &t6d, &h1),
        ("once dir t6l3", false, &od1, &t6d, &h1),
        ("once dir t6l3 h3", false, &od1, &t6d, &h3),
        ("t6 seen l3", false, &o2, &t6d, &h1),
        ("t6 seen any", false, &o2, &t6e, &h1),
        ("t6 seen", false, &o2, &t6a, &h1),
        ("t6 cnt", false, &o2, &t6b, &h1),
        ("t6 both", false, &o2, &t6c, &h1),
        ("once cls joint", false, &oc1, &t5a, &h1),
        ("once cls sep", false, &oc2, &t5a, &h1),
        ("once dir", false, &od1, &t5a, &h1),
        ("t5", false, &o2, &t5a, &h1),
        ("t5 geo", false, &o2, &t5b, &h1),
        ("today", false, &today_once, &today_twice, &today_thrice),
        ("once p", false, &o1, &t1, &h1),
        ("once p4-7", false, &o2, &t1, &h1),
        ("+n t2 h2", false, &o3, &t2, &h2),
        ("t3 h3", false, &o2, &t3, &h3),
        ("t4", false, &o2, &t4, &h1),
        ("twice first", true, &of, &tf, &h1),
    ];
    for (path, mc) in &meshes {
        let (splits, nv) = load(path, 12, *mc);
        let name = format!("{}/{mc}", path.rsplit('/').next().unwrap());
        report(
            &name,
            &splits,
            nv,
            &designs,
            mc == &8000 && path.contains("bun"),
        );
    }
}
