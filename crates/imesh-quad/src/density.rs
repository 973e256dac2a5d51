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
/// 1. the points where the lattice lines cross an axis-parallel boundary piece (the border's
///    and those inside) that are clear of every other piece, so that the lattice meets them
///    square on (split with [`Triangulation::split_piece_at`]);
/// 2. equal splits of every segment piece along a strip narrower than [`STRIP`] spacings
///    into pieces about as long as the strip is deep (along a strip within 5° of an axis,
///    splits where the lattice's lines cross both its sides), then of every piece still
///    longer than [`BOUNDARY_PIECE`] spacings;
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

    // 1. The border and the axis-parallel boundaries.
    let crossings = axis_crossings(t, &lattice, reach);
    split_at_points(t, crossings)?;

    // 2. The boundaries: along a strip too thin for the lattice, pieces as long as the strip
    // is deep (a strip along an axis on the lattice's lines, the same on both sides);
    // elsewhere, at most [`BOUNDARY_PIECE`] spacings.
    let StripSplits { equal, at_lines } = strip_splits(t, piece, &lattice);
    split_at_points(t, at_lines)?;
    t.split_segment_pieces(&equal)?;
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

/// Splits each constrained piece `u w` at its points, given in order from `u`.
fn split_at_points(
    t: &mut Triangulation,
    splits: Vec<(VertexId, VertexId, Vec<Point>)>,
) -> Result<(), GeomError> {
    for (u, w, points) in splits {
        let mut at = u;
        for p in points {
            if let Some(v) = t.split_piece_at(at, w, p)? {
                at = v;
            }
        }
    }
    Ok(())
}

/// The points where the lattice lines cross the axis-parallel boundary pieces (the border's,
/// and those inside the domain) and that are `reach` clear of every other piece: per piece
/// `u w`, its crossings in order from `u`, so that each lies on what the previous split left
/// of it ([`Triangulation::split_piece_at`]).
///
/// A boundary along a lattice row or column, cut where the lattice lines cross it, makes
/// rectangles with the lattice points beside it, which pairing joins into quads whose every
/// corner is square. The border always was; an axis-parallel boundary inside was cut into
/// equal pieces instead (until session 45), and its band was left to refinement, whose triangles pair into skewed quads
/// and leave unpaired ones: stripes 40 px wide at quads of 3.6 px scored a mean
/// shape-and-size of 0.857 with a worst scaled Jacobian of 0.509 and 542 unpaired triangles,
/// against 0.865, 1 (every quad a rectangle) and none. Over 42 images (the fixtures but aloe,
/// unseen photographs and label maps, synthetic rectangles, grains and stripes) the mean rose
/// on 16 and fell on 6 (docs/measurements.md, session 45); only pieces exactly along an axis
/// count: taking those within 5° too
/// (simplification tilts a pixel edge's boundary by a pixel or so) made the band's cells
/// 0.6–1.6 spacings wide with their lattice line kept or dropped along a piece, and
/// scikit-image's checkerboard fell 0.863 → 0.820.
fn axis_crossings(
    t: &Triangulation,
    lattice: &Lattice,
    reach: f64,
) -> Vec<(VertexId, VertexId, Vec<Point>)> {
    let grid = EdgeGrid::new(t, reach);
    let mut crossings = Vec::new();
    for h in t.constrained_edges() {
        let (u, w) = (t.origin(h), t.destination(h));
        let (pu, pw) = (t.point(u), t.point(w));
        // The piece itself is no obstacle; its neighbours are, so no crossing lands within
        // `reach` of a corner or a junction.
        let clear = |p: Point| {
            grid.clear(p, reach, |[a, b]| {
                if (a == pu && b == pw) || (a == pw && b == pu) {
                    f64::INFINITY
                } else {
                    segment_distance(a, b, p)
                }
            })
        };
        // Along a column (x fixed) the rows cross it, along a row the columns.
        let axis = if pu.x == pw.x && pu.y != pw.y {
            1
        } else if pu.y == pw.y && pu.x != pw.x {
            0
        } else {
            continue;
        };
        let points: Vec<Point> = lattice
            .crossings(pu, pw, axis, 1)
            .into_iter()
            .map(|(_, p)| p)
            .filter(|&p| clear(p))
            .collect();
        if !points.is_empty() {
            crossings.push((u, w, points));
        }
    }
    crossings
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

    /// The lattice lines, each cell cut into `sub` equal parts, that cross the piece `pu pw`
    /// strictly between its ends, for a piece running along `axis` (0: along x, crossed by
    /// the columns; 1: along y, by the rows): each line's index (`sub` per cell, from the
    /// lattice's origin) and the crossing, in order from `pu`.
    fn crossings(&self, pu: Point, pw: Point, axis: usize, sub: usize) -> Vec<(usize, Point)> {
        let coordinate = |p: Point| if axis == 1 { p.y } else { p.x };
        let (from, to) = (coordinate(pu), coordinate(pw));
        let (lo, step) = (coordinate(self.lo), self.step[axis] / sub as f64);
        if from == to || !step.is_finite() || step <= 0.0 {
            return Vec::new();
        }
        // Only the lines between the ends.
        let first = ((from.min(to) - lo) / step).floor().max(0.0) as usize;
        let last = (((from.max(to) - lo) / step).ceil() as usize).min(self.n[axis] * sub);
        let mut lines: Vec<(usize, Point)> = (first.max(1)..last)
            .filter_map(|k| {
                let c = lo + k as f64 * step;
                let f = (c - from) / (to - from);
                // Exactly on an axis-parallel piece; interpolated on a tilted one.
                let p = match axis {
                    1 if pu.x == pw.x => Point::new(pu.x, c),
                    0 if pu.y == pw.y => Point::new(c, pu.y),
                    1 => Point::new(pu.x + f * (pw.x - pu.x), c),
                    _ => Point::new(c, pu.y + f * (pw.y - pu.y)),
                };
                (c > from.min(to) && c < from.max(to)).then_some((k, p))
            })
            .collect();
        // The lines come in increasing order: from `pu` when it is the lower end.
        if from > to {
            lines.reverse();
        }
        lines
    }
}

