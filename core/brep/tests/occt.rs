//! The OCCT BREP reader (`tessd_brep::occt`): real files give the document the Python exporters
//! write (counts, surface types, orientation, loops, edges), hand-written texts give exactly
//! the expected document, broken texts give errors naming the line and element, and no input
//! makes it panic.

use serde_json::Value;
use tessd_brep::occt::{self, OcctErrorKind, ReadOptions};
use tessd_brep::{Curve, DVec2, DVec3, Document, Surface, Units};

fn read(text: &str) -> Document {
    let doc = occt::read(text, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    doc.validate().unwrap_or_else(|e| panic!("{e}"));
    doc
}

fn error(text: &str) -> occt::OcctError {
    match occt::read(text, &ReadOptions::default()) {
        Ok(_) => panic!("read a text that should fail"),
        Err(e) => e,
    }
}

fn shared_text(name: &str) -> String {
    let path = tessd_testdata::shared(&format!("brep/{name}"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn fixture(name: &str) -> String {
    let path = format!("{}/tests/data/occt/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// What OCCT and the OCP exporter say of a shared BREP file.
struct Golden {
    name: &'static str,
    faces: usize,
    edges: usize,
    /// Faces per surface type in the OCP exporter's document.
    types: &'static [(&'static str, usize)],
    /// Faces with `reversed` set in it.
    reversed: usize,
}

/// The shared BREP files (all "CASCADE Topology V1", with triangulations and polygons but for
/// face2 and freecad_drilling1_body). Counts from OCP 7.9 (`.venv-cad`), independently of this
/// reader:
///
/// ```python
/// s = TopoDS_Shape(); BRepTools.Read_s(s, path, BRep_Builder())
/// fm = TopTools_IndexedMapOfShape(); TopExp.MapShapes_s(s, TopAbs_FACE, fm)      # faces
/// em = TopTools_IndexedMapOfShape()
/// for i in range(1, fm.Extent() + 1): TopExp.MapShapes_s(fm.FindKey(i), TopAbs_EDGE, em)
/// ```
///
/// (`em.Extent()` equals `MapShapes(s, EDGE)` on every file); surface types and reversed faces
/// from `PYTHONPATH=python .venv-cad/bin/python -m tessd.brep export --no-sew FILE OUT.json`.
const SHARED: &[Golden] = &[
    Golden {
        name: "CrankArm.brep",
        faces: 53,
        edges: 138,
        types: &[
            ("plane", 21),
            ("cylinder", 11),
            ("cone", 5),
            ("bspline", 16),
        ],
        reversed: 30,
    },
    Golden {
        name: "Pump_Nut.brep",
        faces: 25,
        edges: 67,
        types: &[("plane", 8), ("cylinder", 1), ("cone", 14), ("torus", 2)],
        reversed: 2,
    },
    Golden {
        name: "bottle.brep",
        faces: 71,
        edges: 157,
        types: &[
            ("plane", 13),
            ("cylinder", 31),
            ("sphere", 16),
            ("torus", 9),
            ("bspline", 2),
        ],
        reversed: 33,
    },
    Golden {
        name: "face2.brep",
        faces: 1,
        edges: 30,
        types: &[("plane", 1)],
        reversed: 0,
    },
    Golden {
        name: "freecad_drilling1_body.brep",
        faces: 58,
        edges: 135,
        types: &[("plane", 29), ("cylinder", 27), ("extrusion", 2)],
        reversed: 41,
    },
    Golden {
        name: "shell1.brep",
        faces: 99,
        edges: 224,
        types: &[("bspline", 99)],
        reversed: 0,
    },
];

/// The largest distance, in units of the edge's tolerance, between a trim's point on its
/// surface and its edge's 3D point at the same parameter, over the trims whose range is their
/// edge's (OCCT's same-parameter edges): where pcurve, surface, locations, mirroring and
/// orientation are all right, the pcurves lie on their edges within the file's tolerance.
fn worst_pcurve_gap(doc: &Document) -> f64 {
    let edges = doc.edges.as_ref().unwrap();
    let mut worst: f64 = 0.0;
    for face in &doc.faces {
        for trim in face.loops.iter().flat_map(|l| &l.trims) {
            let Some(edge) = trim.edge.map(|id| &edges[id as usize - 1]) else {
                continue;
            };
            let Some(curve) = &edge.curve else {
                continue;
            };
            let (a, b) = (
                trim.range[0].min(trim.range[1]),
                trim.range[0].max(trim.range[1]),
            );
            let same = |x: f64, y: f64| (x - y).abs() <= 1e-9 * (1.0 + x.abs());
            if !(same(a, edge.range[0]) && same(b, edge.range[1])) {
                continue;
            }
            for k in 0..=8 {
                let t = a + (b - a) * f64::from(k) / 8.0;
                let uv = trim.curve.point(t);
                let p = face.surface.point(uv[0], uv[1]);
                let d = (p - curve.point(t)).length();
                worst = worst.max(d / edge.tolerance.unwrap().max(1e-7));
            }
        }
    }
    worst
}

#[test]
fn every_shared_brep_file_reads_validates_and_numbers_like_occt() {
    let dir = tessd_testdata::shared("brep");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.to_lowercase().ends_with(".brep"))
        .collect();
    on_disk.sort();
    let mut golden: Vec<String> = SHARED.iter().map(|g| g.name.to_string()).collect();
    golden.sort();
    assert_eq!(on_disk, golden, "a shared .brep file without golden counts");

    for g in SHARED {
        let text = shared_text(g.name);
        assert!(occt::is_occt_brep(&text), "{}", g.name);
        let doc = read(&text);
        let edges = doc.edges.as_ref().unwrap();
        assert_eq!(
            (doc.faces.len(), edges.len()),
            (g.faces, g.edges),
            "{}",
            g.name
        );
        assert!(
            doc.faces
                .iter()
                .enumerate()
                .all(|(i, f)| f.id == i as u64 + 1)
        );
        assert!(edges.iter().enumerate().all(|(i, e)| e.id == i as u64 + 1));
        let stats = doc.stats();
        for &(t, n) in g.types {
            assert_eq!(stats.faces_by_surface[t], n, "{}: {t} faces", g.name);
        }
        let reversed = doc.faces.iter().filter(|f| f.reversed).count();
        assert_eq!(reversed, g.reversed, "{}: reversed faces", g.name);
        // Every edge bounds a face (a shell's border edges bound one).
        assert!(edges.iter().all(|e| !e.faces.is_empty()), "{}", g.name);
        // The files' own pcurves stray up to 2.22 edge tolerances from their edges (bottle
        // face 2: OCCT's BRep_Tool on the same samples measures the same). Pump_Nut's
        // hyperbolas are rational B-splines whose parameter equals the hyperbola's only at the
        // knots: its cone pcurves (B-splines in the hyperbola's parameter) sit off the edge's
        // point at the same parameter between knots.
        let limit = if g.name == "Pump_Nut.brep" { 1e6 } else { 2.5 };
        let gap = worst_pcurve_gap(&doc);
        assert!(
            gap <= limit,
            "{}: pcurves {gap} edge tolerances off",
            g.name
        );
        println!(
            "{}: {} faces, {} edges, pcurves within {gap:.3} edge tolerances",
            g.name, g.faces, g.edges
        );
    }
}

#[test]
fn units_and_source_are_the_options() {
    let options = ReadOptions {
        units: Units::Inches,
        source: Some("bottle.brep".into()),
    };
    let doc = occt::read(&shared_text("bottle.brep"), &options).unwrap();
    assert_eq!(
        (doc.units, doc.source.as_deref()),
        (Units::Inches, Some("bottle.brep"))
    );
    // Coordinates are not scaled: the bottle is 70 high, whatever the unit.
    let bb = doc.bounding_box().unwrap();
    assert!((bb.size()[0] - 70.0).abs() < 1e-6, "{:?}", bb.size());
}

/// Compares two JSON values: numbers within 1e-9 relative, `null` as absent.
fn same_json(path: &str, a: &Value, b: &Value, out: &mut Vec<String>) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() > 1e-9 * (1.0 + x.abs() + y.abs()) {
                out.push(format!("{path}: {x} ≠ {y}"));
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                out.push(format!("{path}: {} items ≠ {}", x.len(), y.len()));
                return;
            }
            for (i, (x, y)) in x.iter().zip(y).enumerate() {
                same_json(&format!("{path}[{i}]"), x, y, out);
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            for k in x.keys().chain(y.keys()) {
                let (u, v) = (
                    x.get(k).unwrap_or(&Value::Null),
                    y.get(k).unwrap_or(&Value::Null),
                );
                same_json(&format!("{path}.{k}"), u, v, out);
            }
        }
        _ if a == b => {}
        _ => out.push(format!("{path}: {a} ≠ {b}")),
    }
}

/// Our document against the OCP exporter's for the same shape: faces and edges equal but for
/// rounding; bounds (theirs OCCT's UVBounds widened, ours the trims' extent) within 1 % of
/// their size.
fn assert_same_as_exporter(ours: &Document, exporter: &str) {
    let theirs: Value = serde_json::from_str(exporter).unwrap();
    let mut ours = serde_json::to_value(ours).unwrap();
    let mut diffs = Vec::new();
    for (f, g) in ours["faces"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .zip(theirs["faces"].as_array().unwrap())
    {
        let (b, c) = (f["bounds"].take(), &g["bounds"]);
        let b: Vec<f64> = serde_json::from_value(b).unwrap();
        let c: Vec<f64> = serde_json::from_value(c.clone()).unwrap();
        let size = (c[1] - c[0]).hypot(c[3] - c[2]);
        let off = b
            .iter()
            .zip(&c)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(
            off <= 0.01 * size,
            "face {}: bounds {b:?} vs {c:?}",
            f["id"]
        );
        f["bounds"] = g["bounds"].clone();
    }
    same_json("faces", &ours["faces"], &theirs["faces"], &mut diffs);
    same_json("edges", &ours["edges"], &theirs["edges"], &mut diffs);
    assert!(
        diffs.is_empty(),
        "{} differences: {:#?}",
        diffs.len(),
        &diffs[..diffs.len().min(20)]
    );
}

#[test]
fn versions_2_and_3_written_by_ocp_give_the_exporters_document() {
    // core/brep/tests/data/occt: red_cube_blue_cylinder.step read by OCP 7.9, written by
    // BRepTools.Write_s as VERSION_2 (UV points after each pcurve) and, meshed with normals,
    // VERSION_3 (triangulations with normals); cube_cylinder.ocp.json is ocp.export_topods of
    // that shape (sew=False).
    let exporter = fixture("cube_cylinder.ocp.json");
    for name in ["cube_cylinder.v2.brep", "cube_cylinder.v3.brep"] {
        let text = fixture(name);
        let doc = read(&text);
        assert_eq!(
            (doc.faces.len(), doc.edges.as_ref().unwrap().len()),
            (9, 15)
        );
        assert_same_as_exporter(&doc, &exporter);
        assert!(worst_pcurve_gap(&doc) <= 1.5, "{name}");
    }
}

#[test]
fn a_periodic_bspline_across_its_seam_becomes_its_segment() {
    // A planar face bounded by one edge on a periodic rational B-spline (knots 0…5) over
    // [3.7, 8.7]: OCP's exporter cuts the segment with GeomConvert; the reader with knot
    // insertion. Written by OCP 7.9 (BRepTools.Write_s, VERSION_3).
    let doc = read(&fixture("periodic_spline.v3.brep"));
    assert_same_as_exporter(&doc, &fixture("periodic_spline.ocp.json"));
    let edge = &doc.edges.as_ref().unwrap()[0];
    let Some(Curve::Bspline(b)) = &edge.curve else {
        panic!("{:?}", edge.curve);
    };
    assert!(!b.periodic);
    assert_eq!(edge.range, [3.7, 8.7]);
}

const SQUARE: &str = "DBRep_DrawableShape

CASCADE Topology V1, (c) Matra-Datavision
Locations 0
Curve2ds 4
1 0 0 1 0 
1 1 0 0 1 
1 1 1 -1 0 
1 0 1 0 -1 
Curves 4
1 0 0 0 1 0 0 
1 1 0 0 0 1 0 
1 1 1 0 -1 0 0 
1 0 1 0 0 -1 0 
Polygon3D 0
PolygonOnTriangulations 0
Surfaces 1
1 0 0 0 0 0 1 1 0 0 0 1 0 
Triangulations 0

TShapes 10
Ve
1e-07
0 0 0
0 0

0101101
*
Ve
0.001
1 0 0
0 0

0101101
*
Ed
 1e-07 1 1 0
1  1 0 0 1
2  1 1 0 0 1
0

0101000
+10 0 -9 0 *
Ve
0.002
1 1 0
0 0

0101101
*
Ed
 1e-07 1 1 0
1  2 0 0 1
2  2 1 0 0 1
0

0101000
+9 0 -7 0 *
Ve
1e-09
0 1 0
0 0

0101101
*
Ed
 1e-07 1 1 0
1  3 0 0 1
2  3 1 0 0 1
0

0101000
+7 0 -5 0 *
Ed
 2e-05 1 1 0
1  4 0 0 1
2  4 1 0 0 1
0

0101000
+5 0 -10 0 *
Wi

0101000
+8 0 +6 0 +4 0 +3 0 *
Fa
0  1e-07 1 0

0101000
+2 0 *

+1 0 
";

/// A cylinder of radius 1 and height 2 closed by a seam: the seam edge has two pcurves (u = 2π
/// for the FORWARD edge, u = 0 for the REVERSED one) and appears twice in the wire.
const CYLINDER: &str = "DBRep_DrawableShape

CASCADE Topology V1, (c) Matra-Datavision
Locations 0
Curve2ds 4
1 0 0 1 0 
1 0 2 1 0 
1 6.283185307179586 0 0 1 
1 0 0 0 1 
Curves 3
2 0 0 0 0 0 1 1 0 0 0 1 0 1
2 0 0 2 0 0 1 1 0 0 0 1 0 1
1 1 0 0 0 0 1 
Polygon3D 0
PolygonOnTriangulations 0
Surfaces 1
2 0 0 0 0 0 1 1 0 0 0 1 0 1
Triangulations 0

TShapes 7
Ve
1e-07
1 0 0
0 0

0101101
*
Ve
1e-07
1 0 2
0 0

0101101
*
Ed
 1e-07 1 1 0
1  1 0 0 6.283185307179586
2  1 1 0 0 6.283185307179586
0

0101100
+7 0 -7 0 *
Ed
 1e-07 1 1 0
1  3 0 0 2
3  3 4CN 1 0 0 2
0

0101000
+7 0 -6 0 *
Ed
 1e-07 1 1 0
1  2 0 0 6.283185307179586
2  2 1 0 0 6.283185307179586
0

0101100
+6 0 -6 0 *
Wi

0101100
+5 0 +4 0 -3 0 -4 0 *
Fa
0  1e-07 1 0

0101000
+2 0 *

+1 0 
";

/// The same cylinder on an indirect frame (Y written as −(axis × X)): in OCCT's (u, v) the
/// circles run the other way (pcurves u = 2π − t) and the wire takes them reversed. Both texts
/// pass OCCT's BRepCheck_Analyzer.
fn mirrored_cylinder() -> String {
    CYLINDER
        .replace(
            "Curve2ds 4\n1 0 0 1 0 \n1 0 2 1 0 \n",
            "Curve2ds 4\n1 6.283185307179586 0 -1 0 \n1 6.283185307179586 2 -1 0 \n",
        )
        .replace(
            "Surfaces 1\n2 0 0 0 0 0 1 1 0 0 0 1 0 1\n",
            "Surfaces 1\n2 0 0 0 0 0 1 1 0 0 0 -1 0 1\n",
        )
        .replace("+5 0 +4 0 -3 0 -4 0 *", "-5 0 +4 0 +3 0 -4 0 *")
}

fn line2(curve: &Curve<DVec2>) -> ([f64; 2], [f64; 2]) {
    match curve {
        Curve::Line { origin, dir } => (origin.to_array(), dir.to_array()),
        other => panic!("not a line: {other:?}"),
    }
}

/// Points and plain arrays alike, for [`close`].
trait Coords {
    fn coords(&self) -> &[f64];
}

impl Coords for DVec2 {
    fn coords(&self) -> &[f64] {
        AsRef::<[f64; 2]>::as_ref(self)
    }
}

impl Coords for DVec3 {
    fn coords(&self) -> &[f64] {
        AsRef::<[f64; 3]>::as_ref(self)
    }
}

impl<const N: usize> Coords for [f64; N] {
    fn coords(&self) -> &[f64] {
        self
    }
}

fn close(a: &impl Coords, b: &impl Coords) -> bool {
    let (a, b) = (a.coords(), b.coords());
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
}

#[test]
fn a_unit_square_face_is_exactly_the_expected_document() {
    let doc = read(SQUARE);
    assert_eq!(doc.units, Units::Millimetres);
    let [face] = &doc.faces[..] else { panic!() };
    assert_eq!(
        (face.id, face.reversed, face.bounds),
        (1, false, [0.0, 1.0, 0.0, 1.0])
    );
    let Surface::Plane { frame } = &face.surface else {
        panic!("{:?}", face.surface)
    };
    assert_eq!(
        (
            frame.origin.to_array(),
            frame.x_dir.to_array(),
            frame.y_dir.to_array()
        ),
        ([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    );
    let [l] = &face.loops[..] else { panic!() };
    let want = [
        ([0.0, 0.0], [1.0, 0.0]),
        ([1.0, 0.0], [0.0, 1.0]),
        ([1.0, 1.0], [-1.0, 0.0]),
        ([0.0, 1.0], [0.0, -1.0]),
    ];
    assert_eq!(l.trims.len(), 4);
    for (i, (t, w)) in l.trims.iter().zip(want).enumerate() {
        assert_eq!(
            (line2(&t.curve), t.range, t.edge),
            (w, [0.0, 1.0], Some(i as u64 + 1))
        );
    }
    let edges = doc.edges.as_ref().unwrap();
    // Vertex tolerances at range[0] and range[1], at least OCCT's 1e-7 (the 1e-9 vertex).
    let tolerances = [
        (1e-7, [1e-7, 0.001]),
        (1e-7, [0.001, 0.002]),
        (1e-7, [0.002, 1e-7]),
        (2e-5, [1e-7, 1e-7]),
    ];
    for (e, (t, v)) in edges.iter().zip(tolerances) {
        assert_eq!((e.range, &e.faces[..]), ([0.0, 1.0], &[1][..]));
        assert_eq!((e.tolerance, e.vertex_tolerances), (Some(t), Some(v)));
    }
    assert_eq!(
        edges[2].curve,
        Some(Curve::Line {
            origin: DVec3::new(1.0, 1.0, 0.0),
            dir: DVec3::new(-1.0, 0.0, 0.0)
        })
    );

    // The same face REVERSED in its parent: `reversed`, the same loops.
    let rev = read(&SQUARE.replace("\n+1 0 \n", "\n-1 0 \n"));
    assert!(rev.faces[0].reversed);
    assert_eq!(rev.faces[0].loops, face.loops);
}

#[test]
fn locations_compose_on_shapes_and_representations() {
    // A rotation by 90° about z (1), a move by x + 10 (2), and 2 after 1 (3).
    let locations = "Locations 3\n1\n0 -1 0 0\n1 0 0 0\n0 0 1 0\n1\n1 0 0 10\n0 1 0 0\n0 0 1 0\n\
                     2 1 1 2 1 0\n";
    // The whole square placed by 3.
    let placed = read(
        &SQUARE
            .replace("Locations 0\n", locations)
            .replace("\n+1 0 \n", "\n+1 3 \n"),
    );
    let Surface::Plane { frame } = &placed.faces[0].surface else {
        panic!()
    };
    assert!(close(&frame.origin, &[10.0, 0.0, 0.0]));
    assert!(close(&frame.x_dir, &[0.0, 1.0, 0.0]) && close(&frame.y_dir, &[-1.0, 0.0, 0.0]));
    let Some(Curve::Line { origin, dir }) = &placed.edges.as_ref().unwrap()[1].curve else {
        panic!()
    };
    assert!(close(origin, &[10.0, 1.0, 0.0]) && close(dir, &[-1.0, 0.0, 0.0]));
    assert_eq!(placed.faces[0].loops, read(SQUARE).faces[0].loops);
    assert!(worst_pcurve_gap(&placed) < 1e-6);

    // The surface and every curve representation located by 1 inside unlocated shapes: the
    // pcurves are found (their location is the face's surface location over the edge's).
    let inner = SQUARE
        .replace("Locations 0\n", locations)
        .replace("0  1e-07 1 0\n", "0  1e-07 1 1\n")
        .replace("1  1 0 0 1\n2  1 1 0 0 1", "1  1 1 0 1\n2  1 1 1 0 1")
        .replace("1  2 0 0 1\n2  2 1 0 0 1", "1  2 1 0 1\n2  2 1 1 0 1")
        .replace("1  3 0 0 1\n2  3 1 0 0 1", "1  3 1 0 1\n2  3 1 1 0 1")
        .replace("1  4 0 0 1\n2  4 1 0 0 1", "1  4 1 0 1\n2  4 1 1 0 1");
    let doc = read(&inner);
    let Surface::Plane { frame } = &doc.faces[0].surface else {
        panic!()
    };
    assert!(close(&frame.x_dir, &[0.0, 1.0, 0.0]));
    assert!(worst_pcurve_gap(&doc) < 1e-6);

    // The surface located, the pcurves not: on a plane OCCT projects the 3D curves instead.
    let projected = read(
        &SQUARE
            .replace("Locations 0\n", locations)
            .replace("0  1e-07 1 0\n", "0  1e-07 1 2\n"),
    );
    assert_eq!(projected.faces[0].loops.len(), 1);
    let (o, d) = line2(&projected.faces[0].loops[0].trims[0].curve);
    assert!(
        close(&o, &[-10.0, 0.0]) && close(&d, &[1.0, 0.0]),
        "{o:?} {d:?}"
    );

    // A cylinder cannot be projected on: its face has no pcurves at that location.
    let e = error(
        &CYLINDER
            .replace("Locations 0\n", locations)
            .replace("0  1e-07 1 0\n", "0  1e-07 1 2\n"),
    );
    assert_eq!(e.kind, OcctErrorKind::Unsupported);
    assert_eq!(e.message, "face 1: edge 1 has no pcurve on the face");
}

#[test]
fn a_seam_gives_two_trims_with_their_own_pcurves() {
    let doc = read(CYLINDER);
    let face = &doc.faces[0];
    let tau = std::f64::consts::TAU;
    assert_eq!((face.reversed, face.bounds), (false, [0.0, tau, 0.0, 2.0]));
    let Surface::Cylinder { frame, radius } = &face.surface else {
        panic!()
    };
    assert_eq!((frame.y_dir.to_array(), *radius), ([0.0, 1.0, 0.0], 1.0));
    let trims: Vec<_> = face.loops[0]
        .trims
        .iter()
        .map(|t| (line2(&t.curve), t.range, t.edge))
        .collect();
    assert_eq!(
        trims,
        [
            (([0.0, 0.0], [1.0, 0.0]), [0.0, tau], Some(1)),
            (([tau, 0.0], [0.0, 1.0]), [0.0, 2.0], Some(2)),
            (([0.0, 2.0], [1.0, 0.0]), [tau, 0.0], Some(3)),
            (([0.0, 0.0], [0.0, 1.0]), [2.0, 0.0], Some(2)),
        ]
    );
    let edges = doc.edges.as_ref().unwrap();
    assert_eq!(edges.len(), 3);
    assert!(matches!(
        edges[0].curve,
        Some(Curve::Circle { radius: 1.0, .. })
    ));
    assert!(worst_pcurve_gap(&doc) < 1e-6);
}

#[test]
fn an_indirect_frame_is_mirrored_into_the_same_document() {
    // OCP's exporter writes for the mirrored text: the frame (X, −Y) = the direct cylinder's,
    // every pcurve u → 2π − u (so the direct cylinder's pcurves), the loop walked the other
    // way, `reversed` set.
    let direct = read(CYLINDER);
    let doc = read(&mirrored_cylinder());
    let face = &doc.faces[0];
    assert!(face.reversed);
    assert_eq!(face.surface, direct.faces[0].surface);
    assert_eq!(face.bounds, direct.faces[0].bounds);
    let tau = std::f64::consts::TAU;
    let trims: Vec<_> = face.loops[0]
        .trims
        .iter()
        .map(|t| (line2(&t.curve), t.range, t.edge))
        .collect();
    assert_eq!(
        trims,
        [
            (([tau, 0.0], [-0.0, 1.0]), [0.0, 2.0], Some(2)),
            (([0.0, 2.0], [1.0, -0.0]), [tau, 0.0], Some(3)),
            (([0.0, 0.0], [-0.0, 1.0]), [2.0, 0.0], Some(2)),
            (([0.0, 0.0], [1.0, -0.0]), [0.0, tau], Some(1)),
        ]
    );
    assert_eq!(doc.edges, direct.edges);
    assert!(worst_pcurve_gap(&doc) < 1e-6);
}

#[test]
fn broken_texts_name_the_line_and_the_element() {
    let syntax = |text: &str, want: &str| {
        let e = error(text);
        assert_eq!(e.kind, OcctErrorKind::Syntax, "{e}");
        assert_eq!(e.message, want);
    };
    // Truncated in the middle of the last edge (after its 3D curve's number).
    let cut = SQUARE.find("1  4 0 0 1").unwrap() + 4;
    syntax(
        &SQUARE[..cut],
        "line 76: TShapes[8]: the text ends where a location number was expected",
    );
    syntax(
        &SQUARE.replace("1  4 0 0 1\n", "1  9 0 0 1\n"),
        "line 76: TShapes[8]: curve 9 out of range 0..4",
    );
    syntax(
        &SQUARE.replace("Surfaces 1\n1 0 0 0", "Surfaces 1\n12 0 0 0"),
        "line 18: Surfaces[1]: unknown surface type 12",
    );
    syntax(
        &SQUARE.replace("0.001\n1 0 0\n", "nan\n1 0 0\n"),
        "line 30: TShapes[2]: the tolerance is not a finite number: `nan`",
    );
    syntax(
        &SQUARE.replace("Curve2ds 4\n1 0 0 1 0 ", "Curve2ds 4\n1 0 0 1 NaN "),
        "line 6: Curve2ds[1]: a coordinate is not a finite number: `NaN`",
    );
    // The wire naming the face, written after it.
    syntax(
        &SQUARE.replace("+8 0 +6 0 +4 0 +3 0 *", "+8 0 +6 0 +4 0 +1 0 *"),
        "line 85: TShapes[9]: sub-shape 1 out of range 3..10",
    );
    syntax(
        &SQUARE.replace("\n+1 0 \n", "\n+1 4 \n"),
        "line 92: TShapes: location 4 out of range 0..0",
    );
    syntax(
        &SQUARE.replace("TShapes 10\n", "TShapes 1000000000\n"),
        "line 21: TShapes: the shape count 1000000000 is more than the rest of the text can \
         hold",
    );
    syntax(
        "{\"format\": \"tessd-brep\"}",
        "line 1: header: expected `CASCADE Topology V1`, `V2` or `V3`, found \
         `{\"format\": \"tessd-brep\"}`",
    );
    syntax(
        "",
        "header: no `CASCADE Topology` line (an empty or truncated text)",
    );
}

#[test]
fn geometry_without_an_exact_type_is_unsupported_and_named() {
    let unsupported = |text: &str, want: &str| {
        let e = error(text);
        assert_eq!(e.kind, OcctErrorKind::Unsupported, "{e}");
        assert_eq!(e.message, want);
    };
    unsupported(
        &SQUARE.replace("Surfaces 1\n1 0 0 0", "Surfaces 1\n11 0.5\n1 0 0 0"),
        "face 1: an offset surface (Surfaces[1], line 18)",
    );
    unsupported(
        &SQUARE.replace(
            "Curves 4\n1 0 0 0 1 0 0 ",
            "Curves 4\n9 0.5\n0 0 1\n1 0 0 0 1 0 0 ",
        ),
        "edge 1: its curve is an offset curve (Curves[1], line 11)",
    );
    // A mirror placing the face.
    unsupported(
        &SQUARE
            .replace(
                "Locations 0\n",
                "Locations 1\n1\n-1 0 0 0\n0 1 0 0\n0 0 1 0\n",
            )
            .replace("\n+1 0 \n", "\n+1 1 \n"),
        "face 1: line 5: Locations: location with a mirror (determinant -1), not a rigid \
         motion (the exchange format's frames cannot carry it)",
    );
    unsupported(
        &SQUARE.replace("CASCADE Topology V1", "CASCADE Topology V4"),
        "line 3: header: CASCADE Topology V4: only versions 1, 2 and 3 are read",
    );
    // A plane without boundary has no bounded domain.
    unsupported(
        &SQUARE.replace("+2 0 *\n\n+1 0", "*\n\n+1 0"),
        "face 1: no boundary on an unbounded plane surface",
    );
}

#[test]
fn is_occt_brep_tells_occt_text_from_json() {
    assert!(occt::is_occt_brep(SQUARE));
    assert!(occt::is_occt_brep(
        "\nCASCADE Topology V1, (c) Matra-Datavision\n"
    ));
    assert!(!occt::is_occt_brep("{\"format\": \"tessd-brep\"}"));
}

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Reads without panicking; a document that comes back must validate without panicking too.
fn survives(text: &str) {
    if let Ok(doc) = occt::read(text, &ReadOptions::default()) {
        let _ = doc.errors();
    }
}

#[test]
fn truncated_and_corrupted_texts_never_panic() {
    // Truncations of a real file (V1, every section) at many points.
    let bottle = shared_text("bottle.brep");
    let mut cut = 0;
    while cut < bottle.len() {
        survives(&bottle[..cut]);
        cut += 1 + bottle.len() / 300;
    }
    // Random byte changes: into characters that keep the text UTF-8 and mean something to
    // the reader (digits, signs, exponents, separators, orientation and end marks).
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let alphabet = b"0123456789-+.e \n*iCN9";
    for base in [
        SQUARE.to_string(),
        mirrored_cylinder(),
        fixture("cube_cylinder.v3.brep"),
    ] {
        let bytes = base.as_bytes();
        for _ in 0..400 {
            let mut b = bytes.to_vec();
            for _ in 0..1 + rng.below(3) {
                let i = rng.below(b.len());
                if b[i].is_ascii() {
                    b[i] = alphabet[rng.below(alphabet.len())];
                }
            }
            survives(std::str::from_utf8(&b).unwrap());
        }
    }
}
