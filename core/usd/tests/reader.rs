//! The `.usda` reader against this crate's writer (round trips of real meshes, transforms, LOD
//! variant sets) and a catalogue of malformed stages, each with the exact error it must give.
//! (usd-core writes the stages of the independent check in `tests/usd/test_usda_input.py`.)

use std::path::PathBuf;

use tessd_mesh::Mesh;
use tessd_usd::reader::{UsdLodRoot, UsdStage, UsdVariantSet, parse_usda, read_usda};
use tessd_usd::{
    LodSchemaOptions, MeshPrim, MeshPrimOptions, StageOptions, UsdError, write_lod_schema,
    write_lod_variants, write_mesh_stage, write_stage, write_usda_file,
};

/// A mesh of the shared test data (`$TESSD_SHARED_DATA`, else `../shared/data` beside the
/// repository).
fn shared_mesh(name: &str) -> Mesh {
    let path = tessd_testdata::shared(&format!("mesh/{name}"));
    tessd_mesh::io::read_path(&path, &Default::default()).unwrap()
}

/// The first `n` faces of `m` (all its vertices kept): a stand-in for a coarser level.
fn first_faces(m: &Mesh, n: usize) -> Mesh {
    let mut out = Mesh {
        positions: m.positions.clone(),
        ..Mesh::default()
    };
    for f in m.faces().take(n) {
        out.push_face(f);
    }
    out
}

fn text(write: impl FnOnce(&mut Vec<u8>) -> Result<(), tessd_usd::UsdError>) -> String {
    let mut v = Vec::new();
    write(&mut v).unwrap();
    String::from_utf8(v).unwrap()
}

fn faces(m: &Mesh) -> Vec<Vec<u32>> {
    m.faces().map(<[u32]>::to_vec).collect()
}

fn err(text: &str) -> String {
    parse_usda(text, "x.usda").unwrap_err().to_string()
}

#[test]
fn real_mesh_round_trips_exactly() {
    let spot = shared_mesh("spot_triangulated.obj");
    let prim = MeshPrimOptions::default().with_name("spot");
    let t = text(|w| write_mesh_stage(w, &spot, &StageOptions::default(), &prim));
    let stage = parse_usda(&t, "spot.usda").unwrap();
    assert_eq!(stage.up_axis.as_deref(), Some("Z"));
    assert_eq!(stage.meters_per_unit, Some(1.0));
    assert!(stage.variant_sets.is_empty());
    assert_eq!(stage.meshes.len(), 1);
    let m = &stage.meshes[0];
    assert_eq!(
        (m.path.as_str(), &m.variant, m.visible),
        ("/Root/spot", &None, true)
    );
    // Bit-exact positions: the writer's shortest f32 text parsed back as f32.
    let bits = |m: &Mesh| {
        m.positions
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&m.mesh), bits(&spot));
    assert_eq!(faces(&m.mesh), faces(&spot));
    assert_eq!(m.mesh.uvs, spot.uvs);
    assert_eq!(m.mesh.normals, spot.normals);
    assert_eq!(m.mesh.group_names, ["spot"]);
    let composed = stage.composed().unwrap();
    assert_eq!(faces(&composed), faces(&spot));
    assert_eq!(composed.group_names, ["/Root/spot"]);
    assert_eq!(composed.face_groups, vec![0; spot.face_count()]);
    let panels = stage.variant_panels().unwrap();
    assert_eq!(panels.len(), 1);
    assert_eq!(panels[0].0, "spot");
    assert_eq!(panels[0].1, composed);
}

#[test]
fn face_groups_come_back_from_geom_subsets() {
    let mut m = shared_mesh("spot_control_mesh.obj");
    let n = m.face_count();
    m.face_groups = (0..n as u32).map(|f| f % 3).collect();
    m.group_names = vec!["body".into(), "Material.001".into(), "head".into()];
    let t =
        text(|w| write_mesh_stage(w, &m, &StageOptions::default(), &MeshPrimOptions::default()));
    let back = &parse_usda(&t, "g.usda").unwrap().meshes[0].mesh;
    assert_eq!(back.group_names, ["body", "Material_001", "head"]);
    assert_eq!(back.face_groups, m.face_groups);
    assert_eq!(faces(back), faces(&m));
}

