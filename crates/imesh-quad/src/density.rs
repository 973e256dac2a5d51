//! A uniform DT': boundary pieces and an inside lattice of one spacing (DESIGN.md §2, step 6).
//!
//! Shape-and-size compares every quad with the mesh's mean quad area, so a DT' graded from short
//! boundary pieces to a coarse inside scores low however well shaped its elements are. Here every
//! boundary is split into pieces of at most 1.5 spacings (along a strip too thin for the lattice,
//! as long as the strip is deep), and the inside is filled with an axis-aligned square lattice of
//! that spacing, kept clear of the boundaries. Pairing joins the lattice's triangles back into its
//! squares (their diagonal is their longest edge), which the templates cut into squares: the
//! inside becomes a grid of equal squares, and only a band along the boundaries is left to
//! refinement.

use imesh_curves::{segment_distance, SegmentIndex};
use imesh_geom::{GeomError, Location, Point, Triangulation, VertexId, EXTERIOR};

/// How narrow a strip between two boundaries is, in spacings, for its boundary pieces to be
/// cut to its depth ([`uniform_points`], step 2). A strip narrower than about twice the
/// lattice's [`CLEARANCE`] gets no lattice point: DT' spans it from boundary to boundary, and
/// the templates give it two rows of quads, each half the strip deep and half a boundary piece
/// long. With pieces of up to [`BOUNDARY_PIECE`] spacings they were up to 1.5 times the mean
/// quad's area and elongated along the strip (brick's mortar, 4.3 px wide at quads of 2 px,
/// scored 0.2–0.5). Measured with the defaults on nine fixtures (all but aloe), mean
/// shape-and-size: brick 0.8014 → 0.8157, pyvista 0.8725 → 0.8763, grass 0.6907 → 0.6955,
/// gravel 0.7026 → 0.7064, MRI 0.9113 → 0.9086, coins 0.8683 → 0.8673, coffee 0.9143 → 0.9138,
/// camera and stardist equal; worst shape pyvista 0.474 → 0.500 and coffee 0.430 → 0.437, but
/// grass 0.422 → 0.347; scikit-image's `microaneurysms` (thin vessels, not a fixture) 0.809 →
/// 0.830. At 1.1 brick gained 0.006, at 1.3 0.018 (MRI 0.9069, grass's worst scaled Jacobian
/// 0.492 → 0.428).
pub const STRIP: f64 = 1.2;

/// How far a lattice point stays from every boundary piece, in spacings: nearer, it would make a
/// thin triangle with the piece; farther, the band it leaves needs more refinement.
pub const CLEARANCE: f64 = 0.6;

/// The longest boundary piece, in spacings. The triangle between a piece of length `b` and the
/// lattice (at least [`CLEARANCE`] spacings away) has an area of about `b · 0.8 s / 2`: at one
/// spacing that is 0.4 s², so the band of quads along every boundary would be 20 % smaller than
/// the lattice's (0.5 s² per triangle) and score only (0.8)² in relative size; at 1.5 spacings
/// it is about the lattice's (measured: mean shape-and-size 0.79 → 0.90 on the MRI fixture).
pub const BOUNDARY_PIECE: f64 = 1.5;

