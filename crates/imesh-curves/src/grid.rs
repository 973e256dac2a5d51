//! A uniform grid over the graph's bounding box: the spatial index that keeps the
//! topology checks of simplification local (edges and vertices near a shortcut only).

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use rayon::prelude::*;

use crate::graph::CurveGraph;

/// Cells of side `h` over a bounding box; cell `(cx, cy)` has index `cy * nx + cx`.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    origin: Point,
    h: f64,
    /// `1 / h`: cell lookups multiply (a division costs several times as long, and lookups
    /// are most of a query's arithmetic). Rounding makes no difference that matters: a lookup is
    /// monotone in its coordinate either way.
    inverse_h: f64,
    nx: usize,
    ny: usize,
}

impl Grid {
    /// A grid over the bounding box of `points` with about `cells` cells (at least one).
    pub(crate) fn new(points: impl Iterator<Item = Point> + Clone, cells: usize) -> Self {
        let (mut lo, mut hi) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in points {
            lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        if lo.x > hi.x {
            lo = Point::new(0.0, 0.0);
            hi = lo;
        }
        let (w, hgt) = (
            (hi.x - lo.x).max(f64::MIN_POSITIVE),
            (hi.y - lo.y).max(f64::MIN_POSITIVE),
        );
        let cells = cells.clamp(1, 1 << 24) as f64;
        let mut h = (w * hgt / cells).sqrt();
        // A very thin box: cells along its long side only.
        h = h.max(w.max(hgt) / cells).max(f64::MIN_POSITIVE);
        let nx = ((w / h).floor() as usize + 1).min(1 << 24);
        let ny = ((hgt / h).floor() as usize + 1).min(1 << 24);
        Self {
            origin: lo,
            h,
            inverse_h: 1.0 / h,
            nx,
            ny,
        }
    }

    /// The number of cells.
    pub(crate) fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// The number of columns.
    pub(crate) fn columns(&self) -> usize {
        self.nx
    }

    /// The abscissa where column `c` starts.
    pub(crate) fn column_start(&self, c: usize) -> f64 {
        self.origin.x + c as f64 * self.h
    }

    /// The column holding abscissa `x` (clamped to the grid).
    pub(crate) fn column(&self, x: f64) -> usize {
        index((x - self.origin.x) * self.inverse_h, self.nx)
    }

    fn row(&self, y: f64) -> usize {
        index((y - self.origin.y) * self.inverse_h, self.ny)
    }

    /// The cell holding `p` (clamped to the grid).
    pub(crate) fn cell(&self, p: Point) -> usize {
        self.row(p.y) * self.nx + self.column(p.x)
    }

    /// Calls `f` on every cell that meets the segment `ab` grown by `pad` in x and y (a superset of
    /// the cells within distance `pad` of it).
    pub(crate) fn cells_near_segment(
        &self,
        a: Point,
        b: Point,
        pad: f64,
        mut f: impl FnMut(usize),
    ) {
        let (left, right) = if a.x <= b.x { (a, b) } else { (b, a) };
        let dx = right.x - left.x;
        let c0 = self.column(left.x - pad);
        let c1 = self.column(right.x + pad);
        let margin = pad + 1e-9 * self.h;
        if c0 == c1 {
            // One column (most short edges): every row the segment's y-range meets.
            let (y0, y1) = (left.y.min(right.y), left.y.max(right.y));
            for cy in self.row(y0 - margin)..=self.row(y1 + margin) {
                f(cy * self.nx + c0);
            }
            return;
        }
        for cx in c0..=c1 {
            let slab0 = self.origin.x + cx as f64 * self.h - pad;
            let slab1 = slab0 + self.h + 2.0 * pad;
            let (y0, y1) = if dx <= 0.0 {
                (left.y.min(right.y), left.y.max(right.y))
            } else {
                let t0 = ((slab0 - left.x) / dx).clamp(0.0, 1.0);
                let t1 = ((slab1 - left.x) / dx).clamp(0.0, 1.0);
                let (ya, yb) = (
                    left.y + t0 * (right.y - left.y),
                    left.y + t1 * (right.y - left.y),
                );
                (ya.min(yb), ya.max(yb))
            };
            // The parameter arithmetic rounds: the margin widens by a rounding error on top of
            // `pad`.
            for cy in self.row(y0 - margin)..=self.row(y1 + margin) {
                f(cy * self.nx + cx);
            }
        }
    }
}

/// `⌊t⌋` clamped to `0..n`. A cast truncates towards zero, which is the floor for the
/// non-negative values it sees here, and it needs no call to `floor` on baseline x86-64;
/// NaN casts to 0.
fn index(t: f64, n: usize) -> usize {
    if t > 0.0 {
        (t as usize).min(n - 1)
    } else {
        0
    }
}

/// True when the closed segments `ab` and `cd` meet anywhere except at one shared end vertex
/// (vertex identity by index: `ends` are `[a, b]` and `[c, d]`). Sharing an end and running on
/// along the same line (overlap) is a conflict; so is any touch between segments with no common
/// end.
pub(crate) fn conflict(points: &[Point], [a, b]: [u32; 2], [c, d]: [u32; 2]) -> bool {
    let p = |v: u32| points[v as usize];
    if (a == c && b == d) || (a == d && b == c) {
        return true;
    }
    let shared = if a == c || a == d {
        Some((a, b, if a == c { d } else { c }))
    } else if b == c || b == d {
        Some((b, a, if b == c { d } else { c }))
    } else {
        None
    };
    if let Some((x, z, y)) = shared {
        // One common end x: only an overlap along one line conflicts.
        let (px, pz, py) = (p(x), p(z), p(y));
        if orient2d(px, pz, py) != 0.0 {
            return false;
        }
        let same = |u: f64, v: f64| (u > 0.0 && v > 0.0) || (u < 0.0 && v < 0.0);
        return same(pz.x - px.x, py.x - px.x) || same(pz.y - px.y, py.y - px.y);
    }
    let (pa, pb, pc, pd) = (p(a), p(b), p(c), p(d));
    let o1 = orient2d(pa, pb, pc);
    let o2 = orient2d(pa, pb, pd);
    let o3 = orient2d(pc, pd, pa);
    let o4 = orient2d(pc, pd, pb);
    let opposite = |u: f64, v: f64| (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0);
    if opposite(o1, o2) && opposite(o3, o4) {
        return true;
    }
    (o1 == 0.0 && within(pa, pb, pc))
        || (o2 == 0.0 && within(pa, pb, pd))
        || (o3 == 0.0 && within(pc, pd, pa))
        || (o4 == 0.0 && within(pc, pd, pb))
}

/// For `q` collinear with `ab`: true when `q` lies on the closed segment.
pub(crate) fn within(a: Point, b: Point, q: Point) -> bool {
    q.x >= a.x.min(b.x) && q.x <= a.x.max(b.x) && q.y >= a.y.min(b.y) && q.y <= a.y.max(b.y)
}

/// Items per cell, known at the start: stored contiguously per cell (compressed rows), so that a
/// query reads one slice.
#[derive(Clone, Debug)]
pub(crate) struct CellLists<T = u32> {
    first: Vec<u32>,
    items: Vec<T>,
}

impl<T: Copy + Default> CellLists<T> {
    /// The lists of `cells` cells holding `(cell, item)` pairs.
    pub(crate) fn new(cells: usize, pairs: &[(u32, T)]) -> Self {
        // A counting sort by cell.
        let mut first = vec![0u32; cells + 1];
        for &(c, _) in pairs {
            first[c as usize + 1] += 1;
        }
        for c in 0..cells {
            first[c + 1] += first[c];
        }
        let mut fill = first.clone();
        let mut items = vec![T::default(); pairs.len()];
        for &(c, item) in pairs {
            items[fill[c as usize] as usize] = item;
            fill[c as usize] += 1;
        }
        Self { first, items }
    }