#[test]
fn transforms_and_translates_are_applied() {
    let quad = shared_mesh("spot_control_mesh.obj");
    // 90° about Z, scale 2, then move by (10, 20, 30): rows of a row-vector matrix.
    let m = [
        [0.0, 2.0, 0.0, 0.0],
        [-2.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 2.0, 0.0],
        [10.0, 20.0, 30.0, 1.0],
    ];
    let t = [1000.5, -2000.25, 0.125];
    let prims = [
        MeshPrim::new(&quad).with_options(MeshPrimOptions::default().with_name("plain")),
        MeshPrim::new(&quad)
            .with_transform(m)
            .with_options(MeshPrimOptions::default().with_name("xf")),
        MeshPrim::new(&quad)
            .with_translate(t)
            .with_options(MeshPrimOptions::default().with_name("tr")),
        MeshPrim::new(&quad)
            .with_transform(m)
            .with_translate(t)
            .with_options(MeshPrimOptions::default().with_name("both")),
    ];
    let text = text(|w| write_stage(w, &StageOptions::default(), &prims));
    let stage = parse_usda(&text, "xf.usda").unwrap();
    let paths: Vec<_> = stage.meshes.iter().map(|m| m.path.as_str()).collect();
    assert_eq!(paths, ["/Root/plain", "/Root/xf", "/Root/tr", "/Root/both"]);
    let apply = |p: [f64; 3], m: &[[f64; 4]; 4]| -> [f64; 3] {
        std::array::from_fn(|c| p[0] * m[0][c] + p[1] * m[1][c] + p[2] * m[2][c] + m[3][c])
    };
    let shift = |p: [f64; 3]| [p[0] + t[0], p[1] + t[1], p[2] + t[2]];
    for (k, expect) in [
        &(|p| p) as &dyn Fn([f64; 3]) -> [f64; 3],
        &|p| apply(p, &m),
        &|p| shift(p),
        // The translate comes after the transform in xformOpOrder: applied first.
        &|p| apply(shift(p), &m),
    ]
    .into_iter()
    .enumerate()
    {
        let got = &stage.meshes[k].mesh;
        assert_eq!(faces(got), faces(&quad));
        for (v, q) in quad.positions.iter().enumerate() {
            let e = expect(q.map(f64::from)).map(|x| x as f32);
            let g = got.positions[v];
            if k < 3 {
                // One op: the same arithmetic, bit for bit.
                assert_eq!(g, e, "{} vertex {v}", paths[k]);
            } else {
                // Two ops are composed into one matrix first (as usd-core does), which may
                // round the last f32 bit differently.
                let close = (0..3).all(|c| (g[c] - e[c]).abs() <= e[c].abs() * 2.0 * f32::EPSILON);
                assert!(close, "{} vertex {v}: {g:?} vs {e:?}", paths[k]);
            }
        }
    }
    let composed = stage.composed().unwrap();
    assert_eq!(composed.face_count(), 4 * quad.face_count());
    assert_eq!(
        composed.group_names,
        ["/Root/plain", "/Root/xf", "/Root/tr", "/Root/both"]
    );
}

fn lod_levels() -> Vec<Mesh> {
    let spot = shared_mesh("spot_triangulated.obj");
    vec![
        spot.clone(),
        first_faces(&spot, 2000),
        first_faces(&spot, 500),
    ]
}

#[test]
fn lod_variants_give_one_panel_per_level() {
    let levels = lod_levels();
    let refs: Vec<&Mesh> = levels.iter().collect();
    let prim = MeshPrimOptions::default().with_name("spot");
    let t = text(|w| write_lod_variants(w, &StageOptions::default(), &refs, &prim));
    let stage = parse_usda(&t, "lods.usda").unwrap();
    assert_eq!(
        stage.variant_sets,
        [UsdVariantSet {
            prim: "/Root".into(),
            name: "LOD".into(),
            variants: vec!["LOD0".into(), "LOD1".into(), "LOD2".into()],
            selected: Some("LOD0".into()),
        }]
    );
    for (i, m) in stage.meshes.iter().enumerate() {
        assert_eq!(m.path, "/Root/spot");
        assert_eq!(m.variant, Some(("LOD".to_string(), format!("LOD{i}"))));
        assert_eq!(faces(&m.mesh), faces(&levels[i]));
    }
    let panels = stage.variant_panels().unwrap();
    let summary: Vec<_> = panels
        .iter()
        .map(|(l, m)| (l.as_str(), m.face_count()))
        .collect();
    assert_eq!(summary, [("LOD0", 5856), ("LOD1", 2000), ("LOD2", 500)]);
    assert_eq!(panels[2].1.group_names, ["/Root/spot {LOD2}"]);
    let composed = stage.composed().unwrap();
    assert_eq!(faces(&composed), faces(&levels[0]));
    assert_eq!(composed.group_names, ["/Root/spot {LOD0}"]);
}

