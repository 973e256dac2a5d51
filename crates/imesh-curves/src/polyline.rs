//! Cutting the boundary graph into maximal simple open polylines (the paper's preprocessing for
//! Douglas–Peucker, which only handles simple open curves).

use crate::graph::{CurveGraph, GraphEdge};

/// A simple chain of graph vertices between two cut vertices (open, but for the joined pieces
/// of a loop in [`crate::Simplification::polylines`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Polyline {
    /// Its vertices in order (at least two, all distinct but for a closed one's ends).
    pub vertices: Vec<u32>,
    /// The graph edge between `vertices[i]` and `vertices[i + 1]`.
    pub edges: Vec<u32>,
    /// The label on the positive side of the chain walked from its first vertex, then the label on
    /// the negative side (see [`GraphEdge::labels`]).
    pub labels: [u32; 2],
}

impl Polyline {
    /// The first and last vertex.
    pub fn ends(&self) -> [u32; 2] {
        [self.vertices[0], self.vertices[self.vertices.len() - 1]]
    }
}

/// The maximal simple open polylines of `g`.
///
/// A polyline ends at every vertex whose valence is not 2, at every pinned vertex, and where the
/// labels change (which a planar partition never does at a valence-2 vertex, but a caller's
/// graph might). What is left are closed loops of valence-2 vertices: each is cut into three
/// pieces of about equal length, starting at its lowest-then-leftmost vertex, so that no
/// simplification can collapse it to a segment or a point.
///
/// Every edge of `g` is in exactly one polyline.
///
/// ```
/// use imesh_curves::{polylines, CurveGraph, GraphEdge};
/// use imesh_geom::Point;
/// // A square loop: no vertex of valence ≠ 2, so it is cut into three pieces.
/// let points = vec![
///     Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 2.0),
///     Point::new(0.0, 2.0),
/// ];
/// let edges = (0..5u32).map(|i| GraphEdge { ends: [i, (i + 1) % 5], labels: [1, 0] }).collect();
/// let g = CurveGraph::new(points, edges)?;
/// let lines = polylines(&g);
/// assert_eq!(lines.len(), 3);
/// assert_eq!(lines.iter().map(|l| l.edges.len()).sum::<usize>(), 5);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn polylines(g: &CurveGraph) -> Vec<Polyline> {
    polylines_and_loops(g).0
}

/// A closed curve that [`polylines`] cut into three pieces: the pieces are `lines[first]`,
/// `lines[first + 1]` and `lines[first + 2]`, each starting where the one before ends, the
/// third ending where the first starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CutLoop {
    /// The index of the first piece.
    pub first: usize,
    /// True when the loop's start is a cut of its own too (a loop of valence-2 vertices, started
    /// at its lowest-then-leftmost vertex); false when it starts at a vertex that ends
    /// polylines anyway (a loop hanging off a junction or a pinned vertex).
    pub closed: bool,
}

/// [`polylines`], with the closed curves it cut into three pieces: those cuts are the
/// polylines' only ends that the graph does not make (see [`CutLoop`]).
pub(crate) fn polylines_and_loops(g: &CurveGraph) -> (Vec<Polyline>, Vec<CutLoop>) {
    let n = g.points().len() as u32;
    let edges = g.edges();
    let through = Through::new(g);
    let mut used = vec![false; edges.len()];
    let mut lines = Vec::new();
    let mut loops = Vec::new();
    let mut scratch = Polyline {
        vertices: Vec::new(),
        edges: Vec::new(),
        labels: [0, 0],
    };
    for v in 0..n {
        if !through.is_cut(g, v) {
            continue;
        }
        for &e in g.incident(v) {
            if !used[e as usize] {
                through.walk(g, &mut used, v, e, &mut scratch);
                let [a, b] = scratch.ends();
                if a == b {
                    // A loop hanging off a cut vertex: cut it too, keeping that vertex an end.
                    loops.push(CutLoop {
                        first: lines.len(),
                        closed: false,
                    });
                    lines.extend(cut_loop(g, &scratch, false));
                } else {
                    lines.push(scratch.clone());
                }
            }
        }
    }
    // Closed loops of valence-2 vertices remain.
    for e in 0..edges.len() {
        if !used[e] {
            through.walk(g, &mut used, edges[e].ends[0], e as u32, &mut scratch);
            loops.push(CutLoop {
                first: lines.len(),
                closed: true,
            });
            lines.extend(cut_loop(g, &scratch, true));
        }
    }
    (lines, loops)
}

/// `e` walked so that `v` is its end (`leaving == false`) or its start (`leaving == true`).
fn oriented(e: GraphEdge, v: u32, leaving: bool) -> GraphEdge {
    if (e.ends[0] == v) == leaving {
        e
    } else {
        e.reversed()
    }
}

