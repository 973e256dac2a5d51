//! The quality the energy is built on, and the validity of one quad.

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use imesh_quality::quad;

/// The quality `s` the energy is built on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Metric {
    /// Verdict's shape-and-size against the mesh's (fixed) average quad area: shape and
    /// uniform size (the paper's choice).
    #[default]
    ShapeAndSize,
    /// Verdict's shape alone: size is left free.
    Shape,
}

impl Metric {
    /// The metric's value for the quad `p` (counter-clockwise corners), `average_area` being the
    /// mesh's mean quad area.
    ///
    /// ```
    /// use imesh_geom::Point;
    /// use imesh_optim::Metric;
    /// let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(Point::from);
    /// assert_eq!(Metric::Shape.value(&square, 4.0), 1.0);
    /// assert_eq!(Metric::ShapeAndSize.value(&square, 4.0), 1.0 / 16.0);
    /// ```
    pub fn value(self, p: &[Point; 4], average_area: f64) -> f64 {
        let q = p.map(|p| [p.x, p.y]);
        match self {
            Metric::ShapeAndSize => quad::shape_and_size(&q, average_area),
            Metric::Shape => quad::shape(&q),
        }
    }
}

/// True when the quad `p` has a positive Jacobian at all four corners (exact orientation).
#[inline]
pub fn is_valid(p: &[Point; 4]) -> bool {
    (0..4).all(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]) > 0.0)
}
