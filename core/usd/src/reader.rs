//! Reading USD ASCII stages (`.usda`) as meshes: the import side of the crate, so that every
//! mesh input of tessd (and the renderer's LOD panels) accepts what [`crate::write_stage`],
//! [`crate::write_lod_variants`] and other USD tools write.
//!
//! A hand-written reader of one layer, no USD library: the tokenizer (`usda_tokens.rs`) and
//! the recursive-descent parser (`usda_parse.rs`) turn the text into prim specs; this file
//! walks them as usd-core's default traversal does, composing the transforms of
//! `xform_ops.rs`, and builds a [`tessd_mesh::Mesh`] per `Mesh` prim (`usda_mesh.rs`):
//!
//! - prims: `def` prims of any type, nested; `over` and `class` prims (and what they hold) are
//!   not shown, nor inactive ones (`active = false`).
//! - composition: `references` and `payload`s to prims of local `.usda` files (relative to the
//!   layer naming them, or absolute) and of the same layer are followed (`compose.rs`; what the
//!   Blender add-on's `export_usd` writes); other assets (`.usdc`, URLs, resolver paths) are
//!   refused naming the arc and the file; cycles and depth are bounded. `subLayers`,
//!   `inherits` and `specializes` are not followed. [`parse_usda`], which reads no file, follows
//!   internal arcs only.
//! - transforms: the `xformOp:*` of `xformOpOrder` on the prim and its Xformable ancestors
//!   (translate, scale, rotate*, orient, transform, single-axis forms, `!invert!`,
//!   `!resetXformStack!`), applied in double precision as `UsdGeomXformable` does; points end in
//!   stage space, normals with the inverse transpose.
//! - values: the earliest `.timeSamples` sample when there is one (what a viewer shows at the
//!   start of the animation), else the default value.
//! - variants: `variantSet` bodies are read whole; each mesh records the variant it lives in,
//!   each set its variants and selection. Properties authored inside variants (opinions about
//!   the owning prim) are not applied; in a variant nested in another one only the nested
//!   set's selected variant (or first) is read.
//! - visibility: `visibility = "invisible"` hides a prim and its descendants from
//!   [`UsdStage::composed`] and [`UsdStage::variant_panels`]; [`UsdMesh::visible`] says so.
//! - LOD: a prim with the `LODRootAPI` schema (`UsdLod`) has its ordered children as levels
//!   ([`UsdStage::lod_roots`]); [`UsdStage::composed`] shows the visible (default) one,
//!   [`UsdStage::variant_panels`] each level, as for a `LOD` variant set.
//! - a mesh: `points`, `faceVertexCounts` and `faceVertexIndices` are required and checked
//!   (counts ≥ 3 adding up to the indices, indices in range, finite points); face-varying,
//!   vertex, uniform or constant `primvars:normals` (or `normals`) and `primvars:st` (or the
//!   first `texCoord2*` primvar) are read when consistent, dropped otherwise; face `GeomSubset`
//!   children become face groups.
//!
//! Binary crate files (`PXR-USDC`) and `.usdz` packages are refused with
//! [`UsdError::Unsupported`]: export them as `.usda` (`usdcat in.usdc -o out.usda`).
//!
//! ```
//! use tessd_usd::reader::parse_usda;
//!
//! let text = r#"#usda 1.0
//! def Xform "Root"
//! {
//!     double3 xformOp:translate = (10, 0, 0)
//!     uniform token[] xformOpOrder = ["xformOp:translate"]
//!     def Mesh "tri"
//!     {
//!         int[] faceVertexCounts = [3]
//!         int[] faceVertexIndices = [0, 1, 2]
//!         point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
//!     }
//! }
//! "#;
//! let stage = parse_usda(text, "tri.usda").unwrap();
//! assert_eq!(stage.meshes[0].path, "/Root/tri");
//! let mesh = stage.composed().unwrap();
//! assert_eq!(mesh.positions[1], [11.0, 0.0, 0.0]);
//! assert_eq!(mesh.group_names, ["/Root/tri"]);
//! ```

use std::path::Path;

use tessd_mesh::{FaceVarying, Mesh};

