//! The GPU surface evaluator (`shaders/surface_eval.wgsl` over a `SurfacePack`) against
//! `tessd_brep`'s f64 evaluation, the independent reference: random (u, v) inside every face's
//! bounds (fixed seed), on real documents (the bottle, the crank arm, the pump nut, the FreeCAD
//! drilling body, a B-spline face: planes, cylinders, cones, spheres, tori, extrusions,
//! rational B-splines) and a hand-written one for what no real file here has (revolutions of a
//! circle, of a rational and of a periodic B-spline curve; extrusions of a line, an ellipse and
//! a B-spline; a rational B-spline surface periodic in u). The CPU evaluates at the f32
//! parameters the GPU got, so only evaluation error is measured: the point within 10⁻⁵ of the
//! part's bounding-box diagonal, each derivative's direction within 10⁻³ rad where it is not
//! degenerate.
//!
//! Runs on whatever adapter wgpu finds; in CI that is lavapipe. No adapter is a failure.

use tessd_brep::{Document, Surface};
use tessd_gpu::{ErrorScopes, GpuContext};
use tessd_render::surface_pack::SurfacePack;
use wgpu::util::DeviceExt;

const SHADER: &str = concat!(
    include_str!("../../../shaders/surface_eval.wgsl"),
    r#"
struct Query { face: u32, u: f32, v: f32, pad: u32 }
@group(0) @binding(0) var<storage, read> surf_headers: array<SurfaceHeader>;
@group(0) @binding(1) var<storage, read> surf_words: array<f32>;
@group(0) @binding(2) var<storage, read> queries: array<Query>;
@group(0) @binding(3) var<storage, read_write> out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&queries) { return; }
    let q = queries[i];
    let s = surface_eval(q.face, vec2<f32>(q.u, q.v));
    out[3u * i] = vec4<f32>(s.p, 0.0);
    out[3u * i + 1u] = vec4<f32>(s.du, 0.0);
    out[3u * i + 2u] = vec4<f32>(s.dv, 0.0);
}
"#
);

/// Faces for the kinds no real document here has.
const SYNTHETIC: &str = r#"{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [
 {"id": 1, "surface": {"type": "revolution", "axis_origin": [0, 0, 1], "axis_dir": [0.6, 0, 0.8],
   "curve": {"type": "circle", "center": [3, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, 0, 1], "radius": 1}},
  "bounds": [0, 6.283185307179586, 0, 6.283185307179586]},
 {"id": 2, "reversed": true, "surface": {"type": "revolution", "axis_origin": [0, 0, 0], "axis_dir": [0, 0, 1],
   "curve": {"type": "bspline", "degree": 3,
     "poles": [[2, 0, 0], [3, 0, 1], [2.5, 0, 2], [4, 0, 3], [3, 0, 4], [2, 0, 5]],
     "weights": [1, 2, 1, 0.5, 1, 1], "knots": [0, 0.4, 1], "mults": [4, 2, 4]}},
  "bounds": [0, 6.283185307179586, 0, 1]},
 {"id": 3, "surface": {"type": "revolution", "axis_origin": [0, 0, -3], "axis_dir": [1, 0, 0],
   "curve": {"type": "bspline", "degree": 3,
     "poles": [[0, 0, 0], [4, 0, 0], [6, 3, 1], [4, 6, 0], [0, 6, 2], [-2, 3, 0]],
     "knots": [0, 1, 2, 3, 4, 5, 6], "mults": [1, 1, 1, 1, 1, 1, 1], "periodic": true}},
  "bounds": [0, 3, -2, 9]},
 {"id": 4, "surface": {"type": "extrusion", "direction": [0, 0.6, 0.8],
   "curve": {"type": "ellipse", "center": [1, 2, 3], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0],
     "major_radius": 3, "minor_radius": 1}},
  "bounds": [0, 6.283185307179586, -2, 4]},
 {"id": 5, "surface": {"type": "extrusion", "direction": [1, 0, 0],
   "curve": {"type": "bspline", "degree": 3,
     "poles": [[2, 0, 0], [3, 0, 1], [2.5, 0, 2], [4, 0, 3], [3, 0, 4], [2, 0, 5]],
     "weights": [1, 2, 1, 0.5, 1, 1], "knots": [0, 0.4, 1], "mults": [4, 2, 4]}},
  "bounds": [0, 1, -3, 2]},
 {"id": 6, "surface": {"type": "extrusion", "direction": [0, 0, 1],
   "curve": {"type": "line", "origin": [1, 1, 0], "dir": [0.8, 0.6, 0]}},
  "bounds": [-4, 4, 0, 5]},
 {"id": 7, "surface": {"type": "bspline", "degree_u": 2, "degree_v": 1,
   "poles": [[[1, 0, 0], [1, 0, 2]], [[1, 1, 0], [1, 1, 2]], [[-1, 1, 0], [-1, 1, 2]],
             [[-1, -1, 0], [-1, -1, 2]], [[1, -1, 0], [1, -1, 2]]],
   "weights": [[1, 1], [0.5, 0.5], [2, 2], [1, 1], [0.7, 0.7]],
   "knots_u": [0, 1, 2, 3], "mults_u": [2, 1, 2, 2], "knots_v": [0, 1], "mults_v": [2, 2],
   "periodic_u": true, "periodic_v": false},
  "bounds": [-1, 5, 0, 1]}
]}"#;

/// splitmix64: a reproducible stream in [0, 1).
struct Stream(u64);