#[test]
fn lod_schema_shows_only_the_default_level() {
    let levels = lod_levels();
    let refs: Vec<&Mesh> = levels.iter().collect();
    let lod = LodSchemaOptions::default().with_default_index(1);
    let t = text(|w| {
        write_lod_schema(
            w,
            &StageOptions::default(),
            &refs,
            &MeshPrimOptions::default(),
            &lod,
        )
    });
    let stage = parse_usda(&t, "usdlod.usda").unwrap();
    let seen: Vec<_> = stage
        .meshes
        .iter()
        .map(|m| (m.path.as_str(), m.visible))
        .collect();
    assert_eq!(
        seen,
        [
            ("/Root/mesh/LOD0", false),
            ("/Root/mesh/LOD1", true),
            ("/Root/mesh/LOD2", false)
        ]
    );
    assert_eq!(stage.composed().unwrap().face_count(), 2000);
    assert_eq!(
        stage.lod_roots,
        [UsdLodRoot {
            prim: "/Root/mesh".into(),
            levels: vec!["LOD0".into(), "LOD1".into(), "LOD2".into()],
        }]
    );
    // Every level a panel, as for a LOD variant set, whatever its own visibility.
    let panels = stage.variant_panels().unwrap();
    let summary: Vec<_> = panels
        .iter()
        .map(|(l, m)| (l.as_str(), m.face_count()))
        .collect();
    assert_eq!(summary, [("LOD0", 5856), ("LOD1", 2000), ("LOD2", 500)]);
}

#[test]
fn files_are_read_and_binary_ones_refused() {
    let dir = tempfile::tempdir().unwrap();
    let quad = shared_mesh("spot_control_mesh.obj");
    let path = dir.path().join("Control.USDA");
    write_usda_file(&path, |w| {
        write_mesh_stage(
            w,
            &quad,
            &StageOptions::default(),
            &MeshPrimOptions::default(),
        )
    })
    .unwrap();
    let stage = read_usda(&path).unwrap();
    assert_eq!(stage.source, path.display().to_string());
    assert_eq!(stage.variant_panels().unwrap()[0].0, "Control");

    let write = |name: &str, bytes: &[u8]| -> PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let usdc = write("part.usdc", b"PXR-USDC\x00\x08\x00\x00\x00\x00\x00\x00");
    let e = read_usda(&usdc).unwrap_err();
    assert!(matches!(e, UsdError::Unsupported(_)), "{e:?}");
    assert_eq!(e.code(), "unsupported");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: a binary USD crate file (PXR-USDC); binary crate files are not read: export \
             the stage as .usda (usdcat in.usdc -o out.usda)",
            usdc.display()
        )
    );
    // The magic decides, not the extension.
    let disguised = write("part.usda", b"PXR-USDC\x00\x08");
    assert!(
        read_usda(&disguised)
            .unwrap_err()
            .to_string()
            .contains("binary crate files are not read")
    );
    let usdz = write("part.usdz", b"PK\x03\x04\x14\x00");
    let e = read_usda(&usdz).unwrap_err().to_string();
    assert!(e.contains("a .usdz package") && e.contains(".usda"), "{e}");
    let e = read_usda(&dir.path().join("missing.usda")).unwrap_err();
    assert_eq!(e.code(), "io");
    let latin1 = write("latin1.usda", b"#usda 1.0\n\ndef \"caf\xe9\" {}\n");
    assert_eq!(
        read_usda(&latin1).unwrap_err().to_string(),
        format!("{}:3: the text is not valid UTF-8", latin1.display())
    );
    assert!(
        parse_usda("PXR-USDC", "s")
            .unwrap_err()
            .to_string()
            .contains("binary")
    );
}

