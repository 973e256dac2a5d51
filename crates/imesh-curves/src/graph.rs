//! The boundary graph: points, edges with the labels on their two sides, and pinned vertices.

use imesh_geom::Point;

use crate::CurveError;

/// An edge of a [`CurveGraph`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GraphEdge {
    /// Its two vertices (indices into [`CurveGraph::points`]).
    pub ends: [u32; 2],
    /// The label on the positive side of `ends[0] → ends[1]` (where `orient2d(a, b, q) > 0`; in
    /// image coordinates, y down, that is the side a counter-clockwise triangle `a b q` lies on),
    /// then the label on the negative side.
    pub labels: [u32; 2],
}

impl GraphEdge {
    /// The same edge walked the other way: ends and labels swapped.
    pub fn reversed(self) -> Self {
        Self {
            ends: [self.ends[1], self.ends[0]],
            labels: [self.labels[1], self.labels[0]],
        }
    }
}

/// A planar straight-line graph of region boundaries: the c-edges of a segmented image.
///
/// Vertices are indices into `points`; a point that no edge uses is allowed and ignored. Pinned
/// vertices always end a polyline (the domain corners, where the border turns).
///
/// ```
/// use imesh_curves::{CurveGraph, GraphEdge};
/// use imesh_geom::Point;
/// let points = vec![Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 2.0)];
/// let edges = vec![
///     GraphEdge { ends: [0, 1], labels: [1, 0] },
///     GraphEdge { ends: [1, 2], labels: [1, 0] },
///     GraphEdge { ends: [2, 0], labels: [1, 0] },
/// ];
/// let g = CurveGraph::new(points, edges)?;
/// assert_eq!(g.valence(1), 2);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
#[derive(Clone, Debug)]
pub struct CurveGraph {
    points: Vec<Point>,
    edges: Vec<GraphEdge>,
    pinned: Vec<bool>,
    /// Incident edges of each vertex, compressed: those of `v` are
    /// `incident[first[v]..first[v + 1]]`.
    first: Vec<u32>,
    incident: Vec<u32>,
}

