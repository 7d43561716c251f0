//! Parser tests: values, time samples, metadata, and the syntax errors with their lines.

use super::*;

#[test]
fn values_and_samples() {
    let layer = parse_layer(
        r#"#usda 1.0
(
"doc string"
upAxis = "Y"
metersPerUnit = 0.01
subLayers = [@a.usda@ (offset = 1)]
)
def Xform "A" (
customData = { string k = '''v''' }
variants = { string LOD = "LOD1" }
prepend references = @b.usda@</B>
)
{
custom float3[] points = [(1, 2, 3), (4.5, -inf, nan)]
matrix4d xformOp:transform.timeSamples = {
    2: ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (5, 6, 7, 1)),
    -1: None,
}
uniform token[] xformOpOrder = ["xformOp:transform"]
color3f[] primvars:displayColor = [(1, 0, 0)] ( interpolation = "constant" )
rel material:binding = </M>
texCoord2f[] primvars:uv = [(0.1, 0.2)] ( interpolation = "vertex" )
reorder nameChildren = ["b", "a"]
}
"#,
        "t.usda",
    )
    .unwrap();
    assert_eq!(layer.up_axis.as_deref(), Some("Y"));
    assert_eq!(layer.meters_per_unit, Some(0.01));
    let a = &layer.prims[0];
    assert_eq!(a.selections, [("LOD".to_string(), "LOD1".to_string())]);
    let names: Vec<_> = a.attrs.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(
        names,
        ["points", "xformOp:transform", "xformOpOrder", "primvars:uv"]
    );
    let Some(Value::Numbers { nums, arity: 3 }) = a.attrs[0].value() else {
        panic!()
    };
    assert_eq!(nums[3], 4.5);
    assert!(nums[4] == f64::NEG_INFINITY && nums[5].is_nan());
    // The earliest sample is `None`: blocked.
    assert_eq!(a.attrs[1].value(), None);
    assert_eq!(a.attrs[3].interpolation.as_deref(), Some("vertex"));
    assert_eq!(
        a.attrs[3].value(),
        Some(&Value::Numbers {
            nums: vec![0.1f32 as f64, 0.2f32 as f64],
            arity: 2
        })
    );
}

#[test]
fn syntax_errors_name_line_and_element() {
    for (text, want) in [
        (
            "#usda 1.0\ndef Mesh \"m\" {\n int[] faceVertexCounts = [1, (2, 3)]\n}\n",
            "t:3: /m.faceVertexCounts: element 1 has 2 components; the list's first element has 1",
        ),
        (
            "#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(1, 2 3)]\n}",
            "t:3: /m.points: expected ',' or ')' in the tuple, found number 3",
        ),
        (
            "#usda 1.0\ndef \"m\" {\n def \"n\" {\n",
            "t:4: /m/n: unexpected end of file in the prim's body (opened at line 3)",
        ),
        (
            "#usda 1.0\ndef \"m\" { float3 xformOp:scale = [1, 2 }",
            "t:2: /m.xformOp:scale: expected ',' or ']' after element 1, found '}'",
        ),
        (
            "usda 1.0\n",
            "t:1: not a USD ASCII layer: the first line must be \"#usda 1.0\"",
        ),
        (
            "#usda 1.0\nfoo",
            "t:2: expected a prim (def, over or class), found identifier \"foo\"",
        ),
        (
            "#usda 1.0\ndef \"m\" ( kind = { ] ) {}",
            "t:2: /m: expected '}' (to close line 2), found ']'",
        ),
        (
            "#usda 1.0\ndef \"m\" { int[] points = [1.2.3] }",
            "t:2: /m.points: bad number \"1.2.3\"",
        ),
    ] {
        assert_eq!(
            parse_layer(text, "t").unwrap_err().to_string(),
            want,
            "{text}"
        );
    }
}

#[test]
fn deep_nesting_is_refused() {
    let mut text = "#usda 1.0\n".to_string();
    for _ in 0..(MAX_DEPTH + 1) {
        text.push_str("def \"a\" {\n");
    }
    let e = parse_layer(&text, "t").unwrap_err().to_string();
    assert!(e.contains("nested deeper than 100 levels"), "{e}");
    let tuple = format!(
        "#usda 1.0\ndef \"a\" {{ double xformOp:rotateX = {}1{} }}",
        "(".repeat(50),
        ")".repeat(50)
    );
    let e = parse_layer(&tuple, "t").unwrap_err().to_string();
    assert!(
        e.contains("expected a number in the tuple, found '('"),
        "{e}"
    );
}
