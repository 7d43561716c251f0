//! What the viewer draws: each input as an item that keeps its device buffers from frame to
//! frame (uploaded once, again only when its mesh changes: a subdivision level, a LOD, a
//! refinement of a `.tsc`), and renders itself for a camera.
//!
//! - a **mesh** (OBJ, PLY, STL, OFF, `.usda`): its cage, the subdivision level shown (`+`/`-`),
//!   the frames of `--frames`;
//! - a **B-Rep** part (a tessd-brep JSON document or an OpenCASCADE `.brep`): the GPU pipeline of
//!   `tessd render` every frame (tessellation for the frame, trimming with the packed quadtree,
//!   crack detection and filling), its buffers uploaded once;
//! - a **compressed mesh** (`.tsc`): a view session refined by [`super::refine`]'s worker.

use anyhow::{Context, Result, anyhow};
use std::path::{Path, PathBuf};
use tessd_ipc::registry::Request;
use tessd_mesh::Mesh;
use tessd_render::{
    Bounds, BrepReport, BrepScene, Cracks, Frame, GpuBrepScene, GpuScene, RenderSettings, Renderer,
    Scene,
};

use crate::ops::brep_load::{is_brep_path, request_brep};
use crate::ops::mesh_arrays::read_mesh_file;

/// One input of the scene.
pub enum Item {
    /// A mesh, as shown now (cage, subdivided, a LOD or a frame).
    Mesh(Box<MeshItem>),
    /// A B-Rep part on the device.
    Brep(Box<BrepItem>),
}

/// A mesh and its buffers.
pub struct MeshItem {
    /// The file.
    pub path: PathBuf,
    /// The mesh as read (the subdivision cage).
    pub cage: std::sync::Arc<Mesh>,
    /// The mesh shown.
    pub shown: Option<(Scene, GpuScene)>,
    /// Triangles shown.
    pub triangles: usize,
    /// The largest face id of the mesh shown (the next input's ids start after it).
    pub face_ids: u32,
    /// The LOD chain once built (coarser and coarser), with each level's partition cells.
    pub lods: Option<Vec<(Mesh, Vec<tessd_simplify::Cell>)>>,
    /// The input coloured by the cells of the LOD shown, on the device (`P`: drawn instead of
    /// the LOD, in face-id colours).
    pub partition: Option<GpuScene>,
}

/// A B-Rep part and its device buffers.
pub struct BrepItem {
    /// The file.
    pub path: PathBuf,
    /// The part on the device.
    pub gpu: GpuBrepScene,
    /// Faces of the document.
    pub faces: usize,
    /// The last frame's report (steps' times, cracks).
    pub report: BrepReport,
}

/// Whether `path` is a compressed mesh.
pub fn is_tsc(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("tsc"))
}

/// An input read and checked, before the window and its device exist.
pub enum Prepared {
    /// A mesh file, and the further LOD levels of a USD stage's variants (or `UsdLod` levels).
    Mesh(PathBuf, Box<Mesh>, Vec<Mesh>),
    /// A B-Rep part with its trim structures.
    Brep(PathBuf, Box<BrepScene>, usize),
    /// A compressed mesh.
    Tsc(PathBuf, std::sync::Arc<tessd_codec::Tsc>),
}

/// Reads an input, with the errors of every other command, naming the file.
///
/// # Errors
/// The file cannot be read or is not a valid mesh, B-Rep document or `.tsc` file.
pub fn prepare(path: &Path) -> Result<Prepared> {
    let named = |e: String| {
        if e.contains(&path.display().to_string()) {
            anyhow!(e)
        } else {
            anyhow!("{}: {e}", path.display())
        }
    };
    if is_tsc(path) {
        let bytes = std::fs::read(path).map_err(|e| named(format!("cannot read: {e}")))?;
        let tsc = tessd_codec::Tsc::from_shared(std::sync::Arc::from(bytes))
            .map_err(|e| named(e.to_string()))?;
        return Ok(Prepared::Tsc(path.to_path_buf(), std::sync::Arc::new(tsc)));
    }
    if is_brep_path(path) {
        let cwd = std::env::current_dir()?;
        let mut params = serde_json::Map::new();
        params.insert("input".into(), serde_json::json!(path));
        let mut request = Request {
            params,
            base_dir: Some(cwd),
            arrays: Default::default(),
        };
        let doc = request_brep(&mut request).map_err(|e| named(e.message))?;
        doc.validate()
            .map_err(|e| named(crate::ops::brep_load::brep_error(e).message))?;
        let scene = BrepScene::new(&doc, None).map_err(|e| named(e.to_string()))?;
        return Ok(Prepared::Brep(
            path.to_path_buf(),
            Box::new(scene),
            doc.faces.len(),
        ));
    }
    // a LOD stage's levels (`tessd lod`'s schemas): the first shown, `]` steps to the others
    let mut levels = if crate::ops::mesh_arrays::is_usd_input(path) {
        let stage = tessd_usd::read_usda(path).map_err(|e| named(e.to_string()))?;
        let panels = stage.variant_panels().map_err(|e| named(e.to_string()))?;
        panels.into_iter().map(|(_, m)| m).collect()
    } else {
        vec![read_mesh_file(path, &Default::default()).map_err(|e| named(e.message))?]
    };
    if levels.is_empty() || levels[0].face_count() == 0 {
        return Err(named("the mesh has no faces to draw".into()));
    }
    let mesh = levels.remove(0);
    Ok(Prepared::Mesh(path.to_path_buf(), Box::new(mesh), levels))
}