/// Puts the points of a uniform DT' of `spacing` into `t` (a labelled triangulation whose
/// segments are the boundaries, its hull usually an axis-aligned rectangle), and returns how
/// many were inserted:
///
/// 1. the lattice points on the hull that are clear of every other boundary (they split the
///    border segments, so that the lattice meets the border square on);
/// 2. equal splits of every segment piece along a strip narrower than [`STRIP`] spacings
///    into pieces about as long as the strip is deep, then of every piece still longer than
///    [`BOUNDARY_PIECE`] spacings;
/// 3. the lattice points inside the domain (within the hull, not in an [`EXTERIOR`] hole of a
///    labelled triangulation) that are clear of every segment piece.
///
/// The lattice's spacing along x and y is the nearest that divides the domain's width and height.
///
/// ```
/// use imesh_geom::{Point, Triangulation};
/// use imesh_quad::uniform_points;
/// let corners = [Point::new(0.0, 0.0), Point::new(12.0, 0.0), Point::new(12.0, 8.0), Point::new(0.0, 8.0)];
/// let (mut t, v) = Triangulation::from_points(&corners).unwrap();
/// for k in 0..4 {
///     t.insert_segment(v[k], v[(k + 1) % 4]).unwrap();
/// }
/// t.set_labels(|_| 0);
/// // A 12 × 8 rectangle at spacing 2: a 7 × 5 lattice, all of it.
/// assert_eq!(uniform_points(&mut t, 2.0).unwrap(), 7 * 5 - 4);
/// assert_eq!(t.num_triangles(), 2 * 6 * 4);
/// t.check().unwrap();
/// ```
///
/// # Errors
/// [`GeomError`] from an insertion (it cannot happen for a valid triangulation).
pub fn uniform_points(t: &mut Triangulation, spacing: f64) -> Result<usize, GeomError> {
    uniform_points_with_lattice(t, spacing, spacing)
}

/// [`uniform_points`] with a lattice of its own spacing, `lattice`: the boundary pieces follow
/// `spacing`, the lattice and its clearance `lattice`. A lattice a little coarser than the
/// boundary pieces makes the inside's quads as large as the mesh's mean quad where the band
/// along the boundaries holds many small ones.
///
/// ```
/// use imesh_geom::{Point, Triangulation};
/// use imesh_quad::uniform_points_with_lattice;
/// let corners = [Point::new(0.0, 0.0), Point::new(12.0, 0.0), Point::new(12.0, 8.0), Point::new(0.0, 8.0)];
/// let (mut t, v) = Triangulation::from_points(&corners).unwrap();
/// for k in 0..4 {
///     t.insert_segment(v[k], v[(k + 1) % 4]).unwrap();
/// }
/// t.set_labels(|_| 0);
/// // A lattice of 4: 4 × 3 points, 8 of them new (not the corners); its border points cut
/// // the sides into pieces of 4, each split once to stay within 1.5 × 2: 10 more.
/// assert_eq!(uniform_points_with_lattice(&mut t, 2.0, 4.0).unwrap(), (4 * 3 - 4) + 10);
/// t.check().unwrap();
/// ```
///
/// # Errors
/// As [`uniform_points`].
pub fn uniform_points_with_lattice(
    t: &mut Triangulation,
    spacing: f64,
    lattice: f64,
) -> Result<usize, GeomError> {
    let before = t.num_vertices();
    if !(spacing.is_finite() && spacing > 0.0 && lattice.is_finite() && lattice > 0.0)
        || t.is_degenerate()
    {
        return Ok(0);
    }
    let piece = spacing;
    let spacing = lattice;
    let lattice = Lattice::new(t, spacing);
    let reach = CLEARANCE * spacing;

    // 1. The border.
    let grid = EdgeGrid::new(t, reach);
    let mut border = Vec::new();
    for (i, j) in lattice.border() {
        let p = lattice.point(i, j);
        let clear = grid.clear(p, reach, |[a, b]| {
            // A piece of the same border side counts by its ends only: the point lies on it.
            let side = |q: Point| {
                (q.x == p.x && (p.x == lattice.lo.x || p.x == lattice.hi.x))
                    || (q.y == p.y && (p.y == lattice.lo.y || p.y == lattice.hi.y))
            };
            if side(a) && side(b) {
                a.distance_squared(p).min(b.distance_squared(p)).sqrt()
            } else {
                segment_distance(a, b, p)
            }
        });
        // Only on the hull itself: a domain that is not the full rectangle keeps its shape.
        let on_hull = match t.locate(p) {
            Location::OnEdge(h) => t.neighbour(h).is_none() || t.neighbour(t.twin(h)).is_none(),
            _ => false,
        };
        if clear && on_hull {
            border.push(p);
        }
    }
    for p in border {
        t.insert(p)?;
    }

    // 2. The boundaries: along a strip too thin for the lattice, pieces as long as the strip
    // is deep; elsewhere, at most [`BOUNDARY_PIECE`] spacings.
    let splits = strip_splits(t, piece);
    t.split_segment_pieces(&splits)?;
    t.split_long_segments(BOUNDARY_PIECE * piece)?;

    // 3. The inside.
    let grid = EdgeGrid::new(t, reach);
    let labelled = t.triangles().any(|f| t.label(f) != EXTERIOR);
    for j in 1..lattice.n[1] {
        for i in 1..lattice.n[0] {
            let p = lattice.point(i, j);
            if grid.clear(p, reach, |[a, b]| segment_distance(a, b, p)) && inside(t, p, labelled) {
                t.insert(p)?;
            }
        }
    }
    Ok(t.num_vertices() - before)
}

