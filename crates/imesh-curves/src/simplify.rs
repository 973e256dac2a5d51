//! Topology-preserving Douglas–Peucker: the PSLG G' (DESIGN.md §2, step 5).
//!
//! Each polyline is simplified top-down: a chain whose vertices all lie within the tolerance of
//! the chord between its ends is replaced by that chord — unless the chord would change the
//! topology, in which case the farthest vertex is kept and both halves are tried in turn. The
//! chord `s` replacing the chain `C` is safe when
//!
//! - `s` meets no other edge of the current graph (other than at its two ends), so the graph
//!   stays planar; and
//! - the region between `C` and `s` (the points around which the closed curve `C + s` winds, and
//!   the curve itself) holds no vertex of the current graph other than those of `C`.
//!
//! With these, every edge that could enter the region would have to cross `s` or `C` or end
//! inside it, so no curve is jumped over and no face is emptied; a face bounded by `C` and one
//! other edge joining its ends would need `s` to overlap that edge, which the first test refuses.
//! Polylines are simplified one after the other against the current state of all others, and a
//! grid of the current edges and vertices keeps each test local.

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use rayon::prelude::*;

use crate::distance::segment_distance_squared;
use crate::graph::{CurveGraph, GraphEdge};
use crate::grid::{conflict, edge_cells, grid_for, within, CellChains, CellLists, Grid};
use crate::polyline::{polylines, Polyline};
use crate::CurveError;

/// Default simplification tolerance in pixels.
pub const DEFAULT_TOLERANCE: f64 = 2.0;

/// The most pieces of a simplified polyline that its second pass joins into one chord.
pub const MERGE_SPAN: usize = 8;

/// Options of [`simplify`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifyOptions {
    /// The largest distance, in pixels, from a removed vertex to the simplified edge that
    /// replaces it.
    pub tolerance: f64,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

/// The simplified graph G' and where each of its edges comes from.
#[derive(Clone, Debug)]
pub struct Simplification {
    /// The polylines of the input graph (see [`polylines`]).
    pub polylines: Vec<Polyline>,
    /// G': the same points as the input, with the simplified edges (labels as their polyline's).
    /// Every polyline end is pinned.
    pub graph: CurveGraph,
    /// For each edge of G', the original vertices it replaces, from `ends[0]` to `ends[1]`.
    pub chains: Vec<Vec<u32>>,
    /// For each edge of G', the index of its polyline.
    pub polyline_of: Vec<u32>,
    /// Chords within the tolerance refused because they would have changed the topology.
    pub refused: usize,
    /// Vertices that Douglas–Peucker kept and the second pass removed (see
    /// [`MERGE_SPAN`]).
    pub merged: usize,
    /// The largest distance from an original vertex to its simplified edge.
    pub max_deviation: f64,
}

/// Simplifies every polyline of `g` (cut by [`polylines`]) with a topology-preserving
/// Douglas–Peucker at `options.tolerance`.
///
/// # Errors
/// [`CurveError::BadTolerance`] for a negative or non-finite tolerance.
///
/// ```
/// use imesh_curves::{simplify, CurveGraph, GraphEdge, SimplifyOptions};
/// use imesh_geom::Point;
/// // A wavy open curve between two vertices of valence 1.
/// let points: Vec<Point> = (0..=20).map(|i| Point::new(f64::from(i), 0.3 * f64::from(i % 2))).collect();
/// let edges = (0..20u32).map(|i| GraphEdge { ends: [i, i + 1], labels: [1, 2] }).collect();
/// let g = CurveGraph::new(points, edges)?;
/// let s = simplify(&g, &SimplifyOptions { tolerance: 0.5 })?;
/// assert_eq!(s.graph.edges().len(), 1);
/// assert_eq!(s.chains[0].len(), 21);
/// assert!(s.max_deviation <= 0.5);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn simplify(g: &CurveGraph, options: &SimplifyOptions) -> Result<Simplification, CurveError> {
    let tolerance = options.tolerance;
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(CurveError::BadTolerance { tolerance });
    }
    // Cutting the polylines and indexing the graph are independent.
    let (lines, index) = rayon::join(|| polylines(g), || Index::new(g));
    let (kept, state) = simplify_lines(&lines, State::new(&index), tolerance);
    let pieces = || {
        lines
            .iter()
            .zip(&kept)
            .enumerate()
            .flat_map(|(index, (line, kept))| {
                kept.windows(2).map(move |w| (index, line, w[0], w[1]))
            })
    };
    let edges = pieces()
        .map(|(_, line, i, j)| GraphEdge {
            ends: [line.vertices[i], line.vertices[j]],
            labels: line.labels,
        })
        .collect();
    // Indexing G' and copying out the chains are independent.
    let (graph, (chains, polyline_of)) = rayon::join(
        || CurveGraph::new(g.points().to_vec(), edges),
        || {
            pieces()
                .map(|(index, line, i, j)| (line.vertices[i..=j].to_vec(), index as u32))
                .unzip()
        },
    );
    let mut graph = graph?;
    for line in &lines {
        for v in line.ends() {
            graph.pin(v)?;
        }
    }
    Ok(Simplification {
        polylines: lines,
        graph,
        chains,
        polyline_of,
        refused: state.refused,
        merged: state.merged,
        max_deviation: state.max_deviation,
    })
}