    /// The items of `cell`.
    pub(crate) fn get(&self, cell: usize) -> &[T] {
        &self.items[self.first[cell] as usize..self.first[cell + 1] as usize]
    }
}

/// Registers each edge of `g` in the cells it meets.
pub(crate) fn edge_cells(g: &CurveGraph, grid: &Grid) -> CellLists {
    let segments = g.edges().iter().map(|e| e.ends.map(|v| g.point(v)));
    bucket(grid, segments, 0.0)
}

/// Registers each segment (by its position in `segments`) in the cells it meets grown by `pad`.
fn bucket(grid: &Grid, segments: impl ExactSizeIterator<Item = [Point; 2]>, pad: f64) -> CellLists {
    let mut pairs = Vec::with_capacity(2 * segments.len());
    for (k, [a, b]) in segments.enumerate() {
        grid.cells_near_segment(a, b, pad, |c| pairs.push((c as u32, k as u32)));
    }
    CellLists::new(grid.len(), &pairs)
}

/// Segments bucketed by the cells of a uniform grid that come within a distance `reach` of
/// them: the candidates near a point are every segment within `reach` of it, and a few farther
/// ones, read from one cell. For "is anything closer than `reach`?" over many points.
///
/// ```
/// use imesh_curves::{segment_distance, SegmentIndex};
/// use imesh_geom::Point;
/// let segments = [
///     [Point::new(0.0, 0.0), Point::new(10.0, 0.0)],
///     [Point::new(0.0, 5.0), Point::new(0.0, 9.0)],
/// ];
/// let index = SegmentIndex::new(&segments, 1.0);
/// let p = Point::new(5.0, 0.5);
/// let close: Vec<u32> = index
///     .near(p)
///     .filter(|&k| {
///         let [a, b] = segments[k as usize];
///         segment_distance(a, b, p) < 1.0
///     })
///     .collect();
/// assert_eq!(close, [0]);
/// ```
#[derive(Clone, Debug)]
pub struct SegmentIndex {
    grid: Grid,
    cells: CellLists,
}

impl SegmentIndex {
    /// Indexes `segments` (by their position in the slice) for queries within `reach` of them
    /// (a negative or non-finite reach counts as 0). The grid has about one cell per segment.
    pub fn new(segments: &[[Point; 2]], reach: f64) -> Self {
        let reach = if reach.is_finite() {
            reach.max(0.0)
        } else {
            0.0
        };
        let corners = segments.iter().flatten().flat_map(|p| {
            [
                Point::new(p.x - reach, p.y - reach),
                Point::new(p.x + reach, p.y + reach),
            ]
        });
        let grid = Grid::new(corners, segments.len());
        // A segment grown by `reach` in x and y holds every point within `reach` of it.
        let cells = bucket(&grid, segments.iter().copied(), reach);
        Self { grid, cells }
    }