#[test]
fn truncated_files_are_errors_naming_a_line() {
    let cage = shared_mesh("spot_control_mesh.obj");
    let levels = [cage.clone(), first_faces(&cage, 100)];
    let refs: Vec<&Mesh> = levels.iter().collect();
    let full = text(|w| {
        write_lod_variants(
            w,
            &StageOptions::default(),
            &refs,
            &MeshPrimOptions::default(),
        )
    });
    let lines = full.lines().count();
    let root_at = full.find("def Xform").unwrap();
    let mut errors = 0;
    // Every byte offset of the head and tail, every 7th in between.
    let offsets = (0..full.len()).filter(|&k| k < 3000 || k + 3000 > full.len() || k % 7 == 0);
    for k in offsets {
        let cut = &full[..k];
        match parse_usda(cut, "cut.usda") {
            Err(UsdError::Parse {
                path,
                line,
                message,
            }) => {
                assert_eq!(path, "cut.usda");
                assert!((1..=lines + 1).contains(&line), "offset {k}: line {line}");
                assert!(!message.is_empty());
                errors += 1;
            }
            // Whole prims only: before the root prim, or all of it.
            Ok(stage) => assert!(
                k + 2 >= full.len() || (k <= root_at && stage.meshes.is_empty()),
                "offset {k} parsed: {stage:?}"
            ),
            Err(e) => panic!("offset {k}: {e:?}"),
        }
    }
    assert!(errors > 3000);
    // A cut inside the LOD1 mesh names it.
    let at = full.find("\"LOD1\"").unwrap() + 200;
    let e = parse_usda(&full[..at], "cut.usda").unwrap_err().to_string();
    assert!(e.contains("/Root/mesh"), "{e}");
}

const QUAD: &str = r#"#usda 1.0
def Xform "Root"
{
    def Mesh "mesh"
    {
        int[] faceVertexCounts = COUNTS
        int[] faceVertexIndices = INDICES
        point3f[] points = POINTS
    }
}
"#;

fn quad(counts: &str, indices: &str, points: &str) -> String {
    QUAD.replace("COUNTS", counts)
        .replace("INDICES", indices)
        .replace("POINTS", points)
}

const POINTS: &str = "[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]";

#[test]
fn malformed_meshes_name_prim_attribute_and_line() {
    assert_eq!(
        parse_usda(&quad("[4]", "[0, 1, 2, 3]", POINTS), "x.usda")
            .unwrap()
            .meshes[0]
            .mesh
            .face_count(),
        1
    );
    for (stage, want) in [
        (
            quad("[4]", "[0, 1, 2, 4]", POINTS),
            "x.usda:7: /Root/mesh.faceVertexIndices: entry 3 is 4, out of range for 4 points",
        ),
        (
            quad("[4]", "[0, 1, 2, -1]", POINTS),
            "x.usda:7: /Root/mesh.faceVertexIndices: entry 3 is -1, out of range for 4 points",
        ),
        (
            quad(
                "[4]",
                "[0, 1, 2, 3]",
                "[(0, 0, 0), (1, nan, 0), (1, 1, 0), (0, 1, 0)]",
            ),
            "x.usda:8: /Root/mesh.points: point 1 is not finite (1, NaN, 0)",
        ),
        (
            quad(
                "[4]",
                "[0, 1, 2, 3]",
                "[(0, 0, 0), (1, 0, 0), (1, 1, -inf), (0, 1, 0)]",
            ),
            "x.usda:8: /Root/mesh.points: point 2 is not finite (1, 1, -inf)",
        ),
        (
            quad("[3]", "[0, 1, 2, 3]", POINTS),
            "x.usda:6: /Root/mesh.faceVertexCounts: the counts add up to 3 but \
             faceVertexIndices has 4 entries",
        ),
        (
            quad("[4, 3]", "[0, 1, 2, 3]", POINTS),
            "x.usda:6: /Root/mesh.faceVertexCounts: the counts add up to more than the 4 \
             entries of faceVertexIndices (at face 1, count 3)",
        ),
        // A hostile count: refused before anything is sized from it.
        (
            quad("[4000000000000000000000]", "[0, 1, 2, 3]", POINTS),
            "x.usda:6: /Root/mesh.faceVertexCounts: the counts add up to more than the 4 \
             entries of faceVertexIndices (at face 0, count 4000000000000000000000)",
        ),
        (
            quad("[2, 2]", "[0, 1, 2, 3]", POINTS),
            "x.usda:6: /Root/mesh.faceVertexCounts: face 0 has 2 vertices; a face needs at \
             least 3",
        ),
        (
            quad("[4.5]", "[0, 1, 2, 3]", POINTS),
            "x.usda:6: /Root/mesh.faceVertexCounts: entry 0 is 4.5, not an integer",
        ),
        (
            quad("[4]", "[0, 1, 2, 3]", "[(0, 0), (1, 0), (1, 1), (0, 1)]"),
            "x.usda:8: /Root/mesh.points: expected 3 components per element, found 2",
        ),
        (
            quad("[4]", "[0, 1, 2, 3]", "None"),
            "x.usda:4: /Root/mesh: the Mesh has no points (a required attribute)",
        ),
        (
            QUAD.replace("        int[] faceVertexIndices = INDICES\n", "")
                .replace("COUNTS", "[4]")
                .replace("POINTS", POINTS),
            "x.usda:4: /Root/mesh: the Mesh has no faceVertexIndices (a required attribute)",
        ),
        (
            quad(
                "[4]",
                "[0, 1, 2, 3]",
                "[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]\n\
                 def GeomSubset \"red\" { uniform token elementType = \"face\"\n\
                 int[] indices = [0, 1] }",
            ),
            "x.usda:10: /Root/mesh/red.indices: entry 1 is 1, out of range for 1 faces",
        ),
        (
            quad(
                "[4]",
                "[0, 1, 2, 3]",
                "[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)",
            ),
            "x.usda:9: /Root/mesh.points: expected ',' or ']' after element 3, found '}'",
        ),
        (
            quad(
                "[4]",
                "[0, 1, 2, 3]",
                "[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)] (\n",
            ),
            "x.usda:10: /Root/mesh.points: in the attribute's metadata: expected a name, found '}'",
        ),
    ] {
        assert_eq!(err(&stage), want, "{stage}");
    }
}

