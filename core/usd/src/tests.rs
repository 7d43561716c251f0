//! Structure tests of the writer (usd-core checks the files in `tests/usd/`).

use std::io::{self, Write};

use tessd_mesh::{Crease, FaceVarying, Mesh};

use crate::usda_out::{push_f32, push_f64};
use crate::*;

fn quad() -> Mesh {
    let mut m = Mesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        ..Mesh::default()
    };
    m.push_face(&[0, 1, 2, 3]);
    m
}

fn text(mesh: &Mesh, stage: &StageOptions, prim: &MeshPrimOptions) -> String {
    let mut v = Vec::new();
    write_mesh_stage(&mut v, mesh, stage, prim).unwrap();
    String::from_utf8(v).unwrap()
}

#[test]
fn quad_snapshot() {
    let t = text(
        &quad(),
        &StageOptions::default(),
        &MeshPrimOptions::default(),
    );
    assert_eq!(
        t,
        r#"#usda 1.0
(
    defaultPrim = "Root"
    metersPerUnit = 1
    upAxis = "Z"
)

def Xform "Root" (
    kind = "component"
)
{
    def Mesh "mesh"
    {
        float3[] extent = [(0, 0, 0), (1, 1, 0)]
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        uniform bool doubleSided = false
        uniform token orientation = "rightHanded"
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        uniform token subdivisionScheme = "none"
    }
}
"#
    );
}

#[test]
fn quad_with_everything_snapshot() {
    let mut m = quad();
    m.push_face(&[1, 0, 3]);
    m.normals = Some(FaceVarying {
        values: vec![[0.0, 0.0, 1.0]],
        indices: vec![0; 7],
    });
    m.uvs = Some(FaceVarying {
        values: vec![[0.0, 0.0], [1.0, 0.5]],
        indices: vec![0, 1, 1, 0, 0, 1, 0],
    });
    m.creases = vec![
        Crease {
            a: 0,
            b: 1,
            value: 10.0,
        },
        Crease {
            a: 3,
            b: 0,
            value: 0.5,
        },
    ];
    m.face_groups = vec![1, 0];
    m.group_names = vec!["Material.001".into(), "7 steel".into()];
    let stage = StageOptions::default()
        .with_up_axis(UpAxis::Y)
        .with_meters_per_unit(0.001)
        .with_default_prim("My Scene")
        .with_doc("a \"doc\"\nline 2 \\ end");
    let prim = MeshPrimOptions::default()
        .with_name("Plate")
        .with_double_sided(true)
        .with_uv_primvar_name("UVMap")
        .with_subdivision_scheme(Some(SubdivisionScheme::CatmullClark));
    assert_eq!(
        text(&m, &stage, &prim),
        r#"#usda 1.0
(
    defaultPrim = "My_Scene"
    doc = "a \"doc\"\nline 2 \\ end"
    metersPerUnit = 0.001
    upAxis = "Y"
)

def Xform "My_Scene" (
    kind = "component"
)
{
    def Mesh "Plate"
    {
        float3[] extent = [(0, 0, 0), (1, 1, 0)]
        int[] faceVertexCounts = [4, 3]
        int[] faceVertexIndices = [0, 1, 2, 3, 1, 0, 3]
        uniform bool doubleSided = true
        uniform token orientation = "rightHanded"
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        normal3f[] primvars:normals = [(0, 0, 1)] (
            interpolation = "faceVarying"
        )
        int[] primvars:normals:indices = [0, 0, 0, 0, 0, 0, 0]
        texCoord2f[] primvars:UVMap = [(0, 0), (1, 0.5)] (
            interpolation = "faceVarying"
        )
        int[] primvars:UVMap:indices = [0, 1, 1, 0, 0, 1, 0]
        int[] creaseIndices = [0, 1, 3, 0]
        int[] creaseLengths = [2, 2]
        float[] creaseSharpnesses = [10, 0.5]
        uniform token subdivisionScheme = "catmullClark"
        uniform token subsetFamily:materialBind:familyType = "partition"

        def GeomSubset "Material_001"
        {
            uniform token elementType = "face"
            uniform token familyName = "materialBind"
            int[] indices = [1]
        }

        def GeomSubset "_7_steel"
        {
            uniform token elementType = "face"
            uniform token familyName = "materialBind"
            int[] indices = [0]
        }
    }
}
"#
    );
}

