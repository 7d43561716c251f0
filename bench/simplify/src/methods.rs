//! The simplifiers under test, behind one interface: a method name, its numeric parameter and
//! the number of output vertices it lands at.

use meshopt::{SimplifyOptions as MoOptions, VertexDataAdapter};
use tessd_mesh::Mesh;
use tessd_simplify::{
    Count, GridSize, Length, Method as TMethod, Representative, SimplifyOptions, simplify,
};

/// A simplifier and its settings (except the numeric parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// tessd regular grid with cubic cells of side `param`.
    Grid(Rep),
    /// tessd quality goal with absolute tolerance `param`.
    Quality(Rep),
    /// tessd complexity goal with `param` output vertices.
    Complexity(Rep),
    /// meshoptimizer simplifySloppy with target index count `param`.
    Sloppy,
    /// meshoptimizer simplify (edge-collapse QEM) with target index count `param`.
    Qem,
}

/// The tessd representatives benchmarked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rep {
    /// Weighted barycentre.
    Bary,
    /// Quadric minimiser.
    Quadric,
}

/// Every method, in report order.
pub const ALL: [Method; 8] = [
    Method::Grid(Rep::Bary),
    Method::Grid(Rep::Quadric),
    Method::Quality(Rep::Bary),
    Method::Quality(Rep::Quadric),
    Method::Complexity(Rep::Bary),
    Method::Complexity(Rep::Quadric),
    Method::Sloppy,
    Method::Qem,
];

impl Method {
    /// The name used on the command line and in the results.
    pub fn name(self) -> &'static str {
        match self {
            Method::Grid(Rep::Bary) => "tessd-grid-bary",
            Method::Grid(Rep::Quadric) => "tessd-grid-quadric",
            Method::Quality(Rep::Bary) => "tessd-quality-bary",
            Method::Quality(Rep::Quadric) => "tessd-quality-quadric",
            Method::Complexity(Rep::Bary) => "tessd-complexity-bary",
            Method::Complexity(Rep::Quadric) => "tessd-complexity-quadric",
            Method::Sloppy => "meshopt-sloppy",
            Method::Qem => "meshopt-simplify",
        }
    }

    /// The method of a name.
    pub fn parse(s: &str) -> Option<Method> {
        ALL.into_iter().find(|m| m.name() == s)
    }

    /// What the numeric parameter is.
    pub fn param_name(self) -> &'static str {
        match self {
            Method::Grid(_) => "cell_size",
            Method::Quality(_) => "tolerance",
            Method::Complexity(_) => "target_vertices",
            Method::Sloppy | Method::Qem => "target_index_count",
        }
    }

    /// Whether the method runs on meshoptimizer's indexed-triangle input.
    pub fn is_meshopt(self) -> bool {
        matches!(self, Method::Sloppy | Method::Qem)
    }
}

/// An indexed triangle list (polygons fan-triangulated), meshoptimizer's input.
pub struct Triangles {
    /// Positions, as in the mesh.
    pub positions: Vec<[f32; 3]>,
    /// Three vertex indices per triangle.
    pub indices: Vec<u32>,
}

impl Triangles {
    /// Fan-triangulates `mesh`.
    pub fn from_mesh(mesh: &Mesh) -> Triangles {
        let mut indices = Vec::with_capacity(3 * mesh.triangle_count());
        for f in mesh.faces() {
            for k in 1..f.len() - 1 {
                indices.extend_from_slice(&[f[0], f[k], f[k + 1]]);
            }
        }
        Triangles {
            positions: mesh.positions.clone(),
            indices,
        }
    }
}

/// The input a method runs on.
// One value per run: the size difference of the variants costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
pub enum Input {
    /// tessd's polygon mesh.
    Mesh(Mesh),
    /// meshoptimizer's triangle list.
    Triangles(Triangles),
}

impl Input {
    /// The input `method` takes, built from `mesh` (consumed: its memory is released when the
    /// method does not need it).
    pub fn for_method(method: Method, mesh: Mesh) -> Input {
        if method.is_meshopt() {
            Input::Triangles(Triangles::from_mesh(&mesh))
        } else {
            Input::Mesh(mesh)
        }
    }
}