/// Simplifies every polyline against `state`; returns the kept vertex indices of each.
///
/// A polyline's simplification reads and changes the graph only inside the polyline's bounding
/// box: its chords and the regions between them and their chains lie there, and the tests reject
/// anything whose box does not meet the chord's or the chain's. So the polylines strictly left of
/// a vertical line and those strictly right of it are independent: each side is simplified
/// against its own copy of the graph, side by side, the copies are merged, and the polylines
/// that cross the line come last. The result is that of simplifying the left side, then the
/// right side, then the rest, one after the other — the same on any number of threads.
fn simplify_lines<'a>(
    lines: &[Polyline],
    mut state: State<'a>,
    tolerance: f64,
) -> (Vec<Vec<usize>>, State<'a>) {
    let points = state.g().points();
    let extent: Vec<[f64; 2]> = lines
        .par_iter()
        .map(|line| {
            line.vertices
                .iter()
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &v| {
                    let x = points[v as usize].x;
                    [lo.min(x), hi.max(x)]
                })
        })
        .collect();
    let split = state.balanced_split(lines, &extent);
    let mut sides: [Vec<usize>; 3] = Default::default();
    for (k, &[lo, hi]) in extent.iter().enumerate() {
        let side = if hi < split {
            0
        } else if lo > split {
            1
        } else {
            2
        };
        sides[side].push(k);
    }
    let mut kept = vec![Vec::new(); lines.len()];
    let mut right = state.clone();
    let run = |state: &mut State<'a>, ids: &[usize]| -> Vec<Vec<usize>> {
        ids.iter()
            .map(|&k| state.simplify_line(&lines[k], tolerance))
            .collect()
    };
    let (left_kept, right_kept) =
        rayon::join(|| run(&mut state, &sides[0]), || run(&mut right, &sides[1]));
    state.absorb(&right);
    let rest_kept = run(&mut state, &sides[2]);
    for (ids, found) in sides.iter().zip([left_kept, right_kept, rest_kept]) {
        for (&k, indices) in ids.iter().zip(found) {
            kept[k] = indices;
        }
    }
    (kept, state)
}

/// The input graph indexed for the topology tests: its edges and its live vertices by grid
/// cell. It never changes, so every [`State`] shares it.
struct Index<'g> {
    g: &'g CurveGraph,
    grid: Grid,
    edge_cells: CellLists,
    /// The initially live vertices of each cell, with their points alongside so that a query's
    /// box test reads the cell's memory only.
    vertex_cells: CellLists<(u32, Point)>,
}

impl<'g> Index<'g> {
    fn new(g: &'g CurveGraph) -> Self {
        let grid = grid_for(g);
        // The edge lists and the vertex lists are independent: build them side by side.
        let (edge_cells, vertex_cells) =
            rayon::join(|| edge_cells(g, &grid), || vertex_cells(g, &grid));
        Self {
            g,
            grid,
            edge_cells,
            vertex_cells,
        }
    }
}

