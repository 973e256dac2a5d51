//! DT': the labelled Delaunay triangulation that conforms to G' (DESIGN.md §2, step 6).

use imesh_curves::{segment_distance_squared, CurveGraph};
use imesh_geom::{
    Candidate, HalfEdgeId, RefineOptions, RefineReport, SegmentId, TriangleId, Triangulation,
    VertexId,
};

use crate::{Element, ElementMesh, QuadError};

/// "None" in the index maps of [`RegionTriangulation`].
pub const NONE: u32 = u32::MAX;

/// Density control of DT'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityOptions {
    /// Smallest angle wanted by Ruppert refinement, in degrees (default 20.7°, at most 34°).
    pub min_angle_deg: f64,
    /// Most Steiner points refinement may insert.
    pub max_steiner: usize,
    /// Largest element size in pixels: triangles larger than the equilateral triangle of this
    /// side are refined.
    pub max_size: Option<f64>,
    /// Spacing of a uniform DT', in pixels: boundaries are split into pieces no longer than
    /// this, and the inside away from them is filled with an axis-aligned square lattice of this
    /// spacing before refinement ([`uniform_points`](crate::uniform_points)), and refinement
    /// splits every triangle larger than [`MAX_TRIANGLE_AREA`] squared spacings, keeping its points
    /// [`BOUNDARY_CLEARANCE`] spacings off the boundaries of their triangles (thin strips stay
    /// whole). `None` leaves DT' graded from the boundary pieces inwards.
    pub spacing: Option<f64>,
    /// The inside lattice's spacing as a multiple of [`DensityOptions::spacing`] (1: the same;
    /// [`crate::uniform_points_with_lattice`]).
    pub lattice_scale: f64,
}

impl Default for DensityOptions {
    fn default() -> Self {
        Self {
            min_angle_deg: 20.7,
            max_steiner: usize::MAX,
            max_size: None,
            spacing: None,
            lattice_scale: 1.0,
        }
    }
}

/// DT' with its links to G': which G' edge each segment lies on, which G' vertex each vertex is,
/// and a label per triangle.
#[derive(Clone, Debug)]
pub struct RegionTriangulation {
    /// The triangulation: G' edges are its segments (split by Steiner points where refinement
    /// needed), every triangle has its region's label.
    pub triangulation: Triangulation,
    /// For each segment of the triangulation, the G' edge it is ([`NONE`] for any other).
    pub segment_edge: Vec<u32>,
    /// For each vertex of the triangulation, the G' vertex it is ([`NONE`] for a Steiner point).
    pub graph_vertex: Vec<u32>,
    /// What refinement did.
    pub refinement: RefineReport,
}