#[test]
fn optional_data_can_be_left_out() {
    let mut m = quad();
    m.normals = Some(FaceVarying {
        values: vec![[0.0, 0.0, 1.0]],
        indices: vec![0; 4],
    });
    m.uvs = Some(FaceVarying {
        values: vec![[0.0, 0.0]],
        indices: vec![0; 4],
    });
    let prim = MeshPrimOptions::default()
        .with_normals(false)
        .with_uvs(false);
    let t = text(&m, &StageOptions::default(), &prim);
    assert!(!t.contains("primvars"), "{t}");
}

#[test]
fn subsets_skip_empty_groups_and_dedupe_names() {
    let mut m = quad();
    m.push_face(&[0, 2, 3]);
    m.push_face(&[0, 1, 2]);
    m.face_groups = vec![0, 2, 0];
    m.group_names = vec!["a b".into(), "unused".into(), "a.b".into()];
    let t = text(&m, &StageOptions::default(), &MeshPrimOptions::default());
    assert!(t.contains("def GeomSubset \"a_b\"\n"), "{t}");
    assert!(t.contains("def GeomSubset \"a_b_1\"\n"), "{t}");
    assert!(!t.contains("unused"), "{t}");
    assert!(t.contains("int[] indices = [0, 2]\n"), "{t}");
    assert!(t.contains("int[] indices = [1]\n"), "{t}");
}

