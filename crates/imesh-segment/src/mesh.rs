//! The segmented mesh: the sampled triangulation with its partition (the c-edges as segments, a
//! label per triangle), and Imesh step 3, its label-aware quality refinement (DESIGN.md §2,
//! step 4).

use imesh_classify::LabelGrid;
use imesh_geom::{Location, RefineOptions, RefineReport, TriangleId, Triangulation};

use crate::partition::{c_edges, partition, CEdge};
use crate::sample::{sample, SampleOptions, Sampling};
use crate::SegmentError;

/// Default smallest angle of the Imesh triangle output, as in Imesh.
pub const DEFAULT_MIN_ANGLE: f64 = 26.4;

/// A labelled triangulation of the image domain whose region boundaries are segments: the input
/// of the curve and quad stages, and (refined) the Imesh triangle output.
#[derive(Clone, Debug)]
pub struct SegmentedMesh {
    /// The triangulation: c-edges are its segments, every real triangle has a label.
    pub triangulation: Triangulation,
    /// The c-edge graph: boundaries between labels and the domain border.
    pub c_edges: Vec<CEdge>,
    /// Domain width in pixels.
    pub width: u32,
    /// Domain height in pixels.
    pub height: u32,
    /// What sampling did.
    pub inserted: usize,
    /// Rounds of sampling.
    pub rounds: usize,
}

impl SegmentedMesh {
    /// Samples `grid` (Imesh step 1), labels the triangles and extracts the c-edges (step 2).
    ///
    /// # Errors
    /// As [`sample`]; a geometry error if the c-edges cannot be made segments (never expected).
    ///
    /// ```
    /// use imesh_classify::{LabelGrid, Region};
    /// use imesh_segment::{SampleOptions, SegmentedMesh};
    /// let labels = (0..100).map(|i| u32::from(i % 10 < 4)).collect();
    /// let regions = vec![Region { name: "a".into(), colour: [0; 3] }, Region { name: "b".into(), colour: [255; 3] }];
    /// let grid = LabelGrid::new(10, 10, labels, regions).unwrap();
    /// let m = SegmentedMesh::from_grid(&grid, &SampleOptions::default()).unwrap();
    /// m.triangulation.check().unwrap();
    /// assert!(m.label_agreement(&grid) > 0.9);
    /// ```
    pub fn from_grid(grid: &LabelGrid, options: &SampleOptions) -> Result<Self, SegmentError> {
        let sampling = sample(grid, options)?;
        let label = partition(grid, &sampling.triangulation);
        Self::from_partition(sampling, label, grid.width(), grid.height())
    }

    /// The segmented mesh of a sampling with a label per triangle slot (as [`partition`] gives,
    /// possibly edited, e.g. by [`merge_thin_regions`](crate::merge_thin_regions)): the c-edges
    /// are drawn between the labels and made segments.
    ///
    /// # Errors
    /// A geometry error if the c-edges cannot be made segments (never expected).
    ///
    /// ```
    /// use imesh_classify::{LabelGrid, Region};
    /// use imesh_segment::{merge_thin_regions, partition, sample, SampleOptions, SegmentedMesh};
    /// // A one-pixel line across a 20 × 20 image: merged away at a width of 2 px.
    /// let labels = (0..400).map(|i| u32::from(i / 20 == 10)).collect();
    /// let regions = vec![Region { name: "a".into(), colour: [0; 3] }, Region { name: "b".into(), colour: [255; 3] }];
    /// let grid = LabelGrid::new(20, 20, labels, regions).unwrap();
    /// let sampling = sample(&grid, &SampleOptions::default()).unwrap();
    /// let mut label = partition(&grid, &sampling.triangulation);
    /// assert!(merge_thin_regions(&sampling.triangulation, &mut label, 2.0).regions >= 1);
    /// let m = SegmentedMesh::from_partition(sampling, label, 20, 20).unwrap();
    /// assert!(m.c_edges.iter().all(|e| e.labels.contains(&imesh_segment::OUTSIDE)));
    /// ```
    pub fn from_partition(
        sampling: Sampling,
        label: Vec<u32>,
        width: u32,
        height: u32,
    ) -> Result<Self, SegmentError> {
        let Sampling {
            mut triangulation,
            inserted,
            rounds,
            ..
        } = sampling;
        let c_edges = c_edges(&triangulation, &label);
        for e in &c_edges {
            triangulation.insert_segment(e.vertices[0], e.vertices[1])?;
        }
        triangulation.set_labels(|t| label[t.index()]);
        Ok(Self {
            triangulation,
            c_edges,
            width,
            height,
            inserted,
            rounds,
        })
    }

    /// Imesh's triangle output: Ruppert refinement to `options.min_angle_deg` that keeps every
    /// inserted point inside the region of its triangle (a point beyond a c-edge splits that
    /// c-edge instead). Labels follow every insertion. The c-edge list is not updated: its edges
    /// may now be split into several pieces ([`Triangulation::segment_vertices`] lists them).
    ///
    /// # Errors
    /// [`imesh_geom::GeomError::BadAngle`] (as a [`SegmentError`]) for an angle above 34°.
    pub fn refine(&mut self, options: &RefineOptions) -> Result<RefineReport, SegmentError> {
        Ok(self
            .triangulation
            .refine_with_policy(options, |t, c| t.label(c.containing) == t.label(c.bad))?)
    }

    /// Vertices, triangles (counter-clockwise in image coordinates, y down) and a label per
    /// triangle, as plain arrays.
    pub fn arrays(&self) -> (Vec<[f64; 2]>, Vec<[u32; 3]>, Vec<u32>) {
        let t = &self.triangulation;
        let vertices = t.points().iter().map(|p| [p.x, p.y]).collect();
        let faces: Vec<TriangleId> = t.triangles().collect();
        let triangles = faces
            .iter()
            .map(|&f| t.triangle_vertices(f).map(|v| v.index() as u32))
            .collect();
        let labels = faces.iter().map(|&f| t.label(f)).collect();
        (vertices, triangles, labels)
    }

    /// The share of pixels whose centre lies in a triangle with the pixel's label (a centre on an
    /// edge or vertex counts when any triangle there has the label).
    pub fn label_agreement(&self, grid: &LabelGrid) -> f64 {
        let t = &self.triangulation;
        let (w, h) = (grid.width(), grid.height());
        let mut agree = 0usize;
        for r in 0..h {
            // Serpentine order keeps each location next to the previous one.
            let cols: Box<dyn Iterator<Item = u32>> = if r % 2 == 0 {
                Box::new(0..w)
            } else {
                Box::new((0..w).rev())
            };
            for c in cols {
                let p = imesh_geom::Point::new(f64::from(c) + 0.5, f64::from(r) + 0.5);
                let want = grid.label(c, r);
                let ok = match t.locate(p) {
                    Location::InTriangle(f) => t.label(f) == want,
                    Location::OnEdge(e) => {
                        t.label(t.triangle_of(e)) == want
                            || t.neighbour(e).is_some_and(|f| t.label(f) == want)
                    }
                    Location::OnVertex(v) => t.vertex_triangles(v).any(|f| t.label(f) == want),
                    Location::OutsideHull(_) | Location::NoTriangles => false,
                };
                agree += usize::from(ok);
            }
        }
        agree as f64 / (f64::from(w) * f64::from(h))
    }
}