impl RegionTriangulation {
    /// Triangulates the vertices of `g` (a planar graph whose edges include the domain border),
    /// inserts its edges as segments, labels each region from the labels its boundary edges carry
    /// on their sides, and refines to `options`.
    ///
    /// # Errors
    /// [`QuadError::EmptyGraph`] for a graph without edges; [`QuadError::LatticeTooFine`] for a
    /// spacing whose lattice exceeds `max_steiner`; [`QuadError::Geometry`] if a G' edge
    /// cannot be inserted (crossing edges: G' was not planar) or for a bad angle.
    ///
    /// ```
    /// use imesh_curves::{CurveGraph, GraphEdge};
    /// use imesh_geom::Point;
    /// use imesh_quad::{DensityOptions, RegionTriangulation};
    /// // A 4 × 2 domain split into two labels by a vertical line at x = 2.
    /// let points = vec![
    ///     Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(4.0, 0.0),
    ///     Point::new(4.0, 2.0), Point::new(2.0, 2.0), Point::new(0.0, 2.0),
    /// ];
    /// let e = |a, b, labels| GraphEdge { ends: [a, b], labels };
    /// let edges = vec![
    ///     e(0, 1, [0, u32::MAX]), e(1, 2, [1, u32::MAX]), e(2, 3, [1, u32::MAX]),
    ///     e(3, 4, [1, u32::MAX]), e(4, 5, [0, u32::MAX]), e(5, 0, [0, u32::MAX]), e(1, 4, [0, 1]),
    /// ];
    /// let g = CurveGraph::new(points, edges)?;
    /// let dt = RegionTriangulation::new(&g, &DensityOptions::default())?;
    /// let t = &dt.triangulation;
    /// assert!(t.triangles().all(|f| {
    ///     let [a, b, c] = t.triangle_points(f);
    ///     t.label(f) == u32::from((a.x + b.x + c.x) / 3.0 > 2.0)
    /// }));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(g: &CurveGraph, options: &DensityOptions) -> Result<Self, QuadError> {
        if g.edges().is_empty() {
            return Err(QuadError::EmptyGraph);
        }
        // Only the vertices that edges use.
        let mut vertex_of = vec![NONE; g.points().len()];
        let mut points = Vec::new();
        let mut graph_vertex = Vec::new();
        for e in g.edges() {
            for v in e.ends {
                if vertex_of[v as usize] == NONE {
                    vertex_of[v as usize] = points.len() as u32;
                    points.push(g.point(v));
                    graph_vertex.push(v);
                }
            }
        }
        let (mut triangulation, ids) = Triangulation::from_points(&points)?;
        // `from_points` merges duplicate points: map through its ids.
        let vertex = |v: u32| ids[vertex_of[v as usize] as usize];
        let mut segment_edge = Vec::with_capacity(g.edges().len());
        for (k, e) in g.edges().iter().enumerate() {
            let s = triangulation.insert_segment(vertex(e.ends[0]), vertex(e.ends[1]))?;
            if segment_edge.len() <= s.0 as usize {
                segment_edge.resize(s.0 as usize + 1, NONE);
            }
            segment_edge[s.0 as usize] = k as u32;
        }
        let mut graph_vertex_of = vec![NONE; triangulation.num_vertices()];
        for (i, &v) in graph_vertex.iter().enumerate() {
            graph_vertex_of[ids[i].index()] = v;
        }
        let labels = region_labels(&triangulation, &segment_edge, g);
        triangulation.set_labels(|t| labels[t.index()]);
        if let Some(h) = options.spacing {
            let lattice = h * options.lattice_scale;
            let points = crate::density::lattice_points(&triangulation, lattice);
            if points > options.max_steiner as u64 {
                return Err(QuadError::LatticeTooFine {
                    spacing: h,
                    points,
                    limit: options.max_steiner as u64,
                });
            }
            crate::uniform_points_with_lattice(&mut triangulation, h, lattice)?;
        }
        let refine = RefineOptions {
            min_angle_deg: options.min_angle_deg,
            max_steiner: options.max_steiner,
            max_area: largest_area(options),
        };
        let refinement = match options.spacing {
            Some(h) => triangulation.refine_with_policy(&refine, clear_of_boundaries(h))?,
            None => triangulation.refine(&refine)?,
        };
        let mut dt = Self {
            triangulation,
            segment_edge,
            graph_vertex: graph_vertex_of,
            refinement,
        };
        dt.cover_refinement();
        Ok(dt)
    }

    /// The G' edge half-edge `h` lies on, and whether `h` runs along it (from its `ends[0]`).
    pub fn graph_edge(&self, g: &CurveGraph, h: HalfEdgeId) -> Option<(u32, bool)> {
        graph_edge(&self.triangulation, &self.segment_edge, g, h)
    }

    /// The parameter in `[0, 1]` of vertex `v` along the straight G' edge `k` (from `ends[0]`).
    pub fn edge_parameter(&self, g: &CurveGraph, k: u32, v: VertexId) -> f64 {
        let [a, b] = g.edges()[k as usize].ends.map(|x| g.point(x));
        imesh_curves::segment_parameter(a, b, self.triangulation.point(v))
    }

    /// The pieces of segment `s` in order, as vertices.
    pub fn segment_pieces(&self, s: SegmentId) -> Vec<VertexId> {
        self.triangulation.segment_vertices(s)
    }

    /// The label of triangle `f`.
    pub fn label(&self, f: TriangleId) -> u32 {
        self.triangulation.label(f)
    }

    /// Extends the maps to G' over the vertices and segments refinement added, which are no G'
    /// vertex or edge of their own ([`NONE`]).
    fn cover_refinement(&mut self) {
        self.graph_vertex
            .resize(self.triangulation.num_vertices(), NONE);
        let segments = self
            .triangulation
            .num_segments()
            .max(self.segment_edge.len());
        self.segment_edge.resize(segments, NONE);
    }

    /// Refines a uniform DT' (`options.spacing`) once more where pairing left a triangle whose
    /// corner on a boundary is sharper than [`SHARP_UNPAIRED_CORNER`]: each such unpaired
    /// triangle of `elements` is refined to that angle, the triangles its points make to
    /// `options`, with the same clearance from the boundaries. Returns the points inserted
    /// (added to [`refinement`](Self::refinement)); 0 leaves DT' as it was, and so does a
    /// graded DT' (no spacing) or a `min_angle_deg` of that angle or more. The caller pairs
    /// again after any insertion.
    ///
    /// # Errors
    /// [`QuadError::Geometry`] as [`RegionTriangulation::new`]'s refinement.
    pub fn open_sharp_unpaired(
        &mut self,
        elements: &ElementMesh,
        options: &DensityOptions,
    ) -> Result<usize, QuadError> {
        let Some(h) = options.spacing else {
            return Ok(0);
        };
        if options.min_angle_deg >= SHARP_UNPAIRED_CORNER {
            return Ok(0);
        }
        let t = &self.triangulation;
        let unpaired = |f: TriangleId| {
            let e = elements.element_of_triangle[f.index()];
            matches!(
                elements.elements.get(e as usize),
                Some(Element::Triangle(_))
            )
        };
        // A triangle whose shortest side is within the boundaries' clearance is left: its
        // points would be too (a cluster of quads a few hundredths of the mean area, shape 0.31
        // on one image of 150).
        let near2 = (BOUNDARY_CLEARANCE * h).powi(2);
        let sharp: Vec<TriangleId> = t
            .triangles()
            .filter(|&f| {
                unpaired(f)
                    && shortest_side2(t, f) >= near2
                    && sharp_on_boundary(t, f, SHARP_UNPAIRED_CORNER)
            })
            .collect();
        if sharp.is_empty() {
            return Ok(0);
        }
        let refine = RefineOptions {
            min_angle_deg: options.min_angle_deg,
            max_steiner: options.max_steiner.saturating_sub(self.refinement.inserted),
            max_area: largest_area(options),
        };
        let report = self.triangulation.refine_triangles_with_policy(
            &sharp,
            SHARP_UNPAIRED_CORNER,
            &refine,
            clear_of_boundaries(h),
        )?;
        self.cover_refinement();
        self.refinement = RefineReport {
            inserted: self.refinement.inserted + report.inserted,
            ..report
        };
        Ok(report.inserted)
    }
}

