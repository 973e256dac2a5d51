//! Bézier patches over the elements of M: a cubic triangular patch (10 control points) per
//! triangle, a bicubic patch (16) per quad, all in one control net so that neighbouring patches
//! share their edge control points (DESIGN.md §2, step 9; the paper's section V-C).
//!
//! Control point numbering in the net: first one per DT' vertex (the corners), then two per M
//! edge (its inner control points, at 1/3 and 2/3 along the edge's own direction), then each
//! element's inner ones (1 for a triangle, 4 for a quad).

use imesh_geom::{Point, Triangulation, VertexId};
use rayon::prelude::*;

use crate::mesh::disjoint_slices;
use crate::pairing::{Element, ElementMesh};

/// Triangle patch slots as `(a, b)`: powers of the weights of corners 1 and 2 (corner 0 has
/// `3 − a − b`). Slot 5, `(1, 1)`, is the inner control point.
pub const TRIANGLE_SLOTS: [(u8, u8); 10] = [
    (0, 0),
    (1, 0),
    (2, 0),
    (3, 0),
    (0, 1),
    (1, 1),
    (2, 1),
    (0, 2),
    (1, 2),
    (0, 3),
];

/// Triangle patch slots along each side, from its first corner to the next.
const TRIANGLE_SIDES: [[usize; 4]; 3] = [[0, 1, 2, 3], [3, 6, 8, 9], [9, 7, 4, 0]];

/// Quad patch slot of control point `(i, j)` is `i + 4 j`; slots along each side.
const QUAD_SIDES: [[usize; 4]; 4] = [
    [0, 1, 2, 3],
    [3, 7, 11, 15],
    [15, 14, 13, 12],
    [12, 8, 4, 0],
];

/// The inner slots of a quad patch.
const QUAD_INNER: [usize; 4] = [5, 6, 9, 10];

/// How many inner control points (on no side) `element`'s patch has: a triangle's centre, a
/// quad's four.
fn inner_points(element: &Element) -> usize {
    match element {
        Element::Triangle(_) => 1,
        Element::Quad(_) => QUAD_INNER.len(),
    }
}

/// The patch slots along side `side` of `element`, from the side's first corner (whose slot
/// is the first) to the next.
pub(crate) fn side_slots(element: &Element, side: usize) -> [usize; 4] {
    match element {
        Element::Triangle(_) => TRIANGLE_SIDES[side],
        Element::Quad(_) => QUAD_SIDES[side],
    }
}

/// The control net of every patch of M.
#[derive(Clone, Debug)]
pub struct ControlNet {
    /// All control points.
    pub points: Vec<Point>,
    /// Per element, its control points' indices into `points` by slot (triangles use 10 slots in
    /// [`TRIANGLE_SLOTS`] order; quads 16, slot `i + 4 j`).
    pub patches: Vec<[u32; 16]>,
    /// Index of the first inner control point of each M edge (`+ 1` is the second).
    pub(crate) edge_base: u32,
    /// Index of the first of the elements' inner control points.
    pub(crate) inner_base: u32,
}

