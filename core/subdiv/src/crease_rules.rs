//! Sharp-feature rules shared by the triangle schemes ([`crate::loop_scheme`],
//! [`crate::butterfly`]): OpenSubdiv's `Sdc` vertex rules with the *uniform* creasing method
//! and fractional blending, the same rules [`crate::catmull_clark`] applies (paper 002,
//! section 1.4.7 surveys the schemes; the sharpness rules are OpenSubdiv's).
//!
//! Kept apart from `catmull_clark.rs` so that its internals can change freely; the shared
//! vocabulary it reads ([`Boundary`], [`decrement`]) lives below both, in [`crate::boundary`]
//! and [`crate::sharpness`].

use crate::boundary::Boundary;
use crate::sharpness::decrement;
use crate::topology::Topology;

/// Which level's sharpness a rule reads: where a rule changes between a level and the next,
/// the two are blended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// This level's sharpness.
    Parent,
    /// The next level's (one [`decrement`] down).
    Child,
}

impl Phase {
    /// True when an edge of sharpness `s` is sharp in this phase.
    pub fn is_sharp(self, s: f32) -> bool {
        match self {
            Phase::Parent => s > 0.0,
            Phase::Child => decrement(s) > 0.0,
        }
    }
}

/// A vertex's rule, by how many sharp edges meet there (OpenSubdiv's smooth / crease /
/// corner; darts, one sharp edge, are smooth).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// No or one sharp edge: the scheme's smooth mask.
    Smooth,
    /// Exactly two sharp edges: the curve mask along them.
    Crease,
    /// Three or more sharp edges, a non-manifold fan, or a boundary corner: stays put.
    Corner,
}

/// One mask of a vertex point and how much of it the point takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// The mask.
    pub rule: Rule,
    /// Which sharpness says which edges the crease mask follows.
    pub phase: Phase,
    /// Its weight (the parts of a point sum to 1).
    pub weight: f64,
}

/// True when `v` is a corner whatever the sharpness of its edges: its faces do not form one
/// fan (non-manifold), or it is a boundary vertex of a single face under
/// [`Boundary::EdgeAndCorner`].
pub fn forced_corner(topo: &Topology, v: usize, boundary: Boundary) -> bool {
    topo.fan(v).is_corner(boundary)
}

/// How much of the sharper rule remains at a vertex whose rule changes between this level and
/// the next: the mean sharpness of its edges that go from sharp to smooth, at most 1
/// (OpenSubdiv's fractional blending). `sharpness` lists the vertex's edges' sharpness.
pub fn transition_weight(sharpness: impl IntoIterator<Item = f32>) -> f64 {
    let (sum, count) = sharpness
        .into_iter()
        .filter(|&s| s > 0.0 && decrement(s) <= 0.0)
        .fold((0.0f64, 0usize), |(sum, n), s| (sum + f64::from(s), n + 1));
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).min(1.0)
    }
}

/// The sharp edges at `v` in `phase` (boundary edges are infinitely sharp).
pub fn sharp_edges(topo: &Topology, v: usize, phase: Phase) -> impl Iterator<Item = u32> + '_ {
    topo.edges_of(v)
        .iter()
        .copied()
        .filter(move |&e| phase.is_sharp(topo.edge_sharpness[e as usize]))
}

/// The rule of `v` in `phase`.
pub fn vertex_rule(topo: &Topology, v: usize, boundary: Boundary, phase: Phase) -> Rule {
    if forced_corner(topo, v, boundary) {
        return Rule::Corner;
    }
    match sharp_edges(topo, v, phase).count() {
        0 | 1 => Rule::Smooth,
        2 => Rule::Crease,
        _ => Rule::Corner,
    }
}

