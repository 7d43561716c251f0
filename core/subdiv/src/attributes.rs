//! Generic attributes through refinement, each by the rule that fits its domain:
//!
//! - `point:` attributes through the vertex stencils, as positions are (the stencils are affine
//!   combinations, so a value that is an affine function of the position — a coordinate, a
//!   gradient — stays that function of the refined position);
//! - `face:` attributes from the cage face each refined face comes from;
//! - `corner:` attributes as UVs are, by the face-varying refinement of
//!   [`face_varying`](crate::face_varying) with the request's `uv_interpolation` (seams stay
//!   seams, equal values of one vertex are one value), for the schemes that carry face-varying
//!   data; the others drop them ([`dropped`]).
//!
//! Attributes whose corners weld the same way (the common case: values that are continuous
//! across every edge) share one face-varying channel, so its topology is built once.

use crate::face_varying::{self, FaceVaryingRefiner, carries_face_varying, weld_rows};
use crate::sharp_edges::carries_sharp_edges;
use crate::{Refiner, Scheme, SubdivError, SubdivOptions};
use tessd_mesh::{Attribute, Domain, Mesh};

/// The cage's attributes on the refined mesh of `refiner` (built from `cage` with `options`),
/// in the cage's order, less those [`dropped`] lists.
///
/// # Errors
/// A `refiner` not built from this cage (row counts differ).
pub fn refine_attributes(
    cage: &Mesh,
    refiner: &Refiner,
    options: &SubdivOptions,
) -> Result<Vec<Attribute>, SubdivError> {
    let mut channels: Vec<(Vec<u32>, FaceVaryingRefiner)> = Vec::new();
    let mut out = Vec::with_capacity(cage.attributes.len());
    for a in &cage.attributes {
        let values = match a.domain {
            Domain::Point => refiner.apply(&a.values, a.components, &a.label())?,
            Domain::Face => a.gather(refiner.face_origin.iter().copied()).values,
            Domain::Corner => {
                if !carries_face_varying(options.scheme) {
                    continue;
                }
                let rows: Vec<u32> = (0..a.rows() as u32).collect();
                let welded = weld_rows(&cage.face_indices, &rows, &a.values, a.components);
                let k = match channels.iter().position(|(w, _)| *w == welded) {
                    Some(k) => k,
                    None => {
                        let Some(channel) = face_varying::cage_channel(
                            cage,
                            refiner,
                            &welded,
                            rows.len(),
                            options,
                        )?
                        else {
                            continue;
                        };
                        channels.push((welded, channel));
                        channels.len() - 1
                    }
                };
                let channel = &channels[k].1;
                let refined = Attribute {
                    values: channel.apply_rows(&a.values, a.components)?,
                    ..a.empty_like()
                };
                // One row per refined corner, in the refined mesh's corner order.
                refined.gather(channel.indices.iter().copied()).values
            }
        };
        out.push(Attribute {
            values,
            ..a.empty_like()
        });
    }
    Ok(out)
}

/// What refining `cage` with `options` cannot carry, by protocol name: `normals` given with
/// the cage (the refined mesh gets new ones, or none), `uvs` and `corner:` attributes for the
/// schemes without face-varying refinement, `sharp_edges` for Doo–Sabin and √3, and
/// `crease_edges` for Doo–Sabin (which ignores creases).
pub fn dropped(cage: &Mesh, options: &SubdivOptions) -> Vec<String> {
    let fvar = carries_face_varying(options.scheme);
    let mut out = Vec::new();
    let fixed = [
        ("normals", cage.normals.is_some()),
        ("uvs", cage.uvs.is_some() && !fvar),
        (
            "crease_edges",
            !cage.creases.is_empty() && options.scheme == Scheme::DooSabin,
        ),
        (
            "sharp_edges",
            !cage.sharp_edges.is_empty() && !carries_sharp_edges(options.scheme),
        ),
    ];
    out.extend(fixed.iter().filter(|f| f.1).map(|f| f.0.to_string()));
    if !fvar {
        out.extend(
            cage.attributes
                .iter()
                .filter(|a| a.domain == Domain::Corner)
                .map(Attribute::label),
        );
    }
    out
}