impl ControlNet {
    /// The affine (triangles) and bilinear (quads) patches of M: control points at the images of
    /// a uniform grid, so that every patch is exactly its straight element.
    pub fn straight(t: &Triangulation, m: &ElementMesh) -> Self {
        let nv = t.num_vertices();
        // The inner control points of each element follow the edges' in element order (one
        // for a triangle's centre, four for a quad's): their places are known up front, so the
        // elements are laid out side by side.
        let mut inner_first = Vec::with_capacity(m.elements.len());
        let mut inner_count = 0;
        for element in &m.elements {
            inner_first.push(inner_count);
            inner_count += inner_points(element);
        }
        let mut points = vec![Point::new(0.0, 0.0); nv + 2 * m.edges.len() + inner_count];
        let (corners, rest) = points.split_at_mut(nv);
        corners.copy_from_slice(&t.points()[..nv]);
        let (edge_points, inner) = rest.split_at_mut(2 * m.edges.len());
        edge_points
            .par_chunks_mut(2)
            .zip(&m.edges)
            .for_each(|(out, &h)| {
                let (a, b) = (t.point(t.origin(h)), t.point(t.destination(h)));
                out[0] = a + (b - a) * (1.0 / 3.0);
                out[1] = a + (b - a) * (2.0 / 3.0);
            });
        let edge_base = nv as u32;
        let inner_base = (nv + 2 * m.edges.len()) as u32;
        let slices = disjoint_slices(
            inner,
            m.elements
                .iter()
                .zip(&inner_first)
                .map(|(element, &first)| (first, inner_points(element))),
        );
        let patches = m
            .elements
            .par_iter()
            .zip(inner_first)
            .zip(slices)
            .enumerate()
            .map(|(k, ((element, first), out))| {
                let mut slots = [u32::MAX; 16];
                let corners = element.corners();
                let sides: &[[usize; 4]] = match element {
                    Element::Triangle(_) => &TRIANGLE_SIDES,
                    Element::Quad(_) => &QUAD_SIDES,
                };
                for (side, along) in sides.iter().enumerate() {
                    let (e, forward) = m.side_edge(k, side);
                    let inner = [edge_base + 2 * e, edge_base + 2 * e + 1];
                    let (first, second) = if forward {
                        (inner[0], inner[1])
                    } else {
                        (inner[1], inner[0])
                    };
                    slots[along[0]] = corners[side];
                    slots[along[1]] = first;
                    slots[along[2]] = second;
                }
                let first = inner_base + first as u32;
                match element {
                    Element::Triangle(c) => {
                        let p = c.map(|v| t.point(VertexId::new(v)));
                        slots[5] = first;
                        out[0] = (p[0] + p[1] + p[2]) * (1.0 / 3.0);
                    }
                    Element::Quad(c) => {
                        let p = c.map(|v| t.point(VertexId::new(v)));
                        for (n, slot) in QUAD_INNER.into_iter().enumerate() {
                            let (i, j) = ((slot % 4) as f64 / 3.0, (slot / 4) as f64 / 3.0);
                            slots[slot] = first + n as u32;
                            out[n] = bilinear(&p, i, j);
                        }
                    }
                }
                slots
            })
            .collect();
        Self {
            points,
            patches,
            edge_base,
            inner_base,
        }
    }

    /// The four control points along side `side` of element `k`'s patch, from the side's first
    /// corner.
    pub fn side_points(&self, element: &Element, k: usize, side: usize) -> [Point; 4] {
        side_slots(element, side).map(|slot| self.points[self.patches[k][slot] as usize])
    }

    /// The control points apart: those on the elements' sides (corners and edge points), all
    /// before the elements' inner ones (each element's consecutive, from its slot 5), and the
    /// patches.
    pub(crate) fn split_inner(&mut self) -> (&[Point], &mut [Point], &[[u32; 16]]) {
        let (boundary, inner) = self.points.split_at_mut(self.inner_base as usize);
        (boundary, inner, &self.patches)
    }

    /// The inner control points of M edge `e` (at 1/3 and 2/3 along its direction).
    pub fn edge_inner(&self, e: u32) -> [u32; 2] {
        [self.edge_base + 2 * e, self.edge_base + 2 * e + 1]
    }

    /// [`ControlNet::eval_weights`] for the nonzero weights only, `(slot, weight)` in slot order
    /// (as [`crate::Template::terms`] has them): the same sum, term for term.
    pub fn eval_terms(&self, k: usize, terms: &[(u8, f64)]) -> Point {
        eval_patch_terms(&self.patch_points(k), terms)
    }

    /// Element `k`'s control points by slot (a triangle's six unused slots are the origin).
    pub fn patch_points(&self, k: usize) -> [Point; 16] {
        self.patches[k].map(|slot| {
            self.points
                .get(slot as usize)
                .copied()
                .unwrap_or(Point::new(0.0, 0.0))
        })
    }

    /// The point of element `k`'s patch for precomputed basis weights (see [`basis`]).
    pub fn eval_weights(&self, k: usize, weights: &[f64; 16]) -> Point {
        let slots = &self.patches[k];
        let (mut x, mut y) = (0.0, 0.0);
        for (&slot, &w) in slots.iter().zip(weights) {
            if w != 0.0 {
                let p = self.points[slot as usize];
                x += w * p.x;
                y += w * p.y;
            }
        }
        Point::new(x, y)
    }

    /// The point of element `k`'s patch at canonical coordinates `uv`.
    pub fn eval(&self, element: &Element, k: usize, uv: [f64; 2]) -> Point {
        self.eval_weights(k, &basis(matches!(element, Element::Quad(_)), uv))
    }

