//! Topology-preserving Douglas–Peucker: the PSLG G' (DESIGN.md §2, step 5).
//!
//! Each polyline is simplified top-down: a chain whose vertices all lie within the tolerance of
//! the chord between its ends is replaced by that chord — unless the chord would change the
//! topology, in which case the farthest vertex is kept and both halves are tried in turn. The
//! chord `s` replacing the chain `C` is safe when
//!
//! - the region between `C` and `s` (the points around which the closed curve `C + s` winds, and
//!   the curve itself) holds no vertex of the current graph other than those of `C`; and
//! - no other edge of the current graph joins the two ends of `s`.
//!
//! These keep the graph planar without testing `s` against the edges. An edge `e` crossing `s`
//! at a point `X` (not at an end of `s`: edges meet only at their ends) changes the winding
//! number by one there, so on one side of `X` it runs into the region; it cannot cross `s`
//! again (two segments meet once unless collinear) nor `C` (the graph is planar), so it ends in
//! the region or on `C` — the first test refuses the one, and the other makes `e` an edge of `C`
//! (the inner vertices of `C` have no other edges), which `s` replaces. An edge overlapping `s`
//! along its line has an end on `s`, or shares both ends with it, which the second test refuses.
//! So no curve is jumped over and no face is emptied. Polylines are simplified one after the
//! other against the current state of all others, and a grid of the vertices keeps each test
//! local.

use std::collections::HashSet;

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use rayon::prelude::*;

use crate::distance::segment_distance_squared;
use crate::graph::{CurveGraph, GraphEdge};
use crate::grid::{grid_for, within, CellLists, Grid};
use crate::polyline::{polylines_and_loops, CutLoop, Polyline};
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
    /// Pieces shorter than this, in pixels, are joined with a neighbouring piece of their
    /// polyline (the third pass) when the joined chord stays within the larger of the tolerance
    /// and half this length of the original vertices and passes the topology test: short
    /// boundary pieces make small elements along them. A closed curve's cut beside such a
    /// piece goes the same way (see `State::free_loop_cuts`). 0 (default): no third pass.
    pub min_length: f64,
}

impl SimplifyOptions {
    /// Douglas–Peucker at `tolerance` pixels, without the third pass.
    ///
    /// ```
    /// let o = imesh_curves::SimplifyOptions::with_tolerance(3.0);
    /// assert_eq!((o.tolerance, o.min_length), (3.0, 0.0));
    /// ```
    pub fn with_tolerance(tolerance: f64) -> Self {
        Self {
            tolerance,
            ..Self::default()
        }
    }

    /// How far the third pass's chords (and a freed loop cut's) may stray from the original
    /// vertices: the larger of the tolerance and half [`SimplifyOptions::min_length`].
    fn join_deviation(&self) -> f64 {
        self.tolerance.max(0.5 * self.min_length)
    }
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_TOLERANCE,
            min_length: 0.0,
        }
    }
}

/// The simplified graph G' and where each of its edges comes from.
#[derive(Clone, Debug)]
pub struct Simplification {
    /// The polylines of the input graph (see [`polylines`](crate::polylines)); where
    /// simplification freed a closed curve's cut, the two pieces on either side of it are one
    /// polyline (closed, its ends one vertex, when every cut of a loop hanging off a junction
    /// was freed).
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
    /// Vertices that Douglas–Peucker kept and the second pass (see [`MERGE_SPAN`]) or the third
    /// ([`SimplifyOptions::min_length`]) removed.
    pub merged: usize,
    /// The largest distance from an original vertex to its simplified edge.
    pub max_deviation: f64,
}