    /// The indices of the segments that may lie within `reach` of `p`: at least all that do.
    pub fn near(&self, p: Point) -> impl Iterator<Item = u32> + '_ {
        self.cells.get(self.grid.cell(p)).iter().copied()
    }
}

/// A grid with about one cell per four edges (cells a few edge lengths wide).
pub(crate) fn grid_for(g: &CurveGraph) -> Grid {
    let used = g.edges().iter().flat_map(|e| e.ends).map(|v| g.point(v));
    Grid::new(used, g.edges().len() / 4)
}

/// The first pair of conflicting edges of `g`, if any: in the first cell that has one, the
/// first in that cell's order (the cells searched in parallel, the same pair found).
pub(crate) fn first_crossing(g: &CurveGraph) -> Option<[u32; 2]> {
    let grid = grid_for(g);
    let cells = edge_cells(g, &grid);
    (0..grid.len()).into_par_iter().find_map_first(|c| {
        let list = cells.get(c);
        list.iter().enumerate().find_map(|(k, &e)| {
            list[k + 1..].iter().find_map(|&f| {
                conflict(
                    g.points(),
                    g.edges()[e as usize].ends,
                    g.edges()[f as usize].ends,
                )
                .then(|| [e.min(f), e.max(f)])
            })
        })
    })
}
