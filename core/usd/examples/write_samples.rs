//! Writes the sample stages that `tests/usd/test_usd_writer.py` checks with usd-core.
//!
//! ```text
//! cargo run -p tessd-usd --example write_samples -- OUTDIR
//! ```
//!
//! Writes `full.usda` (quad + triangle with normals, UVs, creases and two face groups),
//! `multi.usda` (three objects with transforms and clashing names), `lod.usda` (three LOD
//! levels), `plain.usda` (no optional data) and `samples.json`, the arrays the test compares
//! against.

use std::fmt::Write as _;
use std::path::Path;

use tessd_mesh::{Crease, FaceVarying, Mesh};
use tessd_usd::{
    MeshPrim, MeshPrimOptions, StageOptions, SubdivisionScheme, UpAxis, UsdError,
    write_lod_variants, write_mesh_stage, write_stage, write_usda_file,
};

/// A quad and a triangle sharing an edge, with everything optional filled in.
fn full_mesh() -> Mesh {
    // Awkward values on purpose: they test the float formatting round trip.
    let positions = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, -0.0],
        [1.0, 1.0, 1e-7],
        [0.1, 1.0, 0.0],
        [2.5, 0.5, 12345.678],
        [3.0e20, -1.0e-20, 0.333_333_34], // unreferenced: in points and extent only
    ];
    let mut m = Mesh {
        positions,
        ..Mesh::default()
    };
    m.push_face(&[0, 1, 2, 3]);
    m.push_face(&[1, 4, 2]);
    m.normals = Some(FaceVarying {
        values: vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8]],
        indices: vec![0, 0, 0, 0, 1, 1, 1],
    });
    m.uvs = Some(FaceVarying {
        values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.25]],
        indices: vec![0, 1, 2, 3, 1, 4, 2],
    });
    m.creases = vec![
        Crease {
            a: 1,
            b: 2,
            value: 10.0,
        },
        Crease {
            a: 0,
            b: 1,
            value: 2.5,
        },
    ];
    m.face_groups = vec![1, 0];
    m.group_names = vec!["Red Paint".into(), "metal.001".into()];
    m
}

/// A unit cube of 6 quads.
fn cube() -> Mesh {
    let mut m = Mesh::default();
    for i in 0..8u32 {
        m.positions
            .push([(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32]);
    }
    for f in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        m.push_face(&f);
    }
    m
}

fn triangle() -> Mesh {
    let mut m = Mesh {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        ..Mesh::default()
    };
    m.push_face(&[0, 1, 2]);
    m
}

/// An n × n grid of quads on [0, 1]².
fn grid(n: u32) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            m.positions
                .push([i as f32 / n as f32, j as f32 / n as f32, 0.0]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            m.push_face(&[v, v + 1, v + n + 2, v + n + 1]);
        }
    }
    m
}

/// `{"points": [...], "counts": [...], "indices": [...]}` (Debug output of these types is
/// valid JSON).
fn mesh_json(m: &Mesh) -> String {
    let counts: Vec<u32> = m.faces().map(|f| f.len() as u32).collect();
    format!(
        "{{\"points\": {:?}, \"counts\": {:?}, \"indices\": {:?}}}",
        m.positions, counts, m.face_indices
    )
}

fn main() -> Result<(), UsdError> {
    let out = std::env::args()
        .nth(1)
        .expect("usage: write_samples OUTDIR");
    let out = Path::new(&out);
    std::fs::create_dir_all(out).expect("create OUTDIR");
    let mut json = String::from("{\n");

    let full = full_mesh();
    let stage = StageOptions::default()
        .with_meters_per_unit(0.01)
        .with_doc("tessd sample: \"full\"\nquad + triangle");
    let prim = MeshPrimOptions::default()
        .with_name("Part 1")
        .with_double_sided(true);
    write_usda_file(&out.join("full.usda"), |w| {
        write_mesh_stage(w, &full, &stage, &prim)
    })?;
    let _ = writeln!(
        json,
        "\"full.usda\": {{\"/Root/Part_1\": {}}},",
        mesh_json(&full)
    );

    let (c, t) = (cube(), triangle());
    let translate = |x: f64, y: f64, z: f64| {
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [x, y, z, 1.0],
        ]
    };
    let cage = MeshPrimOptions::default()
        .with_name("Cube")
        .with_subdivision_scheme(Some(SubdivisionScheme::CatmullClark));
    let prims = [
        MeshPrim::new(&c)
            .with_options(cage.clone())
            .with_transform(translate(2.0, 0.0, 0.0)),
        MeshPrim::new(&c)
            .with_options(cage)
            .with_transform(translate(-2.0, 0.5, 0.0)),
        MeshPrim::new(&t)
            .with_options(
                MeshPrimOptions::default()
                    .with_name("Tri")
                    .with_subdivision_scheme(Some(SubdivisionScheme::Loop)),
            )
            .with_transform(translate(0.0, 0.0, 3.0)),
    ];
    let stage = StageOptions::default()
        .with_up_axis(UpAxis::Y)
        .with_default_prim("Scene");
    write_usda_file(&out.join("multi.usda"), |w| write_stage(w, &stage, &prims))?;
    let _ = writeln!(
        json,
        "\"multi.usda\": {{\"/Scene/Cube\": {c}, \"/Scene/Cube_1\": {c}, \"/Scene/Tri\": {t}}},",
        c = mesh_json(&c),
        t = mesh_json(&t)
    );

    let levels = [grid(4), grid(2), grid(1)];
    let refs: Vec<&Mesh> = levels.iter().collect();
    let stage = StageOptions::default().with_meters_per_unit(0.001);
    let prim = MeshPrimOptions::default();
    write_usda_file(&out.join("lod.usda"), |w| {
        write_lod_variants(w, &stage, &refs, &prim)
    })?;
    let lods: Vec<String> = levels.iter().map(mesh_json).collect();
    let _ = writeln!(json, "\"lod.usda\": [{}],", lods.join(", "));

    let plain = cube();
    let (stage, prim) = (StageOptions::default(), MeshPrimOptions::default());
    write_usda_file(&out.join("plain.usda"), |w| {
        write_mesh_stage(w, &plain, &stage, &prim)
    })?;
    let _ = writeln!(
        json,
        "\"plain.usda\": {{\"/Root/mesh\": {}}}",
        mesh_json(&plain)
    );

    json.push_str("}\n");
    std::fs::write(out.join("samples.json"), json).expect("write samples.json");
    Ok(())
}
