//! Whole-mesh quality: every metric of every element, summarised the way the report prints it.

use rayon::prelude::*;
use serde::Serialize;

use crate::{quad, tri, Histogram, Point2, Statistics};

/// Quality statistics of a quad mesh, as the JSON report's `"quality"` block.
///
/// Shape-and-size is measured against the mean area of the mesh's own quads, as `vtkMeshQuality`
/// does, so that anyone can check the figures with VTK.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QuadQuality {
    /// Mean quad area used for shape-and-size.
    pub average_area: f64,
    /// Shape-and-size (threshold 0.2).
    pub shape_and_size: Statistics,
    /// Shape (threshold 0.3).
    pub shape: Statistics,
    /// Scaled Jacobian (threshold 0.3).
    pub scaled_jacobian: Statistics,
    /// Minimum angle in degrees (threshold 45°).
    pub min_angle_deg: Statistics,
    /// Maximum angle in degrees (threshold 135°; `below` counts the good ones).
    pub max_angle_deg: Statistics,
}

/// The report's quality histograms of a quad mesh: shape-and-size and scaled Jacobian, 20 equal
/// bins over [0, 1] each.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QuadHistograms {
    /// Shape-and-size.
    pub shape_and_size: Histogram,
    /// Scaled Jacobian.
    pub scaled_jacobian: Histogram,
}

impl QuadHistograms {
    /// Bins of the report's histograms.
    pub const BINS: usize = 20;

    /// The histograms of per-quad `values`.
    ///
    /// ```
    /// use imesh_quality::{QuadHistograms, QuadValues};
    /// let v = QuadValues { shape_and_size: 0.42, shape: 0.9, scaled_jacobian: 1.0, min_angle_deg: 90.0, max_angle_deg: 90.0 };
    /// let h = QuadHistograms::of_values(&[v]);
    /// assert_eq!(h.shape_and_size.counts[8], 1); // [0.40, 0.45)
    /// assert_eq!(h.scaled_jacobian.counts[QuadHistograms::BINS - 1], 1);
    /// ```
    pub fn of_values(values: &[QuadValues]) -> Self {
        let histogram = |f: fn(&QuadValues) -> f64| {
            let column: Vec<f64> = values.iter().map(f).collect();
            Histogram::of(&column, 0.0, 1.0, Self::BINS)
        };
        Self {
            shape_and_size: histogram(|v| v.shape_and_size),
            scaled_jacobian: histogram(|v| v.scaled_jacobian),
        }
    }
}

/// Per-quad values of the five reported metrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadValues {
    /// Shape-and-size.
    pub shape_and_size: f64,
    /// Shape.
    pub shape: f64,
    /// Scaled Jacobian.
    pub scaled_jacobian: f64,
    /// Minimum angle (degrees).
    pub min_angle_deg: f64,
    /// Maximum angle (degrees).
    pub max_angle_deg: f64,
}

/// The quads of a mesh as corner arrays.
pub fn quad_corners(vertices: &[Point2], quads: &[[u32; 4]]) -> Vec<quad::Quad> {
    quads
        .iter()
        .map(|q| q.map(|v| vertices[v as usize]))
        .collect()
}

/// Mean [`quad::area`] over `quads` (0 for none). Summed in order: a parallel sum's rounding
/// depends on how the work was split, which moved every shape-and-size in the last bits from
/// one run to the next.
pub fn average_quad_area(quads: &[quad::Quad]) -> f64 {
    if quads.is_empty() {
        return 0.0;
    }
    quads.iter().map(quad::area).sum::<f64>() / quads.len() as f64
}

/// Every reported metric of every quad (in parallel).
pub fn quad_values(quads: &[quad::Quad], average_area: f64) -> Vec<QuadValues> {
    quads
        .par_iter()
        .map(|q| {
            let shape = quad::shape(q);
            let (min_angle_deg, max_angle_deg) = quad::angles(q);
            QuadValues {
                shape_and_size: shape * quad::relative_size_squared(q, average_area),
                shape,
                scaled_jacobian: quad::scaled_jacobian(q),
                min_angle_deg,
                max_angle_deg,
            }
        })
        .collect()
}