/// An unpaired triangle keeps its corners in its template's three quads, and where such a
/// corner lies on a boundary neither pairing nor the optimiser can open it (the optimiser moves
/// no G' vertex and slides the rest along their curve only): so a triangle left unpaired with a
/// corner on a boundary sharper than this, in degrees, is refined once more
/// ([`RegionTriangulation::open_sharp_unpaired`]), and the mesh is paired again. Such
/// triangles' quads were most of the quads under 0.5 in shape or scaled Jacobian over 150
/// images (287 of 372 in shape, all 59 in scaled Jacobian). Measured on those 150 images with
/// the defaults (docs/measurements.md, session 49): quads with shape under 0.5 372 → 114, with
/// scaled Jacobian under 0.5 59 → 24, the mean of the mean shape-and-size 0.8482 → 0.8478 (the
/// few more quads lower the mean quad area that every quad's size is measured against); at
/// 22.5° 172 and 36 quads, at 30° 153 and 30 with means 0.002 lower (before tiny triangles were
/// left), and refining every triangle to 23° instead (`--min-angle`) 199 and 28 with means
/// 0.001 lower.
pub const SHARP_UNPAIRED_CORNER: f64 = 25.0;

/// Whether triangle `f` has a corner under `degrees` with one side on a segment (with two,
/// the corner is an angle of G' itself, which refinement leaves as it is).
fn sharp_on_boundary(t: &Triangulation, f: TriangleId, degrees: f64) -> bool {
    let cos2 = degrees.to_radians().cos().powi(2);
    let sides = t.triangle_edges(f);
    let p = t.triangle_points(f);
    (0..3).any(|k| {
        // Corner k lies between the side leaving it (k) and the one arriving (k + 2).
        let on_boundary = t.is_constrained(sides[k]) != t.is_constrained(sides[(k + 2) % 3]);
        let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        let dot = a.x * b.x + a.y * b.y;
        let (a2, b2) = (a.x * a.x + a.y * a.y, b.x * b.x + b.y * b.y);
        on_boundary && dot > 0.0 && dot * dot > cos2 * a2 * b2
    })
}