/// The constrained edges along a strip too thin for the lattice, with the number of equal
/// pieces to cut each into so that the strip's two rows of quads are about as long as they are
/// deep: pieces of length `b` across a strip `H` wide make quads of about `b/2 × H/2`, the mean
/// quad's area (a quarter of a squared spacing `s²`) at `b = s² / H`, no shorter than a quad
/// side `s/2`, and on a side more than 5° from an axis no longer than
/// [`TILTED_STRIP_ASPECT`]` · H` either (quads at most twice as long as deep) unless that is
/// under `s/2`. An edge runs along a strip where at least three quarters of the points sampled
/// along it (every half spacing) have another boundary piece nearer than [`STRIP`] spacings,
/// within 30° of parallel to it and sharing no end with it; `H` is the (upper) median of those
/// distances. The whole edge is cut (a G' edge at this step): cutting the pieces
/// [`BOUNDARY_PIECE`] leaves in two made them too short.
///
/// Where the edge and most of the pieces across run within 5° of one axis ([`NEAR_AXIS`]), it
/// is cut where the lattice's lines cross it instead (every few lines, or the lines and
/// points between them where the strip is thin: pieces at most [`STRIP_ASPECT`] times the
/// strip's depth), so that the pieces of its two sides face each other. Measured over 150
/// images (the fixtures, unseen photographs, and synthetic street grids, Voronoi grains,
/// rectangles and smoothed noise): the worst scaled Jacobian of street grids with streets and
/// a band along the border 4–10 px wide rose from 0.33–0.49 to 0.50 on six of twenty.
fn strip_splits(t: &Triangulation, spacing: f64, lattice: &Lattice) -> StripSplits {
    let reach = STRIP * spacing;
    let grid = EdgeGrid::new(t, reach);
    let ends = &grid.edges;
    // tan 30°: another piece within 30° of parallel has |cross| < tan 30° · |dot|.
    const PARALLEL: f64 = 0.577_350_269_189_625_8;
    let mut splits = StripSplits::default();
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
        let axis = near_axis(d);
        // Per sample, the distance to the nearest piece across, and whether that piece runs
        // near the same axis as this one.
        let mut heights: Vec<(f64, bool)> = (0..samples)
            .map(|i| {
                let p = pa + d * ((i as f64 + 0.5) / samples as f64);
                grid.index
                    .near(p)
                    .filter(|&j| across(j))
                    .map(|j| {
                        let [pc, pe] = ends[j as usize];
                        let same = axis.is_some() && near_axis(pe - pc) == axis;
                        (segment_distance(pc, pe, p), same)
                    })
                    .fold((f64::INFINITY, false), |a, b| if b.0 < a.0 { b } else { a })
            })
            .filter(|&(h, _)| h < reach)
            .collect();
        if heights.len() * 4 < samples * 3 {
            continue;
        }
        let along_axis = heights.iter().filter(|&&(_, same)| same).count() * 4 >= samples * 3;
        heights.sort_by(|a, b| a.0.total_cmp(&b.0));
        let height = heights[heights.len() / 2].0;
        // No piece shorter than a quad side: quads at least half a side long.
        let ideal = (spacing * spacing / height).max(0.5 * spacing);
        // Nor, along a tilted side, longer than TILTED_STRIP_ASPECT depths (above a quad
        // side): quads at most twice as long as deep, where the area rule alone left a strip
        // a pixel or two deep whole, its quads five times as long as deep. A side near an
        // axis is cut on the lattice's lines instead, or keeps the area rule: cut into short
        // equal pieces off those lines, its triangles to the lattice skew (a disc near the
        // border, worst scaled Jacobian 0.504 → 0.384).
        let ideal = match axis {
            None => ideal.min((TILTED_STRIP_ASPECT * height).max(0.5 * spacing)),
            Some(_) => ideal,
        };
        let longest = (length / (BOUNDARY_PIECE * spacing)).ceil();
        let (u, w) = (t.origin(h), t.destination(h));
        // A strip between two sides near one axis: the lattice's lines across each.
        let at = match axis.filter(|_| along_axis) {
            Some(axis) => {
                let most = ideal
                    .min(BOUNDARY_PIECE * spacing)
                    .min(STRIP_ASPECT * height);
                lattice_cuts(lattice, [pa, pb], axis, most)
            }
            None => Vec::new(),
        };
        let pieces = (length / ideal).round();
        if !at.is_empty() {
            splits.at_lines.push((u, w, at));
        } else if pieces > longest.max(1.0) {
            splits.equal.push((u, w, pieces as usize));
        }
    }
    splits
}