/// Simplifies every polyline of `g` (cut by [`polylines`](crate::polylines)) with a
/// topology-preserving Douglas–Peucker at `options.tolerance`, then frees the cuts of closed
/// curves that leave short pieces (see [`SimplifyOptions::min_length`]).
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
/// let s = simplify(&g, &SimplifyOptions::with_tolerance(0.5))?;
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
    let min_length = options.min_length;
    if !(min_length.is_finite() && min_length >= 0.0) {
        return Err(CurveError::BadTolerance {
            tolerance: min_length,
        });
    }
    // Cutting the polylines and indexing the graph are independent.
    let ((lines, loops), index) = rayon::join(|| polylines_and_loops(g), || Index::new(g));
    let (kept, mut state) = simplify_lines(&lines, State::new(&index), options);
    let (lines, kept) = state.free_loop_cuts(lines, kept, &loops, options);
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
    options: &SimplifyOptions,
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
            .map(|&k| state.simplify_line(&lines[k], options))
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

/// The input graph indexed for the topology test: its live vertices by grid cell. It never
/// changes, so every [`State`] shares it.
struct Index<'g> {
    g: &'g CurveGraph,
    grid: Grid,
    /// The initially live vertices of each cell, with their points alongside so that a query's
    /// box test reads the cell's memory only.
    vertex_cells: CellLists<(u32, Point)>,
}

impl<'g> Index<'g> {
    fn new(g: &'g CurveGraph) -> Self {
        let grid = grid_for(g);
        let vertex_cells = vertex_cells(g, &grid);
        Self {
            g,
            grid,
            vertex_cells,
        }
    }
}