impl CurveGraph {
    /// A graph of `points` and `edges`.
    ///
    /// # Errors
    /// [`CurveError::NonFinitePoint`], [`CurveError::BadEdge`] for an edge with an end out of
    /// range or both ends equal, [`CurveError::DuplicateEdge`] for two edges joining the same
    /// vertices, and [`CurveError::TooLarge`] beyond `u32` indices. Planarity (no two edges
    /// crossing) is the caller's promise: [`CurveGraph::crossing`] checks it.
    pub fn new(points: Vec<Point>, edges: Vec<GraphEdge>) -> Result<Self, CurveError> {
        if points.len() >= u32::MAX as usize || edges.len() >= u32::MAX as usize {
            return Err(CurveError::TooLarge);
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(CurveError::NonFinitePoint { index });
        }
        let n = points.len();
        let mut count = vec![0u32; n + 1];
        for (index, e) in edges.iter().enumerate() {
            let [a, b] = e.ends;
            if a as usize >= n || b as usize >= n || a == b {
                return Err(CurveError::BadEdge {
                    index,
                    ends: e.ends,
                });
            }
            count[a as usize + 1] += 1;
            count[b as usize + 1] += 1;
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let first = count;
        let mut fill = first.clone();
        let mut incident = vec![0u32; 2 * edges.len()];
        for (index, e) in edges.iter().enumerate() {
            for v in e.ends {
                incident[fill[v as usize] as usize] = index as u32;
                fill[v as usize] += 1;
            }
        }
        // Two edges joining the same vertices sit in the incident list of their lower end (in
        // edge order): report the first edge that repeats an earlier one.
        let other = |e: u32, v: u32| {
            let [a, b] = edges[e as usize].ends;
            if a == v {
                b
            } else {
                a
            }
        };
        let duplicate = (0..n as u32)
            .filter_map(|v| {
                let inc = &incident[first[v as usize] as usize..first[v as usize + 1] as usize];
                inc.iter()
                    .enumerate()
                    .filter(|&(_, &e)| other(e, v) > v)
                    .filter(|&(j, &e)| inc[..j].iter().any(|&f| other(f, v) == other(e, v)))
                    .map(|(_, &e)| e)
                    .next()
            })
            .min();
        if let Some(e) = duplicate {
            return Err(CurveError::DuplicateEdge {
                ends: edges[e as usize].ends,
            });
        }
        Ok(Self {
            pinned: vec![false; n],
            points,
            edges,
            first,
            incident,
        })
    }

    /// The boundary graph of a segmented image of `width` × `height` pixels: [`CurveGraph::new`],
    /// then [`CurveGraph::pin_domain_corners`].
    ///
    /// # Errors
    /// As [`CurveGraph::new`].
    pub fn image_boundaries(
        points: Vec<Point>,
        edges: Vec<GraphEdge>,
        width: f64,
        height: f64,
    ) -> Result<Self, CurveError> {
        let mut g = Self::new(points, edges)?;
        g.pin_domain_corners(width, height);
        Ok(g)
    }

    /// The points (vertex positions).
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// The position of vertex `v`.
    pub fn point(&self, v: u32) -> Point {
        self.points[v as usize]
    }

    /// The edges.
    pub fn edges(&self) -> &[GraphEdge] {
        &self.edges
    }

    /// The edges incident to vertex `v`.
    pub fn incident(&self, v: u32) -> &[u32] {
        &self.incident[self.first[v as usize] as usize..self.first[v as usize + 1] as usize]
    }

    /// The number of edges at vertex `v`.
    pub fn valence(&self, v: u32) -> usize {
        self.incident(v).len()
    }

    /// Makes vertex `v` end every polyline through it.
    ///
    /// # Errors
    /// [`CurveError::BadVertex`] when `v` is out of range.
    pub fn pin(&mut self, v: u32) -> Result<(), CurveError> {
        let slot = self
            .pinned
            .get_mut(v as usize)
            .ok_or(CurveError::BadVertex { vertex: v })?;
        *slot = true;
        Ok(())
    }

    /// Pins every vertex that lies exactly on a corner of the domain `[0, width] × [0, height]`.
    pub fn pin_domain_corners(&mut self, width: f64, height: f64) {
        let corners = [(0.0, 0.0), (width, 0.0), (width, height), (0.0, height)];
        for (v, p) in self.points.iter().enumerate() {
            if corners.contains(&(p.x, p.y)) {
                self.pinned[v] = true;
            }
        }
    }

    /// True when `v` is pinned.
    pub fn is_pinned(&self, v: u32) -> bool {
        self.pinned[v as usize]
    }

    /// The first pair of edges that cross or overlap (meeting anywhere but at a shared end
    /// vertex), found by brute force over a uniform grid; `None` when the graph is planar.
    pub fn crossing(&self) -> Option<[u32; 2]> {
        crate::grid::first_crossing(self)
    }

    /// The faces of the graph, each a closed walk with the region on its positive side.
    ///
    /// Every face boundary is walked with its face on the positive side (see [`GraphEdge`]), so
    /// a bounded face without holes has a positive signed area and the outer boundary of an
    /// island comes out negative. The label of a face walk is the label its edges carry on that
    /// side; a walk whose edges disagree is reported by [`Face::consistent`].
    pub fn faces(&self) -> Vec<Face> {
        crate::faces::faces(self)
    }
}

/// A closed walk around a face of a [`CurveGraph`].
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The edges walked, as indices into [`CurveGraph::edges`], each with `true` when it is walked
    /// from `ends[0]` to `ends[1]`.
    pub walk: Vec<(u32, bool)>,
    /// The label on the walk's positive side (that of the first edge).
    pub label: u32,
    /// Signed area enclosed by the walk (positive for a face's outer boundary).
    pub area: f64,
    /// True when every edge of the walk carries `label` on the walked side.
    pub consistent: bool,
}

impl Face {
    /// The length of the walk in `g` (the graph it was found in).
    pub fn perimeter(&self, g: &CurveGraph) -> f64 {
        self.walk
            .iter()
            .map(|&(e, _)| {
                let [a, b] = g.edges()[e as usize].ends;
                g.point(a).distance_squared(g.point(b)).sqrt()
            })
            .sum()
    }

    /// `2 · area / perimeter` in `g`: the width of a long strip, the radius of a disc, half the
    /// side of a square; 0 for a walk of negative area (an island's outer side) or no length.
    ///
    /// ```
    /// use imesh_curves::{CurveGraph, GraphEdge};
    /// use imesh_geom::Point;
    /// // A 10 × 1 strip (label 1) walked counter-clockwise; outside it label 0.
    /// let points = vec![Point::new(0.0, 0.0), Point::new(10.0, 0.0), Point::new(10.0, 1.0), Point::new(0.0, 1.0)];
    /// let edges = (0..4u32).map(|i| GraphEdge { ends: [i, (i + 1) % 4], labels: [1, 0] }).collect();
    /// let g = CurveGraph::new(points, edges)?;
    /// let strip = g.faces().into_iter().find(|f| f.label == 1).unwrap();
    /// assert!((strip.width(&g) - 20.0 / 22.0).abs() < 1e-12);
    /// # Ok::<(), imesh_curves::CurveError>(())
    /// ```
    pub fn width(&self, g: &CurveGraph) -> f64 {
        let perimeter = self.perimeter(g);
        if self.area > 0.0 && perimeter > 0.0 {
            2.0 * self.area / perimeter
        } else {
            0.0
        }
    }
}