#[test]
fn hostile_xform_ops_are_named() {
    let with_ops = |ops: &str| {
        QUAD.replace(
            "    def Mesh \"mesh\"\n",
            &format!("{ops}\n    def Mesh \"mesh\"\n"),
        )
        .replace("COUNTS", "[4]")
        .replace("INDICES", "[0, 1, 2, 3]")
        .replace("POINTS", POINTS)
    };
    for (ops, want) in [
        (
            "    uniform token[] xformOpOrder = [\"xformOp:translate\"]",
            "x.usda:4: /Root.xformOpOrder names xformOp:translate, which the prim does not author",
        ),
        (
            "    float3 xformOp:scale = (1, 0, 1)\n    \
             uniform token[] xformOpOrder = [\"!invert!xformOp:scale\"]",
            "x.usda:4: /Root.xformOp:scale: !invert! of a singular transform",
        ),
        (
            "    float xformOp:shear = 1\n    uniform token[] xformOpOrder = [\"xformOp:shear\"]",
            "x.usda:4: /Root.xformOp:shear: unsupported transform op type \"shear\"",
        ),
        (
            "    double3 xformOp:translate = (1, 2)\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]",
            "x.usda:4: /Root.xformOp:translate: expected 3 numbers, found 2",
        ),
        (
            "    float3 xformOp:scale = (1e39, 1, 1)\n    \
             uniform token[] xformOpOrder = [\"xformOp:scale\"]",
            "x.usda:4: /Root.xformOp:scale: the value inf is not finite",
        ),
    ] {
        assert_eq!(err(&with_ops(ops)), want, "{ops}");
    }
}

/// A hand-written stage with what other tools write: nested Xforms with rotations and
/// `!invert!` pivots, time samples, relationships, connections, over/class/inactive prims,
/// two variant sets (one selected, one not), a nested set, metadata of every kind.
const HAND_WRITTEN: &str = r#"#usda 1.0
(
    "A hand-written stage"
    defaultPrim = "World"
    endTimeCode = 10
    metersPerUnit = 0.01
    upAxis = "Y"
    customLayerData = {
        string creator = "a \"tool\""
        dictionary nested = { int[] a = [1, 2] }
    }
)

