//! Imesh step 1: median-error sampling of a label grid (DESIGN.md §2, step 2).
//!
//! A triangle is judged by the pixels along its three medians: where the label changes along a
//! median, the image has a boundary inside the triangle. The deeper such a pixel lies in the
//! triangle (the larger its smallest barycentric coordinate), the worse the triangle represents
//! the image; the deepest one is inserted. Vertices only ever land on pixel centres, each at most
//! once, so sampling stops after at most W·H insertions.

use imesh_classify::LabelGrid;
use imesh_geom::{Point, TriangleId, Triangulation, VertexId};
use rayon::prelude::*;

use crate::traverse::{touched_pixels, Quarter};
use crate::SegmentError;

/// Parameters of [`sample`].
#[derive(Clone, Debug, PartialEq)]
pub struct SampleOptions {
    /// Error threshold `t_e` in [0, 1): a triangle whose median error exceeds it is split.
    /// Smaller values give more vertices and a closer fit. Default 0.1.
    pub te: f64,
    /// Most vertices to insert (default: unlimited).
    pub max_vertices: usize,
}

impl Default for SampleOptions {
    fn default() -> Self {
        Self {
            te: 0.1,
            max_vertices: usize::MAX,
        }
    }
}

/// The result of [`sample`].
#[derive(Clone, Debug)]
pub struct Sampling {
    /// The Delaunay triangulation of the four domain corners and the inserted points.
    pub triangulation: Triangulation,
    /// Points inserted: the label changes along the border (see [`sample`]), then pixel centres.
    pub inserted: usize,
    /// Rounds of parallel evaluation.
    pub rounds: usize,
    /// True when `max_vertices` stopped sampling early.
    pub capped: bool,
}

/// The worst pixel of a triangle: its error `3·min λ` and the pixel index `row·W + col`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MedianError {
    /// `e(σ)`: the largest normalised smallest barycentric coordinate over the label-change pixels
    /// of the medians (0 when there are none).
    pub error: f64,
    /// The pixel reaching it (`u32::MAX` when there is none).
    pub pixel: u32,
}

/// A triangle's vertices in half-pixel units (pixel centres and corners are integers there).
pub(crate) fn doubled(p: [Point; 3]) -> [[i64; 2]; 3] {
    p.map(|q| [(2.0 * q.x).round() as i64, (2.0 * q.y).round() as i64])
}

/// The three medians of a triangle given in half-pixel units, as quarter-pixel segments from each
/// vertex to the midpoint of the opposite edge.
pub(crate) fn medians(v: [[i64; 2]; 3]) -> [(Quarter, Quarter); 3] {
    std::array::from_fn(|k| {
        let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        ([2 * a[0], 2 * a[1]], [b[0] + c[0], b[1] + c[1]])
    })
}

