//! Face walks of a planar graph: the check that simplification kept every region.

use std::cmp::Ordering;

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;

use crate::graph::{CurveGraph, Face};

/// The faces of `g`. At each vertex the edges are sorted counter-clockwise (positive
/// orientation); a walk that keeps its face on the positive side leaves a vertex by the edge just
/// before (clockwise from) the one it came in by — the sharpest turn towards the face.
pub(crate) fn faces(g: &CurveGraph) -> Vec<Face> {
    let n = g.points().len() as u32;
    // Each vertex's incident edges in counter-clockwise order, and where each (edge, end) sits.
    let mut around: Vec<Vec<u32>> = Vec::with_capacity(n as usize);
    for v in 0..n {
        let centre = g.point(v);
        let mut list = g.incident(v).to_vec();
        list.sort_by(|&a, &b| {
            counter_clockwise(centre, far_end(g, a, v), far_end(g, b, v)).then(a.cmp(&b))
        });
        around.push(list);
    }
    let edges = g.edges();
    let mut visited = vec![false; 2 * edges.len()];
    let mut faces = Vec::new();
    for start in 0..2 * edges.len() {
        if visited[start] {
            continue;
        }
        let mut walk = Vec::new();
        let mut h = start;
        let mut area = 0.0;
        while !visited[h] {
            visited[h] = true;
            let e = (h / 2) as u32;
            let forward = h % 2 == 0;
            walk.push((e, forward));
            let [a, b] = edges[e as usize].ends;
            let (from, to) = if forward { (a, b) } else { (b, a) };
            let (p, q) = (g.point(from), g.point(to));
            area += 0.5 * (p.x * q.y - q.x * p.y);
            let list = &around[to as usize];
            let at = list.iter().position(|&x| x == e).unwrap_or(0);
            let next = list[(at + list.len() - 1) % list.len()];
            let forward_next = edges[next as usize].ends[0] == to;
            h = 2 * next as usize + usize::from(!forward_next);
        }
        let label_of = |&(e, forward): &(u32, bool)| {
            let l = edges[e as usize].labels;
            if forward {
                l[0]
            } else {
                l[1]
            }
        };
        let label = label_of(&walk[0]);
        let consistent = walk.iter().all(|w| label_of(w) == label);
        faces.push(Face {
            walk,
            label,
            area,
            consistent,
        });
    }
    faces
}

fn far_end(g: &CurveGraph, e: u32, v: u32) -> Point {
    let [a, b] = g.edges()[e as usize].ends;
    g.point(if a == v { b } else { a })
}

/// Orders `a` and `b` by their angle around `centre`, counter-clockwise from the positive x
/// direction, exactly: half-planes by coordinate signs (exact for differences of floats), then
/// the orientation predicate.
fn counter_clockwise(centre: Point, a: Point, b: Point) -> Ordering {
    let half = |p: Point| {
        let (dx, dy) = (p.x - centre.x, p.y - centre.y);
        u8::from(dy < 0.0 || (dy == 0.0 && dx < 0.0))
    };
    half(a).cmp(&half(b)).then_with(|| {
        let o = orient2d(centre, a, b);
        if o > 0.0 {
            Ordering::Less
        } else if o < 0.0 {
            Ordering::Greater
        } else {
            Ordering::Equal
        }
    })
}