use crate::UsdError;
use crate::usda_parse::parse_layer;
use crate::usda_spec::{Item, Layer, PrimSpec, Specifier, Value};
use crate::xform_ops::{self, Mat4};

/// One mesh prim of a stage, with the transform of its ancestors and itself applied.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdMesh {
    /// Prim path, e.g. `"/Root/spot_triangulated"`.
    pub path: String,
    /// The variant it lives in: (variant set name, variant name), e.g. `("LOD", "LOD2")`;
    /// `None` outside variants. For a variant nested in another variant, the outer one.
    pub variant: Option<(String, String)>,
    /// Whether a viewer draws it: `false` when the prim or an ancestor has
    /// `visibility = "invisible"`.
    pub visible: bool,
    /// The paths of the prims that hide it (itself or ancestors with `visibility =
    /// "invisible"`): a `UsdLod` level's own invisibility does not hide it in its panel.
    hidden_by: Vec<String>,
    /// The mesh: positions transformed to stage space; `face_groups` / `group_names`: the
    /// prim's face `GeomSubset`s (those of the `materialBind` family when there are several
    /// families; faces in no subset get a group named after the prim), else one group named
    /// after the prim; UVs and normals when the stage has consistent ones.
    pub mesh: Mesh,
}

/// A variant set found on a prim.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdVariantSet {
    /// Path of the prim that owns the set (`"/Root"`).
    pub prim: String,
    /// The set's name (`"LOD"`).
    pub name: String,
    /// Its variants, in file order.
    pub variants: Vec<String>,
    /// The authored selection (`variants = { string LOD = "LOD0" }`), if any.
    pub selected: Option<String>,
}

/// A prim with the `UsdLod` schema's `LODRootAPI`: its children are the levels, finest first.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdLodRoot {
    /// Path of the LOD root prim (`"/Root/mesh"`).
    pub prim: String,
    /// Its defined, active child prims in order (`["LOD0", "LOD1", "LOD2"]`).
    pub levels: Vec<String>,
}

/// What a stage holds: its visible and invisible mesh prims (in file order), its variant sets,
/// its `UsdLod` roots and its layer metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdStage {
    /// Every defined, active `Mesh` prim, in every variant.
    pub meshes: Vec<UsdMesh>,
    /// Every variant set, in file order.
    pub variant_sets: Vec<UsdVariantSet>,
    /// Every prim with `LODRootAPI`, in file order.
    pub lod_roots: Vec<UsdLodRoot>,
    /// The `upAxis` layer metadata (`"Y"`, `"Z"`), if authored.
    pub up_axis: Option<String>,
    /// The `metersPerUnit` layer metadata, if authored.
    pub meters_per_unit: Option<f64>,
    /// The file (or the name given to [`parse_usda`]), for labels and messages.
    pub source: String,
}

impl UsdStage {
    /// The meshes a viewer shows by default: those outside any variant plus those in each
    /// set's selected variant (the first variant when none is selected), visible ones only,
    /// merged into one Mesh with one face group per prim (group name = prim path, plus a
    /// `" {LOD2}"`-style suffix when in a variant). UVs and normals are kept when every merged
    /// prim has them.
    ///
    /// # Errors
    /// [`UsdError::NoMeshes`] when nothing is shown; [`UsdError::TooLarge`] when the merged
    /// mesh would not fit 32-bit indices.
    pub fn composed(&self) -> Result<Mesh, UsdError> {
        let parts: Vec<&UsdMesh> = self.meshes.iter().filter(|m| self.shown(m)).collect();
        if parts.is_empty() {
            return Err(UsdError::NoMeshes {
                path: self.source.clone(),
            });
        }
        merge(&parts, &self.source)
    }

