//! Following a layer's composition arcs before [`crate::reader`] walks it: `references` and
//! `payload`s to prims of other local `.usda` files (a path relative to the layer that names
//! it, or an absolute one) and internal references to prims of the same layer (`</Prim>`).
//!
//! What the Blender add-on's `export_usd` writes (an assembly stage of Xforms, each with the
//! object's world matrix and `prepend references = @./scene_Cube.usda@`), `usdview` shows
//! and `tessd stats` / `tessd render` now read. The composition is the subset of usd-core's
//! (Pcp) that meshes need, done on the prim specs:
//!
//! - the target prim (the arc's prim path, else the layer's `defaultPrim`) is read with its own
//!   arcs followed first (relative to its own file), then merged under the referencing prim as
//!   a weaker opinion: the referencing prim keeps its name, and its own type, attributes (with
//!   a value), variant selections and children win; the target's fill in the rest. Children
//!   of both are merged by name, the target's first (usd-core's order), as are variant sets
//!   and their variants. References are stronger than payloads, and earlier arcs stronger than
//!   later ones. So a referencing prim with its own `xformOpOrder` replaces the target's
//!   transform (as in usd-core), and one without keeps it.
//! - refused with [`UsdError::Unsupported`], naming the arc, the prim and the layer: assets that
//!   are not `.usda` files (`.usdc`, `.usd`, `.usdz`, other formats) and asset-resolver or URL
//!   paths (`omniverse://`, `http:`...). A missing file is an [`UsdError::Io`] naming the arc.
//! - a cycle (an arc leading back to a prim being expanded), more than [`MAX_ARC_DEPTH`]
//!   nested arcs, prims nested deeper than [`crate::usda_parse::MAX_DEPTH`] through arcs, or
//!   more than [`MAX_ARCS`] arcs or [`MAX_VALUES`] numbers copied in all, are refused.
//! - not followed: `subLayers`, `inherits`, `specializes`, arcs authored inside variants, and
//!   external arcs of a text given to [`crate::parse_usda`] (it has no folder and reads no
//!   file; internal arcs are followed). Layer offsets do not matter: the earliest time sample
//!   is read.
//!
//! Each file is parsed once however often it is referenced.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::UsdError;
use crate::usda_parse::MAX_DEPTH;
use crate::usda_spec::{ArcSpec, Item, Layer, PrimSpec, Specifier, Value};

/// The most arcs nested in each other (a reference in a referenced file in ...).
pub const MAX_ARC_DEPTH: usize = 32;

/// The most arcs followed in one stage.
pub const MAX_ARCS: usize = 10_000;

/// The most attribute numbers copied from targets in one stage (what 2²⁸ `f64`s weigh, 2 GiB).
pub const MAX_VALUES: usize = 1 << 28;

/// A layer being composed: its file (canonical; `None` for a text without one), its name for
/// messages, and its specs as parsed (the targets of internal arcs).
#[derive(Clone)]
struct LayerCtx {
    file: Option<PathBuf>,
    name: String,
    layer: Arc<Layer>,
}

/// Reads and parses a layer file (what [`crate::read_usda`] does before composing).
pub(crate) type LoadLayer<'l> = &'l dyn Fn(&Path) -> Result<Layer, UsdError>;

struct Composer<'l> {
    load: LoadLayer<'l>,
    /// Parsed layers by canonical path.
    layers: HashMap<PathBuf, Arc<Layer>>,
    /// The arcs being expanded: (layer name, target prim path).
    stack: Vec<(String, String)>,
    arcs: usize,
    values: usize,
}

