//! Crack detection (paper 001 §3.2, `shaders/crack_detect.wgsl`) and image-space crack filling
//! (§3.3, `shaders/image_fill.wgsl`) on synthetic frames made on the CPU, whose expected flags
//! and fills follow from how they are built: two faces with a background gap between them,
//! a lone disk (silhouette only), an occlusion contour, one face's steep valley (same-face
//! exclusion), a far face seen through a gap (d_min), and fills with no usable neighbour.
//!
//! Runs on whatever adapter wgpu finds; in CI that is lavapipe. No adapter is a failure, not a
//! skip.

use std::sync::OnceLock;

use tessd_gpu::GpuContext;
use tessd_render::Frame;
use tessd_render::crack_detect::{CrackDetectPass, count_flags};
use tessd_render::frame_buffers::{CRACK, FILLED, FrameBuffers};
use tessd_render::image_fill::ImageFillPass;

struct Fixture {
    gpu: GpuContext,
    detect: CrackDetectPass,
    fill: ImageFillPass,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let gpu = GpuContext::open("tessd-render crack_fill test")
            .unwrap_or_else(|e| panic!("no GPU for the crack tests: {e}"));
        println!("adapter: {}", gpu.describe());
        let detect = CrackDetectPass::new(&gpu.device);
        let fill = ImageFillPass::new(&gpu.device);
        Fixture { gpu, detect, fill }
    })
}

/// A frame under construction: background everywhere, then pixels set one by one.
struct Builder(Frame);

impl Builder {
    fn new(width: u32, height: u32) -> Builder {
        let n = (width * height) as usize;
        Builder(Frame {
            width,
            height,
            color: vec![0; 4 * n],
            depth: vec![f32::INFINITY; n],
            face_id: vec![0; n],
            uv: vec![[0.0; 2]; n],
        })
    }

    fn set(&mut self, x: u32, y: u32, face: u32, depth: f32, rgba: [u8; 4]) {
        let i = (y * self.0.width + x) as usize;
        self.0.face_id[i] = face;
        self.0.depth[i] = depth;
        self.0.color[4 * i..4 * i + 4].copy_from_slice(&rgba);
        // (u, v) marks the pixel it came from.
        self.0.uv[i] = [x as f32, y as f32];
    }
}

/// Runs detection (when `d_min` is given) then filling (when `fill`), returning the frame and
/// the flags read back.
fn run(frame: &Frame, flags: Option<&[u32]>, d_min: Option<f32>, fill: bool) -> (Frame, Vec<u32>) {
    let f = fixture();
    let (device, queue) = (&f.gpu.device, &f.gpu.queue);
    let buffers = FrameBuffers::upload(device, frame, flags);
    let mut encoder = device.create_command_encoder(&Default::default());
    if let Some(d) = d_min {
        f.detect.encode(device, &mut encoder, &buffers, d);
    }
    if fill {
        f.fill.encode(device, &mut encoder, &buffers);
    }
    queue.submit([encoder.finish()]);
    buffers.read(device, queue).expect("read back")
}

/// The pixels whose flags have `bit`, as (x, y).
fn flagged(frame: &Frame, flags: &[u32], bit: u32) -> Vec<(u32, u32)> {
    (0..frame.height)
        .flat_map(|y| (0..frame.width).map(move |x| (x, y)))
        .filter(|&(x, y)| flags[(y * frame.width + x) as usize] & bit != 0)
        .collect()
}

const W: u32 = 24;
const H: u32 = 16;
/// The gap column of the two-face frames.
const GAP: u32 = 11;

fn face1_color(y: u32) -> [u8; 4] {
    [100 + 5 * y as u8, 20, 30, 255]
}

fn face2_color(y: u32) -> [u8; 4] {
    [10, 200 - 5 * y as u8, 40, 255]
}

/// Face 1 left of the gap column, face 2 right of it, both near depth 10 with slight gradients
/// (face 2 a little farther, so face 1 wins the ties of the fill); the gap column is
/// `gap(y)`: `None` for the background, or a face and depth.
fn two_faces(gap: impl Fn(u32) -> Option<(u32, f32)>) -> Frame {
    let mut b = Builder::new(W, H);
    for y in 0..H {
        for x in 0..W {
            let slope = 0.001 * x as f32 + 0.002 * y as f32;
            if x < GAP {
                b.set(x, y, 1, 10.0 + slope, face1_color(y));
            } else if x > GAP {
                b.set(x, y, 2, 10.01 + slope, face2_color(y));
            } else if let Some((face, depth)) = gap(y) {
                b.set(x, y, face, depth, [0, 0, 255, 255]);
            }
        }
    }
    b.0
}