    /// The "panels" of a LOD chain: when some variant set's variants hold meshes, one merged
    /// Mesh per variant of the FIRST such set (in file order), labelled by the variant name,
    /// with the meshes [`UsdStage::composed`] shows outside that set added to each (a variant
    /// without meshes gives an empty Mesh, or those outside meshes only); else, when a
    /// `UsdLod` root's levels hold meshes, one panel per level of the first such root,
    /// labelled by the level's name, each level shown whatever its own `visibility`, with the
    /// meshes shown outside the root added; otherwise one panel, labelled with the file stem
    /// of [`UsdStage::source`] (or `"stage"`), holding [`UsdStage::composed`]. Groups as in
    /// [`UsdStage::composed`].
    ///
    /// # Errors
    /// As [`UsdStage::composed`].
    pub fn variant_panels(&self) -> Result<Vec<(String, Mesh)>, UsdError> {
        let owners: Vec<Option<usize>> = self.meshes.iter().map(|m| self.owner(m)).collect();
        let Some(set) = (0..self.variant_sets.len()).find(|s| owners.contains(&Some(*s))) else {
            if let Some(panels) = self.lod_panels()? {
                return Ok(panels);
            }
            let label = Path::new(&self.source)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .filter(|s| !s.is_empty())
                .unwrap_or_else(|| "stage".to_string());
            return Ok(vec![(label, self.composed()?)]);
        };
        let mut panels = Vec::new();
        for v in &self.variant_sets[set].variants {
            let parts: Vec<&UsdMesh> = (self.meshes.iter().zip(&owners))
                .filter(|(m, o)| match o {
                    Some(s) if *s == set => {
                        m.visible && m.variant.as_ref().is_some_and(|x| x.1 == *v)
                    }
                    _ => self.shown(m),
                })
                .map(|(m, _)| m)
                .collect();
            panels.push((v.clone(), merge(&parts, &self.source)?));
        }
        Ok(panels)
    }

    /// One panel per level of the first `UsdLod` root whose levels hold meshes.
    fn lod_panels(&self) -> Result<Option<Vec<(String, Mesh)>>, UsdError> {
        let under = |path: &str, prim: &str| {
            path.strip_prefix(prim)
                .is_some_and(|r| r.is_empty() || r.starts_with('/'))
        };
        let root = self.lod_roots.iter().find(|r| {
            r.levels.iter().any(|l| {
                let level = format!("{}/{l}", r.prim);
                self.meshes.iter().any(|m| under(&m.path, &level))
            })
        });
        let Some(root) = root else {
            return Ok(None);
        };
        let mut panels = Vec::with_capacity(root.levels.len());
        for l in &root.levels {
            let level = format!("{}/{l}", root.prim);
            let parts: Vec<&UsdMesh> = (self.meshes.iter())
                .filter(|m| {
                    if under(&m.path, &root.prim) {
                        under(&m.path, &level)
                            && m.hidden_by.iter().all(|h| *h == level)
                            && self.variant_shown(m)
                    } else {
                        self.shown(m)
                    }
                })
                .collect();
            panels.push((l.clone(), merge(&parts, &self.source)?));
        }
        Ok(Some(panels))
    }

    /// The index of the variant set a mesh's variant belongs to: the nearest set of that name
    /// and variant on the mesh's prim or an ancestor.
    fn owner(&self, m: &UsdMesh) -> Option<usize> {
        let (set, variant) = m.variant.as_ref()?;
        let under = |prim: &str| {
            m.path == prim
                || prim == "/"
                || m.path
                    .strip_prefix(prim)
                    .is_some_and(|r| r.starts_with('/'))
        };
        (self.variant_sets.iter().enumerate())
            .filter(|(_, s)| s.name == *set && s.variants.contains(variant) && under(&s.prim))
            .max_by_key(|(_, s)| s.prim.len())
            .map(|(i, _)| i)
    }

    /// Whether [`UsdStage::composed`] shows `m`.
    fn shown(&self, m: &UsdMesh) -> bool {
        m.visible && self.variant_shown(m)
    }

    /// Whether `m` is outside variants or in a selected one.
    fn variant_shown(&self, m: &UsdMesh) -> bool {
        match (&m.variant, self.owner(m)) {
            (None, _) => true,
            (Some((_, v)), Some(s)) => {
                let set = &self.variant_sets[s];
                set.selected.as_ref().or(set.variants.first()) == Some(v)
            }
            (Some(_), None) => false,
        }
    }
}