/// The current graph during simplification: the input's edges and the chords that replaced
/// some of them (edge `m + k` is chord `k`, for `m` input edges), which of them are live, and
/// which vertices are.
#[derive(Clone)]
struct State<'a> {
    index: &'a Index<'a>,
    chords: Vec<[u32; 2]>,
    chord_cells: CellChains,
    /// One stamp per edge and per vertex, so that a query reads one word per candidate:
    /// [`REMOVED`] once it has left the graph; the current query's number while it is in the
    /// curve under test (and, for an edge, once the query has seen it: an edge crosses several
    /// cells, a vertex lies in one).
    edge_mark: Vec<u32>,
    vertex_mark: Vec<u32>,
    query: u32,
    /// Buffers reused from one polyline to the next (most polylines are a few edges long, so
    /// allocating these per polyline would cost more than the work on them).
    scratch: Scratch,
    refused: usize,
    merged: usize,
    /// The largest distance from a removed vertex to its chord.
    max_deviation: f64,
}

impl<'a> State<'a> {
    /// The input graph.
    fn g(&self) -> &'a CurveGraph {
        self.index.g
    }

    fn new(index: &'a Index<'a>) -> Self {
        let g = index.g;
        let vertex_mark = (0..g.points().len() as u32)
            .map(|v| if g.valence(v) > 0 { 0 } else { REMOVED })
            .collect();
        Self {
            index,
            chords: Vec::new(),
            chord_cells: CellChains::new(index.grid.len()),
            edge_mark: vec![0; g.edges().len()],
            vertex_mark,
            query: 0,
            scratch: Scratch::default(),
            refused: 0,
            merged: 0,
            max_deviation: 0.0,
        }
    }

    /// Douglas–Peucker on one polyline; returns the indices (into `line.vertices`) kept.
    fn simplify_line(&mut self, line: &Polyline, tolerance: f64) -> Vec<usize> {
        let v = &line.vertices;
        let mut scratch = std::mem::take(&mut self.scratch);
        let Scratch {
            keep, piece, stack, ..
        } = &mut scratch;
        keep.clear();
        keep.resize(v.len(), false);
        keep[0] = true;
        keep[v.len() - 1] = true;
        // The current edge of the piece starting at each kept vertex.
        piece.clear();
        piece.resize(v.len(), u32::MAX);
        stack.clear();
        stack.push((0, v.len() - 1));
        while let Some((i, j)) = stack.pop() {
            if j <= i + 1 {
                if j == i + 1 {
                    piece[i] = line.edges[i];
                }
                continue;
            }
            let (a, b) = (self.g().point(v[i]), self.g().point(v[j]));
            let (mut far, mut deviation2) = (i + 1, -1.0);
            for (k, &x) in v.iter().enumerate().take(j).skip(i + 1) {
                let d2 = segment_distance_squared(a, b, self.g().point(x));
                if d2 > deviation2 {
                    (far, deviation2) = (k, d2);
                }
            }
            let deviation = deviation2.sqrt();
            if deviation <= tolerance {
                if straight(self.g().points(), &v[i..=j])
                    || self.chord_is_safe(line, i, j, deviation)
                {
                    piece[i] = self.replace(line, i, j);
                    self.max_deviation = self.max_deviation.max(deviation);
                    continue;
                }
                self.refused += 1;
            }
            keep[far] = true;
            stack.push((far, j));
            stack.push((i, far));
        }
        let kept: Vec<usize> = (0..v.len()).filter(|&k| keep[k]).collect();
        let kept = if kept.len() <= 2 {
            kept
        } else {
            self.merge_pieces(line, &kept, &mut scratch, tolerance)
        };
        self.scratch = scratch;
        kept
    }

    /// The two tests of the module documentation for the chord `v[i] v[j]` replacing the chain
    /// `v[i..=j]`, whose vertices are within `deviation` of the chord.
    fn chord_is_safe(&mut self, line: &Polyline, i: usize, j: usize, deviation: f64) -> bool {
        let chain = &line.vertices[i..=j];
        self.shortcut_is_safe(chain, &line.edges[i..j], chain, deviation)
    }

    /// The tests of [`State::chord_is_safe`] for a chord replacing the current curve `chain`
    /// (vertex ids, first and last the chord's ends), whose current edges are `edges`; the
    /// vertices in `own` are the curve's (some no longer live), and every vertex of `chain` is
    /// within `deviation` of the chord.
    fn shortcut_is_safe(
        &mut self,
        chain: &[u32],
        edges: &[u32],
        own: &[u32],
        deviation: f64,
    ) -> bool {
        self.query += 1;
        let q = self.query;
        for &e in edges {
            self.edge_mark[e as usize] = q;
        }
        for &x in own {
            if self.vertex_mark[x as usize] != REMOVED {
                self.vertex_mark[x as usize] = q;
            }
        }
        let chord = [chain[0], chain[chain.len() - 1]];
        let points = self.g().points();
        let (a, b) = (points[chord[0] as usize], points[chord[1] as usize]);

        // 1. The chord meets no other current edge (the bounding boxes must overlap first).
        let (lo, hi) = bounding_box([a, b].into_iter());
        let mut safe = true;
        let (index, chords, chord_cells) = (self.index, &self.chords, &self.chord_cells);
        let (input, m) = (self.g().edges(), self.g().edges().len());
        let edge_mark = &mut self.edge_mark;
        index.grid.cells_near_segment(a, b, 0.0, |c| {
            if !safe {
                return;
            }
            let edges = index.edge_cells.get(c).iter().copied();
            for e in edges.chain(chord_cells.iter(c)) {
                let e = e as usize;
                if edge_mark[e] == q || edge_mark[e] == REMOVED {
                    continue;
                }
                edge_mark[e] = q;
                let [u, w] = if e < m { input[e].ends } else { chords[e - m] };
                let (pu, pw) = (points[u as usize], points[w as usize]);
                if pu.x.max(pw.x) < lo.x
                    || pu.x.min(pw.x) > hi.x
                    || pu.y.max(pw.y) < lo.y
                    || pu.y.min(pw.y) > hi.y
                {
                    continue;
                }
                if conflict(points, chord, [u, w]) {
                    safe = false;
                    return;
                }
            }
        });
        if !safe {
            return false;
        }

        // 2. No other current vertex in the region between the chain and the chord.
        let (lo, hi) = bounding_box(chain.iter().map(|&x| points[x as usize]));
        let vertex_mark = &self.vertex_mark;
        let pad = deviation * (1.0 + 1e-12) + 1e-12;
        let reach2 = (deviation * (1.0 + 1e-9) + 1e-9).powi(2);
        index.grid.cells_near_segment(a, b, pad, |c| {
            if !safe {
                return;
            }
            for &(x, p) in index.vertex_cells.get(c) {
                if p.x < lo.x || p.x > hi.x || p.y < lo.y || p.y > hi.y {
                    continue;
                }
                let mark = vertex_mark[x as usize];
                if mark == q || mark == REMOVED {
                    continue;
                }
                // The region lies within `deviation` of the chord (the distance to a segment is
                // convex, so its largest value on the region is at a chain vertex): a point
                // clearly farther away is outside, without walking the chain.
                if segment_distance_squared(a, b, p) > reach2 {
                    continue;
                }
                if encloses(points, chain, p) {
                    safe = false;
                    return;
                }
            }
        });
        safe
    }

    /// Replaces the chain `v[i..=j]` by its chord in the current graph.
    fn replace(&mut self, line: &Polyline, i: usize, j: usize) -> u32 {
        self.replace_edges(&line.edges[i..j], &line.vertices[i + 1..j]);
        self.add_chord([line.vertices[i], line.vertices[j]])
    }

    /// Removes `edges` and `vertices` from the current graph.
    fn replace_edges(&mut self, edges: &[u32], vertices: &[u32]) {
        for &e in edges {
            self.edge_mark[e as usize] = REMOVED;
        }
        for &x in vertices {
            self.vertex_mark[x as usize] = REMOVED;
        }
    }

    /// The second pass over a simplified polyline: Douglas–Peucker keeps every vertex that is
    /// farthest from some chord, so a needle or a zig-zag (sliver triangles of alternating
    /// labels along a straight boundary) keeps its tips even when the whole run lies within the
    /// tolerance of one chord (a zig-zag's sub-chords all end at a tip: none is within the
    /// tolerance until the whole run is). From each kept vertex, the longest run of up to
    /// [`MERGE_SPAN`] following pieces whose original vertices are all within the tolerance of
    /// one chord, and whose chord passes the topology tests against the current graph, becomes
    /// that chord. Returns the kept indices left.
    fn merge_pieces(
        &mut self,
        line: &Polyline,
        kept: &[usize],
        scratch: &mut Scratch,
        tolerance: f64,
    ) -> Vec<usize> {
        let Scratch {
            piece,
            curve,
            edges,
            ..
        } = scratch;
        let v = &line.vertices;
        let points = self.g().points();
        let mut out = vec![kept[0]];
        let mut a = 0;
        while a + 1 < kept.len() {
            let mut best = (a + 1, 0.0);
            for b in a + 2..kept.len().min(a + MERGE_SPAN + 1) {
                let (i, j) = (kept[a], kept[b]);
                let (p, q) = (points[v[i] as usize], points[v[j] as usize]);
                let deviation = v[i + 1..j]
                    .iter()
                    .map(|&x| segment_distance_squared(p, q, points[x as usize]))
                    .fold(0.0, f64::max)
                    .sqrt();
                if deviation > tolerance {
                    continue;
                }
                curve.clear();
                curve.extend(kept[a..=b].iter().map(|&k| v[k]));
                edges.clear();
                edges.extend(kept[a..b].iter().map(|&k| piece[k]));
                if self.shortcut_is_safe(curve, edges, &v[i..=j], deviation) {
                    best = (b, deviation);
                }
            }
            let (b, deviation) = best;
            if b > a + 1 {
                edges.clear();
                edges.extend(kept[a..b].iter().map(|&k| piece[k]));
                curve.clear();
                curve.extend(kept[a + 1..b].iter().map(|&k| v[k]));
                self.replace_edges(edges, curve);
                self.add_chord([v[kept[a]], v[kept[b]]]);
                self.max_deviation = self.max_deviation.max(deviation);
                self.merged += b - a - 1;
            }
            out.push(kept[b]);
            a = b;
        }
        out
    }

    /// A vertical line `x = split` (a grid column boundary) with about as many polyline vertices
    /// wholly on either side, given each polyline's x-extent.
    fn balanced_split(&self, lines: &[Polyline], extent: &[[f64; 2]]) -> f64 {
        let grid = &self.index.grid;
        let columns = grid.columns();
        let mut weight = vec![0usize; columns + 1];
        for (line, &[lo, hi]) in lines.iter().zip(extent) {
            weight[grid.column(0.5 * (lo + hi))] += line.vertices.len();
        }
        let half = weight.iter().sum::<usize>() / 2;
        let mut sum = 0;
        let column = weight
            .iter()
            .position(|&w| {
                sum += w;
                sum >= half
            })
            .unwrap_or(0);
        grid.column_start(column + 1)
    }

    /// Takes in what `other`, a copy of this state from before any simplification, did: the
    /// edges and vertices it removed and the chords it added and kept.
    fn absorb(&mut self, other: &State<'_>) {
        let m = self.g().edges().len();
        let marks = self.edge_mark[..m].iter_mut().zip(&other.edge_mark[..m]);
        for (mark, &there) in marks.chain(self.vertex_mark.iter_mut().zip(&other.vertex_mark)) {
            if there == REMOVED {
                *mark = REMOVED;
            }
        }
        // Only the chords still live there (the second pass replaces some of the first's), in
        // the cells the other state found for them. Their ids there are `m + k` for chord `k`;
        // here they follow this state's own.
        let mut id = vec![REMOVED; other.chords.len()];
        for (k, (&chord, &mark)) in other.chords.iter().zip(&other.edge_mark[m..]).enumerate() {
            if mark != REMOVED {
                id[k] = self.edge_mark.len() as u32;
                self.chords.push(chord);
                self.edge_mark.push(0);
            }
        }
        for (cell, e) in other.chord_cells.entries() {
            let e = id[e as usize - m];
            if e != REMOVED {
                self.chord_cells.push(cell, e);
            }
        }
        self.merged += other.merged;
        self.refused += other.refused;
        self.max_deviation = self.max_deviation.max(other.max_deviation);
    }

    /// Adds the chord `chord` to the current graph.
    fn add_chord(&mut self, chord: [u32; 2]) -> u32 {
        let id = self.edge_mark.len() as u32;
        self.chords.push(chord);
        self.edge_mark.push(0);
        let (a, b) = (self.g().point(chord[0]), self.g().point(chord[1]));
        let cells = &mut self.chord_cells;
        self.index
            .grid
            .cells_near_segment(a, b, 0.0, |c| cells.push(c, id));
        id
    }
}

