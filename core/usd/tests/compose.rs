//! References and payloads followed by the reader (`compose.rs`): local `.usda` files, relative
//! and absolute, default prims and prim paths, transforms on both sides of the arc, and the
//! refusals (other formats, URLs, missing files, cycles, depth). usd-core's view of the same
//! stages is checked by tests/usd/test_usda_input.py.

use std::path::Path;

use tessd_usd::reader::{parse_usda, read_usda};

const TRI: &str = r#"
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
"#;

/// A layer with a default prim `Part`: an Xform translated by `(10, 0, 0)` holding a triangle.
fn part() -> String {
    format!(
        r#"#usda 1.0
(
    defaultPrim = "Part"
)
def Xform "Part"
{{
    double3 xformOp:translate = (10, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
    def Mesh "tri"
    {{{TRI}    }}
}}
def Mesh "Other"
{{{TRI}}}
"#
    )
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    if let Some(parent) = p.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&p, text).unwrap();
    p
}

fn stage(dir: &Path, body: &str) -> std::path::PathBuf {
    write(dir, "scene.usda", &format!("#usda 1.0\n{body}\n"))
}

fn err(dir: &Path, body: &str) -> String {
    read_usda(&stage(dir, body)).unwrap_err().to_string()
}

#[test]
fn references_and_payloads_are_followed() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "parts/part.usda", &part());
    let abs = dir.path().join("parts/part.usda");
    let s = stage(
        dir.path(),
        &format!(
            r#"def Xform "Scene"
{{
    def "A" (prepend references = @./parts/part.usda@) {{}}
    def "B" (prepend references = @parts/part.usda@</Other>)
    {{
        double3 xformOp:translate = (0, 5, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }}
    def "C" (prepend payload = @{}@) {{}}
    def Xform "D" (
        references = [@./parts/part.usda@ (offset = 2), </Scene/A>]
    )
    {{
        double3 xformOp:translate = (0, 0, 7)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }}
}}"#,
            abs.display()
        ),
    );
    let st = read_usda(&s).unwrap();
    let found: Vec<(&str, [f32; 3])> = st
        .meshes
        .iter()
        .map(|m| (m.path.as_str(), m.mesh.positions[1]))
        .collect();
    assert_eq!(
        found,
        [
            // The target's own transform, kept: the referencing prim has none.
            ("/Scene/A/tri", [11.0, 0.0, 0.0]),
            // A typeless referencing prim takes the Mesh target's type, with its own transform.
            ("/Scene/B", [1.0, 5.0, 0.0]),
            ("/Scene/C/tri", [11.0, 0.0, 0.0]),
            // The referencing prim's xformOpOrder replaces the target's (usd-core's rule).
            ("/Scene/D/tri", [1.0, 0.0, 7.0]),
        ]
    );
    assert_eq!(st.composed().unwrap().face_count(), 4);
}

#[test]
fn internal_references_need_no_file() {
    let t = format!(
        "#usda 1.0\nclass Mesh \"Proto\"\n{{{TRI}}}\ndef \"Copy\" (references = </Proto>)\n{{}}\n"
    );
    let st = parse_usda(&t, "inline.usda").unwrap();
    assert_eq!(st.meshes.len(), 1);
    assert_eq!(st.meshes[0].path, "/Copy");
    // External arcs of a text are not followed: no file to resolve them against.
    let t = "#usda 1.0\ndef \"X\" (references = @part.usda@)\n{\n}\n";
    assert!(parse_usda(t, "t.usda").unwrap().meshes.is_empty());
}

#[test]
fn other_assets_are_refused_naming_the_arc() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let e = err(d, "def \"X\" (references = @./part.usdc@)\n{\n}");
    assert!(
        e.contains(
            "scene.usda:2: /X: references @./part.usdc@: only .usda layers are followed, not .usdc"
        ),
        "{e}"
    );
    assert!(e.contains("usdcat ./part.usdc -o ./part.usda"), "{e}");
    let e = err(d, "def \"X\" (payload = @omniverse://host/a.usda@)\n{\n}");
    assert!(
        e.contains("/X: payload @omniverse://host/a.usda@: only local files are followed"),
        "{e}"
    );
    let e = err(d, "def \"X\" (references = @missing.usda@)\n{\n}");
    assert!(
        e.contains("missing.usda (/X: references @missing.usda@, "),
        "{e}"
    );
    // The OS's own words for a missing file (error 2 on Unix and on Windows alike).
    let not_found = std::io::Error::from_raw_os_error(2).to_string();
    assert!(e.contains(&not_found), "{e}");
    write(d, "nodefault.usda", &part().replace("defaultPrim", "doc"));
    let e = err(d, "def \"X\" (references = @nodefault.usda@)\n{\n}");
    assert!(e.contains("names no prim and"), "{e}");
    assert!(e.contains("has no defaultPrim"), "{e}");
    let e = err(d, "def \"X\" (references = @nodefault.usda@</Nope>)\n{\n}");
    assert!(e.contains("has no prim </Nope>"), "{e}");
}

#[test]
fn cycles_and_depth_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "a.usda",
        "#usda 1.0\n(\n defaultPrim = \"A\"\n)\ndef \"A\" (references = @b.usda@)\n{\n}\n",
    );
    write(
        d,
        "b.usda",
        "#usda 1.0\n(\n defaultPrim = \"B\"\n)\ndef \"B\" (references = @a.usda@)\n{\n}\n",
    );
    let e = err(d, "def \"X\" (references = @a.usda@)\n{\n}");
    assert!(e.contains("a cycle of references"), "{e}");
    // A prim referencing its own ancestor.
    let e = err(d, "def \"P\"\n{\n def \"C\" (references = </P>)\n {\n }\n}");
    assert!(
        e.contains("/P/C: references </P>: a cycle of references"),
        "{e}"
    );
    // A chain of 40 files, each referencing the next.
    for i in 0..40 {
        write(
            d,
            &format!("c{i}.usda"),
            &format!(
                "#usda 1.0\n(\n defaultPrim = \"C\"\n)\ndef \"C\" (references = @c{}.usda@)\n{{\n}}\n",
                i + 1
            ),
        );
    }
    write(d, "c40.usda", &part().replace("\"Part\"", "\"C\""));
    let e = err(d, "def \"X\" (references = @c0.usda@)\n{\n}");
    assert!(e.contains("references nested more than 32 deep"), "{e}");
    // 20 deep is fine.
    let e = read_usda(&stage(d, "def \"X\" (references = @c20.usda@)\n{\n}")).unwrap();
    assert_eq!(e.meshes.len(), 1);
    assert_eq!(e.meshes[0].path, "/X/tri");
}
