//! Exhaustive validation of a triangulation with exact predicates.

use super::{next, Triangulation, GHOST, NONE};
use crate::predicates::{incircle, orient2d};

/// A violated invariant, found by [`Triangulation::check`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TriangulationDefect {
    /// A triangle uses a vertex id out of range, or one vertex twice.
    #[error("triangle {triangle} has invalid vertices {vertices:?}")]
    BadVertices {
        /// The triangle slot.
        triangle: u32,
        /// Its vertex ids (`u32::MAX` is the ghost vertex).
        vertices: [u32; 3],
    },
    /// A real triangle is not strictly counter-clockwise.
    #[error("triangle {triangle} is not counter-clockwise (orient2d = {orient})")]
    NotCounterClockwise {
        /// The triangle slot.
        triangle: u32,
        /// The orientation determinant.
        orient: f64,
    },
    /// `twin(twin(e)) != e`, or the twins do not join the same two vertices in opposite directions.
    #[error("half-edge {edge} and its twin {twin} do not match")]
    BadTwin {
        /// The half-edge.
        edge: u32,
        /// Its recorded twin.
        twin: u32,
    },
    /// A vertex's recorded out-going half-edge does not leave it, or a vertex is in no triangle.
    #[error("vertex {vertex} has no valid out-going half-edge")]
    BadVertexEdge {
        /// The vertex.
        vertex: u32,
    },
    /// The opposite vertex of a neighbour lies strictly inside a triangle's circumcircle.
    #[error("edge {edge} is not locally Delaunay: vertex {vertex} is inside the circumcircle of triangle {triangle}")]
    NotDelaunay {
        /// The shared half-edge.
        edge: u32,
        /// The triangle whose circumcircle is violated.
        triangle: u32,
        /// The vertex inside it.
        vertex: u32,
    },
    /// The hull turns clockwise at a vertex, or winds more than once.
    #[error("the convex hull is not convex at vertex {vertex}")]
    HullNotConvex {
        /// The vertex where the hull turns the wrong way (or `u32::MAX` for a winding error).
        vertex: u32,
    },
    /// V − E + F ≠ 2 on the sphere closed by the ghost vertex.
    #[error("Euler characteristic is {0}, expected 2")]
    Euler(i64),
    /// The two half-edges of an edge disagree about its segment.
    #[error("half-edge {edge} and its twin lie on different segments")]
    SegmentMismatch {
        /// The half-edge.
        edge: u32,
    },
    /// Two triangles sharing an unconstrained edge have different labels.
    #[error(
        "triangles {a} and {b} share an unconstrained edge but have labels {label_a} and {label_b}"
    )]
    LabelLeak {
        /// One triangle.
        a: u32,
        /// The other.
        b: u32,
        /// Its label.
        label_a: u32,
        /// The other's label.
        label_b: u32,
    },
    /// The ghost-triangle count disagrees with the stored hull size.
    #[error("{found} ghost triangles but {stored} recorded")]
    GhostCount {
        /// Ghost triangles found.
        found: usize,
        /// Ghost triangles recorded.
        stored: usize,
    },
}

impl Triangulation {
    /// Verifies every invariant with exact predicates: vertex ids, counter-clockwise orientation of
    /// every triangle, twin symmetry, vertex-to-edge links, the empty-circle property of every
    /// unconstrained edge (which, on a triangulation of the convex hull, is the global — constrained —
    /// Delaunay property), convexity of the hull, the Euler characteristic, and with constraints and
    /// labels: segment ids agree on both sides of an edge, labels agree across unconstrained edges.
    ///
    /// # Errors
    /// The first [`TriangulationDefect`] found.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts: Vec<Point> = (0..100).map(|i| Point::new((i * 37 % 100) as f64, (i * 91 % 100) as f64)).collect();
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// assert!(t.check().is_ok());
    /// ```
    pub fn check(&self) -> Result<(), TriangulationDefect> {
        if self.is_degenerate() {
            return self.check_degenerate();
        }
        let n = self.points.len() as u32;
        let slots = self.origin.len() / 3;
        let mut ghosts = 0;
        for t in 0..slots as u32 {
            let b = 3 * t as usize;
            let v = [self.origin[b], self.origin[b + 1], self.origin[b + 2]];
            let ghost_corners = v.iter().filter(|&&x| x == GHOST).count();
            let distinct = v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
            if ghost_corners > 1 || !distinct || v.iter().any(|&x| x != GHOST && x >= n) {
                return Err(TriangulationDefect::BadVertices {
                    triangle: t,
                    vertices: v,
                });
            }
            if ghost_corners == 1 {
                ghosts += 1;
                continue;
            }
            let [a, bb, c] = v.map(|x| self.points[x as usize]);
            let orient = orient2d(a, bb, c);
            if orient <= 0.0 {
                return Err(TriangulationDefect::NotCounterClockwise {
                    triangle: t,
                    orient,
                });
            }
        }
        if ghosts != self.ghost_count {
            return Err(TriangulationDefect::GhostCount {
                found: ghosts,
                stored: self.ghost_count,
            });
        }
        self.check_twins()?;
        self.check_constraints()?;
        self.check_vertex_edges()?;
        self.check_empty_circles()?;
        self.check_hull()?;
        // On the sphere: vertices n + 1 (the ghost), edges 3F/2, faces F = slots.
        let euler = i64::from(n) + 1 - (3 * slots as i64) / 2 + slots as i64;
        if euler != 2 {
            return Err(TriangulationDefect::Euler(euler));
        }
        Ok(())
    }