    /// Resets element `k`'s inner control points from its boundary: the discrete Coons patch for
    /// a quad, the quadratic-precision blend for a triangle. Both give back the straight patch of
    /// straight boundaries and follow curved ones smoothly.
    pub fn relax_inner(&mut self, element: &Element, k: usize) {
        let slots = self.patches[k];
        let (inner, count) = relaxed_inner(element, &self.patch_points(k));
        for &(slot, point) in &inner[..count] {
            self.points[slots[slot] as usize] = point;
        }
    }
}

/// [`ControlNet::relax_inner`] of the patch with control points `patch` (by slot): the inner
/// slots and their new points (`count` of the four).
pub(crate) fn relaxed_inner(
    element: &Element,
    patch: &[Point; 16],
) -> ([(usize, Point); 4], usize) {
    let p = |slot: usize| patch[slot];
    let mut inner = [(0usize, Point::new(0.0, 0.0)); 4];
    let count = match element {
        Element::Triangle(_) => {
            let edges = [1, 2, 6, 8, 7, 4]
                .iter()
                .fold(Point::new(0.0, 0.0), |s, &x| s + p(x));
            let corners = p(0) + p(3) + p(9);
            inner[0] = (5, edges * 0.25 - corners * (1.0 / 6.0));
            1
        }
        Element::Quad(_) => {
            for (n, slot) in QUAD_INNER.into_iter().enumerate() {
                let (i, j) = (slot % 4, slot / 4);
                let (u, v) = (i as f64 / 3.0, j as f64 / 3.0);
                let ruled_s = p(4 * j) * (1.0 - u) + p(3 + 4 * j) * u;
                let ruled_t = p(i) * (1.0 - v) + p(i + 12) * v;
                let corners = bilinear(&[p(0), p(3), p(15), p(12)], u, v);
                inner[n] = (slot, ruled_s + ruled_t - corners);
            }
            4
        }
    };
    (inner, count)
}

/// The point of the patch with control points `patch` (by slot) for the nonzero basis
/// weights `terms` (see [`ControlNet::eval_terms`]).
pub(crate) fn eval_patch_terms(patch: &[Point; 16], terms: &[(u8, f64)]) -> Point {
    let (mut x, mut y) = (0.0, 0.0);
    for &(slot, w) in terms {
        let p = patch[usize::from(slot)];
        x += w * p.x;
        y += w * p.y;
    }
    Point::new(x, y)
}

/// The Bernstein basis of a triangle (10 slots, the rest 0) or quad (16 slots) patch at
/// canonical coordinates `uv`: the weights of the control points in the patch's point there.
pub fn basis(quad: bool, uv: [f64; 2]) -> [f64; 16] {
    let mut w = [0.0; 16];
    if quad {
        let (bs, bt) = (bernstein3(uv[0]), bernstein3(uv[1]));
        for j in 0..4 {
            for i in 0..4 {
                w[i + 4 * j] = bs[i] * bt[j];
            }
        }
    } else {
        let (l1, l2) = (uv[0], uv[1]);
        // On the side l1 + l2 = 1 the first weight must be exactly 0, or the patch's inner and
        // other-side control points would pull the side's points (a border vertex off the
        // border by 1e-17). Template coordinates are multiples of 1 / (6k²) ≥ 1 / 384, so a
        // remainder below 1e-12 is rounding.
        let l0 = match 1.0 - l1 - l2 {
            r if r.abs() < 1e-12 => 0.0,
            r => r,
        };
        let powers = |x: f64| [1.0, x, x * x, x * x * x];
        let (p0, p1, p2) = (powers(l0), powers(l1), powers(l2));
        for (slot, &(a, b)) in TRIANGLE_SLOTS.iter().enumerate() {
            let (a, b) = (a as usize, b as usize);
            w[slot] = TRIANGLE_COEFFICIENTS[slot] * p0[3 - a - b] * p1[a] * p2[b];
        }
    }
    w
}

/// The trinomial coefficients `3! / (i! a! b!)` of the triangle slots.
const TRIANGLE_COEFFICIENTS: [f64; 10] = [1.0, 3.0, 3.0, 1.0, 3.0, 6.0, 3.0, 3.0, 3.0, 1.0];

/// The cubic Bernstein polynomials at `t`.
pub(crate) fn bernstein3(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

/// The bilinear map of the quad `p` (counter-clockwise from `(0, 0)`) at `(u, v)`.
pub(crate) fn bilinear(p: &[Point; 4], u: f64, v: f64) -> Point {
    p[0] * ((1.0 - u) * (1.0 - v))
        + p[1] * (u * (1.0 - v))
        + p[2] * (u * v)
        + p[3] * ((1.0 - u) * v)
}
