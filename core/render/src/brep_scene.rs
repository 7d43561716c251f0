//! A B-Rep part prepared once for GPU rendering (paper 001 §3: "this conversion, done once in
//! a CPU preprocess"): every face's basis surface ([`SurfacePack`]) and trim structure
//! ([`MultiPack`], paper 000 §3–4 and §7) in flat storage buffers, and per face what the
//! per-frame tessellation factors need (its world box and a bound of its second derivatives).
//!
//! Coordinates: positions on the GPU are f32 relative to [`BrepScene::origin`] (the box
//! centre), so a part far from the world origin keeps its precision. The tessellation grid of
//! a face covers its *quadtree's root square* (the face's `bounds`, grown to hold every trim
//! piece), so that grid cells at level k are quadtree cells at depth k and triangle
//! classification (paper 000 §6) applies; a patch point (s, t) is normalised over `bounds`
//! (see [`tessd_trim::multi_pack`]).

use crate::RenderError;
use crate::bindings;
use crate::camera::{Bounds, Vec3};
use crate::classification_level::classification_level;
use crate::ray_seeds::RaySeeds;
use crate::surface_pack::SurfacePack;
use tessd_brep::{Document, Face};
use tessd_gpu::ErrorScopes;
use tessd_trim::TrimStructure;
use tessd_trim::multi_pack::{MultiPack, NO_LEVEL};

/// The finest tessellation level per axis: 2^9 = 512 grid cells along each side of a face's
/// domain (the hardware tessellators of paper 000 §7 stop at 64; a compute pass has no such
/// limit, but a face finer than 512 × 512 cells at 0.5 pixel would be larger than a 4K screen).
pub const MAX_LEVEL: u32 = 9;

/// The finest level k_i may force on a face whatever its size on screen: 2^6 = 64 cells a
/// side, the hardware tessellators' limit in paper 000 §7. A face whose classification
/// decides 40 % only at a finer level gets no minimum (`k_i = None`): forcing 256 × 256
/// cells on it costs more than the fragment walks it would save (the M6 screw's thread at
/// k_i = 8: 129 k cells a 640 × 480 frame, 2.3 × the frame time).
pub const MAX_CLASSIFICATION_LEVEL: u32 = 6;

/// Samples per side of the grid on which a face's second derivatives are estimated.
const CURVATURE_SAMPLES: usize = 16;

/// Safety factor on the sampled second-derivative bound (sampling can miss the maximum
/// between samples).
const CURVATURE_SAFETY: f64 = 1.5;

/// The default world tolerance of the trim approximation relative to the part's box diagonal:
/// 10⁻⁴, a tenth of a pixel when the part fills a 1080p image.
pub const TRIM_TOLERANCE: f64 = 1e-4;

/// What the per-frame factors need of one face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceInfo {
    /// The face's world box (sampled on the trimmed face and grown by 5 % of its diagonal).
    pub bounds: Bounds,
    /// Bounds of |∂²S/∂x²|, |∂²S/∂y²| and |∂²S/∂x∂y| over the quadtree's root square, in
    /// world units per (normalised quadtree unit)²: the chordal error of a grid of steps
    /// (h_x, h_y) is at most (M_xx h_x² + 2 M_xy h_x h_y + M_yy h_y²) / 8.
    pub curvature: [f64; 3],
    /// The triangle-classification level k_i of paper 000 §6 as the classification pass
    /// decides cells, at most [`MAX_CLASSIFICATION_LEVEL`] (`None` when no level up to it
    /// decides 40 %;
    /// see [`classification_level`]).
    pub k_i: Option<u32>,
}

/// A part's faces ready to upload (see the module documentation).
pub struct BrepScene {
    /// What GPU positions are relative to (the box centre, world coordinates).
    pub origin: [f64; 3],
    /// The part's world box.
    pub bounds: Bounds,
    /// Per face (document order).
    pub faces: Vec<FaceInfo>,
    /// The basis surfaces.
    pub surfaces: SurfacePack,
    /// The trim structures, patch = the face's `bounds`.
    pub trims: MultiPack,
    /// Faces whose trim structure could not be built, with why; they are not drawn.
    pub skipped: Vec<String>,
    /// The world tolerance the trims were approximated with.
    pub trim_tolerance: f64,
    /// The faces as the document gave them, kept for the ray caster's seed boxes
    /// ([`RaySeeds`]), built on its first use: a raster render never pays for them.
    pub source: Vec<Face>,
    /// Per face, whether its trim structure was built (skipped faces are not drawn).
    pub built: Vec<bool>,
}