/// Work buffers of [`State::simplify_line`] and [`State::merge_pieces`].
#[derive(Clone, Default)]
struct Scratch {
    /// Per vertex of the polyline: kept by Douglas–Peucker.
    keep: Vec<bool>,
    /// Per kept vertex of the polyline: the current edge of the piece that starts there.
    piece: Vec<u32>,
    /// Douglas–Peucker's pending index ranges.
    stack: Vec<(usize, usize)>,
    /// A curve under test (vertex ids) and its current edges.
    curve: Vec<u32>,
    edges: Vec<u32>,
}

/// The stamp of an edge or a vertex that has left the current graph (see `State::edge_mark`).
const REMOVED: u32 = u32::MAX;

/// True when every vertex of the chain lies exactly on the segment between its ends: the chord
/// is then the chain itself as a point set, and replacing one by the other changes nothing.
/// (A simple chain on one line runs monotonically from one end to the other.)
fn straight(points: &[Point], chain: &[u32]) -> bool {
    let (a, b) = (
        points[chain[0] as usize],
        points[chain[chain.len() - 1] as usize],
    );
    chain[1..chain.len() - 1]
        .iter()
        .all(|&v| orient2d(a, b, points[v as usize]) == 0.0)
}

/// The vertices of each grid cell that some edge ends at, with their points.
fn vertex_cells(g: &CurveGraph, grid: &Grid) -> CellLists<(u32, Point)> {
    let pairs: Vec<(u32, (u32, Point))> = (0..g.points().len() as u32)
        .filter(|&v| g.valence(v) > 0)
        .map(|v| (grid.cell(g.point(v)) as u32, (v, g.point(v))))
        .collect();
    CellLists::new(grid.len(), &pairs)
}