/// Reads a `.usda` file.
///
/// # Errors
/// [`UsdError::Io`] when it cannot be read; [`UsdError::Unsupported`] for a binary crate file
/// (`PXR-USDC`, whatever its extension) or a `.usdz` package; [`UsdError::Parse`] for text that
/// is not UTF-8 and as [`parse_usda`].
///
/// References and payloads to local `.usda` files are followed (module docs); their failures
/// name the arc, the prim and the layer: [`UsdError::Io`] for a missing file,
/// [`UsdError::Unsupported`] for other assets, [`UsdError::Parse`] for a cycle, a missing
/// target prim or too deep a chain, [`UsdError::TooLarge`] past the limits.
pub fn read_usda(path: &Path) -> Result<UsdStage, UsdError> {
    let name = path.display().to_string();
    let layer = load_layer(path, &name)?;
    let load = |p: &Path| load_layer(p, &p.display().to_string());
    let layer = crate::compose::compose(layer, Some(path), &name, &load)?;
    stage_of(layer, &name)
}

/// Reads and parses one layer file, its arcs not followed.
fn load_layer(path: &Path, name: &str) -> Result<Layer, UsdError> {
    let name = name.to_string();
    let bytes = std::fs::read(path).map_err(|source| UsdError::Io {
        path: name.clone(),
        source,
    })?;
    let usdz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("usdz"));
    if usdz || bytes.starts_with(b"PK\x03\x04") {
        return Err(UsdError::Unsupported(format!(
            "{name}: a .usdz package; tessd reads only USD ASCII stages: unzip it or export \
             the stage as .usda (usdcat in.usdz -o out.usda)"
        )));
    }
    check_binary(&bytes, &name)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| UsdError::Parse {
        path: name.clone(),
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
        message: "the text is not valid UTF-8".to_string(),
    })?;
    check_binary(text.as_bytes(), &name)?;
    parse_layer(text, &name)
}

/// Parses the text of a `.usda` layer; `source` names it in errors and labels.
///
/// # Errors
/// [`UsdError::Parse`], naming `source`, the line and the element (prim path and attribute),
/// for bad syntax, a truncated text, or a mesh whose arrays break the `Mesh` schema;
/// [`UsdError::Unsupported`] for the text of a binary crate file. Internal references and
/// payloads (`</Prim>`) are followed; those to other files are not (a text has no folder to
/// resolve them in: [`read_usda`] follows them).
pub fn parse_usda(text: &str, source: &str) -> Result<UsdStage, UsdError> {
    check_binary(text.as_bytes(), source)?;
    let layer = parse_layer(text, source)?;
    let no_files = |p: &Path| -> Result<Layer, UsdError> {
        Err(UsdError::Unsupported(format!(
            "{source}: {} is not read: a text's references to files are not followed",
            p.display()
        )))
    };
    let layer = crate::compose::compose(layer, None, source, &no_files)?;
    stage_of(layer, source)
}

/// The stage a composed layer shows.
fn stage_of(layer: Layer, source: &str) -> Result<UsdStage, UsdError> {
    let mut walk = Walk {
        meshes: Vec::new(),
        sets: Vec::new(),
        lod_roots: Vec::new(),
    };
    for prim in &layer.prims {
        walk.prim(prim, "", None, &[], None)?;
    }
    Ok(UsdStage {
        meshes: walk.meshes,
        variant_sets: walk.sets,
        lod_roots: walk.lod_roots,
        up_axis: layer.up_axis,
        meters_per_unit: layer.meters_per_unit,
        source: source.to_string(),
    })
}

fn check_binary(bytes: &[u8], name: &str) -> Result<(), UsdError> {
    if bytes.starts_with(b"PXR-USDC") {
        return Err(UsdError::Unsupported(format!(
            "{name}: a binary USD crate file (PXR-USDC); binary crate files are not read: \
             export the stage as .usda (usdcat in.usdc -o out.usda)"
        )));
    }
    Ok(())
}