    fn check_degenerate(&self) -> Result<(), TriangulationDefect> {
        if let Some(v) = (0..self.points.len()).find(|&v| self.out_edge[v] != NONE) {
            return Err(TriangulationDefect::BadVertexEdge { vertex: v as u32 });
        }
        if let [a, b, ..] = self.pending[..] {
            let (pa, pb) = (self.points[a as usize], self.points[b as usize]);
            if let Some(&v) = self
                .pending
                .iter()
                .find(|&&v| orient2d(pa, pb, self.points[v as usize]) != 0.0)
            {
                return Err(TriangulationDefect::HullNotConvex { vertex: v });
            }
        }
        Ok(())
    }

    fn check_twins(&self) -> Result<(), TriangulationDefect> {
        for e in 0..self.origin.len() as u32 {
            let t = self.twin[e as usize];
            let ok = (t as usize) < self.origin.len()
                && t / 3 != e / 3
                && self.twin[t as usize] == e
                && self.origin[t as usize] == self.origin[next(e) as usize]
                && self.origin[next(t) as usize] == self.origin[e as usize];
            if !ok {
                return Err(TriangulationDefect::BadTwin { edge: e, twin: t });
            }
        }
        Ok(())
    }

    fn check_constraints(&self) -> Result<(), TriangulationDefect> {
        if !self.segment.is_empty() {
            if let Some(e) = (0..self.origin.len())
                .find(|&e| self.segment[e] != self.segment[self.twin[e] as usize])
            {
                return Err(TriangulationDefect::SegmentMismatch { edge: e as u32 });
            }
        }
        if self.label.is_empty() {
            return Ok(());
        }
        for e in 0..self.origin.len() as u32 {
            let (a, b) = (e / 3, self.twin[e as usize] / 3);
            let constrained = self.segment.get(e as usize).is_some_and(|&s| s != NONE);
            if constrained || self.is_ghost_slot(a) || self.is_ghost_slot(b) {
                continue;
            }
            let (label_a, label_b) = (self.label[a as usize], self.label[b as usize]);
            if label_a != label_b {
                return Err(TriangulationDefect::LabelLeak {
                    a,
                    b,
                    label_a,
                    label_b,
                });
            }
        }
        Ok(())
    }

    fn check_vertex_edges(&self) -> Result<(), TriangulationDefect> {
        for (v, &e) in self.out_edge.iter().enumerate() {
            if e == NONE || e as usize >= self.origin.len() || self.origin[e as usize] != v as u32 {
                return Err(TriangulationDefect::BadVertexEdge { vertex: v as u32 });
            }
        }
        Ok(())
    }

    fn check_empty_circles(&self) -> Result<(), TriangulationDefect> {
        for e in 0..self.origin.len() as u32 {
            let t = self.twin[e as usize];
            let constrained = self.segment.get(e as usize).is_some_and(|&s| s != NONE);
            if e > t || constrained || self.is_ghost_slot(e / 3) || self.is_ghost_slot(t / 3) {
                continue;
            }
            let b = 3 * (e / 3) as usize;
            let [a, bb, c] = [self.origin[b], self.origin[b + 1], self.origin[b + 2]];
            let opposite = self.origin[next(next(t)) as usize];
            let pt = |v: u32| self.points[v as usize];
            if incircle(pt(a), pt(bb), pt(c), pt(opposite)) > 0.0 {
                return Err(TriangulationDefect::NotDelaunay {
                    edge: e,
                    triangle: e / 3,
                    vertex: opposite,
                });
            }
        }
        Ok(())
    }