class "_base" { def Mesh "ghost" { int[] faceVertexCounts = [3] } }

def Xform "World" (
    kind = "assembly"
    variants = {
        string shape = "tri"
    }
    prepend variantSets = ["shape", "look"]
    customData = { string note = '''multi
line "text"''' }
)
{
    double3 xformOp:translate = (0, 0, 5)
    float xformOp:rotateZ.timeSamples = {
        3: 45,
        1: 90,
    }
    double3 xformOp:translate:pivot = (1, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:translate:pivot", "xformOp:rotateZ", "!invert!xformOp:translate:pivot"]
    custom rel material:binding = </Looks/red>

    def Scope "Geo" {
        double3 xformOp:translate = (100, 0, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]

        def Mesh "base" (
            prepend apiSchemas = ["MaterialBindingAPI"]
            references = @./other.usda@</Thing> (offset = 2; scale = 1)
        )
        {
            float3 xformOp:scale = (2, 2, 2)
            uniform token[] xformOpOrder = ["xformOp:scale"]
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(1, 0, 0), (2, 0, 0), (1, 1, 0)]
            point3f[] points.timeSamples = {
                2: [(0, 0, 0), (0, 0, 0), (0, 0, 0)],
                1: [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
            }
            color3f[] primvars:displayColor = [(1, 0, 0)] (
                interpolation = "constant"
            )
            color3f inputs:color.connect = </Looks/red.outputs:rgb>
            rel proxyPrim
        }
        over "overridden" { def Mesh "notDefined" { int[] faceVertexCounts = [3] } }
        def Mesh "inactive" ( active = false ) { int[] faceVertexCounts = [3] }
        def Mesh "hidden" {
            token visibility = "invisible"
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        }
    }
    variantSet "shape" = {
        "quad" {
            def Mesh "q" {
                int[] faceVertexCounts = [4]
                int[] faceVertexIndices = [0, 1, 2, 3]
                point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
            }
        }
        "tri" (
            variants = { string detail = "fine" }
        ) {
            double3 xformOp:translate = (9, 9, 9)
            variantSet "detail" = {
                "coarse" { def Mesh "t" { int[] faceVertexCounts = [3] } }
                "fine" {
                    def Mesh "t" {
                        int[] faceVertexCounts = [3, 3]
                        int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]
                        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
                    }
                }
            }
        }
    }
    variantSet "look" = {
        "plain" {}
        "fancy" {
            def Mesh "ribbon" {
                int[] faceVertexCounts = [3]
                int[] faceVertexIndices = [0, 1, 2]
                point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
            }
        }
    }
}

over "Looks" { def Material "red" {} }
"#;

#[test]
fn hand_written_stage() {
    let stage: UsdStage = parse_usda(HAND_WRITTEN, "/some/where/hand.usda").unwrap();
    assert_eq!(stage.up_axis.as_deref(), Some("Y"));
    assert_eq!(stage.meters_per_unit, Some(0.01));
    let seen: Vec<_> = stage
        .meshes
        .iter()
        .map(|m| {
            (
                m.path.as_str(),
                m.variant.clone().map(|v| format!("{}={}", v.0, v.1)),
                m.visible,
            )
        })
        .collect();
    let v = |s: &str| Some(s.to_string());
    assert_eq!(
        seen,
        [
            ("/World/Geo/base", None, true),
            ("/World/Geo/hidden", None, false),
            ("/World/q", v("shape=quad"), true),
            ("/World/t", v("shape=tri"), true),
            ("/World/ribbon", v("look=fancy"), true),
        ]
    );
    let sets: Vec<_> = stage
        .variant_sets
        .iter()
        .map(|s| {
            (
                s.prim.as_str(),
                s.name.as_str(),
                s.variants.join(","),
                s.selected.clone(),
            )
        })
        .collect();
    assert_eq!(
        sets,
        [
            ("/World", "shape", "quad,tri".to_string(), v("tri")),
            ("/World", "detail", "coarse,fine".to_string(), v("fine")),
            ("/World", "look", "plain,fancy".to_string(), None),
        ]
    );
    // /World: p → translate by -pivot, rotate 90° (the earliest sample) about Z, + pivot,
    // + (0, 0, 5). The Scope's translate is ignored (a Scope is not Xformable). base: scale 2
    // of the earliest points sample.
    let base = &stage.meshes[0].mesh;
    let world = |p: [f32; 3]| {
        let (x, y) = (f64::from(p[0]) - 1.0, f64::from(p[1]));
        [(-y + 1.0) as f32, x as f32, p[2] + 5.0]
    };
    let expect: Vec<[f32; 3]> = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]
        .into_iter()
        .map(world)
        .collect();
    for (got, want) in base.positions.iter().zip(&expect) {
        assert!(
            (0..3).all(|k| (got[k] - want[k]).abs() < 1e-6),
            "{got:?} vs {want:?}"
        );
    }
    // Composed: base + the selected "tri" (its "fine" detail) + "look"'s first variant
    // ("plain", empty); not the hidden mesh.
    let composed = stage.composed().unwrap();
    assert_eq!(composed.group_names, ["/World/Geo/base", "/World/t {tri}"]);
    assert_eq!(composed.face_count(), 3);
    // Panels by the first set holding meshes ("shape"), the rest as composed shows it.
    let panels = stage.variant_panels().unwrap();
    let summary: Vec<_> = panels
        .iter()
        .map(|(l, m)| (l.as_str(), m.group_names.clone()))
        .collect();
    assert_eq!(
        summary,
        [
            (
                "quad",
                vec!["/World/Geo/base".to_string(), "/World/q {quad}".to_string()]
            ),
            (
                "tri",
                vec!["/World/Geo/base".to_string(), "/World/t {tri}".to_string()]
            ),
        ]
    );
}