impl QuadQuality {
    /// Quality of the quads `quads` over `vertices`.
    ///
    /// ```
    /// use imesh_quality::QuadQuality;
    /// let v = [[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [0.0, 1.0], [1.0, 1.0], [3.0, 1.0]];
    /// let q = QuadQuality::of(&v, &[[0, 1, 4, 3], [1, 2, 5, 4]]);
    /// assert_eq!(q.average_area, 1.5);
    /// assert!((q.shape.min - 0.8).abs() < 1e-15); // the 2 × 1 rectangle
    /// assert!((q.scaled_jacobian.min - 1.0).abs() < 1e-15);
    /// ```
    pub fn of(vertices: &[Point2], quads: &[[u32; 4]]) -> Self {
        Self::with_histograms(vertices, quads).0
    }

    /// [`QuadQuality::of`] and the [`QuadHistograms`] of the same quads, every metric computed
    /// once for both.
    ///
    /// ```
    /// use imesh_quality::QuadQuality;
    /// let v = [[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [0.0, 1.0], [1.0, 1.0], [3.0, 1.0]];
    /// let quads = [[0, 1, 4, 3], [1, 2, 5, 4]];
    /// let (quality, histograms) = QuadQuality::with_histograms(&v, &quads);
    /// assert_eq!(quality, QuadQuality::of(&v, &quads));
    /// // The unit square's scaled Jacobian 1 is in the last bin, the rectangle's too.
    /// assert_eq!(histograms.scaled_jacobian.counts[19], 2);
    /// ```
    pub fn with_histograms(vertices: &[Point2], quads: &[[u32; 4]]) -> (Self, QuadHistograms) {
        let corners = quad_corners(vertices, quads);
        let average_area = average_quad_area(&corners);
        let values = quad_values(&corners, average_area);
        (
            Self::of_values(&values, average_area),
            QuadHistograms::of_values(&values),
        )
    }

    /// The statistics of per-quad `values` measured against `average_area`.
    pub fn of_values(values: &[QuadValues], average_area: f64) -> Self {
        let column = |f: fn(&QuadValues) -> f64| values.iter().map(f).collect::<Vec<f64>>();
        Self {
            average_area,
            shape_and_size: Statistics::of(&column(|v| v.shape_and_size), 0.2),
            shape: Statistics::of(&column(|v| v.shape), 0.3),
            scaled_jacobian: Statistics::of(&column(|v| v.scaled_jacobian), 0.3),
            min_angle_deg: Statistics::of(&column(|v| v.min_angle_deg), 45.0),
            max_angle_deg: Statistics::of(&column(|v| v.max_angle_deg), 135.0),
        }
    }
}

/// Quality statistics of a triangle mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TriangleQuality {
    /// Shape (threshold 0.3).
    pub shape: Statistics,
    /// Scaled Jacobian (threshold 0.3).
    pub scaled_jacobian: Statistics,
    /// Minimum angle in degrees (threshold 30°).
    pub min_angle_deg: Statistics,
    /// Maximum angle in degrees (threshold 120°).
    pub max_angle_deg: Statistics,
}

impl TriangleQuality {
    /// Quality of the triangles `triangles` over `vertices`.
    ///
    /// ```
    /// use imesh_quality::TriangleQuality;
    /// let q = TriangleQuality::of(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], &[[0, 1, 2]]);
    /// assert!((q.min_angle_deg.min - 45.0).abs() < 1e-12);
    /// ```
    pub fn of(vertices: &[Point2], triangles: &[[u32; 3]]) -> Self {
        let t: Vec<tri::Triangle> = triangles
            .iter()
            .map(|t| t.map(|v| vertices[v as usize]))
            .collect();
        let column = |f: fn(&tri::Triangle) -> f64| t.par_iter().map(f).collect::<Vec<f64>>();
        Self {
            shape: Statistics::of(&column(tri::shape), 0.3),
            scaled_jacobian: Statistics::of(&column(tri::scaled_jacobian), 0.3),
            min_angle_deg: Statistics::of(&column(tri::minimum_angle), 30.0),
            max_angle_deg: Statistics::of(&column(tri::maximum_angle), 120.0),
        }
    }
}
