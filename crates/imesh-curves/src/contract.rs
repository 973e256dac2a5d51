//! Merging junctions that a short curve joins: where four regions meet at a pixel corner, the
//! boundary graph has two junctions a fraction of a pixel apart.

use std::collections::HashSet;

use imesh_geom::Point;

use crate::distance::segment_distance_squared;
use crate::graph::{CurveGraph, GraphEdge};
use crate::grid::grid_for;
use crate::polyline::{polylines, Polyline};
use crate::simplify::{encloses, vertex_cells};
use crate::CurveError;

/// A boundary graph with its short links contracted (see [`contract_short_links`]).
#[derive(Clone, Debug)]
pub struct Contraction {
    /// The graph: the same points (a merged pair's survivor moved to where they meet, the other
    /// and the link's inner vertices left unused), the other edges.
    pub graph: CurveGraph,
    /// Links contracted.
    pub contracted: usize,
}

/// Contracts every polyline (see [`polylines`]) between two distinct junctions (valence ≥ 3)
/// that lie closer than `min_length`, when all its vertices lie within `tolerance` of the
/// segment between its ends and nothing lies between it and that segment (the polylines that
/// simplification at `tolerance` would make chords shorter than `min_length`): the polyline goes and its ends become one vertex, at their
/// midpoint (at the pinned end if one is, on the domain's side if one or both lie on it), shortest
/// links first.
///
/// A link between junctions is a boundary between two regions that the mesh must follow with
/// at least one element edge on it: a link much shorter than the elements makes elements of its
/// size. Four regions meeting at a pixel corner give such a link (two triple junctions a
/// fraction of a pixel apart); merging them gives one junction of four curves, and the two
/// regions the link separated touch at that point only.
///
/// A contraction is not made when both ends are pinned, when the ends lie on different sides of
/// the domain `[0, width] × [0, height]`, when another polyline of fewer than three edges joins
/// the same two junctions (a longer one becomes a closed curve, pinned at its thirds), or when moving the ends would make two edges meet
/// or cross (checked on the whole result; an offending contraction is undone).
///
/// # Errors
/// As [`CurveGraph::new`], for a graph that is not a valid input.
///
/// ```
/// use imesh_curves::{contract_short_links, CurveGraph, GraphEdge};
/// use imesh_geom::Point;
/// // Four regions meeting in a 4 × 4 square (label 9 outside), drawn with two triple
/// // junctions 0.2 apart: 0 (regions 0 above, 2 left, 3 right) and 1 (1 below, 2, 3), joined by
/// // a link between 2 and 3.
/// let p = |x, y| Point::new(x, y);
/// let points = vec![
///     p(2.0, 1.9), p(2.0, 2.1), p(0.0, 1.0), p(4.0, 1.0), p(0.0, 3.0), p(4.0, 3.0),
///     p(0.0, 0.0), p(4.0, 0.0), p(4.0, 4.0), p(0.0, 4.0),
/// ];
/// let e = |a, b, labels| GraphEdge { ends: [a, b], labels };
/// let edges = vec![
///     e(0, 1, [2, 3]), e(0, 2, [0, 2]), e(0, 3, [3, 0]), e(1, 4, [2, 1]), e(1, 5, [1, 3]),
///     e(6, 7, [0, 9]), e(7, 3, [0, 9]), e(3, 5, [3, 9]), e(5, 8, [1, 9]), e(8, 9, [1, 9]),
///     e(9, 4, [1, 9]), e(4, 2, [2, 9]), e(2, 6, [0, 9]),
/// ];
/// let g = CurveGraph::image_boundaries(points, edges, 4.0, 4.0)?;
/// let c = contract_short_links(&g, 1.0, 0.5, 4.0, 4.0)?;
/// assert_eq!(c.contracted, 1);
/// assert_eq!(c.graph.edges().len(), 12);
/// assert_eq!(c.graph.point(0), p(2.0, 2.0));
/// assert_eq!((c.graph.valence(0), c.graph.valence(1)), (4, 0)); // one junction of four curves
/// assert!(c.graph.faces().iter().all(|f| f.consistent));
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn contract_short_links(
    g: &CurveGraph,
    min_length: f64,
    tolerance: f64,
    width: f64,
    height: f64,
) -> Result<Contraction, CurveError> {
    let lines = polylines(g);
    let grid = grid_for(g);
    let vertices = vertex_cells(g, &grid);
    // A link the simplification would make a chord shorter than `min_length`, that nothing lies
    // inside of: its ends are close, its vertices within `tolerance` of the segment between
    // them, and the region between the link and that segment holds no other vertex.
    let short = |line: &Polyline| -> Option<f64> {
        let [u, w] = line.ends();
        if u == w || g.valence(u) < 3 || g.valence(w) < 3 {
            return None;
        }
        let (a, b) = (g.point(u), g.point(w));
        let chord = a.distance_squared(b).sqrt();
        let reach2 = tolerance * tolerance;
        if chord >= min_length
            || line
                .vertices
                .iter()
                .any(|&v| segment_distance_squared(a, b, g.point(v)) > reach2)
        {
            return None;
        }
        let mut empty = true;
        grid.cells_near_segment(a, b, tolerance, |c| {
            for &(v, p) in vertices.get(c) {
                if empty && !line.vertices.contains(&v) && encloses(g.points(), &line.vertices, p) {
                    empty = false;
                }
            }
        });
        empty.then_some(chord)
    };
    let mut candidates: Vec<(f64, usize)> = lines
        .iter()
        .enumerate()
        .filter_map(|(k, line)| short(line).map(|chord| (chord, k)))
        .collect();
    if candidates.is_empty() {
        return Ok(Contraction {
            graph: g.clone(),
            contracted: 0,
        });
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let sides = |p: Point| -> u8 {
        u8::from(p.x == 0.0)
            | u8::from(p.x == width) << 1
            | u8::from(p.y == 0.0) << 2
            | u8::from(p.y == height) << 3
    };
    // The polylines ending at each vertex: a contraction's loops are found among those of the
    // smaller of the two merged classes, not by a pass over every polyline (the contractions
    // times the polylines made a photo read as a label map take half a minute).
    let mut lines_at: Vec<Vec<usize>> = vec![Vec::new(); g.points().len()];
    for (j, line) in lines.iter().enumerate() {
        for v in line.ends() {
            lines_at[v as usize].push(j);
        }
    }
    let mut refused: HashSet<usize> = HashSet::new();
    loop {
        // Union of merged vertices: `rep[v]` leads to the survivor, which holds the position.
        let mut rep: Vec<u32> = (0..g.points().len() as u32).collect();
        fn find(rep: &mut [u32], mut v: u32) -> u32 {
            while rep[v as usize] != v {
                rep[v as usize] = rep[rep[v as usize] as usize];
                v = rep[v as usize];
            }
            v
        }
        let mut points = g.points().to_vec();
        let mut pinned: Vec<bool> = (0..points.len() as u32).map(|v| g.is_pinned(v)).collect();
        let mut gone = vec![false; g.edges().len()];
        let mut made: Vec<(usize, u32)> = Vec::new();
        // The vertices merged into each survivor (itself included).
        let mut members: Vec<Vec<u32>> = (0..points.len() as u32).map(|v| vec![v]).collect();
        for &(_, k) in &candidates {
            if refused.contains(&k) {
                continue;
            }
            let [u, w] = lines[k].ends();
            let (ru, rw) = (find(&mut rep, u), find(&mut rep, w));
            if ru == rw || (pinned[ru as usize] && pinned[rw as usize]) {
                continue;
            }
            // Another polyline joining the same two junctions becomes a loop: it is cut at
            // its thirds (as `polylines` cuts a closed curve), and needs three edges for that.
            let mut loops = Vec::new();
            let smaller = if members[ru as usize].len() <= members[rw as usize].len() {
                ru
            } else {
                rw
            };
            for &m in &members[smaller as usize] {
                for &j in &lines_at[m as usize] {
                    let line = &lines[j];
                    if j == k || line.edges.iter().all(|&e| gone[e as usize]) {
                        continue;
                    }
                    let [a, b] = line.ends();
                    let (ra, rb) = (find(&mut rep, a), find(&mut rep, b));
                    if (ra == ru && rb == rw) || (ra == rw && rb == ru) {
                        loops.push(j);
                    }
                }
            }
            if loops.iter().any(|&j| lines[j].edges.len() < 3) {
                continue;
            }
            let (pu, pw) = (points[ru as usize], points[rw as usize]);
            let (su, sw) = (sides(pu), sides(pw));
            let target = if pinned[ru as usize] {
                (sw & !su == 0).then_some(pu)
            } else if pinned[rw as usize] {
                (su & !sw == 0).then_some(pw)
            } else if su == 0 && sw == 0 {
                Some((pu + pw) * 0.5)
            } else if su == 0 {
                Some(pw)
            } else if sw == 0 {
                Some(pu)
            } else {
                // Both on the domain's border: the midpoint stays on a side they share.
                (su & sw != 0).then(|| (pu + pw) * 0.5)
            };
            let Some(target) = target else { continue };
            rep[rw as usize] = ru;
            let merged = std::mem::take(&mut members[rw as usize]);
            members[ru as usize].extend(merged);
            points[ru as usize] = target;
            pinned[ru as usize] |= pinned[rw as usize];
            for &e in &lines[k].edges {
                gone[e as usize] = true;
            }
            for j in loops {
                let v = &lines[j].vertices;
                let n = v.len() - 1;
                for cut in [n / 3, (2 * n).div_ceil(3)] {
                    pinned[v[cut.clamp(1, n - 1)] as usize] = true;
                }
            }
            made.push((k, ru));
        }
        let mut edges = Vec::with_capacity(g.edges().len());
        for (e, edge) in g.edges().iter().enumerate() {
            if !gone[e] {
                edges.push(GraphEdge {
                    ends: edge.ends.map(|v| find(&mut rep, v)),
                    labels: edge.labels,
                });
            }
        }
        // A contraction is to blame for a bad edge when its survivor is an end of the edge.
        let blame = |ends: [u32; 2], refused: &mut HashSet<usize>| -> bool {
            let mut any = false;
            for &(k, survivor) in &made {
                if ends.contains(&survivor) {
                    any |= refused.insert(k);
                }
            }
            any
        };
        match CurveGraph::new(points, edges) {
            Ok(mut graph) => {
                // Edges that cross, or faces whose walk changed (the edges at a merged vertex
                // run around it in another order than the two junctions had them, and a walk
                // goes from one region into another): the contractions at their ends are undone.
                let mut bad: Vec<[u32; 2]> = Vec::new();
                if let Some(pair) = graph.crossing() {
                    bad.extend(pair.map(|e| graph.edges()[e as usize].ends));
                } else {
                    for face in graph.faces() {
                        if !face.consistent || face.area == 0.0 {
                            bad.extend(
                                face.walk
                                    .iter()
                                    .map(|&(e, _)| graph.edges()[e as usize].ends),
                            );
                        }
                    }
                }
                if !bad.is_empty() {
                    let mut any = false;
                    for ends in bad {
                        any |= blame(ends, &mut refused);
                    }
                    if any {
                        continue;
                    }
                    // Not of our making: leave the graph as it was.
                    return Ok(Contraction {
                        graph: g.clone(),
                        contracted: 0,
                    });
                }
                for (v, &p) in pinned.iter().enumerate() {
                    if p && graph.valence(v as u32) > 0 {
                        graph.pin(v as u32)?;
                    }
                }
                return Ok(Contraction {
                    graph,
                    contracted: made.len(),
                });
            }
            Err(CurveError::DuplicateEdge { ends }) if blame(ends, &mut refused) => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(a: u32, b: u32, labels: [u32; 2]) -> GraphEdge {
        GraphEdge {
            ends: [a, b],
            labels,
        }
    }

    /// Two junctions 0.2 apart joined by a link (0–1) and by a longer curve (0–2–3–4–1) around
    /// a region: merging them closes the curve, which is pinned at its thirds (2 and 4) so that
    /// no polyline is a loop.
    #[test]
    fn a_curve_closed_by_a_contraction_is_cut_at_its_thirds() {
        let p = Point::new;
        let points = vec![
            p(5.0, 4.9),
            p(5.0, 5.1),
            p(7.0, 3.0),
            p(9.0, 5.0),
            p(7.0, 7.0),
            p(0.0, 3.0),
            p(0.0, 7.0),
        ];
        // Label 1 inside the curve, 0 everywhere else (the graph is not closed: one face
        // holds all but the region inside).
        let edges = vec![
            e(0, 1, [0, 1]),
            e(0, 2, [1, 0]),
            e(2, 3, [1, 0]),
            e(3, 4, [1, 0]),
            e(4, 1, [1, 0]),
            e(0, 5, [0, 0]),
            e(1, 6, [0, 0]),
        ];
        let g = CurveGraph::new(points, edges).unwrap();
        assert_eq!(g.crossing(), None);
        let c = contract_short_links(&g, 1.0, 0.5, 10.0, 10.0).unwrap();
        assert_eq!(c.contracted, 1);
        assert_eq!(c.graph.crossing(), None);
        assert_eq!(c.graph.point(0), p(5.0, 5.0));
        assert!(c.graph.is_pinned(2) && c.graph.is_pinned(4));
        assert_eq!(polylines(&c.graph).len(), 5);
        for line in polylines(&c.graph) {
            let [a, b] = line.ends();
            assert_ne!(a, b, "a polyline is a loop");
        }
    }

    /// Moving the ends to their midpoint would make an edge at the junction cross a nearby
    /// edge: the contraction is not made.
    #[test]
    fn a_contraction_that_would_cross_an_edge_is_undone() {
        let p = Point::new;
        let points = vec![
            p(0.0, 0.0),
            p(0.4, 0.0),
            p(-2.0, 1.0),
            p(-2.0, -1.0),
            p(2.0, 1.0),
            p(2.0, -1.0),
            p(-0.5, 0.3),
            p(-0.5, 0.6),
        ];
        let edges = vec![
            e(0, 1, [1, 2]),
            e(0, 2, [0, 1]),
            e(0, 3, [2, 0]),
            e(1, 4, [1, 0]),
            e(1, 5, [0, 2]),
            e(6, 7, [0, 0]),
        ];
        let g = CurveGraph::new(points, edges).unwrap();
        assert_eq!(g.crossing(), None);
        let c = contract_short_links(&g, 1.0, 0.5, 10.0, 10.0).unwrap();
        assert_eq!(c.contracted, 0);
        assert_eq!(c.graph.edges(), g.edges());
        assert_eq!(c.graph.points(), g.points());
    }
}