/// What a method returned.
pub enum Output {
    /// A tessd result.
    Tessd(Box<tessd_simplify::Simplified>),
    /// meshoptimizer's index buffer into the input's vertices.
    Indices(Vec<u32>),
}

/// Runs `method` with parameter `param` on `input` (the timed part).
///
/// # Errors
/// tessd's error, as text, or a method/input mismatch.
pub fn run(method: Method, input: &Input, param: f64) -> Result<Output, String> {
    run_observed(method, input, param, &mut |_, _| true)
}

/// [`run`], with tessd's `progress(fraction, stage)` callback (meshoptimizer has none).
///
/// # Errors
/// As [`run`].
pub fn run_observed(
    method: Method,
    input: &Input,
    param: f64,
    progress: &mut dyn FnMut(f64, &str) -> bool,
) -> Result<Output, String> {
    match (method, input) {
        (Method::Sloppy | Method::Qem, Input::Triangles(t)) => {
            let adapter = VertexDataAdapter::new(bytemuck::cast_slice(&t.positions), 12, 0)
                .map_err(|e| e.to_string())?;
            let target = (param.round().max(3.0) as usize).min(t.indices.len());
            Ok(Output::Indices(if method == Method::Sloppy {
                meshopt::simplify_sloppy(&t.indices, &adapter, target, f32::MAX, None)
            } else {
                meshopt::simplify(
                    &t.indices,
                    &adapter,
                    target,
                    f32::MAX,
                    MoOptions::empty(),
                    None,
                )
            }))
        }
        (_, Input::Mesh(mesh)) if !method.is_meshopt() => {
            let (m, rep) = match method {
                Method::Grid(r) => (TMethod::Grid(GridSize::CellSize(param)), r),
                Method::Quality(r) => (TMethod::Quality(Length::Absolute(param)), r),
                Method::Complexity(r) => (
                    TMethod::Complexity(Count::Absolute(param.round() as u64)),
                    r,
                ),
                Method::Sloppy | Method::Qem => unreachable!(),
            };
            let rep = match rep {
                Rep::Bary => Representative::Barycenter,
                Rep::Quadric => Representative::Quadric,
            };
            let options = SimplifyOptions::new(m).with_representative(rep);
            simplify(mesh, &options, progress)
                .map(|s| Output::Tessd(Box::new(s)))
                .map_err(|e| e.to_string())
        }
        _ => Err(format!("{} got the wrong kind of input", method.name())),
    }
}

/// Number of distinct vertices referenced by `indices` (of `vertex_count`).
pub fn referenced(indices: &[u32], vertex_count: usize) -> u64 {
    let mut seen = vec![false; vertex_count];
    let mut n = 0;
    for &i in indices {
        let s = &mut seen[i as usize];
        n += u64::from(!*s);
        *s = true;
    }
    n
}

impl Output {
    /// Output vertices (referenced by a face) and faces.
    pub fn counts(&self, input: &Input) -> (u64, u64) {
        match (self, input) {
            (Output::Tessd(s), _) => (
                referenced(&s.mesh.face_indices, s.mesh.positions.len()),
                s.mesh.face_count() as u64,
            ),
            (Output::Indices(ix), Input::Triangles(t)) => {
                (referenced(ix, t.positions.len()), ix.len() as u64 / 3)
            }
            (Output::Indices(ix), Input::Mesh(m)) => {
                (referenced(ix, m.positions.len()), ix.len() as u64 / 3)
            }
        }
    }

    /// The output as a mesh of its referenced vertices only.
    pub fn into_mesh(self, input: &Input) -> Mesh {
        match self {
            Output::Tessd(s) => s.mesh,
            Output::Indices(ix) => {
                let positions = match input {
                    Input::Triangles(t) => &t.positions,
                    Input::Mesh(m) => &m.positions,
                };
                let mut remap = vec![u32::MAX; positions.len()];
                let mut m = Mesh::default();
                for tri in ix.chunks_exact(3) {
                    let mut f = [0u32; 3];
                    for (k, &v) in tri.iter().enumerate() {
                        if remap[v as usize] == u32::MAX {
                            remap[v as usize] = m.positions.len() as u32;
                            m.positions.push(positions[v as usize]);
                        }
                        f[k] = remap[v as usize];
                    }
                    m.push_face(&f);
                }
                m
            }
        }
    }
}