/// Follows the arcs of every prim of `layer`, read from `file` (`None`: a text without a
/// file, whose external arcs are not followed); `name` names it in messages, `load` reads the
/// layers it references.
///
/// # Errors
/// As the module docs say; and as `load` for the referenced files.
pub(crate) fn compose(
    layer: Layer,
    file: Option<&Path>,
    name: &str,
    load: LoadLayer<'_>,
) -> Result<Layer, UsdError> {
    let has_arcs = |prims: &[PrimSpec]| prims.iter().any(any_arcs);
    if !has_arcs(&layer.prims) {
        return Ok(layer);
    }
    let file = match file {
        Some(f) => Some(std::fs::canonicalize(f).map_err(|source| UsdError::Io {
            path: name.to_string(),
            source,
        })?),
        None => None,
    };
    let layer = Arc::new(layer);
    let mut c = Composer {
        load,
        layers: HashMap::new(),
        stack: Vec::new(),
        arcs: 0,
        values: 0,
    };
    if let Some(f) = &file {
        c.layers.insert(f.clone(), layer.clone());
    }
    let ctx = LayerCtx {
        file,
        name: name.to_string(),
        layer: layer.clone(),
    };
    let mut prims = layer.prims.clone();
    for p in &mut prims {
        c.prim(p, &ctx, "", 1)?;
    }
    Ok(Layer {
        up_axis: layer.up_axis.clone(),
        meters_per_unit: layer.meters_per_unit,
        default_prim: layer.default_prim.clone(),
        prims,
    })
}

fn any_arcs(p: &PrimSpec) -> bool {
    !p.arcs.is_empty() || items_have_arcs(&p.items)
}

fn items_have_arcs(items: &[Item]) -> bool {
    items.iter().any(|i| match i {
        Item::Prim(p) => any_arcs(p),
        Item::VariantSet(s) => s.variants.iter().any(|(_, v)| items_have_arcs(v)),
    })
}