    fn check_hull(&self) -> Result<(), TriangulationDefect> {
        let hull = self.hull();
        if hull.len() != self.ghost_count {
            return Err(TriangulationDefect::HullNotConvex { vertex: u32::MAX });
        }
        let h = hull.len();
        let mut turning = 0.0;
        for i in 0..h {
            let [a, b, c] = [hull[i], hull[(i + 1) % h], hull[(i + 2) % h]].map(|v| self.point(v));
            if orient2d(a, b, c) < 0.0 {
                return Err(TriangulationDefect::HullNotConvex {
                    vertex: hull[(i + 1) % h].0,
                });
            }
            let (u, w) = (b - a, c - b);
            turning += (u.x * w.y - u.y * w.x).atan2(u.x * w.x + u.y * w.y);
        }
        // A convex polygon traversed once turns through exactly 2π; twice round would give 4π.
        if (turning - std::f64::consts::TAU).abs() > 1e-6 {
            return Err(TriangulationDefect::HullNotConvex { vertex: u32::MAX });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Point;

    fn square_with_centre() -> Triangulation {
        let pts = [
            Point::new(0.0, 0.0),
            Point::new(4.0, 0.0),
            Point::new(4.0, 4.0),
            Point::new(0.0, 4.0),
            Point::new(1.0, 2.0),
        ];
        let (t, _) = Triangulation::from_points(&pts).unwrap();
        t.check().unwrap();
        t
    }

    /// Flips the edge `e` of two real triangles (no validity checks: the point is to break things).
    fn flip(t: &mut Triangulation, e: u32) {
        let o = t.twin[e as usize];
        let (a, b) = (t.origin[e as usize], t.origin[o as usize]);
        let c = t.origin[next(next(e)) as usize];
        let d = t.origin[next(next(o)) as usize];
        let (te, to) = (3 * (e / 3), 3 * (o / 3));
        let (ea, eb) = (t.twin[next(o) as usize], t.twin[next(e) as usize]);
        let (ec, ed) = (
            t.twin[next(next(e)) as usize],
            t.twin[next(next(o)) as usize],
        );
        // New triangles (c, d, b) and (d, c, a).
        t.origin[te as usize..te as usize + 3].copy_from_slice(&[c, d, b]);
        t.origin[to as usize..to as usize + 3].copy_from_slice(&[d, c, a]);
        let link = |t: &mut Triangulation, x: u32, y: u32| {
            t.twin[x as usize] = y;
            t.twin[y as usize] = x;
        };
        link(t, te, to);
        link(t, te + 1, ed);
        link(t, te + 2, eb);
        link(t, to + 1, ec);
        link(t, to + 2, ea);
        for (i, &v) in t.origin.clone().iter().enumerate() {
            if v != GHOST {
                t.out_edge[v as usize] = i as u32;
            }
        }
    }

    #[test]
    fn a_flipped_edge_is_not_delaunay() {
        let mut t = square_with_centre();
        let e = (0..t.origin.len() as u32)
            .find(|&e| {
                let o = t.twin[e as usize];
                !t.is_ghost_slot(e / 3) && !t.is_ghost_slot(o / 3) && {
                    let (c, d) = (
                        t.origin[next(next(e)) as usize],
                        t.origin[next(next(o)) as usize],
                    );
                    let (a, b) = (t.origin[e as usize], t.origin[o as usize]);
                    let p = |v: u32| t.points[v as usize];
                    // A flip is geometrically valid when c and d lie on opposite sides of a-b's
                    // replacement, i.e. the quadrilateral is convex.
                    orient2d(p(c), p(d), p(b)) > 0.0 && orient2d(p(d), p(c), p(a)) > 0.0
                }
            })
            .expect("some convex quadrilateral");
        flip(&mut t, e);
        assert!(
            matches!(t.check(), Err(TriangulationDefect::NotDelaunay { .. })),
            "{:?}",
            t.check()
        );
    }

    #[test]
    fn reversed_triangle_is_reported() {
        let mut t = square_with_centre();
        let f = (0..t.origin.len() as u32 / 3)
            .find(|&f| !t.is_ghost_slot(f))
            .unwrap() as usize;
        t.origin.swap(3 * f, 3 * f + 1);
        assert!(matches!(
            t.check(),
            Err(TriangulationDefect::NotCounterClockwise { .. })
        ));
    }

    #[test]
    fn broken_twin_and_vertex_links_are_reported() {
        let mut t = square_with_centre();
        t.twin[0] = t.twin[1];
        assert!(matches!(
            t.check(),
            Err(TriangulationDefect::BadTwin { .. })
        ));
        let mut t = square_with_centre();
        let e = t.out_edge[4];
        t.out_edge[4] = next(e);
        assert!(matches!(
            t.check(),
            Err(TriangulationDefect::BadVertexEdge { vertex: 4 })
        ));
        let mut t = square_with_centre();
        t.ghost_count += 1;
        assert!(matches!(
            t.check(),
            Err(TriangulationDefect::GhostCount { .. })
        ));
    }

    #[test]
    fn a_vertex_outside_the_hull_breaks_convexity() {
        let mut t = square_with_centre();
        // Move the hull corner (4, 0) past the diagonal (0, 0)–(4, 4): the hull turns clockwise there.
        t.points[1] = Point::new(1.5, 1.6);
        assert!(t.check().is_err());
        t.points[1] = Point::new(2.5, 1.0); // still convex, still Delaunay-valid
        assert!(t.check().is_ok());
    }
}