#[test]
fn stages_without_meshes() {
    let e = parse_usda("#usda 1.0\ndef Xform \"Root\" {}\n", "empty.usda").unwrap();
    assert!(e.meshes.is_empty());
    assert_eq!(
        e.composed().unwrap_err().to_string(),
        "empty.usda: the stage has no visible Mesh prim"
    );
    assert_eq!(e.composed().unwrap_err().code(), "invalid_mesh");
    assert_eq!(
        err("def Mesh \"m\" {}"),
        "x.usda:1: not a USD ASCII layer: the first line must be \"#usda 1.0\""
    );
}

/// A deterministic mutation fuzzer (xorshift): bytes replaced by syntax characters, ranges
/// deleted or repeated, over the hand-written stage and a writer's LOD stage. Whatever comes
/// out must be an error naming a line, or a stage whose meshes are valid; never a panic.
#[test]
fn mutated_stages_never_panic() {
    let cage = shared_mesh("spot_control_mesh.obj");
    let lod = text(|w| {
        let levels = [&cage, &cage];
        write_lod_variants(
            w,
            &StageOptions::default(),
            &levels,
            &MeshPrimOptions::default(),
        )
    });
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut rand = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    const ALPHABET: &[u8] = b"{}[]()\"'@<>=,:.-+0123456789eE \n#abcdefNonedefoverclass!";
    let (mut parsed, mut refused) = (0, 0);
    for base in [HAND_WRITTEN.as_bytes(), lod.as_bytes()] {
        for _ in 0..1500 {
            let mut b = base.to_vec();
            for _ in 0..1 + rand(4) {
                let at = rand(b.len());
                match rand(3) {
                    0 => b[at] = ALPHABET[rand(ALPHABET.len())],
                    1 => {
                        let end = (at + rand(40)).min(b.len());
                        b.drain(at..end);
                    }
                    _ => {
                        let end = (at + rand(40)).min(b.len());
                        let piece = b[at..end].to_vec();
                        b.splice(at..at, piece);
                    }
                }
            }
            let Ok(t) = String::from_utf8(b) else {
                continue;
            };
            match parse_usda(&t, "fuzz.usda") {
                Ok(stage) => {
                    parsed += 1;
                    for m in &stage.meshes {
                        m.mesh.validate().unwrap();
                    }
                    if let Ok(m) = stage.composed() {
                        m.validate().unwrap();
                    }
                    let _ = stage.variant_panels();
                }
                Err(UsdError::Parse { line, .. }) => {
                    assert!((1..=t.lines().count() + 1).contains(&line));
                    refused += 1;
                }
                Err(e) => panic!("{e:?}"),
            }
        }
    }
    assert!(
        parsed > 100 && refused > 1000,
        "{parsed} parsed, {refused} refused"
    );
}