/// Where a walk goes on through each end of each edge: for end `s` of edge `e`, at `2e + s`, the
/// next edge `f` and the end `t` of `f` at which the walk enters it, as `2f + t`, or [`STOP`]
/// when that end is a cut vertex.
///
/// A walk then reads one entry per step, and the next step's address is known as soon as that
/// entry is, so the reads of the edges' vertices do not wait on each other: walking the graph's
/// own incidence lists takes three dependent reads per step (edge, vertex, incident edges), each
/// a likely cache miss on a large graph.
struct Through {
    next: Vec<u32>,
}

const STOP: u32 = u32::MAX;

impl Through {
    fn new(g: &CurveGraph) -> Self {
        let edges = g.edges();
        let mut next = vec![STOP; 2 * edges.len()];
        let end = |e: u32, v: u32| 2 * e + u32::from(edges[e as usize].ends[1] == v);
        for v in 0..g.points().len() as u32 {
            if let &[e, f] = g.incident(v) {
                if !g.is_pinned(v) && continues(edges, e, f, v) {
                    let (se, sf) = (end(e, v), end(f, v));
                    next[se as usize] = sf;
                    next[sf as usize] = se;
                }
            }
        }
        Self { next }
    }

    /// True when a polyline ends at `v`: a vertex of valence other than 2, a pinned one, or one
    /// where the labels change.
    fn is_cut(&self, g: &CurveGraph, v: u32) -> bool {
        match g.incident(v) {
            &[e, _] => {
                self.next[(2 * e + u32::from(g.edges()[e as usize].ends[1] == v)) as usize] == STOP
            }
            _ => true,
        }
    }

    /// Walks from `start` along `first` until a cut vertex or back to `start` (a loop), into
    /// `line`: one buffer serves every walk, and a caller copies out what it keeps at its exact
    /// length (most polylines are short: growing two vectors step by step would allocate
    /// several times for each).
    fn walk(&self, g: &CurveGraph, used: &mut [bool], start: u32, first: u32, line: &mut Polyline) {
        let edges = g.edges();
        line.labels = oriented(edges[first as usize], start, true).labels;
        let (vertices, line_edges) = (&mut line.vertices, &mut line.edges);
        vertices.clear();
        vertices.push(start);
        line_edges.clear();
        // `at` is the end of the current edge the walk entered it by.
        let mut at = 2 * first + u32::from(edges[first as usize].ends[1] == start);
        loop {
            let e = at / 2;
            used[e as usize] = true;
            line_edges.push(e);
            let v = edges[e as usize].ends[(1 - at % 2) as usize];
            vertices.push(v);
            at = self.next[(at ^ 1) as usize];
            if at == STOP || v == start {
                break;
            }
        }
    }
}

/// True when walking in along `e` to `v` and out along `f` keeps the same labels on the left and
/// on the right.
fn continues(edges: &[GraphEdge], e: u32, f: u32, v: u32) -> bool {
    let a = oriented(edges[e as usize], v, false);
    let b = oriented(edges[f as usize], v, true);
    a.labels == b.labels
}

/// Cuts a closed loop (first vertex repeated at the end) into three open pieces of about equal
/// length, starting from its first vertex or (`reroot`) from its lowest-then-leftmost vertex.
fn cut_loop(g: &CurveGraph, line: &Polyline, reroot: bool) -> [Polyline; 3] {
    let m = line.edges.len();
    let lowest = |&i: &usize, &j: &usize| {
        let (p, q) = (g.point(line.vertices[i]), g.point(line.vertices[j]));
        (p.y, p.x)
            .partial_cmp(&(q.y, q.x))
            .unwrap_or(std::cmp::Ordering::Equal)
    };
    let start = if reroot {
        (0..m).min_by(lowest).unwrap_or(0)
    } else {
        0
    };
    // Walk the loop from `start`: vertex `i` of the walk is `line.vertices[(start + i) % m]`.
    let at = |i: usize| (start + i) % m;
    let step = |i: usize| {
        let (p, q) = (
            g.point(line.vertices[at(i)]),
            g.point(line.vertices[at(i + 1)]),
        );
        p.distance_squared(q).sqrt()
    };
    let total: f64 = (0..m).map(step).sum();
    // Cut vertices at one and two thirds of the length, kept strictly inside and apart (a loop
    // has at least three edges in a graph without duplicate edges): the first vertex whose
    // length from the start is at least that fraction of the total.
    let (mut cuts, mut length) = ([m; 2], 0.0);
    for i in 0..m {
        for (cut, fraction) in cuts.iter_mut().zip([1.0 / 3.0, 2.0 / 3.0]) {
            if *cut == m && length >= fraction * total {
                *cut = i;
            }
        }
        length += step(i);
    }
    let c1 = cuts[0].clamp(1, m - 2);
    let c2 = cuts[1].clamp(c1 + 1, m - 1);
    [(0, c1), (c1, c2), (c2, m)].map(|(i, j)| Polyline {
        vertices: (i..=j).map(|k| line.vertices[at(k)]).collect(),
        edges: (i..j).map(|k| line.edges[at(k)]).collect(),
        labels: line.labels,
    })
}