fn gap_column() -> Vec<(u32, u32)> {
    (0..H).map(|y| (GAP, y)).collect()
}

#[test]
fn background_gap_between_two_faces_is_flagged_and_filled_from_a_side() {
    let frame = two_faces(|_| None);
    let (_, flags) = run(&frame, None, Some(0.05), false);
    // The horizontal pair stays inside the image on every row, so the whole column is flagged,
    // and nothing else: every other pixel has a same-face neighbour on each side.
    assert_eq!(flagged(&frame, &flags, CRACK), gap_column());
    assert_eq!(count_flags(&flags), (H as usize, 0));

    let (out, flags) = run(&frame, None, Some(0.05), true);
    assert_eq!(count_flags(&flags), (H as usize, H as usize));
    assert_eq!(flagged(&out, &flags, FILLED), gap_column());
    for y in 0..H {
        let i = (y * W + GAP) as usize;
        // Faces 1 and 2 cover equally many neighbours (3 each, 2 on the edge rows); face 1 is
        // nearer, so it is B_p.
        assert_eq!(out.face_id[i], 1, "row {y}");
        let rows: Vec<u32> = (y.saturating_sub(1)..=(y + 1).min(H - 1)).collect();
        let red = rows.iter().map(|&r| face1_color(r)[0] as f32).sum::<f32>() / rows.len() as f32;
        let got = &out.color[4 * i..4 * i + 4];
        assert!(
            (got[0] as f32 - red).abs() <= 1.0,
            "row {y}: {got:?} vs red {red}"
        );
        assert_eq!(&got[1..], &[20, 30, 255], "row {y}");
        let mean = rows
            .iter()
            .map(|&r| 10.0 + 0.001 * (GAP - 1) as f32 + 0.002 * r as f32)
            .sum::<f32>()
            / rows.len() as f32;
        assert!(
            (out.depth[i] - mean).abs() < 1e-5,
            "row {y}: {}",
            out.depth[i]
        );
        // The nearest face-1 neighbour is the one on the row above (depth grows with y).
        assert_eq!(out.uv[i], [(GAP - 1) as f32, rows[0] as f32], "row {y}");
    }
    // Everything else is untouched.
    for i in 0..(W * H) as usize {
        if i % W as usize != GAP as usize {
            assert_eq!(out.face_id[i], frame.face_id[i]);
            assert_eq!(out.depth[i], frame.depth[i]);
            assert_eq!(out.color[4 * i..4 * i + 4], frame.color[4 * i..4 * i + 4]);
            assert_eq!(out.uv[i], frame.uv[i]);
        }
    }
}

#[test]
fn fill_picks_the_face_covering_most_neighbours() {
    // Face 2 farther away but covering 5 of the centre's neighbours, face 1 only 3.
    let mut b = Builder::new(3, 3);
    for y in 0..3 {
        for x in 0..3 {
            if x == 0 {
                b.set(x, y, 1, 5.0, [255, 0, 0, 255]);
            } else {
                b.set(x, y, 2, 20.0 + y as f32, [0, 0, 200, 255]);
            }
        }
    }
    let mut flags = vec![0u32; 9];
    flags[4] = CRACK;
    let (out, flags) = run(&b.0, Some(&flags), None, true);
    assert_eq!(flags[4], CRACK | FILLED);
    assert_eq!(out.face_id[4], 2);
    assert_eq!(&out.color[16..20], &[0, 0, 200, 255]);
    assert!((out.depth[4] - 21.0).abs() < 1e-5, "{}", out.depth[4]);
    assert_eq!(out.uv[4], [1.0, 0.0]);
}

#[test]
fn fill_ties_go_to_the_smaller_id_at_equal_mean_depth() {
    // Faces 7 (left) and 4 (right), 3 neighbours each, same depths: id 4 wins.
    let mut b = Builder::new(3, 3);
    for y in 0..3 {
        b.set(0, y, 7, 10.0, [255, 0, 0, 255]);
        b.set(2, y, 4, 10.0, [0, 255, 0, 255]);
    }
    let mut flags = vec![0u32; 9];
    flags[4] = CRACK;
    let (out, flags) = run(&b.0, Some(&flags), None, true);
    assert_eq!(flags[4], CRACK | FILLED);
    assert_eq!(out.face_id[4], 4);
    assert_eq!(&out.color[16..20], &[0, 255, 0, 255]);
    // Equal depths: the first in ring order, (x+1, y−1).
    assert_eq!(out.uv[4], [2.0, 0.0]);
}