/// True when `p` lies in the domain: inside the hull, and not in a triangle labelled
/// [`EXTERIOR`] (a hole) unless no triangle has a label (then, as for refinement, all are in).
fn inside(t: &Triangulation, p: Point, labelled: bool) -> bool {
    let labelled_in = |f| !labelled || t.label(f) != EXTERIOR;
    match t.locate(p) {
        Location::InTriangle(f) => labelled_in(f),
        Location::OnEdge(h) => labelled_in(t.triangle_of(h)),
        Location::OnVertex(_) | Location::OutsideHull(_) | Location::NoTriangles => false,
    }
}

/// How many points the lattice of `spacing` has over the bounding box of `t`'s points (at
/// most; those near boundaries are left out).
pub(crate) fn lattice_points(t: &Triangulation, spacing: f64) -> u64 {
    if !(spacing.is_finite() && spacing > 0.0) || t.num_vertices() == 0 {
        return 0;
    }
    let [nx, ny] = Lattice::new(t, spacing).n;
    (nx as u64 + 1) * (ny as u64 + 1)
}

/// The bounding box of the triangulation's points.
fn bounds(t: &Triangulation) -> (Point, Point) {
    let (mut lo, mut hi) = (t.points()[0], t.points()[0]);
    for p in t.points() {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    (lo, hi)
}

/// The square lattice over the domain's bounding box.
struct Lattice {
    lo: Point,
    hi: Point,
    /// Cells along x and y.
    n: [usize; 2],
    /// Spacing along x and y.
    step: [f64; 2],
}

impl Lattice {
    fn new(t: &Triangulation, spacing: f64) -> Self {
        let (lo, hi) = bounds(t);
        let cells = |extent: f64| (extent / spacing).round().clamp(1.0, 1e7) as usize;
        let n = [cells(hi.x - lo.x), cells(hi.y - lo.y)];
        Self {
            lo,
            hi,
            n,
            step: [(hi.x - lo.x) / n[0] as f64, (hi.y - lo.y) / n[1] as f64],
        }
    }

    /// Lattice point (i, j); the last row and column land exactly on the far border.
    fn point(&self, i: usize, j: usize) -> Point {
        let along = |k: usize, n: usize, lo: f64, hi: f64, step: f64| {
            if k == n {
                hi
            } else {
                lo + k as f64 * step
            }
        };
        Point::new(
            along(i, self.n[0], self.lo.x, self.hi.x, self.step[0]),
            along(j, self.n[1], self.lo.y, self.hi.y, self.step[1]),
        )
    }

    /// The lattice points on the border, corners excepted.
    fn border(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let [nx, ny] = self.n;
        let rows = (1..nx).flat_map(move |i| [(i, 0), (i, ny)]);
        let columns = (1..ny).flat_map(move |j| [(0, j), (nx, j)]);
        rows.chain(columns)
    }
}

/// The constrained edges along a strip too thin for the lattice, with the number of equal
/// pieces to cut each into so that the strip's two rows of quads are about as long as they are
/// deep: pieces of length `b` across a strip `H` wide make quads of about `b/2 × H/2`, the mean
/// quad's area (a quarter of a squared spacing `s²`) at `b = s² / H`. An edge runs along a strip
/// where at least three quarters of the points sampled along it (every half spacing) have
/// another boundary piece nearer than [`STRIP`] spacings, within 30° of parallel to it and
/// sharing no end with it; `H` is the median of those distances. The whole edge is cut (a G'
/// edge at this step): cutting the pieces [`BOUNDARY_PIECE`] leaves in two made them too short.
fn strip_splits(t: &Triangulation, spacing: f64) -> Vec<(VertexId, VertexId, usize)> {
    let reach = STRIP * spacing;
    let grid = EdgeGrid::new(t, reach);
    let ends = &grid.edges;
    // tan 30°: another piece within 30° of parallel has |cross| < tan 30° · |dot|.
    const PARALLEL: f64 = 0.577_350_269_189_625_8;
    let mut splits = Vec::new();
    // The grid lists the constrained edges in this order.
    for (k, h) in t.constrained_edges().enumerate() {
        let [pa, pb] = ends[k];
        let d = pb - pa;
        let length = pa.distance_squared(pb).sqrt();
        if length.is_nan() || length <= 0.0 {
            continue;
        }
        let across = |j: u32| {
            let [pc, pe] = ends[j as usize];
            let f = pe - pc;
            j as usize != k
                && ![pc, pe].iter().any(|&x| x == pa || x == pb)
                && (f.x * d.y - f.y * d.x).abs() < PARALLEL * (f.x * d.x + f.y * d.y).abs()
        };
        let samples = (length / (0.5 * spacing)).ceil() as usize;
        let mut heights: Vec<f64> = (0..samples)
            .map(|i| {
                let p = pa + d * ((i as f64 + 0.5) / samples as f64);
                grid.index
                    .near(p)
                    .filter(|&j| across(j))
                    .map(|j| {
                        let [pc, pe] = ends[j as usize];
                        segment_distance(pc, pe, p)
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .filter(|&h| h < reach)
            .collect();
        if heights.len() * 4 < samples * 3 {
            continue;
        }
        heights.sort_by(f64::total_cmp);
        let height = heights[heights.len() / 2];
        // No piece shorter than a quad side: quads at least half a side long.
        let ideal = (spacing * spacing / height).max(0.5 * spacing);
        let longest = (length / (BOUNDARY_PIECE * spacing)).ceil();
        let pieces = (length / ideal).round();
        if pieces > longest.max(1.0) {
            splits.push((t.origin(h), t.destination(h), pieces as usize));
        }
    }
    splits
}

/// The triangulation's segment pieces, indexed for "is any within `reach`?".
struct EdgeGrid {
    edges: Vec<[Point; 2]>,
    index: SegmentIndex,
}

impl EdgeGrid {
    fn new(t: &Triangulation, reach: f64) -> Self {
        let edges: Vec<[Point; 2]> = t
            .constrained_edges()
            .map(|h| [t.point(t.origin(h)), t.point(t.destination(h))])
            .collect();
        let index = SegmentIndex::new(&edges, reach);
        Self { edges, index }
    }

    /// True when every piece near `p` is at least `reach` away by `distance`.
    fn clear(&self, p: Point, reach: f64, distance: impl Fn([Point; 2]) -> f64) -> bool {
        self.index
            .near(p)
            .all(|k| distance(self.edges[k as usize]) >= reach)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip 4.4 wide across a 40 × 20 domain at spacing 4 (no lattice point fits in it): its
    /// two boundaries are cut into pieces about as long as the strip is deep (16 / 4.4 ≈ 3.6,
    /// eleven of them, where the 1.5-spacing rule alone gives seven of 5.7), and the borders,
    /// farther from any parallel boundary, keep the lattice's pieces.
    #[test]
    fn a_thin_strip_gets_pieces_as_long_as_it_is_deep() {
        let corners = [(0.0, 0.0), (40.0, 0.0), (40.0, 20.0), (0.0, 20.0)];
        let strip = [(0.0, 8.0), (40.0, 8.0), (40.0, 12.4), (0.0, 12.4)];
        let points: Vec<Point> = corners
            .iter()
            .chain(&strip)
            .map(|&p| Point::from(p))
            .collect();
        let (mut t, v) = Triangulation::from_points(&points).unwrap();
        for (a, b) in [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (7, 6)] {
            t.insert_segment(v[a], v[b]).unwrap();
        }
        t.label_regions(&[
            (Point::new(20.0, 4.0), 0),
            (Point::new(20.0, 10.0), 1),
            (Point::new(20.0, 16.0), 2),
        ]);
        uniform_points(&mut t, 4.0).unwrap();
        t.check().unwrap();
        let pieces_along = |y: f64| -> Vec<f64> {
            t.constrained_edges()
                .map(|h| [t.point(t.origin(h)), t.point(t.destination(h))])
                .filter(|[a, b]| a.y == y && b.y == y)
                .map(|[a, b]| a.distance_squared(b).sqrt())
                .collect()
        };
        for y in [8.0, 12.4] {
            let pieces = pieces_along(y);
            assert_eq!(pieces.len(), 11, "{y}: {pieces:?}");
            assert!(
                pieces.iter().all(|&l| (l - 40.0 / 11.0).abs() < 1e-9),
                "{pieces:?}"
            );
        }
        let border = pieces_along(0.0);
        assert_eq!(border.len(), 10, "{border:?}");
        assert!(border.iter().all(|&l| (l - 4.0).abs() < 1e-9), "{border:?}");
    }

    /// A domain that is not its bounding rectangle (a right triangle with a square hole labelled
    /// [`EXTERIOR`]): no point lands outside the hull or in the hole, the hull keeps its area, and
    /// the inside still gets lattice points.
    #[test]
    fn a_non_rectangular_domain_keeps_its_shape() {
        let corners = [
            Point::new(0.0, 0.0),
            Point::new(30.0, 0.0),
            Point::new(0.0, 30.0),
            Point::new(4.0, 4.0),
            Point::new(10.0, 4.0),
            Point::new(10.0, 10.0),
            Point::new(4.0, 10.0),
        ];
        let domain = || {
            let (mut t, v) = Triangulation::from_points(&corners).unwrap();
            for (a, b) in [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 6), (6, 3)] {
                t.insert_segment(v[a], v[b]).unwrap();
            }
            t
        };
        let mut t = domain();
        t.label_regions(&[(Point::new(15.0, 5.0), 1), (Point::new(7.0, 7.0), EXTERIOR)]);
        let area = |t: &Triangulation| t.triangles().map(|f| t.signed_area(f)).sum::<f64>();
        let before = area(&t);
        let inserted = uniform_points(&mut t, 2.0).unwrap();
        assert!(inserted > 20, "{inserted} points");
        t.check().unwrap();
        assert!((area(&t) - before).abs() < 1e-9 * before);
        // Unlabelled, the same domain is filled everywhere inside the hull, hole included.
        let mut u = domain();
        uniform_points(&mut u, 2.0).unwrap();
        assert!(u
            .points()
            .iter()
            .any(|p| p.x > 4.0 && p.x < 10.0 && p.y > 4.0 && p.y < 10.0));
        for p in t.points() {
            assert!(
                p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 30.0 + 1e-9,
                "{p:?} off the hull"
            );
            let in_hole = p.x > 4.0 && p.x < 10.0 && p.y > 4.0 && p.y < 10.0;
            assert!(!in_hole, "{p:?} in the hole");
        }
    }
}