/// Where to cut the side `ends` of a strip running along `axis` into pieces of at most about
/// `most`: every `stride`-th line of the lattice with its cells cut in `sub`, counted from the
/// lattice's origin, so that both sides of the strip are cut on the same lines and its cells
/// are (nearly) rectangles; none within half a line's gap of an end. Cut each side on its
/// own, the pieces of one fall between the other's, and the strip's triangles pair into
/// rhombi (a scaled Jacobian of 0.33 in a 1.5 px strip along the border).
fn lattice_cuts(lattice: &Lattice, ends: [Point; 2], axis: usize, most: f64) -> Vec<Point> {
    let gap = lattice.step[axis];
    let sub = (gap / most).round().max(1.0) as usize;
    let stride = (most * sub as f64 / gap).floor().max(1.0) as usize;
    let margin = 0.5 * gap / sub as f64;
    lattice
        .crossings(ends[0], ends[1], axis, sub)
        .into_iter()
        .filter(|&(k, p)| {
            k % stride == 0 && ends.iter().all(|&e| p.distance_squared(e).sqrt() >= margin)
        })
        .map(|(_, p)| p)
        .collect()
}

/// The axis a piece of direction `d` runs along within [`NEAR_AXIS`] (0: x, 1: y), if any.
fn near_axis(d: Point) -> Option<usize> {
    if d.x.abs() <= NEAR_AXIS * d.y.abs() {
        Some(1)
    } else if d.y.abs() <= NEAR_AXIS * d.x.abs() {
        Some(0)
    } else {
        None
    }
}

/// tan 5°: how far from an axis the sides of a strip may run for [`strip_splits`] to cut them
/// on the lattice's lines (simplification tilts a pixel row's boundary by a pixel or so).
const NEAR_AXIS: f64 = 0.087_488_663_525_924;

