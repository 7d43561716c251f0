//! Feeds bytes to the codec's decoder as a `.tsc` file held in memory: `Tsc::open` (head,
//! trailer, index), a full decode (`decode(None)`), a coarser prefix
//! (`decode(Some(bits))`, the bits taken from the input's last byte) and a view-dependent decode
//! (`ViewSession::view`) from a fixed camera: three box diagonals from the grid's centre,
//! looking at it, 1280×720, 30°, one pixel.
//!
//! Must hold: no panic, no hang, no runaway allocation (a corrupt file is a `CodecError`); a
//! decode gives one corner per position, triangles and isolated vertices that index them, at
//! most the bits asked; a view's triangles index its positions.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::Arc;
use tessd_codec::{Camera, Decoded, Tsc, ViewSession};

fn check(d: &Decoded, max_bits: u32) {
    assert!(d.bits <= max_bits);
    assert_eq!(d.corners.len(), d.positions.len());
    let n = d.positions.len() as u64;
    assert!(d.triangles.iter().flatten().all(|&v| (v as u64) < n));
    assert!(d.isolated.iter().all(|&v| (v as u64) < n));
}

fuzz_target!(|data: &[u8]| {
    let Ok(tsc) = Tsc::open(data) else {
        return;
    };
    let p = tsc.header.params.bits;
    if let Ok(d) = tsc.decode(None) {
        check(&d, p);
    }
    let bits = u32::from(*data.last().unwrap_or(&0)) % (p + 1);
    if let Ok(d) = tsc.decode(Some(bits)) {
        check(&d, bits);
    }
    let grid = &tsc.header.grid;
    let side = grid.step * (1u64 << p.min(62)) as f64;
    let centre = grid.origin.map(|o| o + side / 2.0);
    let eye = [
        centre[0] + 3.0 * side,
        centre[1] + 3.0 * side,
        centre[2] + 3.0 * side,
    ];
    let camera = Camera {
        eye,
        target: centre,
        up: [0.0, 0.0, 1.0],
        fov: 30.0,
        width: 1280,
        height: 720,
    };
    let mut session = ViewSession::new(Arc::new(tsc));
    if let Ok(v) = session.view(&camera, 1.0) {
        let n = v.positions.len() as u64;
        assert!(v.triangles.iter().flatten().all(|&i| (i as u64) < n));
    }
});