/// Merges meshes into one, one face group per prim.
fn merge(parts: &[&UsdMesh], source: &str) -> Result<Mesh, UsdError> {
    let too_large = |what: &str| {
        UsdError::TooLarge(format!(
            "{source}: the merged meshes have more {what} than 32-bit indices hold"
        ))
    };
    let total = |f: fn(&Mesh) -> usize| parts.iter().map(|p| f(&p.mesh)).sum::<usize>();
    if u32::try_from(total(|m| m.positions.len())).is_err() {
        return Err(too_large("points"));
    }
    if u32::try_from(total(|m| m.face_indices.len())).is_err() {
        return Err(too_large("face corners"));
    }
    let mut out = Mesh::default();
    let every = |f: fn(&Mesh) -> bool| !parts.is_empty() && parts.iter().all(|p| f(&p.mesh));
    let mut uvs = every(|m| m.uvs.is_some()).then(FaceVarying::default);
    let mut normals = every(|m| m.normals.is_some()).then(FaceVarying::default);
    for (g, p) in parts.iter().enumerate() {
        let m = &p.mesh;
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        for face in m.faces() {
            out.face_indices.extend(face.iter().map(|v| v + base));
            out.face_offsets.push(out.face_indices.len() as u32);
            out.face_groups.push(g as u32);
        }
        out.group_names.push(match &p.variant {
            Some((_, v)) => format!("{} {{{v}}}", p.path),
            None => p.path.clone(),
        });
        append(&mut uvs, m.uvs.as_ref(), &too_large)?;
        append(&mut normals, m.normals.as_ref(), &too_large)?;
    }
    out.uvs = uvs;
    out.normals = normals;
    Ok(out)
}

fn append<T: Copy>(
    to: &mut Option<FaceVarying<T>>,
    from: Option<&FaceVarying<T>>,
    too_large: &dyn Fn(&str) -> UsdError,
) -> Result<(), UsdError> {
    if let (Some(to), Some(from)) = (to, from) {
        let base = u32::try_from(to.values.len()).map_err(|_| too_large("normals or UVs"))?;
        to.values.extend_from_slice(&from.values);
        to.indices.extend(from.indices.iter().map(|i| i + base));
    }
    Ok(())
}

/// The walk over the prim specs (usd-core's default traversal, with every variant).
struct Walk {
    meshes: Vec<UsdMesh>,
    sets: Vec<UsdVariantSet>,
    lod_roots: Vec<UsdLodRoot>,
}

/// The variant a walk is in: (set, variant).
type InVariant<'v> = Option<(&'v str, &'v str)>;

impl Walk {
    fn fail(p: &PrimSpec, line: usize, message: String) -> UsdError {
        UsdError::Parse {
            path: p.layer.to_string(),
            line,
            message,
        }
    }

    /// A prim and what it holds; `parent_hidden`: the invisible ancestors.
    fn prim(
        &mut self,
        p: &PrimSpec,
        parent: &str,
        parent_world: Option<Mat4>,
        parent_hidden: &[String],
        variant: InVariant<'_>,
    ) -> Result<(), UsdError> {
        if p.specifier != Specifier::Def || !p.active {
            return Ok(());
        }
        let path = format!("{parent}/{}", p.name);
        let world = match Self::local_transform(p, &path)? {
            None => parent_world,
            Some((local, true)) => Some(local),
            Some((local, false)) => Some(match parent_world {
                Some(pw) => xform_ops::mul(&local, &pw),
                None => local,
            }),
        };
        let own;
        let hidden = if p.token("visibility") == Some("invisible") {
            own = [parent_hidden, std::slice::from_ref(&path)].concat();
            &own[..]
        } else {
            parent_hidden
        };
        if p.type_name == "Mesh" {
            let mesh = crate::usda_mesh::build(p, &path, world.as_ref(), &p.layer)?;
            self.meshes.push(UsdMesh {
                path: path.clone(),
                variant: variant.map(|(s, v)| (s.to_string(), v.to_string())),
                visible: hidden.is_empty(),
                hidden_by: hidden.to_vec(),
                mesh,
            });
        }
        if p.api_schemas.iter().any(|s| s == "LODRootAPI") {
            let levels = (p.items.iter())
                .filter_map(|i| match i {
                    Item::Prim(c) if c.specifier == Specifier::Def && c.active => {
                        Some(c.name.clone())
                    }
                    _ => None,
                })
                .collect();
            self.lod_roots.push(UsdLodRoot {
                prim: path.clone(),
                levels,
            });
        }
        self.items(&p.items, p, &path, world, hidden, variant)
    }