/// The largest triangle of a uniform DT', in squared spacings (twice a lattice triangle). Where
/// a region is too narrow for the lattice (a channel under about 2.4 spacings wide), its
/// triangles span it from boundary piece to boundary piece, up to 1.5 spacings long
/// ([`crate::BOUNDARY_PIECE`]): pairs of them gave quads two to four times the mesh's mean area
/// (shape-and-size 0.1–0.4). Measured on nine fixtures (all but aloe), mean shape-and-size
/// averaged over them: none 0.8181, 1.5 0.8181, 1.25 0.8189, 1.1 0.8212, 1.0 0.8248 (seven
/// higher, pyvista 0.845 → 0.860, camera −0.001), 0.95 0.8261 and 0.9 0.8255 (camera −0.003 and
/// −0.007), 0.75 0.7960 (the band along the boundaries split too).
pub const MAX_TRIANGLE_AREA: f64 = 1.0;

/// How close to a boundary, in spacings, refinement of a uniform DT' may insert a point
/// (a veto on its candidate points). Where a strip is narrower than about twice this, a triangle
/// spanning it is skinny, and its circumcentre (or off-centre) falls inside the strip: inserted,
/// it split the strip into triangles a fraction of its width, hence clusters of quads a tenth
/// of the mesh's mean area and a shape of 0.28 (coffee, a strip 1.1 px wide at a 3 px spacing).
/// Left alone, the skinny triangle pairs with its neighbour across the strip. Measured with the
/// defaults on nine fixtures (all but aloe): coffee's worst shape 0.280 → 0.399 and worst scaled
/// Jacobian 0.453 → 0.500, grass's 0.428 → 0.447; mean shape-and-size 0.8377 → 0.8380 on
/// average, the label agreement unchanged; at 0.15 grass's worst scaled Jacobian stays, at 0.25
/// and 0.3 gravel's worst shape falls 0.313 → 0.238 (and stardist's 0.500 → 0.361 at 0.3).
pub const BOUNDARY_CLEARANCE: f64 = 0.2;

/// The refinement policy of a uniform DT' of `spacing`: no point within
/// [`BOUNDARY_CLEARANCE`] spacings of a segment of the bad triangle or of the triangle holding
/// the point. Unless the bad triangle's shortest side is that short itself: a cascade of ever
/// smaller triangles at a small input angle (a junction of aloe's), which only Ruppert's own
/// rules end (with the veto there, aloe's worst shape fell 0.134 → 0.036).
fn clear_of_boundaries(spacing: f64) -> impl FnMut(&Triangulation, &Candidate) -> bool {
    let near2 = (BOUNDARY_CLEARANCE * spacing).powi(2);
    move |t, c| {
        let near_segment = |f: TriangleId| {
            t.triangle_edges(f).into_iter().any(|h| {
                t.is_constrained(h)
                    && segment_distance_squared(
                        t.point(t.origin(h)),
                        t.point(t.destination(h)),
                        c.point,
                    ) < near2
            })
        };
        shortest_side2(t, c.bad) < near2
            || !(near_segment(c.bad) || (c.containing != c.bad && near_segment(c.containing)))
    }
}

/// The squared length of the shortest side of triangle `f`.
fn shortest_side2(t: &Triangulation, f: TriangleId) -> f64 {
    let [a, b, d] = t.triangle_points(f);
    a.distance_squared(b)
        .min(b.distance_squared(d))
        .min(d.distance_squared(a))
}