fn bounding_box(points: impl Iterator<Item = Point>) -> (Point, Point) {
    points.fold(
        (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        ),
        |(lo, hi), p| {
            (
                Point::new(lo.x.min(p.x), lo.y.min(p.y)),
                Point::new(hi.x.max(p.x), hi.y.max(p.y)),
            )
        },
    )
}

/// True when `p` lies on the closed curve `chain + chord` (chain closed back to its start) or the
/// curve winds around it. Exact: winding number by upward/downward crossings decided with
/// `orient2d`.
fn encloses(points: &[Point], chain: &[u32], p: Point) -> bool {
    let mut winding = 0i64;
    let closing = [chain[chain.len() - 1], chain[0]];
    let edges = chain
        .windows(2)
        .map(|w| [w[0], w[1]])
        .chain(std::iter::once(closing));
    for [u, w] in edges {
        let (a, b) = (points[u as usize], points[w as usize]);
        let in_y = (a.y <= p.y) != (b.y <= p.y);
        let in_box = within(a, b, p);
        if !in_y && !in_box {
            continue;
        }
        let o = orient2d(a, b, p);
        if o == 0.0 && in_box {
            return true;
        }
        if in_y {
            if a.y <= p.y && o > 0.0 {
                winding += 1;
            } else if a.y > p.y && o < 0.0 {
                winding -= 1;
            }
        }
    }
    winding != 0
}