/// The masks a vertex point blends: its rule with weight 1 when the rule is the same at the
/// next level; otherwise the parent rule weighted by the mean sharpness of the edges going
/// smooth (at most 1) and the child rule taking the rest (semi-sharp creases, fractional
/// sharpness included). The second part may have weight 0.
pub fn vertex_parts(topo: &Topology, v: usize, boundary: Boundary) -> [Part; 2] {
    let parent = vertex_rule(topo, v, boundary, Phase::Parent);
    let child = vertex_rule(topo, v, boundary, Phase::Child);
    if parent == child {
        return [
            Part {
                rule: parent,
                phase: Phase::Parent,
                weight: 1.0,
            },
            Part {
                rule: child,
                phase: Phase::Child,
                weight: 0.0,
            },
        ];
    }
    let w = transition_weight(
        topo.edges_of(v)
            .iter()
            .map(|&e| topo.edge_sharpness[e as usize]),
    );
    [
        Part {
            rule: parent,
            phase: Phase::Parent,
            weight: w,
        },
        Part {
            rule: child,
            phase: Phase::Child,
            weight: 1.0 - w,
        },
    ]
}

/// How much of the sharp rule an edge point of sharpness `s` takes (the smooth rule takes
/// the rest): 1 while the edge stays sharp at the next level, its sharpness when it goes
/// smooth there (fractional blending), 0 for a smooth edge.
pub fn edge_sharp_weight(s: f32) -> f64 {
    if s <= 0.0 {
        0.0
    } else if decrement(s) > 0.0 {
        1.0
    } else {
        f64::from(s.min(1.0))
    }
}

/// The sharp edges after every edge of `topo` is split at its point, numbered as the
/// triangle schemes number new vertices (edge points `0..edges`, vertex points after): both
/// halves keep the decremented sharpness; boundary edges are not listed.
pub fn split_creases(topo: &Topology) -> Vec<([u32; 2], f32)> {
    let vp = topo.edge_vertices.len() as u32;
    let mut creases = Vec::new();
    for (e, &[a, b]) in topo.edge_vertices.iter().enumerate() {
        let s = decrement(topo.edge_sharpness[e]);
        if s > 0.0 && !topo.is_boundary(e as u32) {
            let ep = e as u32;
            creases.extend([([vp + a, ep], s), ([ep, vp + b], s)]);
        }
    }
    creases
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sharpness::INFINITELY_SHARP;
    use crate::test_meshes::hex_fan as fan;
    use crate::topology::Faces;

    #[test]
    fn edge_weights_follow_uniform_creasing() {
        assert_eq!(edge_sharp_weight(0.0), 0.0);
        assert_eq!(edge_sharp_weight(0.25), 0.25);
        assert_eq!(edge_sharp_weight(1.0), 1.0);
        assert_eq!(edge_sharp_weight(1.5), 1.0);
        assert_eq!(edge_sharp_weight(INFINITELY_SHARP), 1.0);
    }

    #[test]
    fn semi_sharp_crease_blends_crease_and_smooth() {
        let t = Topology::build(&fan(), &[([0, 1], 0.5), ([0, 4], 0.5)]).unwrap();
        let [p, c] = vertex_parts(&t, 0, Boundary::EdgeOnly);
        assert_eq!((p.rule, p.weight), (Rule::Crease, 0.5));
        assert_eq!((c.rule, c.weight), (Rule::Smooth, 0.5));
        let t = Topology::build(&fan(), &[([0, 1], 2.0), ([0, 4], 3.0)]).unwrap();
        let [p, c] = vertex_parts(&t, 0, Boundary::EdgeOnly);
        assert_eq!((p.rule, p.weight, c.weight), (Rule::Crease, 1.0, 0.0));
    }

    #[test]
    fn boundary_vertices_are_creases_or_corners() {
        let t = Topology::build(&fan(), &[]).unwrap();
        // Ring vertex 1 lies on two boundary edges and two faces.
        assert_eq!(
            vertex_rule(&t, 1, Boundary::EdgeAndCorner, Phase::Parent),
            Rule::Crease
        );
        let one = Faces {
            offsets: vec![0, 3],
            indices: vec![0, 1, 2],
            vertex_count: 3,
        };
        let t = Topology::build(&one, &[]).unwrap();
        assert_eq!(
            vertex_rule(&t, 0, Boundary::EdgeOnly, Phase::Child),
            Rule::Crease
        );
        assert_eq!(
            vertex_rule(&t, 0, Boundary::EdgeAndCorner, Phase::Child),
            Rule::Corner
        );
    }
}