/// Puts a prepared mesh or B-Rep part on the device (a `.tsc` is the refiner's).
///
/// # Errors
/// The device refuses the buffers.
pub fn upload(prepared: Prepared, renderer: &Renderer) -> Result<Item> {
    match prepared {
        Prepared::Mesh(path, mesh, levels) => {
            let mut item = MeshItem::new(path, *mesh);
            if !levels.is_empty() {
                // a stage's own levels have no partition to show
                item.lods = Some(levels.into_iter().map(|m| (m, Vec::new())).collect());
            }
            let cage = item.cage.clone();
            item.show(&cage, renderer)?;
            Ok(Item::Mesh(Box::new(item)))
        }
        Prepared::Brep(path, scene, faces) => {
            let gpu = renderer
                .upload_brep(*scene)
                .with_context(|| format!("{}: upload", path.display()))?;
            Ok(Item::Brep(Box::new(BrepItem {
                path,
                gpu,
                faces,
                report: BrepReport::default(),
            })))
        }
        Prepared::Tsc(path, _) => Err(anyhow!(
            "{}: a .tsc is refined, not uploaded",
            path.display()
        )),
    }
}

impl MeshItem {
    /// An item showing nothing yet.
    pub fn new(path: PathBuf, cage: Mesh) -> MeshItem {
        MeshItem {
            path,
            cage: std::sync::Arc::new(cage),
            shown: None,
            triangles: 0,
            face_ids: 0,
            lods: None,
            partition: None,
        }
    }

    /// Shows the input coloured by the cells `cells` (none: hides them).
    ///
    /// # Errors
    /// The device refuses the buffer.
    pub fn show_partition(
        &mut self,
        cells: Option<&[tessd_simplify::Cell]>,
        renderer: &Renderer,
    ) -> Result<()> {
        self.partition = match cells.filter(|c| !c.is_empty()) {
            Some(c) => {
                let colored = super::partition_colors::colored_by_cell(&self.cage, c);
                Some(renderer.upload(&Scene::from_mesh(&colored))?)
            }
            None => None,
        };
        Ok(())
    }

    /// Shows `mesh` (uploads its triangles once).
    ///
    /// # Errors
    /// The device refuses the buffer.
    pub fn show(&mut self, mesh: &Mesh, renderer: &Renderer) -> Result<()> {
        self.show_scene(Scene::from_mesh(mesh), renderer)
    }

    /// Shows triangles already laid out for the device (a `.tsc` worker makes them).
    ///
    /// # Errors
    /// The device refuses the buffer.
    pub fn show_scene(&mut self, scene: Scene, renderer: &Renderer) -> Result<()> {
        let gpu = renderer
            .upload(&scene)
            .with_context(|| format!("{}: upload", self.path.display()))?;
        self.triangles = scene.vertices.len() / 3;
        self.face_ids = scene.vertices.iter().map(|v| v.face_id).max().unwrap_or(0);
        self.shown = Some((scene, gpu));
        Ok(())
    }
}

impl Item {
    /// The item's box (none for an empty mesh).
    pub fn bounds(&self) -> Option<Bounds> {
        match self {
            Item::Mesh(m) => m.shown.as_ref().and_then(|(s, _)| s.bounds),
            Item::Brep(b) => Some(b.gpu.scene.bounds),
        }
    }

    /// The file the item came from.
    pub fn path(&self) -> &Path {
        match self {
            Item::Mesh(m) => &m.path,
            Item::Brep(b) => &b.path,
        }
    }

    /// Triangles drawn for the last frame (for a B-Rep part, those of its frame tessellation).
    pub fn triangles(&self) -> u64 {
        match self {
            Item::Mesh(m) => m.triangles as u64,
            Item::Brep(b) => 2 * b.report.cells,
        }
    }

    /// Renders the item.
    ///
    /// # Errors
    /// The device fails.
    pub fn render(
        &mut self,
        renderer: &Renderer,
        camera: &tessd_render::Camera,
        settings: &RenderSettings,
        cracks: Cracks,
    ) -> Result<Option<Frame>> {
        Ok(match self {
            Item::Mesh(m) => match (&m.partition, &m.shown) {
                (Some(cells), _) => {
                    let colors = settings.with_shading(tessd_render::Shading::FaceIds);
                    Some(renderer.render(cells, camera, &colors)?.0)
                }
                (None, Some((_, gpu))) => Some(renderer.render(gpu, camera, settings)?.0),
                (None, None) => None,
            },
            Item::Brep(b) => {
                let (frame, report) = renderer.render_brep(&b.gpu, camera, settings, cracks)?;
                b.report = report;
                Some(frame)
            }
        })
    }
}

/// Puts `frame` over `into` where it is nearer, its face ids shifted by `offset` (so that each
/// item's faces keep ids of their own).
pub fn composite(into: &mut Frame, frame: &Frame, offset: u32) {
    for i in 0..into.depth.len() {
        if frame.face_id[i] != 0 && frame.depth[i] < into.depth[i] {
            into.depth[i] = frame.depth[i];
            into.face_id[i] = frame.face_id[i] + offset;
            into.uv[i] = frame.uv[i];
            into.color[4 * i..4 * i + 4].copy_from_slice(&frame.color[4 * i..4 * i + 4]);
        }
    }
}