impl Stream {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Evaluates `queries` (face, u, v) of `pack` on the device: (S, S_u, S_v) each.
fn evaluate(gpu: &GpuContext, pack: &SurfacePack, queries: &[[u32; 4]]) -> Vec<[[f32; 4]; 3]> {
    let device = &gpu.device;
    let scopes = ErrorScopes::push(device);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("surface_eval test"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("surface_eval test"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input = |label, bytes: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let headers = input("headers", pack.header_bytes());
    let words = input("words", pack.word_bytes());
    let qs = input("queries", bytemuck::cast_slice(queries));
    let size = (queries.len() * 48) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[&headers, &words, &qs, &out]
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((queries.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &staging, 0, size);
    gpu.queue.submit([encoder.finish()]);
    staging.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    scopes.pop_blocking().expect("no wgpu error");
    let view = staging.get_mapped_range(..).unwrap();
    let floats: Vec<f32> = view
        .chunks_exact(4)
        .map(|c| f32::from_ne_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    floats
        .chunks_exact(12)
        .map(|c| [0, 1, 2].map(|k| [c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]))
        .collect()
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    norm(c).atan2(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
}

#[test]
fn gpu_surfaces_match_the_f64_evaluation() {
    let gpu = GpuContext::open("tessd-render surface_eval test")
        .unwrap_or_else(|e| panic!("no GPU for the surface tests: {e}"));
    println!("adapter: {}", gpu.describe());
    let documents = [
        ("synthetic", SYNTHETIC),
        ("bottle", include_str!("../../trim/tests/data/bottle.json")),
        (
            "CrankArm",
            include_str!("../../tessellate/tests/data/CrankArm.json"),
        ),
        (
            "Pump_Nut",
            include_str!("../../tessellate/tests/data/Pump_Nut.json"),
        ),
        (
            "freecad_drilling1_body",
            include_str!("../../tessellate/tests/data/freecad_drilling1_body.json"),
        ),
        (
            "bspline_face",
            include_str!("../../brep/tests/data/bspline_face.json"),
        ),
    ];
    let mut kinds_seen = std::collections::BTreeSet::new();
    let mut rng = Stream(21);
    for (name, text) in documents {
        let doc = Document::from_json(text).unwrap();
        let b = doc.bounding_box().unwrap();
        let origin = [0, 1, 2].map(|k| 0.5 * (b.min[k] + b.max[k]));
        let diagonal = norm([0, 1, 2].map(|k| b.max[k] - b.min[k]));
        let mut pack = SurfacePack::new(origin);
        let mut queries = Vec::new();
        for (i, face) in doc.faces.iter().enumerate() {
            assert_eq!(pack.push(face), i);
            kinds_seen.insert(face.surface.type_name());
            if let Surface::Revolution { curve, .. } | Surface::Extrusion { curve, .. } =
                &face.surface
            {
                kinds_seen.insert(match curve.type_name() {
                    "line" => "curve line",
                    "circle" => "curve circle",
                    "ellipse" => "curve ellipse",
                    _ => "curve bspline",
                });
            }
            let [u0, u1, v0, v1] = face.bounds;
            for _ in 0..48 {
                let u = (u0 + rng.next() * (u1 - u0)) as f32;
                let v = (v0 + rng.next() * (v1 - v0)) as f32;
                queries.push([i as u32, u.to_bits(), v.to_bits(), 0]);
            }
        }
        let out = evaluate(&gpu, &pack, &queries);
        let (mut worst_p, mut worst_d) = (0.0f64, 0.0f64);
        let mut worst_kind = "";
        for (q, o) in queries.iter().zip(&out) {
            let face = &doc.faces[q[0] as usize];
            let (u, v) = (f32::from_bits(q[1]) as f64, f32::from_bits(q[2]) as f64);
            let e = face.surface.eval(u, v);
            let p = [0, 1, 2].map(|k| e.point[k] - origin[k]);
            let g = o.map(|w| [w[0] as f64, w[1] as f64, w[2] as f64]);
            let err = norm([0, 1, 2].map(|k| g[0][k] - p[k]));
            assert!(
                err <= 1e-5 * diagonal,
                "{name}: face {} ({}) at ({u}, {v}): GPU point {:?}, CPU {p:?}, error {err:e} \
                 over {:e}",
                face.id,
                face.surface.type_name(),
                g[0],
                1e-5 * diagonal
            );
            if err > worst_p {
                worst_p = err;
                worst_kind = face.surface.type_name();
            }
            // Derivatives: direction, where the derivative is not degenerate.
            let degenerate = 1e-3 * norm(e.du.into()).max(norm(e.dv.into())).max(1e-300);
            for (which, cpu, gpu_d) in [("du", e.du, g[1]), ("dv", e.dv, g[2])] {
                if norm(cpu.into()) <= degenerate || norm(cpu.into()) < 1e-9 * diagonal {
                    continue;
                }
                let a = angle(cpu.into(), gpu_d);
                assert!(
                    a <= 1e-3,
                    "{name}: face {} ({}) at ({u}, {v}): {which} GPU {gpu_d:?} vs CPU {cpu:?}, \
                     {a:e} rad",
                    face.id,
                    face.surface.type_name()
                );
                worst_d = worst_d.max(a);
            }
        }
        println!(
            "{name}: {} faces, {} queries: worst point error {:.3e} of the diagonal ({worst_kind}), \
             worst derivative angle {worst_d:.3e} rad",
            doc.faces.len(),
            queries.len(),
            worst_p / diagonal
        );
    }
    println!("kinds covered: {kinds_seen:?}");
    for kind in Surface::TYPE_NAMES {
        assert!(
            kinds_seen.contains(kind),
            "no {kind} face in the test documents"
        );
    }
    for kind in [
        "curve line",
        "curve circle",
        "curve ellipse",
        "curve bspline",
    ] {
        assert!(kinds_seen.contains(kind), "no swept {kind}");
    }
}