/// The current graph during simplification, as far as the topology test needs it: which
/// vertices are live, and which pairs of polyline ends a chord now joins directly.
#[derive(Clone)]
struct State<'a> {
    index: &'a Index<'a>,
    /// One stamp per vertex, so that a query reads one word per candidate: [`REMOVED`] once it
    /// has left the graph; the current query's number while it is in the curve under test.
    vertex_mark: Vec<u32>,
    query: u32,
    /// The end pairs (lower id first) of the polylines that a chord has replaced whole.
    joined: HashSet<[u32; 2]>,
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
            vertex_mark,
            query: 0,
            joined: HashSet::new(),
            scratch: Scratch::default(),
            refused: 0,
            merged: 0,
            max_deviation: 0.0,
        }
    }

    /// Douglas–Peucker on one polyline; returns the indices (into `line.vertices`) kept.
    fn simplify_line(&mut self, line: &Polyline, options: &SimplifyOptions) -> Vec<usize> {
        let tolerance = options.tolerance;
        let v = &line.vertices;
        let mut scratch = std::mem::take(&mut self.scratch);
        let Scratch { keep, stack, .. } = &mut scratch;
        keep.clear();
        keep.resize(v.len(), false);
        keep[0] = true;
        keep[v.len() - 1] = true;
        stack.clear();
        stack.push((0, v.len() - 1));
        while let Some((i, j)) = stack.pop() {
            if j <= i + 1 {
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
                let chain = &v[i..=j];
                if straight(self.g().points(), chain)
                    || self.shortcut_is_safe(chain, chain, deviation)
                {
                    self.replace(chain, v.len() == chain.len());
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
        let kept = if kept.len() <= 2 || options.min_length <= 0.0 {
            kept
        } else {
            self.join_short_pieces(line, kept, &mut scratch, options)
        };
        self.scratch = scratch;
        kept
    }

    /// The topology test of the module documentation for a chord replacing the current curve
    /// `chain` (vertex ids, first and last the chord's ends, at least three); the vertices in
    /// `own` are the curve's (some no longer live), and every vertex of `chain` is within
    /// `deviation` of the chord.
    fn shortcut_is_safe(&mut self, chain: &[u32], own: &[u32], deviation: f64) -> bool {
        let points = self.g().points();
        let chord = [chain[0], chain[chain.len() - 1]];
        // Another edge joining the chord's ends: only an input edge or a chord replacing a
        // whole polyline can (an inner vertex of a polyline has no edges but the polyline's).
        let other = |e: &u32| {
            let [u, w] = self.g().edges()[*e as usize].ends;
            let far = if u == chord[0] { w } else { u };
            far == chord[1]
        };
        if self.g().incident(chord[0]).iter().any(other) || self.joined.contains(&pair(chord)) {
            return false;
        }
        self.query += 1;
        let q = self.query;
        for &x in own {
            if self.vertex_mark[x as usize] != REMOVED {
                self.vertex_mark[x as usize] = q;
            }
        }
        let (a, b) = (points[chord[0] as usize], points[chord[1] as usize]);
        let (lo, hi) = bounding_box(chain.iter().map(|&x| points[x as usize]));
        let (index, vertex_mark) = (self.index, &self.vertex_mark);
        let pad = deviation * (1.0 + 1e-12) + 1e-12;
        let reach2 = (deviation * (1.0 + 1e-9) + 1e-9).powi(2);
        let mut safe = true;
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

    /// Replaces the current curve `chain` by its chord, which joins the ends of its polyline
    /// when `whole`.
    fn replace(&mut self, chain: &[u32], whole: bool) {
        for &x in &chain[1..chain.len() - 1] {
            self.vertex_mark[x as usize] = REMOVED;
        }
        if whole {
            self.joined.insert(pair([chain[0], chain[chain.len() - 1]]));
        }
    }

    /// The second pass over a simplified polyline: Douglas–Peucker keeps every vertex that is
    /// farthest from some chord, so a needle or a zig-zag (sliver triangles of alternating
    /// labels along a straight boundary) keeps its tips even when the whole run lies within the
    /// tolerance of one chord (a zig-zag's sub-chords all end at a tip: none is within the
    /// tolerance until the whole run is). From each kept vertex, the longest run of up to
    /// [`MERGE_SPAN`] following pieces whose original vertices are all within the tolerance of
    /// one chord, and whose chord passes the topology test against the current graph, becomes
    /// that chord. Returns the kept indices left.
    fn merge_pieces(
        &mut self,
        line: &Polyline,
        kept: &[usize],
        scratch: &mut Scratch,
        tolerance: f64,
    ) -> Vec<usize> {
        let curve = &mut scratch.curve;
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
                if self.shortcut_is_safe(curve, &v[i..=j], deviation) {
                    best = (b, deviation);
                }
            }
            let (b, deviation) = best;
            if b > a + 1 {
                curve.clear();
                curve.extend(kept[a..=b].iter().map(|&k| v[k]));
                self.replace(curve, a == 0 && b == kept.len() - 1);
                self.max_deviation = self.max_deviation.max(deviation);
                self.merged += b - a - 1;
            }
            out.push(kept[b]);
            a = b;
        }
        out
    }

    /// Frees the cuts that [`polylines_and_loops`] made in closed curves where they leave a
    /// short piece. A cut is a pinned end of two pieces only because Douglas–Peucker needs open
    /// curves, so the third pass ([`SimplifyOptions::min_length`]) cannot join a short piece
    /// across it: on coins, an island of some 40 px² kept six vertices, two of them cuts beside
    /// pieces shorter than a quad side, and the unpaired triangle on one of those had quads of
    /// a fifth of the mean area (with the cuts freed it is a quadrilateral). A cut with a piece
    /// shorter than `min_length` on either side, whose two neighbours on the simplified curve
    /// can be joined by one chord (within the third pass's deviation of the original vertices,
    /// passing the topology test), is removed, the straightest first, while the loop keeps at
    /// least four vertices and, when its start was a cut too, one cut (a closed line's first
    /// vertex); the joined pieces then get the third pass again. (Freeing every cut that may
    /// go, short pieces or not, turned axis-parallel runs that a cut had ended into slanted
    /// chords within the tolerance: over 150 random images, 69 meshes changed, 40 of them
    /// down.)
    /// Returns the polylines, a loop's joined pieces in place of its three, and their kept
    /// indices.
    fn free_loop_cuts(
        &mut self,
        lines: Vec<Polyline>,
        kept: Vec<Vec<usize>>,
        loops: &[CutLoop],
        options: &SimplifyOptions,
    ) -> (Vec<Polyline>, Vec<Vec<usize>>) {
        if loops.is_empty() {
            return (lines, kept);
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut out = Vec::with_capacity(lines.len());
        let mut next_loop = loops.iter().peekable();
        let mut input = lines.into_iter().zip(kept).enumerate();
        while let Some((i, line)) = input.next() {
            let Some(l) = next_loop.next_if(|l| l.first == i) else {
                out.push(line);
                continue;
            };
            let mut pieces: Vec<(Polyline, Vec<usize>)> = std::iter::once(line)
                .chain(input.by_ref().take(2).map(|(_, piece)| piece))
                .collect();
            // cut[j]: the end of pieces[j] (the start of the next) is a cut of ours.
            let mut cut = vec![true, true, l.closed];
            let mut joined = false;
            while let Some((j, curve, deviation)) =
                self.freest_cut(&pieces, &cut, l.closed, options)
            {
                // The joined piece ends where the right one did.
                let next = (j + 1) % pieces.len();
                cut[j] = cut[next];
                cut.remove(next);
                let (right, right_kept) = pieces.remove(next);
                let j = if next < j { j - 1 } else { j };
                let (left, left_kept) = &mut pieces[j];
                let shift = left.vertices.len() - 1;
                left_kept.pop();
                left_kept.extend(right_kept[1..].iter().map(|&k| k + shift));
                left.vertices.extend_from_slice(&right.vertices[1..]);
                left.edges.extend_from_slice(&right.edges);
                self.replace(&curve, left_kept.len() == 2);
                self.max_deviation = self.max_deviation.max(deviation);
                self.merged += 1;
                joined = true;
            }
            for (line, line_kept) in pieces {
                let line_kept = if joined && options.min_length > 0.0 && line_kept.len() > 2 {
                    self.join_short_pieces(&line, line_kept, &mut scratch, options)
                } else {
                    line_kept
                };
                out.push((line, line_kept));
            }
        }
        self.scratch = scratch;
        out.into_iter().unzip()
    }

    /// The cut of [`State::free_loop_cuts`] to free next among a loop's `pieces` (each a
    /// polyline and its kept indices, in order around the loop; `cut[j]` when the end of piece
    /// `j` is a cut of ours): the one whose chord strays least from the original vertices,
    /// with that chord's current curve (the cut's two neighbours and the cut) and its
    /// deviation. None when no cut may go.
    fn freest_cut(
        &mut self,
        pieces: &[(Polyline, Vec<usize>)],
        cut: &[bool],
        closed: bool,
        options: &SimplifyOptions,
    ) -> Option<(usize, [u32; 3], f64)> {
        let vertices: usize = pieces.iter().map(|(_, k)| k.len() - 1).sum();
        let cuts = cut.iter().filter(|&&c| c).count();
        if vertices < 4 || cuts == 0 || (closed && cuts == 1) {
            return None;
        }
        let points = self.g().points();
        // A cut next to a short piece, joined as the third pass joins short pieces.
        let short = options.min_length * options.min_length;
        let bar = options.join_deviation();
        let mut best: Option<(usize, [u32; 3], f64)> = None;
        let mut own = Vec::new();
        for j in (0..pieces.len()).filter(|&j| cut[j]) {
            let (left, left_kept) = &pieces[j];
            let (right, right_kept) = &pieces[(j + 1) % pieces.len()];
            let i = left_kept[left_kept.len() - 2];
            own.clear();
            own.extend_from_slice(&left.vertices[i..]);
            own.extend_from_slice(&right.vertices[1..=right_kept[1]]);
            let (a, b) = (own[0], own[own.len() - 1]);
            let (p, q) = (points[a as usize], points[b as usize]);
            let at = points[left.vertices[left.vertices.len() - 1] as usize];
            if at.distance_squared(p) >= short && at.distance_squared(q) >= short {
                continue;
            }
            let deviation = own[1..own.len() - 1]
                .iter()
                .map(|&x| segment_distance_squared(p, q, points[x as usize]))
                .fold(0.0, f64::max)
                .sqrt();
            if deviation > bar || best.is_some_and(|(_, _, d)| d <= deviation) {
                continue;
            }
            let curve = [a, left.vertices[left.vertices.len() - 1], b];
            if self.shortcut_is_safe(&curve, &own, deviation) {
                best = Some((j, curve, deviation));
            }
        }
        best
    }

    /// The third pass over a simplified polyline: a piece shorter than `options.min_length`
    /// loses one of its inner ends (the one whose removal keeps the joined chord closer to the
    /// original vertices, within the third pass's deviation, and passes the topology test),
    /// until no short piece can be joined. The polyline's own ends (junctions, the domain's corners) stay. Returns the kept
    /// indices left.
    fn join_short_pieces(
        &mut self,
        line: &Polyline,
        mut kept: Vec<usize>,
        scratch: &mut Scratch,
        options: &SimplifyOptions,
    ) -> Vec<usize> {
        let (min_length, tolerance) = (options.min_length, options.join_deviation());
        let curve = &mut scratch.curve;
        let v = &line.vertices;
        let points = self.g().points();
        let point = |k: usize| points[v[k] as usize];
        // A closed line (a loop whose cuts were freed) keeps three vertices besides its end.
        let floor = if v[0] == v[v.len() - 1] { 4 } else { 2 };
        let mut a = 0;
        while a + 1 < kept.len() && kept.len() > floor {
            if point(kept[a]).distance_squared(point(kept[a + 1])) >= min_length * min_length {
                a += 1;
                continue;
            }
            // Remove kept[r], joining the pieces on either side of it.
            let mut best: Option<(usize, f64)> = None;
            for r in [a, a + 1] {
                if r == 0 || r + 1 >= kept.len() {
                    continue;
                }
                let (i, j) = (kept[r - 1], kept[r + 1]);
                let (p, q) = (point(i), point(j));
                let deviation = v[i + 1..j]
                    .iter()
                    .map(|&x| segment_distance_squared(p, q, points[x as usize]))
                    .fold(0.0, f64::max)
                    .sqrt();
                if deviation > tolerance || best.is_some_and(|(_, d)| d <= deviation) {
                    continue;
                }
                curve.clear();
                curve.extend(kept[r - 1..=r + 1].iter().map(|&k| v[k]));
                if self.shortcut_is_safe(curve, &v[i..=j], deviation) {
                    best = Some((r, deviation));
                }
            }
            let Some((r, deviation)) = best else {
                a += 1;
                continue;
            };
            curve.clear();
            curve.extend(kept[r - 1..=r + 1].iter().map(|&k| v[k]));
            self.replace(curve, r == 1 && r + 2 == kept.len());
            self.max_deviation = self.max_deviation.max(deviation);
            self.merged += 1;
            kept.remove(r);
            // The joined piece starts at kept[r - 1]: look at it (and the one before) again.
            a = r.saturating_sub(2);
        }
        kept
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
    /// vertices it removed and the polylines it replaced whole.
    fn absorb(&mut self, other: &State<'_>) {
        for (mark, &there) in self.vertex_mark.iter_mut().zip(&other.vertex_mark) {
            if there == REMOVED {
                *mark = REMOVED;
            }
        }
        self.joined.extend(other.joined.iter().copied());
        self.merged += other.merged;
        self.refused += other.refused;
        self.max_deviation = self.max_deviation.max(other.max_deviation);
    }
}

/// Work buffers of [`State::simplify_line`] and [`State::merge_pieces`].
#[derive(Clone, Default)]
struct Scratch {
    /// Per vertex of the polyline: kept by Douglas–Peucker.
    keep: Vec<bool>,
    /// Douglas–Peucker's pending index ranges.
    stack: Vec<(usize, usize)>,
    /// A curve under test (vertex ids).
    curve: Vec<u32>,
}

/// An edge's ends, lower id first.
fn pair([u, w]: [u32; 2]) -> [u32; 2] {
    [u.min(w), u.max(w)]
}

/// The stamp of a vertex that has left the current graph (see `State::vertex_mark`).
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
pub(crate) fn vertex_cells(g: &CurveGraph, grid: &Grid) -> CellLists<(u32, Point)> {
    let pairs: Vec<(u32, (u32, Point))> = (0..g.points().len() as u32)
        .filter(|&v| g.valence(v) > 0)
        .map(|v| (grid.cell(g.point(v)) as u32, (v, g.point(v))))
        .collect();
    CellLists::new(grid.len(), &pairs)
}

/// The lower-left and upper-right corners of the box around `points`.
pub(crate) fn bounding_box(points: impl Iterator<Item = Point>) -> (Point, Point) {
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
pub(crate) fn encloses(points: &[Point], chain: &[u32], p: Point) -> bool {
    let closing = [chain[chain.len() - 1], chain[0]];
    let sides = chain
        .windows(2)
        .map(|w| [w[0], w[1]])
        .chain(std::iter::once(closing))
        .map(|[u, w]| (points[u as usize], points[w as usize]));
    winds_around(sides, p)
}

/// True when `p` lies on the closed curve made of `sides` (each from its first point to its
/// second, end to end) or the curve winds around it; exact, as [`encloses`].
pub(crate) fn winds_around(sides: impl IntoIterator<Item = (Point, Point)>, p: Point) -> bool {
    let mut winding = 0i64;
    for (a, b) in sides {
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

/// A chain vertex is kept at a neck when it lies this many times farther from the vertex across
/// the neck than the simplified edge does: where simplification took a third of the face's width
/// or more. (A face that is narrow in the image as well gains little from the vertex, and each
/// vertex kept shortens the boundary pieces, and the elements, around it: kept whenever farther,
/// the camera fixture resized to 4096², with quads 41 px wide, lost 0.07 of mean shape-and-size;
/// at 1.5, 0.008; at 2, the smaller fixtures lost most of the gain.)
pub const NECK_RATIO: f64 = 1.5;

/// Two simplified edges leaving a vertex at less than this angle (degrees) make a wedge that
/// [`neck_vertices`] treats as a neck: the far end of the one may lie a hair from the other
/// (on the aloe fixture a junction 0.02 px from an 80 px edge, an angle of 0.7° that neither
/// refinement nor pairing can widen; worst scaled Jacobian 0.014). Measured with no options:
/// at 5°, 10° and 15° the worst scaled Jacobian on grass 0.127 → 0.21 and on aloe 0.014 →
/// 0.067, nothing else lower; at 20° pyvista's fell 0.275 → 0.24.
pub const WEDGE_ANGLE_DEG: f64 = 10.0;

/// Two consecutive simplified edges at a vertex closer than this angle (degrees) make a sharp
/// sector that [`sharp_vertices`] tries to widen: a quad's corner there can be no wider, and the
/// scaled Jacobian is its sine.
pub const SHARP_SECTOR_DEG: f64 = 25.0;

/// How much wider (degrees) the boundary's own directions must leave a sharp sector than the
/// simplified edges do for [`sharp_vertices`] to keep them.
pub const SHARP_GAIN_DEG: f64 = 5.0;

/// The vertices of `g` that widen the sharp sectors simplification made: where two consecutive
/// edges of G' (`s`, the simplification of `g`) leave a vertex less than [`SHARP_SECTOR_DEG`]
/// apart, the first inner vertex of each one's chain at least `length` from it, when the
/// directions to those vertices open the sector by [`SHARP_GAIN_DEG`] or more. A long chord
/// from the tip of a spike, or from a junction, runs nearly along its neighbour though the
/// boundaries leave the vertex wider apart; pinned (see [`CurveGraph::pin`]) and simplified again,
/// the first piece of each follows its boundary's direction. Where the image itself is that
/// sharp, nothing is kept.
///
/// ```
/// use imesh_curves::{sharp_vertices, simplify, CurveGraph, GraphEdge, SimplifyOptions};
/// use imesh_geom::Point;
/// // A spike 2 px wide with a blunt tip at (0, 0), its sides from (3, ±1) to (30, ±1).
/// let p = Point::new;
/// let points = vec![p(0.0, 0.0), p(3.0, 1.0), p(30.0, 1.0), p(3.0, -1.0), p(30.0, -1.0)];
/// let e = |a, b| GraphEdge { ends: [a, b], labels: [1, 0] };
/// let mut g = CurveGraph::new(points, vec![e(0, 1), e(1, 2), e(4, 3), e(3, 0), e(2, 4)])?;
/// g.pin(0)?;
/// let options = SimplifyOptions::with_tolerance(1.5);
/// let s = simplify(&g, &options)?;
/// // Simplified: 0–2 (over 1), 2–4, 4–3, 3–0. At the tip, the chord to (30, 1) runs 20.3° from
/// // the edge to (3, −1); the boundary through (3, 1) leaves it 36.9° from it.
/// assert_eq!(s.chains[0], [0, 1, 2]);
/// assert_eq!(sharp_vertices(&g, &s, 3.0), [1]);
/// g.pin(1)?;
/// // Simplified again, the other side's chord 0–4 (over 3) now runs 20.3° from 0–1.
/// let s = simplify(&g, &options)?;
/// assert_eq!(sharp_vertices(&g, &s, 3.0), [3]);
/// g.pin(3)?;
/// assert!(sharp_vertices(&g, &simplify(&g, &options)?, 3.0).is_empty());
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn sharp_vertices(g: &CurveGraph, s: &Simplification, length: f64) -> Vec<u32> {
    let gs = &s.graph;
    if !(length.is_finite() && length > 0.0) {
        return Vec::new();
    }
    let sharp = SHARP_SECTOR_DEG.to_radians();
    let gain = SHARP_GAIN_DEG.to_radians();
    let angle = |d: Point| d.y.atan2(d.x);
    // The angle from direction a to direction b, counter-clockwise, in [0, 2π).
    let turn = |a: f64, b: f64| (b - a).rem_euclid(std::f64::consts::TAU);
    let mut found = Vec::new();
    for v in 0..gs.points().len() as u32 {
        let incident = gs.incident(v);
        if incident.len() < 2 {
            continue;
        }
        let p = gs.point(v);
        // Each edge leaving v: its chord's angle, and its boundary's first vertex `length` away.
        let mut around: Vec<(f64, Option<u32>, f64)> = incident
            .iter()
            .map(|&e| {
                let chain = &s.chains[e as usize];
                let from_v = chain.first() == Some(&v);
                let far = if from_v { chain.last() } else { chain.first() };
                let chord = angle(gs.point(*far.unwrap_or(&v)) - p);
                let inner = chain.get(1..chain.len().saturating_sub(1)).unwrap_or(&[]);
                let reach = |&w: &u32| g.point(w).distance_squared(p) >= length * length;
                let first = if from_v {
                    inner.iter().find(|w| reach(w))
                } else {
                    inner.iter().rev().find(|w| reach(w))
                };
                let local = first.map_or(chord, |&w| angle(g.point(w) - p));
                (chord, first.copied(), local)
            })
            .collect();
        around.sort_by(|x, y| x.0.total_cmp(&y.0));
        let n = around.len();
        for i in 0..n {
            let (a, b) = (around[i], around[(i + 1) % n]);
            let sector = turn(a.0, b.0);
            if sector >= sharp || (a.1.is_none() && b.1.is_none()) {
                continue;
            }
            // The boundaries' own directions, the sector measured the same way round.
            let wider = turn(a.2, b.2);
            if wider >= sector + gain && wider < std::f64::consts::PI {
                found.extend(a.1.into_iter().chain(b.1));
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}

/// The vertices of `g` that undo the necks simplification made: where an edge of G' (`s`, the
/// simplification of `g`) passes closer than `min_width` to a vertex of G' that is neither one
/// of its ends nor joined to one (unless the joining edge leaves that end at less than
/// [`WEDGE_ANGLE_DEG`] from it), the inner vertex of that edge's chain nearest the G' vertex,
/// when it lies [`NECK_RATIO`] times farther from it than the edge does (the chord cut into the
/// face there). Pinned (see [`CurveGraph::pin`]) before simplifying again, they keep the
/// boundary where the image has it at the narrowest places, so that no element there is made
/// smaller than the image asks for.
///
/// ```
/// use imesh_curves::{neck_vertices, simplify, CurveGraph, GraphEdge, SimplifyOptions};
/// use imesh_geom::Point;
/// // An arch (0–1–2) over a line (3–4–5) with a stem at 4: simplified at 1.5 px, the arch's
/// // chord passes 0.2 px from the junction 4, where the image has 1.5 px.
/// let p = Point::new;
/// let points = vec![
///     p(0.0, 2.8), p(5.0, 1.5), p(10.0, 2.8), p(0.0, 3.0), p(5.0, 3.0), p(10.0, 3.0), p(5.0, 5.0),
/// ];
/// let e = |a, b, labels| GraphEdge { ends: [a, b], labels };
/// let edges = vec![
///     e(0, 1, [1, 0]), e(1, 2, [1, 0]), e(3, 4, [2, 1]), e(4, 5, [2, 1]), e(4, 6, [2, 3]),
/// ];
/// let mut g = CurveGraph::new(points, edges)?;
/// let options = SimplifyOptions::with_tolerance(1.5);
/// let s = simplify(&g, &options)?;
/// assert_eq!(s.chains.iter().find(|c| c[0] == 0).unwrap(), &[0, 1, 2]);
/// assert_eq!(neck_vertices(&g, &s, 0.5), [1]);
/// g.pin(1)?;
/// let again = simplify(&g, &options)?;
/// assert!(neck_vertices(&g, &again, 0.5).is_empty());
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn neck_vertices(g: &CurveGraph, s: &Simplification, min_width: f64) -> Vec<u32> {
    let gs = &s.graph;
    if !(min_width.is_finite() && min_width > 0.0) {
        return Vec::new();
    }
    let segments: Vec<[Point; 2]> = gs
        .edges()
        .iter()
        .map(|e| e.ends.map(|v| gs.point(v)))
        .collect();
    let index = crate::grid::SegmentIndex::new(&segments, min_width);
    let joined = |u: u32, w: u32| {
        gs.incident(u)
            .iter()
            .any(|&e| gs.edges()[e as usize].ends.contains(&w))
    };
    let wedge_cos2 = WEDGE_ANGLE_DEG.to_radians().cos().powi(2);
    let mut found = Vec::new();
    for v in 0..gs.points().len() as u32 {
        if gs.valence(v) == 0 {
            continue;
        }
        let p = gs.point(v);
        for k in index.near(p) {
            let [a, b] = gs.edges()[k as usize].ends;
            if a == v || b == v {
                continue;
            }
            // A vertex joined to an end of the edge is a neck only where the two leave that end
            // at under WEDGE_ANGLE_DEG: a thin wedge.
            let wedge = |end: u32, far: u32| {
                let (x, y) = (gs.point(far) - gs.point(end), p - gs.point(end));
                let dot = x.x * y.x + x.y * y.y;
                dot > 0.0
                    && dot * dot > wedge_cos2 * (x.x * x.x + x.y * x.y) * (y.x * y.x + y.y * y.y)
            };
            if (joined(v, a) && !wedge(a, b)) || (joined(v, b) && !wedge(b, a)) {
                continue;
            }
            let [pa, pb] = segments[k as usize];
            let d2 = segment_distance_squared(pa, pb, p);
            if d2 >= min_width * min_width {
                continue;
            }
            let chain = &s.chains[k as usize];
            let inner = &chain[1..chain.len().saturating_sub(1)];
            let nearest = inner.iter().copied().min_by(|&x, &y| {
                let (dx, dy) = (
                    g.point(x).distance_squared(p),
                    g.point(y).distance_squared(p),
                );
                dx.total_cmp(&dy).then(x.cmp(&y))
            });
            if let Some(w) = nearest {
                if g.point(w).distance_squared(p) > NECK_RATIO * NECK_RATIO * d2 {
                    found.push(w);
                }
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}