    /// A prim's (or a variant's) child prims and variant sets.
    fn items(
        &mut self,
        items: &[Item],
        owner: &PrimSpec,
        path: &str,
        world: Option<Mat4>,
        hidden: &[String],
        variant: InVariant<'_>,
    ) -> Result<(), UsdError> {
        for item in items {
            match item {
                Item::Prim(c) => self.prim(c, path, world, hidden, variant)?,
                Item::VariantSet(set) => {
                    let selected = (owner.selections.iter().rev())
                        .find(|(s, _)| *s == set.name)
                        .map(|(_, v)| v.clone())
                        .filter(|v| !v.is_empty());
                    self.sets.push(UsdVariantSet {
                        prim: path.to_string(),
                        name: set.name.clone(),
                        variants: set.variants.iter().map(|(v, _)| v.clone()).collect(),
                        selected: selected.clone(),
                    });
                    let chosen = selected
                        .as_deref()
                        .or(set.variants.first().map(|v| v.0.as_str()));
                    for (v, vitems) in &set.variants {
                        // Nested in another variant: only this set's selection.
                        if variant.is_some() && chosen != Some(v.as_str()) {
                            continue;
                        }
                        let inner = variant.or(Some((set.name.as_str(), v.as_str())));
                        self.items(vitems, owner, path, world, hidden, inner)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The prim's local transform from its `xformOpOrder` (`None` when it has none or is not
    /// Xformable) and whether it resets the parents' transform.
    fn local_transform(p: &PrimSpec, path: &str) -> Result<Option<(Mat4, bool)>, UsdError> {
        const NOT_XFORMABLE: [&str; 8] = [
            "",
            "Scope",
            "GeomSubset",
            "Material",
            "Shader",
            "NodeGraph",
            "SkelAnimation",
            "BlendShape",
        ];
        let Some(order) = p
            .attr("xformOpOrder")
            .filter(|_| !NOT_XFORMABLE.contains(&p.type_name.as_str()))
        else {
            return Ok(None);
        };
        let ops: &[String] = match order.value() {
            Some(Value::Strings(s)) => s,
            Some(Value::Numbers { nums, .. }) if nums.is_empty() => &[],
            None => return Ok(None),
            Some(_) => {
                return Err(Self::fail(
                    p,
                    order.line,
                    format!("{path}.xformOpOrder: expected a list of op names"),
                ));
            }
        };
        let mut m = xform_ops::IDENTITY;
        let mut reset = false;
        for op in ops {
            if op == "!resetXformStack!" {
                reset = true;
                m = xform_ops::IDENTITY;
                continue;
            }
            let (name, inverted) = match op.strip_prefix("!invert!") {
                Some(n) => (n, true),
                None => (op.as_str(), false),
            };
            let at =
                |line: usize, msg: String| Self::fail(p, line, format!("{path}.{name}: {msg}"));
            let attr = p.attr(name).ok_or_else(|| {
                Self::fail(
                    p,
                    order.line,
                    format!("{path}.xformOpOrder names {name}, which the prim does not author"),
                )
            })?;
            let kind = name.split(':').nth(1).unwrap_or("");
            let arity = xform_ops::op_arity(kind)
                .ok_or_else(|| at(attr.line, format!("unsupported transform op type {kind:?}")))?;
            let v = match attr.value() {
                Some(Value::Numbers { nums, .. }) if nums.len() == arity => nums,
                Some(Value::Numbers { nums, .. }) => {
                    return Err(at(
                        attr.line,
                        format!("expected {arity} numbers, found {}", nums.len()),
                    ));
                }
                _ => return Err(at(attr.line, "has no numeric value".to_string())),
            };
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(at(attr.line, format!("the value {x} is not finite")));
            }
            let mut om = xform_ops::op_matrix(kind, v).map_err(|e| at(attr.line, e))?;
            if inverted {
                om = xform_ops::invert(&om)
                    .ok_or_else(|| at(attr.line, "!invert! of a singular transform".to_string()))?;
            }
            m = xform_ops::mul(&om, &m);
        }
        Ok(Some((m, reset)))
    }
}