#[test]
fn fill_leaves_pixels_without_usable_neighbours() {
    // A 5×5 frame: the centre 3×3 block all flagged CRACK (covered or not), surrounded by
    // background. The centre pixel's ring is all CRACK, the others see only background or
    // CRACK pixels: nothing is usable, nothing changes.
    let mut b = Builder::new(5, 5);
    b.set(2, 1, 3, 4.0, [9, 9, 9, 255]);
    b.set(1, 2, 3, 4.0, [9, 9, 9, 255]);
    let mut flags = vec![0u32; 25];
    for y in 1..4 {
        for x in 1..4 {
            flags[y * 5 + x] = CRACK;
        }
    }
    let (out, got) = run(&b.0, Some(&flags), None, true);
    assert_eq!(got, flags);
    assert_eq!(out, b.0);
}

#[test]
fn lone_disk_silhouette_is_not_flagged() {
    let mut b = Builder::new(40, 32);
    let (cx, cy, r) = (19.5f32, 15.0f32, 11.0f32);
    for y in 0..32 {
        for x in 0..40 {
            let (dx, dy) = (x as f32 - cx, y as f32 - cy);
            if dx * dx + dy * dy <= r * r {
                b.set(x, y, 1, 10.0 + 0.01 * dx + 0.02 * dy, [200, 200, 200, 255]);
            }
        }
    }
    let (_, flags) = run(&b.0, None, Some(1e-3), false);
    assert_eq!(count_flags(&flags), (0, 0));
}

#[test]
fn occlusion_contour_is_not_flagged() {
    // Face 2 (depth 5) in front of face 1 (depth 10) on the left half: the face-1 pixels along
    // the contour have a nearer face on one side only.
    let mut b = Builder::new(20, 12);
    for y in 0..12 {
        for x in 0..20 {
            if x < 8 {
                b.set(x, y, 2, 5.0, [0, 255, 0, 255]);
            } else {
                b.set(x, y, 1, 10.0, [255, 0, 0, 255]);
            }
        }
    }
    let (_, flags) = run(&b.0, None, Some(0.01), false);
    assert_eq!(count_flags(&flags), (0, 0));
}

#[test]
fn same_face_valley_is_not_flagged() {
    // One face whose depth peaks at the centre column (a steep valley seen in perspective):
    // the centre pixels are 5 deeper than both horizontal neighbours, but of the same face.
    let valley = |centre_face: u32| {
        let mut b = Builder::new(15, 9);
        for y in 0..9 {
            for x in 0..15 {
                let depth = 20.0 - 5.0 * (x as f32 - 7.0).abs();
                let face = if x == 7 { centre_face } else { 1 };
                b.set(x, y, face, depth, [50, 50, 50, 255]);
            }
        }
        b.0
    };
    let (_, flags) = run(&valley(1), None, Some(1.0), false);
    assert_eq!(count_flags(&flags), (0, 0));
    // Control: the same depths with the centre column on another face are flagged.
    let frame = valley(2);
    let (_, flags) = run(&frame, None, Some(1.0), false);
    let column: Vec<(u32, u32)> = (0..9).map(|y| (7, y)).collect();
    assert_eq!(flagged(&frame, &flags, CRACK), column);
}

#[test]
fn far_face_through_a_gap_is_flagged_by_d_min() {
    let frame = two_faces(|_| Some((3, 50.0)));
    let (_, flags) = run(&frame, None, Some(1.0), false);
    assert_eq!(flagged(&frame, &flags, CRACK), gap_column());
    let (_, flags) = run(&frame, None, Some(100.0), false);
    assert_eq!(count_flags(&flags), (0, 0));
}

#[test]
fn detection_keeps_other_flag_bits() {
    // Flags already set stay set; detection only adds CRACK.
    let frame = two_faces(|_| None);
    let mut flags = vec![0u32; (W * H) as usize];
    flags[0] = FILLED;
    flags[5] = 4;
    let (_, got) = run(&frame, Some(&flags), Some(0.05), false);
    assert_eq!(got[0], FILLED);
    assert_eq!(got[5], 4);
    assert_eq!(got[GAP as usize], CRACK);
}
