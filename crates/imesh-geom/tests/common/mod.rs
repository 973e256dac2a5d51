//! Shared helpers of the geometry tests: polygons and point-in-polygon.

use imesh_geom::{Point, TriangleId, Triangulation};

/// A star-shaped polygon around `c` (vertex `i` at angle 2πi/n, radius `radii[i]`), its vertices
/// rounded to multiples of 1/64: imesh's boundaries lie on a dyadic lattice (pixel centres and
/// their midpoints), where midpoint splits are exact.
pub fn star(c: Point, radii: &[f64]) -> Vec<Point> {
    let n = radii.len();
    let snap = |v: f64| (v * 64.0).round() / 64.0;
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            Point::new(
                snap(c.x + radii[i] * a.cos()),
                snap(c.y + radii[i] * a.sin()),
            )
        })
        .collect()
}

/// Even-odd point-in-polygon test.
pub fn inside(poly: &[Point], p: Point) -> bool {
    let mut inside = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// The centroid of triangle `f`.
pub fn centroid(t: &Triangulation, f: TriangleId) -> Point {
    let [a, b, c] = t.triangle_points(f);
    Point::new((a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0)
}