impl Composer<'_> {
    /// Follows `p`'s arcs (merging their targets under it), then its children's; `parent` is
    /// its parent's path in `ctx`'s layer, `depth` its nesting in the composed stage.
    fn prim(
        &mut self,
        p: &mut PrimSpec,
        ctx: &LayerCtx,
        parent: &str,
        depth: usize,
    ) -> Result<(), UsdError> {
        let path = format!("{parent}/{}", p.name);
        if depth > MAX_DEPTH {
            return Err(UsdError::Parse {
                path: ctx.name.clone(),
                line: p.line,
                message: format!(
                    "{path}: prims nested deeper than {MAX_DEPTH} levels through references"
                ),
            });
        }
        for arc in std::mem::take(&mut p.arcs) {
            if let Some(weak) = self.target(&arc, ctx, &path, depth)? {
                merge(p, weak);
            }
        }
        self.items(&mut p.items, ctx, &path, depth)
    }

    fn items(
        &mut self,
        items: &mut [Item],
        ctx: &LayerCtx,
        path: &str,
        depth: usize,
    ) -> Result<(), UsdError> {
        for item in items {
            match item {
                Item::Prim(c) => self.prim(c, ctx, path, depth + 1)?,
                Item::VariantSet(s) => {
                    for (_, v) in &mut s.variants {
                        self.items(v, ctx, path, depth)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The composed target of `arc`, authored on the prim at `path` of `ctx`'s layer; `None`
    /// for an external arc of a text without a file.
    fn target(
        &mut self,
        arc: &ArcSpec,
        ctx: &LayerCtx,
        path: &str,
        depth: usize,
    ) -> Result<Option<PrimSpec>, UsdError> {
        let shown = format!(
            "{}{}",
            arc.asset
                .as_ref()
                .map_or_else(String::new, |a| format!("@{a}@")),
            arc.prim
                .as_ref()
                .map_or_else(String::new, |p| format!("<{p}>"))
        );
        let what = format!("{path}: {} {shown}", arc.kind.key());
        let fail = |line: usize, message: String| UsdError::Parse {
            path: ctx.name.clone(),
            line,
            message,
        };
        let target_ctx = match &arc.asset {
            None => ctx.clone(),
            Some(asset) => {
                let Some(base) = &ctx.file else {
                    return Ok(None);
                };
                self.layer(asset, base, ctx, arc, &what)?
            }
        };
        let target = match (&arc.prim, &target_ctx.layer.default_prim) {
            (Some(p), _) => p.clone(),
            (None, Some(d)) => format!("/{}", d.trim_start_matches('/')),
            (None, None) => {
                return Err(fail(
                    arc.line,
                    format!(
                        "{what}: names no prim and {} has no defaultPrim; name the prim \
                         (@{}@</Prim>) or author defaultPrim in that layer",
                        target_ctx.name,
                        arc.asset.as_deref().unwrap_or_default()
                    ),
                ));
            }
        };
        if target.contains('{') || target.contains('.') {
            return Err(UsdError::Unsupported(format!(
                "{}:{}: {what}: only prim paths are followed, not variant or property paths",
                ctx.name, arc.line
            )));
        }
        let key = (target_ctx.name.clone(), target.clone());
        if self.stack.contains(&key) {
            let chain: Vec<String> = (self.stack.iter().chain([&key]))
                .map(|(l, p)| format!("{l}<{p}>"))
                .collect();
            return Err(fail(
                arc.line,
                format!("{what}: a cycle of references: {}", chain.join(" -> ")),
            ));
        }
        if self.stack.len() >= MAX_ARC_DEPTH {
            return Err(fail(
                arc.line,
                format!("{what}: references nested more than {MAX_ARC_DEPTH} deep"),
            ));
        }
        self.arcs += 1;
        if self.arcs > MAX_ARCS {
            return Err(UsdError::TooLarge(format!(
                "{}: more than {MAX_ARCS} references and payloads to follow",
                ctx.name
            )));
        }
        let Some(spec) = find(&target_ctx.layer.prims, &target) else {
            return Err(fail(
                arc.line,
                format!("{what}: {} has no prim <{target}>", target_ctx.name),
            ));
        };
        self.values += values(spec);
        if self.values > MAX_VALUES {
            return Err(UsdError::TooLarge(format!(
                "{}: the references copy more than {MAX_VALUES} attribute values",
                ctx.name
            )));
        }
        let mut spec = spec.clone();
        let parent = target.rsplit_once('/').map_or("", |(p, _)| p).to_string();
        self.stack.push(key);
        let composed = self.prim(&mut spec, &target_ctx, &parent, depth);
        self.stack.pop();
        composed?;
        Ok(Some(spec))
    }

    /// The layer an external arc names, parsed once.
    fn layer(
        &mut self,
        asset: &str,
        base: &Path,
        ctx: &LayerCtx,
        arc: &ArcSpec,
        what: &str,
    ) -> Result<LayerCtx, UsdError> {
        let refuse =
            |why: &str| UsdError::Unsupported(format!("{}:{}: {what}: {why}", ctx.name, arc.line));
        if asset.is_empty() {
            return Err(refuse("an empty asset path"));
        }
        // A URL or an asset-resolver path (`omniverse://`, `http:`), not a Windows drive.
        let scheme = asset
            .split_once(':')
            .is_some_and(|(s, _)| s.len() > 1 && !s.contains(['/', '\\']));
        if scheme {
            return Err(refuse(
                "only local files are followed, not URLs or asset-resolver paths",
            ));
        }
        let ext = Path::new(asset)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if ext.as_deref() != Some("usda") {
            return Err(refuse(&format!(
                "only .usda layers are followed, not {}; export it as .usda \
                 (usdcat {asset} -o {}.usda) and reference that",
                ext.map_or_else(
                    || "files without an extension".to_string(),
                    |e| format!(".{e}")
                ),
                Path::new(asset).with_extension("").display()
            )));
        }
        let folder = base.parent().unwrap_or(Path::new(""));
        let resolved = folder.join(asset);
        let io = |source: std::io::Error| UsdError::Io {
            path: format!("{} ({what}, {}:{})", resolved.display(), ctx.name, arc.line),
            source,
        };
        let file = std::fs::canonicalize(&resolved).map_err(io)?;
        let layer = match self.layers.get(&file) {
            Some(l) => l.clone(),
            None => {
                let l = Arc::new((self.load)(&file)?);
                self.layers.insert(file.clone(), l.clone());
                l
            }
        };
        Ok(LayerCtx {
            name: resolved.display().to_string(),
            file: Some(file),
            layer,
        })
    }
}

/// The prim spec at `path` (`/A/B`) among `prims` and their children (not in variants).
fn find<'p>(prims: &'p [PrimSpec], path: &str) -> Option<&'p PrimSpec> {
    let mut names = path.split('/').filter(|n| !n.is_empty());
    let first = names.next()?;
    let mut at = prims.iter().find(|p| p.name == first)?;
    for n in names {
        at = at.items.iter().find_map(|i| match i {
            Item::Prim(c) if c.name == n => Some(c),
            _ => None,
        })?;
    }
    Some(at)
}

/// The attribute numbers of a prim spec and everything under it.
fn values(p: &PrimSpec) -> usize {
    let own: usize = p
        .attrs
        .iter()
        .flat_map(|a| [a.default.as_ref(), a.sample.as_ref().map(|s| &s.1)])
        .flatten()
        .map(|v| match v {
            Value::Numbers { nums, .. } => nums.len(),
            Value::Strings(s) => s.len(),
            Value::Blocked => 0,
        })
        .sum();
    own + items_values(&p.items)
}

fn items_values(items: &[Item]) -> usize {
    items
        .iter()
        .map(|i| match i {
            Item::Prim(c) => values(c),
            Item::VariantSet(s) => s.variants.iter().map(|(_, v)| items_values(v)).sum(),
        })
        .sum()
}

/// Merges `weak` under `strong` (the module docs' rules).
fn merge(strong: &mut PrimSpec, weak: PrimSpec) {
    use Specifier::*;
    if strong.attr("points").is_none() && weak.attr("points").is_some() {
        strong.layer = weak.layer.clone();
    }
    strong.specifier = match (strong.specifier, weak.specifier) {
        (Def, _) | (_, Def) => Def,
        (Class, _) | (_, Class) => Class,
        _ => Over,
    };
    if strong.type_name.is_empty() {
        strong.type_name = weak.type_name;
    }
    strong.active &= weak.active;
    // The last selection of a set wins: the weak ones go first.
    let own = std::mem::replace(&mut strong.selections, weak.selections);
    strong.selections.extend(own);
    for s in weak.api_schemas {
        if !strong.api_schemas.contains(&s) {
            strong.api_schemas.push(s);
        }
    }
    for wa in weak.attrs {
        match strong.attrs.iter_mut().find(|a| a.name == wa.name) {
            Some(sa) => {
                if sa.default.is_none() && sa.sample.is_none() {
                    sa.default = wa.default;
                    sa.sample = wa.sample;
                    sa.line = wa.line;
                }
                if sa.interpolation.is_none() {
                    sa.interpolation = wa.interpolation;
                }
            }
            None => strong.attrs.push(wa),
        }
    }
    let own = std::mem::take(&mut strong.items);
    strong.items = merge_items(own, weak.items);
}

/// The children and variant sets of a strong and a weak spec, merged by name, the weak
/// spec's first.
fn merge_items(strong: Vec<Item>, mut out: Vec<Item>) -> Vec<Item> {
    for item in strong {
        match item {
            Item::Prim(sp) => {
                let same = out.iter_mut().find_map(|i| match i {
                    Item::Prim(w) if w.name == sp.name => Some(w),
                    _ => None,
                });
                match same {
                    Some(w) => {
                        let weak = std::mem::replace(w, sp);
                        merge(w, weak);
                    }
                    None => out.push(Item::Prim(sp)),
                }
            }
            Item::VariantSet(ss) => {
                let same = out.iter_mut().find_map(|i| match i {
                    Item::VariantSet(w) if w.name == ss.name => Some(w),
                    _ => None,
                });
                match same {
                    Some(ws) => {
                        for (name, items) in ss.variants {
                            match ws.variants.iter_mut().find(|(n, _)| *n == name) {
                                Some((_, w)) => {
                                    let weak = std::mem::take(w);
                                    *w = merge_items(items, weak);
                                }
                                None => ws.variants.push((name, items)),
                            }
                        }
                    }
                    None => out.push(Item::VariantSet(ss)),
                }
            }
        }
    }
    out
}