#[test]
fn multi_prims_get_unique_names_and_transforms() {
    let (a, b) = (quad(), quad());
    let mut t = [[0.0; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    t[3] = [2.0, -0.0, 0.25, 1.0];
    let prims = [
        MeshPrim::new(&a).with_options(MeshPrimOptions::default().with_name("Cube")),
        MeshPrim::new(&b)
            .with_options(MeshPrimOptions::default().with_name("Cube"))
            .with_transform(t),
    ];
    let mut v = Vec::new();
    write_stage(&mut v, &StageOptions::default(), &prims).unwrap();
    let s = String::from_utf8(v).unwrap();
    assert!(s.contains("    def Mesh \"Cube\"\n"), "{s}");
    assert!(s.contains("    def Mesh \"Cube_1\"\n"), "{s}");
    assert!(
        s.contains(
            "        matrix4d xformOp:transform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), \
             (2, -0.0, 0.25, 1) )\n        uniform token[] xformOpOrder = [\"xformOp:transform\"]\n"
        ),
        "{s}"
    );
    assert_eq!(s.matches("xformOpOrder").count(), 1);
}

#[test]
fn lod_variants_structure() {
    let mut tri = Mesh {
        positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        ..Mesh::default()
    };
    tri.push_face(&[0, 1, 2]);
    let q = quad();
    let mut v = Vec::new();
    let prim = MeshPrimOptions::default().with_name("Body");
    write_lod_variants(&mut v, &StageOptions::default(), &[&q, &tri], &prim).unwrap();
    let s = String::from_utf8(v).unwrap();
    let expected_head = r#"def Xform "Root" (
    kind = "component"
    variants = {
        string LOD = "LOD0"
    }
    prepend variantSets = "LOD"
)
{
    variantSet "LOD" = {
        "LOD0" {
            def Mesh "Body"
            {
"#;
    assert!(s.contains(expected_head), "{s}");
    assert!(
        s.contains("        }\n        \"LOD1\" {\n            def Mesh \"Body\"\n"),
        "{s}"
    );
    assert!(s.ends_with("            }\n        }\n    }\n}\n"), "{s}");
    assert_eq!(s.matches("def Mesh").count(), 2);
    let e = write_lod_variants(&mut Vec::new(), &StageOptions::default(), &[], &prim);
    assert_eq!(e.unwrap_err().code(), "invalid_request");
}

#[test]
fn invalid_input_writes_nothing() {
    let mut m = quad();
    m.positions[1][0] = f32::NAN;
    let mut v = Vec::new();
    let prim = MeshPrimOptions::default().with_name("Bad");
    let e = write_mesh_stage(&mut v, &m, &StageOptions::default(), &prim).unwrap_err();
    assert_eq!(e.code(), "invalid_mesh");
    assert_eq!(
        e.to_string(),
        "mesh prim \"Bad\": vertex 1 has a non-finite coordinate x = NaN"
    );
    assert!(v.is_empty());

    let q = quad();
    let bad_lod = m.clone();
    let e = write_lod_variants(&mut v, &StageOptions::default(), &[&q, &bad_lod], &prim);
    assert!(
        e.unwrap_err()
            .to_string()
            .starts_with("mesh prim \"Bad (LOD1)\": vertex 1")
    );

    let stage = StageOptions::default().with_meters_per_unit(0.0);
    let e = write_mesh_stage(&mut v, &q, &stage, &prim).unwrap_err();
    assert_eq!(e.code(), "invalid_request");

    let mut t = [[0.0; 4]; 4];
    t[0][0] = f64::INFINITY;
    let e = write_stage(
        &mut v,
        &StageOptions::default(),
        &[MeshPrim::new(&q).with_transform(t)],
    );
    assert_eq!(e.unwrap_err().code(), "invalid_request");

    let loop_prim =
        MeshPrimOptions::default().with_subdivision_scheme(Some(SubdivisionScheme::Loop));
    let e = write_mesh_stage(&mut v, &q, &StageOptions::default(), &loop_prim).unwrap_err();
    assert!(
        e.to_string()
            .contains("needs a triangle mesh; face 0 has 4 vertices"),
        "{e}"
    );
    assert!(v.is_empty());
}

#[test]
fn empty_mesh_has_no_extent() {
    let t = text(
        &Mesh::default(),
        &StageOptions::default(),
        &MeshPrimOptions::default(),
    );
    assert!(!t.contains("extent"));
    assert!(t.contains("int[] faceVertexCounts = []\n"));
    assert!(t.contains("point3f[] points = []\n"));
}

#[test]
fn extent_covers_all_points() {
    let mut m = quad();
    m.positions.push([-5.0, 2.0, 3.0]); // unreferenced
    let t = text(&m, &StageOptions::default(), &MeshPrimOptions::default());
    assert!(
        t.contains("float3[] extent = [(-5, 0, 0), (1, 2, 3)]\n"),
        "{t}"
    );
}

#[test]
fn floats_are_shortest_round_trip() {
    let f = |v: f32| {
        let mut s = String::new();
        push_f32(&mut s, v);
        s
    };
    assert_eq!(f(0.1), "0.1");
    assert_eq!(f(1.0), "1");
    assert_eq!(f(-2.5), "-2.5");
    assert_eq!(f(0.0), "0");
    assert_eq!(f(-0.0), "-0.0");
    assert_eq!(f(1e20), "1e20");
    assert_eq!(f(1.5e-7), "1.5e-7");
    assert_eq!(f(f32::MAX), "3.4028235e38");
    assert_eq!(f(123456.79), "123456.79");
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..100_000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let v = f32::from_bits(state as u32);
        if v.is_finite() {
            let s = f(v);
            assert_eq!(s.parse::<f32>().unwrap().to_bits(), v.to_bits(), "{s}");
            assert!(s.len() <= 16, "{s}");
        }
    }
    let mut s = String::new();
    push_f64(&mut s, 0.001);
    assert_eq!(s, "0.001");
}

/// A writer that counts the calls it gets and fails after `fail_after` bytes.
struct Probe {
    writes: usize,
    bytes: usize,
    max_write: usize,
    fail_after: usize,
}

impl Write for Probe {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.bytes + buf.len() > self.fail_after {
            return Err(io::Error::other("full"));
        }
        self.writes += 1;
        self.bytes += buf.len();
        self.max_write = self.max_write.max(buf.len());
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

fn big_grid(n: u32) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            m.positions
                .push([i as f32 * 0.37, j as f32 * 1.13, (i * j) as f32 * 0.01]);
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

#[test]
fn output_is_streamed_in_chunks() {
    let m = big_grid(300);
    let mut p = Probe {
        writes: 0,
        bytes: 0,
        max_write: 0,
        fail_after: usize::MAX,
    };
    write_mesh_stage(
        &mut p,
        &m,
        &StageOptions::default(),
        &MeshPrimOptions::default(),
    )
    .unwrap();
    assert!(p.bytes > 2_000_000, "{}", p.bytes);
    assert!(p.writes > 20, "{}", p.writes);
    assert!(p.max_write < 80_000, "{}", p.max_write);

    let mut p = Probe {
        writes: 0,
        bytes: 0,
        max_write: 0,
        fail_after: 100_000,
    };
    let e = write_mesh_stage(
        &mut p,
        &m,
        &StageOptions::default(),
        &MeshPrimOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "<stream>: full");
    assert_eq!(e.code(), "io");
}

#[test]
fn file_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("quad.usda");
    let (stage, prim) = (StageOptions::default(), MeshPrimOptions::default());
    write_usda_file(&path, |w| write_mesh_stage(w, &quad(), &stage, &prim)).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        text(&quad(), &stage, &prim)
    );

    let mut bad = quad();
    bad.push_face(&[0, 1, 99]);
    let path = dir.path().join("bad.usda");
    let e = write_usda_file(&path, |w| write_mesh_stage(w, &bad, &stage, &prim)).unwrap_err();
    assert_eq!(e.code(), "invalid_mesh");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn lod_schema_structure() {
    let mut tri = Mesh {
        positions: vec![[0.0; 3], [2.0, 0.0, 0.0], [0.0, 1.0, -1.0]],
        ..Mesh::default()
    };
    tri.push_face(&[0, 1, 2]);
    let q = quad();
    let prim = MeshPrimOptions::default().with_name("Body");
    let mut v = Vec::new();
    write_lod_schema(
        &mut v,
        &StageOptions::default(),
        &[&q, &tri],
        &prim,
        &LodSchemaOptions::default(),
    )
    .unwrap();
    let s = String::from_utf8(v).unwrap();
    let head = r#"def Xform "Root" (
    kind = "component"
)
{
    def Xform "Body" (
        prepend apiSchemas = ["LODRootAPI"]
    )
    {
        int lod:default:index = 0
        rel lod:heuristics = </Root/Body_lodHeuristic>

        def Mesh "LOD0"
        {
"#;
    assert!(s.contains(head), "{s}");
    assert!(s.contains("\n\n        def Mesh \"LOD1\"\n"), "{s}");
    let tail = r#"    }

    def LODScreenSizeHeuristic "Body_lodHeuristic"
    {
        float3[] extent = [(0, 0, -1), (2, 1, 0)]
        uniform token lod:domain = "imaging"
        uniform float[] thresholds = [0.375]
    }
}
"#;
    assert!(s.ends_with(tail), "{s}");
    // Only the default level is visible, and the level order is the child order.
    let lod0 = s.find("def Mesh \"LOD0\"").unwrap();
    let lod1 = s.find("def Mesh \"LOD1\"").unwrap();
    assert!(lod0 < lod1);
    assert!(s[lod0..lod1].contains("token visibility = \"inherited\""));
    assert!(s[lod1..].contains("token visibility = \"invisible\""));
    assert_eq!(s.matches("token visibility").count(), 2);

    // The second level as the default, with explicit thresholds.
    let lod = LodSchemaOptions::default()
        .with_default_index(1)
        .with_screen_size_thresholds(vec![0.2]);
    let mut v = Vec::new();
    write_lod_schema(&mut v, &StageOptions::default(), &[&q, &tri], &prim, &lod).unwrap();
    let s = String::from_utf8(v).unwrap();
    assert!(s.contains("int lod:default:index = 1\n"));
    assert!(s.contains("uniform float[] thresholds = [0.2]\n"));
    let lod1 = s.find("def Mesh \"LOD1\"").unwrap();
    assert!(s[lod1..].contains("token visibility = \"inherited\""));

    // Checked before anything is written.
    let bad = [
        LodSchemaOptions::default().with_default_index(2),
        LodSchemaOptions::default().with_screen_size_thresholds(vec![]),
        LodSchemaOptions::default().with_screen_size_thresholds(vec![f32::NAN]),
        LodSchemaOptions::default().with_screen_size_thresholds(vec![0.0]),
    ];
    for lod in bad {
        let mut v = Vec::new();
        let e = write_lod_schema(&mut v, &StageOptions::default(), &[&q, &tri], &prim, &lod);
        assert_eq!(e.unwrap_err().code(), "invalid_request", "{lod:?}");
        assert!(v.is_empty());
    }
    let mut v = Vec::new();
    let three = [&q, &tri, &tri];
    let lod = LodSchemaOptions::default().with_screen_size_thresholds(vec![0.1, 0.2]);
    let e = write_lod_schema(&mut v, &StageOptions::default(), &three, &prim, &lod);
    assert!(e.unwrap_err().to_string().contains("must not increase"));
    let e = write_lod_schema(
        &mut v,
        &StageOptions::default(),
        &[],
        &prim,
        &LodSchemaOptions::default(),
    );
    assert_eq!(e.unwrap_err().code(), "invalid_request");
    assert!(v.is_empty());
}

#[test]
fn animated_points_are_time_samples() {
    let m = quad();
    let frames: Vec<Vec<[f32; 3]>> = (0..3)
        .map(|k| m.positions.iter().map(|p| [p[0], p[1], k as f32]).collect())
        .collect();
    let mut v = Vec::new();
    let prims = [MeshPrim::new(&m).with_point_samples(&frames)];
    write_stage(&mut v, &StageOptions::default(), &prims).unwrap();
    let s = String::from_utf8(v).unwrap();
    assert!(
        s.contains("    startTimeCode = 1\n    endTimeCode = 3\n"),
        "{s}"
    );
    assert!(s.contains("point3f[] points.timeSamples = {\n"), "{s}");
    assert!(s.contains("        3: [(0, 0, 2), "), "{s}");
    assert!(s.contains("        2: [(0, 0, 1), (1, 1, 1)],\n"), "{s}");

    // A frame of another size, or with NaN, is refused before anything is written.
    let mut short = frames.clone();
    short[1].pop();
    let mut nan = frames.clone();
    nan[2][1][0] = f32::NAN;
    for (bad, why) in [(short, "frame 1 has 3 points"), (nan, "frame 2, point 1")] {
        let mut v = Vec::new();
        let e = write_stage(
            &mut v,
            &StageOptions::default(),
            &[MeshPrim::new(&m).with_point_samples(&bad)],
        )
        .unwrap_err();
        assert!(e.to_string().contains(why), "{e}");
        assert!(v.is_empty());
    }
}

#[test]
fn translate_is_a_double3_op_after_the_transform() {
    let a = quad();
    let origin = [20030.000000001, -0.5, 1e-7];
    let prims = [MeshPrim::new(&a).with_translate(origin)];
    let mut v = Vec::new();
    write_stage(&mut v, &StageOptions::default(), &prims).unwrap();
    let s = String::from_utf8(v).unwrap();
    assert!(
        s.contains(
            "        double3 xformOp:translate = (20030.000000001, -0.5, 1e-7)\n        uniform \
             token[] xformOpOrder = [\"xformOp:translate\"]\n"
        ),
        "{s}"
    );
    let mut t = [[0.0; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 2.0;
    }
    let prims = [MeshPrim::new(&a).with_transform(t).with_translate(origin)];
    let mut v = Vec::new();
    write_stage(&mut v, &StageOptions::default(), &prims).unwrap();
    let s = String::from_utf8(v).unwrap();
    assert!(
        s.contains("xformOpOrder = [\"xformOp:transform\", \"xformOp:translate\"]\n"),
        "{s}"
    );
    let bad = [MeshPrim::new(&a).with_translate([0.0, f64::NAN, 0.0])];
    let e = write_stage(&mut Vec::new(), &StageOptions::default(), &bad).unwrap_err();
    assert!(e.to_string().contains("translate"), "{e}");
}