/// The longest piece along a strip cut on the lattice's lines, in strip depths: the strip's
/// triangles then have angles of 21.8° or more, above refinement's 20.7°, which would split the
/// pieces of one side only, between the other's.
const STRIP_ASPECT: f64 = 2.5;

/// The longest piece along a tilted strip (cut into equal pieces), in strip depths, unless
/// that is under a quad side: its quads at most twice as long as deep. Measured over 150
/// images (session 47's), the quads with a shape under 0.5 went from 546 to 372 and those with
/// a scaled Jacobian under 0.5 from 82 to 59, the means within 0.003; at 2.5 depths 419 and 63,
/// at 3 474 and 73; at 1.75 332 and 54 but the means lower on 11 images, at 1.5 on 21.
const TILTED_STRIP_ASPECT: f64 = 2.0;

/// The cuts [`strip_splits`] makes: equal pieces, or at given points (in order from the
/// first vertex).
#[derive(Default)]
struct StripSplits {
    equal: Vec<(VertexId, VertexId, usize)>,
    at_lines: Vec<(VertexId, VertexId, Vec<Point>)>,
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
    use proptest::prelude::*;

    /// The triangulation of `points` with the `segments` between them, its regions labelled
    /// from `seeds`, and the points of a uniform DT' of spacing 4 inserted.
    fn uniform_at_4(
        points: &[Point],
        segments: &[(usize, usize)],
        seeds: &[(Point, u32)],
    ) -> Triangulation {
        let (mut t, v) = Triangulation::from_points(points).unwrap();
        for &(a, b) in segments {
            t.insert_segment(v[a], v[b]).unwrap();
        }
        t.label_regions(seeds);
        uniform_points(&mut t, 4.0).unwrap();
        t.check().unwrap();
        t
    }

    /// The lengths of the segment pieces on the line through `through` along `direction`.
    fn pieces_on_line(t: &Triangulation, through: Point, direction: Point) -> Vec<f64> {
        let on = |p: Point| {
            let r = p - through;
            (r.x * direction.y - r.y * direction.x).abs() < 1e-9
        };
        t.constrained_edges()
            .map(|h| [t.point(t.origin(h)), t.point(t.destination(h))])
            .filter(|&[a, b]| on(a) && on(b))
            .map(|[a, b]| a.distance_squared(b).sqrt())
            .collect()
    }

