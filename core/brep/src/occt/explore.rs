//! Step 5: walking the shape graph as OCCT's `TopExp_Explorer` / `TopExp::MapShapes` do, so
//! faces and edges get the numbers the host (and the Python exporters) give them.
//!
//! An occurrence is a record seen through the path that reached it: its orientation and
//! location composed along the path (`TopoDS_Iterator`). The explorer is depth-first over the
//! stored sub-shapes in order; `MapShapes` keeps the first occurrence of each (record,
//! location) pair — OCCT's `IsSame`, orientation ignored. The walk uses its own stack (a
//! hostile text can nest compounds deeply) and a budget of visited occurrences (shared
//! sub-shapes make the graph a DAG whose paths can multiply).

use std::collections::HashMap;

use super::locations::{LocId, Locations};
use super::topology::{Kind, Orient, SubShape, Topology};
use super::{OcctError, OcctErrorKind};

/// Occurrences one read may visit in all.
const BUDGET: usize = 5_000_000;

/// A record reached through a path: orientation and location composed along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Occ {
    /// The record, 0-based.
    pub shape: usize,
    /// The composed orientation.
    pub orient: Orient,
    /// The composed location.
    pub loc: LocId,
}

impl Occ {
    /// The root reference as an occurrence.
    pub fn root(root: &SubShape) -> Occ {
        Occ {
            shape: root.shape,
            orient: root.orient,
            loc: root.loc,
        }
    }

    /// The same record and location, FORWARD (OCCT's `Oriented(TopAbs_FORWARD)`).
    pub fn forward(self) -> Occ {
        Occ {
            orient: Orient::Forward,
            ..self
        }
    }
}

/// The walker: the topology, the location store (products are interned as they are met) and
/// what is left of the budget.
pub(crate) struct Walker<'t> {
    /// The shapes.
    pub topo: &'t Topology,
    /// The locations.
    pub locs: &'t mut Locations,
    budget: usize,
}

impl<'t> Walker<'t> {
    /// A walker with the full budget.
    pub fn new(topo: &'t Topology, locs: &'t mut Locations) -> Walker<'t> {
        Walker {
            topo,
            locs,
            budget: BUDGET,
        }
    }

    /// The kind of an occurrence's record.
    pub fn kind(&self, o: Occ) -> Kind {
        self.topo.shapes[o.shape].kind
    }

    /// Sub-shape `sub` of `parent` as seen from the root (`TopoDS_Iterator` with cumulative
    /// orientation and location).
    pub fn child(&mut self, parent: Occ, sub: &SubShape) -> Result<Occ, OcctError> {
        if self.budget == 0 {
            return Err(OcctError {
                kind: OcctErrorKind::Syntax,
                message: format!(
                    "TShapes: the shape graph expands to more than {BUDGET} sub-shape \
                     occurrences"
                ),
            });
        }
        self.budget -= 1;
        let loc = self.locs.mul(parent.loc, sub.loc).map_err(|m| OcctError {
            kind: OcctErrorKind::Syntax,
            message: format!("line {}: TShapes: {m}", self.topo.shapes[parent.shape].line),
        })?;
        Ok(Occ {
            shape: sub.shape,
            orient: parent.orient.compose(sub.orient),
            loc,
        })
    }

    /// The direct sub-shapes of `parent`, composed.
    pub fn children(&mut self, parent: Occ) -> Result<Vec<Occ>, OcctError> {
        let topo = self.topo;
        topo.shapes[parent.shape]
            .subs
            .iter()
            .map(|s| self.child(parent, s))
            .collect()
    }

    /// `TopExp_Explorer(from, kind)`: every occurrence of `kind` below `from` (or `from`
    /// itself when it is one), depth-first in stored order; only shapes more complex than
    /// `kind` are entered.
    pub fn explore(&mut self, from: Occ, kind: Kind) -> Result<Vec<Occ>, OcctError> {
        let mut out = Vec::new();
        let top = self.kind(from);
        if top == kind {
            out.push(from);
            return Ok(out);
        }
        if top > kind {
            return Ok(out);
        }
        let topo = self.topo;
        let mut stack: Vec<(Occ, usize)> = vec![(from, 0)];
        while let Some((parent, next)) = stack.last_mut() {
            let (parent, i) = (*parent, *next);
            let subs = &topo.shapes[parent.shape].subs;
            if i >= subs.len() {
                stack.pop();
                continue;
            }
            *next += 1;
            let c = self.child(parent, &subs[i])?;
            let k = self.kind(c);
            if k == kind {
                out.push(c);
            } else if k < kind {
                stack.push((c, 0));
            }
        }
        Ok(out)
    }
}

/// `TopExp::MapShapes` into an indexed map: occurrences numbered 1, 2, … in the order met,
/// one per (record, location); the first occurrence met is the one kept.
#[derive(Default)]
pub(crate) struct ShapeMap {
    /// The kept occurrences, 0-based (id − 1).
    pub items: Vec<Occ>,
    ids: HashMap<(usize, LocId), usize>,
}

impl ShapeMap {
    /// Adds an occurrence (if no same one is there) and returns its 1-based id.
    pub fn add(&mut self, o: Occ) -> usize {
        let n = self.items.len();
        let id = *self.ids.entry((o.shape, o.loc)).or_insert(n + 1);
        if id == n + 1 {
            self.items.push(o);
        }
        id
    }

    /// The 1-based id of the same occurrence, if mapped.
    pub fn find(&self, o: Occ) -> Option<usize> {
        self.ids.get(&(o.shape, o.loc)).copied()
    }
}
