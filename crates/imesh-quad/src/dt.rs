//! DT': the labelled Delaunay triangulation that conforms to G' (DESIGN.md §2, step 6).

use imesh_curves::CurveGraph;
use imesh_geom::{
    HalfEdgeId, RefineOptions, RefineReport, SegmentId, TriangleId, Triangulation, VertexId,
};

use crate::QuadError;

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
    /// spacing before refinement ([`uniform_points`]), and refinement splits every triangle
    /// larger than [`MAX_TRIANGLE_AREA`] squared spacings. `None` leaves DT' graded from the
    /// boundary pieces inwards.
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
        let refinement = triangulation.refine(&refine)?;
        graph_vertex_of.resize(triangulation.num_vertices(), NONE);
        segment_edge.resize(triangulation.num_segments().max(segment_edge.len()), NONE);
        let dt = Self {
            triangulation,
            segment_edge,
            graph_vertex: graph_vertex_of,
            refinement,
        };
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
