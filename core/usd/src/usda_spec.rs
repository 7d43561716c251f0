//! The tree of specs a `.usda` layer parses into ([`crate::usda_parse`]): prims with the
//! attributes meshes need, their variant sets and composition arcs, and the layer's own
//! metadata. What the parser builds and composition ([`crate::compose`]) and the mesh reader
//! ([`crate::usda_mesh`], [`crate::reader`]) read, kept apart from the grammar that fills it.

/// A parsed attribute value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    /// Numbers, flattened: `arity` per element (3 for `point3f`, 16 for `matrix4d`).
    Numbers {
        /// All numbers in order.
        nums: Vec<f64>,
        /// Numbers per element.
        arity: usize,
    },
    /// Strings, tokens (a scalar is a one-element list).
    Strings(Vec<String>),
    /// `None` (a blocked value), or a value of a kind not parsed.
    Blocked,
}

/// One attribute that meshes need, with its default value and earliest time sample.
#[derive(Clone, Debug)]
pub(crate) struct Attr {
    /// Name without `.timeSamples` (`primvars:st`).
    pub(crate) name: String,
    /// Declared type without `[]` (`texCoord2f`).
    pub(crate) type_name: String,
    /// Line of its first declaration.
    pub(crate) line: usize,
    /// `= value`.
    pub(crate) default: Option<Value>,
    /// `.timeSamples`: the earliest time and its value.
    pub(crate) sample: Option<(f64, Value)>,
    /// The `interpolation` metadata of primvars.
    pub(crate) interpolation: Option<String>,
}

impl Attr {
    /// The value a viewer shows: the earliest time sample, else the default; `None` when
    /// blocked or never authored.
    pub(crate) fn value(&self) -> Option<&Value> {
        let v = match &self.sample {
            Some((_, v)) => Some(v),
            None => self.default.as_ref(),
        };
        v.filter(|v| **v != Value::Blocked)
    }
}

/// `def`, `over` or `class`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Specifier {
    /// `def`: a defined prim.
    Def,
    /// `over`: an override, defining nothing by itself.
    Over,
    /// `class`: an abstract prim, not shown.
    Class,
}

/// The kind of a composition arc kept from a prim's metadata.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ArcKind {
    /// `references = ...`.
    Reference,
    /// `payload = ...` (weaker than the references, loaded as usd-core's default does).
    Payload,
}

impl ArcKind {
    /// The metadata key, for messages.
    pub(crate) fn key(self) -> &'static str {
        match self {
            ArcKind::Reference => "references",
            ArcKind::Payload => "payload",
        }
    }
}

/// One reference or payload: `@asset@</prim>`, `@asset@` (the layer's default prim) or
/// `</prim>` (a prim of the same layer).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ArcSpec {
    pub(crate) kind: ArcKind,
    /// The asset path, without its `@`s; `None` for an internal arc.
    pub(crate) asset: Option<String>,
    /// The target prim path, if given.
    pub(crate) prim: Option<String>,
    /// Line of the arc.
    pub(crate) line: usize,
}

/// A prim spec.
#[derive(Clone, Debug)]
pub(crate) struct PrimSpec {
    pub(crate) specifier: Specifier,
    /// Type name (`Mesh`), empty for typeless prims.
    pub(crate) type_name: String,
    pub(crate) name: String,
    pub(crate) line: usize,
    /// `active = false` makes it false.
    pub(crate) active: bool,
    /// Variant selections (`variants = { string LOD = "LOD0" }`), also those authored in its
    /// variants' metadata; the last one of a set wins.
    pub(crate) selections: Vec<(String, String)>,
    /// `apiSchemas` (`LODRootAPI`, ...).
    pub(crate) api_schemas: Vec<String>,
    /// References, then payloads, strongest first; emptied once composed.
    pub(crate) arcs: Vec<ArcSpec>,
    /// The layer the prim (its mesh attributes, when composed from several) was read from,
    /// for messages.
    pub(crate) layer: std::sync::Arc<str>,
    pub(crate) attrs: Vec<Attr>,
    /// Child prims and variant sets in file order.
    pub(crate) items: Vec<Item>,
}

impl PrimSpec {
    /// The attribute named `name`, if authored.
    pub(crate) fn attr(&self, name: &str) -> Option<&Attr> {
        self.attrs.iter().find(|a| a.name == name)
    }

    /// The first string of a token attribute (`visibility`, `elementType`).
    pub(crate) fn token(&self, name: &str) -> Option<&str> {
        match self.attr(name)?.value()? {
            Value::Strings(s) => s.first().map(String::as_str),
            _ => None,
        }
    }
}

/// What a prim body (or a variant's) holds besides properties.
#[derive(Clone, Debug)]
pub(crate) enum Item {
    Prim(PrimSpec),
    VariantSet(VariantSetSpec),
}

/// `variantSet "name" = { "a" { ... } "b" { ... } }`.
#[derive(Clone, Debug)]
pub(crate) struct VariantSetSpec {
    pub(crate) name: String,
    /// Each variant's name and the prims and variant sets it holds (its properties, opinions
    /// about the owning prim, are not read).
    pub(crate) variants: Vec<(String, Vec<Item>)>,
}

/// A parsed layer.
#[derive(Debug, Default)]
pub(crate) struct Layer {
    pub(crate) up_axis: Option<String>,
    pub(crate) meters_per_unit: Option<f64>,
    /// `defaultPrim`: the root prim a reference without a prim path targets.
    pub(crate) default_prim: Option<String>,
    pub(crate) prims: Vec<PrimSpec>,
}