impl BrepScene {
    /// The ray caster's seed boxes of the part (see [`RaySeeds::new`]).
    pub fn ray_seeds(&self) -> RaySeeds {
        RaySeeds::new(
            &self.source,
            &self.built,
            self.origin,
            2.0 * self.bounds.radius(),
        )
    }
}

impl BrepScene {
    /// Prepares `doc`, approximating trims at `trim_tolerance` (world units; `None`:
    /// [`TRIM_TOLERANCE`] × the box diagonal).
    ///
    /// # Errors
    /// [`RenderError::Camera`] when the part has no finite bounding box (nothing to look at).
    pub fn new(doc: &Document, trim_tolerance: Option<f64>) -> Result<BrepScene, RenderError> {
        let b = doc
            .bounding_box()
            .ok_or_else(|| RenderError::Camera("the part has no finite point to look at".into()))?;
        let bounds = Bounds {
            min: b.min,
            max: b.max,
        };
        let origin = bounds.center().to_array();
        let diagonal = 2.0 * bounds.radius();
        let eps = trim_tolerance.unwrap_or(TRIM_TOLERANCE * diagonal.max(f64::MIN_POSITIVE));
        let mut scene = BrepScene {
            origin,
            bounds,
            faces: Vec::with_capacity(doc.faces.len()),
            surfaces: SurfacePack::new(origin),
            trims: MultiPack::new(),
            skipped: Vec::new(),
            trim_tolerance: eps,
            source: doc.faces.clone(),
            built: Vec::with_capacity(doc.faces.len()),
        };
        for face in &doc.faces {
            scene.surfaces.push(face);
            let trim = match TrimStructure::build(face, eps) {
                Ok(t) => t,
                Err(e) => {
                    // An empty structure keeps the face indices aligned; its face is culled.
                    scene.skipped.push(e.to_string());
                    scene.trims.push(&empty_trim(face, eps), face.bounds);
                    scene.faces.push(FaceInfo {
                        bounds: Bounds {
                            min: origin.into(),
                            max: origin.into(),
                        },
                        curvature: [0.0; 3],
                        k_i: None,
                    });
                    scene.built.push(false);
                    continue;
                }
            };
            let index = scene.trims.push(&trim, face.bounds);
            // k_i as the classification pass decides cells (paper 000 §6 on the triangles
            // really drawn), not the quadtree's own diagonal-split estimate.
            let k_i = classification_level(&scene.trims, index, MAX_CLASSIFICATION_LEVEL);
            scene.trims.headers[index].k_i = k_i.unwrap_or(NO_LEVEL);
            scene.faces.push(face_info(face, &trim, &bounds, k_i));
            scene.built.push(true);
        }
        Ok(scene)
    }
}

/// A structure for a face whose own could not be built: the whole bounds rectangle with no
/// trims, used only to keep indices aligned (the face is marked empty and never drawn).
fn empty_trim(face: &Face, eps: f64) -> TrimStructure {
    let mut bare = face.clone();
    bare.loops.clear();
    let [u0, u1, v0, v1] = bare.bounds;
    if !(u0 < u1 && v0 < v1 && bare.bounds.iter().all(|x| x.is_finite())) {
        bare.bounds = [0.0, 1.0, 0.0, 1.0];
    }
    TrimStructure::build(&bare, eps).expect("a bare unit rectangle always builds")
}