    /// A strip 4.4 deep across a 40 × 20 domain at spacing 4 (no lattice point fits in it),
    /// rising 4 over its length (5.7°: a strip nearer an axis is cut on the lattice's lines
    /// instead): its two boundaries are cut into pieces about as long as the strip is deep
    /// (16 / 4.38 ≈ 3.7, eleven of them, where the 1.5-spacing rule alone gives seven of
    /// 5.7), and the borders, farther from any parallel boundary, keep the lattice's pieces.
    #[test]
    fn a_thin_strip_gets_pieces_as_long_as_it_is_deep() {
        let corners = [(0.0, 0.0), (40.0, 0.0), (40.0, 20.0), (0.0, 20.0)];
        let strip = [(0.0, 6.0), (40.0, 10.0), (40.0, 14.4), (0.0, 10.4)];
        let points: Vec<Point> = corners
            .iter()
            .chain(&strip)
            .map(|&p| Point::from(p))
            .collect();
        let t = uniform_at_4(
            &points,
            &[(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (7, 6)],
            &[
                (Point::new(20.0, 4.0), 0),
                (Point::new(20.0, 10.2), 1),
                (Point::new(20.0, 16.0), 2),
            ],
        );
        // The pieces on the line y = y0 + rise · x (the border's with rise 0).
        let pieces_along =
            |y0: f64, rise: f64| pieces_on_line(&t, Point::new(0.0, y0), Point::new(1.0, rise));
        let length = (40.0f64 * 40.0 + 4.0 * 4.0).sqrt();
        for y0 in [6.0, 10.4] {
            let pieces = pieces_along(y0, 0.1);
            assert_eq!(pieces.len(), 11, "{y0}: {pieces:?}");
            assert!(
                pieces.iter().all(|&l| (l - length / 11.0).abs() < 1e-9),
                "{pieces:?}"
            );
        }
        let border = pieces_along(0.0, 0.0);
        assert_eq!(border.len(), 10, "{border:?}");
        assert!(border.iter().all(|&l| (l - 4.0).abs() < 1e-9), "{border:?}");
    }

    /// A strip 1 deep and 10 long at 36.9° (a parallelogram region) in a 40 × 20 domain at
    /// spacing 4: its long sides are cut into five pieces of 2 (a quad side: the bound, two
    /// depths, is no shorter), quads about twice as long as deep, where the area rule alone
    /// (pieces of `s² / H` = 16) left them to the 1.5-spacing rule's two pieces of 5 (quads
    /// five times as long as deep).
    #[test]
    fn a_tilted_thin_strip_gets_pieces_at_most_two_depths_long() {
        let (d, n) = (Point::new(0.8, 0.6), Point::new(-0.6, 0.8));
        let a = Point::new(10.0, 5.0);
        let b = a + n;
        let corners = [(0.0, 0.0), (40.0, 0.0), (40.0, 20.0), (0.0, 20.0)].map(Point::from);
        let strip = [a, a + d * 10.0, b + d * 10.0, b];
        let points: Vec<Point> = corners.iter().chain(&strip).copied().collect();
        let t = uniform_at_4(
            &points,
            &[
                (0, 1),
                (1, 2),
                (2, 3),
                (3, 0),
                (4, 5),
                (5, 6),
                (6, 7),
                (7, 4),
            ],
            &[(Point::new(30.0, 4.0), 0), (a + d * 5.0 + n * 0.5, 1)],
        );
        for start in [a, b] {
            let pieces = pieces_on_line(&t, start, d);
            assert_eq!(pieces.len(), 5, "{start:?}: {pieces:?}");
            assert!(pieces.iter().all(|&l| (l - 2.0).abs() < 1e-9), "{pieces:?}");
        }
    }

    /// A strip 1.3–1.5 deep along the top border of a 40 × 20 domain at spacing 4, its inner
    /// side tilted by 0.3°: both sides are cut where the lattice's columns cross them, so that
    /// the strip's cells are (nearly) rectangles. Each cut on its own, the inner side's pieces
    /// fell between the border's and the strip's triangles paired into rhombi.
    #[test]
    fn a_strip_near_an_axis_is_cut_on_the_same_lattice_lines_on_both_sides() {
        let points: Vec<Point> = [
            (0.0, 0.0),
            (40.0, 0.0),
            (40.0, 20.0),
            (0.0, 20.0),
            (0.0, 18.5),
            (40.0, 18.7),
        ]
        .iter()
        .map(|&p| Point::from(p))
        .collect();
        let t = uniform_at_4(
            &points,
            &[(0, 1), (1, 5), (5, 2), (2, 3), (3, 4), (4, 0), (4, 5)],
            &[(Point::new(20.0, 10.0), 0), (Point::new(20.0, 19.5), 1)],
        );
        // The x of the vertices strictly inside each side, in order.
        let inside_on = |y: &dyn Fn(f64) -> f64| -> Vec<f64> {
            let mut xs: Vec<f64> = t
                .points()
                .iter()
                .filter(|p| p.x > 0.0 && p.x < 40.0 && (p.y - y(p.x)).abs() < 1e-9)
                .map(|p| p.x)
                .collect();
            xs.sort_by(f64::total_cmp);
            xs
        };
        let border = inside_on(&|_| 20.0);
        let inner = inside_on(&|x| 18.5 + 0.005 * x);
        let columns: Vec<f64> = (1..10).map(|k| 4.0 * k as f64).collect();
        assert_eq!(border, columns);
        assert_eq!(inner.len(), columns.len(), "{inner:?}");
        for (x, c) in inner.iter().zip(&columns) {
            assert!((x - c).abs() < 1e-9, "{inner:?}");
        }
    }

    /// A rectangle 40 × 20 cut by the vertical boundary x = 13, off the lattice's columns at
    /// spacing 4 (x = 12 is too near it, x = 16 is kept): the rows cross it at y = 4, 8, 12 and
    /// 16, and every triangle on one of its pieces is a right triangle with its apex in line
    /// with an end of the piece, half of a rectangle reaching the nearest column kept.
    #[test]
    fn an_axis_parallel_boundary_is_cut_where_the_lattice_rows_cross_it() {
        let points = [
            (0.0, 0.0),
            (40.0, 0.0),
            (40.0, 20.0),
            (0.0, 20.0),
            (13.0, 0.0),
            (13.0, 20.0),
        ]
        .map(Point::from);
        let t = uniform_at_4(
            &points,
            &[(0, 4), (4, 1), (1, 2), (2, 5), (5, 3), (3, 0), (4, 5)],
            &[(Point::new(5.0, 10.0), 0), (Point::new(30.0, 10.0), 1)],
        );
        let pieces: Vec<[Point; 2]> = t
            .constrained_edges()
            .map(|h| [t.point(t.origin(h)), t.point(t.destination(h))])
            .filter(|[a, b]| a.x == 13.0 && b.x == 13.0)
            .collect();
        let mut ends: Vec<f64> = pieces.iter().flat_map(|[a, b]| [a.y, b.y]).collect();
        ends.sort_by(f64::total_cmp);
        ends.dedup();
        assert_eq!(ends, [0.0, 4.0, 8.0, 12.0, 16.0, 20.0]);
        for h in t.edges().flat_map(|h| [h, t.twin(h)]) {
            let (a, b) = (t.point(t.origin(h)), t.point(t.destination(h)));
            if !(t.is_constrained(h) && a.x == 13.0 && b.x == 13.0)
                || t.neighbour(t.twin(h)).is_none()
            {
                continue;
            }
            let apex = t.point(t.origin(t.prev(h)));
            assert!(apex.y == a.y || apex.y == b.y, "{a:?} {b:?} {apex:?}");
            assert!(apex.x == 8.0 || apex.x == 16.0, "{apex:?}");
        }
    }

    proptest! {
        /// Axis-parallel boundaries anywhere in a rectangle: the lattice's crossings keep the
        /// triangulation valid, the domain's area, and every piece of such a boundary exactly
        /// on its line.
        #[test]
        fn axis_parallel_boundaries_stay_straight_and_the_domain_whole(
            cuts in proptest::collection::vec((any::<bool>(), 1u32..59, 0u32..40, 1u32..40), 1..6),
            spacing in 1.5f64..7.0,
        ) {
            let (w, h) = (60.0, 40.0);
            let mut points = vec![Point::new(0.0, 0.0), Point::new(w, 0.0), Point::new(w, h), Point::new(0.0, h)];
            for &(vertical, at, from, len) in &cuts {
                let (at, from) = (f64::from(at) + 0.5, f64::from(from));
                let to = (from + f64::from(len)).min(if vertical { h } else { w });
                if to <= from {
                    continue;
                }
                let (a, b) = if vertical {
                    (Point::new(at.min(w - 0.5), from), Point::new(at.min(w - 0.5), to))
                } else {
                    (Point::new(from, at.min(h - 0.5)), Point::new(to, at.min(h - 0.5)))
                };
                points.push(a);
                points.push(b);
            }
            let (mut t, v) = Triangulation::from_points(&points).unwrap();
            for k in 0..4 {
                t.insert_segment(v[k], v[(k + 1) % 4]).unwrap();
            }
            for k in (4..points.len()).step_by(2) {
                // Crossing cuts are a different test: keep those that cross nothing.
                if t.insert_segment(v[k], v[k + 1]).is_err() {
                    return Ok(());
                }
            }
            t.set_labels(|_| 0);
            let area = |t: &Triangulation| t.triangles().map(|f| t.signed_area(f)).sum::<f64>();
            let before = area(&t);
            uniform_points(&mut t, spacing).unwrap();
            t.check().unwrap();
            prop_assert!((area(&t) - before).abs() < 1e-9 * before);
            for s in 4..t.num_segments() {
                let [a, b] = t.segment_ends(imesh_geom::SegmentId(s as u32)).map(|x| t.point(x));
                for u in t.segment_vertices(imesh_geom::SegmentId(s as u32)) {
                    let p = t.point(u);
                    prop_assert!(if a.x == b.x { p.x == a.x } else { p.y == a.y }, "{p:?} off {a:?} {b:?}");
                }
            }
        }
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
