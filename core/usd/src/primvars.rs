//! Generic mesh attributes as USD primvars: how each [`Attribute`] is named, typed and
//! interpolated in a `Mesh` prim.
//!
//! USD has a primvar interpolation for each of the mesh model's domains — `vertex` (one value
//! per point, what Blender's point attributes become), `faceVarying` (one per face corner) and
//! `uniform` (one per face) — and value types of 1 to 4 floats (`float`, `float2`, `float3`,
//! `float4`). Wider rows are a `float[]` with `elementSize` = components, USD's own way of
//! storing several values per element. Values are written one per element (not indexed):
//! attributes come from hosts that store them that way.
//!
//! Primvar names are the attribute names sanitized into identifiers; a name that another
//! primvar of the prim already uses (`normals`, the UV set's name, or an attribute of another
//! domain with the same name) gets `_1`, `_2`... as prim names do.

use crate::MeshPrimOptions;
use crate::names::UniqueNames;
use tessd_mesh::{Attribute, Domain, Mesh};

/// One attribute as it is written.
pub(crate) struct AttributePrimvar<'a> {
    /// The data.
    pub attribute: &'a Attribute,
    /// The primvar's name, without `primvars:`.
    pub name: String,
    /// The value type, with `[]`.
    pub type_name: &'static str,
    /// `elementSize` metadata, for rows wider than 4 floats.
    pub element_size: Option<usize>,
    /// The `interpolation` token.
    pub interpolation: &'static str,
}

/// The primvars of `mesh`'s attributes, in the mesh's order, named clear of the prim's other
/// primvars (`normals` and the UV set when `options` writes them).
pub(crate) fn attribute_primvars<'a>(
    mesh: &'a Mesh,
    options: &MeshPrimOptions,
) -> Vec<AttributePrimvar<'a>> {
    if mesh.attributes.is_empty() {
        return Vec::new();
    }
    let mut names = UniqueNames::default();
    if options.write_normals && mesh.normals.is_some() {
        names.claim("normals", "normals");
    }
    if options.write_uvs && mesh.uvs.is_some() {
        names.claim(&options.uv_primvar_name, "st");
    }
    mesh.attributes
        .iter()
        .map(|a| {
            let (type_name, element_size) = match a.components {
                1 => ("float[]", None),
                2 => ("float2[]", None),
                3 => ("float3[]", None),
                4 => ("float4[]", None),
                c => ("float[]", Some(c)),
            };
            AttributePrimvar {
                attribute: a,
                name: names.claim(&a.name, "attribute"),
                type_name,
                element_size,
                interpolation: match a.domain {
                    Domain::Point => "vertex",
                    Domain::Corner => "faceVarying",
                    Domain::Face => "uniform",
                },
            }
        })
        .collect()
}

/// What a `Mesh` prim written with `options` leaves out of `mesh`, by protocol name: sharp
/// edges (USD has no edge primvars; creases would change the surface), and normals or UVs when
/// `options` does not write them.
pub fn dropped_by_usd(mesh: &Mesh, options: &MeshPrimOptions) -> Vec<String> {
    let mut out = Vec::new();
    if mesh.normals.is_some() && !options.write_normals {
        out.push("normals".to_string());
    }
    if mesh.uvs.is_some() && !options.write_uvs {
        out.push("uvs".to_string());
    }
    if !mesh.sharp_edges.is_empty() {
        out.push("sharp_edges".to_string());
    }
    out
}
