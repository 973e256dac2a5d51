//! The worst corner the boundaries force: a quad corner held between two boundary edges (a label
//! boundary or the domain's border) fills a whole sector of its region at a boundary vertex, so
//! no smoothing that keeps the boundaries can change its angle, and its sine bounds the mesh's
//! worst scaled Jacobian.

use rayon::slice::ParallelSliceMut;
use serde::Serialize;

use crate::Point2;

/// A quad corner between two boundary edges: the one with the smallest signed sine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BoundaryCorner {
    /// The corner's signed sine (its scaled Jacobian at that corner): the mesh's worst scaled
    /// Jacobian is at most this.
    pub scaled_jacobian: f64,
    /// The corner's angle in degrees.
    pub angle_deg: f64,
    /// Where it is (the corner vertex).
    pub at: Point2,
}

/// The boundary corner with the smallest sine among `quads` (counter-clockwise, over
/// `vertices`, one label per quad), or `None` when no corner lies between two boundary edges.
/// An edge is a boundary edge when one quad has it, or two of different labels.
///
/// ```
/// use imesh_quality::sharpest_boundary_corner;
/// // Two unit squares side by side, one label: the four outer corners are each between two
/// // border edges (90°); the middle vertices are not.
/// let v = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0]];
/// let c = sharpest_boundary_corner(&v, &[[0, 1, 4, 3], [1, 2, 5, 4]], &[0, 0]).unwrap();
/// assert!((c.scaled_jacobian - 1.0).abs() < 1e-15 && (c.angle_deg - 90.0).abs() < 1e-12);
/// ```
pub fn sharpest_boundary_corner(
    vertices: &[Point2],
    quads: &[[u32; 4]],
    labels: &[u32],
) -> Option<BoundaryCorner> {
    // Every quad side as (smaller end << 32 | larger end, label, side 4q + k), sorted so that
    // an edge's sides are neighbours: it is a boundary edge when it has one, or two of
    // different labels, and each side is marked so.
    let mut sides: Vec<(u64, u32, u32)> = quads
        .iter()
        .zip(labels)
        .enumerate()
        .flat_map(|(i, (q, &label))| {
            (0..4).map(move |k| {
                let (a, b) = (q[k], q[(k + 1) % 4]);
                (crate::validate::edge_key(a, b), label, (4 * i + k) as u32)
            })
        })
        .collect();
    sides.par_sort_unstable_by_key(|s| s.0);
    let mut boundary = vec![false; 4 * quads.len()];
    for edge in sides.chunk_by(|x, y| x.0 == y.0) {
        if edge.len() == 1 || edge.iter().any(|s| s.1 != edge[0].1) {
            for s in edge {
                boundary[s.2 as usize] = true;
            }
        }
    }
    let mut sharpest: Option<BoundaryCorner> = None;
    for (i, q) in quads.iter().enumerate() {
        for k in 0..4 {
            let (prev, v, next) = (q[(k + 3) % 4], q[k], q[(k + 1) % 4]);
            // Side k runs v → next, side k − 1 prev → v.
            if !(boundary[4 * i + (k + 3) % 4] && boundary[4 * i + k]) {
                continue;
            }
            let (p, c, n) = (
                vertices[prev as usize],
                vertices[v as usize],
                vertices[next as usize],
            );
            let (a, b) = ([n[0] - c[0], n[1] - c[1]], [p[0] - c[0], p[1] - c[1]]);
            let lengths = ((a[0] * a[0] + a[1] * a[1]) * (b[0] * b[0] + b[1] * b[1])).sqrt();
            if lengths <= 0.0 {
                continue;
            }
            let cross = a[0] * b[1] - a[1] * b[0];
            let sine = cross / lengths;
            if sharpest.is_none_or(|s| sine < s.scaled_jacobian) {
                let dot = a[0] * b[0] + a[1] * b[1];
                sharpest = Some(BoundaryCorner {
                    scaled_jacobian: sine,
                    angle_deg: cross.atan2(dot).to_degrees(),
                    at: c,
                });
            }
        }
    }
    sharpest
}

#[cfg(test)]
mod tests {
    use super::sharpest_boundary_corner;

    /// Two quads of different labels around a vertex on the border: the label boundary between
    /// them and the border make each quad's corner there a boundary corner (30° and 150°, both
    /// of sine 0.5), the first reported; with one label the shared side is interior and the
    /// sharpest corner is elsewhere (113°).
    #[test]
    fn the_sharper_sector_at_a_boundary_vertex() {
        let s = 30f64.to_radians();
        // Border along y = 0; the two quads meet along the ray at 30° from the origin.
        let v = [
            [0.0, 0.0],
            [3.0, 0.0],
            [3.5, 1.2],
            [3.0 * s.cos(), 3.0 * s.sin()],
            [-3.0, 3.0],
            [-3.0, 0.0],
        ];
        let quads = [[0, 1, 2, 3], [0, 3, 4, 5]];
        let c = sharpest_boundary_corner(&v, &quads, &[0, 1]).unwrap();
        assert!((c.angle_deg - 30.0).abs() < 1e-9, "{c:?}");
        assert!((c.scaled_jacobian - 0.5).abs() < 1e-12);
        assert_eq!(c.at, [0.0, 0.0]);
        let one = sharpest_boundary_corner(&v, &quads, &[0, 0]).unwrap();
        assert!(one.angle_deg > 30.0 + 1e-6, "{one:?}");
        assert_ne!(one.at, [0.0, 0.0]);
    }
}