/// Refinement's area bound: that of [`DensityOptions::max_size`], and of a uniform DT'
/// ([`MAX_TRIANGLE_AREA`]), whichever is smaller.
fn largest_area(options: &DensityOptions) -> Option<f64> {
    let by_size = options.max_size.map(|s| 3f64.sqrt() / 4.0 * s * s);
    let by_spacing = options.spacing.map(|h| MAX_TRIANGLE_AREA * h * h);
    match (by_size, by_spacing) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// A label per triangle slot: each set of triangles connected without crossing a segment
/// takes the label its boundary edges carry on its side.
fn region_labels(t: &Triangulation, segment_edge: &[u32], g: &CurveGraph) -> Vec<u32> {
    let mut label = vec![NONE; t.num_triangle_slots()];
    let mut stack = Vec::new();
    let mut component = Vec::new();
    for start in t.triangles() {
        if label[start.index()] != NONE {
            continue;
        }
        component.clear();
        stack.push(start);
        label[start.index()] = 0;
        let mut found = None;
        while let Some(f) = stack.pop() {
            component.push(f);
            for h in t.triangle_edges(f) {
                if let Some((k, forward)) = graph_edge(t, segment_edge, g, h) {
                    // The triangle lies on the positive side of its own half-edge.
                    let l = g.edges()[k as usize].labels;
                    found.get_or_insert(if forward { l[0] } else { l[1] });
                    continue;
                }
                if let Some(n) = t.neighbour(h) {
                    if label[n.index()] == NONE {
                        label[n.index()] = 0;
                        stack.push(n);
                    }
                }
            }
        }
        let l = found.unwrap_or(NONE);
        for &f in &component {
            label[f.index()] = l;
        }
    }
    label
}

/// The G' edge half-edge `h` lies on, and whether `h` runs along it.
fn graph_edge(
    t: &Triangulation,
    segment_edge: &[u32],
    g: &CurveGraph,
    h: HalfEdgeId,
) -> Option<(u32, bool)> {
    let s = t.segment_of(h)?;
    let k = *segment_edge.get(s.0 as usize)?;
    if k == NONE {
        return None;
    }
    let a = g.point(g.edges()[k as usize].ends[0]);
    let (u, w) = (t.point(t.origin(h)), t.point(t.destination(h)));
    Some((k, a.distance_squared(u) < a.distance_squared(w)))
}

#[cfg(test)]
mod tests {
    use imesh_geom::{Candidate, Point, Triangulation};

    use super::clear_of_boundaries;

    /// A strip one unit wide (between the segments y = 0 and y = 1, its vertices 4 apart and
    /// staggered) in a 12 × 9 domain, and the triangle of it with its base on y = 0 at x 0–4.
    fn strip() -> (Triangulation, imesh_geom::TriangleId) {
        let mut pts = vec![
            Point::new(0.0, -4.0),
            Point::new(12.0, -4.0),
            Point::new(12.0, 5.0),
            Point::new(0.0, 5.0),
        ];
        let bottom: Vec<Point> = [0.0, 4.0, 8.0, 12.0].map(|x| Point::new(x, 0.0)).into();
        let top: Vec<Point> = [0.0, 2.0, 6.0, 10.0, 12.0]
            .map(|x| Point::new(x, 1.0))
            .into();
        pts.extend(&bottom);
        pts.extend(&top);
        let (mut t, v) = Triangulation::from_points(&pts).expect("a valid point set");
        for chain in [4..8, 8..13] {
            let ids: Vec<_> = chain.map(|i| v[i]).collect();
            for w in ids.windows(2) {
                t.insert_segment(w[0], w[1])
                    .expect("segments that cross nothing");
            }
        }
        let base = t
            .triangles()
            .find(|&f| {
                let p = t.triangle_points(f);
                [(0.0, 0.0), (4.0, 0.0), (2.0, 1.0)]
                    .iter()
                    .all(|&q| p.contains(&Point::from(q)))
            })
            .expect("the strip's triangle on x 0–4");
        (t, base)
    }

    #[test]
    fn a_uniform_dt_keeps_refinement_points_off_the_boundaries_of_a_thin_strip() {
        let (t, bad) = strip();
        let inside = Candidate {
            bad,
            point: Point::new(2.0, 0.5),
            containing: bad,
        };
        // Half a unit from both boundaries: within 0.2 spacings of 5, not of 1.
        assert!(!clear_of_boundaries(5.0)(&t, &inside));
        assert!(clear_of_boundaries(1.0)(&t, &inside));
        // A point far from every segment of its triangles is always welcome.
        let (far_bad, far) = t
            .triangles()
            .map(|f| {
                let [a, b, c] = t.triangle_points(f);
                (
                    f,
                    Point::new((a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0),
                )
            })
            .find(|(_, c)| c.y < -2.5 && c.x > 3.0 && c.x < 9.0)
            .expect("a triangle well below the strip");
        let away = Candidate {
            bad: far_bad,
            point: far,
            containing: far_bad,
        };
        assert!(clear_of_boundaries(5.0)(&t, &away));
        // A bad triangle whose shortest side (√5 here) is itself within the clearance is a
        // cascade at a small angle: refined as usual.
        assert!(clear_of_boundaries(20.0)(&t, &inside));
    }
}