/// The face's world box and second-derivative bounds over its quadtree's root square, with
/// its level `k_i`.
fn face_info(face: &Face, trim: &TrimStructure, part: &Bounds, k_i: Option<u32>) -> FaceInfo {
    let d = trim.packed.domain;
    let (w, h) = (d[1] - d[0], d[3] - d[2]);
    let n = CURVATURE_SAMPLES;
    let step = 1.0 / n as f64;
    let p = |i: usize, j: usize| {
        face.surface
            .point(d[0] + w * i as f64 * step, d[2] + h * j as f64 * step)
    };
    let grid: Vec<[f64; 3]> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| p(i, j).to_array())
        .collect();
    let at = |i: usize, j: usize| grid[j * (n + 1) + i];
    let second = |a: [f64; 3], b: [f64; 3], c: [f64; 3], e: [f64; 3]| {
        let v = [0, 1, 2].map(|k| a[k] - b[k] - c[k] + e[k]);
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() / (step * step)
    };
    let mut m = [0f64; 3];
    for j in 0..=n {
        for i in 0..=n {
            if i > 0 && i < n {
                m[0] = m[0].max(second(at(i + 1, j), at(i, j), at(i, j), at(i - 1, j)));
            }
            if j > 0 && j < n {
                m[1] = m[1].max(second(at(i, j + 1), at(i, j), at(i, j), at(i, j - 1)));
            }
            if i < n && j < n {
                m[2] = m[2].max(second(
                    at(i + 1, j + 1),
                    at(i + 1, j),
                    at(i, j + 1),
                    at(i, j),
                ));
            }
        }
    }
    // A surface that does not evaluate (NaN) gets the part's size as its bound: finest factors.
    let fallback = 8.0 * part.radius();
    let curvature = m.map(|x| {
        if x.is_finite() {
            CURVATURE_SAFETY * x
        } else {
            fallback
        }
    });
    let bounds = match face.bounding_box() {
        Some(b) => {
            let grow = 0.05
                * [0, 1, 2]
                    .map(|k| b.max[k] - b.min[k])
                    .iter()
                    .fold(0.0, |s, x| s + x * x)
                    .sqrt();
            Bounds {
                min: Vec3::from(b.min) - grow,
                max: Vec3::from(b.max) + grow,
            }
        }
        None => *part,
    };
    FaceInfo {
        bounds,
        curvature,
        k_i,
    }
}

/// A [`BrepScene`] on the device: the six storage buffers the passes bind (bind group 1,
/// [`GpuBrep::entries`]) and the ray caster's seed boxes (bound by [`crate::ray_cast`] alone).
pub struct GpuBrep {
    /// Per-face surface headers.
    pub surf_headers: wgpu::Buffer,
    /// Surface data words.
    pub surf_words: wgpu::Buffer,
    /// Per-face trim headers.
    pub trim_headers: wgpu::Buffer,
    /// Quadtree node words.
    pub trim_nodes: wgpu::Buffer,
    /// Curve maps.
    pub trim_curves: wgpu::Buffer,
    /// Two-curve records.
    pub trim_lines: wgpu::Buffer,
    /// Bytes of the trim buffers (table 3 of paper 000).
    pub trim_bytes: usize,
}

impl GpuBrep {
    /// Uploads `scene`'s packs.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a buffer is over the device's limits.
    pub fn upload(device: &wgpu::Device, scene: &BrepScene) -> Result<GpuBrep, RenderError> {
        let scopes = ErrorScopes::push(device);
        let make = |label, bytes: &[u8]| bindings::storage_init(device, label, bytes);
        let t = &scene.trims;
        let out = GpuBrep {
            surf_headers: make("surface headers", scene.surfaces.header_bytes())?,
            surf_words: make("surface words", bytemuck::cast_slice(&scene.surfaces.words))?,
            trim_headers: make("trim headers", t.header_bytes())?,
            trim_nodes: make("trim nodes", bytemuck::cast_slice(&t.nodes))?,
            trim_curves: make("trim curves", bytemuck::cast_slice(&t.curves))?,
            trim_lines: make("trim lines", bytemuck::cast_slice(&t.lines))?,
            trim_bytes: t.bytes(),
        };
        scopes.pop_blocking()?;
        Ok(out)
    }

    /// Bind-group entries for the six buffers at bindings `first..first + 6`, in the order
    /// surface headers, surface words, trim headers, nodes, curves, lines.
    pub fn entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'_>> {
        [
            &self.surf_headers,
            &self.surf_words,
            &self.trim_headers,
            &self.trim_nodes,
            &self.trim_curves,
            &self.trim_lines,
        ]
        .into_iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry {
            binding: first + k as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
    }
}

/// The bind group 1 of the B-Rep passes for `brep` (layout [`bindings::brep_layout`]).
pub fn brep_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    brep: &GpuBrep,
) -> wgpu::BindGroup {
    bindings::bind_buffers(
        device,
        "brep buffers",
        layout,
        &[
            &brep.surf_headers,
            &brep.surf_words,
            &brep.trim_headers,
            &brep.trim_nodes,
            &brep.trim_curves,
            &brep.trim_lines,
        ],
    )
}