/// `e(σ)` for the triangle with corners `p` (pixel centres or domain corners).
///
/// ```
/// use imesh_classify::{LabelGrid, Region};
/// use imesh_geom::Point;
/// use imesh_segment::median_error;
/// // A 4×4 grid whose right half is label 1; the triangle covers the whole grid.
/// let labels = (0..16).map(|i| u32::from(i % 4 >= 2)).collect();
/// let regions = vec![Region { name: "a".into(), colour: [0; 3] }, Region { name: "b".into(), colour: [255; 3] }];
/// let grid = LabelGrid::new(4, 4, labels, regions).unwrap();
/// let e = median_error(&grid, [Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(0.0, 4.0)]);
/// assert!(e.error > 0.0 && e.error <= 1.0);
/// ```
pub fn median_error(grid: &LabelGrid, p: [Point; 3]) -> MedianError {
    let v = doubled(p);
    let (w, h) = (grid.width(), grid.height());
    let labels = grid.labels();
    // Twice the signed area, in half-pixel units: the barycentric denominator.
    let orient = |a: [i64; 2], b: [i64; 2], c: [i64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let area = orient(v[0], v[1], v[2]);
    let mut best = MedianError {
        error: 0.0,
        pixel: u32::MAX,
    };
    if area == 0 {
        return best;
    }
    for (a, b) in medians(v) {
        let mut previous = u32::MAX;
        touched_pixels(a, b, w, h, |c, r| {
            let index = r * w + c;
            let label = labels[index as usize];
            let changed = previous != u32::MAX && label != previous;
            previous = label;
            if !changed {
                return;
            }
            let q = [2 * i64::from(c) + 1, 2 * i64::from(r) + 1];
            let lambda = [
                orient(v[1], v[2], q),
                orient(v[2], v[0], q),
                orient(v[0], v[1], q),
            ];
            let min = *lambda.iter().min().unwrap_or(&0);
            let error = 3.0 * min as f64 / area as f64;
            if error > best.error || (error == best.error && error > 0.0 && index < best.pixel) {
                best = MedianError {
                    error,
                    pixel: index,
                };
            }
        });
    }
    best
}

/// The points of the domain border between two neighbouring border pixels of different labels.
fn border_changes(grid: &LabelGrid) -> Vec<Point> {
    let (w, h) = (grid.width(), grid.height());
    let (fw, fh) = (f64::from(w), f64::from(h));
    let mut points = Vec::new();
    for c in 1..w {
        if grid.label(c - 1, 0) != grid.label(c, 0) {
            points.push(Point::new(f64::from(c), 0.0));
        }
        if grid.label(c - 1, h - 1) != grid.label(c, h - 1) {
            points.push(Point::new(f64::from(c), fh));
        }
    }
    for r in 1..h {
        if grid.label(0, r - 1) != grid.label(0, r) {
            points.push(Point::new(0.0, f64::from(r)));
        }
        if grid.label(w - 1, r - 1) != grid.label(w - 1, r) {
            points.push(Point::new(fw, f64::from(r)));
        }
    }
    points
}

/// Samples the label grid: starting from the triangulation of the domain's corners and the
/// label changes along its border, inserts the worst pixel centre of every triangle whose median
/// error exceeds `te`, round after round, until none does.
///
/// The border points sit on the border between two border pixels of different labels. Without
/// them the border has no vertex but the corners: the triangles along it reach from a corner to
/// pixel centres half a pixel inside, and take one label over a whole side, so that every region
/// touching the border is cut off from it by a strip half a pixel wide (and its boundary ends in a
/// needle at the corner).
///
/// Each round evaluates the triangles the previous round created, in parallel, then inserts their
/// worst pixels one after another in a fixed order (largest error first, then pixel index),
/// skipping a triangle an earlier insertion of the round destroyed (its replacements are evaluated
/// next round). The result does not depend on the number of threads.
///
/// # Errors
/// [`SegmentError::BadThreshold`] for `te` outside [0, 1); [`SegmentError::EmptyGrid`] for a
/// grid without pixels.
///
/// ```
/// use imesh_classify::{LabelGrid, Region};
/// use imesh_segment::{sample, SampleOptions};
/// let labels = (0..64).map(|i| u32::from((i % 8) * (i % 8) + (i / 8) * (i / 8) < 20)).collect();
/// let regions = vec![Region { name: "out".into(), colour: [0; 3] }, Region { name: "in".into(), colour: [255; 3] }];
/// let grid = LabelGrid::new(8, 8, labels, regions).unwrap();
/// let s = sample(&grid, &SampleOptions::default()).unwrap();
/// assert!(s.inserted > 0);
/// assert_eq!(s.triangulation.num_vertices(), 4 + s.inserted);
/// ```
pub fn sample(grid: &LabelGrid, options: &SampleOptions) -> Result<Sampling, SegmentError> {
    if !(0.0..1.0).contains(&options.te) {
        return Err(SegmentError::BadThreshold { te: options.te });
    }
    let (w, h) = (grid.width(), grid.height());
    if w == 0 || h == 0 {
        return Err(SegmentError::EmptyGrid);
    }
    let (fw, fh) = (f64::from(w), f64::from(h));
    let corners = [
        Point::new(0.0, 0.0),
        Point::new(fw, 0.0),
        Point::new(fw, fh),
        Point::new(0.0, fh),
    ];
    let border = border_changes(grid);
    let mut start = corners.to_vec();
    start.extend_from_slice(&border);
    let (mut tri, _) = Triangulation::from_points(&start)?;
    let mut used = vec![false; w as usize * h as usize];
    let mut pending: Vec<TriangleId> = tri.triangles().collect();
    let (mut inserted, mut rounds, mut capped) = (border.len(), 0usize, false);
    while !pending.is_empty() {
        rounds += 1;
        let evaluated: Vec<(TriangleId, [VertexId; 3], MedianError)> = pending
            .par_iter()
            .map(|&t| {
                (
                    t,
                    tri.triangle_vertices(t),
                    median_error(grid, tri.triangle_points(t)),
                )
            })
            .collect();
        let mut worst: Vec<_> = evaluated
            .into_iter()
            .filter(|(_, _, e)| e.error > options.te && e.pixel != u32::MAX)
            .collect();
        worst.sort_by(|x, y| {
            y.2.error
                .total_cmp(&x.2.error)
                .then(x.2.pixel.cmp(&y.2.pixel))
        });
        let mut created: Vec<TriangleId> = Vec::new();
        for (t, vertices, e) in worst {
            if inserted >= options.max_vertices {
                capped = true;
                break;
            }
            // The triangle must still be the one evaluated (slots are reused by insertions).
            if !tri.is_triangle(t) || tri.triangle_vertices(t) != vertices {
                continue;
            }
            if std::mem::replace(&mut used[e.pixel as usize], true) {
                continue;
            }
            let (c, r) = (e.pixel % w, e.pixel / w);
            let p = Point::new(f64::from(c) + 0.5, f64::from(r) + 0.5);
            tri.insert_near(p, t)?;
            inserted += 1;
            created.extend_from_slice(tri.created_triangles());
        }
        if capped {
            break;
        }
        created.sort_unstable();
        created.dedup();
        pending = created;
    }
    Ok(Sampling {
        triangulation: tri,
        inserted,
        rounds,
        capped,
    })
}
